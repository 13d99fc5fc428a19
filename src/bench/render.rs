//! `poser bench render`: speed against error for the three render backends, on every shipped
//! scene.
//!
//! Each backend renders each scene's first pose at a reduced size and increasing samples per
//! pixel (spp). The error of an image is its relative RMSE against that backend's own
//! converged reference, so that differences in conventions do not floor the curve; the
//! reference is the average of two independent renders, and its remaining noise is removed
//! from every error (E[MSE(img, (a+b)/2)] = σ²(img) + MSE(a, b)/4). The references of the
//! three backends are then compared with each other (channel means), which shows that the
//! curves time the same physics.
//!
//! Time is wall-clock, as a user sees it: every render is a whole `Backend::render` call
//! (a fresh Python process for Mitsuba and Cycles; for native, the scene, BVH and texture bake
//! are rebuilt each time). A least-squares fit `t = t₀ + k·spp` over all renders splits it into
//! a fixed start-up cost `t₀` and a cost per sample `k`; `k` × threads / pixels is the cost per
//! path in core-µs. The spp needed to reach each of [`TARGETS`] is interpolated log-log between
//! the bracketing points (extrapolated with RMSE ∝ spp^-½ past the last one, and marked so).
//! The report gives, per backend and target, the time with and without start-up, and native's
//! speed-up over the faster of the other two.
//!
//! | setting | quick (`--quick`) | full |
//! |---|---|---|
//! | scenes | the two benchmark scenes below, `scenarios/*.toml`, `scenarios/lessons/*.toml` | the same |
//! | size | 48 px wide (each camera scaled, aspect kept) | 128 px wide |
//! | spp of the curve | 1, 4 | 1, 8, 64 |
//! | reference | 2 × 32 spp | 2 × 256 spp |
//! | poses | the first | the first |
//! | native | the scene's own daylight estimator; where the water column lights it, a second curve `native_traced` (`render.daylight = "traced"`, `render.bounces = 1000`: the converged brute force) whose reference measures the column's bias ([`Bias`]), counted in the column's error ([`Curve::count_bias`]) | the same |
//!
//! The two benchmark scenes isolate the estimators:
//!
//! | scene | content |
//! |---|---|
//! | `strobe_backscatter` | bounces = 1 (direct light and single scattering); camera in air behind a flat PMMA port; scattering and absorbing water (σa = 0.40/0.10/0.05, σs = 0.08/0.10/0.12 1/m, HG g = 0.9); a rig strobe in the water; a diffuse back plane 3 m away and three boxes |
//! | `clear_strobe` | the same without scattering (σs = 0) and with bounces = 4: absorption, interreflection and the port only |
//!
//! A backend that refuses a scene (caustics) or fails is reported as such, and the others go
//! on. A scene black at its first pose is reported, with no curve.

use crate::backend::{Backend, RenderOptions};
use crate::model::*;
use glam::{DMat3, DVec3};
use std::path::Path;

/// Relative RMSEs the report times each backend to.
pub const TARGETS: [f64; 2] = [0.05, 0.02];

/// The size and sampling of a run (see the module table).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Form {
    /// Width of every camera's image, px (the height keeps the aspect).
    pub width: u32,
    /// Samples per pixel of each of the two renders of a reference.
    pub reference_spp: u32,
    /// The spp of the measured curve.
    pub spps: Vec<u32>,
}

impl Form {
    pub fn new(quick: bool) -> Form {
        if quick {
            Form {
                width: 48,
                reference_spp: 32,
                spps: vec![1, 4],
            }
        } else {
            Form {
                width: 128,
                reference_spp: 256,
                spps: vec![1, 8, 64],
            }
        }
    }
}

/// The benchmark scenes (see the module table), at `width`×`height`.
pub fn bench_models(width: u32, height: u32) -> Vec<Model> {
    let scattering = bench_model(width, height);
    let mut clear = scattering.clone();
    clear.name = "clear_strobe".into();
    clear.description = "benchmark: strobe through a flat port in clear, absorbing water".into();
    clear.source = "bench/clear_strobe.toml".into();
    if let Some(w) = clear.water.as_mut() {
        w.scattering = [0.0; 3];
    }
    clear.render.max_bounces = 4;
    vec![scattering, clear]
}

/// The benchmark scene (see the module table).
pub fn bench_model(width: u32, height: u32) -> Model {
    let f = 140.0 * width as f64 / 160.0;
    // Camera looking along +y world: x right = +x, y down = -z, z forward = +y.
    let rot = DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y);
    let rig = Pose {
        rotation: rot,
        translation: DVec3::new(0.0, -0.05, -5.0),
    };
    let lambert = |a: [f64; 3]| Material {
        albedo: a,
        pattern: None,
        variation: 0.0,
        texel: None,
        grid: None,
        glass: None,
        fill: None,
    };
    let boxed = |name: &str, at: DVec3, size: f64, a: [f64; 3]| Object {
        name: name.into(),
        shape: Shape::Box {
            size: DVec3::splat(size),
        },
        pose: Pose {
            rotation: DMat3::from_rotation_z(0.5),
            translation: at,
        },
        scale: DVec3::ONE,
        material: lambert(a),
        backdrop: false,
    };
    Model {
        name: "strobe_backscatter".into(),
        description: "benchmark: strobe backscatter through a flat port".into(),
        source: "bench/strobe_backscatter.toml".into(),
        water: Some(Water {
            ior: [1.33; 3],
            ior_source: IorSource::Constant,
            absorption: [0.40, 0.10, 0.05],
            scattering: [0.08, 0.10, 0.12],
            jerlov: None,
            phase: Phase::HenyeyGreenstein { g: 0.9 },
            extent: WaterExtent::Everywhere,
        }),
        site: Site {
            depth: 20.0,
            surface: SeaSurface::None,
            altitude: 0.0,
            seed: 0,
        },
        sun: None,
        cameras: vec![Camera {
            name: "cam".into(),
            width,
            height,
            pixel_pitch: 5e-6,
            focal_length: f * 5e-6,
            fx: f,
            fy: f,
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
            lens: LensModel::Rectilinear,
            distortion: Distortion::default(),
            focus_distance: None,
            f_number: None,
            port: Port::Flat {
                normal: DVec3::Z,
                distance: 0.03,
                thickness: 0.012,
                glass: Glass {
                    name: "PMMA".into(),
                    ior: [1.49; 3],
                },
                outer_layers: vec![],
            },
            rig_from_camera: Pose::IDENTITY,
        }],
        lights: vec![Light {
            name: "strobe".into(),
            mount: Mount::Rig,
            kind: LightKind::Point {
                position: DVec3::new(0.4, -0.2, 0.2),
                intensity: [4.0; 3],
            },
        }],
        objects: vec![
            Object {
                name: "back".into(),
                shape: Shape::Plane {
                    width: 8.0,
                    height: 6.0,
                },
                pose: Pose {
                    rotation: DMat3::from_cols(DVec3::X, DVec3::Z, -DVec3::Y),
                    translation: DVec3::new(0.0, 3.0, -5.0),
                },
                scale: DVec3::ONE,
                material: lambert([0.5; 3]),
                backdrop: false,
            },
            boxed("box_a", DVec3::new(-0.6, 1.5, -5.4), 0.4, [0.8, 0.3, 0.2]),
            boxed("box_b", DVec3::new(0.5, 2.0, -4.8), 0.5, [0.2, 0.7, 0.3]),
            boxed("box_c", DVec3::new(0.0, 2.5, -5.8), 0.6, [0.3, 0.4, 0.8]),
        ],
        targets: vec![],
        poses: vec![RigPose {
            name: "bench".into(),
            world_from_rig: rig,
            time: 0.0,
            strip: 0,
        }],
        network: NetworkSummary::default(),
        diver: None,
        render: RenderSettings {
            samples: 16,
            seed: 1,
            max_bounces: 1,
            dispersion: false,
            outputs: vec!["rgb".into()],
            exposure: 1.0,
            denoise_radius: None,
            noise: None,
            // The benchmark isolates the traced estimators.
            daylight: crate::model::Daylight::Traced,
            texture_filter: Default::default(),
            sampler: Default::default(),
            surface_from_below: Default::default(),
            crop: None,
        },
        sensor: None,
        lesson: None,
        needs: Needs {
            medium: true,
            refraction: true,
            reasons: vec!["benchmark scene".into()],
            ..Needs::default()
        },
    }
}

fn mean_of(img: &[f32]) -> f64 {
    img.iter().map(|&v| v as f64).sum::<f64>() / img.len().max(1) as f64
}

/// Mean squared difference of two images (all channels).
pub fn mse(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum::<f64>()
        / n
}

/// Relative RMSE of `img` against `reference` (all channels), normalised by the reference mean.
pub fn relative_rmse(img: &[f32], reference: &[f32]) -> f64 {
    mse(img, reference).sqrt() / mean_of(reference).max(1e-300)
}

/// A converged reference: the average of two independent renders.
pub struct Reference {
    pub image: Vec<f32>,
    /// MSE(a, b) / 4: the variance left in the averaged image.
    pub residual_mse: f64,
    pub mean: f64,
}

impl Reference {
    pub fn new(a: &[f32], b: &[f32]) -> Reference {
        let image: Vec<f32> = a.iter().zip(b).map(|(&x, &y)| 0.5 * (x + y)).collect();
        let mean = mean_of(&image);
        Reference {
            residual_mse: mse(a, b) / 4.0,
            mean,
            image,
        }
    }
    /// Relative RMSE of `img` with the reference's own noise removed (never below 0).
    pub fn error_of(&self, img: &[f32]) -> f64 {
        (mse(img, &self.image) - self.residual_mse).max(0.0).sqrt() / self.mean.max(1e-300)
    }
    /// Relative RMSE of the reference's remaining noise.
    pub fn residual(&self) -> f64 {
        self.residual_mse.sqrt() / self.mean.max(1e-300)
    }
}

/// One measured point of a speed/error curve.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Point {
    pub spp: u32,
    pub seconds: f64,
    pub rmse: f64,
}

/// Least-squares fit `seconds = t0 + k·spp` (t0 clamped to ≥ 0); returns (t0, k).
pub fn fit_cost(samples: &[(f64, f64)]) -> (f64, f64) {
    let n = samples.len() as f64;
    if samples.is_empty() {
        return (0.0, 0.0);
    }
    let (sx, sy) = samples
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = samples.iter().map(|&(x, _)| (x - mx).powi(2)).sum();
    let sxy: f64 = samples.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    if sxx <= 0.0 {
        return (0.0, my / mx.max(1e-300));
    }
    let k = sxy / sxx;
    let t0 = my - k * mx;
    if t0 < 0.0 || k <= 0.0 {
        // Through the origin.
        let sxy0: f64 = samples.iter().map(|&(x, y)| x * y).sum();
        let sxx0: f64 = samples.iter().map(|&(x, _)| x * x).sum();
        return (0.0, sxy0 / sxx0.max(1e-300));
    }
    (t0, k)
}

/// Samples per pixel needed to reach `target`: log-log interpolation between the bracketing
/// points, or RMSE ∝ spp^-½ from the nearest end point outside them. Returns (spp, extrapolated).
pub fn spp_to(points: &[Point], target: f64) -> Option<(f64, bool)> {
    let usable: Vec<&Point> = points.iter().filter(|p| p.rmse > 0.0).collect();
    let first = *usable.first()?;
    if first.rmse <= target {
        return Some((
            first.spp as f64 * (first.rmse / target).powi(2),
            first.spp > 1,
        ));
    }
    for w in usable.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b.rmse <= target {
            let (la, lb) = (a.rmse.ln(), b.rmse.ln());
            if (la - lb).abs() < 1e-12 {
                return Some((b.spp as f64, false));
            }
            let f = (la - target.ln()) / (la - lb);
            let ls = (a.spp as f64).ln() + f * ((b.spp as f64).ln() - (a.spp as f64).ln());
            return Some((ls.exp(), false));
        }
    }
    let last = *usable.last()?;
    Some((last.spp as f64 * (last.rmse / target).powi(2), true))
}

/// What one backend needs to reach one target error.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ToTarget {
    /// The target relative RMSE.
    pub rmse: f64,
    /// spp needed, and whether it was extrapolated past the last measured point.
    pub spp: f64,
    pub extrapolated: bool,
    /// Wall-clock seconds, with the start-up cost and without it.
    pub seconds: f64,
    pub render_seconds: f64,
}

/// One backend's curve on one scene.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Curve {
    pub backend: String,
    /// Why the backend could not render the scene, when it could not.
    pub error: Option<String>,
    pub reference_spp: u32,
    /// Wall-clock seconds of one reference render.
    pub reference_seconds: f64,
    /// Relative RMSE left in the averaged reference.
    pub reference_residual: f64,
    /// Per-channel means of the reference, linear radiance.
    pub reference_means: [f64; 3],
    /// Standard error of each of those means (from the two renders' per-pixel difference).
    #[serde(default)]
    pub reference_mean_se: [f64; 3],
    /// The native renderer's daylight estimator in this curve (`column` or `traced`; empty for
    /// the other backends).
    #[serde(default)]
    pub daylight: String,
    /// For native lit by the water column: its mean's difference from the brute-force
    /// reference (native, traced), counted in its error ([`Curve::count_bias`]).
    #[serde(default)]
    pub bias: Option<Bias>,
    pub points: Vec<Point>,
    /// Fixed start-up seconds and seconds per spp of the fit `t = t0 + k·spp`.
    pub startup_seconds: f64,
    pub seconds_per_spp: f64,
    /// Cost per path (one sample of one pixel), core-µs: `k` × threads / pixels.
    pub core_us_per_path: f64,
    /// One entry per [`TARGETS`] it has a curve for, in order.
    pub to_target: Vec<ToTarget>,
}

impl Curve {
    fn empty(backend: &str, reference_spp: u32) -> Curve {
        Curve {
            backend: backend.into(),
            error: None,
            reference_spp,
            reference_seconds: 0.0,
            reference_residual: 0.0,
            reference_means: [0.0; 3],
            reference_mean_se: [0.0; 3],
            daylight: String::new(),
            bias: None,
            points: vec![],
            startup_seconds: 0.0,
            seconds_per_spp: 0.0,
            core_us_per_path: 0.0,
            to_target: vec![],
        }
    }

    /// Its entry for `target`, if it has one.
    pub fn at(&self, target: f64) -> Option<&ToTarget> {
        self.to_target.iter().find(|t| t.rmse == target)
    }

    /// Whether the measured noise is too heavy-tailed for the extrapolation to be trusted:
    /// the error did not fall at every step of the curve, or the reference's own remaining
    /// noise is more than half the last point's error (with finite per-pixel variance it is
    /// √(spp / 2·reference spp) of it: 0.35 at 64 against 2 × 256). Rare, very bright paths
    /// (fireflies) do both.
    pub fn heavy_tailed(&self) -> bool {
        let falls = self.points.windows(2).all(|w| w[1].rmse < w[0].rmse);
        let last = self.points.last().map_or(0.0, |p| p.rmse);
        !falls || self.reference_residual > 0.5 * last
    }

    /// Count a bias against the brute-force reference in the error: the error at `spp` is
    /// √(noise(spp)² + b²), `b` the bias's RMS over the channels, so a target `e` needs the
    /// noise to reach √(e² − b²); a target at or under `b` is never reached (no entry).
    pub fn count_bias(&mut self, bias: Bias) {
        let b = bias.rms();
        self.to_target.clear();
        for target in TARGETS {
            if target <= b {
                continue;
            }
            let noise = (target * target - b * b).sqrt();
            if let Some((spp, extrapolated)) = spp_to(&self.points, noise) {
                self.to_target.push(ToTarget {
                    rmse: target,
                    spp,
                    extrapolated,
                    seconds: self.startup_seconds + self.seconds_per_spp * spp,
                    render_seconds: self.seconds_per_spp * spp,
                });
            }
        }
        self.bias = Some(bias);
    }
}

/// The difference of a column-lit native reference's channel means from the brute-force
/// (traced) reference's, with its standard error (both references' noise). Only the image
/// means are compared: a brute-force reference of the deep sky-lit scenes keeps 30–70 % noise
/// per pixel at 2 × 256 spp, but its mean is known to about 1 %.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bias {
    /// Per channel, relative to the traced channel's mean.
    pub relative: [f64; 3],
    /// Standard error of each of those.
    pub se: [f64; 3],
    /// The bias as the error measures it: √(mean over channels of (difference of the means)²)
    /// over the traced image's mean, as a relative RMSE normalises (a near-black channel's
    /// large relative bias weighs what its light weighs).
    #[serde(default)]
    pub rmse: f64,
    /// Its standard error.
    #[serde(default)]
    pub rmse_se: f64,
}

impl Bias {
    /// `column`'s reference means against `traced`'s (`None` where a traced mean is 0).
    pub fn between(column: &Curve, traced: &Curve) -> Option<Bias> {
        let (c, t) = (column.reference_means, traced.reference_means);
        if t.iter().any(|&m| m <= 0.0) {
            return None;
        }
        let (cs, ts) = (column.reference_mean_se, traced.reference_mean_se);
        let mean = t.iter().sum::<f64>() / 3.0;
        let abs_se: [f64; 3] = std::array::from_fn(|i| (cs[i].powi(2) + ts[i].powi(2)).sqrt());
        Some(Bias {
            relative: std::array::from_fn(|i| c[i] / t[i] - 1.0),
            se: std::array::from_fn(|i| {
                ((cs[i] / t[i]).powi(2) + (c[i] * ts[i] / (t[i] * t[i])).powi(2)).sqrt()
            }),
            rmse: ((0..3).map(|i| (c[i] - t[i]).powi(2)).sum::<f64>() / 3.0).sqrt() / mean,
            rmse_se: (abs_se.iter().map(|s| s * s).sum::<f64>() / 3.0).sqrt() / mean,
        })
    }

    /// The bias counted in the error: [`Bias::rmse`]. The references' noise is not taken off:
    /// what is counted is at most the bias plus that noise (conservative).
    pub fn rms(&self) -> f64 {
        self.rmse
    }

    /// "−1.2, +0.4, +0.9 % (± 0.6)": per channel, with the largest standard error.
    pub fn text(&self) -> String {
        let se = self.se.iter().copied().fold(0.0, f64::max);
        let v: Vec<String> = self
            .relative
            .iter()
            .map(|b| format!("{:+.1}", 100.0 * b))
            .collect();
        format!("{} % (± {:.1})", v.join(", "), 100.0 * se)
    }
}

/// One scene's results.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SceneReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub max_bounces: u32,
    /// Set when the scene is black at its first pose in every backend (no curves).
    pub dark: bool,
    pub curves: Vec<Curve>,
}

/// Whole report.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Report {
    pub form: Form,
    pub targets: Vec<f64>,
    pub threads: usize,
    pub scenes: Vec<SceneReport>,
}

/// A scene to benchmark: its name and its model at the run's size.
pub struct BenchScene {
    pub name: String,
    pub model: Model,
}

/// The scenes of a run: the two benchmark scenes, then every shipped scene (or those whose
/// file name contains `only`), each scaled to `width` px and reduced to its first pose.
pub fn scenes(root: &Path, width: u32, only: Option<&str>) -> Result<Vec<BenchScene>, String> {
    let mut out = Vec::new();
    let keep = |name: &str| only.is_none_or(|o| name.contains(o));
    for m in bench_models(width, width * 3 / 4) {
        if keep(&m.name) {
            out.push(BenchScene {
                name: m.name.clone(),
                model: m,
            });
        }
    }
    for path in crate::bench::parity::shipped_scenes(root) {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !keep(&name) {
            continue;
        }
        let mut model = crate::scene::load(&path, &[])
            .map_err(|f| f.render())?
            .model;
        let w0 = model.cameras.first().map_or(width, |c| c.width).max(1);
        model = model.with_resolution_scale(width as f64 / w0 as f64);
        model.poses.truncate(1);
        out.push(BenchScene { name, model });
    }
    Ok(out)
}

/// Pixels of one rig pose: every camera's.
fn pixels_per_pose(model: &Model) -> f64 {
    model
        .cameras
        .iter()
        .map(|c| c.width as f64 * c.height as f64)
        .sum::<f64>()
        .max(1.0)
}

fn render_rgb(
    backend: Backend,
    model: &Model,
    spp: u32,
    dir: &Path,
) -> Result<(Vec<f32>, f64), String> {
    let opts = RenderOptions {
        samples: Some(spp),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    let t0 = std::time::Instant::now();
    let report = backend.render(model, dir, &opts)?;
    let secs = t0.elapsed().as_secs_f64().max(report.seconds);
    let path = dir.join(format!("{}.exr", model.image_name(0, 0)));
    let img = crate::compare::LinearImage::read(&path)?;
    Ok((img.rgb.into_flattened(), secs))
}

/// Standard error of each channel's mean of the average of two independent RGB renders: per
/// pixel the average's variance is (a − b)² / 4.
fn mean_se(a: &[f32], b: &[f32]) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        sum[k % 3] += (*x as f64 - *y as f64).powi(2) / 4.0;
    }
    let n = (a.len() / 3).max(1) as f64;
    sum.map(|s| s.sqrt() / n)
}

/// Below this reference mean an image counts as black (nothing reaches the camera).
const DARK: f64 = 1e-9;
/// The error of a curve on a scene black at its first pose.
const BLACK: &str = "black at the first pose";
/// The start of the error of a backend that refuses a scene.
const REFUSED: &str = "refused: ";

/// The curves of one backend on one scene: one ([`curve`]), or for native lit by the water
/// column two: the column (the scene's default, its bias against the other counted in its
/// error) and the brute force (`render.daylight = "traced"`, `render.bounces` =
/// [`TRACED_BOUNCES`], named `native_traced`).
fn curves_of(backend: Backend, model: &Model, form: &Form, threads: usize) -> Vec<Curve> {
    if backend != Backend::Native {
        return vec![curve(backend, backend.name(), model, form, threads)];
    }
    let seen = crate::geometry::seen::views_past_seabed(model);
    let column = model.daylight_choice(seen).0.is_some();
    let mut native = curve(backend, backend.name(), model, form, threads);
    native.daylight = if column { "column" } else { "traced" }.into();
    if !column {
        return vec![native];
    }
    let mut m = model.clone();
    m.render.daylight = crate::model::Daylight::Traced;
    m.render.max_bounces = TRACED_BOUNCES;
    let mut traced = curve(backend, TRACED, &m, form, threads);
    traced.daylight = "traced".into();
    let mut sc = SceneReport {
        scene: String::new(),
        width: 0,
        height: 0,
        max_bounces: 0,
        dark: false,
        curves: vec![native, traced],
    };
    sc.count_bias();
    sc.curves
}

/// The name of native's brute-force curve beside its column-lit one.
pub const TRACED: &str = "native_traced";

/// `render.bounces` of the brute-force curve: high enough that no light is cut off (as
/// `poser bench column`'s reference), so that it measures the column's bias, not the scene's
/// bounce limit (flat_port_deformation's 5 cut 2 % of its blue).
pub const TRACED_BOUNCES: u32 = 1000;

/// One backend's curve on one scene (`name` in the report): two references, then the form's
/// spp in turn (stopping once the error is under half the smallest target).
fn curve(backend: Backend, name: &str, model: &Model, form: &Form, threads: usize) -> Curve {
    let mut c = Curve::empty(name, form.reference_spp);
    let run = |c: &mut Curve| -> Result<(), String> {
        let tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
        // A backend that does not take the scene says so when it compiles it (not timed);
        // `Backend::compile` runs `Backend::refuse` first.
        if backend != Backend::Native {
            backend
                .compile(model, &tmp.path().join("compiled"))
                .map_err(|e| format!("{REFUSED}{e}"))?;
        }
        let mut timings = Vec::new();
        let mut refs = Vec::new();
        let ref_spp = form.reference_spp;
        for (k, seed) in [9_999u64, 19_999].into_iter().enumerate() {
            let mut m = model.clone();
            m.render.seed = seed;
            let dir = tmp.path().join(format!("ref{k}"));
            let (img, secs) = render_rgb(backend, &m, ref_spp, &dir)?;
            eprintln!("  {name:>13} reference {k}: {ref_spp} spp {secs:8.2} s");
            timings.push((ref_spp as f64, secs));
            c.reference_seconds = secs;
            refs.push(img);
        }
        let reference = Reference::new(&refs[0], &refs[1]);
        c.reference_residual = reference.residual();
        c.reference_means = crate::compare::channel_means(&reference.image);
        c.reference_mean_se = mean_se(&refs[0], &refs[1]);
        if reference.mean < DARK {
            return Err(BLACK.into());
        }
        let smallest = TARGETS.iter().copied().fold(f64::INFINITY, f64::min);
        for &spp in &form.spps {
            let dir = tmp.path().join(format!("s{spp}"));
            let (img, secs) = render_rgb(backend, model, spp, &dir)?;
            let rmse = reference.error_of(&img);
            eprintln!("  {name:>13} {spp:>5} spp  {secs:>8.3} s  rel. RMSE {rmse:.4}");
            timings.push((spp as f64, secs));
            c.points.push(Point {
                spp,
                seconds: secs,
                rmse,
            });
            if rmse < 0.5 * smallest {
                break;
            }
        }
        let (t0, k) = fit_cost(&timings);
        c.startup_seconds = t0;
        c.seconds_per_spp = k;
        c.core_us_per_path = k * threads as f64 * 1e6 / pixels_per_pose(model);
        for target in TARGETS {
            if let Some((spp, extrapolated)) = spp_to(&c.points, target) {
                c.to_target.push(ToTarget {
                    rmse: target,
                    spp,
                    extrapolated,
                    seconds: t0 + k * spp,
                    render_seconds: k * spp,
                });
            }
        }
        Ok(())
    };
    if let Err(e) = run(&mut c) {
        c.error = Some(e);
    }
    c
}

/// The name a report gives a backend.
fn display(backend: &str) -> &str {
    match backend {
        "mitsuba" => "Mitsuba",
        "blender" => "Cycles",
        TRACED => "native, traced",
        other => other,
    }
}

/// Seconds with three significant figures at most.
fn fmt_s(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn times(v: Option<f64>) -> String {
    v.map(|r| format!("{r:.1}×")).unwrap_or_else(|| "–".into())
}

impl SceneReport {
    /// Where native was lit by the water column and timed by brute force too, count the
    /// column's bias against the brute force in its error ([`Curve::count_bias`]).
    pub fn count_bias(&mut self) {
        let ok = |c: &Curve| c.error.is_none();
        let Some(t) = self
            .curves
            .iter()
            .position(|c| c.backend == TRACED && ok(c))
        else {
            return;
        };
        let Some(n) = self
            .curves
            .iter()
            .position(|c| c.backend == "native" && c.daylight == "column" && ok(c))
        else {
            return;
        };
        if let Some(b) = Bias::between(&self.curves[n], &self.curves[t]) {
            self.curves[n].count_bias(b);
        }
    }

    /// The native curve (the scene's own daylight estimator), when it rendered.
    fn native(&self) -> Option<&Curve> {
        self.curves
            .iter()
            .find(|c| c.backend == "native" && c.error.is_none())
    }

    /// native's speed-up to `target` over the faster of Mitsuba and Cycles: (wall, render
    /// only).
    pub fn speedup(&self, target: f64) -> (Option<f64>, Option<f64>) {
        let ok = |c: &&Curve| c.error.is_none();
        let native = self
            .curves
            .iter()
            .filter(ok)
            .find(|c| c.backend == "native");
        let others: Vec<&Curve> = self
            .curves
            .iter()
            .filter(ok)
            .filter(|c| c.backend != "native" && c.backend != TRACED)
            .collect();
        let best = |f: fn(&ToTarget) -> f64| -> Option<f64> {
            let n = f(native?.at(target)?);
            let o = others
                .iter()
                .filter_map(|c| c.at(target).map(f))
                .fold(f64::INFINITY, f64::min);
            (o.is_finite() && n > 0.0).then(|| o / n)
        };
        (best(|t| t.seconds), best(|t| t.render_seconds))
    }

    /// Markdown: the curves, then the agreement of the references.
    pub fn to_markdown(&self, targets: &[f64]) -> String {
        let mut s = format!(
            "### `{}` ({}×{}, bounces = {})\n\n",
            self.scene, self.width, self.height, self.max_bounces
        );
        if self.dark {
            s += "Black at the first pose in every backend: nothing to time.\n";
            return s;
        }
        let heads: Vec<String> = targets
            .iter()
            .map(|t| format!("to {:.0} %: spp, s, s w/o start-up", 100.0 * t))
            .collect();
        s += &format!(
            "| backend | {} | start-up (s) | s per spp | core-µs per path | curve (spp: s, RMSE) |\n|---|{}---|---|---|---|\n",
            heads.join(" | "),
            "---|".repeat(targets.len())
        );
        for c in &self.curves {
            if let Some(e) = &c.error {
                let first = e.lines().next().unwrap_or("").replace('|', "/");
                let gap = " |".repeat(targets.len() + 4);
                s += &format!("| {} | {first}{gap}\n", display(&c.backend));
                continue;
            }
            let cols: Vec<String> = targets
                .iter()
                .map(|&t| match c.at(t) {
                    Some(x) => format!(
                        "{:.1}{}, {}, {}",
                        x.spp,
                        if x.extrapolated { " (extrap.)" } else { "" },
                        fmt_s(x.seconds),
                        fmt_s(x.render_seconds)
                    ),
                    None => "–".into(),
                })
                .collect();
            let pts: Vec<String> = c
                .points
                .iter()
                .map(|p| format!("{}: {:.2}, {:.3}", p.spp, p.seconds, p.rmse))
                .collect();
            s += &format!(
                "| {}{} | {} | {:.2} | {:.4} | {:.2} | {} |\n",
                display(&c.backend),
                if c.heavy_tailed() { " †" } else { "" },
                cols.join(" | "),
                c.startup_seconds,
                c.seconds_per_spp,
                c.core_us_per_path,
                pts.join("; ")
            );
        }
        s += "\n";
        for &t in targets {
            let (wall, render) = self.speedup(t);
            s += &format!(
                "native's speed-up over the faster of the others to {:.0} %: {} wall-clock, {} without start-up.\n",
                100.0 * t,
                times(wall),
                times(render)
            );
        }
        if let Some(b) = self.native().and_then(|c| c.bias) {
            s += &format!(
                "native lit by the water column, its mean against native traced (brute force): {}; counted in its error as {:.2} % (± {:.2}).\n",
                b.text(),
                100.0 * b.rmse,
                100.0 * b.rmse_se
            );
        }
        s += "\n| backend | reference | residual noise | mean R, G, B | vs native |\n|---|---|---|---|---|\n";
        let native = self
            .curves
            .iter()
            .find(|c| c.backend == "native" && c.error.is_none())
            .map(|c| c.reference_means);
        for c in self.curves.iter().filter(|c| c.error.is_none()) {
            let m = c.reference_means;
            let vs = match native {
                Some(n) if c.backend != "native" => {
                    let d: Vec<String> = (0..3)
                        .map(|i| {
                            if n[i] > 0.0 {
                                format!("{:+.1} %", 100.0 * (m[i] / n[i] - 1.0))
                            } else {
                                "–".into()
                            }
                        })
                        .collect();
                    d.join(", ")
                }
                _ => "–".into(),
            };
            s += &format!(
                "| {} | 2 × {} spp ({} s each) | {:.2} % | {:.4}, {:.4}, {:.4} | {vs} |\n",
                display(&c.backend),
                c.reference_spp,
                fmt_s(c.reference_seconds),
                100.0 * c.reference_residual,
                m[0],
                m[1],
                m[2]
            );
        }
        s
    }
}

/// The first and last lines of the README's generated block.
pub const README_BEGIN: &str =
    "<!-- generated by `poser bench render --readme README.md`: begin -->";
pub const README_END: &str = "<!-- generated by `poser bench render --readme README.md`: end -->";

impl Report {
    /// Count each scene's column bias in its native curve again ([`SceneReport::count_bias`]):
    /// a report saved before a change of how the bias is counted reads as a new run would.
    pub fn count_biases(&mut self) {
        for sc in &mut self.scenes {
            sc.count_bias();
        }
    }

    /// The summary table, one row per scene: each backend's wall-clock seconds to each
    /// target, native's cost per path, and native's speed-up to the last target.
    pub fn summary(&self) -> String {
        let ts: Vec<String> = self
            .targets
            .iter()
            .map(|t| format!("{:.0} %", 100.0 * t))
            .collect();
        let ts = ts.join(" / ");
        let last = self.targets.last().copied().unwrap_or(0.0);
        let mut s = format!(
            "| scene | size | native daylight | native, s to {ts} | native traced, s to {ts} | Mitsuba, s to {ts} | Cycles, s to {ts} | column's mean vs traced (R, G, B; bias counted) | native core-µs per path | native's speed-up to {:.0} %, wall (render only) |\n|---|---|---|---|---|---|---|---|---|---|\n",
            100.0 * last
        );
        for sc in &self.scenes {
            let size = format!("{}×{}", sc.width, sc.height);
            if sc.dark {
                s += &format!("| `{}` | {size} | {BLACK} | | | | | | | |\n", sc.scene);
                continue;
            }
            let native = sc.curves.iter().find(|c| c.backend == "native");
            let daylight = native.map_or("–", |c| {
                if c.daylight.is_empty() {
                    "–"
                } else {
                    &c.daylight
                }
            });
            let col = |b: &str| -> String {
                let Some(c) = sc.curves.iter().find(|c| c.backend == b) else {
                    return if b == TRACED && native.is_some_and(|c| c.daylight == "traced") {
                        "as native".into()
                    } else {
                        "not run".into()
                    };
                };
                if let Some(e) = &c.error {
                    return if e.starts_with(REFUSED) {
                        "refused".into()
                    } else {
                        "failed".into()
                    };
                }
                let heavy = if c.heavy_tailed() { "†" } else { "" };
                let v: Vec<String> = self
                    .targets
                    .iter()
                    .map(|&t| match c.at(t) {
                        Some(x) => {
                            let extra = if x.extrapolated { "*" } else { "" };
                            format!("{}{extra}{heavy}", fmt_s(x.seconds))
                        }
                        None => "–".into(),
                    })
                    .collect();
                v.join(" / ")
            };
            let us = sc
                .native()
                .map_or("–".into(), |c| format!("{:.1}", c.core_us_per_path));
            let traced_heavy = sc
                .curves
                .iter()
                .any(|c| c.backend == TRACED && c.error.is_none() && c.heavy_tailed());
            let bias = sc.native().and_then(|c| c.bias).map_or("–".into(), |b| {
                format!(
                    "{}; {:.1} %{}",
                    b.text(),
                    100.0 * b.rmse,
                    if traced_heavy { " †" } else { "" }
                )
            });
            let (wall, render) = sc.speedup(last);
            let heavy = sc
                .curves
                .iter()
                .any(|c| c.error.is_none() && c.heavy_tailed());
            s += &format!(
                "| `{}` | {size} | {daylight} | {} | {} | {} | {} | {bias} | {us} | {} ({}){} |\n",
                sc.scene,
                col("native"),
                col(TRACED),
                col("mitsuba"),
                col("blender"),
                times(wall),
                times(render),
                if heavy && wall.is_some() { " †" } else { "" }
            );
        }
        s += "\n\\* extrapolated past the last measured point with RMSE ∝ spp^-½. \
              † heavy-tailed noise (fireflies): the error did not fall at every step, or the \
              reference is not converged enough to measure it; the time is an order of \
              magnitude, not a measurement. native renders each scene with its own daylight \
              estimator: the water column where it applies, else traced. The column's mean is \
              compared with the brute-force render's (per channel, ± the standard error) and \
              the difference is counted in its error as a relative RMSE (after the \
              semicolon): a target below it is never reached (–); † on it: the brute-force \
              reference is heavy-tailed, so part of that difference is the reference's \
              shortfall, not the column's bias.\n";
        s
    }

    /// The README's block: the markers around a line on the run and the summary.
    pub fn readme_block(&self) -> String {
        format!(
            "{README_BEGIN}\n{} threads; every camera {} px wide; first pose; wall-clock seconds to a relative RMSE, start-up included.\n\n{}{README_END}",
            self.threads,
            self.form.width,
            self.summary()
        )
    }

    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "Render speed against error ({} threads; times are wall-clock; every camera {} px wide; first pose; references 2 × {} spp).\n\n{}\n",
            self.threads,
            self.form.width,
            self.form.reference_spp,
            self.summary()
        );
        for sc in &self.scenes {
            s += &sc.to_markdown(&self.targets);
            s += "\n";
        }
        s
    }

    /// Log-log plots of error against wall-clock time, one panel per scene, four to a row.
    pub fn plot_svg(&self) -> Result<String, String> {
        crate::plan::plot::register_font()?;
        use plotters::prelude::*;
        const COLS: usize = 4;
        let mut buf = String::new();
        {
            let n = self.scenes.len().max(1);
            let rows = n.div_ceil(COLS);
            let cols = n.min(COLS);
            let root = SVGBackend::with_string(&mut buf, (420 * cols as u32, 320 * rows as u32))
                .into_drawing_area();
            root.fill(&WHITE).map_err(|e| e.to_string())?;
            let panels = root.split_evenly((rows, cols));
            let colour = |b: &str| match b {
                "native" => RGBColor(200, 40, 40),
                TRACED => RGBColor(110, 20, 90),
                "mitsuba" => RGBColor(20, 80, 200),
                _ => RGBColor(230, 130, 20),
            };
            for (sc, area) in self.scenes.iter().zip(panels.iter()) {
                let pts = sc.curves.iter().flat_map(|c| c.points.iter());
                let (mut tmin, mut tmax, mut emin, mut emax) = (f64::MAX, 0f64, f64::MAX, 0f64);
                for p in pts.filter(|p| p.rmse > 0.0 && p.seconds > 0.0) {
                    tmin = tmin.min(p.seconds);
                    tmax = tmax.max(p.seconds);
                    emin = emin.min(p.rmse);
                    emax = emax.max(p.rmse);
                }
                if tmax <= 0.0 {
                    continue;
                }
                for &t in &self.targets {
                    emin = emin.min(t);
                    emax = emax.max(t);
                }
                let (emin, emax) = (emin * 0.8, emax * 1.25);
                let (t0, t1) = (tmin * 0.8, tmax * 1.25);
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!("{} ({}×{})", sc.scene, sc.width, sc.height),
                        ("sans-serif", 15),
                    )
                    .margin(8)
                    .x_label_area_size(34)
                    .y_label_area_size(48)
                    .build_cartesian_2d((t0..t1).log_scale(), (emin..emax).log_scale())
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc("wall-clock time (s)")
                    .y_desc("relative RMSE")
                    .x_label_formatter(&|v| tick(*v))
                    .y_label_formatter(&|v| tick(*v))
                    .draw()
                    .map_err(|e| e.to_string())?;
                for &target in &self.targets {
                    chart
                        .draw_series(LineSeries::new(
                            [(t0, target), (t1, target)],
                            BLACK.mix(0.35),
                        ))
                        .map_err(|e| e.to_string())?;
                }
                for c in sc.curves.iter().filter(|c| c.error.is_none()) {
                    let col = colour(&c.backend);
                    let line: Vec<(f64, f64)> = c
                        .points
                        .iter()
                        .filter(|p| p.rmse > 0.0 && p.seconds > 0.0)
                        .map(|p| (p.seconds, p.rmse))
                        .collect();
                    chart
                        .draw_series(LineSeries::new(line.clone(), col.stroke_width(2)))
                        .map_err(|e| e.to_string())?
                        .label(display(&c.backend).to_string())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
                    chart
                        .draw_series(line.into_iter().map(|p| Circle::new(p, 3, col.filled())))
                        .map_err(|e| e.to_string())?;
                }
                crate::plan::plot::legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
            }
            root.present().map_err(|e| e.to_string())?;
        }
        Ok(buf)
    }
}

/// An axis label: at most three significant figures, no trailing zeros.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Replace the block from [`README_BEGIN`] to [`README_END`] (markers included) in `text`
/// with `block`.
pub fn replace_block(text: &str, block: &str) -> Result<String, String> {
    let a = text
        .find(README_BEGIN)
        .ok_or_else(|| format!("no line `{README_BEGIN}` to replace from"))?;
    let b = text[a..]
        .find(README_END)
        .map(|i| a + i + README_END.len())
        .ok_or_else(|| format!("no line `{README_END}` after `{README_BEGIN}`"))?;
    Ok(format!("{}{block}{}", &text[..a], &text[b..]))
}

/// Options of the render benchmark.
#[derive(Debug, Clone, Default)]
pub struct BenchOptions {
    pub quick: bool,
    /// Backends to run (default: all).
    pub backends: Vec<Backend>,
    /// Only the scenes whose name contains this.
    pub only: Option<String>,
    pub json: Option<std::path::PathBuf>,
    pub plot: Option<std::path::PathBuf>,
    /// A Markdown file (the README) whose generated block gets the summary.
    pub readme: Option<std::path::PathBuf>,
    /// A saved JSON report to rebuild the outputs from, without rendering (the column's bias
    /// counted again, [`Report::count_biases`]).
    pub from: Option<std::path::PathBuf>,
}

/// Run the render benchmark on the scenes under `root`: prints a Markdown report; writes
/// JSON, an SVG plot and the README's block when asked.
pub fn run(root: &Path, opts: &BenchOptions) -> Result<Report, String> {
    // Check the README's markers before the rendering, not after.
    let readme = match &opts.readme {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            replace_block(&text, "").map_err(|e| format!("{}: {e}", p.display()))?;
            Some((p.clone(), text))
        }
        None => None,
    };
    let report = match &opts.from {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            let mut r: Report =
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))?;
            r.count_biases();
            r
        }
        None => measure(root, opts)?,
    };
    println!("{}", report.to_markdown());
    if let Some(p) = &opts.json {
        let s = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        crate::io::write_atomic(p, s.as_bytes()).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    if let Some(p) = &opts.plot {
        let svg = report.plot_svg()?;
        crate::io::write_atomic(p, svg.as_bytes()).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    if let Some((p, text)) = readme {
        let new = replace_block(&text, &report.readme_block())?;
        crate::io::write_atomic(&p, new.as_bytes()).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(report)
}

/// Render the curves of the run `opts` asks for (see the module table).
fn measure(root: &Path, opts: &BenchOptions) -> Result<Report, String> {
    let form = Form::new(opts.quick);
    let backends: Vec<Backend> = if opts.backends.is_empty() {
        Backend::ALL.to_vec()
    } else {
        opts.backends.clone()
    };
    let threads = rayon::current_num_threads();
    let mut reports = Vec::new();
    for bs in scenes(root, form.width, opts.only.as_deref())? {
        let model = &bs.model;
        let (width, height) = model
            .cameras
            .first()
            .map_or((0, 0), |c| (c.width, c.height));
        let mut curves = Vec::new();
        for b in &backends {
            eprintln!(
                "bench render: {} ({width}×{height}) with {b} (reference 2 × {} spp)",
                bs.name, form.reference_spp
            );
            curves.extend(curves_of(*b, model, &form, threads));
        }
        let dark = curves.iter().any(|c| c.error.as_deref() == Some(BLACK))
            && curves.iter().all(|c| c.error.is_some());
        reports.push(SceneReport {
            scene: bs.name,
            width,
            height,
            max_bounces: model.render.max_bounces,
            dark,
            curves,
        });
    }
    Ok(Report {
        form,
        targets: TARGETS.to_vec(),
        threads,
        scenes: reports,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(spp: u32, rmse: f64) -> Point {
        Point {
            spp,
            seconds: spp as f64,
            rmse,
        }
    }

    #[test]
    fn spp_to_target_interpolates_log_log_and_extrapolates() {
        let pts = vec![pt(1, 0.2), pt(4, 0.1), pt(16, 0.05)];
        // RMSE ∝ spp^-1/2: 0.0707 is reached at spp = 8.
        let (s, extra) = spp_to(&pts, 0.1 / 2f64.sqrt()).unwrap();
        assert!((s - 8.0).abs() < 1e-9 && !extra, "{s}");
        // Past the last point: 0.025 needs 4× the spp of 0.05.
        let (s, extra) = spp_to(&pts, 0.025).unwrap();
        assert!((s - 64.0).abs() < 1e-9 && extra, "{s}");
        // Before the first point at 1 spp: exact by the same law, not extrapolated past data.
        assert_eq!(spp_to(&pts, 0.4), Some((0.25, false)));
        assert_eq!(spp_to(&[], 0.1), None);
    }

    #[test]
    fn rmse_is_relative_and_reference_noise_is_removed() {
        assert!((relative_rmse(&[1.1, 0.9], &[1.0, 1.0]) - 0.1).abs() < 1e-6);
        // Two references 1 ± 0.2: residual MSE = 0.16/4 = 0.04.
        let r = Reference::new(&[1.2, 0.8], &[0.8, 1.2]);
        assert!((r.residual_mse - 0.04).abs() < 1e-6);
        assert!((r.residual() - 0.2).abs() < 1e-6);
        // An image equal to the average has no error beyond the reference's.
        assert_eq!(r.error_of(&[1.0, 1.0]), 0.0);
        // MSE(img, avg) = 0.09 → σ² = 0.05.
        assert!((r.error_of(&[1.3, 0.7]) - 0.05f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn cost_fit_separates_start_up_from_cost_per_sample() {
        let (t0, k) = fit_cost(&[(1.0, 2.01), (4.0, 2.04), (16.0, 2.16), (64.0, 2.64)]);
        assert!(
            (t0 - 2.0).abs() < 1e-9 && (k - 0.01).abs() < 1e-9,
            "{t0} {k}"
        );
        // A negative intercept falls back to a fit through the origin.
        let (t0, k) = fit_cost(&[(1.0, 0.0), (2.0, 2.0)]);
        assert_eq!(t0, 0.0);
        assert!((k - 0.8).abs() < 1e-9, "{k}");
    }

    #[test]
    fn the_scenes_differ_in_what_they_exercise() {
        let m = bench_models(16, 12);
        assert_eq!(m.len(), 2);
        assert!(m[0].water.as_ref().unwrap().scattering[1] > 0.0);
        assert_eq!(m[1].water.as_ref().unwrap().scattering, [0.0; 3]);
        assert!(m[1].render.max_bounces > m[0].render.max_bounces);
        assert_eq!(m[0].port_interfaces(), 2);
    }

    fn curve_to(b: &str, t: f64) -> Curve {
        let mut c = Curve::empty(b, 1);
        c.reference_means = [1.0; 3];
        c.core_us_per_path = 2.5;
        for (rmse, f) in [(0.05, 1.0), (0.02, 6.25)] {
            c.to_target.push(ToTarget {
                rmse,
                spp: f,
                extrapolated: b == "mitsuba",
                seconds: t * f,
                render_seconds: t * f / 2.0,
            });
        }
        c
    }

    fn report() -> Report {
        let sc = SceneReport {
            scene: "s".into(),
            width: 128,
            height: 96,
            max_bounces: 1,
            dark: false,
            curves: vec![
                curve_to("native", 1.0),
                curve_to("mitsuba", 30.0),
                curve_to("blender", 12.0),
            ],
        };
        let mut refused = sc.clone();
        refused.scene = "r".into();
        refused.curves[1].error = Some(format!("{REFUSED}no caustics"));
        refused.curves[1].to_target.clear();
        Report {
            form: Form::new(false),
            targets: TARGETS.to_vec(),
            threads: 2,
            scenes: vec![sc, refused],
        }
    }

    #[test]
    fn speedup_is_against_the_faster_other_backend() {
        let r = report();
        let sc = &r.scenes[0];
        assert_eq!(sc.speedup(0.02), (Some(12.0), Some(12.0)));
        // A backend that failed does not count.
        let mut failed = sc.clone();
        failed.curves[2].error = Some("bpy crashed".into());
        assert_eq!(failed.speedup(0.05), (Some(30.0), Some(30.0)));
        let md = sc.to_markdown(&TARGETS);
        assert!(md.contains("to 2 %: 12.0× wall-clock"), "{md}");
    }

    #[test]
    fn summary_gives_every_backend_and_target_and_marks_refusals_and_extrapolation() {
        let s = report().summary();
        let row = s.lines().find(|l| l.starts_with("| `s` |")).unwrap();
        assert_eq!(
            row,
            "| `s` | 128×96 | – | 1.00 / 6.25 | not run | 30.0* / 188* | 12.0 / 75.0 | – | 2.5 | 12.0× (12.0×) |"
        );
        let row = s.lines().find(|l| l.starts_with("| `r` |")).unwrap();
        assert!(row.contains("| refused |"), "{row}");
    }

    #[test]
    fn readme_block_is_replaced_in_place_and_missing_markers_are_an_error() {
        let r = report();
        let text = format!("# poser\n\nbefore\n{README_BEGIN}\nold\n{README_END}\nafter\n");
        let new = replace_block(&text, &r.readme_block()).unwrap();
        assert!(new.starts_with("# poser\n\nbefore\n"));
        assert!(new.ends_with(&format!("{README_END}\nafter\n")));
        assert!(new.contains("| `s` | 128×96 |") && !new.contains("old"));
        // Idempotent.
        assert_eq!(replace_block(&new, &r.readme_block()).unwrap(), new);
        assert!(replace_block("no markers", "x").is_err());
        assert!(replace_block(README_BEGIN, "x").is_err());
    }

    #[test]
    fn heavy_tailed_noise_is_flagged_from_the_curve_and_the_reference() {
        let mut c = curve_to("native", 1.0);
        c.points = vec![pt(1, 1.0), pt(8, 0.36), pt(64, 0.125)];
        // Finite variance: the reference (2 × 256) keeps 0.35 of the 64-spp error.
        c.reference_residual = 0.044;
        assert!(!c.heavy_tailed());
        // A firefly in the 8-spp image: the error rose.
        c.points[1].rmse = 1.3;
        assert!(c.heavy_tailed());
        c.points[1].rmse = 0.36;
        // The reference is as noisy as the image it measures.
        c.reference_residual = 0.1;
        assert!(c.heavy_tailed());
        let mut r = report();
        r.scenes[0].curves[0] = c;
        let s = r.summary();
        let row = s.lines().find(|l| l.starts_with("| `s` |")).unwrap();
        assert!(row.ends_with("(12.0×) † |"), "{row}");
        assert!(
            row.contains("| 1.00† / 6.25† | not run | 30.0* / 188* |"),
            "{row}"
        );
    }

    /// A column-lit native curve with its bias against the traced one counted: the target
    /// needs the noise to fall to √(e² − b²), and a target at or under the bias is never met.
    #[test]
    fn the_columns_bias_is_counted_in_its_error() {
        let mut c = curve_to("native", 1.0);
        c.daylight = "column".into();
        c.points = vec![pt(1, 0.2), pt(8, 0.2 / 8f64.sqrt()), pt(64, 0.025)];
        (c.startup_seconds, c.seconds_per_spp) = (1.0, 0.5);
        let mut traced = curve_to(TRACED, 1.0);
        traced.daylight = "traced".into();
        traced.reference_means = [1.0, 1.0, 1.0];
        traced.reference_mean_se = [0.005; 3];
        // 1.2 % on every channel: the 2 % target needs 1.6 % of noise.
        c.reference_means = [1.012; 3];
        let b = Bias::between(&c, &traced).unwrap();
        assert!((b.rms() - 0.012).abs() < 1e-12);
        assert!(
            b.text().starts_with("+1.2, +1.2, +1.2 % (± 0.5)"),
            "{}",
            b.text()
        );
        let mut biased = c.clone();
        biased.count_bias(b);
        let (free, with) = (
            spp_to(&c.points, 0.02).unwrap().0,
            biased.at(0.02).unwrap().spp,
        );
        assert!(
            (with / free - (0.02f64 / 0.016).powi(2)).abs() < 1e-9,
            "{free} {with}"
        );
        assert_eq!(biased.at(0.02).unwrap().seconds, 1.0 + 0.5 * with);
        // A near-black channel's large relative bias weighs what its light weighs: +5 % of a
        // red at 1/60 of the blue counts 0.1 %, as it does in the image's relative RMSE.
        let mut dark = c.clone();
        traced.reference_means = [0.01, 0.3, 0.6];
        dark.reference_means = [0.0105, 0.3, 0.6];
        let d = Bias::between(&dark, &traced).unwrap();
        assert!((d.relative[0] - 0.05).abs() < 1e-12);
        let want = (0.0005f64.powi(2) / 3.0).sqrt() / (0.91 / 3.0);
        assert!((d.rmse - want).abs() < 1e-12 && d.rmse < 0.001, "{d:?}");
        traced.reference_means = [1.0; 3];
        // 2.5 %: the 2 % target is out of reach, the 5 % one is not.
        let mut far = c.clone();
        far.reference_means = [1.025; 3];
        let b = Bias::between(&far, &traced).unwrap();
        far.count_bias(b);
        assert!(far.at(0.02).is_none() && far.at(0.05).is_some());
        // The summary names the estimator and the bias, and the traced curve beside it.
        let mut r = report();
        r.scenes[0].curves[0] = biased;
        r.scenes[0].curves.insert(1, traced);
        let s = r.summary();
        let row = s.lines().find(|l| l.starts_with("| `s` |")).unwrap();
        assert!(row.starts_with("| `s` | 128×96 | column |"), "{row}");
        assert!(row.contains("| 1.00 / 6.25 | 30.0* / 188* |"), "{row}");
        assert!(
            row.contains("| +1.2, +1.2, +1.2 % (± 0.5); 1.2 % |"),
            "{row}"
        );
        // The traced curve is not one of the backends native is compared with.
        assert_eq!(
            r.scenes[0].speedup(0.05).0,
            Some(12.0 / (1.0 + 0.5 * far_spp(&r)))
        );
    }

    /// The 5 % target's spp of the scene's native curve (for the speed-up above).
    fn far_spp(r: &Report) -> f64 {
        r.scenes[0].native().unwrap().at(0.05).unwrap().spp
    }

    #[test]
    fn axis_labels_are_short() {
        let t: Vec<String> = [0.7000000000000001, 0.02, 1.0, 12.5, 1234.0, 0.0012345]
            .into_iter()
            .map(tick)
            .collect();
        assert_eq!(t, ["0.7", "0.02", "1", "12.5", "1234", "0.00123"]);
    }

    #[test]
    fn the_report_survives_its_json() {
        let r = report();
        let json = serde_json::to_string(&r).unwrap();
        let back: Report = serde_json::from_str(&json).unwrap();
        assert_eq!(back.summary(), r.summary());
    }
}
