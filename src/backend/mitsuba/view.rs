//! One view document per (pose, camera[, channel pass]): `{image}.xml` or
//! `{image}.{r,g,b}.xml`, in the order it is written by [`view`]:
//!
//! | item | function | Mitsuba 3 |
//! |---|---|---|
//! | header and integrator | [`view`] | `volpathmis` with water (spectral MIS), else `volpath`; `include` of `world.xml` |
//! | water | `medium_region`, `water_medium`, [`ff_table`] | `homogeneous` medium in a `null` cube |
//! | camera | [`check_camera`], `sensor`, `thin_lens` | `perspective` or `thinlens` sensor |
//! | port and housing | `port_shapes` (the housing from [`crate::optics::port::housing`], `dielectric`) | `dielectric` shapes, black housing walls |
//! | rig-mounted lights | `world::light` (shared with the world) | as world-mounted lights |
//!
//! Indices: a dielectric needs one number per side; without per-channel passes the G channel
//! (550 nm) index is used ([`super::SINGLE_PASS_CHANNEL`]), with them each pass uses its own
//! channel's indices.

// `!(x > y)` is deliberate: it rejects NaN as well as the failing comparison.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::world::{Intensity, intensity_defaults, light, scene_bounds};
use super::xml::{self, El};
use super::{SEA_MARGIN, TABPHASE_SAMPLES, WATER_ID, basis};
use crate::model::*;
use crate::optics::phase::ff_cdf;
use crate::optics::port::{self, Face, Shape};
use glam::{DMat3, DVec3};

/// What one view document needs to know besides the model.
pub struct ViewSpec {
    pub pose: usize,
    pub camera: usize,
    /// Channel whose indices the dielectrics use.
    pub channel: usize,
    /// Sampler seed.
    pub seed: u32,
    /// File name of the world include (`None` when the world is empty).
    pub world_file: Option<String>,
    /// Human-readable title for the header comment.
    pub title: String,
}

/// One view document.
pub fn view(model: &Model, spec: &ViewSpec) -> Result<El, String> {
    let cam = &model.cameras[spec.camera];
    check_camera(cam)?;
    let world_from_cam = model.world_from_camera(spec.pose, spec.camera);
    let world_from_rig = model.poses[spec.pose].world_from_rig;
    let cam_pos = world_from_cam.translation;
    let region = medium_region(model, cam_pos);
    let emit_port = model.needs.refraction && !matches!(cam.port, Port::None);
    let n_out = model.ambient_ior()[spec.channel];
    let port = if emit_port {
        port_shapes(
            cam,
            &world_from_cam,
            spec.channel,
            n_out,
            region.contains(cam_pos),
        )?
    } else {
        None
    };
    if let (Some(p), MediumRegion::Cube { min, max }) = (&port, region)
        && region.contains(cam_pos)
    {
        let room = (cam_pos - min).min(max - cam_pos).min_element();
        if p.extent >= room {
            return Err(format!(
                "camera `{}`: the water box around the camera ({room:.3} m to its nearest \
                 face) is too small to contain the port ({:.3} m)",
                cam.name, p.extent
            ));
        }
    }
    let in_water = port.is_none() && region.contains(cam_pos);
    let near_clip = port
        .as_ref()
        .map(|p| (0.25 * p.clearance).min(1e-3))
        .unwrap_or(1e-3);

    let mut root = El::new("scene").attr("version", "3.0.0");
    root.push_comment(spec.title.clone());
    // Per-view coordinates: the camera at Mitsuba's origin, in millimetres
    // (xml::ORIGIN_PARAMS).
    root.push_comment(
        "per-view coordinates: millimetres ($poser_unit per metre), the world's origin at \
         ($poser_origin_x, _y, _z), minus the camera's centre, so that the port's glass sits at \
         Mitsuba's origin, where its float32 ray offsets are smallest; every placed element's \
         to_world ends with that scale and translation",
    );
    let unit = xml::VIEW_UNIT;
    for d in xml::placement_defaults(-cam_pos * unit, unit) {
        root.push(d);
    }
    // World-mounted point and spot lights (in world.xml) in this document's unit.
    for d in intensity_defaults(model, unit) {
        root.push(d);
    }
    // With water, `volpathmis`: free-flight distances sampled with spectral MIS over the
    // three channels. `volpath` samples them in one channel picked per path and reweights the
    // others, and in deep, strongly chromatic water the paths sampled in red almost never
    // reach the surface, so at any practical sample count the image is a third too dark in
    // every channel (gsd_reef, clear Jerlov IB at 30 m under ambient light: −36 % against
    // native and Cycles with `volpath`, +2 % with `volpathmis`; grey water agrees with both).
    // Filled objects in air keep `volpath`: on a sphere of scattering water (HG g = 0.8,
    // σs = 1.5/m) under an ambient sky, `volpathmis` rendered the jar 1.7 % darker in every
    // channel than `volpath`, native and Cycles, which agree within 0.1 % (tests/filled_objects.rs).
    let integrator = if region.exists() {
        "volpathmis"
    } else {
        "volpath"
    };
    root.push(
        El::typed("integrator", integrator)
            .comment("max_depth counts path vertices: max_bounces + 1, plus the port's glass faces")
            .integer(
                "max_depth",
                model.render.max_bounces as i64 + 1 + model.port_interfaces() as i64,
            ),
    );
    if let Some(w) = &spec.world_file {
        root.push(El::new("include").attr("filename", w.as_str()));
    }
    if region.exists() {
        let water = model.water.as_ref().expect("medium region implies water");
        root.push(water_medium(water));
        if let MediumRegion::Cube { min, max } = region {
            let c = 0.5 * (min + max);
            let hs = 0.5 * (max - min);
            root.push(
                El::typed("shape", "cube")
                    .comment(match water.extent {
                        WaterExtent::Everywhere => {
                            "the sea: boundary of the water (no surface, no reflection)"
                        }
                        WaterExtent::BoxAroundCamera { .. } => {
                            "water box around the camera; outside it, clear water"
                        }
                    })
                    .to_world(DMat3::from_diagonal(hs), c)
                    .child(El::typed("bsdf", "null"))
                    .reference("interior", WATER_ID),
            );
        }
    }
    root.push(sensor(model, spec, near_clip, unit, in_water));
    if let Some(p) = port {
        for s in p.shapes {
            root.push(s);
        }
    }
    for s in glass_objects(model, spec.channel, region) {
        root.push(s);
    }
    for l in model.lights.iter().filter(|l| l.mount == Mount::Rig) {
        root.push(light(l, &world_from_rig, Intensity::In(unit)));
    }
    xml::place_at_origin(&mut root);
    Ok(root)
}

/// Check that Mitsuba can express a camera; the error names the camera.
pub fn check_camera(cam: &Camera) -> Result<(), String> {
    let name = &cam.name;
    match cam.lens {
        LensModel::Rectilinear => {}
        LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
            let kind = if cam.lens == LensModel::FisheyeEquidistant {
                "equidistant"
            } else {
                "equisolid"
            };
            return Err(format!(
                "camera `{name}`: the {kind} fisheye lens cannot be expressed by Mitsuba 3's \
                 perspective sensor\n  help: render this scene with the native backend, or use \
                 `lens = \"rectilinear\"` for Mitsuba"
            ));
        }
    }
    if !cam.distortion.is_zero() {
        return Err(format!(
            "camera `{name}`: Brown–Conrady distortion (k1..k3, p1, p2) cannot be expressed by \
             Mitsuba 3's perspective sensor\n  help: render with the native backend, or set the \
             distortion to zero for Mitsuba"
        ));
    }
    if (cam.fx - cam.fy).abs() > 1e-9 * cam.fx.abs() {
        return Err(format!(
            "camera `{name}`: fx = {} px and fy = {} px differ; Mitsuba 3's perspective sensor has \
             square pixels only",
            cam.fx, cam.fy
        ));
    }
    if cam.width == 0 || cam.height == 0 || !(cam.fx > 0.0) {
        return Err(format!(
            "camera `{name}`: image size and fx must be positive"
        ));
    }
    if thin_lens(cam).is_some() {
        let off = (cam.cx - cam.width as f64 / 2.0)
            .abs()
            .max((cam.cy - cam.height as f64 / 2.0).abs());
        if off > 1e-9 {
            return Err(format!(
                "camera `{name}`: depth of field (focus distance and f-number) with an off-centre \
                 principal point cannot be expressed by Mitsuba 3 (its `thinlens` sensor has no \
                 principal point offset)\n  help: remove `focus`/`aperture` for Mitsuba, or centre \
                 the principal point"
            ));
        }
    }
    Ok(())
}

/// Where the water medium is, if one is emitted.
#[derive(Debug, Clone, Copy)]
enum MediumRegion {
    /// No medium (no water, or clear water).
    None,
    /// A `null` cube with the water inside (min, max corners, world).
    Cube { min: DVec3, max: DVec3 },
}

impl MediumRegion {
    fn contains(&self, p: DVec3) -> bool {
        match *self {
            MediumRegion::None => false,
            MediumRegion::Cube { min, max } => p.cmpgt(min).all() && p.cmplt(max).all(),
        }
    }
    fn exists(&self) -> bool {
        !matches!(self, MediumRegion::None)
    }
}

/// Decide where the medium goes for the camera at `cam_pos`.
fn medium_region(model: &Model, cam_pos: DVec3) -> MediumRegion {
    let Some(water) = &model.water else {
        return MediumRegion::None;
    };
    if !model.needs.medium {
        return MediumRegion::None;
    }
    match water.extent {
        WaterExtent::BoxAroundCamera { half_size } => MediumRegion::Cube {
            min: cam_pos - half_size,
            max: cam_pos + half_size,
        },
        WaterExtent::Everywhere => {
            let bounded_top = !matches!(model.site.surface, SeaSurface::None)
                || model.sun.is_some()
                || model
                    .lights
                    .iter()
                    .any(|l| matches!(l.kind, LightKind::Ambient { .. }));
            let (lo, hi) = scene_bounds(model);
            let r = SEA_MARGIN.max(10.0 * (hi - lo).max_element());
            let c = 0.5 * (lo + hi);
            let top = if bounded_top { 0.0 } else { c.z + r };
            let bottom = (-model.site.depth).min(lo.z) - r;
            MediumRegion::Cube {
                min: DVec3::new(c.x - r, c.y - r, bottom),
                max: DVec3::new(c.x + r, c.y + r, top),
            }
        }
    }
}

fn water_medium(water: &Water) -> El {
    medium_el(water, WATER_ID, "water")
}

/// A filled object's water ([`crate::model::Material::fill`]): the medium `fill_<k>` (`k` the
/// object's index), referenced as the object's `interior`.
fn fill_medium(water: &Water, k: usize, name: &str) -> El {
    medium_el(
        water,
        &format!("fill_{k}"),
        &format!("object `{name}`'s water"),
    )
}

/// A `homogeneous` medium of `water`'s coefficients and phase, with id `id`.
fn medium_el(water: &Water, id: &str, what: &str) -> El {
    let phase = match water.phase {
        Phase::HenyeyGreenstein { g } => El::typed("phase", "hg").float("g", g),
        Phase::FournierForand { n, mu, backscatter } => {
            let table = ff_table(n, mu, TABPHASE_SAMPLES);
            let vals: Vec<String> = table.iter().map(|v| super::xml::num(*v)).collect();
            El::typed("phase", "tabphase")
                .comment(format!(
                    "Fournier–Forand n = {n}, mu = {mu} (backscatter {backscatter:.5}; this table \
                     {:.5}), {TABPHASE_SAMPLES} values uniform in cos θ from -1 (back) to 1 (forward)",
                    table_backscatter(&table)
                ))
                .string("values", &vals.join(", "))
        }
    };
    El::typed("medium", "homogeneous")
        .attr("id", id)
        .comment(format!(
            "{what}: absorption {:?} 1/m, scattering {:?} 1/m{}",
            water.absorption,
            water.scattering,
            water
                .jerlov
                .as_ref()
                .map(|j| format!(" (Jerlov {j})"))
                .unwrap_or_default()
        ))
        .child(
            // A bare `<rgb>` here is a reflectance spectrum limited to [0, 1] (turbid water has
            // σt > 1/m); inside a `constvolume` it is unbounded.
            El::typed("volume", "constvolume")
                .attr("name", "sigma_t")
                .rgb("value", water.extinction()),
        )
        .rgb("albedo", water.albedo())
        .comment("σt is per metre; scale = metres per length unit of the document")
        .child(
            El::new("float")
                .attr("name", "scale")
                .attr("value", format!("${}", xml::PER_UNIT_PARAM)),
        )
        .child(phase)
}

/// Fournier–Forand phase function tabulated for `tabphase`: values on a uniform grid of cos θ
/// from -1 to 1 (θ the scattering angle, forward at cos θ = 1), each the exact mean density
/// of the cells around it (from [`crate::optics::phase::ff_cdf`]), so the forward peak keeps its mass.
pub fn ff_table(n: f64, mu: f64, samples: usize) -> Vec<f64> {
    let cells = samples - 1;
    let dmu = 2.0 / cells as f64;
    // Mass in each cell [mu_j, mu_{j+1}] (mu increasing = angle decreasing).
    let mass: Vec<f64> = (0..cells)
        .map(|j| {
            let m0 = -1.0 + j as f64 * dmu;
            let m1 = (m0 + dmu).min(1.0);
            (ff_cdf(n, mu, m0.clamp(-1.0, 1.0).acos()) - ff_cdf(n, mu, m1.acos())).max(0.0)
        })
        .collect();
    let density: Vec<f64> = mass
        .iter()
        .map(|m| m / (2.0 * std::f64::consts::PI * dmu))
        .collect();
    (0..samples)
        .map(|i| {
            if i == 0 {
                density[0]
            } else if i == cells {
                density[cells - 1]
            } else {
                0.5 * (density[i - 1] + density[i])
            }
        })
        .collect()
}

/// Backscatter fraction of a `tabphase` table (piecewise linear in cos θ), for checking.
pub fn table_backscatter(values: &[f64]) -> f64 {
    let cells = values.len() - 1;
    let dmu = 2.0 / cells as f64;
    let (mut back, mut total) = (0.0, 0.0);
    for j in 0..cells {
        let m = 0.5 * (values[j] + values[j + 1]) * dmu;
        total += m;
        let mid = -1.0 + (j as f64 + 0.5) * dmu;
        if mid < 0.0 {
            back += m;
        }
    }
    back / total
}

/// The sensor; `near_clip` in metres, lengths written in `unit`s per metre.
fn sensor(model: &Model, spec: &ViewSpec, near_clip: f64, unit: f64, in_water: bool) -> El {
    let cam = &model.cameras[spec.camera];
    let pose = model.world_from_camera(spec.pose, spec.camera);
    let (w, h) = (cam.width as f64, cam.height as f64);
    let fov = (2.0 * (w / (2.0 * cam.fx)).atan()).to_degrees();
    let to_world = pose.rotation * DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0));
    let mut s = match thin_lens(cam) {
        Some((aperture, focus)) => El::typed("sensor", "thinlens")
            .comment(format!(
                "f/{} focused at {focus} m",
                cam.f_number.unwrap_or(0.0)
            ))
            .float("aperture_radius", aperture * unit)
            .float("focus_distance", focus * unit),
        None => El::typed("sensor", "perspective"),
    };
    s = s.float("fov", fov).string("fov_axis", "x");
    if thin_lens(cam).is_none() {
        s = s
            .float("principal_point_offset_x", 0.5 - cam.cx / w)
            .float("principal_point_offset_y", 0.5 - cam.cy / h);
    }
    s = s
        .float("near_clip", near_clip * unit)
        .float("far_clip", 1e6 * unit)
        .comment(
            "OpenCV camera axes: Mitsuba's +X points left, so to_world = [R·diag(-1,-1,1) | C]",
        )
        .to_world(to_world, pose.translation);
    if in_water {
        s = s.reference("medium", WATER_ID);
    }
    s.child(
        El::typed("sampler", "independent")
            .integer("sample_count", model.render.samples.max(1) as i64)
            .integer("seed", spec.seed as i64),
    )
    .child(film(model, cam))
}

/// The `hdrfilm`: the camera's whole image, or the rectangle of `render.crop` (Mitsuba's
/// `crop_offset_*` and `crop_*` keep the whole image's pixel grid).
fn film(model: &Model, cam: &Camera) -> El {
    let mut film = El::typed("film", "hdrfilm")
        .integer("width", cam.width as i64)
        .integer("height", cam.height as i64);
    if let Some(c) = model.render.crop {
        film = film
            .integer("crop_offset_x", c.x as i64)
            .integer("crop_offset_y", c.y as i64)
            .integer("crop_width", c.width as i64)
            .integer("crop_height", c.height as i64);
    }
    film.string("pixel_format", "rgb")
        .string("component_format", "float32")
        .child(El::typed("rfilter", "box"))
}

/// `(aperture radius, focus distance)` when the camera has depth of field.
fn thin_lens(cam: &Camera) -> Option<(f64, f64)> {
    match (cam.focus_distance, cam.f_number) {
        (Some(d), Some(n)) if n > 0.0 && d > 0.0 => Some((cam.focal_length / (2.0 * n), d)),
        _ => None,
    }
}

/// Port geometry in the world, with the smallest distance from the pupil to the glass (for
/// the sensor's near clip).
struct PortShapes {
    shapes: Vec<El>,
    clearance: f64,
    /// Radius about the pupil that contains all the port geometry, m.
    extent: f64,
}

/// The port's housing ([`crate::optics::port::housing`], camera frame) as Mitsuba shapes in
/// the world: glass faces as `dielectric`s (`n_out`: the index outside the glass in this
/// channel; with `medium_outside`, the outer faces' exterior is the water medium), walls black.
fn port_shapes(
    cam: &Camera,
    world_from_cam: &Pose,
    channel: usize,
    n_out: f64,
    medium_outside: bool,
) -> Result<Option<PortShapes>, String> {
    let name = &cam.name;
    let Some(h) = port::housing(cam).map_err(|e| format!("camera `{name}`: {e}"))? else {
        return Ok(None);
    };
    let n_g = cam.port.glass().map_or(1.0, |g| g.ior[channel]);
    let wp = |p: DVec3| world_from_cam.transform_point(p);
    // A camera-frame direction in the world, unit length.
    let wv = |v: DVec3| (world_from_cam.rotation * v).normalize();
    let shapes = h
        .parts
        .iter()
        .map(|part| {
            let kind = match part.shape {
                Shape::Rectangle { .. } => "rectangle",
                Shape::Disk { .. } => "disk",
                Shape::Sphere { .. } => "sphere",
                Shape::Cylinder { .. } => "cylinder",
            };
            let el = match part.label {
                Some((of, what)) => {
                    El::typed("shape", kind).comment(format!("{of} of `{name}`: {what}"))
                }
                None => El::typed("shape", kind),
            };
            let el = match part.shape {
                Shape::Rectangle {
                    centre,
                    shift,
                    x,
                    y,
                    normal,
                } => {
                    let c = match shift {
                        Some((d, l)) => wp(centre) + wv(d) * l,
                        None => wp(centre),
                    };
                    el.to_world(
                        DMat3::from_cols(wv(x.0) * x.1, wv(y.0) * y.1, wv(normal)),
                        c,
                    )
                }
                Shape::Disk {
                    centre,
                    normal,
                    radius,
                } => {
                    let nrm = wv(normal);
                    let (e1, e2) = basis(nrm);
                    el.to_world(DMat3::from_cols(e1 * radius, e2 * radius, nrm), wp(centre))
                }
                Shape::Sphere { center, radius } => {
                    el.point("center", wp(center)).float("radius", radius)
                }
                Shape::Cylinder { p0, p1, radius } => el
                    .point("p0", wp(p0))
                    .point("p1", wp(p1))
                    .float("radius", radius),
            };
            match part.face {
                Face::Inner { glass_inside: true } => el.child(dielectric(n_g, 1.0)),
                Face::Inner {
                    glass_inside: false,
                } => el.child(dielectric(1.0, n_g)),
                Face::Outer if medium_outside => el
                    .child(dielectric(n_g, n_out))
                    .reference("exterior", WATER_ID),
                Face::Outer => el.child(dielectric(n_g, n_out)),
                Face::Wall => el.child(black_bsdf()),
            }
        })
        .collect();
    Ok(Some(PortShapes {
        shapes,
        clearance: h.clearance,
        extent: h.extent,
    }))
}

/// The glass objects ([`crate::model::Material::glass`]): a `cube` (a box), a `sphere`, or a
/// `cylinder` closed by two `disk`s, with a smooth `dielectric` BSDF of the glass's and the surrounding water's (or air's) indices in
/// `channel`, and the water medium as its exterior when the box stands in it. In the view,
/// not in world.xml, since the medium is declared here.
fn glass_objects(model: &Model, channel: usize, region: MediumRegion) -> Vec<El> {
    use crate::model::Shape;
    let n_out = model.ambient_ior()[channel];
    let mut out = Vec::new();
    for (k, o) in model.objects.iter().enumerate() {
        let Some(g) = o.material.glass.as_ref() else {
            continue;
        };
        let comment = match &o.material.fill {
            Some(_) => format!("object `{}`: filled with water", o.name),
            None => format!("object `{}`: {} glass", o.name, g.name),
        };
        let bsdf = dielectric(g.ior[channel], n_out);
        let (m, t) = (o.pose.rotation, o.pose.translation);
        let shapes = match o.shape {
            Shape::Box { size } => vec![
                El::typed("shape", "cube")
                    .comment(comment)
                    .to_world(m * DMat3::from_diagonal(o.scale * size * 0.5), t)
                    .child(bsdf),
            ],
            // Uniformly scaled (the front end's rule): Mitsuba's exact sphere.
            Shape::Sphere { radius } => vec![
                El::typed("shape", "sphere")
                    .comment(comment)
                    .to_world(m * DMat3::from_diagonal(o.scale * radius), t)
                    .child(bsdf),
            ],
            // Scaled alike in x and y (the front end's rule): Mitsuba's exact cylinder, capped.
            Shape::Cylinder { radius, height } => super::world::capped_cylinder(
                m,
                t,
                radius * o.scale.x,
                0.5 * height * o.scale.z,
                &bsdf,
                comment,
            ),
            _ => continue,
        };
        let in_water = region.contains(t);
        let fill = o.material.fill.as_ref().map(|w| {
            out.push(fill_medium(w, k, &o.name));
            format!("fill_{k}")
        });
        out.extend(shapes.into_iter().map(|el| {
            let el = match &fill {
                Some(id) => el.reference("interior", id),
                None => el,
            };
            if in_water {
                el.reference("exterior", WATER_ID)
            } else {
                el
            }
        }));
    }
    out
}

/// The inside of a housing: black on both sides.
fn black_bsdf() -> El {
    El::typed("bsdf", "twosided").child(El::typed("bsdf", "diffuse").rgb("reflectance", [0.0; 3]))
}

fn dielectric(int_ior: f64, ext_ior: f64) -> El {
    El::typed("bsdf", "dielectric")
        .float("int_ior", int_ior)
        .float("ext_ior", ext_ior)
}
