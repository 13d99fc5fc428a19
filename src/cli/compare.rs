//! `poser compare`: render with several backends; report agreement with truth and each other.
use super::{CliError, SceneArgs, load_model};
use crate::backend::{Backend, RenderOptions};
use std::path::PathBuf;

/// The arguments of `poser compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Backends to compare.
    #[arg(long, value_delimiter = ',', default_value = "native,mitsuba,blender")]
    pub backends: Vec<Backend>,
    #[arg(short, long)]
    pub out: PathBuf,
    /// Override samples per pixel.
    #[arg(long, value_parser = super::common::parse_samples)]
    pub samples: Option<u32>,
    /// Render only these pose indices (e.g. `0,3,5`).
    #[arg(long, value_delimiter = ',')]
    pub poses: Option<Vec<usize>>,
    /// Compare at a fraction of the cameras' resolution (e.g. `0.25`): same field of view, lens
    /// and port; the truth the targets are measured against is the scaled one.
    #[arg(long)]
    pub scale: Option<f64>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backends, out, samples, poses) = (
        &args.scene,
        &args.backends,
        &args.out,
        args.samples,
        args.poses.clone(),
    );
    let model = super::common::apply_scale(load_model(scene)?, args.scale)?;
    let opts = RenderOptions {
        samples,
        poses,
        progress: true,
        resume: false,
    };
    let report = crate::compare::run(&model, backends, out, &opts).map_err(CliError::Failed)?;
    print!("{}", report.to_markdown());
    eprintln!("report: {}", out.join("report.md").display());
    // Every requested backend must render: one that fails makes the command fail (exit 1),
    // after the report (which shows it as failed) is written.
    let failed: Vec<String> = report
        .backends
        .iter()
        .filter_map(|b| {
            b.error.as_ref().map(|e| {
                format!(
                    "backend `{}` failed: {}",
                    b.backend,
                    e.lines().next().unwrap_or("")
                )
            })
        })
        .collect();
    if !failed.is_empty() {
        return Err(CliError::Failed(failed.join("\n")));
    }
    Ok(())
}
