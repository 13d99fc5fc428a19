//! `poser compare` end to end (backends tier: it runs Mitsuba and Cycles): the report a person
//! reads, with the error against analytic radiometry, labelled chart, and a failing backend
//! making the command fail and shown as failed.

use std::path::Path;
use std::process::Command;

fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}

const SETS: [&str; 6] = [
    "--set",
    "camera.width=64",
    "--set",
    "camera.height=48",
    "--set",
    "render.samples=16",
];

#[test]
fn compare_reports_truth_analytic_and_each_backend() {
    // absorbing_strobe has a closed-form radiance (one spot, one Lambertian patch, absorbing
    // water): every backend's error against it is in the report.
    let dir = tempfile::tempdir().unwrap();
    let out = poser()
        .args(["compare", "tests/canonical/absorbing_strobe.toml", "-o"])
        .arg(dir.path())
        .args(["--backends", "native,mitsuba,blender"])
        .args(SETS)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    eprintln!("{md}");
    assert!(md.contains("Analytic radiometry: the first image"), "{md}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    for b in json["backends"].as_array().unwrap() {
        let name = b["backend"].as_str().unwrap();
        assert!(b["error"].is_null(), "{name}: {}", b["error"]);
        let rel = b["analytic_rel"].as_array().expect("analytic error");
        for (c, r) in rel.iter().enumerate() {
            let r = r.as_f64().unwrap();
            // 16 spp on a 16×12 window: a few percent of noise at most (measured in the log).
            assert!(
                r.abs() < 0.05,
                "{name} channel {c}: {r:+.4} against analytic"
            );
        }
    }
    assert_eq!(json["pairs"].as_array().unwrap().len(), 3);
    let svg = std::fs::read_to_string(dir.path().join("report.svg")).unwrap();
    for label in [
        "RMS error (px)",
        "relative error (%)",
        "radiance vs analytic",
        "blender",
    ] {
        assert!(svg.contains(label), "chart lacks {label}");
    }
}

#[test]
fn a_failing_backend_fails_the_command_and_is_shown_failed() {
    // Cycles without its Python (POSER_PYTHON pointing nowhere) fails; native renders.
    let dir = tempfile::tempdir().unwrap();
    let out = poser()
        .args(["compare", "tests/canonical/absorbing_strobe.toml", "-o"])
        .arg(dir.path())
        .args(["--backends", "native,blender"])
        .args(SETS)
        .env("POSER_PYTHON", Path::new("/nonexistent/python"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("backend `blender` failed"), "{stderr}");
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("| blender | failed:"), "{md}");
    assert!(md.contains("| native | ok |"), "{md}");
    let svg = std::fs::read_to_string(dir.path().join("report.svg")).unwrap();
    assert!(svg.contains("blender (failed)"), "{svg}");
    assert!(svg.lines().any(|l| l.trim() == "failed"), "{svg}");
}
