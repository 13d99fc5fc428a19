//! The `poser` command line: argument definitions (clap) and dispatch to one handler per
//! subcommand. Each handler lives in its own file under `cli/` and calls into the library.
//!
//! Exit codes: 0 success, 1 invalid scene or failed run, 2 usage error.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

mod bench;
mod column;
mod common;
mod compare;
mod compile;
mod dive;
mod evaluate;
pub mod explain;
mod export;
mod import;
mod keygen;
mod lesson;
mod pack;
mod plan;
pub mod project;
mod render;
mod rerun;
mod schema;
mod sensor;
mod slurm;
mod truth;
mod unpack;
mod validate;

pub use common::{CliError, load_model, load_scene};

const EXAMPLES: &str = "\
Examples:
  poser render scenarios/reef_strip.toml -o out/reef          # native renderer, no Python
  poser validate scenarios/*.toml
  poser explain scenarios/calibration_flat.toml --set water.temperature=12
  poser column scenarios/reef_strip.toml -o out/column        # the water column's light
  poser project scenarios/calibration_flat.toml --points pts.csv --frame world
  poser truth scenarios/reef_strip.toml -o out/truth
  poser compile scenarios/dome_orbit.toml --backend mitsuba -o out/mi
  poser render scenarios/dome_orbit.toml --backend blender -o out/cycles
  poser compare scenarios/calibration_flat.toml --backends native,mitsuba -o out/cmp
  poser plan scenarios/paper_survey.toml
  poser evaluate scenarios/lessons/flat_port_deformation.toml -o out/eval
  poser lesson scenarios/lessons/calibration_by_port.toml -o out/lesson
  poser dive scenarios/paper_survey.toml -o dive.ssrf
  poser import out/mi/img_*.xml -o imported.toml              # Mitsuba 3 XML → poser scene
  poser export scenarios/reef_strip.toml -o reef.glb         # glTF preview for any viewer
  poser pack scenarios/dome_orbit.toml -o orbit.poserpack --run \"render --scale 0.1 --poses 0\"
  poser rerun orbit.poserpack -o out/rerun
  poser keygen -o me.key                                      # then pack --sign me.key, rerun --trust me.key.pub
  poser slurm scenarios/reef_strip.toml -o /scratch/reef --shards 32 --cpus 8
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
    Validate(validate::Args),
    /// Print the resolved model's key numbers and what will be modelled, and why.
    Explain(explain::Args),
    /// Solve the water column's light (sun, sky, scattering, seabed) and write its profiles:
    /// column.json, column.csv and column.svg.
    Column(column::Args),
    /// Write the JSON Schema of the scene format (and the format reference in docs/).
    Schema(schema::Args),
    /// Project 3D points (CSV `id,x,y,z`) to pixels through the port; writes `id,u,v,status`.
    Project(project::Args),
    /// Write exact ground truth for every image: target pixels, intrinsics, poses, COLMAP model.
    Truth(truth::Args),
    /// Compile a scene for another renderer (Mitsuba 3 XML or a Blender/bpy script).
    Compile(compile::Args),
    /// Render every pose (linear EXR + PNG) and write the ground truth beside the images.
    Render(render::Args),
    /// Run the sensor stage on a linear EXR: exposure, shot and read noise, white balance, tone
    /// curve, 8-bit JPEG/PNG (the scene's `[sensor]`, or the default sensor).
    Sensor(sensor::Args),
    /// Survey plan: image count, path, time, GSD, footprint, overlaps achieved.
    Plan(plan::Args),
    /// Render with several backends and report target-position and radiometric agreement.
    Compare(compare::Args),
    /// Benchmarks: speed against error of the port solvers (`projection`) and the backends
    /// (`render`); `sensor`, `column`, `evaluate`, `parity`, `images`, `mesh`.
    Bench(bench::Args),
    /// Process the simulated survey with COLMAP; errors against the truth, the bowl, a report.
    Evaluate(evaluate::Args),
    /// Run a lesson scene and write its self-contained HTML page.
    Lesson(lesson::Args),
    /// Dive profile, decompression and gas verdict; export to Subsurface.
    Dive(dive::Args),
    /// Pack a scene, its includes and assets, and the commands run on it with the hashes of
    /// their outputs, into one reproducible archive.
    Pack(pack::Args),
    /// Check a pack and write its files into a folder.
    Unpack(unpack::Args),
    /// Rerun a pack's commands and report, file by file, whether the outputs are identical.
    Rerun(rerun::Args),
    /// Make an ed25519 key pair to sign packs with (`pack --sign KEY`, `rerun --trust KEY.pub`).
    Keygen(keygen::Args),
    /// Write the scene as a glTF 2.0 binary preview (.glb): site, targets, water surface, ports,
    /// every camera pose, the swim path and the lights, for any glTF viewer.
    Export(export::Args),
    /// Import Mitsuba 3 XML scenes into a poser scene file (meshes as glTF assets); what cannot
    /// be expressed is listed with file, line and column.
    Import(import::Args),
    /// Write SLURM job-array scripts that render the survey in shards on a cluster.
    Slurm(slurm::Args),
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
    let result = dispatch(cli.command);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => e.report(),
    }
}

/// Run one parsed command.
pub fn dispatch(command: Command) -> Result<(), CliError> {
    match command {
        Command::Validate(args) => validate::run(&args),
        Command::Explain(args) => explain::run(&args),
        Command::Column(args) => column::run(&args),
        Command::Schema(args) => schema::run(&args),
        Command::Project(args) => project::run(&args),
        Command::Truth(args) => truth::run(&args),
        Command::Compile(args) => compile::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Sensor(args) => sensor::run(&args),
        Command::Plan(args) => plan::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Evaluate(args) => evaluate::run(&args),
        Command::Lesson(args) => lesson::run(&args),
        Command::Dive(args) => dive::run(&args),
        Command::Pack(args) => pack::run(&args),
        Command::Unpack(args) => unpack::run(&args),
        Command::Rerun(args) => rerun::run(&args),
        Command::Keygen(args) => keygen::run(&args),
        Command::Slurm(args) => slurm::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Import(args) => import::run(&args),
    }
}
