//! The `poser` command line: argument definitions (clap) and dispatch to one handler per
//! subcommand. Each handler lives in its own file under `cli/` and calls into the library.
//!
//! Exit codes: 0 success, 1 invalid scene or failed run, 2 usage error.

use crate::backend::Backend;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

mod bench;
mod common;
mod compare;
mod compile;
mod dive;
mod evaluate;
mod explain;
mod lesson;
mod plan;
pub mod project;
mod render;
mod schema;
mod sensor;
mod truth;
mod validate;

pub use common::{CliError, load_model};

const EXAMPLES: &str = "\
Examples:
  poser render scenarios/reef_strip.toml -o out/reef          # native renderer, no Python
  poser validate scenarios/*.toml
  poser explain scenarios/calibration_flat.toml --set water.temperature=12
  poser project scenarios/calibration_flat.toml --points pts.csv --frame world
  poser truth scenarios/reef_strip.toml -o out/truth
  poser compile scenarios/dome_orbit.toml --backend mitsuba -o out/mi
  poser render scenarios/dome_orbit.toml --backend blender -o out/cycles
  poser compare scenarios/calibration_flat.toml --backends native,mitsuba -o out/cmp
  poser plan scenarios/paper_survey.toml
  poser evaluate scenarios/lessons/flat_port_deformation.toml -o out/eval
  poser lesson scenarios/lessons/calibration_by_port.toml -o out/lesson
  poser dive scenarios/paper_survey.toml -o dive.ssrf
  poser schema";

#[derive(Parser, Debug)]
#[command(
    name = "poser",
    version,
    about = "Simulate underwater photogrammetry surveys: validate, plan, render, ground truth.",
    after_help = EXAMPLES
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// A scene file plus command-line overrides.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Override any value of the scene, e.g. `--set water.temperature=12` or
    /// `--set 'render.samples=64'`. Repeatable; applied after includes.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FrameArg {
    Camera,
    World,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Check scenes and report every error and warning with file:line:column.
    Validate {
        /// Scene files.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Override values in every scene (`KEY=VALUE`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Treat warnings as errors.
        #[arg(long)]
        deny_warnings: bool,
    },
    /// Print the resolved model's key numbers and what will be modelled, and why.
    Explain {
        #[command(flatten)]
        scene: SceneArgs,
        /// Print the whole resolved model as JSON instead.
        #[arg(long)]
        json: bool,
    },
    /// Write the JSON Schema of the scene format (and the format reference in docs/).
    Schema {
        /// Directory of the schema.
        #[arg(short, long, default_value = "schema")]
        out: PathBuf,
        /// Directory of the generated format reference.
        #[arg(long, default_value = "docs")]
        docs: PathBuf,
        /// Do not write; fail if the files on disk are stale.
        #[arg(long)]
        check: bool,
    },
    /// Project 3D points (CSV `id,x,y,z`) to pixels through the port; writes `id,u,v,status`.
    Project {
        #[command(flatten)]
        scene: SceneArgs,
        /// CSV file with header `id,x,y,z` (metres).
        #[arg(long)]
        points: PathBuf,
        /// Camera of the rig (default: the first).
        #[arg(long)]
        camera: Option<String>,
        /// Frame of the input points.
        #[arg(long, value_enum, default_value = "camera")]
        frame: FrameArg,
        /// Rig pose index for `--frame world` (default 0).
        #[arg(long, default_value_t = 0)]
        pose: usize,
        /// Colour channel: r, g or b (default g).
        #[arg(long, default_value = "g")]
        channel: String,
        /// Output CSV (default: standard output).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Write exact ground truth for every image: target pixels, intrinsics, poses, COLMAP model.
    Truth {
        #[command(flatten)]
        scene: SceneArgs,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Compile a scene for another renderer (Mitsuba 3 XML or a Blender/bpy script).
    Compile {
        #[command(flatten)]
        scene: SceneArgs,
        #[arg(long, value_enum)]
        backend: Backend,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Render every pose (linear EXR + PNG) and write the ground truth beside the images.
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        #[arg(long, value_enum, default_value = "native")]
        backend: Backend,
        #[arg(short, long)]
        out: PathBuf,
        /// Override samples per pixel.
        #[arg(long)]
        samples: Option<u32>,
        /// Render only these pose indices (e.g. `0,3,5`).
        #[arg(long, value_delimiter = ',')]
        poses: Option<Vec<usize>>,
        /// Preview at a fraction of the cameras' resolution (e.g. `0.25`): same field of view,
        /// lens and port; the ground truth is written for the scaled images.
        #[arg(long)]
        scale: Option<f64>,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
        /// Run the camera's sensor stage (docs/sensor.md) with the default sensor when the
        /// scene has no `[sensor]`; writes `OUT/camera/<image>.jpg` and `.sensor.json`.
        #[arg(long)]
        sensor: bool,
    },
    /// Run the sensor stage on a linear EXR: exposure, shot and read noise, white balance, tone
    /// curve, 8-bit JPEG/PNG (the scene's `[sensor]`, or the default sensor).
    Sensor {
        #[command(flatten)]
        scene: SceneArgs,
        /// The linear EXR rendered from this scene.
        input: PathBuf,
        /// The camera image to write (`.jpg`/`.jpeg` or `.png`); the sidecar
        /// `<stem>.sensor.json` goes beside it.
        #[arg(short, long)]
        out: PathBuf,
        /// Rig pose index of the image (seeds its noise).
        #[arg(long, default_value_t = 0)]
        pose: usize,
        /// Camera of the rig (default: the first).
        #[arg(long)]
        camera: Option<String>,
        /// Per-pixel variance of the render (`<image>.variance.exr`) for the noise report.
        #[arg(long)]
        variance: Option<PathBuf>,
        /// Samples per pixel of the render (for the noise report's hint).
        #[arg(long)]
        samples: Option<u32>,
    },
    /// Survey plan: image count, path, time, GSD, footprint, overlaps achieved.
    Plan {
        #[command(flatten)]
        scene: SceneArgs,
        #[arg(long)]
        json: bool,
        /// Also write the coverage map/mesh into this directory.
        #[arg(long)]
        coverage: Option<PathBuf>,
    },
    /// Render with several backends and report target-position and radiometric agreement.
    Compare {
        #[command(flatten)]
        scene: SceneArgs,
        /// Backends to compare.
        #[arg(long, value_delimiter = ',', default_value = "native,mitsuba,blender")]
        backends: Vec<Backend>,
        #[arg(short, long)]
        out: PathBuf,
        /// Override samples per pixel.
        #[arg(long)]
        samples: Option<u32>,
        /// Render only these pose indices (e.g. `0,3,5`).
        #[arg(long, value_delimiter = ',')]
        poses: Option<Vec<usize>>,
    },
    /// Speed-against-error reports: `projection` (port solvers) or `render` (backends).
    Bench {
        /// What to benchmark: `projection`, `render` or `evaluate`.
        what: String,
        /// Write the report as JSON too.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Smaller, quicker run.
        #[arg(long)]
        quick: bool,
        /// `render` only: the backends to compare (default: all three).
        #[arg(long, value_enum, value_delimiter = ',')]
        backends: Vec<Backend>,
        /// `render` only: write the speed-against-error curves as an SVG plot.
        #[arg(long)]
        plot: Option<PathBuf>,
    },
    /// Process the simulated survey with COLMAP; errors against the truth, the bowl, a report.
    Evaluate(evaluate::Args),
    /// Run a lesson scene and write its self-contained HTML page.
    Lesson(lesson::Args),
    /// Dive profile, decompression and gas verdict; export to Subsurface.
    Dive {
        #[command(flatten)]
        scene: SceneArgs,
        /// Subsurface log to write (`.ssrf`).
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Plot of depth, ceiling and NDL over time (`.svg` or `.png`).
        #[arg(long)]
        plot: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
}

pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    ExitCode::SUCCESS
                }
                _ => ExitCode::from(2),
            };
        }
    };
    let result = match cli.command {
        Command::Validate {
            scenes,
            sets,
            deny_warnings,
        } => validate::run(&scenes, &sets, deny_warnings),
        Command::Explain { scene, json } => explain::run(&scene, json),
        Command::Schema { out, docs, check } => schema::run(&out, &docs, check),
        Command::Project {
            scene,
            points,
            camera,
            frame,
            pose,
            channel,
            output,
        } => project::run(
            &scene,
            &points,
            camera.as_deref(),
            frame,
            pose,
            &channel,
            output.as_deref(),
        ),
        Command::Truth { scene, out } => truth::run(&scene, &out),
        Command::Compile {
            scene,
            backend,
            out,
        } => compile::run(&scene, backend, &out),
        Command::Render {
            scene,
            backend,
            out,
            samples,
            poses,
            scale,
            quiet,
            sensor,
        } => render::run(&scene, backend, &out, samples, poses, scale, quiet, sensor),
        Command::Sensor {
            scene,
            input,
            out,
            pose,
            camera,
            variance,
            samples,
        } => sensor::run(
            &scene,
            &input,
            &out,
            pose,
            camera.as_deref(),
            variance.as_deref(),
            samples,
        ),
        Command::Plan {
            scene,
            json,
            coverage,
        } => plan::run(&scene, json, coverage.as_deref()),
        Command::Compare {
            scene,
            backends,
            out,
            samples,
            poses,
        } => compare::run(&scene, &backends, &out, samples, poses),
        Command::Bench {
            what,
            json,
            quick,
            backends,
            plot,
        } => bench::run(&what, json, quick, backends, plot),
        Command::Evaluate(args) => evaluate::run(&args),
        Command::Lesson(args) => lesson::run(&args),
        Command::Dive {
            scene,
            out,
            plot,
            json,
        } => dive::run(&scene, out.as_deref(), plot.as_deref(), json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => e.report(),
    }
}
