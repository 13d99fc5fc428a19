//! Lesson kind `metrology`: a stereo rig's lighting and its measurement accuracy, per variant.
//! Two halves, each from the tool that owns it:
//!
//! | number | from |
//! |---|---|
//! | the view | the native renderer, camera 0 (the left camera) at the rig pose nearest the first target (a checkerboard), at [`VIEW_SCALE`] of the camera's resolution and the scene's samples |
//! | backscatter | the same view rendered with every object and target removed: the light the water scatters back, nothing behind it; mean radiance over the frame |
//! | contrast, contrast without backscatter, colour cast, veiling share | [`super::contrast::measure`] on the board (exact projection of its squares) |
//! | lamps apart | distance between the first two spot lights, m |
//! | accuracy | `poser evaluate` in observations mode with the rig calibrated beforehand (`--rig`: intrinsics held at their in-water-equivalent values, the cameras' poses in the rig held), aligned on the targets (`--gcp`), [`DENSITY`] tie points per m², 0.3 px noise: RMS error of the tie points per axis and 3D, and the scale error of the block (the similarity's scale − 1) |
//! | one pair's depth precision | the normal case of stereo, `σZ = Z² · √2 σ / (B · f)`: depth `Z` of the board from the left camera, baseline `B`, in-water-equivalent focal length `f` (px) and σ = 0.3 px per image (so √2 σ on the disparity) |
//!
//! The evaluation solves the whole block (every rig position along the pipe, with the targets
//! as control points), so it is better than one pair's precision; the ratio is the strength the
//! block adds.

use super::Case;
use super::contrast::{self, Measured};
use super::dive::{self, Accuracy};
use super::html::{case_row, escape, png, svg};
use crate::evaluate::{Options, water_equivalent};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Scale of the rendered views against the camera's resolution.
pub const VIEW_SCALE: f64 = 0.125;
/// Tie points per m² for the evaluation (close-range metrology sees fine texture).
pub const DENSITY: f64 = 100.0;

/// One variant's numbers and views.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    /// `poser evaluate …` for this case alone.
    pub command: String,
    /// Distance between the first two spot lights, m (NaN with fewer).
    pub lamp_separation_m: f64,
    /// Distance between the first two cameras' entrance pupils, m (NaN with one camera).
    pub baseline_m: f64,
    /// Depth of the board's centre in the left camera's frame at the viewed pose, m.
    pub distance_m: f64,
    pub light: Measured,
    pub accuracy: Accuracy,
    /// One stereo pair's depth precision at the board's distance, mm (normal case).
    pub pair_sigma_z_mm: f64,
    pub seconds: f64,
    #[serde(skip)]
    pub view_png: Vec<u8>,
    #[serde(skip)]
    pub backscatter_png: Vec<u8>,
}

/// Render, measure and evaluate one case.
pub fn run_case(c: &Case, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let t0 = std::time::Instant::now();
    let err = |e: String| format!("variant `{}`: {e}", c.label);
    let m = &c.model;
    let board = m.targets.first().ok_or_else(|| {
        err(
            "the metrology lesson needs a checkerboard as its first target\n  help: add \
             `[[targets]]` with `type = \"checkerboard\"` in view of the network"
                .into(),
        )
    })?;
    if m.poses.is_empty() || m.cameras.is_empty() {
        return Err(err("the network has no images".into()));
    }
    // The rig pose nearest the board (horizontally), alone, at a reduced resolution.
    let at = board.pose.translation;
    let pose = (0..m.poses.len())
        .min_by(|&a, &b| {
            let d = |i: usize| {
                let t = m.poses[i].world_from_rig.translation - at;
                t.x.hypot(t.y)
            };
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    let mut view = m.clone();
    view.poses = vec![m.poses[pose].clone()];
    let view = view.with_resolution_scale(VIEW_SCALE);
    progress(&format!("rendering `{}`", c.label));
    let img = contrast::render(&view).map_err(err)?;
    let mut empty = view.clone();
    empty.targets.clear();
    empty.objects.clear();
    progress(&format!("rendering `{}` with nothing but water", c.label));
    let bs = contrast::render(&empty).map_err(err)?;
    let light = contrast::measure(&view, &img, &bs).map_err(err)?;
    let dir = out.join(&c.slug);
    let view_png = contrast::view_png(&img, &dir.join("view.png")).map_err(err)?;
    let backscatter_png = contrast::view_png(&bs, &dir.join("backscatter.png")).map_err(err)?;

    let distance = m.world_from_camera(pose, 0).inverse().transform_point(at).z;
    let baseline = if m.cameras.len() >= 2 {
        (m.cameras[0].rig_from_camera.translation - m.cameras[1].rig_from_camera.translation)
            .length()
    } else {
        f64::NAN
    };
    let opts = Options {
        gcp: true,
        rig: true,
        density: DENSITY,
        ..Options::default()
    };
    let f = water_equivalent(m, 0, distance).map_err(err)?[0];
    let pair_sigma_z = distance * distance * std::f64::consts::SQRT_2 * opts.noise / (baseline * f);
    progress(&format!(
        "evaluating `{}` ({} images)",
        c.label,
        m.poses.len() * m.cameras.len()
    ));
    let accuracy = dive::accuracy(m, &opts, &dir).map_err(err)?;
    Ok(Row {
        label: c.label.clone(),
        command: format!("{} --gcp --rig --density {DENSITY}", c.command("evaluate")),
        lamp_separation_m: contrast::strobe_separation(m),
        baseline_m: baseline,
        distance_m: distance,
        light,
        accuracy,
        pair_sigma_z_mm: 1e3 * pair_sigma_z,
        seconds: t0.elapsed().as_secs_f64(),
        view_png,
        backscatter_png,
    })
}

/// RMS Z of the block against the baseline (points), and one pair's σZ (the curve), SVG.
pub fn baseline_plot(rows: &[Row]) -> Result<String, String> {
    use plotters::prelude::*;
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.baseline_m.is_finite())
        .map(|r| (r.baseline_m, r.accuracy.rms_xyz_mm[2]))
        .collect();
    let Some(first) = rows.iter().find(|r| r.baseline_m.is_finite()) else {
        return Ok(String::new());
    };
    // σZ·B is the same for every baseline at one distance and focal length.
    let k = first.pair_sigma_z_mm * first.baseline_m;
    let b_max = pts.iter().map(|p| p.0).fold(0.0, f64::max) * 1.2;
    let b_min = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) * 0.8;
    let curve: Vec<(f64, f64)> = (0..=100)
        .map(|i| b_min + (b_max - b_min) * i as f64 / 100.0)
        .map(|b| (b, k / b))
        .collect();
    let y_max = curve
        .iter()
        .chain(&pts)
        .map(|p| p.1)
        .filter(|y| y.is_finite())
        .fold(0.0, f64::max)
        * 1.1;
    crate::plan::plot::register_font()?;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (520, 320)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Depth error against the stereo baseline",
                ("sans-serif", 15),
            )
            .margin(10)
            .x_label_area_size(34)
            .y_label_area_size(48)
            .build_cartesian_2d(b_min..b_max, 0.0..y_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("baseline, m")
            .y_desc("depth error, mm")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(curve, RED))
            .map_err(|e| e.to_string())?
            .label("one pair, σZ = Z²·√2σ/(B·f)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, BLUE.filled())))
            .map_err(|e| e.to_string())?
            .label("the block (evaluate), RMS Z")
            .legend(|(x, y)| Circle::new((x + 8, y), 4, BLUE.filled()));
        crate::plan::plot::legend(&mut chart, SeriesLabelPosition::MiddleRight)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(s)
}

/// The page's numbers and figures.
pub fn html(rows: &[Row]) -> String {
    let mut s = String::from(
        "<h2>Light: backscatter and contrast</h2>\n<p>The left camera's view of the board at the \
         rig position nearest it, rendered by the native renderer, and the same view with \
         nothing but water in it: what the lamps light in the water between the camera and the \
         scene comes back as a veil. Contrast: Michelson, green channel, over the central half \
         of every square (found by the board's exact projection).</p>\n<table><tr><th>case</th>\
         <th>lamps apart, m</th><th>backscatter (G), W/(m²·sr)</th><th>Michelson contrast</th>\
         <th>contrast without backscatter</th><th>veiling share, %</th><th>R/G</th><th>B/G</th>\
         </tr>\n",
    );
    for r in rows {
        let l = &r.light;
        case_row(
            &mut s,
            &r.label,
            &[
                ("lamp_separation_m", format!("{:.2}", r.lamp_separation_m)),
                ("backscatter", format!("{:.3e}", l.backscatter[1])),
                ("contrast", format!("{:.3}", l.contrast)),
                (
                    "contrast_without_backscatter",
                    format!("{:.3}", l.contrast_without_backscatter),
                ),
                ("veiling_share", format!("{:.1}", 100.0 * l.veiling_share)),
                ("r_over_g", format!("{:.3}", l.r_over_g)),
                ("b_over_g", format!("{:.3}", l.b_over_g)),
            ],
        );
    }
    s.push_str(
        "</table>\n<h2>Measurement: the stereo baseline</h2>\n<p><code>poser evaluate</code> \
         in observations mode: exact refractive projections of tie points on the pipe and the \
         seabed with 0.3 px noise, bundle-adjusted by COLMAP with the rig calibrated \
         beforehand (intrinsics and the cameras' poses in the rig held), aligned on the \
         control points. One pair: the normal case of stereo at the board's distance, \
         σZ = Z²·√2σ/(B·f).</p>\n<table><tr><th>case</th><th>baseline, m</th><th>images</th>\
         <th>points</th><th>reprojection, px</th><th>RMS X, mm</th><th>RMS Y, mm</th>\
         <th>RMS Z, mm</th><th>RMS 3D, mm</th><th>one pair's σZ, mm</th>\
         <th>scale error, ppm</th></tr>\n",
    );
    for r in rows {
        let a = &r.accuracy;
        case_row(
            &mut s,
            &r.label,
            &[
                ("baseline_m", format!("{:.2}", r.baseline_m)),
                ("images", a.images.to_string()),
                ("points", a.points.to_string()),
                ("reprojection_px", format!("{:.3}", a.reprojection_px)),
                ("rms_x_mm", format!("{:.2}", a.rms_xyz_mm[0])),
                ("rms_y_mm", format!("{:.2}", a.rms_xyz_mm[1])),
                ("rms_z_mm", format!("{:.2}", a.rms_xyz_mm[2])),
                ("rms_3d_mm", format!("{:.2}", a.rms_3d_mm)),
                ("pair_sigma_z_mm", format!("{:.2}", r.pair_sigma_z_mm)),
                ("scale_error_ppm", format!("{:.0}", a.scale_error_ppm)),
            ],
        );
    }
    s.push_str("</table>\n");
    match baseline_plot(rows) {
        Ok(plot) if !plot.is_empty() => {
            let _ = writeln!(
                s,
                "<figure>{}<figcaption>The block's RMS depth error (blue) and one stereo \
                 pair's (red) against the baseline.</figcaption></figure>",
                svg(&plot)
            );
        }
        Ok(_) => {}
        Err(e) => {
            let _ = writeln!(s, "<p class=\"small\">(no plot: {})</p>", escape(&e));
        }
    }
    s.push_str(
        "<p class=\"small\">Each view is scaled to its own brightness (99th percentile): \
         compare the numbers, not the brightness.</p>\n<h2>Views</h2>\n",
    );
    for r in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{a}<figcaption>The left camera's view.</figcaption></figure>\n\
             <figure>{b}<figcaption>The same view with nothing but water: backscatter only.\
             </figcaption></figure>\n<p class=\"small\">Evaluate this case alone: \
             <code>{cmd}</code></p>\n",
            l = escape(&r.label),
            a = png(&r.view_png, &format!("view, {}", r.label)),
            b = png(&r.backscatter_png, &format!("backscatter, {}", r.label)),
            cmd = escape(&r.command),
        );
    }
    s
}
