//! What the cameras see: a grid of exact camera rays (through the port) over the network's
//! images, classified by what each ray hits first. The images-mode pre-check needs texture in
//! view; the daylight choice needs every view to end on the seabed (a ray that heads down and
//! hits nothing looks into water without a bottom, which the solved column and traced daylight
//! light differently, docs/column.md).

use crate::geometry::{Bvh, Ray, SurfaceId};
use crate::model::{Model, Shape};

/// What the cameras see, as shares of a grid of sampled pixels over the network's images.
#[derive(Debug, Clone, Copy)]
pub struct TextureSeen {
    /// Pixels whose ray hits any surface.
    pub surface: f64,
    /// Pixels whose ray hits a textured surface: an object with a pattern or colour variation,
    /// a mesh whose file gives its colours (image textures, material or vertex colours: a
    /// photogrammetric model), or a printed target.
    pub textured: f64,
    /// Pixels whose ray heads downward and hits nothing: past the scene's seabed into water
    /// without a bottom.
    pub bottomless: f64,
}

/// The share of the cameras' view that looks past the seabed into water without a bottom,
/// where it matters for the daylight choice ([`Model::daylight_choice`]): `None` when the scene
/// is no water column, whose daylight is traced whatever the views (no rays are cast then).
pub fn past_seabed(model: &Model, scene: &Bvh) -> Option<f64> {
    model
        .column_input()
        .is_ok()
        .then(|| texture_seen(model, scene).bottomless)
}

/// [`past_seabed`] on the scene's own geometry: the BVH is built only where the views can
/// change the daylight choice (a water column).
pub fn views_past_seabed(model: &Model) -> Option<f64> {
    model
        .column_input()
        .ok()
        .and_then(|_| Bvh::of_model(model).ok())
        .and_then(|b| past_seabed(model, &b))
}

/// Cast a 16 × 12 grid of exact camera rays through up to 64 evenly spread images of the
/// network (every camera of the rig) and classify what each ray hits first.
pub fn texture_seen(model: &Model, scene: &Bvh) -> TextureSeen {
    let n_poses = model.poses.len();
    let step = n_poses.div_ceil(64).max(1);
    let (mut rays, mut hit, mut textured, mut bottomless) = (0usize, 0usize, 0usize, 0usize);
    for (ci, cam) in model.cameras.iter().enumerate() {
        let Ok(pr) = model.projector(ci, 1) else {
            continue;
        };
        for pi in (0..n_poses).step_by(step) {
            for j in 0..12 {
                for i in 0..16 {
                    let u = (i as f64 + 0.5) / 16.0 * cam.width as f64;
                    let v = (j as f64 + 0.5) / 12.0 * cam.height as f64;
                    rays += 1;
                    let Ok((o, d, _)) = pr.pixel_ray_world(pi, u, v) else {
                        continue;
                    };
                    let Some(h) = scene.intersect(&Ray { origin: o, dir: d }, f64::INFINITY) else {
                        bottomless += (d.z < 0.0) as usize;
                        continue;
                    };
                    hit += 1;
                    let tex = match h.surface {
                        SurfaceId::Object(k) => model.objects.get(k as usize).is_some_and(|o| {
                            o.material.pattern.is_some()
                                || o.material.variation > 0.0
                                || matches!(o.shape, Shape::Mesh { textured: true, .. })
                        }),
                        SurfaceId::Target(_) => true,
                        #[allow(unreachable_patterns)]
                        _ => false,
                    };
                    textured += tex as usize;
                }
            }
        }
    }
    let r = rays.max(1) as f64;
    TextureSeen {
        surface: hit as f64 / r,
        textured: textured as f64 / r,
        bottomless: bottomless as f64 / r,
    }
}
