//! `poser compile`: write a scene for Mitsuba 3 (XML) or Blender (bpy script).
use super::{CliError, SceneArgs, load_model};
use crate::backend::Backend;
use std::path::Path;

pub fn run(scene: &SceneArgs, backend: Backend, out: &Path) -> Result<(), CliError> {
    let model = load_model(scene)?;
    if !backend.capabilities().compiles {
        return Err(CliError::Usage(
            "the native backend renders directly; use `poser render` (compile targets: mitsuba, blender)".into(),
        ));
    }
    backend.compile(&model, out).map_err(CliError::Failed)
}
