//! The skeleton of the `scene.py` that `poser compile --backend blender` writes: the script
//! around the data, with the embedded builder source and the scene literal cut, so that the
//! snapshot stays readable (the builder is linted and tested on its own in
//! backends/blender/tests). The scene descriptions themselves are pinned per scene by
//! `tests/compile_out.rs` in `tests/out/blender/`.

use poser::backend::blender::{data, script_with_sources};
use std::path::Path;

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
