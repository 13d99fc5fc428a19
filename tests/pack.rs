//! Reproducible packs: `poser pack` → `poser rerun` gives byte-identical native outputs; a pack
//! is itself deterministic; a changed file, an unlisted file, and hostile archives (`..`,
//! absolute paths, links, huge entries) are refused before anything is written; a different
//! result and a different version are reported by name.

use flate2::{Compression, read::GzDecoder, write::GzEncoder};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A raw archive entry: path bytes, type, data, and a declared size not backed by data.
type Raw = (Vec<u8>, tar::EntryType, Vec<u8>, Option<u64>);

fn poser() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Pack the canonical pinhole scene (it includes `common.toml`) with one small native render.
fn make_pack(dir: &Path, name: &str, outputs: bool) -> PathBuf {
    let pack = dir.join(name);
    let mut c = poser();
    c.args(["pack", "tests/canonical/pinhole_air.toml", "-o"])
        .arg(&pack)
        .args(["--set", "render.samples=2"])
        .args([
            "--run",
            "render --scale 0.5 --poses 0 --quiet",
            "--run",
            "truth",
        ]);
    if outputs {
        c.arg("--outputs");
    }
    let o = c.output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    pack
}

/// The entries of a pack: (path bytes, entry type, data).
fn entries(pack: &Path) -> Vec<(Vec<u8>, tar::EntryType, Vec<u8>)> {
    let mut ar = tar::Archive::new(GzDecoder::new(std::fs::File::open(pack).unwrap()));
    ar.entries()
        .unwrap()
        .map(|e| {
            let mut e = e.unwrap();
            let mut d = Vec::new();
            e.read_to_end(&mut d).unwrap();
            (e.path_bytes().to_vec(), e.header().entry_type(), d)
        })
        .collect()
}

/// Write a pack from raw entries: names are put into the header as given (no checks), so that
/// hostile names can be built.
fn write_raw(pack: &Path, list: &[Raw]) {
    let mut tar = tar::Builder::new(GzEncoder::new(
        std::fs::File::create(pack).unwrap(),
        Compression::fast(),
    ));
    for (name, ty, data, declared) in list {
        let mut h = tar::Header::new_old();
        {
            let old = h.as_old_mut();
            old.name[..name.len()].copy_from_slice(name);
        }
        h.set_entry_type(*ty);
        h.set_mode(0o644);
        h.set_size(declared.unwrap_or(data.len() as u64));
        if *ty == tar::EntryType::Symlink {
            h.set_link_name("/etc/passwd").unwrap();
        }
        h.set_cksum();
        if declared.is_some() {
            // Header only: the declared size is never backed by data.
            tar.get_mut().write_all(h.as_bytes()).unwrap();
        } else {
            tar.append(&h, data.as_slice()).unwrap();
        }
    }
    tar.into_inner().unwrap().finish().unwrap();
}

fn manifest(pack: &Path) -> serde_json::Value {
    let e = entries(pack);
    assert_eq!(e[0].0, b"manifest.json");
    serde_json::from_slice(&e[0].2).unwrap()
}

fn rebuild_with_manifest(src: &Path, dst: &Path, m: &serde_json::Value) {
    let mut list: Vec<_> = entries(src)
        .into_iter()
        .map(|(n, t, d)| (n, t, d, None))
        .collect();
    list[0].2 = serde_json::to_vec_pretty(m).unwrap();
    write_raw(dst, &list);
}

fn files_below(dir: &Path) -> usize {
    if !dir.exists() {
        return 0;
    }
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        n += if p.is_dir() { files_below(&p) } else { 1 };
    }
    n
}

#[test]
fn pack_then_rerun_gives_the_same_bytes_and_the_pack_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let a = make_pack(dir.path(), "a.poserpack", true);
    let b = make_pack(dir.path(), "b.poserpack", true);
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "the same scene and commands give a different pack"
    );
    let m = manifest(&a);
    let names: Vec<&str> = m["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["path"].as_str().unwrap())
        .collect();
    // The scene, its include, and with --outputs what both commands wrote.
    assert!(names.contains(&"scene/pinhole_air.toml"), "{names:?}");
    assert!(names.contains(&"scene/common.toml"), "{names:?}");
    assert!(
        names
            .iter()
            .any(|n| n.starts_with("outputs/0/") && n.ends_with(".exr"))
    );
    assert!(names.iter().any(|n| n.starts_with("outputs/1/")));
    assert_eq!(m["sets"][0], "render.samples=2");
    assert!(m["versions"]["backends"]["mitsuba"].is_string());
    let rendered = m["commands"][0]["outputs"].as_array().unwrap().len();
    assert!(rendered >= 3, "{rendered} outputs recorded");

    let out = dir.path().join("rerun");
    let o = poser()
        .arg("rerun")
        .arg(&a)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains(&format!("{rendered} identical, 0 differ")),
        "{t}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("rerun.json")).unwrap()).unwrap();
    assert_eq!(report["identical"], true);
    assert!(out.join("pack/scene/common.toml").is_file());

    // A second rerun into the same folder is refused (stale files would pass as outputs).
    let o = poser()
        .arg("rerun")
        .arg(&a)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}

#[test]
fn a_different_result_and_a_different_version_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let a = make_pack(dir.path(), "a.poserpack", false);
    let mut m = manifest(&a);
    // As if the pack had been made by another build whose render gave other bytes.
    m["versions"]["commit"] = "0123456789ab".into();
    m["versions"]["backends"]["mitsuba"] = "3.0.0".into();
    let first = m["commands"][0]["outputs"][0]["path"]
        .as_str()
        .unwrap()
        .to_string();
    m["commands"][0]["outputs"][0]["sha256"] = "00".repeat(32).into();
    let b = dir.path().join("b.poserpack");
    rebuild_with_manifest(&a, &b, &m);
    let out = dir.path().join("rerun");
    let o = poser()
        .arg("rerun")
        .arg(&b)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains(&format!("Differs: {first}")), "{t}");
    assert!(t.contains("poser commit 0123456789ab (pack)"), "{t}");
    assert!(t.contains("mitsuba 3.0.0 (pack) vs 3.9.1 (here)"), "{t}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("rerun.json")).unwrap()).unwrap();
    assert_eq!(report["identical"], false);
}

#[test]
fn tampered_and_hostile_packs_are_refused_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = make_pack(dir.path(), "good.poserpack", false);
    let list: Vec<_> = entries(&good)
        .into_iter()
        .map(|(n, t, d)| (n, t, d, None))
        .collect();
    let reg = tar::EntryType::Regular;
    let mut cases: Vec<(&str, Vec<Raw>, &str)> = Vec::new();
    // A scene file changed after packing.
    let mut t = list.clone();
    let k = t.iter().position(|e| e.0 == b"scene/common.toml").unwrap();
    t[k].2.extend_from_slice(b"\n[water]\nior = 1.5\n");
    cases.push((
        "tampered",
        t,
        "scene/common.toml` does not have the SHA-256",
    ));
    let mut t = list.clone();
    t.push((b"scene/extra.toml".to_vec(), reg, b"x = 1".to_vec(), None));
    cases.push(("unlisted", t, "`scene/extra.toml` is not listed"));
    let mut t = list.clone();
    t.push((b"../escape.txt".to_vec(), reg, b"x".to_vec(), None));
    cases.push(("dotdot", t, "not a plain relative path"));
    let mut t = list.clone();
    t.push((b"/tmp/poser-abs.txt".to_vec(), reg, b"x".to_vec(), None));
    cases.push(("absolute", t, "not a plain relative path"));
    let mut t = list.clone();
    t.push((
        b"scene/link".to_vec(),
        tar::EntryType::Symlink,
        vec![],
        None,
    ));
    cases.push(("symlink", t, "regular files only"));
    let mut t = list.clone();
    t.push((b"scene/huge.bin".to_vec(), reg, vec![], Some(1 << 40)));
    cases.push(("huge", t, "more than the"));
    let mut t = list.clone();
    t.swap(0, 1);
    cases.push(("manifest-not-first", t, "not `manifest.json`"));

    for (name, entries, want) in cases {
        let pack = dir.path().join(format!("{name}.poserpack"));
        write_raw(&pack, &entries);
        for cmd in ["unpack", "rerun"] {
            let out = dir.path().join(format!("{name}-{cmd}"));
            let o = poser()
                .arg(cmd)
                .arg(&pack)
                .arg("-o")
                .arg(&out)
                .output()
                .unwrap();
            let t = text(&o);
            assert_eq!(o.status.code(), Some(1), "{name} {cmd}: {t}");
            assert!(t.contains(want), "{name} {cmd}: {t}");
            assert_eq!(files_below(&out), 0, "{name} {cmd}: wrote files");
        }
    }
    assert!(!dir.path().join("escape.txt").exists());
    assert!(!Path::new("/tmp/poser-abs.txt").exists());
}

#[test]
fn pack_refuses_commands_it_cannot_replay() {
    let dir = tempfile::tempdir().unwrap();
    for run in [
        "evaluate --mode images",
        "render -o /tmp/elsewhere",
        "render --set a=1",
    ] {
        let pack = dir.path().join("x.poserpack");
        let o = poser()
            .args(["pack", "tests/canonical/pinhole_air.toml", "-o"])
            .arg(&pack)
            .args(["--run", run])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{run}: {}", text(&o));
        assert!(!pack.exists(), "{run}: a pack was written");
    }
}
