//! Lesson kind `completeness`: how much of a coral colony's surface, or of a photogrammetric
//! model's, a camera network covers well enough to be modelled. Each case's subject (the
//! scene's `shape = "coral"` and `shape = "mesh"` objects) is sampled uniformly by area (seeded
//! by `render.seed`); a sample counts as *covered* when at least [`MIN_IMAGES`] images see it
//! within [`MAX_ANGLE_DEG`] of its normal.
//!
//! | item | meaning |
//! |---|---|
//! | surface | the corals' triangles above their base plane (object-frame z > 0: the buried base and the part hidden in the substrate are not surface to photograph), and every triangle of every mesh object (a model of a site is all surface to photograph) |
//! | sample | a point uniform by area on that surface, with its triangle's outward normal |
//! | seen by an image | its exact refractive projection (G channel, [`crate::optics::project::Projector`]) lands on the sensor; the water path from the point to where that pixel's ray leaves the port is not blocked by anything of the scene ([`crate::geometry::Bvh::occluded`], the ground truth's occlusion test); and that path is within [`MAX_ANGLE_DEG`] of the normal |
//! | completeness | the share of samples (so of the area) seen by ≥ [`MIN_IMAGES`] images |
//! | seen at all | the share seen by ≥ 1 image |
//! | maps | top and side views of the samples: blue ≥ [`MIN_IMAGES`] images, yellow 1–2, vermillion none |
//!
//! Quick form: [`SAMPLES_QUICK`] samples per case; full form: [`SAMPLES_FULL`]. The counts are
//! independent per sample (rayon), so the numbers do not depend on the thread count.

use super::Case;
use super::html::{base64, case_row, escape};
use crate::geometry::Bvh;
use crate::geometry::mesh::{TriMesh, shape_mesh};
use crate::model::{Model, Shape};
use crate::optics::project::Projector;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Images a surface point needs to count as covered (three rays: a point, checked).
pub const MIN_IMAGES: u32 = 3;
/// Largest angle between a viewing ray and the surface normal, degrees.
pub const MAX_ANGLE_DEG: f64 = 60.0;
/// Surface samples per case, quick form.
pub const SAMPLES_QUICK: usize = 20_000;
/// Surface samples per case, full form.
pub const SAMPLES_FULL: usize = 200_000;

/// One case's numbers and maps.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    pub command: String,
    /// Images of the network (poses × cameras).
    pub images: usize,
    /// Area of the sampled coral surface, m².
    pub area_m2: f64,
    pub samples: usize,
    /// Share of the surface seen by at least one image (within the angle).
    pub seen: f64,
    /// Share of the surface seen by at least [`MIN_IMAGES`] images within [`MAX_ANGLE_DEG`].
    pub completeness: f64,
    /// Mean number of such images per surface point.
    pub mean_images: f64,
    pub seconds: f64,
    /// Top view of the samples (PNG).
    #[serde(skip)]
    pub top_png: Vec<u8>,
    /// Side view of the samples, looking along +y (PNG).
    #[serde(skip)]
    pub side_png: Vec<u8>,
}

/// A surface sample: point and unit outward normal, world frame.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    pub point: DVec3,
    pub normal: DVec3,
}

/// The subject's surface in the world frame: the corals' above their base plane, and every
/// mesh object's whole.
pub fn coral_surface(model: &Model) -> Result<TriMesh, String> {
    let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
    let mut out = TriMesh::default();
    for o in &model.objects {
        let whole = match o.shape {
            Shape::Coral { .. } => false,
            Shape::Mesh { .. } => true,
            _ => continue,
        };
        let local = shape_mesh(&o.shape, base).map_err(|e| format!("object `{}`: {e}", o.name))?;
        let world = local.transformed(&o.pose, o.scale);
        if whole {
            out.append(&world);
            continue;
        }
        let mut part = TriMesh {
            positions: world.positions,
            triangles: Vec::new(),
        };
        for (t, tw) in local.triangles.iter().zip(&world.triangles) {
            let z = t
                .iter()
                .map(|&i| local.positions[i as usize].z)
                .sum::<f64>()
                / 3.0;
            if z > 0.0 {
                part.triangles.push(*tw);
            }
        }
        out.append(&part);
    }
    if out.triangles.is_empty() {
        return Err(
            "a completeness lesson needs a coral or a mesh object\n  help: add `[[objects]]` with \
             `shape = \"coral\"`, or `shape = \"mesh\"` and the model's `path` (see docs/format.md)"
                .into(),
        );
    }
    Ok(out)
}

/// `n` samples uniform by area on `mesh`, from `seed`.
pub fn sample(mesh: &TriMesh, n: usize, seed: u64) -> Vec<Sample> {
    let mut cum = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        total += 0.5 * (b - a).cross(c - a).length();
        cum.push(total);
    }
    let mut rng = crate::rng::SplitMix64(seed ^ 0xC0_4A1);
    (0..n)
        .map(|_| {
            let x = rng.next_f64() * total;
            let k = cum.partition_point(|&c| c <= x).min(cum.len() - 1);
            let [a, b, c] = mesh.triangles[k].map(|i| mesh.positions[i as usize]);
            let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
            Sample {
                point: a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2),
                normal: mesh.face_normal(k),
            }
        })
        .collect()
}

/// For every sample, how many images of `model` see it within the angle (see the module).
pub fn counts(model: &Model, scene: &Bvh, samples: &[Sample]) -> Result<Vec<u32>, String> {
    let projectors: Vec<Projector> = (0..model.cameras.len())
        .map(|ci| model.projector(ci, 1))
        .collect::<Result<_, _>>()?;
    let cos_max = MAX_ANGLE_DEG.to_radians().cos();
    // A cheap, conservative first cut on the direction to the entrance pupil (the port's exit
    // point is centimetres from it, a few degrees at the distances of a survey).
    let cos_pre = (MAX_ANGLE_DEG + 15.0).to_radians().cos();
    Ok(samples
        .par_iter()
        .map(|s| {
            let mut n = 0;
            for (ci, pr) in projectors.iter().enumerate() {
                for pi in 0..model.poses.len() {
                    let centre = model.world_from_camera(pi, ci).translation;
                    let to = centre - s.point;
                    if to.dot(s.normal) < cos_pre * to.length() {
                        continue;
                    }
                    let Ok(uv) = pr.project_world(pi, s.point) else {
                        continue;
                    };
                    let Ok((exit, _, _)) = pr.pixel_ray_world(pi, uv[0], uv[1]) else {
                        continue;
                    };
                    let view = exit - s.point;
                    if view.dot(s.normal) < cos_max * view.length() {
                        continue;
                    }
                    if !scene.occluded(s.point, exit) {
                        n += 1;
                    }
                }
            }
            n
        })
        .collect())
}

/// Measure one case.
pub fn run_case(c: &Case, full: bool, progress: &(dyn Fn(&str) + Sync)) -> Result<Row, String> {
    let n = if full { SAMPLES_FULL } else { SAMPLES_QUICK };
    let t0 = std::time::Instant::now();
    let m = &c.model;
    let images = m.poses.len() * m.cameras.len();
    progress(&format!(
        "`{}`: {n} surface points × {images} images",
        c.label
    ));
    let err = |e: String| format!("variant `{}`: {e}", c.label);
    let surface = coral_surface(m).map_err(err)?;
    let samples = sample(&surface, n, m.render.seed);
    let scene = Bvh::of_model(m).map_err(err)?;
    let counts = counts(m, &scene, &samples).map_err(err)?;
    let share = |k: u32| counts.iter().filter(|&&c| c >= k).count() as f64 / n as f64;
    Ok(Row {
        label: c.label.clone(),
        command: c.command("render"),
        images,
        area_m2: surface.area(),
        samples: n,
        seen: share(1),
        completeness: share(MIN_IMAGES),
        mean_images: counts.iter().map(|&c| c as f64).sum::<f64>() / n as f64,
        seconds: t0.elapsed().as_secs_f64(),
        top_png: map_png(&samples, &counts, View::Top)?,
        side_png: map_png(&samples, &counts, View::Side)?,
    })
}

/// Which way a map looks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// Down along −z (x right, y up).
    Top,
    /// Along +y (x right, z up).
    Side,
}

/// Blue ≥ [`MIN_IMAGES`], yellow 1 to [`MIN_IMAGES`] − 1, vermillion none (Okabe–Ito colours,
/// readable with every common colour-vision deficiency).
pub fn colour(count: u32) -> [u8; 3] {
    if count >= MIN_IMAGES {
        [0, 114, 178]
    } else if count > 0 {
        [240, 228, 66]
    } else {
        [213, 94, 0]
    }
}

/// The samples as dots seen from `view`, the nearest on top, on a white ground (PNG).
pub fn map_png(samples: &[Sample], counts: &[u32], view: View) -> Result<Vec<u8>, String> {
    // (horizontal, vertical, depth towards the viewer)
    let project = |p: DVec3| match view {
        View::Top => (p.x, p.y, p.z),
        View::Side => (p.x, p.z, -p.y),
    };
    let pts: Vec<(f64, f64, f64, u32)> = samples
        .iter()
        .zip(counts)
        .map(|(s, &c)| {
            let (h, v, d) = project(s.point);
            (h, v, d, c)
        })
        .collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &pts {
        lo = [lo[0].min(p.0), lo[1].min(p.1)];
        hi = [hi[0].max(p.0), hi[1].max(p.1)];
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
    let (w, margin) = (420u32, 10.0);
    let scale = (w as f64 - 2.0 * margin) / span;
    let h = ((hi[1] - lo[1]) * scale + 2.0 * margin).ceil().max(20.0) as u32;
    let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| pts[a].2.total_cmp(&pts[b].2).then(a.cmp(&b)));
    let r = (1.0 + 300.0 / (pts.len() as f64).sqrt()).clamp(1.0, 4.0);
    for i in order {
        let (ph, pv, _, c) = pts[i];
        let x = margin + (ph - lo[0]) * scale;
        let y = h as f64 - margin - (pv - lo[1]) * scale;
        let (x0, x1) = ((x - r).floor() as i64, (x + r).ceil() as i64);
        let (y0, y1) = ((y - r).floor() as i64, (y + r).ceil() as i64);
        for yy in y0.max(0)..=y1.min(h as i64 - 1) {
            for xx in x0.max(0)..=x1.min(w as i64 - 1) {
                if (xx as f64 + 0.5 - x).powi(2) + (yy as f64 + 0.5 - y).powi(2) <= r * r {
                    img.put_pixel(xx as u32, yy as u32, image::Rgb(colour(c)));
                }
            }
        }
    }
    let mut bytes = Vec::new();
    image::DynamicImage::ImageRgb8(img)
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}

fn swatch(c: [u8; 3]) -> String {
    format!(
        "<span style=\"display:inline-block;width:.9em;height:.9em;background:rgb({},{},{});\
         border:1px solid #888\"></span>",
        c[0], c[1], c[2]
    )
}

/// The page's numbers and maps (the part of `index.html` between the set-up and "try next").
pub fn section(rows: &[Row]) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "<h2>The numbers</h2>\n<p>The subject's surface (a coral above the substrate, or a whole \
         model) is sampled uniformly by area. A point counts as seen by an image when its exact projection through the port \
         lands on the sensor, nothing blocks its line of sight to the port, and that line is \
         within {MAX_ANGLE_DEG:.0}° of the surface normal. <b>Completeness</b> is the share of \
         the surface seen by at least {MIN_IMAGES} images.</p>\n<table><tr><th>case</th>\
         <th>images</th><th>surface, m²</th><th>points</th><th>seen at all, %</th>\
         <th>completeness, %</th><th>images per point</th></tr>\n"
    );
    for row in rows {
        case_row(
            &mut s,
            &row.label,
            &[
                ("images", row.images.to_string()),
                ("area_m2", format!("{:.3}", row.area_m2)),
                ("samples", row.samples.to_string()),
                ("seen", format!("{:.1}", 100.0 * row.seen)),
                ("completeness", format!("{:.1}", 100.0 * row.completeness)),
                ("mean_images", format!("{:.1}", row.mean_images)),
            ],
        );
    }
    let _ = write!(
        s,
        "</table>\n<h2>Seen and unseen surface</h2>\n<p class=\"small\">{} seen by at least \
         {MIN_IMAGES} images, {} by 1 or 2, {} by none (within {MAX_ANGLE_DEG:.0}° of the \
         normal). Top view and side view (looking north); the nearest points on top.</p>\n",
        swatch(colour(MIN_IMAGES)),
        swatch(colour(1)),
        swatch(colour(0)),
    );
    for row in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure><img alt=\"top view, {l}\" src=\"data:image/png;base64,{top}\">\
             <figcaption>From above.</figcaption></figure>\n<figure><img alt=\"side view, {l}\" \
             src=\"data:image/png;base64,{side}\"><figcaption>From the south.</figcaption>\
             </figure>\n<p class=\"small\">Render alone: <code>{cmd}</code></p>\n",
            l = escape(&row.label),
            top = base64(&row.top_png),
            side = base64(&row.side_png),
            cmd = escape(&row.command),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::coral::{Growth, coral};
    use crate::geometry::mesh;

    #[test]
    fn samples_are_uniform_by_area_and_deterministic() {
        // Two unit squares' worth of triangles, one 3 × larger: a quarter of the points on
        // the small one.
        let mut m = mesh::plane(1.0, 1.0);
        let mut big = mesh::plane(3.0, 1.0);
        for p in &mut big.positions {
            p.x += 5.0;
        }
        m.append(&big);
        let s = sample(&m, 40_000, 3);
        let small = s.iter().filter(|p| p.point.x < 1.0).count() as f64 / 40_000.0;
        assert!((small - 0.25).abs() < 0.01, "{small}");
        assert!(s.iter().all(|p| (p.normal - DVec3::Z).length() < 1e-12));
        let again = sample(&m, 40_000, 3);
        assert!(s.iter().zip(&again).all(|(a, b)| a.point == b.point));
    }

    #[test]
    fn maps_are_pngs_of_the_three_colours() {
        let m = coral(Growth::Massive, 0.3, 1);
        let s = sample(&m, 2000, 1);
        let c: Vec<u32> = (0..s.len() as u32).map(|i| i % 5).collect();
        for v in [View::Top, View::Side] {
            let png = map_png(&s, &c, v).unwrap();
            let img = image::load_from_memory(&png).unwrap().to_rgb8();
            for k in [0, 1, MIN_IMAGES] {
                assert!(img.pixels().any(|p| p.0 == colour(k)), "{v:?} {k}");
            }
        }
    }
}
