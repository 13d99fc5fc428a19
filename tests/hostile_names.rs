//! Hostile names: names that would escape the output folder are refused by the front end
//! (one located diagnostic, nothing written, whatever the backend), and characters that XML
//! forbids never reach a Mitsuba document.

use crate::support;
use poser::backend::mitsuba::{self, xml::is_xml_char};
use std::path::Path;
use std::process::Command;

/// A multi-camera rig with a camera named `../../../x`: `poser render` fails with the scene's
/// file:line:column and writes nothing, for every backend (the check is in the front end, so
/// the backend is never started).
#[test]
fn camera_name_leaving_the_output_folder_is_refused_and_nothing_is_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("tests/invalid/camera_name_leaves_output.toml");
    for backend in ["native", "mitsuba", "blender"] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("a/b/c/out");
        let o = Command::new(env!("CARGO_BIN_EXE_poser"))
            .current_dir(root)
            .args(["render", "tests/invalid/camera_name_leaves_output.toml"])
            .args(["--backend", backend, "--quiet", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{backend}: accepted\n{err}");
        assert!(err.contains("error[E0234]"), "{backend}: {err}");
        assert!(
            err.contains("tests/invalid/camera_name_leaves_output.toml:6:8"),
            "{backend}: no file:line:col in\n{err}"
        );
        assert!(err.contains("help:"), "{backend}: {err}");
        let written: Vec<_> = walk(tmp.path());
        assert!(written.is_empty(), "{backend} wrote {written:?}");
    }
    assert!(scene.exists());
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        }
        out.push(p);
    }
    out
}

/// Names with U+FFFE, U+FFFF and C0 controls (XML-illegal) on the scene, lights, objects and
/// targets: every compiled document contains only characters XML 1.0 allows.
#[test]
fn xml_illegal_characters_in_names_never_reach_the_documents() {
    let hostile = |s: &str| format!("{s}\u{FFFE}\u{FFFF}\u{1}\u{8}\u{1B}\u{7F}x");
    let mut m = support::mitsuba::showcase();
    m.name = hostile("scene");
    for l in &mut m.lights {
        l.name = hostile(&l.name);
    }
    for o in &mut m.objects {
        o.name = hostile(&o.name);
    }
    for t in &mut m.targets {
        t.name = hostile(&t.name);
    }
    let c = mitsuba::build(&m).unwrap();
    let mut docs = 0;
    for (f, bytes) in &c.files {
        if !f.ends_with(".xml") {
            continue;
        }
        docs += 1;
        let s = std::str::from_utf8(bytes).unwrap();
        if let Some(bad) = s.chars().find(|&ch| !is_xml_char(ch)) {
            panic!("{f}: XML-illegal character {:?}", bad);
        }
        assert!(
            s.contains('\u{FFFD}'),
            "{f}: the names were not written at all"
        );
    }
    assert!(docs >= 2);
}
