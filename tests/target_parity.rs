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
//! * archaeology (a coded target's dot, 65 px in radius, located by its edge): native
//!   0.0001 px at 64 spp, Cycles 0.034 px at 256, Mitsuba 0.039 px at 256 and 0.0015 px at
//!   1024: this test. With the area centroid Mitsuba had read 0.12 px (Δv +0.12) at 2048
//!   and 8192 spp: the centroid, not Mitsuba (docs/backends.md, "Targets at full size").
//! * turbidity_contrast's corners: 0.146 / 0.123 px natively at 2048 / 8192 spp, heavy-tailed noise of
//!   the strobes' light in 1/m scattering water (0.0002 px without the scattering).
//! * subsea_metrology: its first measurable point is a disk (75 px in radius) under the veil
//!   of its lamps' backscatter: 0.057 / 0.020 / 0.085 px (native / Mitsuba / Cycles) at
//!   256 spp, noise (native 0.007–0.084 px over three seeds at 64 spp; 0.0015 px without the
//!   scattering). Not run here: 0.05 px on one disk needs more samples than the tier allows.
//! * dome_orbit (full size), reef_strip (at twice) and caustics_shallow (three times): native
//!   holds them to 0.05 px (`crop::native_holds_the_small_and_oblique_shipped_targets…`, fast
//!   tier); Mitsuba and Cycles are noise-limited there (0.17–1.67 px at 64 spp, not falling by
//!   512) or refuse the wavy surface.
//! * uav_through_waves: through the waves a disk's outline departs 1.3–4.8 px from an ellipse
//!   and its surround is bent alike: no window measures it.

use poser::backend::{Backend, RenderOptions};

fn require_python() {
    for m in ["mitsuba", "bpy"] {
        if let Err(e) = poser::backend::python::require_module(m) {
            panic!("the target parity test renders with the real Mitsuba 3 and Cycles: {e}");
        }
    }
}

/// Render `pose` of `model` (cropped) with `backend` at `samples` into `dir/backend`: the
/// offsets from the truth of the points of `kind` (`disk` or `corner`) found, and how many
/// were expected.
fn offsets(
    model: &poser::model::Model,
    dir: &std::path::Path,
    backend: &str,
    samples: u32,
    kind: &str,
    pose: usize,
) -> (Vec<[f64; 2]>, usize) {
    let opts = RenderOptions {
        samples: Some(samples),
        poses: Some(vec![pose]),
        progress: false,
        resume: false,
    };
    let out = dir.join(backend);
    Backend::parse(backend)
        .unwrap()
        .render(model, &out, &opts)
        .unwrap();
    let name = model.image_name(pose, 0);
    let img = poser::image::read_exr(&out.join(format!("{name}.exr"))).unwrap();
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
    let geometry = poser::geometry::Bvh::of_model(&model).unwrap();
    let crop =
        poser::compare::target_crop(&model, &geometry, 0, 256, poser::compare::Points::Disks)
            .unwrap()
            .expect("the first image shows the circle grid");
    assert_eq!(model.cameras[0].width, 1600, "the full size");
    model.render.crop = Some(crop);
    let dir = tempfile::tempdir().unwrap();
    // (backend, samples, bound on the RMS distance to the truth in px, why that bound). The
    // disks (24 px in radius) are located by their edges (`poser::compare::sectors::disk_edge`).
    // Measured: native 0.0041 px at 64 spp; Cycles 0.0240 at 64 (0.0152 at 128); Mitsuba
    // 0.0129 at 128 (0.0112 at 512). With the area centroid they measured 0.011, 0.045 and
    // 0.037 px (Mitsuba at 512 spp, 0.198 at 64): a centroid adds every pixel's noise in the
    // window, the edge only the pixels along it.
    let cases = [
        ("native", 64, 0.05, "issue 37's bound"),
        ("blender", 64, 0.05, "issue 37's bound"),
        ("mitsuba", 128, 0.05, "issue 37's bound"),
    ];
    let mut failures = Vec::new();
    for (name, samples, bound, why) in cases {
        let (found, expected) = offsets(&model, dir.path(), name, samples, "disk", 0);
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
        // right at the frame's right edge): their mean Δu. In metres (before views in
        // millimetres) Mitsuba's ray offset at the glass faces, (1 + max |coordinate|) ×
        // 8.94e-5 units, biased every disk by Δu +0.088 px (4096 spp, centroids;
        // docs/backends.md, "Per-view coordinates").
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
    let cases: Vec<_> = ["native", "mitsuba", "blender"]
        .into_iter()
        .map(|b| (b, samples, 0.05, "issue 37's bound"))
        .collect();
    points_at_full_size_in(scene, kind, &cases);
}

/// [`points_at_full_size`] with each backend's samples and bound: `(backend, samples, bound
/// in px, why that bound)`.
fn points_at_full_size_in(scene: &str, kind: &str, cases: &[(&str, u32, f64, &str)]) {
    require_python();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut model = poser::scene::load(&root.join(scene), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let which = match kind {
        "corner" => poser::compare::Points::Corners,
        _ => poser::compare::Points::All,
    };
    // The first image that shows one (as `poser compare --crop targets` picks it).
    let geometry = poser::geometry::Bvh::of_model(&model).unwrap();
    let (pose, crop) = (0..model.poses.len())
        .find_map(|p| {
            poser::compare::target_crop(&model, &geometry, p, 256, which)
                .unwrap()
                .map(|c| (p, c))
        })
        .expect("an image shows the target");
    model.render.crop = Some(crop);
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for &(name, samples, bound, why) in cases {
        let (found, expected) = offsets(&model, dir.path(), name, samples, kind, pose);
        assert!(expected >= 1, "{scene}, {name}: no {kind} expected");
        assert_eq!(found.len(), expected, "{scene}, {name}: {kind}s lost");
        let rms = rms(&found);
        eprintln!(
            "{scene}, {name}: {} {kind}(s), {rms:.4} px RMS at {samples} spp",
            found.len()
        );
        if rms > bound {
            failures.push(format!("{name}: {kind}s {rms:.4} px RMS > {bound} ({why})"));
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

/// archaeology's coded target `gcp_nw/3`, its centre dot 65 px in radius at full size (6000 ×
/// 4000 px) in a sunlit, strobe-lit trench 25 m down, located by its edge.
#[test]
fn archaeology_coded_target_dot_at_full_size_in_every_backend() {
    points_at_full_size_in(
        "scenarios/lessons/archaeology.toml",
        "disk",
        &[
            // Measured 0.0001 px at 64 spp.
            ("native", 64, 0.05, "issue 37's bound"),
            // Measured 0.039 px at 256 spp (0.083 with the band taken from the window, before
            // the gap along each radius), 0.0015 at 1024: noise. The area centroid read
            // Mitsuba's dot 0.55 px off at 256 spp, and 0.12 px (Δv +0.12) at 2048 and 8192,
            // which this bound refuses.
            ("mitsuba", 256, 0.10, "Mitsuba's noise at 256 spp"),
            // Measured 0.034 px at 256 spp (the centroid: 0.43).
            ("blender", 256, 0.05, "issue 37's bound"),
        ],
    );
}
