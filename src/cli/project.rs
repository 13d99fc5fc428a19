//! `poser project`: project CSV points through the camera and port.
use super::{CliError, FrameArg, SceneArgs};
use std::path::Path;

pub fn run(
    _scene: &SceneArgs,
    _points: &Path,
    _camera: Option<&str>,
    _frame: FrameArg,
    _pose: usize,
    _channel: &str,
    _output: Option<&Path>,
) -> Result<(), CliError> {
    Err(CliError::Failed("project: not implemented yet".into()))
}
