//! Dive safety: every cylinder with its own gas (pO₂/MOD and hypoxic checks, deco gas
//! switches, per-cylinder accounting), one criterion for "in decompression" (the ceiling), and
//! a property test that a verdict never calls a dangerous plan OK.
use crate::support;
use poser::model::{CylinderRole, DecoMode};
use poser::plan::deco::{Environment, Gas, GradientFactors, Tissues};
use poser::plan::dive::*;
use proptest::prelude::*;
use support::plan as common;
use support::plan::{breathed, cyl, flat_dive};

#[test]
fn ndl_verdict_agrees_with_the_ceiling() {
    // The case: GF 100/100, 15 m, the bottom ending a minute after the NDL. The
    // report said "NDL runs out" and then "within the NDL" because the ascent needed no stop.
    let mut d = common::diver(24.0, 232.0);
    d.gf_low = 1.0;
    d.gf_high = 1.0;
    let env = Environment::SEA;
    let mut t = Tissues::surface(env, GradientFactors::NONE);
    t.travel(0.0, 15.0, Gas::AIR, 15.0 / 0.3, 1.0);
    let ndl = match t.ndl(15.0, Gas::AIR) {
        poser::plan::deco::Ndl::Limit(s) => s,
        other => panic!("{other:?}"),
    };
    assert!((80.0 * 60.0..100.0 * 60.0).contains(&ndl), "NDL {ndl}");
    let m = flat_dive(15.0, (ndl + 60.0) / 60.0, d);
    let r = plan_dive(&m, 10.0).unwrap();
    // The bug's regime: the ceiling left the surface, yet the ascent clears it without a stop.
    assert!(r.dive.deco_from.is_some() && r.dive.ceiling_at_end > 0.0);
    assert!(r.dive.stops.is_empty(), "{:?}", r.dive.stops);
    // One criterion: the verdict, the result and the samples all say decompression.
    assert!(r.verdict.deco_required && !r.verdict.within_ndl && !r.verdict.ok);
    assert!(r.dive.samples.iter().any(|s| s.in_deco));
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("decompression"))
    );
}

#[test]
fn deco_gas_is_switched_at_its_mod_and_shortens_the_stops() {
    let air_only = common::diver(24.0, 232.0);
    let mut with_deco = air_only.clone();
    with_deco
        .cylinders
        .push(cyl("deco", 7.0, 200.0, 0.5, 0.0, CylinderRole::Deco));
    let a = plan_dive(&flat_dive(30.0, 35.0, air_only), 10.0).unwrap();
    let b = plan_dive(&flat_dive(30.0, 35.0, with_deco), 10.0).unwrap();
    // EAN50's MOD at pO₂ 1.6 in sea water is 21.6 m: switch depth 21 m.
    assert_eq!(b.config.tanks[1].switch_depth, Some(21.0));
    let sw = b.dive.switches.iter().find(|s| s.cylinder == 1).unwrap();
    assert!((sw.depth - 21.0).abs() < 0.5, "{sw:?}");
    let stops = |r: &DiveReport| r.dive.stops.iter().map(|s| s.duration).sum::<f64>();
    assert!(stops(&a) > 0.0);
    assert!(stops(&b) < stops(&a), "{} vs {}", stops(&b), stops(&a));
    let u = &b.dive.gas.cylinders[1];
    assert!(u.used > 0.0 && u.po2_ok && u.max_po2.unwrap() <= 1.6);
    // The deco cylinder's gas is its own: the back gas is what ran the bottom.
    assert!(b.dive.gas.cylinders[0].used > u.used);
}

#[test]
fn deco_gas_on_a_no_deco_dive_adds_no_stop() {
    // A deco cylinder carried on a dive within the NDL: the ascent is direct with the safety
    // stop; a switch's hold must not turn it into a "decompression" dive.
    let mut d = common::diver(12.0, 232.0);
    d.cylinders
        .push(cyl("deco", 7.0, 200.0, 0.5, 0.0, CylinderRole::Deco));
    let r = plan_dive(&flat_dive(15.0, 25.0, d), 10.0).unwrap();
    assert!(r.dive.deco_from.is_none() && r.dive.stops.is_empty());
    assert!(r.verdict.ok, "{:?}", r.verdict.problems);
    assert_eq!(r.dive.gas.cylinders[1].used, 0.0);
}

#[test]
fn stage_is_breathed_first_down_to_its_reserve() {
    let mut d = common::diver(12.0, 200.0);
    d.cylinders
        .insert(0, cyl("stage", 7.0, 200.0, 0.21, 0.0, CylinderRole::Stage));
    let r = plan_dive(&flat_dive(15.0, 40.0, d), 10.0).unwrap();
    let g = &r.dive.gas;
    assert_eq!(r.dive.switches[0].cylinder, 0);
    assert!(r.dive.switches.iter().any(|s| s.cylinder == 1));
    assert!(g.cylinders.iter().all(|c| c.reserve_ok), "{g:?}");
    // The stage was used down to (just above) its 50 bar reserve.
    assert!((g.cylinders[0].end_pressure - 50.0).abs() < 2.0, "{g:?}");
}

#[test]
fn hypoxic_bottom_gas_is_not_ok() {
    let mut d = common::diver(12.0, 200.0);
    d.cylinders[0].o2 = 0.10;
    d.cylinders[0].he = 0.70;
    let r = plan_dive(&flat_dive(15.0, 10.0, d), 10.0).unwrap();
    assert!(r.dive.gas.cylinders[0].hypoxic);
    assert!(!r.verdict.ok && r.verdict.problems.iter().any(|p| p.contains("hypoxic")));
}

#[test]
fn configured_po2_limit_is_used() {
    // EAN32 at 30 m: pO₂ 1.29 bar, fine at 1.4, not at a configured 1.2.
    let mut d = common::diver(24.0, 232.0);
    d.cylinders[0].o2 = 0.32;
    let ok = plan_dive(&flat_dive(30.0, 8.0, d.clone()), 10.0).unwrap();
    assert!(ok.dive.gas.cylinders[0].po2_ok);
    d.po2_bottom = 1.2;
    let r = plan_dive(&flat_dive(30.0, 8.0, d), 10.0).unwrap();
    assert!(!r.dive.gas.cylinders[0].po2_ok && !r.verdict.ok);
}

#[test]
fn salt_water_is_1030_in_code_and_docs() {
    assert_eq!(Environment::new(true, 0.0).water_density, 1030.0);
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/format.md")).unwrap();
    assert!(doc.contains("1030 kg/m³") && !doc.contains("1025 kg/m³"));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// "Dive safety is safety": for random gases, depths and times the verdict is never OK
    /// when a breathed gas exceeds its pO₂ limit, is hypoxic at the surface, the ceiling is
    /// below the surface at the end of the bottom, or a cylinder runs below its reserve.
    #[test]
    fn verdict_never_calls_a_dangerous_plan_ok(
        depth in 5.0f64..45.0,
        minutes in 3.0f64..45.0,
        o2 in 0.08f64..1.0,
        he_share in 0.0f64..1.0,
        litres in 3.0f64..24.0,
        bar in 60.0f64..300.0,
        deco in proptest::option::of((0.3f64..1.0, 0.0f64..36.0, proptest::bool::ANY)),
        travel in proptest::option::of((0.18f64..0.6, 0.0f64..45.0, proptest::bool::ANY)),
        gf_high in 0.5f64..1.0,
        po2_bottom in 1.2f64..1.6,
        planned in proptest::bool::ANY,
    ) {
        let he = (1.0 - o2) * he_share * 0.9;
        let mut d = common::diver(litres, bar);
        d.cylinders[0].o2 = o2;
        d.cylinders[0].he = he;
        d.gf_low = 0.3;
        d.gf_high = gf_high;
        d.po2_bottom = po2_bottom;
        if planned {
            d.deco = DecoMode::Planned;
        }
        if let Some((deco_o2, sw, given)) = deco {
            let mut c = cyl("deco", 7.0, 200.0, deco_o2, 0.0, CylinderRole::Deco);
            c.switch_depth = given.then_some(sw);
            d.cylinders.push(c);
        }
        if let Some((travel_o2, sw, given)) = travel {
            let mut c = cyl("travel", 11.0, 200.0, travel_o2, 0.0, CylinderRole::Travel);
            c.switch_depth = given.then_some(sw);
            d.cylinders.push(c);
        }
        let m = flat_dive(depth, minutes, d.clone());
        let cfg = DiveConfig::from_model(&m).unwrap();
        let track = Track::from_model(&m).unwrap();
        let dive = simulate_fresh(&cfg, &track, None);
        let v = verdict(&cfg, &track, &dive);
        let env = cfg.env;
        let bottom = Gas { o2, he };

        // Independent checks, from the inputs and physics, not from the simulator's flags.
        let po2_deep = env.pressure(depth) * o2 > po2_bottom + 1e-6;
        let hyp = 0.16_f64.min(0.209 * env.surface_pressure);
        // Without a travel gas the bottom gas is breathed from the surface.
        let hypoxic = travel.is_none() && o2 * env.surface_pressure < hyp;
        // Every gas where it is breathed, from the profile and the switches alone: within the
        // pO₂ limit of its role and not hypoxic.
        let report = DiveReport { config: cfg.clone(), dive: dive.clone(), verdict: v.clone() };
        let unfit = breathed(&report).into_iter().any(|(c, at)| {
            let t = &cfg.tanks[c];
            let p = env.pressure(at) * t.gas.o2;
            let limit = if t.role == CylinderRole::Deco { d.po2_deco } else { po2_bottom };
            p > limit + 1e-6 || p < hyp - 1e-9
        });
        let deco_po2 = dive.switches.iter().any(|s| {
            let t = &cfg.tanks[s.cylinder];
            t.role == CylinderRole::Deco && env.pressure(s.depth) * t.gas.o2 > d.po2_deco + 1e-6
        });
        let mut t = Tissues::surface(env, cfg.gf);
        // The descent: on the travel gas down to its switch depth, if there is one.
        let sw = cfg
            .tanks
            .iter()
            .find(|t| t.role == CylinderRole::Travel)
            .and_then(|t| t.switch_depth.map(|s| (t.gas, s.min(depth))));
        match sw {
            Some((tg, s)) => {
                t.travel(0.0, s, tg, s / cfg.descent_rate, 1.0);
                t.travel(s, depth, bottom, (depth - s) / cfg.descent_rate, 1.0);
            }
            None => t.travel(0.0, depth, bottom, depth / cfg.descent_rate, 1.0),
        }
        t.travel(depth, depth, bottom, track.duration(), 1.0);
        let ceiling = t.ceiling() > 1e-6;
        let bottom_gas = 20.0 * (env.pressure(depth) / 1.01325) * track.duration() / 60.0;
        let tank = &cfg.tanks[0];
        let short = tank.start - bottom_gas < tank.reserve - 1e-6;

        // A planned decompression is no fault in itself; its ascent must keep the diver
        // below the ceiling, which is checked by integrating the tissues again along the
        // flown profile, each stretch on the cylinder the switches name.
        let ceiling = ceiling && !planned;
        if planned && v.ok {
            let mut t = Tissues::surface(env, cfg.gf);
            let gas_at = |time: f64| {
                let c = dive.switches.iter().rev().find(|s| s.time <= time + 1e-9)
                    .map(|s| s.cylinder).unwrap_or(dive.switches[0].cylinder);
                cfg.tanks[c].gas
            };
            let mut worst = f64::NEG_INFINITY;
            for w in dive.profile.windows(2) {
                let ((t0, d0), (t1, d1)) = (w[0], w[1]);
                let n = (t1 - t0).ceil().max(1.0) as usize;
                for k in 0..n {
                    let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
                    let ta = t0 + (t1 - t0) * a;
                    let h = (t1 - t0) / n as f64;
                    t.travel(d0 + (d1 - d0) * a, d0 + (d1 - d0) * b, gas_at(ta + 0.5 * h), h, 1.0);
                    if ta >= dive.descent_time + dive.bottom_time - 1e-9 {
                        worst = worst.max(t.ceiling() - (d0 + (d1 - d0) * b));
                    }
                }
            }
            prop_assert!(worst <= 0.05, "planned OK with the ceiling {worst:.3} m below the diver");
        }
        if po2_deep || hypoxic || deco_po2 || ceiling || short || unfit {
            prop_assert!(!v.ok, "OK despite po2 {po2_deep} hypoxic {hypoxic} deco {deco_po2} \
                ceiling {ceiling} short {short} unfit {unfit}: {:?}", v.problems);
            prop_assert!(!v.problems.is_empty());
            prop_assert!(!dive.ok() || planned);
        }
        prop_assert_eq!(v.ok, v.problems.is_empty());
    }
}
