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
    /// Render only these poses, counted from 0: indices and ranges (`0,3,5`, `0-9`).
    #[arg(long, value_parser = super::common::parse_poses)]
    pub poses: Option<super::common::PoseList>,
    /// Compare at a fraction of the cameras' resolution (e.g. `0.25`): same field of view, lens
    /// and port; the truth the targets are measured against is the scaled one.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Render only a rectangle of each image: `X,Y,W,H` in pixels of the image as rendered
    /// (after `--scale`), or `targets`: the first image (of `--poses`) that shows a measurable
    /// disk or checkerboard corner, alone, cropped to those nearest its centre (at most 256 px
    /// on a side), to measure targets at full size for a small share of the cost.
    #[arg(long, value_name = "X,Y,W,H|targets", value_parser = parse_crop_arg)]
    pub crop: Option<CropArg>,
}

/// `--crop`: a rectangle, or `targets`.
#[derive(Debug, Clone, Copy)]
pub enum CropArg {
    Rect(crate::model::Crop),
    Targets,
}

fn parse_crop_arg(s: &str) -> Result<CropArg, String> {
    if s.trim() == "targets" {
        Ok(CropArg::Targets)
    } else {
        super::common::parse_crop(s).map(CropArg::Rect)
    }
}

/// The largest side of `--crop targets`' rectangle, px.
const TARGET_CROP_SIDE: u32 = 256;

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, backends, out, samples, mut poses) = (
        &args.scene,
        &args.backends,
        &args.out,
        args.samples,
        args.poses.clone().map(|p| p.0),
    );
    let mut model = super::common::apply_scale(load_model(scene)?, args.scale)?;
    let crop = match args.crop {
        None => None,
        Some(CropArg::Rect(c)) => Some(c),
        Some(CropArg::Targets) => {
            // The first image (of the poses asked for) where a disk or a checkerboard corner
            // can be measured; only that pose is rendered.
            let candidates = poses
                .clone()
                .unwrap_or_else(|| (0..model.poses.len()).collect());
            let mut found = None;
            let geometry = crate::geometry::Bvh::of_model(&model).map_err(CliError::Failed)?;
            for &p in &candidates {
                if let Some(c) = crate::compare::target_crop(
                    &model,
                    &geometry,
                    p,
                    TARGET_CROP_SIDE,
                    crate::compare::Points::All,
                )
                .map_err(CliError::Failed)?
                {
                    found = Some((p, c));
                    break;
                }
            }
            let (p, c) = found.ok_or_else(|| {
                CliError::Usage(
                    "--crop targets: no image of camera 0 shows a disk target or a checkerboard corner that can be measured"
                        .into(),
                )
            })?;
            eprintln!(
                "--crop targets: image {} (pose {p}), {},{},{},{}",
                model.image_name(p, 0),
                c.x,
                c.y,
                c.width,
                c.height
            );
            poses = Some(vec![p]);
            Some(c)
        }
    };
    super::common::apply_crop(&mut model, crop)?;
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
