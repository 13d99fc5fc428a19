//! The geometry service: every triangle of the model's objects and targets in one
//! bounding-volume hierarchy (binned SAH, f64, built on every core: the same tree at any
//! thread count), with closest-hit and shadow (occlusion) queries. Glass spheres and cylinders
//! are not tessellated: they are intersected exactly beside the tree (refraction needs the
//! true surface and normal). Used by the ground truth (occlusion), the survey planner (coverage)
//! and the native renderer.
//!
//! | item | meaning |
//! |---|---|
//! | [`SurfaceId`] | which object or target a triangle belongs to (for its material) |
//! | [`Bvh::of_model`] | objects via [`super::mesh::object_mesh`]; targets as planes of their printed extent |
//! | [`Bvh::of_model_with`] | the same, with some objects' meshes given (with UVs): what the textured geometry (`texture::Textured`) builds |
//! | [`Bvh::uv_at`] | texture coordinates at a hit |
//! | [`Bvh::source_of`] | a hit's triangle index in its object's mesh, when kept |
//! | [`Bvh::intersect`] | closest hit with `t ∈ (RAY_EPSILON, tmax)` |
//! | [`Bvh::occluded`] | is the open segment between two points blocked? |
//!
//! Queries are read-only, so one `Bvh` is shared by every thread. Above [`LAZY_ABOVE`]
//! triangles the subtrees of ranges of at most [`LAZY_MAX`] triangles are built when a ray
//! first enters their box (one `OnceLock` each): the tree is the one the whole build makes,
//! so every query answers the same; what no ray reaches is never built.

use super::mesh::{TriMesh, object_mesh};
use crate::model::Model;
use glam::{DVec3, Vec3A};
use std::path::Path;

/// Smallest accepted hit distance, m (self-intersection guard; geometry is f64).
pub const RAY_EPSILON: f64 = 1e-7;

/// A ray; `dir` need not be normalised (then `t` is in units of `|dir|`).
#[derive(Debug, Clone, Copy)]
pub struct Ray {
    pub origin: DVec3,
    pub dir: DVec3,
}

/// What a triangle belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceId {
    /// Index into `model.objects`.
    Object(u32),
    /// Index into `model.targets`.
    Target(u32),
}

/// A closest hit.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    pub point: DVec3,
    /// Unit geometric normal from the winding (not flipped towards the ray).
    pub normal: DVec3,
    /// Triangle index (in the scene's order).
    pub triangle: u32,
    pub surface: SurfaceId,
}

#[derive(Debug, Clone, Copy)]
struct Tri {
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Tri {
    /// The triangle's box.
    fn bounds(&self) -> (DVec3, DVec3) {
        let (b, c) = (self.v0 + self.e1, self.v0 + self.e2);
        (self.v0.min(b).min(c), self.v0.max(b).max(c))
    }
}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Inner node (`count == 0`): index of the left child (right = left + 1). Leaf: first
    /// triangle.
    start: u32,
    count: u32,
}

/// Traversal node: f32 SIMD bounds, conservatively enlarged (geometry and hits stay f64).
#[derive(Debug, Clone, Copy)]
struct FNode {
    lo: Vec3A,
    hi: Vec3A,
    start: u32,
    count: u32,
}

impl FNode {
    fn from_node(n: &Node) -> FNode {
        let m = n.lo.abs().max(n.hi.abs()).max_element();
        // f32 rounding of bounds and ray origins: a few ulps at the box's magnitude.
        let eps = 4e-6 * (m + 1.0);
        let lo = n.lo - DVec3::splat(eps);
        let hi = n.hi + DVec3::splat(eps);
        FNode {
            lo: Vec3A::new(lo.x as f32, lo.y as f32, lo.z as f32),
            hi: Vec3A::new(hi.x as f32, hi.y as f32, hi.z as f32),
            start: n.start,
            count: n.count,
        }
    }
}

/// All triangles of a model, with their BVH.
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    tris: Vec<Tri>,
    surface: Vec<SurfaceId>,
    /// Texture coordinates of each triangle's corners (empty when nothing is baked).
    uv: Vec<[[f32; 2]; 3]>,
    /// Index of each triangle in its surface's mesh (empty when no object is a textured mesh:
    /// only those look up per-triangle materials and vertex colours).
    source: Vec<u32>,
    nodes: Vec<FNode>,
    /// The subtrees built when a ray first reaches them ([`LAZY_MAX`]): node `count`
    /// [`LAZY`] points at one by its `start`.
    lazy: Vec<Lazy>,
    /// The glass spheres and cylinders, intersected exactly.
    solids: Vec<Solid>,
}

/// A node's `count` bit marking a subtree built on first use (`start` is its index in
/// [`Bvh::lazy`]).
const LAZY: u32 = 1 << 31;
/// In a BVH of more than [`LAZY_ABOVE`] triangles, ranges of at most this many triangles (and
/// more than [`LAZY_LEAST`]) are built when a ray first enters their box, not up front: a
/// render or a truth query that sees a small part of a large site (a 60 m reef plot at
/// 5 cm) builds only that part. The subtree is the one the whole build would make (the same
/// decisions on the same triangles in the same order), so every hit is the same.
const LAZY_MAX: usize = 1 << 12;
const LAZY_LEAST: usize = 256;
const LAZY_ABOVE: usize = 1 << 17;

/// A range of triangles whose subtree is built on first use.
#[derive(Debug, Clone, Default)]
struct Lazy {
    /// The range's first triangle and count, in the order of [`Bvh::tris`].
    start: u32,
    count: u32,
    tree: std::sync::OnceLock<Sub>,
}

/// A subtree built on first use: its nodes (leaves index `tris`), its triangles in leaf order
/// and each one's index in [`Bvh::tris`].
#[derive(Debug, Clone, Default)]
struct Sub {
    nodes: Vec<FNode>,
    tris: Vec<Tri>,
    ids: Vec<u32>,
}

/// The [`Hit::triangle`] of a hit on a glass sphere or cylinder (it has no triangle).
pub const NO_TRIANGLE: u32 = u32::MAX;

/// A glass sphere or cylinder ([`crate::model::Material::glass`] on a
/// [`crate::model::Shape::Sphere`] scaled uniformly, or a [`crate::model::Shape::Cylinder`]
/// scaled alike across its axis), world frame.
#[derive(Debug, Clone, Copy)]
struct Solid {
    centre: DVec3,
    /// World from object rotation (the cylinder's axis is its z).
    rotation: glam::DMat3,
    radius: f64,
    /// A cylinder's half-height; `None`: a sphere.
    half_height: Option<f64>,
    surface: SurfaceId,
}

/// The roots of a t² + 2 b t + c = 0 in increasing order, cancellation-free (`None`: no real
/// root).
fn roots(a: f64, b: f64, c: f64) -> Option<[f64; 2]> {
    let disc = b * b - a * c;
    if !(disc >= 0.0 && a > 0.0) {
        return None;
    }
    let q = -(b + disc.sqrt().copysign(b));
    let t1 = q / a;
    let t2 = if q != 0.0 { c / q } else { t1 };
    Some([t1.min(t2), t1.max(t2)])
}

impl Solid {
    /// Object `i`, `o`, as a solid when it is a glass sphere or cylinder.
    fn of(o: &crate::model::Object, i: usize) -> Option<Solid> {
        o.material.glass.as_ref()?;
        let (radius, half_height) = match o.shape {
            crate::model::Shape::Sphere { radius } => (radius, None),
            crate::model::Shape::Cylinder { radius, height } => {
                (radius, Some(0.5 * height * o.scale.z))
            }
            _ => return None,
        };
        Some(Solid {
            centre: o.pose.translation,
            rotation: o.pose.rotation,
            radius: radius * o.scale.x,
            half_height,
            surface: SurfaceId::Object(i as u32),
        })
    }

    /// The smallest `t ∈ (RAY_EPSILON, tmax)` where the ray meets the solid's surface, with the
    /// surface's outward unit normal there.
    fn hit(&self, ray: &Ray, tmax: f64) -> Option<(f64, DVec3)> {
        let in_range = |t: f64| t > RAY_EPSILON && t < tmax;
        let oc = ray.origin - self.centre;
        let Some(hz) = self.half_height else {
            let t = roots(
                ray.dir.length_squared(),
                oc.dot(ray.dir),
                oc.length_squared() - self.radius * self.radius,
            )?
            .into_iter()
            .find(|&t| in_range(t))?;
            let n = (ray.origin + t * ray.dir - self.centre) / self.radius;
            return Some((t, n.normalize()));
        };
        // In the cylinder's frame: its side x² + y² = r², |z| ≤ hz; its caps z = ±hz.
        let to_local = self.rotation.transpose();
        let (o, d) = (to_local * oc, to_local * ray.dir);
        let mut best: Option<(f64, DVec3)> = None;
        let mut take = |t: f64, n: DVec3| {
            if in_range(t) && best.is_none_or(|(b, _)| t < b) {
                best = Some((t, n));
            }
        };
        let r2 = self.radius * self.radius;
        if let Some(ts) = roots(
            d.x * d.x + d.y * d.y,
            o.x * d.x + o.y * d.y,
            o.x * o.x + o.y * o.y - r2,
        ) {
            for t in ts {
                let p = o + t * d;
                if p.z.abs() <= hz {
                    take(t, DVec3::new(p.x, p.y, 0.0) / self.radius);
                }
            }
        }
        if d.z != 0.0 {
            for side in [-1.0, 1.0] {
                let t = (side * hz - o.z) / d.z;
                let p = o + t * d;
                if p.x * p.x + p.y * p.y <= r2 {
                    take(t, DVec3::new(0.0, 0.0, side));
                }
            }
        }
        best.map(|(t, n)| (t, (self.rotation * n).normalize()))
    }

    /// The world box holding the solid.
    fn bounds(&self) -> (DVec3, DVec3) {
        let extent = match self.half_height {
            None => DVec3::splat(self.radius),
            // Per world axis: the disk's reach r·√(1 − a²) plus the axis's, |a|·hz.
            Some(hz) => {
                let a = self.rotation.z_axis;
                let disk = (DVec3::ONE - a * a).max(DVec3::ZERO);
                DVec3::new(disk.x.sqrt(), disk.y.sqrt(), disk.z.sqrt()) * self.radius + a.abs() * hz
            }
        };
        (self.centre - extent, self.centre + extent)
    }
}

const LEAF_SIZE: usize = 4;
const BINS: usize = 16;

/// A world-frame mesh of a surface, with per-vertex texture coordinates when it is textured.
pub type UvMesh = (SurfaceId, TriMesh, Option<Vec<[f32; 2]>>);

/// An object's world-frame mesh given to [`Bvh::of_model_with`], with its per-vertex UVs.
pub type GivenMesh = (TriMesh, Option<Vec<[f32; 2]>>);

impl Bvh {
    /// Tessellate every object and target of the model and build the BVH (no textures: what
    /// occlusion tests need). glTF paths are resolved against the directory of `model.source`.
    pub fn of_model(model: &Model) -> Result<Bvh, String> {
        Bvh::of_model_with(model, Vec::new(), false)
    }

    /// [`Bvh::of_model`], with object `i`'s world-frame mesh and its UVs taken from `given[i]`
    /// where that is `Some` (a baked or mapped texture's mesh: the same triangles, vertices
    /// split at UV seams), and each triangle's index in its mesh kept when `keep_source`.
    pub fn of_model_with(
        model: &Model,
        mut given: Vec<Option<GivenMesh>>,
        keep_source: bool,
    ) -> Result<Bvh, String> {
        let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
        given.resize_with(model.objects.len(), || None);
        let mut meshes = Vec::new();
        let mut solids = Vec::new();
        for ((i, o), g) in model.objects.iter().enumerate().zip(given) {
            let (mesh, uv) = match g {
                Some(m) => m,
                None => {
                    if let Some(s) = Solid::of(o, i) {
                        solids.push(s);
                        continue;
                    }
                    (object_mesh(o, base)?, None)
                }
            };
            meshes.push((SurfaceId::Object(i as u32), mesh, uv));
        }
        for (i, t) in model.targets.iter().enumerate() {
            meshes.push((SurfaceId::Target(i as u32), target_mesh(t), None));
        }
        let mut s = Bvh::build(meshes, keep_source);
        s.solids = solids;
        Ok(s)
    }

    /// Build from world-frame meshes.
    pub fn from_meshes(meshes: Vec<(SurfaceId, TriMesh)>) -> Bvh {
        Bvh::from_meshes_uv(meshes.into_iter().map(|(id, m)| (id, m, None)).collect())
    }

    /// Build from world-frame meshes, some with per-vertex texture coordinates.
    pub fn from_meshes_uv(meshes: Vec<UvMesh>) -> Bvh {
        Bvh::build(meshes, false)
    }

    /// [`Bvh::from_meshes_uv`], keeping each triangle's index in its mesh when `keep_source`.
    fn build(meshes: Vec<UvMesh>, keep_source: bool) -> Bvh {
        Bvh::build_with(meshes, keep_source, true)
    }

    /// [`Bvh::build`]; `lazy`: large ranges' subtrees are built on first use ([`LAZY_MAX`]).
    fn build_with(meshes: Vec<UvMesh>, keep_source: bool, lazy: bool) -> Bvh {
        // Sized once: a 5 M-triangle mesh would otherwise double its way up to 8 M slots.
        let n: usize = meshes.iter().map(|m| m.1.triangles.len()).sum();
        let any_uv = meshes.iter().any(|m| m.2.is_some());
        let mut tris = Vec::with_capacity(n);
        let mut surface = Vec::with_capacity(n);
        let mut uvs = Vec::with_capacity(if any_uv { n } else { 0 });
        let mut source = Vec::with_capacity(if keep_source { n } else { 0 });
        for (id, m, uv) in &meshes {
            for (k, t) in m.triangles.iter().enumerate() {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let e1 = b - a;
                let e2 = c - a;
                if e1.cross(e2).length_squared() == 0.0 {
                    continue; // degenerate: never hit
                }
                tris.push(Tri { v0: a, e1, e2 });
                surface.push(*id);
                if keep_source {
                    source.push(k as u32);
                }
                if any_uv {
                    uvs.push(match uv {
                        Some(uv) => t.map(|i| uv[i as usize]),
                        None => [[0.0; 2]; 3],
                    });
                }
            }
        }
        drop(meshes);
        let mut s = Bvh {
            tris,
            surface,
            uv: uvs,
            source,
            nodes: Vec::new(),
            lazy: Vec::new(),
            solids: Vec::new(),
        };
        s.build_bvh(lazy);
        s
    }

    /// Barycentric weights of a hit's point on its triangle's corners (`[1, 0, 0]` for a
    /// degenerate triangle).
    pub fn barycentric(&self, h: &Hit) -> [f64; 3] {
        let Some(t) = self.tris.get(h.triangle as usize) else {
            return [1.0, 0.0, 0.0];
        };
        let d = h.point - t.v0;
        let (d11, d12, d22) = (t.e1.dot(t.e1), t.e1.dot(t.e2), t.e2.dot(t.e2));
        let (r1, r2) = (d.dot(t.e1), d.dot(t.e2));
        let den = d11 * d22 - d12 * d12;
        if den.is_nan() || den <= 0.0 {
            return [1.0, 0.0, 0.0];
        }
        let b1 = (d22 * r1 - d12 * r2) / den;
        let b2 = (d11 * r2 - d12 * r1) / den;
        [1.0 - b1 - b2, b1, b2]
    }

    /// Texture coordinates at a hit (barycentric interpolation of the triangle's corner UVs);
    /// `None` when the scene has none.
    pub fn uv_at(&self, h: &Hit) -> Option<[f64; 2]> {
        let uv = self.uv.get(h.triangle as usize)?;
        let w = self.barycentric(h);
        let f = |k: usize| w[0] * uv[0][k] as f64 + w[1] * uv[1][k] as f64 + w[2] * uv[2][k] as f64;
        Some([f(0), f(1)])
    }

    /// The index of a hit's triangle in its object's mesh, when the BVH keeps them
    /// ([`Bvh::of_model_with`] with `keep_source`).
    pub fn source_of(&self, h: &Hit) -> Option<u32> {
        self.source.get(h.triangle as usize).copied()
    }

    /// Number of (non-degenerate) triangles.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Bounds of all geometry (`None` when empty).
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let tris = self
            .nodes
            .first()
            .filter(|_| !self.tris.is_empty())
            .map(|n| {
                let f = |v: Vec3A| DVec3::new(v.x as f64, v.y as f64, v.z as f64);
                (f(n.lo), f(n.hi))
            });
        self.solids.iter().fold(tris, |b, s| {
            let (lo, hi) = s.bounds();
            Some(b.map_or((lo, hi), |(a, z)| (a.min(lo), z.max(hi))))
        })
    }

    fn build_bvh(&mut self, lazy: bool) {
        use rayon::prelude::*;
        let n = self.tris.len();
        if n == 0 {
            return;
        }
        let lazy = lazy && n > LAZY_ABOVE;
        let bounds: Vec<(DVec3, DVec3)> = self.tris.par_iter().map(Tri::bounds).collect();
        let cent: Vec<DVec3> = bounds.par_iter().map(|(l, h)| 0.5 * (*l + *h)).collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut scratch = vec![0u32; n];
        let nodes = Builder {
            bounds: &bounds,
            cent: &cent,
            lazy,
        }
        .subtree(&mut order, &mut scratch, 0, 0);
        // The per-triangle boxes are done with: free them before the triangles are copied.
        drop((bounds, cent, scratch));
        let tris = &self.tris;
        self.tris = order.par_iter().map(|&i| tris[i as usize]).collect();
        let surface = &self.surface;
        self.surface = order.par_iter().map(|&i| surface[i as usize]).collect();
        if !self.uv.is_empty() {
            let uv = &self.uv;
            self.uv = order.par_iter().map(|&i| uv[i as usize]).collect();
        }
        if !self.source.is_empty() {
            let source = &self.source;
            self.source = order.par_iter().map(|&i| source[i as usize]).collect();
        }
        self.nodes = nodes.par_iter().map(FNode::from_node).collect();
        // Lazy ranges, numbered in node order.
        for node in self.nodes.iter_mut().filter(|n| n.count & LAZY != 0) {
            self.lazy.push(Lazy {
                start: node.start,
                count: node.count & !LAZY,
                tree: std::sync::OnceLock::new(),
            });
            node.start = self.lazy.len() as u32 - 1;
        }
    }

    /// The subtree of lazy range `i`, built on first use: what the whole build would have
    /// built there (one thread, the same decisions on the same triangles in the same order).
    fn sub(&self, i: u32) -> &Sub {
        let l = &self.lazy[i as usize];
        l.tree.get_or_init(|| {
            let range = l.start as usize..(l.start + l.count) as usize;
            let tris = &self.tris[range.clone()];
            let bounds: Vec<(DVec3, DVec3)> = tris.iter().map(Tri::bounds).collect();
            let cent: Vec<DVec3> = bounds.iter().map(|(l, h)| 0.5 * (*l + *h)).collect();
            let mut order: Vec<u32> = (0..tris.len() as u32).collect();
            let mut scratch = vec![0u32; tris.len()];
            let nodes = Builder {
                bounds: &bounds,
                cent: &cent,
                lazy: false,
            }
            .serial(&mut order, &mut scratch, 0);
            Sub {
                nodes: nodes.iter().map(FNode::from_node).collect(),
                tris: order.iter().map(|&k| tris[k as usize]).collect(),
                ids: order.iter().map(|&k| l.start + k).collect(),
            }
        })
    }

    #[inline]
    fn slab(n: &FNode, o: Vec3A, inv: Vec3A, tmax: f32) -> Option<f32> {
        let t0 = (n.lo - o) * inv;
        let t1 = (n.hi - o) * inv;
        let enter = t0.min(t1).max_element().max(0.0);
        let exit = t0.max(t1).min_element().min(tmax);
        (enter <= exit).then_some(enter)
    }

    #[inline]
    fn hit_tri(t: &Tri, o: DVec3, d: DVec3, tmax: f64) -> Option<f64> {
        let p = d.cross(t.e2);
        let det = t.e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - t.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(t.e1);
        let v = d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let tt = t.e2.dot(q) * inv;
        (tt > RAY_EPSILON && tt < tmax).then_some(tt)
    }

    /// Walk the BVH; `any` stops at the first hit.
    fn traverse(&self, ray: &Ray, tmax: f64, any: bool) -> Option<(f64, u32)> {
        if self.tris.is_empty() || tmax.is_nan() || tmax <= RAY_EPSILON {
            return None;
        }
        let o = ray.origin;
        let d = ray.dir;
        let o32 = Vec3A::new(o.x as f32, o.y as f32, o.z as f32);
        let inv = Vec3A::ONE / Vec3A::new(d.x as f32, d.y as f32, d.z as f32);
        let t32 = |t: f64| {
            if t.is_finite() {
                (t * (1.0 + 1e-5)) as f32
            } else {
                f32::INFINITY
            }
        };
        // Most rays of a path tracer (shadow rays in open water) miss the root box: that test
        // comes before anything else, the stack included.
        Self::slab(&self.nodes[0], o32, inv, t32(tmax))?;
        self.walk(o, d, o32, inv, tmax, any)
    }

    /// [`Bvh::traverse`] below the root, whose box the ray enters.
    fn walk(
        &self,
        o: DVec3,
        d: DVec3,
        o32: Vec3A,
        inv: Vec3A,
        tmax: f64,
        any: bool,
    ) -> Option<(f64, u32)> {
        // One stack for the walk and the lazy subtrees' walks within it (each takes the part
        // above its caller's entries), zeroed once per ray.
        let mut stack = [0u32; 160];
        let ray = (o, d, o32, inv);
        self.walk_in(&self.nodes, &self.tris, None, ray, tmax, any, &mut stack)
    }

    /// Walk the tree `nodes` over `tris` from its root; `ids` maps a subtree's triangles to
    /// [`Bvh::tris`] (`None`: the top tree, whose lazy ranges are walked as they are met).
    #[allow(clippy::too_many_arguments)]
    fn walk_in(
        &self,
        nodes: &[FNode],
        tris: &[Tri],
        ids: Option<&[u32]>,
        ray: (DVec3, DVec3, Vec3A, Vec3A),
        mut tmax: f64,
        any: bool,
        stack: &mut [u32],
    ) -> Option<(f64, u32)> {
        let (o, d, o32, inv) = ray;
        let t32 = |t: f64| {
            if t.is_finite() {
                (t * (1.0 + 1e-5)) as f32
            } else {
                f32::INFINITY
            }
        };
        let mut best: Option<(f64, u32)> = None;
        let mut sp = 0usize;
        let mut cur = 0u32;
        loop {
            let n = &nodes[cur as usize];
            if n.count & LAZY != 0 {
                let sub = self.sub(n.start);
                let above = &mut stack[sp..];
                if let Some(h) =
                    self.walk_in(&sub.nodes, &sub.tris, Some(&sub.ids), ray, tmax, any, above)
                {
                    tmax = h.0;
                    best = Some(h);
                    if any {
                        return best;
                    }
                }
            } else if n.count > 0 {
                for k in n.start..n.start + n.count {
                    if let Some(t) = Self::hit_tri(&tris[k as usize], o, d, tmax) {
                        tmax = t;
                        best = Some((t, ids.map_or(k, |ids| ids[k as usize])));
                        if any {
                            return best;
                        }
                    }
                }
            } else {
                let (a, b) = (n.start, n.start + 1);
                let tm = t32(tmax);
                let ta = Self::slab(&nodes[a as usize], o32, inv, tm);
                let tb = Self::slab(&nodes[b as usize], o32, inv, tm);
                match (ta, tb) {
                    (Some(x), Some(y)) => {
                        let (near, far) = if x <= y { (a, b) } else { (b, a) };
                        if sp < stack.len() {
                            stack[sp] = far;
                            sp += 1;
                        }
                        cur = near;
                        continue;
                    }
                    (Some(_), None) => {
                        cur = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        cur = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node still in front of the current closest hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let c = stack[sp];
                if Self::slab(&nodes[c as usize], o32, inv, t32(tmax)).is_some() {
                    cur = c;
                    break;
                }
            }
        }
    }

    /// Closest hit with `t ∈ (RAY_EPSILON, tmax)`.
    pub fn intersect(&self, ray: &Ray, tmax: f64) -> Option<Hit> {
        let tri = self.traverse(ray, tmax, false);
        let t_tri = tri.map_or(tmax, |(t, _)| t);
        let mut solid: Option<(f64, DVec3, SurfaceId)> = None;
        for s in &self.solids {
            if let Some((t, n)) = s.hit(ray, solid.map_or(t_tri, |h| h.0)) {
                solid = Some((t, n, s.surface));
            }
        }
        if let Some((t, normal, surface)) = solid {
            return Some(Hit {
                t,
                point: ray.origin + t * ray.dir,
                normal,
                triangle: NO_TRIANGLE,
                surface,
            });
        }
        let (t, k) = tri?;
        let tri = &self.tris[k as usize];
        Some(Hit {
            t,
            point: ray.origin + t * ray.dir,
            normal: tri.e1.cross(tri.e2).normalize(),
            triangle: k,
            surface: self.surface[k as usize],
        })
    }

    /// Whether anything is hit along `ray` with `t ∈ (RAY_EPSILON, tmax)`.
    pub fn occluded_ray(&self, ray: &Ray, tmax: f64) -> bool {
        self.solids.iter().any(|s| s.hit(ray, tmax).is_some())
            || self.traverse(ray, tmax, true).is_some()
    }

    /// Whether anything blocks the open segment between `a` and `b` (both ends excluded by a
    /// relative margin, so surfaces the points lie on do not count).
    pub fn occluded(&self, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let len = d.length();
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        let margin = 1e-6 * (1.0 + a.abs().max_element().max(b.abs().max_element())) / len;
        self.occluded_ray(
            &Ray {
                origin: a + d * margin,
                dir: d,
            },
            1.0 - 2.0 * margin,
        )
    }
}

/// Ranges of at least this many triangles build their two halves in parallel (above that, down
/// to [`PARALLEL_DEPTH`] levels).
const PARALLEL_MIN: usize = 1 << 16;
/// Deepest level split in parallel: 2^6 subtrees keep two cores busy whatever the SAH's
/// imbalance; each level copies the nodes below it once.
const PARALLEL_DEPTH: u32 = 6;

/// What the binned SAH decides for one node's range (the range is reordered in place).
enum Decision {
    Leaf,
    /// Split after this many triangles of the range.
    Split(usize),
}

/// The BVH builder over the per-triangle boxes and centroids.
///
/// Deterministic, and the same tree at any thread count: a subtree is the nodes the serial
/// depth-first build allocates for it (its root at index 0, then each split's two children
/// appended, left subtree first), so two halves built in parallel are joined by shifting
/// their child indices.
struct Builder<'a> {
    bounds: &'a [(DVec3, DVec3)],
    cent: &'a [DVec3],
    /// Ranges within [`LAZY_LEAST`]..=[`LAZY_MAX`] become lazy nodes (their boxes only).
    lazy: bool,
}

impl Builder<'_> {
    /// The nodes of the subtree over `order` (the triangles `base..base + order.len()` of the
    /// final order), its root first.
    fn subtree(
        &self,
        order: &mut [u32],
        scratch: &mut [u32],
        base: usize,
        depth: u32,
    ) -> Vec<Node> {
        if self.is_lazy(order.len()) {
            let (lo, hi) = self.bounds_of(order);
            return vec![lazy_node(lo, hi, base, order.len())];
        }
        if order.len() < PARALLEL_MIN || depth >= PARALLEL_DEPTH {
            return self.serial(order, scratch, base);
        }
        let (lo, hi, decision) = self.decide(order, scratch);
        let mid = match decision {
            Decision::Leaf => return vec![leaf(lo, hi, base, order.len())],
            Decision::Split(mid) => mid,
        };
        let (ol, or) = order.split_at_mut(mid);
        let (sl, sr) = scratch.split_at_mut(mid);
        let (left, right) = rayon::join(
            || self.subtree(ol, sl, base, depth + 1),
            || self.subtree(or, sr, base + mid, depth + 1),
        );
        // Layout: the root, its children at 1 and 2, the left child's descendants from 3, then
        // the right child's.
        let nl = left.len() as u32;
        let shift = |by: u32| {
            move |n: &Node| Node {
                start: if n.count == 0 { n.start + by } else { n.start },
                ..*n
            }
        };
        let (sl, sr) = (shift(2), shift(nl + 1));
        let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
        nodes.push(Node {
            lo,
            hi,
            start: 1,
            count: 0,
        });
        nodes.push(sl(&left[0]));
        nodes.push(sr(&right[0]));
        nodes.extend(left[1..].iter().map(sl));
        drop(left);
        nodes.extend(right[1..].iter().map(sr));
        nodes
    }

    /// [`Builder::subtree`] on one thread: depth first, left child first.
    fn serial(&self, order: &mut [u32], scratch: &mut [u32], base: usize) -> Vec<Node> {
        let mut nodes = Vec::with_capacity(2 * order.len() / LEAF_SIZE + 1);
        nodes.push(leaf(DVec3::ZERO, DVec3::ZERO, 0, 0));
        // Explicit stack: (node index, range start, range end) within `order`.
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, s, e)) = stack.pop() {
            if self.is_lazy(e - s) {
                let (lo, hi) = self.bounds_of(&order[s..e]);
                nodes[ni] = lazy_node(lo, hi, base + s, e - s);
                continue;
            }
            let (lo, hi, decision) = self.decide(&mut order[s..e], &mut scratch[s..e]);
            match decision {
                Decision::Leaf => nodes[ni] = leaf(lo, hi, base + s, e - s),
                Decision::Split(mid) => {
                    let l = nodes.len();
                    nodes.push(leaf(lo, hi, 0, 0));
                    nodes.push(leaf(lo, hi, 0, 0));
                    nodes[ni] = Node {
                        lo,
                        hi,
                        start: l as u32,
                        count: 0,
                    };
                    stack.push((l + 1, s + mid, e));
                    stack.push((l, s, s + mid));
                }
            }
        }
        nodes
    }

    fn is_lazy(&self, count: usize) -> bool {
        self.lazy && (LAZY_LEAST + 1..=LAZY_MAX).contains(&count)
    }

    /// The box of `order`'s triangles (as [`Builder::decide`] computes it).
    fn bounds_of(&self, order: &[u32]) -> (DVec3, DVec3) {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in order {
            let (l, h) = self.bounds[i as usize];
            lo = lo.min(l);
            hi = hi.max(h);
        }
        (lo, hi)
    }

    /// The bounds of `order`'s triangles and the binned SAH's decision; a split reorders
    /// `order` (stable: each side keeps its order), with `scratch` as room.
    fn decide(&self, order: &mut [u32], scratch: &mut [u32]) -> (DVec3, DVec3, Decision) {
        let (bounds, cent) = (self.bounds, self.cent);
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in order.iter() {
            let (l, h) = bounds[i as usize];
            lo = lo.min(l);
            hi = hi.max(h);
            clo = clo.min(cent[i as usize]);
            chi = chi.max(cent[i as usize]);
        }
        let count = order.len();
        if count <= LEAF_SIZE {
            return (lo, hi, Decision::Leaf);
        }
        // Binned SAH over the widest centroid axis.
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        if ext[axis] <= 0.0 {
            // All centroids coincide: split in the middle of the list.
            return (lo, hi, Decision::Split(count / 2));
        }
        let bin_of =
            |c: DVec3| (((c[axis] - clo[axis]) / ext[axis] * BINS as f64) as usize).min(BINS - 1);
        let mut bcount = [0usize; BINS];
        let mut blo = [DVec3::INFINITY; BINS];
        let mut bhi = [DVec3::NEG_INFINITY; BINS];
        for &i in order.iter() {
            let b = bin_of(cent[i as usize]);
            bcount[b] += 1;
            blo[b] = blo[b].min(bounds[i as usize].0);
            bhi[b] = bhi[b].max(bounds[i as usize].1);
        }
        let area = |l: DVec3, h: DVec3| {
            let d = (h - l).max(DVec3::ZERO);
            d.x * d.y + d.y * d.z + d.z * d.x
        };
        // Prefix/suffix sweeps.
        let mut left_area = [0.0; BINS];
        let mut left_n = [0usize; BINS];
        let (mut l, mut h, mut c) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
        for b in 0..BINS {
            l = l.min(blo[b]);
            h = h.max(bhi[b]);
            c += bcount[b];
            left_area[b] = if c > 0 { area(l, h) } else { 0.0 };
            left_n[b] = c;
        }
        let (mut best, mut best_cost) = (usize::MAX, f64::INFINITY);
        let (mut l, mut h, mut c) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
        for b in (1..BINS).rev() {
            l = l.min(blo[b]);
            h = h.max(bhi[b]);
            c += bcount[b];
            let cost = left_area[b - 1] * left_n[b - 1] as f64 + area(l, h) * c as f64;
            if left_n[b - 1] > 0 && c > 0 && cost < best_cost {
                best_cost = cost;
                best = b;
            }
        }
        let leaf_cost = area(lo, hi) * count as f64;
        if best != usize::MAX && best_cost >= leaf_cost && count <= 4 * LEAF_SIZE {
            return (lo, hi, Decision::Leaf);
        }
        if best == usize::MAX {
            // Cannot separate by bins: median split along the axis.
            order.sort_by(|&a, &b| {
                cent[a as usize][axis]
                    .total_cmp(&cent[b as usize][axis])
                    .then(a.cmp(&b))
            });
            return (lo, hi, Decision::Split(count / 2));
        }
        // Partition, stable: the left side's count is known from the bins.
        let mid = left_n[best - 1];
        let (mut nl, mut nr) = (0, mid);
        for &i in order.iter() {
            if bin_of(cent[i as usize]) < best {
                scratch[nl] = i;
                nl += 1;
            } else {
                scratch[nr] = i;
                nr += 1;
            }
        }
        order.copy_from_slice(scratch);
        (lo, hi, Decision::Split(mid))
    }
}

/// A lazy node over the triangles `start..start + count` ([`LAZY`]).
fn lazy_node(lo: DVec3, hi: DVec3, start: usize, count: usize) -> Node {
    Node {
        lo,
        hi,
        start: start as u32,
        count: count as u32 | LAZY,
    }
}

/// A leaf over the triangles `start..start + count` (a placeholder with `count` 0).
fn leaf(lo: DVec3, hi: DVec3, start: usize, count: usize) -> Node {
    Node {
        lo,
        hi,
        start: start as u32,
        count: count as u32,
    }
}

/// A target's printed face as a plane mesh in the world frame (its extent from
/// [`crate::geometry::targets`]).
pub fn target_mesh(target: &crate::model::Target) -> TriMesh {
    if let crate::model::TargetKind::TestObject {
        size, levels, step, ..
    } = target.kind
    {
        // Staircase pyramid: step k is a box of the step's top side from z = k·step up.
        let mut m = TriMesh::default();
        for k in 0..levels {
            let (side, top) = crate::geometry::targets::test_object_step(size, levels, step, k);
            let mut b = crate::geometry::mesh::cuboid(DVec3::new(side, side, step));
            for p in &mut b.positions {
                p.z += top - 0.5 * step;
            }
            m.append(&b);
        }
        return m.transformed(&target.pose, DVec3::ONE);
    }
    let (w, h) = target_extent(target);
    crate::geometry::mesh::plane(w, h).transformed(&target.pose, DVec3::ONE)
}

/// Printed reflectance at (x, y) of the target frame (grey, all channels).
pub fn target_reflectance(kind: &crate::model::TargetKind, x: f64, y: f64) -> f64 {
    crate::geometry::targets::reflectance(kind, x, y)
}

/// Width and height (target x, y) of a target's printed face, m.
pub fn target_extent(target: &crate::model::Target) -> (f64, f64) {
    crate::geometry::targets::extent(&target.kind)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh;

    /// Deterministic uniform numbers in [0, 1) from `seed`.
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut h = seed;
        move || {
            h = crate::noise::mix64(h);
            (h >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn brute(meshes: &[(SurfaceId, TriMesh)], ray: &Ray) -> Option<f64> {
        let mut best: Option<f64> = None;
        for (_, m) in meshes {
            for t in &m.triangles {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let tri = Tri {
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                };
                if let Some(t) = Bvh::hit_tri(&tri, ray.origin, ray.dir, f64::INFINITY)
                    && best.is_none_or(|b| t < b)
                {
                    best = Some(t);
                }
            }
        }
        best
    }

    #[test]
    fn bvh_matches_brute_force() {
        let meshes = vec![
            (SurfaceId::Object(0), mesh::boulders(4.0, 4.0, 40, 0.3, 1)),
            (
                SurfaceId::Object(1),
                mesh::seabed(6.0, 6.0, 0.1, 0.2, 2, None).unwrap(),
            ),
        ];
        let scene = Bvh::from_meshes(meshes.clone());
        let mut rnd = uniform(12345);
        for _ in 0..400 {
            let o = DVec3::new(rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0, 2.0);
            let d = DVec3::new(rnd() - 0.5, rnd() - 0.5, -1.0).normalize();
            let ray = Ray { origin: o, dir: d };
            let a = scene.intersect(&ray, f64::INFINITY).map(|h| h.t);
            let b = brute(&meshes, &ray);
            match (a, b) {
                (Some(x), Some(y)) => assert!((x - y).abs() < 1e-12, "{x} {y}"),
                (None, None) => {}
                other => panic!("mismatch {other:?}"),
            }
            if let Some(t) = a {
                assert!(scene.occluded(o, o + d * (t + 0.01)));
                assert!(!scene.occluded(o, o + d * (t - 0.01)));
            }
        }
    }

    #[test]
    fn plane_hit_point_and_normal() {
        let s = Bvh::from_meshes(vec![(SurfaceId::Target(3), mesh::plane(2.0, 2.0))]);
        let h = s
            .intersect(
                &Ray {
                    origin: DVec3::new(0.2, 0.3, 5.0),
                    dir: -DVec3::Z,
                },
                100.0,
            )
            .unwrap();
        assert!((h.t - 5.0).abs() < 1e-12);
        assert_eq!(h.normal, DVec3::Z);
        assert_eq!(h.surface, SurfaceId::Target(3));
        assert!(
            s.intersect(
                &Ray {
                    origin: DVec3::new(1.2, 0.0, 5.0),
                    dir: -DVec3::Z
                },
                1e9
            )
            .is_none()
        );
    }

    /// A digest of the tree (nodes and triangle order), to compare builds.
    fn digest(b: &Bvh) -> u64 {
        let mut h = 0u64;
        let mut eat = |x: u64| h = crate::noise::mix64(h ^ x);
        for n in &b.nodes {
            for v in [n.lo.x, n.lo.y, n.lo.z, n.hi.x, n.hi.y, n.hi.z] {
                eat(v.to_bits() as u64);
            }
            eat(((n.start as u64) << 32) | n.count as u64);
        }
        for t in &b.tris {
            for v in [t.v0.x, t.v0.y, t.v0.z, t.e1.x, t.e2.z] {
                eat(v.to_bits());
            }
        }
        h
    }

    impl Bvh {
        /// The whole tree up front (no lazy ranges).
        fn eager(meshes: Vec<(SurfaceId, TriMesh)>) -> Bvh {
            Bvh::build_with(
                meshes.into_iter().map(|(id, m)| (id, m, None)).collect(),
                false,
                false,
            )
        }
    }

    /// Lazy ranges ([`LAZY_MAX`]) give every hit the whole build gives: the same distance,
    /// the same triangle (by its corners and surface) and the same occlusion, from any thread.
    #[test]
    fn lazy_subtrees_hit_what_the_whole_tree_hits() {
        let eager = Bvh::eager(large());
        let lazy = Bvh::from_meshes(large());
        assert!(eager.lazy.is_empty());
        assert!(lazy.lazy.len() > 10, "{} lazy ranges", lazy.lazy.len());
        assert!(lazy.nodes.len() < eager.nodes.len() / 4);
        let rays: Vec<Ray> = {
            let mut rnd = uniform(4242);
            (0..20_000)
                .map(|i| {
                    let o = DVec3::new(rnd() * 10.0 - 5.0, rnd() * 10.0 - 5.0, rnd() * 2.0 - 0.5);
                    // Down, grazing and up: every kind of ray a render casts.
                    let dz = [-1.0, -0.05, 0.3][i % 3];
                    let d = DVec3::new(rnd() - 0.5, rnd() - 0.5, dz).normalize();
                    Ray { origin: o, dir: d }
                })
                .collect()
        };
        let key = |b: &Bvh, h: Option<Hit>| {
            h.map(|h| {
                let t = &b.tris[h.triangle as usize];
                (
                    h.t.to_bits(),
                    [t.v0, t.e1, t.e2].map(|v| v.to_array().map(f64::to_bits)),
                    h.surface,
                )
            })
        };
        use rayon::prelude::*;
        let hits: Vec<_> = rays
            .par_iter()
            .map(|r| key(&lazy, lazy.intersect(r, f64::INFINITY)))
            .collect();
        let mut seen = 0;
        for (r, got) in rays.iter().zip(hits) {
            let want = key(&eager, eager.intersect(r, f64::INFINITY));
            seen += want.is_some() as usize;
            assert_eq!(got, want, "{r:?}");
            assert_eq!(
                lazy.occluded_ray(r, 3.0),
                eager.occluded_ray(r, 3.0),
                "{r:?}"
            );
        }
        assert!(seen > 5_000, "{seen} hits");
        // Rays from above an 8 m patch reach most ranges; one ray reaches few.
        let built = lazy.lazy.iter().filter(|l| l.tree.get().is_some()).count();
        assert!(built > 0, "{built} of {} built", lazy.lazy.len());
        let fresh = Bvh::from_meshes(large());
        assert!(fresh.intersect(&rays[0], f64::INFINITY).is_some());
        let one = fresh.lazy.iter().filter(|l| l.tree.get().is_some()).count();
        assert!(
            one <= 4,
            "one ray built {one} of {} ranges",
            fresh.lazy.len()
        );
    }

    /// A large mesh with every case of the builder: SAH splits, coincident centroids (a
    /// stack of copies of one triangle) and bins that cannot separate.
    fn large() -> Vec<(SurfaceId, TriMesh)> {
        let mut stack = mesh::plane(0.01, 0.01);
        for _ in 0..6 {
            let c = stack.clone();
            stack.append(&c);
        }
        vec![
            (
                SurfaceId::Object(0),
                mesh::seabed(8.0, 8.0, 0.05, 0.02, 3, None).unwrap(),
            ),
            (SurfaceId::Object(1), mesh::boulders(6.0, 6.0, 300, 0.2, 4)),
            (SurfaceId::Target(0), stack),
        ]
    }

    /// The parallel build gives the tree of the serial one, at any thread count: the digest is
    /// that of the one-thread depth-first builder this replaced (so renders keep their bytes).
    #[test]
    fn parallel_build_is_the_serial_tree() {
        let build = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| Bvh::eager(large()))
        };
        let (one, four) = (build(1), build(4));
        assert_eq!((one.nodes.len(), one.tris.len()), (424_923, 704_128));
        assert_eq!(digest(&one), 0xec53_2b1f_3e60_94a4);
        assert_eq!(digest(&four), digest(&one));
        // And it finds what brute force finds.
        let meshes = large();
        let mut rnd = uniform(777);
        for _ in 0..50 {
            let o = DVec3::new(rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0, 2.0);
            let d = DVec3::new(rnd() - 0.5, rnd() - 0.5, -1.0).normalize();
            let ray = Ray { origin: o, dir: d };
            let a = four.intersect(&ray, f64::INFINITY).map(|h| h.t);
            assert_eq!(a, brute(&meshes, &ray));
        }
    }
}
