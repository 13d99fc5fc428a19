//! `poser truth`: write the exact ground truth of every image.
use super::{CliError, SceneArgs, load_model};
use std::path::Path;

pub fn run(scene: &SceneArgs, out: &Path) -> Result<(), CliError> {
    let model = load_model(scene)?;
    crate::truth::write(&model, out).map_err(CliError::Failed)?;
    eprintln!(
        "wrote ground truth of {} image(s) into {}",
        model.poses.len() * model.cameras.len(),
        out.display()
    );
    Ok(())
}
