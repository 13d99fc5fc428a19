//! Camera rays of one camera at one rig pose for one colour channel: pixel → (origin, unit
//! direction, weight) in the medium the camera looks into, world frame.
//!
//! Rays come from the optics core ([`crate::optics::project::Projector`]): lens model and
//! distortion, then exact refraction through every surface of the port, with the product of the
//! Fresnel transmittances. The weight is that transmittance times the n² radiance law
//! (docs/render-conventions.md, §3.4 "The n² law"): a camera in air behind a port sees water radiance scaled by
//! `(n_air/n_water)²`; a camera without a port sits in the medium and sees it unscaled. A
//! camera in the air above the sea surface (a drone) sees the water through the surface: its
//! rays refract where they meet it ([`crate::optics::surface`]), weighted by the Fresnel
//! transmittance and the same `(1/n_water)²`; the sky the surface reflects is not rendered.

use crate::model::{Model, Port, Pose};
use crate::optics::project::Projector;
use crate::optics::surface::SeaInterface;
use glam::DVec3;

/// Pixel → ray for one camera, pose and channel.
#[derive(Debug, Clone)]
pub struct CameraRays {
    projector: Projector,
    pose: usize,
    world_from_camera: Pose,
    /// (n_inside / n_water)² when the camera is behind a port or above the water, else 1.
    n2_factor: f64,
    /// The sea surface, when the camera is in the air above it: its rays refract there.
    surface: Option<SeaInterface>,
}

impl CameraRays {
    pub fn new(
        model: &Model,
        pose: usize,
        cam: usize,
        channel: usize,
    ) -> Result<CameraRays, String> {
        let c = &model.cameras[cam];
        let n_w = model.ambient_ior()[channel];
        let surface = if model.above_surface(pose, cam) {
            model.sea_interface(channel)
        } else {
            None
        };
        let n2_factor = match (&c.port, &surface) {
            (Port::None, None) => 1.0,
            _ => (1.0 / n_w).powi(2),
        };
        Ok(CameraRays {
            projector: model.projector(cam, channel)?,
            pose,
            world_from_camera: model.world_from_camera(pose, cam),
            n2_factor,
            surface,
        })
    }

    /// `world_from_camera` of this image.
    pub fn pose(&self) -> &Pose {
        &self.world_from_camera
    }

    /// Ray through pixel position (u, v): (origin, unit direction, weight); `None` when no
    /// ray leaves the camera there (beyond a fisheye's field, total internal reflection, …).
    #[inline]
    pub fn ray(&self, u: f64, v: f64) -> Option<(DVec3, DVec3, f64)> {
        let (o, d, t) = self.projector.pixel_ray_world(self.pose, u, v).ok()?;
        let (o, d, t) = match &self.surface {
            // From the air: refracted into the water where the ray meets the surface.
            Some(s) => {
                let (p, w, ts) = s.refract_down(o, d).ok()?;
                (p, w, t * ts)
            }
            None => (o, d, t),
        };
        (o.is_finite() && d.is_finite() && t.is_finite()).then_some((o, d, t * self.n2_factor))
    }
}
