//! The coral self-occlusion lesson's page opened in real headless Chromium (Debian's
//! `chromium`, installed by backends/setup.sh when run as root): every number of
//! `lesson.json` in its `data-key` cell of the DOM Chromium builds, formatted as the page
//! formats it; the seen/unseen maps decoded as images; the screenshot not blank; the same
//! numbers on one thread. The physics bands are checked in the fast tier
//! (`lesson_completeness.rs`).

use crate::support;

use base64::Engine as _;
use support::lesson::{
    assert_self_contained, cell, dump_dom, run_lesson, run_lesson_on_threads, screenshot_variance,
};

const SCENE: &str = "scenarios/lessons/coral_self_occlusion.toml";

#[test]
fn completeness_lesson_page_shows_every_number_and_map_in_chromium() {
    let (_tmp, out, json) = run_lesson(SCENE, "coral");
    let page = out.join("index.html");
    assert_self_contained(&std::fs::read_to_string(&page).unwrap());
    let dom = dump_dom(&page, &out);
    let rows = json["results"]["rows"].as_array().unwrap();
    for r in rows {
        let k = poser::lesson::slug(r["label"].as_str().unwrap());
        let f = |q: &str| r[q].as_f64().unwrap();
        assert_eq!(cell(&dom, &format!("{k}.images")), r["images"].to_string());
        assert_eq!(
            cell(&dom, &format!("{k}.samples")),
            r["samples"].to_string()
        );
        assert_eq!(
            cell(&dom, &format!("{k}.area_m2")),
            format!("{:.3}", f("area_m2"))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.seen")),
            format!("{:.1}", 100.0 * f("seen"))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.completeness")),
            format!("{:.1}", 100.0 * f("completeness"))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.mean_images")),
            format!("{:.1}", f("mean_images"))
        );
    }
    // Two maps per case and the camera's view, each a PNG that decodes and holds more than
    // one colour.
    let maps: Vec<&str> = dom
        .split("src=\"data:image/png;base64,")
        .skip(1)
        .map(|s| &s[..s.find('"').unwrap()])
        .collect();
    assert_eq!(maps.len(), 2 * rows.len() + 1);
    for m in maps {
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(m)
            .expect("base64");
        let img = image::load_from_memory(&bytes).expect("a PNG").to_rgb8();
        let first = img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| p != first), "a blank map");
    }
    assert!(dom.contains("Try next"));
    // Same scene, same seed, one thread: the same numbers (the timings aside).
    let (_one_tmp, _, one) = run_lesson_on_threads(SCENE, "coral", 1);
    let numbers = |json: &serde_json::Value| -> Vec<serde_json::Value> {
        let mut rows = support::lesson::rows(json).clone();
        for r in &mut rows {
            r.as_object_mut().unwrap().remove("seconds");
        }
        rows
    };
    assert_eq!(
        numbers(&json),
        numbers(&one),
        "one thread gave other numbers"
    );
    let var = screenshot_variance(&page, &out);
    assert!(
        var > 200.0,
        "the screenshot looks blank (grey-level variance {var:.1})"
    );
}
