//! `poser plan`: survey plan and achieved coverage.
use super::{CliError, SceneArgs};
use std::path::Path;

pub fn run(_scene: &SceneArgs, _json: bool, _coverage: Option<&Path>) -> Result<(), CliError> {
    Err(CliError::Failed("plan: not implemented yet".into()))
}
