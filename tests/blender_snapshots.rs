//! Snapshots of what `poser compile --backend blender` writes for the example and canonical
//! scenes: the scene description (the data part of `scene.py`, as in `scene.json`), the list
//! of assets, and the script skeleton. The embedded builder source is left out so that the
//! snapshots stay readable; it is linted and tested on its own (backends/blender/tests).

use poser::backend::blender::{data, readable_json, script_with_sources};
use std::path::{Path, PathBuf};

/// The three example scenes of the brief and the canonical port scenes. A fixed list, so that a
/// scene added elsewhere does not need a snapshot here first.
const SCENES: [&str; 7] = [
    "scenarios/calibration_flat.toml",
    "scenarios/dome_orbit.toml",
    "scenarios/reef_strip.toml",
    "tests/canonical/pinhole_air.toml",
    "tests/canonical/flat_tilted.toml",
    "tests/canonical/dome_decentred.toml",
    "tests/canonical/cylinder_off_axis.toml",
];

fn scenes() -> Vec<PathBuf> {
    SCENES.iter().map(PathBuf::from).collect()
}

/// FNV-1a, to pin asset bytes without storing them.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x100000001b3)
    })
}

#[test]
fn compiled_scenes() {
    let mut seen = 0;
    for path in scenes() {
        let loaded = poser::scene::load(&path, &[])
            .unwrap_or_else(|f| panic!("{}: {}", path.display(), f.render()));
        let desc =
            data::describe(&loaded.model).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut text = readable_json(&desc.json);
        text.push_str("\n# assets\n");
        for a in &desc.assets {
            text.push_str(&format!(
                "{}  {} bytes  fnv {:016x}\n",
                a.path,
                a.bytes.len(),
                fnv(&a.bytes)
            ));
        }
        for w in &desc.warnings {
            text.push_str(&format!("# warning: {w}\n"));
        }
        let name = format!(
            "{}__{}",
            Path::new(&path)
                .parent()
                .unwrap()
                .display()
                .to_string()
                .replace('/', "_"),
            path.file_stem().unwrap().to_string_lossy()
        );
        insta::assert_snapshot!(name, text);
        seen += 1;
    }
    assert_eq!(seen, SCENES.len());
}

#[test]
fn script_skeleton() {
    let loaded = poser::scene::load(Path::new("scenarios/calibration_flat.toml"), &[])
        .map_err(|f| f.render())
        .unwrap();
    let desc = data::describe(&loaded.model).unwrap();
    let full = script_with_sources(&desc.json, true);
    assert!(full.is_ascii());
    // The skeleton, with the JSON literal cut to its first characters.
    let skeleton = script_with_sources(&desc.json, false);
    let cut: Vec<String> = skeleton
        .lines()
        .map(|l| match l.strip_prefix("SCENE_JSON = ") {
            Some(lit) => format!("SCENE_JSON = {}...", &lit[..60]),
            None => l.to_string(),
        })
        .collect();
    insta::assert_snapshot!(cut.join("\n"));
}
