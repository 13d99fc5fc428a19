//! `poser compile`: write a scene for Mitsuba 3 (XML) or Blender (bpy script).
use super::{BackendArg, CliError, SceneArgs, load_model};
use std::path::Path;

pub fn run(scene: &SceneArgs, backend: BackendArg, out: &Path) -> Result<(), CliError> {
    let model = load_model(scene)?;
    match backend {
        BackendArg::Native => Err(CliError::Usage(
            "the native backend renders directly; use `poser render` (compile targets: mitsuba, blender)".into(),
        )),
        BackendArg::Mitsuba => crate::backend::mitsuba::compile(&model, out).map_err(CliError::Failed),
        BackendArg::Blender => crate::backend::blender::compile(&model, out).map_err(CliError::Failed),
    }
}
