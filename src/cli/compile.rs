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
    /// Compile at a fraction of the cameras' resolution (e.g. `0.25`), as `poser render
    /// --scale` previews: same field of view, lens and port; textures are baked for the
    /// coarser pixels, so the files are smaller and quicker to write and to load.
    #[arg(long)]
    pub scale: Option<f64>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backend, out) = (&args.scene, args.backend, &args.out);
    let model = super::common::apply_scale(load_model(scene)?, args.scale)?;
    if !backend.capabilities().compiles {
        return Err(CliError::Usage(
            "the native backend renders directly; use `poser render` (compile targets: mitsuba, blender)".into(),
        ));
    }
    backend.compile(&model, out).map_err(CliError::Failed)
}
