//! `poser bench`: speed-against-error reports (projection solvers; render backends).
use super::CliError;
use crate::backend::Backend;
use std::path::PathBuf;

/// The arguments of `poser bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to benchmark: `projection`, `render` or `evaluate`.
    pub what: String,
    /// Write the report as JSON too.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Smaller, quicker run.
    #[arg(long)]
    pub quick: bool,
    /// `render` only: the backends to compare (default: all three).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backends: Vec<Backend>,
    /// `render` only: write the speed-against-error curves as an SVG plot.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (what, json, quick, backends, plot) = (
        args.what.as_str(),
        args.json.clone(),
        args.quick,
        args.backends.clone(),
        args.plot.clone(),
    );
    if what != "render" && (!backends.is_empty() || plot.is_some()) {
        return Err(CliError::Usage(
            "--backends and --plot apply to `poser bench render` only".into(),
        ));
    }
    match what {
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
                json,
                plot,
            };
            crate::bench::render::run(&opts)
                .map(|_| ())
                .map_err(CliError::Failed)
        }
        "evaluate" => {
            let lessons = crate::backend::python::repo_root().join("scenarios/lessons");
            let rows = crate::bench::evaluate::run(&lessons, quick).map_err(CliError::Failed)?;
            print!("{}", crate::bench::evaluate::table(&rows));
            write_json(json.as_deref(), &rows)
        }
        other => Err(CliError::Usage(format!(
            "bench `{other}`: expected `projection`, `render` or `evaluate`"
        ))),
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
