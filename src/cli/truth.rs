//! `poser truth`: write the exact ground truth of every image.
use super::{CliError, SceneArgs, load_model};
use std::path::PathBuf;

/// The arguments of `poser truth`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(short, long)]
    pub out: PathBuf,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, out) = (&args.scene, &args.out);
    let model = load_model(scene)?;
    crate::truth::write(&model, out).map_err(CliError::Failed)?;
    eprintln!(
        "wrote ground truth of {} image(s) into {}",
        model.poses.len() * model.cameras.len(),
        out.display()
    );
    Ok(())
}
