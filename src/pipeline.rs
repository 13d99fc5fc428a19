//! The image pipeline: render → ground truth → camera, the sequence every command that makes
//! images runs, in one place. `poser render`, `poser evaluate --mode images`, `poser bench
//! images` and the lessons call [`run`]; what differs between them is only which steps they
//! want ([`Steps`]).
//!
//! | step | what it writes | when |
//! |---|---|---|
//! | render | `OUT/<image>.exr` (+ `.png`, `.variance.exr`, …), through [`Backend::render`] | always |
//! | truth | `OUT/truth/` ([`crate::truth::write`]), the same for every backend | [`Steps::truth`] |
//! | camera | `OUT/camera/<image>.jpg` and `.sensor.json` ([`crate::sensor::files::apply`]) | [`Steps::camera`] and the model has a `[sensor]` |
//!
//! A bare render (`poser compare`, `poser bench render`, `poser import --verify`) calls
//! [`Backend::render`] alone.
//!
//! The camera sees the images of the poses rendered ([`RenderOptions::pose_indices`]) at the
//! samples they were rendered with (the override, else `render.samples`), so its
//! render-noise figures are the render's.

use crate::backend::{Backend, RenderOptions, RenderReport};
use crate::model::Model;
use crate::sensor::files::Done;
use std::path::Path;

/// Which steps after the render to run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Steps {
    /// Write the ground truth into `OUT/truth/`.
    pub truth: bool,
    /// Pass the images through the model's `[sensor]` (nothing when it has none).
    pub camera: bool,
}

/// What a run produced.
#[derive(Debug, Clone, Default)]
pub struct Output {
    /// The render's images and time.
    pub report: RenderReport,
    /// The camera's images, one per rendered (pose, camera), when the camera step ran.
    pub developed: Vec<Done>,
}

/// Render `model` with `backend` into `out` and run `steps` after it.
pub fn run(
    model: &Model,
    backend: Backend,
    out: &Path,
    opts: &RenderOptions,
    steps: Steps,
) -> Result<Output, String> {
    if steps.camera && model.sensor.is_some() && model.render.crop.is_some() {
        return Err(
            "the camera step (`[sensor]`, `--sensor`) develops whole images, and the render is \
             cropped: drop `--crop`, or the sensor"
                .into(),
        );
    }
    let report = backend.render(model, out, opts)?;
    if steps.truth {
        crate::truth::write(model, &out.join("truth"))?;
    }
    let developed = match (&model.sensor, steps.camera) {
        (Some(sensor), true) => {
            let spp = opts.samples.unwrap_or(model.render.samples).max(1);
            let poses = opts.pose_indices(model.poses.len());
            crate::sensor::files::apply(model, sensor, out, &poses, spp)?
        }
        _ => Vec::new(),
    };
    Ok(Output { report, developed })
}
