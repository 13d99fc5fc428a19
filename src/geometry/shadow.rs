//! Where a camera housing's sun shadow falls: the images it enters and the target points it
//! covers. poser's housings cast no shadow (docs/render-conventions.md, "The housing is a
//! measuring device"), and neither do the native and Cycles renders; Mitsuba 3 cannot leave a
//! surface out of shadow rays, so its housing shadows the sun. This says where that shows,
//! so that its warning can name the images and targets it changes (docs/backends.md, "The
//! housing's shadow").
//!
//! The housing is taken as its bounding sphere about the entrance pupil
//! ([`crate::optics::port::Housing::extent`]): the shadow found is a little larger than the
//! real one, never smaller, so an image or target reported clear is clear.
//!
//! | quantity | how |
//! |---|---|
//! | the sun's direction | the green channel's refracted direction in the water ([`crate::model::Sun::direction_water`]) |
//! | shadow in an image | a ray from the pupil and from [`RIM`] points of the sphere's rim (⊥ the sun) along the sun hits a surface whose point projects onto the sensor (exact projection through the port) |
//! | target point in the shadow | it projects onto the sensor and lies within the sphere's radius plus the printed feature's radius ([`feature_radius`]) of the shadow's axis, beyond the pupil |

use crate::geometry::{Bvh, Ray};
use crate::model::{Model, TargetKind};
use crate::optics::port;
use glam::DVec3;

/// Rim points of the housing's bounding sphere traced besides its centre.
pub const RIM: usize = 8;

/// Where the housings' sun shadows fall over the network.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HousingShadow {
    /// Images (camera × pose) in which some of the shadow lands on a surface in view.
    pub images: usize,
    /// Images of cameras with a housing.
    pub of: usize,
    /// `(image, target point id)` of every target point in view inside a shadow, in the
    /// network's order.
    pub points: Vec<(String, String)>,
}

/// The radius, m, of the printed feature a target point marks (a disk's, a star's; 0 for a
/// checkerboard's corner): a shadow's edge within it moves the measured centre.
pub fn feature_radius(kind: &TargetKind) -> f64 {
    match kind {
        TargetKind::Checkerboard { .. } => 0.0,
        TargetKind::CircleGrid { diameter, .. }
        | TargetKind::Coded { diameter, .. }
        | TargetKind::ScaleBar { diameter, .. }
        | TargetKind::SiemensStar { diameter, .. }
        | TargetKind::Disk { diameter }
        | TargetKind::TestObject { diameter, .. } => 0.5 * diameter,
    }
}

/// Where the sun shadows of the model's camera housings fall (`None` without a sun, or when
/// no camera has a housing).
pub fn housing_shadow(model: &Model, scene: &Bvh) -> Option<HousingShadow> {
    let sun = model.sun.as_ref()?.direction_water.normalize();
    let mut out = HousingShadow::default();
    let mut any = false;
    for (ci, cam) in model.cameras.iter().enumerate() {
        let Ok(Some(h)) = port::housing(cam) else {
            continue;
        };
        let Ok(pr) = model.projector(ci, 1) else {
            continue;
        };
        any = true;
        let r = h.extent;
        let (e1, e2) = port::basis(sun);
        for pi in 0..model.poses.len() {
            out.of += 1;
            let pupil = pr.world_from_camera(pi).translation;
            let seen = |p: DVec3| pr.project_world(pi, p).is_ok_and(|px| pr.on_sensor(px));
            let in_image = (0..=RIM).any(|k| {
                let o = if k == 0 {
                    pupil
                } else {
                    let a = std::f64::consts::TAU * k as f64 / RIM as f64;
                    pupil + r * (a.cos() * e1 + a.sin() * e2)
                };
                let ray = Ray {
                    origin: o + sun * r,
                    dir: sun,
                };
                scene
                    .intersect(&ray, f64::INFINITY)
                    .is_some_and(|hit| seen(hit.point))
            });
            out.images += in_image as usize;
            for t in &model.targets {
                let reach = r + feature_radius(&t.kind);
                for p in &t.points {
                    let v = p.world - pupil;
                    let s = v.dot(sun);
                    if s > 0.0 && (v - s * sun).length() < reach && seen(p.world) {
                        out.points.push((model.image_name(pi, ci), p.id.clone()));
                    }
                }
            }
        }
    }
    any.then_some(out)
}

impl HousingShadow {
    /// Where the shadow shows, in words: "it falls inside N of M images and on K target
    /// point(s) seen in them (first: ID in IMAGE)", or "it falls outside every image".
    pub fn describe(&self) -> String {
        if self.images == 0 && self.points.is_empty() {
            return format!("it falls outside every image ({} checked)", self.of);
        }
        let mut s = format!("it falls inside {} of {} images", self.images, self.of);
        match self.points.first() {
            None => s.push_str(" and on no target"),
            Some((image, id)) => s.push_str(&format!(
                " and on {} target point(s) seen in them (first: {id} in {image})",
                self.points.len()
            )),
        }
        s
    }
}
