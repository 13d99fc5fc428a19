//! `poser validate`: check scenes, print every diagnostic.
use super::CliError;
use std::path::PathBuf;

pub fn run(_scenes: &[PathBuf], _sets: &[String], _deny_warnings: bool) -> Result<(), CliError> {
    Err(CliError::Failed("validate: not implemented yet".into()))
}
