//! `poser compare`'s per-target residuals (issue 37), with the native backend alone (fast
//! tier; the three backends together are `compare_cli`): every disk the truth expects in an
//! image is listed with its exact centre and each backend's measured offset, in report.md and
//! report.json, and the backend's RMS is the RMS of those offsets.

use std::process::Command;

#[test]
fn compare_lists_every_target_with_its_offset_from_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["compare", "scenarios/calibration_flat.toml", "-o"])
        .arg(dir.path())
        .args(["--backends", "native", "--scale", "0.2", "--samples", "4"])
        .args(["--poses", "0"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    let native = &json["backends"][0];
    let targets = native["targets"].as_array().unwrap();
    let expected = native["targets_expected"].as_u64().unwrap() as usize;
    assert!(
        expected >= 4,
        "the first pose sees the board's disks: {expected}"
    );
    assert_eq!(targets.len(), expected);
    let offsets: Vec<[f64; 2]> = targets
        .iter()
        .filter_map(|t| t["offset"].as_array())
        .map(|o| [o[0].as_f64().unwrap(), o[1].as_f64().unwrap()])
        .collect();
    assert_eq!(
        offsets.len(),
        native["targets_measured"].as_u64().unwrap() as usize
    );
    let rms = (offsets
        .iter()
        .map(|d| d[0] * d[0] + d[1] * d[1])
        .sum::<f64>()
        / offsets.len() as f64)
        .sqrt();
    let reported = native["target_rms_px"].as_f64().unwrap();
    assert!((rms - reported).abs() < 1e-9, "{rms} vs {reported}");
    // Every disk in report.md, with its exact centre as the JSON has it, and the convention.
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("pixel centres at +0.5"), "{md}");
    assert!(
        md.contains("| target | image | exact u, v | native Δu, Δv (px) |"),
        "{md}"
    );
    for t in targets {
        let truth = t["truth"].as_array().unwrap();
        let row = format!(
            "| {} | {} | {:.3}, {:.3} |",
            t["id"].as_str().unwrap(),
            t["image"].as_str().unwrap(),
            truth[0].as_f64().unwrap(),
            truth[1].as_f64().unwrap()
        );
        assert!(md.contains(&row), "report.md lacks {row}:\n{md}");
    }
}
