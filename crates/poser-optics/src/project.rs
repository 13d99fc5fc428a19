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
//! Pixel coordinates follow COLMAP's convention: pixel (i, j) covers [i, i+1]×[j, j+1], its
//! centre is at (i + 0.5, j + 0.5). OpenCV puts pixel centres at integers: subtract 0.5.
//! Points farther than [`FAR`] are first scaled towards the pupil by an exact power of two
//! (same ray, no overflow in the port solvers; the pixel of a point that far is its
//! direction's limit to far below 1e-50 px).
//! Nothing allocates after construction; `Projector` is `Send + Sync` and cheap to share.

use super::NoSolution;
use super::lens::Lens;
use super::port::{PortRay, PortSolver};
use super::types::{Camera, Pose};
use glam::DVec3;

/// Largest coordinate (m) handed to the port solvers as is; farther points are scaled by a
/// power of two to below it. Squares of coordinates stay far from f64's overflow at 1.3e154.
pub const FAR: f64 = 1e100;

/// `p` scaled by an exact power of two so that its largest coordinate is at most [`FAR`]: the
/// same direction from the entrance pupil, bit for bit.
#[inline]
fn tame(p: DVec3) -> DVec3 {
    let m = p.abs().max_element();
    if m <= FAR {
        return p;
    }
    // 2^-e with 2^e ≥ m / FAR; exact, since it only changes the exponents.
    let e = (m / FAR).log2().ceil() as i32;
    p * 2f64.powi(-e)
}

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
    /// builds these: `Projector::new` in `poser::model`).
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
        let d = self.port.forward(tame(p))?;
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
        let mut tamed = [DVec3::ZERO; CHUNK];
        for (pc, oc) in ps.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let dirs = &mut dirs[..pc.len()];
            if pc.iter().any(|p| p.abs().max_element() > FAR) {
                for (t, p) in tamed.iter_mut().zip(pc) {
                    *t = tame(*p);
                }
                self.port.forward_many(&tamed[..pc.len()], dirs);
            } else {
                self.port.forward_many(pc, dirs);
            }
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

    /// Many points, in the camera frame (`world_pose` `None`) or in the world at rig pose
    /// `world_pose`, to pixels without the sensor-bounds check (the batch solver; check
    /// [`Projector::on_sensor`] for the `off_sensor` status). What `poser project` and the
    /// Python module's `Scene.project` return.
    pub fn project_points(
        &self,
        pts: &[DVec3],
        world_pose: Option<usize>,
    ) -> Vec<Result<[f64; 2], NoSolution>> {
        let cam: Vec<DVec3> = pts
            .iter()
            .map(|&x| match world_pose {
                Some(pose) => self.world_to_camera(pose, x),
                None => x,
            })
            .collect();
        let mut px = vec![Err(NoSolution::NoConvergence); cam.len()];
        self.project_camera_many_unbounded(&cam, &mut px);
        px
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

/// Parse a colour channel name (`r`, `g`, `b`, `red`, …, or `0`, `1`, `2`) into the channel
/// index a [`Projector`] takes (`poser project --channel`, Python's `Scene.project(channel=)`).
pub fn parse_channel(s: &str) -> Result<usize, String> {
    match s.to_ascii_lowercase().as_str() {
        "r" | "red" | "0" => Ok(0),
        "g" | "green" | "1" => Ok(1),
        "b" | "blue" | "2" => Ok(2),
        _ => Err(format!("--channel `{s}`: expected r, g or b")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Distortion, Glass, LensModel, Port};

    fn camera(port: Port) -> Camera {
        Camera {
            name: "c".into(),
            width: 1200,
            height: 800,
            pixel_pitch: 4e-6,
            focal_length: 4e-3,
            fx: 1000.0,
            fy: 1000.0,
            cx: 600.0,
            cy: 400.0,
            lens: LensModel::Rectilinear,
            distortion: Distortion::default(),
            focus_distance: None,
            f_number: None,
            port,
            rig_from_camera: Pose::IDENTITY,
        }
    }

    fn glass() -> Glass {
        Glass {
            name: "custom".into(),
            ior: [1.5; 3],
        }
    }

    /// Points beyond 1e154 m overflowed the squares in the port solvers and came back as a
    /// garbage pixel marked `off_sensor`. Far points now land on their direction's limit, for
    /// every port, through the single and the batch paths alike.
    #[test]
    fn far_points_project_to_their_directions_limit() {
        let ports = [
            Port::None,
            Port::Flat {
                normal: DVec3::new(0.05, -0.02, 1.0).normalize(),
                distance: 0.03,
                thickness: 0.015,
                glass: glass(),
                outer_layers: vec![],
            },
            Port::Dome {
                center: DVec3::new(0.004, 0.002, 0.01),
                inner_radius: 0.1,
                thickness: 0.01,
                glass: glass(),
            },
            Port::Cylinder {
                axis_point: DVec3::new(0.0, 0.0, 0.02),
                axis: DVec3::Y,
                inner_radius: 0.05,
                thickness: 0.01,
                glass: glass(),
            },
        ];
        let dirs = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.2, -0.1, 1.0),
            DVec3::new(-0.3, 0.2, 1.0),
        ];
        for port in ports {
            let pr = Projector::for_camera(&camera(port.clone()), 1, 1.34).unwrap();
            for d in dirs {
                // The limit: the same direction at 1e12 m (the port's offsets are centimetres,
                // so the ray to it differs from the limit by ~1e-14 rad, 1e-11 px).
                let near = pr.project_camera(d * 1e12).unwrap();
                for scale in [1e150, 1e155, 1e200, 1e300, f64::MAX / 4.0] {
                    let p = d * scale;
                    let one = pr.project_camera(p);
                    let mut many = [Err(NoSolution::NoConvergence)];
                    pr.project_camera_many(&[p], &mut many);
                    for got in [one, many[0]] {
                        let px = got.unwrap_or_else(|e| {
                            panic!("{} port, {d:?}·{scale:e}: {e:?}", port.kind_name())
                        });
                        let err = (px[0] - near[0]).hypot(px[1] - near[1]);
                        assert!(
                            err < 1e-6,
                            "{} port, {d:?}·{scale:e}: {px:?} vs {near:?}",
                            port.kind_name()
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn taming_is_exact_scaling() {
        let p = DVec3::new(3e200, -1e199, 7e201);
        let t = tame(p);
        assert!(t.abs().max_element() <= FAR);
        let s = p.x / t.x;
        assert_eq!(s.log2().fract(), 0.0, "a power of two");
        assert_eq!(t * s, p);
        let q = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(tame(q), q);
    }
}
