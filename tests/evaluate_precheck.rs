//! `poser evaluate --mode images` refuses an untextured scene before rendering it (SIFT finds
//! nothing on uniform albedo), with a hint; the shipped survey scenes pass the same check.
//! No Python: the check runs before COLMAP.

use std::process::Command;

#[test]
fn an_untextured_scene_is_refused_before_rendering() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ev");
    // reef_strip with every pattern removed: a plain grey seabed and plain boulders.
    let scene = tmp.path().join("plain.toml");
    let text = std::fs::read_to_string("scenarios/reef_strip.toml").unwrap();
    let plain = strip_patterns(&text);
    assert!(!plain.contains("pattern"), "{plain}");
    std::fs::write(&scene, plain).unwrap();
    let shared = tmp.path().join("shared");
    std::fs::create_dir_all(&shared).unwrap();
    for e in std::fs::read_dir("scenarios/shared").unwrap().flatten() {
        std::fs::copy(e.path(), shared.join(e.file_name())).unwrap();
    }
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .arg("evaluate")
        .arg(&scene)
        .args(["--mode", "images", "--quiet", "--set", "network.length=4"])
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("almost no texture") && err.contains("help:"),
        "{err}"
    );
    assert!(
        !out.join("images").exists(),
        "nothing may be rendered for a scene that is refused"
    );
}

/// The scene without its `pattern = …` lines and `[objects.pattern]` tables.
fn strip_patterns(text: &str) -> String {
    let mut out = String::new();
    let mut skipping = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with('[') {
            skipping = t.contains(".pattern]");
        }
        if skipping || t.starts_with("pattern") || t.starts_with("variation") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

#[test]
fn the_shipped_survey_scenes_see_enough_texture() {
    for s in [
        "scenarios/reef_strip.toml",
        "scenarios/dome_orbit.toml",
        "scenarios/paper_survey.toml",
        // Both were refused before their patterns (a checker with nothing at the pixel; none).
        "scenarios/lessons/archaeology.toml",
        "scenarios/lessons/coral_self_occlusion.toml",
        "scenarios/lessons/subsea_metrology.toml",
    ] {
        let m = poser::scene::load(std::path::Path::new(s), &[])
            .unwrap_or_else(|f| panic!("{}", f.render()))
            .model;
        let seen = poser::evaluate::check_images_texture(&m).unwrap_or_else(|e| panic!("{s}: {e}"));
        assert!(seen.textured > 0.5, "{s}: {seen:?}");
    }
}

#[test]
fn a_calibrated_rig_belongs_to_observations_mode() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ev");
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args([
            "evaluate",
            "scenarios/lessons/subsea_metrology.toml",
            "--mode",
            "images",
            "--rig",
            "--quiet",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("--rig belongs to `--mode observations`"),
        "{err}"
    );
    assert!(!out.exists(), "nothing may be written");
}
