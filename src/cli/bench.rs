//! `poser bench`: speed-against-error reports (projection solvers; render backends).
use super::CliError;
use std::path::Path;

pub fn run(what: &str, _json: Option<&Path>, _quick: bool) -> Result<(), CliError> {
    Err(CliError::Usage(format!(
        "bench `{what}`: not implemented yet"
    )))
}
