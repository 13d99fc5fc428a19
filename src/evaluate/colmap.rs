//! The bridge to COLMAP: a JSON request for `backends/colmap/evaluate.py` (pycolmap, pinned in
//! `backends/requirements.txt`), run in the pinned Python environment, and its JSON result.
//!
//! | item | meaning |
//! |---|---|
//! | [`CameraModel`] | the camera model COLMAP self-calibrates (the port is ignored, as practitioners do) |
//! | [`Request`] | cameras (initial intrinsics), images (initial `cam_from_world`), points, observations, control points weighted in the adjustment ([`RequestGcp`]) |
//! | [`Reconstruction`] | what COLMAP returns: refined cameras, registered images, points |
//! | [`run`] | write the request, run the script, read the result |
//!
//! Pixel coordinates in both files are COLMAP's: pixel centres at +0.5 (poser's convention).
//! Quaternions are (w, x, y, z) of `cam_from_world`, as in COLMAP's text format.

use crate::backend::python;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A COLMAP camera model, self-calibrated by the bundle adjustment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum CameraModel {
    /// fx, fy, cx, cy.
    Pinhole,
    /// f, cx, cy, k (one radial term).
    SimpleRadial,
    /// f, cx, cy, k1, k2.
    Radial,
    /// fx, fy, cx, cy, k1, k2, p1, p2 (Brown–Conrady as OpenCV).
    Opencv,
    /// fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6.
    FullOpencv,
}

impl CameraModel {
    pub fn name(self) -> &'static str {
        match self {
            CameraModel::Pinhole => "pinhole",
            CameraModel::SimpleRadial => "simple_radial",
            CameraModel::Radial => "radial",
            CameraModel::Opencv => "opencv",
            CameraModel::FullOpencv => "full_opencv",
        }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct RequestCamera {
    pub id: u32,
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct RequestImage {
    pub id: u32,
    pub name: String,
    pub camera: u32,
    /// The rig pose (frame) the image belongs to, with a calibrated rig.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub qvec: Option<[f64; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tvec: Option<[f64; 3]>,
    /// `[u, v, point id]`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub observations: Vec<[f64; 3]>,
}

#[derive(Debug, Clone, Serialize)]
pub struct RequestPoint {
    pub id: u64,
    pub xyz: [f64; 3],
}

/// A control point weighted in the bundle adjustment: the request point `id` is known to lie
/// at `xyz` (m) with accuracy `sigma` (m, per axis).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RequestGcp {
    pub id: u64,
    pub xyz: [f64; 3],
    pub sigma: f64,
}

/// A job for `backends/colmap/evaluate.py`.
#[derive(Debug, Clone, Serialize)]
pub struct Request {
    /// `"bundle"` or `"images"`.
    pub job: &'static str,
    pub model: CameraModel,
    pub refine_principal_point: bool,
    pub seed: u64,
    pub cameras: Vec<RequestCamera>,
    pub images: Vec<RequestImage>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<RequestPoint>,
    /// Control points weighted in the adjustment (`bundle`, `--gcp-sigma`); their views hold
    /// the datum, so no camera is held.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gcps: Vec<RequestGcp>,
    /// With `gcps`: the σ of an image measurement, px, against which a control point's σ
    /// weighs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tie_sigma_px: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image_dir: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub work_dir: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matcher: Option<&'static str>,
    pub threads: usize,
    /// A calibrated rig (observations mode, `--rig`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rig: Option<RequestRig>,
    /// Images mode, `--stock`: run COLMAP with its defaults (the camera from the images'
    /// EXIF), except this initial-pair triangulation angle, degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stock: Option<f64>,
}

/// A rig calibrated beforehand: each camera's pose in the rig (camera 1 is the reference,
/// identity) and the initial pose of every rig position.
#[derive(Debug, Clone, Serialize)]
pub struct RequestRig {
    pub sensor_from_rig: Vec<RequestSensor>,
    pub frames: Vec<RequestFrame>,
}

/// `sensor_from_rig`, COLMAP's (w, x, y, z) quaternion and translation.
#[derive(Debug, Clone, Serialize)]
pub struct RequestSensor {
    pub qvec: [f64; 4],
    pub tvec: [f64; 3],
}

/// One rig position: `rig_from_world`.
#[derive(Debug, Clone, Serialize)]
pub struct RequestFrame {
    pub id: u32,
    pub qvec: [f64; 4],
    pub tvec: [f64; 3],
}

#[derive(Debug, Clone, Deserialize, Serialize)]
pub struct ResultCamera {
    pub id: u32,
    pub model: String,
    pub params: Vec<f64>,
    pub width: u32,
    pub height: u32,
}

impl ResultCamera {
    /// (fx, fy, cx, cy) and the named extra parameters of a COLMAP camera.
    pub fn intrinsics(&self) -> ([f64; 4], Vec<(&'static str, f64)>) {
        let p = &self.params;
        let get = |i: usize| p.get(i).copied().unwrap_or(f64::NAN);
        let one_f = |names: &'static [&'static str]| ([get(0), get(0), get(1), get(2)], names, 3);
        let two_f = |names: &'static [&'static str]| ([get(0), get(1), get(2), get(3)], names, 4);
        let (base, names, skip): ([f64; 4], &[&'static str], usize) = match self.model.as_str() {
            "SIMPLE_PINHOLE" => one_f(&[]),
            "SIMPLE_RADIAL" => one_f(&["k"]),
            "RADIAL" => one_f(&["k1", "k2"]),
            "PINHOLE" => two_f(&[]),
            "OPENCV" => two_f(&["k1", "k2", "p1", "p2"]),
            "FULL_OPENCV" => two_f(&["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"]),
            _ => ([f64::NAN; 4], &[], 0),
        };
        let extra = names
            .iter()
            .enumerate()
            .map(|(i, n)| (*n, get(skip + i)))
            .collect();
        (base, extra)
    }
}

#[derive(Debug, Clone, Deserialize, Serialize)]
pub struct ResultImage {
    pub id: u32,
    pub name: String,
    pub qvec: [f64; 4],
    pub tvec: [f64; 3],
}

#[derive(Debug, Clone, Deserialize, Serialize)]
pub struct ResultPoint {
    pub id: u64,
    pub xyz: [f64; 3],
    pub error: f64,
    pub track: u32,
}

/// COLMAP's reconstruction as returned by the script.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub struct Reconstruction {
    pub cameras: Vec<ResultCamera>,
    pub images: Vec<ResultImage>,
    pub points: Vec<ResultPoint>,
    pub summary: serde_json::Value,
}

/// The camera centre (world) of a `cam_from_world` pose given as COLMAP's (qvec, tvec).
pub fn centre(qvec: [f64; 4], tvec: [f64; 3]) -> glam::DVec3 {
    let q = glam::DQuat::from_xyzw(qvec[1], qvec[2], qvec[3], qvec[0]).normalize();
    -(q.inverse() * glam::DVec3::from_array(tvec))
}

/// The script `poser evaluate` runs (`backends/colmap/evaluate.py`), embedded in the binary.
pub const SCRIPT_SOURCE: &str = include_str!("../../backends/colmap/evaluate.py");

/// Run one request in the pinned Python environment; `work` is a scratch directory.
pub fn run(req: &Request, work: &Path) -> Result<Reconstruction, String> {
    python::require_module("pycolmap")?;
    let result = python::run_json(work, "evaluate.py", SCRIPT_SOURCE, req, "COLMAP");
    if result.is_ok()
        && let Some(keep) = std::env::var_os("POSER_EVALUATE_KEEP")
    {
        // Debugging aid: keep a copy of the request and the result.
        let keep = std::path::PathBuf::from(keep);
        let (req_path, res_path) = python::json_paths(work, "evaluate.py");
        let _ = std::fs::create_dir_all(&keep);
        let _ = std::fs::copy(&req_path, keep.join("request.json"));
        let _ = std::fs::copy(&res_path, keep.join("result.json"));
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intrinsics_are_read_per_model() {
        let c = |model: &str, params: Vec<f64>| ResultCamera {
            id: 1,
            model: model.into(),
            params,
            width: 10,
            height: 10,
        };
        let (b, e) = c("SIMPLE_RADIAL", vec![800.0, 300.0, 200.0, 0.01]).intrinsics();
        assert_eq!(b, [800.0, 800.0, 300.0, 200.0]);
        assert_eq!(e, vec![("k", 0.01)]);
        let (b, e) = c(
            "OPENCV",
            vec![800.0, 810.0, 300.0, 200.0, 0.1, 0.2, 0.3, 0.4],
        )
        .intrinsics();
        assert_eq!(b, [800.0, 810.0, 300.0, 200.0]);
        assert_eq!(e[3], ("p2", 0.4));
        let (b, _) = c("PINHOLE", vec![800.0, 800.0, 300.0, 200.0]).intrinsics();
        assert_eq!(b, [800.0, 800.0, 300.0, 200.0]);
    }

    #[test]
    fn centre_inverts_cam_from_world() {
        // Camera at (1, 2, 3) looking down: R = diag(1, −1, −1), t = −R·C.
        let q = glam::DQuat::from_mat3(&glam::DMat3::from_diagonal(glam::DVec3::new(
            1.0, -1.0, -1.0,
        )));
        let c = glam::DVec3::new(1.0, 2.0, 3.0);
        let t = -(q * c);
        let back = centre([q.w, q.x, q.y, q.z], t.to_array());
        assert!((back - c).length() < 1e-12);
    }
}
