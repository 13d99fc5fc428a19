//! `poser bench`: speed-against-error reports (projection solvers; render backends), the cost
//! of an image at the sensor's noise (`sensor`), the water column's bias (`column`), COLMAP on
//! rendered surveys (`images`), the backends' agreement on every shipped scene (`parity`), and a
//! large textured mesh's load, BVH, truth and render (`mesh`).
use super::CliError;
use crate::backend::Backend;
use std::path::PathBuf;

/// The arguments of `poser bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to benchmark: `projection`, `render`, `sensor`, `column`, `evaluate`, `parity`,
    /// `images` or `mesh`.
    pub what: String,
    /// Write the report as JSON too.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Smaller, quicker run.
    #[arg(long)]
    pub quick: bool,
    /// `render` and `parity`: the backends to compare (default: all three).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backends: Vec<Backend>,
    /// `render` only: write the speed-against-error curves as an SVG plot.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// `render` only: replace the generated summary block of this Markdown file (the README).
    #[arg(long)]
    pub readme: Option<PathBuf>,
    /// `render`, `sensor`, `column`, `parity` and `images`: only the scenes whose file name
    /// contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// `parity`, `sensor`, `column` and `images`: keep the renders (and `parity`'s `poser compare` reports) here
    /// (default: a temporary folder, removed afterwards).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// `mesh` only: triangles of the generated site (default 5 000 000; `--quick`: 500 000).
    #[arg(long)]
    pub triangles: Option<u64>,
    /// `mesh` only: side of its square texture, texels (default 8192; `--quick`: 2048).
    #[arg(long)]
    pub texture: Option<u32>,
    /// `mesh` only: keep the generated site, its scene and the render here (default: a
    /// temporary folder, removed afterwards).
    #[arg(long)]
    pub keep: Option<PathBuf>,
    /// `mesh` only: write the site alone (`model.obj`, `model.mtl`, `model.jpg`) into this
    /// folder and stop, no bench; sizes from `--triangles` and `--texture`, by default the
    /// shipped site's (32 000 triangles, 2048²): `poser bench mesh --site
    /// scenarios/sites/assets/textured_bommie` rewrites it.
    #[arg(long)]
    pub site: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (what, json, quick, backends, plot) = (
        args.what.as_str(),
        args.json.clone(),
        args.quick,
        args.backends.clone(),
        args.plot.clone(),
    );
    if what != "render" && (plot.is_some() || args.readme.is_some()) {
        return Err(CliError::Usage(
            "--plot and --readme apply to `poser bench render` only".into(),
        ));
    }
    if !matches!(what, "render" | "parity") && !backends.is_empty() {
        return Err(CliError::Usage(
            "--backends applies to `poser bench render` and `poser bench parity` only".into(),
        ));
    }
    if !matches!(what, "render" | "sensor" | "column" | "parity" | "images") && args.only.is_some()
    {
        return Err(CliError::Usage(
            "--only applies to `poser bench render`, `sensor`, `column`, `parity` and `images` only"
                .into(),
        ));
    }
    if !matches!(what, "parity" | "sensor" | "column" | "images") && args.out.is_some() {
        return Err(CliError::Usage(
            "--out applies to `poser bench parity`, `sensor`, `column` and `images` only".into(),
        ));
    }
    if what != "mesh"
        && (args.triangles.is_some()
            || args.texture.is_some()
            || args.keep.is_some()
            || args.site.is_some())
    {
        return Err(CliError::Usage(
            "--triangles, --texture, --keep and --site apply to `poser bench mesh` only".into(),
        ));
    }
    match what {
        "mesh" if args.site.is_some() => site_only(args),
        "mesh" => {
            if cfg!(debug_assertions) {
                eprintln!(
                    "warning: this is a debug build; speeds are not representative (use --release)"
                );
            }
            let mut opts = crate::bench::mesh::Options::new(quick);
            opts.triangles = args.triangles.unwrap_or(opts.triangles);
            opts.texture = args.texture.unwrap_or(opts.texture);
            opts.keep = args.keep.clone();
            let report = crate::bench::mesh::run(&opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::mesh::table(&report));
            write_json(json.as_deref(), &report)
        }
        "projection" => {
            if cfg!(debug_assertions) {
                eprintln!(
                    "warning: this is a debug build; speeds are not representative (use --release)"
                );
            }
            let rows = crate::bench::projection::run(quick);
            println!(
                "batch solvers: {} lanes, {} build\n",
                crate::optics::port::LANES,
                crate::optics::port::Simd::detect().name()
            );
            print!("{}", crate::bench::projection::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        "render" => {
            if cfg!(debug_assertions) {
                eprintln!(
                    "warning: this is a debug build; speeds are not representative (use --release)"
                );
            }
            let opts = crate::bench::render::BenchOptions {
                quick,
                backends,
                only: args.only.clone(),
                json,
                plot,
                readme: args.readme.clone(),
            };
            let root = crate::backend::python::repo_root();
            crate::bench::render::run(&root, &opts)
                .map(|_| ())
                .map_err(CliError::Failed)
        }
        "evaluate" => {
            let lessons = crate::backend::python::repo_root().join("scenarios/lessons");
            let rows = crate::bench::evaluate::run(&lessons, quick).map_err(CliError::Failed)?;
            print!("{}", crate::bench::evaluate::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        "parity" => {
            let backends = if backends.is_empty() {
                Backend::ALL.to_vec()
            } else {
                backends
            };
            let (_tmp, out) = out_dir(args.out.as_ref())?;
            let root = crate::backend::python::repo_root();
            let rows =
                crate::bench::parity::run(&root, &backends, quick, args.only.as_deref(), &out)
                    .map_err(CliError::Failed)?;
            print!("{}", crate::bench::parity::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        "sensor" => {
            let (_tmp, out) = out_dir(args.out.as_ref())?;
            let poser = std::env::current_exe().map_err(|e| CliError::Failed(e.to_string()))?;
            let opts = crate::bench::sensor::Options {
                scale: if quick { 0.25 } else { 1.0 },
                pilots: [2, 8],
                only: args.only.clone(),
                poser,
                out,
            };
            let root = crate::backend::python::repo_root();
            let rows = crate::bench::sensor::run(&root, &opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::sensor::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        "column" => {
            let (_tmp, out) = out_dir(args.out.as_ref())?;
            let poser = std::env::current_exe().map_err(|e| CliError::Failed(e.to_string()))?;
            let mut opts = crate::bench::column::Options::new(quick, poser, out);
            opts.only = args.only.clone();
            let root = crate::backend::python::repo_root();
            let rows = crate::bench::column::run(&root, &opts).map_err(CliError::Failed)?;
            print!("{}", crate::bench::column::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        "images" => {
            let (_tmp, out) = out_dir(args.out.as_ref())?;
            let root = crate::backend::python::repo_root();
            let rows = crate::bench::images::run(&root, quick, args.only.as_deref(), &out)
                .map_err(CliError::Failed)?;
            print!("{}", crate::bench::images::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        other => Err(CliError::Usage(format!(
            "bench `{other}`: expected `projection`, `render`, `sensor`, `column`, `evaluate`, \
             `parity`, `images` or `mesh`"
        ))),
    }
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
fn site_only(args: &Args) -> Result<(), CliError> {
    use crate::geometry::bommie;
    if args.keep.is_some() || args.json.is_some() || args.quick {
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
