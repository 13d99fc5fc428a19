//! `poser bench`: speed-against-error reports (projection solvers; render backends).
use super::CliError;
use std::path::Path;

pub fn run(what: &str, json: Option<&Path>, quick: bool) -> Result<(), CliError> {
    match what {
        "projection" => {
            if cfg!(debug_assertions) {
                eprintln!(
                    "warning: this is a debug build; speeds are not representative (use --release)"
                );
            }
            let rows = crate::optics::bench::run(quick);
            print!("{}", crate::optics::bench::table(&rows));
            if let Some(path) = json {
                let text = serde_json::to_string_pretty(&rows)
                    .map_err(|e| CliError::Failed(e.to_string()))?;
                crate::io::write_atomic(path, text.as_bytes())
                    .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
            }
            Ok(())
        }
        "render" => crate::render::bench::run(json, quick).map_err(CliError::Failed),
        other => Err(CliError::Usage(format!(
            "bench `{other}`: expected `projection` or `render`"
        ))),
    }
}
