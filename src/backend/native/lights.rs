//! The lights of one rig pose in the world frame (rig-mounted lights moved with the rig).
//!
//! | light | radiometry (docs/render-conventions.md, §2.2 "Light units") |
//! |---|---|
//! | point | intensity `I` W/sr per channel, irradiance `I·cos/r²` |
//! | spot | point light restricted to the sharp cone `angle(direction, x − p) ≤ half_angle` |
//! | area | one-sided rectangle emitting along its frame's +z, radiance `L` W/(m²·sr) |
//! | sun | directional light in the water: propagation `direction_water` per channel (each channel refracted with its own index; shadow rays follow green's), irradiance `irradiance_water` just below z = 0, attenuated by the water between the point and z = 0 |
//! | ambient | uniform radiance from every direction, reached by rays that leave the scene |

use crate::model::{LightKind, Model, Pose};
use glam::DVec3;

#[derive(Debug, Clone)]
pub struct PointLight {
    pub pos: DVec3,
    pub intensity: DVec3,
    /// (unit axis, cos of the half angle) for spots.
    pub cone: Option<(DVec3, f64)>,
}

impl PointLight {
    /// Intensity towards `x` (zero outside a spot's cone).
    #[inline]
    pub fn intensity_to(&self, x: DVec3) -> DVec3 {
        match self.cone {
            Some((axis, cos_half)) => {
                let d = (x - self.pos).normalize_or_zero();
                if d.dot(axis) >= cos_half {
                    self.intensity
                } else {
                    DVec3::ZERO
                }
            }
            None => self.intensity,
        }
    }
}

#[derive(Debug, Clone)]
pub struct AreaLight {
    /// Centre, half-extent axes (world, length = half width/height) and unit normal (+z).
    pub center: DVec3,
    pub ax: DVec3,
    pub ay: DVec3,
    pub normal: DVec3,
    pub area: f64,
    pub radiance: DVec3,
}

impl AreaLight {
    /// Ray parameter of a hit on the emitting or back face, within (eps, tmax).
    pub fn intersect(&self, o: DVec3, d: DVec3, tmax: f64) -> Option<f64> {
        let dn = d.dot(self.normal);
        if dn == 0.0 {
            return None;
        }
        let t = (self.center - o).dot(self.normal) / dn;
        if !(t > 1e-7 && t < tmax) {
            return None;
        }
        let q = o + t * d - self.center;
        let (u, v) = (
            q.dot(self.ax) / self.ax.length_squared(),
            q.dot(self.ay) / self.ay.length_squared(),
        );
        (u.abs() <= 1.0 && v.abs() <= 1.0).then_some(t)
    }
}

#[derive(Debug, Clone)]
pub struct SunLight {
    /// Unit propagation direction per channel, z < 0 (in water each channel refracts with
    /// its own index, [`Model::sun_directions_water`]; all three the same in air).
    pub dirs: [DVec3; 3],
    pub irradiance: DVec3,
}

impl SunLight {
    /// The green channel's direction, which shadow rays follow.
    #[inline]
    pub fn dir(&self) -> DVec3 {
        self.dirs[1]
    }

    /// Whether the channels' directions differ: cosines, path lengths and phase angles are
    /// then taken per channel.
    #[inline]
    pub fn chromatic(&self) -> bool {
        self.dirs[0] != self.dirs[1] || self.dirs[2] != self.dirs[1]
    }
}

/// Every light at one rig pose.
#[derive(Debug, Clone, Default)]
pub struct Lights {
    pub points: Vec<PointLight>,
    pub areas: Vec<AreaLight>,
    pub sun: Option<SunLight>,
    pub ambient: DVec3,
}

impl Lights {
    pub fn at_pose(model: &Model, world_from_rig: &Pose) -> Lights {
        let mut out = Lights::default();
        for l in &model.lights {
            match l.in_world(world_from_rig).kind {
                LightKind::Point {
                    position,
                    intensity,
                } => out.points.push(PointLight {
                    pos: position,
                    intensity: DVec3::from_array(intensity),
                    cone: None,
                }),
                LightKind::Spot {
                    position,
                    direction,
                    half_angle,
                    intensity,
                } => out.points.push(PointLight {
                    pos: position,
                    intensity: DVec3::from_array(intensity),
                    cone: Some((direction.normalize(), half_angle.cos())),
                }),
                LightKind::Area {
                    frame: f,
                    width,
                    height,
                    radiance,
                } => {
                    let ax = f.rotation.x_axis * (0.5 * width);
                    let ay = f.rotation.y_axis * (0.5 * height);
                    out.areas.push(AreaLight {
                        center: f.translation,
                        ax,
                        ay,
                        normal: f.rotation.z_axis.normalize(),
                        area: width * height,
                        radiance: DVec3::from_array(radiance),
                    })
                }
                LightKind::Ambient { radiance } => out.ambient += DVec3::from_array(radiance),
            }
        }
        if let Some(s) = &model.sun {
            let (dirs, e) = match model.sun_directions_water() {
                Some(dirs) if model.water.is_some() => (dirs, s.irradiance_water),
                _ => ([s.direction_air; 3], s.irradiance),
            };
            if dirs.iter().all(|d| d.z < 0.0) {
                out.sun = Some(SunLight {
                    dirs: dirs.map(DVec3::normalize),
                    irradiance: DVec3::from_array(e),
                });
            }
        }
        out
    }
}
