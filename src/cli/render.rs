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
    #[arg(long, value_parser = super::common::parse_samples)]
    pub samples: Option<u32>,
    /// Render only these poses, counted from 0: indices and ranges (`0,3,5`, `0-9`).
    #[arg(long, value_parser = super::common::parse_poses)]
    pub poses: Option<super::common::PoseList>,
    /// Preview at a fraction of the cameras' resolution (e.g. `0.25`): same field of view,
    /// lens and port; the ground truth is written for the scaled images.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Render only this rectangle of every image, `X,Y,W,H` in pixels of the image as
    /// rendered (after `--scale`), from the top-left corner; the same pixels as in the whole
    /// image, in every backend. The ground truth stays in the whole image's pixels.
    #[arg(long, value_name = "X,Y,W,H", value_parser = super::common::parse_crop)]
    pub crop: Option<crate::model::Crop>,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Run the camera's sensor stage (docs/sensor.md) with the default sensor when the
    /// scene has no `[sensor]`; writes `OUT/camera/<image>.jpg` and `.sensor.json`.
    #[arg(long)]
    pub sensor: bool,
    /// Render only shard `I` of `N` (`--shard 0/4` … `3/4`): the poses whose index modulo N
    /// is I, after `--poses`. The shards together write exactly the files of one whole run.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Native: skip the images that an earlier, interrupted run into the same folder finished
    /// (`OUT/render-manifest.json`, same model and samples, files unchanged).
    #[arg(long)]
    pub resume: bool,
    /// Do not write `OUT/truth/` (a job that writes it once, such as `poser slurm`'s merge
    /// job, does).
    #[arg(long)]
    pub skip_truth: bool,
}

/// `I/N` with `I < N`.
fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let err = || format!("`{s}`: expected I/N with 0 ≤ I < N, e.g. 0/4");
    let (i, n) = s.split_once('/').ok_or_else(err)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| err())?,
        n.trim().parse().map_err(|_| err())?,
    );
    if n == 0 || i >= n {
        return Err(err());
    }
    Ok((i, n))
}

/// The poses of shard `i` of `n` among `poses` (all `count` when `None`).
pub fn shard_poses(poses: Option<Vec<usize>>, count: usize, (i, n): (usize, usize)) -> Vec<usize> {
    poses
        .unwrap_or_else(|| (0..count).collect())
        .into_iter()
        .filter(|p| p % n == i)
        .collect()
}

#[allow(clippy::too_many_arguments)]
pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backend, out, samples, poses, scale, quiet, sensor) = (
        &args.scene,
        args.backend,
        &args.out,
        args.samples,
        args.poses.clone().map(|p| p.0),
        args.scale,
        args.quiet,
        args.sensor,
    );
    let mut model = super::common::apply_scale(load_model(scene)?, scale)?;
    super::common::apply_crop(&mut model, args.crop)?;
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
    if model.render.denoise_radius.is_some() && backend != Backend::Native {
        eprintln!(
            "warning: render.denoise is the native renderer's; {}'s images are not filtered",
            backend.name()
        );
    }
    if model.render.noise.is_some() && backend != Backend::Native {
        eprintln!(
            "warning: render.noise is the native renderer's; {} takes render.samples per pixel",
            backend.name()
        );
    }
    if args.resume && backend != Backend::Native {
        return Err(CliError::Usage(format!(
            "--resume: only the native backend records finished images; {} renders every image again",
            backend.name()
        )));
    }
    let poses = match args.shard {
        Some(sh) => {
            let list = shard_poses(poses, model.poses.len(), sh);
            if list.is_empty() {
                eprintln!("shard {}/{}: no pose to render", sh.0, sh.1);
                if !args.skip_truth {
                    crate::truth::write(&model, &out.join("truth")).map_err(CliError::Failed)?;
                }
                return Ok(());
            }
            Some(list)
        }
        None => poses,
    };
    let opts = RenderOptions {
        samples,
        poses,
        progress: !quiet,
        resume: args.resume,
    };
    // Render, the ground truth beside the images (the same for every backend), the camera.
    let steps = crate::pipeline::Steps {
        truth: !args.skip_truth,
        camera: true,
    };
    let done =
        crate::pipeline::run(&model, backend, out, &opts, steps).map_err(CliError::Failed)?;
    eprintln!(
        "rendered {} image(s) into {} in {:.2} s",
        done.report.images.len(),
        out.display(),
        done.report.seconds
    );
    if model.sensor.is_some() {
        super::sensor::report(&done.developed, out);
    }
    Ok(())
}
