//! `poser explain`: prints [`crate::explain::explain`], the resolved model's key numbers for a
//! person (`--json`: the whole resolved model).
use super::{CliError, SceneArgs};

/// The arguments of `poser explain`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Print the whole resolved model as JSON instead.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, json) = (&args.scene, args.json);
    let model = super::load_model(scene)?;
    if json {
        let s =
            serde_json::to_string_pretty(&model).map_err(|e| CliError::Failed(e.to_string()))?;
        println!("{s}");
    } else {
        print!("{}", crate::explain::explain(&model));
    }
    Ok(())
}
