//! `poser bench render`: speed against error for the render backends.
//!
//! Each backend renders the same benchmark scene at increasing samples per pixel; the error of
//! each image is its relative RMSE against that backend's own converged reference (a render
//! at [`REF_SPP`] spp — or [`QUICK_REF_SPP`] with `--quick`), so differences in conventions do
//! not floor the curve. The report gives, per backend, the wall-clock time to reach
//! [`TARGET_RMSE`] (interpolated log-log between the bracketing points) and the whole curve.
//!
//! | scene | content |
//! |---|---|
//! | `strobe_backscatter` | bounces = 1 (direct light and single scattering, so every backend's reference converges; multiple scattering next to a strobe gives every unidirectional tracer fireflies); camera in air behind a flat PMMA port, 160×120 (80×60 quick); scattering and absorbing water (σa = 0.40/0.10/0.05, σs = 0.08/0.10/0.12 1/m, HG g = 0.9); a rig strobe in the water; a diffuse back plane 3 m away and three boxes |
//!
//! Mitsuba and Cycles run through [`crate::backend::mitsuba::render`] and
//! [`crate::backend::blender::render`] when their Python modules are available; a backend that
//! fails is reported as such and skipped. Times include each backend's fixed start-up cost
//! (Python import and scene build for the other two), as a user sees it.

use crate::backend::RenderOptions;
use crate::model::*;
use glam::{DMat3, DVec3};
use std::path::Path;

/// Relative RMSE the report times each backend to.
pub const TARGET_RMSE: f64 = 0.10;
/// Samples per pixel of the converged references.
pub const REF_SPP: u32 = 1024;
pub const QUICK_REF_SPP: u32 = 256;

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
        },
        needs: Needs {
            medium: true,
            refraction: true,
            reasons: vec!["benchmark scene".into()],
            ..Needs::default()
        },
    }
}

/// Relative RMSE of `img` against `reference` (all channels), normalised by the reference mean.
pub fn relative_rmse(img: &[f32], reference: &[f32]) -> f64 {
    let n = reference.len().min(img.len()).max(1) as f64;
    let mean = reference.iter().map(|&v| v as f64).sum::<f64>() / n;
    let se: f64 = img
        .iter()
        .zip(reference)
        .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
        .sum();
    (se / n).sqrt() / mean.max(1e-300)
}

/// One measured point of a speed/error curve.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Point {
    pub spp: u32,
    pub seconds: f64,
    pub rmse: f64,
}

/// One backend's curve.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Curve {
    pub backend: String,
    /// Error message when the backend could not run.
    pub error: Option<String>,
    pub reference_spp: u32,
    pub reference_seconds: f64,
    pub points: Vec<Point>,
    /// Seconds to reach [`TARGET_RMSE`] (None: not reached).
    pub seconds_to_target: Option<f64>,
}

/// Whole report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub target_rmse: f64,
    pub threads: usize,
    pub curves: Vec<Curve>,
}

fn render_rgb(
    backend: &str,
    model: &Model,
    spp: u32,
    dir: &Path,
) -> Result<(Vec<f32>, f64), String> {
    let opts = RenderOptions {
        samples: Some(spp),
        poses: None,
        progress: false,
    };
    let t0 = std::time::Instant::now();
    let report = crate::compare::render_with(backend, model, dir, &opts)?;
    let secs = t0.elapsed().as_secs_f64().max(report.seconds);
    let path = dir.join(format!("{}.exr", model.image_name(0, 0)));
    let img = image::open(&path)
        .map_err(|e| format!("{}: {e}", path.display()))?
        .into_rgb32f();
    Ok((img.into_raw(), secs))
}

/// Time to reach `target`: log-log interpolation between the first point at or below it and
/// the one before.
pub fn time_to(points: &[Point], target: f64) -> Option<f64> {
    let k = points.iter().position(|p| p.rmse <= target)?;
    if k == 0 {
        return Some(points[0].seconds);
    }
    let (a, b) = (&points[k - 1], &points[k]);
    let (la, lb) = (a.rmse.ln(), b.rmse.ln());
    if (la - lb).abs() < 1e-12 {
        return Some(b.seconds);
    }
    let f = (la - target.ln()) / (la - lb);
    Some((a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp())
}

fn curve(backend: &str, model: &Model, ref_spp: u32, ladder: &[u32]) -> Curve {
    let mut c = Curve {
        backend: backend.into(),
        error: None,
        reference_spp: ref_spp,
        reference_seconds: 0.0,
        points: vec![],
        seconds_to_target: None,
    };
    let run = || -> Result<(f64, Vec<Point>), String> {
        let tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
        let mut refm = model.clone();
        refm.render.seed = 9_999;
        let (reference, rs) = render_rgb(backend, &refm, ref_spp, &tmp.path().join("ref"))?;
        let mut pts = Vec::new();
        for &spp in ladder {
            let (img, secs) = render_rgb(backend, model, spp, &tmp.path().join(format!("s{spp}")))?;
            let rmse = relative_rmse(&img, &reference);
            eprintln!("  {backend:>8} {spp:>5} spp  {secs:>8.3} s  rel. RMSE {rmse:.4}");
            pts.push(Point {
                spp,
                seconds: secs,
                rmse,
            });
            if rmse < 0.5 * TARGET_RMSE {
                break;
            }
        }
        Ok((rs, pts))
    };
    match run() {
        Ok((rs, pts)) => {
            c.reference_seconds = rs;
            c.seconds_to_target = time_to(&pts, TARGET_RMSE);
            c.points = pts;
        }
        Err(e) => c.error = Some(e),
    }
    c
}

impl Report {
    /// Markdown table, one row per backend.
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "scene `{}` {}×{}, target relative RMSE {:.0} %, {} threads\n\n\
             | backend | time to target (s) | speed-up vs native | curve (spp: s, RMSE) |\n|---|---|---|---|\n",
            self.scene,
            self.width,
            self.height,
            100.0 * self.target_rmse,
            self.threads
        );
        let native = self
            .curves
            .iter()
            .find(|c| c.backend == "native")
            .and_then(|c| c.seconds_to_target);
        for c in &self.curves {
            let t = match (&c.error, c.seconds_to_target) {
                (Some(e), _) => format!("failed: {}", e.lines().next().unwrap_or("")),
                (None, Some(t)) => format!("{t:.3}"),
                (None, None) => "not reached".into(),
            };
            let ratio = match (native, c.seconds_to_target) {
                (Some(n), Some(t)) if n > 0.0 => format!("{:.1}×", t / n),
                _ => "–".into(),
            };
            let pts: Vec<String> = c
                .points
                .iter()
                .map(|p| format!("{}: {:.2}, {:.3}", p.spp, p.seconds, p.rmse))
                .collect();
            s += &format!("| {} | {t} | {ratio} | {} |\n", c.backend, pts.join("; "));
        }
        s
    }
}

/// Run the render benchmark: native always, Mitsuba and Cycles when available. Prints a
/// Markdown table; writes the JSON report to `json` when given.
pub fn run(json: Option<&Path>, quick: bool) -> Result<(), String> {
    run_backends(json, quick, &["native", "mitsuba", "blender"])
}

/// [`run`] restricted to some backends.
pub fn run_backends(json: Option<&Path>, quick: bool, backends: &[&str]) -> Result<(), String> {
    let (w, h) = if quick { (80, 60) } else { (160, 120) };
    let model = bench_model(w, h);
    let ref_spp = if quick { QUICK_REF_SPP } else { REF_SPP };
    let ladder: Vec<u32> = if quick {
        vec![1, 4, 16, 64]
    } else {
        vec![1, 2, 4, 8, 16, 32, 64, 128, 256]
    };
    let mut curves = Vec::new();
    for &b in backends {
        eprintln!("bench render: {b} (reference {ref_spp} spp)");
        curves.push(curve(b, &model, ref_spp, &ladder));
    }
    let report = Report {
        scene: model.name.clone(),
        width: w,
        height: h,
        target_rmse: TARGET_RMSE,
        threads: rayon::current_num_threads(),
        curves,
    };
    println!("{}", report.to_markdown());
    if let Some(p) = json {
        let s = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        crate::io::write_atomic(p, s.as_bytes()).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_to_target_interpolates_log_log() {
        let pts = vec![
            Point {
                spp: 1,
                seconds: 1.0,
                rmse: 0.2,
            },
            Point {
                spp: 4,
                seconds: 4.0,
                rmse: 0.1,
            },
            Point {
                spp: 16,
                seconds: 16.0,
                rmse: 0.05,
            },
        ];
        // RMSE ∝ t^-1/2: 0.0707 is reached at t = 8.
        let t = time_to(&pts, 0.1 / 2f64.sqrt()).unwrap();
        assert!((t - 8.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to(&pts, 0.01), None);
        assert_eq!(time_to(&pts, 0.5), Some(1.0));
    }

    #[test]
    fn rmse_is_relative() {
        assert!((relative_rmse(&[1.1, 0.9], &[1.0, 1.0]) - 0.1).abs() < 1e-6);
    }
}
