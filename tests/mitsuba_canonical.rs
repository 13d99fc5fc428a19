//! The canonical scenes of `tests/canonical/` (one effect each) rendered with Mitsuba 3 and
//! measured with `poser::compare` against the exact truth of `poser::optics` (disk-image
//! centroids vs the centroid of the exactly projected disk outline).

use poser::backend::RenderOptions;
use poser::model::Model;
use std::path::PathBuf;

fn load(name: &str) -> Model {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/canonical/{name}.toml"));
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{name}: {}", f.render()),
    }
}

/// RMS of measured − expected disk centroids (px) over the scene's disks.
fn geometry_rms(name: &str) -> f64 {
    if let Err(e) = poser::backend::python::require_module("mitsuba") {
        panic!("this test renders with the real Mitsuba 3: {e}");
    }
    let model = load(name);
    let tmp = tempfile::tempdir().unwrap();
    // POSER_SPP overrides the scene's samples (for measuring how the error falls with noise).
    let samples = std::env::var("POSER_SPP").ok().and_then(|s| s.parse().ok());
    let opts = RenderOptions {
        samples,
        poses: None,
        progress: false,
    };
    poser::backend::mitsuba::render(&model, tmp.path(), &opts)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let (found, expected) = poser::compare::measure_targets(&model, tmp.path()).unwrap();
    assert!(
        expected >= 12,
        "{name}: only {expected} disks expected in view"
    );
    assert_eq!(found.len(), expected, "{name}: disks lost");
    if std::env::var("POSER_DEBUG").is_ok() {
        for f in &found {
            eprintln!("{f:?}");
        }
        eprintln!("DIR {}", tmp.keep().display());
    }
    let rms = (found
        .iter()
        .map(|(_, _, d)| d[0] * d[0] + d[1] * d[1])
        .sum::<f64>()
        / found.len() as f64)
        .sqrt();
    let max = found
        .iter()
        .map(|(_, _, d)| d[0].hypot(d[1]))
        .fold(0.0, f64::max);
    eprintln!(
        "mitsuba {name}: {} disks, RMS {rms:.4} px, max {max:.4} px",
        found.len()
    );
    rms
}

// Issue 7's target: ≤ 0.05 px RMS for every backend and port.
const MAX_RMS_PX: f64 = 0.05;

macro_rules! geometry_test {
    ($fn:ident, $name:literal) => {
        #[test]
        fn $fn() {
            let rms = geometry_rms($name);
            assert!(
                rms <= MAX_RMS_PX,
                "{}: RMS {rms:.4} px > {MAX_RMS_PX}",
                $name
            );
        }
    };
}

geometry_test!(pinhole_air, "pinhole_air");
geometry_test!(flat_pupil_1mm, "flat_pupil_1mm");
geometry_test!(flat_pupil_10cm, "flat_pupil_10cm");
geometry_test!(flat_tilted, "flat_tilted");
geometry_test!(dome_decentred, "dome_decentred");
geometry_test!(cylinder_off_axis, "cylinder_off_axis");
geometry_test!(dispersion, "dispersion");
