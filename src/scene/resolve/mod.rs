//! Resolution: the merged scene tree → [`Model`] in SI units, with presets applied, optical
//! constants computed (through [`crate::optics`]), networks expanded (through
//! [`crate::plan::network::expand`]) and [`Needs`] decided. Every table's keys, units and
//! defaults are documented in [`super::format`] (the source of the JSON Schema and of
//! `docs/format.md`); the checks here must stay in step with it.
//!
//! This file holds the entry point [`resolve`] (which reads the sections in dependency order:
//! the site before the water, the cameras before the network), the [`Spans`] kept for the
//! whole-scene checks of [`super::check`], [`needs`], and the small pose helpers the sections
//! share. Each scene section is read by one file:
//!
//! | file | scene section | resolves to |
//! |---|---|---|
//! | `mod.rs` | top level: `name`, `description`, `include` | [`Model`], [`Spans`], [`Needs`] |
//! | `environment.rs` | `[site]`, `[water]`, `[sun]` | [`Site`], [`Water`], [`Sun`] |
//! | `render.rs` | `[render]` | [`RenderSettings`] |
//! | `camera.rs` | `[camera]` (its `distortion` and `port`, flat-port `layers`), `[rig]` | [`Camera`]s with their [`Port`] |
//! | `lights.rs` | `[[lights]]` | [`Light`]s |
//! | `objects.rs` | `[[objects]]`: shapes, mesh files, materials and patterns | [`Object`]s |
//! | `coral.rs` | a `shape = "coral"` object's keys (for `objects.rs`) | [`Shape::Coral`] |
//! | `targets.rs` | `[[targets]]`, points files included | [`Target`]s |
//! | `network.rs` | `[network]`, its `trigger` and `[[network.poses]]` | [`RigPose`]s, [`NetworkSummary`] |
//! | `diver.rs` | `[diver]`, `[[diver.cylinders]]` | [`Diver`] |
//! | `sensor.rs` | `[sensor]` | [`Sensor`] |
//! | `lesson.rs` | `[lesson]`, `[[lesson.variants]]`, `[[lesson.try_next]]` | [`Lesson`] |

mod camera;
mod coral;
mod diver;
mod environment;
mod georef;
mod lesson;
mod lights;
mod network;
mod objects;
mod render;
mod sensor;
mod targets;

pub use diver::parse_gas;

use super::diag::{Diagnostic, Span};
use super::reader::{Cx, Tab};
use super::source::{Node, Sources};
use crate::model::*;
use crate::optics;
use crate::scene::format::types as F;
use crate::units::Dim;
use glam::{DMat3, DVec3, EulerRot};
use std::path::Path;

/// Spans of things later checks need to point at.
#[derive(Default)]
pub struct Spans {
    pub camera: Vec<CameraSpans>,
    pub targets: Vec<Span>,
    pub objects: Vec<Span>,
    pub lights: Vec<(Span, Span)>,
    pub network: Span,
    pub sidelap: Option<Span>,
    /// `overlap` / `sidelap` as written in the scene (absent when defaulted).
    pub overlap_asked: Option<Span>,
    pub sidelap_asked: Option<Span>,
    pub water: Span,
    /// The stereo baseline, when given.
    pub baseline: Option<Span>,
}

/// Spans of one camera's port keys, for the checks that point at them.
#[derive(Default, Clone)]
pub struct CameraSpans {
    pub port: Span,
    pub thickness: Span,
    pub distance: Span,
    pub center: Span,
    pub material: Span,
}

/// Read the whole scene into a [`Model`]; every problem found goes to `cx`.
pub fn resolve(root: &Node, scene_path: &Path, sources: &Sources, cx: &mut Cx) -> (Model, Spans) {
    let top = Span {
        file: 0,
        start: 0,
        end: 0,
    };
    let mut t = Tab::open(cx, Some(root), "", top);
    let mut spans = Spans::default();
    let name = t.opt_str(cx, F::Scene::name).unwrap_or_else(|| {
        scene_path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default()
    });
    let description = t.opt_str(cx, F::Scene::description).unwrap_or_default();
    t.get(F::Scene::include); // handled by the loader; known here

    // Site first: the water's pressure depth and seabed defaults depend on it.
    let water_present = t.has(F::Scene::water);
    let site = environment::site(cx, &mut t, water_present);
    let water = if water_present {
        let node = t.get(F::Scene::water);
        spans.water = t.span_of(F::Scene::water);
        environment::water(cx, node, &site, top)
    } else {
        t.get(F::Scene::water);
        None
    };
    let ior = water.as_ref().map(|w| w.ior).unwrap_or([1.0; 3]);
    let sun = environment::sun(cx, t.get(F::Scene::sun), water.as_ref(), &site, top);
    let mut render_at = render::RenderSpans::default();
    let render = render::render(cx, t.get(F::Scene::render), top, &mut render_at);
    let cameras = camera::cameras(cx, &mut t, water.is_some(), &mut spans, top);
    let f_number = cameras.first().and_then(|c| c.f_number);
    let sensor = sensor::sensor(cx, t.get(F::Scene::sensor), f_number, top);
    let lights = lights::lights(cx, &mut t, &mut spans);
    let objects = objects::objects(cx, &mut t, &site, sources, scene_path, &mut spans);
    let targets = targets::targets(cx, &mut t, &mut spans, &objects, &site, sources, scene_path);
    let diver = diver::diver(cx, t.get(F::Scene::diver), top);
    let lesson = lesson::lesson(
        cx,
        t.get(F::Scene::lesson),
        sources,
        &name,
        &description,
        top,
    );
    let speed_default = diver.as_ref().map(|d| d.speed).unwrap_or(0.2);
    let (poses, summary) = network::network(
        cx,
        t.get(F::Scene::network),
        &cameras,
        ior,
        &site,
        speed_default,
        &mut spans,
        top,
    );
    t.finish(cx);

    let mut model = Model {
        name,
        description,
        source: sources
            .files
            .first()
            .map(|f| f.0.clone())
            .unwrap_or_default(),
        water,
        site,
        sun,
        cameras,
        lights,
        objects,
        targets,
        poses,
        network: summary,
        diver,
        render,
        sensor,
        needs: Needs::default(),
        lesson,
    };
    model.needs = needs(&model);
    if model.render.daylight == Daylight::Column
        && let (Some(span), Err(why)) = (render_at.daylight, model.column_input())
    {
        cx.push(
            Diagnostic::error("E0238", "the water column cannot light this scene")
                .label(span, why)
                .help("use `daylight = \"traced\"` (or `\"auto\"`, which falls back to it)"),
        );
    }
    if !cx.has_errors() {
        match render_at.bounces {
            Some(at) => {
                bounce_limit(cx, &model, at);
                filled_bounce_limit(cx, &model, at);
            }
            None => {
                default_bounces(cx, &mut model, spans.water);
                if scattering_fill(&model).is_some() {
                    model.render.max_bounces = model.render.max_bounces.max(FILLED_BOUNCES);
                }
            }
        }
    }
    (model, spans)
}

/// The bounce limit a scene with a scattering filled object gets when `render.bounces` is not
/// written: every scattering inside the object and every face a path crosses or reflects
/// from counts, and the light that reflects totally inside it meets many. Measured on a
/// 1.2 m sphere of water (σs 1.5/m, HG g 0.8) under a sky, the centre's light against 256
/// bounces: 8 cut off 5 / 10 / 11 % (R / G / B), 16 2.5 %, 32 0.5 %, 64 0.01 %
/// (tests/filled_objects.rs). Russian roulette ends the paths that carry little.
pub const FILLED_BOUNCES: u32 = 64;

/// The first filled object whose water scatters, if any.
fn scattering_fill(model: &Model) -> Option<&crate::model::Object> {
    model.objects.iter().find(|o| {
        o.material
            .fill
            .as_ref()
            .is_some_and(|w| w.scattering.iter().any(|&s| s > 0.0))
    })
}

/// W0241: `render.bounces` written below [`FILLED_BOUNCES`] in a scene with a scattering
/// filled object, whose light it may cut off.
fn filled_bounce_limit(cx: &mut Cx, model: &Model, at: Span) {
    let b = model.render.max_bounces;
    let Some(o) = scattering_fill(model) else {
        return;
    };
    if b >= FILLED_BOUNCES {
        return;
    }
    cx.push(
        Diagnostic::warning(
            "W0241",
            format!("render.bounces = {b} may cut off the light scattered inside filled object `{}`", o.name),
        )
        .label(at, format!("paths end after {b} bounces"))
        .note(
            "every scattering in its water and every face a path crosses or reflects from \
             counts as a bounce; on a 1.2 m sphere of scattering water under a sky, 8 bounces \
             cut off 5 / 10 / 11 % of the light (R / G / B), 16 bounces 2.5 %, 32 bounces 0.5 % \
             (docs/scenes.md, \"Filled objects\")",
        )
        .help(format!("raise `render.bounces` to {FILLED_BOUNCES}, or leave it out (the default then is {FILLED_BOUNCES})")),
    );
}

/// `render.bounces` not written: [`DEFAULT_BOUNCES`], raised where traced daylight through the
/// scene's water column has scattered more often, to what cuts off at most
/// [`crate::model::BOUNCE_CUT_WARN`] of the light the cameras see ([`Model::bounce_cut`]; at
/// most [`MAX_DEFAULT_BOUNCES`], beyond which W0239 says what is still cut off).
fn default_bounces(cx: &mut Cx, model: &mut Model, water: Span) {
    // Under "auto" the renderer may still trace (views past the seabed, which only the
    // renderer's geometry can tell): the limit is set for that case too.
    if model.render.daylight == Daylight::Column && model.daylight_choice(None).0.is_some() {
        return;
    }
    let Some(cut) = model.bounce_cut() else {
        return;
    };
    let need = cut
        .needed
        .unwrap_or(MAX_DEFAULT_BOUNCES)
        .min(MAX_DEFAULT_BOUNCES);
    if need > model.render.max_bounces {
        model.render.max_bounces = need;
        if cut.needed.is_none() {
            bounce_limit(cx, model, water);
        }
    }
}

/// `render.bounces` when the scene does not say (and its water column needs no more).
pub const DEFAULT_BOUNCES: u32 = 8;
/// The largest bounce limit the default rises to.
pub const MAX_DEFAULT_BOUNCES: u32 = 254;

/// W0239: traced daylight whose bounce limit cuts off more than
/// [`crate::model::BOUNCE_CUT_WARN`] of the light the cameras see, in a channel that is not
/// black at the seabed. The share is measured on the scene's own water column by a quick
/// solve ([`Model::bounce_cut`]); scenes whose daylight comes from the column lose nothing to
/// the limit, and scenes that are not a column (a water box, no scattering) get no estimate.
fn bounce_limit(cx: &mut Cx, model: &Model, at: Span) {
    if model.daylight_choice(None).0.is_some() {
        return;
    }
    let Some(cut) = model.bounce_cut() else {
        return;
    };
    if cut.worst() <= crate::model::BOUNCE_CUT_WARN {
        return;
    }
    let b = cut.bounces;
    cx.push(
        Diagnostic::warning(
            "W0239",
            format!(
                "render.bounces = {b} cuts off {} of the daylight the cameras see (R / G / B)",
                cut.shares_text()
            ),
        )
        .label(at, format!("paths end after {b} scatterings"))
        .note(
            "light scattered many times in the water is lost, not approximated: the images \
             render darker than they are (measured on the scene's water column, \
             docs/column.md)",
        )
        .help(format!(
            "raise `render.bounces` to {} (cuts off ≤ {:.0} %), or set \
             `render.daylight = \"column\"` (the column holds every order)",
            cut.needed_text(),
            crate::model::BOUNCE_CUT_WARN * 100.0
        )),
    );
}

// ------------------------------------------------------------------------------------------
// Pose helpers shared by the sections
// ------------------------------------------------------------------------------------------

/// The rotation of Euler angles `[x, y, z]` (radians), applied about x, then y, then z.
fn euler(v: DVec3) -> DMat3 {
    DMat3::from_euler(EulerRot::ZYX, v.z, v.y, v.x)
}

/// A right-handed frame whose +z is `z` (−z when `z` is zero); x and y are arbitrary but fixed.
fn orthonormal_frame(z: DVec3) -> DMat3 {
    let z = z.try_normalize().unwrap_or(DVec3::NEG_Z);
    let helper = if z.z.abs() < 0.9 { DVec3::Z } else { DVec3::Y };
    let x = helper.cross(z).normalize();
    let y = z.cross(x);
    DMat3::from_cols(x, y, z)
}

/// `world_from_x` from `position` and `rotation` (Euler XYZ angles) or `look_at` (+z towards
/// a point).
fn placement(cx: &mut Cx, t: &mut Tab, default_pos: DVec3) -> Pose {
    let position = t.vec3(cx, F::Object::position, Dim::Length, default_pos);
    let rotation = t.opt_vec3(cx, F::Object::rotation, Dim::Angle);
    let look = t.opt_vec3(cx, F::Object::look_at, Dim::Length);
    let r = match (rotation, look) {
        (Some(r), None) => euler(r),
        (None, Some(p)) => match (p - position).try_normalize() {
            Some(z) => orthonormal_frame(z),
            None => {
                let sp = t.span_of(F::Object::look_at);
                cx.push(
                    Diagnostic::error("E0270", "`look_at` is the object's own position")
                        .label(sp, "no direction to face")
                        .help("look at a point other than `position`"),
                );
                DMat3::IDENTITY
            }
        },
        (Some(r), Some(_)) => {
            let sp = t.key_span(F::Object::look_at);
            cx.push(
                Diagnostic::error("E0271", "give either `rotation` or `look_at`, not both")
                    .label(sp, "remove this or `rotation`")
                    .help("`look_at` turns the +z axis (the printed face) towards a point"),
            );
            euler(r)
        }
        (None, None) => DMat3::IDENTITY,
    };
    Pose {
        rotation: r,
        translation: position,
    }
}

// ------------------------------------------------------------------------------------------

/// One line per filled object for [`needs`]: its water and its boundary.
fn filled_reasons(m: &Model, n: &mut Needs) {
    for o in &m.objects {
        let Some(w) = &o.material.fill else { continue };
        let (a, b) = (w.absorption, w.scattering);
        n.reasons.push(format!(
            "filled object `{}`: water inside, σa = [{:.4}, {:.4}, {:.4}], σs = [{:.4}, {:.4}, \
             {:.4}] 1/m (R, G, B), behind a smooth boundary of index {:.4} (green)",
            o.name, a[0], a[1], a[2], b[0], b[1], b[2], w.ior[1]
        ));
    }
}

/// Decide what the scene needs modelled, with reasons.
pub fn needs(m: &Model) -> Needs {
    let mut n = Needs::default();
    let ior = m.ambient_ior();
    let filled = m
        .objects
        .iter()
        .filter(|o| o.material.fill.is_some())
        .count();
    match &m.water {
        None if filled > 0 => n.reasons.push(format!(
            "no [water]: survey in air; water only inside the {filled} filled object(s)"
        )),
        None => n
            .reasons
            .push("no [water]: survey in air, no medium is emitted".into()),
        Some(w) => {
            let t = w.extinction();
            n.medium = t.iter().any(|x| *x > 0.0);
            if n.medium {
                n.reasons.push(format!(
                    "medium: σt = [{:.4}, {:.4}, {:.4}] 1/m (R, G, B){}",
                    t[0],
                    t[1],
                    t[2],
                    w.jerlov
                        .as_ref()
                        .map(|j| format!(" from Jerlov type {j}"))
                        .unwrap_or_default()
                ));
            } else {
                n.reasons.push("no medium: the water has zero absorption and scattering (clear water, index kept)".into());
            }
            if let WaterExtent::BoxAroundCamera { half_size } = w.extent {
                n.medium_box = n.medium;
                n.reasons.push(format!(
                    "medium box: water.extent = \"box\", half-size [{:.2}, {:.2}, {:.2}] m around each camera",
                    half_size.x, half_size.y, half_size.z
                ));
            }
        }
    }
    filled_reasons(m, &mut n);
    let ports: Vec<&str> = m
        .cameras
        .iter()
        .filter(|c| !matches!(c.port, Port::None))
        .map(|c| c.port.kind_name())
        .collect();
    n.refraction = !ports.is_empty();
    if n.refraction {
        n.reasons.push(format!(
            "refraction: {} port{} in front of the camera{}",
            ports.join(", "),
            if ports.len() > 1 { "s" } else { "" },
            if m.cameras.len() > 1 { "s" } else { "" }
        ));
    } else {
        n.reasons.push("no refraction: no housing port".into());
    }
    n.lateral_color_px = m
        .cameras
        .iter()
        .map(|c| optics::lateral_color_px(c, ior))
        .fold(0.0, f64::max);
    if !n.lateral_color_px.is_finite() {
        n.lateral_color_px = 0.0;
    }
    n.per_channel_passes = m.render.dispersion && n.lateral_color_px >= 0.1;
    n.reasons.push(if !m.render.dispersion {
        format!(
            "one render pass: dispersion is off (lateral colour would be {:.3} px)",
            n.lateral_color_px
        )
    } else if n.per_channel_passes {
        format!(
            "one pass per channel: dispersion is on and lateral colour is {:.3} px ≥ 0.1 px",
            n.lateral_color_px
        )
    } else {
        format!(
            "one render pass: dispersion is on but lateral colour is only {:.3} px < 0.1 px",
            n.lateral_color_px
        )
    });
    if let Some(_s) = &m.sun {
        if m.water.is_some() && !matches!(m.site.surface, SeaSurface::None) {
            n.sun_refraction = true;
            n.reasons
                .push("sun refraction: sunlight enters the water through the sea surface".into());
        }
        if m.water.is_some() && matches!(m.site.surface, SeaSurface::Waves { .. }) {
            n.caustics = true;
            n.reasons
                .push("caustics: the sun shines through a wavy surface".into());
        }
    }
    n
}
