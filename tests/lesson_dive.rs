//! The dive lessons end to end, on their quick forms, through the binary: the SCUBA survey
//! (kind `dive`) and the archaeology excavation (kind `survey`, with the real COLMAP through
//! pycolmap for the accuracy), each page opened in real headless Chromium.
//!
//! The numbers must fall in the bands physics and the dive rules predict: Boyle's rule of
//! thumb for 12 l at 15 m and 40 m, a decompression obligation and a verdict that is not OK
//! for the paper's 104-minute dive on air, a longer no-stop time on EAN32, more gas and fewer
//! minutes deeper, accuracy no better in the plume; and the page must show them in their
//! `data-key` cells.

use crate::support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::lesson::{assert_self_contained, cell, dump_dom, screenshot_variance};

fn run_lesson(scene: &str, name: &str) -> (tempfile::TempDir, PathBuf, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["lesson", scene, "-o", out.to_str().unwrap(), "--quiet"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run poser");
    assert!(
        o.status.success(),
        "poser lesson {scene} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lesson.json")).unwrap()).unwrap();
    (tmp, out, json)
}

fn rows(json: &serde_json::Value) -> &Vec<serde_json::Value> {
    json["results"]["rows"].as_array().unwrap()
}

fn row<'a>(json: &'a serde_json::Value, label: &str) -> &'a serde_json::Value {
    rows(json)
        .iter()
        .find(|r| r["label"] == label)
        .unwrap_or_else(|| panic!("no row `{label}`"))
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn slug(label: &str) -> String {
    poser::lesson::slug(label)
}

/// The page is self-contained, has one dive plot per case, and is not blank; returns the DOM.
fn check_page(out: &Path, json: &serde_json::Value) -> String {
    let page = out.join("index.html");
    assert_self_contained(&std::fs::read_to_string(&page).unwrap());
    let dom = dump_dom(&page, out);
    assert!(
        dom.matches("<svg").count() >= rows(json).len(),
        "dive plots missing"
    );
    assert!(dom.contains("Try next") && dom.contains("Rule of thumb"));
    let var = screenshot_variance(&page, out);
    assert!(
        var > 200.0,
        "the screenshot looks blank (grey-level variance {var:.1})"
    );
    dom
}

/// Cells every dive row shows, formatted as the page formats them.
fn check_dive_cells(dom: &str, r: &serde_json::Value) {
    let k = slug(r["label"].as_str().unwrap());
    assert_eq!(cell(dom, &format!("{k}.images")), r["images"].to_string());
    assert_eq!(
        cell(dom, &format!("{k}.survey_min")),
        format!("{:.1}", f(&r["survey_min"]))
    );
    assert_eq!(
        cell(dom, &format!("{k}.deco_min")),
        format!("{:.1}", f(&r["deco_min"]))
    );
    assert_eq!(
        cell(dom, &format!("{k}.verdict")),
        if r["ok"] == true {
            "OK"
        } else {
            "NOT SAFE AS PLANNED"
        }
    );
    let dives = match r["dives"].as_u64() {
        Some(n) => n.to_string(),
        None => "no split fits".into(),
    };
    assert_eq!(cell(dom, &format!("{k}.dives")), dives);
}

#[test]
fn scuba_survey_lesson_reports_deco_gas_fixes_and_the_rule_of_thumb() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/scuba_survey.toml", "scuba");
    assert_eq!(json["results"]["kind"], "dive");
    let planned = row(&json, "as planned: 12 l of air");
    // The exercise: 20 strips, about 1100 m at 15 m, about 104 minutes.
    assert_eq!(planned["strips"], 20);
    assert!(
        (1000.0..1200.0).contains(&f(&planned["path_m"])),
        "{planned}"
    );
    assert!(
        (95.0..115.0).contains(&f(&planned["survey_min"])),
        "{planned}"
    );
    assert!((f(&planned["max_depth_m"]) - 15.0).abs() < 0.5);
    // 104 minutes at 15 m on air is far past the no-stop time (ZHL-16C at GF 30/75: under an
    // hour at 15 m): a decompression obligation, and 12 l cannot supply ≈ 100 min at 2.5 bar.
    assert_eq!(planned["ok"], false);
    assert_eq!(planned["deco_required"], true);
    assert_eq!(planned["gas_ok"], false);
    assert!(f(&planned["deco_min"]) > 0.0, "{planned}");
    let ndl_air = f(&planned["ndl_runs_out_min"]);
    assert!((30.0..80.0).contains(&ndl_air), "{planned}");
    // The planner splits it into dives that are each within the rules.
    assert!(
        planned["dives"].as_u64().is_some_and(|n| n >= 2),
        "{planned}"
    );
    // EAN32 holds less nitrogen: the no-stop time is longer (or not reached).
    let nitrox = row(&json, "EAN32, 12 l");
    let ndl_nx = f(&nitrox["ndl_runs_out_min"]);
    assert!(
        nitrox["ndl_runs_out_min"].is_null() || ndl_nx > ndl_air + 5.0,
        "EAN32 {ndl_nx} vs air {ndl_air}"
    );
    // A twin set doubles the gas, not the no-stop time: the same breathing and deco, fewer
    // dives in the split.
    let twin = row(&json, "twin 12 l of air");
    let start = |r: &serde_json::Value| f(&r["cylinders"][0]["start_l"]);
    assert!((start(twin) / start(planned) - 2.0).abs() < 0.01, "{twin}");
    assert_eq!(twin["ndl_runs_out_min"], planned["ndl_runs_out_min"]);
    assert!(twin["dives"].as_u64() < planned["dives"].as_u64(), "{twin}");
    // A faster swim shortens the survey in proportion.
    let fast = row(&json, "air, swum at 0.2 m/s");
    let ratio = f(&planned["survey_min"]) / f(&fast["survey_min"]);
    assert!((ratio - 0.2 / 0.176).abs() < 0.03, "{ratio}");
    // Never "OK" with a problem; split dives only for plans that are not OK.
    for r in rows(&json) {
        assert_eq!(
            r["ok"] == true,
            r["problems"].as_array().unwrap().is_empty(),
            "{r}"
        );
        if r["ok"] == true {
            assert_eq!(r["dives"], 1);
        }
    }
    // Rule of thumb: 12 l × 200 bar / (20 l/min × 2.5 bar) = 48 min at 15 m, 24 min at 40 m;
    // the real gas and sea water give a little less, the 50 bar reserve a quarter less again.
    let rule = &json["results"]["rule_of_thumb"];
    let at = |d: f64| {
        rule["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| (f(&r["depth_m"]) - d).abs() < 0.1)
            .unwrap_or_else(|| panic!("no rule-of-thumb row at {d} m"))
    };
    let (r15, r40) = (at(15.0), at(40.0));
    assert!((f(&r15["rule_min"]) - 48.0).abs() < 1e-6);
    assert!((f(&r40["rule_min"]) - 24.0).abs() < 1e-6);
    assert!((42.0..48.0).contains(&f(&r15["to_empty_min"])), "{r15}");
    assert!((20.0..24.0).contains(&f(&r40["to_empty_min"])), "{r40}");
    for r in [r15, r40] {
        let share = f(&r["to_reserve_min"]) / f(&r["to_empty_min"]);
        assert!((0.7..0.8).contains(&share), "{r}");
    }
    let dom = check_page(&out, &json);
    for r in rows(&json) {
        check_dive_cells(&dom, r);
    }
    assert_eq!(
        cell(&dom, "rule_15m.to_empty_min"),
        format!("{:.1}", f(&r15["to_empty_min"]))
    );
    assert_eq!(
        cell(&dom, "rule_40m.to_reserve_min"),
        format!("{:.1}", f(&r40["to_reserve_min"]))
    );
    assert!(dom.contains("NOT SAFE AS PLANNED"));
}

#[test]
fn archaeology_lesson_reports_images_dives_gas_and_accuracy() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/archaeology.toml", "archaeology");
    assert_eq!(json["results"]["kind"], "survey");
    let clear = row(&json, "25 m, clear");
    let plume = row(&json, "25 m, excavation plume");
    let close = row(&json, "25 m, plume, camera at 1 m");
    let deep = row(&json, "40 m, clear");
    // A few hundred images in the quick form; closer means more of them, and a finer GSD.
    for r in rows(&json) {
        let n = r["images"].as_u64().unwrap();
        assert!((50..600).contains(&n), "{r}");
        assert_eq!(r["accuracy"]["registered"], r["accuracy"]["images"]);
        assert_eq!(r["accuracy"]["alignment"], "gcp");
    }
    assert!(close["images"].as_u64() > clear["images"].as_u64());
    assert!(f(&close["gsd_mm"]) < f(&clear["gsd_mm"]));
    // The plume leaves less of the targets' contrast; the camera brought closer wins some back.
    assert!(f(&plume["contrast_left"]) < 0.8 * f(&clear["contrast_left"]));
    assert!(f(&close["contrast_left"]) > f(&plume["contrast_left"]));
    // Same geometry, same observations: the plume cannot make the model more accurate.
    assert!(
        f(&plume["accuracy"]["rms_3d_mm"]) >= f(&clear["accuracy"]["rms_3d_mm"]) - 1e-9,
        "{plume} {clear}"
    );
    // Accuracy at 0.3 px noise, 1.5 m away, aligned on GCPs: millimetres, not centimetres.
    for r in [clear, deep] {
        assert!(f(&r["accuracy"]["rms_3d_mm"]) < 5.0, "{r}");
    }
    // 40 m costs more gas per minute (5.1 vs 3.5 bar ambient) and allows fewer minutes: the
    // same survey breathes more and is no more within the rules than at 25 m.
    let used = |r: &serde_json::Value| f(&r["cylinders"][0]["used_l"]);
    assert!(
        used(deep) > 1.3 * used(clear),
        "{} vs {}",
        used(deep),
        used(clear)
    );
    let ndl_or_inf = |r: &serde_json::Value| {
        r["ndl_runs_out_min"]
            .as_f64()
            .unwrap_or(f64::INFINITY)
            .min(r["min_ndl_min"].as_f64().unwrap_or(f64::INFINITY) + f(&r["survey_min"]))
    };
    assert!(ndl_or_inf(deep) < ndl_or_inf(clear), "{deep} {clear}");
    assert!(deep["dives"].as_u64().unwrap_or(u64::MAX) >= clear["dives"].as_u64().unwrap());
    assert!(f(&deep["max_depth_m"]) > 38.0 && f(&clear["max_depth_m"]) < 25.0);
    let dom = check_page(&out, &json);
    for r in rows(&json) {
        check_dive_cells(&dom, r);
        let k = slug(r["label"].as_str().unwrap());
        assert_eq!(
            cell(&dom, &format!("{k}.rms_3d_mm")),
            format!("{:.1}", f(&r["accuracy"]["rms_3d_mm"]))
        );
        assert!(out.join(&k).join("report.md").exists());
    }
}
