//! A rectangle of the image rendered alone (`poser render --crop`, `poser compare --crop`):
//! the native renderer gives the very pixels of the whole image (the same random numbers), a
//! rectangle outside the image is refused before anything is written, and `--crop targets`
//! measures disk targets at the full image size for a small share of its cost. The Mitsuba and
//! Cycles crops are checked in the full tier (`target_parity`).

use std::path::Path;
use std::process::{Command, Output};

fn poser(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .arg("-o")
        .arg(out)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

/// `poser compare SCENE --backends native --samples 16 --crop targets` with `extra`
/// arguments, into `dir`: its stderr, and the native backend's entry of report.json, with how
/// many targets it measured checked to be all of at least `least` expected, and their RMS
/// distance to the truth, px.
fn native_crop(
    scene: &str,
    extra: &[&str],
    dir: &Path,
    least: u64,
) -> (String, serde_json::Value, f64) {
    let mut args = vec![
        "compare",
        scene,
        "--backends",
        "native",
        "--samples",
        "16",
        "--crop",
        "targets",
    ];
    args.extend_from_slice(extra);
    let out = poser(&args, dir);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{scene}: {stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let native = json["backends"][0].clone();
    let (found, expected) = (
        native["targets_measured"].as_u64().unwrap(),
        native["targets_expected"].as_u64().unwrap(),
    );
    assert!(
        expected >= least && found == expected,
        "{scene}: {found} of {expected}"
    );
    let rms = native["target_rms_px"].as_f64().unwrap();
    (stderr, native, rms)
}

const RENDER: [&str; 10] = [
    "render",
    "scenarios/calibration_flat.toml",
    "--poses",
    "0",
    "--scale",
    "0.1",
    "--samples",
    "4",
    "--skip-truth",
    "--quiet",
];

#[test]
fn a_crop_is_the_same_pixels_as_the_whole_image() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, part) = (dir.path().join("whole"), dir.path().join("part"));
    let out = poser(&RENDER, &whole);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut args = RENDER.to_vec();
    args.extend(["--crop", "30,20,50,40"]);
    let out = poser(&args, &part);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let a = poser::image::read_exr(&whole.join("img_0001.exr")).unwrap();
    let b = poser::image::read_exr(&part.join("img_0001.exr")).unwrap();
    assert_eq!((a.width, a.height), (160, 120));
    assert_eq!((b.width, b.height), (50, 40));
    let mut differ = 0;
    for j in 0..40 {
        for i in 0..50 {
            let (pa, pb) = (a.rgb[(20 + j) * 160 + 30 + i], b.rgb[j * 50 + i]);
            differ += usize::from(pa != pb);
        }
    }
    assert_eq!(
        differ, 0,
        "of 2000 pixels, {differ} differ from the whole image's"
    );
    // The depth image is cropped alike.
    let d = poser::image::read_exr(&part.join("img_0001.depth.exr")).unwrap();
    assert_eq!((d.width, d.height), (50, 40));
}

#[test]
fn a_crop_outside_the_image_is_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    for (crop, words) in [
        ("150,100,20,10", "leaves camera"),
        ("0,0,0,10", "empty"),
        ("1,2,3", "X,Y,W,H"),
    ] {
        let out_dir = dir.path().join(crop.replace(',', "_"));
        let mut args = RENDER.to_vec();
        args.extend(["--crop", crop]);
        let out = poser(&args, &out_dir);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "--crop {crop}: {stderr}");
        assert!(stderr.contains(words), "--crop {crop}: {stderr}");
        assert!(
            !out_dir.exists(),
            "--crop {crop} wrote {}",
            out_dir.display()
        );
    }
}

#[test]
fn compare_crop_targets_measures_the_targets_at_full_size() {
    // calibration_flat at its full 1600 × 1200 px: the rectangle around the targets nearest
    // the first image's centre, the checkerboard's corners (before corners were measured, the
    // disks': 4 of 4 at 16 spp, 0.015 px RMS, and 0.11 px before the detector fitted the
    // background as a plane). Measured at 16 spp: 4 of 4 corners, 0.011 px RMS.
    let dir = tempfile::tempdir().unwrap();
    let (stderr, native, rms) = native_crop("scenarios/calibration_flat.toml", &[], dir.path(), 4);
    assert!(
        stderr.contains("--crop targets: image img_0001 (pose 0)"),
        "{stderr}"
    );
    assert_eq!(native["images"], 1);
    assert!(
        rms <= 0.05,
        "targets {rms:.4} px RMS from the truth at full size"
    );
    // The truth is in the whole image's pixels: the targets lie inside the rectangle there.
    let model = poser::scene::load(Path::new("scenarios/calibration_flat.toml"), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let geometry = poser::geometry::Bvh::of_model(&model).unwrap();
    let crop = poser::compare::target_crop(&model, &geometry, 0, 256, poser::compare::Points::All)
        .unwrap()
        .unwrap();
    let img = poser::image::read_exr(&dir.path().join("native/img_0001.exr")).unwrap();
    assert_eq!((img.width, img.height), (crop.width, crop.height));
    assert!(
        img.width <= 256 && img.height <= 256,
        "{}×{}",
        img.width,
        img.height
    );
    for t in native["targets"].as_array().unwrap() {
        let (u, v) = (
            t["truth"][0].as_f64().unwrap(),
            t["truth"][1].as_f64().unwrap(),
        );
        assert!(
            (crop.x as f64..(crop.x + crop.width) as f64).contains(&u)
                && (crop.y as f64..(crop.y + crop.height) as f64).contains(&v),
            "exact point {u}, {v} px: not in the whole image's pixels of {crop:?}"
        );
        assert_eq!(t["kind"], "corner");
    }
}

/// `--crop targets` measures only what the truth sees: in dome_orbit's first image the coded
/// targets nearest the image's centre (codes/4 and codes/5, at u = 800 px) stand behind the
/// amphora, so the crop goes to codes/1 and codes/2 (u ≈ 360–430 px), which the ground truth
/// lists as seen. Without the occlusion test the crop centred on the hidden ones, where every
/// backend then found "not found".
#[test]
fn a_target_crop_skips_targets_the_scene_hides() {
    let model = poser::scene::load(Path::new("scenarios/dome_orbit.toml"), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let geometry = poser::geometry::Bvh::of_model(&model).unwrap();
    let truth = poser::truth::compute_in(&model, &geometry).unwrap();
    let seen: Vec<&str> = truth.images[0]
        .points
        .iter()
        .map(|p| p.id.as_str())
        .collect();
    assert!(
        !seen.contains(&"codes/4") && seen.contains(&"codes/1"),
        "{seen:?}"
    );
    let crop = poser::compare::target_crop(&model, &geometry, 0, 256, poser::compare::Points::All)
        .unwrap()
        .expect("codes/1 and codes/2 are measurable");
    assert!(
        crop.x + crop.width < 600 && crop.y > 700,
        "the crop {crop:?} is not around codes/1 and codes/2"
    );
}

/// The shipped scenes whose targets are too small or too hidden for the calibration scenes'
/// checks, measured by the native renderer with `--crop targets` at a size where their dots
/// can be located (`--scale`: the sensor's pixels split 2 or 3 ways; the scene is the same):
/// dome_orbit's oblique coded targets at full size (by their edge), reef_strip's scale-bar dot
/// at twice (by its centroid, 7 px in radius) and caustics_shallow's at three times (by its
/// edge, under the waves' caustics). Measured at 16 spp: 0.027, 0.022 and 0.008 px (0.0038,
/// 0.0173, 0.0011 at 64). Mitsuba and Cycles are noise-limited on these sunlit scenes, or
/// refuse the wavy surface (docs/backends.md, "Targets at full size").
#[test]
fn native_holds_the_small_and_oblique_shipped_targets_to_five_hundredths_of_a_pixel() {
    for (scene, scale) in [
        ("scenarios/dome_orbit.toml", "1"),
        ("scenarios/reef_strip.toml", "2"),
        ("scenarios/caustics_shallow.toml", "3"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let (_, _, rms) = native_crop(scene, &["--scale", scale], dir.path(), 1);
        assert!(rms <= 0.05, "{scene}: {rms:.4} px RMS from the truth");
    }
}
