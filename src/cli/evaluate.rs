//! `poser evaluate`: process the simulated survey with COLMAP and measure what went wrong.
//!
//! | option | default | meaning |
//! |---|---|---|
//! | `--mode` | observations | `observations`: exact projections of tie points + noise, bundle-adjusted; `images`: COLMAP's full pipeline on rendered images |
//! | `--model` | opencv (observations), radial (images) | camera model COLMAP self-calibrates (the port is ignored, as practitioners do) |
//! | `--noise` | 0.3 px | Gaussian pixel noise on every observation (observations mode) |
//! | `--density` | 20 /m² | tie points per m² of surface (observations mode) |
//! | `--gcp [IDS]` | off | align on the targets' points (GCPs); with IDS (comma-separated target names) only those are control points and the other targets are check points; the default aligns on all points |
//! | `--check IDS` | – | with `--gcp`: these targets are check points, held out of the alignment |
//! | `--gcp-sigma [METRES]` | off (0.002 when given alone) | with `--gcp`: the control points enter the bundle adjustment as weighted constraints, each known to this σ per axis, as Metashape weights markers; no similarity after |
//! | `--strict` | off | a health warning (images dropped, focal length not determined or far from the nominal, camera model not fitting, outlier-driven RMS) is an error: exit status 1 after the report is written |
//! | `--rig` | off | observations mode: the rig is calibrated beforehand — intrinsics held at the in-water-equivalent values, the cameras' poses in the rig held at the truth; the bundle adjuster solves one pose per rig position (its baseline sets the scale) |
//! | `--images DIR` | render | images mode: use the images already rendered in DIR (any backend); without it the network is rendered into `OUT/images.partial/` and renamed to `OUT/images/` when complete (a run cut short resumes there) |
//! | `--samples`, `--scale` | scene's | images mode: the native render's samples and resolution scale |
//! | `--stock` | off | images mode: COLMAP as it ships, fed only the image files: the camera from their EXIF (`simple-radial`), default extraction, matching (exhaustive, sequential above [`crate::evaluate::EXHAUSTIVE_MAX_IMAGES`] images) and mapping, except the initial pair's triangulation angle ([`crate::evaluate::STOCK_INIT_ANGLE_DEG`]) |
use super::{CliError, SceneArgs, load_model};
use crate::backend::{Backend, RenderOptions};
use crate::evaluate::colmap::CameraModel;
use crate::evaluate::{self, Mode, Options};
use crate::progress::Progress;
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Arguments of `poser evaluate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory (report.json, report.md, errors.csv, deformation.png, profile.svg).
    #[arg(short, long)]
    pub out: PathBuf,
    #[arg(long, value_enum, default_value = "observations")]
    pub mode: Mode,
    /// Camera model COLMAP self-calibrates [default: opencv in observations mode, radial
    /// (one focal length) in images mode].
    #[arg(long, value_enum)]
    pub model: Option<CameraModel>,
    /// Pixel noise (σ, px) added to every observation (observations mode).
    #[arg(long, default_value_t = 0.3)]
    pub noise: f64,
    /// Tie points per m² of surface (observations mode).
    #[arg(long, default_value_t = 20.0)]
    pub density: f64,
    /// Align on the scene's targets as ground control points instead of on all points. With
    /// IDS (comma-separated target names, as in errors.csv), only those are control points and
    /// the other targets are check points.
    #[arg(long, value_name = "IDS", num_args = 0..=1, default_missing_value = "")]
    pub gcp: Option<String>,
    /// With --gcp: these targets (comma-separated) are check points, held out of the
    /// alignment; the others are control points unless --gcp names its own.
    #[arg(long, value_name = "IDS")]
    pub check: Option<String>,
    /// With --gcp: weight the control points in the bundle adjustment, each known to this
    /// accuracy (σ per axis, metres; 0.002 when the flag is given alone), instead of only
    /// aligning the result on them. Check points stay out of the adjustment.
    #[arg(long, value_name = "METRES", num_args = 0..=1, default_missing_value = "0.002")]
    pub gcp_sigma: Option<f64>,
    /// Exit with status 1 when a health warning is given (the report is still written).
    #[arg(long)]
    pub strict: bool,
    /// Let the bundle adjustment refine the principal point too.
    #[arg(long)]
    pub refine_principal_point: bool,
    /// Observations mode: treat the rig as calibrated beforehand (intrinsics held at their
    /// in-water-equivalent values, the cameras' poses in the rig held at the truth); the
    /// bundle adjustment solves one pose per rig position.
    #[arg(long)]
    pub rig: bool,
    /// Seed of the tie points, the noise and the perturbed start.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Initial camera and point positions are off by this fraction of the median viewing
    /// distance (σ per axis).
    #[arg(long, default_value_t = 0.02)]
    pub perturb_position: f64,
    /// Initial camera rotations are off by this angle (σ, degrees).
    #[arg(long, default_value_t = 1.0)]
    pub perturb_rotation: f64,
    /// Images mode: images already rendered into this directory (by any backend).
    #[arg(long)]
    pub images: Option<PathBuf>,
    /// Images mode: the backend that renders the images (when `--images` is not given).
    #[arg(long, default_value = "native")]
    pub backend: Backend,
    /// Images mode: samples per pixel of the render.
    #[arg(long, value_parser = super::common::parse_samples)]
    pub samples: Option<u32>,
    /// Images mode: render at this fraction of the cameras' resolution.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Images mode: run COLMAP as it ships, fed only the image files. The camera comes from
    /// their EXIF (COLMAP's `simple-radial`, self-calibrated throughout); extraction,
    /// matching (exhaustive; sequential above 40 images) and mapping keep COLMAP's defaults,
    /// except the initial pair's minimum triangulation angle (8° for COLMAP's 16°, which a
    /// survey's neighbours do not reach). What another user of COLMAP gets from poser's
    /// images.
    #[arg(long)]
    pub stock: bool,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let mut model = load_model(&args.scene)?;
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        return Err(CliError::Usage(format!(
            "--noise {}: expected a pixel σ ≥ 0, e.g. 0.3",
            args.noise
        )));
    }
    if let Some(s) = args.scale {
        if !(s.is_finite() && s > 0.0 && s <= 4.0) {
            return Err(CliError::Usage(format!(
                "--scale {s}: expected a factor in (0, 4], e.g. 0.5"
            )));
        }
        model = model.with_resolution_scale(s);
    }
    if args.mode == Mode::Images && args.rig {
        return Err(CliError::Usage(
            "--rig belongs to `--mode observations` (COLMAP's mapper in images mode knows no rig)"
                .into(),
        ));
    }
    if args.mode == Mode::Observations && (args.images.is_some() || args.samples.is_some()) {
        return Err(CliError::Usage(
            "--images and --samples belong to `--mode images`".into(),
        ));
    }
    if args.check.is_some() && args.gcp.is_none() {
        return Err(CliError::Usage(
            "--check holds targets out of a GCP alignment: give --gcp too (without IDS, every \
             other target is a control point)"
                .into(),
        ));
    }
    if args.gcp_sigma.is_some() && args.gcp.is_none() {
        return Err(CliError::Usage(
            "--gcp-sigma weights the control points in the adjustment: give --gcp too (with \
             IDS for the control points, or --check IDS for the check points)"
                .into(),
        ));
    }
    if let Some(s) = args.gcp_sigma
        && !(s.is_finite() && s > 0.0)
    {
        return Err(CliError::Usage(format!(
            "--gcp-sigma {s}: expected the control points' accuracy in metres, > 0, e.g. 0.002"
        )));
    }
    if args.stock && args.mode != Mode::Images {
        return Err(CliError::Usage(
            "--stock runs COLMAP's own pipeline on images: give `--mode images` too".into(),
        ));
    }
    if args.stock && args.model.is_some_and(|m| m != CameraModel::SimpleRadial) {
        return Err(CliError::Usage(
            "--stock uses COLMAP's default camera model (simple-radial, from the images' EXIF); \
             drop --model, or drop --stock to choose the model"
                .into(),
        ));
    }
    if args.gcp.is_some() && args.mode == Mode::Images {
        return Err(CliError::Usage(
            "--gcp belongs to `--mode observations` (images mode aligns on the camera centres)"
                .into(),
        ));
    }
    if args.stock && args.images.is_none() && model.sensor.is_none() {
        // What another user of COLMAP has: camera files with their EXIF (the default camera
        // of `poser render --sensor`), not the backend's previews.
        model.sensor = Some(crate::model::Sensor::default());
    }
    let opts = Options {
        model: if args.stock {
            CameraModel::SimpleRadial
        } else {
            args.model.unwrap_or(args.mode.default_model())
        },
        stock: args.stock,
        noise: args.noise,
        density: args.density,
        gcp: args.gcp.is_some(),
        control: target_ids(&args.gcp),
        check: target_ids(&args.check),
        gcp_sigma: args.gcp_sigma,
        seed: args.seed,
        refine_principal_point: args.refine_principal_point,
        rig: args.rig,
        progress: !args.quiet,
        perturb_position: args.perturb_position,
        perturb_rotation: args.perturb_rotation.to_radians(),
    };
    // The evaluation's own stages (observations, SIFT, matching, mapping, adjustment); the
    // render in images mode reports its own progress first.
    let bar = std::sync::OnceLock::new();
    let bar = || bar.get_or_init(|| Progress::new(!args.quiet, "evaluating", "steps", 0));
    let progress = |what: &str, k: u64, n: u64| {
        let bar = bar();
        bar.set_length(n);
        bar.set_message(what);
        bar.set_position(k);
    };
    let ev = match args.mode {
        Mode::Observations => evaluate::evaluate_observations(&model, &opts, &progress),
        Mode::Images => {
            let dir = match &args.images {
                Some(d) => d.clone(),
                None => render_images(&model, args)?,
            };
            evaluate::evaluate_images(&model, &dir, &opts, &progress)
        }
    };
    bar().finish();
    let ev = ev.map_err(CliError::Failed)?;
    evaluate::report::write(&ev, &args.out).map_err(CliError::Failed)?;
    print_summary(&ev, &args.out);
    if args.stock && ev.colmap.get("exif_focal_px").is_some_and(|v| v.is_null()) {
        eprintln!(
            "note: COLMAP found no focal length in the images' EXIF and started from its guess \
             (1.2 × the image's larger side)\n  help: give it the sensor stage's camera images \
             (`poser render SCENE --sensor`, `OUT/camera/*.jpg`), which carry the focal length"
        );
    }
    for w in &ev.warnings {
        eprintln!("warning: {w}");
    }
    if args.strict && !ev.warnings.is_empty() {
        return Err(CliError::Failed(format!(
            "--strict: {} health warning(s) above ({}); the report is written but its figures \
             do not describe a sound block",
            ev.warnings.len(),
            ev.warnings
                .iter()
                .map(|w| w.code)
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(())
}

/// Images mode without `--images`: render the network into `OUT/images.partial/` and pass it
/// through the camera, then rename it to `OUT/images/` (replacing an earlier run's), so that
/// `OUT/images/` only ever holds a finished set. A run cut short leaves `images.partial/`, which
/// the next run resumes (the native backend skips the images it finished with the same scene
/// and samples).
fn render_images(model: &crate::model::Model, args: &Args) -> Result<PathBuf, CliError> {
    // Refuse an untextured scene before spending the render on it.
    evaluate::check_images_texture(model).map_err(CliError::Failed)?;
    let dir = args.out.join("images");
    let partial = args.out.join("images.partial");
    let opts = RenderOptions {
        samples: args.samples,
        poses: None,
        progress: !args.quiet,
        resume: true,
    };
    let steps = crate::pipeline::Steps {
        truth: false,
        camera: true,
    };
    crate::pipeline::run(model, args.backend, &partial, &opts, steps).map_err(CliError::Failed)?;
    crate::io::replace_dir(&partial, &dir)
        .map_err(|e| CliError::Failed(format!("{}: {e}", dir.display())))?;
    Ok(dir)
}

/// The target names of a comma-separated `--gcp`/`--check` list (none when absent).
fn target_ids(v: &Option<String>) -> Vec<String> {
    v.as_deref()
        .unwrap_or("")
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

/// The evaluation's summary on stderr: registration, height error, control and check
/// points, tie-point RMS and where the report is.
fn print_summary(ev: &evaluate::Evaluation, out: &std::path::Path) {
    let cam = ev.cameras.first();
    eprintln!(
        "{}: {} of {} images registered, {} points, track {:.1}, reprojection {:.3} px{}",
        ev.scene,
        ev.registered,
        ev.images,
        ev.points,
        ev.mean_track_length,
        ev.reprojection_error,
        cam.map(|c| format!(
            ", focal {:+.2} % against the water-equivalent truth{}",
            100.0 * c.focal_error,
            if ev.focal_determined() == Some(false) {
                " (not determined by these images)"
            } else {
                ""
            }
        ))
        .unwrap_or_default()
    );
    let r = &ev.tie_errors.robust_z;
    eprintln!(
        "height error: median {:+.2} mm, NMAD {:.2} mm, LE90 {:.2} mm ({:.1} % beyond 3 NMAD)",
        r.median * 1e3,
        r.nmad * 1e3,
        r.le90 * 1e3,
        100.0 * r.outliers
    );
    if let (Some(c), "gcp") = (&ev.control_errors, ev.alignment.as_str()) {
        eprintln!(
            "control points: {}{}, RMSE X/Y/Z {:.2}/{:.2}/{:.2} mm",
            c.count,
            ev.gcp_sigma
                .map(|s| format!(" (weighted in the adjustment, σ {:.1} mm)", s * 1e3))
                .unwrap_or_default(),
            c.rms[0] * 1e3,
            c.rms[1] * 1e3,
            c.rms[2] * 1e3
        );
    }
    if let (Some(c), "gcp") = (&ev.check_errors, ev.alignment.as_str()) {
        eprintln!(
            "check points: {}, RMSE X/Y/Z {:.2}/{:.2}/{:.2} mm",
            c.count,
            c.rms[0] * 1e3,
            c.rms[1] * 1e3,
            c.rms[2] * 1e3
        );
    }
    eprintln!(
        "tie-point RMS error X/Y/Z {:.2}/{:.2}/{:.2} mm{}; report in {}",
        ev.tie_errors.rms[0] * 1e3,
        ev.tie_errors.rms[1] * 1e3,
        ev.tie_errors.rms[2] * 1e3,
        ev.bowl
            .map(|b| format!(
                ", bowl {:.2} mm peak-to-peak explains {:.0} % of the height error",
                b.peak_to_peak * 1e3,
                100.0 * b.explained
            ))
            .unwrap_or_default(),
        out.join("report.md").display()
    );
}
