//! Reproducible packs: `poser pack` → `poser rerun` gives byte-identical native outputs; a pack
//! is itself deterministic; a changed file, an unlisted file, and hostile archives (`..`,
//! absolute paths, links, huge entries) are refused before anything is written; a different
//! result and a different version are reported by name.

use crate::support::pack::{entries, manifest, poser, text};
use flate2::{Compression, write::GzEncoder};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A raw archive entry: path bytes, type, data, and a declared size not backed by data.
type Raw = (Vec<u8>, tar::EntryType, Vec<u8>, Option<u64>);

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

/// Write a pack from raw entries: names are put into the header as given (no checks), so that
/// hostile names can be built.
/// Rewrite the manifest (entry 0) so that `path`'s hash and size match entry `k` again: an
/// attacker's edit that a hash check alone would not catch.
fn rehash(l: &mut [Raw], k: usize, path: &str) {
    let mut m: serde_json::Value = serde_json::from_slice(&l[0].2).unwrap();
    for f in m["files"].as_array_mut().unwrap() {
        if f["path"] == path {
            f["sha256"] = poser::io::sha256(&l[k].2).into();
            f["bytes"] = l[k].2.len().into();
        }
    }
    l[0].2 = serde_json::to_vec_pretty(&m).unwrap();
}

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
    // Native commands start no Python: no installed packages are recorded.
    assert!(
        m["versions"].get("installed").is_none(),
        "{}",
        m["versions"]
    );
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

/// Run `cmd`, killing it after `limit` (the test then fails: it hung or read without end).
fn output_within(cmd: &mut Command, limit: std::time::Duration) -> (Output, std::time::Duration) {
    use std::process::Stdio;
    let t0 = std::time::Instant::now();
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} still running after {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let took = t0.elapsed();
    (child.wait_with_output().unwrap(), took)
}

/// `unpack` writes only into a new or empty folder that is not a link, as `rerun` does: a
/// folder holding a link (`D/scene → elsewhere`) is refused and nothing reaches `elsewhere`;
/// a folder that is itself a link is refused too; an empty folder is fine and keeps no
/// temporary files.
#[test]
fn unpack_writes_only_into_a_new_or_empty_folder_never_through_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let good = make_pack(dir.path(), "good.poserpack", false);
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    // D/scene → elsewhere.
    let d = dir.path().join("d");
    std::fs::create_dir(&d).unwrap();
    std::os::unix::fs::symlink(&elsewhere, d.join("scene")).unwrap();
    // E → elsewhere (the output folder itself is a link to an empty folder).
    let e = dir.path().join("e");
    std::os::unix::fs::symlink(&elsewhere, &e).unwrap();
    // F holds an earlier file.
    let f = dir.path().join("f");
    std::fs::create_dir(&f).unwrap();
    std::fs::write(f.join("notes.txt"), "mine").unwrap();
    for (cmd, out, want) in [
        ("unpack", &d, "is not empty"),
        ("unpack", &e, "is a symbolic link"),
        ("rerun", &e, "is a symbolic link"),
        ("unpack", &f, "is not empty"),
    ] {
        let o = poser()
            .arg(cmd)
            .arg(&good)
            .arg("-o")
            .arg(out)
            .output()
            .unwrap();
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{cmd} {}: {t}", out.display());
        assert!(t.contains(want), "{cmd} {}: {t}", out.display());
        assert_eq!(
            std::fs::read_dir(&elsewhere).unwrap().count(),
            0,
            "{cmd} {}: wrote through the link",
            out.display()
        );
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    assert_eq!(
        std::fs::read_to_string(f.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read_dir(&f).unwrap().count(), 1);
    // An existing empty folder is fine, and keeps no temporary folder.
    let g = dir.path().join("g");
    std::fs::create_dir(&g).unwrap();
    let o = poser()
        .arg("unpack")
        .arg(&good)
        .arg("-o")
        .arg(&g)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(g.join("scene/common.toml").is_file());
    let mut names: Vec<String> = std::fs::read_dir(&g)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["manifest.json", "scene"]);
}

/// A compression bomb — a valid pack (manifest, hashes) whose one extra entry is 1 GiB of
/// zeros in about 1 MB — is refused by its compression ratio within a second, before more than
/// a few MiB are decompressed, and writes nothing (it used to write the whole entry).
#[test]
fn a_compression_bomb_is_refused_within_a_second_and_writes_nothing() {
    use sha2::Digest;
    const N: u64 = 1 << 30;
    let dir = tempfile::tempdir().unwrap();
    let good = make_pack(dir.path(), "good.poserpack", false);
    let list = entries(&good);
    let mut h = sha2::Sha256::new();
    let block = vec![0u8; 1 << 20];
    for _ in 0..N >> 20 {
        h.update(&block);
    }
    let sha: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
    let mut m: serde_json::Value = serde_json::from_slice(&list[0].2).unwrap();
    m["files"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"path": "scene/zeros.bin", "sha256": sha, "bytes": N}));
    let bomb = dir.path().join("bomb.poserpack");
    {
        let mut tar = tar::Builder::new(GzEncoder::new(
            std::fs::File::create(&bomb).unwrap(),
            Compression::best(),
        ));
        for (k, (name, _, data)) in list.iter().enumerate() {
            let data = if k == 0 {
                serde_json::to_vec_pretty(&m).unwrap()
            } else {
                data.clone()
            };
            let mut hd = tar::Header::new_gnu();
            hd.set_size(data.len() as u64);
            hd.set_mode(0o644);
            hd.set_cksum();
            tar.append_data(&mut hd, std::str::from_utf8(name).unwrap(), data.as_slice())
                .unwrap();
        }
        let mut hd = tar::Header::new_gnu();
        hd.set_size(N);
        hd.set_mode(0o644);
        hd.set_cksum();
        tar.append_data(&mut hd, "scene/zeros.bin", std::io::repeat(0).take(N))
            .unwrap();
        tar.into_inner().unwrap().finish().unwrap();
    }
    let size = std::fs::metadata(&bomb).unwrap().len();
    assert!(size < 4 << 20, "the bomb is {size} bytes");
    for cmd in ["unpack", "rerun"] {
        let out = dir.path().join(format!("bomb-{cmd}"));
        let (o, took) = output_within(
            poser().arg(cmd).arg(&bomb).arg("-o").arg(&out),
            std::time::Duration::from_secs(60),
        );
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{cmd}: {t}");
        assert!(t.contains("compression bomb"), "{cmd}: {t}");
        assert!(
            took < std::time::Duration::from_secs(1),
            "{cmd}: took {took:?}"
        );
        assert_eq!(files_below(&out), 0, "{cmd}: wrote files");
    }
}

/// A pack whose scene names a file outside the pack — `/dev/zero`, or a `..` that climbs out
/// of the unpacked folder — passes the archive's checks but is refused before anything is
/// written (a rerun would otherwise read it); a `..` that stays inside the pack is fine.
#[test]
fn a_pack_whose_scene_reads_outside_the_pack_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let good = make_pack(dir.path(), "good.poserpack", false);
    std::fs::write(dir.path().join("secret.toml"), "[water]\ntemperature = 3\n").unwrap();
    let list = entries(&good);
    let k = list
        .iter()
        .position(|e| e.0 == b"scene/pinhole_air.toml")
        .unwrap();
    for (name, include, want) in [
        ("devzero", "/dev/zero", "an absolute path"),
        ("dotdot", "../../secret.toml", "climbs out of the pack"),
    ] {
        let mut l: Vec<Raw> = list
            .iter()
            .cloned()
            .map(|(n, t, d)| (n, t, d, None))
            .collect();
        let scene = String::from_utf8(l[k].2.clone()).unwrap().replacen(
            "include = [\"common.toml\"]",
            &format!("include = [\"common.toml\", \"{include}\"]"),
            1,
        );
        assert!(scene.contains(include));
        l[k].2 = scene.into_bytes();
        rehash(&mut l, k, "scene/pinhole_air.toml");
        let pack = dir.path().join(format!("{name}.poserpack"));
        write_raw(&pack, &l);
        for cmd in ["unpack", "rerun"] {
            let out = dir.path().join(format!("{name}-{cmd}"));
            let (o, _) = output_within(
                poser().arg(cmd).arg(&pack).arg("-o").arg(&out),
                std::time::Duration::from_secs(20),
            );
            let t = text(&o);
            assert_eq!(o.status.code(), Some(1), "{name} {cmd}: {t}");
            assert!(
                t.contains(&format!("`{include}` is outside the pack")) && t.contains(want),
                "{name} {cmd}: {t}"
            );
            assert!(t.contains("scene/pinhole_air.toml:2:"), "{name} {cmd}: {t}");
            assert!(t.contains("help:"), "{name} {cmd}: {t}");
            assert_eq!(files_below(&out), 0, "{name} {cmd}: wrote files");
        }
    }
}

/// The front end confined to a folder (how a pack's scene is read): a link that leads out of
/// it is refused where it is named, a `..` that stays inside is fine.
#[test]
fn a_confined_scene_follows_no_link_out_and_may_climb_inside() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("pack/scene");
    let canon = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/canonical");
    std::fs::create_dir_all(root.join("main")).unwrap();
    std::fs::create_dir_all(root.join("shared")).unwrap();
    std::fs::copy(canon.join("common.toml"), root.join("shared/common.toml")).unwrap();
    let own = std::fs::read_to_string(canon.join("pinhole_air.toml")).unwrap();
    let scene = root.join("main/scene.toml");
    std::fs::write(
        &scene,
        own.replacen("\"common.toml\"", "\"../shared/common.toml\"", 1),
    )
    .unwrap();
    assert!(poser::scene::load_within(&scene, &[], &root).is_ok());
    // A link inside the folder to a file outside it.
    std::fs::write(dir.path().join("outside.toml"), "name = \"x\"\n").unwrap();
    std::os::unix::fs::symlink(dir.path().join("outside.toml"), root.join("main/link.toml"))
        .unwrap();
    std::fs::write(
        &scene,
        own.replacen(
            "\"common.toml\"",
            "\"../shared/common.toml\", \"link.toml\"",
            1,
        ),
    )
    .unwrap();
    let Err(f) = poser::scene::load_within(&scene, &[], &root) else {
        panic!("a link out of the pack was followed");
    };
    let t = f.render();
    assert!(
        t.contains("`link.toml` is outside the pack") && t.contains("a link that leads out"),
        "{t}"
    );
    // Not confined, the same scene loads (the link is the user's own).
    assert!(poser::scene::load(&scene, &[]).is_ok());
}

/// `poser pack` refuses a scene whose packed copy would read files outside the pack (an
/// absolute include reads the packer's own file on every rerun) and writes no pack.
#[test]
fn pack_refuses_a_scene_that_names_files_by_absolute_paths() {
    let dir = tempfile::tempdir().unwrap();
    let canon = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/canonical");
    let own = std::fs::read_to_string(canon.join("pinhole_air.toml")).unwrap();
    let common = canon.join("common.toml");
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        own.replacen("\"common.toml\"", &format!("\"{}\"", common.display()), 1),
    )
    .unwrap();
    let pack = dir.path().join("x.poserpack");
    let o = poser()
        .arg("pack")
        .arg(&scene)
        .arg("-o")
        .arg(&pack)
        .output()
        .unwrap();
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("is outside the pack") && t.contains("an absolute path"),
        "{t}"
    );
    assert!(!pack.exists());
}

/// Signed packs. `poser keygen` makes a key pair (PEM files OpenSSL reads); `pack --sign`
/// signs deterministically; `rerun --trust` runs a pack signed by that key, and refuses,
/// writing nothing, an unsigned pack, a pack signed by another key, and a pack changed after it
/// was signed — even with the changed file's hash rewritten in the manifest, with the
/// signature removed, or re-signed by another key. A changed signed pack is refused without
/// `--trust` too. An unsigned pack, run without `--trust`, says plainly that it is unsigned.
#[test]
fn signed_packs_run_only_unchanged_and_by_the_trusted_key() {
    use poser::pack::sign;
    let dir = tempfile::tempdir().unwrap();
    let key = |name: &str| {
        let k = dir.path().join(name);
        let o = poser().arg("keygen").arg("-o").arg(&k).output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
        k
    };
    let (a, b) = (key("alice.key"), key("bob.key"));
    let pubkey = |k: &Path| sign::pub_path(k);
    let print = |k: &Path| sign::fingerprint(&sign::read_verifying_key(k).unwrap());
    let signed_pack = |name: &str| {
        let pack = dir.path().join(name);
        let o = poser()
            .args(["pack", "tests/canonical/pinhole_air.toml", "-o"])
            .arg(&pack)
            .args(["--run", "truth", "--sign"])
            .arg(&a)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        assert!(text(&o).contains(&format!("signed with key {}", print(&a))));
        pack
    };
    let signed = signed_pack("signed.poserpack");
    assert_eq!(
        std::fs::read(&signed).unwrap(),
        std::fs::read(signed_pack("again.poserpack")).unwrap(),
        "a signed pack is not byte-stable"
    );
    let list = entries(&signed);
    assert_eq!(list[1].0, b"manifest.sig");
    let run = |pack: &Path, trust: Option<&Path>, out: &str| {
        let mut c = poser();
        c.arg("rerun").arg(pack).arg("-o").arg(dir.path().join(out));
        if let Some(k) = trust {
            c.arg("--trust").arg(k);
        }
        let o = c.output().unwrap();
        (
            o.status.code(),
            text(&o),
            files_below(&dir.path().join(out)),
        )
    };

    let (code, t, _) = run(&signed, Some(&pubkey(&a)), "ok");
    assert_eq!(code, Some(0), "{t}");
    assert!(
        t.contains(&format!("signed by trusted key {}", print(&a))),
        "{t}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("ok/rerun.json")).unwrap()).unwrap();
    assert_eq!(report["signed_by"], print(&a).as_str());
    assert_eq!(report["trusted"], true);
    let (code, t, _) = run(&signed, None, "untrusted");
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("not checked against a key you trust"), "{t}");

    // Unsigned: said plainly, and refused under --trust.
    let unsigned = make_pack(dir.path(), "unsigned.poserpack", false);
    let (code, t, _) = run(&unsigned, None, "unsigned-plain");
    assert_eq!(code, Some(0), "{t}");
    assert!(
        t.contains("unsigned: nothing shows who made this pack"),
        "{t}"
    );
    let mut refused: Vec<(&str, PathBuf, Option<PathBuf>, String)> = vec![(
        "unsigned",
        unsigned,
        Some(pubkey(&a)),
        "the pack is unsigned, and --trust asks for a signature by".into(),
    )];
    refused.push((
        "other-key",
        signed.clone(),
        Some(pubkey(&b)),
        format!(
            "signed by key {}, not by key {} that --trust names",
            print(&a),
            print(&b)
        ),
    ));

    // Changed after signing: a scene file edited and its hash rewritten in the manifest.
    let mut l: Vec<Raw> = list
        .iter()
        .cloned()
        .map(|(n, t, d)| (n, t, d, None))
        .collect();
    let k = l.iter().position(|e| e.0 == b"scene/common.toml").unwrap();
    l[k].2.extend_from_slice(b"\n# changed\n");
    rehash(&mut l, k, "scene/common.toml");
    let rehashed = dir.path().join("rehashed.poserpack");
    write_raw(&rehashed, &l);
    let changed = format!(
        "does not match `manifest.json`: the pack was changed after it was signed (by key {})",
        print(&a)
    );
    refused.push((
        "rehashed",
        rehashed.clone(),
        Some(pubkey(&a)),
        changed.clone(),
    ));
    refused.push(("rehashed-no-trust", rehashed, None, changed));
    // ... and the signature removed.
    let mut stripped = l.clone();
    stripped.remove(1);
    let p = dir.path().join("stripped.poserpack");
    write_raw(&p, &stripped);
    refused.push((
        "stripped",
        p,
        Some(pubkey(&a)),
        "the pack is unsigned".into(),
    ));
    // ... and signed again by another key.
    let mut resigned = l.clone();
    resigned[1].2 = sign::sign(&sign::read_signing_key(&b).unwrap(), &l[0].2);
    let p = dir.path().join("resigned.poserpack");
    write_raw(&p, &resigned);
    refused.push((
        "resigned",
        p,
        Some(pubkey(&a)),
        format!("signed by key {}, not by key {}", print(&b), print(&a)),
    ));
    // A signature that is not the second entry.
    let mut moved: Vec<Raw> = list
        .iter()
        .cloned()
        .map(|(n, t, d)| (n, t, d, None))
        .collect();
    let sig = moved.remove(1);
    moved.push(sig);
    let p = dir.path().join("moved.poserpack");
    write_raw(&p, &moved);
    refused.push((
        "moved",
        p,
        Some(pubkey(&a)),
        "a signature is the second entry".into(),
    ));

    for (name, pack, trust, want) in refused {
        let (code, t, written) = run(&pack, trust.as_deref(), &format!("{name}-rerun"));
        assert_eq!(code, Some(1), "{name}: {t}");
        assert!(t.contains(&want), "{name}: {t}");
        assert_eq!(written, 0, "{name}: wrote files");
        let mut c = poser();
        c.arg("unpack")
            .arg(&pack)
            .arg("-o")
            .arg(dir.path().join(format!("{name}-unpack")));
        if let Some(k) = &trust {
            c.arg("--trust").arg(k);
        }
        let o = c.output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{name} unpack: {}", text(&o));
        assert!(text(&o).contains(&want), "{name} unpack: {}", text(&o));
    }

    // A key file that is not a key is a usage error before anything runs.
    let o = poser()
        .args(["pack", "tests/canonical/pinhole_air.toml", "-o"])
        .arg(dir.path().join("x.poserpack"))
        .arg("--sign")
        .arg(pubkey(&a))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("a public key; signing needs the private key"));
}
