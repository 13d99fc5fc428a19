//! The camera network, `[network]`: where the rig takes its pictures. Each kind of network is
//! read by its own function — a `lawnmower` of parallel strips, a `spiral`, an `orbit` of
//! rings around a point, or `explicit` `[[network.poses]]` — into a [`NetworkSpec`], which
//! [`crate::plan::network::expand`] turns into poses (spacings through the exact port), with the
//! diver's hand-held jitter added. The `trigger` says when a picture is taken.

use super::{Spans, euler};
use crate::model::*;
use crate::optics;
use crate::plan::network::{self, ExplicitPose, NetworkContext, NetworkSpec, Orientation, Trigger};
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span, num};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Node, Val};
use crate::units::Dim;
use glam::DVec3;

/// `[network]` → the rig poses and the network summary (none when anything in the scene is in
/// error, so that a broken scene is not expanded).
#[allow(clippy::too_many_arguments)]
pub(super) fn network(
    cx: &mut Cx,
    node: Option<&Node>,
    cameras: &[Camera],
    ior: Rgb,
    site: &Site,
    speed_default: f64,
    spans: &mut Spans,
    fallback: Span,
) -> (Vec<RigPose>, NetworkSummary) {
    let Some(node) = node else {
        cx.push(
            Diagnostic::error("E0310", "the scene has no camera network")
                .label(fallback, "no [network] table in this scene")
                .help("add `[network]` with `type = \"explicit\"` and `[[network.poses]]`, or a lawnmower/spiral/orbit"),
        );
        return (vec![], NetworkSummary::default());
    };
    let mut t = Tab::open(cx, Some(node), F::Scene::network, fallback);
    spans.network = t.span;
    let ty = t
        .choice(
            cx,
            F::Network::kind,
            &["explicit", "lawnmower", "spiral", "orbit"],
        )
        .unwrap_or("explicit");
    let speed = t.f64(cx, F::Network::speed, Dim::Speed, speed_default);
    check::positive(cx, &t, F::Network::speed, speed, "m/s");
    let jitter = jitter(cx, &mut t);
    let ctx = context(cameras, ior, site, speed);
    let spec = match ty {
        "lawnmower" => lawnmower(cx, &mut t, &ctx, spans),
        "spiral" => spiral(cx, &mut t, &ctx, spans),
        "orbit" => orbit(cx, &mut t, site),
        _ => explicit(cx, &mut t),
    };
    t.finish_as(cx, Some(&format!("a {ty} network")));
    let failed = || NetworkSummary {
        kind: ty.into(),
        speed,
        ..Default::default()
    };
    if cx.has_errors() {
        return (vec![], failed());
    }
    match network::expand(&spec, &ctx) {
        Ok((mut poses, summary)) => {
            network::jitter(&mut poses, &jitter);
            if poses.is_empty() {
                cx.push(
                    Diagnostic::error("E0318", "the network has no poses")
                        .label(spans.network, "expands to zero images")
                        .help("make the survey area larger than one footprint, or add rings/poses"),
                );
            }
            (poses, summary)
        }
        Err(m) => {
            cx.push(
                Diagnostic::error("E0319", "cannot expand the camera network")
                    .label(spans.network, m)
                    .help("check the network's sizes, altitude and speed"),
            );
            (vec![], failed())
        }
    }
}

/// The hand-held wobble added to every pose: `jitter_position`, `jitter_rotation` (σ) and
/// `jitter_seed`.
fn jitter(cx: &mut Cx, t: &mut Tab) -> network::Jitter {
    let jitter = network::Jitter {
        position: t.f64(cx, F::Network::jitter_position, Dim::Length, 0.0),
        rotation: t.f64(cx, F::Network::jitter_rotation, Dim::Angle, 0.0),
        seed: t.opt_u64(cx, F::Network::jitter_seed).unwrap_or(1),
    };
    if !(jitter.position >= 0.0 && jitter.rotation >= 0.0 && jitter.rotation < 0.5) {
        let sp = t.span_of(F::Network::jitter_rotation);
        cx.push(
            Diagnostic::error("E0315", "jitter must be a small, non-negative spread")
                .label(sp, "the σ of a hand-held camera's wobble")
                .help("a diver holds a camera to a few centimetres and a few degrees, e.g. `jitter_position = \"3 cm\"`, `jitter_rotation = \"2 deg\"`"),
        );
    }
    jitter
}

/// What the expansion needs to know of the first camera, its port and the site.
fn context(cameras: &[Camera], ior: Rgb, site: &Site, speed: f64) -> NetworkContext {
    let cam = cameras.first();
    let magnification = match cam.map(|c| &c.port) {
        Some(Port::Flat { .. }) => ior[1],
        _ => 1.0,
    };
    NetworkContext {
        width: cam.map(|c| c.width).unwrap_or(1).max(1),
        height: cam.map(|c| c.height).unwrap_or(1).max(1),
        focal_px: cam.map(|c| c.fx).unwrap_or(1.0),
        magnification,
        seabed_z: -site.depth,
        speed: if speed > 0.0 { speed } else { 0.2 },
        // Footprints and spacings through the exact port (a flat port narrows a wide lens's
        // view at the edges: the paraxial spacing misses the requested overlap).
        exact: cam
            .and_then(|c| optics::project::Projector::for_camera(c, 1, ior[1]).ok())
            .map(std::sync::Arc::new),
    }
}

/// The survey height above the seabed: `altitude`, or the one that gives `gsd` (one of the two
/// is required).
fn altitude(cx: &mut Cx, t: &mut Tab, ctx: &NetworkContext, ty: &str) -> f64 {
    let a = t.opt_f64(cx, F::Network::altitude, Dim::Length);
    let g = t.opt_f64(cx, F::Network::gsd, Dim::Gsd);
    match (a, g) {
        (Some(a), None) => {
            check::positive(cx, t, F::Network::altitude, a, "m");
            a
        }
        (None, Some(g)) => {
            check::positive(cx, t, F::Network::gsd, g, "m/px");
            ctx.altitude_for_gsd(g)
        }
        (Some(a), Some(_)) => {
            let sp = t.key_span(F::Network::gsd);
            cx.push(
                Diagnostic::error("E0311", "give either `altitude` or `gsd`, not both")
                    .label(sp, "remove this or `altitude`")
                    .help("the altitude follows from the GSD through the camera and port"),
            );
            a
        }
        (None, None) => {
            let sp = t.span;
            cx.push(
                Diagnostic::error(
                    "E0311",
                    format!("a {ty} network needs an `altitude` or a `gsd`"),
                )
                .label(sp, "neither is given")
                .help("e.g. `altitude = \"2 m\"` or `gsd = \"1 mm/px\"`"),
            );
            2.0
        }
    }
}

/// A fraction in [0, 1) (`overlap`, `sidelap`); `d` when absent or out of range.
fn fraction(cx: &mut Cx, t: &mut Tab, key: &'static str, d: f64) -> f64 {
    let v = t.f64(cx, key, Dim::Fraction, d);
    if !(0.0..1.0).contains(&v) {
        let sp = t.span_of(key);
        cx.push(
            Diagnostic::error("E0312", format!("`{key}` must be a fraction in [0, 1)"))
                .label(sp, num(v))
                .help(format!("write e.g. `{key} = 0.6` or `{key} = \"60 %\"`")),
        );
        return d;
    }
    v
}

/// `overlap` (along a strip) and `sidelap` (between strips) of a lawnmower or spiral, with the
/// spans the coverage checks point at.
fn laps(cx: &mut Cx, t: &mut Tab, spans: &mut Spans) -> (f64, f64) {
    let overlap = fraction(cx, t, F::Network::overlap, 0.8);
    let sidelap = fraction(cx, t, F::Network::sidelap, 0.6);
    spans.sidelap = Some(t.span_of(F::Network::sidelap));
    spans.overlap_asked = t
        .has(F::Network::overlap)
        .then(|| t.span_of(F::Network::overlap));
    spans.sidelap_asked = t
        .has(F::Network::sidelap)
        .then(|| t.span_of(F::Network::sidelap));
    (overlap, sidelap)
}

/// `type = "lawnmower"`: parallel strips over a `width` × `length` rectangle, optionally
/// crossed and with oblique images.
fn lawnmower(cx: &mut Cx, t: &mut Tab, ctx: &NetworkContext, spans: &mut Spans) -> NetworkSpec {
    let center = t
        .opt_vec23(cx, F::Network::center, Dim::Length, 0.0)
        .unwrap_or(DVec3::ZERO);
    let width = t.f64(cx, F::Network::width, Dim::Length, 10.0);
    let length = t.f64(cx, F::Network::length, Dim::Length, 10.0);
    check::positive(cx, t, F::Network::width, width, "m");
    check::positive(cx, t, F::Network::length, length, "m");
    let heading = t.f64(cx, F::Network::heading, Dim::Angle, 0.0);
    let altitude = altitude(cx, t, ctx, "lawnmower");
    let (overlap, sidelap) = laps(cx, t, spans);
    let strips = t.opt_u32(cx, F::Network::strips);
    if strips == Some(0) {
        let sp = t.span_of(F::Network::strips);
        cx.push(
            Diagnostic::error("E0313", "a lawnmower needs at least one strip")
                .label(sp, "0 strips")
                .help("remove `strips` to derive it from the side-lap"),
        );
    }
    let cross_strips = t.bool(cx, F::Network::cross_strips, false);
    let tilt = t.f64(cx, F::Network::tilt, Dim::Angle, 0.0);
    let obliques = t.f64(cx, F::Network::obliques, Dim::Angle, 0.0);
    if obliques.abs() >= std::f64::consts::FRAC_PI_2 {
        let sp = t.span_of(F::Network::obliques);
        cx.push(
            Diagnostic::error("E0314", "oblique tilt must be below 90°")
                .label(sp, format!("{:.1}°", obliques.to_degrees()))
                .help("obliques are usually tilted 20–45° forward from nadir"),
        );
    }
    let trigger = trigger(cx, t);
    NetworkSpec::Lawnmower {
        center,
        width,
        length,
        heading,
        altitude,
        overlap,
        sidelap,
        strips,
        cross_strips,
        tilt,
        obliques,
        trigger,
    }
}

/// `type = "spiral"`: a spiral out to `radius` around `center`.
fn spiral(cx: &mut Cx, t: &mut Tab, ctx: &NetworkContext, spans: &mut Spans) -> NetworkSpec {
    let center = t
        .opt_vec23(cx, F::Network::center, Dim::Length, 0.0)
        .unwrap_or(DVec3::ZERO);
    let radius = t.f64(cx, F::Network::radius, Dim::Length, 5.0);
    check::positive(cx, t, F::Network::radius, radius, "m");
    let altitude = altitude(cx, t, ctx, "spiral");
    let (overlap, sidelap) = laps(cx, t, spans);
    let trigger = trigger(cx, t);
    NetworkSpec::Spiral {
        center,
        radius,
        altitude,
        overlap,
        sidelap,
        trigger,
    }
}

/// `type = "orbit"`: rings of `per_ring` images at each of the `elevations`, looking at
/// `center` (on the seabed unless given) from `radius`.
fn orbit(cx: &mut Cx, t: &mut Tab, site: &Site) -> NetworkSpec {
    let center = t
        .opt_vec23(cx, F::Network::center, Dim::Length, -site.depth)
        .unwrap_or(DVec3::new(0.0, 0.0, -site.depth));
    let radius = t.f64(cx, F::Network::radius, Dim::Length, 2.0);
    check::positive(cx, t, F::Network::radius, radius, "m");
    let elevations = t
        .opt_list(cx, F::Network::elevations, Dim::Angle)
        .unwrap_or(vec![20f64.to_radians(), 45f64.to_radians()]);
    if elevations.is_empty() {
        let sp = t.span_of(F::Network::elevations);
        cx.push(
            Diagnostic::error("E0314", "an orbit needs at least one ring")
                .label(sp, "empty list")
                .help("e.g. `elevations = \"20, 45 deg\"`"),
        );
    }
    if let Some(e) = elevations
        .iter()
        .find(|e| e.abs() >= std::f64::consts::FRAC_PI_2)
    {
        let sp = t.span_of(F::Network::elevations);
        cx.push(
            Diagnostic::error("E0314", "orbit elevations must be between -90 and 90 degrees")
                .label(sp, format!("{:.1}° is out of range", e.to_degrees()))
                .help("elevations are angles above the horizontal plane through `center`, e.g. \"20, 45 deg\""),
        );
    }
    let per_ring = t.u32(cx, F::Network::per_ring, 24);
    let per_ring = check::capped(
        cx,
        t,
        F::Network::per_ring,
        per_ring,
        100_000,
        "images per ring",
        1,
    );
    check::at_least(cx, t, F::Network::per_ring, per_ring, 1);
    NetworkSpec::Orbit {
        center,
        radius,
        elevations,
        per_ring,
    }
}

/// `type = "explicit"`: the `[[network.poses]]` as written (at least one).
fn explicit(cx: &mut Cx, t: &mut Tab) -> NetworkSpec {
    let entries = t.tables(cx, F::Network::poses);
    let mut poses = Vec::new();
    for (i, n) in entries.into_iter().enumerate() {
        poses.push(explicit_pose(cx, i, n));
    }
    if poses.is_empty() {
        let sp = t.span;
        cx.push(
            Diagnostic::error("E0318", "the network has no poses")
                .label(sp, "an explicit network with no [[network.poses]]")
                .help("add `[[network.poses]]` tables with `position` and `look_at`"),
        );
    }
    NetworkSpec::Explicit { poses }
}

/// One `[[network.poses]]` entry: a `position` and either `look_at` (with `up`) or `rotation`;
/// with neither, the camera looks straight down.
fn explicit_pose(cx: &mut Cx, i: usize, n: &Node) -> ExplicitPose {
    let mut p = Tab::open(cx, Some(n), &format!("network.poses[{i}]"), n.span);
    let position = p.opt_vec3(cx, F::PoseTable::position, Dim::Length);
    if position.is_none() && !p.has(F::PoseTable::position) {
        cx.push(
            Diagnostic::error("E0315", "a pose needs a `position`")
                .label(p.span, "no position")
                .help("write `position = [x, y, z]` (metres, world frame, z up)"),
        );
    }
    let look = p.opt_vec3(cx, F::PoseTable::look_at, Dim::Length);
    let up = p.vec3(cx, F::PoseTable::up, Dim::Number, DVec3::Z);
    let rot = p.opt_vec3(cx, F::PoseTable::rotation, Dim::Angle);
    let orientation = match (look, rot) {
        (Some(target), None) => Orientation::LookAt { target, up },
        (None, Some(r)) => Orientation::Rotation { rotation: euler(r) },
        (Some(target), Some(_)) => {
            let sp = p.key_span(F::PoseTable::rotation);
            cx.push(
                Diagnostic::error("E0316", "give either `look_at` or `rotation`, not both")
                    .label(sp, "remove this or `look_at`")
                    .help("`look_at` points the optical axis at a world point"),
            );
            Orientation::LookAt { target, up }
        }
        (None, None) => Orientation::LookAt {
            target: position.unwrap_or(DVec3::ZERO) - DVec3::Z,
            up: DVec3::Y,
        },
    };
    let parsed = position.is_some();
    let position = position.unwrap_or(DVec3::ZERO);
    if let Orientation::LookAt { target, up } = &orientation
        && parsed
        && network::look_rotation(*target - position, *up).is_none()
    {
        let sp = p.span_of(F::PoseTable::look_at);
        cx.push(
            Diagnostic::error("E0317", "this pose has no viewing direction")
                .label(
                    sp,
                    "the look-at point equals the position, or `up` is parallel to the view",
                )
                .help("look at a different point, or give another `up` vector"),
        );
    }
    p.finish(cx);
    ExplicitPose {
        position,
        orientation,
    }
}

/// `trigger`: when a picture is taken — `"overlap"` (the default: spaced for the overlap),
/// every given distance (`"0.5 m"`), or every given time (`"2 s"`).
fn trigger(cx: &mut Cx, t: &mut Tab) -> Trigger {
    let sp = t.span_of(F::Network::trigger);
    let Some(n) = t.get(F::Network::trigger) else {
        return Trigger::Overlap;
    };
    let bad = |cx: &mut Cx| {
        cx.push(
            Diagnostic::error("E0300", "invalid trigger")
                .label(sp, "expected \"overlap\", a distance or a time")
                .help("write `trigger = \"overlap\"`, `trigger = \"0.5 m\"` (every 0.5 m) or `trigger = \"2 s\"`"),
        );
        Trigger::Overlap
    };
    match &n.val {
        Val::Str(s) if s == "overlap" => Trigger::Overlap,
        Val::Str(s) => {
            let r = if let Ok(d) = crate::units::parse_quantity(s, Dim::Length) {
                if s.trim().ends_with('m') {
                    Some(Trigger::Distance(d))
                } else {
                    None
                }
            } else if let Ok(t) = crate::units::parse_quantity(s, Dim::Time) {
                Some(Trigger::Time(t))
            } else {
                None
            };
            match r {
                Some(Trigger::Distance(v)) | Some(Trigger::Time(v)) if !(v > 0.0) => bad(cx),
                Some(r) => r,
                None => bad(cx),
            }
        }
        _ => bad(cx),
    }
}
