//! `poser compile`: write a scene for Mitsuba 3 (XML) or Blender (bpy script).
use super::{CliError, SceneArgs, load_model};
use crate::backend::Backend;
use std::path::PathBuf;

/// The arguments of `poser compile`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, value_enum)]
    pub backend: Backend,
    #[arg(short, long)]
    pub out: PathBuf,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backend, out) = (&args.scene, args.backend, &args.out);
    let model = load_model(scene)?;
    if !backend.capabilities().compiles {
        return Err(CliError::Usage(
            "the native backend renders directly; use `poser render` (compile targets: mitsuba, blender)".into(),
        ));
    }
    backend.compile(&model, out).map_err(CliError::Failed)
}
