//! Baking a textured object into one triangle mesh with per-vertex UVs and one RGB image that
//! all three backends use: the native renderer samples it with [`Texture::sample`], Mitsuba
//! with a `bitmap` texture (bilinear, clamp, raw), Cycles with an Image Texture node (Linear,
//! Extend, Non-Color). The three agree because they sample the same 8-bit texels with the same
//! convention: texel (i, j) is centred at UV ((i + ½)/W, (j + ½)/H), bilinear between the four
//! nearest centres, edge texels repeated outside; row 0 of the image is v = 0 (Mitsuba's and
//! poser's convention; Blender's v runs the other way, so its PLY gets t = 1 - v).
//!
//! | step | what |
//! |---|---|
//! | charts | planes and seabeds: one planar chart (object x, y). Other shapes: every triangle goes to the chart of its dominant normal axis and sign (triplanar), per part (each rock of a boulder field is a part); vertices are duplicated where charts meet |
//! | texel | the material's `texel`, else half the finest ground sample distance of any camera at any pose on the object's bounding box (`distance / (fx · n)`, n the largest ambient index: water magnifies through a flat port); [`FALLBACK_TEXEL`] without poses |
//! | atlas | charts (plus a [`MARGIN`]-texel border baked from the same formula) shelf-packed; when a side would exceed [`MAX_SIDE`] the texel is coarsened until it fits, and the result says so |
//! | budget | all baked textures of a scene together hold at most [`TEXEL_BUDGET`] texels: when they would hold more, every object whose texel the scene does not set is coarsened by one common factor ([`scene_plan`]), and the result says so and by how much |
//! | texels | the pattern ([`super::albedo`]) × the part's colour variation at each texel centre, clamped to [0, 1], stored as linear 8-bit (value × 255, rounded) |
//!
//! Pattern coordinates are the chart's projected object-frame coordinates in metres (after
//! scale); the planar chart uses the object's own x, y, so a seabed's texture is fixed to it.
//! Baking is parallel over rows and deterministic; results are cached by content.

use super::{At, albedo, hash2, mix64, name_hash, unit, variation};
use crate::geometry::mesh::TriMesh;
use crate::model::{Model, Object, Pattern, Shape};
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex, Weak};

/// Largest side of a baked texture, texels.
pub const MAX_SIDE: u32 = 8192;
/// Most texels of all baked textures of one scene together (16 Mi = 4096², 48 MiB of 8-bit
/// RGB): bakes in a few seconds and keeps compiled scenes small.
pub const TEXEL_BUDGET: u64 = 1 << 24;
/// Border of every chart, texels (bilinear filtering reads one).
pub const MARGIN: u32 = 2;
/// Deepest mip level of an atlas of several charts ([`super::mip`]): level 1's boxes (2
/// texels) stay within the charts' [`MARGIN`] of baked border, so a filtered lookup near a
/// chart's edge reads (almost) only its own chart. A single chart has no cap.
pub const ATLAS_MAX_LEVEL: u32 = 1;
/// Texel size when no camera position is known, m.
pub const FALLBACK_TEXEL: f64 = 0.002;

/// An RGB image of linear albedo, 8 bits per channel, row-major from row 0 (v = 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl Texture {
    fn texel(&self, i: i64, j: i64) -> [f64; 3] {
        let i = i.clamp(0, self.width as i64 - 1) as usize;
        let j = j.clamp(0, self.height as i64 - 1) as usize;
        let k = 3 * (j * self.width as usize + i);
        [0, 1, 2].map(|c| self.rgb[k + c] as f64 / 255.0)
    }

    /// Bilinear lookup at (u, v) with texel centres at ((i + ½)/W, (j + ½)/H) and clamped edges:
    /// Mitsuba's `bitmap` (`filter_type = bilinear`, `wrap_mode = clamp`) and Cycles' Image
    /// Texture (`Linear`, `EXTEND`).
    pub fn sample(&self, u: f64, v: f64) -> [f64; 3] {
        super::bilinear(self.width, self.height, u, v, |i, j| self.texel(i, j))
    }

    /// Mean of every texel, per channel.
    pub fn mean(&self) -> [f64; 3] {
        let n = (self.width as f64) * (self.height as f64);
        let mut s = [0u64; 3];
        for px in self.rgb.chunks_exact(3) {
            for c in 0..3 {
                s[c] += px[c] as u64;
            }
        }
        s.map(|v| v as f64 / 255.0 / n)
    }

    /// The image as an 8-bit RGB PNG (values are linear, not sRGB); deterministic bytes.
    pub fn png(&self) -> Result<Vec<u8>, String> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Sub,
        )
        .write_image(
            &self.rgb,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| format!("cannot encode a texture: {e}"))?;
        Ok(out)
    }
}

/// A baked object: its mesh with UVs and its texture.
#[derive(Debug, Clone)]
pub struct Baked {
    /// Object frame, before scale (same shape as [`crate::geometry::mesh::shape_mesh`], with vertices
    /// duplicated along chart seams).
    pub mesh: TriMesh,
    /// Per vertex; v = 0 at the texture's row 0.
    pub uv: Vec<[f32; 2]>,
    pub texture: Texture,
    /// Mip levels of [`Baked::texture`] for footprint-filtered lookups ([`Baked::sample_footprint`]).
    pub mips: super::mip::Pyramid,
    /// Texel size used, m.
    pub texel: f64,
    /// Texel size wanted (before the scene budget and the [`MAX_SIDE`] cap), m, and how it
    /// was chosen.
    pub wanted: f64,
    pub reason: String,
    pub charts: usize,
    /// Why the texel is coarser than wanted ("" when it is not).
    pub limit: String,
    /// Wall time of the bake, s (not part of the content).
    pub seconds: f64,
}

impl Baked {
    /// The texture at (u, v) averaged over a footprint `width` metres wide on the surface
    /// ([`super::mip::Pyramid::sample`]); [`Texture::sample`] when the footprint is below a
    /// texel (or not finite).
    pub fn sample_footprint(&self, u: f64, v: f64, width: f64) -> [f64; 3] {
        let texels = width / self.texel;
        self.mips
            .sample(u, v, texels, |u, v| self.texture.sample(u, v))
    }

    /// Whether the size cap made the texture coarser than wanted.
    pub fn coarsened(&self) -> bool {
        self.texel > self.wanted * 1.000_001
    }

    /// One line for `poser explain` and warnings.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}×{} texels of {:.2} mm in {} chart(s); {}",
            self.texture.width,
            self.texture.height,
            self.texel * 1e3,
            self.charts,
            self.reason
        );
        if self.coarsened() {
            s.push_str(&coarsened_note(self.wanted, self.texel, &self.limit));
        }
        s
    }
}

/// "; COARSENED ..." for a texel coarser than wanted.
fn coarsened_note(wanted: f64, texel: f64, limit: &str) -> String {
    format!(
        "; COARSENED ×{:.2} from {:.2} mm {limit}: detail at the pixel is lost (make the \
         object smaller or set `pattern.texel`)",
        texel / wanted,
        wanted * 1e3
    )
}

/// Why a texel was coarsened: the scene budget (`factor` > 1) and/or the side cap.
fn limit_text(factor: f64, texel: f64, start: f64) -> String {
    let budget = format!(
        "to fit the scene's budget of {:.1} M texels",
        TEXEL_BUDGET as f64 / 1e6
    );
    let side = format!("to fit {MAX_SIDE} texels a side");
    match (factor > 1.000_001, texel > start * 1.000_001) {
        (true, true) => format!("{budget} and {side}"),
        (true, false) => budget,
        (false, true) => side,
        (false, false) => String::new(),
    }
}

/// The texel plan of one baked object within its scene.
#[derive(Debug, Clone)]
pub struct ObjectPlan {
    /// Texel wanted, m, and how it was chosen.
    pub wanted: f64,
    pub reason: String,
    /// Texel the layout starts from: `wanted`, times the scene's budget factor unless the
    /// scene sets the texel.
    pub start: f64,
    /// Texel after the [`MAX_SIDE`] cap, m, atlas size and charts.
    pub texel: f64,
    pub width: u32,
    pub height: u32,
    pub charts: usize,
    /// Why `texel` exceeds `wanted` ("" when it does not).
    pub limit: String,
}

/// Texel plans of every object of the scene (`None` for objects that are not baked): each at
/// its wanted texel, unless their textures together would exceed [`TEXEL_BUDGET`] texels; then
/// the objects whose texel the scene does not set are all coarsened by one factor, the smallest
/// (to 1 %) that fits what the others leave (at least a quarter of the budget). Deterministic:
/// depends on the model only.
pub fn scene_plan(model: &Model) -> Result<Vec<Option<ObjectPlan>>, String> {
    let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
    struct Item {
        index: usize,
        local: TriMesh,
        scaled: Vec<DVec3>,
        per_part: usize,
        seed: u64,
        wanted: f64,
        reason: String,
        fixed: bool,
    }
    let mut items = Vec::new();
    for (index, o) in model.objects.iter().enumerate() {
        if !o.material.is_baked() {
            continue;
        }
        let local = crate::geometry::mesh::shape_mesh(&o.shape, base)
            .map_err(|e| format!("object `{}`: {e}", o.name))?;
        let (wanted, reason) = wanted_texel(model, o, local.bounds());
        let scaled = local.positions.iter().map(|&p| p * o.scale).collect();
        let (per_part, seed) = parts(o, local.triangles.len());
        items.push(Item {
            index,
            local,
            scaled,
            per_part,
            seed,
            wanted,
            reason,
            fixed: o.material.texel.is_some(),
        });
    }
    let sizes = |factor: f64| -> Vec<(f64, f64, u32, u32, usize)> {
        items
            .iter()
            .map(|it| {
                let start = if it.fixed {
                    it.wanted
                } else {
                    it.wanted * factor
                };
                let o = &model.objects[it.index];
                let (charts, _, texel, w, h) = layout(
                    o,
                    &it.local,
                    &it.scaled,
                    it.per_part,
                    it.seed,
                    start,
                    MAX_SIDE,
                );
                (start, texel, w, h, charts.len())
            })
            .collect()
    };
    let count = |v: &[(f64, f64, u32, u32, usize)], fixed: bool| -> u64 {
        v.iter()
            .zip(&items)
            .filter(|(_, it)| it.fixed == fixed)
            .map(|(s, _)| s.2 as u64 * s.3 as u64)
            .sum()
    };
    let mut factor = 1.0;
    let mut sized = sizes(factor);
    let room = TEXEL_BUDGET
        .saturating_sub(count(&sized, true))
        .max(TEXEL_BUDGET / 4);
    let mut guard = 0;
    while count(&sized, false) > room && guard < 100 {
        // Texel count goes as 1 / texel²; margins make it fall a little slower.
        let ratio = count(&sized, false) as f64 / room as f64;
        factor *= ratio.sqrt().max(1.01);
        // Round up to 1 % steps, so that small changes of a scene do not change the factor.
        factor = (factor * 100.0).ceil() / 100.0;
        sized = sizes(factor);
        guard += 1;
    }
    let mut out = vec![None; model.objects.len()];
    for (it, (start, texel, w, h, charts)) in items.iter().zip(sized) {
        let f = if it.fixed { 1.0 } else { factor };
        out[it.index] = Some(ObjectPlan {
            wanted: it.wanted,
            reason: it.reason.clone(),
            start,
            texel,
            width: w,
            height: h,
            charts,
            limit: limit_text(f, texel, start),
        });
    }
    Ok(out)
}

/// The texel wanted for an object: the material's, or half the finest ground sample distance.
pub fn wanted_texel(
    model: &Model,
    o: &Object,
    local_bounds: Option<(DVec3, DVec3)>,
) -> (f64, String) {
    if let Some(t) = o.material.texel {
        return (t, "texel set by the scene".into());
    }
    let Some((lo, hi)) = local_bounds else {
        return (FALLBACK_TEXEL, "empty mesh".into());
    };
    // World bounding box of the scaled, posed local box.
    let (mut wlo, mut whi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let w = o.pose.transform_point(c * o.scale);
        wlo = wlo.min(w);
        whi = whi.max(w);
    }
    let n = model.ambient_ior().iter().cloned().fold(1.0, f64::max);
    let mut best: Option<(f64, f64)> = None;
    for p in 0..model.poses.len() {
        for (c, cam) in model.cameras.iter().enumerate() {
            let eye = model.world_from_camera(p, c).translation;
            let d = (eye.clamp(wlo, whi) - eye).length().max(0.05);
            let gsd = d / (cam.fx.max(cam.fy) * n);
            if best.is_none_or(|(g, _)| gsd < g) {
                best = Some((gsd, d));
            }
        }
    }
    match best {
        Some((gsd, d)) => (
            0.5 * gsd,
            format!(
                "half the finest GSD ({:.2} mm at {:.2} m, water index {:.3})",
                gsd * 1e3,
                d,
                n
            ),
        ),
        None => (FALLBACK_TEXEL, "no camera position: fallback texel".into()),
    }
}

type CacheMap = HashMap<(u64, u64), Weak<Baked>>;
static CACHE: Mutex<Option<CacheMap>> = Mutex::new(None);

/// The plans of the most recent model ([`scene_plan`] of the whole model, by its content):
/// every baked object of a scene needs the same plans, and planning tessellates every baked
/// object, so a scene of several baked objects plans once, not once per object.
type PlanCache = Option<(u64, Arc<Vec<Option<ObjectPlan>>>)>;
static PLANS: Mutex<PlanCache> = Mutex::new(None);

/// [`scene_plan`]'s entry for object `index`, planned once per content of what the plans
/// depend on (the objects, the cameras and their poses, the water's index and the scene's
/// folder; not the render settings, which a benchmark's or a lesson's renders vary).
fn object_plan(model: &Model, index: usize) -> Result<Option<ObjectPlan>, String> {
    let inputs = (
        &model.source,
        &model.objects,
        &model.cameras,
        &model.poses,
        &model.water,
    );
    let json = serde_json::to_string(&inputs).map_err(|e| e.to_string())?;
    let key = name_hash(&json);
    let cached = PLANS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .as_ref()
        .filter(|(k, _)| *k == key)
        .map(|(_, p)| p.clone());
    let plans = match cached {
        Some(p) => p,
        None => {
            let p = Arc::new(scene_plan(model)?);
            *PLANS.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, p.clone()));
            p
        }
    };
    Ok(plans.get(index).cloned().flatten())
}
/// The most recent bakes, held strongly (oldest first) so that a process that compiles or
/// renders the same scene again (a test binary, the Python module, a lesson's variants, a
/// Mitsuba compile followed by a Cycles one) does not bake it again once the first user let
/// go. At most [`RECENT_TEXELS`] texels are held.
static RECENT: Mutex<std::collections::VecDeque<Arc<Baked>>> =
    Mutex::new(std::collections::VecDeque::new());
/// Texels the recent bakes may hold together: three scenes' [`TEXEL_BUDGET`] (144 MiB).
const RECENT_TEXELS: u64 = 3 * TEXEL_BUDGET;

/// Keep `b` among the recent bakes (moved to the newest end when already there).
fn hold(b: &Arc<Baked>) {
    let mut recent = RECENT.lock().unwrap_or_else(|e| e.into_inner());
    recent.retain(|r| !Arc::ptr_eq(r, b));
    recent.push_back(b.clone());
    let texels = |r: &Arc<Baked>| r.texture.width as u64 * r.texture.height as u64;
    let mut total: u64 = recent.iter().map(texels).sum();
    while total > RECENT_TEXELS && recent.len() > 1 {
        total -= recent.pop_front().as_ref().map_or(0, texels);
    }
}

/// The baked form of object `index` of the model (`None` when its material is not baked),
/// cached by content while any user holds it, and the most recent ones a while longer
/// ([`RECENT_TEXELS`]). A cached bake is the very result of baking again: the key is the
/// object's whole description, its scene file and the planned texel.
pub fn bake_object(model: &Model, index: usize) -> Result<Option<Arc<Baked>>, String> {
    let o = &model.objects[index];
    if !o.material.is_baked() {
        return Ok(None);
    }
    let Some(plan) = object_plan(model, index)? else {
        return Ok(None);
    };
    let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
    let json = serde_json::to_string(o).map_err(|e| e.to_string())?;
    let key = (
        name_hash(&json)
            ^ mix64(name_hash(&model.source))
            ^ mix64(plan.start.to_bits())
            ^ mix64(name_hash(&plan.reason) ^ mix64(name_hash(&plan.limit))),
        plan.wanted.to_bits(),
    );
    {
        let mut g = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        let map = g.get_or_insert_with(HashMap::new);
        map.retain(|_, w| w.strong_count() > 0);
        if let Some(b) = map.get(&key).and_then(Weak::upgrade) {
            drop(g);
            hold(&b);
            return Ok(Some(b));
        }
    }
    let local = crate::geometry::mesh::shape_mesh(&o.shape, base)
        .map_err(|e| format!("object `{}`: {e}", o.name))?;
    let mut b = bake_from(o, &local, plan.start, plan.reason, MAX_SIDE);
    b.wanted = plan.wanted;
    b.limit = plan.limit;
    let b = Arc::new(b);
    let mut g = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    g.get_or_insert_with(HashMap::new)
        .insert(key, Arc::downgrade(&b));
    drop(g);
    hold(&b);
    Ok(Some(b))
}

/// `y.round() as u8` for `y` in [0, 255] (or NaN), without libm's `round` call and without a
/// branch: the truncation is the floor there and `y − ⌊y⌋` is exact, so halves round up
/// exactly as `f64::round` does (NaN gives 0, as `NaN as u8`).
#[inline]
fn round_unit(y: f64) -> u8 {
    let i = y as u8;
    i + (y - i as f64 >= 0.5) as u8
}

#[derive(Debug, Clone)]
struct Chart {
    part: u32,
    /// Projection axis (0 = x, 1 = y, 2 = z).
    axis: usize,
    lo: [f64; 2],
    hi: [f64; 2],
    /// Placement in the atlas and size, texels (margins included).
    ox: u32,
    oy: u32,
    w: u32,
    h: u32,
    seed: u64,
    offset: [f64; 2],
}

fn project(p: DVec3, axis: usize) -> [f64; 2] {
    match axis {
        0 => [p.y, p.z],
        1 => [p.x, p.z],
        _ => [p.x, p.y],
    }
}

/// Shelf-pack the charts at `texel`; returns the atlas size.
fn pack(charts: &mut [Chart], texel: f64) -> (u64, u64) {
    for c in charts.iter_mut() {
        let side = |k: usize| ((c.hi[k] - c.lo[k]) / texel).ceil().max(1.0) + 2.0 * MARGIN as f64;
        c.w = side(0).min(u32::MAX as f64 / 4.0) as u32;
        c.h = side(1).min(u32::MAX as f64 / 4.0) as u32;
    }
    let area: f64 = charts.iter().map(|c| c.w as f64 * c.h as f64).sum();
    let widest = charts.iter().map(|c| c.w).max().unwrap_or(1) as u64;
    let width = widest.max(area.sqrt().ceil() as u64);
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| charts[b].h.cmp(&charts[a].h).then(a.cmp(&b)));
    let (mut x, mut y, mut shelf, mut used_w) = (0u64, 0u64, 0u64, 0u64);
    for i in order {
        let c = &mut charts[i];
        if x + c.w as u64 > width {
            y += shelf;
            x = 0;
            shelf = 0;
        }
        c.ox = x as u32;
        c.oy = y as u32;
        x += c.w as u64;
        used_w = used_w.max(x);
        shelf = shelf.max(c.h as u64);
    }
    (used_w, y + shelf)
}

/// Charts of every triangle, their packing, and the texel that fits `max_side`.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn layout(
    o: &Object,
    local: &TriMesh,
    scaled: &[DVec3],
    per_part: usize,
    object_seed: u64,
    wanted: f64,
    max_side: u32,
) -> (Vec<Chart>, Vec<usize>, f64, u32, u32) {
    let planar = matches!(o.shape, Shape::Plane { .. } | Shape::Seabed { .. });
    let ntri = local.triangles.len();
    // Charts and the new mesh (vertices duplicated per chart).
    let mut chart_of: HashMap<(u32, usize, bool), usize> = HashMap::new();
    let mut charts: Vec<Chart> = Vec::new();
    let mut tri_chart = Vec::with_capacity(ntri);
    for (k, t) in local.triangles.iter().enumerate() {
        let part = (k / per_part) as u32;
        let (axis, positive) = if planar {
            (2, true)
        } else {
            let [a, b, c] = t.map(|i| scaled[i as usize]);
            let n = (b - a).cross(c - a);
            let m = n.abs();
            let axis = if m.x >= m.y && m.x >= m.z {
                0
            } else if m.y >= m.z {
                1
            } else {
                2
            };
            (axis, n[axis] >= 0.0)
        };
        let id = *chart_of.entry((part, axis, positive)).or_insert_with(|| {
            let seed =
                mix64(object_seed ^ ((part as u64) << 3 | (axis as u64) << 1 | positive as u64));
            let offset = if axis == 2 && positive {
                [0.0, 0.0]
            } else {
                [4096.0 * unit(seed), 4096.0 * unit(mix64(seed))]
            };
            charts.push(Chart {
                part,
                axis,
                lo: [f64::INFINITY; 2],
                hi: [f64::NEG_INFINITY; 2],
                ox: 0,
                oy: 0,
                w: 0,
                h: 0,
                seed,
                offset,
            });
            charts.len() - 1
        });
        let c = &mut charts[id];
        for &i in t {
            let q = project(scaled[i as usize], axis);
            for (d, &v) in q.iter().enumerate() {
                c.lo[d] = c.lo[d].min(v);
                c.hi[d] = c.hi[d].max(v);
            }
        }
        tri_chart.push(id);
    }

    // Texel: wanted, coarsened until the atlas fits.
    let mut texel = wanted.max(1e-6);
    let (mut w, mut h) = pack(&mut charts, texel);
    let mut guard = 0;
    while (w > max_side as u64 || h > max_side as u64) && guard < 200 {
        let f = (w.max(h) as f64 / max_side as f64).max(1.0);
        texel *= f.sqrt().max(1.01);
        (w, h) = pack(&mut charts, texel);
        guard += 1;
    }
    let (w, h) = (w.max(1) as u32, h.max(1) as u32);

    (charts, tri_chart, texel, w, h)
}

/// What baking object `index` would give (texture size, texel, coarsening), without baking:
/// for `poser explain`. `None` when the object is not baked.
pub fn plan(model: &Model, index: usize) -> Result<Option<String>, String> {
    let Some(p) = object_plan(model, index)? else {
        return Ok(None);
    };
    let mut s = format!(
        "{}×{} texels of {:.2} mm in {} chart(s); {}",
        p.width,
        p.height,
        p.texel * 1e3,
        p.charts,
        p.reason
    );
    if p.texel > p.wanted * 1.000_001 {
        // Information here: the commands that render or compile the texture warn about it.
        s.push_str(&format!(
            "; coarsened ×{:.2} from {:.2} mm {}, so detail at the pixel is lost (`poser \
             render` and `compile` warn; make the object smaller or set `pattern.texel` to keep it)",
            p.texel / p.wanted,
            p.wanted * 1e3,
            p.limit
        ));
    }
    Ok(Some(s))
}

/// Triangles per part (each rock of a boulder field is one) and the object's seed.
fn parts(o: &Object, ntri: usize) -> (usize, u64) {
    let per_part = match o.shape {
        Shape::Boulders { count, .. } if count > 0 && ntri.is_multiple_of(count as usize) => {
            ntri / count as usize
        }
        _ => ntri.max(1),
    };
    let pattern_seed = match &o.material.pattern {
        Some(
            Pattern::Noise { seed, .. }
            | Pattern::Fbm { seed, .. }
            | Pattern::Sand { seed, .. }
            | Pattern::Rock { seed, .. }
            | Pattern::Coral { seed, .. },
        ) => *seed,
        _ => 0,
    };
    (per_part, mix64(pattern_seed ^ name_hash(&o.name)))
}

/// Bake an object whose local (object-frame, unscaled) mesh is `local`, at texel `wanted` (or
/// coarser, to fit `max_side`).
pub fn bake(o: &Object, local: &TriMesh, wanted: f64, reason: String, max_side: u32) -> Baked {
    let mut b = bake_from(o, local, wanted, reason, max_side);
    b.limit = limit_text(1.0, b.texel, wanted);
    b
}

/// [`bake`] without the `limit` text.
fn bake_from(o: &Object, local: &TriMesh, wanted: f64, reason: String, max_side: u32) -> Baked {
    let t0 = std::time::Instant::now();
    let scaled: Vec<DVec3> = local.positions.iter().map(|&p| p * o.scale).collect();
    let (per_part, object_seed) = parts(o, local.triangles.len());

    let (charts, tri_chart, texel, w, h) =
        layout(o, local, &scaled, per_part, object_seed, wanted, max_side);

    // Mesh with UVs.
    let mut mesh = TriMesh::default();
    let mut uv = Vec::new();
    let mut remap: HashMap<(u32, usize), u32> = HashMap::new();
    for (k, t) in local.triangles.iter().enumerate() {
        let ci = tri_chart[k];
        let c = &charts[ci];
        let tri = t.map(|i| {
            *remap.entry((i, ci)).or_insert_with(|| {
                let q = project(scaled[i as usize], c.axis);
                let u = (c.ox + MARGIN) as f64 + (q[0] - c.lo[0]) / texel;
                let v = (c.oy + MARGIN) as f64 + (q[1] - c.lo[1]) / texel;
                mesh.positions.push(local.positions[i as usize]);
                uv.push([(u / w as f64) as f32, (v / h as f64) as f32]);
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.triangles.push(tri);
    }

    // Texels.
    let base = o.material.albedo;
    let flat = Pattern::Fbm {
        size: 1.0,
        smallest: 0.0,
        gain: 0.5,
        contrast: 0.0,
        seed: 0,
    };
    let pattern = match &o.material.pattern {
        Some(p) if !matches!(p, Pattern::Checker { .. }) => p,
        _ => &flat,
    };
    let tints: Vec<[f64; 3]> = (0..=charts.iter().map(|c| c.part).max().unwrap_or(0))
        .map(|p| variation(mix64(object_seed ^ 0x5EED ^ p as u64), o.material.variation))
        .collect();
    let mut rgb = vec![0u8; 3 * w as usize * h as usize];
    rgb.par_chunks_mut(3 * w as usize)
        .enumerate()
        .for_each(|(row, line)| {
            let row = row as u32;
            for c in charts.iter().filter(|c| row >= c.oy && row < c.oy + c.h) {
                let j = row - c.oy;
                let y = c.lo[1] + (j as f64 - MARGIN as f64 + 0.5) * texel;
                let tint = tints[c.part as usize];
                for i in 0..c.w {
                    let x = c.lo[0] + (i as f64 - MARGIN as f64 + 0.5) * texel;
                    let at = At {
                        x: x + c.offset[0],
                        y: y + c.offset[1],
                        texel,
                        texel_hash: hash2(c.seed, i as i64, j as i64),
                    };
                    let a = albedo(pattern, base, &at);
                    let cover = o
                        .material
                        .grid
                        .map_or(0.0, |g| grid_cover(&g, at.x, at.y, texel));
                    let k = 3 * (c.ox + i) as usize;
                    for ch in 0..3 {
                        let v = (1.0 - cover) * a[ch] * tint[ch]
                            + cover * o.material.grid.map_or(0.0, |g| g.albedo[ch]);
                        line[k + ch] = round_unit(v.clamp(0.0, 1.0) * 255.0);
                    }
                }
            }
        });
    let texture = Texture {
        width: w,
        height: h,
        rgb,
    };
    let mips = pyramid(&texture, &charts);
    Baked {
        mesh,
        uv,
        texture,
        mips,
        texel,
        wanted,
        reason,
        charts: charts.len(),
        limit: String::new(),
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// The mip levels of a baked atlas: coverage 1 inside every chart (with its border), 0 in the
/// gaps between them; capped at [`ATLAS_MAX_LEVEL`] when there are several charts.
fn pyramid(t: &Texture, charts: &[Chart]) -> super::mip::Pyramid {
    let (w, h) = (t.width as usize, t.height as usize);
    let mut cover = vec![false; w * h];
    for c in charts {
        for j in c.oy as usize..(c.oy + c.h) as usize {
            for i in c.ox as usize..(c.ox + c.w) as usize {
                if let Some(x) = cover.get_mut(j * w + i) {
                    *x = true;
                }
            }
        }
    }
    let max_level = if charts.len() > 1 {
        ATLAS_MAX_LEVEL
    } else {
        u32::MAX
    };
    let wrap = crate::geometry::meshfile::Wrap::Clamp;
    super::mip::Pyramid::build(t.width, t.height, wrap, max_level, |i, j| {
        let k = 3 * (j * w + i);
        let c = [0, 1, 2].map(|c| t.rgb[k + c] as f64 / 255.0);
        (c, if cover[j * w + i] { 1.0 } else { 0.0 })
    })
}

/// PLY with per-vertex texture coordinates `s`, `t` (the names both Mitsuba's and Blender's
/// PLY readers take), binary little-endian; `flip_t` writes t = 1 - v (Blender's image rows
/// run bottom-up). Deterministic bytes.
pub fn ply_bytes(mesh: &TriMesh, uv: &[[f32; 2]], flip_t: bool) -> Vec<u8> {
    ply_bytes_with(mesh, Some(uv), None, flip_t)
}

/// [`ply_bytes`] with optional texture coordinates and optional per-vertex linear colours
/// (`float red, green, blue`: Mitsuba's `vertex_color` attribute, Blender's `Col` when imported
/// with linear colours).
pub fn ply_bytes_with(
    mesh: &TriMesh,
    uv: Option<&[[f32; 2]]>,
    colors: Option<&[[f32; 3]]>,
    flip_t: bool,
) -> Vec<u8> {
    use std::fmt::Write;
    let mut head = String::from("ply\nformat binary_little_endian 1.0\n");
    if uv.is_some() {
        let _ = writeln!(
            head,
            "comment poser textured mesh; t = {}",
            if flip_t {
                "1 - v (image row 0 at t = 1)"
            } else {
                "v (image row 0 at t = 0)"
            }
        );
    }
    if colors.is_some() {
        head.push_str("comment poser mesh; vertex colours are linear\n");
    }
    let _ = write!(
        head,
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        mesh.positions.len()
    );
    if uv.is_some() {
        head.push_str("property float s\nproperty float t\n");
    }
    if colors.is_some() {
        head.push_str("property float red\nproperty float green\nproperty float blue\n");
    }
    let _ = write!(
        head,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.triangles.len()
    );
    let mut out = head.into_bytes();
    let per_vertex = 12 + if uv.is_some() { 8 } else { 0 } + if colors.is_some() { 12 } else { 0 };
    out.reserve(mesh.positions.len() * per_vertex + mesh.triangles.len() * 13);
    for (k, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
        if let Some(uv) = uv {
            let q = uv[k];
            let t = if flip_t { 1.0 - q[1] } else { q[1] };
            out.extend_from_slice(&q[0].to_le_bytes());
            out.extend_from_slice(&t.to_le_bytes());
        }
        if let Some(colors) = colors {
            for c in colors[k] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for t in &mesh.triangles {
        out.push(3);
        for i in t {
            out.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    out
}

/// Fraction of a texel centred at (x, y) (chart coordinates, m) that a grid's lines cover:
/// a smoothstep one texel wide around each line's edge, as for cracks.
fn grid_cover(g: &crate::model::Grid, x: f64, y: f64, texel: f64) -> f64 {
    let d = |v: f64| (v - (v / g.spacing).round() * g.spacing).abs();
    let half = 0.5 * g.width;
    let edge = |d: f64| {
        let t = ((d - (half - 0.5 * texel)) / texel).clamp(0.0, 1.0);
        1.0 - t * t * (3.0 - 2.0 * t)
    };
    edge(d(x)).max(edge(d(y)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texel quantiser rounds like `f64::round` on every value it can meet.
    #[test]
    fn round_unit_is_f64_round() {
        for i in 0..=2_550_000u32 {
            let y = i as f64 * 1e-4;
            for v in [y, y.next_up(), y.next_down().max(0.0)] {
                assert_eq!(round_unit(v), v.round() as u8, "{v}");
            }
        }
        assert_eq!(round_unit(f64::NAN), 0);
    }
    use crate::model::{Material, Pose};

    fn object(shape: Shape, pattern: Pattern) -> Object {
        Object {
            backdrop: false,
            name: "o".into(),
            shape,
            pose: Pose::IDENTITY,
            scale: DVec3::ONE,
            material: Material {
                albedo: [0.4, 0.35, 0.3],
                pattern: Some(pattern),
                variation: 0.2,
                texel: None,
                grid: None,
                glass: None,
                fill: None,
            },
        }
    }

    fn rock() -> Pattern {
        Pattern::Rock {
            size: 0.3,
            crack: 0.1,
            crack_width: 0.003,
            speckle: 0.002,
            contrast: 0.25,
            seed: 1,
        }
    }

    #[test]
    fn sampling_follows_the_texel_centre_convention() {
        let t = Texture {
            width: 2,
            height: 1,
            rgb: vec![0, 0, 0, 255, 255, 255],
        };
        assert_eq!(t.sample(0.25, 0.5), [0.0; 3]);
        assert_eq!(t.sample(0.75, 0.5), [1.0; 3]);
        assert_eq!(t.sample(0.5, 0.5), [0.5; 3]);
        // Clamped outside the centres.
        assert_eq!(t.sample(0.0, 0.0), [0.0; 3]);
        assert_eq!(t.sample(1.0, 1.0), [1.0; 3]);
    }

    #[test]
    fn plane_bakes_one_chart_at_the_wanted_texel() {
        let o = object(
            Shape::Plane {
                width: 0.2,
                height: 0.1,
            },
            rock(),
        );
        let local = crate::geometry::mesh::shape_mesh(&o.shape, Path::new(".")).unwrap();
        let b = bake(&o, &local, 0.001, "test".into(), MAX_SIDE);
        assert_eq!(b.charts, 1);
        assert_eq!((b.texture.width, b.texture.height), (204, 104));
        assert!(!b.coarsened());
        // Corner (-0.1, -0.05) is at texel (2, 2)'s corner.
        assert_eq!(b.uv[0], [2.0 / 204.0, 2.0 / 104.0]);
        let again = bake(&o, &local, 0.001, "test".into(), MAX_SIDE);
        assert_eq!(again.texture, b.texture);
        let png = b.texture.png().unwrap();
        assert_eq!(png, again.texture.png().unwrap());
    }

    #[test]
    fn a_grid_draws_its_lines_over_the_pattern_on_the_objects_axes() {
        // A 0.2 × 0.1 m plane with a grid every 5 cm, 4 mm wide, at 1 mm texels.
        let mut o = object(
            Shape::Plane {
                width: 0.2,
                height: 0.1,
            },
            rock(),
        );
        o.material.variation = 0.0;
        let local = crate::geometry::mesh::shape_mesh(&o.shape, Path::new(".")).unwrap();
        let plain = bake(&o, &local, 0.001, "test".into(), MAX_SIDE);
        o.material.grid = Some(crate::model::Grid {
            spacing: 0.05,
            width: 0.004,
            albedo: [1.0, 0.0, 0.0],
        });
        let lined = bake(&o, &local, 0.001, "test".into(), MAX_SIDE);
        let at = |b: &Baked, x: f64, y: f64| {
            // Texel of the point (x, y) of the plane (corner (−0.1, −0.05) at texel (2, 2)).
            let i = (2.0 + (x + 0.1) / 0.001).floor() as usize;
            let j = (2.0 + (y + 0.05) / 0.001).floor() as usize;
            let k = 3 * (j * b.texture.width as usize + i);
            [b.texture.rgb[k], b.texture.rgb[k + 1], b.texture.rgb[k + 2]]
        };
        // On the lines x = 0, x = ±0.05 and y = 0: the line's colour.
        for (x, y) in [
            (0.0005, 0.023),
            (0.0505, -0.031),
            (-0.0495, 0.012),
            (0.033, 0.0005),
        ] {
            assert_eq!(at(&lined, x, y), [255, 0, 0], "({x}, {y})");
        }
        // Between them: the pattern, untouched.
        for (x, y) in [(0.0255, 0.0255), (-0.0245, -0.0205), (0.071, 0.031)] {
            assert_eq!(at(&lined, x, y), at(&plain, x, y), "({x}, {y})");
        }
        // Five lines across x (−0.1 … 0.1 m, 4 texels each, in 204 texels with the borders) and
        // three across y (in 104): 1 − (1 − 20/204)(1 − 12/104) ≈ 20 % of the texels.
        let red = lined
            .texture
            .rgb
            .chunks(3)
            .filter(|p| p == &[255, 0, 0])
            .count() as f64
            / (lined.texture.width * lined.texture.height) as f64;
        assert!((0.18..0.22).contains(&red), "{red}");
    }

    #[test]
    fn closed_meshes_get_triplanar_charts_and_the_cap_coarsens() {
        let o = object(
            Shape::Boulders {
                width: 2.0,
                length: 2.0,
                count: 3,
                radius: 0.2,
                seed: 4,
            },
            rock(),
        );
        let local = crate::geometry::mesh::shape_mesh(&o.shape, Path::new(".")).unwrap();
        let b = bake(&o, &local, 0.002, "test".into(), MAX_SIDE);
        assert_eq!(b.charts, 18);
        assert_eq!(b.mesh.triangles.len(), local.triangles.len());
        assert!(b.mesh.positions.len() > local.positions.len());
        assert!(
            b.uv.iter()
                .all(|q| (0.0..=1.0).contains(&q[0]) && (0.0..=1.0).contains(&q[1]))
        );
        let small = bake(&o, &local, 0.002, "test".into(), 256);
        assert!(small.coarsened());
        assert!(small.texture.width <= 256 && small.texture.height <= 256);
        // Parts differ in colour (variation 0.2).
        assert!(small.summary().contains("COARSENED"));
    }

    #[test]
    fn ply_has_uvs_and_flips_for_blender() {
        let m = crate::geometry::mesh::plane(1.0, 1.0);
        let uv = vec![[0.0, 0.25], [1.0, 0.25], [1.0, 1.0], [0.0, 1.0]];
        let a = ply_bytes(&m, &uv, false);
        let b = ply_bytes(&m, &uv, true);
        let end = |x: &[u8]| {
            let s = String::from_utf8_lossy(x);
            s.find("end_header\n").unwrap() + 11
        };
        let (ea, eb) = (end(&a), end(&b));
        assert_eq!(a.len() - ea, 4 * 20 + 2 * 13);
        let t0 = |x: &[u8], e: usize| f32::from_le_bytes(x[e + 16..e + 20].try_into().unwrap());
        assert_eq!(t0(&a, ea), 0.25);
        assert_eq!(t0(&b, eb), 0.75);
    }
}
