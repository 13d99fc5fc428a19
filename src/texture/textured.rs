//! The native renderer's textured geometry: the model's [`Bvh`] with each object's baked
//! texture ([`super::bake`]: the baked mesh with its UVs) or prepared textured mesh
//! ([`super::mapped`]: the file's triangles, materials and colours), by object index. The
//! geometry service knows nothing of textures; this pairs them, so that textures may read
//! meshes and the BVH never names a texture.
//!
//! | item | meaning |
//! |---|---|
//! | [`Textured::of_model`] | bake or prepare every textured object, then build the BVH on their meshes |
//! | [`Textured::mapped_albedo`] | albedo at a hit on a textured mesh |
//!
//! It dereferences to its [`Bvh`], so `textured.intersect(…)` is the geometry's query.

use super::bake::{Baked, bake_object};
use super::mapped::{Prepared, prepare_object};
use crate::geometry::{Bvh, Hit, SurfaceId};
use crate::model::Model;
use std::sync::Arc;

/// The geometry with its textures.
#[derive(Debug, Clone, Default)]
pub struct Textured {
    pub bvh: Bvh,
    /// The baked texture of each object, by object index.
    pub textures: Vec<Option<Arc<Baked>>>,
    /// The prepared textured mesh of each object, by object index.
    pub meshes: Vec<Option<Arc<Prepared>>>,
}

impl Textured {
    /// Every object's texture (a textured mesh is prepared, a pattern baked), and the BVH on
    /// their meshes: textured meshes keep their file's triangles (the geometry `object_mesh`
    /// reads), baked objects use the baked mesh (same triangles, vertices split at UV seams).
    pub fn of_model(model: &Model) -> Result<Textured, String> {
        let mut given = Vec::with_capacity(model.objects.len());
        let mut textures = Vec::with_capacity(model.objects.len());
        let mut meshes = Vec::with_capacity(model.objects.len());
        for (i, o) in model.objects.iter().enumerate() {
            let mapped = prepare_object(model, i)?;
            let baked = match mapped {
                None => bake_object(model, i)?,
                Some(_) => None,
            };
            given.push(match (&mapped, &baked) {
                (Some(p), _) => {
                    let f = &p.plan.file;
                    let uv = (!f.uv.is_empty()).then(|| f.uv.clone());
                    Some((f.mesh.transformed(&o.pose, o.scale), uv))
                }
                (None, Some(b)) => Some((b.mesh.transformed(&o.pose, o.scale), Some(b.uv.clone()))),
                (None, None) => None,
            });
            textures.push(baked);
            meshes.push(mapped);
        }
        let keep_source = meshes.iter().any(Option::is_some);
        Ok(Textured {
            bvh: Bvh::of_model_with(model, given, keep_source)?,
            textures,
            meshes,
        })
    }

    /// Albedo at a hit on a textured mesh: its material's image, colour or vertex colours
    /// there; `None` for every other surface.
    pub fn mapped_albedo(&self, h: &Hit) -> Option<[f64; 3]> {
        self.mapped_albedo_over(h, 0.0)
    }

    /// [`Textured::mapped_albedo`] with the image averaged over a footprint `width` metres
    /// wide ([`Prepared::albedo_over`]).
    pub fn mapped_albedo_over(&self, h: &Hit, width: f64) -> Option<[f64; 3]> {
        let SurfaceId::Object(i) = h.surface else {
            return None;
        };
        let p = self.meshes.get(i as usize)?.as_ref()?;
        let src = self.bvh.source_of(h)?;
        let k = *p.plan.file.material.get(src as usize)?;
        Some(p.albedo_over(k, self.bvh.uv_at(h), src, self.bvh.barycentric(h), width))
    }
}

impl std::ops::Deref for Textured {
    type Target = Bvh;
    fn deref(&self) -> &Bvh {
        &self.bvh
    }
}
