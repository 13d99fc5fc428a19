//! Dive safety, round two (issue 38): the gas the planner names is within the pO₂ and END
//! limits at the depth it is named for (a property test on the pure function, and through the
//! verdict); MODs and switch depths shown to a diver are rounded down; air is one gas however
//! the scene spells it; a deco gas at its reserve hands over to the back gas and the rest of
//! the ascent is planned on the gas breathed.
use crate::support;
use poser::model::{CylinderRole, Model};
use poser::plan::deco::{Environment, Gas};
use poser::plan::dive::*;
use poser::plan::gas::{MAX_BOTTOM_O2, bottom_gas, depth_limit, hypoxic_limit};
use poser::scene::resolve::parse_gas;
use proptest::prelude::*;
use std::path::Path;
use std::process::Command;
use support::plan as common;
use support::plan::{cyl, flat_dive};

fn scenario(name: &str) -> String {
    format!("{}/scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

fn load(name: &str, sets: &[&str]) -> Model {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match poser::scene::load(Path::new(&scenario(name)), &sets) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

/// The independent checks of a named gas at `depth`: pO₂ and END (O₂ narcotic: the narcotic
/// pressure is P·(1 − He), air's at the END limit is the ambient pressure there).
fn within_limits(
    env: &Environment,
    gas: Gas,
    depth: f64,
    po2: f64,
    end: f64,
) -> Result<(), String> {
    let p = env.surface_pressure + depth * env.water_density * 0.981e-4;
    let p_end = env.surface_pressure + end * env.water_density * 0.981e-4;
    if !(gas.o2 > 0.0 && gas.he >= 0.0 && gas.o2 + gas.he <= 1.0 + 1e-9) {
        return Err(format!("not a mix: {gas:?}"));
    }
    if gas.o2 * p > po2 + 1e-9 {
        return Err(format!("{gas:?} at {depth} m: pO₂ {} > {po2}", gas.o2 * p));
    }
    if p * (1.0 - gas.he) > p_end + 1e-9 {
        return Err(format!(
            "{gas:?} at {depth} m: narcotic {} bar > {} bar (END limit {end} m)",
            p * (1.0 - gas.he),
            p_end
        ));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// For every depth 0–100 m, pO₂ limit 1.0–1.6 bar, END limit 20–50 m, sea or fresh water
    /// at up to 3000 m altitude: the suggested gas keeps pO₂ ≤ limit and END ≤ limit at that
    /// depth; a gas hypoxic at the surface comes with a travel gas that is itself within both
    /// limits where the bottom gas takes over, and breathable at the surface. And it is the
    /// richest such gas to the percent (no trivially "safe" 1 % O₂ answer).
    #[test]
    fn suggested_gas_is_within_the_po2_and_end_limits(
        depth in 0.0f64..=100.0,
        po2 in 1.0f64..=1.6,
        end in 20.0f64..=50.0,
        salt in proptest::bool::ANY,
        altitude in prop_oneof![Just(0.0), 0.0f64..3000.0],
    ) {
        let env = Environment::new(salt, altitude);
        let b = bottom_gas(&env, depth, po2, end);
        prop_assert!(b.is_some(), "no gas at {depth} m (pO₂ {po2}, END {end})");
        let b = b.unwrap();
        if let Err(e) = within_limits(&env, b.gas, depth, po2, end) {
            prop_assert!(false, "{}", e);
        }
        let p = env.pressure(depth);
        let hyp = hypoxic_limit(&env);
        match b.travel {
            None => prop_assert!(b.gas.o2 * env.surface_pressure >= hyp, "{b:?}"),
            Some((travel, from)) => {
                prop_assert!(b.gas.o2 * env.surface_pressure < hyp, "{b:?}");
                prop_assert!(from <= depth && b.gas.o2 * env.pressure(from) >= hyp, "{b:?}");
                if let Err(e) = within_limits(&env, travel, from, po2, end) {
                    prop_assert!(false, "travel gas: {}", e);
                }
                prop_assert!(travel.o2 * env.surface_pressure >= hyp, "{b:?}");
            }
        }
        // Richest to the percent: one more percent of O₂ or one less of He breaks a limit
        // (or the EAN40 cap); air counts as 21 %.
        let o2 = (b.gas.o2 * 100.0).round() / 100.0;
        prop_assert!(
            (o2 + 0.01) * p > po2 || (o2 + 0.01) > MAX_BOTTOM_O2 + 1e-9
                || p * (1.0 - b.gas.he) > env.pressure(end) * (1.0 - 1e-12)
                || o2 + 0.01 + b.gas.he > 1.0 + 1e-9,
            "O₂ could be richer: {b:?} at {depth} m"
        );
        if b.gas.he > 0.0 {
            prop_assert!(
                p * (1.0 - (b.gas.he - 0.01)) > env.pressure(end),
                "more He than the END needs: {b:?} at {depth} m"
            );
        }
    }
}

/// The gas named in the "breathable gases" suggestion, parsed back from its text.
fn named_gas(text: &str) -> Gas {
    let name = text
        .split("e.g. ")
        .nth(1)
        .and_then(|t| t.split([';', ' ']).next())
        .unwrap_or_else(|| panic!("no gas named: {text}"));
    let (o2, he) = parse_gas(name).unwrap_or_else(|| panic!("not a gas `{name}`: {text}"));
    Gas { o2, he }
}

fn gas_suggestion(r: &DiveReport) -> String {
    r.verdict
        .suggestions
        .iter()
        .find(|s| s.kind == "gas")
        .unwrap_or_else(|| panic!("no gas advice: {:?}", r.verdict))
        .text
        .clone()
}

#[test]
fn gas_advice_never_names_a_gas_beyond_its_limits() {
    // The cases: air at 60 m (pO₂ 1.49 bar, END 60 m) was "e.g. air"; with a 1.0 bar
    // bottom limit at 40 m, air was flagged and then named as the fix.
    let deep = plan_dive(&flat_dive(60.0, 5.0, common::diver(24.0, 232.0)), 10.0).unwrap();
    let mut d = common::diver(24.0, 232.0);
    d.po2_bottom = 1.0;
    let strict = plan_dive(&flat_dive(40.0, 5.0, d), 10.0).unwrap();
    for (r, depth, po2) in [(&deep, 60.0, 1.4), (&strict, 40.0, 1.0)] {
        assert!(!r.verdict.gases_ok, "{:?}", r.verdict);
        let text = gas_suggestion(r);
        assert!(!text.contains("e.g. air"), "{text}");
        let gas = named_gas(&text);
        within_limits(&r.config.env, gas, depth, po2, 30.0)
            .unwrap_or_else(|e| panic!("{e}: {text}"));
        // Deeper than the END limit: trimix, and the text says why.
        assert!(
            gas.he > 0.0 && text.contains("He for an END within 30 m"),
            "{text}"
        );
    }
}

#[test]
fn narcosis_beyond_the_end_limit_is_advised_and_the_limit_comes_from_the_scene() {
    // 35 m on air: END 35 m, past the default 30 m: advice (not a failing problem) naming a gas
    // within both limits; a scene's `end_limit = "40 m"` takes it back.
    let r = plan_dive(&flat_dive(35.0, 5.0, common::diver(24.0, 232.0)), 10.0).unwrap();
    let advice = r
        .verdict
        .advice
        .iter()
        .find(|a| a.contains("narcosis"))
        .expect("END advice");
    assert!(advice.contains("30 m END limit"), "{advice}");
    let mut d = common::diver(24.0, 232.0);
    d.end_limit = 40.0;
    let r = plan_dive(&flat_dive(35.0, 5.0, d), 10.0).unwrap();
    assert!(
        !r.verdict.advice.iter().any(|a| a.contains("narcosis")),
        "{:?}",
        r.verdict.advice
    );

    // Through the front end: the key, its default, its check.
    let m = load("paper_survey", &[]);
    assert_eq!(m.diver.as_ref().unwrap().end_limit, 30.0);
    let m = load("paper_survey", &["diver.end_limit=\"40 m\""]);
    assert_eq!(m.diver.as_ref().unwrap().end_limit, 40.0);
    let bad = poser::scene::load(
        Path::new(&scenario("paper_survey")),
        &["diver.end_limit=\"0 m\"".to_string()],
    );
    let err = bad.err().expect("END limit 0 m is refused").render();
    assert!(err.contains("E0327") && err.contains("end_limit"), "{err}");
}

#[test]
fn nitrox_remedy_keeps_the_divers_po2_limit() {
    // 25 m past the NDL on air with a 1.2 bar bottom limit: the nitrox remedy was checked
    // and shown at 1.4 bar (EAN36, pO₂ 1.29 bar at 25 m, passed that check).
    let mut d = common::diver(36.0, 232.0);
    d.po2_bottom = 1.2;
    let r = plan_dive(&flat_dive(25.0, 20.0, d), 10.0).unwrap();
    assert!(r.verdict.deco_required);
    let env = r.config.env;
    let nitrox: Vec<_> = r
        .verdict
        .suggestions
        .iter()
        .filter(|s| s.kind == "nitrox")
        .collect();
    assert!(!nitrox.is_empty(), "{:?}", r.verdict.suggestions);
    for s in nitrox {
        let o2: f64 = s.text["nitrox: EAN".len()..][..2].parse().unwrap();
        assert!(o2 / 100.0 * env.pressure(25.0) <= 1.2, "{}", s.text);
        assert!(s.text.contains("at pO₂ 1.2"), "{}", s.text);
    }
}

fn dive_text(name: &str, sets: &[&str]) -> String {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.arg("dive").arg(scenario(name));
    for s in sets {
        c.arg("--set").arg(s);
    }
    let out = c.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

#[test]
fn mods_shown_to_the_diver_are_rounded_down() {
    // EAN50's MOD at 1.6 bar in sea water is 21.6 m, O₂'s 5.8 m: shown 21 m and 5 m, never
    // 22 m and 6 m.
    let env = Environment::SEA;
    let ean50 = Gas { o2: 0.5, he: 0.0 }.mod_depth(&env, 1.6);
    let oxygen = Gas { o2: 1.0, he: 0.0 }.mod_depth(&env, 1.6);
    assert!(
        ean50.fract() > 0.5 && oxygen.fract() > 0.5,
        "{ean50} {oxygen}"
    );
    let o2 = "diver.cylinders=[{name = \"back\", volume = \"12 l\", pressure = \"232 bar\", \
              gas = \"air\"}, {name = \"deco\", volume = \"7 l\", pressure = \"200 bar\", \
              gas = \"EAN50\"}, {name = \"oxygen\", volume = \"3 l\", pressure = \"200 bar\", \
              gas = \"O2\"}]";
    let text = dive_text("two_gas_dive", &[o2]);
    assert!(text.contains("EAN50 (deco from 21 m, MOD 21 m)"), "{text}");
    assert!(text.contains("O₂ (deco from 5 m, MOD 5 m)"), "{text}");
    assert!(
        !text.contains("MOD 22 m") && !text.contains("MOD 6 m"),
        "{text}"
    );
    // A deco gas breathed too deep: the problem's MOD is rounded down too (was `{:.1}`,
    // rounding 21.56 m up to 21.6 m).
    let mut d = common::diver(24.0, 232.0);
    let mut c = cyl("deco", 7.0, 200.0, 0.5, 0.0, CylinderRole::Deco);
    c.switch_depth = Some(27.0);
    d.cylinders.push(c);
    let r = plan_dive(&flat_dive(40.0, 20.0, d), 10.0).unwrap();
    let p = r
        .verdict
        .problems
        .iter()
        .find(|p| p.contains("'deco'"))
        .expect("EAN50 from 27 m is too deep");
    assert!(
        p.contains("(MOD 21 m)") && p.contains("switch depth is 27 m"),
        "{p}"
    );
    assert_eq!(depth_limit(ean50), 21.0);
}

#[test]
fn air_is_one_gas_whatever_its_spelling() {
    // The paper's diver is the default diver with `gas = "air"` written out; without a
    // [diver], with a cylinder that names no gas, and with "air": one plan, to the second.
    let named = load("paper_survey", &["network.strips=4"]);
    let mut none = named.clone();
    none.diver = None;
    let unnamed = load(
        "paper_survey",
        &[
            "network.strips=4",
            "diver.cylinders=[{name = \"12 l\", volume = \"12 l\", pressure = \"200 bar\"}]",
        ],
    );
    assert_eq!(named.diver.as_ref().unwrap().cylinders[0].o2, Gas::AIR.o2);
    let plans: Vec<DiveReport> = [&named, &none, &unnamed]
        .iter()
        .map(|m| plan_dive(m, 10.0).unwrap())
        .collect();
    let key = |r: &DiveReport| {
        (
            r.dive.min_ndl,
            r.dive.deco_from,
            r.dive.runtime,
            r.dive.stops.clone(),
            r.dive.gas.used,
            r.dive
                .samples
                .iter()
                .map(|s| (s.ndl, s.ceiling))
                .collect::<Vec<_>>(),
        )
    };
    assert!(plans[0].dive.min_ndl.is_some(), "a dive with an NDL margin");
    for r in &plans[1..] {
        assert_eq!(key(r), key(&plans[0]));
        assert_eq!(r.config.tanks[0].gas, Gas::AIR);
    }
}

#[test]
fn deco_gas_at_its_reserve_hands_over_to_the_back_gas() {
    // 40 m for 25 min on air, O₂ from 5 m in a small cylinder (2 l at 150 bar): its gas above
    // the 50 bar reserve runs out at the 3 m stop. The diver goes back to the back gas there (it was
    // breathed down to 30 bar while the back gas was never touched), and the rest of the stop
    // is planned on air: longer than with O₂ to the end, and never above the ceiling.
    let dive = |o2_litres: f64| {
        let mut d = common::diver(24.0, 232.0);
        d.cylinders.push(cyl(
            "oxygen",
            o2_litres,
            150.0,
            1.0,
            0.0,
            CylinderRole::Deco,
        ));
        plan_dive(&flat_dive(40.0, 25.0, d), 10.0).unwrap()
    };
    let small = dive(2.0);
    let large = dive(40.0);
    let o2 = &small.dive.gas.cylinders[1];
    assert!(o2.used > 0.0, "{o2:?}");
    assert!(o2.reserve_ok && o2.end_pressure >= 49.0, "{o2:?}");
    // Breathed O₂ first, then back to the back gas.
    let to_o2 = small
        .dive
        .switches
        .iter()
        .position(|s| s.cylinder == 1)
        .expect("switch to O₂");
    let back = small.dive.switches[to_o2..]
        .iter()
        .find(|s| s.cylinder == 0)
        .expect("back to the back gas");
    assert!(back.depth <= 5.0 + 1e-6, "{back:?}");
    // The large O₂ cylinder is breathed to the end: no hand-over there.
    assert!(
        !large.dive.switches.iter().skip(1).any(|s| s.cylinder == 0),
        "{:?}",
        large.dive.switches
    );
    let total = |r: &DiveReport| r.dive.stops.iter().map(|s| s.duration).sum::<f64>();
    assert!(
        total(&small) > total(&large) + 60.0,
        "{} vs {}",
        total(&small),
        total(&large)
    );
    // Stops computed on the gas breathed: the ceiling never above the diver.
    for s in small
        .dive
        .samples
        .iter()
        .filter(|s| s.time > small.dive.descent_time + small.dive.bottom_time)
    {
        assert!(
            s.ceiling <= s.depth + 0.05,
            "ceiling {} above the diver at {} m, {} s",
            s.ceiling,
            s.depth,
            s.time
        );
    }
    assert!(
        small.dive.gas.cylinders[0].reserve_ok,
        "{:?}",
        small.dive.gas
    );
}

#[test]
fn stage_at_its_reserve_on_the_ascent_hands_over_to_the_back_gas() {
    // An EAN32 stage sized (from a first run of the same dive) to reach its reserve halfway
    // up a decompression ascent: the ascent goes on on the back gas (air), planned again on
    // it, and the stage keeps its reserve.
    let dive = |stage_bar: f64| {
        let mut d = common::diver(24.0, 232.0);
        d.cylinders.insert(
            0,
            cyl("stage", 20.0, stage_bar, 0.32, 0.0, CylinderRole::Stage),
        );
        plan_dive(&flat_dive(30.0, 30.0, d), 10.0).unwrap()
    };
    let full = dive(300.0);
    assert!(full.verdict.deco_required && full.dive.gas.cylinders[0].reserve_ok);
    let bottom_end = full.dive.descent_time + full.dive.bottom_time;
    let at_end = full
        .dive
        .samples
        .iter()
        .find(|s| s.time >= bottom_end - 1e-6)
        .unwrap();
    // Litres the stage gives on the bottom and on the ascent, from the first run.
    let ean32 = Gas { o2: 0.32, he: 0.0 };
    let tank = &full.config.tanks[0];
    let used_bottom = tank.start - poser::plan::gas::contents(ean32, 20.0, at_end.pressures[0]);
    let used_ascent = full.dive.gas.cylinders[0].used - used_bottom;
    assert!(used_ascent > 100.0, "{used_ascent}");
    let reserve = poser::plan::gas::contents(ean32, 20.0, 50.0);
    let bar =
        poser::plan::gas::pressure_for(ean32, 20.0, reserve + used_bottom + 0.5 * used_ascent);
    let r = dive(bar);
    let stage = &r.dive.gas.cylinders[0];
    assert!(stage.reserve_ok && stage.end_pressure >= 49.0, "{stage:?}");
    let back = r
        .dive
        .switches
        .iter()
        .find(|s| s.cylinder == 1)
        .expect("back gas breathed");
    assert!(back.time > bottom_end, "{back:?} before the ascent");
    assert!(r.dive.gas.cylinders[1].used > 0.0);
    for s in r.dive.samples.iter().filter(|s| s.time > bottom_end) {
        assert!(
            s.ceiling <= s.depth + 0.05,
            "ceiling {} above the diver at {} m, {} s",
            s.ceiling,
            s.depth,
            s.time
        );
    }
}
