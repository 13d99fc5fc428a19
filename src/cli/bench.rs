//! `poser bench`: speed-against-error reports (projection solvers; render backends).
use super::CliError;
use std::path::PathBuf;

pub fn run(
    what: &str,
    json: Option<PathBuf>,
    quick: bool,
    backends: Vec<crate::backend::Backend>,
    plot: Option<PathBuf>,
) -> Result<(), CliError> {
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
