//! Target positions at a decisive size, in every backend (issue 37). The quick parity runs
//! (`scenario_parity`, a tenth of the resolution) hold targets to 1 px, and the canonical
//! scenes (`cross_backend`, 160 × 120 px) to 0.05 px near the image centre; neither can see an
//! error that grows across a full-size frame. Here a shipped scene is rendered at its full
//! size, cropped to the targets nearest the image centre (`render.crop`, `poser compare --crop
//! targets`), by every backend, and each backend's disks, checkerboard corners or Siemens star
//! centre are held to the truth.
//!
//! The shipped scenes with targets, measured with `poser compare SCENE --samples N --crop
//! targets -o DIR` (docs/backends.md, "Targets at full size", "Checkerboard corners and Siemens
//! stars"):
//! * calibration_flat (disks and corners), calibration_by_port (corners), gsd_reef (a star):
//!   these tests.
//! * archaeology: native 0.016 px at 64 spp; Cycles 0.54 px (64), 0.134 px (1024): noise;
//!   Mitsuba 0.122 px at 2048 and 8192 spp, a bias of Δv +0.12 px that is neither the ray
//!   offset nor the texture (docs/backends.md, "Targets at full size"): not run here, the
//!   native render alone takes 50 s, and Mitsuba's bias turns with the sun (not by the
//!   housing's sun shadow, which falls 2 000 px and more away: `tests/housing_shadow.rs`,
//!   `poser::geometry::shadow`); its cause is open.
//! * turbidity_contrast's corners: 0.10 px natively at 2048–8192 spp, heavy-tailed noise of
//!   the strobes' light in 1/m scattering water (0.0002 px without the scattering).
//! * subsea_metrology: its first measurable point is a disk at 1.2–1.6 px (64–256 spp), not
//!   decided between noise and bias.
//! * dome_orbit, reef_strip, caustics_shallow, uav_through_waves: no disk of theirs can be
//!   measured in any image (coded targets' and scale bars' dots have too narrow a white
//!   surround for the detector's window: it needs a dot at least 12 px across).

use poser::backend::{Backend, RenderOptions};

fn require_python() {
    for m in ["mitsuba", "bpy"] {
        if let Err(e) = poser::backend::python::require_module(m) {
            panic!("the target parity test renders with the real Mitsuba 3 and Cycles: {e}");
        }
    }
}

/// Render pose 0 of `model` (cropped) with `backend` at `samples` into `dir/backend`: the
/// offsets from the truth of the points of `kind` (`disk` or `corner`) found, and how many
/// were expected.
fn offsets(
    model: &poser::model::Model,
    dir: &std::path::Path,
    backend: &str,
    samples: u32,
    kind: &str,
) -> (Vec<[f64; 2]>, usize) {
    let opts = RenderOptions {
        samples: Some(samples),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    let out = dir.join(backend);
    Backend::parse(backend)
        .unwrap()
        .render(model, &out, &opts)
        .unwrap();
    let img = poser::image::read_exr(&out.join("img_0001.exr")).unwrap();
    let crop = model.render.crop.unwrap();
    assert_eq!(
        (img.width, img.height),
        (crop.width, crop.height),
        "{backend}"
    );
    let all: Vec<_> = poser::compare::target_residuals(model, &out, 1)
        .unwrap()
        .into_iter()
        .filter(|t| t.kind == kind)
        .collect();
    (all.iter().filter_map(|t| t.offset).collect(), all.len())
}

/// The RMS length of `d`, px.
fn rms(d: &[[f64; 2]]) -> f64 {
    (d.iter().map(|d| d[0] * d[0] + d[1] * d[1]).sum::<f64>() / d.len() as f64).sqrt()
}

#[test]
fn calibration_flat_targets_at_full_size_in_every_backend() {
    require_python();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut model = poser::scene::load(&root.join("scenarios/calibration_flat.toml"), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let crop = poser::compare::target_crop(&model, 0, 256, poser::compare::Points::Disks)
        .unwrap()
        .expect("the first image shows the circle grid");
    assert_eq!(model.cameras[0].width, 1600, "the full size");
    model.render.crop = Some(crop);
    let dir = tempfile::tempdir().unwrap();
    // (backend, samples, bound on the RMS distance to the truth in px, why that bound).
    let cases = [
        // Measured 0.011 px at 64 spp.
        ("native", 64, 0.05, "issue 37's bound"),
        // Measured 0.045 px at 64 spp (noise), 0.041 px at 128.
        ("blender", 128, 0.05, "issue 37's bound"),
        // Measured 0.037 px at 512 spp, mean Δu −0.012 (0.198 at 64, 0.072 at 1024, 0.0255 at
        // 4096): noise. In metres (before views in millimetres) Mitsuba's ray offset at the
        // glass faces, (1 + max |coordinate|) × 8.94e-5 units, biased every disk by Δu
        // +0.088 px (4096 spp), which the mean Δu bound below refuses; it measured 0.16 px at
        // 256 spp and 0.11 at 1024 (docs/backends.md, "Per-view coordinates", "Targets at full
        // size").
        (
            "mitsuba",
            512,
            0.10,
            "Mitsuba's noise at 512 spp (0.05 px is met at 4096 spp: 0.0255 px measured)",
        ),
    ];
    let mut failures = Vec::new();
    for (name, samples, bound, why) in cases {
        let (found, expected) = offsets(&model, dir.path(), name, samples, "disk");
        assert!(expected >= 4, "{name}: {expected} disks expected");
        assert_eq!(found.len(), expected, "{name}: disks lost");
        let rms = rms(&found);
        eprintln!(
            "{name}: {} disks, {rms:.4} px RMS at {samples} spp",
            found.len()
        );
        if rms > bound {
            failures.push(format!("{name}: {rms:.4} px RMS > {bound} ({why})"));
        }
        // A bias shared by the disks (a float32 ray offset at the glass shifts them all to the
        // right at the frame's right edge): their mean Δu, measured −0.012 px for Mitsuba at
        // 512 spp, +0.088 px in metres.
        let mean_du = found.iter().map(|d| d[0]).sum::<f64>() / found.len() as f64;
        if mean_du.abs() > 0.05 {
            failures.push(format!("{name}: mean Δu {mean_du:+.4} px, beyond ±0.05"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The checkerboard's inner corners and a Siemens star's centre, fitted by their exact
/// box-filtered image (`poser::compare::sectors`), in every backend at full size, cropped to
/// those nearest the first image's centre: `(scene, samples, kind)`. Measured with `poser
/// compare SCENE --samples N --crop targets` (RMS, native / Mitsuba / Cycles):
/// calibration_flat's four corners 0.0073 / 0.0141 / 0.0085 px at 128 spp (0.0063 / 0.0056 /
/// 0.0070 at 512); calibration_by_port's 54 corners 0.0138 / 0.0279 / 0.0167 px at 256 spp
/// (native 0.025 at 64); gsd_reef's star 0.0005 / 0.0115 / 0.0017 px at 64 spp.
fn points_at_full_size(scene: &str, samples: u32, kind: &str) {
    require_python();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut model = poser::scene::load(&root.join(scene), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let which = match kind {
        "corner" => poser::compare::Points::Corners,
        _ => poser::compare::Points::All,
    };
    let crop = poser::compare::target_crop(&model, 0, 256, which)
        .unwrap()
        .expect("the first image shows the target");
    model.render.crop = Some(crop);
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for name in ["native", "mitsuba", "blender"] {
        let (found, expected) = offsets(&model, dir.path(), name, samples, kind);
        assert!(expected >= 1, "{scene}, {name}: no {kind} expected");
        assert_eq!(found.len(), expected, "{scene}, {name}: {kind}s lost");
        let rms = rms(&found);
        eprintln!(
            "{scene}, {name}: {} {kind}(s), {rms:.4} px RMS at {samples} spp",
            found.len()
        );
        if rms > 0.05 {
            failures.push(format!(
                "{name}: {kind}s {rms:.4} px RMS > 0.05 (issue 37's bound)"
            ));
        }
    }
    assert!(failures.is_empty(), "{scene}: {failures:#?}");
}

#[test]
fn calibration_flat_checkerboard_corners_at_full_size_in_every_backend() {
    points_at_full_size("scenarios/calibration_flat.toml", 128, "corner");
}

#[test]
fn calibration_by_port_checkerboard_corners_at_full_size_in_every_backend() {
    points_at_full_size("scenarios/lessons/calibration_by_port.toml", 256, "corner");
}

#[test]
fn gsd_reef_siemens_star_centre_at_full_size_in_every_backend() {
    points_at_full_size("scenarios/lessons/gsd_reef.toml", 64, "star");
}
