//! `poser lesson` kind `metrology` end to end on the subsea metrology lesson's quick form:
//! native renders for the light, `poser evaluate --rig --gcp` (real COLMAP) for the
//! accuracy, and the page in real headless Chromium — hence the `backends` tier.
//!
//! The bands physics predicts: lamps beside the ports light the water in front of them far more
//! than lamps on arms, so the backscatter and the veil over the target are larger; the rig
//! calibrated beforehand holds its focal length exactly and gives the block its scale to a
//! fraction of a millimetre per metre; one pair's depth precision is inversely proportional to
//! the baseline; the block, where every rig position along the pipe triangulates each point,
//! beats one narrow pair.

use crate::support;

use support::lesson::{
    assert_self_contained, cell, dump_dom, f, row, rows, run_lesson_with, screenshot_variance, slug,
};

#[test]
fn metrology_lesson_quick_form_compares_lamps_and_baselines_and_shows_it() {
    // The views at 16 samples per pixel, not the quick form's 64: the bands below are means
    // over the board and the water, which 16 samples already hold (the render is most of the
    // lesson's time).
    let (_tmp, out, json) = run_lesson_with(
        "scenarios/lessons/subsea_metrology.toml",
        "metrology",
        &["render.samples=16"],
    );
    assert_eq!(json["results"]["kind"], "metrology");
    assert_eq!(rows(&json).len(), 4);
    let ports = row(&json, "lamps at the ports, 30 cm baseline");
    let arms = row(&json, "lamps on arms, 30 cm baseline");
    let narrow = row(&json, "lamps on arms, 10 cm baseline");
    let wide = row(&json, "lamps on arms, 60 cm baseline");

    for r in rows(&json) {
        let l = &r["light"];
        let c = f(&l["contrast"]);
        assert!(c > 0.0 && c < 1.0, "{}: contrast {c}", r["label"]);
        for k in 0..2 {
            assert!(
                l["samples"][k].as_u64().unwrap() >= 100,
                "{}: the board is not in view: {}",
                r["label"],
                l["samples"]
            );
        }
        let a = &r["accuracy"];
        assert_eq!(a["registered"], a["images"], "{}", r["label"]);
        assert_eq!(a["alignment"], "gcp");
        assert!(a["alignment_count"].as_u64().unwrap() >= 6);
        // The rig is calibrated: its intrinsics are held at the in-water-equivalent values.
        assert!(f(&a["focal_error_percent"]).abs() < 1e-9, "{}", a);
        // Its baseline sets the block's scale: within 0.5 mm per metre of the control points.
        assert!(f(&a["scale_error_ppm"]).abs() < 500.0, "{}", a);
        let rms = f(&a["rms_3d_mm"]);
        assert!(rms > 0.0 && rms < 5.0, "{}: RMS 3D {rms} mm", r["label"]);
        // About 0.9 m to the board on the pipe's top.
        let z = f(&r["distance_m"]);
        assert!((0.8..1.0).contains(&z), "board depth {z}");
    }
    // Lamps beside the ports light the water in front of them: more backscatter, more veil.
    let (bp, ba) = (
        f(&ports["light"]["backscatter"][1]),
        f(&arms["light"]["backscatter"][1]),
    );
    assert!(
        ba > 0.0 && bp > 2.0 * ba,
        "backscatter at the ports {bp}, on arms {ba}"
    );
    assert!(f(&ports["light"]["veiling_share"]) > f(&arms["light"]["veiling_share"]));
    // One pair: σZ ∝ 1/B at the same distance and focal length.
    let ratio = f(&narrow["pair_sigma_z_mm"]) / f(&arms["pair_sigma_z_mm"]);
    assert!((ratio - 3.0).abs() < 1e-6, "σZ(10 cm)/σZ(30 cm) = {ratio}");
    let ratio = f(&arms["pair_sigma_z_mm"]) / f(&wide["pair_sigma_z_mm"]);
    assert!((ratio - 2.0).abs() < 1e-6, "σZ(30 cm)/σZ(60 cm) = {ratio}");
    // With a calibrated rig the block (every rig position along the pipe triangulates each
    // point) beats one narrow pair: σZ of a 10 cm pair is 1.4 mm at 0.9 m.
    let z = |r: &serde_json::Value| f(&r["accuracy"]["rms_xyz_mm"][2]);
    assert!(
        z(narrow) < f(&narrow["pair_sigma_z_mm"]),
        "RMS Z {} against one pair's σZ {}",
        z(narrow),
        f(&narrow["pair_sigma_z_mm"])
    );
    // The same lamps and rig, lit differently: the same geometry, the same accuracy.
    assert_eq!(
        ports["accuracy"]["rms_3d_mm"],
        arms["accuracy"]["rms_3d_mm"]
    );

    // The page: every number in its cell as the page formats it, the views, the plot.
    let page = out.join("index.html");
    assert_self_contained(&std::fs::read_to_string(&page).unwrap());
    let dom = dump_dom(&page, &out);
    for r in rows(&json) {
        let k = slug(r["label"].as_str().unwrap());
        let l = &r["light"];
        let a = &r["accuracy"];
        for (key, text) in [
            ("backscatter", format!("{:.3e}", f(&l["backscatter"][1]))),
            ("contrast", format!("{:.3}", f(&l["contrast"]))),
            (
                "veiling_share",
                format!("{:.1}", 100.0 * f(&l["veiling_share"])),
            ),
            ("baseline_m", format!("{:.2}", f(&r["baseline_m"]))),
            ("images", a["images"].to_string()),
            ("rms_z_mm", format!("{:.2}", f(&a["rms_xyz_mm"][2]))),
            ("rms_3d_mm", format!("{:.2}", f(&a["rms_3d_mm"]))),
            (
                "pair_sigma_z_mm",
                format!("{:.2}", f(&r["pair_sigma_z_mm"])),
            ),
            (
                "scale_error_ppm",
                format!("{:.0}", f(&a["scale_error_ppm"])),
            ),
        ] {
            assert_eq!(cell(&dom, &format!("{k}.{key}")), text, "{k}.{key}");
        }
    }
    assert!(
        dom.matches("src=\"data:image/png;base64,").count() >= 2 * rows(&json).len(),
        "views missing"
    );
    assert!(dom.contains("<svg"), "the baseline plot is missing");
    assert!(dom.contains("Try next"));
    let var = screenshot_variance(&page, &out);
    assert!(
        var > 200.0,
        "the screenshot looks blank (grey-level variance {var:.1})"
    );
}
