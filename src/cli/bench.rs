//! `poser bench`: speed-against-error reports (projection solvers; render backends), the cost
//! of an image at the sensor's noise (`sensor`), the water column's bias (`column`), COLMAP on
//! rendered surveys (`images`), the backends' agreement on every shipped scene (`parity`), and a
//! large textured mesh's load, BVH, truth and render (`mesh`). One clap subcommand per report,
//! each with its own `Args`.
use super::CliError;
use crate::backend::Backend;
use std::path::PathBuf;

/// The arguments of `poser bench`: one subcommand per report, each with only its own options
/// (clap refuses another report's option, e.g. `poser bench projection --triangles 10`).
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

/// Which report.
#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// The port solvers: speed against error of the exact and fast projections.
    Projection(Common),
    /// The render backends: speed against error on every shipped scene.
    Render(RenderArgs),
    /// The cost of an image at the sensor's own noise, per daylight estimator.
    Sensor(ScenesArgs),
    /// The water column's bias and noise against the random walks.
    Column(ScenesArgs),
    /// COLMAP on the lessons' surveys, against the truth.
    Evaluate(Common),
    /// The backends' agreement on every shipped scene.
    Parity(ParityArgs),
    /// COLMAP on rendered surveys: registered share, reprojection error, focal length.
    Images(ImagesArgs),
    /// A large textured mesh: load, BVH, truth and render, with the peak memory.
    Mesh(MeshArgs),
}

/// The options every report has.
#[derive(clap::Args, Debug)]
pub struct Common {
    /// Write the report as JSON too.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Smaller, quicker run.
    #[arg(long)]
    pub quick: bool,
}

/// `sensor`, `column` and `images`.
#[derive(clap::Args, Debug)]
pub struct ScenesArgs {
    #[command(flatten)]
    pub common: Common,
    /// Only the scenes whose file name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Keep the renders here (default: a temporary folder, removed afterwards).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `images`.
#[derive(clap::Args, Debug)]
pub struct ImagesArgs {
    #[command(flatten)]
    pub scenes: ScenesArgs,
    /// Also hand the same JPEGs to COLMAP as it ships (`poser evaluate --stock`: its
    /// defaults, the focal length from the EXIF, the initial pair's angle lowered to 8°) and
    /// report its registration beside poser's pipeline.
    #[arg(long)]
    pub stock: bool,
}

/// `render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: Common,
    /// The backends to compare (default: all three).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backends: Vec<Backend>,
    /// Only the scenes whose file name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Write the speed-against-error curves as an SVG plot.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Replace the generated summary block of this Markdown file (the README).
    #[arg(long)]
    pub readme: Option<PathBuf>,
    /// Rebuild the report, its JSON, plot and README block from a saved JSON report, without
    /// rendering (the column's bias counted again).
    #[arg(long, value_name = "JSON")]
    pub from: Option<PathBuf>,
}

/// `parity`.
#[derive(clap::Args, Debug)]
pub struct ParityArgs {
    #[command(flatten)]
    pub scenes: ScenesArgs,
    /// The backends to compare (default: all three).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backends: Vec<Backend>,
    /// Render each scene again with four times the samples until every pair of backends is
    /// decided (noise allowance ≤ 1 %) or differs, within this many seconds per scene.
    #[arg(long, value_name = "SECONDS")]
    pub decisive: Option<f64>,
}

/// `mesh`.
#[derive(clap::Args, Debug)]
pub struct MeshArgs {
    #[command(flatten)]
    pub common: Common,
    /// Triangles of the generated site (default 5 000 000; `--quick`: 500 000).
    #[arg(long)]
    pub triangles: Option<u64>,
    /// Side of its square texture, texels (default 8192; `--quick`: 2048).
    #[arg(long)]
    pub texture: Option<u32>,
    /// Keep the generated site, its scene and the render here (default: a temporary folder,
    /// removed afterwards).
    #[arg(long)]
    pub keep: Option<PathBuf>,
    /// Write the site alone (`model.obj`, `model.mtl`, `model.jpg`) into this folder and stop,
    /// no bench; sizes from `--triangles` and `--texture`, by default the shipped site's
    /// (32 000 triangles, 2048²): `poser bench mesh --site
    /// scenarios/sites/assets/textured_bommie` rewrites it.
    #[arg(long)]
    pub site: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let root = crate::backend::python::repo_root;
    match &args.what {
        What::Mesh(a) if a.site.is_some() => site_only(a),
        What::Mesh(a) => {
            speed_warning();
            let mut opts = crate::bench::mesh::Options::new(a.common.quick);
            opts.triangles = a.triangles.unwrap_or(opts.triangles);
            opts.texture = a.texture.unwrap_or(opts.texture);
            opts.keep = a.keep.clone();
            let report = crate::bench::mesh::run(&opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::mesh::table(&report));
            write_json(a.common.json.as_deref(), &report)
        }
        What::Projection(c) => {
            speed_warning();
            let rows = crate::bench::projection::run(c.quick);
            println!(
                "batch solvers: {} lanes, {} build\n",
                crate::optics::port::LANES,
                crate::optics::port::Simd::detect().name()
            );
            print!("{}", crate::bench::projection::table(&rows));
            write_json(c.json.as_deref(), &rows)
        }
        What::Render(a) => {
            speed_warning();
            let opts = crate::bench::render::BenchOptions {
                quick: a.common.quick,
                backends: a.backends.clone(),
                only: a.only.clone(),
                json: a.common.json.clone(),
                plot: a.plot.clone(),
                readme: a.readme.clone(),
                from: a.from.clone(),
            };
            crate::bench::render::run(&root(), &opts)
                .map(|_| ())
                .map_err(CliError::Failed)
        }
        What::Evaluate(c) => {
            let lessons = root().join("scenarios/lessons");
            let rows = crate::bench::evaluate::run(&lessons, c.quick).map_err(CliError::Failed)?;
            print!("{}", crate::bench::evaluate::table(&rows));
            write_json(c.json.as_deref(), &rows)
        }
        What::Parity(a) => {
            let backends = if a.backends.is_empty() {
                Backend::ALL.to_vec()
            } else {
                a.backends.clone()
            };
            let s = &a.scenes;
            let (_tmp, out) = out_dir(s.out.as_ref())?;
            let rows = crate::bench::parity::run(
                &root(),
                &backends,
                s.common.quick,
                s.only.as_deref(),
                &out,
                a.decisive,
            )
            .map_err(CliError::Failed)?;
            print!("{}", crate::bench::parity::table(&rows));
            write_json(s.common.json.as_deref(), &rows)
        }
        What::Sensor(a) => {
            let (_tmp, out) = out_dir(a.out.as_ref())?;
            let opts = crate::bench::sensor::Options {
                scale: if a.common.quick { 0.25 } else { 1.0 },
                pilots: [2, 8],
                only: a.only.clone(),
                poser: this_program()?,
                out,
            };
            let rows = crate::bench::sensor::run(&root(), &opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::sensor::table(&rows));
            write_json(a.common.json.as_deref(), &rows)
        }
        What::Column(a) => {
            let (_tmp, out) = out_dir(a.out.as_ref())?;
            let mut opts = crate::bench::column::Options::new(a.common.quick, this_program()?, out);
            opts.only = a.only.clone();
            let rows = crate::bench::column::run(&root(), &opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::column::table(&rows));
            write_json(a.common.json.as_deref(), &rows)
        }
        What::Images(ImagesArgs { scenes: a, stock }) => {
            let (_tmp, out) = out_dir(a.out.as_ref())?;
            let rows =
                crate::bench::images::run(&root(), a.common.quick, a.only.as_deref(), *stock, &out)
                    .map_err(CliError::Failed)?;
            print!("{}", crate::bench::images::table(&rows));
            write_json(a.common.json.as_deref(), &rows)
        }
    }
}

/// The reports that time code say so when the build is not optimised for speed.
fn speed_warning() {
    if cfg!(debug_assertions) {
        eprintln!("warning: this is a debug build; speeds are not representative (use --release)");
    }
}

/// This `poser` executable, which the benches that measure whole runs start as a child.
fn this_program() -> Result<PathBuf, CliError> {
    std::env::current_exe().map_err(|e| CliError::Failed(e.to_string()))
}

/// `--out DIR`, else a temporary folder (removed when the returned guard drops).
fn out_dir(out: Option<&PathBuf>) -> Result<(Option<tempfile::TempDir>, PathBuf), CliError> {
    match out {
        Some(o) => Ok((None, o.clone())),
        None => {
            let tmp = tempfile::tempdir().map_err(|e| CliError::Failed(e.to_string()))?;
            let path = tmp.path().to_path_buf();
            Ok((Some(tmp), path))
        }
    }
}

/// Write a bench's rows as JSON when `--json` was given (atomically).
fn write_json(
    path: Option<&std::path::Path>,
    rows: &impl serde::Serialize,
) -> Result<(), CliError> {
    let Some(path) = path else { return Ok(()) };
    let text = serde_json::to_string_pretty(rows).map_err(|e| CliError::Failed(e.to_string()))?;
    crate::io::write_atomic(path, text.as_bytes())
        .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))
}

/// `poser bench mesh --site DIR`: the site's files alone, at the shipped sizes unless given.
fn site_only(args: &MeshArgs) -> Result<(), CliError> {
    use crate::geometry::bommie;
    if args.keep.is_some() || args.common.json.is_some() || args.common.quick {
        return Err(CliError::Usage(
            "--site writes the site alone: without --keep, --json or --quick".into(),
        ));
    }
    let dir = args.site.as_deref().unwrap_or(std::path::Path::new("."));
    let triangles = args.triangles.unwrap_or(bommie::SHIPPED_TRIANGLES);
    let texture = args.texture.unwrap_or(bommie::SHIPPED_TEXTURE);
    let w = bommie::write(dir, triangles, texture).map_err(CliError::Failed)?;
    println!(
        "{}: model.obj ({triangles} triangles, {} vertices, {} bytes), model.mtl, model.jpg \
         ({texture}², {} bytes)",
        dir.display(),
        w.vertices,
        w.obj_bytes,
        w.image_bytes
    );
    Ok(())
}
