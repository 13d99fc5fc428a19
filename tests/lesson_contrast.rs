//! `poser lesson` kinds `contrast` and `gsd` end to end on their quick forms (native renders
//! only), with each page opened in real headless Chromium (hence the `backends` tier).
//!
//! The numbers must fall in the bands physics predicts — contrast falls with the water path at
//! the same GSD, green lake water casts green, strobes far apart light less of the water in
//! front of the port, the height for a GSD scales with the GSD, a flat port needs about n
//! times the height in air, and the smallest resolved element is one to three planned GSDs —
//! and the page must show every number of `lesson.json` as it formats it.

use crate::support;

use support::lesson::{cell, check_page, f, row, rows, run_lesson, slug};

#[test]
fn contrast_lesson_quick_form_loses_contrast_with_distance_and_shows_it() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/turbidity_contrast.toml", "contrast");
    assert_eq!(json["results"]["kind"], "contrast");
    let near = row(&json, "wide lens near, strobes 60 cm apart");
    let far = row(&json, "long lens far, strobes 60 cm apart");
    let port = row(&json, "long lens far, strobes at the port");
    let apart = row(&json, "long lens far, strobes 1.2 m apart");
    for r in rows(&json) {
        let c = f(&r["contrast"]);
        assert!(c > 0.0 && c < 1.0, "{}: contrast {c}", r["label"]);
        // Same GSD for every case, so a 3× focal length sits ≈ 3× farther.
        assert!(f(&r["gsd_mm"]) > 0.0);
        // Green lake water: red is absorbed most, so the white squares look green.
        let g_over_r = 1.0 / f(&r["r_over_g"]);
        assert!(g_over_r > 1.0, "{}: G/R {g_over_r}", r["label"]);
    }
    let ratio = f(&far["distance_m"]) / f(&near["distance_m"]);
    assert!((2.5..3.5).contains(&ratio), "distance ratio {ratio}");
    // Contrast falls with distance at the same GSD.
    assert!(
        f(&far["contrast"]) < f(&near["contrast"]),
        "far {} near {}",
        far["contrast"],
        near["contrast"]
    );
    // The longer water path casts more green.
    assert!(f(&far["r_over_g"]) < f(&near["r_over_g"]));
    // Strobes far from the port light less of the water in front of it.
    let (bp, ba) = (f(&port["backscatter"][1]), f(&apart["backscatter"][1]));
    assert!(
        ba > 0.0 && ba < bp,
        "backscatter apart {ba} at the port {bp}"
    );
    assert!(f(&apart["veiling_share"]) < f(&port["veiling_share"]));
    let dom = check_page(&out, &json);
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        assert_eq!(
            cell(&dom, &format!("{k}.contrast")),
            format!("{:.3}", f(&r["contrast"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.r_over_g")),
            format!("{:.3}", f(&r["r_over_g"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.b_over_g")),
            format!("{:.3}", f(&r["b_over_g"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.backscatter")),
            format!("{:.3e}", f(&r["backscatter"][1]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.distance_m")),
            format!("{:.3}", f(&r["distance_m"]))
        );
    }
}

#[test]
fn gsd_lesson_quick_form_plans_heights_and_resolves_about_a_gsd() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/gsd_reef.toml", "gsd");
    assert_eq!(json["results"]["kind"], "gsd");
    for port in ["flat port", "dome"] {
        let one = row(&json, &format!("{port}, 1 mm"));
        let three = row(&json, &format!("{port}, 3 mm"));
        let (h1, h3) = (f(&one["height_m"]), f(&three["height_m"]));
        assert!((2.8..3.2).contains(&(h3 / h1)), "{port}: heights {h1} {h3}");
    }
    for r in rows(&json) {
        let label = r["label"].as_str().unwrap();
        let (h, air) = (f(&r["height_m"]), f(&r["height_air_m"]));
        if label.starts_with("flat") {
            // A flat port magnifies by about the water's index.
            assert!((1.28..1.38).contains(&(h / air)), "{label}: {h} / {air}");
        } else {
            // A centred dome keeps about the height in air.
            assert!((0.9..1.1).contains(&(h / air)), "{label}: {h} / {air}");
        }
        // The camera was placed where the GSD is the planned one.
        let g = f(&r["gsd_at_star_mm"]) / f(&r["gsd_mm"]);
        assert!(
            (0.99..1.01).contains(&g),
            "{label}: GSD at the star / planned {g}"
        );
        let q = f(&r["resolved_over_gsd"]);
        assert!((1.0..3.0).contains(&q), "{label}: resolved / GSD {q}");
        let px = f(&r["smallest_resolved_px"]);
        assert!((1.0..3.0).contains(&px), "{label}: {px} px");
    }
    let dom = check_page(&out, &json);
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        for (key, prec) in [
            ("height_m", 3),
            ("height_air_m", 3),
            ("smallest_resolved_mm", 2),
            ("smallest_resolved_px", 2),
            ("resolved_over_gsd", 2),
        ] {
            assert_eq!(
                cell(&dom, &format!("{k}.{key}")),
                format!("{:.*}", prec, f(&r[key])),
                "{k}.{key}"
            );
        }
    }
}
