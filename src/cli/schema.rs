//! `poser schema`: write (or check) the JSON Schema and the generated format reference.
use super::CliError;
use std::path::Path;

pub fn run(_out: &Path, _docs: &Path, _check: bool) -> Result<(), CliError> {
    Err(CliError::Failed("schema: not implemented yet".into()))
}
