//! Physical checks: small per-value checks used while reading (positive sizes, indices ≥ 1,
//! …) and whole-scene checks on the resolved model (targets inside the port glass, doubtful
//! overlaps, strobes too close to the port).

use super::diag::{Diagnostic, num};
use super::reader::{Cx, Tab};
use super::resolve::Spans;
use crate::model::*;
use crate::scene::format::types as F;

pub fn positive(cx: &mut Cx, t: &Tab, key: &str, v: f64, unit: &str) {
    if !(v > 0.0) {
        let what = if key.contains(F::PortTable::thickness) {
            "non-positive thickness"
        } else {
            "value must be positive"
        };
        cx.push(
            Diagnostic::error("E0045", format!("`{}` must be greater than 0", t.full(key)))
                .label(
                    t.span_of(key),
                    format!(
                        "{what}: {v}{}{unit}",
                        if unit.is_empty() { "" } else { " " }
                    ),
                )
                .help(format!("give a positive `{key}`")),
        );
    }
}

/// A value ≥ 0 (0 switches a feature off).
pub fn non_negative(cx: &mut Cx, t: &Tab, key: &str, v: f64, unit: &str) {
    if !(v >= 0.0) || !v.is_finite() {
        cx.push(
            Diagnostic::error("E0048", format!("`{}` must not be negative", t.full(key)))
                .label(
                    t.span_of(key),
                    format!("{v}{}{unit}", if unit.is_empty() { "" } else { " " }),
                )
                .help(format!("give `{key}` ≥ 0 (0 switches it off)")),
        );
    }
}

/// A value in [lo, hi].
pub fn within(cx: &mut Cx, t: &Tab, key: &str, v: f64, lo: f64, hi: f64) {
    if !(lo..=hi).contains(&v) {
        cx.push(
            Diagnostic::error(
                "E0051",
                format!(
                    "`{}` must be between {} and {}",
                    t.full(key),
                    num(lo),
                    num(hi)
                ),
            )
            .label(t.span_of(key), format!("{} is outside", num(v)))
            .help(format!(
                "give `{key}` a value in [{}, {}]",
                num(lo),
                num(hi)
            )),
        );
    }
}

pub fn at_least(cx: &mut Cx, t: &Tab, key: &str, v: u32, min: u32) {
    if v < min {
        cx.push(
            Diagnostic::error("E0046", format!("`{}` must be at least {min}", t.full(key)))
                .label(t.span_of(key), format!("{v} is too small"))
                .help(format!("use {min} or more")),
        );
    }
}

pub fn fits(cx: &mut Cx, t: &Tab, key: &str, v: f64, limit: f64, what: &str) {
    if v > 0.0 && limit > 0.0 && v >= limit {
        cx.push(
            Diagnostic::error(
                "E0047",
                format!("`{}` is too large for {what}", t.full(key)),
            )
            .label(
                t.span_of(key),
                format!(
                    "the printed marks would overlap ({} ≥ {} m)",
                    num(v),
                    num(limit)
                ),
            )
            .help(format!("make `{key}` smaller than {what}")),
        );
    }
}

/// Reject counts that would make a target, field or image absurdly large (and the
/// resolver allocate without bound).
pub fn at_most(cx: &mut Cx, t: &Tab, key: &str, v: u64, max: u64, what: &str) -> bool {
    if v > max {
        cx.push(
            Diagnostic::error("E0050", format!("`{}` is too large", t.full(key)))
                .label(
                    t.span_of(key),
                    format!("{v} {what}; at most {max} are supported"),
                )
                .help(format!("use a smaller `{key}`")),
        );
        return false;
    }
    true
}

/// A count through [`at_most`]: the count itself, or `fallback` (a size that can be built)
/// when it is over `max`, so that reading goes on.
pub fn capped(cx: &mut Cx, t: &Tab, key: &str, v: u32, max: u64, what: &str, fallback: u32) -> u32 {
    if at_most(cx, t, key, v as u64, max, what) {
        v
    } else {
        fallback
    }
}

pub fn non_negative_rgb(cx: &mut Cx, t: &Tab, key: &str, v: Rgb, unit: &str) {
    if v.iter().any(|x| *x < 0.0) {
        cx.push(
            Diagnostic::error("E0048", format!("`{}` must not be negative", t.full(key)))
                .label(
                    t.span_of(key),
                    format!(
                        "negative value{}",
                        if unit.is_empty() {
                            String::new()
                        } else {
                            format!(" ({unit})")
                        }
                    ),
                )
                .help("use values ≥ 0"),
        );
    }
}

/// Refractive indices must be ≥ 1 (and sane).
pub fn index(cx: &mut Cx, t: &Tab, key: &str, v: Rgb) {
    if v.iter().any(|x| *x < 1.0) {
        cx.push(
            Diagnostic::error(
                "E0049",
                format!("refractive index below 1 in `{}`", t.full(key)),
            )
            .label(
                t.span_of(key),
                format!("n = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2])),
            )
            .help("an index is ≥ 1 (water ≈ 1.34, glass ≈ 1.5); did you mean a different number?"),
        );
    } else if v.iter().any(|x| *x > 4.0) {
        cx.push(
            Diagnostic::error(
                "E0049",
                format!("refractive index implausibly high in `{}`", t.full(key)),
            )
            .label(
                t.span_of(key),
                format!("n = [{}, {}, {}]", num(v[0]), num(v[1]), num(v[2])),
            )
            .help("optical materials have indices between 1 and ~2.5"),
        );
    }
}

/// Whole-scene checks on the resolved model.
pub fn scene(cx: &mut Cx, m: &Model, spans: &Spans) {
    camera_above_surface(cx, m, spans);
    camera_below_seabed(cx, m, spans);
    if target_inside_port(cx, m, spans) {
        return;
    }
    ports_overlap(cx, m, spans);
    glass_objects(cx, m, spans);
    filled_objects(cx, m, spans);
    solids_overlap(cx, m, spans);
    wide_lens_behind_flat_port(cx, m, spans);
    overlap_delivered(cx, m, spans);
    seabed_seen(cx, m, spans);
    strobes_near_axis(cx, m, spans);
}

/// Whether world point `p` is inside object `o`'s box, sphere or cylinder (scale applied).
fn inside_solid(o: &crate::model::Object, p: glam::DVec3) -> bool {
    use crate::model::Shape;
    let a = o.pose.inverse().transform_point(p) / o.scale;
    match o.shape {
        Shape::Box { size } => a.abs().cmplt(0.5 * size).all(),
        Shape::Sphere { radius } => a.length() < radius,
        Shape::Cylinder { radius, height } => {
            a.truncate().length() < radius && a.z.abs() < 0.5 * height
        }
        _ => false,
    }
}

/// The filled objects ([`crate::model::Material::fill`]): no camera's pupil (E0304) and no
/// point, spot or area light (E0305) inside one. A camera in a tank would need the tank's water
/// as the water its port meets; a lamp inside lights it through no face, and a shadow ray from
/// it would have to leave the water through a refracting face that no backend follows.
fn filled_objects(cx: &mut Cx, m: &Model, spans: &Spans) {
    use crate::model::LightKind;
    let filled: Vec<(usize, &crate::model::Object)> = m
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material.fill.is_some())
        .collect();
    if filled.is_empty() {
        return;
    }
    let at = |i: usize| spans.objects.get(i).copied().unwrap_or(spans.network);
    let rig_poses: Vec<&crate::model::RigPose> = m.poses.iter().take(2000).collect();
    for (pi, pose) in rig_poses.iter().enumerate() {
        for ci in 0..m.cameras.len() {
            let c = m.world_from_camera(pi, ci).translation;
            if let Some(&(i, o)) = filled.iter().find(|(_, o)| inside_solid(o, c)) {
                cx.push(
                    Diagnostic::error(
                        "E0304",
                        format!("camera `{}` is inside filled object `{}`", m.cameras[ci].name, o.name),
                    )
                    .label(at(i), format!("the camera's pupil is inside it at pose {}", pose.name))
                    .help("cameras look at a filled object from outside it; to survey in that water, make it the scene's `[water]`"),
                );
                return;
            }
        }
    }
    let identity = crate::model::Pose::IDENTITY;
    let poses: Vec<&crate::model::Pose> = if rig_poses.is_empty() {
        vec![&identity]
    } else {
        rig_poses.iter().map(|p| &p.world_from_rig).collect()
    };
    for (li, light) in m.lights.iter().enumerate() {
        for w in &poses {
            let l = light.in_world(w);
            let p = match l.kind {
                LightKind::Point { position, .. } | LightKind::Spot { position, .. } => position,
                LightKind::Area { frame, .. } => frame.translation,
                LightKind::Ambient { .. } => continue,
            };
            if let Some(&(i, o)) = filled.iter().find(|(_, o)| inside_solid(o, p)) {
                let sp = spans.lights.get(li).map(|s| s.0).unwrap_or(at(i));
                cx.push(
                    Diagnostic::error(
                        "E0305",
                        format!("light `{}` is inside filled object `{}`", light.name, o.name),
                    )
                    .label(sp, "this light")
                    .label(at(i), "is inside this object")
                    .help("light a filled object from outside it (its faces refract the light in); move the light or the object"),
                );
                return;
            }
        }
    }
}

/// A target point inside the port glass (or between the pupil and the port) of a camera
/// (E0400, the first found). Returns whether there is one.
fn target_inside_port(cx: &mut Cx, m: &Model, spans: &Spans) -> bool {
    for (pi, _) in m.poses.iter().enumerate().take(2000) {
        for (ci, cam) in m.cameras.iter().enumerate() {
            let cam_from_world = m.world_from_camera(pi, ci).inverse();
            for (ti, t) in m.targets.iter().enumerate() {
                if let Some(p) = t
                    .points
                    .iter()
                    .find(|p| inside_housing(&cam.port, cam_from_world.transform_point(p.world)))
                {
                    if let Some(sp) = spans.targets.get(ti) {
                        cx.push(
                            Diagnostic::error("E0400", format!("target `{}` is inside the housing port of camera `{}`", t.name, cam.name))
                                .label(*sp, format!("point {} is inside the glass or behind the port at pose {}", p.id, m.poses[pi].name))
                                .help("move the target or the camera: targets must be in the water in front of the port"),
                        );
                    }
                    return true;
                }
            }
        }
    }
    false
}

/// The glass objects ([`crate::model::Material::glass`]: boxes, spheres, cylinders): they need
/// water everywhere or none (E0404: a water box around the camera would cut them), no camera's
/// pupil may be inside one (E0405), and a target seen through one gets a warning (W0406: the
/// ground truth does not refract through glass objects; it counts them as opaque, so those
/// observations are left out of the truth, while the images show the target through the
/// glass).
fn glass_objects(cx: &mut Cx, m: &Model, spans: &Spans) {
    let glass: Vec<(usize, &crate::model::Object)> = m
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material.glass.is_some())
        .collect();
    let Some(&(first, o)) = glass.first() else {
        return;
    };
    let at = |i: usize| spans.objects.get(i).copied().unwrap_or(spans.network);
    if let Some(w) = &m.water
        && matches!(w.extent, crate::model::WaterExtent::BoxAroundCamera { .. })
    {
        cx.push(
            Diagnostic::error(
                "E0404",
                format!("glass object `{}` in a water box around the camera", o.name),
            )
            .label(
                at(first),
                "a glass object needs water everywhere, or no water",
            )
            .help("remove the water's `extent`, so that the water fills the scene"),
        );
        return;
    }
    let mut seen_through: Option<(usize, String, String, usize)> = None;
    for (pi, pose) in m.poses.iter().enumerate().take(2000) {
        for ci in 0..m.cameras.len() {
            let c = m.world_from_camera(pi, ci).translation;
            for &(i, o) in &glass {
                // A filled glass object holding the camera is E0304 (`filled_objects`).
                if inside_solid(o, c) && o.material.fill.is_none() {
                    cx.push(
                        Diagnostic::error("E0405", format!("camera `{}` is inside glass object `{}`", m.cameras[ci].name, o.name))
                            .label(at(i), format!("the camera's pupil is inside it at pose {}", pose.name))
                            .help("move the camera or the glass: cameras look at glass from the water (or the air)"),
                    );
                    return;
                }
                for t in &m.targets {
                    for p in &t.points {
                        if segment_meets_solid(o, c, p.world) {
                            let e = seen_through.get_or_insert((
                                i,
                                t.name.clone(),
                                pose.name.clone(),
                                0,
                            ));
                            e.3 += 1;
                        }
                    }
                }
            }
        }
    }
    if let Some((i, target, pose, n)) = seen_through {
        cx.push(
            Diagnostic::warning("W0406", format!("target `{target}` is seen through {} object `{}`", if m.objects[i].material.fill.is_some() { "filled" } else { "glass" }, m.objects[i].name))
                .label(at(i), format!("{n} line(s) of sight from a camera to a target point cross it (first at pose {pose})"))
                .help("the ground truth does not refract through glass objects: it counts them as opaque, so those points are left out of the truth where glass hides them; move the target or the glass"),
        );
    }
}

/// Glass and filled objects whose insides overlap (E0407): each back end follows one boundary
/// at a time, with the water or air of the scene on its other side, so glass inside water inside
/// glass is not what any of them renders. Tested on a 16 × 16 × 16 grid of cell centres over
/// the smaller object's bounding box: an overlap thicker than about a sixteenth of its size is
/// found; objects that only touch (a window against a tank's water) pass.
fn solids_overlap(cx: &mut Cx, m: &Model, spans: &Spans) {
    let solids: Vec<(usize, &crate::model::Object, f64)> = m
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material.glass.is_some() || o.material.fill.is_some())
        .filter_map(|(i, o)| solid_extent(o).map(|e| (i, o, (e * o.scale).element_product())))
        .collect();
    let at = |i: usize| spans.objects.get(i).copied().unwrap_or(spans.network);
    for (k, &(i, a, size_a)) in solids.iter().enumerate() {
        for &(j, b, size_b) in &solids[..k] {
            // Sample inside the smaller one (by its bounding box's volume).
            let (small, other) = if size_a <= size_b { (a, b) } else { (b, a) };
            let Some(half) = solid_extent(small) else {
                continue;
            };
            const N: usize = 16;
            let hit = (0..N * N * N).find_map(|n| {
                let f = |k: usize| (k as f64 + 0.5) / N as f64 * 2.0 - 1.0;
                let local = glam::DVec3::new(f(n % N), f(n / N % N), f(n / (N * N))) * half;
                let world = small.pose.transform_point(local * small.scale);
                (inside_solid(small, world) && inside_solid(other, world)).then_some(world)
            });
            if let Some(p) = hit {
                let kind = |o: &crate::model::Object| {
                    if o.material.fill.is_some() {
                        "filled"
                    } else {
                        "glass"
                    }
                };
                cx.push(
                    Diagnostic::error("E0407", format!("{} object `{}` and {} object `{}` overlap", kind(b), b.name, kind(a), a.name))
                        .label(at(j), format!("both hold the point [{:.3}, {:.3}, {:.3}]", p.x, p.y, p.z))
                        .label(at(i), "overlaps this one")
                        .help("place them side by side (a glass window against a tank's water may touch it); one object cannot be inside another glass or filled object"),
                );
                return;
            }
        }
    }
}

/// Half the unscaled extent of a box, sphere or cylinder along its own axes; `None` for other
/// shapes.
fn solid_extent(o: &crate::model::Object) -> Option<glam::DVec3> {
    use crate::model::Shape;
    match o.shape {
        Shape::Box { size } => Some(0.5 * size),
        Shape::Sphere { radius } => Some(glam::DVec3::splat(radius)),
        Shape::Cylinder { radius, height } => Some(glam::DVec3::new(radius, radius, 0.5 * height)),
        _ => None,
    }
}

/// Whether the segment between world points `a` and `b` crosses object `o`'s box, sphere or
/// cylinder (scale applied; false for other shapes). In the object's frame divided by its
/// scale, an affine map that keeps which segments meet which solids, the shape is the
/// unscaled one.
fn segment_meets_solid(o: &crate::model::Object, a: glam::DVec3, b: glam::DVec3) -> bool {
    use crate::model::Shape;
    let from_world = o.pose.inverse();
    let (a, b) = (
        from_world.transform_point(a) / o.scale,
        from_world.transform_point(b) / o.scale,
    );
    match o.shape {
        Shape::Box { size } => segment_meets_box(a, b, 0.5 * size),
        Shape::Sphere { radius } => segment_distance_to_origin(a, b) < radius,
        Shape::Cylinder { radius, height } => {
            // Clip the segment to the slab |z| < height / 2, then its distance from the axis.
            let h = 0.5 * height;
            let d = b - a;
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            if d.z.abs() < 1e-300 {
                if a.z.abs() >= h {
                    return false;
                }
            } else {
                let (u, v) = ((-h - a.z) / d.z, (h - a.z) / d.z);
                t0 = t0.max(u.min(v));
                t1 = t1.min(u.max(v));
                if t0 > t1 {
                    return false;
                }
            }
            let (p, q) = (a + t0 * d, a + t1 * d);
            segment_distance_to_origin(p.truncate().extend(0.0), q.truncate().extend(0.0)) < radius
        }
        _ => false,
    }
}

/// The distance from the origin to the segment from `a` to `b`.
fn segment_distance_to_origin(a: glam::DVec3, b: glam::DVec3) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        (-a.dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + t * d).length()
}

/// Whether the segment from `a` to `b` crosses the box `|x| ≤ half` (slab test).
fn segment_meets_box(a: glam::DVec3, b: glam::DVec3, half: glam::DVec3) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-300 {
            if a[k].abs() > half[k] {
                return false;
            }
            continue;
        }
        let (u, v) = ((-half[k] - a[k]) / d[k], (half[k] - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Overlapping port surfaces between cameras of a rig: two housings intersecting (E0401).
fn ports_overlap(cx: &mut Cx, m: &Model, spans: &Spans) {
    for i in 0..m.cameras.len() {
        for j in 0..i {
            let (a, b) = (&m.cameras[i], &m.cameras[j]);
            let d = (a.rig_from_camera.translation - b.rig_from_camera.translation).length();
            let n = m.ambient_ior()[1];
            let (ra, rb) = (port_radius(a, n), port_radius(b, n));
            if ra > 0.0 && rb > 0.0 && d < ra + rb {
                let sp = spans
                    .baseline
                    .or(spans.camera.get(i).map(|c| c.port))
                    .unwrap_or(spans.network);
                cx.push(
                    Diagnostic::error(
                        "E0401",
                        format!("the ports of cameras `{}` and `{}` overlap", b.name, a.name),
                    )
                    .label(
                        sp,
                        format!(
                            "pupils {d:.3} m apart, ports need at least {:.3} m",
                            ra + rb
                        ),
                    )
                    .help("increase the rig baseline or use smaller ports"),
                );
            }
        }
    }
}

/// A very wide lens behind a flat port in water (W0250): the corners bend strongly
/// (distortion and lateral colour grow fast); a dome port is the usual remedy.
fn wide_lens_behind_flat_port(cx: &mut Cx, m: &Model, spans: &Spans) {
    if m.water.is_some() {
        for (i, c) in m.cameras.iter().enumerate() {
            if !matches!(c.port, Port::Flat { .. }) {
                continue;
            }
            let r = ((c.width as f64 / 2.0).powi(2) + (c.height as f64 / 2.0).powi(2)).sqrt();
            let half = match c.lens {
                LensModel::Rectilinear => (r / c.fx).atan(),
                LensModel::FisheyeEquidistant => r / c.fx,
                LensModel::FisheyeEquisolid => 2.0 * (r / (2.0 * c.fx)).min(1.0).asin(),
            };
            if half > 60f64.to_radians()
                && let Some(cs) = spans.camera.get(i)
            {
                cx.push(
                    Diagnostic::warning(
                        "W0250",
                        format!(
                            "camera `{}` sees {:.0}° from its axis to the image corner through a flat port",
                            c.name,
                            half.to_degrees()
                        ),
                    )
                    .label(cs.port, "flat port with a very wide lens")
                    .help("expect strong pincushion distortion and colour fringes at the corners; use a dome port for wide-angle lenses"),
                );
            }
        }
    }
}

/// A doubtful side-lap (W0300), and what the network delivers against the overlaps asked
/// (W0301; exact footprint over a flat seabed).
fn overlap_delivered(cx: &mut Cx, m: &Model, spans: &Spans) {
    // Doubtful side-lap.
    if let (Some(s), Some(sp)) = (m.network.sidelap, spans.sidelap)
        && s < 0.6
    {
        cx.push(
            Diagnostic::warning(
                "W0300",
                format!("the strips give a side-lap of only {:.0} %", s * 100.0),
            )
            .label(sp, "below the 60 % recommended")
            .help(
                "photogrammetry between strips needs ≥ 60 % side-lap to tie reliably; expect gaps",
            ),
        );
    }
    // What the network delivers against what was asked (exact footprint over a flat seabed).
    for (what, got, want, sp) in [
        (
            "forward overlap",
            m.network.overlap,
            m.network.overlap_requested,
            spans.overlap_asked,
        ),
        (
            "side-lap",
            m.network.sidelap,
            m.network.sidelap_requested,
            spans.sidelap_asked,
        ),
    ] {
        if let (Some(got), Some(want), Some(sp)) = (got, want, sp)
            && got < want - 0.02
        {
            cx.push(
                Diagnostic::warning(
                    "W0301",
                    format!(
                        "the network gives {:.0} % {what}, not the {:.0} % asked",
                        got * 100.0,
                        want * 100.0
                    ),
                )
                .label(sp, "asked here")
                .help("`strips`, or a `trigger` by distance or time, fixes the spacing; remove it to space the images for the requested overlap"),
            );
        }
    }
}

/// Strobes close to the optical axis and port, where backscatter dominates (W0310).
fn strobes_near_axis(cx: &mut Cx, m: &Model, spans: &Spans) {
    if let Some(w) = &m.water {
        let scatter = w.scattering.iter().cloned().fold(0.0, f64::max);
        for (li, l) in m.lights.iter().enumerate() {
            if l.mount != Mount::Rig {
                continue;
            }
            let (LightKind::Spot { position, .. } | LightKind::Point { position, .. }) = l.kind
            else {
                continue;
            };
            let lateral = position.truncate().length();
            if scatter > 0.0
                && lateral < 0.15
                && let Some((_, psp)) = spans.lights.get(li)
            {
                {
                    cx.push(
                        Diagnostic::warning("W0310", format!("light `{}` is only {:.0} cm from the camera axis", l.name, lateral * 100.0))
                            .label(*psp, "close to the port")
                            .help("backscatter will dominate the image; mount strobes ≥ 30 cm to the side and aim them outwards"),
                    );
                }
            }
        }
    }
}

/// A seabed (or boulder field) with less than this share inside the union of the images'
/// ground footprints is mostly unseen (W0302) ...
pub const SEABED_SEEN_MIN: f64 = 0.5;
/// ... and below this share of the footprints' union on that seabed, the network looks past
/// it: the two do not match. A seabed larger than the network with every image on it (scenery
/// around the site, as the water column wants) is not warned about.
pub const NETWORK_ON_SEABED_MIN: f64 = 0.9;

/// `26 %`, or `0.4 %` below 10 %.
fn percent(x: f64) -> String {
    if x < 0.1 {
        format!("{:.1} %", 100.0 * x)
    } else {
        format!("{:.0} %", 100.0 * x)
    }
}

/// A seabed or boulder field (not a backdrop) mostly outside the network's footprints while the
/// network also looks past it: the usual cause is a seabed's `width`/`length` (along x/y) swapped against a lawnmower's
/// (across/along its strips), or a network centred elsewhere.
fn seabed_seen(cx: &mut Cx, m: &Model, spans: &Spans) {
    if cx.has_errors() || m.poses.is_empty() {
        return;
    }
    for (i, o) in m.objects.iter().enumerate() {
        let (Shape::Seabed { width, length, .. } | Shape::Boulders { width, length, .. }) = o.shape
        else {
            continue;
        };
        if o.backdrop || !(width > 0.0 && length > 0.0) {
            continue;
        }
        let (hx, hy) = (0.5 * width * o.scale.x, 0.5 * length * o.scale.y);
        let corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
            .map(|(x, y)| o.pose.transform_point(glam::DVec3::new(x, y, 0.0)));
        if (corners[0].z - corners[2].z).abs() > 1e-6 || (corners[1].z - corners[3].z).abs() > 1e-6
        {
            continue; // a tilted seabed: its plane is not horizontal
        }
        let Some(seen) = crate::plan::footprints::seen(m, corners) else {
            continue;
        };
        let Some(sp) = spans.objects.get(i) else {
            continue;
        };
        if seen.rect_seen < SEABED_SEEN_MIN && seen.on_rect < NETWORK_ON_SEABED_MIN {
            cx.push(
                Diagnostic::warning(
                    "W0302",
                    format!(
                        "the camera network sees {} of seabed `{}`",
                        percent(seen.rect_seen),
                        o.name
                    ),
                )
                .label(
                    *sp,
                    format!(
                        "{} m × {} m (x × y): the images' footprints cover {} of it, and {} of \
                         what they see is past it",
                        num(width * o.scale.x),
                        num(length * o.scale.y),
                        percent(seen.rect_seen),
                        percent(1.0 - seen.on_rect)
                    ),
                )
                .help(
                    "a seabed's `width` runs along x (east) and its `length` along y (north), while a \
                     lawnmower's `width` is across its strips and its `length` along them (`heading`, \
                     clockwise from north): check that the two agree, that the network is centred on the \
                     seabed, and that the seabed covers the surveyed area",
                ),
            );
        }
    }
}

/// A camera above the sea surface is modelled only as a camera in the air (no port) above
/// every crest of a modelled surface (flat or waves): it looks through the surface. Any
/// other camera out of the water would be modelled as if in it (its port, the medium).
fn camera_above_surface(cx: &mut Cx, m: &Model, spans: &Spans) {
    if m.water.is_some() {
        let wrong = |pi: usize, ci: usize| {
            m.world_from_camera(pi, ci).translation.z >= 0.0
                && !(matches!(m.cameras[ci].port, crate::model::Port::None)
                    && m.above_surface(pi, ci))
        };
        let above = (0..m.poses.len())
            .flat_map(|pi| (0..m.cameras.len()).map(move |ci| (pi, ci)))
            .find(|&(pi, ci)| wrong(pi, ci));
        if let Some((pi, ci)) = above {
            let z = m.world_from_camera(pi, ci).translation.z;
            let n = (0..m.poses.len())
                .flat_map(|pi| (0..m.cameras.len()).map(move |ci| (pi, ci)))
                .filter(|&(pi, ci)| wrong(pi, ci))
                .count();
            cx.push(
                Diagnostic::error(
                    "E0402",
                    format!(
                        "camera `{}` is {z:.2} m above the sea surface at pose {} ({n} image{} in all)",
                        m.cameras[ci].name,
                        m.poses[pi].name,
                        if n == 1 { "" } else { "s" }
                    ),
                )
                .label(spans.network, "puts cameras above the water")
                .help("cameras are in the water (z < 0, the surface is z = 0): lower the altitude or raise `site.depth`; for a survey in air, remove [water]; for a drone looking down through the water, give the camera `[camera.port] type = \"none\"`, model the surface (`site.surface = \"flat\"` or `\"waves\"`) and keep it above the crests"),
            );
        }
    }
}

/// A camera at or below the nominal seabed (z = −`site.depth`): it looks at the underside of
/// the site's ground, and it sits below the bottom of the water column that lights the
/// scene. Usually a pose list written up from the seabed, not down from the surface.
fn camera_below_seabed(cx: &mut Cx, m: &Model, spans: &Spans) {
    if m.water.is_some() && m.site.depth > 0.0 {
        let bed = -m.site.depth;
        let low = |pi: usize, ci: usize| m.world_from_camera(pi, ci).translation.z < bed + 0.05;
        let pairs =
            || (0..m.poses.len()).flat_map(|pi| (0..m.cameras.len()).map(move |ci| (pi, ci)));
        if let Some((pi, ci)) = pairs().find(|&(pi, ci)| low(pi, ci)) {
            let n = pairs().filter(|&(pi, ci)| low(pi, ci)).count();
            let lowest = pairs()
                .map(|(pi, ci)| m.world_from_camera(pi, ci).translation.z)
                .fold(f64::INFINITY, f64::min);
            cx.push(
                Diagnostic::warning(
                    "W0403",
                    format!(
                        "camera `{}` is at or below the seabed at pose {} ({n} image{} in all, \
                         the lowest {:.2} m below it)",
                        m.cameras[ci].name,
                        m.poses[pi].name,
                        if n == 1 { "" } else { "s" },
                        (bed - lowest).max(0.0)
                    ),
                )
                .label(
                    spans.network,
                    format!("puts cameras within 5 cm of z = {bed} m or below"),
                )
                .help(format!(
                    "the nominal seabed is `site.depth` = {} m below the surface (z = {bed} m): \
                     give the network an altitude above it (z is up, 0 at the \
                     surface), or deepen the site",
                    m.site.depth
                )),
            );
        }
    }
}

/// Whether a point (camera frame) is inside the port glass or between the pupil and the port.
fn inside_housing(port: &Port, p: glam::DVec3) -> bool {
    match port {
        Port::None => false,
        Port::Flat {
            normal, distance, ..
        } => {
            let d = normal.dot(p);
            // Within the housing's cross-section (a generous 20 cm radius) only.
            let lateral = (p - *normal * d).length();
            d <= distance + port.total_thickness() && d > -0.05 && lateral < 0.2
        }
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => (p - *center).length() <= inner_radius + thickness,
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => {
            let v = p - *axis_point;
            let along = v.dot(*axis);
            (v - *axis * along).length() <= inner_radius + thickness
                && along.abs() < 0.2
                && v.dot(glam::DVec3::Z) > -0.05
        }
    }
}

/// A rough outer radius of a port around the pupil, m (0 for no port).
/// Radius (m, across the optical axis) that camera `cam`'s port occupies. A dome or cylinder:
/// its outer surface about the pupil. A flat port: the glass must pass the whole field of
/// view, so its aperture reaches at least as far from the axis as the sensor corners' rays
/// where they leave the glass (exact refraction).
fn port_radius(cam: &crate::model::Camera, n_water: f64) -> f64 {
    match &cam.port {
        Port::None => 0.0,
        Port::Flat { normal, .. } => {
            let Ok(pr) = crate::optics::project::Projector::for_camera(cam, 1, n_water) else {
                return 0.0;
            };
            let (w, h) = (cam.width as f64, cam.height as f64);
            [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
                .iter()
                .filter_map(|&(u, v)| pr.camera_ray(u, v).ok())
                .map(|r| (r.origin - *normal * normal.dot(r.origin)).length())
                .fold(0.0, f64::max)
        }
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => center.length() + inner_radius + thickness,
        Port::Cylinder {
            inner_radius,
            thickness,
            ..
        } => inner_radius + thickness,
    }
}
