//! Camera rays of one camera at one rig pose for one colour channel: pixel → (origin, unit
//! direction, weight) in the medium the camera looks into, world frame.
//!
//! The weight is the port's Fresnel transmittance times the n² radiance law (render-conventions
//! §3.4): a camera in air behind a port sees water radiance scaled by `(n_air/n_water)²`; a
//! camera without a port sits in the medium and sees it unscaled.

use crate::model::{LensModel, Model, Port, Pose};
use glam::DVec3;

/// Pixel → ray for one camera, pose and channel.
#[derive(Debug, Clone)]
pub struct CameraRays {
    world_from_camera: Pose,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    lens: LensModel,
    /// (n_inside / n_water)² when the camera is behind a port, else 1.
    n2_factor: f64,
}

impl CameraRays {
    pub fn new(model: &Model, pose: usize, cam: usize, channel: usize) -> Result<CameraRays, String> {
        let c = &model.cameras[cam];
        let n_w = model.ambient_ior()[channel];
        let n2_factor = match c.port {
            Port::None => 1.0,
            _ => (1.0 / n_w).powi(2),
        };
        Ok(CameraRays {
            world_from_camera: model.world_from_camera(pose, cam),
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            lens: c.lens,
            n2_factor,
        })
    }

    /// `world_from_camera` of this image.
    pub fn pose(&self) -> &Pose {
        &self.world_from_camera
    }

    /// Ray through pixel position (u, v): (origin, unit direction, weight); `None` when no
    /// ray leaves the camera there (beyond a fisheye's field, total internal reflection, …).
    pub fn ray(&self, u: f64, v: f64) -> Option<(DVec3, DVec3, f64)> {
        let x = (u - self.cx) / self.fx;
        let y = (v - self.cy) / self.fy;
        let d = match self.lens {
            LensModel::Rectilinear => DVec3::new(x, y, 1.0),
            LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
                let r = (x * x + y * y).sqrt();
                let th = match self.lens {
                    LensModel::FisheyeEquidistant => r,
                    _ => {
                        if r / 2.0 > 1.0 {
                            return None;
                        }
                        2.0 * (r / 2.0).asin()
                    }
                };
                if th >= std::f64::consts::PI {
                    return None;
                }
                if r == 0.0 {
                    DVec3::Z
                } else {
                    DVec3::new(th.sin() * x / r, th.sin() * y / r, th.cos())
                }
            }
        };
        let d = self.world_from_camera.transform_vector(d.normalize());
        Some((self.world_from_camera.translation, d, self.n2_factor))
    }
}
