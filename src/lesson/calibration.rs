//! Lesson kind `calibration`: each variant's images are rendered by the native renderer into
//! `OUT/<variant>/images/`, and `backends/opencv/calibrate.py` (OpenCV, in the pinned Python
//! environment) finds the checkerboard's corners in those images — never from the truth — and
//! calibrates a pinhole camera with k1, k2, p1, p2, k3, in grey and per colour channel.
//!
//! | number | meaning |
//! |---|---|
//! | RMS | OpenCV's RMS reprojection error, px |
//! | fx/f_air, fy/f_air | calibrated focal lengths over the camera's in-air focal length (`focal_length / pixel_pitch`) |
//! | cx, cy | principal point in OpenCV's convention (pixel centres at integers = poser's − 0.5) |
//! | k1 … k3 | distortion coefficients |
//! | lateral colour | distance between the red and the blue calibrations' pixels at the image corners (the board corners seen nearest to them; see the script), and the same distance between the detected corners |
//!
//! The board is the scene's first checkerboard target; its inner corners are what OpenCV
//! looks for.

use super::Case;
use crate::backend::{Backend, RenderOptions, python};
use crate::model::TargetKind;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// OpenCV's answer for one channel (or grey).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Intrinsics {
    pub rms: f64,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub dist: Distortion,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Distortion {
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    pub k3: f64,
}

/// Lateral colour at the image corners (the board corners seen nearest to them), px.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LateralColour {
    /// Through the per-channel calibrations.
    pub r_minus_b_px: f64,
    pub r_minus_g_px: f64,
    pub b_minus_g_px: f64,
    /// Between the corners detected in the red and the blue channel, directly.
    pub detected_r_minus_b_px: f64,
    /// Those corners' mean distance from the image centre over the half-diagonal.
    pub radius_fraction: f64,
}

/// The script's result (`backends/opencv/calibrate.py`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Calibrated {
    pub conventions: String,
    pub width: u32,
    pub height: u32,
    pub views: Vec<String>,
    pub rejected: Vec<String>,
    #[serde(flatten)]
    pub grey: Intrinsics,
    pub cx_poser: f64,
    pub cy_poser: f64,
    /// `[u, v, du, dv]`: corner (OpenCV pixels) and observed − reprojected, px.
    #[serde(skip_serializing)]
    pub residuals: Vec<[f64; 4]>,
    pub opencv: String,
    pub channels: Option<std::collections::BTreeMap<String, Intrinsics>>,
    pub lateral_colour: Option<LateralColour>,
}

/// One variant's numbers and plots.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    pub command: String,
    /// The camera's in-air focal length, px.
    pub f_air: f64,
    pub fx_ratio: f64,
    pub fy_ratio: f64,
    pub calibration: Calibrated,
    pub seconds: f64,
    /// The first rendered view (PNG).
    #[serde(skip)]
    pub view_png: Vec<u8>,
    /// The residual vectors over the image (SVG).
    #[serde(skip)]
    pub residuals_svg: String,
}

/// `backends/opencv/calibrate.py`, embedded in the binary (an installed `poser` runs it).
const SCRIPT_SOURCE: &str = include_str!("../../backends/opencv/calibrate.py");

/// Run the OpenCV calibration on `images`.
pub fn calibrate(
    images: &[PathBuf],
    pattern: (u32, u32),
    square: f64,
    work: &Path,
) -> Result<Calibrated, String> {
    python::require_module("cv2")?;
    let req = serde_json::json!({
        "images": images,
        "pattern": [pattern.0, pattern.1],
        "square": square,
        "per_channel": true,
    });
    python::run_json(
        work,
        "calibrate.py",
        SCRIPT_SOURCE,
        &req,
        "OpenCV calibration",
    )
}

/// Render, detect and calibrate one case.
pub fn run_case(c: &Case, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let t0 = std::time::Instant::now();
    let m = &c.model;
    let (cols, rows_, square) = m
        .targets
        .iter()
        .find_map(|t| match t.kind {
            TargetKind::Checkerboard { cols, rows, square } => Some((cols, rows, square)),
            _ => None,
        })
        .ok_or_else(|| {
            format!(
                "variant `{}`: a calibration lesson needs a checkerboard target\n  help: add \
                 `[[targets]]` with `type = \"checkerboard\"`",
                c.label
            )
        })?;
    let dir = out.join(&c.slug);
    let images_dir = dir.join("images");
    progress(&format!(
        "rendering `{}` ({} views)",
        c.label,
        m.poses.len()
    ));
    let opts = RenderOptions::default();
    crate::pipeline::run(m, Backend::Native, &images_dir, &opts, Default::default())?;
    let mut images: Vec<PathBuf> = std::fs::read_dir(&images_dir)
        .map_err(|e| format!("{}: {e}", images_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    images.sort();
    progress(&format!("calibrating `{}` with OpenCV", c.label));
    let cal = calibrate(&images, (cols - 1, rows_ - 1), square, &dir)
        .map_err(|e| format!("variant `{}`: {e}", c.label))?;
    let cam = &m.cameras[0];
    let view_png =
        std::fs::read(&images[0]).map_err(|e| format!("{}: {e}", images[0].display()))?;
    let residuals_svg = residual_svg(&cal)?;
    Ok(Row {
        label: c.label.clone(),
        command: c.command("render"),
        f_air: cam.fx,
        fx_ratio: cal.grey.fx / cam.fx,
        fy_ratio: cal.grey.fy / cam.fy,
        calibration: cal,
        seconds: t0.elapsed().as_secs_f64(),
        view_png,
        residuals_svg,
    })
}

/// The residual vectors drawn over the image frame, scaled so that the largest is a tenth of
/// the image width.
pub fn residual_svg(cal: &Calibrated) -> Result<String, String> {
    use plotters::prelude::*;
    crate::plan::plot::register_font()?;
    let (w, h) = (cal.width as f64, cal.height as f64);
    let max = cal
        .residuals
        .iter()
        .map(|r| r[2].hypot(r[3]))
        .fold(0.0, f64::max)
        .max(1e-6);
    let scale = 0.1 * w / max;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (480, 360)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("Residuals × {scale:.0} (largest {max:.2} px)"),
                ("sans-serif", 15),
            )
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(0.0..w, h..0.0)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("u, px")
            .y_desc("v, px")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(cal.residuals.iter().map(|r| {
                PathElement::new(
                    vec![(r[0], r[1]), (r[0] + scale * r[2], r[1] + scale * r[3])],
                    RED,
                )
            }))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(
                cal.residuals
                    .iter()
                    .map(|r| Circle::new((r[0], r[1]), 1, BLACK.filled())),
            )
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
