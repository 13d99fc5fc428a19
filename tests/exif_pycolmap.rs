//! The camera images' EXIF as the real pycolmap reads it (full tier): COLMAP's focal-length
//! prior from poser's JPEG is the one the written tags give, and close to the true focal length.

use std::path::{Path, PathBuf};

/// Full tier: `poser render --sensor` writes a JPEG whose EXIF pycolmap's
/// `infer_camera_from_image` turns into a camera with a focal-length prior. COLMAP takes the
/// 35 mm equivalent first (`f35 / 43.27 mm × image diagonal in pixels`), so its prior is the
/// written whole-mm equivalent's, within half a millimetre of equivalent focal length of the
/// true `fx`; the make, model and size it reads are poser's.
#[test]
fn pycolmap_infers_the_focal_length_poser_wrote_in_the_jpeg_exif() {
    const SCRIPT: &str = r#"
import json, sys
import pycolmap
cam = pycolmap.infer_camera_from_image(sys.argv[1])
print(json.dumps({
    "model": cam.model.name, "width": cam.width, "height": cam.height,
    "params": list(cam.params), "focal": cam.mean_focal_length(),
    "prior": bool(cam.has_prior_focal_length),
}))
"#;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let py = std::env::var_os("POSER_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .current_dir(root)
        .args([
            "render",
            "scenarios/calibration_flat.toml",
            "--scale",
            "0.1",
            "--samples",
            "1",
            "--poses",
            "0",
            "--quiet",
            "--sensor",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let jpg = out.join("camera/img_0001.jpg");
    // What poser wrote, read back with kamadak-exif.
    let x = exif::Reader::new()
        .read_from_container(&mut std::io::BufReader::new(
            std::fs::File::open(&jpg).unwrap(),
        ))
        .unwrap();
    let get = |tag| {
        x.get_field(tag, exif::In::PRIMARY)
            .and_then(|f| match &f.value {
                exif::Value::Rational(v) => Some(v[0].to_f64()),
                v => v.get_uint(0).map(|u| u as f64),
            })
            .unwrap()
    };
    let f35 = get(exif::Tag::FocalLengthIn35mmFilm);
    let (w, h) = (
        get(exif::Tag::PixelXDimension),
        get(exif::Tag::PixelYDimension),
    );
    let o = std::process::Command::new(&py)
        .args(["-c", SCRIPT])
        .arg(&jpg)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    eprintln!("pycolmap: {got}; poser wrote f35 = {f35} mm, {w} × {h} px");
    assert_eq!(got["prior"], true, "{got}");
    assert_eq!(
        (got["width"].as_f64(), got["height"].as_f64()),
        (Some(w), Some(h))
    );
    let focal = got["focal"].as_f64().unwrap();
    // COLMAP's reading of the 35 mm equivalent (float arithmetic: 1e-6).
    let expect = f35 / 43.27 * w.hypot(h);
    assert!(
        (focal / expect - 1.0).abs() < 1e-6,
        "{focal} px against {expect}"
    );
    // And the true in-air focal length of this 160 × 120 preview.
    let cam = &crate::support::scenario("calibration_flat.toml").cameras[0];
    let fx = cam.fx * w / cam.width as f64;
    assert!(
        (focal / fx - 1.0).abs() <= 0.5 / f35 + 1e-3,
        "{focal} px against the true {fx} px"
    );
}
