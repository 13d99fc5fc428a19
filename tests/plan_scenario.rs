//! The paper's example scene (`scenarios/paper_survey.toml`) through the real front end: poser
//! must find the decompression obligation and the gas problem and compute what fixes them.
use poser::plan::dive::plan_dive;

#[test]
fn paper_scenario_verdict() {
    let m = poser::scene::load(std::path::Path::new("scenarios/paper_survey.toml"), &[])
        .map_err(|f| f.render())
        .unwrap()
        .model;
    // The paper's numbers: 20 strips, ≈ 1100 m of path (±5 %), 15 m, ≈ 104 min of swimming
    // (an average of 0.176 m/s over the path).
    assert_eq!(m.network.strips, 20);
    assert!(
        (m.network.path_length - 1100.0).abs() < 55.0,
        "{}",
        m.network.path_length
    );
    assert!((m.network.speed - 0.176).abs() < 1e-12);
    let r = plan_dive(&m, 10.0).unwrap();
    assert!((r.dive.max_depth - 15.0).abs() < 1e-6);
    // Survey: the paper's ≈ 104 min (1093 m / 0.176 m/s = 103:32).
    assert!(
        (r.dive.bottom_time / 60.0 - 104.0).abs() < 1.0,
        "{}",
        r.dive.bottom_time
    );
    assert!(r.dive.runtime / 60.0 >= 110.0);

    assert!(r.verdict.deco_required, "the paper's deco obligation");
    assert!(!r.verdict.gas_ok, "the paper's gas problem");
    assert!(r.dive.gas.used > 2.0 * r.config.supply.start);
    let fix = r
        .verdict
        .suggestions
        .iter()
        .find(|s| s.fixes_all)
        .expect("a remedy that fixes all");
    assert_eq!(fix.kind, "split_dives");
    // A tiny override turns it into a fine dive: 2 strips.
    let small = poser::scene::load(
        std::path::Path::new("scenarios/paper_survey.toml"),
        &[
            "network.strips=2".to_string(),
            "network.width=2".to_string(),
            "network.length=30".to_string(),
        ],
    )
    .map_err(|f| f.render())
    .unwrap()
    .model;
    let r2 = plan_dive(&small, 10.0).unwrap();
    assert!(r2.verdict.problems.is_empty(), "{:?}", r2.verdict.problems);
}
