//! `poser dive`: dive profile, decompression, gas; Subsurface export.
use super::{CliError, SceneArgs};
use std::path::Path;

pub fn run(
    _scene: &SceneArgs,
    _out: Option<&Path>,
    _plot: Option<&Path>,
    _json: bool,
) -> Result<(), CliError> {
    Err(CliError::Failed("dive: not implemented yet".into()))
}
