//! Lesson kind `contrast`: each variant's camera is placed facing the scene's first target
//! (a checkerboard) at the distance that gives the lesson's GSD at the target's centre
//! (exact projection through the port, [`crate::plan::survey::distance_for_gsd`]); the native
//! renderer renders that view and the same view with the targets removed, and the numbers are
//! measured on the linear radiance (never the sRGB preview).
//!
//! | number | meaning |
//! |---|---|
//! | distance | camera (entrance pupil) to target centre along the optical axis, m |
//! | Michelson contrast | (I_light − I_dark)/(I_light + I_dark), green channel, I = mean over the central half of every light (dark) square, the brightest and darkest 5 % of its sample points left out (fireflies near lamps) |
//! | contrast without backscatter | the same with the backscatter render subtracted at the same pixels |
//! | R/G, B/G | channel ratios of the light squares' mean radiance (the colour cast of a white card) |
//! | backscatter | mean green radiance of the render with the targets removed, over the whole frame (nothing is behind it: pure path radiance) |
//! | veiling share | backscatter at the target's sample pixels over the target's mean radiance there (both means trimmed as above) |
//!
//! Which square is light or dark comes from the printed pattern
//! ([`crate::geometry::targets::reflectance`]) at each sample point of the target's own frame,
//! and its pixel from the exact projection ([`crate::optics::project::Projector`]) — no pixel
//! box is typed in. The helpers [`place`], [`render`], [`bilinear`] and [`view_png`] are shared
//! with the kind `gsd`, and [`measure`] and [`strobe_separation`] with the kind `metrology`.

use super::Case;
use super::html::{case_row, escape, png, svg};
use crate::backend::native;
use crate::geometry::targets;
use crate::model::{LightKind, Model, TargetKind};
use crate::optics::project::Projector;
use glam::DVec3;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Move the first rig pose along the first camera's optical axis so that the first target's
/// centre is on the axis at the distance giving `gsd` (m/px) there (exact projection, green
/// channel, `n_water` of the scene; `n = 1` without water); drop the other poses. Returns
/// that distance, m.
pub fn place(model: &mut Model, gsd: f64, label: &str) -> Result<f64, String> {
    let centre = model
        .targets
        .first()
        .map(|t| t.pose.translation)
        .ok_or_else(|| {
            format!("variant `{label}`: this lesson needs a target\n  help: add `[[targets]]`")
        })?;
    if model.cameras.is_empty() || model.poses.is_empty() {
        return Err(format!(
            "variant `{label}`: this lesson needs a camera and one pose (it sets the pose's \
             distance)\n  help: add `[camera]` and an explicit `[[network.poses]]` looking at \
             the target"
        ));
    }
    let pr = Projector::for_camera(&model.cameras[0], 1, model.ambient_ior()[1])?;
    let d = distance_for_gsd(&pr, gsd).ok_or_else(|| {
        format!(
            "variant `{label}`: no distance gives {:.3} mm/px through this port",
            gsd * 1e3
        )
    })?;
    model.poses.truncate(1);
    let wfc = model.world_from_camera(0, 0);
    let axis = wfc.rotation * DVec3::Z;
    let shift = centre - d * axis - wfc.translation;
    model.poses[0].world_from_rig.translation += shift;
    let z = model.world_from_camera(0, 0).translation.z;
    if model.water.is_some() && z > 0.0 {
        return Err(format!(
            "variant `{label}`: for {:.2} mm/px the camera would be {d:.2} m from the target, \
             {z:.2} m above the sea surface (z = 0)\n  help: put the target deeper \
             (`site.depth` and the target's `position`) or ask for a finer `lesson.gsd`",
            gsd * 1e3
        ));
    }
    Ok(d)
}

/// [`crate::plan::survey::distance_for_gsd`] (exact GSD on the optical axis).
pub fn distance_for_gsd(pr: &Projector, gsd: f64) -> Option<f64> {
    crate::plan::survey::distance_for_gsd(pr, gsd).filter(|d| d.is_finite() && *d > 0.0)
}

/// Render pose 0, camera 0 with the scene's samples.
pub fn render(model: &Model) -> Result<native::Image, String> {
    let scene = native::scene::Scene::build(model)?;
    native::render_image(model, &scene, 0, 0, model.render.samples, None)
}

/// Channel `ch` of `img` at pixel position (u, v), poser's convention (pixel centres at +0.5),
/// bilinear; `None` off the image.
pub fn bilinear(img: &native::Image, u: f64, v: f64, ch: usize) -> Option<f64> {
    let (x, y) = (u - 0.5, v - 0.5);
    let (w, h) = (img.width as f64, img.height as f64);
    if !(x >= 0.0 && y >= 0.0 && x <= w - 1.0 && y <= h - 1.0) {
        return None;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = (
        (x0 + 1).min(img.width as usize - 1),
        (y0 + 1).min(img.height as usize - 1),
    );
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let p = |i: usize, j: usize| img.rgb[j * img.width as usize + i][ch] as f64;
    Some(
        (1.0 - fy) * ((1.0 - fx) * p(x0, y0) + fx * p(x1, y0))
            + fy * ((1.0 - fx) * p(x0, y1) + fx * p(x1, y1)),
    )
}

/// PNG preview of `img` written to `path` (sRGB), scaled so that the 99th percentile of the
/// brightest channel is 0.9 (each view its own scale: near and far views differ by orders
/// of magnitude). Returns the PNG's bytes.
pub fn view_png(img: &native::Image, path: &Path) -> Result<Vec<u8>, String> {
    let mut m: Vec<f32> = img
        .rgb
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]))
        .filter(|v| v.is_finite())
        .collect();
    m.sort_by(f32::total_cmp);
    let p99 = m.get(m.len() * 99 / 100).copied().unwrap_or(1.0) as f64;
    let exposure = if p99 > 0.0 { 0.9 / p99 } else { 1.0 };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    native::write_png(path, img, exposure)?;
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// One variant's numbers and views.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    pub command: String,
    pub focal_length_mm: f64,
    /// Planned GSD at the target's centre, mm/px.
    pub gsd_mm: f64,
    /// Entrance pupil to target centre, m.
    pub distance_m: f64,
    /// Distance between the first two spot lights, m (NaN with fewer).
    pub strobe_separation_m: f64,
    /// Contrast, colour cast and backscatter (`bs`: the view without targets), flat in the
    /// row's JSON.
    #[serde(flatten)]
    pub measured: Measured,
    pub seconds: f64,
    #[serde(skip)]
    pub view_png: Vec<u8>,
    #[serde(skip)]
    pub backscatter_png: Vec<u8>,
    /// Green radiance along a row of squares, with and without the board (SVG).
    #[serde(skip)]
    pub profile_svg: String,
}

/// A sample point of the target: pixel and whether its print is light.
struct Sample {
    u: f64,
    v: f64,
    light: bool,
}

/// Points over the central half of every square of a checkerboard (5 × 5 per square),
/// projected exactly into the view.
fn samples(model: &Model) -> Result<Vec<Sample>, String> {
    let t = &model.targets[0];
    let TargetKind::Checkerboard { cols, rows, square } = t.kind else {
        return Err(format!(
            "target `{}`: the contrast lesson measures a checkerboard\n  help: make the first \
             target `type = \"checkerboard\"`",
            t.name
        ));
    };
    let pr = model.projector(0, 1)?;
    let (w, h) = (cols as f64 * square, rows as f64 * square);
    let mut out = Vec::new();
    for i in 0..cols {
        for j in 0..rows {
            let (cx, cy) = (
                -w / 2.0 + (i as f64 + 0.5) * square,
                -h / 2.0 + (j as f64 + 0.5) * square,
            );
            for a in 0..5 {
                for b in 0..5 {
                    let x = cx + (a as f64 / 4.0 - 0.5) * 0.5 * square;
                    let y = cy + (b as f64 / 4.0 - 0.5) * 0.5 * square;
                    let p = t.pose.transform_point(DVec3::new(x, y, 0.0));
                    if let Ok([u, v]) = pr.project_world(0, p) {
                        out.push(Sample {
                            u,
                            v,
                            light: targets::reflectance(&t.kind, x, y) > 0.5,
                        });
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Share of the sample points dropped at each end by [`trimmed_mean`].
pub const TRIM: f64 = 0.05;

/// The mean of the values between the [`TRIM`] and 1 − [`TRIM`] quantiles (NaN without
/// values). A view of lamps in turbid water carries rare fireflies, pixels thousands of times
/// their neighbours' radiance from the few paths that pass close to a lamp; one of them on a
/// board point moved the metrology lesson's veiling share from 2.6 % to 24 % (seed 1, 64 spp,
/// "lamps on arms, 30 cm"), while the quantities measured here are smooth over the board.
fn trimmed_mean(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let cut = (v.len() as f64 * TRIM).floor() as usize;
    let kept = &v[cut..v.len() - cut];
    if kept.is_empty() {
        f64::NAN
    } else {
        kept.iter().sum::<f64>() / kept.len() as f64
    }
}

/// Distance between the first two spot lights of `model`, m (NaN with fewer): how far apart
/// the strobes are.
pub fn strobe_separation(model: &Model) -> f64 {
    let spots: Vec<DVec3> = model
        .lights
        .iter()
        .filter_map(|l| match l.kind {
            LightKind::Spot { position, .. } => Some(position),
            _ => None,
        })
        .collect();
    if spots.len() >= 2 {
        (spots[0] - spots[1]).length()
    } else {
        f64::NAN
    }
}

/// What is measured on a view of a checkerboard (pose 0, camera 0, the first target) and on
/// the same view without it (`bs`): the numbers of the module's table.
#[derive(Debug, Clone, Serialize)]
pub struct Measured {
    pub contrast: f64,
    pub contrast_without_backscatter: f64,
    pub r_over_g: f64,
    pub b_over_g: f64,
    /// Mean radiance of `bs` over the whole frame, [r, g, b], W/(m²·sr).
    pub backscatter: [f64; 3],
    pub veiling_share: f64,
    /// Sample points on the light and the dark squares.
    pub samples: [usize; 2],
}

/// Measure the checkerboard of `model` in `img`, with `bs` the same view rendered without it.
pub fn measure(model: &Model, img: &native::Image, bs: &native::Image) -> Result<Measured, String> {
    let pts = samples(model)?;
    let at = |im: &native::Image, s: &Sample, ch| bilinear(im, s.u, s.v, ch);
    let class = |light: bool, im: &native::Image, ch: usize| {
        trimmed_mean(
            pts.iter()
                .filter(|s| s.light == light)
                .filter_map(|s| at(im, s, ch)),
        )
    };
    let (il, id) = (class(true, img, 1), class(false, img, 1));
    let (bl, bd) = (class(true, bs, 1), class(false, bs, 1));
    let n = (bs.rgb.len() as f64).max(1.0);
    let on_target = trimmed_mean(pts.iter().filter_map(|s| at(bs, s, 1)));
    let target = trimmed_mean(pts.iter().filter_map(|s| at(img, s, 1)));
    Ok(Measured {
        contrast: (il - id) / (il + id),
        contrast_without_backscatter: ((il - bl) - (id - bd)) / ((il - bl) + (id - bd)),
        r_over_g: class(true, img, 0) / il,
        b_over_g: class(true, img, 2) / il,
        backscatter: std::array::from_fn(|k| bs.rgb.iter().map(|p| p[k] as f64).sum::<f64>() / n),
        veiling_share: on_target / target,
        samples: [
            pts.iter().filter(|s| s.light).count(),
            pts.iter().filter(|s| !s.light).count(),
        ],
    })
}

/// Render and measure one case.
pub fn run_case(c: &Case, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let t0 = std::time::Instant::now();
    let mut m = c.model.clone();
    let gsd = m.lesson.as_ref().and_then(|l| l.gsd).ok_or_else(|| {
        format!(
            "variant `{}`: a contrast lesson needs `lesson.gsd`\n  help: write e.g. \
             `gsd = \"3 mm/px\"` in `[lesson]`",
            c.label
        )
    })?;
    let d = place(&mut m, gsd, &c.label)?;
    progress(&format!("rendering `{}` at {d:.2} m", c.label));
    let img = render(&m)?;
    let mut empty = m.clone();
    empty.targets.clear();
    progress(&format!("rendering `{}` without the target", c.label));
    let bs = render(&empty)?;
    let me = measure(&m, &img, &bs)?;
    let dir = out.join(&c.slug);
    let profile_svg = profile(&m, &img, &bs, &c.label)?;
    Ok(Row {
        label: c.label.clone(),
        command: c.command("render"),
        focal_length_mm: m.cameras[0].focal_length * 1e3,
        gsd_mm: gsd * 1e3,
        distance_m: d,
        strobe_separation_m: strobe_separation(&m),
        measured: me,
        seconds: t0.elapsed().as_secs_f64(),
        view_png: view_png(&img, &dir.join("view.png"))?,
        backscatter_png: view_png(&bs, &dir.join("backscatter.png"))?,
        profile_svg,
    })
}

/// Green radiance along the board's row of squares just above its centre line (exact
/// projection of 400 points), in the view and in the view without the board.
fn profile(
    model: &Model,
    img: &native::Image,
    bs: &native::Image,
    label: &str,
) -> Result<String, String> {
    use plotters::prelude::*;
    let t = &model.targets[0];
    let (w, _) = targets::extent(&t.kind);
    let y = match t.kind {
        TargetKind::Checkerboard { square, .. } => 0.5 * square,
        _ => 0.0,
    };
    let pr = model.projector(0, 1)?;
    let mut a = Vec::new();
    let mut b = Vec::new();
    for k in 0..400 {
        let x = -w / 2.0 + w * (k as f64 + 0.5) / 400.0;
        let Ok([u, v]) = pr.project_world(0, t.pose.transform_point(DVec3::new(x, y, 0.0))) else {
            continue;
        };
        if let (Some(p), Some(q)) = (bilinear(img, u, v, 1), bilinear(bs, u, v, 1)) {
            a.push((x * 1e3, p));
            b.push((x * 1e3, q));
        }
    }
    let ymax = a.iter().chain(&b).map(|p| p.1).fold(1e-12, f64::max) * 1.05;
    crate::plan::plot::register_font()?;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (480, 300)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Across the board, {label}"), ("sans-serif", 14))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(50)
            .build_cartesian_2d(-w / 2.0 * 1e3..w / 2.0 * 1e3, 0.0..ymax)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("x on the board, mm")
            .y_desc("green radiance")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(a, BLUE))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(b, RED))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(s)
}

/// The page's numbers and figures.
pub fn html(rows: &[Row]) -> String {
    let mut s = String::from(
        "<h2>The numbers</h2>\n<p>Measured on the linear radiance of the native renders. \
         Contrast: Michelson, (I<sub>light</sub> − I<sub>dark</sub>)/(I<sub>light</sub> + \
         I<sub>dark</sub>), green channel, over the central half of every square (found by the \
         exact projection of the board). Colour cast: the light squares' red and blue over \
         their green. Backscatter: the same view rendered without the target, mean green \
         radiance over the frame.</p>\n<table><tr><th>case</th><th>lens, mm</th>\
         <th>GSD, mm/px</th><th>distance, m</th><th>strobes apart, m</th>\
         <th>Michelson contrast</th><th>contrast without backscatter</th><th>R/G</th>\
         <th>B/G</th><th>backscatter (G), W/(m²·sr)</th><th>veiling share, %</th></tr>\n",
    );
    for r in rows {
        let me = &r.measured;
        case_row(
            &mut s,
            &r.label,
            &[
                ("focal_length_mm", format!("{:.0}", r.focal_length_mm)),
                ("gsd_mm", format!("{:.2}", r.gsd_mm)),
                ("distance_m", format!("{:.3}", r.distance_m)),
                (
                    "strobe_separation_m",
                    format!("{:.2}", r.strobe_separation_m),
                ),
                ("contrast", format!("{:.3}", me.contrast)),
                (
                    "contrast_without_backscatter",
                    format!("{:.3}", me.contrast_without_backscatter),
                ),
                ("r_over_g", format!("{:.3}", me.r_over_g)),
                ("b_over_g", format!("{:.3}", me.b_over_g)),
                ("backscatter", format!("{:.3e}", me.backscatter[1])),
                ("veiling_share", format!("{:.1}", 100.0 * me.veiling_share)),
            ],
        );
    }
    s.push_str(
        "</table>\n<p class=\"small\">Veiling share: the backscatter at the board's pixels over \
         the board's radiance there. Each view below is scaled to its own brightness (99th \
         percentile), so compare the numbers, not the brightness.</p>\n<h2>Views</h2>\n",
    );
    for r in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{a}<figcaption>The view.</figcaption></figure>\n<figure>{b}\
             <figcaption>The same view without the board: backscatter only.</figcaption>\
             </figure>\n<figure>{p}<figcaption>Green radiance along a row of squares (blue) \
             and the backscatter at the same pixels (red).</figcaption></figure>\n<p class=\"small\">This case's scene (the lesson moves its camera to the distance above): <code>{cmd}</code></p>\n",
            l = escape(&r.label),
            a = png(&r.view_png, &format!("view, {}", r.label)),
            b = png(&r.backscatter_png, &format!("backscatter, {}", r.label)),
            p = svg(&r.profile_svg),
            cmd = escape(&r.command),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trimmed_mean_ignores_a_firefly_and_keeps_the_core() {
        // 100 board points near 3.5e-3 and one firefly 7 700 times brighter: the plain mean is
        // eight times the core's, the trimmed one within a percent of it.
        let core: Vec<f64> = (0..100)
            .map(|i| 3.5e-3 * (1.0 + 0.01 * (i % 7) as f64))
            .collect();
        let with_firefly = core.iter().copied().chain([27.0]);
        let exact = core.iter().sum::<f64>() / core.len() as f64;
        let plain = (core.iter().sum::<f64>() + 27.0) / 101.0;
        assert!(plain > 8.0 * exact);
        let t = trimmed_mean(with_firefly);
        assert!((t / exact - 1.0).abs() < 0.01, "{t} against {exact}");
        // A constant stays itself, non-finite values are ignored, no values give NaN.
        assert_eq!(trimmed_mean([2.0; 7].into_iter().chain([f64::NAN])), 2.0);
        assert!(trimmed_mean(std::iter::empty()).is_nan());
    }

    #[test]
    fn bilinear_reads_pixel_centres_at_half_integers() {
        let img = native::Image {
            width: 2,
            height: 1,
            rgb: vec![[1.0, 2.0, 3.0], [3.0, 4.0, 5.0]],
            depth: vec![0.0; 2],
            variance: vec![[0.0; 3]; 2],
            albedo: Vec::new(),
            noise: None,
        };
        assert_eq!(bilinear(&img, 0.5, 0.5, 1), Some(2.0));
        assert_eq!(bilinear(&img, 1.5, 0.5, 0), Some(3.0));
        assert_eq!(bilinear(&img, 1.0, 0.5, 2), Some(4.0));
        assert_eq!(bilinear(&img, 0.2, 0.5, 0), None);
    }
}
