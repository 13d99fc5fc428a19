//! The environment the survey happens in: the `[site]` (depth, sea surface, altitude), the
//! `[water]` (refractive index from temperature, salinity and pressure, or given; absorption
//! and scattering from a Jerlov type or given; phase function; extent) and the `[sun]` (from
//! elevation and azimuth or from place and time, refracted into the water through the sea
//! surface). The formulas themselves are in [`crate::optics::water`] and [`crate::optics::sun`].

use crate::model::*;
use crate::optics;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span, num};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Node, Val};
use crate::units::Dim;
use glam::DVec3;

/// `[site]`; the sea surface defaults to flat when the scene has water, none without.
pub(super) fn site(cx: &mut Cx, t: &mut Tab, water: bool) -> Site {
    let fallback = t.span;
    let mut s = Tab::open(cx, t.get(F::Scene::site), F::Scene::site, fallback);
    let depth = s.f64(cx, F::Site::depth, Dim::Length, 10.0);
    let dspan = s.span_of(F::Site::depth);
    if !(depth >= 0.0) {
        cx.push(
            Diagnostic::error("E0200", "the site depth must not be negative")
                .label(dspan, format!("{} m", num(depth)))
                .help("depth is measured downwards from the surface: write `depth = \"12 m\"`"),
        );
    }
    let kind = s
        .choice(cx, F::Site::surface, &["none", "flat", "waves"])
        .unwrap_or(if water { "flat" } else { "none" });
    let height = s.f64(cx, F::Site::wave_height, Dim::Length, 0.5);
    let wavelength = s.f64(cx, F::Site::wave_length, Dim::Length, 10.0);
    let wind_speed = s.f64(cx, F::Site::wind_speed, Dim::Speed, 5.0);
    if kind == "waves" {
        check::positive(cx, &s, F::Site::wave_height, height, "m");
        check::positive(cx, &s, F::Site::wave_length, wavelength, "m");
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
    let altitude = s.f64(cx, F::Site::altitude, Dim::Length, 0.0);
    let seed = s.opt_u64(cx, F::Site::seed).unwrap_or(0);
    s.finish(cx);
    Site {
        depth: depth.max(0.0),
        surface,
        altitude,
        seed,
    }
}

/// `[water]`: index, inherent optical properties, phase function and extent.
pub(super) fn water(
    cx: &mut Cx,
    node: Option<&Node>,
    site: &Site,
    fallback: Span,
) -> Option<Water> {
    let mut w = Tab::open(cx, node, F::Scene::water, fallback);
    let water = water_keys(cx, &mut w, site, true);
    w.finish(cx);
    Some(water)
}

/// The water inside a filled object (`fill = { … }`, at `path`): `[water]`'s keys but
/// `extent` and `box_half_size` (the object is its extent).
pub(super) fn fill_water(cx: &mut Cx, node: &Node, path: &str, site: &Site) -> Water {
    let mut w = Tab::open(cx, Some(node), path, node.span);
    let water = water_keys(cx, &mut w, site, false);
    w.finish_as(
        cx,
        Some("the water of a filled object (the object is its extent)"),
    );
    water
}

/// A water table's keys, read in this order: index, inherent optical properties, phase
/// function, and (`with_extent`) extent; without it the water is everywhere it is put.
fn water_keys(cx: &mut Cx, w: &mut Tab, site: &Site, with_extent: bool) -> Water {
    let (ior, ior_source) = index(cx, w, site);
    let (absorption, scattering, jerlov) = iops(cx, w);
    let phase = phase(cx, w);
    let extent = if with_extent {
        extent(cx, w)
    } else {
        WaterExtent::Everywhere
    };
    Water {
        ior,
        ior_source,
        absorption,
        scattering,
        jerlov,
        phase,
        extent,
    }
}

/// The refractive index of the water per channel: `ior` as given, or from `temperature`,
/// `salinity` and `ior_depth` (the site depth by default) by the seawater formula.
fn index(cx: &mut Cx, w: &mut Tab, site: &Site) -> (Rgb, IorSource) {
    let temperature = w.f64(cx, F::Water::temperature, Dim::Temperature, 20.0);
    let salinity = w.f64(cx, F::Water::salinity, Dim::Number, 35.0);
    let ior_depth = w.f64(cx, F::Water::ior_depth, Dim::Length, site.depth);
    let (ior, ior_source) = match w.opt_rgb(cx, F::Water::ior, Dim::Number) {
        Some(v) => (v, IorSource::Constant),
        None => {
            if !(-2.0..=40.0).contains(&temperature) {
                let sp = w.span_of(F::Water::temperature);
                cx.push(
                    Diagnostic::error("E0201", "water temperature out of range")
                        .label(sp, format!("{} °C", num(temperature)))
                        .help("liquid water in the sea is between -2 °C and 40 °C"),
                );
            }
            if !(0.0..=45.0).contains(&salinity) {
                let sp = w.span_of(F::Water::salinity);
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
    check::index(cx, w, F::Water::ior, ior);
    (ior, ior_source)
}

/// Absorption and scattering (1/m per channel): from a Jerlov water type (IB when neither
/// `absorption` nor `scattering` is given), each overridden by its key when given.
fn iops(cx: &mut Cx, w: &mut Tab) -> (Rgb, Rgb, Option<String>) {
    let jerlov_name = w.opt_str(cx, F::Water::jerlov);
    let jspan = w.span_of(F::Water::jerlov);
    let has_iops = w.has(F::Water::absorption) || w.has(F::Water::scattering);
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
                        crate::scene::reader::did_you_mean(
                            &j,
                            optics::water::JERLOV_TYPES.iter().copied(),
                        )
                    });
                d = match close {
                    Some(s) => d.help(format!("did you mean `{s}`?")),
                    None => d.help("oceanic types I–III, coastal 1C–9C (clearest first)"),
                };
                cx.push(d);
            }
        }
    }
    if let Some(a) = w.opt_rgb(cx, F::Water::absorption, Dim::Number) {
        check::non_negative_rgb(cx, w, F::Water::absorption, a, "1/m");
        absorption = a;
    }
    if let Some(b) = w.opt_rgb(cx, F::Water::scattering, Dim::Number) {
        check::non_negative_rgb(cx, w, F::Water::scattering, b, "1/m");
        scattering = b;
    }
    (absorption, scattering, jerlov)
}

/// The scattering phase function: Henyey–Greenstein (`g`) or Fournier–Forand
/// (`particle_index`, `junge_slope`).
fn phase(cx: &mut Cx, w: &mut Tab) -> Phase {
    let phase_kind = w
        .choice(cx, F::Water::phase, &["hg", "fournier_forand"])
        .unwrap_or("hg");
    let g = w.f64(cx, F::Water::g, Dim::Number, 0.9);
    let n = w.f64(cx, F::Water::particle_index, Dim::Number, 1.1);
    let mu = w.f64(cx, F::Water::junge_slope, Dim::Number, 3.6);
    if phase_kind == "fournier_forand" {
        if !(n > 1.0) {
            let sp = w.span_of(F::Water::particle_index);
            cx.push(
                Diagnostic::error("E0203", "Fournier–Forand needs a particle index above 1")
                    .label(sp, num(n))
                    .help("the index of particles relative to water is typically 1.05–1.20"),
            );
        }
        if !(mu > 3.0 && mu <= 5.0) {
            let sp = w.span_of(F::Water::junge_slope);
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
            let sp = w.span_of(F::Water::g);
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
    }
}

/// Where the water is: everywhere, or a box of `box_half_size` around each camera.
fn extent(cx: &mut Cx, w: &mut Tab) -> WaterExtent {
    let extent_kind = w
        .choice(cx, F::Water::extent, &["everywhere", "box"])
        .unwrap_or("everywhere");
    let half = match w.get(F::Water::box_half_size) {
        Some(n) if matches!(n.val, Val::Array(_)) => {
            crate::scene::reader::vector(cx, n, Dim::Length, "water.box_half_size", Some(3))
                .map(|v| DVec3::new(v[0], v[1], v[2]))
        }
        Some(n) => crate::scene::reader::number(cx, n, Dim::Length, "water.box_half_size")
            .map(DVec3::splat),
        None => None,
    }
    .unwrap_or(DVec3::splat(2.0));
    if extent_kind == "box" {
        if !(half.min_element() > 0.0) {
            let sp = w.span_of(F::Water::box_half_size);
            cx.push(
                Diagnostic::error("E0204", "the water box must have a positive size")
                    .label(sp, "every half-size must be > 0")
                    .help("e.g. `box_half_size = \"3 m\"`"),
            );
        }
        WaterExtent::BoxAroundCamera { half_size: half }
    } else {
        WaterExtent::Everywhere
    }
}

/// `[sun]`, when present, with its direction and irradiance in the water.
pub(super) fn sun(
    cx: &mut Cx,
    node: Option<&Node>,
    water: Option<&Water>,
    site: &Site,
    fallback: Span,
) -> Option<Sun> {
    node?;
    let mut s = Tab::open(cx, node, F::Scene::sun, fallback);
    let irradiance = s.rgb(cx, F::Sun::irradiance, Dim::Irradiance, [1.0; 3]);
    check::non_negative_rgb(cx, &s, F::Sun::irradiance, irradiance, "W/m²");
    let el = s.opt_f64(cx, F::Sun::elevation, Dim::Angle);
    let az = s.opt_f64(cx, F::Sun::azimuth, Dim::Angle);
    let lat = s.opt_degrees(cx, F::Sun::latitude);
    let lon = s.opt_degrees(cx, F::Sun::longitude);
    let dt = match s.get(F::Sun::datetime) {
        Some(Node {
            val: Val::Datetime(d),
            ..
        })
        | Some(Node {
            val: Val::Str(d), ..
        }) => Some(d.clone()),
        Some(n) => {
            cx.push(crate::scene::reader::type_error(
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
                let sp = s.key_span(F::Sun::azimuth);
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
                    let sp = s.span_of(F::Sun::datetime);
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
        let sp = s.span_of(F::Sun::elevation);
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
