//! `poser sensor`: the camera's sensor stage on one linear EXR ([`crate::sensor`]), and the
//! hook `poser render` calls after rendering when the scene has a `[sensor]` (or `--sensor`).
use super::{CliError, SceneArgs, load_model};
use crate::model::SensorFormat;
use std::path::Path;
use std::path::PathBuf;

/// After `poser render`'s camera step ([`crate::pipeline`]): a summary line, and one warning
/// line when the render noise of images exceeds the sensor's (naming the image when there is
/// one).
pub fn report(done: &[crate::sensor::files::Done], out: &Path) {
    let noisy: Vec<&crate::sensor::files::Done> =
        done.iter().filter(|d| d.warning.is_some()).collect();
    match noisy.as_slice() {
        [] => {}
        [one] => eprintln!("warning: {}", one.warning.as_deref().unwrap_or_default()),
        many => {
            let worst = many
                .iter()
                .filter_map(|d| d.sidecar.render_noise.as_ref())
                .fold((0.0f64, 0u64), |(r, n), x| {
                    (
                        r.max(x.ratio_median.max(x.ratio_rms)),
                        n.max(x.samples_needed.unwrap_or(0)),
                    )
                });
            eprintln!(
                "warning: render noise exceeds the sensor's noise in {} of {} images (ratio up \
                 to {:.2}×; each image's numbers are in its .sensor.json); raise \
                 render.samples to about {}, or set render.noise = \"sensor\" (native)",
                many.len(),
                done.len(),
                worst.0,
                worst.1
            );
        }
    }
    let worst = done
        .iter()
        .filter_map(|d| d.sidecar.render_noise.as_ref().map(|r| r.ratio_rms))
        .fold(None, |m: Option<f64>, r| Some(m.map_or(r, |m| m.max(r))));
    eprintln!(
        "sensor: {} camera image(s) in {}{}",
        done.len(),
        out.join("camera").display(),
        worst
            .map(|r| format!("; render/sensor noise (RMS ratio) up to {r:.2}×"))
            .unwrap_or_default()
    );
}

/// The arguments of `poser sensor`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The linear EXR rendered from this scene.
    pub input: PathBuf,
    /// The camera image to write (`.jpg`/`.jpeg` or `.png`); the sidecar
    /// `<stem>.sensor.json` goes beside it.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Rig pose index of the image (seeds its noise).
    #[arg(long, default_value_t = 0)]
    pub pose: usize,
    /// Camera of the rig (default: the first).
    #[arg(long)]
    pub camera: Option<String>,
    /// Per-pixel variance of the render (`<image>.variance.exr`) for the noise report.
    #[arg(long)]
    pub variance: Option<PathBuf>,
    /// Samples per pixel of the render (for the noise report's hint).
    #[arg(long, value_parser = super::common::parse_samples)]
    pub samples: Option<u32>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, input, out, pose, camera, variance, samples) = (
        &args.scene,
        &args.input,
        &args.out,
        args.pose,
        args.camera.as_deref(),
        args.variance.as_deref(),
        args.samples,
    );
    let model = load_model(scene)?;
    let mut sensor = model.sensor.clone().unwrap_or_default();
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    sensor.format = match ext.as_deref() {
        Some("png") => SensorFormat::Png,
        Some("jpg" | "jpeg") => match sensor.format {
            SensorFormat::Jpeg(q) => SensorFormat::Jpeg(q),
            SensorFormat::Png => SensorFormat::Jpeg(95),
        },
        _ => {
            return Err(CliError::Usage(format!(
                "-o {}: expected a .jpg, .jpeg or .png file name",
                out.display()
            )));
        }
    };
    let c = match camera {
        None => 0,
        Some(name) => model
            .cameras
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| {
                CliError::Usage(format!(
                    "--camera {name}: the rig has {}",
                    model
                        .cameras
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?,
    };
    let cam = model
        .cameras
        .get(c)
        .ok_or_else(|| CliError::Failed("the scene has no camera".into()))?;
    if pose >= model.poses.len().max(1) {
        return Err(CliError::Usage(format!(
            "--pose {pose}: the network has {} poses",
            model.poses.len()
        )));
    }
    let img = crate::image::read_exr(input)?;
    let var = variance.map(crate::image::read_exr).transpose()?;
    let seed = crate::sensor::image_seed(model.render.seed, pose, c);
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    // The file is written as `<stem>.jpg` (or `.png`); honour a `.jpeg` name too.
    let done = crate::sensor::files::process(
        &sensor,
        &img,
        input,
        var.as_ref(),
        samples,
        cam,
        seed,
        dir,
        &stem,
    )?;
    if done.image != *out {
        std::fs::rename(&done.image, out)
            .map_err(|e| CliError::Failed(format!("{}: {e}", out.display())))?;
    }
    if let Some(w) = &done.warning {
        eprintln!("warning: {w}");
    }
    eprintln!(
        "wrote {} (shutter {:.3} ms, f/{}, ISO {}, {:.2} % clipped)",
        out.display(),
        done.sidecar.exposure.shutter * 1e3,
        done.sidecar.exposure.f_number,
        done.sidecar.exposure.iso,
        100.0 * done.sidecar.clipped_fraction
    );
    Ok(())
}
