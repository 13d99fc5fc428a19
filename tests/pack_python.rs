//! What a pack records of the Python that ran its commands (full tier: real Mitsuba).

use crate::support::pack::{manifest, poser, text};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Full tier: a pack whose command renders with Mitsuba records the Python packages installed
/// where it ran, as the interpreter reports them (the version there is the one the module itself
/// reports), and a rerun where another Mitsuba is installed names it. The other Mitsuba is the
/// real one under a distribution record of version 3.0.0 placed first on the interpreter's path
/// (what `pip` would report after installing 3.0.0 over it).
#[test]
fn a_pack_records_the_installed_python_packages_and_a_rerun_names_another() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let py = std::env::var_os("POSER_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    let ask = |code: &str| {
        let o = Command::new(&py).args(["-c", code]).output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
        String::from_utf8(o.stdout).unwrap().trim().to_string()
    };
    let mitsuba = ask("import mitsuba; print(mitsuba.__version__)");
    let numpy = ask("import numpy; print(numpy.__version__)");
    let dir = tempfile::tempdir().unwrap();
    let pack = dir.path().join("mi.poserpack");
    let o = poser()
        .env("POSER_PYTHON", &py)
        .args(["pack", "tests/canonical/pinhole_air.toml", "-o"])
        .arg(&pack)
        .args([
            "--run",
            "render --backend mitsuba --scale 0.1 --samples 1 --poses 0 --quiet",
        ])
        .output()
        .unwrap();
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("Python used by the commands"), "{t}");
    let m = manifest(&pack);
    let installed = &m["versions"]["installed"];
    assert_eq!(installed["mitsuba"], mitsuba.as_str(), "{installed}");
    assert_eq!(installed["numpy"], numpy.as_str(), "{installed}");
    assert!(
        installed["python"]
            .as_str()
            .is_some_and(|v| v.starts_with('3'))
    );

    // Another Mitsuba, as far as the interpreter's package records go.
    let fake = dir.path().join("fake");
    let info = fake.join("mitsuba-3.0.0.dist-info");
    std::fs::create_dir_all(&info).unwrap();
    std::fs::write(
        info.join("METADATA"),
        "Metadata-Version: 2.1\nName: mitsuba\nVersion: 3.0.0\n",
    )
    .unwrap();
    let wrapper = dir.path().join("python");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\nPYTHONPATH=\"{}${{PYTHONPATH:+:$PYTHONPATH}}\" exec \"{}\" \"$@\"\n",
            fake.display(),
            py.display()
        ),
    )
    .unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let out = dir.path().join("rerun");
    let o = poser()
        .env("POSER_PYTHON", &wrapper)
        .arg("rerun")
        .arg(&pack)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let t = text(&o);
    let line = format!("installed mitsuba {mitsuba} (pack) vs 3.0.0 (here)");
    assert!(t.contains(&format!("version: {line}")), "{t}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("rerun.json")).unwrap()).unwrap();
    let diffs = report["version_differences"].as_array().unwrap();
    assert!(diffs.iter().any(|d| d == line.as_str()), "{diffs:?}");
    // Only Mitsuba differs among the installed packages.
    assert_eq!(
        diffs
            .iter()
            .filter(|d| d.as_str().unwrap().starts_with("installed "))
            .count(),
        1,
        "{diffs:?}"
    );
}
