//! Oxygen toxicity of a dive plan: CNS % against the NOAA single-exposure limits and OTU
//! (Lambertsen / REPEX), checked against hand-computed values, a ramp, a shipped scenario on
//! EAN32 and oxygen-rich deco cases (issue 38).
use crate::support;
use poser::model::CylinderRole;
use poser::plan::dive::plan_dive;
use poser::plan::oxygen::{Exposure, NOAA_CNS_LIMITS, cns_rate, otu_rate};
use support::plan as common;
use support::plan::{cyl, flat_dive};

fn paper() -> poser::model::Model {
    poser::scene::load(std::path::Path::new("scenarios/paper_survey.toml"), &[])
        .map_err(|f| f.render())
        .unwrap()
        .model
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn noaa_table_rows_are_exact() {
    // The NOAA Diving Manual's single-exposure limits, typed here from the manual.
    let rows = [
        (0.6, 720.0),
        (0.7, 570.0),
        (0.8, 450.0),
        (0.9, 360.0),
        (1.0, 300.0),
        (1.1, 240.0),
        (1.2, 210.0),
        (1.3, 180.0),
        (1.4, 150.0),
        (1.5, 120.0),
        (1.6, 45.0),
    ];
    assert_eq!(NOAA_CNS_LIMITS.len(), rows.len());
    for (p, limit) in rows {
        // At each row, the limit in minutes uses exactly 100 %.
        let e = Exposure::segment(p, p, limit * 60.0);
        assert!(close(e.cns_percent, 100.0, 1e-9), "{p}: {e:?}");
    }
    // No loading at or below 0.5 bar, neither CNS nor OTU.
    for p in [0.0, 0.21, 0.4, 0.5] {
        assert_eq!(cns_rate(p), 0.0);
        assert_eq!(otu_rate(p), 0.0);
    }
    // 0.5–0.6 bar: the 0.6 bar row (conservative).
    assert!(close(cns_rate(0.55), 100.0 / 720.0, 1e-12));
    // Between rows the rate is interpolated: 1.55 bar lies between 1/120 and 1/45 per minute.
    assert!(close(cns_rate(1.55), 50.0 / 120.0 + 50.0 / 45.0, 1e-9));
    // Beyond the table, steeper than the last row and growing.
    assert!(cns_rate(1.7) > cns_rate(1.6) * 2.0);
    assert!(cns_rate(1.8) > cns_rate(1.7));
}

#[test]
fn constant_depth_segment_by_hand() {
    // 30 min at pO₂ 1.4 bar: 30/150 = 20 % CNS; OTU = 30 · ((1.4 − 0.5)/0.5)^0.83 = 30 · 1.8^0.83.
    let e = Exposure::segment(1.4, 1.4, 30.0 * 60.0);
    assert!(close(e.cns_percent, 20.0, 1e-9), "{e:?}");
    let otu = 30.0 * 1.8_f64.powf(0.83);
    assert!(close(e.otu, otu, 1e-9), "{e:?} vs {otu}");
    assert!(close(otu, 48.865, 0.001), "{otu}");
    // 45 min at 1.0 bar: 15 % CNS and 45 OTU exactly (1.0 bar is one OTU per minute).
    let e = Exposure::segment(1.0, 1.0, 45.0 * 60.0);
    assert!(
        close(e.cns_percent, 15.0, 1e-9) && close(e.otu, 45.0, 1e-9),
        "{e:?}"
    );
}

#[test]
fn ramp_by_hand() {
    // pO₂ from 1.2 to 1.4 bar over 20 min. CNS: the rate is linear in pO₂ between rows, so
    // each 10 min half is the mean of its two rows' rates:
    // 10·(100/210 + 100/180)/2 + 10·(100/180 + 100/150)/2 = 11.2698… %.
    let e = Exposure::segment(1.2, 1.4, 20.0 * 60.0);
    let cns = 5.0 * (100.0 / 210.0 + 100.0 / 180.0) + 5.0 * (100.0 / 180.0 + 100.0 / 150.0);
    assert!(close(e.cns_percent, cns, 1e-6), "{e:?} vs {cns}");
    assert!(close(cns, 11.2698, 1e-4));
    // OTU: ∫ ((p − 0.5)/0.5)^0.83 dt, here by Simpson's rule on 2000 intervals.
    let n = 2000;
    let f = |i: usize| otu_rate(1.2 + 0.2 * i as f64 / n as f64);
    let mut s = f(0) + f(n);
    for i in 1..n {
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i);
    }
    let otu = s * (20.0 / n as f64) / 3.0;
    assert!(close(e.otu, otu, 1e-6), "{e:?} vs {otu}");
    // The ramp lies between its end points' constant exposures, and reversing it changes
    // nothing.
    let lo = Exposure::segment(1.2, 1.2, 1200.0);
    let hi = Exposure::segment(1.4, 1.4, 1200.0);
    assert!(lo.otu < e.otu && e.otu < hi.otu);
    assert!(lo.cns_percent < e.cns_percent && e.cns_percent < hi.cns_percent);
    let back = Exposure::segment(1.4, 1.2, 1200.0);
    assert!(close(back.otu, e.otu, 1e-9) && close(back.cns_percent, e.cns_percent, 1e-9));
    // A descent crossing 0.5 bar loads only above it: from 0.3 to 0.7 bar in 10 min is
    // the same as 0.5 → 0.7 in 5 min.
    let cross = Exposure::segment(0.3, 0.7, 600.0);
    let upper = Exposure::segment(0.5, 0.7, 300.0);
    assert!(close(cross.otu, upper.otu, 1e-9), "{cross:?} {upper:?}");
    assert!(close(cross.cns_percent, upper.cns_percent, 1e-6));
}

#[test]
fn scenario_on_ean32_loads_cns() {
    let mut m = paper();
    m.diver.as_mut().unwrap().cylinders[0].o2 = 0.32;
    let r = plan_dive(&m, 10.0).unwrap();
    let ox = r.dive.oxygen;
    // The survey flies at 15 m: pO₂ = 0.32 · (1.01325 + 15 · 0.0101043) ≈ 0.809 bar, i.e.
    // 100·(0.91/450 + 0.09/360) ≈ 0.227 % and ((0.809 − 0.5)/0.5)^0.83 ≈ 0.67 OTU a minute.
    let p = 0.32 * r.config.env.pressure(15.0);
    assert!(close(p, 0.809, 0.002), "{p}");
    let bottom_min = r.dive.bottom_time / 60.0;
    let (cns_bottom, otu_bottom) = (cns_rate(p) * bottom_min, otu_rate(p) * bottom_min);
    assert!(ox.cns_percent > 0.0);
    assert!(
        ox.cns_percent >= cns_bottom - 0.5 && ox.cns_percent <= cns_bottom + 2.0,
        "CNS {} vs bottom {cns_bottom}",
        ox.cns_percent
    );
    assert!(
        ox.otu >= otu_bottom - 0.5 && ox.otu <= otu_bottom + 3.0,
        "OTU {} vs bottom {otu_bottom}",
        ox.otu
    );
    assert!(close(ox.max_po2, p, 0.02), "{ox:?}");
    // The same survey on air loads less of both.
    let air = plan_dive(&paper(), 10.0).unwrap();
    assert!(air.dive.oxygen.cns_percent < ox.cns_percent);
    assert!(air.dive.oxygen.otu < ox.otu);
    // Shown in the text report and in the JSON of `poser dive`.
    let run = |json: bool| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_poser"));
        c.arg("dive")
            .arg(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/scenarios/paper_survey.toml"
            ))
            .args(["--set", "diver.cylinders.0.gas=\"EAN32\""]);
        if json {
            c.arg("--json");
        }
        String::from_utf8(c.output().unwrap().stdout).unwrap()
    };
    let text = run(false);
    assert!(
        text.contains(&format!("CNS {:.1} % → OK", ox.cns_percent)),
        "{text}"
    );
    assert!(text.contains(&format!("OTU {:.1} → OK", ox.otu)), "{text}");
    let json: serde_json::Value = serde_json::from_str(&run(true)).unwrap();
    let j = &json["dive"]["oxygen"];
    assert!(
        close(j["cns_percent"].as_f64().unwrap(), ox.cns_percent, 1e-6),
        "{j}"
    );
    assert!(close(j["otu"].as_f64().unwrap(), ox.otu, 1e-6), "{j}");
    // And in the Subsurface log, as Subsurface saves them.
    let xml = String::from_utf8(poser::plan::ssrf::to_ssrf(&m, &r).unwrap()).unwrap();
    assert!(
        xml.contains(&format!("cns='{}%'", ox.cns_percent.round()))
            || xml.contains(&format!("cns=\"{}%\"", ox.cns_percent.round())),
        "{xml:.600}"
    );
}

/// A deep dive on EAN28 with an O₂ deco cylinder, big enough cylinders that gas is no issue.
fn o2_deco_model(depth: f64, minutes: f64) -> poser::model::Model {
    let mut d = common::diver(60.0, 232.0);
    d.cylinders = vec![
        cyl("back", 60.0, 232.0, 0.28, 0.0, CylinderRole::Bottom),
        cyl("O2", 40.0, 200.0, 1.0, 0.0, CylinderRole::Deco),
    ];
    flat_dive(depth, minutes, d)
}

#[test]
fn oxygen_deco_reaching_the_warning_is_flagged() {
    // 34 m on EAN28 (pO₂ 1.25 bar) for 120 min, O₂ from 5 m: ≈ 62 % on the bottom, and the
    // long O₂ stop at 3 m (pO₂ 1.32 bar) brings CNS to ≈ 95 %. The plan is a decompression plan
    // (already not OK); the CNS warning must be there.
    let m = o2_deco_model(34.0, 120.0);
    let r = plan_dive(&m, 10.0).unwrap();
    let ox = r.dive.oxygen;
    assert!(
        r.dive.switches.iter().any(|s| s.cylinder == 1),
        "O₂ breathed"
    );
    assert!(ox.cns_percent > 80.0, "{ox:?} stops {:?}", r.dive.stops);
    assert!(ox.max_po2 <= 1.6 + 1e-9, "{ox:?}");
    let all: Vec<&String> = r.verdict.problems.iter().chain(&r.verdict.advice).collect();
    assert!(all.iter().any(|p| p.contains("CNS")), "{all:?}");
    assert!(!r.verdict.ok);
    if ox.cns_percent > 100.0 {
        assert!(r.verdict.problems.iter().any(|p| p.contains("CNS")));
        assert!(!r.dive.ok());
    }
}

/// Pure O₂ breathed as the bottom gas at 4 m (pO₂ 1.42 bar, within a 1.6 bar bottom limit the
/// diver chose): within the NDL and with plenty of gas, so only oxygen can fail the plan.
fn shallow_o2(minutes: f64) -> poser::model::Model {
    let mut d = common::diver(50.0, 232.0);
    d.po2_bottom = 1.6;
    d.cylinders = vec![cyl("O2", 50.0, 232.0, 1.0, 0.0, CylinderRole::Bottom)];
    flat_dive(4.0, minutes, d)
}

#[test]
fn cns_above_100_is_not_safe_even_within_the_ndl() {
    // 200 min at 1.42 bar against a ≈ 144 min limit: CNS ≈ 139 %, OTU ≈ 330.
    let m = shallow_o2(200.0);
    let r = plan_dive(&m, 10.0).unwrap();
    let ox = r.dive.oxygen;
    assert!(
        !r.dive.deco_required() && r.dive.gas.ok(),
        "{:?}",
        r.verdict
    );
    assert!(ox.cns_percent > 100.0 && ox.otu > 300.0, "{ox:?}");
    assert!(!r.verdict.ok && !r.dive.ok());
    assert!(
        r.verdict.problems.iter().any(|p| p.contains("CNS")),
        "{:?}",
        r.verdict.problems
    );
    assert!(r.verdict.advice.iter().any(|a| a.contains("OTU")));

    // 125 min: CNS ≈ 87 %: a warning, the plan itself unchanged (OK, as before).
    let m = shallow_o2(125.0);
    let r = plan_dive(&m, 10.0).unwrap();
    let ox = r.dive.oxygen;
    assert!(ox.cns_percent > 80.0 && ox.cns_percent < 100.0, "{ox:?}");
    assert!(r.verdict.advice.iter().any(|a| a.contains("CNS")));
    assert!(!r.verdict.problems.iter().any(|p| p.contains("CNS")));
    assert!(r.verdict.ok, "{:?}", r.verdict.problems);

    // 100 min: CNS ≈ 70 %, no oxygen remark at all.
    let r = plan_dive(&shallow_o2(100.0), 10.0).unwrap();
    let o = r.dive.oxygen;
    assert!(
        o.cns_percent > 60.0 && o.cns_percent < 80.0 && o.otu < 300.0,
        "{o:?}"
    );
    assert!(
        !r.verdict
            .problems
            .iter()
            .chain(&r.verdict.advice)
            .any(|p| p.contains("CNS") || p.contains("OTU"))
    );
}

#[test]
fn po2_beyond_the_table_is_never_fine() {
    // The diver raises the deco limit to 1.65 bar and switches to O₂ at 6 m (pO₂ 1.62 bar):
    // the cylinder check passes under the diver's own limit, the NOAA table does not.
    let mut m = o2_deco_model(30.0, 40.0);
    let d = m.diver.as_mut().unwrap();
    d.po2_deco = 1.65;
    d.cylinders[1].switch_depth = Some(6.0);
    let r = plan_dive(&m, 10.0).unwrap();
    let ox = r.dive.oxygen;
    assert!(ox.max_po2 > 1.6, "{ox:?} stops {:?}", r.dive.stops);
    assert!(ox.minutes_above_table > 0.0);
    assert!(
        r.dive.gas.cylinders[1].po2_ok,
        "the diver's own limit is kept"
    );
    assert!(!r.verdict.ok && !r.dive.ok());
    assert!(
        r.verdict
            .problems
            .iter()
            .any(|p| p.contains("beyond the 1.6 bar")),
        "{:?}",
        r.verdict.problems
    );
}
