//! `poser truth`: write the exact ground truth of every image.
use super::{CliError, SceneArgs};
use std::path::Path;

pub fn run(_scene: &SceneArgs, _out: &Path) -> Result<(), CliError> {
    Err(CliError::Failed("truth: not implemented yet".into()))
}
