//! `poser lesson` end to end, on the quick forms, with the real COLMAP and OpenCV (pinned in
//! backends/requirements.txt) and the page opened in real headless Chromium (Debian's
//! `chromium`, installed by backends/setup.sh when run as root).
//!
//! Each lesson's numbers must fall in the band physics predicts, and the page must show them:
//! every number of `lesson.json` is found, formatted as the page formats it, in its
//! `data-key` cell of the DOM Chromium builds; the images and plots are there; and the
//! screenshot is not blank.

use crate::support;

use support::lesson::{cell, check_page, f, row, rows, run_lesson, slug};

#[test]
fn deformation_lesson_quick_form_bends_behind_a_flat_port_and_shows_it() {
    let (_tmp, out, json) = run_lesson(
        "scenarios/lessons/flat_port_deformation.toml",
        "deformation",
    );
    assert_eq!(json["results"]["kind"], "deformation");
    assert_eq!(json["form"], "quick");
    let flat = row(&json, "flat, pupil 3 cm");
    let dome = row(&json, "centred dome");
    let air = row(&json, "in air");
    let oblique = row(&json, "flat, pupil 3 cm, + obliques");
    let (p1, p10) = (
        row(&json, "flat, pupil 1 mm"),
        row(&json, "flat, pupil 10 cm"),
    );
    // A centred dome bends no ray through the pupil: the survey is the one in air, at the
    // noise level (0.3 px of 6000 at 1.2 m: well under 2 mm).
    for r in [air, dome] {
        assert!(f(&r["rms_z_mm"]) < 2.0, "{r}");
    }
    // Behind a flat port the block bends by centimetres, a systematic bowl, growing with the
    // pupil-to-port distance; a second, oblique pass cuts it.
    assert!(
        f(&flat["bowl_mm"]) > 10.0 * f(&dome["bowl_mm"]),
        "{flat} {dome}"
    );
    assert!(f(&flat["rms_z_mm"]) > 10.0, "{flat}");
    assert!(f(&flat["bowl_share"]) > 0.9, "{flat}");
    assert!(f(&p1["bowl_mm"]) < f(&flat["bowl_mm"]) && f(&flat["bowl_mm"]) < f(&p10["bowl_mm"]));
    assert!(
        f(&oblique["rms_z_mm"]) < 0.5 * f(&flat["rms_z_mm"]),
        "{oblique}"
    );
    // Every image is fitted to about half a pixel: the processing looks fine.
    for r in rows(&json) {
        assert!(f(&r["reprojection_px"]) < 1.0, "{r}");
        assert_eq!(r["registered"], r["images"]);
    }
    // The numbers `poser evaluate` gives on these quick forms (the lesson runs the same
    // evaluations: same models, `evaluate`'s default options; tests/evaluate.rs no longer
    // repeats them). In air: 0.3 px of noise at a GSD of 0.4 mm, and the focal length found.
    assert!(f(&air["reprojection_px"]) < 0.45, "{air}");
    assert!(f(&air["focal_error_percent"]).abs() < 0.5, "{air}");
    // Behind the flat port the heights are bent, systematically, far beyond the noise; an
    // oblique pass cuts the error several times and a centred dome removes it.
    let z = |r: &serde_json::Value| f(&r["rms_z_mm"]);
    assert!(z(&flat) > 20.0 * z(&air), "{flat} {air}");
    assert!(z(&oblique) * 3.0 < z(&flat), "{oblique} {flat}");
    assert!(z(&dome) * 10.0 < z(&flat), "{dome} {flat}");
    // The error grows with the pupil-to-port distance.
    assert!(z(&p1) < z(&flat) && z(&flat) < z(&p10), "{p1} {flat} {p10}");
    let dom = check_page(&out, &json);
    // The quick form says so, and how to run the full one.
    assert!(dom.contains("Quick form.") && dom.contains("--full"));
    // One colour scale for every map: the largest case's (the flat port's, not the dome's
    // fraction of a millimetre), printed on the page.
    let scale = rows(&json)
        .iter()
        .map(|r| f(&r["own_scale_mm"]))
        .fold(0.0, f64::max);
    assert!(scale > 10.0 * f(&dome["own_scale_mm"]), "{scale}");
    for r in rows(&json) {
        assert_eq!(f(&r["map_scale_mm"]), scale);
    }
    assert_eq!(cell(&dom, "map_scale_mm"), format!("{scale:.1}"));
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        assert_eq!(
            cell(&dom, &format!("{k}.rms_z_mm")),
            format!("{:.1}", f(&r["rms_z_mm"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.nmad_z_mm")),
            format!("{:.1}", f(&r["nmad_z_mm"]))
        );
        // Each map's colour-bar range is printed beside it, the page's one scale.
        assert_eq!(
            cell(&dom, &format!("{k}.map_range_mm")),
            format!("−{scale:.1} … +{scale:.1}")
        );
        assert_eq!(
            cell(&dom, &format!("{k}.bowl_mm")),
            format!("{:.1}", f(&r["bowl_mm"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.focal_error_percent")),
            format!("{:+.2}", f(&r["focal_error_percent"]))
        );
        // Each variant's own evaluation report is there too.
        assert!(out.join(&k).join("report.md").exists());
    }
}

#[test]
fn calibration_lesson_quick_form_measures_each_port_and_shows_it() {
    let (_tmp, out, json) = run_lesson("scenarios/lessons/calibration_by_port.toml", "calibration");
    assert_eq!(json["results"]["kind"], "calibration");
    let air = row(&json, "in air");
    let flat = row(&json, "flat port");
    let dome = row(&json, "centred dome");
    let off = row(&json, "decentred dome");
    let cyl = row(&json, "cylinder");
    for r in rows(&json) {
        let c = &r["calibration"];
        assert!(c["views"].as_array().unwrap().len() >= 10, "{}", r["label"]);
        assert!(f(&c["rms"]) < 1.0, "{}: RMS {}", r["label"], c["rms"]);
    }
    // In air the calibration finds the lens: f/f_air = 1.
    assert!((f(&air["fx_ratio"]) - 1.0).abs() < 0.02, "{air}");
    // A flat port multiplies the paraxial focal length by the water's index (fresh water
    // 1.333 at 550 nm; the calibrated value also absorbs part of the port's pincushion).
    for k in ["fx_ratio", "fy_ratio"] {
        let v = f(&flat[k]);
        assert!((1.30..1.38).contains(&v), "flat port {k} = {v}");
    }
    // and its pincushion shows as a positive k1.
    assert!(f(&flat["calibration"]["dist"]["k1"]) > 0.1, "{flat}");
    // A centred dome leaves the focal length alone; a decentred one changes it.
    assert!((f(&dome["fx_ratio"]) - 1.0).abs() < 0.03, "{dome}");
    assert!(
        (f(&off["fx_ratio"]) - f(&dome["fx_ratio"])).abs() > 0.02,
        "{off}"
    );
    // A cylinder with a vertical axis is a flat port along its axis (y) and dome-like across
    // it (x).
    assert!((1.28..1.38).contains(&f(&cyl["fy_ratio"])), "{cyl}");
    assert!(f(&cyl["fx_ratio"]) < f(&cyl["fy_ratio"]) - 0.1, "{cyl}");
    // Colour: none in air; a flat port separates red and blue more than a centred dome.
    let lc = |r: &serde_json::Value, k: &str| f(&r["calibration"]["lateral_colour"][k]);
    assert!(lc(air, "r_minus_b_px") < 0.05 && lc(air, "detected_r_minus_b_px") < 0.05);
    assert!(
        lc(flat, "detected_r_minus_b_px") > lc(dome, "detected_r_minus_b_px"),
        "{flat} {dome}"
    );
    let dom = check_page(&out, &json);
    assert!(
        dom.contains("pixel centres at integers"),
        "the pixel convention is not stated"
    );
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        assert_eq!(
            cell(&dom, &format!("{k}.fx_ratio")),
            format!("{:.3}", f(&r["fx_ratio"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.rms")),
            format!("{:.3}", f(&r["calibration"]["rms"]))
        );
        assert_eq!(
            cell(&dom, &format!("{k}.k1")),
            format!("{:.3}", f(&r["calibration"]["dist"]["k1"]))
        );
    }
}
