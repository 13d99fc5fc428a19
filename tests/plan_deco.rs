//! Decompression model checks: NDLs against a published table and an independent
//! implementation, ceilings and stops on a dive past the NDL.
use poser::plan::deco::*;

fn ndl_min(depth: f64, gf: GradientFactors) -> f64 {
    match Tissues::surface(Environment::SEA, gf).ndl_capped(depth, Gas::AIR, 6.0 * 3600.0) {
        Ndl::Limit(s) => s / 60.0,
        other => panic!("no NDL at {depth} m: {other:?}"),
    }
}

/// PADI Recreational Dive Planner (metric table, air, 2nd ed.) no-decompression limits, min.
/// 15/21/24 m are linearly interpolated between the table's 14/16, 20/22 and 22/25 m rows.
const PADI_RDP: [(f64, f64); 6] = [
    (12.0, 147.0),
    (15.0, 85.0),
    (18.0, 56.0),
    (21.0, 41.0),
    (24.0, 31.7),
    (30.0, 20.0),
];

#[test]
fn ndl_gf100_close_to_padi_rdp() {
    // ZHL-16C at GF 100/100 is a different model from the RDP's (DSAT, Rogers/Powell), so only
    // broad agreement is expected: within 20 % (the largest gap is at 30 m: ZHL-16C ≈ 16 min,
    // the RDP 20 min, where ZHL-16C is known to be the more conservative).
    for (d, table) in PADI_RDP {
        let ours = ndl_min(d, GradientFactors::NONE);
        let rel = (ours - table).abs() / table;
        assert!(
            rel < 0.20,
            "{d} m: ours {ours:.1} min, RDP {table} min ({:.0} %)",
            rel * 100.0
        );
    }
}

#[test]
fn ndl_agrees_with_dive_deco_crate() {
    // dive-deco (an independent Rust ZHL-16C) differs in compartment 1 (4 min instead of
    // Subsurface's 1b at 5 min), the initial N₂ loading (79 % instead of 78.1 %) and integrates
    // with whole minutes; tolerance 2 min + 4 % for that.
    use dive_deco::{BuhlmannConfig, BuhlmannModel, DecoModel, Depth, Gas as DG, Time};
    for (gl, gh) in [(100u8, 100u8), (30, 75), (30, 70)] {
        let gf = GradientFactors {
            low: gl as f64 / 100.0,
            high: gh as f64 / 100.0,
        };
        for d in [15.0, 18.0, 21.0, 24.0, 30.0, 40.0] {
            let cfg = BuhlmannConfig::new()
                .with_gradient_factors(gl, gh)
                .with_surface_pressure(1013);
            let mut m = BuhlmannModel::new(cfg);
            m.record(Depth::from_meters(d), Time::zero(), &DG::new(0.209, 0.0));
            let theirs = m.ndl().as_minutes();
            let ours = ndl_min(d, gf);
            assert!(
                (ours - theirs).abs() <= 2.0 + 0.04 * theirs,
                "GF {gl}/{gh} {d} m: ours {ours:.1}, dive-deco {theirs}"
            );
        }
    }
}

#[test]
fn ndl_depends_on_gf_high_only_and_shrinks_with_depth() {
    let a = ndl_min(
        18.0,
        GradientFactors {
            low: 0.3,
            high: 0.75,
        },
    );
    let b = ndl_min(
        18.0,
        GradientFactors {
            low: 0.9,
            high: 0.75,
        },
    );
    assert_eq!(
        a, b,
        "GF low must not change the NDL (Subsurface's GF line)"
    );
    let mut last = f64::INFINITY;
    for d in [12.0, 15.0, 18.0, 21.0, 24.0, 30.0, 40.0] {
        let n = ndl_min(d, GradientFactors::SUBSURFACE);
        assert!(n < last, "NDL must shrink with depth ({d} m: {n})");
        assert!(
            n < ndl_min(d, GradientFactors::NONE),
            "GF 75 must be stricter than 100"
        );
        last = n;
    }
    // Nitrox 32 lengthens the NDL at 18 m clearly (less N₂: EAD ≈ 13 m).
    let air = ndl_min(18.0, GradientFactors::SUBSURFACE);
    let nx = Tissues::surface(Environment::SEA, GradientFactors::SUBSURFACE)
        .ndl(18.0, Gas { o2: 0.32, he: 0.0 });
    match nx {
        Ndl::Limit(s) => assert!(s / 60.0 > 1.4 * air, "EAN32 {} vs air {air}", s / 60.0),
        Ndl::Unlimited => {}
        Ndl::InDeco => panic!("in deco at the surface"),
    }
}

#[test]
fn deco_dive_needs_stops_and_clears_them() {
    // 40 min at 30 m on air at GF 30/75: well past the NDL (≈ 9 min), so stops are required.
    let env = Environment::SEA;
    let gas = Gas::AIR;
    let mut t = Tissues::surface(env, GradientFactors::SUBSURFACE);
    t.travel(0.0, 30.0, gas, 100.0, 1.0);
    t.expose(30.0, gas, 40.0 * 60.0);
    assert!(t.in_deco());
    let ceiling = t.ceiling();
    assert!(ceiling > 3.0 && ceiling < 15.0, "ceiling {ceiling}");
    let runtime = 100.0 + 2400.0;
    let a = t.ascend(30.0, 9.0 / 60.0, gas, runtime);
    assert!(!a.stops.is_empty());
    // Stops are on 3 m levels, deepest first, shallowest at 3 m.
    for w in a.stops.windows(2) {
        assert!(w[0].depth > w[1].depth);
    }
    for s in &a.stops {
        assert!((s.depth / 3.0 - (s.depth / 3.0).round()).abs() < 1e-9 && s.depth >= 3.0);
        // Each stop ends on a whole runtime minute.
    }
    assert_eq!(a.stops.last().unwrap().depth, 3.0);
    let total: f64 = a.stops.iter().map(|s| s.duration).sum();
    // Pure travel is 30 m / 9 m/min = 200 s; TTS adds the stops.
    assert!(
        (a.tts - total - 200.0).abs() < 1.0,
        "tts {} stops {total}",
        a.tts
    );
    // Well above a trivial obligation but not absurd: 10–60 min of stops (DecoPlanner-class
    // schedules for 30 m/40 min air GF 30/75 are around 20–30 min).
    assert!(total > 600.0 && total < 3600.0, "total stop time {total}");
    // After the ascent the diver is clean at the surface.
    assert!(!t.in_deco());

    // Independent check: dive-deco's planner on the same exposure (GF 30/75, 9 m/min). Its stop
    // logic differs (no trial ascent crediting off-gassing on the way, whole-minute stops,
    // compartment 1 at 4 min), so agreement within 25 % of the TTS is what we ask.
    use dive_deco::{BuhlmannConfig, BuhlmannModel, DecoModel, Depth, Gas as DG, Time};
    let cfg = BuhlmannConfig::new()
        .with_gradient_factors(30, 75)
        .with_surface_pressure(1013)
        .with_deco_ascent_rate(9.0);
    let mut m = BuhlmannModel::new(cfg);
    let air = DG::new(0.209, 0.0);
    m.record_travel(Depth::from_meters(30.0), Time::from_seconds(100.0), &air);
    m.record(Depth::from_meters(30.0), Time::from_seconds(2400.0), &air);
    let theirs = m.deco(vec![air]).unwrap().tts.as_seconds();
    assert!(
        (a.tts - theirs).abs() < 0.25 * theirs,
        "TTS ours {:.0} s, dive-deco {theirs:.0} s; stops {:?}",
        a.tts,
        a.stops
    );
    eprintln!(
        "30 m/40 min GF30/75: TTS ours {:.0} s, dive-deco {theirs:.0} s, stops {:?}",
        a.tts, a.stops
    );
}

#[test]
fn within_ndl_no_stops() {
    let env = Environment::SEA;
    let mut t = Tissues::surface(env, GradientFactors::SUBSURFACE);
    t.travel(0.0, 18.0, Gas::AIR, 60.0, 1.0);
    t.expose(18.0, Gas::AIR, 20.0 * 60.0);
    let a = t.ascend(18.0, 0.15, Gas::AIR, 1260.0);
    assert!(a.stops.is_empty(), "{:?}", a.stops);
    assert!((a.tts - 120.0).abs() < 1e-6);
}

/// Subsurface's planner regression test `TestPlan::testMetric` (tests/testplan.cpp): 79 m on
/// TX15/45 for 30 min including a 23 m/min descent, EAN36 and O₂ as deco gases (switch depths
/// from pO₂ 1.6 rounded to 3 m: 33 m and 6 m), GF 100/100, sea water, 1 atm, ascent 30 ft/min,
/// last 6 m at 10 ft/min, last stop at 6 m. Subsurface expects a runtime of 109 min and accepts
/// 1 % + 60 s (its `compareDecoTime`); we use the same tolerance.
#[test]
fn subsurface_testplan_metric_runtime() {
    let env = Environment {
        surface_pressure: 1.01325,
        water_density: 1030.0,
    };
    let bottom = Gas { o2: 0.15, he: 0.45 };
    let ean36 = Gas { o2: 0.36, he: 0.0 };
    let o2 = Gas { o2: 1.0, he: 0.0 };
    let (sw36, swo2) = (
        ean36.switch_depth(&env, 1.6, 3.0),
        o2.switch_depth(&env, 1.6, 3.0),
    );
    assert_eq!((sw36, swo2), (33.0, 6.0), "switch depths as in the test");
    let mut t = Tissues::surface(env, GradientFactors::NONE);
    let droptime = (79_000 * 60 / 23_000) as f64; // integer seconds as in the test
    t.travel(0.0, 79.0, bottom, droptime, 1.0);
    t.expose(79.0, bottom, 30.0 * 60.0 - droptime);
    let plan = AscentPlan {
        rate: 0.3048 * 30.0 / 60.0,
        rate_last6: 0.3048 * 10.0 / 60.0,
        last_stop: 6.0,
        deco_gases: vec![(ean36, sw36), (o2, swo2)],
        switch_time: 60.0,
        stop_step: 3.0,
    };
    let a = t.ascend_with(79.0, bottom, &plan, 1800.0);
    let runtime = 1800.0 + a.tts;
    let expected = 109.0 * 60.0;
    let tol = 0.01 * expected + 60.0;
    eprintln!(
        "runtime {:.0} s (Subsurface 6540 s), stops {:?}, switches {:?}",
        runtime, a.stops, a.switches
    );
    assert!(
        (runtime - expected).abs() <= tol,
        "runtime {runtime} s vs {expected} ± {tol}"
    );
    // The gas switches happen at 33 m and 6 m, in that order.
    let depths: Vec<f64> = a.switches.iter().map(|s| s.1).collect();
    assert_eq!(depths, vec![33.0, 6.0]);
}

/// `TestPlan::testImperial`: the same plan in feet — 260 ft, descent 75 ft/min, switch depths
/// rounded to 10 ft (110 ft, 20 ft), stops every 10 ft, last stop 20 ft. Subsurface expects
/// 111 min − 2 s, tolerance 1 % + 60 s.
#[test]
fn subsurface_testplan_imperial_runtime() {
    let ft = 0.3048;
    let env = Environment {
        surface_pressure: 1.01325,
        water_density: 1030.0,
    };
    let bottom = Gas { o2: 0.15, he: 0.45 };
    let ean36 = Gas { o2: 0.36, he: 0.0 };
    let o2 = Gas { o2: 1.0, he: 0.0 };
    let (sw36, swo2) = (
        ean36.switch_depth(&env, 1.6, 10.0 * ft),
        o2.switch_depth(&env, 1.6, 10.0 * ft),
    );
    assert!(
        (sw36 - 110.0 * ft).abs() < 1e-9 && (swo2 - 20.0 * ft).abs() < 1e-9,
        "{sw36} {swo2}"
    );
    let depth = 260.0 * ft;
    let mut t = Tissues::surface(env, GradientFactors::NONE);
    // m_or_ft(79, 260).mm * 60 / m_or_ft(23, 75).mm with integer millimetres.
    let droptime =
        ((depth * 1000.0).round() as i64 * 60 / (75.0 * ft * 1000.0).round() as i64) as f64;
    t.travel(0.0, depth, bottom, droptime, 1.0);
    t.expose(depth, bottom, 30.0 * 60.0 - droptime);
    let plan = AscentPlan {
        rate: ft * 30.0 / 60.0,
        rate_last6: ft * 10.0 / 60.0,
        last_stop: 20.0 * ft,
        deco_gases: vec![(ean36, sw36), (o2, swo2)],
        switch_time: 60.0,
        stop_step: 10.0 * ft,
    };
    let a = t.ascend_with(depth, bottom, &plan, 1800.0);
    let runtime = 1800.0 + a.tts;
    let expected = 111.0 * 60.0 - 2.0;
    let tol = 0.01 * expected + 60.0;
    eprintln!("imperial runtime {runtime:.0} s (Subsurface {expected} s)");
    assert!(
        (runtime - expected).abs() <= tol,
        "runtime {runtime} s vs {expected} ± {tol}"
    );
}
