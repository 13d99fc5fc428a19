//! Gas roles (issue 38): bottom, stage, travel, deco and bailout cylinders, their switch depths
//! and the checks of each gas where it is breathed. A hypoxic trimix with a travel gas is no
//! longer NOT SAFE for being hypoxic; the same mix without one, or with a travel gas left too
//! shallow, still is.
use crate::support;
use poser::model::{CylinderRole, Diver};
use poser::plan::deco::{Environment, Gas};
use poser::plan::dive::*;
use poser::plan::gas::{breathable_from, end_depth, hypoxic_limit};
use support::plan as common;
use support::plan::{breathed, cyl, flat_dive};

/// Twin 12 l of `bottom` (O₂, He) at 232 bar, with the given further cylinders.
fn tech_diver(bottom: (f64, f64), more: Vec<poser::model::Cylinder>) -> Diver {
    let mut d = common::diver(24.0, 232.0);
    d.cylinders[0].o2 = bottom.0;
    d.cylinders[0].he = bottom.1;
    d.cylinders.extend(more);
    d
}

fn travel32() -> poser::model::Cylinder {
    cyl("travel", 11.0, 200.0, 0.32, 0.0, CylinderRole::Travel)
}

#[test]
fn hypoxic_trimix_with_an_ean32_travel_gas_is_not_hypoxic() {
    let env = Environment::SEA;
    // TX10/70 is hypoxic at the surface: breathable from 5.8 m (pO₂ 0.16 bar) down.
    let tx = Gas { o2: 0.10, he: 0.70 };
    assert!(tx.o2 * env.surface_pressure < hypoxic_limit(&env));
    let from = breathable_from(&env, tx);
    assert!((from - 5.8).abs() < 0.1, "{from}");

    // Without a travel gas: NOT SAFE, hypoxic (the cause named, with the cure).
    let alone = plan_dive(
        &flat_dive(60.0, 10.0, tech_diver((0.10, 0.70), vec![])),
        10.0,
    )
    .unwrap();
    assert!(alone.dive.gas.cylinders[0].hypoxic);
    assert!(!alone.verdict.ok && !alone.verdict.gases_ok);
    assert!(
        alone
            .verdict
            .problems
            .iter()
            .any(|p| p.contains("hypoxic") && p.contains("role = \"travel\"")),
        "{:?}",
        alone.verdict.problems
    );

    // With EAN32 as travel gas: it is breathed from the surface to 30 m (pO₂ 1.29 bar; END
    // 30 m, the limit) and from 30 m up; the trimix only deeper. Nothing is hypoxic.
    let r = plan_dive(
        &flat_dive(60.0, 10.0, tech_diver((0.10, 0.70), vec![travel32()])),
        10.0,
    )
    .unwrap();
    assert_eq!(r.config.tanks[1].switch_depth, Some(30.0));
    let g = &r.dive.gas;
    assert!(g.cylinders.iter().all(|c| !c.hypoxic && c.po2_ok), "{g:#?}");
    assert!(r.verdict.gases_ok, "{:?}", r.verdict.problems);
    assert!(
        !r.verdict
            .problems
            .iter()
            .any(|p| p.contains("hypoxic") || p.contains("pO₂")),
        "{:?}",
        r.verdict.problems
    );
    // The order: travel from the surface, the bottom gas from 30 m, the travel gas again on
    // the way up at 30 m.
    let s = &r.dive.switches;
    assert_eq!(s[0].cylinder, 1);
    assert_eq!(s[1].cylinder, 0);
    assert!((s[1].depth - 30.0).abs() < 1e-6, "{s:?}");
    assert!(
        s.iter()
            .skip(2)
            .any(|x| x.cylinder == 1 && x.depth <= 30.0 + 1e-6),
        "{s:?}"
    );
    // Independently of the per-cylinder flags: the trimix is never breathed shallower than
    // 30 m, and every gas's pO₂ where breathed is within its limits.
    for (c, depth) in breathed(&r) {
        let gas = r.config.tanks[c].gas;
        let p = env.pressure(depth) * gas.o2;
        assert!(
            p >= hypoxic_limit(&env) - 1e-9,
            "cylinder {c} at {depth} m: {p}"
        );
        assert!(p <= 1.4 + 1e-9, "cylinder {c} at {depth} m: {p}");
        if c == 0 {
            assert!(depth >= 30.0 - 1e-6, "trimix at {depth} m");
        }
    }
    // The travel gas's END where it is breathed is within the 30 m limit.
    let t = &g.cylinders[1];
    assert!(Gas { o2: 0.32, he: 0.0 }.end(&env, t.max_po2_depth) <= 30.0 + 1e-6);
}

#[test]
fn a_travel_gas_left_too_shallow_makes_the_bottom_gas_hypoxic() {
    // TX10/70 is breathable from 5.8 m; a travel gas left at 3 m hands over too early.
    let mut t = travel32();
    t.switch_depth = Some(3.0);
    let r = plan_dive(
        &flat_dive(60.0, 10.0, tech_diver((0.10, 0.70), vec![t])),
        10.0,
    )
    .unwrap();
    let c = &r.dive.gas.cylinders[0];
    assert!(c.hypoxic, "{c:?}");
    assert!(c.min_po2_depth < 5.8 && c.min_po2.unwrap() < 0.16, "{c:?}");
    assert!(!r.verdict.ok && !r.verdict.gases_ok);
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("hypoxic") && p.contains("from 6 m down")),
        "{:?}",
        r.verdict.problems
    );
}

#[test]
fn travel_switch_depth_defaults_within_po2_and_end_and_is_checked() {
    let env = Environment::SEA;
    let ean32 = Gas { o2: 0.32, he: 0.0 };
    // MOD at 1.4 bar 33.3 m, END limit 30 m → 30 m; with a 40 m END limit the MOD rules: 33 m.
    assert!((ean32.mod_depth(&env, 1.4) - 33.27).abs() < 0.05);
    assert!((end_depth(&env, ean32, 30.0) - 30.0).abs() < 1e-9);
    let cfg = |end: f64, sw: Option<f64>| {
        let mut t = travel32();
        t.switch_depth = sw;
        let mut d = tech_diver((0.18, 0.45), vec![t]);
        d.end_limit = end;
        flat_dive(50.0, 8.0, d)
    };
    let c = DiveConfig::from_model(&cfg(30.0, None)).unwrap();
    assert_eq!(c.tanks[1].switch_depth, Some(30.0));
    let c = DiveConfig::from_model(&cfg(40.0, None)).unwrap();
    assert_eq!(c.tanks[1].switch_depth, Some(33.0));

    // Switched at 33 m with the 30 m END limit: within pO₂, past the END — NOT SAFE, named.
    let r = plan_dive(&cfg(30.0, Some(33.0)), 10.0).unwrap();
    assert!(r.dive.gas.cylinders[1].po2_ok);
    assert!(!r.verdict.ok);
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("travel gas 'travel'") && p.contains("END")),
        "{:?}",
        r.verdict.problems
    );
    // Switched at 36 m: past its MOD as well.
    let r = plan_dive(&cfg(40.0, Some(36.0)), 10.0).unwrap();
    assert!(!r.dive.gas.cylinders[1].po2_ok && !r.verdict.ok);
}

#[test]
fn within_the_ndl_the_ascent_returns_to_the_travel_gas() {
    // TX10/50 at 20 m for 10 min (within the NDL): a travel gas down to the bottom, and on
    // the direct ascent with its safety stop the travel gas again, so the hypoxic mix is never
    // breathed in the shallows. No decompression, no deco gas: OK.
    let r = plan_dive(
        &flat_dive(20.0, 10.0, tech_diver((0.10, 0.50), vec![travel32()])),
        10.0,
    )
    .unwrap();
    assert!(!r.dive.deco_required(), "{:?}", r.dive.stops);
    assert!(r.dive.safety_stop.is_some());
    assert!(r.verdict.ok, "{:?}", r.verdict.problems);
    let s = &r.dive.switches;
    assert_eq!((s[0].cylinder, s[1].cylinder), (1, 0), "{s:?}");
    assert!(
        (s[1].depth - 20.0).abs() < 1e-6,
        "switch at the bottom: {s:?}"
    );
    assert_eq!(s.last().unwrap().cylinder, 1, "{s:?}");
    let env = Environment::SEA;
    for (c, depth) in breathed(&r) {
        if c == 0 {
            assert!(env.pressure(depth) * 0.10 >= 0.16, "trimix at {depth} m");
        }
    }
}

#[test]
fn a_bailout_cylinder_is_not_breathed_in_the_plan() {
    let bail = cyl("bailout", 7.0, 200.0, 0.21, 0.0, CylinderRole::Bailout);
    let r = plan_dive(
        &flat_dive(20.0, 10.0, tech_diver((0.32, 0.0), vec![bail])),
        10.0,
    )
    .unwrap();
    let b = &r.dive.gas.cylinders[1];
    assert_eq!(b.used, 0.0);
    assert!(b.max_po2.is_none());
    assert!(r.dive.switches.iter().all(|s| s.cylinder != 1));
    // It is not pooled with the bottom gas either.
    assert!((r.dive.gas.start - r.config.tanks[0].start).abs() < 1e-9);
}

#[test]
fn stage_then_back_gas_then_travel_on_the_ascent() {
    // A stage of the bottom mix is breathed first on the bottom (after the travel gas), down to
    // its reserve, then the back gas; the ascent returns to the travel gas.
    let stage = cyl("stage", 11.0, 200.0, 0.18, 0.45, CylinderRole::Stage);
    let mut d = tech_diver((0.18, 0.45), vec![travel32()]);
    d.cylinders.insert(0, stage);
    let r = plan_dive(&flat_dive(45.0, 20.0, d), 10.0).unwrap();
    let order: Vec<usize> = r.dive.switches.iter().map(|s| s.cylinder).collect();
    // Cylinders: 0 stage, 1 back, 2 travel.
    assert_eq!(&order[..3], &[2, 0, 1], "{order:?}");
    assert!(order[3..].contains(&2), "{order:?}");
    let g = &r.dive.gas;
    assert!((g.cylinders[0].end_pressure - 50.0).abs() < 2.0, "{g:?}");
    assert!(g.cylinders.iter().all(|c| c.reserve_ok), "{g:?}");
}
