//! Lesson kind `surface`: a camera in the air (a drone) looking down through the sea surface,
//! per variant (usually a sea state).
//!
//! | number | from |
//! |---|---|
//! | moved, px | every target point seen by camera 0 at the first pose: its pixel through the scene's surface against its pixel through a flat sea ([`crate::optics::surface::image_through`], green channel); RMS and largest, over the points that have an image through both |
//! | no image | target points with an image through the flat sea but none found through the waves (they sit at a caustic of the view) |
//! | caustic contrast | std/mean of the sun's irradiance on horizontal planes 1, 2, …, 10 m down, relative to a flat sea: the native renderer's caustic volume ([`crate::backend::native::caustics::CausticVolume`]) sampled on a 256 × 256 grid over one period of the waves |
//! | the view | the native renderer's image at [`VIEW_SCALE`] of the camera's resolution and the scene's samples: the drone's picture |

use super::Case;
use super::contrast::view_png;
use super::html::{case_row, escape, num, png, svg};
use crate::backend::native::caustics::CausticVolume;
use crate::model::SeaSurface;
use crate::optics::surface::{SeaInterface, image_through};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Scale of the rendered view against the camera's resolution.
pub const VIEW_SCALE: f64 = 0.5;
/// Depths of the caustic-contrast curve, m.
pub const DEPTHS: [f64; 10] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0];

/// One variant's numbers and view.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    /// `poser render …` for this case alone.
    pub command: String,
    /// Significant wave height, m (0 for a flat sea).
    pub wave_height_m: f64,
    /// Target points with an image through the flat sea and through the waves.
    pub points: usize,
    /// Target points with an image through the flat sea but none through the waves.
    pub no_image: usize,
    pub moved_rms_px: f64,
    pub moved_max_px: f64,
    /// (depth m, std/mean of the sun's irradiance) at [`DEPTHS`]; empty without sun or waves.
    pub caustic_contrast: Vec<(f64, f64)>,
    pub seconds: f64,
    #[serde(skip)]
    pub view_png: Vec<u8>,
}

/// Measure and render one case.
pub fn run_case(c: &Case, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let t0 = std::time::Instant::now();
    let err = |e: String| format!("variant `{}`: {e}", c.label);
    let m = &c.model;
    if m.poses.is_empty() || m.cameras.is_empty() || !m.above_surface(0, 0) {
        return Err(err(
            "the surface lesson needs camera 0 above the sea surface at the first pose\n  \
             help: put the first pose in the air (z above the crests), give the camera \
             `[camera.port] type = \"none\"` and model the surface (`site.surface`)"
                .into(),
        ));
    }
    let waves = m
        .sea_interface(1)
        .ok_or_else(|| err("no sea surface".into()))?;
    let flat = SeaInterface::flat(waves.n_water);
    let pr = m.projector(0, 1).map_err(err)?;
    let ray = |u: f64, v: f64| pr.pixel_ray_world(0, u, v).map(|(o, d, _)| (o, d));
    progress(&format!(
        "projecting `{}`'s targets through the surface",
        c.label
    ));
    let (mut sum2, mut max, mut n, mut lost) = (0.0f64, 0.0f64, 0usize, 0usize);
    for t in &m.targets {
        for p in &t.points {
            let Ok(start) = pr.project_world_unbounded(0, p.world) else {
                continue;
            };
            let Ok(a) = image_through(&flat, &ray, p.world, start) else {
                continue;
            };
            if !pr.on_sensor(a) {
                continue;
            }
            match image_through(&waves, &ray, p.world, a) {
                Ok(b) => {
                    let d = (a[0] - b[0]).hypot(a[1] - b[1]);
                    sum2 += d * d;
                    max = max.max(d);
                    n += 1;
                }
                Err(_) => lost += 1,
            }
        }
    }
    let wave_height_m = match m.site.surface {
        SeaSurface::Waves { height, .. } => height,
        _ => 0.0,
    };
    progress(&format!("caustics of `{}`", c.label));
    let caustic_contrast = caustics(m);
    progress(&format!("rendering `{}`", c.label));
    let small = m.clone().with_resolution_scale(VIEW_SCALE);
    let scene = crate::backend::native::scene::Scene::build(&small).map_err(err)?;
    let img =
        crate::backend::native::render_image(&small, &scene, 0, 0, small.render.samples, None)
            .map_err(err)?;
    let view_png = view_png(&img, &out.join(&c.slug).join("view.png")).map_err(err)?;
    Ok(Row {
        label: c.label.clone(),
        command: c.command("render"),
        wave_height_m,
        points: n,
        no_image: lost,
        moved_rms_px: if n > 0 {
            (sum2 / n as f64).sqrt()
        } else {
            f64::NAN
        },
        moved_max_px: if n > 0 { max } else { f64::NAN },
        caustic_contrast,
        seconds: t0.elapsed().as_secs_f64(),
        view_png,
    })
}

/// Caustic contrast at [`DEPTHS`] (empty without sun or waves).
fn caustics(m: &crate::model::Model) -> Vec<(f64, f64)> {
    let Some(vol) = CausticVolume::for_model(m, -DEPTHS[DEPTHS.len() - 1] - 0.5) else {
        return Vec::new();
    };
    const N: usize = 256;
    let period = vol.period();
    DEPTHS
        .iter()
        .map(|&depth| {
            let mut v = Vec::with_capacity(N * N);
            for j in 0..N {
                for i in 0..N {
                    let x = (i as f64 + 0.5) / N as f64 * period;
                    let y = (j as f64 + 0.5) / N as f64 * period;
                    v.push(vol.factor(glam::DVec3::new(x, y, -depth)));
                }
            }
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / v.len() as f64;
            (depth, var.sqrt() / mean)
        })
        .collect()
}

/// Caustic contrast against depth, one line per case (SVG).
fn caustic_plot(rows: &[Row]) -> Result<String, String> {
    use plotters::prelude::*;
    let y_max = rows
        .iter()
        .flat_map(|r| r.caustic_contrast.iter().map(|p| p.1))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
        * 1.1;
    if !(y_max > 0.0) {
        return Ok(String::new());
    }
    crate::plan::plot::register_font()?;
    let colours = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (520, 320)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Caustic contrast against depth", ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(34)
            .y_label_area_size(48)
            .build_cartesian_2d(0.0..10.5, 0.0..y_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("depth, m")
            .y_desc("std / mean of the sun's irradiance")
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, r) in rows.iter().enumerate() {
            let col = colours[k % colours.len()];
            chart
                .draw_series(LineSeries::new(r.caustic_contrast.iter().copied(), col))
                .map_err(|e| e.to_string())?
                .label(r.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], col));
        }
        crate::plan::plot::legend(&mut chart, SeriesLabelPosition::MiddleRight)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(s)
}

/// The page's numbers and figures.
pub fn html(rows: &[Row]) -> String {
    let mut s = String::from(
        "<h2>How far the waves move the seabed</h2>\n<p>Each coded target's points, seen by the \
         drone's camera through the wavy sea and through a flat one: the exact refraction at the \
         surface (green channel), solved for the pixel whose refracted ray passes through the \
         point. A point at a caustic of the view may have no image near its flat-sea one.</p>\n\
         <table><tr><th>case</th><th>wave height, m</th><th>points</th><th>moved, RMS px</th>\
         <th>moved, largest px</th><th>no image</th></tr>\n",
    );
    for r in rows {
        case_row(
            &mut s,
            &r.label,
            &[
                ("wave_height_m", format!("{:.2}", r.wave_height_m)),
                ("points", r.points.to_string()),
                ("moved_rms_px", format!("{:.2}", r.moved_rms_px)),
                ("moved_max_px", format!("{:.2}", r.moved_max_px)),
                ("no_image", r.no_image.to_string()),
            ],
        );
    }
    s.push_str(
        "</table>\n<h2>Caustics on the seabed</h2>\n<p>The sun's irradiance under the waves \
         relative to a flat sea, on horizontal planes 1 to 10 m down: its standard deviation \
         over its mean (0 under a flat sea).</p>\n<table><tr><th>depth, m</th>",
    );
    for r in rows {
        let _ = write!(s, "<th>{}</th>", escape(&r.label));
    }
    s.push_str("</tr>\n");
    for (i, depth) in DEPTHS.iter().enumerate() {
        let _ = write!(s, "<tr><th>{depth:.0}</th>");
        for r in rows {
            let k = super::slug(&r.label);
            let v = r.caustic_contrast.get(i).map_or(f64::NAN, |p| p.1);
            s.push_str(&num(&format!("{k}.caustic_{depth:.0}m"), format!("{v:.3}")));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
    match caustic_plot(rows) {
        Ok(p) if !p.is_empty() => {
            let _ = writeln!(
                s,
                "<figure>{}<figcaption>Caustic contrast against depth, per case.</figcaption>\
                 </figure>",
                svg(&p)
            );
        }
        Ok(_) => {}
        Err(e) => {
            let _ = writeln!(s, "<p class=\"small\">(no plot: {})</p>", escape(&e));
        }
    }
    s.push_str("<h2>The drone's view</h2>\n");
    for r in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{a}<figcaption>The view through the surface (native \
             renderer; the sky the surface reflects is not rendered).</figcaption></figure>\n\
             <p class=\"small\">Render this case alone: <code>{cmd}</code></p>\n",
            l = escape(&r.label),
            a = png(&r.view_png, &format!("view, {}", r.label)),
            cmd = escape(&r.command),
        );
    }
    s
}
