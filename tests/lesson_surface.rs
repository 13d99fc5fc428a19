//! `poser lesson` kind `surface` end to end on the drone lesson's quick form (native renders,
//! the exact view through the surface, the caustic volume), with the page in real headless
//! Chromium (hence the `backends` tier).
//!
//! The bands physics predicts: the higher the waves, the farther they move a seabed target in
//! the image, and calm 5 cm waves move it by about a pixel at most; caustics are faint just
//! below calm water and grow with depth towards their focus, while steeper waves focus them
//! nearer the surface, so the depth of the strongest caustics moves up as the waves grow.

use crate::support;

use support::lesson::{
    assert_self_contained, cell, dump_dom, f, row, rows, run_lesson, screenshot_variance, slug,
};

/// Depth (m) of the largest caustic contrast of a row.
fn focus(r: &serde_json::Value) -> f64 {
    r["caustic_contrast"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (f(&p[0]), f(&p[1])))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .0
}

#[test]
fn surface_lesson_quick_form_moves_targets_with_the_waves_and_shows_it() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/uav_through_waves.toml", "uav");
    assert_eq!(json["results"]["kind"], "surface");
    let calm = row(&json, "calm, 5 cm waves");
    let chop = row(&json, "light chop, 15 cm waves");
    let choppy = row(&json, "choppy, 40 cm waves");
    for r in rows(&json) {
        assert!(r["points"].as_u64().unwrap() >= 10, "{}", r["label"]);
        assert_eq!(r["caustic_contrast"].as_array().unwrap().len(), 10);
        for p in r["caustic_contrast"].as_array().unwrap() {
            let c = f(&p[1]);
            assert!(c > 0.0 && c < 3.0, "{}: contrast {c}", r["label"]);
        }
    }
    let moved = |r: &serde_json::Value| f(&r["moved_rms_px"]);
    assert!(
        moved(calm) > 0.1 && moved(calm) < 1.5,
        "calm {}",
        moved(calm)
    );
    assert!(moved(calm) < moved(chop) && moved(chop) < moved(choppy));
    assert!(f(&choppy["moved_max_px"]) >= moved(choppy));
    // Caustics: faint under calm water near the surface, focusing deeper than under chop.
    assert!(f(&calm["caustic_contrast"][0][1]) < f(&choppy["caustic_contrast"][0][1]));
    assert!(focus(calm) >= focus(chop) && focus(chop) >= focus(choppy));
    assert!(
        focus(calm) > focus(choppy),
        "calm {} choppy {}",
        focus(calm),
        focus(choppy)
    );

    let page = out.join("index.html");
    assert_self_contained(&std::fs::read_to_string(&page).unwrap());
    let dom = dump_dom(&page, &out);
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        assert_eq!(
            cell(&dom, &format!("{k}.moved_rms_px")),
            format!("{:.2}", moved(r))
        );
        assert_eq!(cell(&dom, &format!("{k}.points")), r["points"].to_string());
        assert_eq!(
            cell(&dom, &format!("{k}.caustic_5m")),
            format!("{:.3}", f(&r["caustic_contrast"][4][1]))
        );
    }
    assert!(dom.matches("src=\"data:image/png;base64,").count() >= rows(&json).len());
    assert!(dom.contains("<svg"), "the caustics plot is missing");
    let var = screenshot_variance(&page, &out);
    assert!(
        var > 200.0,
        "the screenshot looks blank (grey-level variance {var:.1})"
    );
}
