//! The snapshot suite, in naga's shape: every scene in `tests/in/*.toml` goes through the front
//! end and each back end, and every result is pinned in `tests/out/<stage>/<scene>.snap`.
//!
//! | out | what is pinned |
//! |---|---|
//! | `tests/out/model/` | the resolved model as JSON (lists longer than 12 entries cut to their first three and last one; the checkout's path written `$CARGO_MANIFEST_DIR`) |
//! | `tests/out/mitsuba/` | the compiled file list, `world.xml` and the first view's XML (tabulated phase values cut); or Mitsuba's refusal |
//! | `tests/out/blender/` | the scene description that `scene.py` carries, its assets (size and FNV-1a hash), warnings; or Blender's refusal |
//!
//! The list of scenes is the directory: add a file to `tests/in/` and its three snapshots follow
//! (`cargo insta review`, or `INSTA_UPDATE=always cargo test --test suite compile_out::`, then review the
//! diff). A file there is usually a one-line `include` of a shipped scene, so that a scenario is
//! pinned exactly as a user runs it. The Mitsuba output is also compiled twice and compared, byte
//! for byte. Refusals are snapshots too: what a backend cannot express is part of its contract.

use poser::backend::{blender, mitsuba};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every `tests/in/*.toml`, sorted.
fn inputs() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("tests/in"))
        .expect("tests/in")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "tests/in has no scenes");
    v
}

fn settings(stage: &str, input: &Path) -> insta::Settings {
    let mut s = insta::Settings::clone_current();
    s.set_snapshot_path(root().join("tests/out").join(stage));
    s.set_prepend_module_to_snapshot(false);
    s.set_input_file(input);
    s.set_omit_expression(true);
    s
}

/// Cut every list longer than 12 entries to its first three entries, a marker and its last one.
fn cut_long_lists(v: &mut Value) {
    match v {
        Value::Array(a) => {
            for x in a.iter_mut() {
                cut_long_lists(x);
            }
            if a.len() > 12 {
                let n = a.len();
                let last = a[n - 1].clone();
                a.truncate(3);
                a.push(Value::String(format!("… {} more …", n - 4)));
                a.push(last);
            }
        }
        Value::Object(o) => o.values_mut().for_each(cut_long_lists),
        _ => {}
    }
}

fn model_text(model: &poser::model::Model) -> String {
    let mut v = serde_json::to_value(model).unwrap();
    cut_long_lists(&mut v);
    // Paths are absolute in the model; pin them relative to the checkout, wherever it is.
    let root = format!("{}/", root().display());
    serde_json::to_string_pretty(&v)
        .unwrap()
        .replace(&root, "$CARGO_MANIFEST_DIR/")
}

/// Drop long number lists (tabulated phase values) from an XML document.
fn shorten(doc: &str) -> String {
    doc.lines()
        .map(|l| {
            if l.contains("name=\"values\"") {
                "      <string name=\"values\" value=\"…\"/>".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn mitsuba_text(c: &mitsuba::Compiled) -> String {
    let names: Vec<String> = c.files.keys().cloned().collect();
    let file = |name: &str| String::from_utf8_lossy(&c.files[name]).to_string();
    let first = &c.manifest.views[0].passes[0].xml;
    let mut snap = format!("files: {}\n\n", names.join(" "));
    if c.files.contains_key(mitsuba::WORLD_FILE) {
        snap.push_str(&format!(
            "==== {} ====\n{}\n",
            mitsuba::WORLD_FILE,
            shorten(&file(mitsuba::WORLD_FILE))
        ));
    }
    snap.push_str(&format!("==== {first} ====\n{}\n", shorten(&file(first))));
    snap
}

/// FNV-1a, to pin asset bytes without storing them.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x100000001b3)
    })
}

fn blender_text(desc: &blender::data::Description) -> String {
    let mut text = blender::readable_json(&desc.json);
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
    text
}

// The inputs in two halves (alternate files), so that the two halves run side by side: baking
// the scenes' textures makes this the suite's longest item.
#[test]
fn every_input_to_every_output_1_of_2() {
    every_input_to_every_output(0);
}

#[test]
fn every_input_to_every_output_2_of_2() {
    every_input_to_every_output(1);
}

/// Pin the inputs `half`, `half + 2`, … of [`inputs`].
fn every_input_to_every_output(half: usize) {
    for input in inputs().into_iter().skip(half).step_by(2) {
        let stem = input.file_stem().unwrap().to_string_lossy().to_string();
        let shown = input.strip_prefix(root()).unwrap_or(&input).display();
        let loaded =
            poser::scene::load(&input, &[]).unwrap_or_else(|f| panic!("{shown}: {}", f.render()));
        let model = &loaded.model;
        if let Err(e) = model.validate() {
            panic!("{shown}: {e}");
        }

        settings("model", &input).bind(|| insta::assert_snapshot!(stem.clone(), model_text(model)));

        let mitsuba = match mitsuba::build(model) {
            Ok(c) => {
                // Byte-stable: a second compile gives the same files. Where the compile bakes
                // object textures (`textures/object-*`), the bake is most of its time, and its
                // bytes are pinned across runs by the Blender snapshot's asset hashes below
                // (the same bake); the XML of those scenes is written by the same code as the
                // others', compiled twice here.
                let bakes = c.files.keys().any(|k| k.starts_with("textures/object-"));
                if !bakes {
                    let again = mitsuba::build(model).unwrap();
                    assert_eq!(
                        c.files, again.files,
                        "{shown}: Mitsuba compile is not byte-stable"
                    );
                }
                mitsuba_text(&c)
            }
            Err(e) => format!("refused: {e}\n"),
        };
        settings("mitsuba", &input).bind(|| insta::assert_snapshot!(stem.clone(), mitsuba));

        let blender = match blender::data::describe(model) {
            Ok(desc) => blender_text(&desc),
            Err(e) => format!("refused: {e}\n"),
        };
        settings("blender", &input).bind(|| insta::assert_snapshot!(stem.clone(), blender));
    }
}

/// `tests/out` holds nothing stale: every snapshot there belongs to a scene of `tests/in`.
#[test]
fn no_orphan_outputs() {
    let stems: Vec<String> = inputs()
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    for stage in ["model", "mitsuba", "blender"] {
        let dir = root().join("tests/out").join(stage);
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in rd {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            let stem = name.strip_suffix(".snap").unwrap_or(&name);
            assert!(
                stems.iter().any(|s| s == stem),
                "{}: no tests/in/{stem}.toml; delete it or restore the input",
                p.display()
            );
        }
    }
}
