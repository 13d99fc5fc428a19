//! The truth for OpenCV: calibration files that `cv::FileStorage` reads, and observations in
//! OpenCV's pixel convention.
//!
//! | file | contents |
//! |---|---|
//! | `opencv/camera_<k>.yml` | camera k (1-based, model order): `image_width`, `image_height`, `camera_matrix`, `distortion_coefficients`, `distortion_model` (`plumb_bob` for `cv::calibrateCamera`/`cv::projectPoints`, `fisheye` for `cv::fisheye`), the port for reference |
//! | `opencv/points.csv` | `image,camera,target,id,u,v,u_r,v_r,u_b,v_b,x,y,z`: every visible target point, pixels in OpenCV's convention |
//! | `opencv/images.csv` | `image,camera,rvec_x,rvec_y,rvec_z,tvec_x,tvec_y,tvec_z`: `camera_from_world` as `cv::solvePnP` returns it (Rodrigues vector, translation in metres) |
//!
//! **Pixel convention.** OpenCV puts pixel centres at integer coordinates; poser and COLMAP
//! put them at +0.5. Every pixel and the principal point here are poser's value − 0.5.
//! The camera frame is the same in all three (x right, y down, z forward).
//!
//! A camera behind a port is written with its in-air intrinsics; the port's refraction is not
//! a model OpenCV has, so `cv::projectPoints` with these files reproduces the observations
//! only for cameras without a port (the port's parameters are written for reference).

use super::colmap::fisheye_fit;
use super::{Truth, csv_field, port_params};
use crate::model::LensModel;
use glam::{DMat3, DQuat};
use std::fmt::Write as _;

/// OpenCV's pixel coordinate of a poser (COLMAP-convention) coordinate.
pub fn to_opencv(x: f64) -> f64 {
    x - 0.5
}

/// A YAML double-quoted string that `cv::FileStorage` reads back as the same text.
fn yaml_str(s: &str) -> String {
    let mut out = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A number as OpenCV writes doubles: always with a decimal point or an exponent.
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn matrix(name: &str, rows: usize, cols: usize, data: &[f64]) -> String {
    format!(
        "{name}: !!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {} ]\n",
        data.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
    )
}

/// Rodrigues vector of a rotation matrix (axis × angle, angle in [0, π]).
fn rodrigues(r: [[f64; 3]; 3]) -> [f64; 3] {
    let m = DMat3::from_cols_array_2d(&r).transpose(); // rows → glam's columns
    let q = DQuat::from_mat3(&m).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    let (axis, angle) = q.to_axis_angle();
    if angle == 0.0 || !angle.is_finite() {
        return [0.0; 3];
    }
    (axis * angle).to_array().map(|x| x + 0.0)
}

/// The OpenCV files of the truth (see the module table).
pub(super) fn files(truth: &Truth) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for (i, c) in truth.cameras.iter().enumerate() {
        let mut y = String::from("%YAML:1.0\n---\n");
        let _ = writeln!(y, "name: {}", yaml_str(&c.name));
        let _ = writeln!(
            y,
            "pixel_convention: \"OpenCV: pixel centres at integer coordinates (poser and COLMAP value - 0.5)\""
        );
        let _ = writeln!(y, "image_width: {}", c.width);
        let _ = writeln!(y, "image_height: {}", c.height);
        y.push_str(&matrix(
            "camera_matrix",
            3,
            3,
            &[
                c.fx,
                0.0,
                to_opencv(c.cx),
                0.0,
                c.fy,
                to_opencv(c.cy),
                0.0,
                0.0,
                1.0,
            ],
        ));
        let d = c.distortion;
        match c.lens {
            LensModel::Rectilinear => {
                let _ = writeln!(y, "distortion_model: \"plumb_bob\"");
                y.push_str(&matrix(
                    "distortion_coefficients",
                    1,
                    5,
                    &[d.k1, d.k2, d.p1, d.p2, d.k3],
                ));
            }
            LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
                let (k, err) = fisheye_fit(c);
                let _ = writeln!(y, "distortion_model: \"fisheye\"");
                y.push_str(&matrix("distortion_coefficients", 1, 4, &k));
                let _ = writeln!(y, "fisheye_fit_max_error_px: {}", num(err));
                if !d.is_zero() {
                    let _ = writeln!(
                        y,
                        "note: \"Brown distortion on a fisheye has no cv::fisheye model; it is left out here\""
                    );
                }
            }
        }
        let _ = writeln!(y, "port: {}", yaml_str(c.port.kind_name()));
        let pp = port_params(&c.port);
        if !pp.is_empty() {
            y.push_str(&matrix("port_parameters", 1, pp.len(), &pp));
            let _ = writeln!(
                y,
                "port_parameters_order: {}",
                yaml_str(match c.port {
                    crate::model::Port::Flat { .. } =>
                        "normal x y z, inner distance, thickness (m)",
                    crate::model::Port::Dome { .. } => "centre x y z, inner radius, thickness (m)",
                    _ => "axis point x y z, axis x y z, inner radius, thickness (m)",
                })
            );
            y.push_str(&matrix(
                "port_ior_glass_rgb",
                1,
                3,
                &c.ior_glass.unwrap_or([1.0; 3]),
            ));
            y.push_str(&matrix("port_ior_water_rgb", 1, 3, &c.ior_water));
            if let crate::model::Port::Flat { outer_layers, .. } = &c.port
                && !outer_layers.is_empty()
            {
                // Rows: thickness (m), then the glass index in R, G, B; outward of the first
                // layer, whose thickness and index are above.
                let rows: Vec<f64> = outer_layers
                    .iter()
                    .flat_map(|l| [l.thickness, l.glass.ior[0], l.glass.ior[1], l.glass.ior[2]])
                    .collect();
                y.push_str(&matrix("port_outer_layers", outer_layers.len(), 4, &rows));
                y.push_str("port_outer_layers_order: \"thickness (m), ior r g b; from the first layer outwards\"\n");
            }
        }
        out.push((format!("opencv/camera_{}.yml", i + 1), y.into_bytes()));
    }

    let opt =
        |x: Option<[f64; 2]>, k: usize| x.map(|p| to_opencv(p[k]).to_string()).unwrap_or_default();
    let mut pts = String::from("image,camera,target,id,u,v,u_r,v_r,u_b,v_b,x,y,z\n");
    let mut ims = String::from("image,camera,rvec_x,rvec_y,rvec_z,tvec_x,tvec_y,tvec_z\n");
    for im in &truth.images {
        for o in &im.points {
            let _ = writeln!(
                pts,
                "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&im.name),
                im.camera_index + 1,
                csv_field(&o.target),
                csv_field(&o.id),
                to_opencv(o.u),
                to_opencv(o.v),
                opt(o.uv_rgb[0], 0),
                opt(o.uv_rgb[0], 1),
                opt(o.uv_rgb[2], 0),
                opt(o.uv_rgb[2], 1),
                o.world.x,
                o.world.y,
                o.world.z
            );
        }
        let p = &im.camera_from_world;
        let r = rodrigues(p.rotation);
        let _ = writeln!(
            ims,
            "{},{},{},{},{},{},{},{}",
            csv_field(&im.name),
            im.camera_index + 1,
            r[0],
            r[1],
            r[2],
            p.translation[0],
            p.translation[1],
            p.translation[2]
        );
    }
    out.push(("opencv/points.csv".into(), pts.into_bytes()));
    out.push(("opencv/images.csv".into(), ims.into_bytes()));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rodrigues_matches_axis_angle() {
        let q = DQuat::from_axis_angle(glam::DVec3::new(1.0, -2.0, 0.5).normalize(), 2.5);
        let m = DMat3::from_quat(q);
        let rows = [0, 1, 2].map(|i| [m.x_axis[i], m.y_axis[i], m.z_axis[i]]);
        let r = rodrigues(rows);
        let back = DMat3::from_axis_angle(
            glam::DVec3::from_array(r).normalize(),
            glam::DVec3::from_array(r).length(),
        );
        assert!((back - m).to_cols_array().iter().all(|x| x.abs() < 1e-12));
        assert_eq!(
            rodrigues([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
            [0.0; 3]
        );
    }

    #[test]
    fn yaml_strings_cannot_break_out() {
        assert_eq!(yaml_str("a\"b\\c\nd"), "\"a\\\"b\\\\c d\"");
    }
}
