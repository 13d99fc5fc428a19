//! Every example scene under `scenarios/` (and `scenarios/lessons/`, `scenarios/sites/`) loads with no errors and no warnings, and resolves
//! to a model with cameras and poses. A scenario whose lesson is a warning declares it in a
//! header line `# expect-warnings: W0300 …`: then exactly those warnings must appear.
use std::path::Path;

#[test]
fn every_example_scene_validates() {
    let mut n = 0;
    let mut entries: Vec<_> = ["scenarios", "scenarios/lessons", "scenarios/sites"]
        .iter()
        .flat_map(|d| std::fs::read_dir(d).unwrap())
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        n += 1;
        let text = std::fs::read_to_string(&p).unwrap();
        let mut expected: Vec<String> = text
            .lines()
            .filter_map(|l| l.strip_prefix("# expect-warnings:"))
            .flat_map(|l| l.split_whitespace().map(str::to_string))
            .take_while(|w| !w.starts_with('—') && !w.starts_with('-'))
            .collect();
        expected.sort();
        match poser::scene::load(&p, &[]) {
            Ok(l) => {
                // What the front end resolves passes the model's own validation pass, which
                // the back ends run on every model, however built.
                if let Err(e) = l.model.validate() {
                    panic!("{}: {e}", p.display());
                }
                let mut got: Vec<String> = l.warnings.iter().map(|d| d.code.to_string()).collect();
                got.sort();
                assert_eq!(
                    got,
                    expected,
                    "{}: warnings:\n{}",
                    p.display(),
                    l.render_warnings()
                );
                if let Some(lesson) = &l.model.lesson {
                    // A lesson page opens with its answer in plain words: two or three
                    // sentences.
                    let sentences = lesson.shows.matches(". ").count() + 1;
                    assert!(
                        lesson.shows.ends_with('.') && (2..=4).contains(&sentences),
                        "{}: `lesson.shows` must say what the page shows in two or three \
                         sentences, found {sentences}: {:?}",
                        p.display(),
                        lesson.shows
                    );
                }
                assert!(!l.model.cameras.is_empty(), "{}: no cameras", p.display());
                assert!(!l.model.poses.is_empty(), "{}: no poses", p.display());
            }
            Err(f) => panic!("{} is invalid:\n{}", p.display(), f.render()),
        }
    }
    assert!(n >= 3, "expected at least three example scenes, found {n}");
}

#[test]
fn overrides_change_the_model() {
    let p = Path::new("scenarios/reef_strip.toml");
    let base = poser::scene::load(p, &[]).unwrap().model;
    let m = poser::scene::load(
        p,
        &["render.samples=7".into(), "site.depth=\"20 m\"".into()],
    )
    .unwrap()
    .model;
    assert_eq!(m.render.samples, 7);
    assert_eq!(m.site.depth, 20.0);
    assert_ne!(base.render.samples, 7);
}

fn poser(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn validate_exit_codes() {
    // 0: valid.
    let o = poser(&[
        "validate",
        "scenarios/calibration_flat.toml",
        "scenarios/reef_strip.toml",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // 1: invalid, with the diagnostic on stderr.
    let o = poser(&["validate", "tests/invalid/unknown_key_water.toml"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("tests/invalid/unknown_key_water.toml:4:1"),
        "{err}"
    );
    assert!(err.contains("did you mean `temperature`?"), "{err}");
    // 1: a bad override on an otherwise valid scene.
    let o = poser(&[
        "validate",
        "scenarios/reef_strip.toml",
        "--set",
        "water.temprature=12",
    ]);
    assert_eq!(o.status.code(), Some(1));
    // Warnings pass, unless denied.
    let o = poser(&["validate", "tests/invalid/warn_low_sidelap.toml"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("warning[W0300]"));
    let o = poser(&[
        "validate",
        "--deny-warnings",
        "tests/invalid/warn_low_sidelap.toml",
    ]);
    assert_eq!(o.status.code(), Some(1));
    // 2: usage error.
    let o = poser(&["validate"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn explain_prints_the_key_numbers() {
    let o = poser(&["explain", "scenarios/calibration_flat.toml"]);
    assert_eq!(o.status.code(), Some(0));
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "images: 5 ",
        "GSD",
        "footprint",
        "n = [",
        "lateral colour",
        "refraction: flat port",
    ] {
        assert!(out.contains(needle), "`{needle}` missing from:\n{out}");
    }
    // An override shows up in the explanation.
    let o = poser(&[
        "explain",
        "scenarios/calibration_flat.toml",
        "--set",
        "water.temperature=4",
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Quan–Fry at 4 °C"));
    // --json is the whole model.
    let o = poser(&["explain", "--json", "scenarios/reef_strip.toml"]);
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(!v["poses"].as_array().unwrap().is_empty());
    assert_eq!(v["render"]["samples"], 64);
}

#[test]
fn schema_check_passes_on_the_committed_files() {
    let o = poser(&["schema", "--check"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("schema");
    let docs = dir.path().join("docs");
    let o = poser(&[
        "schema",
        "--check",
        "-o",
        out.to_str().unwrap(),
        "--docs",
        docs.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "an empty directory is stale");
}

/// The README's main job, as a user types it (a pose range, the noise target "sensor"), at a
/// smaller scale and two poses: linear EXR, PNG, camera JPEG and ground truth per image,
/// images of the scaled size, a non-black and unsaturated preview (the scenario's exposure
/// suits its radiance), and the noise target's report: more samples than the pilot where the
/// pilot said so.
#[test]
fn readme_main_job_renders_previews_with_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("reef");
    let o = poser(&[
        "render",
        "scenarios/reef_strip.toml",
        "-o",
        out.to_str().unwrap(),
        "--scale",
        "0.05",
        "--poses",
        "0-1",
        "--samples",
        "2",
        "--set",
        "render.noise=sensor",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for img in ["img_0001", "img_0002"] {
        let noise: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("{img}.noise.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(noise["target"], 1.0, "{noise}");
        let mean = noise["samples"]["mean"].as_f64().unwrap();
        assert!(
            mean > 2.0,
            "{img}: {mean} samples per pixel after a pilot of 2"
        );
        assert!(out.join("camera").join(format!("{img}.jpg")).is_file());
        let png = image::open(out.join(format!("{img}.png")))
            .unwrap()
            .into_rgb8();
        assert_eq!((png.width(), png.height()), (60, 40));
        let px: Vec<u8> = png.into_raw();
        let mean = px.iter().map(|&v| v as f64).sum::<f64>() / px.len() as f64;
        let saturated = px.iter().filter(|&&v| v == 255).count() as f64 / px.len() as f64;
        assert!(
            mean > 20.0 && saturated < 0.05,
            "{img}: mean {mean}, saturated {saturated}"
        );
        assert!(out.join(format!("{img}.exr")).is_file());
    }
    assert!(out.join("truth").is_dir());
    let bad = poser(&[
        "render",
        "scenarios/reef_strip.toml",
        "-o",
        "/tmp/x",
        "--scale",
        "0",
    ]);
    assert_eq!(bad.status.code(), Some(2), "--scale 0 is a usage error");
    let bad = poser(&[
        "render",
        "scenarios/reef_strip.toml",
        "-o",
        "/tmp/x",
        "--poses",
        "3-1",
    ]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "an empty pose range is a usage error"
    );
    assert!(String::from_utf8_lossy(&bad.stderr).contains("empty range"));
}

/// `render.seed` draws the noise; `site.seed` the site. A new render seed must not move a
/// generated seabed or the waves (it once did: objects without a `seed` took render seed +
/// index, so two renders meant to differ only by their noise showed two different seabeds).
#[test]
fn the_render_seed_draws_noise_not_the_site() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    // Two generated objects without a `seed` of their own, and one with.
    std::fs::write(
        &scene,
        r#"
[site]
depth = "6 m"
[water]
jerlov = "II"
[camera]
width = 64
height = 48
pixel_pitch = "5 µm"
focal_length = "8 mm"
[[objects]]
shape = "seabed"
width = "4 m"
length = "4 m"
[[objects]]
shape = "boulders"
width = "4 m"
length = "4 m"
[[objects]]
shape = "coral"
seed = 40
position = [0.0, 0.0, -6.0]
[network]
type = "lawnmower"
width = "2 m"
length = "2 m"
altitude = "1.5 m"
"#,
    )
    .unwrap();
    let seeds = |sets: &[&str]| -> Vec<u64> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let m = poser::scene::load(&scene, &sets)
            .unwrap_or_else(|f| panic!("{}", f.render()))
            .model;
        m.objects
            .iter()
            .map(|o| match o.shape {
                poser::model::Shape::Seabed { seed, .. }
                | poser::model::Shape::Boulders { seed, .. }
                | poser::model::Shape::Coral { seed, .. } => seed,
                ref s => panic!("not generated: {s:?}"),
            })
            .collect()
    };
    assert_eq!(seeds(&[]), [0, 1, 40]);
    assert_eq!(seeds(&["render.seed=12345"]), [0, 1, 40]);
    assert_eq!(seeds(&["site.seed=7"]), [7, 8, 40]);
    // Waves: the wavy lesson's sea follows `site.seed` alone.
    let sea = |sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let m = poser::scene::load(Path::new("scenarios/lessons/uav_through_waves.toml"), &sets)
            .unwrap_or_else(|f| panic!("{}", f.render()))
            .model;
        format!("{:?}", m.sea_interface(1).unwrap().field)
    };
    let waves = sea(&[]);
    assert_eq!(sea(&["render.seed=99"]), waves);
    assert_ne!(sea(&["site.seed=99"]), waves);
}
