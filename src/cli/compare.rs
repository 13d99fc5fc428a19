//! `poser compare`: render with several backends; report agreement with truth and each other.
use super::{CliError, SceneArgs, load_model};
use crate::backend::{Backend, RenderOptions};
use std::path::Path;

pub fn run(
    scene: &SceneArgs,
    backends: &[Backend],
    out: &Path,
    samples: Option<u32>,
    poses: Option<Vec<usize>>,
) -> Result<(), CliError> {
    let model = load_model(scene)?;
    let opts = RenderOptions {
        samples,
        poses,
        progress: true,
    };
    let report = crate::compare::run(&model, backends, out, &opts).map_err(CliError::Failed)?;
    print!("{}", report.to_markdown());
    eprintln!("report: {}", out.join("report.md").display());
    if report.backends.iter().all(|b| b.error.is_some()) {
        return Err(CliError::Failed("no backend rendered".into()));
    }
    Ok(())
}
