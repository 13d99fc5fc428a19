//! The COLMAP binary model as the real pycolmap reads it (full tier).

use crate::support::scenario as load;

/// Full tier: `colmap/` also holds the binary model (cameras.bin, images.bin, points3D.bin),
/// and the real pycolmap reads it to the same model as the text: every camera (model, size,
/// parameters), image (name, camera, pose, observations and their point ids) and point
/// (position, colour, error, track), compared exactly, for each camera model the export writes
/// (PINHOLE, OPENCV, FULL_OPENCV, OPENCV_FISHEYE). The files are also byte for byte what
/// pycolmap writes for the text model, and the folder as written (both forms) reads too.
#[test]
fn colmap_binary_model_reads_in_pycolmap_as_the_text_model() {
    const SCRIPT: &str = r#"
import json, os, shutil, sys, tempfile
import pycolmap

def cams(r):
    return {i: (c.model.name, c.width, c.height, list(c.params)) for i, c in r.cameras.items()}

def imgs(r):
    out = {}
    for i, im in r.images.items():
        p = im.cam_from_world()
        out[i] = (im.name, im.camera_id, list(p.rotation.quat), list(p.translation),
                  [(list(q.xy), q.point3D_id) for q in im.points2D])
    return out

def pts(r):
    return {i: (list(p.xyz), list(p.color), p.error,
                [(e.image_id, e.point2D_idx) for e in p.track.elements])
            for i, p in r.points3D.items()}

report = []
for d in sys.argv[1:]:
    src = os.path.join(d, "colmap")
    text, binary, again = (tempfile.mkdtemp() for _ in range(3))
    for f in ("cameras", "images", "points3D"):
        shutil.copy(os.path.join(src, f + ".txt"), text)
        shutil.copy(os.path.join(src, f + ".bin"), binary)
    rt, rb = pycolmap.Reconstruction(text), pycolmap.Reconstruction(binary)
    both = pycolmap.Reconstruction(src)
    rt.write_binary(again)
    same_bytes = {f: open(os.path.join(again, f), "rb").read() == open(os.path.join(src, f), "rb").read()
                  for f in ("cameras.bin", "images.bin", "points3D.bin")}
    report.append({
        "dir": d,
        "models": sorted({c[0] for c in cams(rb).values()}),
        "cameras": len(rb.cameras), "images": len(rb.images), "points": len(rb.points3D),
        "observations": sum(len(i.points2D) for i in rb.images.values()),
        "same_cameras": cams(rt) == cams(rb) == cams(both),
        "same_images": imgs(rt) == imgs(rb) == imgs(both),
        "same_points": pts(rt) == pts(rb) == pts(both),
        "same_bytes": same_bytes,
    })
print(json.dumps(report))
"#;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let py = std::env::var_os("POSER_PYTHON")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    let d = tempfile::tempdir().unwrap();
    let mut dirs = Vec::new();
    for (k, variant) in ["pinhole", "opencv", "full_opencv", "fisheye"]
        .iter()
        .enumerate()
    {
        let mut model = load("calibration_flat.toml");
        for c in &mut model.cameras {
            match *variant {
                "opencv" => {
                    c.distortion.k1 = -0.08;
                    c.distortion.p2 = 1e-3;
                }
                "full_opencv" => {
                    c.distortion.k1 = 0.05;
                    c.distortion.k3 = -0.01;
                }
                "fisheye" => {
                    model.water = None;
                    c.port = poser::model::Port::None;
                    c.lens = poser::model::LensModel::FisheyeEquisolid;
                    c.fx *= 0.15;
                    c.fy *= 0.15;
                }
                _ => {}
            }
        }
        let dir = d.path().join(k.to_string());
        poser::truth::write(&model, &dir).unwrap();
        dirs.push(dir);
    }
    let o = std::process::Command::new(&py)
        .arg("-c")
        .arg(SCRIPT)
        .args(&dirs)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut models = Vec::new();
    for r in report.as_array().unwrap() {
        assert!(r["images"].as_u64().unwrap() >= 5, "{r}");
        assert!(r["points"].as_u64().unwrap() >= 10, "{r}");
        assert!(r["observations"].as_u64().unwrap() >= 50, "{r}");
        for k in ["same_cameras", "same_images", "same_points"] {
            assert_eq!(r[k], true, "{k}: {r}");
        }
        for (f, same) in r["same_bytes"].as_object().unwrap() {
            assert_eq!(same, true, "{f} is not what pycolmap writes: {r}");
        }
        models.push(r["models"][0].as_str().unwrap().to_string());
    }
    assert_eq!(
        models,
        ["PINHOLE", "OPENCV", "FULL_OPENCV", "OPENCV_FISHEYE"]
    );
}
