//! The truth as COLMAP models: `colmap/` for upstream COLMAP and pycolmap (text and binary),
//! and `colmap_refractive/` for Refractive COLMAP, which also reads the housing port (text and
//! binary).
//!
//! | file | contents |
//! |---|---|
//! | `colmap/cameras.txt` | one camera per line: PINHOLE, OPENCV, FULL_OPENCV or OPENCV_FISHEYE; the port in a comment (upstream COLMAP has no port) |
//! | `colmap/images.txt` | true `camera_from_world` poses and the refracted target observations |
//! | `colmap/points3D.txt` | every observed target point with its track |
//! | `colmap/cameras.bin`, `images.bin`, `points3D.bin` | the same model in COLMAP's binary format ([`Bin`]), which COLMAP reads in preference to the text when both are present |
//! | `colmap_refractive/*.txt` | the same, with `FLATPORT …` / `DOMEPORT …` after each camera's parameters |
//! | `colmap_refractive/*.bin` | the same in the fork's binary format: its `cameras.bin` adds each camera's port ([`refractive_cameras_bin`]); `images.bin` and `points3D.bin` are upstream's |
//!
//! Pixel convention: COLMAP's, the same as poser's — the top-left pixel's centre is at
//! (0.5, 0.5). The observations are refracted, so the upstream model, which has no port,
//! reprojects them with errors of up to hundreds of pixels behind a flat port; the refractive
//! model reprojects them exactly.
//!
//! Refractive COLMAP (She, Seegräber, Nakath & Köser, *Refractive COLMAP: Refractive
//! Structure-from-Motion Revisited*, IROS 2024; the `colmap_underwater` fork) writes and reads
//! a refractive camera as `ID MODEL W H PARAMS… FLATPORT Nx Ny Nz int_dist int_thick na ng nw`
//! (or `DOMEPORT Cx Cy Cz int_radius int_thick na ng nw`), single spaces, in the camera frame,
//! metres: the same geometry as poser's flat and dome ports (`docs/projection.md`). Its
//! `Reconstruction::ReadCamerasText` reads exactly the camera model's number of parameters,
//! then takes the next word as the refraction model's name and every remaining word as its
//! parameters (eight for both ports), so nothing may stand between the two. Cylinder ports have
//! no Refractive COLMAP model; such a camera is written without a port and with a comment
//! saying so. The indices are the G channel's (550 nm).

use super::{CameraTruth, Truth, lens_name, port_params};
use crate::model::{LensModel, Model, Port};
use glam::DVec3;
use std::fmt::Write as _;

/// The COLMAP camera model and parameters of one camera: PINHOLE (no distortion), OPENCV
/// (k3 = 0), FULL_OPENCV, or OPENCV_FISHEYE for the fisheyes. The equidistant fisheye without
/// distortion is exact; the equisolid one gets fitted coefficients ([`fisheye_fit`]). The
/// third item is a note for a comment where the model is approximate.
pub fn camera_model(c: &CameraTruth) -> (&'static str, Vec<f64>, Option<String>) {
    let d = c.distortion;
    match c.lens {
        LensModel::Rectilinear if d.is_zero() => ("PINHOLE", vec![c.fx, c.fy, c.cx, c.cy], None),
        LensModel::Rectilinear if d.k3 == 0.0 => (
            "OPENCV",
            vec![c.fx, c.fy, c.cx, c.cy, d.k1, d.k2, d.p1, d.p2],
            None,
        ),
        LensModel::Rectilinear => (
            "FULL_OPENCV",
            vec![
                c.fx, c.fy, c.cx, c.cy, d.k1, d.k2, d.p1, d.p2, d.k3, 0.0, 0.0, 0.0,
            ],
            None,
        ),
        LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
            let (k, err) = fisheye_fit(c);
            let mut note = None;
            if c.lens == LensModel::FisheyeEquisolid {
                note = Some(format!(
                    "equisolid fisheye as OPENCV_FISHEYE with fitted k1..k4: at most {err:.2e} px off over the sensor"
                ));
            }
            if !d.is_zero() {
                note = Some(format!(
                    "{} lens with Brown distortion has no exact COLMAP model; OPENCV_FISHEYE below ignores the Brown terms",
                    lens_name(c.lens)
                ));
            }
            (
                "OPENCV_FISHEYE",
                vec![c.fx, c.fy, c.cx, c.cy, k[0], k[1], k[2], k[3]],
                note,
            )
        }
    }
}

/// Largest field angle (rad) seen by a fisheye camera: at the sensor corner farthest from the
/// principal point.
fn fisheye_theta_max(c: &CameraTruth) -> f64 {
    let (w, h) = (c.width as f64, c.height as f64);
    let r = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
        .iter()
        .map(|&(u, v)| ((u - c.cx) / c.fx).hypot((v - c.cy) / c.fy))
        .fold(0.0, f64::max);
    match c.lens {
        LensModel::FisheyeEquisolid => 2.0 * (0.5 * r).min(1.0).asin(),
        _ => r,
    }
    .min(std::f64::consts::PI)
}

/// The image radius (focal units) of a field angle θ for the camera's fisheye.
fn fisheye_radius(lens: LensModel, theta: f64) -> f64 {
    match lens {
        LensModel::FisheyeEquisolid => 2.0 * (0.5 * theta).sin(),
        _ => theta,
    }
}

/// OPENCV_FISHEYE (= OpenCV's `cv::fisheye`) coefficients k1..k4 for the camera's fisheye, by
/// least squares of θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸) against the lens's radius over
/// the field angles the sensor sees, and the largest error in pixels. The equidistant
/// fisheye is θ_d = θ: all zero, exact.
pub fn fisheye_fit(c: &CameraTruth) -> ([f64; 4], f64) {
    if c.lens != LensModel::FisheyeEquisolid {
        return ([0.0; 4], 0.0);
    }
    let tmax = fisheye_theta_max(c);
    const N: usize = 400;
    let thetas: Vec<f64> = (1..=N).map(|i| tmax * i as f64 / N as f64).collect();
    let a = nalgebra::DMatrix::from_fn(N, 4, |i, j| thetas[i].powi(2 * j as i32 + 3));
    let b = nalgebra::DVector::from_fn(N, |i, _| fisheye_radius(c.lens, thetas[i]) - thetas[i]);
    let k = match a.svd(true, true).solve(&b, 1e-15) {
        Ok(k) => [k[0], k[1], k[2], k[3]],
        Err(_) => [0.0; 4],
    };
    let f = c.fx.max(c.fy);
    let err = thetas
        .iter()
        .map(|&t| {
            let t2 = t * t;
            let td = t * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
            (td - fisheye_radius(c.lens, t)).abs() * f
        })
        .fold(0.0, f64::max);
    (k, err)
}

/// Refractive COLMAP's port model and parameters (G channel), or `None` with the reason.
pub fn refractive_port(c: &CameraTruth) -> Result<Option<(&'static str, Vec<f64>)>, String> {
    let g = c.ior_glass.unwrap_or([1.0; 3]);
    let name = match &c.port {
        Port::None => return Ok(None),
        Port::Flat { outer_layers, .. } if !outer_layers.is_empty() => {
            return Err(format!(
                "Refractive COLMAP's FLATPORT has one glass layer; this port has {}",
                1 + outer_layers.len()
            ));
        }
        Port::Flat { .. } => "FLATPORT",
        Port::Dome { .. } => "DOMEPORT",
        Port::Cylinder { .. } => {
            return Err("cylinder ports have no Refractive COLMAP model".into());
        }
    };
    let mut pp = port_params(&c.port);
    pp.extend([c.ior_air[1], g[1], c.ior_water[1]]);
    Ok(Some((name, pp)))
}

/// COLMAP's binary model format (`Reconstruction::WriteBinary`; little-endian, no padding):
///
/// | file | layout |
/// |---|---|
/// | `cameras.bin` | u64 count; per camera: u32 id, i32 model id, u64 width, u64 height, f64 params… |
/// | `images.bin` | u64 count; per image: u32 id, f64 qw qx qy qz, f64 tx ty tz, u32 camera id, name bytes and a NUL, u64 count, per observation f64 x, f64 y, u64 point id |
/// | `points3D.bin` | u64 count; per point: u64 id, f64 x y z, u8 r g b, f64 error, u64 track length, per element u32 image id, u32 observation index |
///
/// The same f64 values as the text model, which writes each with the digits that read back to
/// it exactly, so both read to the same model.
#[derive(Default)]
struct Bin(Vec<u8>);

impl Bin {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: usize) {
        self.0
            .extend_from_slice(&u32::try_from(v).unwrap_or(u32::MAX).to_le_bytes());
    }
    fn i32(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: usize) {
        self.0.extend_from_slice(&(v as u64).to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
}

/// COLMAP's id of a camera model this export writes (`colmap/sensor/models.h`).
fn model_id(name: &str) -> i32 {
    match name {
        "PINHOLE" => 1,
        "OPENCV" => 4,
        "OPENCV_FISHEYE" => 5,
        "FULL_OPENCV" => 6,
        other => unreachable!("camera_model returned {other}"),
    }
}

fn cameras_bin(truth: &Truth) -> Vec<u8> {
    let mut b = Bin::default();
    b.u64(truth.cameras.len());
    for (i, c) in truth.cameras.iter().enumerate() {
        camera_record(&mut b, i, c);
    }
    b.0
}

/// Upstream COLMAP's binary camera record: id, model id, width, height, parameters.
fn camera_record(b: &mut Bin, i: usize, c: &CameraTruth) {
    let (name, params, _) = camera_model(c);
    b.u32(i + 1);
    b.i32(model_id(name));
    b.u64(c.width as usize);
    b.u64(c.height as usize);
    for p in params {
        b.f64(p);
    }
}

/// The Refractive COLMAP fork's `cameras.bin` (`Reconstruction::WriteCamerasBinary` /
/// `ReadCamerasBinary` in its src/colmap/scene/reconstruction.cc): upstream's camera record,
/// then an i32 refraction model id (`CameraRefracModelId`: −1 none, 0 `FLATPORT`, 1 `DOMEPORT`)
/// and, unless −1, its eight f64 parameters in the text model's order. Upstream COLMAP cannot
/// read this file (the extra i32), so it is written only in `colmap_refractive/`. A camera whose
/// port has no Refractive COLMAP model is written with −1, as the text writes it without a port.
pub fn refractive_cameras_bin(truth: &Truth) -> Vec<u8> {
    let mut b = Bin::default();
    b.u64(truth.cameras.len());
    for (i, c) in truth.cameras.iter().enumerate() {
        camera_record(&mut b, i, c);
        match refractive_port(c) {
            Ok(Some((model, pp))) => {
                b.i32(if model == "FLATPORT" { 0 } else { 1 });
                for p in pp {
                    b.f64(p);
                }
            }
            Ok(None) | Err(_) => b.i32(-1),
        }
    }
    b.0
}

fn join(xs: &[f64]) -> String {
    xs.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

fn cameras_txt(truth: &Truth, refractive: bool) -> String {
    let mut cams = String::from(
        "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
    );
    // The fork's own header line (`Reconstruction::WriteCamerasText`).
    cams.push_str(if refractive {
        " OPTIONAL[REFRAC_MODEL REFRAC_PARAMS[]]\n"
    } else {
        "\n"
    });
    cams.push_str(
        "# Pixel convention: COLMAP's (top-left pixel centre at 0.5, 0.5), the same as poser's.\n",
    );
    if refractive {
        cams.push_str("# Refractive COLMAP format; the port in the camera frame, metres, G-channel indices.\n");
    } else {
        cams.push_str("# Upstream COLMAP has no port: the observations are refracted, so this model reprojects\n# them with large errors behind a flat port. colmap_refractive/ has the port.\n");
    }
    let _ = writeln!(cams, "# Number of cameras: {}", truth.cameras.len());
    for (i, c) in truth.cameras.iter().enumerate() {
        let (name, params, note) = camera_model(c);
        if let Some(n) = note {
            let _ = writeln!(cams, "# camera {}: {n}", i + 1);
        }
        let mut line = format!(
            "{} {} {} {} {}",
            i + 1,
            name,
            c.width,
            c.height,
            join(&params)
        );
        match refractive_port(c) {
            Ok(Some((model, pp))) if refractive => {
                let _ = write!(line, " {model} {}", join(&pp));
            }
            Ok(Some((model, pp))) => {
                let _ = writeln!(
                    cams,
                    "# camera {} `{}` port {} (Refractive COLMAP {model}): {}",
                    i + 1,
                    c.name.replace(['\n', '\r'], " "),
                    c.port.kind_name(),
                    join(&pp)
                );
            }
            Ok(None) => {}
            Err(why) => {
                let _ = writeln!(
                    cams,
                    "# camera {} `{}`: {why}; its port is in truth.json",
                    i + 1,
                    c.name.replace(['\n', '\r'], " ")
                );
            }
        }
        let _ = writeln!(cams, "{line}");
    }
    cams
}

/// The COLMAP text models (`colmap/` and `colmap_refractive/`) of the true poses and the
/// visible target points.
pub(super) fn files(model: &Model, truth: &Truth) -> Vec<(String, Vec<u8>)> {
    // Point ids: every observed target point, in model order.
    let mut ids: std::collections::HashMap<(&str, &str), usize> = std::collections::HashMap::new();
    let mut point_list: Vec<(String, String, DVec3)> = Vec::new();
    for t in &model.targets {
        for p in &t.points {
            let seen = truth
                .images
                .iter()
                .any(|im| im.points.iter().any(|o| o.target == t.name && o.id == p.id));
            if seen && !ids.contains_key(&(t.name.as_str(), p.id.as_str())) {
                ids.insert((t.name.as_str(), p.id.as_str()), point_list.len() + 1);
                point_list.push((t.name.clone(), p.id.clone(), p.world));
            }
        }
    }
    let mut tracks: Vec<Vec<(usize, usize)>> = vec![Vec::new(); point_list.len()];

    let mut ims_bin = Bin::default();
    ims_bin.u64(truth.images.len());
    let mut ims = String::from(
        "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    let _ = writeln!(ims, "# Number of images: {}", truth.images.len());
    for (k, im) in truth.images.iter().enumerate() {
        let p = &im.camera_from_world;
        let _ = writeln!(
            ims,
            "{} {} {} {} {} {} {} {} {} {}.png",
            k + 1,
            p.quaternion[0],
            p.quaternion[1],
            p.quaternion[2],
            p.quaternion[3],
            p.translation[0],
            p.translation[1],
            p.translation[2],
            im.camera_index + 1,
            im.name
        );
        ims_bin.u32(k + 1);
        for x in p.quaternion.iter().chain(&p.translation) {
            ims_bin.f64(*x);
        }
        ims_bin.u32(im.camera_index + 1);
        ims_bin
            .0
            .extend_from_slice(format!("{}.png", im.name).as_bytes());
        ims_bin.u8(0);
        ims_bin.u64(im.points.len());
        let mut line = Vec::new();
        for (j, o) in im.points.iter().enumerate() {
            let pid = ids[&(o.target.as_str(), o.id.as_str())];
            tracks[pid - 1].push((k + 1, j));
            line.push(format!("{} {} {}", o.u, o.v, pid));
            ims_bin.f64(o.u);
            ims_bin.f64(o.v);
            ims_bin.u64(pid);
        }
        let _ = writeln!(ims, "{}", line.join(" "));
    }

    let mut p3 = String::from(
        "# 3D point list with one line of data per point:\n#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n",
    );
    let _ = writeln!(p3, "# Number of points: {}", point_list.len());
    for (i, (t, id, w)) in point_list.iter().enumerate() {
        let _ = writeln!(
            p3,
            "# {} = {}/{}",
            i + 1,
            t.replace(['\n', '\r'], " "),
            id.replace(['\n', '\r'], " ")
        );
        let tr: Vec<String> = tracks[i]
            .iter()
            .map(|(im, j)| format!("{im} {j}"))
            .collect();
        let _ = writeln!(
            p3,
            "{} {} {} {} 255 255 255 0 {}",
            i + 1,
            w.x,
            w.y,
            w.z,
            tr.join(" ")
        );
    }
    let mut p3_bin = Bin::default();
    p3_bin.u64(point_list.len());
    for (i, (_, _, w)) in point_list.iter().enumerate() {
        p3_bin.u64(i + 1);
        for x in [w.x, w.y, w.z] {
            p3_bin.f64(x);
        }
        for _ in 0..3 {
            p3_bin.u8(255);
        }
        p3_bin.f64(0.0);
        p3_bin.u64(tracks[i].len());
        for &(im, j) in &tracks[i] {
            p3_bin.u32(im);
            p3_bin.u32(j);
        }
    }
    let (ims, p3) = (ims.into_bytes(), p3.into_bytes());
    vec![
        (
            "colmap/cameras.txt".into(),
            cameras_txt(truth, false).into_bytes(),
        ),
        ("colmap/images.txt".into(), ims.clone()),
        ("colmap/points3D.txt".into(), p3.clone()),
        ("colmap/cameras.bin".into(), cameras_bin(truth)),
        ("colmap/images.bin".into(), ims_bin.0.clone()),
        ("colmap/points3D.bin".into(), p3_bin.0.clone()),
        (
            "colmap_refractive/cameras.txt".into(),
            cameras_txt(truth, true).into_bytes(),
        ),
        ("colmap_refractive/images.txt".into(), ims),
        ("colmap_refractive/points3D.txt".into(), p3),
        (
            "colmap_refractive/cameras.bin".into(),
            refractive_cameras_bin(truth),
        ),
        ("colmap_refractive/images.bin".into(), ims_bin.0),
        ("colmap_refractive/points3D.bin".into(), p3_bin.0),
    ]
}
