//! Dive planning on Rust-built models: the paper's survey, a short survey within the NDL.
use crate::support;
use poser::plan::deco::Environment;
use poser::plan::dive::*;
use support::plan as common;

#[test]
fn paper_survey_needs_deco_and_runs_out_of_gas() {
    // 20 strips, ≈ 1090 m at 15 m and 0.2 m/s: ≈ 91 min of survey on a 12 l/200 bar cylinder.
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let r = plan_dive(&m, 10.0).unwrap();
    let d = &r.dive;
    assert!((d.bottom_time - m.network.duration).abs() < 1e-6);
    assert!((d.max_depth - 15.0).abs() < 1e-9);
    // Decompression: the GF 30/75 NDL at 15 m is ≈ 54 min (see plan_deco), far below 91 min.
    assert!(r.verdict.deco_required && !r.verdict.within_ndl);
    let deco_from = d.deco_from.unwrap() - d.descent_time;
    assert!(
        (45.0 * 60.0..65.0 * 60.0).contains(&deco_from),
        "NDL ran out after {deco_from} s"
    );
    assert!(!d.stops.is_empty() && d.stops.last().unwrap().depth == 3.0);
    // Gas: 20 l/min × 2.53 bar × 91 min ≈ 4600 l + descent/ascent, against 2287 l in the cylinder.
    let expect = 20.0 * (Environment::SEA.pressure(15.0) / 1.01325) * d.bottom_time / 60.0;
    assert!(
        d.gas.used > expect && d.gas.used < expect * 1.15,
        "used {}",
        d.gas.used
    );
    assert!(!r.verdict.gas_ok && !d.gas.reserve_ok && d.gas.empty_at.is_some());
    // Remedies are computed, and at least one fixes everything.
    let kinds: Vec<&str> = r
        .verdict
        .suggestions
        .iter()
        .map(|s| s.kind.as_str())
        .collect();
    for k in [
        "bigger_cylinder",
        "max_strips",
        "split_dives",
        "faster_swim",
        "nitrox",
    ] {
        assert!(kinds.contains(&k), "missing {k} in {kinds:?}");
    }
    assert!(r.verdict.suggestions.iter().any(|s| s.fixes_all));
}

#[test]
fn max_strips_is_the_boundary() {
    // The "fewer strips" number must be exact: k strips fit, k+1 do not.
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let cfg = DiveConfig::from_model(&m).unwrap();
    let track = Track::from_model(&m).unwrap();
    let dive = simulate_fresh(&cfg, &track, None);
    let v = verdict(&cfg, &track, &dive);
    let s = v
        .suggestions
        .iter()
        .find(|s| s.kind == "max_strips")
        .unwrap();
    let k: usize = s
        .text
        .split("at most ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(simulate_fresh(&cfg, &track.strip_range(0, k), None).ok());
    assert!(!simulate_fresh(&cfg, &track.strip_range(0, k + 1), None).ok());
    // And the split plan really works dive by dive with repetitive tissues.
    let split = v
        .suggestions
        .iter()
        .find(|s| s.kind == "split_dives")
        .unwrap();
    let dives: usize = split
        .text
        .split(": ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(dives >= 20usize.div_ceil(k));
}

#[test]
fn short_survey_is_fine_with_safety_stop() {
    let (poses, net) = common::lawnmower(3, 30.0, 2.0, 12.0, 0.2, 1.0);
    let m = common::model(poses, net, Some(common::diver(12.0, 200.0)), 14.0);
    let r = plan_dive(&m, 10.0).unwrap();
    assert!(r.verdict.problems.is_empty(), "{:?}", r.verdict.problems);
    assert!(r.verdict.suggestions.is_empty());
    assert!(r.dive.stops.is_empty());
    let s = r.dive.safety_stop.expect("safety stop at 12 m");
    assert_eq!((s.depth, s.duration), (5.0, 180.0));
    // Runtime = descent + survey + ascent with the stop.
    let expect = 12.0 / 0.3 + r.dive.bottom_time + 7.0 / 0.15 + 180.0 + 5.0 / 0.15;
    assert!(
        (r.dive.runtime - expect).abs() < 1e-6,
        "{} vs {expect}",
        r.dive.runtime
    );
    // End pressure consistent with the Z-corrected contents.
    let left = r.config.supply.start - r.dive.gas.used;
    let p = poser::plan::gas::pressure_for(r.config.gas(), 12.0, left);
    assert!((p - r.dive.gas.end_pressure).abs() < 0.01);
}

#[test]
fn fresh_water_and_altitude_change_the_numbers() {
    let mk = |salt: bool| {
        let mut d = common::diver(12.0, 200.0);
        d.salt_water = salt;
        common::paper_model(Some(d))
    };
    let sea = plan_dive(&mk(true), 30.0).unwrap();
    let fresh = plan_dive(&mk(false), 30.0).unwrap();
    // Less pressure at 15 m in fresh water: less gas used, later NDL end.
    assert!(fresh.dive.gas.used < sea.dive.gas.used);
    assert!(fresh.dive.deco_from.unwrap() > sea.dive.deco_from.unwrap());
    // At altitude the surface pressure drops and the same depth is relatively worse (NDL shorter).
    let mut alt = mk(false);
    alt.site.altitude = 2000.0;
    let a = plan_dive(&alt, 30.0).unwrap();
    assert!(a.config.env.surface_pressure < 0.8);
    assert!(a.dive.deco_from.unwrap() < fresh.dive.deco_from.unwrap());
}

#[test]
fn bad_diver_is_an_error_not_a_panic() {
    let mut d = common::diver(12.0, 200.0);
    d.cylinders.clear();
    let m = common::paper_model(Some(d));
    assert!(plan_dive(&m, 10.0).unwrap_err().contains("cylinder"));
    let mut d = common::diver(12.0, 200.0);
    d.gf_low = 0.9;
    d.gf_high = 0.5;
    assert!(plan_dive(&common::paper_model(Some(d)), 10.0).is_err());
    let mut m = common::paper_model(None);
    m.poses.clear();
    assert!(plan_dive(&m, 10.0).is_err());
    let mut m = common::paper_model(None);
    m.water = None;
    assert!(plan_dive(&m, 10.0).unwrap_err().contains("no water"));
    // Without a diver, Subsurface's defaults are used and said so.
    let r = plan_dive(&common::paper_model(None), 10.0).unwrap();
    assert!(r.config.defaulted && (r.config.gf.high - 0.75).abs() < 1e-12);
}
