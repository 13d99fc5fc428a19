//! The canonical scenes of `tests/canonical/` (one effect each) rendered with Mitsuba 3 and
//! measured with `poser::compare` against the exact truth of `poser::optics` (disk-image
//! centroids vs the centroid of the exactly projected disk outline).

use crate::support;
use poser::backend::RenderOptions;
use support::canonical::{analytic, load};

/// RMS of measured − expected disk centroids (px) over the scene's disks.
fn geometry_rms(name: &str) -> f64 {
    if let Err(e) = poser::backend::python::require_module("mitsuba") {
        panic!("this test renders with the real Mitsuba 3: {e}");
    }
    let model = load(name);
    let tmp = tempfile::tempdir().unwrap();
    // POSER_SPP overrides the scene's samples (for measuring how the error falls with noise).
    let samples = Some(
        std::env::var("POSER_SPP")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(SPP),
    );
    let opts = RenderOptions {
        samples,
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::mitsuba::render(&model, tmp.path(), &opts)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let (found, expected) = poser::compare::measure_targets(&model, tmp.path()).unwrap();
    // The cylinder stretches the grid across its axis: 9 of its 20 disks are measurable.
    assert!(
        expected >= 8,
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

/// Samples per pixel for these renders (the scenes ask for 16).
///
/// Measured RMS (px) of the 20 disks with Mitsuba 3.9.1 — the error is Monte Carlo noise of the
/// ambient light (Mitsuba's MIS between the uniform-sphere `constant` emitter and the BSDF gives
/// ≈ 7 % per-pixel noise at 16 spp on the white card), and falls as 1/√spp:
///
/// | scene | 16 spp | 256 spp | 1024 spp |
/// |---|---|---|---|
/// | pinhole_air | 0.158 | 0.049 | 0.024 |
/// | flat_tilted | 0.232 | 0.068 | 0.044 |
/// | dome_decentred | 0.151 | — | 0.017 |
///
/// Issue 7's 0.05 px target therefore needs ≈ 1024 spp with Mitsuba; CI uses 256.
const SPP: u32 = 256;

/// At 256 spp: 1.3 × the worst measured RMS (0.068 px, noise). Any convention error (half a
/// pixel, a flipped axis, the wrong principal point or index) is ≥ 0.3 px.
const MAX_RMS_PX: f64 = 0.09;

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
/// Through the cylinder the grid is compressed in x; the detector samples the white card
/// in the max norm, so only the disks whose window stays on the card are measured.
#[test]
fn cylinder_off_axis() {
    let rms = geometry_rms("cylinder_off_axis");
    assert!(
        rms <= MAX_RMS_PX,
        "cylinder_off_axis: RMS {rms:.4} px > {MAX_RMS_PX}"
    );
}
geometry_test!(dispersion, "dispersion");

/// Rendered/analytic over the central 40×30 window, per channel: (mean ratio, standard error
/// of that mean from the per-pixel scatter).
fn radiometry(name: &str) -> Vec<(f64, f64)> {
    let model = load(name);
    let tmp = tempfile::tempdir().unwrap();
    let opts = RenderOptions {
        samples: None,
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::mitsuba::render(&model, tmp.path(), &opts)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let img = poser::compare::LinearImage::read(
        &tmp.path().join(format!("{}.exr", model.image_name(0, 0))),
    )
    .unwrap();
    let (x0, y0) = (img.width / 2 - 20, img.height / 2 - 15);
    (0..3)
        .map(|c| {
            let mut r = Vec::new();
            for y in y0..y0 + 30 {
                for x in x0..x0 + 40 {
                    r.push(
                        img.rgb[y * img.width + x][c] as f64
                            / analytic(&model, x as f64 + 0.5, y as f64 + 0.5, c),
                    );
                }
            }
            let k = r.len() as f64;
            let mean = r.iter().sum::<f64>() / k;
            let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
            eprintln!(
                "mitsuba {name} channel {c}: rendered/analytic = {mean:.5} ± {:.5}",
                sd / k.sqrt()
            );
            (mean, sd / k.sqrt())
        })
        .collect()
}

fn check_radiometry(name: &str) {
    for (c, (mean, se)) in radiometry(name).into_iter().enumerate() {
        // 4 standard errors of the window mean (Mitsuba's noise on this image) + 0.5 % for what
        // the analytic value leaves out (slab inter-reflections, pixel-area averaging).
        let tol = 4.0 * se + 0.005;
        assert!(
            (mean - 1.0).abs() <= tol,
            "{name} channel {c}: {mean:.5} (tolerance ±{tol:.4})"
        );
    }
}

#[test]
fn radiometry_absorbing_strobe() {
    check_radiometry("absorbing_strobe");
}

#[test]
fn radiometry_sun_seabed() {
    check_radiometry("sun_seabed");
}
