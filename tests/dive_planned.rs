//! Planned decompression as a verdict (issue 38): with `diver.deco = "planned"` a dive whose
//! decompression plan holds is "OK, decompression planned" with its plan; every other fault
//! (gas, pO₂, CNS, a hypoxic gas, the ceiling) stays NOT SAFE, and without the key a dive that
//! needs stops stays NOT SAFE.
use crate::support;
use poser::model::{CylinderRole, DecoMode};
use poser::plan::dive::*;
use std::process::Command;
use support::plan as common;
use support::plan::{cyl, flat_dive};

fn two_gas(sets: &[&str]) -> (String, bool) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.arg("dive").arg(format!(
        "{}/scenarios/two_gas_dive.toml",
        env!("CARGO_MANIFEST_DIR")
    ));
    for s in sets {
        c.arg("--set").arg(s);
    }
    let out = c.output().unwrap();
    (
        String::from_utf8_lossy(&out.stdout).to_string(),
        out.status.success(),
    )
}

#[test]
fn the_readme_two_gas_dive_is_ok_when_its_decompression_is_planned() {
    let (text, ok) = two_gas(&[]);
    assert!(
        ok && text.contains("Verdict: NOT SAFE AS PLANNED"),
        "{text}"
    );
    assert!(text.contains("✗ decompression obligation"), "{text}");
    let (text, ok) = two_gas(&["diver.deco=\"planned\""]);
    assert!(ok, "{text}");
    assert!(
        text.contains("Verdict: OK, decompression planned — the decompression plan holds"),
        "{text}"
    );
    // The plan itself: the stops, the switch to EAN50 at 21 m, the runtime; no remedies.
    assert!(
        text.contains("✓ decompression obligation")
            && text.contains("EAN50 at 21 m")
            && text.contains("runtime 23:20"),
        "{text}"
    );
    assert!(
        !text.contains('✗') && !text.contains("What would fix it"),
        "{text}"
    );
}

fn deco_diver() -> poser::model::Diver {
    let mut d = common::diver(24.0, 232.0);
    d.cylinders
        .push(cyl("deco", 11.0, 200.0, 0.5, 0.0, CylinderRole::Deco));
    d.deco = DecoMode::Planned;
    d
}

#[test]
fn planned_decompression_with_every_rule_kept_is_ok_with_its_plan() {
    let r = plan_dive(&flat_dive(30.0, 30.0, deco_diver()), 10.0).unwrap();
    assert!(r.dive.deco_required() && !r.dive.stops.is_empty());
    assert!(
        r.verdict.ok && r.verdict.deco_planned,
        "{:?}",
        r.verdict.problems
    );
    assert!(r.verdict.problems.is_empty() && r.verdict.suggestions.is_empty());
    assert!(
        r.verdict
            .deco_plan
            .as_deref()
            .unwrap()
            .contains("EAN50 at 21 m")
    );
    assert!(r.dive.ascent_ceiling_excess <= CEILING_TOLERANCE);
    // The same dive without the key is NOT SAFE, as before.
    let mut d = deco_diver();
    d.deco = DecoMode::None;
    let r = plan_dive(&flat_dive(30.0, 30.0, d), 10.0).unwrap();
    assert!(!r.verdict.ok && !r.verdict.deco_planned);
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("decompression"))
    );
}

#[test]
fn planned_decompression_stays_not_safe_for_every_other_fault() {
    // Too little gas: a 10 l back gas for 30 min at 30 m.
    let mut d = deco_diver();
    d.cylinders[0].volume = 0.010;
    let r = plan_dive(&flat_dive(30.0, 30.0, d), 10.0).unwrap();
    assert!(!r.verdict.ok && !r.verdict.deco_planned, "{:?}", r.verdict);
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("not enough gas"))
    );

    // A deco gas switched past its MOD (EAN50 at 27 m: pO₂ 1.88 bar).
    let mut d = deco_diver();
    d.cylinders[1].switch_depth = Some(27.0);
    let r = plan_dive(&flat_dive(30.0, 30.0, d), 10.0).unwrap();
    assert!(!r.verdict.ok && !r.verdict.deco_planned);
    assert!(r.verdict.problems.iter().any(|p| p.contains("pO₂")));

    // CNS beyond 100 %: EAN36 at 30 m (pO₂ 1.45 bar within a 1.5 bar limit) for 150 min.
    let mut d = deco_diver();
    d.cylinders[0].o2 = 0.36;
    d.cylinders[0].volume = 0.060;
    d.cylinders[1].volume = 0.030;
    d.po2_bottom = 1.5;
    let r = plan_dive(&flat_dive(30.0, 150.0, d), 10.0).unwrap();
    assert!(
        r.dive.oxygen.cns_percent > 100.0,
        "{}",
        r.dive.oxygen.cns_percent
    );
    assert!(!r.verdict.ok && !r.verdict.deco_planned);

    // A hypoxic bottom gas without a travel gas.
    let mut d = deco_diver();
    d.cylinders[0].o2 = 0.10;
    d.cylinders[0].he = 0.70;
    let r = plan_dive(&flat_dive(60.0, 10.0, d), 10.0).unwrap();
    assert!(!r.verdict.ok && !r.verdict.deco_planned);
}
