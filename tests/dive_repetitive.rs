//! Oxygen toxicity across surface intervals (issue 38): the dives of a split survey carry CNS %
//! over each surface interval, halved every 90 min (NOAA; Subsurface does the same), and count
//! the day's OTU against REPEX's 850. Checked against hand-computed values.
use crate::support;
use poser::model::{CylinderRole, Model};
use poser::plan::dive::{DiveConfig, Track, max_strips, split};
use poser::plan::oxygen::{CNS_LIMIT, OTU_DAY_LIMIT, cns_after_surface_interval};
use support::plan::{cyl, diver, lawnmower, model};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn cns_halves_every_90_minutes_at_the_surface() {
    // By hand: 80 % × 2^(−t/90 min).
    assert!(close(
        cns_after_surface_interval(80.0, 90.0 * 60.0),
        40.0,
        1e-12
    ));
    assert!(close(
        cns_after_surface_interval(80.0, 180.0 * 60.0),
        20.0,
        1e-12
    ));
    // 60 min: 2^(−2/3) = 0.629960524947…
    assert!(close(
        cns_after_surface_interval(80.0, 3600.0),
        50.396841995795,
        1e-9
    ));
    // 24 h: 2^(−16) of it is left.
    assert!(close(
        cns_after_surface_interval(100.0, 86400.0),
        100.0 / 65536.0,
        1e-12
    ));
    // No time, a negative or NaN interval: unchanged, never NaN.
    assert_eq!(cns_after_surface_interval(50.0, 0.0), 50.0);
    assert_eq!(cns_after_surface_interval(50.0, -60.0), 50.0);
    assert_eq!(cns_after_surface_interval(50.0, f64::NAN), 50.0);
}

/// `strips` strips of 120 m (10 min each at 0.2 m/s) at 5 m on pure O₂ (pO₂ 1.52 bar, allowed
/// with `po2_bottom = 1.6`): no decompression, plenty of gas, but CNS about 1.08 % a minute.
fn oxygen_survey(strips: u32) -> Model {
    let mut d = diver(12.0, 200.0);
    d.cylinders = vec![cyl("O2", 40.0, 232.0, 1.0, 0.0, CylinderRole::Bottom)];
    d.po2_bottom = 1.6;
    let (poses, net) = lawnmower(strips, 120.0, 2.0, 5.0, 0.2, 4.0);
    model(poses, net, Some(d), 7.0)
}

/// The NOAA table's rate between 1.5 bar (120 min) and 1.6 bar (45 min), % per minute.
fn noaa_rate(po2: f64) -> f64 {
    let f = (po2 - 1.5) / 0.1;
    100.0 * ((1.0 - f) / 120.0 + f / 45.0)
}

#[test]
fn a_split_carries_cns_over_its_surface_intervals() {
    let m = oxygen_survey(12);
    let cfg = DiveConfig::from_model(&m).unwrap();
    let track = Track::from_model(&m).unwrap();
    assert_eq!(cfg.surface_interval, 3600.0);
    // One dive from clean tissues carries 9 of the 12 strips within 100 % CNS.
    let k = max_strips(&cfg, &track);
    assert!((2..12).contains(&k), "{k}");
    let parts = split(&cfg, &track, k, None).expect("a split fits");

    let po2 = cfg.env.pressure(5.0); // pure O₂
    assert!(close(po2, 1.518, 0.002), "{po2}");
    let keep = 0.5_f64.powf(3600.0 / 5400.0); // 60 min at the surface
    let mut carried = 0.0;
    let mut otu_day = 0.0;
    for (i, p) in parts.iter().enumerate() {
        let ox = &p.dive.oxygen;
        // What the dive brings in: the previous dive's end CNS × 2^(−60/90).
        assert!(close(ox.cns_carried, carried, 1e-9), "dive {i}: {ox:?}");
        // Its own CNS, by hand: the time at 5 m at the NOAA rate, plus the descent and ascent
        // (16.7 s and 33.3 s, at most the 5 m rate, at least the 1.0 bar row's 1/300).
        let own = ox.cns_percent - ox.cns_carried;
        let at_depth = p.dive.bottom_time / 60.0 * noaa_rate(po2);
        assert!(
            own >= at_depth + 50.0 / 60.0 * 100.0 / 300.0 - 1e-6
                && own <= at_depth + 50.0 / 60.0 * noaa_rate(po2) + 1e-6,
            "dive {i}: own {own}, at depth {at_depth}"
        );
        assert!(ox.cns_percent <= CNS_LIMIT);
        otu_day += ox.otu;
        assert!(close(p.otu_day, otu_day, 1e-9));
        carried = ox.cns_percent * keep;
    }
    // Without the carry two dives of six strips would do (about 65 % each); with it the second
    // would end near 65 + 0.63 × 65 ≈ 106 %, so the planner needs a third dive.
    assert!(k >= 6, "{k}");
    assert_eq!(parts.len(), 3, "{parts:#?}");
    let first_of_two = 6.0 * 600.0 / 60.0 * noaa_rate(po2);
    assert!(first_of_two * (1.0 + keep) > CNS_LIMIT);
    assert!(otu_day <= OTU_DAY_LIMIT);
}

#[test]
fn the_split_remedy_names_the_carried_cns_and_the_days_otu() {
    let m = oxygen_survey(12);
    let r = poser::plan::dive::plan_dive(&m, 10.0).unwrap();
    assert!(!r.verdict.ok, "120 min on O₂ at 5 m is over 100 % CNS");
    let text: Vec<&str> = r
        .verdict
        .suggestions
        .iter()
        .filter(|s| s.kind == "split_dives")
        .map(|s| s.text.as_str())
        .collect();
    assert_eq!(text.len(), 1, "{:#?}", r.verdict.suggestions);
    assert!(
        text[0].starts_with("two or more dives: 3 dives"),
        "{}",
        text[0]
    );
    assert!(text[0].contains("halved every 90 min"), "{}", text[0]);
    assert!(text[0].contains("OTU of the day"), "{}", text[0]);
}
