//! Lesson kind `gsd`: the camera height that gives the lesson's GSD, through the port and in
//! air, from the exact projection ([`crate::plan::survey::distance_for_gsd`]: the GSD on the
//! optical axis, a 1 mm step across it); the camera is placed at that height over the first
//! target (a Siemens star), the native renderer renders the view, and the smallest resolved
//! element of the star is measured on the linear radiance (green channel).
//!
//! | number | meaning |
//! |---|---|
//! | height | entrance pupil to the star along the optical axis, m, for the planned GSD |
//! | height in air | the same camera and port with n = 1 |
//! | mean contrast at radius r | (I_light − I_dark)/(I_light + I_dark) over points in the central half of every sector on the circle of radius r, each projected exactly into the image and read bilinearly; light or dark from the printed pattern (an MTF-like curve: it still sees some modulation past Nyquist, where the bars alias) |
//! | bar dips at radius r | for every light sector, the pixel holding its middle against the pixels holding its two dark neighbours' middles: Michelson (L − max D)/(L + max D) — a Rayleigh-like dip |
//! | smallest resolved element | the bar (sector) width π·r/spokes at the smallest radius down to which, on every circle, every light sector's dip is ≥ [`RESOLVED`]; in mm and in pixels (the projected chord of one sector there) |
//! | 10 % mean contrast | the bar width where the mean contrast falls to [`RESOLVED`] (for comparison) |
//!
//! Circles not wholly on the sensor are skipped.

use super::Case;
use super::contrast::{bilinear, distance_for_gsd, place, render, view_png};
use super::html::{escape, num, png, svg};
use crate::geometry::targets;
use crate::model::{Model, TargetKind};
use crate::optics::project::Projector;
use crate::optics::types::Port;
use glam::DVec3;
use serde::Serialize;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// Michelson contrast from which an element counts as resolved.
pub const RESOLVED: f64 = 0.10;
/// Circles measured, from 0.95 of the star's radius inwards (geometric steps).
const CIRCLES: usize = 90;
/// Points per sector, in its central half.
const PER_SECTOR: usize = 4;

/// Contrast on one circle.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Circle {
    pub radius_mm: f64,
    pub bar_mm: f64,
    pub bar_px: f64,
    /// Mean contrast of light against dark sectors.
    pub contrast: f64,
    /// Smallest dip of a light sector against its dark neighbours.
    pub min_dip: f64,
}

/// One variant's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    pub command: String,
    /// `"flat"`, `"dome"`, `"cylinder"` or `"none"`.
    pub port: String,
    pub gsd_mm: f64,
    pub height_m: f64,
    pub height_air_m: f64,
    /// GSD measured on the star's plane at its centre from the exact projection, mm/px.
    pub gsd_at_star_mm: f64,
    pub smallest_resolved_mm: f64,
    pub smallest_resolved_px: f64,
    /// Smallest resolved bar width over the planned GSD.
    pub resolved_over_gsd: f64,
    /// Bar width where the mean contrast falls to [`RESOLVED`], px.
    pub mean_contrast_10_px: f64,
    pub spokes: u32,
    pub circles: Vec<Circle>,
    pub seconds: f64,
    #[serde(skip)]
    pub view_png: Vec<u8>,
    #[serde(skip)]
    pub contrast_svg: String,
}

fn port_name(p: &Port) -> &'static str {
    match p {
        Port::None => "none",
        Port::Flat { .. } => "flat",
        Port::Dome { .. } => "dome",
        _ => "cylinder",
    }
}

/// The contrast on circles of the star (target 0) in `img`.
fn circles(model: &Model, img: &crate::backend::native::Image) -> Result<Vec<Circle>, String> {
    let t = &model.targets[0];
    let TargetKind::SiemensStar { diameter, spokes } = t.kind else {
        return Err(format!(
            "target `{}`: the GSD lesson measures a Siemens star\n  help: make the first \
             target `type = \"siemens_star\"`",
            t.name
        ));
    };
    let pr = model.projector(0, 1)?;
    let sector = PI / spokes as f64;
    let world = |r: f64, a: f64| {
        t.pose
            .transform_point(DVec3::new(r * a.cos(), r * a.sin(), 0.0))
    };
    let mut out = Vec::new();
    for k in 0..CIRCLES {
        let r = 0.95 * diameter / 2.0 * (0.01f64 / 0.95).powf(k as f64 / (CIRCLES - 1) as f64);
        let (mut light, mut dark) = ((0.0, 0usize), (0.0, 0usize));
        let mut total = 0usize;
        for s in 0..2 * spokes as usize {
            for q in 0..PER_SECTOR {
                let a = (s as f64 + 0.25 + 0.5 * (q as f64 + 0.5) / PER_SECTOR as f64) * sector;
                total += 1;
                let (x, y) = (r * a.cos(), r * a.sin());
                let Ok([u, v]) = pr.project_world(0, world(r, a)) else {
                    continue;
                };
                let Some(val) = bilinear(img, u, v, 1) else {
                    continue;
                };
                let acc = if targets::reflectance(&t.kind, x, y) > 0.5 {
                    &mut light
                } else {
                    &mut dark
                };
                acc.0 += val;
                acc.1 += 1;
            }
        }
        if light.1 + dark.1 < total || light.1 == 0 || dark.1 == 0 {
            continue;
        }
        // The pixel holding each sector's middle (all on the sensor, checked above).
        let n = 2 * spokes as usize;
        let mid: Vec<Option<(f64, bool)>> = (0..n)
            .map(|s| {
                let a = (s as f64 + 0.5) * sector;
                let (x, y) = (r * a.cos(), r * a.sin());
                let [u, v] = pr.project_world(0, world(r, a)).ok()?;
                let (i, j) = (u.floor(), v.floor());
                let val = bilinear(img, i + 0.5, j + 0.5, 1)?;
                Some((val, targets::reflectance(&t.kind, x, y) > 0.5))
            })
            .collect();
        let mut min_dip = f64::INFINITY;
        for s in 0..n {
            let (Some((l, true)), Some((a, _)), Some((b, _))) =
                (mid[s], mid[(s + n - 1) % n], mid[(s + 1) % n])
            else {
                continue;
            };
            let d = a.max(b);
            min_dip = min_dip.min((l - d) / (l + d));
        }
        let (il, id) = (light.0 / light.1 as f64, dark.0 / dark.1 as f64);
        // The projected chord of one sector, px (mean over four directions).
        let bar_px = (0..4)
            .filter_map(|q| {
                let a = q as f64 * PI / 2.0 + 0.25 * sector;
                let p0 = pr.project_world_unbounded(0, world(r, a)).ok()?;
                let p1 = pr.project_world_unbounded(0, world(r, a + sector)).ok()?;
                Some((p1[0] - p0[0]).hypot(p1[1] - p0[1]))
            })
            .sum::<f64>()
            / 4.0;
        out.push(Circle {
            radius_mm: r * 1e3,
            bar_mm: r * sector * 1e3,
            bar_px,
            contrast: (il - id) / (il + id),
            min_dip,
        });
    }
    Ok(out)
}

/// GSD on the star's plane at its centre: 1 mm along the target's x, exact projection, m/px.
fn gsd_at_star(model: &Model) -> Option<f64> {
    let pr = model.projector(0, 1).ok()?;
    let t = &model.targets[0];
    let a = pr
        .project_world_unbounded(0, t.pose.transform_point(DVec3::ZERO))
        .ok()?;
    let b = pr
        .project_world_unbounded(0, t.pose.transform_point(DVec3::new(1e-3, 0.0, 0.0)))
        .ok()?;
    let d = (b[0] - a[0]).hypot(b[1] - a[1]);
    (d > 0.0).then(|| 1e-3 / d)
}

/// Plan, render and measure one case.
pub fn run_case(c: &Case, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let t0 = std::time::Instant::now();
    let mut m = c.model.clone();
    let gsd = m.lesson.as_ref().and_then(|l| l.gsd).ok_or_else(|| {
        format!(
            "variant `{}`: a GSD lesson needs `lesson.gsd`\n  help: write e.g. `gsd = \"1 \
             mm/px\"` in `[lesson]` or the variant's `set`",
            c.label
        )
    })?;
    let h = place(&mut m, gsd, &c.label)?;
    let air = Projector::for_camera(&m.cameras[0], 1, 1.0)
        .ok()
        .and_then(|p| distance_for_gsd(&p, gsd))
        .unwrap_or(f64::NAN);
    progress(&format!("rendering `{}` at {h:.2} m", c.label));
    let img = render(&m)?;
    let circ = circles(&m, &img)?;
    // Down from the outermost circle while every circle is resolved.
    let smallest = circ
        .iter()
        .take_while(|k| k.min_dip >= RESOLVED)
        .last()
        .copied();
    let mtf10 = circ
        .iter()
        .take_while(|k| k.contrast >= RESOLVED)
        .last()
        .map_or(f64::NAN, |k| k.bar_px);
    let spokes = match m.targets[0].kind {
        TargetKind::SiemensStar { spokes, .. } => spokes,
        _ => 0,
    };
    let (mm, px) = smallest.map_or((f64::NAN, f64::NAN), |k| (k.bar_mm, k.bar_px));
    let contrast_svg = contrast_plot(&c.label, &circ, gsd)?;
    Ok(Row {
        label: c.label.clone(),
        command: c.command("render"),
        port: port_name(&m.cameras[0].port).into(),
        gsd_mm: gsd * 1e3,
        height_m: h,
        height_air_m: air,
        gsd_at_star_mm: gsd_at_star(&m).map_or(f64::NAN, |g| g * 1e3),
        smallest_resolved_mm: mm,
        smallest_resolved_px: px,
        resolved_over_gsd: mm / (gsd * 1e3),
        mean_contrast_10_px: mtf10,
        spokes,
        circles: circ,
        seconds: t0.elapsed().as_secs_f64(),
        view_png: view_png(&img, &out.join(&c.slug).join("view.png"))?,
        contrast_svg,
    })
}

/// Contrast against bar width (in planned GSDs), with the threshold.
fn contrast_plot(label: &str, circ: &[Circle], gsd: f64) -> Result<String, String> {
    use plotters::prelude::*;
    crate::plan::plot::register_font()?;
    let pts: Vec<(f64, f64)> = circ
        .iter()
        .map(|k| (k.bar_mm / (gsd * 1e3), k.contrast))
        .collect();
    let dips: Vec<(f64, f64)> = circ
        .iter()
        .map(|k| (k.bar_mm / (gsd * 1e3), k.min_dip.max(-0.1)))
        .collect();
    let xmax = pts.iter().map(|p| p.0).fold(1.0, f64::max);
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (480, 320)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Star contrast, {label}"), ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(0.0..xmax, -0.1..1.0)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("bar width / planned GSD")
            .y_desc("Michelson contrast")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), BLUE))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(dips.iter().copied(), BLACK))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(
                vec![(0.0, RESOLVED), (xmax, RESOLVED)],
                RED,
            ))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(s)
}

/// The page's numbers and figures.
pub fn html(rows: &[Row]) -> String {
    let mut s = format!(
        "<h2>The numbers</h2>\n<p>Height: entrance pupil to the star along the optical axis \
         for the planned GSD, from the exact projection through the port (in air: the same \
         camera with n = 1). Resolved: on circles of the star placed in the image by the exact \
         projection, green channel of the linear radiance, every light sector's pixel is \
         brighter than both its dark neighbours' pixels by a Michelson contrast of at least \
         {:.0} % (a Rayleigh-like dip), on every circle from the rim inwards; the smallest \
         resolved element is the bar (sector) width at the last such circle. The mean \
         contrast of all light against all dark sectors falls to the same level a little \
         further in (last column): past a bar of about a pixel the bars alias.</p>\n<table><tr>\
         <th>case</th><th>port</th><th>planned GSD, mm/px</th><th>height, m</th>\
         <th>height in air, m</th><th>GSD at the star, mm/px</th>\
         <th>smallest resolved bar, mm</th><th>smallest resolved bar, px</th>\
         <th>resolved / GSD</th><th>mean contrast 10 %, px</th></tr>\n",
        100.0 * RESOLVED
    );
    for r in rows {
        let k = super::slug(&r.label);
        let _ = writeln!(
            s,
            "<tr><th>{}</th><td>{}</td>{}{}{}{}{}{}{}{}</tr>",
            escape(&r.label),
            escape(&r.port),
            num(&format!("{k}.gsd_mm"), format!("{:.2}", r.gsd_mm)),
            num(&format!("{k}.height_m"), format!("{:.3}", r.height_m)),
            num(
                &format!("{k}.height_air_m"),
                format!("{:.3}", r.height_air_m)
            ),
            num(
                &format!("{k}.gsd_at_star_mm"),
                format!("{:.3}", r.gsd_at_star_mm)
            ),
            num(
                &format!("{k}.smallest_resolved_mm"),
                format!("{:.2}", r.smallest_resolved_mm)
            ),
            num(
                &format!("{k}.smallest_resolved_px"),
                format!("{:.2}", r.smallest_resolved_px)
            ),
            num(
                &format!("{k}.resolved_over_gsd"),
                format!("{:.2}", r.resolved_over_gsd)
            ),
            num(
                &format!("{k}.mean_contrast_10_px"),
                format!("{:.2}", r.mean_contrast_10_px)
            ),
        );
    }
    s.push_str(
        "</table>\n<p class=\"small\">A flat port magnifies by about the water's index: the \
         same GSD needs the camera about 1.33 times higher than in air; a centred dome keeps \
         nearly the height in air. The pixel sets the limit: a bar narrower than about a \
         pixel cannot be told from its neighbours.</p>\n<h2>Views and contrast</h2>\n",
    );
    for r in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{a}<figcaption>The view at {h:.2} m.</figcaption></figure>\n\
             <figure>{b}<figcaption>Blue: mean contrast of the star's sectors; black: the \
             smallest bar dip on the circle; against the bar width; red: the {t:.0} % \
             threshold.</figcaption></figure>\n<p class=\"small\">This case's \
             scene (the lesson moves its camera to the height above): <code>{cmd}</code></p>\n",
            l = escape(&r.label),
            a = png(&r.view_png, &format!("view, {}", r.label)),
            h = r.height_m,
            b = svg(&r.contrast_svg),
            t = 100.0 * RESOLVED,
            cmd = escape(&r.command),
        );
    }
    s
}
