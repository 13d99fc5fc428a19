//! Resolution: the merged scene tree → [`Model`] in SI units, with presets applied, optical
//! constants computed (through [`crate::optics`]), networks expanded (through
//! [`crate::plan::network::expand`]) and [`Needs`] decided. Every table's keys, units and
//! defaults are documented in [`super::format`] (the source of the JSON Schema and of
//! `docs/format.md`); the checks here must stay in step with it.

use super::check;
use super::diag::{Diagnostic, Span, num};
use super::reader::{Cx, Tab};
use super::source::{Node, Sources, Val, merge};
use crate::model::*;
use crate::optics;
use crate::plan::network::{self, ExplicitPose, NetworkContext, NetworkSpec, Orientation, Trigger};
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

#[derive(Default, Clone)]
pub struct CameraSpans {
    pub port: Span,
    pub thickness: Span,
    pub distance: Span,
    pub center: Span,
    pub material: Span,
}

pub fn resolve(root: &Node, scene_path: &Path, sources: &Sources, cx: &mut Cx) -> (Model, Spans) {
    let top = Span {
        file: 0,
        start: 0,
        end: 0,
    };
    let mut t = Tab::open(cx, Some(root), "", top);
    let mut spans = Spans::default();
    let name = t.opt_str(cx, "name").unwrap_or_else(|| {
        scene_path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default()
    });
    let description = t.opt_str(cx, "description").unwrap_or_default();
    t.get("include"); // handled by the loader; known here

    // Site first: the water's pressure depth and seabed defaults depend on it.
    let water_present = t.has("water");
    let site = site(cx, &mut t, water_present);
    let water = if water_present {
        let node = t.get("water");
        spans.water = t.span_of("water");
        water(cx, node, &site, top)
    } else {
        t.get("water");
        None
    };
    let ior = water.as_ref().map(|w| w.ior).unwrap_or([1.0; 3]);
    let sun = sun(cx, t.get("sun"), water.as_ref(), &site, top);
    let render = render(cx, t.get("render"), top);
    let cameras = cameras(cx, &mut t, water.is_some(), &mut spans, top);
    let f_number = cameras.first().and_then(|c| c.f_number);
    let sensor = super::sensor::sensor(cx, t.get("sensor"), f_number, top);
    let lights = lights(cx, &mut t, &mut spans);
    let objects = objects(
        cx,
        &mut t,
        &site,
        sources,
        scene_path,
        &mut spans,
        render.seed,
    );
    let targets = targets(cx, &mut t, &mut spans, &objects, &site, sources, scene_path);
    let diver = diver(cx, t.get("diver"), top);
    let lesson = super::lesson::lesson(cx, t.get("lesson"), sources, &name, &description, top);
    let speed_default = diver.as_ref().map(|d| d.speed).unwrap_or(0.2);
    let (poses, summary) = network(
        cx,
        t.get("network"),
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
    (model, spans)
}

// ------------------------------------------------------------------------------------------

fn site(cx: &mut Cx, t: &mut Tab, water: bool) -> Site {
    let fallback = t.span;
    let mut s = Tab::open(cx, t.get("site"), "site", fallback);
    let depth = s.f64(cx, "depth", Dim::Length, 10.0);
    let dspan = s.span_of("depth");
    if !(depth >= 0.0) {
        cx.push(
            Diagnostic::error("E0200", "the site depth must not be negative")
                .label(dspan, format!("{} m", num(depth)))
                .help("depth is measured downwards from the surface: write `depth = \"12 m\"`"),
        );
    }
    let kind = s
        .choice(cx, "surface", &["none", "flat", "waves"])
        .unwrap_or(if water { "flat" } else { "none" });
    let height = s.f64(cx, "wave_height", Dim::Length, 0.5);
    let wavelength = s.f64(cx, "wave_length", Dim::Length, 10.0);
    let wind_speed = s.f64(cx, "wind_speed", Dim::Speed, 5.0);
    if kind == "waves" {
        check::positive(cx, &s, "wave_height", height, "m");
        check::positive(cx, &s, "wave_length", wavelength, "m");
    }
    let surface = match kind {
        "none" => SeaSurface::None,
        "waves" => SeaSurface::Waves {
            height,
            wavelength,
            wind_speed,
        },
        _ => SeaSurface::Flat,
    };
    let altitude = s.f64(cx, "altitude", Dim::Length, 0.0);
    s.finish(cx);
    Site {
        depth: depth.max(0.0),
        surface,
        altitude,
    }
}

fn water(cx: &mut Cx, node: Option<&Node>, site: &Site, fallback: Span) -> Option<Water> {
    let mut w = Tab::open(cx, node, "water", fallback);
    // Index: constant, per channel, or from temperature/salinity/depth.
    let temperature = w.f64(cx, "temperature", Dim::Temperature, 20.0);
    let salinity = w.f64(cx, "salinity", Dim::Number, 35.0);
    let ior_depth = w.f64(cx, "ior_depth", Dim::Length, site.depth);
    let (ior, ior_source) = match w.opt_rgb(cx, "ior", Dim::Number) {
        Some(v) => (v, IorSource::Constant),
        None => {
            if !(-2.0..=40.0).contains(&temperature) {
                let sp = w.span_of("temperature");
                cx.push(
                    Diagnostic::error("E0201", "water temperature out of range")
                        .label(sp, format!("{} °C", num(temperature)))
                        .help("liquid water in the sea is between -2 °C and 40 °C"),
                );
            }
            if !(0.0..=45.0).contains(&salinity) {
                let sp = w.span_of("salinity");
                cx.push(
                    Diagnostic::error("E0201", "salinity out of range")
                        .label(sp, format!("{} PSU", num(salinity)))
                        .help("sea water is about 35 PSU, fresh water 0; the index formula holds up to ~45"),
                );
            }
            (
                CHANNEL_WAVELENGTHS_NM.map(|l| {
                    optics::water::seawater_ior(temperature, salinity, ior_depth.max(0.0), l)
                }),
                IorSource::Seawater {
                    temperature,
                    salinity,
                    depth: ior_depth.max(0.0),
                },
            )
        }
    };
    check::index(cx, &w, "ior", ior);
    // Inherent optical properties.
    let jerlov_name = w.opt_str(cx, "jerlov");
    let jspan = w.span_of("jerlov");
    let has_iops = w.has("absorption") || w.has("scattering");
    let mut absorption = [0.0; 3];
    let mut scattering = [0.0; 3];
    let mut jerlov = None;
    let jname = jerlov_name.or_else(|| (!has_iops).then(|| "IB".to_string()));
    if let Some(j) = jname {
        match optics::water::jerlov(&j) {
            Some((a, b)) => {
                absorption = a;
                scattering = b;
                jerlov = Some(j);
            }
            None => {
                let mut d = Diagnostic::error("E0202", format!("unknown Jerlov water type `{j}`"))
                    .label(
                        jspan,
                        format!("known types: {}", optics::water::JERLOV_TYPES.join(", ")),
                    );
                let fixed = j.to_uppercase().replace(['1', 'L'], "I");
                let close = optics::water::JERLOV_TYPES
                    .iter()
                    .copied()
                    .find(|t| **t == fixed || **t == j.to_uppercase())
                    .or_else(|| {
                        super::reader::did_you_mean(&j, optics::water::JERLOV_TYPES.iter().copied())
                    });
                d = match close {
                    Some(s) => d.help(format!("did you mean `{s}`?")),
                    None => d.help("oceanic types I–III, coastal 1C–9C (clearest first)"),
                };
                cx.push(d);
            }
        }
    }
    if let Some(a) = w.opt_rgb(cx, "absorption", Dim::Number) {
        check::non_negative_rgb(cx, &w, "absorption", a, "1/m");
        absorption = a;
    }
    if let Some(b) = w.opt_rgb(cx, "scattering", Dim::Number) {
        check::non_negative_rgb(cx, &w, "scattering", b, "1/m");
        scattering = b;
    }
    // Phase function.
    let phase_kind = w
        .choice(cx, "phase", &["hg", "fournier_forand"])
        .unwrap_or("hg");
    let g = w.f64(cx, "g", Dim::Number, 0.9);
    let n = w.f64(cx, "particle_index", Dim::Number, 1.1);
    let mu = w.f64(cx, "junge_slope", Dim::Number, 3.6);
    let phase = if phase_kind == "fournier_forand" {
        if !(n > 1.0) {
            let sp = w.span_of("particle_index");
            cx.push(
                Diagnostic::error("E0203", "Fournier–Forand needs a particle index above 1")
                    .label(sp, num(n))
                    .help("the index of particles relative to water is typically 1.05–1.20"),
            );
        }
        if !(mu > 3.0 && mu <= 5.0) {
            let sp = w.span_of("junge_slope");
            cx.push(
                Diagnostic::error("E0203", "Fournier–Forand needs a Junge slope in (3, 5]")
                    .label(sp, num(mu))
                    .help("typical ocean values are 3.5–4"),
            );
        }
        Phase::FournierForand {
            n,
            mu,
            backscatter: optics::phase::ff_backscatter(n, mu),
        }
    } else {
        if !(g > -1.0 && g < 1.0) {
            let sp = w.span_of("g");
            cx.push(
                Diagnostic::error(
                    "E0203",
                    "the Henyey–Greenstein g must be strictly between -1 and 1",
                )
                .label(sp, format!("g = {}", num(g)))
                .help("ocean water is strongly forward scattering: g ≈ 0.9"),
            );
        }
        Phase::HenyeyGreenstein { g }
    };
    // Extent.
    let extent_kind = w
        .choice(cx, "extent", &["everywhere", "box"])
        .unwrap_or("everywhere");
    let half = match w.get("box_half_size") {
        Some(n) if matches!(n.val, Val::Array(_)) => {
            super::reader::vector(cx, n, Dim::Length, "water.box_half_size", Some(3))
                .map(|v| DVec3::new(v[0], v[1], v[2]))
        }
        Some(n) => {
            super::reader::number(cx, n, Dim::Length, "water.box_half_size").map(DVec3::splat)
        }
        None => None,
    }
    .unwrap_or(DVec3::splat(2.0));
    let extent = if extent_kind == "box" {
        if !(half.min_element() > 0.0) {
            let sp = w.span_of("box_half_size");
            cx.push(
                Diagnostic::error("E0204", "the water box must have a positive size")
                    .label(sp, "every half-size must be > 0")
                    .help("e.g. `box_half_size = \"3 m\"`"),
            );
        }
        WaterExtent::BoxAroundCamera { half_size: half }
    } else {
        WaterExtent::Everywhere
    };
    w.finish(cx);
    Some(Water {
        ior,
        ior_source,
        absorption,
        scattering,
        jerlov,
        phase,
        extent,
    })
}

fn sun(
    cx: &mut Cx,
    node: Option<&Node>,
    water: Option<&Water>,
    site: &Site,
    fallback: Span,
) -> Option<Sun> {
    node?;
    let mut s = Tab::open(cx, node, "sun", fallback);
    let irradiance = s.rgb(cx, "irradiance", Dim::Irradiance, [1.0; 3]);
    check::non_negative_rgb(cx, &s, "irradiance", irradiance, "W/m²");
    let el = s.opt_f64(cx, "elevation", Dim::Angle);
    let az = s.opt_f64(cx, "azimuth", Dim::Angle);
    let lat = s.opt_degrees(cx, "latitude");
    let lon = s.opt_degrees(cx, "longitude");
    let dt = match s.get("datetime") {
        Some(Node {
            val: Val::Datetime(d),
            ..
        })
        | Some(Node {
            val: Val::Str(d), ..
        }) => Some(d.clone()),
        Some(n) => {
            cx.push(super::reader::type_error(
                n,
                "sun.datetime",
                "a date-time like 2024-06-21T10:30:00+02:00",
                &n.val,
            ));
            None
        }
        None => None,
    };
    let (elevation, azimuth, from_time) = match (el, lat, lon, &dt) {
        (Some(e), None, None, None) => (e, az.unwrap_or(std::f64::consts::PI), None),
        (None, Some(la), Some(lo), Some(d)) => {
            if az.is_some() {
                let sp = s.key_span("azimuth");
                cx.push(
                    Diagnostic::error("E0210", "the sun is given both by time and by azimuth")
                        .label(sp, "remove this, or remove latitude/longitude/datetime")
                        .help("give either `elevation` (+ `azimuth`) or `latitude`, `longitude` and `datetime`"),
                );
            }
            match optics::sun::position(la, lo, d) {
                Ok((e, a)) => (
                    e,
                    a,
                    Some(SunTime {
                        latitude: la,
                        longitude: lo,
                        datetime: d.clone(),
                    }),
                ),
                Err(m) => {
                    let sp = s.span_of("datetime");
                    cx.push(
                        Diagnostic::error("E0211", "cannot compute the sun position")
                            .label(sp, m)
                            .help("write the date-time with its offset, e.g. 2024-06-21T10:30:00+02:00, or give `elevation` and `azimuth`"),
                    );
                    (1.0, 0.0, None)
                }
            }
        }
        _ => {
            cx.push(
                Diagnostic::error("E0210", "the sun needs either an elevation or latitude, longitude and datetime")
                    .label(s.span, "incomplete or mixed sun position")
                    .help("write `elevation = \"60 deg\"` and `azimuth = \"135 deg\"`, or `latitude`, `longitude` and `datetime` (all three)"),
            );
            (1.0, 0.0, None)
        }
    };
    if elevation <= 0.0 {
        let sp = s.span_of("elevation");
        cx.push(
            Diagnostic::warning("W0210", "the sun is at or below the horizon")
                .label(sp, "no direct sunlight reaches the water")
                .help("raise the elevation, or remove [sun] and use lights"),
        );
    }
    s.finish(cx);
    let direction_air = optics::sun::direction_from(elevation, azimuth);
    let (direction_water, irradiance_water) = match water {
        Some(w) if !matches!(site.surface, SeaSurface::None) => {
            let (dir, _) = optics::sun::refract_into_water(direction_air, w.ior[1]);
            let f = [0, 1, 2].map(|c| optics::sun::refract_into_water(direction_air, w.ior[c]).1);
            (dir, [0, 1, 2].map(|c| irradiance[c] * f[c]))
        }
        _ => (direction_air, irradiance),
    };
    Some(Sun {
        elevation,
        azimuth,
        irradiance,
        direction_air,
        direction_water,
        irradiance_water,
        from_time,
    })
}

fn render(cx: &mut Cx, node: Option<&Node>, fallback: Span) -> RenderSettings {
    let mut r = Tab::open(cx, node, "render", fallback);
    let samples = r.u32(cx, "samples", 64);
    if samples == 0 {
        let sp = r.span_of("samples");
        cx.push(
            Diagnostic::error("E0220", "at least one sample per pixel is needed")
                .label(sp, "0 samples")
                .help("use e.g. `samples = 64`"),
        );
    }
    let seed = r.opt_u64(cx, "seed").unwrap_or(0);
    let max_bounces = r.u32(cx, "bounces", 8);
    let dispersion = r.bool(cx, "dispersion", false);
    let outputs = match r.get("outputs") {
        None => vec!["rgb".to_string(), "depth".into(), "truth".into()],
        Some(n) => match &n.val {
            Val::Array(a) => {
                let mut out = Vec::new();
                for x in a {
                    match &x.val {
                        Val::Str(s) if ["rgb", "depth", "truth"].contains(&s.as_str()) => {
                            out.push(s.clone())
                        }
                        _ => {
                            let mut d = Diagnostic::error("E0221", "unknown output")
                                .label(x.span, "expected \"rgb\", \"depth\" or \"truth\"");
                            if let Val::Str(s) = &x.val
                                && let Some(m) =
                                    super::reader::did_you_mean(s, ["rgb", "depth", "truth"])
                            {
                                d = d.help(format!("did you mean `{m}`?"));
                            } else {
                                d = d.help("outputs = [\"rgb\", \"depth\", \"truth\"]");
                            }
                            cx.push(d);
                        }
                    }
                }
                out
            }
            v => {
                cx.push(super::reader::type_error(
                    n,
                    "render.outputs",
                    "a list of strings",
                    v,
                ));
                vec![]
            }
        },
    };
    let exposure = r.f64(cx, "exposure", Dim::Number, 1.0);
    check::positive(cx, &r, "exposure", exposure, "");
    r.finish(cx);
    RenderSettings {
        samples,
        seed,
        max_bounces,
        dispersion,
        outputs,
        exposure,
    }
}

// ------------------------------------------------------------------------------------------
// Cameras
// ------------------------------------------------------------------------------------------

fn euler(v: DVec3) -> DMat3 {
    DMat3::from_euler(EulerRot::ZYX, v.z, v.y, v.x)
}

fn cameras(
    cx: &mut Cx,
    t: &mut Tab,
    water: bool,
    spans: &mut Spans,
    fallback: Span,
) -> Vec<Camera> {
    let cam_node = t.get("camera");
    let mut rig = Tab::open(cx, t.get("rig"), "rig", fallback);
    let kind = rig
        .choice(cx, "type", &["single", "stereo", "multi"])
        .unwrap_or("single");
    let base = cam_node.cloned().unwrap_or(Node {
        val: Val::Table(Default::default()),
        span: fallback,
    });
    let mut out = Vec::new();
    match kind {
        "stereo" => {
            let b = rig.f64(cx, "baseline", Dim::Length, 0.3);
            spans.baseline = Some(rig.span_of("baseline"));
            check::positive(cx, &rig, "baseline", b, "m");
            let conv = rig.f64(cx, "convergence", Dim::Angle, 0.0);
            for (name, sx) in [("left", -1.0), ("right", 1.0)] {
                let pose = Pose {
                    rotation: DMat3::from_rotation_y(-sx * conv / 2.0),
                    translation: DVec3::new(sx * b / 2.0, 0.0, 0.0),
                };
                if let Some(c) = camera(cx, &base, "camera", water, name, pose, spans) {
                    out.push(c);
                }
            }
        }
        "multi" => {
            let entries = rig.tables(cx, "cameras");
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
            if let Some(c) = camera(cx, &base, "camera", water, "cam", Pose::IDENTITY, spans) {
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
        .opt_str(cx, "name")
        .unwrap_or_else(|| default_name.to_string());
    if !crate::model::is_safe_file_name(&name) {
        // Camera names become file names (`{camera}_{pose}.exr` in a rig): checked once here
        // for every backend.
        let sp = if c.has("name") {
            c.span_of("name")
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
    let position = c.opt_vec3(cx, "position", Dim::Length);
    let rotation = c.opt_vec3(cx, "rotation", Dim::Angle);
    let rig_from_camera = match (position, rotation) {
        (None, None) => rig_pose,
        (p, r) => Pose {
            rotation: r.map(euler).unwrap_or(DMat3::IDENTITY),
            translation: p.unwrap_or(DVec3::ZERO),
        },
    };
    let width = c.u32(cx, "width", 1600);
    let height = c.u32(cx, "height", 1200);
    for (k, v) in [("width", width), ("height", height)] {
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
    let pitch = match (
        c.opt_f64(cx, "pixel_pitch", Dim::Length),
        c.opt_f64(cx, "sensor_width", Dim::Length),
    ) {
        (Some(p), None) => p,
        (None, Some(sw)) => sw / width.max(1) as f64,
        (Some(p), Some(_)) => {
            let sp = c.key_span("sensor_width");
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
    let pitch_key = if c.has("sensor_width") {
        "sensor_width"
    } else {
        "pixel_pitch"
    };
    check::positive(cx, &c, pitch_key, pitch, "m");
    let fx = match (
        c.opt_f64(cx, "focal_length", Dim::Length),
        c.opt_f64(cx, "fx", Dim::Number),
    ) {
        (Some(f), None) => f / pitch,
        (None, Some(fx)) => fx,
        (Some(f), Some(_)) => {
            let sp = c.key_span("fx");
            cx.push(
                Diagnostic::error("E0233", "give either `focal_length` or `fx`, not both")
                    .label(sp, "remove this or `focal_length`")
                    .help("fx (pixels) = focal_length / pixel_pitch"),
            );
            f / pitch
        }
        (None, None) => 0.016 / pitch,
    };
    let fkey = if c.has("fx") { "fx" } else { "focal_length" };
    check::positive(cx, &c, fkey, fx, "");
    let fx = if fx.is_finite() && fx > 0.0 { fx } else { 1.0 };
    let pp = c.opt_list(cx, "principal_point", Dim::Number);
    let (cx_, cy_) = match pp {
        Some(v) if v.len() == 2 => (v[0], v[1]),
        Some(_) => {
            let sp = c.span_of("principal_point");
            cx.push(
                Diagnostic::error("E0044", "`principal_point` needs 2 values")
                    .label(sp, "expected [cx, cy] in pixels")
                    .help("the image centre is [width/2, height/2]"),
            );
            (width as f64 / 2.0, height as f64 / 2.0)
        }
        None => (width as f64 / 2.0, height as f64 / 2.0),
    };
    let lens = match c.choice(
        cx,
        "lens",
        &["rectilinear", "fisheye_equidistant", "fisheye_equisolid"],
    ) {
        Some("fisheye_equidistant") => LensModel::FisheyeEquidistant,
        Some("fisheye_equisolid") => LensModel::FisheyeEquisolid,
        _ => LensModel::Rectilinear,
    };
    let distortion = {
        let n = c.get("distortion");
        let mut d = Tab::open(cx, n, &c.full("distortion"), c.span);
        let r = Distortion {
            k1: d.f64(cx, "k1", Dim::Number, 0.0),
            k2: d.f64(cx, "k2", Dim::Number, 0.0),
            k3: d.f64(cx, "k3", Dim::Number, 0.0),
            p1: d.f64(cx, "p1", Dim::Number, 0.0),
            p2: d.f64(cx, "p2", Dim::Number, 0.0),
        };
        d.finish(cx);
        r
    };
    let focus_distance = c.opt_f64(cx, "focus_distance", Dim::Length);
    if let Some(f) = focus_distance {
        check::positive(cx, &c, "focus_distance", f, "m");
    }
    let f_number = c.opt_f64(cx, "f_number", Dim::Number);
    if let Some(f) = f_number {
        check::positive(cx, &c, "f_number", f, "");
    }
    let port_node = c.get("port");
    let mut cs = CameraSpans {
        port: c.span_of("port"),
        ..Default::default()
    };
    let port = port(cx, port_node, &c.full("port"), water, c.span, &mut cs);
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

fn glass(cx: &mut Cx, p: &mut Tab, default: &str, cs: &mut CameraSpans) -> Glass {
    cs.material = p.span_of(if p.has("ior") { "ior" } else { "material" });
    if let Some(ior) = p.opt_rgb(cx, "ior", Dim::Number) {
        if p.has("material") {
            let sp = p.key_span("material");
            cx.push(
                Diagnostic::error(
                    "E0240",
                    "give either `material` or `ior` for the port, not both",
                )
                .label(sp, "remove this or `ior`")
                .help("`ior` defines a custom glass; `material` picks one from the catalogue"),
            );
        }
        p.get("material");
        check::index(cx, p, "ior", ior);
        return Glass {
            name: "custom".into(),
            ior,
        };
    }
    let mspan = p.span_of("material");
    let name = p
        .opt_str(cx, "material")
        .unwrap_or_else(|| default.to_string());
    let canonical = match name.to_lowercase().as_str() {
        "acrylic" | "pmma" => "PMMA".to_string(),
        "bk7" | "n-bk7" => "N-BK7".to_string(),
        "fused silica" | "fused_silica" | "quartz" => "fused_silica".to_string(),
        "sapphire" => "sapphire".to_string(),
        _ => name.clone(),
    };
    match CHANNEL_WAVELENGTHS_NM.map(|l| optics::glass::catalogue_ior(&canonical, l)) {
        [Some(r), Some(g), Some(b)] => Glass {
            name: canonical,
            ior: [r, g, b],
        },
        _ => {
            let mut d = Diagnostic::error("E0241", format!("unknown port material `{name}`"))
                .label(
                    mspan,
                    format!("catalogue: {}", optics::glass::CATALOGUE.join(", ")),
                );
            d = match super::reader::did_you_mean(&name, optics::glass::CATALOGUE.iter().copied()) {
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

/// `layers = [{ thickness, material | ior }, …]` of a flat port: the first layer, and the
/// ones outward of it. The port's own `thickness`, `material` and `ior` must then be absent.
fn flat_layers(
    cx: &mut Cx,
    p: &mut Tab,
    path: &str,
    cs: &mut CameraSpans,
) -> (f64, Glass, Vec<GlassLayer>) {
    let lspan = p.span_of("layers");
    for key in ["thickness", "material", "ior"] {
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
    let _ = (p.get("thickness"), p.get("material"), p.get("ior"));
    cs.thickness = lspan;
    cs.material = lspan;
    let nodes = p.tables(cx, "layers");
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
        let thickness = match t.opt_f64(cx, "thickness", Dim::Length) {
            Some(v) => {
                check::positive(cx, &t, "thickness", v, "m");
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
        .choice(cx, "type", &["none", "flat", "dome", "cylinder"])
        .unwrap_or(if water { "flat" } else { "none" });
    cs.thickness = p.span_of("thickness");
    let port = match kind {
        "none" => Port::None,
        "flat" => {
            let distance = p.f64(cx, "pupil_distance", Dim::Length, 0.01);
            cs.distance = p.span_of("pupil_distance");
            let tilt = p.f64(cx, "tilt", Dim::Angle, 0.0);
            let tilt_dir = p.f64(cx, "tilt_direction", Dim::Angle, 0.0);
            let (thickness, glass, outer_layers) = if p.has("layers") {
                flat_layers(cx, &mut p, path, cs)
            } else {
                let thickness = p.f64(cx, "thickness", Dim::Length, 0.01);
                let glass = glass(cx, &mut p, "N-BK7", cs);
                check::positive(cx, &p, "thickness", thickness, "m");
                (thickness, glass, vec![])
            };
            if !(distance > 0.0) {
                let sp = p.span_of("pupil_distance");
                cx.push(
                    Diagnostic::error("E0250", "the entrance pupil is outside the housing")
                        .label(sp, format!("pupil_distance = {} m puts the pupil at or beyond the port", num(distance)))
                        .help("`pupil_distance` is from the entrance pupil forward to the inner face of the glass; it must be > 0"),
                );
            }
            if tilt.abs() >= std::f64::consts::FRAC_PI_2 * 0.9 {
                let sp = p.span_of("tilt");
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
        "dome" => {
            let inner_radius = p.f64(cx, "inner_radius", Dim::Length, 0.05);
            let thickness = p.f64(cx, "thickness", Dim::Length, 0.005);
            let center = p.vec3(cx, "decentering", Dim::Length, DVec3::ZERO);
            cs.center = p.span_of("decentering");
            cs.distance = cs.center;
            let glass = glass(cx, &mut p, "PMMA", cs);
            check::positive(cx, &p, "inner_radius", inner_radius, "m");
            check::positive(cx, &p, "thickness", thickness, "m");
            if inner_radius > 0.0 && center.length() >= inner_radius {
                let sp = p.span_of("decentering");
                cx.push(
                    Diagnostic::error("E0250", "the entrance pupil is outside the dome")
                        .label(sp, format!("|decentering| = {:.4} m ≥ inner radius {:.4} m", center.length(), inner_radius))
                        .help("`decentering` is the dome centre relative to the entrance pupil; keep it well inside the inner radius (ideally 0)"),
                );
            }
            // The dome centre is the pupil offset by −decentering? No: `center` = dome centre in
            // the camera frame = the decentering vector.
            Port::Dome {
                center,
                inner_radius,
                thickness,
                glass,
            }
        }
        _ => {
            let inner_radius = p.f64(cx, "inner_radius", Dim::Length, 0.05);
            let thickness = p.f64(cx, "thickness", Dim::Length, 0.005);
            let axis = p.vec3(cx, "axis", Dim::Number, DVec3::Y);
            let axis_point = p.vec3(cx, "offset", Dim::Length, DVec3::ZERO);
            cs.center = p.span_of("offset");
            cs.distance = cs.center;
            let glass = glass(cx, &mut p, "PMMA", cs);
            check::positive(cx, &p, "inner_radius", inner_radius, "m");
            check::positive(cx, &p, "thickness", thickness, "m");
            let axis_n = axis.try_normalize();
            if axis_n.is_none() {
                let sp = p.span_of("axis");
                cx.push(
                    Diagnostic::error("E0252", "the cylinder axis must not be zero")
                        .label(sp, "zero vector")
                        .help("e.g. `axis = [0, 1, 0]` (vertical in the image)"),
                );
            }
            let axis = axis_n.unwrap_or(DVec3::Y);
            let off = axis_point - axis * axis_point.dot(axis);
            if inner_radius > 0.0 && off.length() >= inner_radius {
                let sp = p.span_of("offset");
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
    };
    p.finish_as(cx, Some(&format!("a {kind} port (`{path}`)")));
    port
}

// ------------------------------------------------------------------------------------------
// Lights, objects, targets
// ------------------------------------------------------------------------------------------

fn orthonormal_frame(z: DVec3) -> DMat3 {
    let z = z.try_normalize().unwrap_or(DVec3::NEG_Z);
    let helper = if z.z.abs() < 0.9 { DVec3::Z } else { DVec3::Y };
    let x = helper.cross(z).normalize();
    let y = z.cross(x);
    DMat3::from_cols(x, y, z)
}

fn lights(cx: &mut Cx, t: &mut Tab, spans: &mut Spans) -> Vec<Light> {
    let mut out = Vec::new();
    for (i, n) in t.tables(cx, "lights").into_iter().enumerate() {
        let path = format!("lights[{i}]");
        let mut l = Tab::open(cx, Some(n), &path, n.span);
        let name = l.opt_str(cx, "name").unwrap_or_else(|| format!("light{i}"));
        let ty = l
            .choice(cx, "type", &["spot", "strobe", "point", "area", "ambient"])
            .unwrap_or("spot");
        let default_mount = if ty == "area" || ty == "ambient" {
            Mount::World
        } else {
            Mount::Rig
        };
        let mount = match l.choice(cx, "mount", &["rig", "world"]) {
            Some("rig") => Mount::Rig,
            Some("world") => Mount::World,
            _ => default_mount,
        };
        let position = l.vec3(cx, "position", Dim::Length, DVec3::ZERO);
        let color = l.rgb(cx, "color", Dim::Number, [1.0; 3]);
        let forward = if mount == Mount::Rig {
            DVec3::Z
        } else {
            DVec3::NEG_Z
        };
        let mut direction = || -> DVec3 {
            let aim = l.opt_vec3(cx, "aim", Dim::Number);
            let target = l.opt_vec3(cx, "target", Dim::Length);
            let d = match (aim, target) {
                (Some(a), _) => a,
                (None, Some(p)) => p - position,
                _ => forward,
            };
            match d.try_normalize() {
                Some(v) => v,
                None => {
                    let sp = l.span_of(if l.has("aim") { "aim" } else { "target" });
                    cx.push(
                        Diagnostic::error("E0260", "the light has no direction")
                            .label(sp, "zero direction (or the target is the light's own position)")
                            .help("give `aim = [x, y, z]` (a direction) or `target = [x, y, z]` (a point)"),
                    );
                    forward
                }
            }
        };
        let kind = match ty {
            "spot" | "strobe" | "point" => {
                let dir = if ty == "point" { DVec3::Z } else { direction() };
                let intensity = match (
                    l.opt_rgb(cx, "power", Dim::Power),
                    l.opt_rgb(cx, "intensity", Dim::Intensity),
                ) {
                    (Some(p), None) => p.map(|x| x / (4.0 * std::f64::consts::PI)),
                    (None, Some(i)) => i,
                    (Some(p), Some(_)) => {
                        let sp = l.key_span("intensity");
                        cx.push(
                            Diagnostic::error(
                                "E0261",
                                "give either `power` or `intensity`, not both",
                            )
                            .label(sp, "remove this or `power`")
                            .help("intensity (W/sr) = power (W) / 4π"),
                        );
                        p.map(|x| x / (4.0 * std::f64::consts::PI))
                    }
                    (None, None) => [10.0 / (4.0 * std::f64::consts::PI); 3],
                };
                let key = if l.has("intensity") {
                    "intensity"
                } else {
                    "power"
                };
                check::non_negative_rgb(cx, &l, key, intensity, "");
                let intensity = [0, 1, 2].map(|c| intensity[c] * color[c]);
                if ty == "point" {
                    LightKind::Point {
                        position,
                        intensity,
                    }
                } else {
                    let beam = l.f64(cx, "beam_angle", Dim::Angle, 100f64.to_radians());
                    if !(beam > 0.0 && beam < std::f64::consts::PI) {
                        let sp = l.span_of("beam_angle");
                        cx.push(
                            Diagnostic::error("E0262", "the beam angle must be between 0 and 180 degrees")
                                .label(sp, format!("{:.1}°", beam.to_degrees()))
                                .help("`beam_angle` is the full cone angle, e.g. \"100 deg\" for a wide strobe"),
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
            "area" => {
                let dir = direction();
                let width = l.f64(cx, "width", Dim::Length, 0.5);
                let height = l.f64(cx, "height", Dim::Length, 0.5);
                check::positive(cx, &l, "width", width, "m");
                check::positive(cx, &l, "height", height, "m");
                let radiance = match (
                    l.opt_rgb(cx, "power", Dim::Power),
                    l.opt_rgb(cx, "radiance", Dim::Radiance),
                ) {
                    (Some(p), _) => {
                        p.map(|x| x / (std::f64::consts::PI * (width * height).max(1e-12)))
                    }
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
            _ => {
                let radiance = l.rgb(cx, "radiance", Dim::Radiance, [0.1; 3]);
                LightKind::Ambient {
                    radiance: [0, 1, 2].map(|c| radiance[c] * color[c]),
                }
            }
        };
        spans.lights.push((l.span, l.span_of("position")));
        l.finish_as(cx, Some(&format!("a {ty} light (`{path}`)")));
        out.push(Light { name, mount, kind });
    }
    out
}

/// `world_from_x` from `position` and `rotation` (Euler XYZ angles) or `look_at` (+z towards
/// a point).
fn placement(cx: &mut Cx, t: &mut Tab, default_pos: DVec3) -> Pose {
    let position = t.vec3(cx, "position", Dim::Length, default_pos);
    let rotation = t.opt_vec3(cx, "rotation", Dim::Angle);
    let look = t.opt_vec3(cx, "look_at", Dim::Length);
    let r = match (rotation, look) {
        (Some(r), None) => euler(r),
        (None, Some(p)) => match (p - position).try_normalize() {
            Some(z) => orthonormal_frame(z),
            None => {
                let sp = t.span_of("look_at");
                cx.push(
                    Diagnostic::error("E0270", "`look_at` is the object's own position")
                        .label(sp, "no direction to face")
                        .help("look at a point other than `position`"),
                );
                DMat3::IDENTITY
            }
        },
        (Some(r), Some(_)) => {
            let sp = t.key_span("look_at");
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

fn objects(
    cx: &mut Cx,
    t: &mut Tab,
    site: &Site,
    sources: &Sources,
    scene: &Path,
    spans: &mut Spans,
    seed0: u64,
) -> Vec<Object> {
    let mut out = Vec::new();
    for (i, n) in t.tables(cx, "objects").into_iter().enumerate() {
        let path = format!("objects[{i}]");
        let mut o = Tab::open(cx, Some(n), &path, n.span);
        let name = o
            .opt_str(cx, "name")
            .unwrap_or_else(|| format!("object{i}"));
        let shape_kind = o
            .choice(
                cx,
                "shape",
                &[
                    "mesh", "plane", "box", "sphere", "cylinder", "seabed", "boulders", "coral",
                ],
            )
            .unwrap_or("box");
        let seed = o
            .opt_u64(cx, "seed")
            .unwrap_or(seed0.wrapping_add(i as u64));
        let shape = match shape_kind {
            "mesh" => {
                let sp = o.span_of("path");
                let rel = o.opt_str(cx, "path").unwrap_or_default();
                if !o.has("path") {
                    cx.push(
                        Diagnostic::error("E0280", "a mesh object needs a `path`")
                            .label(o.span, "no `path`")
                            .help("give the glTF file relative to this scene file: `path = \"assets/amphora.glb\"`"),
                    );
                }
                let resolved = resolve_asset(cx, &rel, sp, sources, scene);
                Shape::Mesh { path: resolved }
            }
            "plane" => {
                let w = o.f64(cx, "width", Dim::Length, 1.0);
                let h = o.f64(cx, "height", Dim::Length, 1.0);
                check::positive(cx, &o, "width", w, "m");
                check::positive(cx, &o, "height", h, "m");
                Shape::Plane {
                    width: w,
                    height: h,
                }
            }
            "box" => {
                let size = o.vec3(cx, "size", Dim::Length, DVec3::ONE);
                if !(size.min_element() > 0.0) {
                    let sp = o.span_of("size");
                    cx.push(
                        Diagnostic::error("E0281", "a box needs a positive size")
                            .label(sp, "every side must be > 0")
                            .help("e.g. `size = [1, 0.5, 0.3]` (metres)"),
                    );
                }
                Shape::Box { size }
            }
            "sphere" => {
                let r = o.f64(cx, "radius", Dim::Length, 0.5);
                check::positive(cx, &o, "radius", r, "m");
                Shape::Sphere { radius: r }
            }
            "cylinder" => {
                let r = o.f64(cx, "radius", Dim::Length, 0.5);
                let h = o.f64(cx, "height", Dim::Length, 1.0);
                check::positive(cx, &o, "radius", r, "m");
                check::positive(cx, &o, "height", h, "m");
                Shape::Cylinder {
                    radius: r,
                    height: h,
                }
            }
            "seabed" => {
                let width = o.f64(cx, "width", Dim::Length, 20.0);
                let length = o.f64(cx, "length", Dim::Length, 20.0);
                let roughness = o.f64(cx, "roughness", Dim::Length, 0.1);
                let resolution = o.f64(cx, "resolution", Dim::Length, 0.05);
                check::positive(cx, &o, "width", width, "m");
                check::positive(cx, &o, "length", length, "m");
                check::positive(cx, &o, "resolution", resolution, "m");
                if roughness < 0.0 {
                    check::positive(cx, &o, "roughness", roughness, "m");
                }
                if width > 0.0
                    && length > 0.0
                    && resolution > 0.0
                    && (width / resolution) * (length / resolution) > 5e7
                {
                    let sp = o.span_of("resolution");
                    cx.push(
                        Diagnostic::error("E0282", "the seabed heightfield is too fine")
                            .label(
                                sp,
                                format!(
                                    "{:.0} cells",
                                    (width / resolution) * (length / resolution)
                                ),
                            )
                            .help(
                                "keep width/resolution × length/resolution under 50 million cells",
                            ),
                    );
                }
                Shape::Seabed {
                    width,
                    length,
                    roughness,
                    resolution,
                    seed,
                }
            }
            "coral" => super::coral::shape(cx, &mut o, seed),
            _ => {
                let width = o.f64(cx, "width", Dim::Length, 20.0);
                let length = o.f64(cx, "length", Dim::Length, 20.0);
                let count = o.u32(cx, "count", 30);
                let radius = o.f64(cx, "radius", Dim::Length, 0.3);
                let count = if check::at_most(cx, &o, "count", count as u64, 1_000_000, "boulders")
                {
                    count
                } else {
                    0
                };
                check::positive(cx, &o, "width", width, "m");
                check::positive(cx, &o, "length", length, "m");
                check::positive(cx, &o, "radius", radius, "m");
                Shape::Boulders {
                    width,
                    length,
                    count,
                    radius,
                    seed,
                }
            }
        };
        let default_pos = if matches!(shape, Shape::Seabed { .. } | Shape::Boulders { .. }) {
            DVec3::new(0.0, 0.0, -site.depth)
        } else {
            DVec3::ZERO
        };
        let pose = placement(cx, &mut o, default_pos);
        let scale = match o.get("scale") {
            Some(n) if matches!(n.val, Val::Array(_)) => {
                super::reader::vector(cx, n, Dim::Number, &o.full("scale"), Some(3))
                    .map(|v| DVec3::new(v[0], v[1], v[2]))
            }
            Some(n) => {
                super::reader::number(cx, n, Dim::Number, &o.full("scale")).map(DVec3::splat)
            }
            None => None,
        }
        .unwrap_or(DVec3::ONE);
        if !(scale.min_element() > 0.0) {
            let sp = o.span_of("scale");
            cx.push(
                Diagnostic::error("E0283", "the scale must be positive")
                    .label(sp, "every factor must be > 0")
                    .help("use `scale = 1` for the original size"),
            );
        }
        let material = material(cx, &mut o, 0.3);
        spans.objects.push(o.span);
        o.finish_as(cx, Some(&format!("a {shape_kind} object (`{path}`)")));
        out.push(Object {
            name,
            shape,
            pose,
            scale,
            material,
        });
    }
    out
}

fn resolve_asset(cx: &mut Cx, rel: &str, span: Span, sources: &Sources, scene: &Path) -> String {
    if rel.is_empty() {
        return String::new();
    }
    let dir = sources
        .dir_of(span.file)
        .unwrap_or_else(|| scene.parent().map(Path::to_path_buf).unwrap_or_default());
    let p = dir.join(rel);
    match std::fs::metadata(&p) {
        Ok(m) if m.is_file() => {
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            if ext != "glb" && ext != "gltf" {
                cx.push(
                    Diagnostic::error("E0285", "meshes must be glTF files")
                        .label(span, format!("`.{ext}` file"))
                        .help("convert the mesh to glTF (`.glb` or `.gltf`), e.g. with Blender's exporter"),
                );
            } else {
                match std::fs::read(&p).map_err(|e| e.to_string()).and_then(|b| {
                    gltf::Gltf::from_slice(&b)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                }) {
                    Ok(()) => cx.files.push(p.clone()),
                    Err(e) => cx.push(
                        Diagnostic::error(
                            "E0287",
                            format!(
                                "`{}` is not a readable glTF file",
                                super::source::display(&p)
                            ),
                        )
                        .label(span, e)
                        .help("re-export the mesh as glTF 2.0 (`.glb`), e.g. from Blender"),
                    ),
                }
            }
            // The model carries the canonical path, so every backend finds the file
            // wherever it runs from; it must stay inside the scene's directory tree.
            let canon = p.canonicalize().unwrap_or_else(|_| p.clone());
            let roots: Vec<std::path::PathBuf> =
                [Some(dir.clone()), scene.parent().map(Path::to_path_buf)]
                    .into_iter()
                    .flatten()
                    .filter_map(|d| {
                        (if d.as_os_str().is_empty() {
                            Path::new(".").to_path_buf()
                        } else {
                            d
                        })
                        .canonicalize()
                        .ok()
                    })
                    .collect();
            if !roots.iter().any(|r| canon.starts_with(r)) {
                cx.push(
                    Diagnostic::error("E0286", "the mesh file is outside the scene's directory")
                        .label(span, "this path leaves the directory of the scene")
                        .help("keep assets next to the scene (e.g. `assets/wreck.glb`) so the scene can be shared as one folder"),
                );
            }
            return canon.to_string_lossy().to_string();
        }
        Ok(_) => cx.push(
            Diagnostic::error(
                "E0284",
                format!("`{}` is not a file", super::source::display(&p)),
            )
            .label(span, "a directory")
            .help("give the path of the .glb/.gltf file itself"),
        ),
        Err(_) => cx.push(
            Diagnostic::error(
                "E0284",
                format!("mesh file `{}` not found", super::source::display(&p)),
            )
            .label(span, "no such file")
            .help("paths are relative to the scene file that names them"),
        ),
    }
    super::source::display(&p)
}

fn material(cx: &mut Cx, o: &mut Tab, default_albedo: f64) -> Material {
    let albedo = o.rgb(cx, "albedo", Dim::Number, [default_albedo; 3]);
    if albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
        let sp = o.span_of("albedo");
        cx.push(
            Diagnostic::error("E0290", "albedo must be between 0 and 1")
                .label(sp, "outside [0, 1]")
                .help("albedo is the fraction of light reflected: 0.05 black ink, 0.9 white paper"),
        );
    }
    let mut variation = 0.0;
    let mut texel = None;
    let pattern = o.get("pattern").map(|n| {
        let mut p = Tab::open(cx, Some(n), &o.full("pattern"), n.span);
        let ty = p
            .choice(
                cx,
                "type",
                &["checker", "noise", "fbm", "sand", "rock", "coral"],
            )
            .unwrap_or("noise");
        let seed = |cx: &mut Cx, p: &mut Tab| p.opt_u64(cx, "seed").unwrap_or(0);
        // A length ≥ 0 (0 switches the feature off).
        let len0 = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Length, default);
            check::non_negative(cx, p, key, v, "m");
            v
        };
        let len = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Length, default);
            check::positive(cx, p, key, v, "m");
            v
        };
        let fraction = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Number, default);
            check::within(cx, p, key, v, 0.0, 1.0);
            v
        };
        let r = match ty {
            "checker" => Pattern::Checker {
                size: len(cx, &mut p, "size", 0.1),
                contrast: p.f64(cx, "contrast", Dim::Number, 0.5),
            },
            "fbm" => Pattern::Fbm {
                size: len(cx, &mut p, "size", 1.0),
                smallest: len0(cx, &mut p, "smallest", 0.0),
                gain: fraction(cx, &mut p, "gain", 0.7),
                contrast: fraction(cx, &mut p, "contrast", 0.3),
                seed: seed(cx, &mut p),
            },
            "sand" => Pattern::Sand {
                wavelength: len0(cx, &mut p, "wavelength", 0.1),
                direction: p.f64(cx, "direction", Dim::Angle, 0.0),
                ripple: fraction(cx, &mut p, "ripple", 0.15),
                grain: len0(cx, &mut p, "grain", 0.0005),
                contrast: fraction(cx, &mut p, "contrast", 0.2),
                seed: seed(cx, &mut p),
            },
            "rock" => Pattern::Rock {
                size: len(cx, &mut p, "size", 0.5),
                crack: len0(cx, &mut p, "crack", 0.2),
                crack_width: len0(cx, &mut p, "crack_width", 0.003),
                speckle: len0(cx, &mut p, "speckle", 0.002),
                contrast: fraction(cx, &mut p, "contrast", 0.25),
                seed: seed(cx, &mut p),
            },
            "coral" => {
                let size = len(cx, &mut p, "size", 0.3);
                let cover = fraction(cx, &mut p, "cover", 0.6);
                let colors = coral_colors(cx, &mut p);
                Pattern::Coral {
                    size,
                    cover,
                    colors,
                    polyp: len0(cx, &mut p, "polyp", 0.005),
                    contrast: fraction(cx, &mut p, "contrast", 0.2),
                    seed: seed(cx, &mut p),
                }
            }
            _ => Pattern::Noise {
                size: len(cx, &mut p, "size", 0.1),
                amount: p.f64(cx, "amount", Dim::Number, 0.5),
                seed: seed(cx, &mut p),
            },
        };
        if ty != "checker" {
            variation = fraction(cx, &mut p, "variation", 0.0);
            texel = p.opt_f64(cx, "texel", Dim::Length);
            if let Some(t) = texel {
                check::positive(cx, &p, "texel", t, "m");
            }
        }
        p.finish_as(cx, Some(&format!("a {ty} pattern")));
        r
    });
    Material {
        albedo,
        pattern,
        variation,
        texel,
    }
}

/// `colors = [[r, g, b], …]` of a coral pattern: albedos in [0, 1]; empty = the default palette.
fn coral_colors(cx: &mut Cx, p: &mut Tab) -> Vec<crate::model::Rgb> {
    let full = p.full("colors");
    let Some(n) = p.get("colors") else {
        return vec![];
    };
    let Val::Array(items) = &n.val else {
        cx.push(super::reader::type_error(
            n,
            &full,
            "a list of [r, g, b] albedos",
            &n.val,
        ));
        return vec![];
    };
    let mut out = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let Some(v) = super::reader::vector(cx, item, Dim::Number, &format!("{full}.{i}"), Some(3))
        else {
            continue;
        };
        if v.iter().any(|a| !(0.0..=1.0).contains(a)) {
            cx.push(
                Diagnostic::error("E0290", "albedo must be between 0 and 1")
                    .label(item.span, "outside [0, 1]")
                    .help("each colour is an albedo `[r, g, b]` with values in [0, 1]"),
            );
            continue;
        }
        out.push([v[0], v[1], v[2]]);
    }
    out
}

fn targets(
    cx: &mut Cx,
    t: &mut Tab,
    spans: &mut Spans,
    objects: &[Object],
    site: &Site,
    sources: &Sources,
    scene: &Path,
) -> Vec<Target> {
    let mut out: Vec<Target> = Vec::new();
    for (i, n) in t.tables(cx, "targets").into_iter().enumerate() {
        let path = format!("targets[{i}]");
        let mut g = Tab::open(cx, Some(n), &path, n.span);
        let name = g
            .opt_str(cx, "name")
            .unwrap_or_else(|| format!("target{i}"));
        let ty = g
            .choice(
                cx,
                "type",
                &[
                    "checkerboard",
                    "circle_grid",
                    "coded",
                    "scale_bar",
                    "siemens_star",
                    "test_object",
                    "points_file",
                ],
            )
            .unwrap_or("checkerboard");
        if ty == "points_file" {
            let disks = points_file(cx, &mut g, &name, objects, site, sources, scene);
            for d in &disks {
                if out.iter().any(|o| o.name == d.name) {
                    cx.push(
                        Diagnostic::error("E0291", format!("two targets are named `{}`", d.name))
                            .label(g.span_of("name"), "a point of this file has a taken name")
                            .help("a points file's disks are named `name/id`; give this target another `name`"),
                    );
                    break;
                }
            }
            spans.targets.extend(disks.iter().map(|_| g.span));
            g.finish_as(cx, Some(&format!("a points_file target (`{path}`)")));
            out.extend(disks);
            continue;
        }
        let kind = match ty {
            "checkerboard" => {
                let cols = g.u32(cx, "cols", 9);
                let rows = g.u32(cx, "rows", 6);
                let square = g.f64(cx, "square", Dim::Length, 0.04);
                check::at_least(cx, &g, "cols", cols, 2);
                check::at_least(cx, &g, "rows", rows, 2);
                check::positive(cx, &g, "square", square, "m");
                let (cols, rows) = limit_grid(cx, &g, cols, rows);
                TargetKind::Checkerboard { cols, rows, square }
            }
            "circle_grid" => {
                let cols = g.u32(cx, "cols", 7);
                let rows = g.u32(cx, "rows", 5);
                let spacing = g.f64(cx, "spacing", Dim::Length, 0.05);
                let diameter = g.f64(cx, "diameter", Dim::Length, 0.02);
                check::at_least(cx, &g, "cols", cols, 1);
                check::at_least(cx, &g, "rows", rows, 1);
                check::positive(cx, &g, "spacing", spacing, "m");
                check::positive(cx, &g, "diameter", diameter, "m");
                check::fits(cx, &g, "diameter", diameter, spacing, "the spacing");
                let (cols, rows) = limit_grid(cx, &g, cols, rows);
                TargetKind::CircleGrid {
                    cols,
                    rows,
                    spacing,
                    diameter,
                }
            }
            "coded" => {
                let count = g.u32(cx, "count", 12);
                let spacing = g.f64(cx, "spacing", Dim::Length, 0.1);
                let diameter = g.f64(cx, "diameter", Dim::Length, 0.02);
                let first_code = g.u32(cx, "first_code", 1);
                check::at_least(cx, &g, "count", count, 1);
                let count =
                    if check::at_most(cx, &g, "count", count as u64, 10_000, "coded targets") {
                        count
                    } else {
                        1
                    };
                check::positive(cx, &g, "spacing", spacing, "m");
                check::positive(cx, &g, "diameter", diameter, "m");
                check::fits(
                    cx,
                    &g,
                    "diameter",
                    diameter * 2.5,
                    spacing,
                    "the spacing (the code ring is 2.5 × the diameter)",
                );
                TargetKind::Coded {
                    count,
                    spacing,
                    diameter,
                    first_code,
                }
            }
            "scale_bar" => {
                let length = g.f64(cx, "length", Dim::Length, 1.0);
                let width = g.f64(cx, "width", Dim::Length, 0.04);
                let diameter = g.f64(cx, "diameter", Dim::Length, 0.02);
                check::positive(cx, &g, "length", length, "m");
                check::positive(cx, &g, "width", width, "m");
                check::positive(cx, &g, "diameter", diameter, "m");
                check::fits(cx, &g, "diameter", diameter, width, "the bar width");
                TargetKind::ScaleBar {
                    length,
                    width,
                    diameter,
                }
            }
            "siemens_star" => {
                let diameter = g.f64(cx, "diameter", Dim::Length, 0.2);
                let spokes = g.u32(cx, "spokes", 16);
                check::positive(cx, &g, "diameter", diameter, "m");
                check::at_least(cx, &g, "spokes", spokes, 2);
                let spokes = if check::at_most(cx, &g, "spokes", spokes as u64, 10_000, "spokes") {
                    spokes
                } else {
                    16
                };
                TargetKind::SiemensStar { diameter, spokes }
            }
            _ => {
                let size = g.f64(cx, "size", Dim::Length, 0.5);
                let levels = g.u32(cx, "levels", 3);
                let step = g.f64(cx, "step", Dim::Length, 0.05);
                let diameter = g.f64(cx, "diameter", Dim::Length, 0.02);
                check::positive(cx, &g, "size", size, "m");
                check::at_least(cx, &g, "levels", levels, 1);
                let levels = if check::at_most(cx, &g, "levels", levels as u64, 1000, "levels") {
                    levels
                } else {
                    1
                };
                check::positive(cx, &g, "step", step, "m");
                check::positive(cx, &g, "diameter", diameter, "m");
                TargetKind::TestObject {
                    size,
                    levels: levels.max(1),
                    step,
                    diameter,
                }
            }
        };
        let pose = placement(cx, &mut g, DVec3::ZERO);
        if out.iter().any(|o| o.name == name) {
            let sp = g.span_of("name");
            cx.push(
                Diagnostic::error("E0291", format!("two targets are named `{name}`"))
                    .label(sp, "duplicate name")
                    .help("target point ids are `name/index`, so names must be unique"),
            );
        }
        spans.targets.push(g.span);
        g.finish_as(cx, Some(&format!("a {ty} target (`{path}`)")));
        let points = crate::geometry::targets::points(&name, &kind, &pose);
        out.push(Target {
            name,
            kind,
            pose,
            points,
        });
    }
    out
}

/// `type = "points_file"` (see [`super::points_file`]): one disk target per line of `file`.
fn points_file(
    cx: &mut Cx,
    g: &mut Tab,
    name: &str,
    objects: &[Object],
    site: &Site,
    sources: &Sources,
    scene: &Path,
) -> Vec<Target> {
    let diameter = g.f64(cx, "diameter", Dim::Length, 0.1);
    check::positive(cx, g, "diameter", diameter, "m");
    let surface = g
        .choice(cx, "surface", &["given", "seabed"])
        .unwrap_or("given");
    let frame = placement(cx, g, DVec3::ZERO);
    let fspan = g.span_of("file");
    let Some(rel) = g.opt_str(cx, "file") else {
        cx.push(
            Diagnostic::error("E0293", format!("`{}` needs a `file`", g.path))
                .label(g.span, "no `file`")
                .help("give the list of `id x y z` relative to this scene file: `file = \"gcps.txt\"`"),
        );
        return vec![];
    };
    let dir = sources
        .dir_of(fspan.file)
        .unwrap_or_else(|| scene.parent().map(Path::to_path_buf).unwrap_or_default());
    let file = dir.join(&rel);
    let pts = super::points_file::read(cx, &file, fspan);
    if !pts.is_empty() {
        cx.files.push(file.clone());
    }
    if pts.is_empty() || !(diameter > 0.0) {
        return vec![];
    }
    if surface == "given" {
        return super::points_file::given(name, diameter, &frame, &pts);
    }
    match super::points_file::dropped(name, diameter, &frame, &pts, objects, -site.depth) {
        Ok((disks, missed)) => {
            if !missed.is_empty() {
                cx.push(
                    Diagnostic::warning(
                        "W0292",
                        format!(
                            "{} of {} points are above no object and lie on the nominal seabed",
                            missed.len(),
                            pts.len()
                        ),
                    )
                    .label(g.span_of("surface"), format!("e.g. `{}`", missed[0]))
                    .help(
                        "add a seabed object under them, or use `surface = \"given\"` with their z",
                    ),
                );
            }
            disks
        }
        Err(e) => {
            cx.push(
                Diagnostic::error("E0294", "cannot drop the points onto the scene's objects")
                    .label(g.span_of("surface"), e)
                    .help("fix the objects' meshes, or use `surface = \"given\"`"),
            );
            vec![]
        }
    }
}

// ------------------------------------------------------------------------------------------
// Network, diver
// ------------------------------------------------------------------------------------------

/// Grids of more than a million points are refused (and replaced by a small one so that
/// checking continues without allocating them).
fn limit_grid(cx: &mut Cx, g: &Tab, cols: u32, rows: u32) -> (u32, u32) {
    if cols as u64 * rows as u64 > 1_000_000 {
        cx.push(
            Diagnostic::error("E0050", format!("`{}` has too many points", g.path))
                .label(
                    g.span_of("cols"),
                    format!("{cols} × {rows} exceeds one million"),
                )
                .help("real targets have at most a few thousand points"),
        );
        return (2, 2);
    }
    (cols, rows)
}

fn trigger(cx: &mut Cx, t: &mut Tab) -> Trigger {
    let sp = t.span_of("trigger");
    let Some(n) = t.get("trigger") else {
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

#[allow(clippy::too_many_arguments)]
fn network(
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
    let mut t = Tab::open(cx, Some(node), "network", fallback);
    spans.network = t.span;
    let ty = t
        .choice(cx, "type", &["explicit", "lawnmower", "spiral", "orbit"])
        .unwrap_or("explicit");
    let speed = t.f64(cx, "speed", Dim::Speed, speed_default);
    check::positive(cx, &t, "speed", speed, "m/s");
    let jitter = network::Jitter {
        position: t.f64(cx, "jitter_position", Dim::Length, 0.0),
        rotation: t.f64(cx, "jitter_rotation", Dim::Angle, 0.0),
        seed: t.opt_u64(cx, "jitter_seed").unwrap_or(1),
    };
    if !(jitter.position >= 0.0 && jitter.rotation >= 0.0 && jitter.rotation < 0.5) {
        let sp = t.span_of("jitter_rotation");
        cx.push(
            Diagnostic::error("E0315", "jitter must be a small, non-negative spread")
                .label(sp, "the σ of a hand-held camera's wobble")
                .help("a diver holds a camera to a few centimetres and a few degrees, e.g. `jitter_position = \"3 cm\"`, `jitter_rotation = \"2 deg\"`"),
        );
    }
    let altitude = |cx: &mut Cx, t: &mut Tab, ctx: &NetworkContext| -> f64 {
        let a = t.opt_f64(cx, "altitude", Dim::Length);
        let g = t.opt_f64(cx, "gsd", Dim::Gsd);
        match (a, g) {
            (Some(a), None) => {
                check::positive(cx, t, "altitude", a, "m");
                a
            }
            (None, Some(g)) => {
                check::positive(cx, t, "gsd", g, "m/px");
                ctx.altitude_for_gsd(g)
            }
            (Some(a), Some(_)) => {
                let sp = t.key_span("gsd");
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
    };
    let cam = cameras.first();
    let magnification = match cam.map(|c| &c.port) {
        Some(Port::Flat { .. }) => ior[1],
        _ => 1.0,
    };
    let ctx = NetworkContext {
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
    };
    let fraction = |cx: &mut Cx, t: &mut Tab, key: &'static str, d: f64| -> f64 {
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
    };
    let spec = match ty {
        "lawnmower" => {
            let center = t
                .opt_vec23(cx, "center", Dim::Length, 0.0)
                .unwrap_or(DVec3::ZERO);
            let width = t.f64(cx, "width", Dim::Length, 10.0);
            let length = t.f64(cx, "length", Dim::Length, 10.0);
            check::positive(cx, &t, "width", width, "m");
            check::positive(cx, &t, "length", length, "m");
            let heading = t.f64(cx, "heading", Dim::Angle, 0.0);
            let altitude = altitude(cx, &mut t, &ctx);
            let overlap = fraction(cx, &mut t, "overlap", 0.8);
            let sidelap = fraction(cx, &mut t, "sidelap", 0.6);
            spans.sidelap = Some(t.span_of("sidelap"));
            spans.overlap_asked = t.has("overlap").then(|| t.span_of("overlap"));
            spans.sidelap_asked = t.has("sidelap").then(|| t.span_of("sidelap"));
            let strips = t.opt_u32(cx, "strips");
            if strips == Some(0) {
                let sp = t.span_of("strips");
                cx.push(
                    Diagnostic::error("E0313", "a lawnmower needs at least one strip")
                        .label(sp, "0 strips")
                        .help("remove `strips` to derive it from the side-lap"),
                );
            }
            let cross_strips = t.bool(cx, "cross_strips", false);
            let tilt = t.f64(cx, "tilt", Dim::Angle, 0.0);
            let obliques = t.f64(cx, "obliques", Dim::Angle, 0.0);
            if obliques.abs() >= std::f64::consts::FRAC_PI_2 {
                let sp = t.span_of("obliques");
                cx.push(
                    Diagnostic::error("E0314", "oblique tilt must be below 90°")
                        .label(sp, format!("{:.1}°", obliques.to_degrees()))
                        .help("obliques are usually tilted 20–45° forward from nadir"),
                );
            }
            let trigger = trigger(cx, &mut t);
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
        "spiral" => {
            let center = t
                .opt_vec23(cx, "center", Dim::Length, 0.0)
                .unwrap_or(DVec3::ZERO);
            let radius = t.f64(cx, "radius", Dim::Length, 5.0);
            check::positive(cx, &t, "radius", radius, "m");
            let altitude = altitude(cx, &mut t, &ctx);
            let overlap = fraction(cx, &mut t, "overlap", 0.8);
            let sidelap = fraction(cx, &mut t, "sidelap", 0.6);
            spans.sidelap = Some(t.span_of("sidelap"));
            spans.overlap_asked = t.has("overlap").then(|| t.span_of("overlap"));
            spans.sidelap_asked = t.has("sidelap").then(|| t.span_of("sidelap"));
            let trigger = trigger(cx, &mut t);
            NetworkSpec::Spiral {
                center,
                radius,
                altitude,
                overlap,
                sidelap,
                trigger,
            }
        }
        "orbit" => {
            let center = t
                .opt_vec23(cx, "center", Dim::Length, -site.depth)
                .unwrap_or(DVec3::new(0.0, 0.0, -site.depth));
            let radius = t.f64(cx, "radius", Dim::Length, 2.0);
            check::positive(cx, &t, "radius", radius, "m");
            let elevations = t
                .opt_list(cx, "elevations", Dim::Angle)
                .unwrap_or(vec![20f64.to_radians(), 45f64.to_radians()]);
            if elevations.is_empty() {
                let sp = t.span_of("elevations");
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
                let sp = t.span_of("elevations");
                cx.push(
                    Diagnostic::error("E0314", "orbit elevations must be between -90 and 90 degrees")
                        .label(sp, format!("{:.1}° is out of range", e.to_degrees()))
                        .help("elevations are angles above the horizontal plane through `center`, e.g. \"20, 45 deg\""),
                );
            }
            let per_ring = t.u32(cx, "per_ring", 24);
            let per_ring = if check::at_most(
                cx,
                &t,
                "per_ring",
                per_ring as u64,
                100_000,
                "images per ring",
            ) {
                per_ring
            } else {
                1
            };
            check::at_least(cx, &t, "per_ring", per_ring, 1);
            NetworkSpec::Orbit {
                center,
                radius,
                elevations,
                per_ring,
            }
        }
        _ => {
            let entries = t.tables(cx, "poses");
            let mut poses = Vec::new();
            for (i, n) in entries.into_iter().enumerate() {
                let mut p = Tab::open(cx, Some(n), &format!("network.poses[{i}]"), n.span);
                let position = p.opt_vec3(cx, "position", Dim::Length);
                if position.is_none() && !p.has("position") {
                    cx.push(
                        Diagnostic::error("E0315", "a pose needs a `position`")
                            .label(p.span, "no position")
                            .help("write `position = [x, y, z]` (metres, world frame, z up)"),
                    );
                }
                let look = p.opt_vec3(cx, "look_at", Dim::Length);
                let up = p.vec3(cx, "up", Dim::Number, DVec3::Z);
                let rot = p.opt_vec3(cx, "rotation", Dim::Angle);
                let orientation = match (look, rot) {
                    (Some(target), None) => Orientation::LookAt { target, up },
                    (None, Some(r)) => Orientation::Rotation { rotation: euler(r) },
                    (Some(target), Some(_)) => {
                        let sp = p.key_span("rotation");
                        cx.push(
                            Diagnostic::error(
                                "E0316",
                                "give either `look_at` or `rotation`, not both",
                            )
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
                    let sp = p.span_of("look_at");
                    cx.push(
                        Diagnostic::error("E0317", "this pose has no viewing direction")
                            .label(sp, "the look-at point equals the position, or `up` is parallel to the view")
                            .help("look at a different point, or give another `up` vector"),
                    );
                }
                p.finish(cx);
                poses.push(ExplicitPose {
                    position,
                    orientation,
                });
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
    };
    t.finish_as(cx, Some(&format!("a {ty} network")));
    if cx.has_errors() {
        return (
            vec![],
            NetworkSummary {
                kind: ty.into(),
                speed,
                ..Default::default()
            },
        );
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
            (
                vec![],
                NetworkSummary {
                    kind: ty.into(),
                    speed,
                    ..Default::default()
                },
            )
        }
    }
}

fn diver(cx: &mut Cx, node: Option<&Node>, fallback: Span) -> Option<Diver> {
    node?;
    let mut d = Tab::open(cx, node, "diver", fallback);
    let speed = d.f64(cx, "speed", Dim::Speed, 0.2);
    let descent_rate = d.f64(cx, "descent_rate", Dim::Speed, 18.0 / 60.0);
    let ascent_rate = d.f64(cx, "ascent_rate", Dim::Speed, 9.0 / 60.0);
    let sac = d.f64(cx, "sac", Dim::Flow, 20e-3 / 60.0);
    for (k, v, u) in [
        ("speed", speed, "m/s"),
        ("descent_rate", descent_rate, "m/s"),
        ("ascent_rate", ascent_rate, "m/s"),
        ("sac", sac, "m³/s"),
    ] {
        check::positive(cx, &d, k, v, u);
    }
    let gf_low = d.f64(cx, "gf_low", Dim::Fraction, 0.3);
    // Subsurface's default gradient factors, 30/75 (its `core/pref.cpp`), as without [diver].
    let gf_high = d.f64(cx, "gf_high", Dim::Fraction, 0.75);
    for (k, v) in [("gf_low", gf_low), ("gf_high", gf_high)] {
        if !(v > 0.0 && v <= 1.0) {
            let sp = d.span_of(k);
            cx.push(
                Diagnostic::error("E0320", format!("`{k}` must be a fraction in (0, 1]"))
                    .label(sp, num(v))
                    .help(format!(
                        "gradient factors are fractions: `{k} = 0.3` or `{k} = \"30 %\"`"
                    )),
            );
        }
    }
    if gf_low > gf_high {
        let sp = d.span_of("gf_low");
        cx.push(
            Diagnostic::error("E0320", "`gf_low` is above `gf_high`")
                .label(sp, format!("{} > {}", num(gf_low), num(gf_high)))
                .help("the low gradient factor applies at depth and must not exceed the high one (e.g. 30/70)"),
        );
    }
    let reserve = d.f64(cx, "reserve", Dim::Pressure, 50e5);
    let po2_bottom = d.f64(cx, "po2_bottom", Dim::Pressure, 1.4e5) / 1e5;
    let po2_deco = d.f64(cx, "po2_deco", Dim::Pressure, 1.6e5) / 1e5;
    for (k, v) in [("po2_bottom", po2_bottom), ("po2_deco", po2_deco)] {
        if !(v.is_finite() && (0.16..=2.0).contains(&v)) {
            let sp = d.span_of(k);
            cx.push(
                Diagnostic::error("E0324", format!("`{k}` must be a pO₂ limit in 0.16…2 bar"))
                    .label(sp, format!("{} bar", num(v)))
                    .help(format!(
                        "Subsurface's limits are 1.4 bar on the bottom and 1.6 bar for deco gases: `{k} = \"{}\"`",
                        if k == "po2_deco" { "1.6 bar" } else { "1.4 bar" }
                    )),
            );
        }
    }
    let salt_water = !matches!(d.choice(cx, "water", &["salt", "fresh"]), Some("fresh"));
    let mut cylinders: Vec<Cylinder> = Vec::new();
    for (i, n) in d.tables(cx, "cylinders").into_iter().enumerate() {
        let mut c = Tab::open(cx, Some(n), &format!("diver.cylinders[{i}]"), n.span);
        let name = c
            .opt_str(cx, "name")
            .unwrap_or_else(|| format!("cylinder{i}"));
        let volume = c.f64(cx, "volume", Dim::Volume, 0.012);
        let pressure = c.f64(cx, "pressure", Dim::Pressure, 200e5);
        check::positive(cx, &c, "volume", volume, "m³");
        check::positive(cx, &c, "pressure", pressure, "Pa");
        let gas_span = c.span_of("gas");
        let (mut o2, mut he) = match c.opt_str(cx, "gas") {
            None => (0.21, 0.0),
            Some(g) => match parse_gas(&g) {
                Some(x) => x,
                None => {
                    cx.push(
                        Diagnostic::error("E0321", format!("unknown gas `{g}`"))
                            .label(gas_span, "not a gas name")
                            .help("write \"air\", \"EAN32\" (nitrox 32 % O₂), \"TX18/45\" (trimix), \"O2\", or give `o2`/`he` fractions"),
                    );
                    (0.21, 0.0)
                }
            },
        };
        if let Some(x) = c.opt_f64(cx, "o2", Dim::Fraction) {
            o2 = x;
        }
        if let Some(x) = c.opt_f64(cx, "he", Dim::Fraction) {
            he = x;
        }
        let mut mix_ok = true;
        for (k, v, lo) in [("o2", o2, 0.0), ("he", he, -1e-12)] {
            if !(v > lo && v <= 1.0 + 1e-12) {
                mix_ok = false;
                let sp = c.span_of(if c.has(k) { k } else { "gas" });
                cx.push(
                    Diagnostic::error("E0322", format!("`{k}` fraction out of range"))
                        .label(
                            sp,
                            format!(
                                "{} is not a fraction in {}",
                                num(v),
                                if k == "o2" { "(0, 1]" } else { "[0, 1]" }
                            ),
                        )
                        .help(format!(
                            "gas fractions are parts of one: `{k} = 0.32` or `{k} = \"32 %\"`"
                        )),
                );
            }
        }
        if mix_ok && o2 + he > 1.0 + 1e-12 {
            let sp = c.span_of(if c.has("he") {
                "he"
            } else if c.has("o2") {
                "o2"
            } else {
                "gas"
            });
            cx.push(
                Diagnostic::error("E0322", "impossible gas mix: O₂ + He exceed the whole")
                    .label(sp, format!("O₂ {} + He {} = {} > 1", num(o2), num(he), num(o2 + he)))
                    .help("the fractions of O₂ and He must add up to at most 1 (the rest is N₂), e.g. TX18/45: `o2 = 0.18`, `he = 0.45`"),
            );
        }
        let role_given = c.choice(cx, "role", &["bottom", "stage", "deco"]);
        let role = match role_given {
            Some("stage") => CylinderRole::Stage,
            Some("deco") => CylinderRole::Deco,
            Some(_) => CylinderRole::Bottom,
            // Unsaid: the first cylinder is the back gas; a later richer gas is for deco.
            None => match cylinders.first() {
                Some(first) if o2 > first.o2 + 1e-9 => CylinderRole::Deco,
                _ => CylinderRole::Bottom,
            },
        };
        let sw_span = c.span_of("switch_depth");
        let switch_depth = c.opt_f64(cx, "switch_depth", Dim::Length);
        if let Some(sw) = switch_depth {
            if !(sw.is_finite() && sw >= 0.0) {
                cx.push(
                    Diagnostic::error("E0325", "`switch_depth` must be a depth ≥ 0")
                        .label(sw_span, format!("{} m", num(sw)))
                        .help("the depth from which the deco gas is breathed, e.g. `switch_depth = \"21 m\"` for EAN50"),
                );
            } else if role != CylinderRole::Deco {
                cx.push(
                    Diagnostic::error("E0325", "`switch_depth` is only for deco cylinders")
                        .label(sw_span, "this cylinder is not a deco gas")
                        .help("add `role = \"deco\"` or remove `switch_depth`"),
                );
            }
        }
        c.finish(cx);
        cylinders.push(Cylinder {
            name,
            volume,
            pressure,
            o2,
            he,
            role,
            switch_depth,
        });
    }
    if cylinders.is_empty() {
        cylinders.push(Cylinder {
            name: "back".into(),
            volume: 0.012,
            pressure: 200e5,
            o2: 0.21,
            he: 0.0,
            role: CylinderRole::Bottom,
            switch_depth: None,
        });
    }
    if !cylinders.iter().any(|c| c.role != CylinderRole::Deco) {
        let sp = d.span_of("cylinders");
        cx.push(
            Diagnostic::error("E0326", "no bottom gas: every cylinder is a deco gas")
                .label(sp, "no cylinder with role \"bottom\" or \"stage\"")
                .help("mark the back gas `role = \"bottom\"`"),
        );
    }
    d.finish(cx);
    Some(Diver {
        speed,
        descent_rate,
        ascent_rate,
        sac,
        cylinders,
        gf_low,
        gf_high,
        reserve,
        salt_water,
        po2_bottom,
        po2_deco,
    })
}

/// `"air"`, `"EAN32"`, `"nitrox32"`, `"TX18/45"`, `"O2"` → (O₂, He) fractions.
pub fn parse_gas(s: &str) -> Option<(f64, f64)> {
    let u = s.trim().to_uppercase().replace(' ', "");
    if u == "AIR" {
        return Some((0.21, 0.0));
    }
    if u == "O2" || u == "OXYGEN" {
        return Some((1.0, 0.0));
    }
    for p in ["EAN", "NITROX", "NX"] {
        if let Some(r) = u.strip_prefix(p) {
            let v: f64 = r.parse().ok()?;
            return (v > 0.0 && v <= 100.0).then_some((v / 100.0, 0.0));
        }
    }
    for p in ["TX", "TRIMIX"] {
        if let Some(r) = u.strip_prefix(p) {
            let (a, b) = r.split_once('/')?;
            let (o, h): (f64, f64) = (a.parse().ok()?, b.parse().ok()?);
            return (o > 0.0 && h >= 0.0 && o + h <= 100.0).then_some((o / 100.0, h / 100.0));
        }
    }
    None
}

// ------------------------------------------------------------------------------------------

/// Decide what the scene needs modelled, with reasons.
pub fn needs(m: &Model) -> Needs {
    let mut n = Needs::default();
    let ior = m.ambient_ior();
    match &m.water {
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
