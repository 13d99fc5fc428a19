//! The sensor stage on files: reads a rendered linear EXR (and the native renderer's
//! `<image>.variance.exr` when present), writes the camera's file and a JSON sidecar saying
//! everything that was applied.
//!
//! | file | content |
//! |---|---|
//! | `OUT/camera/<image>.jpg` or `.png` | the camera's 8-bit image ([`super::develop`]) with its EXIF block ([`super::exif`]) |
//! | `OUT/camera/<image>.sensor.json` | [`Sidecar`]: sensor, exposure, white balance, seed, clipping, render noise |
//!
//! The camera images sit in their own folder so that photogrammetry software pointed at it
//! sees only them (the backends' sRGB previews `OUT/<image>.png` stay where they were).

use super::{Exposure, Linear, RenderNoise};
use crate::image::read_exr;
use crate::model::{Camera, Model, Sensor};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Everything the sensor stage did to one image (the `.sensor.json` sidecar).
#[derive(Debug, Clone, Serialize)]
pub struct Sidecar {
    /// Always `"poser sensor stage 1"`.
    pub format: &'static str,
    pub image: String,
    /// The linear input the camera image was made from.
    pub input: String,
    pub width: u32,
    pub height: u32,
    /// Pixel convention of the image (poser's and COLMAP's).
    pub pixel_convention: &'static str,
    pub sensor: Sensor,
    pub exposure: Exposure,
    /// Seed of this image's shot and read noise.
    pub seed: u64,
    /// Share of pixels with a channel at full well or at the ADC maximum.
    pub clipped_fraction: f64,
    /// Render noise against the sensor's own noise (native renderer, ≥ 2 samples per pixel).
    pub render_noise: Option<RenderNoise>,
    /// Why `render_noise` is missing, or the warning it raised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub render_noise_note: Option<String>,
}

/// What came out of one image.
#[derive(Debug, Clone)]
pub struct Done {
    pub image: PathBuf,
    pub sidecar: Sidecar,
    /// A one-line warning when the render noise exceeds the sensor noise.
    pub warning: Option<String>,
}

/// Run the sensor on one linear image and write `<dir>/<stem>.<ext>` and
/// `<dir>/<stem>.sensor.json`. `camera` took the image (at any resolution: its pixel pitch and
/// EXIF tags are taken at the image's size, [`at_image_size`]); `variance` is the render's
/// per-pixel variance of the mean, `samples` its samples per pixel.
#[allow(clippy::too_many_arguments)]
pub fn process(
    sensor: &Sensor,
    img: &Linear,
    input: &Path,
    variance: Option<&Linear>,
    samples: Option<u32>,
    camera: &Camera,
    seed: u64,
    dir: &Path,
    stem: &str,
) -> Result<Done, String> {
    let cam = at_image_size(camera, img.width);
    let exposure = super::expose(sensor, img, cam.pixel_pitch);
    let raw = super::capture(sensor, &exposure, img, seed);
    let rgb8 = super::develop(sensor, &exposure, &raw);
    let tags = super::exif::CameraTags::of(&cam, img.width, img.height);
    let exif = super::exif::block(&tags, sensor, &exposure)?;
    let bytes = super::encode(sensor, img.width, img.height, &rgb8, &exif)?;
    let out = dir.join(format!("{stem}.{}", super::extension(sensor)));
    let (render_noise, mut note) = match (variance, samples) {
        (None, _) => (
            None,
            Some("no per-pixel variance: only the native renderer writes it".to_string()),
        ),
        (Some(_), Some(n)) if n < 2 => (
            None,
            Some("one sample per pixel: the render noise cannot be estimated".to_string()),
        ),
        (Some(v), _) if v.width != img.width || v.height != img.height => (
            None,
            Some("the variance image does not match the image size".to_string()),
        ),
        (Some(v), n) => (super::render_noise(sensor, &exposure, img, &v.rgb, n), None),
    };
    let warning = render_noise.as_ref().and_then(|r| {
        (r.ratio_median > 1.0 || r.ratio_rms > 1.0).then(|| {
            format!(
                "render noise exceeds the sensor's noise in {stem}: median {:.2}× (95th \
                 percentile {:.2}×, RMS {:.2}×), {:.1} % of the signal; raise render.samples{}",
                r.ratio_median,
                r.ratio_p95,
                r.ratio_rms,
                100.0 * r.relative_median,
                r.samples_needed
                    .map(|n| format!(" to about {n}"))
                    .unwrap_or_default()
            ) + ", or let the native renderer sample each pixel to it (render.noise = \"sensor\")"
        })
    });
    if warning.is_some() {
        note = warning.clone();
    }
    let sidecar = Sidecar {
        format: "poser sensor stage 1",
        image: out
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default(),
        input: input.display().to_string(),
        width: img.width,
        height: img.height,
        pixel_convention: "pixel (i, j) covers [i, i+1]×[j, j+1]; centres at +0.5 (COLMAP)",
        sensor: sensor.clone(),
        exposure,
        seed,
        clipped_fraction: raw.clipped_fraction,
        render_noise,
        render_noise_note: note,
    };
    let mut json = serde_json::to_string_pretty(&sidecar).map_err(|e| e.to_string())?;
    json.push('\n');
    crate::io::write_atomic(&out, &bytes).map_err(|e| format!("{}: {e}", out.display()))?;
    let side = dir.join(format!("{stem}.sensor.json"));
    crate::io::write_atomic(&side, json.as_bytes())
        .map_err(|e| format!("{}: {e}", side.display()))?;
    Ok(Done {
        image: out,
        sidecar,
        warning,
    })
}

/// The sensor stage after `poser render`: every (pose, camera) image in `out`, written to
/// `out/camera/`. `samples`: the render's samples per pixel.
pub fn apply(
    model: &Model,
    sensor: &Sensor,
    out: &Path,
    poses: &[usize],
    samples: u32,
) -> Result<Vec<Done>, String> {
    let dir = out.join("camera");
    let mut done = Vec::new();
    for &p in poses {
        for (c, cam) in model.cameras.iter().enumerate() {
            let name = model.image_name(p, c);
            // With the native renderer's illumination denoiser on, the camera sees the
            // denoised render (an explicit option of the scene; the sidecar names its input).
            let denoised = out.join(format!("{name}.denoised.exr"));
            let (exr, var_path) = if model.render.denoise_radius.is_some() && denoised.exists() {
                (denoised, out.join(format!("{name}.denoised.variance.exr")))
            } else {
                (
                    out.join(format!("{name}.exr")),
                    out.join(format!("{name}.variance.exr")),
                )
            };
            let img = read_exr(&exr)?;
            let variance = if var_path.exists() {
                Some(read_exr(&var_path)?)
            } else {
                None
            };
            let seed = super::image_seed(model.render.seed, p, c);
            done.push(process(
                sensor,
                &img,
                &exr,
                variance.as_ref(),
                Some(samples),
                cam,
                seed,
                &dir,
                &name,
            )?);
        }
    }
    Ok(done)
}

/// Pixel pitch of `cam` for an image `width` pixels wide (a `--scale` preview has larger
/// pixels on the same sensor), computed as [`crate::model::Camera::with_resolution_scale`]
/// does so that `poser sensor` and `poser render` agree to the bit.
pub fn pixel_pitch(cam: &Camera, width: u32) -> f64 {
    at_image_size(cam, width).pixel_pitch
}

/// `cam` resampled to an image `width` pixels wide: the same sensor and lens, the pixel pitch
/// and intrinsics of that pixel grid ([`Camera::with_resolution_scale`]; `cam` itself when the
/// width is its own).
pub fn at_image_size(cam: &Camera, width: u32) -> Camera {
    if width == cam.width || cam.width == 0 {
        cam.clone()
    } else {
        cam.with_resolution_scale(width as f64 / cam.width as f64)
    }
}
