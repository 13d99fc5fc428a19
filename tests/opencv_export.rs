//! The `opencv/` truth files, read by the real OpenCV (the pinned `opencv-python-headless`):
//! `cv::FileStorage` loads each camera file, and `cv::projectPoints` / `cv::fisheye::projectPoints`
//! with the written poses reproduce the written observations. Full tier (`cargo test --test backends`).
use std::path::Path;
use std::process::Command;

const CHECK: &str = r#"
import csv, sys
import cv2
import numpy as np

d = sys.argv[1]
fs = cv2.FileStorage(d + "/opencv/camera_1.yml", cv2.FILE_STORAGE_READ)
assert fs.isOpened()
K = fs.getNode("camera_matrix").mat()
dist = fs.getNode("distortion_coefficients").mat().ravel()
model = fs.getNode("distortion_model").string()
assert int(fs.getNode("image_width").real()) > 0
poses = {r["image"]: r for r in csv.DictReader(open(d + "/opencv/images.csv"))}
worst, n = 0.0, 0
by_image = {}
for r in csv.DictReader(open(d + "/opencv/points.csv")):
    by_image.setdefault(r["image"], []).append(r)
for name, rows in by_image.items():
    p = poses[name]
    rvec = np.array([float(p[k]) for k in ("rvec_x", "rvec_y", "rvec_z")])
    tvec = np.array([float(p[k]) for k in ("tvec_x", "tvec_y", "tvec_z")])
    X = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    uv = np.array([[float(r["u"]), float(r["v"])] for r in rows])
    if model == "fisheye":
        proj, _ = cv2.fisheye.projectPoints(X.reshape(-1, 1, 3), rvec, tvec, K, dist)
    else:
        proj, _ = cv2.projectPoints(X, rvec, tvec, K, dist)
    worst = max(worst, float(np.abs(proj.reshape(-1, 2) - uv).max()))
    n += len(rows)
print(model, n, worst)
"#;

fn python() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("POSER_PYTHON") {
        return p.into();
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python")
}

fn load() -> poser::model::Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/calibration_flat.toml");
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

/// Run OpenCV on the written files: (distortion model, observations, worst error in px).
fn opencv_reprojection(model: &poser::model::Model) -> (String, usize, f64) {
    let d = tempfile::tempdir().unwrap();
    poser::truth::write(model, d.path()).unwrap();
    let out = Command::new(python())
        .args(["-c", CHECK])
        .arg(d.path())
        .output()
        .expect("run the pinned Python (backends/setup.sh)");
    assert!(
        out.status.success(),
        "OpenCV check failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = String::from_utf8(out.stdout).unwrap();
    let f: Vec<&str> = s.split_whitespace().collect();
    (
        f[0].to_string(),
        f[1].parse().unwrap(),
        f[2].parse().unwrap(),
    )
}

/// An in-air camera with Brown distortion: OpenCV reproduces every observation to 1e-6 px
/// (a +0.5 error in the convention, or a wrong coefficient order, would show as ≥ 0.5 px).
#[test]
fn opencv_reads_the_calibration_and_reprojects_the_observations() {
    let mut model = load();
    model.water = None;
    for c in &mut model.cameras {
        c.port = poser::model::Port::None;
        c.distortion = poser::model::Distortion {
            k1: -0.08,
            k2: 0.02,
            k3: -0.003,
            p1: 4e-4,
            p2: -2e-4,
        };
    }
    let (m, n, worst) = opencv_reprojection(&model);
    eprintln!("OpenCV {m}: {n} observations, worst {worst:.2e} px");
    assert_eq!(m, "plumb_bob");
    assert!(n > 50, "{n} observations");
    assert!(worst < 1e-6, "cv::projectPoints is {worst} px off");
}

/// An equisolid fisheye through `cv::fisheye` with the fitted coefficients: within 0.01 px.
#[test]
fn opencv_fisheye_reprojects_the_equisolid_observations() {
    let mut model = load();
    model.water = None;
    for c in &mut model.cameras {
        c.port = poser::model::Port::None;
        c.lens = poser::model::LensModel::FisheyeEquisolid;
        c.fx *= 0.15;
        c.fy *= 0.15;
    }
    let (m, n, worst) = opencv_reprojection(&model);
    eprintln!("OpenCV {m}: {n} observations, worst {worst:.2e} px");
    assert_eq!(m, "fisheye");
    assert!(n > 50, "{n} observations");
    assert!(worst < 0.01, "cv::fisheye::projectPoints is {worst} px off");
}
