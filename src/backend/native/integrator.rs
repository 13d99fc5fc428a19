//! The light-transport estimator: a unidirectional volumetric path tracer in RGB.
//!
//! * Surfaces: two-sided Lambertian (albedo × pattern, or the target's printed reflectance).
//! * Water: homogeneous per channel. Free-flight distances are sampled with a channel picked
//!   uniformly and weighted by the one-sample MIS density over the three channels (spectral
//!   MIS); a non-scattering water uses its analytic transmittance.
//! * Next-event estimation at the surface ending a water segment is weighted by the analytic
//!   transmittance on both branches of the free-flight sample.
//! * Next-event estimation at every vertex: point/spot lights and the sun (delta lights; under
//!   a wavy surface the sun is scaled by the caustic factor at the vertex, [`super::caustics`]),
//!   area lights (MIS with BSDF/phase sampling, power heuristic).
//! * Equiangular sampling (Kulla & Fajardo 2012) of in-scattering from point/spot lights along
//!   every medium segment, combined with distance sampling by MIS (power heuristic).
//! * Phase-angular sampling of in-scattering from point/spot lights on every medium segment: the
//!   distance whose direction to the light makes a scattering angle drawn from the phase
//!   function (restricted to the angles the segment spans). A ray that passes near a lamp in
//!   forward-scattering water sees its glow mostly where the angle is small, far before the
//!   lamp, where equiangular sampling (uniform in the angle seen from the light) rarely goes.
//!   Free flight, equiangular and phase-angular samples are combined by MIS (power heuristic).
//! * Sun-aware distance sampling of in-scattered sunlight along every medium segment, combined
//!   with free-flight sampling by MIS (power heuristic): sunlight scattered at distance `t`
//!   along a ray has crossed `t` of water from the ray's start plus the water above the point,
//!   so along a ray climbing towards the sun its contribution barely falls with `t`, while
//!   free flight places vertices with density `σt e^(−σt t)` — the vertices near the surface
//!   then carry weights `e^(σt t)` times the mean (fireflies in sunlit water). The sampled
//!   density is the truncated exponential of the product's rate ([`Integrator::sun_rate`]).
//! * In sunlit, scattering water, bounces at surfaces and in the medium sample a mixture of
//!   their own lobe (cosine, or the phase function about the path) and the phase function's
//!   lobe about the sun ([`AUREOLE_FRACTION`]; one-sample MIS, so unbiased): the
//!   forward-scattered sun (the aureole, p(0°) ≈ 300× the isotropic value at g = 0.92) is what
//!   lights a seabed from above, and the path's own lobe alone finds it as fireflies.
//! * Daylight from the water column ([`crate::optics::column`], when the scene has one,
//!   [`Integrator::column`]): daylight's paths have no medium vertices. The camera ray gathers
//!   the column's light scattered along it ([`Integrator::column_gather`]), each gathered
//!   direction traced to the local geometry: a surface it meets gives its own textured,
//!   shadowed daylight, the water before it is gathered again ([`GATHER_LEVELS`]), so the
//!   forward-scattered image of the seabed keeps its texture; each surface
//!   vertex estimates the column's light arriving from every direction by next-event
//!   estimation alone ([`Integrator::column_nee`]: a direction drawn from the table's bins
//!   in proportion to luminance × cos θ, visibility traced to the local geometry, the light
//!   between read from the table), so the segments after a surface bounce carry none of it,
//!   and bounces sample the cosine lobe, not the sun's aureole (the table holds it). The
//!   sun's direct light and its first scattering along the camera ray stay traced (shadows,
//!   shafts). A path that scatters in the water carries strobe light only from there on.
//! * `max_bounces` = the largest number of scattering vertices (surface or medium) on a path;
//!   Russian roulette after three, except in sunlit, scattering water
//!   ([`Integrator::roulette_from`]).

use super::footprint::{Footprint, PixelSpread};
use super::lights::{Lights, SunLight};
use super::medium::{Medium, tr};
use super::sampler::Sampler;
use super::scene::{Hit, Ray, Scene, SurfaceId};
use crate::model::{Model, Pose};
use crate::optics::column;
use glam::DVec3;
use std::f64::consts::PI;

/// Share of surface bounces that sample the sun's aureole (when there is one, see
/// [`Integrator::aureole`]); the rest are cosine-weighted.
pub const AUREOLE_FRACTION: f64 = 0.5;
/// Phase functions flatter than this peak value (per sr, forward) gain nothing from aureole
/// sampling: 4× isotropic.
const AUREOLE_MIN_PEAK: f64 = 4.0 / (4.0 * PI);

/// With a column, the share of medium segments that try a free-flight vertex (for the strobes'
/// light scattered more than once in the water); the others pass to the next surface with the
/// analytic transmittance and keep their daylight.
pub const COLUMN_FREE_FLIGHT: f64 = 0.25;

/// How many scatterings of the column's light towards the camera are traced through the
/// local geometry ([`Integrator::column_towards`]), the camera ray's gather counted: along a
/// gathered direction that meets a surface the water is gathered again, up to this many levels;
/// past them the column's table stands for the water. Measured on the first pose of paper_survey (1 % of full size, column
/// at 512 spp against traced at 2 048, G / B): without tracing the gather the column was
/// brighter by +3.6 / +4.3 % and its image held 0.45 / 0.33 of the texture's contrast; one level
/// +1.5 / +2.5 % and 0.8; two levels +0.7 / +1.3 % and 0.95 / 0.89; three levels +0.4 /
/// +1.0 % (± 0.3 / 0.2) and 0.99 / 0.98. Three levels cost 1.5× the CPU time per sample on
/// reef_strip (quarter size) and 1.4× the variance on an untextured seabed (more with a
/// texture: the texture's own contrast, now in the image). Gathering the water again for half
/// the directions only (the table's difference as a control variate for the rest) saved a
/// tenth of the time for 1.4–1.8× the variance.
pub const GATHER_LEVELS: u32 = 3;

/// The scattering optical depth (the most scattering channel's σs × the segment's length)
/// from which a gathered direction's water, up to the surface it meets, is gathered again
/// (up to [`GATHER_LEVELS`]); thinner water is read from the table. Measured on reef_strip's
/// first pose (Jerlov IB, 2 m above the seabed, quarter size, 48 spp): one level instead of
/// three moved the image mean by +0.03 / +0.05 % (G / B) at the same noise and cut the CPU
/// time per sample 0.93–1.03 → 0.63 s; in coastal water 3 m deep (σs·t ≈ 1–4,
/// `column_keeps_the_texture_of_the_seabed_seen_through_the_water`) one level lost 18 % of the
/// texture's contrast and 1 % of the mean, which the deeper levels keep.
pub const GATHER_DEEPER_FROM: f64 = 0.25;

/// Share of the directions gathered along the camera ray drawn from the column's table (the
/// rest from the phase function, [`Integrator::column_gather`]). Measured on the first pose
/// of paper_survey and two_gas_dive (sky only, 15–18 m; 10 % of full size, 24 spp): 0 → 0.05
/// cuts the relative noise of the image mean per pixel from 6.2 to 2.3 % (G); 0.1 gives
/// 3.4 %, 0.2 gives 6.0 % (larger shares are noisier as measured; why was not isolated).
pub const GATHER_TABLE: f64 = 0.05;

/// Share of the column's next-event directions at surfaces drawn from the cosine lobe (the
/// rest from the column's table, [`Integrator::column_nee`]).
pub const COLUMN_NEE_COSINE: f64 = 0.02;

/// Depth from which Russian roulette may end a path (outside sunlit water).
pub const ROULETTE_FROM: u32 = 3;

/// Offset of new ray origins along the surface normal, m.
const SURFACE_OFFSET: f64 = 1e-6;

#[inline]
fn power(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

#[inline]
fn mean(v: DVec3) -> f64 {
    (v.x + v.y + v.z) / 3.0
}

/// The odds of drawing a free flight's distance with each channel's σt (spectral one-sample
/// MIS, the balance heuristic over the channels): in proportion to the path's throughput
/// `beta`, uniform where it has none (a camera ray: uniform). With uniform odds a channel's
/// weight at a vertex, `σs_c T_c / mean_k(σt_k T_k)`, reaches 3 ω_c where the other channels'
/// light has died (blue, after red and green are absorbed), and over a long path the product
/// grows without bound (blue weights of 10–1 400 on dome_orbit's traced paths of 8–21
/// scatterings). With odds ∝ β the weights' sum never grows by more than the largest
/// single-scattering albedo per vertex (measured: docs/native.md, "Water").
fn channel_odds(beta: DVec3) -> DVec3 {
    let s = beta.x + beta.y + beta.z;
    if s > 0.0 && s.is_finite() && beta.min_element() >= 0.0 {
        beta / s
    } else {
        DVec3::splat(1.0 / 3.0)
    }
}

/// The channel drawn with odds `pc` by the uniform `u`.
fn pick_channel(pc: DVec3, u: f64) -> usize {
    if u < pc.x {
        0
    } else if u < pc.x + pc.y || pc.z <= 0.0 {
        1
    } else {
        2
    }
}

/// How a path's segment through the water ends ([`Integrator::medium_segment`]).
enum SegmentEnd {
    /// The path ends.
    Ends,
    /// The segment is passed; `beta_nee` weighs next-event estimation at the surface ending it.
    Passed { beta_nee: DVec3 },
    /// A free-flight vertex: the path goes on from `o` along `d`, sampled with density `pdf`.
    Scattered { o: DVec3, d: DVec3, pdf: f64 },
}

/// A path's state with respect to the glass objects
/// ([`crate::model::Material::glass`]).
#[derive(Debug, Clone, Copy, Default)]
struct GlassPath {
    /// Between a glass object's faces: no water there (a filled object's own water, if it is
    /// one: [`Integrator::fill`]).
    inside: bool,
    /// The glass or filled object the path is inside.
    object: Option<u32>,
    /// The channel whose indices the path follows through glass when each channel is rendered
    /// alone (`needs.per_channel_passes`): drawn uniformly at the first glass face, with the
    /// path's weight that channel's alone ×3; `None` before, or when one index serves all.
    channel: Option<usize>,
}

/// Everything needed to estimate radiance along camera rays of one image.
pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub model: &'a Model,
    pub medium: Option<Medium>,
    pub lights: Lights,
    pub max_bounces: u32,
    /// Unit direction towards the sun in the water, when surface bounces sample its aureole
    /// (`None` turns that sampling off; the estimate stays the same, only noisier).
    pub aureole: Option<DVec3>,
    /// Depth from which Russian roulette may end a path ([`Integrator::roulette`]):
    /// [`ROULETTE_FROM`], or `max_bounces` in sunlit, scattering water.
    pub roulette_from: u32,
    /// Sun-aware distance sampling along medium segments (`false` turns it off; the estimate
    /// stays the same, only noisier).
    pub sun_sampling: bool,
    /// Phase-angular sampling of point/spot lights' in-scattering (`false` turns it off; the
    /// estimate stays the same, only noisier).
    pub lamp_phase_sampling: bool,
    /// The water column lighting the scene with daylight (`None`: daylight is traced).
    pub column: Option<&'a crate::optics::column::Column>,
    /// Share of medium segments on which a free-flight vertex is tried: 1 when daylight is
    /// traced; with a column, [`COLUMN_FREE_FLIGHT`] with strobes or area lights, else 0.
    pub ff_share: f64,
    /// The water's index per channel where the sea surface reflects the light coming up to
    /// it and shows the sky through Snell's window ([`Model::underside`]); `None`: open.
    pub underside: Option<DVec3>,
    /// Per object: the index of its glass per channel ([`crate::model::Material::glass`]),
    /// `None` for an opaque object.
    glass: Vec<Option<DVec3>>,
    /// Per object: the water inside a filled object ([`crate::model::Material::fill`]), as a
    /// medium bounded by the object's faces (`None`: clear, or not filled).
    fill: Vec<Option<Medium>>,
    /// The index around the glass objects per channel: the water's, or air's.
    n_around: DVec3,
    object_from_world: Vec<Pose>,
    target_from_world: Vec<Pose>,
}

impl<'a> Integrator<'a> {
    pub fn new(
        scene: &'a Scene,
        model: &'a Model,
        medium: Option<Medium>,
        lights: Lights,
    ) -> Integrator<'a> {
        let aureole = match (&lights.sun, &medium) {
            (Some(sun), Some(m))
                if m.scatters()
                    && m.phase.eval(1.0) > AUREOLE_MIN_PEAK
                    && scene.column.is_none() =>
            {
                Some(-sun.dir())
            }
            _ => None,
        };
        let no_lamps = lights.points.is_empty() && lights.areas.is_empty();
        Integrator {
            scene,
            model,
            medium,
            lights,
            max_bounces: model.render.max_bounces,
            aureole,
            // In sunlit, scattering water the light grows towards the surface: a path that
            // roulette lets survive deep down with its weight raised to ~1 then climbs into
            // sunlight 10–100× brighter (a firefly). There, only `max_bounces` ends paths.
            roulette_from: if aureole.is_some() {
                model.render.max_bounces
            } else {
                ROULETTE_FROM
            },
            sun_sampling: true,
            lamp_phase_sampling: true,
            column: scene.column.as_deref(),
            ff_share: match (&scene.column, no_lamps) {
                (None, _) => 1.0,
                (Some(_), true) => 0.0,
                (Some(_), false) => COLUMN_FREE_FLIGHT,
            },
            underside: match model.underside() {
                crate::optics::column::Top::Fresnel(n) => Some(DVec3::from_array(n)),
                crate::optics::column::Top::Open => None,
            },
            glass: model
                .objects
                .iter()
                .map(|o| o.material.glass.as_ref().map(|g| DVec3::from_array(g.ior)))
                .collect(),
            fill: model
                .objects
                .iter()
                .map(|o| {
                    let w = o.material.fill.as_ref()?;
                    let (sa, ss) = (
                        DVec3::from_array(w.absorption),
                        DVec3::from_array(w.scattering),
                    );
                    ((sa + ss).max_element() > 0.0)
                        .then(|| Medium::everywhere(sa, ss, w.phase.phase_fn()))
                })
                .collect(),
            n_around: DVec3::from_array(model.ambient_ior()),
            object_from_world: model.objects.iter().map(|o| o.pose.inverse()).collect(),
            target_from_world: model.targets.iter().map(|t| t.pose.inverse()).collect(),
        }
    }

    /// Albedo per channel at a hit.
    pub fn albedo(&self, h: &Hit) -> DVec3 {
        self.albedo_over(h, None)
    }

    /// Albedo per channel at a hit, textures averaged over the pixel's footprint `fp` there
    /// (its centre and width, [`super::footprint`]; `None`: a point lookup at the hit).
    pub fn albedo_over(&self, h: &Hit, fp: Option<Footprint>) -> DVec3 {
        match h.surface {
            SurfaceId::Object(i) => {
                let o = &self.model.objects[i as usize];
                // Textures are read at the footprint's centre, on the hit's triangle's plane.
                let (th, width) = match fp {
                    Some(f) => (
                        &Hit {
                            point: f.centre,
                            ..*h
                        },
                        f.width,
                    ),
                    None => (h, 0.0),
                };
                if let Some(a) = self.scene.mapped_albedo_over(th, width) {
                    return DVec3::from_array(a);
                }
                if let Some(Some(b)) = self.scene.textures.get(i as usize)
                    && let Some([u, v]) = self.scene.uv_at(th)
                {
                    return DVec3::from_array(b.sample_footprint(u, v, width));
                }
                let a = DVec3::from_array(o.material.albedo);
                match &o.material.pattern {
                    Some(p) => {
                        let q = self.object_from_world[i as usize].transform_point(h.point);
                        a * crate::texture::pattern_factor(p, q)
                    }
                    None => a,
                }
            }
            SurfaceId::Target(i) => {
                let t = &self.model.targets[i as usize];
                let q = self.target_from_world[i as usize].transform_point(h.point);
                DVec3::splat(crate::geometry::bvh::target_reflectance(&t.kind, q.x, q.y))
            }
        }
    }

    /// Density (per sr) of the surface-bounce direction `w` about normal `n`: cosine-weighted,
    /// or the mixture with the sun's aureole.
    fn surface_pdf(&self, n: DVec3, w: DVec3) -> f64 {
        let c = n.dot(w).max(0.0) / PI;
        match (self.aureole, &self.medium) {
            (Some(s), Some(m)) => {
                (1.0 - AUREOLE_FRACTION) * c + AUREOLE_FRACTION * m.phase.eval(s.dot(w))
            }
            _ => c,
        }
    }

    /// Sample a surface-bounce direction about normal `n`; returns (direction, density).
    fn sample_surface(&self, n: DVec3, rng: &mut Sampler) -> (DVec3, f64) {
        let pick = rng.next();
        let (u1, u2) = rng.next2();
        let w = match (self.aureole, &self.medium) {
            (Some(s), Some(m)) if pick < AUREOLE_FRACTION => m.phase.sample(s, u1, u2).0,
            _ => {
                let r = u1.sqrt();
                let phi = 2.0 * PI * u2;
                let (tx, ty) = n.any_orthonormal_pair();
                let z = (1.0 - u1).max(0.0).sqrt();
                (tx * (r * phi.cos()) + ty * (r * phi.sin()) + n * z).normalize()
            }
        };
        (w, self.surface_pdf(n, w))
    }

    /// Density (per sr) of the direction `w` sampled at a medium vertex reached along `d`:
    /// the phase function about `d`, or its mixture with the phase lobe about the sun.
    fn medium_pdf(&self, m: &Medium, d: DVec3, w: DVec3) -> f64 {
        let p = m.phase.eval(d.dot(w));
        match self.aureole {
            Some(s) => (1.0 - AUREOLE_FRACTION) * p + AUREOLE_FRACTION * m.phase.eval(s.dot(w)),
            None => p,
        }
    }

    /// Sample the direction leaving a medium vertex reached along `d`; returns (direction,
    /// density).
    fn sample_medium(&self, m: &Medium, d: DVec3, rng: &mut Sampler) -> (DVec3, f64) {
        let pick = rng.next();
        let (u1, u2) = rng.next2();
        let w = match self.aureole {
            Some(s) if pick < AUREOLE_FRACTION => m.phase.sample(s, u1, u2).0,
            _ => m.phase.sample(d, u1, u2).0,
        };
        (w, self.medium_pdf(m, d, w))
    }

    fn tr_seg(&self, o: DVec3, d: DVec3, len: f64) -> DVec3 {
        match &self.medium {
            Some(m) => m.transmittance(o, d, 0.0, len),
            None => DVec3::ONE,
        }
    }

    /// `f` towards the sun times the water's transmittance from `p` up to the surface plane
    /// z = 0 (the sun's irradiance is given just below it), per channel: in water each channel
    /// has its own refracted direction, so its own cosine or phase angle and path length
    /// (up to about 1 % from green's on the shipped scenes' direct beam; docs/backends.md).
    /// Visibility is the caller's: one shadow ray along green's direction.
    fn sun_arriving(&self, sun: &SunLight, p: DVec3, f: &impl Fn(DVec3) -> DVec3) -> DVec3 {
        let at = |d: DVec3| {
            let s = if p.z < 0.0 { p.z / d.z } else { 0.0 };
            let fv = f(-d);
            if fv == DVec3::ZERO {
                DVec3::ZERO
            } else {
                fv * self.tr_seg(p, -d, s)
            }
        };
        if sun.chromatic() {
            DVec3::new(at(sun.dirs[0]).x, at(sun.dirs[1]).y, at(sun.dirs[2]).z)
        } else {
            at(sun.dir())
        }
    }

    /// Radiance arriving at `p` from the delta lights and area lights, weighted by `f(dir)`
    /// (BSDF·cos or phase) whose sampling density is `pdf(dir)` (for area-light MIS).
    /// `point_weight(i)` is the MIS weight of point light `i` (1 at surfaces).
    fn direct(
        &self,
        p: DVec3,
        f: impl Fn(DVec3) -> DVec3,
        pdf: impl Fn(DVec3) -> f64,
        point_weight: impl Fn(usize, DVec3) -> f64,
        sun_weight: f64,
        rng: &mut Sampler,
    ) -> DVec3 {
        let mut l = DVec3::ZERO;
        for (i, pl) in self.lights.points.iter().enumerate() {
            let i_to = pl.intensity_to(p);
            if i_to == DVec3::ZERO {
                continue;
            }
            let wl = pl.pos - p;
            let r2 = wl.length_squared();
            let r = r2.sqrt();
            let dir = wl / r;
            let fv = f(dir);
            if fv == DVec3::ZERO {
                continue;
            }
            let w = point_weight(i, pl.pos);
            if w <= 0.0 || self.scene.occluded(p, pl.pos) {
                continue;
            }
            l += fv * i_to * self.tr_seg(p, dir, r) / r2 * w;
        }
        l += self.sun_direct(p, &f, sun_weight);
        for a in &self.lights.areas {
            let (u1, u2) = rng.next2();
            let q = a.center + a.ax * (2.0 * u1 - 1.0) + a.ay * (2.0 * u2 - 1.0);
            let wl = q - p;
            let r2 = wl.length_squared();
            let r = r2.sqrt();
            let dir = wl / r;
            let cos_l = -dir.dot(a.normal);
            if cos_l <= 0.0 || a.area <= 0.0 {
                continue;
            }
            let fv = f(dir);
            if fv == DVec3::ZERO {
                continue;
            }
            let pdf_l = r2 / (a.area * cos_l);
            if self.scene.occluded(p, q) {
                continue;
            }
            let w = power(pdf_l, pdf(dir));
            l += fv * a.radiance * self.tr_seg(p, dir, r) / pdf_l * w;
        }
        l
    }

    /// The sun's light arriving at `p`, weighted by `f(dir)` and by `sun_weight` (its MIS
    /// weight), with one shadow ray; caustics under waves scale it.
    fn sun_direct(&self, p: DVec3, f: &impl Fn(DVec3) -> DVec3, sun_weight: f64) -> DVec3 {
        let Some(sun) = &self.lights.sun else {
            return DVec3::ZERO;
        };
        if sun_weight <= 0.0 {
            return DVec3::ZERO;
        }
        let ft = self.sun_arriving(sun, p, f);
        if ft == DVec3::ZERO {
            return DVec3::ZERO;
        }
        let blocked = self.scene.occluded_ray(
            &Ray {
                origin: p,
                dir: -sun.dir(),
            },
            f64::INFINITY,
        );
        if blocked {
            return DVec3::ZERO;
        }
        // Caustics under waves: the irradiance relative to the flat surface at p (the
        // direction stays the flat-surface one; see render::caustics).
        let c = self.scene.caustics.as_ref().map_or(1.0, |v| v.factor(p));
        ft * sun.irradiance * (c * sun_weight)
    }

    /// Radiance along the ray `o + t·d` (unit `d`), towards `o`.
    pub fn li(&self, o: DVec3, d: DVec3, rng: &mut Sampler) -> DVec3 {
        self.li_spread(o, d, None, rng)
    }

    /// The pixel's footprint at the camera ray's first hit `h` (`depth` 0, with the pixel's
    /// differentials `spread`), for the texture lookup there; `None` (a point lookup) at deeper
    /// vertices: a bounce's light already averages the surface over its lobe, and the first
    /// hit carries the texture's variance within the pixel.
    fn footprint(
        &self,
        spread: Option<PixelSpread>,
        depth: u32,
        o: DVec3,
        d: DVec3,
        h: &Hit,
    ) -> Option<Footprint> {
        match spread {
            Some(s) if depth == 0 => Some(s.at_hit(o, d, h.point, h.normal)),
            _ => None,
        }
    }

    /// What the ray `o + t d` meets first: the scene's hit, the distance to what ends it (∞:
    /// nothing), and the area light that ends it before any surface, if one does.
    fn first_hit(&self, o: DVec3, d: DVec3) -> (Option<Hit>, f64, Option<usize>) {
        let hit = self
            .scene
            .intersect(&Ray { origin: o, dir: d }, f64::INFINITY);
        let mut t_end = hit.as_ref().map_or(f64::INFINITY, |h| h.t);
        let mut area_hit = None;
        for (i, a) in self.lights.areas.iter().enumerate() {
            if let Some(t) = a.intersect(o, d, t_end) {
                t_end = t;
                area_hit = Some(i);
            }
        }
        (hit, t_end, area_hit)
    }

    /// The index per channel of the glass object `h` lies on, if it is one.
    fn glass_of(&self, h: &Hit) -> Option<DVec3> {
        match h.surface {
            SurfaceId::Object(k) => self.glass.get(k as usize).copied().flatten(),
            #[allow(unreachable_patterns)]
            _ => None,
        }
    }

    /// The water a path's segment runs through: the scene's, none inside a glass object, or a
    /// filled object's own inside it.
    fn segment_water(&self, glass: &GlassPath) -> Option<&Medium> {
        if glass.inside {
            glass
                .object
                .and_then(|k| self.fill.get(k as usize))
                .and_then(Option::as_ref)
        } else {
            self.medium.as_ref()
        }
    }

    /// The bounce of a path along `d` at a glass object's face `h` (indices `ior`): Fresnel
    /// reflection or Snell refraction, one of them drawn with the reflectance's odds (total
    /// internal reflection always reflects). Returns the new origin, just off the face on the
    /// side the path goes on, and direction; `glass` tracks whether the path is inside.
    /// With each channel rendered alone (dispersion), a path follows one channel's indices,
    /// drawn at its first glass face, its weight that channel's alone ×3 ([`GlassPath`]).
    /// Radiance's n² factors cancel: a path that enters a glass object leaves it into the
    /// same water.
    fn glass_bounce(
        &self,
        h: &Hit,
        d: DVec3,
        ior: DVec3,
        glass: &mut GlassPath,
        beta: &mut DVec3,
        rng: &mut Sampler,
    ) -> Option<(DVec3, DVec3)> {
        let c = if self.model.needs.per_channel_passes {
            *glass.channel.get_or_insert_with(|| {
                let c = ((rng.next() * 3.0) as usize).min(2);
                let mut only = DVec3::ZERO;
                only[c] = 3.0;
                *beta *= only;
                c
            })
        } else {
            1
        };
        let (n_glass, n_out) = (ior[c], self.n_around[c]);
        let (n1, n2) = if glass.inside {
            (n_glass, n_out)
        } else {
            (n_out, n_glass)
        };
        // The face's normal on the side the path comes from.
        let n = if h.normal.dot(d) > 0.0 {
            -h.normal
        } else {
            h.normal
        };
        let cos_i = -n.dot(d);
        let reflect = d + 2.0 * cos_i * n;
        let off = SURFACE_OFFSET * (1.0 + h.point.abs().max_element());
        let r = match crate::optics::interface::refract(d, -n, n1 / n2) {
            Some((t, cos_t)) => {
                let tr = crate::optics::interface::fresnel_transmittance(n1, n2, cos_i, cos_t);
                if rng.next() >= 1.0 - tr {
                    glass.inside = !glass.inside;
                    glass.object = match (glass.inside, h.surface) {
                        (true, SurfaceId::Object(k)) => Some(k),
                        _ => None,
                    };
                    return Some((h.point - n * off, t.normalize()));
                }
                reflect
            }
            None => reflect,
        };
        Some((h.point + n * off, r.normalize()))
    }

    /// [`Integrator::li`] of a camera ray with its pixel's differentials (`spread`): the
    /// textures at its first hit are averaged over the pixel's footprint
    /// ([`super::footprint`]).
    pub fn li_spread(
        &self,
        mut o: DVec3,
        mut d: DVec3,
        spread: Option<PixelSpread>,
        rng: &mut Sampler,
    ) -> DVec3 {
        let mut l = DVec3::ZERO;
        let mut beta = DVec3::ONE;
        // Density of the direction sampled at the previous vertex (0: camera ray, no MIS).
        let mut prev_pdf = 0.0;
        let mut depth = 0u32;
        // The path still carries daylight; with a column, a medium vertex ends that.
        let mut day = true;
        // Inside a glass object (no water there), and the channel whose indices a path
        // through glass follows when each channel is rendered with its own ([`GlassPath`]).
        let mut glass = GlassPath::default();
        loop {
            let (hit, t_end, area_hit) = self.first_hit(o, d);
            let can_scatter = depth < self.max_bounces;
            rng.segment(depth);
            // The column's light scattered along the camera ray. At the surfaces its light
            // is next-event estimated alone ([`Integrator::column_nee`]), so the segments
            // after a surface bounce carry none of it.
            if day
                && depth == 0
                && self.max_bounces > 0
                && let Some(col) = self.column
            {
                l += beta * self.column_gather(col, o, d, t_end, 0, rng);
            }
            // Weight of next-event estimation at the surface ending this segment: the analytic
            // transmittance, whichever way the free flight below goes (both branches add it
            // exactly once), so direct light on surfaces carries no free-flight noise.
            let mut beta_nee = beta;
            if let Some(m) = self.segment_water(&glass)
                && let Some((a, b)) = m.interval(o, d, 0.0, t_end)
            {
                // A glass face takes no next-event estimate (it is a delta BSDF).
                let surface = hit
                    .as_ref()
                    .filter(|h| area_hit.is_none() && self.glass_of(h).is_none());
                let at = (o, d, depth, day);
                match self.medium_segment(
                    m,
                    (a, b),
                    at,
                    surface,
                    spread,
                    can_scatter,
                    &mut l,
                    &mut beta,
                    rng,
                ) {
                    SegmentEnd::Ends => break,
                    SegmentEnd::Passed { beta_nee: bn } => beta_nee = bn,
                    SegmentEnd::Scattered { o: no, d: nd, pdf } => {
                        o = no;
                        d = nd;
                        prev_pdf = pdf;
                        depth += 1;
                        if self.column.is_some() {
                            day = false;
                        }
                        if !self.roulette(&mut beta, depth, rng) {
                            break;
                        }
                        continue;
                    }
                }
            }
            if let Some(i) = area_hit {
                let a = &self.lights.areas[i];
                let cos_l = -d.dot(a.normal);
                if cos_l > 0.0 {
                    let w = if prev_pdf > 0.0 {
                        power(prev_pdf, t_end * t_end / (a.area * cos_l))
                    } else {
                        1.0
                    };
                    l += beta * a.radiance * w;
                }
                break;
            }
            let Some(h) = hit else {
                // The ray leaves: the sky, or the sea surface seen from below, whose
                // reflection is followed as a mirror bounce.
                let Some(mirror) = self.leave(o, d, day, can_scatter, &mut l, &mut beta, rng)
                else {
                    break;
                };
                (o, d, prev_pdf) = (mirror.0, mirror.1, 0.0);
                depth += 1;
                // With a column, the light the surface reflects is in its table: the mirror
                // path carries strobe light only.
                day &= self.column.is_none();
                if !self.roulette(&mut beta, depth, rng) {
                    break;
                }
                continue;
            };
            if !can_scatter {
                break;
            }
            if let Some(ior) = self.glass_of(&h) {
                // A smooth dielectric: reflect or refract, chosen by the Fresnel reflectance
                // (the weight stays: the choice's odds are the reflectance itself).
                let Some((no, nd)) = self.glass_bounce(&h, d, ior, &mut glass, &mut beta, rng)
                else {
                    break;
                };
                (o, d, prev_pdf) = (no, nd, 0.0);
                depth += 1;
                if !self.roulette(&mut beta, depth, rng) {
                    break;
                }
                continue;
            }
            let n = if h.normal.dot(d) > 0.0 {
                -h.normal
            } else {
                h.normal
            };
            let albedo = self.albedo_over(&h, self.footprint(spread, depth, o, d, &h));
            if albedo == DVec3::ZERO {
                break;
            }
            let p = h.point + n * SURFACE_OFFSET * (1.0 + h.point.abs().max_element());
            rng.surface(depth);
            l += beta_nee * self.surface_direct(&h, d, albedo, day, rng);
            // f·cos/pdf = albedo·(cos/π)/pdf (= albedo for pure cosine sampling).
            let (nd, pdf) = self.sample_surface(n, rng);
            let cos = n.dot(nd);
            if cos <= 0.0 || pdf <= 0.0 {
                break;
            }
            prev_pdf = pdf;
            beta *= albedo * (cos / PI / pdf);
            o = p;
            d = nd;
            depth += 1;
            if !self.roulette(&mut beta, depth, rng) {
                break;
            }
        }
        l
    }

    /// A path's segment `[a, b]` through the water `m`, from `o` along `d` at bounce `depth`
    /// (`day`: the path still carries daylight): the strobe and sun light scattered along it
    /// (added to `l`), then free flight. At a medium vertex, `surface` (the surface ending the
    /// segment, unless an area light does) gets its direct light first and the scattered
    /// direction is returned; a passed segment leaves `beta` weighted by its transmittance.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn medium_segment(
        &self,
        m: &Medium,
        (a, b): (f64, f64),
        (o, d, depth, day): (DVec3, DVec3, u32, bool),
        surface: Option<&Hit>,
        spread: Option<PixelSpread>,
        can_scatter: bool,
        l: &mut DVec3,
        beta: &mut DVec3,
        rng: &mut Sampler,
    ) -> SegmentEnd {
        if m.scatters() && can_scatter {
            // The channel whose σt draws the free flight, in proportion to the throughput
            // ([`channel_odds`]); every density of the free flight below uses the same odds.
            let pc = channel_odds(*beta);
            // Equiangular in-scattering from point/spot lights on every segment: it
            // removes the 1/r² spikes of vertices that land near a strobe.
            // Each lamp's geometry relative to this segment, computed once and shared by
            // its two samplers and the MIS weights at a free-flight vertex.
            let mut segs = [LampSeg::default(); LAMP_CACHE];
            for (i, pl) in self.lights.points.iter().enumerate() {
                let seg = LampSeg::new(m, o, d, a, b, pl.pos, self.lamp_phase_sampling);
                if let Some(c) = segs.get_mut(i) {
                    *c = seg;
                }
                *l += *beta * self.equiangular(m, pl, o, d, a, &seg, pc, rng);
                if self.lamp_phase_sampling {
                    *l += *beta * self.lamp_phase(m, pl, o, d, a, b, &seg, pc, rng);
                }
            }
            // Sun-aware distance sampling of the sunlight scattered along [a, b].
            // With a column, only the camera ray traces the sun's first scattering.
            let sun_rate = if day && (self.column.is_none() || depth == 0) {
                self.sun_rate(m, d, b - a).map(|k| TruncExp::new(k, a, b))
            } else {
                None
            };
            if let Some(k) = &sun_rate {
                *l += *beta * self.sun_inscatter(m, k, o, d, a, b, pc, rng);
            }
            // With a column only strobe light needs medium vertices: a share of the
            // free flights is tried (none without strobes), the rest pass analytically.
            let share = self.ff_share;
            let attempt = share >= 1.0 || (share > 0.0 && rng.next() < share);
            let c = pick_channel(pc, rng.next());
            let u = rng.next();
            let st = m.sigma_t[c];
            let t = if attempt && st > 0.0 {
                a - (1.0 - u).ln() / st
            } else {
                f64::INFINITY
            };
            if t < b {
                if let Some(h) = surface {
                    let albedo = self.albedo_over(h, self.footprint(spread, depth, o, d, h));
                    let lit = self.surface_direct(h, d, albedo, day, rng);
                    *l += *beta * tr(m.sigma_t, b - a) * lit;
                }
                let trv = tr(m.sigma_t, t - a);
                let pdf_d = share * pc.dot(m.sigma_t * trv);
                *beta *= m.sigma_s * trv / pdf_d;
                let p = o + t * d;
                let phase = &m.phase;
                let f = |w: DVec3| DVec3::splat(phase.eval(d.dot(w)));
                let pdf = |w: DVec3| self.medium_pdf(m, d, w);
                let pw = |i: usize, x: DVec3| {
                    let seg = match segs.get(i) {
                        Some(s) => *s,
                        None => LampSeg::new(m, o, d, a, b, x, self.lamp_phase_sampling),
                    };
                    let pe = seg.equiangular_pdf(t);
                    let pp = seg.phase_pdf(m, t);
                    power3(pdf_d, pe, pp)
                };
                // With a column, daylight ends at a medium vertex (the column holds
                // the light scattered in the water).
                let sw = if self.column.is_some() || !day {
                    0.0
                } else {
                    sun_rate.map_or(1.0, |k| power(pdf_d, k.pdf(t)))
                };
                *l += *beta * self.direct(p, f, pdf, pw, sw, rng);
                let (nd, ppdf) = self.sample_medium(m, d, rng);
                if ppdf <= 0.0 {
                    return SegmentEnd::Ends;
                }
                *beta *= phase.eval(d.dot(nd)) / ppdf;
                return SegmentEnd::Scattered {
                    o: p,
                    d: nd,
                    pdf: ppdf,
                };
            }
            let trv = tr(m.sigma_t, b - a);
            let p_pass = if share >= 1.0 {
                pc.dot(trv)
            } else {
                (1.0 - share) + share * pc.dot(trv)
            };
            if p_pass <= 0.0 {
                return SegmentEnd::Ends;
            }
            let beta_nee = *beta * trv;
            *beta *= trv / p_pass;
            SegmentEnd::Passed { beta_nee }
        } else {
            *beta *= tr(m.sigma_t, b - a);
            SegmentEnd::Passed { beta_nee: *beta }
        }
    }

    /// A ray that meets nothing, leaving from `o` along `d`: adds the sky to `l` where the path
    /// carries traced daylight. Where it leaves the water upwards under a reflecting surface
    /// ([`Integrator::underside`]) the sky is seen through Snell's window, and the mirrored
    /// ray is returned when the path follows the reflection (Fresnel, total beyond the
    /// critical angle; chosen with the channels' mean reflectance, `beta` reweighted). The
    /// flat mean plane serves under waves too, as in the column.
    #[allow(clippy::too_many_arguments)]
    fn leave(
        &self,
        o: DVec3,
        d: DVec3,
        day: bool,
        can_scatter: bool,
        l: &mut DVec3,
        beta: &mut DVec3,
        rng: &mut Sampler,
    ) -> Option<(DVec3, DVec3)> {
        // With a column the sky is in its table (added along the segment before).
        let sky = if day && self.column.is_none() {
            self.lights.ambient
        } else {
            DVec3::ZERO
        };
        let Some(n) = self.underside.filter(|_| d.z > 0.0 && o.z < 0.0) else {
            *l += *beta * sky;
            return None;
        };
        let r = DVec3::from_array([0, 1, 2].map(|c| column::reflectance_from_below(n[c], d.z)));
        *l += *beta * DVec3::from_array([0, 1, 2].map(|c| column::sky_below(n[c], sky[c], d.z)));
        let q = mean(r);
        if !can_scatter || !(q > 0.0) || rng.next() >= q {
            return None;
        }
        *beta *= r / q;
        let p = o + (-o.z / d.z) * d;
        let p = DVec3::new(p.x, p.y, -SURFACE_OFFSET * (1.0 + p.abs().max_element()));
        Some((p, DVec3::new(d.x, d.y, -d.z)))
    }

    /// The column's daylight scattered towards `o` along the ray `o + t d` up to `t_end` (a
    /// surface, or ∞): `L_m(z_o, d) − T(t_end) L_m(z_end, d)` ([`crate::optics::column`]),
    /// without the sun's first scattering (the camera ray traces it, with the shadows it
    /// shows): the gather's fallback where it cannot draw a distance.
    fn column_segment(
        &self,
        col: &crate::optics::column::Column,
        o: DVec3,
        d: DVec3,
        t_end: f64,
    ) -> DVec3 {
        self.column_between(col, o, d, t_end, |z, w| col.radiance(z, w, false))
    }

    /// `read(z_o, d) − T(o→q) · read(z_q, d)` up to a surface at `q = o + t_end d`, or
    /// `read(z_o, d)` plus the column's boundary through the water when nothing is hit: the
    /// column's light reaching `o` along `d`, with the column's radiance read by `read`.
    fn column_between(
        &self,
        col: &crate::optics::column::Column,
        o: DVec3,
        d: DVec3,
        t_end: f64,
        read: impl Fn(f64, DVec3) -> DVec3,
    ) -> DVec3 {
        self.column_from(col, o, d, t_end, read(-o.z, d), read)
    }

    /// [`Integrator::column_between`] with the near end's value `near` (`read(z_o, d)`) given.
    fn column_from(
        &self,
        col: &crate::optics::column::Column,
        o: DVec3,
        d: DVec3,
        t_end: f64,
        near: DVec3,
        read: impl Fn(f64, DVec3) -> DVec3,
    ) -> DVec3 {
        if !t_end.is_finite() {
            // Nothing in the way: the sky or the column's bottom through the water.
            let s = col.to_boundary(-o.z, d);
            return if s.is_finite() {
                near + self.tr_seg(o, d, s) * col.boundary(d)
            } else {
                near
            };
        }
        let q = o + t_end * d;
        near - self.tr_seg(o, d, t_end) * read(-q.z, d)
    }

    /// The column's daylight scattered towards `o` along the camera ray `o + t d` up to
    /// `t_end`, gathered: one distance drawn ∝ the transmittance (spectral one-sample MIS),
    /// one direction from the phase function mixed with the table ([`GATHER_TABLE`]), and
    /// the column's whole diffuse radiance there
    /// (the table with the sun's first scattering, plus the boundary through the water). It
    /// estimates the same integral as [`Integrator::column_segment`], but averages the table
    /// over the phase function instead of reading two of its bins, so the table's noise does
    /// not print a bias on the image (the difference of two bins moved image means by 1–3 %).
    /// The open column's in-scattered light along the whole segment is added exactly
    /// ([`crate::optics::column::Column::scattered_along`]: the table's radiance averaged
    /// over the phase function, integrated in each channel's transmittance), and the drawn
    /// point and direction estimate only what the local geometry changes,
    /// `σs T p · (seen − h) / pdf` (a control variate, as [`Integrator::column_nee`]'s at
    /// surfaces): in open water the two nearly cancel.
    /// Adds the sky's or the bottom's radiance through the water when nothing is hit.
    fn column_gather(
        &self,
        col: &crate::optics::column::Column,
        o: DVec3,
        d: DVec3,
        t_end: f64,
        level: u32,
        rng: &mut Sampler,
    ) -> DVec3 {
        let Some(m) = &self.medium else {
            return self.column_segment(col, o, d, t_end);
        };
        let (u0, u1, u2, u3) = (rng.next(), rng.next(), rng.next(), rng.next());
        let (s, beyond) = if t_end.is_finite() {
            (t_end, DVec3::ZERO)
        } else {
            let sb = col.to_boundary(-o.z, d);
            if !sb.is_finite() {
                // Horizontal to infinity: the table's own value along it.
                return self.column_segment(col, o, d, t_end);
            }
            (sb, self.tr_seg(o, d, sb) * col.boundary(d))
        };
        // Clear water scatters nothing towards the camera: the sky or the bottom through it.
        if !m.scatters() {
            return beyond;
        }
        let Some((a, b)) = m.interval(o, d, 0.0, s) else {
            return beyond;
        };
        // The open column's in-scattered light along the segment, integrated exactly: the
        // drawn point and direction estimate only what the local geometry changes (a control
        // variate, as [`Integrator::column_nee`]'s at surfaces).
        let xa = o + a * d;
        let open = col.scattered_along(-xa.z, d, b - a, m.sigma_s, m.sigma_t) + beyond;
        let seg = TruncExp::new(m.sigma_t, a, b);
        let c = ((u0 * 3.0) as usize).min(2);
        let t = sample_trunc_exp_with(seg.k[c], a, b, u1, seg.em1[c]);
        let pdf = seg.pdf(t);
        if !(pdf > 0.0 && pdf.is_finite() && t >= a && t <= b) {
            return open;
        }
        let x = o + t * d;
        let z = -x.z;
        // One direction from the mixture of the phase function about the ray and, for
        // [`GATHER_TABLE`] of them, the table's upper half: a down-looking ray sees the bright
        // light from above by backscatter, which the phase function alone draws rarely and
        // then with a weight 10–30× the mean.
        let (u4, u5) = (rng.next(), rng.next());
        let w = if u4 < GATHER_TABLE {
            col.sample(z, true, u2, u3, u5).map(|s| s.0)
        } else {
            Some(m.phase.sample(d, u2, u3).0)
        };
        let Some(w) = w else { return open };
        let ph = m.phase.eval(d.dot(w));
        let pw = GATHER_TABLE * col.pdf(z, true, w) + (1.0 - GATHER_TABLE) * ph;
        if !(pw > 0.0) {
            return open;
        }
        let seen = self.column_towards(col, x, w, level, rng);
        let residual = seen - col.radiance_scattered(z, w);
        m.sigma_s * tr(m.sigma_t, t - a) * residual * (ph / pw) / pdf + open
    }

    /// The column's daylight arriving at the medium point `x` along `w` (from `-w`), with the
    /// local geometry in the way: where `w` meets a surface, the column's light scattered in
    /// the water up to it plus the surface's own daylight (sun and column, next-event
    /// estimated with its texture and shadows) through the water; else the column's whole
    /// diffuse radiance and its boundary (sky, bottom) through the water. Reading the
    /// column's bottom instead of the surface would light the water from a uniform seabed of
    /// the bottom albedo: the forward-scattered image of the seabed, 30–60 % of what a camera
    /// 3 m above it sees in coastal water, would lose its texture and take the bottom's mean
    /// albedo for the footprint's.
    fn column_towards(
        &self,
        col: &crate::optics::column::Column,
        x: DVec3,
        w: DVec3,
        level: u32,
        rng: &mut Sampler,
    ) -> DVec3 {
        let z = -x.z;
        let (hit, t_end, area_hit) = self.first_hit(x, w);
        if let Some(h) = hit.filter(|_| area_hit.is_none()) {
            let albedo = self.albedo(&h);
            let lit = if albedo == DVec3::ZERO {
                DVec3::ZERO
            } else {
                self.surface_light(&h, w, albedo, false, true, rng)
            };
            // Gathered again only where the water up to the surface scatters enough for its
            // texture-blind table value to matter ([`GATHER_DEEPER_FROM`]).
            let deeper = self
                .medium
                .as_ref()
                .is_some_and(|m| m.sigma_s.max_element() * h.t >= GATHER_DEEPER_FROM);
            let water = if level + 1 < GATHER_LEVELS && deeper {
                self.column_gather(col, x, w, h.t, level + 1, rng)
            } else {
                self.column_between(col, x, w, h.t, |z, v| col.radiance(z, v, true))
                    .max(DVec3::ZERO)
            };
            return water + self.tr_seg(x, w, h.t) * lit;
        }
        if area_hit.is_some() {
            // An area light is no daylight: the water up to it.
            return self
                .column_between(col, x, w, t_end, |z, v| col.radiance(z, v, true))
                .max(DVec3::ZERO);
        }
        let lw = col.radiance(z, w, true);
        let sb = col.to_boundary(z, w);
        let lb = if sb.is_finite() {
            self.tr_seg(x, w, sb) * col.boundary(w)
        } else {
            DVec3::ZERO
        };
        lw + lb
    }

    /// Next-event estimate of the light reflected at surface hit `h` (of albedo `albedo`,
    /// [`Integrator::albedo`]) towards `-d` (no path weight). `day`: the path still carries
    /// daylight (sun, and the column's light when there is one).
    fn surface_direct(
        &self,
        h: &Hit,
        d: DVec3,
        albedo: DVec3,
        day: bool,
        rng: &mut Sampler,
    ) -> DVec3 {
        self.surface_light(h, d, albedo, true, day, rng)
    }

    /// [`Integrator::surface_direct`] from the lamps (strobes, area lights) when `lamps`, and
    /// from daylight (the sun, and the column's light) when `day`.
    fn surface_light(
        &self,
        h: &Hit,
        d: DVec3,
        albedo: DVec3,
        lamps: bool,
        day: bool,
        rng: &mut Sampler,
    ) -> DVec3 {
        let n = if h.normal.dot(d) > 0.0 {
            -h.normal
        } else {
            h.normal
        };
        if albedo == DVec3::ZERO {
            return DVec3::ZERO;
        }
        let p = h.point + n * SURFACE_OFFSET * (1.0 + h.point.abs().max_element());
        let f = |w: DVec3| {
            let c = n.dot(w);
            if c > 0.0 {
                albedo * (c / PI)
            } else {
                DVec3::ZERO
            }
        };
        let pdf = |w: DVec3| self.surface_pdf(n, w);
        let mut l = if lamps {
            self.direct(p, f, pdf, |_, _| 1.0, if day { 1.0 } else { 0.0 }, rng)
        } else if day {
            self.sun_direct(p, &f, 1.0)
        } else {
            DVec3::ZERO
        };
        if day && let Some(col) = self.column {
            l += self.column_nee(col, p, n, albedo, rng);
        }
        l
    }

    /// Next-event estimate of the column's daylight reflected at `p` (normal `n`, Lambertian
    /// `albedo`), with the open plane's irradiance as a control variate: the
    /// irradiance the column puts on an unshaded plane of normal `n` at that depth
    /// ([`crate::optics::column::Column::irradiance_open`], exact but for the normals' grid),
    /// plus a one-direction estimate of what the local geometry changes,
    /// `f · (seen − open) / pdf`: `seen` is the light arriving along the direction (the
    /// column's in the water up to what it meets, traced to the local geometry), `open` what
    /// an open plane receives ([`crate::optics::column::Column::radiance_open`]). Where nothing
    /// shades the point the two nearly cancel, so a rough seabed's unshaded facets carry no
    /// noise from the column's light. The direction comes from the column's normal-aware
    /// sampler ([`crate::optics::column::Column::sample_open`], nearly ∝ open radiance ×
    /// max(0, n·ω), so that `f · open / pdf` stays near the open irradiance where the point
    /// is shaded) mixed with the cosine lobe ([`COLUMN_NEE_COSINE`], so that every direction
    /// the surface faces has a density). It is the only estimator of the column's light at
    /// surfaces: the bounce leaving `p` adds none.
    fn column_nee(
        &self,
        col: &crate::optics::column::Column,
        p: DVec3,
        n: DVec3,
        albedo: DVec3,
        rng: &mut Sampler,
    ) -> DVec3 {
        let z = -p.z;
        let open = albedo / PI * col.irradiance_open(z, n);
        let (u0, u1, u2, u3) = (rng.next(), rng.next(), rng.next(), rng.next());
        let table = 1.0 - COLUMN_NEE_COSINE;
        // The direction, and the table's density there when it drew it (the cosine lobe's
        // draws look it up).
        let drawn = if u0 < table {
            col.sample_open(z, n, [u0 / table, u1, u2, u3])
                .map(|(w, p)| (w, Some(p)))
        } else {
            let r = u1.sqrt();
            let phi = 2.0 * PI * u2;
            let (tx, ty) = n.any_orthonormal_pair();
            let c = (1.0 - u1).max(0.0).sqrt();
            Some((
                (tx * (r * phi.cos()) + ty * (r * phi.sin()) + n * c).normalize(),
                None,
            ))
        };
        // A draw that fails, or falls below the surface's horizon, estimates the difference
        // as 0 there: the mixture's density covers every direction the surface faces.
        let Some((w, p_table)) = drawn else {
            return open;
        };
        let cos = n.dot(w);
        if cos <= 0.0 || albedo == DVec3::ZERO {
            return open;
        }
        let fv = albedo * (cos / PI);
        let p_table = p_table.unwrap_or_else(|| col.pdf_open(z, n, w));
        let pdf = table * p_table + COLUMN_NEE_COSINE * cos / PI;
        if !(pdf > 0.0) {
            return open;
        }
        let t = self
            .scene
            .intersect(&Ray { origin: p, dir: w }, f64::INFINITY)
            .map_or(f64::INFINITY, |h| h.t);
        // `seen` and `h` read the same bin at the point: looked up once.
        let b = col.binned_sum(z, w);
        let seen = self
            .column_from(col, p, w, t, b.max(DVec3::ZERO), |z, w| {
                col.radiance_binned(z, w)
            })
            .max(DVec3::ZERO);
        open + fv * (seen - (b + col.boundary_open(z, w.z))) / pdf
    }

    fn roulette(&self, beta: &mut DVec3, depth: u32, rng: &mut Sampler) -> bool {
        if depth < self.roulette_from {
            return true;
        }
        let q = beta.max_element().min(0.95);
        if q <= 0.0 || rng.next() >= q {
            return false;
        }
        *beta /= q;
        true
    }

    /// Rates per channel (1/m) of the truncated exponentials that sample the sunlight scattered
    /// along a medium segment of direction `d` and length `len`: the water crossed from the
    /// segment's start plus the water above the point towards the sun, `σt (1 + d_z / s_z)`
    /// for the sun's propagation direction `s`. `None` without a sun, or when a rate is not
    /// positive on an unbounded segment (no normalisable density).
    fn sun_rate(&self, m: &Medium, d: DVec3, len: f64) -> Option<DVec3> {
        let sun = self.lights.sun.as_ref()?;
        if !self.sun_sampling || sun.dir().z >= 0.0 || !(len > 0.0) {
            return None;
        }
        let k = m.sigma_t * (DVec3::ONE + d.z / DVec3::from_array(sun.dirs.map(|s| s.z)));
        if !len.is_finite() && k.min_element() <= 0.0 {
            return None;
        }
        Some(k)
    }

    /// Sunlight scattered towards `o` along `[a, b]` of the ray, at a distance sampled by
    /// [`TruncExp::pdf`] and MIS-weighted against free-flight sampling. Excludes the ray's `beta`.
    #[allow(clippy::too_many_arguments)]
    fn sun_inscatter(
        &self,
        m: &Medium,
        k: &TruncExp,
        o: DVec3,
        d: DVec3,
        a: f64,
        b: f64,
        pc: DVec3,
        rng: &mut Sampler,
    ) -> DVec3 {
        let Some(sun) = &self.lights.sun else {
            return DVec3::ZERO;
        };
        let c = ((rng.next() * 3.0) as usize).min(2);
        let u = rng.next();
        let t = sample_trunc_exp_with(k.k[c], a, b, u, k.em1[c]);
        if !(t >= a && t <= b) {
            return DVec3::ZERO;
        }
        let pdf_s = k.pdf(t);
        if !(pdf_s > 0.0 && pdf_s.is_finite()) {
            return DVec3::ZERO;
        }
        let p = o + t * d;
        let dir = -sun.dir();
        let phase = |w: DVec3| DVec3::splat(m.phase.eval(d.dot(w)));
        let ft = self.sun_arriving(sun, p, &phase);
        if ft == DVec3::ZERO {
            return DVec3::ZERO;
        }
        let trc = tr(m.sigma_t, t - a);
        let pdf_d = pc.dot(m.sigma_t * trc);
        // With a column no medium vertex gathers sunlight: this sampler is the only one.
        let w = if self.column.is_some() {
            1.0
        } else {
            power(pdf_s, pdf_d)
        };
        if w <= 0.0
            || self
                .scene
                .occluded_ray(&Ray { origin: p, dir }, f64::INFINITY)
        {
            return DVec3::ZERO;
        }
        let caustic = self.scene.caustics.as_ref().map_or(1.0, |v| v.factor(p));
        m.sigma_s * trc * ft * sun.irradiance * (caustic * w / pdf_s)
    }

    /// In-scattered radiance from point light `pl` along `[a, b]` of the ray, at a distance
    /// sampled by phase-angular sampling ([`Integrator::lamp_phase_pdf`]) and MIS-weighted
    /// against free flight and equiangular sampling. Excludes the ray's `beta`.
    #[allow(clippy::too_many_arguments)]
    fn lamp_phase(
        &self,
        m: &Medium,
        pl: &super::lights::PointLight,
        o: DVec3,
        d: DVec3,
        a: f64,
        b: f64,
        seg: &LampSeg,
        pc: DVec3,
        rng: &mut Sampler,
    ) -> DVec3 {
        let (delta, dd) = (seg.delta, seg.dd);
        let (ua, ub) = (seg.ua, seg.ub);
        let u = ua + (ub - ua) * rng.next();
        let mu = m.phase.sample_cos(u).clamp(-1.0 + 1e-12, 1.0 - 1e-12);
        let t = delta - dd * mu / (1.0 - mu * mu).sqrt();
        if !(t >= a && t <= b) {
            return DVec3::ZERO;
        }
        let pdf_p = seg.phase_pdf(m, t);
        let pdf_e = seg.equiangular_pdf(t);
        self.lamp_inscatter_at(m, pl, o, d, a, t, pdf_p, pdf_e, pc)
    }

    /// One sample of a lamp's in-scattering at distance `t` on `[a, …]` of the ray, drawn
    /// with density `pdf_own` by one of the two lamp techniques; `pdf_other` is the other
    /// technique's density there. MIS-weighted (power heuristic) against both and free flight.
    #[allow(clippy::too_many_arguments)]
    fn lamp_inscatter_at(
        &self,
        m: &Medium,
        pl: &super::lights::PointLight,
        o: DVec3,
        d: DVec3,
        a: f64,
        t: f64,
        pdf_own: f64,
        pdf_other: f64,
        pc: DVec3,
    ) -> DVec3 {
        if !(pdf_own > 0.0 && pdf_own.is_finite()) {
            return DVec3::ZERO;
        }
        let p = o + t * d;
        let i_to = pl.intensity_to(p);
        if i_to == DVec3::ZERO {
            return DVec3::ZERO;
        }
        let wl = pl.pos - p;
        let r2 = wl.length_squared();
        let r = r2.sqrt();
        let dir = wl / r;
        let trc = tr(m.sigma_t, t - a);
        let pdf_d = self.ff_share * pc.dot(m.sigma_t * trc);
        let w = power3(pdf_own, pdf_d, pdf_other);
        if w <= 0.0 || self.scene.occluded(p, pl.pos) {
            return DVec3::ZERO;
        }
        m.sigma_s * trc * m.phase.eval(d.dot(dir)) * i_to * self.tr_seg(p, dir, r) / r2
            * (w / pdf_own)
    }

    /// In-scattered radiance from point light `pl` along `[a, b]` of the ray, sampled
    /// equiangularly and MIS-weighted against distance sampling. Excludes the ray's `beta`.
    #[allow(clippy::too_many_arguments)]
    fn equiangular(
        &self,
        m: &Medium,
        pl: &super::lights::PointLight,
        o: DVec3,
        d: DVec3,
        a: f64,
        seg: &LampSeg,
        pc: DVec3,
        rng: &mut Sampler,
    ) -> DVec3 {
        let (delta, dd, ta, tb) = (seg.delta, seg.dd, seg.ta, seg.tb);
        if tb <= ta {
            return DVec3::ZERO;
        }
        let u = rng.next();
        let t = delta + dd * (ta + u * (tb - ta)).tan();
        if !(t >= seg.a && t <= seg.b) {
            return DVec3::ZERO;
        }
        let pdf_e = seg.equiangular_pdf(t);
        let pdf_p = seg.phase_pdf(m, t);
        self.lamp_inscatter_at(m, pl, o, d, a, t, pdf_e, pdf_p, pc)
    }
}

/// Density at `t` of the truncated exponential of rate `k` (1/m, any sign) on `[a, b]`:
/// `k e^(−k (t−a)) / (1 − e^(−k (b−a)))`, uniform as `k → 0`.
#[cfg(test)]
fn trunc_exp_pdf(k: f64, a: f64, b: f64, t: f64) -> f64 {
    trunc_exp_pdf_with(k, a, b, t, trunc_exp_em1(k, b - a))
}

/// `e^(−|k| len) − 1`: the normalisation shared by [`trunc_exp_pdf_with`] and
/// [`sample_trunc_exp_with`] on a segment of length `len` (computed once per segment).
#[inline]
fn trunc_exp_em1(k: f64, len: f64) -> f64 {
    (-k.abs() * len).exp_m1()
}

/// [`trunc_exp_pdf`] given `em1 = trunc_exp_em1(k, b − a)`.
#[inline]
fn trunc_exp_pdf_with(k: f64, a: f64, b: f64, t: f64, em1: f64) -> f64 {
    let len = b - a;
    if !len.is_finite() {
        return if k > 0.0 {
            k * (-k * (t - a)).exp()
        } else {
            0.0
        };
    }
    if (k * len).abs() < 1e-9 {
        return 1.0 / len;
    }
    if k > 0.0 {
        k * (-k * (t - a)).exp() / -em1
    } else {
        // Written from the far end so that nothing overflows: q e^(−q (b−t)) / (1 − e^(−q len)).
        let q = -k;
        q * (-q * (b - t)).exp() / -em1
    }
}

/// Sample `t` on `[a, b]` from the truncated exponential of rate `k` with the uniform `u`.
#[cfg(test)]
fn sample_trunc_exp(k: f64, a: f64, b: f64, u: f64) -> f64 {
    sample_trunc_exp_with(k, a, b, u, trunc_exp_em1(k, b - a))
}

/// [`sample_trunc_exp`] given `em1 = trunc_exp_em1(k, b − a)`.
#[inline]
fn sample_trunc_exp_with(k: f64, a: f64, b: f64, u: f64, em1: f64) -> f64 {
    let len = b - a;
    if !len.is_finite() {
        return a - (1.0 - u).ln() / k;
    }
    if (k * len).abs() < 1e-9 {
        return a + u * len;
    }
    if k > 0.0 {
        (a - (u * em1).ln_1p() / k).clamp(a, b)
    } else {
        let q = -k;
        (b + (u * em1).ln_1p() / q).clamp(a, b)
    }
}

/// Truncated exponentials on one medium segment `[a, b]`, one rate per channel, with their
/// normalisations computed once per segment for the sampler and the densities: sun-aware
/// distance sampling ([`Integrator::sun_rate`]) and the column's gather (rates σt).
#[derive(Debug, Clone, Copy)]
struct TruncExp {
    k: DVec3,
    a: f64,
    b: f64,
    /// `trunc_exp_em1(k_c, b − a)` per channel.
    em1: DVec3,
}

impl TruncExp {
    fn new(k: DVec3, a: f64, b: f64) -> TruncExp {
        let len = b - a;
        TruncExp {
            k,
            a,
            b,
            em1: DVec3::new(
                trunc_exp_em1(k.x, len),
                trunc_exp_em1(k.y, len),
                trunc_exp_em1(k.z, len),
            ),
        }
    }

    /// Density at `t` with a channel picked uniformly: the mean of the three channels'
    /// truncated exponentials.
    #[inline]
    fn pdf(&self, t: f64) -> f64 {
        let (k, a, b, e) = (self.k, self.a, self.b, self.em1);
        (trunc_exp_pdf_with(k.x, a, b, t, e.x)
            + trunc_exp_pdf_with(k.y, a, b, t, e.y)
            + trunc_exp_pdf_with(k.z, a, b, t, e.z))
            / 3.0
    }
}

/// Power heuristic among three techniques: the weight of the first.
#[inline]
fn power3(a: f64, b: f64, c: f64) -> f64 {
    let (a2, b2, c2) = (a * a, b * b, c * c);
    if a2 + b2 + c2 > 0.0 {
        a2 / (a2 + b2 + c2)
    } else {
        0.0
    }
}

/// Distance of `x` along the ray `o + t d` (`δ`) and off it (`dd`, at least 1e-9 m).
fn along_off(o: DVec3, d: DVec3, x: DVec3) -> (f64, f64) {
    let delta = (x - o).dot(d);
    (delta, (o + delta * d - x).length().max(1e-9))
}

/// The phase sampler's variable `u` at the two ends `a`, `b` of a segment whose light lies
/// `delta` along and `dd` off the ray: phase-angular sampling draws `u` between them.
fn phase_window(m: &Medium, delta: f64, dd: f64, a: f64, b: f64) -> (f64, f64) {
    (
        m.phase.u_of_cos(mu_at(delta, dd, a)),
        m.phase.u_of_cos(mu_at(delta, dd, b)),
    )
}

/// Cosine between the ray and the direction from its point at `t` to a light at (`δ`, `dd`);
/// −1 at `t = +∞`.
fn mu_at(delta: f64, dd: f64, t: f64) -> f64 {
    if t.is_infinite() {
        return -t.signum();
    }
    let q = delta - t;
    q / (dd * dd + q * q).sqrt()
}

/// Point lights whose [`LampSeg`] a medium segment keeps (on the stack); the MIS weights of
/// any further light recompute it.
const LAMP_CACHE: usize = 8;

/// A point light's geometry relative to one medium segment `[a, b]` of the ray `o + t d`,
/// shared by equiangular and phase-angular sampling and their densities (computed once per
/// segment and light: the two `atan2` and the phase window are the costly part).
#[derive(Debug, Clone, Copy, Default)]
struct LampSeg {
    a: f64,
    b: f64,
    /// The light's distance along (`δ`) and off (`dd`) the ray.
    delta: f64,
    dd: f64,
    /// Equiangular sampling's angles at `a` and `b`.
    ta: f64,
    tb: f64,
    /// Phase-angular sampling's window `[u(a), u(b)]` and its mass (0 when that sampling is
    /// off).
    ua: f64,
    ub: f64,
    mass: f64,
}

impl LampSeg {
    /// The segment `[a, b]` of `o + t d` seen from a light at `x`; `phase` when phase-angular
    /// sampling is on.
    fn new(m: &Medium, o: DVec3, d: DVec3, a: f64, b: f64, x: DVec3, phase: bool) -> LampSeg {
        let (delta, dd) = along_off(o, d, x);
        let ta = (a - delta).atan2(dd);
        let tb = (b - delta).atan2(dd);
        let (ua, ub) = if phase {
            phase_window(m, delta, dd, a, b)
        } else {
            (0.0, 0.0)
        };
        LampSeg {
            a,
            b,
            delta,
            dd,
            ta,
            tb,
            ua,
            ub,
            mass: (ua - ub).abs(),
        }
    }

    /// Density of equiangular sampling of `t` on the segment.
    #[inline]
    fn equiangular_pdf(&self, t: f64) -> f64 {
        let (delta, dd, ta, tb) = (self.delta, self.dd, self.ta, self.tb);
        if tb <= ta {
            return 0.0;
        }
        dd / ((tb - ta) * (dd * dd + (t - delta) * (t - delta)))
    }

    /// Density at `t` of phase-angular sampling (0 when it is off): the cosine
    /// `μ(t) = (δ − t)/r` between the ray and the direction to the light is drawn from the
    /// phase function restricted to `[μ(b), μ(a)]`, so `p(t) = 2π p(μ) · dd²/r³ / mass`
    /// (`r`: from the point to the light).
    #[inline]
    fn phase_pdf(&self, m: &Medium, t: f64) -> f64 {
        let mass = self.mass;
        if !(mass > 0.0) {
            return 0.0;
        }
        let (delta, dd) = (self.delta, self.dd);
        let r = (dd * dd + (t - delta) * (t - delta)).sqrt();
        let mu = (delta - t) / r;
        2.0 * PI * m.phase.eval(mu) * dd * dd / (r * r * r) / mass
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The truncated exponential's sampler and density agree: the density integrates to 1 and
    /// the share of samples in each tenth of the interval matches its integral, for rising,
    /// falling, flat and unbounded segments.
    #[test]
    fn truncated_exponential_sampling_matches_its_density() {
        for &(k, a, b) in &[
            (2.0, 1.0, 4.0),
            (-1.5, 0.0, 3.0),
            (1e-12, 0.5, 2.5),
            (-4.0, 0.0, 30.0),
            (0.7, 0.2, f64::INFINITY),
        ] {
            let hi = if f64::is_finite(b) { b } else { a + 20.0 / k };
            let bins = 10;
            let w = (hi - a) / bins as f64;
            let n = 200_000;
            let mut counts = vec![0usize; bins];
            for i in 0..n {
                let u = (i as f64 + 0.5) / n as f64;
                let t = sample_trunc_exp(k, a, b, u);
                assert!(t >= a && t <= b, "k {k}: t {t} outside [{a}, {b}]");
                let j = (((t - a) / w) as usize).min(bins - 1);
                counts[j] += 1;
            }
            let mut total = 0.0;
            for (j, &c) in counts.iter().enumerate() {
                // Integral of the density over the bin (Simpson, 64 panels).
                let (lo, up) = (a + j as f64 * w, a + (j + 1) as f64 * w);
                let m = 64;
                let h = (up - lo) / m as f64;
                let mass: f64 = (0..=m)
                    .map(|i| {
                        let c = if i == 0 || i == m {
                            1.0
                        } else if i % 2 == 1 {
                            4.0
                        } else {
                            2.0
                        };
                        c * trunc_exp_pdf(k, a, b, lo + i as f64 * h)
                    })
                    .sum::<f64>()
                    * h
                    / 3.0;
                total += mass;
                let share = c as f64 / n as f64;
                assert!(
                    (share - mass).abs() < 2e-3,
                    "k {k}, bin {j}: {share} vs {mass}"
                );
            }
            assert!(
                (total - 1.0).abs() < 2e-3 || !f64::is_finite(b),
                "k {k}: {total}"
            );
        }
        // Steep rates on long segments neither overflow nor lose the sample.
        let (k, a, b) = (-400.0, 0.0, 30.0);
        let t = sample_trunc_exp(k, a, b, 0.5);
        assert!((b - t - 2f64.ln() / 400.0).abs() < 1e-9, "{t}");
        assert!((trunc_exp_pdf(k, a, b, b) - 400.0).abs() < 1e-9);
        assert_eq!(trunc_exp_pdf(k, a, b, a), 0.0);
    }
}
