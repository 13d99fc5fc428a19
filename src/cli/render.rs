//! `poser render`: render every pose with the chosen backend (native by default).
use super::{CliError, SceneArgs, load_model};
use crate::backend::{Backend, RenderOptions};
use std::path::PathBuf;

/// The arguments of `poser render`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, value_enum, default_value = "native")]
    pub backend: Backend,
    #[arg(short, long)]
    pub out: PathBuf,
    /// Override samples per pixel.
    #[arg(long)]
    pub samples: Option<u32>,
    /// Render only these pose indices (e.g. `0,3,5`).
    #[arg(long, value_delimiter = ',')]
    pub poses: Option<Vec<usize>>,
    /// Preview at a fraction of the cameras' resolution (e.g. `0.25`): same field of view,
    /// lens and port; the ground truth is written for the scaled images.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Run the camera's sensor stage (docs/sensor.md) with the default sensor when the
    /// scene has no `[sensor]`; writes `OUT/camera/<image>.jpg` and `.sensor.json`.
    #[arg(long)]
    pub sensor: bool,
}

#[allow(clippy::too_many_arguments)]
pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backend, out, samples, poses, scale, quiet, sensor) = (
        &args.scene,
        args.backend,
        &args.out,
        args.samples,
        args.poses.clone(),
        args.scale,
        args.quiet,
        args.sensor,
    );
    let mut model = load_model(scene)?;
    if let Some(s) = scale {
        if !(s.is_finite() && s > 0.0 && s <= 4.0) {
            return Err(CliError::Usage(format!(
                "--scale {s}: expected a factor in (0, 4], e.g. 0.25 for a quarter-resolution preview"
            )));
        }
        model = model.with_resolution_scale(s);
    }
    if let Some(p) = poses
        .as_ref()
        .and_then(|p| p.iter().find(|&&i| i >= model.poses.len()))
    {
        return Err(CliError::Usage(format!(
            "--poses: index {p} is out of range (the network has {} poses)",
            model.poses.len()
        )));
    }
    if sensor && model.sensor.is_none() {
        model.sensor = Some(crate::model::Sensor::default());
    }
    let opts = RenderOptions {
        samples,
        poses,
        progress: !quiet,
    };
    let report = backend
        .render(&model, out, &opts)
        .map_err(CliError::Failed)?;
    // The ground truth beside the images, the same for every backend.
    crate::truth::write(&model, &out.join("truth")).map_err(CliError::Failed)?;
    eprintln!(
        "rendered {} image(s) into {} in {:.2} s",
        report.images.len(),
        out.display(),
        report.seconds
    );
    if let Some(s) = &model.sensor {
        let spp = opts.samples.unwrap_or(model.render.samples).max(1);
        let list = opts.pose_indices(model.poses.len());
        super::sensor::after_render(&model, s, out, &list, spp)?;
    }
    Ok(())
}
