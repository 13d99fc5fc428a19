//! `poser evaluate`: process the simulated survey with a real photogrammetry engine (COLMAP,
//! through pycolmap) and measure what went wrong against the exact truth.
//!
//! | mode | what COLMAP gets | alignment to the truth |
//! |---|---|---|
//! | observations (default) | exact refractive projections of sampled tie points ([`observe`]) with seeded pixel noise; a perturbed initial network; self-calibrating bundle adjustment with a camera model that ignores the port | 7-parameter similarity from the targets as GCPs (`gcp`) or from all points; or control points weighted in the adjustment (`gcp_sigma`), no similarity after |
//! | images | rendered images: SIFT, matching, incremental mapping | similarity from the registered camera centres and axes |
//!
//! | item | meaning |
//! |---|---|
//! | [`Options`] | the knobs of one evaluation |
//! | [`evaluate_observations`], [`evaluate_images`] | run one mode, return an [`Evaluation`] |
//! | [`Evaluation`] | registered images, track length, reprojection error, recovered intrinsics against the in-water-equivalent truth, 3D errors, the fitted bowl |
//! | [`health`] | the checks that flag a degenerate block (images dropped, a focal length the block does not determine — the probe and the adjustment's covariance — or that lands far from the nominal one, an RMS driven by outliers) |
//! | [`gcp`] | the control/check split of `--gcp`: the similarity fitted on the control points, or the control points weighted in the adjustment (`--gcp-sigma`); every point's error after it |
//! | [`report`] | `report.json`, `report.md`, `errors.csv`, `deformation.png`, `profile.svg` |
//!
//! The *in-water-equivalent* intrinsics are what a pinhole camera model would need to match the
//! camera behind its port near the image centre: the paraxial focal length measured through
//! the exact projection at the survey's median distance (behind a flat port, about
//! `n_water × f` in air; behind a centred dome, `f`).

pub mod align;
pub mod colmap;
pub mod gcp;
pub mod health;
pub mod observe;
pub mod report;

use crate::geometry::bvh::target_mesh;
use crate::geometry::mesh::{TriMesh, object_mesh};
use crate::geometry::seen::{TextureSeen, texture_seen};
use crate::geometry::{Bvh as Scene, Ray, SurfaceId};
use crate::model::{Model, Pose};
use crate::optics::project::Projector;
use crate::rng::SplitMix64;
use align::{AxisStats, Bowl, Similarity};
use colmap::{CameraModel, Reconstruction, Request, RequestCamera, RequestImage, RequestPoint};
use glam::{DQuat, DVec3};
use observe::{ImageObservations, gauss};
use serde::Serialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Which processing `poser evaluate` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Exact projections of tie points, bundle-adjusted (no rendering).
    Observations,
    /// COLMAP's full pipeline on rendered images.
    Images,
}

impl Mode {
    /// The camera model COLMAP self-calibrates unless told otherwise. Observations mode:
    /// OpenCV's Brown–Conrady (fx, fy, k1, k2, p1, p2), to show how a port deforms a block.
    /// Images mode: `radial` (one focal length, k1, k2), the calibration SfM software fits
    /// from scratch (COLMAP's and Metashape's defaults keep one focal length: pixels are
    /// square). With two focal lengths, obliques tilted only forward determine fy and leave
    /// fx free (measured on coral_self_occlusion's quick form: fy −0.02 %, fx +16.6 %).
    pub fn default_model(self) -> CameraModel {
        match self {
            Mode::Observations => CameraModel::Opencv,
            Mode::Images => CameraModel::Radial,
        }
    }
}

/// The knobs of one evaluation.
#[derive(Debug, Clone)]
pub struct Options {
    /// See [`Mode::default_model`].
    pub model: CameraModel,
    /// Pixel noise added to every observation, px (observations mode).
    pub noise: f64,
    /// Tie points per m² of surface (observations mode).
    pub density: f64,
    /// Align on the targets' points (GCPs) instead of all points.
    pub gcp: bool,
    /// With `gcp`: the targets that are control points (empty: every target not in `check`).
    /// A target is named as in `errors.csv` (`name`, `name/point` or a points file's id).
    pub control: Vec<String>,
    /// With `gcp`: the targets held out as check points (empty: those not in `control`).
    pub check: Vec<String>,
    /// With `gcp` (observations mode): weight the control points in the bundle adjustment,
    /// each known to this accuracy (σ per axis, m), as Metashape weights a marker, instead of
    /// only fitting a similarity to them afterwards. The adjustment then holds no camera: the
    /// control points fix the datum, and the errors are read with no similarity. `None`: the
    /// control points only align.
    pub gcp_sigma: Option<f64>,
    pub seed: u64,
    /// Let the bundle adjustment refine the principal point (COLMAP's default: no).
    pub refine_principal_point: bool,
    /// Observations mode: the rig is calibrated beforehand. The intrinsics are held at their
    /// in-water-equivalent values ([`water_equivalent`]) and the cameras' poses in the rig at
    /// the truth; COLMAP's bundle adjuster solves one pose per rig position (a COLMAP rig
    /// and frames), so the rig's baseline, not the alignment, sets the scale.
    pub rig: bool,
    /// Initial camera and point positions are off by this fraction of the median viewing
    /// distance (σ per axis), and rotations by `perturb_rotation` (σ, rad).
    pub perturb_position: f64,
    pub perturb_rotation: f64,
    pub progress: bool,
    /// Images mode: COLMAP as it ships ([`STOCK_INIT_ANGLE_DEG`]): the images' EXIF for the
    /// camera, no intrinsics handed over, COLMAP's default options throughout.
    pub stock: bool,
}

/// The one option `--stock` changes from COLMAP's defaults: the initial pair's minimum
/// triangulation angle, degrees (COLMAP's default 16°). Neighbours in a survey strip at 80 %
/// overlap are about 8° apart, so no pair reaches 16° early in a strip; with 16° stock COLMAP
/// registered 3 of 16 images of a reef strip. poser's own pipeline uses the same 8°.
pub const STOCK_INIT_ANGLE_DEG: f64 = 8.0;

/// Above this many images, images mode matches each image with its neighbours in the network's
/// order (COLMAP's sequential matcher, its default overlap of 10), in both setups, instead of
/// with every other image: exhaustive matching grows with the square of the images, and on
/// 234 images of 600 × 400 px it matched 3 pairs a second on 2 cores (about 2.5 h for the
/// 27 261 pairs).
pub const EXHAUSTIVE_MAX_IMAGES: usize = 40;

impl Default for Options {
    fn default() -> Options {
        Options {
            model: CameraModel::Opencv,
            noise: 0.3,
            density: 20.0,
            gcp: false,
            control: Vec::new(),
            check: Vec::new(),
            gcp_sigma: None,
            seed: 1,
            refine_principal_point: false,
            rig: false,
            perturb_position: 0.02,
            perturb_rotation: 1f64.to_radians(),
            progress: false,
            stock: false,
        }
    }
}

/// A camera's intrinsics as recovered by COLMAP against the truth.
#[derive(Debug, Clone, Serialize)]
pub struct CameraEval {
    pub name: String,
    /// The camera's in-air focal length, px (what EXIF gives; COLMAP starts from it).
    pub f_air: f64,
    /// In-water-equivalent truth (fx, fy, cx, cy), px, at `distance` m.
    pub truth: [f64; 4],
    pub distance: f64,
    /// Recovered (fx, fy, cx, cy), px, and the model's other parameters.
    pub recovered: [f64; 4],
    pub extra: Vec<(String, f64)>,
    /// (recovered − truth) / truth of the mean focal length.
    pub focal_error: f64,
}

/// One point's error after alignment (truth frame, m).
#[derive(Debug, Clone, Serialize)]
pub struct PointError {
    pub id: u64,
    pub label: String,
    pub kind: &'static str,
    pub truth: [f64; 3],
    pub error: [f64; 3],
    pub track: u32,
}

/// Everything `poser evaluate` measured.
#[derive(Debug, Clone, Serialize)]
pub struct Evaluation {
    pub scene: String,
    pub mode: Mode,
    pub camera_model: CameraModel,
    pub conventions: &'static str,
    pub settings: serde_json::Value,
    pub images: usize,
    pub registered: usize,
    pub points: usize,
    pub observations: usize,
    pub mean_track_length: f64,
    /// Mean reprojection error after processing, px.
    pub reprojection_error: f64,
    pub cameras: Vec<CameraEval>,
    /// `"gcp"`, `"all points"` or `"camera centres"`, and how many were used.
    pub alignment: String,
    pub alignment_count: usize,
    /// With `"gcp"`: the control points were weighted in the adjustment at this σ (m), and
    /// `similarity` is the identity; `None`: the similarity was fitted to them afterwards.
    pub gcp_sigma: Option<f64>,
    pub similarity: Similarity,
    /// Errors of the points used as ties (observations mode: 3D; images mode: height only).
    pub tie_errors: AxisStats,
    /// Errors of target points not used for the alignment (check points), if any.
    pub check_errors: Option<AxisStats>,
    /// Errors of the control points (the GCPs the alignment used), with `--gcp`.
    pub control_errors: Option<AxisStats>,
    /// Camera-centre errors after alignment.
    pub camera_errors: AxisStats,
    pub bowl: Option<Bowl>,
    /// COLMAP's own summary (version, iterations, …).
    pub colmap: serde_json::Value,
    /// Images of the network that are not in the result: too few tie points to enter the
    /// adjustment (observations mode) or not registered (images mode).
    pub dropped: Vec<String>,
    /// What makes the figures above less than they seem ([`health`]).
    pub warnings: Vec<health::Warning>,
    pub seconds: f64,
    #[serde(skip)]
    pub point_errors: Vec<PointError>,
    /// True camera centres of the registered images (for the map).
    #[serde(skip)]
    pub centres: Vec<DVec3>,
}

/// Below this rise of the mean reprojection error, with the focal length held 10 % off its
/// estimate, the block does not determine the focal length (images mode; see
/// [`Evaluation::focal_sensitivity`]).
pub const FOCAL_DETERMINED: f64 = 0.005;
/// The largest focal-probe rise `backends/colmap/evaluate.py` reports (`RISE_CAP`, 1000 %): a
/// probe that ran away says only that the block holds the focal length firmly.
pub const FOCAL_RISE_CAP: f64 = 10.0;

impl Evaluation {
    /// The first camera's focal length error, % (NaN without a camera): the one focal number
    /// the lesson pages and `poser bench evaluate` show.
    pub fn focal_error_percent(&self) -> f64 {
        self.cameras
            .first()
            .map_or(f64::NAN, |c| 100.0 * c.focal_error)
    }

    /// Images mode: the relative rise of the mean reprojection error when the focal length is
    /// held 10 % above COLMAP's estimate and the rest is adjusted again (`focal_sensitivity`
    /// in `backends/colmap/evaluate.py`). Below [`FOCAL_DETERMINED`] the images do not
    /// determine the focal length (a flat nadir block: focal length and height trade).
    pub fn focal_sensitivity(&self) -> Option<f64> {
        self.colmap
            .get("focal_sensitivity")
            .and_then(|v| v.as_f64())
    }

    /// Tie points the adjustment left with an absurd reprojection error, removed before any
    /// figure was taken (`drop_diverged_points` in `backends/colmap/evaluate.py`).
    pub fn diverged_points(&self) -> u64 {
        self.colmap
            .get("diverged_points")
            .and_then(|v| v.as_u64())
            .unwrap_or(0)
    }

    /// The focal length's standard deviation from the adjustment's covariance (the inverse
    /// normal matrix, COLMAP's `estimate_ba_covariance`), relative to the focal length, per
    /// pixel of image-measurement σ (`focal_covariance` in `backends/colmap/evaluate.py`).
    /// `None` when not computed or when the normal matrix is singular ([`Self::focal_singular`]).
    pub fn focal_sd(&self) -> Option<f64> {
        self.colmap.get("focal_sd").and_then(|v| v.as_f64())
    }

    /// The adjustment's normal matrix is rank deficient: a direction of the camera's
    /// parameters and the poses (focal length against height, over a flat block at one
    /// height) the images do not fix at all.
    pub fn focal_singular(&self) -> bool {
        self.colmap.get("focal_covariance").and_then(|v| v.as_str()) == Some("rank_deficient")
    }

    /// Whether the block determines the focal length (`None`: not measured): the focal probe
    /// rises by [`FOCAL_DETERMINED`] or more, and the covariance is neither singular nor above
    /// [`FOCAL_SD_MAX`].
    pub fn focal_determined(&self) -> Option<bool> {
        let probe = self.focal_sensitivity().map(|s| s >= FOCAL_DETERMINED);
        let cov = if self.focal_singular() {
            Some(false)
        } else {
            self.focal_sd().map(|sd| sd <= FOCAL_SD_MAX)
        };
        match (probe, cov) {
            (None, None) => None,
            (a, b) => Some(a != Some(false) && b != Some(false)),
        }
    }
}

/// Above this standard deviation of the focal length per pixel of image σ, relative to the
/// focal length ([`Evaluation::focal_sd`]), the block does not determine the focal length.
/// Measured on the quick forms: 0.08 % for the flat port and the dome flown with the diver's
/// wobble, 8.9 % for the flat port flown without it (focal −59.5 %, which the probe passed).
pub const FOCAL_SD_MAX: f64 = 0.01;
/// Beyond this relative difference between the self-calibrated focal length and the nominal
/// one (the in-water-equivalent truth: about n_water × f behind a flat port, f behind a centred
/// dome), the calibration is reported as implausible. Healthy quick forms stay within 3.7 %.
pub const FOCAL_DRIFT_MAX: f64 = 0.10;

/// World-frame meshes of every object and target of the site, labelled (tie points are sampled
/// on them; backdrop objects are scenery and left out), and the occlusion scene built from
/// every surface, backdrop included.
fn surfaces(model: &Model) -> Result<(Vec<(String, TriMesh)>, Scene), String> {
    let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
    let mut labelled = Vec::new();
    let mut all = Vec::new();
    for (i, o) in model.objects.iter().enumerate() {
        let mesh = object_mesh(o, base)?;
        all.push((SurfaceId::Object(i as u32), mesh.clone()));
        if !o.backdrop {
            labelled.push((o.name.clone(), mesh));
        }
    }
    for (i, t) in model.targets.iter().enumerate() {
        let mesh = target_mesh(t);
        all.push((SurfaceId::Target(i as u32), mesh.clone()));
        labelled.push((t.name.clone(), mesh));
    }
    Ok((labelled, Scene::from_meshes(all)))
}

/// The smallest σ of an image measurement, px, that control points weighted in the adjustment
/// are weighed against (with `--noise 0` the pixels would otherwise outweigh any control
/// point without bound).
pub const MIN_TIE_SIGMA_PX: f64 = 0.1;

/// Below this share of textured pixels, images mode refuses before running COLMAP.
pub const MIN_TEXTURED_SHARE: f64 = 0.2;

/// Images mode's pre-check (before rendering): the images must see enough texture for SIFT.
pub fn check_images_texture(model: &Model) -> Result<TextureSeen, String> {
    let (_, scene) = surfaces(model)?;
    check_texture_seen(texture_seen(model, &scene))
}

fn check_texture_seen(seen: TextureSeen) -> Result<TextureSeen, String> {
    if seen.textured < MIN_TEXTURED_SHARE {
        return Err(format!(
            "the images see almost no texture: {:.0} % of the sampled pixels land on a \
             textured surface ({:.0} % on any surface); SIFT finds no features on uniform \
             albedo or open water, so COLMAP cannot match the images\n  help: give the seabed \
             and objects a pattern at the images' GSD (e.g. `pattern = {{ type = \"fbm\" }}`, \
             see docs/textures.md), or point the cameras at them",
            100.0 * seen.textured,
            100.0 * seen.surface
        ));
    }
    Ok(seen)
}

/// The request's cameras at their in-water-equivalent intrinsics at distance `d`: what a
/// calibration in the water beforehand would give (`--rig`).
fn calibrated_cameras(model: &Model, d: f64) -> Result<Vec<RequestCamera>, String> {
    let mut cams = request_cameras(model);
    for (i, c) in cams.iter_mut().enumerate() {
        [c.fx, c.fy, c.cx, c.cy] = water_equivalent(model, i, d)?;
    }
    Ok(cams)
}

/// The paraxial in-water-equivalent (fx, fy, cx, cy) of camera `ci` at distance `d`.
pub fn water_equivalent(model: &Model, ci: usize, d: f64) -> Result<[f64; 4], String> {
    let cam = &model.cameras[ci];
    let pr = Projector::for_camera(cam, 1, model.ambient_ior()[1])?;
    let t = 1e-4;
    let p = |x: f64, y: f64| {
        pr.project_camera_unbounded(DVec3::new(x * d, y * d, d))
            .map_err(|e| format!("camera `{}`: no projection near the axis ({e:?})", cam.name))
    };
    let c = p(0.0, 0.0)?;
    let (px, mx) = (p(t, 0.0)?, p(-t, 0.0)?);
    let (py, my) = (p(0.0, t)?, p(0.0, -t)?);
    Ok([
        (px[0] - mx[0]) / (2.0 * t),
        (py[1] - my[1]) / (2.0 * t),
        c[0],
        c[1],
    ])
}

fn random_rotation(rng: &mut SplitMix64, sigma: f64) -> DQuat {
    let axis = DVec3::new(gauss(rng), gauss(rng), gauss(rng));
    let axis = if axis.length() > 0.0 {
        axis.normalize()
    } else {
        DVec3::Z
    };
    DQuat::from_axis_angle(axis, sigma * gauss(rng))
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn request_cameras(model: &Model) -> Vec<RequestCamera> {
    model
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| RequestCamera {
            id: i as u32 + 1,
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
        })
        .collect()
}

fn camera_evals(
    model: &Model,
    rec: &Reconstruction,
    distance: f64,
) -> Result<Vec<CameraEval>, String> {
    let mut out = Vec::new();
    for (ci, cam) in model.cameras.iter().enumerate() {
        let Some(rc) = rec.cameras.iter().find(|c| c.id == ci as u32 + 1) else {
            continue;
        };
        let truth = water_equivalent(model, ci, distance)?;
        let (recovered, extra) = rc.intrinsics();
        let ft = 0.5 * (truth[0] + truth[1]);
        let fr = 0.5 * (recovered[0] + recovered[1]);
        out.push(CameraEval {
            name: cam.name.clone(),
            f_air: 0.5 * (cam.fx + cam.fy),
            truth,
            distance,
            recovered,
            extra: extra.into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
            focal_error: (fr - ft) / ft,
        });
    }
    Ok(out)
}

fn summary_f64(rec: &Reconstruction, key: &str) -> f64 {
    rec.summary
        .get(key)
        .and_then(|v| v.as_f64())
        .unwrap_or(f64::NAN)
}

/// Observations mode: sample, observe, perturb, bundle-adjust with COLMAP, compare.
pub fn evaluate_observations(
    model: &Model,
    opts: &Options,
    progress: &(dyn Fn(&str, u64, u64) + Sync),
) -> Result<Evaluation, String> {
    let t0 = std::time::Instant::now();
    if model.poses.is_empty() {
        return Err("the scene's network has no poses: nothing to evaluate".into());
    }
    if model.any_above_surface() {
        return Err(
            "observations mode projects through the cameras' ports only, and this \
                    network has images taken from above the sea surface\n  help: use `--mode \
                    images` (the native renderer's images refract at the surface)"
                .into(),
        );
    }
    let (meshes, scene) = surfaces(model)?;
    let points = observe::sample_points(model, &meshes, opts.density, opts.seed)?;
    if opts.gcp {
        // Before minutes of adjustment: a misspelt --gcp or --check id fails at once.
        gcp::check_target_names(&points, opts)?;
    }
    let n_images = (model.poses.len() * model.cameras.len()) as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    let mut images = observe::observe(model, &scene, &points, &|| {
        let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress("observing", k, n_images);
    })?;
    observe::add_noise(&mut images, opts.noise, opts.seed);

    let (seen, used) = tie_points(&images, points.len())?;
    let distance = median_distance(model, &used, &points);
    let sigma_pos = opts.perturb_position * distance;

    let mut rng = SplitMix64(opts.seed ^ 0x1417_1A11_5EED);
    // A perturbed `world_from_x` as COLMAP's (w, x, y, z) and t of `x_from_world`.
    let mut perturbed = |wfc: Pose| {
        let rot = random_rotation(&mut rng, opts.perturb_rotation)
            * DQuat::from_mat3(&wfc.rotation).normalize();
        let c = wfc.translation
            + sigma_pos * DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng));
        let q = rot.inverse(); // x_from_world rotation
        ([q.w, q.x, q.y, q.z], (-(q * c)).to_array())
    };
    // With a calibrated rig: one perturbed start per rig pose (the first camera's frame,
    // COLMAP's reference sensor); the images follow it through the rig.
    let rig = opts.rig.then(|| rig_request(model, &used, &mut perturbed));
    let req_images = request_images(model, &used, &seen, opts.rig, &mut perturbed);
    let req_points = request_points(&points, &seen, sigma_pos, &mut rng);
    // Control points weighted in the adjustment: their known positions, against the pixels'
    // σ (the simulated noise, at least MIN_TIE_SIGMA_PX).
    let weighted = opts.gcp_sigma.filter(|_| opts.gcp);
    let gcps = match weighted {
        Some(sigma) => gcp::priors(&points, &seen, opts, sigma)?,
        None => Vec::new(),
    };
    let req = Request {
        job: "bundle",
        model: opts.model,
        refine_principal_point: opts.refine_principal_point,
        seed: opts.seed,
        cameras: if opts.rig {
            calibrated_cameras(model, distance)?
        } else {
            request_cameras(model)
        },
        images: req_images,
        points: req_points,
        tie_sigma_px: weighted.map(|_| opts.noise.max(MIN_TIE_SIGMA_PX)),
        gcps,
        rig,
        image_dir: None,
        work_dir: None,
        matcher: None,
        threads: rayon::current_num_threads(),
        stock: None,
    };
    progress("bundle adjustment (COLMAP)", 0, 0);
    let work = tempfile::tempdir().map_err(|e| format!("temporary directory: {e}"))?;
    let rec = colmap::run(&req, work.path())?;

    // Align and measure.
    let by_id: HashMap<u64, &colmap::ResultPoint> = rec.points.iter().map(|p| (p.id, p)).collect();
    let pairs: Vec<(usize, DVec3)> = rec
        .points
        .iter()
        .map(|p| ((p.id - 1) as usize, DVec3::from_array(p.xyz)))
        .collect();
    let aligned = match weighted {
        // The control points fixed the datum inside the adjustment: no similarity after.
        Some(_) => gcp::Alignment {
            name: "gcp",
            count: summary_f64(&rec, "gcps_weighted") as usize,
            sim: Similarity::identity(),
        },
        None => gcp::align(&points, &pairs, opts)?,
    };
    let sim = aligned.sim;
    let res = gcp::residuals(&points, &pairs, &sim, opts, |id| {
        by_id.get(&id).map_or(0, |r| r.track)
    });
    let (camera_errors, centres) = camera_centre_errors(model, &rec, &sim, &used_names(&used));
    let dropped = dropped(images.iter().map(|im| im.name.as_str()), &rec);
    finish(
        model,
        Evaluation {
            scene: model.name.clone(),
            mode: Mode::Observations,
            camera_model: opts.model,
            conventions: CONVENTIONS,
            settings: serde_json::json!({
                "noise_px": opts.noise,
                "density_per_m2": opts.density,
                "seed": opts.seed,
                "refine_principal_point": opts.refine_principal_point,
                "calibrated_rig": opts.rig,
                "perturb_position_m": sigma_pos,
                "perturb_rotation_deg": opts.perturb_rotation.to_degrees(),
                "tie_points_sampled": points.len(),
                "gcp_sigma_m": weighted,
                "tie_sigma_px": req.tie_sigma_px,
            }),
            images: images.len(),
            registered: rec.images.len(),
            points: rec.points.len(),
            observations: summary_f64(&rec, "observations") as usize,
            mean_track_length: summary_f64(&rec, "mean_track_length"),
            reprojection_error: summary_f64(&rec, "reprojection_error"),
            cameras: camera_evals(model, &rec, distance)?,
            alignment: aligned.name.into(),
            alignment_count: aligned.count,
            gcp_sigma: weighted,
            similarity: sim,
            tie_errors: AxisStats::of(&res.tie),
            check_errors: (!res.check.is_empty()).then(|| AxisStats::of(&res.check)),
            control_errors: (!res.control.is_empty()).then(|| AxisStats::of(&res.control)),
            camera_errors,
            bowl: Bowl::fit(&res.bowl_samples),
            colmap: rec.summary.clone(),
            dropped,
            warnings: Vec::new(),
            seconds: t0.elapsed().as_secs_f64(),
            point_errors: res.point_errors,
            centres,
        },
        !opts.rig,
    )
}

/// The used images' request: their tie points' pixels and, without a rig, a perturbed start.
fn request_images(
    model: &Model,
    used: &[&ImageObservations],
    seen: &[u32],
    rig: bool,
    perturbed: &mut impl FnMut(Pose) -> ([f64; 4], [f64; 3]),
) -> Vec<RequestImage> {
    let mut req_images = Vec::new();
    for (n, im) in used.iter().enumerate() {
        let (qvec, tvec) = if rig {
            ([1.0, 0.0, 0.0, 0.0], [0.0; 3]) // unused: the frame's pose
        } else {
            perturbed(model.world_from_camera(im.pose, im.camera))
        };
        req_images.push(RequestImage {
            id: n as u32 + 1,
            name: im.name.clone(),
            camera: im.camera as u32 + 1,
            frame: rig.then_some(im.pose as u32 + 1),
            qvec: Some(qvec),
            tvec: Some(tvec),
            observations: im
                .points
                .iter()
                .filter(|(k, _)| seen[*k] >= 2)
                .map(|(k, px)| [px[0], px[1], (*k + 1) as f64])
                .collect(),
        });
    }
    req_images
}

/// The tie points seen twice or more, each started `sigma_pos` (σ per axis) off its truth.
fn request_points(
    points: &[observe::SurveyPoint],
    seen: &[u32],
    sigma_pos: f64,
    rng: &mut SplitMix64,
) -> Vec<RequestPoint> {
    points
        .iter()
        .enumerate()
        .filter(|(k, _)| seen[*k] >= 2)
        .map(|(k, p)| {
            let d = sigma_pos * DVec3::new(gauss(rng), gauss(rng), gauss(rng));
            RequestPoint {
                id: k as u64 + 1,
                xyz: (p.world + d).to_array(),
            }
        })
        .collect()
}

/// How many images see each point, and the images that see at least 8 points seen twice or
/// more; an error when too few images or points tie the network together.
fn tie_points(
    images: &[ImageObservations],
    n_points: usize,
) -> Result<(Vec<u32>, Vec<&ImageObservations>), String> {
    let mut seen = vec![0u32; n_points];
    for im in images {
        for (k, _) in &im.points {
            seen[*k] += 1;
        }
    }
    let used: Vec<&ImageObservations> = images
        .iter()
        .filter(|im| im.points.iter().filter(|(k, _)| seen[*k] >= 2).count() >= 8)
        .collect();
    let tie_count = seen.iter().filter(|&&s| s >= 2).count();
    if used.len() < 3 || tie_count < 10 {
        return Err(format!(
            "only {} image(s) see enough tie points and {tie_count} point(s) are seen twice or \
             more\n  help: the network must overlap on textured surfaces; raise --density, the \
             overlap, or check that the cameras look at the scene",
            used.len()
        ));
    }
    Ok((seen, used))
}

/// The median viewing distance of the used images' points, for the perturbation scale and the
/// equivalent focal length.
fn median_distance(
    model: &Model,
    used: &[&ImageObservations],
    points: &[observe::SurveyPoint],
) -> f64 {
    let mut depths = Vec::new();
    for im in used.iter().step_by((used.len() / 50).max(1)) {
        let cfw = model.world_from_camera(im.pose, im.camera).inverse();
        for (k, _) in im.points.iter().step_by(7) {
            depths.push(cfw.transform_point(points[*k].world).z);
        }
    }
    median(depths)
}

/// The calibrated rig's request: one perturbed start per rig pose (the first camera's frame,
/// COLMAP's reference sensor) and the cameras' true poses in the rig.
fn rig_request(
    model: &Model,
    used: &[&ImageObservations],
    perturbed: &mut impl FnMut(Pose) -> ([f64; 4], [f64; 3]),
) -> colmap::RequestRig {
    let mut poses: Vec<usize> = used.iter().map(|im| im.pose).collect();
    poses.sort_unstable();
    poses.dedup();
    let frames = poses
        .iter()
        .map(|&p| {
            let (qvec, tvec) = perturbed(model.world_from_camera(p, 0));
            colmap::RequestFrame {
                id: p as u32 + 1,
                qvec,
                tvec,
            }
        })
        .collect();
    let sensor_from_rig = (0..model.cameras.len())
        .map(|k| {
            let s = model
                .world_from_camera(0, k)
                .inverse()
                .compose(&model.world_from_camera(0, 0));
            let q = DQuat::from_mat3(&s.rotation).normalize();
            colmap::RequestSensor {
                qvec: [q.w, q.x, q.y, q.z],
                tvec: s.translation.to_array(),
            }
        })
        .collect();
    colmap::RequestRig {
        sensor_from_rig,
        frames,
    }
}

/// The evaluation with its [`health`] checks run.
fn finish(model: &Model, mut ev: Evaluation, self_calibrated: bool) -> Result<Evaluation, String> {
    ev.warnings = health::check(model, &ev, self_calibrated);
    Ok(ev)
}

/// The network's images (in order) that are not in COLMAP's result.
fn dropped<'a>(all: impl Iterator<Item = &'a str>, rec: &Reconstruction) -> Vec<String> {
    let registered: std::collections::HashSet<&str> =
        rec.images.iter().map(|im| im.name.as_str()).collect();
    all.filter(|n| !registered.contains(n))
        .map(str::to_string)
        .collect()
}

const CONVENTIONS: &str = "world z up, metres; errors = aligned reconstruction − truth; pixel \
                           centres at +0.5 (COLMAP); intrinsics in pixels of the evaluated images";

fn used_names(used: &[&ImageObservations]) -> HashMap<String, (usize, usize)> {
    used.iter()
        .map(|im| (im.name.clone(), (im.pose, im.camera)))
        .collect()
}

/// Camera-centre errors of the registered images after `sim`, and their true centres.
fn camera_centre_errors(
    model: &Model,
    rec: &Reconstruction,
    sim: &Similarity,
    names: &HashMap<String, (usize, usize)>,
) -> (AxisStats, Vec<DVec3>) {
    let mut errs = Vec::new();
    let mut centres = Vec::new();
    for im in &rec.images {
        if let Some(&(pi, ci)) = names.get(&im.name) {
            let truth = model.world_from_camera(pi, ci).translation;
            errs.push(sim.apply(colmap::centre(im.qvec, im.tvec)) - truth);
            centres.push(truth);
        }
    }
    (AxisStats::of(&errs), centres)
}

/// An image file of a render directory: (file name, pose index, camera index).
pub type ImageFile = (String, usize, usize);

/// The directory and file of every image of the model in a render directory: the sensor
/// stage's camera images (`DIR/camera/<name>.jpg|png`) when they are all there, else the
/// backend's previews (`DIR/<name>.png`).
pub fn rendered_images(model: &Model, dir: &Path) -> Result<(PathBuf, Vec<ImageFile>), String> {
    let find = |d: &Path| -> Option<Vec<ImageFile>> {
        let mut out = Vec::new();
        for pi in 0..model.poses.len() {
            for ci in 0..model.cameras.len() {
                let name = model.image_name(pi, ci);
                let file = ["jpg", "png"]
                    .iter()
                    .map(|e| format!("{name}.{e}"))
                    .find(|f| d.join(f).is_file())?;
                out.push((file, pi, ci));
            }
        }
        Some(out)
    };
    let camera = dir.join("camera");
    if let Some(v) = find(&camera) {
        return Ok((camera, v));
    }
    find(dir).map(|v| (dir.to_path_buf(), v)).ok_or_else(|| {
        format!(
            "{}: not every image of the network is there (`<image>.png`, or `camera/<image>.jpg` \
             from a sensor stage)\n  help: render the scene into this directory first \
             (`poser render SCENE -o DIR`) or drop --images to let evaluate render it",
            dir.display()
        )
    })
}

/// The COLMAP job of images mode on the image files in `abs_dir`: poser's pipeline or,
/// with `opts.stock`, COLMAP's own.
fn images_request(
    model: &Model,
    files: &[ImageFile],
    abs_dir: &Path,
    work: &Path,
    opts: &Options,
) -> Request {
    Request {
        job: "images",
        model: opts.model,
        refine_principal_point: opts.refine_principal_point,
        seed: opts.seed,
        cameras: request_cameras(model).into_iter().take(1).collect(),
        images: files
            .iter()
            .enumerate()
            .map(|(n, (f, _, ci))| RequestImage {
                id: n as u32 + 1,
                name: f.clone(),
                camera: *ci as u32 + 1,
                frame: None,
                qvec: None,
                tvec: None,
                observations: Vec::new(),
            })
            .collect(),
        points: Vec::new(),
        gcps: Vec::new(),
        tie_sigma_px: None,
        image_dir: Some(abs_dir.to_string_lossy().into_owned()),
        work_dir: Some(work.to_string_lossy().into_owned()),
        rig: None,
        matcher: Some(if files.len() > EXHAUSTIVE_MAX_IMAGES {
            "sequential"
        } else {
            "exhaustive"
        }),
        threads: rayon::current_num_threads(),
        stock: opts.stock.then_some(STOCK_INIT_ANGLE_DEG),
    }
}

/// Images mode: COLMAP's pipeline on the rendered images in `image_dir`.
pub fn evaluate_images(
    model: &Model,
    image_dir: &Path,
    opts: &Options,
    progress: &(dyn Fn(&str, u64, u64) + Sync),
) -> Result<Evaluation, String> {
    let t0 = std::time::Instant::now();
    let (image_dir, files) = rendered_images(model, image_dir)?;
    let image_dir = image_dir.as_path();
    if files.len() < 3 {
        return Err(format!(
            "images mode needs at least 3 images; the network has {}",
            files.len()
        ));
    }
    let (_, scene) = surfaces(model)?;
    check_texture_seen(texture_seen(model, &scene))?;
    let abs_dir: PathBuf =
        std::fs::canonicalize(image_dir).map_err(|e| format!("{}: {e}", image_dir.display()))?;
    let work = tempfile::tempdir().map_err(|e| format!("temporary directory: {e}"))?;
    let req = images_request(model, &files, &abs_dir, work.path(), opts);
    progress("features, matching and mapping (COLMAP)", 0, 0);
    let rec = colmap::run(&req, work.path())?;
    let names: HashMap<String, (usize, usize)> = files
        .iter()
        .map(|(f, p, c)| (f.clone(), (*p, *c)))
        .collect();
    // Align on camera centres plus a point 1 unit along each camera's axes (the poses'
    // orientation fixes the roll about a single strip's line).
    let mut from = Vec::new();
    let mut to = Vec::new();
    let mut rec_centres = Vec::new();
    let mut true_centres = Vec::new();
    for im in &rec.images {
        if let Some(&(pi, ci)) = names.get(&im.name) {
            rec_centres.push(colmap::centre(im.qvec, im.tvec));
            true_centres.push(model.world_from_camera(pi, ci).translation);
        }
    }
    if rec_centres.len() < 3 {
        return Err(format!(
            "COLMAP registered only {} of {} images; at least 3 are needed to compare with the \
             truth\n  help: texture the scene at the image's GSD, raise samples, or add overlap",
            rec_centres.len(),
            files.len()
        ));
    }
    let spread = |v: &[DVec3]| {
        let m = v.iter().copied().sum::<DVec3>() / v.len() as f64;
        (v.iter().map(|p| (*p - m).length_squared()).sum::<f64>() / v.len() as f64).sqrt()
    };
    let s0 = spread(&true_centres) / spread(&rec_centres).max(1e-12);
    let arm = {
        let d = spread(&true_centres).max(0.1);
        (d, d / s0)
    };
    for im in &rec.images {
        if let Some(&(pi, ci)) = names.get(&im.name) {
            let wfc = model.world_from_camera(pi, ci);
            let q = DQuat::from_xyzw(im.qvec[1], im.qvec[2], im.qvec[3], im.qvec[0]).normalize();
            let c_rec = colmap::centre(im.qvec, im.tvec);
            from.push(c_rec);
            to.push(wfc.translation);
            for axis in [DVec3::X, DVec3::Z] {
                from.push(c_rec + q.inverse() * axis * arm.1);
                to.push(wfc.translation + wfc.rotation * axis * arm.0);
            }
        }
    }
    let sim = Similarity::estimate(&from, &to)
        .ok_or("the registered cameras are degenerate; no similarity to the truth")?;
    let (point_errors, tie, bowl_samples) = height_errors(&rec, &sim, &scene);
    let (camera_errors, centres) = camera_centre_errors(model, &rec, &sim, &names);
    let distance = camera_height(&scene, &true_centres);
    let dropped = dropped(files.iter().map(|(f, _, _)| f.as_str()), &rec);
    finish(
        model,
        Evaluation {
            scene: model.name.clone(),
            mode: Mode::Images,
            camera_model: opts.model,
            conventions: CONVENTIONS,
            settings: serde_json::json!({
                "image_dir": image_dir.display().to_string(),
                "seed": opts.seed,
                "refine_principal_point": opts.refine_principal_point,
                "matcher": req.matcher,
                "colmap_options": if opts.stock {
                    format!("stock: COLMAP's defaults, camera from EXIF, init_min_tri_angle {STOCK_INIT_ANGLE_DEG}°")
                } else {
                    "poser's: intrinsics held at the prior while mapping, one self-calibrating adjustment at the end".to_string()
                },
                "keypoints_per_image": rec.summary.get("keypoints_per_image"),
            }),
            images: files.len(),
            registered: rec.images.len(),
            points: rec.points.len(),
            observations: summary_f64(&rec, "observations") as usize,
            mean_track_length: summary_f64(&rec, "mean_track_length"),
            reprojection_error: summary_f64(&rec, "reprojection_error"),
            cameras: camera_evals(model, &rec, distance)?,
            alignment: "camera centres".into(),
            alignment_count: rec_centres.len(),
            gcp_sigma: None,
            similarity: sim,
            tie_errors: AxisStats::of(&tie),
            check_errors: None,
            control_errors: None,
            camera_errors,
            bowl: Bowl::fit(&bowl_samples),
            colmap: rec.summary.clone(),
            dropped,
            warnings: Vec::new(),
            seconds: t0.elapsed().as_secs_f64(),
            point_errors,
            centres,
        },
        true,
    )
}

/// The height error of each well-measured point of `rec` after `sim` against the true
/// surface below or above it: the points' errors, the error vectors and the bowl's samples.
fn height_errors(
    rec: &Reconstruction,
    sim: &Similarity,
    scene: &Scene,
) -> (Vec<PointError>, Vec<DVec3>, Vec<(f64, f64, f64)>) {
    let mut point_errors = Vec::new();
    let mut tie = Vec::new();
    let mut bowl_samples = Vec::new();
    for p in &rec.points {
        if p.track < 3 || p.error > 2.0 {
            continue;
        }
        let x = sim.apply(DVec3::from_array(p.xyz));
        let top = Ray {
            origin: DVec3::new(x.x, x.y, x.z + 50.0),
            dir: -DVec3::Z,
        };
        let Some(hit) = scene.intersect(&top, 100.0) else {
            continue;
        };
        let dz = x.z - hit.point.z;
        let e = DVec3::new(0.0, 0.0, dz);
        tie.push(e);
        bowl_samples.push((x.x, x.y, dz));
        point_errors.push(PointError {
            id: p.id,
            label: String::new(),
            kind: "tie",
            truth: hit.point.to_array(),
            error: e.to_array(),
            track: p.track,
        });
    }
    (point_errors, tie, bowl_samples)
}

/// The median height of the true camera centres above the surface below them (2 m when
/// none is above one).
fn camera_height(scene: &Scene, centres: &[DVec3]) -> f64 {
    let distance = median(
        centres
            .iter()
            .filter_map(|c| {
                scene
                    .intersect(
                        &Ray {
                            origin: *c,
                            dir: -DVec3::Z,
                        },
                        1e3,
                    )
                    .map(|h| h.t)
            })
            .collect(),
    );
    if distance.is_finite() { distance } else { 2.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_values() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert!(median(vec![]).is_nan());
    }
}
