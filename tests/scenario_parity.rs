//! Backend parity on the shipped scenes (issue 15): each scene below is rendered by the native
//! backend, the real Mitsuba 3 and the real Cycles at a tenth of its resolution, first pose,
//! 16 spp (`poser bench parity --quick`, the same code), and every pair of backends must agree:
//! image means within 2 % per channel plus a noise allowance computed from the images
//! (`poser::bench::parity`). Disk targets, where a scene has them, must be found by every
//! backend and sit within [`TARGET_RMS_PX`] of the exact truth.
//!
//! The whole list, every scenario and lesson scene, is `poser bench parity`
//! (docs/bench/parity.md). A scene or pair left out here is left out for a measured reason,
//! written beside it; the list is the CI's share of that table.

mod support;
use poser::backend::Backend;
use poser::bench::parity::{Row, run_scene};

/// At a tenth of the resolution and 16 spp, disk centroids are located to about 0.1–0.6 px
/// RMS (measured: calibration_flat 0.14 native, 0.16 Cycles, 0.62 Mitsuba, whose images are
/// the noisiest at equal spp). The 0.05 px agreement is checked at full size and 256 spp on
/// the canonical scenes (`cross_backend.rs`, `mitsuba_canonical.rs`); this bound catches a
/// convention error (half a pixel, a wrong port or focal length), not noise.
const TARGET_RMS_PX: f64 = 1.0;

fn require_python() {
    for m in ["mitsuba", "bpy"] {
        if let Err(e) = poser::backend::python::require_module(m) {
            panic!("the parity tests render with the real Mitsuba 3 and Cycles: {e}");
        }
    }
}

/// Render `name` with every backend and check every pair except those in `skip` (each with
/// its measured reason at the call site).
fn check(name: &str, skip: &[(&str, &str)]) -> Row {
    check_refusing(name, skip, &[])
}

/// [`check`], where the backends in `refuse` must refuse the scene with a message containing
/// the given words (a refusal is part of a backend's contract, as in `tests/out/`).
fn check_refusing(name: &str, skip: &[(&str, &str)], refuse: &[(&str, &str)]) -> Row {
    require_python();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = poser::bench::parity::shipped_scenes(root)
        .into_iter()
        .find(|p| p.file_stem().is_some_and(|s| s == name))
        .unwrap_or_else(|| panic!("no shipped scene `{name}`"));
    let out = tempfile::tempdir().unwrap();
    let row = run_scene(
        &scene,
        &Backend::ALL,
        poser::bench::parity::Form::new(true),
        out.path(),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut failures = Vec::new();
    for b in &row.backends {
        let expected = refuse.iter().find(|(r, _)| *r == b.backend);
        match (&b.refused, expected) {
            (Some(e), None) => failures.push(format!("{}: did not render: {e}", b.backend)),
            (Some(e), Some((_, words))) if !e.contains(words) => failures.push(format!(
                "{}: refused, but not for `{words}`: {e}",
                b.backend
            )),
            (None, Some((_, words))) => failures.push(format!(
                "{}: rendered a scene it should refuse ({words})",
                b.backend
            )),
            _ => {}
        }
        if b.targets.1 > 0 {
            if b.targets.0 < b.targets.1 {
                failures.push(format!(
                    "{}: found {} of {} disk targets",
                    b.backend, b.targets.0, b.targets.1
                ));
            }
            if let Some(rms) = b.target_rms_px.filter(|&r| r > TARGET_RMS_PX) {
                failures.push(format!(
                    "{}: targets {rms:.3} px RMS from the truth",
                    b.backend
                ));
            }
        }
    }
    for p in &row.pairs {
        let skipped = skip
            .iter()
            .any(|(a, b)| (p.a == *a && p.b == *b) || (p.a == *b && p.b == *a));
        if !skipped && !p.agree {
            failures.push(format!(
                "{} vs {}: means differ by {:+.2} / {:+.2} / {:+.2} % (allowed ±{:.2} %)",
                p.b,
                p.a,
                100.0 * p.rel_diff[0],
                100.0 * p.rel_diff[1],
                100.0 * p.rel_diff[2],
                100.0 * (poser::bench::parity::TOLERANCE + p.allowance)
            ));
        }
    }
    assert!(row.status != "dark", "{name}: black in every backend");
    assert!(failures.is_empty(), "{name}:\n  {}", failures.join("\n  "));
    row
}

// Scenes where all three backends agree (quick form, measured by `poser bench parity --quick`).

#[test]
fn calibration_flat() {
    check("calibration_flat", &[]);
}

#[test]
fn in_air() {
    check("in_air", &[]);
}

#[test]
fn dome_orbit() {
    check("dome_orbit", &[]);
}

#[test]
fn subsea_metrology() {
    // The stereo rig at 1/10 size: square pixels must stay square (Mitsuba refused it).
    check("subsea_metrology", &[]);
}

#[test]
fn turbidity_contrast() {
    check("turbidity_contrast", &[]);
}

// Refusals: a camera in the air over waves, and the sun's caustics, are native-only.

#[test]
fn caustics_shallow() {
    check_refusing(
        "caustics_shallow",
        &[],
        &[("mitsuba", "caustics"), ("blender", "caustics")],
    );
}

#[test]
fn uav_through_waves() {
    check_refusing(
        "uav_through_waves",
        &[],
        &[
            ("mitsuba", "camera in the air"),
            ("blender", "camera in the air"),
        ],
    );
}

// Known differences, measured (docs/backends.md, "Every shipped scene"); the pairs that do
// not involve them are still checked.

#[test]
fn reef_strip() {
    // Sun and strobes in scattering water, flat port. Cycles was +32 / +14 / +18 % here while
    // its housing let the light that the port reflects inwards out to the sky (HOUSING_INSIDE
    // in backends/blender/poser_blender/builder.py); now −0.6 / −1.4 / −1.5 %.
    check("reef_strip", &[]);
}

#[test]
fn paper_survey() {
    // Deep (15 m) ambient-lit water, flat port: Cycles was +254 / +82 / +158 % from the same
    // leak. Each of Mitsuba (−3.6 / −2.4 / −3.1 %) and Cycles (−0.5 / +3.4 / +1.6 %) agrees
    // with native within its allowance; being on either side of it, they differ from each
    // other by +3.2 / +6.0 / +4.9 % against an allowance of 4.4 % (quick form, 16 spp), so
    // that pair is left to the full form.
    check("paper_survey", &[("mitsuba", "blender")]);
}

#[test]
fn flat_port_deformation_dome() {
    // A dome port in sunlit water: Mitsuba and Cycles were both +17 % G, light reflected back
    // into the housing leaving through the dome's back (Mitsuba's spheres are whole) or the
    // housing body (Cycles). Both housings are now black inside.
    check("flat_port_deformation_dome", &[]);
}

#[test]
fn gsd_reef() {
    // Clear, strongly chromatic water (Jerlov IB, no scattering) at 30 m under ambient light:
    // Mitsuba's `volpath` was −36 % in every channel (its red-sampled free flights almost
    // never reach the surface); `volpathmis` (spectral MIS) agrees.
    check("gsd_reef", &[]);
}

#[test]
fn coral_self_occlusion() {
    // A dome port in sunlit scattering water. Mitsuba now agrees with native (−0.7 / −0.8 /
    // −0.8 %, its dome housing closed); Cycles is +8.3 / +4.4 / +5.4 % against native and
    // +9.0 / +5.2 / +6.2 % against Mitsuba (quick form), cause not yet found
    // (docs/backends.md, "Known differences").
    check(
        "coral_self_occlusion",
        &[("native", "blender"), ("mitsuba", "blender")],
    );
}
