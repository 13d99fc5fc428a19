//! Third-party Mitsuba scenes (issue 37): scenes of Mitsuba's own data repository
//! (github.com/mitsuba-renderer/mitsuba-data, commit 01100fa) imported with `poser import --verify` against the real Mitsuba 3 at 64 px
//! wide and 64 spp, within the default 2 % per channel; or, where poser cannot hold what the
//! scene shows (a glass object, a volume of medium inside a shape), refused up front with the
//! shape's file, line and column and a `help:` line, nothing written.
//!
//! mitsuba-data carries no licence, so poser does not ship its files: these tests read a
//! checkout named by `POSER_MITSUBA_DATA` and say that they skipped without one
//! (docs/import.md, "Scenes from mitsuba-data"). The scenes are read where they are (its
//! `<path>` folders lead to its `common/`, hence `--root`); everything is written into a
//! temporary folder.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The mitsuba-data checkout, or `None` (and a line saying the test skipped) without one.
fn data() -> Option<PathBuf> {
    let d = std::env::var_os("POSER_MITSUBA_DATA").map(PathBuf::from);
    if d.is_none() {
        eprintln!(
            "skipped: set POSER_MITSUBA_DATA to a checkout of mitsuba-renderer/mitsuba-data \
             (commit 01100fa); it has no licence, so poser does not ship it"
        );
    }
    d
}

/// `poser import DATA/xml -o out/scene.toml --root DATA`, with `--verify` at 64 px, 64 spp.
fn import(data: &Path, xml: &str, out: &Path, verify: bool) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.arg("import")
        .arg(data.join(xml))
        .arg("-o")
        .arg(out.join("scene.toml"))
        .arg("--root")
        .arg(data);
    if verify {
        c.args(["--verify", "--verify-width", "64", "--verify-samples", "64"]);
    }
    c.output().unwrap()
}

/// The scene imports and passes `--verify` at the default tolerance; returns its stderr
/// (`None`: no checkout, skipped).
fn passes(xml: &str) -> Option<String> {
    let data = data()?;
    let dir = tempfile::tempdir().unwrap();
    let out = import(&data, xml, dir.path(), true);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    eprintln!("{xml}:\n{err}");
    assert!(out.status.success(), "{xml}: {err}");
    assert!(err.contains("mean per channel"), "{err}");
    assert!(err.contains("verify: ok"), "{err}");
    assert!(dir.path().join("scene_verify/source.exr").is_file());
    Some(err)
}

/// The import fails before anything is written, naming `shape` (`file:line:col`) with `what`
/// and a `help:` line.
fn refused(xml: &str, shape: &str, what: &str) {
    let Some(data) = data() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = import(&data, xml, dir.path(), true);
    let err = String::from_utf8_lossy(&out.stderr);
    eprintln!("{xml}:\n{err}");
    assert!(!out.status.success(), "{err}");
    assert!(err.contains(shape), "the shape's location `{shape}`: {err}");
    assert!(err.contains(what), "`{what}`: {err}");
    assert!(err.contains("help: "), "{err}");
    assert!(!err.contains("verify:"), "refused before rendering: {err}");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing written"
    );
}

#[test]
fn the_rgb_cornell_box_passes_verify() {
    let Some(err) = passes("scenes/cbox/cbox-rgb.xml") else {
        return;
    };
    assert!(err.contains("7 object(s), 1 light(s)"), "{err}");
}

#[test]
fn the_spectral_cornell_box_passes_verify() {
    let Some(err) = passes("scenes/cbox/cbox-spectral.xml") else {
        return;
    };
    assert!(err.contains("spectrum"), "the spectra are noted: {err}");
}

#[test]
fn the_single_file_spectral_cornell_box_passes_verify() {
    let Some(err) = passes("scenes/cbox/cbox.xml") else {
        return;
    };
    assert!(
        err.contains("`gaussian` reconstruction filter is not imported"),
        "its Gaussian filter is noted: {err}"
    );
}

/// `max_depth` 2: direct light only, poser's `render.bounces = 1`.
#[test]
fn the_direct_light_cornell_box_passes_verify() {
    passes("docs/scenes/integrator_depth_2.xml");
}

/// A homogeneous medium inside two spheres the camera is outside of.
#[test]
fn a_medium_inside_a_sphere_is_refused() {
    refused(
        "tests/scenes/participating_media/test_homo_area_light_volpath.xml",
        "test_homo_area_light_volpath.xml:14:5",
        "bounds medium `medium1`, and the camera is outside it",
    );
}

/// A dielectric sphere (water, with a medium inside) in front of the camera.
#[test]
fn a_dielectric_sphere_is_refused() {
    refused(
        "tests/scenes/participating_media/test_homo_dielectric_envmap_volpath.xml",
        "test_homo_dielectric_envmap_volpath.xml:18:5",
        "`dielectric` BSDF",
    );
}

/// `scenes/hello.xml` (a PLY teapot rotated about the non-unit axis (0, 1, 1), two point
/// lights) with its `direct` integrator replaced by `path` at depth 2: its `direct` integrator
/// renders point lights once per emitter sample at full weight (4× here, noted by the import),
/// which no scene file can say. Mitsuba 3 uses a rotation axis as written, not normalised;
/// normalising it cost this scene 7 % of its light (docs/import.md).
#[test]
fn hello_with_a_path_integrator_passes_verify() {
    let Some(data) = data() else { return };
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    std::fs::create_dir_all(root.join("common/meshes")).unwrap();
    std::fs::create_dir_all(root.join("scenes")).unwrap();
    std::fs::copy(
        data.join("common/meshes/teapot.ply"),
        root.join("common/meshes/teapot.ply"),
    )
    .unwrap();
    let xml = std::fs::read_to_string(data.join("scenes/hello.xml")).unwrap();
    let (a, b) = (
        xml.find("<integrator").unwrap(),
        xml.find("</integrator>").unwrap() + "</integrator>".len(),
    );
    let xml = format!(
        "{}<integrator type=\"path\"><integer name=\"max_depth\" value=\"2\"/></integrator>{}",
        &xml[..a],
        &xml[b..]
    );
    assert!(xml.contains(r#"<rotate x="0.0" y="1.0" z="1.0" angle="15"/>"#));
    std::fs::write(root.join("scenes/hello.xml"), xml).unwrap();
    let out = import(root, "scenes/hello.xml", &root.join("out"), true);
    let err = String::from_utf8_lossy(&out.stderr);
    eprintln!("{err}");
    assert!(out.status.success(), "{err}");
    assert!(err.contains("verify: ok"), "{err}");
}
