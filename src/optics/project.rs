//! Exact projection of one camera (lens + port) for one colour channel, in the camera frame
//! and in the world at any rig pose of the network.
//!
//! | method | what | failure |
//! |---|---|---|
//! | [`Projector::project_camera`] | camera-frame point in water → pixel on the sensor | [`NoSolution`] incl. `off_sensor` |
//! | [`Projector::project_camera_unbounded`] | same, without the sensor-bounds check | |
//! | [`Projector::project_camera_many`] | many camera-frame points → pixels (batch port solver, same results) | per point |
//! | [`Projector::project_world`] | world point at rig pose `i` → pixel | |
//! | [`Projector::camera_ray`] | pixel → ray in water (camera frame) with Fresnel transmittance | |
//! | [`Projector::pixel_ray_world`] | pixel → (origin, unit direction, transmittance) in the world | |
//!
//! Pixel coordinates follow OpenCV: pixel (i, j) covers [i, i+1]×[j, j+1], centre at +0.5.
//! Nothing allocates after construction; `Projector` is `Send + Sync` and cheap to share.

use super::NoSolution;
use super::lens::Lens;
use super::port::{PortRay, PortSolver};
use super::types::{Camera, Pose};
use glam::DVec3;

#[derive(Debug, Clone)]
pub struct Projector {
    pub lens: Lens,
    pub port: PortSolver,
    pub width: f64,
    pub height: f64,
    pub channel: usize,
    /// `world_from_camera` at every rig pose, and its inverse.
    world_from_camera: Vec<Pose>,
    camera_from_world: Vec<Pose>,
}

impl Projector {
    /// A projector for one camera alone (camera frame only; no poses), in a medium of index
    /// `n_water` (1 in air).
    pub fn for_camera(camera: &Camera, channel: usize, n_water: f64) -> Result<Projector, String> {
        let port = PortSolver::new(&camera.port, channel, 1.0, n_water)
            .map_err(|e| format!("camera `{}`: {e}", camera.name))?;
        Ok(Projector {
            lens: Lens::from_camera(camera),
            port,
            width: camera.width as f64,
            height: camera.height as f64,
            channel,
            world_from_camera: Vec::new(),
            camera_from_world: Vec::new(),
        })
    }

    /// The same projector placed at rig poses: `world_from_camera` at each pose (the model
    /// builds these: `Projector::new` in [`crate::model`]).
    pub fn with_poses(mut self, world_from_camera: Vec<Pose>) -> Projector {
        self.camera_from_world = world_from_camera.iter().map(Pose::inverse).collect();
        self.world_from_camera = world_from_camera;
        self
    }

    /// Number of rig poses known to this projector.
    pub fn poses(&self) -> usize {
        self.world_from_camera.len()
    }

    /// `world_from_camera` at rig pose `pose` (panics if out of range, like slice indexing).
    pub fn world_from_camera(&self, pose: usize) -> Pose {
        self.world_from_camera[pose]
    }

    /// Whether a pixel position lies on the sensor `[0, w]×[0, h]`.
    #[inline]
    pub fn on_sensor(&self, px: [f64; 2]) -> bool {
        px[0] >= 0.0 && px[0] <= self.width && px[1] >= 0.0 && px[1] <= self.height
    }

    /// Camera-frame point in water → pixel, wherever it falls (may be far off the sensor).
    #[inline]
    pub fn project_camera_unbounded(&self, p: DVec3) -> Result<[f64; 2], NoSolution> {
        if !p.is_finite() {
            return Err(NoSolution::NoConvergence);
        }
        let d = self.port.forward(p)?;
        self.lens.project(d)
    }

    /// Camera-frame point in water → pixel on the sensor.
    #[inline]
    pub fn project_camera(&self, p: DVec3) -> Result<[f64; 2], NoSolution> {
        let px = self.project_camera_unbounded(p)?;
        if self.on_sensor(px) {
            Ok(px)
        } else {
            Err(NoSolution::OffSensor)
        }
    }

    /// Many camera-frame points → pixels, wherever they fall: the same results as
    /// [`Projector::project_camera_unbounded`] point by point, computed with the batch port
    /// solver ([`PortSolver::forward_many`]). `out[i]` is for `ps[i]` (equal lengths).
    pub fn project_camera_many_unbounded(
        &self,
        ps: &[DVec3],
        out: &mut [Result<[f64; 2], NoSolution>],
    ) {
        assert_eq!(ps.len(), out.len(), "one output per point");
        const CHUNK: usize = 64;
        let mut dirs = [Err(NoSolution::NoConvergence); CHUNK];
        for (pc, oc) in ps.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let dirs = &mut dirs[..pc.len()];
            self.port.forward_many(pc, dirs);
            for ((p, d), o) in pc.iter().zip(dirs.iter()).zip(oc.iter_mut()) {
                *o = if p.is_finite() {
                    d.and_then(|d| self.lens.project(d))
                } else {
                    Err(NoSolution::NoConvergence)
                };
            }
        }
    }

    /// Many camera-frame points → pixels on the sensor ([`Projector::project_camera`] point
    /// by point, with the batch port solver).
    pub fn project_camera_many(&self, ps: &[DVec3], out: &mut [Result<[f64; 2], NoSolution>]) {
        self.project_camera_many_unbounded(ps, out);
        for o in out.iter_mut() {
            if let Ok(px) = *o
                && !self.on_sensor(px)
            {
                *o = Err(NoSolution::OffSensor);
            }
        }
    }

    /// World point → camera frame at rig pose `pose` (panics if out of range).
    #[inline]
    pub fn world_to_camera(&self, pose: usize, p_world: DVec3) -> DVec3 {
        self.camera_from_world[pose].transform_point(p_world)
    }

    /// World point seen from rig pose `pose` → pixel on the sensor.
    #[inline]
    pub fn project_world(&self, pose: usize, p_world: DVec3) -> Result<[f64; 2], NoSolution> {
        self.project_camera(self.camera_from_world[pose].transform_point(p_world))
    }

    /// World point → pixel, without the sensor-bounds check.
    #[inline]
    pub fn project_world_unbounded(
        &self,
        pose: usize,
        p_world: DVec3,
    ) -> Result<[f64; 2], NoSolution> {
        self.project_camera_unbounded(self.camera_from_world[pose].transform_point(p_world))
    }

    /// Pixel → ray in water, camera frame (origin on the port's outer surface).
    #[inline]
    pub fn camera_ray(&self, u: f64, v: f64) -> Result<PortRay, NoSolution> {
        let d = self.lens.unproject(u, v)?;
        self.port.backward(d)
    }

    /// Pixel → (origin, unit direction, Fresnel transmittance) of the ray in water, world frame.
    #[inline]
    pub fn pixel_ray_world(
        &self,
        pose: usize,
        u: f64,
        v: f64,
    ) -> Result<(DVec3, DVec3, f64), NoSolution> {
        let r = self.camera_ray(u, v)?;
        let w = &self.world_from_camera[pose];
        Ok((
            w.transform_point(r.origin),
            w.transform_vector(r.dir),
            r.transmittance,
        ))
    }
}
