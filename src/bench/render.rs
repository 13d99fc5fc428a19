//! `poser bench render`: speed against error for the three render backends.
//!
//! Each backend renders the same benchmark scenes at increasing samples per pixel (spp). The
//! error of an image is its relative RMSE against that backend's own converged reference, so
//! that differences in conventions do not floor the curve; the reference is the average of two
//! independent renders at [`REF_SPP`] spp, and its remaining noise is removed from every error
//! (E[MSE(img, (a+b)/2)] = σ²(img) + MSE(a, b)/4). The references of the three backends are
//! then compared with each other (channel means), which shows that the curves time the same
//! physics.
//!
//! Time is wall-clock, as a user sees it, and is split by a least-squares fit
//! `t = t₀ + k·spp` over all renders into a fixed start-up cost `t₀` (Python import, scene
//! build, BVH) and a cost per sample `k`. The spp needed to reach [`TARGET_RMSE`] is
//! interpolated log-log between the bracketing points (extrapolated with RMSE ∝ spp^-½ past
//! the last one, and marked so). The report gives, per backend, the time to the target with and
//! without start-up, and native's speed-up over the faster of the other two.
//!
//! | scene | content |
//! |---|---|
//! | `strobe_backscatter` | bounces = 1 (direct light and single scattering); camera in air behind a flat PMMA port, 160×120 (80×60 with `--quick`); scattering and absorbing water (σa = 0.40/0.10/0.05, σs = 0.08/0.10/0.12 1/m, HG g = 0.9); a rig strobe in the water; a diffuse back plane 3 m away and three boxes |
//! | `clear_strobe` | the same without scattering (σs = 0) and with bounces = 4: absorption, interreflection and the port only |
//!
//! Every backend runs through [`crate::backend::Backend::render`]; Mitsuba and Cycles need
//! their Python modules, and a backend that fails is reported as such and skipped.

use crate::backend::{Backend, RenderOptions};
use crate::model::*;
use glam::{DMat3, DVec3};
use std::path::Path;

/// Relative RMSE the report times each backend to.
pub const TARGET_RMSE: f64 = 0.10;
/// Samples per pixel of each of the two renders of a converged reference.
pub const REF_SPP: u32 = 1024;
pub const QUICK_REF_SPP: u32 = 256;

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
#[derive(Debug, Clone, serde::Serialize)]
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

/// One backend's curve on one scene.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Curve {
    pub backend: String,
    /// Error message when the backend could not run.
    pub error: Option<String>,
    pub reference_spp: u32,
    /// Wall-clock seconds of one reference render.
    pub reference_seconds: f64,
    /// Relative RMSE left in the averaged reference.
    pub reference_residual: f64,
    /// Per-channel means of the reference, linear radiance.
    pub reference_means: [f64; 3],
    pub points: Vec<Point>,
    /// Fixed start-up seconds and seconds per spp of the fit `t = t0 + k·spp`.
    pub startup_seconds: f64,
    pub seconds_per_spp: f64,
    /// spp needed to reach [`TARGET_RMSE`], and whether it was extrapolated.
    pub spp_to_target: Option<f64>,
    pub extrapolated: bool,
    /// Wall-clock seconds to the target, with and without the start-up cost.
    pub seconds_to_target: Option<f64>,
    pub render_seconds_to_target: Option<f64>,
}

/// One scene's results.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SceneReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub max_bounces: u32,
    pub curves: Vec<Curve>,
}

/// Whole report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    pub target_rmse: f64,
    pub threads: usize,
    pub scenes: Vec<SceneReport>,
}

fn render_rgb(
    backend: Backend,
    model: &Model,
    spp: u32,
    dir: &Path,
) -> Result<(Vec<f32>, f64), String> {
    let opts = RenderOptions {
        samples: Some(spp),
        poses: None,
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

fn curve(backend: Backend, model: &Model, ref_spp: u32, max_spp: u32) -> Curve {
    let mut c = Curve {
        backend: backend.name().into(),
        error: None,
        reference_spp: ref_spp,
        reference_seconds: 0.0,
        reference_residual: 0.0,
        reference_means: [0.0; 3],
        points: vec![],
        startup_seconds: 0.0,
        seconds_per_spp: 0.0,
        spp_to_target: None,
        extrapolated: false,
        seconds_to_target: None,
        render_seconds_to_target: None,
    };
    let run = |c: &mut Curve| -> Result<(), String> {
        let tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
        let mut timings = Vec::new();
        let mut refs = Vec::new();
        for (k, seed) in [9_999u64, 19_999].into_iter().enumerate() {
            let mut m = model.clone();
            m.render.seed = seed;
            let dir = tmp.path().join(format!("ref{k}"));
            let (img, secs) = render_rgb(backend, &m, ref_spp, &dir)?;
            eprintln!("  {backend:>8} reference {k}: {ref_spp} spp {secs:8.2} s");
            timings.push((ref_spp as f64, secs));
            c.reference_seconds = secs;
            refs.push(img);
        }
        let reference = Reference::new(&refs[0], &refs[1]);
        c.reference_residual = reference.residual();
        c.reference_means = crate::compare::channel_means(&reference.image);
        let mut spp = 1;
        while spp <= max_spp {
            let dir = tmp.path().join(format!("s{spp}"));
            let (img, secs) = render_rgb(backend, model, spp, &dir)?;
            let rmse = reference.error_of(&img);
            eprintln!("  {backend:>8} {spp:>5} spp  {secs:>8.3} s  rel. RMSE {rmse:.4}");
            timings.push((spp as f64, secs));
            c.points.push(Point {
                spp,
                seconds: secs,
                rmse,
            });
            if rmse < 0.5 * TARGET_RMSE {
                break;
            }
            spp *= 4;
        }
        let (t0, k) = fit_cost(&timings);
        c.startup_seconds = t0;
        c.seconds_per_spp = k;
        if let Some((s, extra)) = spp_to(&c.points, TARGET_RMSE) {
            c.spp_to_target = Some(s);
            c.extrapolated = extra;
            c.seconds_to_target = Some(t0 + k * s);
            c.render_seconds_to_target = Some(k * s);
        }
        Ok(())
    };
    if let Err(e) = run(&mut c) {
        c.error = Some(e);
    }
    c
}

impl SceneReport {
    /// native's speed-up over the faster of the others: (wall, render only).
    pub fn speedup(&self) -> (Option<f64>, Option<f64>) {
        let native = self.curves.iter().find(|c| c.backend == "native");
        let others = self.curves.iter().filter(|c| c.backend != "native");
        let best = |f: fn(&Curve) -> Option<f64>| -> Option<f64> {
            let n = f(native?)?;
            let o = others.clone().filter_map(f).fold(f64::INFINITY, f64::min);
            (o.is_finite() && n > 0.0).then(|| o / n)
        };
        (
            best(|c| c.seconds_to_target),
            best(|c| c.render_seconds_to_target),
        )
    }

    /// Markdown: the speed table, then the agreement of the references.
    pub fn to_markdown(&self, target: f64) -> String {
        let mut s = format!(
            "### `{}` ({}×{}, bounces = {}), target relative RMSE {:.0} %\n\n\
             | backend | spp to target | time to target (s) | without start-up (s) | start-up (s) | s per spp | curve (spp: s, RMSE) |\n\
             |---|---|---|---|---|---|---|\n",
            self.scene,
            self.width,
            self.height,
            self.max_bounces,
            100.0 * target
        );
        for c in &self.curves {
            if let Some(e) = &c.error {
                s += &format!(
                    "| {} | failed: {} | | | | | |\n",
                    c.backend,
                    e.lines().next().unwrap_or("")
                );
                continue;
            }
            let opt = |v: Option<f64>, p: usize| {
                v.map(|x| format!("{x:.p$}")).unwrap_or_else(|| "–".into())
            };
            let mark = if c.extrapolated { " (extrap.)" } else { "" };
            let pts: Vec<String> = c
                .points
                .iter()
                .map(|p| format!("{}: {:.2}, {:.3}", p.spp, p.seconds, p.rmse))
                .collect();
            s += &format!(
                "| {} | {}{mark} | {} | {} | {:.2} | {:.4} | {} |\n",
                c.backend,
                opt(c.spp_to_target, 1),
                opt(c.seconds_to_target, 3),
                opt(c.render_seconds_to_target, 3),
                c.startup_seconds,
                c.seconds_per_spp,
                pts.join("; ")
            );
        }
        let (wall, render) = self.speedup();
        let x = |v: Option<f64>| v.map(|r| format!("{r:.1}×")).unwrap_or_else(|| "–".into());
        s += &format!(
            "\nnative's speed-up over the faster of the others at equal error: {} wall-clock, {} without start-up.\n\n",
            x(wall),
            x(render)
        );
        s += "| backend | reference | residual noise | mean R, G, B | vs native |\n|---|---|---|---|---|\n";
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
                        .map(|i| format!("{:+.2} %", 100.0 * (m[i] / n[i].max(1e-300) - 1.0)))
                        .collect();
                    d.join(", ")
                }
                _ => "–".into(),
            };
            s += &format!(
                "| {} | 2 × {} spp ({:.1} s each) | {:.2} % | {:.4}, {:.4}, {:.4} | {vs} |\n",
                c.backend,
                c.reference_spp,
                c.reference_seconds,
                100.0 * c.reference_residual,
                m[0],
                m[1],
                m[2]
            );
        }
        s
    }
}

impl Report {
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "Render speed against error ({} threads; times are wall-clock).\n\n",
            self.threads
        );
        for sc in &self.scenes {
            s += &sc.to_markdown(self.target_rmse);
            s += "\n";
        }
        s
    }

    /// Log-log plot of error against wall-clock time, one panel per scene.
    pub fn plot_svg(&self) -> Result<String, String> {
        crate::plan::plot::register_font()?;
        use plotters::prelude::*;
        let mut buf = String::new();
        {
            let n = self.scenes.len().max(1);
            let root = SVGBackend::with_string(&mut buf, (560 * n as u32, 420)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| e.to_string())?;
            let panels = root.split_evenly((1, n));
            let colours = [
                RGBColor(200, 40, 40),
                RGBColor(20, 80, 200),
                RGBColor(230, 130, 20),
            ];
            for (sc, area) in self.scenes.iter().zip(panels.iter()) {
                let pts = sc.curves.iter().flat_map(|c| c.points.iter());
                let (mut tmin, mut tmax, mut emin, mut emax) = (f64::MAX, 0f64, f64::MAX, 0f64);
                for p in pts.filter(|p| p.rmse > 0.0) {
                    tmin = tmin.min(p.seconds);
                    tmax = tmax.max(p.seconds);
                    emin = emin.min(p.rmse);
                    emax = emax.max(p.rmse);
                }
                if tmax <= 0.0 {
                    continue;
                }
                emin = emin.min(self.target_rmse) * 0.8;
                emax = emax.max(self.target_rmse) * 1.25;
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!("{} ({}×{})", sc.scene, sc.width, sc.height),
                        ("sans-serif", 18),
                    )
                    .margin(12)
                    .x_label_area_size(40)
                    .y_label_area_size(56)
                    .build_cartesian_2d(
                        (tmin * 0.8..tmax * 1.25).log_scale(),
                        (emin..emax).log_scale(),
                    )
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc("wall-clock time (s)")
                    .y_desc("relative RMSE")
                    .draw()
                    .map_err(|e| e.to_string())?;
                let target = self.target_rmse;
                chart
                    .draw_series(LineSeries::new(
                        [(tmin * 0.8, target), (tmax * 1.25, target)],
                        BLACK.mix(0.4),
                    ))
                    .map_err(|e| e.to_string())?;
                for (k, c) in sc.curves.iter().enumerate() {
                    let col = colours[k % colours.len()];
                    let line: Vec<(f64, f64)> = c
                        .points
                        .iter()
                        .filter(|p| p.rmse > 0.0)
                        .map(|p| (p.seconds, p.rmse))
                        .collect();
                    chart
                        .draw_series(LineSeries::new(line.clone(), col.stroke_width(2)))
                        .map_err(|e| e.to_string())?
                        .label(c.backend.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
                    chart
                        .draw_series(line.into_iter().map(|p| Circle::new(p, 3, col.filled())))
                        .map_err(|e| e.to_string())?;
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
            root.present().map_err(|e| e.to_string())?;
        }
        Ok(buf)
    }
}

/// Options of the render benchmark.
#[derive(Debug, Clone, Default)]
pub struct BenchOptions {
    pub quick: bool,
    /// Backends to run (default: all).
    pub backends: Vec<Backend>,
    pub json: Option<std::path::PathBuf>,
    pub plot: Option<std::path::PathBuf>,
}

/// Run the render benchmark: prints a Markdown report; writes JSON and an SVG plot when asked.
pub fn run(opts: &BenchOptions) -> Result<Report, String> {
    let (w, h) = if opts.quick { (80, 60) } else { (160, 120) };
    let ref_spp = if opts.quick { QUICK_REF_SPP } else { REF_SPP };
    let backends: Vec<Backend> = if opts.backends.is_empty() {
        Backend::ALL.to_vec()
    } else {
        opts.backends.clone()
    };
    let mut scenes = Vec::new();
    for model in bench_models(w, h) {
        let mut curves = Vec::new();
        for b in &backends {
            eprintln!(
                "bench render: {} with {b} (reference 2 × {ref_spp} spp)",
                model.name
            );
            curves.push(curve(*b, &model, ref_spp, ref_spp / 4));
        }
        scenes.push(SceneReport {
            scene: model.name.clone(),
            width: w,
            height: h,
            max_bounces: model.render.max_bounces,
            curves,
        });
    }
    let report = Report {
        target_rmse: TARGET_RMSE,
        threads: rayon::current_num_threads(),
        scenes,
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
    Ok(report)
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

    #[test]
    fn speedup_is_against_the_faster_other_backend() {
        let c = |b: &str, t: f64| Curve {
            backend: b.into(),
            error: None,
            reference_spp: 1,
            reference_seconds: 0.0,
            reference_residual: 0.0,
            reference_means: [1.0; 3],
            points: vec![],
            startup_seconds: 0.0,
            seconds_per_spp: 0.0,
            spp_to_target: Some(1.0),
            extrapolated: false,
            seconds_to_target: Some(t),
            render_seconds_to_target: Some(t / 2.0),
        };
        let sc = SceneReport {
            scene: "s".into(),
            width: 1,
            height: 1,
            max_bounces: 1,
            curves: vec![c("native", 1.0), c("mitsuba", 30.0), c("blender", 12.0)],
        };
        assert_eq!(sc.speedup(), (Some(12.0), Some(12.0)));
        let md = sc.to_markdown(0.1);
        assert!(md.contains("12.0× wall-clock"), "{md}");
    }
}
