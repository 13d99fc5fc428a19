//! One view document per (pose, camera[, channel pass]): `{image}.xml` or
//! `{image}.{r,g,b}.xml`, in the order it is written by [`view`]:
//!
//! | item | function | Mitsuba 3 |
//! |---|---|---|
//! | header and integrator | [`view`] | `volpathmis` with water (spectral MIS), else `volpath`; `include` of `world.xml` |
//! | water | `medium_region`, `water_medium`, [`ff_table`] | `homogeneous` medium in a `null` cube |
//! | camera | [`check_camera`], `sensor`, `thin_lens` | `perspective` or `thinlens` sensor |
//! | port and housing | `port_shapes` (`border_rays`, `rect_to_world`, `dielectric`) | `dielectric` shapes, black housing walls |
//! | rig-mounted lights | `world::light` (shared with the world) | as world-mounted lights |
//!
//! Indices: a dielectric needs one number per side; without per-channel passes the G channel
//! (550 nm) index is used ([`super::SINGLE_PASS_CHANNEL`]), with them each pass uses its own
//! channel's indices.

// `!(x > y)` is deliberate: it rejects NaN as well as the failing comparison.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::world::{light, scene_bounds};
use super::xml::El;
use super::{SEA_MARGIN, TABPHASE_SAMPLES, WATER_ID, basis};
use crate::model::*;
use crate::optics::phase::ff_cdf;
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
    // With water, `volpathmis`: free-flight distances sampled with spectral MIS over the
    // three channels. `volpath` samples them in one channel picked per path and reweights the
    // others, and in deep, strongly chromatic water the paths sampled in red almost never
    // reach the surface, so at any practical sample count the image is a third too dark in
    // every channel (gsd_reef, clear Jerlov IB at 30 m under ambient light: −36 % against
    // native and Cycles with `volpath`, +2 % with `volpathmis`; grey water agrees with both).
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
    root.push(sensor(model, spec, near_clip, in_water));
    if let Some(p) = port {
        for s in p.shapes {
            root.push(s);
        }
    }
    for l in model.lights.iter().filter(|l| l.mount == Mount::Rig) {
        root.push(light(l, &world_from_rig));
    }
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
        .attr("id", WATER_ID)
        .comment(format!(
            "water: absorption {:?} 1/m, scattering {:?} 1/m{}",
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
        .float("scale", 1.0)
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

fn sensor(model: &Model, spec: &ViewSpec, near_clip: f64, in_water: bool) -> El {
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
            .float("aperture_radius", aperture)
            .float("focus_distance", focus),
        None => El::typed("sensor", "perspective"),
    };
    s = s.float("fov", fov).string("fov_axis", "x");
    if thin_lens(cam).is_none() {
        s = s
            .float("principal_point_offset_x", 0.5 - cam.cx / w)
            .float("principal_point_offset_y", 0.5 - cam.cy / h);
    }
    s = s
        .float("near_clip", near_clip)
        .float("far_clip", 1e6)
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
    .child(
        El::typed("film", "hdrfilm")
            .integer("width", cam.width as i64)
            .integer("height", cam.height as i64)
            .string("pixel_format", "rgb")
            .string("component_format", "float32")
            .child(El::typed("rfilter", "box")),
    )
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

/// Where a port's shapes go: the camera, its pose in the world and the medium outside.
struct PortPlacement<'a> {
    cam: &'a Camera,
    world_from_cam: &'a Pose,
    /// Refractive index outside the glass in this channel.
    n_out: f64,
    medium_outside: bool,
}

impl PortPlacement<'_> {
    /// A camera-frame point in the world.
    fn wp(&self, p: DVec3) -> DVec3 {
        self.world_from_cam.transform_point(p)
    }

    /// A camera-frame direction in the world, unit length.
    fn wv(&self, v: DVec3) -> DVec3 {
        (self.world_from_cam.rotation * v).normalize()
    }

    /// A glass face towards the outside, in the water medium when there is one.
    fn outer(&self, el: El) -> El {
        if self.medium_outside {
            el.reference("exterior", WATER_ID)
        } else {
            el
        }
    }
}

fn port_shapes(
    cam: &Camera,
    world_from_cam: &Pose,
    channel: usize,
    n_out: f64,
    medium_outside: bool,
) -> Result<Option<PortShapes>, String> {
    let at = PortPlacement {
        cam,
        world_from_cam,
        n_out,
        medium_outside,
    };
    match &cam.port {
        Port::None => Ok(None),
        Port::Flat {
            normal,
            distance,
            thickness,
            glass,
            ..
        } => flat_port(&at, *normal, *distance, *thickness, glass.ior[channel]).map(Some),
        Port::Dome {
            center,
            inner_radius,
            thickness,
            glass,
        } => dome_port(&at, *center, *inner_radius, *thickness, glass.ior[channel]).map(Some),
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            glass,
        } => cylinder_port(
            &at,
            *axis_point,
            *axis,
            *inner_radius,
            *thickness,
            glass.ior[channel],
        )
        .map(Some),
    }
}

/// A flat port: the glass slab's six faces and the black housing walls behind it.
fn flat_port(
    at: &PortPlacement,
    normal: DVec3,
    distance: f64,
    thickness: f64,
    n_g: f64,
) -> Result<PortShapes, String> {
    let n = normal.normalize();
    let (name, wp, wv) = (&at.cam.name, |p| at.wp(p), |v| at.wv(v));
    if !(distance > 0.0) || !(thickness > 0.0) {
        return Err(format!(
            "camera `{name}`: the flat port needs a positive distance and thickness"
        ));
    }
    let mut max_tan: f64 = 0.0;
    for r in border_rays(at.cam) {
        let c = r.dot(n);
        if c < 0.1 {
            return Err(format!(
                "camera `{name}`: the field of view reaches {:.1}° from the flat port's \
                 normal; the port cannot cover it",
                c.clamp(-1.0, 1.0).acos().to_degrees()
            ));
        }
        max_tan = max_tan.max((1.0 - c * c).sqrt() / c);
    }
    let (d, t) = (distance, thickness);
    let half = 1.5 * (d + t) * max_tan + 2.0 * t;
    let (e1, e2) = basis(n);
    let (we1, we2, wn) = (wv(e1), wv(e2), wv(n));
    let mut shapes = Vec::new();
    // Inner face, normal towards the camera: interior (behind the normal) is glass.
    shapes.push(
        rect_to_world(
            El::typed("shape", "rectangle")
                .comment(format!("port of `{name}`: inner face (air | glass)")),
            wp(n * d),
            we2,
            we1,
            -wn,
            half,
            half,
        )
        .child(dielectric(n_g, 1.0)),
    );
    // Outer face, normal towards the water.
    shapes.push(
        at.outer(
            rect_to_world(
                El::typed("shape", "rectangle")
                    .comment(format!("port of `{name}`: outer face (glass | water)")),
                wp(n * (d + t)),
                we1,
                we2,
                wn,
                half,
                half,
            )
            .child(dielectric(n_g, at.n_out)),
        ),
    );
    // Four edge faces, normals outward.
    let mid = wp(n * (d + 0.5 * t));
    for (axis, other) in [(we1, we2), (-we1, -we2), (we2, -we1), (-we2, we1)] {
        // Rectangle local x = other (half), y = wn (t/2), z = axis (outward normal).
        shapes.push(
            at.outer(
                El::typed("shape", "rectangle")
                    .to_world(
                        DMat3::from_cols(other * half, wn * (0.5 * t), axis),
                        mid + axis * half,
                    )
                    .child(dielectric(n_g, at.n_out)),
            ),
        );
    }
    // The housing behind the port: five black walls (back and four sides, from the
    // inner face back to `d + t` behind the pupil) close the air pocket, so rays
    // reflected by the glass back into the housing end there instead of escaping to
    // the ambient light (a real housing is dark inside).
    let back = d + t;
    let black = black_bsdf();
    shapes.push(
        rect_to_world(
            El::typed("shape", "rectangle")
                .comment(format!("housing of `{name}`: black walls behind the port")),
            wp(-n * back),
            we1,
            we2,
            -wn,
            half,
            half,
        )
        .child(black.clone()),
    );
    let wall_mid = wp(n * (0.5 * (d - back)));
    for (axis, other) in [(we1, we2), (-we1, -we2), (we2, -we1), (-we2, we1)] {
        shapes.push(
            El::typed("shape", "rectangle")
                .to_world(
                    DMat3::from_cols(other * half, wn * (0.5 * (d + back)), axis),
                    wall_mid + axis * half,
                )
                .child(black.clone()),
        );
    }
    let extent = ((d + t).powi(2) + 2.0 * half * half).sqrt();
    Ok(PortShapes {
        shapes,
        clearance: d,
        extent,
    })
}

/// A dome port: the inner and outer spheres and the black disk behind them.
fn dome_port(
    at: &PortPlacement,
    center: DVec3,
    r: f64,
    t: f64,
    n_g: f64,
) -> Result<PortShapes, String> {
    let (name, wp, wv) = (&at.cam.name, |p| at.wp(p), |v| at.wv(v));
    if !(r > 0.0) || !(t > 0.0) {
        return Err(format!(
            "camera `{name}`: the dome port needs a positive radius and thickness"
        ));
    }
    if center.length() >= r {
        return Err(format!(
            "camera `{name}`: the dome's centre is {:.4} m from the entrance pupil, outside \
             its inner radius {r} m",
            center.length()
        ));
    }
    let c = wp(center);
    let inner = El::typed("shape", "sphere")
        .comment(format!(
            "dome port of `{name}`: inner sphere (air inside | glass)"
        ))
        .point("center", c)
        .float("radius", r)
        .child(dielectric(1.0, n_g));
    let outer_s = at.outer(
        El::typed("shape", "sphere")
            .comment(format!(
                "dome port of `{name}`: outer sphere (glass inside | water)"
            ))
            .point("center", c)
            .float("radius", r + t)
            .child(dielectric(n_g, at.n_out)),
    );
    // The housing behind the dome: a black disk across the inner sphere, behind the
    // pupil and the glass the field of view uses (its rim at the field angle + 15°,
    // 60°..170° from the axis, as the Blender backend's housing). The spheres are
    // whole, so without it light the glass reflects back into the housing crossed the
    // spheres' back halves to the water and the sky: flat_port_deformation_dome was
    // +17 % G over native (`poser bench parity --quick`).
    let max_field = border_rays(at.cam)
        .iter()
        .map(|d| d.z.clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max);
    let alpha = (max_field + 15f64.to_radians()).clamp(60f64.to_radians(), 170f64.to_radians());
    let z_back = (center.z + r * alpha.cos()).min(0.0) - 0.01 * r;
    let rho = (r * r - (z_back - center.z).powi(2)).max(0.0).sqrt() * (1.0 - 1e-6);
    let axis = wv(DVec3::Z);
    let (e1, e2) = basis(axis);
    let housing = El::typed("shape", "disk")
        .comment(format!("housing of `{name}`: black disk behind the dome"))
        .to_world(
            DMat3::from_cols(e1 * rho, e2 * rho, axis),
            wp(DVec3::new(center.x, center.y, z_back)),
        )
        .child(black_bsdf());
    Ok(PortShapes {
        shapes: vec![inner, outer_s, housing],
        clearance: r - center.length(),
        extent: center.length() + r + t,
    })
}

/// A cylinder port: the inner and outer cylinders, each closed by two disks.
fn cylinder_port(
    at: &PortPlacement,
    axis_point: DVec3,
    axis: DVec3,
    r: f64,
    t: f64,
    n_g: f64,
) -> Result<PortShapes, String> {
    let (name, wp, wv) = (&at.cam.name, |p| at.wp(p), |v| at.wv(v));
    let u = axis.normalize();
    if !(r > 0.0) || !(t > 0.0) {
        return Err(format!(
            "camera `{name}`: the cylinder port needs a positive radius and thickness"
        ));
    }
    // Pupil (origin) relative to the axis.
    let w = -axis_point - (-axis_point).dot(u) * u;
    if w.length() >= r {
        return Err(format!(
            "camera `{name}`: the entrance pupil is {:.4} m from the cylinder axis, outside \
             its inner radius {r} m",
            w.length()
        ));
    }
    let mut max_axial: f64 = 0.0;
    for d in border_rays(at.cam) {
        let dp = d - d.dot(u) * u;
        let a = dp.length_squared();
        if a < 1e-6 {
            return Err(format!(
                "camera `{name}`: the field of view contains the cylinder port's axis; the \
                 port cannot cover it"
            ));
        }
        let b = 2.0 * w.dot(dp);
        let cc = w.length_squared() - r * r;
        let s = (-b + (b * b - 4.0 * a * cc).sqrt()) / (2.0 * a);
        max_axial = max_axial.max((s * d - axis_point).dot(u).abs());
    }
    let half_len = 1.5 * max_axial + 4.0 * t + 0.5 * r;
    let a0 = axis_point;
    let mut shapes = Vec::new();
    for (rad, hl, int_ior, ext_ior, label) in [
        (r, half_len, 1.0, n_g, "inner (air inside | glass)"),
        (
            r + t,
            half_len + t,
            n_g,
            at.n_out,
            "outer (glass inside | water)",
        ),
    ] {
        let is_outer = rad > r;
        let cyl = El::typed("shape", "cylinder")
            .comment(format!("cylinder port of `{name}`: {label}"))
            .point("p0", wp(a0 - u * hl))
            .point("p1", wp(a0 + u * hl))
            .float("radius", rad)
            .child(dielectric(int_ior, ext_ior));
        shapes.push(if is_outer { at.outer(cyl) } else { cyl });
        for sign in [-1.0, 1.0] {
            let nrm = wv(u * sign);
            let (e1, e2) = basis(nrm);
            let disk = El::typed("shape", "disk")
                .to_world(
                    DMat3::from_cols(e1 * rad, e2 * rad, nrm),
                    wp(a0 + u * (sign * hl)),
                )
                .child(dielectric(int_ior, ext_ior));
            shapes.push(if is_outer { at.outer(disk) } else { disk });
        }
    }
    Ok(PortShapes {
        shapes,
        clearance: r - w.length(),
        extent: axis_point.length() + (half_len + t).hypot(r + t),
    })
}

/// Camera-frame rays through the image border (pixel-edge samples), unit length.
fn border_rays(cam: &Camera) -> Vec<DVec3> {
    let (w, h) = (cam.width as f64, cam.height as f64);
    let n = 32;
    let mut pts = Vec::with_capacity(4 * n);
    for k in 0..n {
        let s = k as f64 / n as f64;
        pts.push((s * w, 0.0));
        pts.push((w, s * h));
        pts.push((w - s * w, h));
        pts.push((0.0, h - s * h));
    }
    pts.into_iter()
        .map(|(u, v)| DVec3::new((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0).normalize())
        .collect()
}

fn rect_to_world(el: El, centre: DVec3, e1: DVec3, e2: DVec3, n: DVec3, h1: f64, h2: f64) -> El {
    el.to_world(DMat3::from_cols(e1 * h1, e2 * h2, n), centre)
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
