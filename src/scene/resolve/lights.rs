//! The `[[lights]]` of a scene: spot lights and strobes, point lights, rectangular area lights
//! and ambient light, mounted on the rig (moving with the camera) or fixed in the world, with
//! power or intensity or radiance turned into the model's radiometric units.

use super::{Spans, orthonormal_frame};
use crate::model::*;
use crate::scene::check;
use crate::scene::diag::Diagnostic;
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::units::Dim;
use glam::DVec3;

/// Every `[[lights]]` entry; the spans of each go to `spans.lights`.
pub(super) fn lights(cx: &mut Cx, t: &mut Tab, spans: &mut Spans) -> Vec<Light> {
    let mut out = Vec::new();
    for (i, n) in t.tables(cx, F::Scene::lights).into_iter().enumerate() {
        let path = format!("lights[{i}]");
        let mut l = Tab::open(cx, Some(n), &path, n.span);
        let name = l
            .opt_str(cx, F::Light::name)
            .unwrap_or_else(|| format!("light{i}"));
        let ty = l
            .choice(
                cx,
                F::Light::kind,
                &["spot", "strobe", "point", "area", "ambient"],
            )
            .unwrap_or("spot");
        let default_mount = if ty == "area" || ty == "ambient" {
            Mount::World
        } else {
            Mount::Rig
        };
        let mount = match l.choice(cx, F::Light::mount, &["rig", "world"]) {
            Some("rig") => Mount::Rig,
            Some("world") => Mount::World,
            _ => default_mount,
        };
        let position = l.vec3(cx, F::Light::position, Dim::Length, DVec3::ZERO);
        let color = l.rgb(cx, F::Light::color, Dim::Number, [1.0; 3]);
        let forward = if mount == Mount::Rig {
            DVec3::Z
        } else {
            DVec3::NEG_Z
        };
        let kind = match ty {
            "spot" | "strobe" | "point" => spot(cx, &mut l, ty, position, color, forward),
            "area" => area(cx, &mut l, position, color, forward),
            _ => {
                let radiance = l.rgb(cx, F::Light::radiance, Dim::Radiance, [0.1; 3]);
                LightKind::Ambient {
                    radiance: [0, 1, 2].map(|c| radiance[c] * color[c]),
                }
            }
        };
        spans.lights.push((l.span, l.span_of(F::Light::position)));
        l.finish_as(cx, Some(&format!("a {ty} light (`{path}`)")));
        out.push(Light { name, mount, kind });
    }
    out
}

/// The unit direction a light points in: `aim` (a direction) or `target` (a point), else
/// `forward` (the camera's view on the rig, straight down in the world).
fn direction(cx: &mut Cx, l: &mut Tab, position: DVec3, forward: DVec3) -> DVec3 {
    let aim = l.opt_vec3(cx, F::Light::aim, Dim::Number);
    let target = l.opt_vec3(cx, F::Light::target, Dim::Length);
    let d = match (aim, target) {
        (Some(a), _) => a,
        (None, Some(p)) => p - position,
        _ => forward,
    };
    match d.try_normalize() {
        Some(v) => v,
        None => {
            let sp = l.span_of(if l.has(F::Light::aim) {
                F::Light::aim
            } else {
                F::Light::target
            });
            cx.push(
                Diagnostic::error("E0260", "the light has no direction")
                    .label(
                        sp,
                        "zero direction (or the target is the light's own position)",
                    )
                    .help("give `aim = [x, y, z]` (a direction) or `target = [x, y, z]` (a point)"),
            );
            forward
        }
    }
}

/// A spot light or strobe (a cone of `beam_angle`), or a point light: intensity from `power`
/// (W, over 4π sr) or `intensity` (W/sr), times `color`.
fn spot(
    cx: &mut Cx,
    l: &mut Tab,
    ty: &str,
    position: DVec3,
    color: Rgb,
    forward: DVec3,
) -> LightKind {
    let dir = if ty == "point" {
        DVec3::Z
    } else {
        direction(cx, l, position, forward)
    };
    let intensity = match (
        l.opt_rgb(cx, F::Light::power, Dim::Power),
        l.opt_rgb(cx, F::Light::intensity, Dim::Intensity),
    ) {
        (Some(p), None) => p.map(|x| x / (4.0 * std::f64::consts::PI)),
        (None, Some(i)) => i,
        (Some(p), Some(_)) => {
            let sp = l.key_span(F::Light::intensity);
            cx.push(
                Diagnostic::error("E0261", "give either `power` or `intensity`, not both")
                    .label(sp, "remove this or `power`")
                    .help("intensity (W/sr) = power (W) / 4π"),
            );
            p.map(|x| x / (4.0 * std::f64::consts::PI))
        }
        (None, None) => [10.0 / (4.0 * std::f64::consts::PI); 3],
    };
    let key = if l.has(F::Light::intensity) {
        F::Light::intensity
    } else {
        F::Light::power
    };
    check::non_negative_rgb(cx, l, key, intensity, "");
    let intensity = [0, 1, 2].map(|c| intensity[c] * color[c]);
    if ty == "point" {
        LightKind::Point {
            position,
            intensity,
        }
    } else {
        let beam = l.f64(cx, F::Light::beam_angle, Dim::Angle, 100f64.to_radians());
        if !(beam > 0.0 && beam < std::f64::consts::PI) {
            let sp = l.span_of(F::Light::beam_angle);
            cx.push(
                Diagnostic::error("E0262", "the beam angle must be between 0 and 180 degrees")
                    .label(sp, format!("{:.1}°", beam.to_degrees()))
                    .help(
                        "`beam_angle` is the full cone angle, e.g. \"100 deg\" for a wide strobe",
                    ),
            );
        }
        LightKind::Spot {
            position,
            direction: dir,
            half_angle: beam / 2.0,
            intensity,
        }
    }
}

/// A rectangular area light of `width` × `height` facing its direction: radiance given, or
/// from `power` (W) over π × its area, times `color`.
fn area(cx: &mut Cx, l: &mut Tab, position: DVec3, color: Rgb, forward: DVec3) -> LightKind {
    let dir = direction(cx, l, position, forward);
    let width = l.f64(cx, F::Light::width, Dim::Length, 0.5);
    let height = l.f64(cx, F::Light::height, Dim::Length, 0.5);
    check::positive(cx, l, F::Light::width, width, "m");
    check::positive(cx, l, F::Light::height, height, "m");
    let radiance = match (
        l.opt_rgb(cx, F::Light::power, Dim::Power),
        l.opt_rgb(cx, F::Light::radiance, Dim::Radiance),
    ) {
        (Some(p), _) => p.map(|x| x / (std::f64::consts::PI * (width * height).max(1e-12))),
        (None, Some(r)) => r,
        (None, None) => [1.0; 3],
    };
    let radiance = [0, 1, 2].map(|c| radiance[c] * color[c]);
    LightKind::Area {
        frame: Pose {
            rotation: orthonormal_frame(dir),
            translation: position,
        },
        width,
        height,
        radiance,
    }
}
