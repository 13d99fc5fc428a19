//! Every example scene under `scenarios/` loads with no errors and no warnings, and resolves
//! to a model with cameras and poses.
use std::path::Path;

#[test]
fn every_example_scene_validates() {
    let mut n = 0;
    let mut entries: Vec<_> = std::fs::read_dir("scenarios")
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        n += 1;
        match poser::scene::load(&p, &[]) {
            Ok(l) => {
                assert!(
                    l.warnings.is_empty(),
                    "{}: warnings:\n{}",
                    p.display(),
                    l.render_warnings()
                );
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
