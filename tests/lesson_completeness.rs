//! The coral self-occlusion lesson (`scenarios/lessons/coral_self_occlusion.toml`, kind
//! `completeness`) end to end on its quick form, and the procedural coral it stands on. No
//! Python: this runs in the fast tier (the page in Chromium: `lesson_completeness_page.rs`).
//!
//! Physics bands: seen from all round (a dome of rings, an orbit) a branching colony is far
//! more complete than from a nadir lawnmower, whose images see the tops of the branches and
//! little of their sides; a massive dome hides less of itself than a branching colony, so
//! under nadir it is more complete; shares lie in [0, 1], completeness below "seen at all"
//! (that the numbers do not change with the thread count: the full tier's page test).

use poser::geometry::mesh::{TriMesh, shape_mesh};
use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

const SCENE: &str = "scenarios/lessons/coral_self_occlusion.toml";

fn row<'a>(json: &'a serde_json::Value, label: &str) -> &'a serde_json::Value {
    json["results"]["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["label"] == label)
        .unwrap_or_else(|| panic!("no row `{label}`"))
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
fn quick_form_measures_coral_completeness_in_the_physical_bands_and_shows_it() {
    let (_tmp, out, json) = crate::support::lesson::run_lesson(SCENE, "coral");
    assert_eq!(json["results"]["kind"], "completeness");
    assert_eq!(json["form"], "quick");
    let rows = json["results"]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    for r in rows {
        let (seen, c) = (f(&r["seen"]), f(&r["completeness"]));
        assert!(
            (0.0..=1.0).contains(&seen) && (0.0..=1.0).contains(&c),
            "{r}"
        );
        assert!(c <= seen, "{r}");
        assert!(r["images"].as_u64().unwrap() >= 30, "{r}");
        assert!(f(&r["area_m2"]) > 0.05, "{r}");
        assert_eq!(r["samples"], 20_000);
    }
    let c = |label: &str| f(&row(&json, label)["completeness"]);
    // All round beats straight down on a branching colony, by far.
    for all_round in ["branching, dome of rings", "branching, orbit"] {
        assert!(
            c(all_round) > c("branching, nadir lawnmower") + 0.2,
            "{all_round}: {} vs nadir {}",
            c(all_round),
            c("branching, nadir lawnmower")
        );
    }
    // A massive dome hides less of itself than a branching colony.
    assert!(
        c("massive, nadir lawnmower") > c("branching, nadir lawnmower") + 0.2,
        "{json}"
    );
    for net in ["nadir lawnmower", "dome of rings", "orbit"] {
        assert!(
            c(&format!("massive, {net}")) >= c(&format!("branching, {net}")),
            "{net}"
        );
    }
    // The page holds every number, formatted as it formats them, and a top and a side map per
    // case; it is self-contained.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for r in rows {
        let k = poser::lesson::slug(r["label"].as_str().unwrap());
        let cell = |q: &str| {
            let tag = format!("data-key=\"{k}.{q}\">");
            let i = html.find(&tag).unwrap_or_else(|| panic!("no cell {k}.{q}")) + tag.len();
            html[i..i + html[i..].find('<').unwrap()].to_string()
        };
        assert_eq!(
            cell("completeness"),
            format!("{:.1}", 100.0 * f(&r["completeness"]))
        );
        assert_eq!(cell("seen"), format!("{:.1}", 100.0 * f(&r["seen"])));
        assert_eq!(cell("images"), r["images"].to_string());
        assert_eq!(cell("area_m2"), format!("{:.3}", f(&r["area_m2"])));
        assert_eq!(cell("mean_images"), format!("{:.1}", f(&r["mean_images"])));
    }
    // Two maps per case, and the camera's view.
    assert_eq!(
        html.matches("src=\"data:image/png;base64,").count(),
        2 * rows.len() + 1
    );
    for bad in ["src=\"http", "href=\"http", "<script", "url("] {
        assert!(!html.contains(bad), "not self-contained: {bad}");
    }
    // Same scene, same seed, one thread instead of two: the same numbers (a second run of
    // the lesson, in the full tier: `lesson_completeness_page.rs`).
}

/// Every directed edge has its reverse exactly once: closed, consistently wound.
fn closed_and_consistent(m: &TriMesh) -> bool {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    edges
        .iter()
        .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

#[test]
fn the_lesson_corals_are_deterministic_closed_meshes_with_outward_normals() {
    for growth in ["branching", "massive"] {
        let set = vec![format!("objects.1.growth=\"{growth}\"")];
        let m = poser::scene::load(Path::new(SCENE), &set).unwrap().model;
        let o = &m.objects[1];
        let mesh = shape_mesh(&o.shape, Path::new(".")).unwrap();
        assert_eq!(mesh, shape_mesh(&o.shape, Path::new(".")).unwrap());
        assert!(closed_and_consistent(&mesh), "{growth}");
        assert!(
            mesh.signed_volume() > 0.0,
            "{growth}: normals point inwards"
        );
        let (lo, hi) = mesh.bounds().unwrap();
        // Within its radius (0.4 m) and a bit, standing on z = 0 with the base buried.
        assert!(lo.z < 0.0 && hi.z > 0.2, "{growth}: {lo} {hi}");
        assert!(
            lo.x > -0.6 && hi.x < 0.6 && lo.y > -0.6 && hi.y < 0.6,
            "{growth}"
        );
        // Another seed grows another colony.
        let other = poser::scene::load(
            Path::new(SCENE),
            &[set[0].clone(), "objects.1.seed=2".into()],
        )
        .unwrap()
        .model;
        assert_ne!(
            mesh,
            shape_mesh(&other.objects[1].shape, Path::new(".")).unwrap()
        );
    }
}

#[test]
fn bad_coral_keys_are_located_errors_with_help() {
    let err = |set: &str| {
        poser::scene::load(Path::new(SCENE), &[set.to_string()])
            .err()
            .map(|f| f.render())
            .unwrap_or_default()
    };
    let e = err("objects.1.growth=\"massiv\"");
    assert!(e.contains("did you mean `massive`"), "{e}");
    let e = err("objects.1.radius=\"20 m\"");
    assert!(
        e.contains("E0288") && e.contains("objects[1].radius"),
        "{e}"
    );
    let e = err("objects.1.radius=\"-1 m\"");
    assert!(e.contains("objects[1].radius"), "{e}");
    // A completeness lesson without a coral or a mesh says what to add.
    let tmp = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args([
            "lesson",
            SCENE,
            "-o",
            tmp.path().join("x").to_str().unwrap(),
            "--quiet",
            "--set",
            "objects.1={name = \"rock\", shape = \"sphere\", radius = \"0.3 m\"}",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("needs a coral or a mesh object") && e.contains("help:"),
        "{e}"
    );
}
