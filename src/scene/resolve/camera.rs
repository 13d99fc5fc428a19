//! The camera side of a scene: `[camera]` (image size, pixel pitch, focal length, principal
//! point, lens projection, `distortion`, focus and aperture), the `[rig]` that repeats it
//! (single, stereo pair, or a list of `[[rig.cameras]]`), and each camera's housing
//! `[camera.port]` — flat (one glass or up to four `layers`, tilt), dome or cylinder — with its
//! glass from the catalogue of [`crate::optics::glass`] or a custom index. The ports' optics
//! (refraction, projection) live in [`crate::optics::port`]; here the keys are read and
//! checked, with the spans kept in [`CameraSpans`] for the whole-scene checks.

use super::{CameraSpans, Spans, euler};
use crate::model::*;
use crate::optics;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span, num};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Node, Val, merge};
use crate::units::Dim;
use glam::{DMat3, DVec3};

/// The cameras of `[camera]` and `[rig]`: one, a stereo pair, or every `[[rig.cameras]]`
/// entry merged over `[camera]`; their names must be unique.
pub(super) fn cameras(
    cx: &mut Cx,
    t: &mut Tab,
    water: bool,
    spans: &mut Spans,
    fallback: Span,
) -> Vec<Camera> {
    let cam_node = t.get(F::Scene::camera);
    let mut rig = Tab::open(cx, t.get(F::Scene::rig), F::Scene::rig, fallback);
    let kind = rig
        .choice(cx, F::Rig::kind, &["single", "stereo", "multi"])
        .unwrap_or("single");
    let base = cam_node.cloned().unwrap_or(Node {
        val: Val::Table(Default::default()),
        span: fallback,
    });
    let mut out = Vec::new();
    match kind {
        "stereo" => {
            let b = rig.f64(cx, F::Rig::baseline, Dim::Length, 0.3);
            spans.baseline = Some(rig.span_of(F::Rig::baseline));
            check::positive(cx, &rig, F::Rig::baseline, b, "m");
            let conv = rig.f64(cx, F::Rig::convergence, Dim::Angle, 0.0);
            for (name, sx) in [("left", -1.0), ("right", 1.0)] {
                let pose = Pose {
                    rotation: DMat3::from_rotation_y(-sx * conv / 2.0),
                    translation: DVec3::new(sx * b / 2.0, 0.0, 0.0),
                };
                if let Some(c) = camera(cx, &base, F::Scene::camera, water, name, pose, spans) {
                    out.push(c);
                }
            }
        }
        "multi" => {
            let entries = rig.tables(cx, F::Rig::cameras);
            if entries.is_empty() {
                let sp = rig.span;
                cx.push(
                    Diagnostic::error("E0230", "a multi-camera rig needs cameras")
                        .label(sp, "no [[rig.cameras]] entries")
                        .help(
                            "add `[[rig.cameras]]` tables with `name`, `position` and `rotation`",
                        ),
                );
            }
            for (i, e) in entries.into_iter().enumerate() {
                let mut merged = base.clone();
                merge(&mut merged, e.clone());
                if let Some(c) = camera(
                    cx,
                    &merged,
                    &format!("rig.cameras[{i}]"),
                    water,
                    &format!("cam{i}"),
                    Pose::IDENTITY,
                    spans,
                ) {
                    out.push(c);
                }
            }
        }
        _ => {
            if let Some(c) = camera(
                cx,
                &base,
                F::Scene::camera,
                water,
                DEFAULT_CAMERA_NAME,
                Pose::IDENTITY,
                spans,
            ) {
                out.push(c);
            }
        }
    }
    rig.finish(cx);
    // Unique names.
    for i in 0..out.len() {
        for j in 0..i {
            if out[i].name == out[j].name {
                let sp = spans.camera[i].port;
                cx.push(
                    Diagnostic::error("E0231", format!("two cameras are named `{}`", out[i].name))
                        .label(sp, "second camera with this name")
                        .help("give every camera of the rig its own `name`"),
                );
            }
        }
    }
    out
}

/// One camera: `node` is `[camera]`, or a `[[rig.cameras]]` entry merged over it; `rig_pose`
/// places it in the rig unless it gives its own `position` or `rotation`.
fn camera(
    cx: &mut Cx,
    node: &Node,
    path: &str,
    water: bool,
    default_name: &str,
    rig_pose: Pose,
    spans: &mut Spans,
) -> Option<Camera> {
    let mut c = Tab::open(cx, Some(node), path, node.span);
    let name = c
        .opt_str(cx, F::Camera::name)
        .unwrap_or_else(|| default_name.to_string());
    if !crate::model::is_safe_file_name(&name) {
        // Camera names become file names (`{camera}_{pose}.exr` in a rig); they are checked
        // here, once for every backend.
        let sp = if c.has(F::Camera::name) {
            c.span_of(F::Camera::name)
        } else {
            node.span
        };
        cx.push(
            Diagnostic::error(
                "E0234",
                format!(
                    "camera name `{}` cannot be part of a file name",
                    name.escape_debug()
                ),
            )
            .label(sp, "images are named after the camera")
            .help("use letters, digits, `_`, `-` and `.` only (not first), at most 100 characters"),
        );
    }
    let position = c.opt_vec3(cx, F::Camera::position, Dim::Length);
    let rotation = c.opt_vec3(cx, F::Camera::rotation, Dim::Angle);
    let rig_from_camera = match (position, rotation) {
        (None, None) => rig_pose,
        (p, r) => Pose {
            rotation: r.map(euler).unwrap_or(DMat3::IDENTITY),
            translation: p.unwrap_or(DVec3::ZERO),
        },
    };
    let width = c.u32(cx, F::Camera::width, 1600);
    let height = c.u32(cx, F::Camera::height, 1200);
    for (k, v) in [(F::Camera::width, width), (F::Camera::height, height)] {
        check::at_most(cx, &c, k, v as u64, 65_536, "pixels");
        if v == 0 {
            let sp = c.span_of(k);
            cx.push(
                Diagnostic::error("E0232", format!("the image {k} must be at least 1 pixel"))
                    .label(sp, "0 px")
                    .help("use the sensor's pixel count, e.g. `width = 1600`"),
            );
        }
    }
    let pitch = pixel_pitch(cx, &mut c, width);
    let fx = focal_px(cx, &mut c, pitch);
    let (cx_, cy_) = principal_point(cx, &mut c, width, height);
    let lens = lens(cx, &mut c);
    let distortion = distortion(cx, &mut c);
    let focus_distance = c.opt_f64(cx, F::Camera::focus_distance, Dim::Length);
    if let Some(f) = focus_distance {
        check::positive(cx, &c, F::Camera::focus_distance, f, "m");
    }
    let f_number = c.opt_f64(cx, F::Camera::f_number, Dim::Number);
    if let Some(f) = f_number {
        check::positive(cx, &c, F::Camera::f_number, f, "");
    }
    let port_node = c.get(F::Camera::port);
    let mut cs = CameraSpans {
        port: c.span_of(F::Camera::port),
        ..Default::default()
    };
    let port = port(
        cx,
        port_node,
        &c.full(F::Camera::port),
        water,
        c.span,
        &mut cs,
    );
    c.finish(cx);
    spans.camera.push(cs);
    Some(Camera {
        name,
        width,
        height,
        pixel_pitch: pitch,
        focal_length: fx * pitch,
        fx,
        fy: fx,
        cx: cx_,
        cy: cy_,
        lens,
        distortion,
        focus_distance,
        f_number,
        port,
        rig_from_camera,
    })
}

/// `pixel_pitch`, or `sensor_width` / `width` (metres; 3.76 µm when neither is given).
fn pixel_pitch(cx: &mut Cx, c: &mut Tab, width: u32) -> f64 {
    let pitch = match (
        c.opt_f64(cx, F::Camera::pixel_pitch, Dim::Length),
        c.opt_f64(cx, F::Camera::sensor_width, Dim::Length),
    ) {
        (Some(p), None) => p,
        (None, Some(sw)) => sw / width.max(1) as f64,
        (Some(p), Some(_)) => {
            let sp = c.key_span(F::Camera::sensor_width);
            cx.push(
                Diagnostic::error(
                    "E0233",
                    "give either `pixel_pitch` or `sensor_width`, not both",
                )
                .label(sp, "remove this or `pixel_pitch`")
                .help("the pixel pitch is sensor_width / width"),
            );
            p
        }
        (None, None) => 3.76e-6,
    };
    let pitch_key = if c.has(F::Camera::sensor_width) {
        F::Camera::sensor_width
    } else {
        F::Camera::pixel_pitch
    };
    check::positive(cx, c, pitch_key, pitch, "m");
    pitch
}

/// The focal length in pixels, from `focal_length` / pitch or `fx` (16 mm when neither is
/// given); 1 px when it is not positive, so that checking continues.
fn focal_px(cx: &mut Cx, c: &mut Tab, pitch: f64) -> f64 {
    let fx = match (
        c.opt_f64(cx, F::Camera::focal_length, Dim::Length),
        c.opt_f64(cx, F::Camera::fx, Dim::Number),
    ) {
        (Some(f), None) => f / pitch,
        (None, Some(fx)) => fx,
        (Some(f), Some(_)) => {
            let sp = c.key_span(F::Camera::fx);
            cx.push(
                Diagnostic::error("E0233", "give either `focal_length` or `fx`, not both")
                    .label(sp, "remove this or `focal_length`")
                    .help("fx (pixels) = focal_length / pixel_pitch"),
            );
            f / pitch
        }
        (None, None) => 0.016 / pitch,
    };
    let fkey = if c.has(F::Camera::fx) {
        F::Camera::fx
    } else {
        F::Camera::focal_length
    };
    check::positive(cx, c, fkey, fx, "");
    if fx.is_finite() && fx > 0.0 { fx } else { 1.0 }
}

/// `principal_point = [cx, cy]` in pixels (poser's convention: pixel centres at +0.5); the
/// image centre by default.
fn principal_point(cx: &mut Cx, c: &mut Tab, width: u32, height: u32) -> (f64, f64) {
    match c.opt_list(cx, F::Camera::principal_point, Dim::Number) {
        Some(v) if v.len() == 2 => (v[0], v[1]),
        Some(_) => {
            let sp = c.span_of(F::Camera::principal_point);
            cx.push(
                Diagnostic::error("E0044", "`principal_point` needs 2 values")
                    .label(sp, "expected [cx, cy] in pixels")
                    .help("the image centre is [width/2, height/2]"),
            );
            (width as f64 / 2.0, height as f64 / 2.0)
        }
        None => (width as f64 / 2.0, height as f64 / 2.0),
    }
}

/// `lens`: the projection of the lens (rectilinear by default, or a fisheye).
fn lens(cx: &mut Cx, c: &mut Tab) -> LensModel {
    match c.choice(
        cx,
        F::Camera::lens,
        &["rectilinear", "fisheye_equidistant", "fisheye_equisolid"],
    ) {
        Some("fisheye_equidistant") => LensModel::FisheyeEquidistant,
        Some("fisheye_equisolid") => LensModel::FisheyeEquisolid,
        _ => LensModel::Rectilinear,
    }
}

/// `[camera.distortion]`: the radial `k1`–`k3` and tangential `p1`, `p2` coefficients (all 0 by
/// default).
fn distortion(cx: &mut Cx, c: &mut Tab) -> Distortion {
    let n = c.get(F::Camera::distortion);
    let mut d = Tab::open(cx, n, &c.full(F::Camera::distortion), c.span);
    let r = Distortion {
        k1: d.f64(cx, F::DistortionTable::k1, Dim::Number, 0.0),
        k2: d.f64(cx, F::DistortionTable::k2, Dim::Number, 0.0),
        k3: d.f64(cx, F::DistortionTable::k3, Dim::Number, 0.0),
        p1: d.f64(cx, F::DistortionTable::p1, Dim::Number, 0.0),
        p2: d.f64(cx, F::DistortionTable::p2, Dim::Number, 0.0),
    };
    d.finish(cx);
    r
}

/// The glass of a port or layer: `material` from the catalogue (with common aliases) or a
/// custom `ior`, not both; N-BK7 after an error, so that checking continues.
fn glass(cx: &mut Cx, p: &mut Tab, default: &str, cs: &mut CameraSpans) -> Glass {
    cs.material = p.span_of(if p.has(F::PortTable::ior) {
        F::PortTable::ior
    } else {
        F::PortTable::material
    });
    if let Some(ior) = p.opt_rgb(cx, F::PortTable::ior, Dim::Number) {
        if p.has(F::PortTable::material) {
            let sp = p.key_span(F::PortTable::material);
            cx.push(
                Diagnostic::error(
                    "E0240",
                    "give either `material` or `ior` for the port, not both",
                )
                .label(sp, "remove this or `ior`")
                .help("`ior` defines a custom glass; `material` picks one from the catalogue"),
            );
        }
        p.get(F::PortTable::material);
        check::index(cx, p, F::PortTable::ior, ior);
        return Glass {
            name: "custom".into(),
            ior,
        };
    }
    let mspan = p.span_of(F::PortTable::material);
    let name = p
        .opt_str(cx, F::PortTable::material)
        .unwrap_or_else(|| default.to_string());
    match catalogue_glass(&name) {
        Some(g) => g,
        None => {
            let mut d = Diagnostic::error("E0241", format!("unknown port material `{name}`"))
                .label(
                    mspan,
                    format!("catalogue: {}", optics::glass::CATALOGUE.join(", ")),
                );
            d = match crate::scene::reader::did_you_mean(
                &name,
                optics::glass::CATALOGUE.iter().copied(),
            ) {
                Some(s) => d.help(format!("did you mean `{s}`?")),
                None => d.help("pick a catalogue material, or give a custom index: `ior = 1.52`"),
            };
            cx.push(d);
            Glass {
                name: "N-BK7".into(),
                ior: [1.5168; 3],
            }
        }
    }
}

/// The catalogue glass `name` (with the common aliases: acrylic, BK7, quartz, …) with its
/// index per channel; `None` when the catalogue does not have it.
pub(super) fn catalogue_glass(name: &str) -> Option<Glass> {
    let canonical = match name.to_lowercase().as_str() {
        "acrylic" | "pmma" => "PMMA".to_string(),
        "bk7" | "n-bk7" => "N-BK7".to_string(),
        "fused silica" | "fused_silica" | "quartz" => "fused_silica".to_string(),
        "sapphire" => "sapphire".to_string(),
        _ => name.to_string(),
    };
    match CHANNEL_WAVELENGTHS_NM.map(|l| optics::glass::catalogue_ior(&canonical, l)) {
        [Some(r), Some(g), Some(b)] => Some(Glass {
            name: canonical,
            ior: [r, g, b],
        }),
        _ => None,
    }
}

/// `layers = [{ thickness, material | ior }, …]` of a flat port: the first layer, and the
/// ones outward of it. The port's own `thickness`, `material` and `ior` must then be absent.
fn flat_layers(
    cx: &mut Cx,
    p: &mut Tab,
    path: &str,
    cs: &mut CameraSpans,
) -> (f64, Glass, Vec<GlassLayer>) {
    let lspan = p.span_of(F::PortTable::layers);
    for key in [
        F::PortTable::thickness,
        F::PortTable::material,
        F::PortTable::ior,
    ] {
        if p.has(key) {
            let sp = p.key_span(key);
            cx.push(
                Diagnostic::error(
                    "E0242",
                    format!("`{path}.{key}` and `{path}.layers` both given"),
                )
                .label(sp, "remove this")
                .help(
                    "with `layers`, each layer gives its own `thickness` and `material` or `ior`",
                ),
            );
        }
    }
    // Mark the port-level keys read (they were reported above when present).
    let _ = (
        p.get(F::PortTable::thickness),
        p.get(F::PortTable::material),
        p.get(F::PortTable::ior),
    );
    cs.thickness = lspan;
    cs.material = lspan;
    let nodes = p.tables(cx, F::PortTable::layers);
    let max = crate::optics::port::MAX_LAYERS;
    if nodes.is_empty() || nodes.len() > max {
        cx.push(
            Diagnostic::error(
                "E0243",
                format!("a flat port has 1 to {max} glass layers, not {}", nodes.len()),
            )
            .label(lspan, "here")
            .help("e.g. `layers = [{ thickness = \"6 mm\", material = \"N-BK7\" }, { thickness = \"2 mm\", material = \"sapphire\" }]`"),
        );
    }
    let mut layers = Vec::new();
    for (i, n) in nodes.into_iter().take(max).enumerate() {
        let lpath = format!("{path}.layers[{i}]");
        let mut t = Tab::open(cx, Some(n), &lpath, lspan);
        let thickness = match t.opt_f64(cx, F::PortLayer::thickness, Dim::Length) {
            Some(v) => {
                check::positive(cx, &t, F::PortLayer::thickness, v, "m");
                v
            }
            None => {
                cx.push(
                    Diagnostic::error("E0243", format!("`{lpath}.thickness` is required"))
                        .label(n.span, "this layer has no thickness")
                        .help("write e.g. `thickness = \"6 mm\"`"),
                );
                0.01
            }
        };
        let mut spans = CameraSpans::default();
        let g = glass(cx, &mut t, "N-BK7", &mut spans);
        t.finish(cx);
        layers.push(GlassLayer {
            thickness,
            glass: g,
        });
    }
    if layers.is_empty() {
        layers.push(GlassLayer {
            thickness: 0.01,
            glass: Glass {
                name: "N-BK7".into(),
                ior: [1.5168; 3],
            },
        });
    }
    let first = layers.remove(0);
    (first.thickness, first.glass, layers)
}

/// `[camera.port]`: none, flat, dome or cylinder (flat by default in water, none in air).
fn port(
    cx: &mut Cx,
    node: Option<&Node>,
    path: &str,
    water: bool,
    fallback: Span,
    cs: &mut CameraSpans,
) -> Port {
    let mut p = Tab::open(cx, node, path, fallback);
    let kind = p
        .choice(
            cx,
            F::PortTable::kind,
            &["none", "flat", "dome", "cylinder"],
        )
        .unwrap_or(if water { "flat" } else { "none" });
    cs.thickness = p.span_of(F::PortTable::thickness);
    let port = match kind {
        "none" => Port::None,
        "flat" => flat_port(cx, &mut p, path, cs),
        "dome" => dome_port(cx, &mut p, cs),
        _ => cylinder_port(cx, &mut p, cs),
    };
    p.finish_as(cx, Some(&format!("a {kind} port (`{path}`)")));
    port
}

/// A flat port: the glass (one plate, or `layers`) at `pupil_distance` in front of the
/// entrance pupil, its normal tilted by `tilt` towards `tilt_direction`.
fn flat_port(cx: &mut Cx, p: &mut Tab, path: &str, cs: &mut CameraSpans) -> Port {
    let distance = p.f64(cx, F::PortTable::pupil_distance, Dim::Length, 0.01);
    cs.distance = p.span_of(F::PortTable::pupil_distance);
    let tilt = p.f64(cx, F::PortTable::tilt, Dim::Angle, 0.0);
    let tilt_dir = p.f64(cx, F::PortTable::tilt_direction, Dim::Angle, 0.0);
    let (thickness, glass, outer_layers) = if p.has(F::PortTable::layers) {
        flat_layers(cx, p, path, cs)
    } else {
        let thickness = p.f64(cx, F::PortTable::thickness, Dim::Length, 0.01);
        let glass = glass(cx, p, "N-BK7", cs);
        check::positive(cx, p, F::PortTable::thickness, thickness, "m");
        (thickness, glass, vec![])
    };
    if !(distance > 0.0) {
        let sp = p.span_of(F::PortTable::pupil_distance);
        cx.push(
            Diagnostic::error("E0250", "the entrance pupil is outside the housing")
                .label(sp, format!("pupil_distance = {} m puts the pupil at or beyond the port", num(distance)))
                .help("`pupil_distance` is from the entrance pupil forward to the inner face of the glass; it must be > 0"),
        );
    }
    if tilt.abs() >= std::f64::consts::FRAC_PI_2 * 0.9 {
        let sp = p.span_of(F::PortTable::tilt);
        cx.push(
            Diagnostic::error("E0251", "the port is tilted too far")
                .label(sp, format!("{:.1}°", tilt.to_degrees()))
                .help("a port tilt is a small misalignment, a few degrees at most"),
        );
    }
    // Normal: +z tilted by `tilt` about the in-plane axis at `tilt_direction` from +x.
    let axis = DVec3::new(tilt_dir.cos(), tilt_dir.sin(), 0.0);
    let normal = glam::DQuat::from_axis_angle(axis, tilt) * DVec3::Z;
    Port::Flat {
        normal,
        distance,
        thickness,
        glass,
        outer_layers,
    }
}

/// A dome port: a spherical shell of `inner_radius` and `thickness` centred at `decentering`
/// from the entrance pupil.
fn dome_port(cx: &mut Cx, p: &mut Tab, cs: &mut CameraSpans) -> Port {
    let inner_radius = p.f64(cx, F::PortTable::inner_radius, Dim::Length, 0.05);
    let thickness = p.f64(cx, F::PortTable::thickness, Dim::Length, 0.005);
    let center = p.vec3(cx, F::PortTable::decentering, Dim::Length, DVec3::ZERO);
    cs.center = p.span_of(F::PortTable::decentering);
    cs.distance = cs.center;
    let glass = glass(cx, p, "PMMA", cs);
    check::positive(cx, p, F::PortTable::inner_radius, inner_radius, "m");
    check::positive(cx, p, F::PortTable::thickness, thickness, "m");
    if inner_radius > 0.0 && center.length() >= inner_radius {
        let sp = p.span_of(F::PortTable::decentering);
        cx.push(
            Diagnostic::error("E0250", "the entrance pupil is outside the dome")
                .label(sp, format!("|decentering| = {:.4} m ≥ inner radius {:.4} m", center.length(), inner_radius))
                .help("`decentering` is the dome centre relative to the entrance pupil; keep it well inside the inner radius (ideally 0)"),
        );
    }
    // The model's `center` is the dome centre in the camera frame, which is the
    // `decentering` vector itself (the entrance pupil is the camera frame's origin).
    Port::Dome {
        center,
        inner_radius,
        thickness,
        glass,
    }
}

/// A cylindrical port: a shell of `inner_radius` and `thickness` around the line through
/// `offset` along `axis` (both relative to the entrance pupil).
fn cylinder_port(cx: &mut Cx, p: &mut Tab, cs: &mut CameraSpans) -> Port {
    let inner_radius = p.f64(cx, F::PortTable::inner_radius, Dim::Length, 0.05);
    let thickness = p.f64(cx, F::PortTable::thickness, Dim::Length, 0.005);
    let axis = p.vec3(cx, F::PortTable::axis, Dim::Number, DVec3::Y);
    let axis_point = p.vec3(cx, F::PortTable::offset, Dim::Length, DVec3::ZERO);
    cs.center = p.span_of(F::PortTable::offset);
    cs.distance = cs.center;
    let glass = glass(cx, p, "PMMA", cs);
    check::positive(cx, p, F::PortTable::inner_radius, inner_radius, "m");
    check::positive(cx, p, F::PortTable::thickness, thickness, "m");
    let axis_n = axis.try_normalize();
    if axis_n.is_none() {
        let sp = p.span_of(F::PortTable::axis);
        cx.push(
            Diagnostic::error("E0252", "the cylinder axis must not be zero")
                .label(sp, "zero vector")
                .help("e.g. `axis = [0, 1, 0]` (vertical in the image)"),
        );
    }
    let axis = axis_n.unwrap_or(DVec3::Y);
    let off = axis_point - axis * axis_point.dot(axis);
    if inner_radius > 0.0 && off.length() >= inner_radius {
        let sp = p.span_of(F::PortTable::offset);
        cx.push(
            Diagnostic::error("E0250", "the entrance pupil is outside the cylindrical port")
                .label(sp, format!("the pupil is {:.4} m from the axis, the inner radius is {:.4} m", off.length(), inner_radius))
                .help("`offset` is a point of the cylinder axis relative to the entrance pupil; keep it inside the inner radius"),
        );
    }
    Port::Cylinder {
        axis_point,
        axis,
        inner_radius,
        thickness,
        glass,
    }
}
