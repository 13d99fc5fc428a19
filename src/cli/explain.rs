//! `poser explain`: the resolved model's key numbers for a person.
use super::{CliError, SceneArgs};

pub fn run(_scene: &SceneArgs, _json: bool) -> Result<(), CliError> {
    Err(CliError::Failed("explain: not implemented yet".into()))
}
