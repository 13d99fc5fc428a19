//! Lost-gas plans (issue 38): the decompression on the back gas (or the gases left) when a
//! travel or deco gas is lost at the end of the bottom time, and the ascent on the bailout when
//! the bottom gas is lost; each with its runtime and gas check, in the verdict.
use crate::support;
use poser::model::{CylinderRole, DecoMode};
use poser::plan::dive::*;
use std::process::Command;
use support::plan as common;
use support::plan::{cyl, flat_dive};

fn deco_diver(back_l: f64) -> poser::model::Diver {
    let mut d = common::diver(back_l, 232.0);
    d.cylinders
        .push(cyl("deco", 11.0, 200.0, 0.5, 0.0, CylinderRole::Deco));
    d.deco = DecoMode::Planned;
    d
}

#[test]
fn losing_the_deco_gas_means_a_longer_deco_on_the_back_gas() {
    let r = plan_dive(&flat_dive(30.0, 30.0, deco_diver(24.0)), 10.0).unwrap();
    assert!(
        r.verdict.ok && r.verdict.deco_planned,
        "{:?}",
        r.verdict.problems
    );
    let l = &r.verdict.lost_gas;
    assert_eq!(l.len(), 1, "{l:?}");
    let p = &l[0];
    assert_eq!(
        (p.kind.as_str(), p.lost.as_slice()),
        ("deco", &["deco".to_string()][..])
    );
    // Longer on air than on EAN50, more back gas breathed, the deco cylinder untouched after
    // the loss.
    assert!(
        p.runtime > r.dive.runtime + 60.0,
        "{} vs {}",
        p.runtime,
        r.dive.runtime
    );
    let back = &p.cylinders[0];
    assert!(back.2 > r.dive.gas.cylinders[0].used);
    assert_eq!(p.cylinders[1].2, 0.0);
    assert!(p.holds, "{:?}", p.faults);
}

#[test]
fn a_lost_gas_plan_that_runs_out_of_gas_is_not_safe() {
    // A planned decompression dive (45 m, 20 min, air and EAN50) that holds, with a bailout cylinder shrunk until the ascent
    // on it (the bottom gas lost at the end of the bottom time, EAN50 from 21 m) breathes it
    // empty: then the verdict is NOT SAFE for that reason alone.
    let mut found = None;
    let mut l = 11.0;
    while l > 0.5 {
        let mut d = deco_diver(24.0);
        d.cylinders
            .push(cyl("bailout", l, 200.0, 0.209, 0.0, CylinderRole::Bailout));
        let r = plan_dive(&flat_dive(45.0, 20.0, d), 10.0).unwrap();
        let bail = r
            .verdict
            .lost_gas
            .iter()
            .find(|p| p.kind == "bottom")
            .unwrap();
        if !bail.holds {
            found = Some((l, r));
            break;
        }
        assert!(
            r.verdict.ok && r.verdict.deco_planned,
            "{l} l: {:?}",
            r.verdict.problems
        );
        l -= 0.5;
    }
    let (l, r) = found.expect("some bailout size that runs out");
    assert!(!r.verdict.ok && !r.verdict.deco_planned, "{l} l");
    assert!(
        r.verdict
            .problems
            .iter()
            .all(|p| p.starts_with("lost-gas plan")),
        "{:?}",
        r.verdict.problems
    );
    assert!(
        r.verdict.problems[0].contains("'bailout' (air) is breathed empty"),
        "{:?}",
        r.verdict.problems
    );
}

#[test]
fn a_bailout_is_checked_by_its_own_ascent() {
    // Within the NDL: 20 m for 15 min on air, an EAN32 bailout. Its plan: the ascent from the
    // end of the bottom time on it.
    let mut d = common::diver(12.0, 232.0);
    d.cylinders
        .push(cyl("bailout", 7.0, 200.0, 0.32, 0.0, CylinderRole::Bailout));
    let r = plan_dive(&flat_dive(20.0, 15.0, d.clone()), 10.0).unwrap();
    assert!(r.verdict.ok, "{:?}", r.verdict.problems);
    let p = &r.verdict.lost_gas[0];
    assert_eq!(p.kind, "bottom");
    assert!(p.holds && p.cylinders[1].2 > 0.0, "{p:?}");
    // Pure O₂ as a bailout at 20 m: pO₂ 3 bar where it would be breathed — NOT SAFE.
    d.cylinders[1].o2 = 1.0;
    let r = plan_dive(&flat_dive(20.0, 15.0, d), 10.0).unwrap();
    assert!(!r.verdict.ok);
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.starts_with("lost-gas plan") && p.contains("pO₂")),
        "{:?}",
        r.verdict.problems
    );
}

#[test]
fn the_report_and_the_json_carry_the_lost_gas_plan() {
    let scene = format!("{}/scenarios/two_gas_dive.toml", env!("CARGO_MANIFEST_DIR"));
    let run = |json: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
        c.arg("dive")
            .arg(&scene)
            .arg("--set")
            .arg("diver.deco=\"planned\"");
        if json {
            c.arg("--json");
        }
        String::from_utf8(c.output().unwrap().stdout).unwrap()
    };
    let text = run(false);
    assert!(
        text.contains("lost gas    'deco' lost at the end of the bottom time: runtime"),
        "{text}"
    );
    let v: serde_json::Value = serde_json::from_str(&run(true)).unwrap();
    let l = &v["verdict"]["lost_gas"][0];
    assert_eq!(l["lost"][0], "deco");
    assert!(l["runtime"].as_f64().unwrap() > v["dive"]["runtime"].as_f64().unwrap());
}
