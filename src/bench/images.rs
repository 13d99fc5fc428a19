//! `poser bench images`: can real photogrammetry software process poser's images? Each
//! shipped survey scene is rendered by the native backend at a reduced size, run through its
//! sensor stage (the scene's `[sensor]`, else the default camera of `poser render --sensor`),
//! and handed to COLMAP's whole pipeline (`poser evaluate
//! --mode images`, the same code): the share of images registered, points, track length,
//! reprojection error and the recovered focal length against the in-water-equivalent truth.
//!
//! | scene | network (both forms) | quick: scale, samples | full: scale, samples |
//! |---|---|---|---|
//! | `scenarios/reef_strip.toml` | a 1.5 × 3 m corner: 4 strips, 44 images | 0.4, 16 | 0.8, 64 |
//! | `scenarios/dome_orbit.toml` | as shipped: 36 images | 0.25, 16 | 0.5, 64 |
//! | `scenarios/lessons/archaeology.toml` | a 3 × 3 m trench: 36 images | 0.1, 16 | 0.2, 64 |
//! | `scenarios/lessons/coral_self_occlusion.toml` | as shipped: 50 images | 0.25, 16 | 0.5, 64 |
//! | `scenarios/lessons/subsea_metrology.toml` | 2 m of pipeline: 11 stereo pairs, 22 images | 0.2, 16 | 0.4, 64 |
//! | `scenarios/sites/textured_bommie.toml` | the bommie's 1.6 × 1.6 m centre, nadir: 28 images of the textured model | 0.2, 8 | 0.4, 32 |
//!
//! A scene that cannot be processed (untextured, or COLMAP registering fewer than three
//! images) is a row with its reason, never a skipped line. Beside COLMAP's numbers each row
//! gives the render's median relative Monte Carlo noise (√var / L, from the sidecars) and
//! whether the images determine the focal length at all
//! ([`crate::evaluate::Evaluation::focal_sensitivity`]): over a flat block seen from above,
//! focal length and height trade against each other, and the focal error is then no
//! measurement.

use super::evaluate::cpu_seconds;
use crate::backend::{Backend, RenderOptions};
use crate::evaluate::{Options, check_images_texture, evaluate_images};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// One scene of the bench: where it is, the `--set`s of its network, its reduced size.
pub struct Case {
    pub scene: &'static str,
    pub sets: &'static [&'static str],
    /// Resolution scale and samples per pixel of the quick form; the full form doubles the
    /// scale and quadruples the samples.
    pub scale: f64,
    pub samples: u32,
}

/// The shipped survey scenes (issue 21's list), and the textured model of issue 36.
pub const CASES: &[Case] = &[
    Case {
        scene: "scenarios/reef_strip.toml",
        sets: &[
            "network.width=\"1.5 m\"",
            "network.length=\"3 m\"",
            "network.obliques=\"30 deg\"",
        ],
        scale: 0.4,
        samples: 16,
    },
    Case {
        scene: "scenarios/dome_orbit.toml",
        sets: &[],
        scale: 0.25,
        samples: 16,
    },
    Case {
        scene: "scenarios/lessons/archaeology.toml",
        sets: &["network.width=\"3 m\"", "network.length=\"3 m\""],
        scale: 0.1,
        samples: 16,
    },
    Case {
        scene: "scenarios/lessons/coral_self_occlusion.toml",
        sets: &["network.obliques=\"30 deg\""],
        scale: 0.25,
        samples: 16,
    },
    Case {
        scene: "scenarios/lessons/subsea_metrology.toml",
        sets: &["network.length=\"2 m\"", "network.obliques=\"15 deg\""],
        scale: 0.2,
        samples: 16,
    },
    Case {
        scene: "scenarios/sites/textured_bommie.toml",
        // Nadir only: with a 30° oblique pass COLMAP registered 43 of 56 images (two of the
        // four oblique strips dropped; docs/lessons.md).
        // 8 samples per pixel: at 16 the quick form's 28 images took 11 CPU-s each (the
        // column's gather traced through the bommie's relief), the longest test of CI's tier.
        // Fewer are too noisy for the half-pixel bar (measured at 0.25 of full size: 0.56 px
        // at 4 spp, 0.69 px at 2; 0.45 px at 8). At 0.2 of full size (320 × 240 px): 28 of 28
        // registered, 0.43 px, 256 CPU-s for the test against 384 at 0.25.
        sets: &["network.width=\"1.6 m\"", "network.length=\"1.6 m\""],
        scale: 0.2,
        samples: 8,
    },
];

/// One scene processed by COLMAP.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub scene: String,
    pub form: &'static str,
    pub width: usize,
    pub height: usize,
    pub samples: u32,
    /// σ of the native illumination denoiser when the scene turns it on (`render.denoise`).
    pub denoise_radius: Option<f64>,
    pub images: usize,
    pub registered: usize,
    /// registered / images.
    pub share: f64,
    pub points: usize,
    pub mean_track_length: f64,
    pub reprojection_px: f64,
    /// (f recovered − f truth)/f truth, the truth being the in-water-equivalent focal length
    /// (first camera).
    pub focal_error: Option<f64>,
    /// Rise of the mean reprojection error with the focal length held 10 % off; below
    /// [`crate::evaluate::FOCAL_DETERMINED`] the images do not determine the focal length.
    pub focal_sensitivity: Option<f64>,
    /// Median over the images of the median relative Monte Carlo noise of a pixel's radiance,
    /// √var / L, as the sensor stage's sidecars report it (pixel-channels with signal below
    /// the full well): what SIFT has to see through.
    pub render_noise: Option<f64>,
    /// Wall seconds of the render (and sensor stage), and of COLMAP's pipeline.
    pub render_wall_s: f64,
    pub colmap_wall_s: f64,
    pub cpu_s: f64,
    /// Why the scene could not be processed, if it could not.
    pub failure: Option<String>,
    /// COLMAP as it ships on the same JPEGs (`--stock`), when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stock: Option<StockRow>,
}

/// Stock COLMAP's result on a scene's images ([`crate::evaluate::Options::stock`]).
#[derive(Debug, Clone, Serialize)]
pub struct StockRow {
    pub registered: usize,
    pub share: f64,
    /// Separate models the mapper made (the largest is kept).
    pub models: Option<u64>,
    pub reprojection_px: f64,
    pub focal_error: Option<f64>,
    /// The focal length COLMAP read from the images' EXIF, px (`None`: none found).
    pub exif_focal_px: Option<f64>,
    pub colmap_wall_s: f64,
    pub failure: Option<String>,
}

/// Run the cases whose file name contains `only` (all when `None`); renders go to `out`.
pub fn run(
    root: &Path,
    quick: bool,
    only: Option<&str>,
    stock: bool,
    out: &Path,
) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for case in CASES {
        if only.is_some_and(|o| !case.scene.contains(o)) {
            continue;
        }
        eprintln!("bench images: {}", case.scene);
        rows.push(run_case(root, case, quick, stock, out)?);
    }
    if rows.is_empty() {
        return Err(format!(
            "--only {}: no scene of `poser bench images` matches",
            only.unwrap_or("")
        ));
    }
    Ok(rows)
}

/// Render and process one case.
pub fn run_case(
    root: &Path,
    case: &Case,
    quick: bool,
    stock: bool,
    out: &Path,
) -> Result<Row, String> {
    let (scale, samples) = if quick {
        (case.scale, case.samples)
    } else {
        (2.0 * case.scale, 4 * case.samples)
    };
    let sets: Vec<String> = case.sets.iter().map(|s| s.to_string()).collect();
    let mut model = crate::scene::load(&root.join(case.scene), &sets)
        .map_err(|f| f.render())?
        .model
        .with_resolution_scale(scale);
    // Every image goes through a camera: the scene's `[sensor]`, else the default one (as
    // `poser render --sensor`), which also writes the render's variance for the noise column.
    model
        .sensor
        .get_or_insert_with(crate::model::Sensor::default);
    let stem = Path::new(case.scene)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let cam = &model.cameras[0];
    let mut row = Row {
        scene: stem.clone(),
        form: if quick { "quick" } else { "full" },
        width: cam.width as usize,
        height: cam.height as usize,
        samples,
        denoise_radius: model.render.denoise_radius,
        images: model.poses.len() * model.cameras.len(),
        registered: 0,
        share: 0.0,
        points: 0,
        mean_track_length: 0.0,
        reprojection_px: f64::NAN,
        focal_error: None,
        focal_sensitivity: None,
        render_noise: None,
        render_wall_s: 0.0,
        colmap_wall_s: 0.0,
        cpu_s: 0.0,
        failure: None,
        stock: None,
    };
    let c0 = cpu_seconds();
    if let Err(e) = check_images_texture(&model) {
        row.failure = Some(first_line(&e));
        return Ok(row);
    }
    let dir = out.join(&stem);
    let t0 = std::time::Instant::now();
    let opts = RenderOptions {
        samples: Some(samples),
        poses: None,
        progress: false,
        resume: false,
    };
    let steps = crate::pipeline::Steps {
        truth: false,
        camera: true,
    };
    let developed = crate::pipeline::run(&model, Backend::Native, &dir, &opts, steps)?.developed;
    row.render_wall_s = t0.elapsed().as_secs_f64();
    // Median over the images of each one's median √var / L, as its sidecar reports it.
    row.render_noise = crate::sensor::percentile(
        developed
            .iter()
            .filter_map(|d| d.sidecar.render_noise.as_ref().map(|n| n.relative_median))
            .collect(),
        0.5,
    );
    let t1 = std::time::Instant::now();
    let opts = Options {
        model: crate::evaluate::Mode::Images.default_model(),
        ..Options::default()
    };
    match evaluate_images(&model, &dir, &opts, &|_, _, _| {}) {
        Ok(ev) => {
            row.registered = ev.registered;
            row.share = ev.registered as f64 / ev.images.max(1) as f64;
            row.points = ev.points;
            row.mean_track_length = ev.mean_track_length;
            row.reprojection_px = ev.reprojection_error;
            row.focal_error = ev.cameras.first().map(|c| c.focal_error);
            row.focal_sensitivity = ev.focal_sensitivity();
        }
        Err(e) => row.failure = Some(first_line(&e)),
    }
    row.colmap_wall_s = t1.elapsed().as_secs_f64();
    if stock {
        row.stock = Some(run_stock(&model, &dir));
    }
    row.cpu_s = cpu_seconds() - c0;
    Ok(row)
}

/// COLMAP as it ships on the JPEGs in `dir` (`poser evaluate --mode images --stock`).
fn run_stock(model: &crate::model::Model, dir: &Path) -> StockRow {
    let t = std::time::Instant::now();
    let opts = Options {
        model: crate::evaluate::colmap::CameraModel::SimpleRadial,
        stock: true,
        ..Options::default()
    };
    let mut s = StockRow {
        registered: 0,
        share: 0.0,
        models: None,
        reprojection_px: f64::NAN,
        focal_error: None,
        exif_focal_px: None,
        colmap_wall_s: 0.0,
        failure: None,
    };
    match evaluate_images(model, dir, &opts, &|_, _, _| {}) {
        Ok(ev) => {
            s.registered = ev.registered;
            s.share = ev.registered as f64 / ev.images.max(1) as f64;
            s.models = ev.colmap.get("models").and_then(|v| v.as_u64());
            s.reprojection_px = ev.reprojection_error;
            s.focal_error = ev.cameras.first().map(|c| c.focal_error);
            s.exif_focal_px = ev.colmap.get("exif_focal_px").and_then(|v| v.as_f64());
        }
        Err(e) => s.failure = Some(first_line(&e)),
    }
    s.colmap_wall_s = t.elapsed().as_secs_f64();
    s
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or_default().to_string()
}

/// The Markdown table of the rows.
pub fn table(rows: &[Row]) -> String {
    let noise = |n: Option<f64>| n.map_or("—".to_string(), |n| format!("{:.0} %", 100.0 * n));
    let mut s = String::from(
        "| scene | form | size | images | registered | points | track | reprojection | focal error | render noise | render | COLMAP | note |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        // A scene COLMAP could not process has no reconstruction columns, only its reason.
        let (points, track, reprojection, focal, note) = match &r.failure {
            Some(f) => (
                "—".into(),
                "—".into(),
                "—".into(),
                "—".into(),
                format!(" {}", f.replace('|', "/")),
            ),
            None => (
                r.points.to_string(),
                format!("{:.1}", r.mean_track_length),
                format!("{:.2} px", r.reprojection_px),
                match (r.focal_error, r.focal_sensitivity) {
                    (Some(f), Some(s)) if s < crate::evaluate::FOCAL_DETERMINED => format!(
                        "({:+.1} %, not determined: {:+.4} % at f + 10 %)",
                        100.0 * f,
                        100.0 * s
                    ),
                    (Some(f), Some(s)) => {
                        format!("{:+.1} % ({:+.2} % at f + 10 %)", 100.0 * f, 100.0 * s)
                    }
                    (Some(f), None) => format!("{:+.1} %", 100.0 * f),
                    _ => "—".into(),
                },
                String::new(),
            ),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {}×{}, {} spp{} | {} | {} ({:.0} %) | {points} | {track} | {reprojection} | {focal} | {} | {:.0} s | {:.0} s |{note} |",
            r.scene,
            r.form,
            r.width,
            r.height,
            r.samples,
            r.denoise_radius
                .map_or(String::new(), |d| format!(", denoised (σ {d} px)")),
            r.images,
            r.registered,
            100.0 * r.share,
            noise(r.render_noise),
            r.render_wall_s,
            r.colmap_wall_s,
        );
    }
    if rows.iter().any(|r| r.stock.is_some()) {
        s.push_str(
            "\nStock COLMAP on the same JPEGs (`--stock`: COLMAP's defaults, the focal length from \
             the EXIF, the initial pair's angle lowered to 8°):\n\n\
             | scene | registered | models | reprojection | focal error | EXIF focal | COLMAP | note |\n\
             |---|---|---|---|---|---|---|---|\n",
        );
        for r in rows {
            let Some(k) = &r.stock else { continue };
            let _ = writeln!(
                s,
                "| {} | {} of {} ({:.0} %) | {} | {} | {} | {} | {:.0} s | {} |",
                r.scene,
                k.registered,
                r.images,
                100.0 * k.share,
                k.models.map_or("—".into(), |m| m.to_string()),
                if k.reprojection_px.is_finite() {
                    format!("{:.2} px", k.reprojection_px)
                } else {
                    "—".into()
                },
                k.focal_error
                    .map_or("—".into(), |f| format!("{:+.1} %", 100.0 * f)),
                k.exif_focal_px
                    .map_or("none".into(), |f| format!("{f:.1} px")),
                k.colmap_wall_s,
                k.failure.as_deref().unwrap_or("").replace('|', "/"),
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(failure: Option<&str>) -> Row {
        Row {
            scene: "s".into(),
            form: "quick",
            width: 40,
            height: 30,
            samples: 4,
            denoise_radius: None,
            images: 10,
            registered: if failure.is_some() { 0 } else { 10 },
            share: if failure.is_some() { 0.0 } else { 1.0 },
            points: 123,
            mean_track_length: 4.25,
            reprojection_px: 0.5,
            focal_error: Some(0.012),
            focal_sensitivity: Some(0.02),
            render_noise: Some(0.2),
            render_wall_s: 3.0,
            colmap_wall_s: 1.0,
            cpu_s: 4.0,
            failure: failure.map(str::to_string),
            stock: None,
        }
    }

    #[test]
    fn every_row_has_the_headers_columns() {
        let t = table(&[row(None), row(Some("COLMAP failed | badly"))]);
        let lines: Vec<&str> = t.lines().collect();
        let columns = |l: &str| l.matches('|').count();
        assert!(lines.iter().all(|l| columns(l) == columns(lines[0])), "{t}");
        assert!(lines[2].starts_with(
            "| s | quick | 40×30, 4 spp | 10 | 10 (100 %) | 123 | 4.2 | 0.50 px | +1.2 % (+2.00 % at f + 10 %) | 20 % | 3 s | 1 s |"
        ), "{t}");
        assert!(
            lines[3].contains("| — | — | — | — | 20 % |")
                && lines[3].contains("COLMAP failed / badly"),
            "{t}"
        );
    }

    #[test]
    fn stock_colmap_gets_its_own_table() {
        assert!(!table(&[row(None)]).contains("Stock COLMAP"));
        let mut r = row(None);
        r.stock = Some(StockRow {
            registered: 3,
            share: 0.3,
            models: Some(2),
            reprojection_px: 0.61,
            focal_error: Some(-0.5),
            exif_focal_px: Some(333.3),
            colmap_wall_s: 7.0,
            failure: None,
        });
        let t = table(&[r]);
        let stock = t.split("Stock COLMAP").nth(1).expect("a stock table");
        let lines: Vec<&str> = stock.lines().filter(|l| l.starts_with('|')).collect();
        let columns = |l: &str| l.matches('|').count();
        assert!(lines.iter().all(|l| columns(l) == columns(lines[0])), "{t}");
        assert!(
            lines[2].starts_with("| s | 3 of 10 (30 %) | 2 | 0.61 px | -50.0 % | 333.3 px | 7 s |"),
            "{t}"
        );
    }
}
