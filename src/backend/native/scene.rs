//! What the native renderer traces against: the model's geometry with its textures
//! ([`crate::texture::Textured`], its BVH shared with the truth and the planner) plus what only the renderer needs, the sun's caustic
//! volume under waves ([`super::caustics`]) and the water column's light, precomputed once.
//!
//! | item | meaning |
//! |---|---|
//! | [`Scene::build`] | the BVH of every object and target, and the caustic volume when the model needs caustics |
//! | [`Scene::bvh`] | the geometry and its textures (also reached through `Deref`: `scene.intersect(…)`, `scene.textures`) |
//! | [`Scene::caustics`] | the caustic volume, if any |
//! | [`Scene::column`] | the water column's light ([`crate::optics::column`]), when daylight comes from it ([`Model::daylight_choice`]) |
//!
//! Queries are read-only, so one `Scene` is shared by every rendering thread.

use crate::model::Model;
use crate::texture::Textured;
use std::sync::Arc;

pub use crate::geometry::{Hit, RAY_EPSILON, Ray, SurfaceId};

/// The geometry and the caustics of one model.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    pub bvh: Textured,
    /// The sun's caustics under a wavy surface, when the model needs them.
    pub caustics: Option<Arc<super::caustics::CausticVolume>>,
    /// The solved water column, when the scene's daylight comes from it.
    pub column: Option<Arc<crate::optics::column::Column>>,
}

impl Scene {
    /// What the renderer needs: the model's [`Bvh`], plus the caustic volume when the model asks
    /// for caustics.
    pub fn build(model: &Model) -> Result<Scene, String> {
        Ok(Scene::with_bvh(model, Textured::of_model(model)?))
    }

    /// The renderer's scene around an already built BVH of `model`.
    pub fn with_bvh(model: &Model, bvh: Textured) -> Scene {
        let caustics = if model.needs.caustics {
            // Planes down to below the deepest geometry (or the nominal seabed).
            let lo = bvh.bounds().map_or(-model.site.depth, |(lo, _)| lo.z);
            let z_bottom = lo.min(-model.site.depth) - 0.5;
            super::caustics::CausticVolume::for_model(model, z_bottom).map(Arc::new)
        } else {
            None
        };
        // A solve can still refuse odd input; then the scene is traced (`explain` says why).
        // Under "auto", a view past the seabed keeps daylight traced (Model::daylight_choice).
        let past = (model.render.daylight == crate::model::Daylight::Auto)
            .then(|| crate::geometry::seen::past_seabed(model, &bvh))
            .flatten();
        let column = model
            .daylight_choice(past)
            .0
            .and_then(|i| crate::optics::column::solve(&i).ok())
            .map(Arc::new);
        Scene {
            bvh,
            caustics,
            column,
        }
    }
}

impl std::ops::Deref for Scene {
    type Target = Textured;
    fn deref(&self) -> &Textured {
        &self.bvh
    }
}
