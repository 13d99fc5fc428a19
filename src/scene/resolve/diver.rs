//! The `[diver]` who carries the camera: swimming speed, descent and ascent rates, gas
//! consumption (SAC), gradient factors, pO₂ limits, reserve, and the `[[diver.cylinders]]`
//! with their gas (named like `"EAN32"` or `"TX18/45"` by [`parse_gas`], or given as
//! fractions) and role. Dive planning itself is in [`crate::plan`].

use crate::model::*;
use crate::plan::deco::Gas;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span, num};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::Node;
use crate::units::Dim;

/// `[diver]`, when present; without cylinders the diver breathes one 12 l tank of air. Air is
/// [`Gas::AIR`] (20.9 % O₂) wherever it comes from: the default cylinder, a cylinder without a
/// gas, `gas = "air"`.
pub(super) fn diver(cx: &mut Cx, node: Option<&Node>, fallback: Span) -> Option<Diver> {
    node?;
    let mut d = Tab::open(cx, node, F::Scene::diver, fallback);
    let speed = d.f64(cx, F::Diver::speed, Dim::Speed, 0.2);
    let descent_rate = d.f64(cx, F::Diver::descent_rate, Dim::Speed, 18.0 / 60.0);
    let ascent_rate = d.f64(cx, F::Diver::ascent_rate, Dim::Speed, 9.0 / 60.0);
    let sac = d.f64(cx, F::Diver::sac, Dim::Flow, 20e-3 / 60.0);
    for (k, v, u) in [
        (F::Diver::speed, speed, "m/s"),
        (F::Diver::descent_rate, descent_rate, "m/s"),
        (F::Diver::ascent_rate, ascent_rate, "m/s"),
        (F::Diver::sac, sac, "m³/s"),
    ] {
        check::positive(cx, &d, k, v, u);
    }
    // Subsurface's default gradient factors, 30/75 (its `core/pref.cpp`), as without [diver].
    let gf_low = d.f64(cx, F::Diver::gf_low, Dim::Fraction, 0.3);
    let gf_high = d.f64(cx, F::Diver::gf_high, Dim::Fraction, 0.75);
    for (k, v) in [(F::Diver::gf_low, gf_low), (F::Diver::gf_high, gf_high)] {
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
        let sp = d.span_of(F::Diver::gf_low);
        cx.push(
            Diagnostic::error("E0320", "`gf_low` is above `gf_high`")
                .label(sp, format!("{} > {}", num(gf_low), num(gf_high)))
                .help("the low gradient factor applies at depth and must not exceed the high one (e.g. 30/70)"),
        );
    }
    let reserve = d.f64(cx, F::Diver::reserve, Dim::Pressure, 50e5);
    let po2_bottom = d.f64(cx, F::Diver::po2_bottom, Dim::Pressure, 1.4e5) / 1e5;
    let po2_deco = d.f64(cx, F::Diver::po2_deco, Dim::Pressure, 1.6e5) / 1e5;
    for (k, v) in [
        (F::Diver::po2_bottom, po2_bottom),
        (F::Diver::po2_deco, po2_deco),
    ] {
        if !(v.is_finite() && (0.16..=2.0).contains(&v)) {
            let sp = d.span_of(k);
            cx.push(
                Diagnostic::error("E0324", format!("`{k}` must be a pO₂ limit in 0.16…2 bar"))
                    .label(sp, format!("{} bar", num(v)))
                    .help(format!(
                        "Subsurface's limits are 1.4 bar on the bottom and 1.6 bar for deco gases: `{k} = \"{}\"`",
                        if k == F::Diver::po2_deco { "1.6 bar" } else { "1.4 bar" }
                    )),
            );
        }
    }
    let end_limit = d.f64(cx, F::Diver::end_limit, Dim::Length, DEFAULT_END_LIMIT);
    if !(end_limit.is_finite() && end_limit > 0.0 && end_limit <= 100.0) {
        let sp = d.span_of(F::Diver::end_limit);
        cx.push(
            Diagnostic::error("E0327", "`end_limit` must be a depth in (0, 100] m")
                .label(sp, format!("{} m", num(end_limit)))
                .help("the deepest equivalent narcotic depth a gas may have, customarily 30 m: `end_limit = \"30 m\"`"),
        );
    }
    let salt_water = !matches!(
        d.choice(cx, F::Diver::water, &["salt", "fresh"]),
        Some("fresh")
    );
    let deco = match d.choice(cx, F::Diver::deco, &["none", "planned"]) {
        Some("planned") => DecoMode::Planned,
        _ => DecoMode::None,
    };
    let mut cylinders: Vec<Cylinder> = Vec::new();
    for (i, n) in d.tables(cx, F::Diver::cylinders).into_iter().enumerate() {
        let c = cylinder(cx, i, n, cylinders.first());
        cylinders.push(c);
    }
    if cylinders.is_empty() {
        cylinders.push(Cylinder {
            name: "back".into(),
            volume: 0.012,
            pressure: 200e5,
            o2: Gas::AIR.o2,
            he: 0.0,
            role: CylinderRole::Bottom,
            switch_depth: None,
        });
    }
    if !cylinders.iter().any(|c| c.role.is_bottom()) {
        let sp = d.span_of(F::Diver::cylinders);
        cx.push(
            Diagnostic::error(
                "E0326",
                "no bottom gas: every cylinder is a travel, deco or bailout gas",
            )
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
        end_limit,
        deco,
    })
}

/// One `[[diver.cylinders]]` entry: size, fill pressure, gas and role; `first` is the
/// list's first cylinder, if any (the back gas, against which the default role is decided).
fn cylinder(cx: &mut Cx, i: usize, n: &Node, first: Option<&Cylinder>) -> Cylinder {
    let mut c = Tab::open(cx, Some(n), &format!("diver.cylinders[{i}]"), n.span);
    let name = c
        .opt_str(cx, F::CylinderTable::name)
        .unwrap_or_else(|| format!("cylinder{i}"));
    let volume = c.f64(cx, F::CylinderTable::volume, Dim::Volume, 0.012);
    let pressure = c.f64(cx, F::CylinderTable::pressure, Dim::Pressure, 200e5);
    check::positive(cx, &c, F::CylinderTable::volume, volume, "m³");
    check::positive(cx, &c, F::CylinderTable::pressure, pressure, "Pa");
    let gas_span = c.span_of(F::CylinderTable::gas);
    let (mut o2, mut he) = match c.opt_str(cx, F::CylinderTable::gas) {
        None => (Gas::AIR.o2, 0.0),
        Some(g) => match parse_gas(&g) {
            Some(x) => x,
            None => {
                cx.push(
                    Diagnostic::error("E0321", format!("unknown gas `{g}`"))
                        .label(gas_span, "not a gas name")
                        .help("write \"air\", \"EAN32\" (nitrox 32 % O₂), \"TX18/45\" (trimix), \"O2\", or give `o2`/`he` fractions"),
                );
                (Gas::AIR.o2, 0.0)
            }
        },
    };
    if let Some(x) = c.opt_f64(cx, F::CylinderTable::o2, Dim::Fraction) {
        o2 = x;
    }
    if let Some(x) = c.opt_f64(cx, F::CylinderTable::he, Dim::Fraction) {
        he = x;
    }
    let mut mix_ok = true;
    for (k, v, lo) in [
        (F::CylinderTable::o2, o2, 0.0),
        (F::CylinderTable::he, he, -1e-12),
    ] {
        if !(v > lo && v <= 1.0 + 1e-12) {
            mix_ok = false;
            let sp = c.span_of(if c.has(k) { k } else { F::CylinderTable::gas });
            cx.push(
                Diagnostic::error("E0322", format!("`{k}` fraction out of range"))
                    .label(
                        sp,
                        format!(
                            "{} is not a fraction in {}",
                            num(v),
                            if k == F::CylinderTable::o2 {
                                "(0, 1]"
                            } else {
                                "[0, 1]"
                            }
                        ),
                    )
                    .help(format!(
                        "gas fractions are parts of one: `{k} = 0.32` or `{k} = \"32 %\"`"
                    )),
            );
        }
    }
    if mix_ok && o2 + he > 1.0 + 1e-12 {
        let sp = c.span_of(if c.has(F::CylinderTable::he) {
            F::CylinderTable::he
        } else if c.has(F::CylinderTable::o2) {
            F::CylinderTable::o2
        } else {
            F::CylinderTable::gas
        });
        cx.push(
            Diagnostic::error("E0322", "impossible gas mix: O₂ + He exceed the whole")
                .label(sp, format!("O₂ {} + He {} = {} > 1", num(o2), num(he), num(o2 + he)))
                .help("the fractions of O₂ and He must add up to at most 1 (the rest is N₂), e.g. TX18/45: `o2 = 0.18`, `he = 0.45`"),
        );
    }
    let role_given = c.choice(
        cx,
        F::CylinderTable::role,
        &["bottom", "stage", "travel", "deco", "bailout"],
    );
    let role = match role_given {
        Some("stage") => CylinderRole::Stage,
        Some("travel") => CylinderRole::Travel,
        Some("deco") => CylinderRole::Deco,
        Some("bailout") => CylinderRole::Bailout,
        Some(_) => CylinderRole::Bottom,
        // No role given: the first cylinder is the back gas; a later richer gas is for deco.
        None => match first {
            Some(first) if o2 > first.o2 + 1e-9 => CylinderRole::Deco,
            _ => CylinderRole::Bottom,
        },
    };
    let sw_span = c.span_of(F::CylinderTable::switch_depth);
    let switch_depth = c.opt_f64(cx, F::CylinderTable::switch_depth, Dim::Length);
    if let Some(sw) = switch_depth {
        if !(sw.is_finite() && sw >= 0.0) {
            cx.push(
                Diagnostic::error("E0325", "`switch_depth` must be a depth ≥ 0")
                    .label(sw_span, format!("{} m", num(sw)))
                    .help("the depth from which the deco gas is breathed, e.g. `switch_depth = \"21 m\"` for EAN50"),
            );
        } else if !role.switched() {
            cx.push(
                Diagnostic::error(
                    "E0325",
                    "`switch_depth` is only for travel and deco cylinders",
                )
                .label(sw_span, "this cylinder is neither a travel nor a deco gas")
                .help("add `role = \"deco\"` or `role = \"travel\"`, or remove `switch_depth`"),
            );
        }
    }
    c.finish(cx);
    Cylinder {
        name,
        volume,
        pressure,
        o2,
        he,
        role,
        switch_depth,
    }
}

/// `"air"` ([`Gas::AIR`], 20.9 % O₂), `"EAN32"`, `"nitrox32"`, `"TX18/45"`, `"O2"` → (O₂,
/// He) fractions.
pub fn parse_gas(s: &str) -> Option<(f64, f64)> {
    let u = s.trim().to_uppercase().replace(' ', "");
    if u == "AIR" {
        return Some((Gas::AIR.o2, Gas::AIR.he));
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
