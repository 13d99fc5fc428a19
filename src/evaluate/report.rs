//! The files `poser evaluate` writes, each atomically (temporary file, then rename), and only
//! after the whole evaluation succeeded, so a failed run leaves no partial report.
//!
//! | file | contents |
//! |---|---|
//! | `report.json` | the whole [`Evaluation`] (numbers, settings, COLMAP's summary), and `target_points`: each target point's label, role (`control`, `check`, `target`), truth, error and images |
//! | `report.md` | the same numbers as tables a person reads |
//! | `errors.csv` | `id,kind,label,x,y,z,dx,dy,dz,track`: one row per reconstructed point (truth frame, m) |
//! | `deformation.png` | top view of the plot, each point coloured by its height error (blue low, red high, white zero; the colour bar is labelled with its range, ± the 99th percentile of |dz|, also in `report.md`); black dots are the camera centres |
//! | `profile.svg` | mean height error along and across the plot, in bins |

use super::Evaluation;
use crate::io::write_atomic;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;

/// Write every report file into `dir`.
pub fn write(ev: &Evaluation, dir: &Path) -> Result<(), String> {
    let files = [
        ("report.json", json(ev)?),
        ("report.md", markdown(ev).into_bytes()),
        ("errors.csv", csv(ev).into_bytes()),
        ("deformation.png", deformation_png(ev)?),
        ("profile.svg", profile_svg(ev)?.into_bytes()),
    ];
    for (name, bytes) in files {
        let p = dir.join(name);
        write_atomic(&p, &bytes).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(())
}

fn json(ev: &Evaluation) -> Result<Vec<u8>, String> {
    let mut doc = serde_json::to_value(ev).map_err(|e| e.to_string())?;
    if let Some(o) = doc.as_object_mut() {
        o.insert("target_points".into(), target_points(ev));
    }
    let mut v = serde_json::to_vec_pretty(&doc).map_err(|e| e.to_string())?;
    v.push(b'\n');
    Ok(v)
}

fn mm(x: f64) -> String {
    format!("{:.2}", x * 1e3)
}

/// The report as Markdown.
pub fn markdown(ev: &Evaluation) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# poser evaluate: {}\n", ev.scene);
    let aligned = match ev.gcp_sigma {
        Some(sigma) => format!(
            "the control points **weighted in the bundle adjustment** (σ {} mm per axis; {} \
             used), with no similarity after",
            mm(sigma),
            ev.alignment_count
        ),
        None => format!(
            "aligned on **{}** ({} used)",
            ev.alignment, ev.alignment_count
        ),
    };
    let _ = writeln!(
        s,
        "Mode **{:?}**, camera model **{}** (self-calibrated, the port ignored), {aligned}. {}.\n",
        ev.mode,
        ev.camera_model.name(),
        ev.conventions
    );
    let _ = writeln!(s, "| quantity | value |\n|---|---|");
    let _ = writeln!(
        s,
        "| registered images | {} of {} ({:.1} %) |",
        ev.registered,
        ev.images,
        100.0 * ev.registered as f64 / ev.images.max(1) as f64
    );
    let _ = writeln!(s, "| 3D points | {} |", ev.points);
    let _ = writeln!(s, "| mean track length | {:.2} |", ev.mean_track_length);
    let _ = writeln!(
        s,
        "| mean reprojection error | {:.3} px |",
        ev.reprojection_error
    );
    let _ = writeln!(s, "| run time | {:.1} s |\n", ev.seconds);
    health(&mut s, ev);
    let r = &ev.tie_errors.robust_z;
    let _ = writeln!(
        s,
        "**Height error of the tie points:** median {:+.2} mm, NMAD {} mm, LE90 {} mm \
         (robust); RMS {} mm; {:.1} % of the points beyond 3 NMAD.\n",
        1e3 * r.median,
        mm(r.nmad),
        mm(r.le90),
        mm(ev.tie_errors.rms[2]),
        100.0 * r.outliers
    );

    intrinsics(&mut s, ev);
    let _ = writeln!(s, "\n## 3D errors after alignment (mm)\n");
    let _ = writeln!(
        s,
        "| points | count | RMS X | RMS Y | RMS Z | RMS 3D | max X | max Y | max Z |\n|---|---|---|---|---|---|---|---|---|"
    );
    let mut row = |name: &str, a: &super::AxisStats| {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} |",
            a.count,
            mm(a.rms[0]),
            mm(a.rms[1]),
            mm(a.rms[2]),
            mm(a.rms_3d),
            mm(a.max[0]),
            mm(a.max[1]),
            mm(a.max[2])
        );
    };
    row("tie points", &ev.tie_errors);
    if let Some(c) = &ev.control_errors {
        row("control points (GCPs)", c);
    }
    if let Some(c) = &ev.check_errors {
        row("targets (check points)", c);
    }
    row("camera centres", &ev.camera_errors);
    let _ = writeln!(
        s,
        "\nRobust figures of the height error (mm): the median is the systematic shift, NMAD \
         (1.4826 × the median absolute deviation) the spread of the core, LE90 the 90 % \
         quantile of |dz|.\n"
    );
    let _ = writeln!(
        s,
        "| points | median Z | NMAD Z | LE90 Z | beyond 3 NMAD |\n|---|---|---|---|---|"
    );
    let mut robust = |name: &str, a: &super::AxisStats| {
        let r = &a.robust_z;
        let _ = writeln!(
            s,
            "| {name} | {:+.2} | {} | {} | {:.1} % |",
            1e3 * r.median,
            mm(r.nmad),
            mm(r.le90),
            100.0 * r.outliers
        );
    };
    robust("tie points", &ev.tie_errors);
    if let Some(c) = &ev.check_errors {
        robust("targets (check points)", c);
    }
    target_tables(&mut s, ev);
    let _ = writeln!(s, "\n## The systematic part (\"bowl\")\n");
    match &ev.bowl {
        Some(b) => {
            let _ = writeln!(
                s,
                "A quadratic surface fitted to the height errors explains **{:.1} %** of their \
                 variance: peak-to-peak **{} mm**, RMS {} mm; what is left has an RMS of {} mm.\n",
                100.0 * b.explained,
                mm(b.peak_to_peak),
                mm(b.rms_fit),
                mm(b.rms_residual)
            );
        }
        None => {
            let _ = writeln!(s, "Too few points to fit a surface.\n");
        }
    }
    let _ = writeln!(
        s,
        "`deformation.png`: height error per point, blue −{m} mm … white 0 … red +{m} mm; black \
         dots: camera centres. `profile.svg`: mean height error along and across the plot.",
        m = mm(color_scale(ev))
    );
    s
}

/// The recovered intrinsics against the in-water-equivalent truth, and whether the images
/// determine the focal length.
fn intrinsics(s: &mut String, ev: &Evaluation) {
    let _ = writeln!(s, "## Intrinsics against the in-water-equivalent truth\n");
    let _ = writeln!(
        s,
        "| camera | f in air | f truth (water-equiv.) | f recovered | focal error | cx, cy truth | cx, cy recovered | other |\n|---|---|---|---|---|---|---|---|"
    );
    for c in &ev.cameras {
        let other: Vec<String> = c
            .extra
            .iter()
            .map(|(n, v)| format!("{n} = {v:.4e}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {:.1} px | {:.1} × {:.1} px (at {:.2} m) | {:.1} × {:.1} px | {:+.2} % | {:.1}, {:.1} | {:.1}, {:.1} | {} |",
            c.name,
            c.f_air,
            c.truth[0],
            c.truth[1],
            c.distance,
            c.recovered[0],
            c.recovered[1],
            100.0 * c.focal_error,
            c.truth[2],
            c.truth[3],
            c.recovered[2],
            c.recovered[3],
            other.join(", ")
        );
    }
    let mut evidence = Vec::new();
    if let Some(sens) = ev.focal_sensitivity() {
        evidence.push(format!(
            "holding the focal length 10 % off its estimate raises the mean reprojection error \
             by {}",
            if sens >= super::FOCAL_RISE_CAP {
                format!("more than {:.0} %", 100.0 * super::FOCAL_RISE_CAP)
            } else {
                format!("{:.3} %", 100.0 * sens)
            }
        ));
    }
    if ev.focal_singular() {
        evidence.push(
            "the adjustment's normal matrix is singular in the camera and the poses".to_string(),
        );
    } else if let Some(sd) = ev.focal_sd() {
        evidence.push(format!(
            "the adjustment's covariance gives it a standard deviation of {:.3} % per pixel of \
             image noise (about {:.3} % at this block's reprojection error)",
            100.0 * sd,
            100.0 * sd * ev.reprojection_error
        ));
    }
    if let Some(determined) = ev.focal_determined() {
        let mut first = evidence.join("; ");
        if let Some(c) = first.get_mut(..1) {
            c.make_ascii_uppercase();
        }
        let _ = writeln!(
            s,
            "\n{first}: {}",
            if determined {
                "the images determine the focal length."
            } else {
                "**the images do not determine the focal length** (a nearly flat block seen \
                 from above: focal length and height trade against each other), so the focal \
                 error above is not a measurement. Obliques, the diver's wobble or a calibration \
                 beforehand fix it; relief or a second height does not help a block whose \
                 images all look one way."
            }
        );
    }
}

/// The health warnings, or a line saying there are none.
fn health(s: &mut String, ev: &Evaluation) {
    if ev.warnings.is_empty() {
        let _ = writeln!(
            s,
            "Health: no warning (every image registered; where self-calibrated, the focal \
             length determined and near its nominal value; the camera model fits; no \
             outlier-driven RMS).\n"
        );
        return;
    }
    let _ = writeln!(s, "## ⚠ Warnings\n");
    for w in &ev.warnings {
        let _ = writeln!(s, "- **{}** — {} *Help:* {}.", w.code, w.message, w.help);
    }
    s.push('\n');
}

/// The control and check tables of a `--gcp` evaluation (the targets' table otherwise), and
/// which RMSE is the accuracy: the check points', since the alignment fitted the control points.
fn target_tables(s: &mut String, ev: &Evaluation) {
    let n = |kind: &str| ev.point_errors.iter().filter(|p| p.kind == kind).count();
    if ev.alignment != "gcp" {
        points_table(s, ev, "target", "Targets (not used by the alignment)");
        return;
    }
    let (control, check, fitted) = match ev.gcp_sigma {
        Some(sigma) => (
            format!(
                "Control points (GCPs, weighted in the adjustment, σ = {} mm)",
                mm(sigma)
            ),
            "Check points (held out of the adjustment)".to_string(),
            "the adjustment was pulled onto",
        ),
        None => (
            "Control points (GCPs, used by the alignment)".to_string(),
            "Check points (held out of the alignment)".to_string(),
            "the alignment was fitted to",
        ),
    };
    points_table(s, ev, "gcp", &control);
    points_table(s, ev, "check", &check);
    let _ = if n("check") > 0 {
        writeln!(
            s,
            "\n**The check points' RMSE is the honest accuracy figure**: {fitted} the {} \
             control point(s), so their RMSE shows how well the block was made to meet them, \
             not how right the model is.",
            n("gcp")
        )
    } else {
        writeln!(
            s,
            "\n**No check points: the control RMSE above is a fit, not an accuracy.** The \
             alignment was fitted to these {} point(s); hold some targets out with `--check IDS` \
             (or name the control points with `--gcp IDS`) to measure the model's accuracy.",
            n("gcp")
        )
    };
}

/// The target points of `report.json`: label, role (`control`, `check` or `target`: not used
/// by the alignment), error (m) and images, one per reconstructed target point.
fn target_points(ev: &Evaluation) -> serde_json::Value {
    ev.point_errors
        .iter()
        .filter(|p| p.kind != "tie")
        .map(|p| {
            serde_json::json!({
                "label": p.label,
                "role": if p.kind == "gcp" { "control" } else { p.kind },
                "truth": p.truth,
                "error": p.error,
                "error_3d": DVec3::from_array(p.error).length(),
                "images": p.track,
            })
        })
        .collect()
}

/// One row per point of `kind`, and their RMSE, as Metashape's marker tables give them (mm).
fn points_table(s: &mut String, ev: &Evaluation, kind: &str, title: &str) {
    let pts: Vec<&super::PointError> = ev.point_errors.iter().filter(|p| p.kind == kind).collect();
    if pts.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n### {title}\n\n| point | X error | Y error | Z error | 3D error | images |\n|---|---|---|---|---|---|"
    );
    let errors: Vec<DVec3> = pts.iter().map(|p| DVec3::from_array(p.error)).collect();
    for (p, e) in pts.iter().zip(&errors) {
        let _ = writeln!(
            s,
            "| {} | {:+.2} | {:+.2} | {:+.2} | {} | {} |",
            p.label.replace('|', "\\|"),
            1e3 * e.x,
            1e3 * e.y,
            1e3 * e.z,
            mm(e.length()),
            p.track
        );
    }
    let rmse = super::AxisStats::of(&errors);
    let _ = writeln!(
        s,
        "| **RMSE** ({}) | {} | {} | {} | {} | |",
        rmse.count,
        mm(rmse.rms[0]),
        mm(rmse.rms[1]),
        mm(rmse.rms[2]),
        mm(rmse.rms_3d)
    );
}

fn csv(ev: &Evaluation) -> String {
    let mut s = String::from("id,kind,label,x,y,z,dx,dy,dz,track\n");
    for p in &ev.point_errors {
        let _ = writeln!(
            s,
            "{},{},{},{:.6},{:.6},{:.6},{:.6e},{:.6e},{:.6e},{}",
            p.id,
            p.kind,
            crate::truth::csv_field(&p.label),
            p.truth[0],
            p.truth[1],
            p.truth[2],
            p.error[0],
            p.error[1],
            p.error[2],
            p.track
        );
    }
    s
}

/// The colour scale of the map, m: the 99th percentile of |dz| (outliers saturate).
pub fn color_scale(ev: &Evaluation) -> f64 {
    let mut v: Vec<f64> = ev.point_errors.iter().map(|p| p.error[2].abs()).collect();
    if v.is_empty() {
        return 1e-3;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * 0.99) as usize].max(1e-6)
}

fn diverging(t: f64) -> [u8; 3] {
    // Blue (−1) → white (0) → red (+1).
    let t = t.clamp(-1.0, 1.0);
    let (r, g, b) = if t < 0.0 {
        let a = -t;
        (1.0 - 0.8 * a, 1.0 - 0.6 * a, 1.0)
    } else {
        (1.0, 1.0 - 0.75 * t, 1.0 - 0.8 * t)
    };
    [r, g, b].map(|c| (c * 255.0).round() as u8)
}

/// Top view of the plot coloured by height error, on its own scale ([`color_scale`]).
pub fn deformation_png(ev: &Evaluation) -> Result<Vec<u8>, String> {
    deformation_png_scaled(ev, color_scale(ev))
}

/// Top view of the plot coloured by height error, blue at −`scale` and red at +`scale` (m),
/// so that several maps can share one scale. Target points (control, check) are ringed in
/// black; camera centres are black dots.
pub fn deformation_png_scaled(ev: &Evaluation, scale: f64) -> Result<Vec<u8>, String> {
    let pts: Vec<(DVec3, f64)> = ev
        .point_errors
        .iter()
        .map(|p| (DVec3::from_array(p.truth), p.error[2]))
        .collect();
    let targets: Vec<(DVec3, f64)> = ev
        .point_errors
        .iter()
        .filter(|p| p.kind != "tie")
        .map(|p| (DVec3::from_array(p.truth), p.error[2]))
        .collect();
    let all = pts.iter().map(|p| p.0).chain(ev.centres.iter().copied());
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in all {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let (w_px, h_px) = if lo.x.is_finite() && hi.x > lo.x && hi.y > lo.y {
        let aspect = (hi.y - lo.y) / (hi.x - lo.x);
        let w = 800u32;
        (w, ((w as f64 * aspect).round() as u32).clamp(50, 2400))
    } else {
        (100, 100)
    };
    let bar = 30u32 + BAR_LABELS;
    let mut img = image::RgbImage::from_pixel(w_px + bar, h_px, image::Rgb([96, 96, 96]));
    let to_px = |p: DVec3| {
        let x = (p.x - lo.x) / (hi.x - lo.x).max(1e-9) * (w_px - 1) as f64;
        let y = (hi.y - p.y) / (hi.y - lo.y).max(1e-9) * (h_px - 1) as f64;
        (x, y)
    };
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1e-3
    };
    let r = (2.0 + 800.0 / (pts.len() as f64).sqrt().max(1.0) * 0.3).min(6.0);
    let dot = |img: &mut image::RgbImage, x: f64, y: f64, r: f64, c: [u8; 3]| {
        let (x0, x1) = ((x - r).floor() as i64, (x + r).ceil() as i64);
        let (y0, y1) = ((y - r).floor() as i64, (y + r).ceil() as i64);
        for yy in y0..=y1 {
            for xx in x0..=x1 {
                if xx < 0 || yy < 0 || xx >= w_px as i64 || yy >= h_px as i64 {
                    continue;
                }
                if ((xx as f64 - x).powi(2) + (yy as f64 - y).powi(2)) <= r * r {
                    img.put_pixel(xx as u32, yy as u32, image::Rgb(c));
                }
            }
        }
    };
    for (p, dz) in &pts {
        let (x, y) = to_px(*p);
        dot(&mut img, x, y, r, diverging(dz / scale));
    }
    for c in &ev.centres {
        let (x, y) = to_px(*c);
        dot(&mut img, x, y, 1.5, [0, 0, 0]);
    }
    for (p, dz) in &targets {
        let (x, y) = to_px(*p);
        dot(&mut img, x, y, 7.0, [0, 0, 0]);
        dot(&mut img, x, y, 4.5, diverging(dz / scale));
    }
    for yy in 0..h_px {
        let t = 1.0 - 2.0 * yy as f64 / (h_px - 1).max(1) as f64;
        for xx in w_px + 8..w_px + 26 {
            img.put_pixel(xx, yy, image::Rgb(diverging(t)));
        }
    }
    label_bar(&mut img, w_px + 30, scale)?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

/// Width of the colour bar's labels in `deformation.png`, px.
const BAR_LABELS: u32 = 90;

/// The colour bar's range written beside it, so that a map read alone says its scale:
/// `+S mm` at the top, `0` in the middle, `−S mm` at the bottom (`scale` in m).
fn label_bar(img: &mut image::RgbImage, x: u32, scale: f64) -> Result<(), String> {
    crate::plan::plot::register_font()?;
    use plotters::prelude::*;
    let (w, h) = img.dimensions();
    let v = 1e3 * scale;
    let num = if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    };
    let size = (h / 50).clamp(11, 18);
    let root = BitMapBackend::with_buffer(img, (w, h)).into_drawing_area();
    let style = ("sans-serif", size).into_font().color(&WHITE);
    let (x, h, sz) = (x as i32, h as i32, size as i32);
    for (text, y) in [
        (format!("+{num} mm"), 3),
        ("0".to_string(), h / 2 - sz / 2),
        (format!("−{num} mm"), h - sz - 3),
    ] {
        root.draw_text(&text, &style, (x, y))
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}

/// Binned means of the height error along x and along y, as an SVG chart.
pub fn profile_svg(ev: &Evaluation) -> Result<String, String> {
    crate::plan::plot::register_font()?;
    use plotters::prelude::*;
    let bins = 24usize;
    let series = |axis: usize| -> Vec<(f64, f64)> {
        let xs: Vec<(f64, f64)> = ev
            .point_errors
            .iter()
            .map(|p| (p.truth[axis], p.error[2]))
            .collect();
        let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.0), a.1.max(p.0))
        });
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Vec::new();
        }
        let mut sum = vec![(0.0, 0usize); bins];
        for (x, dz) in xs {
            let b = (((x - lo) / (hi - lo)) * bins as f64)
                .floor()
                .min(bins as f64 - 1.0) as usize;
            sum[b].0 += dz;
            sum[b].1 += 1;
        }
        sum.iter()
            .enumerate()
            .filter(|(_, s)| s.1 > 0)
            .map(|(i, s)| {
                (
                    lo + (i as f64 + 0.5) / bins as f64 * (hi - lo),
                    1e3 * s.0 / s.1 as f64,
                )
            })
            .collect()
    };
    let along_x = series(0);
    let along_y = series(1);
    let all = along_x.iter().chain(&along_y);
    let (x0, x1, y0, y1) = all.fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |a, p| (a.0.min(p.0), a.1.max(p.0), a.2.min(p.1), a.3.max(p.1)),
    );
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { (0.0, 1.0) };
    let pad = ((y1 - y0) * 0.1).max(0.01);
    let (y0, y1) = if y1 >= y0 {
        (y0 - pad, y1 + pad)
    } else {
        (-1.0, 1.0)
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 400)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Mean height error along the plot", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("world x or y, m")
            .y_desc("dz, mm")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(along_x.iter().copied(), &RED))
            .map_err(|e| e.to_string())?
            .label("along x")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart
            .draw_series(LineSeries::new(along_y.iter().copied(), &BLUE))
            .map_err(|e| e.to_string())?
            .label("along y")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::PointError;

    fn point(label: &str, kind: &'static str, mm: [f64; 3]) -> PointError {
        PointError {
            id: 1,
            label: label.into(),
            kind,
            truth: [0.0; 3],
            error: mm.map(|v| v * 1e-3),
            track: 5,
        }
    }

    /// The row of `md`'s table titled `title` whose first cell is `first`, as its cells.
    fn row(md: &str, title: &str, first: &str) -> Vec<String> {
        let at = md
            .find(title)
            .unwrap_or_else(|| panic!("no {title} in\n{md}"));
        let line = md[at..]
            .lines()
            .find(|l| l.starts_with(&format!("| {first} ")))
            .unwrap_or_else(|| panic!("no row {first} under {title}"));
        line.split('|').map(|c| c.trim().to_string()).collect()
    }

    /// Control and check points with known residuals: each point's X/Y/Z and 3D error, and the
    /// RMSE of each table, as arithmetic gives them.
    #[test]
    fn control_and_check_tables_give_known_residuals_and_their_rmse() {
        let mut ev = crate::evaluate::health::tests::healthy();
        ev.alignment = "gcp".into();
        ev.point_errors = vec![
            point("tie", "tie", [9.0, 9.0, 9.0]),
            point("G1/1", "gcp", [3.0, 4.0, 0.0]),
            point("G2/1", "gcp", [-3.0, -4.0, 0.0]),
            point("C1/1", "check", [0.0, 0.0, 12.0]),
            point("C2/1", "check", [0.0, 0.0, -5.0]),
        ];
        let md = markdown(&ev);
        let control = "### Control points (GCPs, used by the alignment)";
        let check = "### Check points (held out of the alignment)";
        assert_eq!(
            row(&md, control, "G1/1")[1..6],
            ["G1/1", "+3.00", "+4.00", "+0.00", "5.00"]
        );
        // RMSE X 3, Y 4, Z 0, 3D 5 mm over the two control points.
        assert_eq!(
            row(&md, control, "**RMSE**")[1..6],
            ["**RMSE** (2)", "3.00", "4.00", "0.00", "5.00"]
        );
        // Z: √((12² + 5²)/2) = 9.19 mm; the tie point is in neither table.
        assert_eq!(
            row(&md, check, "**RMSE**")[1..6],
            ["**RMSE** (2)", "0.00", "0.00", "9.19", "9.19"]
        );
        assert_eq!(row(&md, check, "C2/1")[4], "-5.00");
        assert!(!md[md.find(control).unwrap()..].contains("| tie |"));
        assert!(md.contains("**The check points' RMSE is the honest accuracy figure**"));
        // Without check points the control RMSE is called a fit.
        ev.point_errors.retain(|p| p.kind != "check");
        let md = markdown(&ev);
        assert!(!md.contains(check));
        assert!(md.contains("**No check points: the control RMSE above is a fit"));
    }

    /// The labels drawn beside the colour bar of a 300 px tall map: white text in the label
    /// column at the top, middle and bottom, and a different text for a different range.
    #[test]
    fn the_colour_bar_is_labelled_with_its_range() {
        let (w, h) = (40 + BAR_LABELS, 300u32);
        let labelled = |scale: f64| {
            let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([96, 96, 96]));
            label_bar(&mut img, 40, scale).unwrap();
            img
        };
        let a = labelled(0.254);
        let bright = |img: &image::RgbImage, y0: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (40..w).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y)[0] > 200)
                .count()
        };
        for (y0, y1) in [(0, 30), (h / 2 - 15, h / 2 + 15), (h - 30, h)] {
            assert!(bright(&a, y0, y1) > 5, "no label in rows {y0}..{y1}");
        }
        // Nothing drawn left of the label column (the map) nor between the labels.
        assert_eq!(bright(&a, 40, h / 2 - 20), 0);
        assert!((0..40).all(|x| (0..h).all(|y| a.get_pixel(x, y)[0] == 96)));
        assert_ne!(
            a,
            labelled(0.00062),
            "the range is written, not a fixed label"
        );
    }
}
