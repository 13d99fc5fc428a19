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
//!   these tests. moorea's GCP disk (`scenarios/sites/`): native and Cycles hold it as
//!   shipped, Mitsuba at 1024 spp; tested without the water's scattering (below).
//! * archaeology (a coded target's dot, 65 px in radius, located by its edge): native
//!   0.0001 px at 64 spp, Cycles 0.034 px at 256, Mitsuba 0.036 px at 1024: this test. With the area centroid Mitsuba had read 0.12 px (Δv +0.12) at 2048
//!   and 8192 spp: the centroid, not Mitsuba (docs/backends.md, "Targets at full size").
//! * dome_orbit (full size), reef_strip (at twice), subsea_metrology and turbidity_contrast:
//!   as shipped, Mitsuba and Cycles are noise-limited there (0.17–1.67 px at 64 spp on the
//!   first two, not falling by 512; subsea's disk 0.02–0.085 px at 256; turbidity's corners
//!   0.12–0.36 px up to 8192 spp natively), the heavy-tailed noise of light scattered in the
//!   water. With the water's scattering off (`water.scattering = 0`: the port, the geometry,
//!   the water's index and absorption unchanged) every backend holds them to 0.05 px:
//!   `the_noisy_scenes_targets_without_the_waters_scattering_in_every_backend`. Native holds
//!   dome_orbit, reef_strip and caustics_shallow as shipped
//!   (`crop::native_holds_the_small_and_oblique_shipped_targets…`, fast tier); Mitsuba and
//!   Cycles refuse caustics_shallow's wavy surface.
//! * uav_through_waves (native only; the peers refuse a camera over the sea): through the
//!   waves a disk's outline departs 1.3–4.8 px from an ellipse; its exact outline, shifted, is
//!   fitted instead. Lit by the sky alone (the sun's caustics shade the surround in patches):
//!   this test.

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
    points_in(scene, &[], 1.0, kind, cases);
}

/// [`points_at_full_size_in`] with the scene's values overridden (`sets`, as `--set`) and its
/// cameras' resolution scaled by `scale` (as `--scale`).
fn points_in(scene: &str, sets: &[&str], scale: f64, kind: &str, cases: &[(&str, u32, f64, &str)]) {
    require_python();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut model = poser::scene::load(&root.join(scene), &sets)
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    if scale != 1.0 {
        model = model.with_checked_resolution_scale(scale).unwrap();
    }
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
            // Measured 0.036 px at 1024 spp (0.039 at 256, 0.061 at 64: noise, its direction
            // changing with the samples). The area centroid read Mitsuba's dot 0.55 px off
            // at 256 spp, and 0.12 px (Δv +0.12) at 2048 and 8192, which this bound refuses.
            ("mitsuba", 1024, 0.05, "issue 37's bound"),
            // Measured 0.034 px at 256 spp (the centroid: 0.43).
            ("blender", 256, 0.05, "issue 37's bound"),
        ],
    );
}

/// The targets where Mitsuba and Cycles are noise-limited as shipped, with the water's
/// scattering off (`water.scattering = 0`: the port, the water's index and absorption, the
/// lights and the geometry unchanged; the heavy-tailed noise of light scattered in the water
/// gone): what a target's position depends on, the refraction through the port and the
/// projection, is then held to 0.05 px in every backend. As shipped they measure 0.17–1.67 px
/// (dome_orbit, reef_strip; not falling from 64 to 512 spp) and 0.085 px (subsea_metrology,
/// Cycles at 256), docs/backends.md "Targets at full size".
#[test]
fn the_noisy_scenes_targets_without_the_waters_scattering_in_every_backend() {
    let dry = ["water.scattering=0"];
    let bound = |b, spp| (b, spp, 0.05, "issue 37's bound");
    // Measured (native / Cycles at 64 spp, Mitsuba at the samples given): dome_orbit's coded
    // targets at full size 0.0062 / 0.0278 / 0.0169 px (256; 0.074 at 64).
    let at_256 = [
        bound("native", 64),
        bound("blender", 64),
        bound("mitsuba", 256),
    ];
    points_in("scenarios/dome_orbit.toml", &dry, 1.0, "disk", &at_256);
    // reef_strip's scale-bar dot at twice its size (7 px in radius, its centroid): 0.0071 /
    // 0.0257 / 0.035 px (1024; 0.145 at 256: Mitsuba's render stays the noisiest, lit by the
    // light the seabed sends back up, and a centroid sums every pixel of its window).
    let at_1024 = [
        bound("native", 64),
        bound("blender", 64),
        bound("mitsuba", 1024),
    ];
    points_in("scenarios/reef_strip.toml", &dry, 2.0, "disk", &at_1024);
    // subsea_metrology's disk by its edge: 0.0016 / 0.0346 / 0.0013 px (256).
    let subsea = "scenarios/lessons/subsea_metrology.toml";
    points_in(subsea, &dry, 1.0, "disk", &at_256);
    // turbidity_contrast's 35 corners: 0.0041 / 0.0117 / 0.0282 px (256).
    let turbidity = "scenarios/lessons/turbidity_contrast.toml";
    points_in(turbidity, &dry, 1.0, "corner", &at_256);
    // POSER's Moorea layout (`scenarios/sites/`): a 10 cm GCP disk by its edge, 0.0009 /
    // 0.0060 / 0.034 px (256). As shipped: native 0.0014 px, Cycles 0.038 (64 spp), Mitsuba 0.058 /
    // 0.059 / 0.012 px at 64 / 256 / 1024 (noise; 1024 spp costs a minute more here).
    points_in("scenarios/sites/moorea.toml", &dry, 1.0, "disk", &at_256);
}

/// uav_through_waves (native only: Mitsuba and Cycles refuse a camera in the air over the
/// sea): its disks seen from 20 m through 15 cm waves, whose outlines the waves bend out of
/// any ellipse, located by shifting their exact outlines (`sectors::outline_edge`) at three
/// times the size. Under the sun the caustics on the sand shade the white surround in
/// patches no plane follows, and pull the edge 0.05–0.37 px (64 spp, not falling with
/// samples); lit by a sky alone (`sun.irradiance = 0`, an ambient light added) the same disks
/// are 0.056 px (64 spp), 0.029 (128), 0.016 (256) from the exact refraction through the
/// waves.
#[test]
fn uav_through_waves_disks_by_their_exact_outline_lit_by_the_sky() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let lesson = root.join("scenarios/lessons");
    std::fs::create_dir(dir.path().join("assets")).unwrap();
    std::fs::copy(
        lesson.join("assets/uav_targets.txt"),
        dir.path().join("assets/uav_targets.txt"),
    )
    .unwrap();
    let text = std::fs::read_to_string(lesson.join("uav_through_waves.toml")).unwrap();
    let scene = dir.path().join("uav_sky.toml");
    std::fs::write(
        &scene,
        format!("{text}\n[[lights]]\ntype = \"ambient\"\nradiance = 100\n"),
    )
    .unwrap();
    points_in(
        scene.to_str().unwrap(),
        &["sun.irradiance=0"],
        3.0,
        "disk",
        &[("native", 128, 0.05, "issue 37's bound")],
    );
}
