//! The water column's light: the plane-parallel radiative-transfer problem of ocean optics
//! (what Hydrolight and DISORT solve), solved once per scene by a 1D Monte Carlo into a
//! radiance table, so that the 3D renderer lights the local scene with it instead of
//! random-walking daylight up tens of metres of water (docs/column.md).
//!
//! | input ([`ColumnInput`]) | meaning |
//! |---|---|
//! | `depth` | the column's Lambertian bottom, m below the surface (the site's seabed) |
//! | `sigma_a`, `sigma_s` | per channel, 1/m; absorption must be > 0 in every channel |
//! | `phase` | [`PhaseFn`]: HG, or Fournier–Forand tabulated exactly as the renderer's |
//! | `sun` | refracted beam per channel: its direction in the water (each channel refracts with its own index), irradiance on a plane normal to the beam just below the surface |
//! | `ambient` | the sky's isotropic radiance: with [`Top::Open`], arriving from every downward direction just below the surface; with [`Top::Fresnel`], the sky above the surface, seen below it through Snell's window (refracted, times the Fresnel transmittance and `n²`: [`sky_below`]) |
//! | `bottom_albedo` | per channel |
//! | `top` | [`Top::Open`]: light reaching the surface from below leaves (the renderers' model); [`Top::Fresnel`]: a flat water–air surface reflects it with the unpolarised Fresnel reflectance, wholly beyond the critical angle (total internal reflection) |
//!
//! | output ([`Column`]) | meaning |
//! |---|---|
//! | [`Column::radiance`] | `L_m(z, ω)`: radiance seen at depth `z` looking along `ω` that was scattered in the water on its way, the sun's *first* scattering apart (the renderer traces it on camera rays, with shadows) |
//! | [`Column::boundary`] | the sky's and the bottom's own radiance (analytic: `L_sky` or the sky through Snell's window, `A·E_d(H)/π`), seen through the water where a ray meets no geometry |
//! | [`Profile`] | per channel, at `nz + 1` planes: E_d (direct, diffuse), E_u, E_0, K_d, with standard errors |
//! | [`Column::seen_orders`] | the radiance seen looking down in every layer, split by the number of events the light met: what a bounce limit cuts off ([`Column::share_seen_beyond`]) |
//!
//! Method: photons are launched from the sun (its direct beam is analytic) and from the sky,
//! flown with implicit capture, and tallied by track length into `nz` depth layers × `nmu`
//! polar bins uniform in angle (3.75°) × `nphi` bins of azimuth relative to the sun (folded by symmetry),
//! and by crossings of the `nz + 1` planes for the irradiances. Photon tracks are tagged by
//! order: the sun's first-scattered light is tallied apart (the profiles include it, the
//! table does not). A weight window `w(z) ∝ e^(−K z)` splits and roulettes photons so that
//! every depth keeps a population (turbid water 30 m deep is 10⁻⁴ of the surface light).
//! Batches with independent counter-seeded streams run in parallel and are summed in order:
//! the bytes do not depend on the thread count; the batches give the standard errors.

mod clear;
mod open;
mod scatter;

use super::phase::PhaseFn;
use crate::rng::SplitMix64;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Depth layers of the table.
pub const NZ: usize = 64;
/// Bins in the polar angle of the look direction (uniform in angle, from the nadir to the
/// zenith: 3.75° each, so that light peaked about the vertical, red through deep water, is
/// resolved at the poles).
pub const NMU: usize = 48;
/// Bins of azimuth relative to the sun, over [0, π] (folded).
pub const NPHI: usize = 18;

/// Independent batches per round (standard errors, parallelism).
pub const BATCHES: usize = 32;
/// Rounds at most: the solve stops earlier once E_d at the seabed is known to
/// [`TARGET_STDERR`].
pub const MAX_ROUNDS: usize = 16;
/// Relative standard error of E_d at the seabed a channel is solved to.
pub const TARGET_STDERR: f64 = 0.002;
/// Channels keeping less than this share of the surface's light at the seabed take one round
/// (they are black in an image: 10 stops down).
pub const VISIBLE: f64 = 1e-3;
/// Scattering events after which a photon history is ended (its weight is counted as lost).
const MAX_EVENTS: u32 = 200_000;
/// Scattering orders the radiance seen looking down is split into ([`Column::seen_orders`]);
/// the last bin holds this many events or more.
pub const ORDERS: usize = 256;
/// Cosine of the cone about the nadir whose radiance [`Column::share_seen_beyond`] splits by
/// order (30°: the view of a survey camera looking down).
pub const SEEN_CONE: f64 = 0.866;
/// Flights a batch may spend per launched photon before it stops splitting (the weight
/// window's estimate of the attenuation can be off; this bounds the work, never the light).
const FLIGHT_BUDGET: usize = 60;

/// The refracted sun in the water.
#[derive(Debug, Clone, Copy)]
pub struct ColumnSun {
    /// Unit propagation direction in the water per channel (z < 0, world z up): the sun
    /// refracts with each channel's index.
    pub dirs: [DVec3; 3],
    /// Irradiance on a plane normal to `dir`, just below the surface, W/m² per channel.
    pub irradiance: [f64; 3],
}

/// Everything the column depends on.
#[derive(Debug, Clone)]
pub struct ColumnInput {
    pub depth: f64,
    pub sigma_a: [f64; 3],
    pub sigma_s: [f64; 3],
    pub phase: PhaseFn,
    pub sun: Option<ColumnSun>,
    pub ambient: [f64; 3],
    pub bottom_albedo: [f64; 3],
    pub top: Top,
    /// Photons per channel per round (sun and sky together; see [`MAX_ROUNDS`]).
    pub photons: usize,
    pub seed: u64,
}

/// The sea surface seen from below.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Top {
    /// Light reaching the surface from below leaves the water.
    #[default]
    Open,
    /// A flat surface of water of this index (per channel) under air: light from below is
    /// reflected with the unpolarised Fresnel reflectance, totally beyond the critical angle,
    /// and the sky's light comes in through Snell's window ([`sky_below`]).
    Fresnel([f64; 3]),
}

impl Top {
    /// The water's index under a reflecting surface (the sky through Snell's window).
    pub fn window(self) -> Option<[f64; 3]> {
        match self {
            Top::Fresnel(n) => Some(n),
            Top::Open => None,
        }
    }
}

/// The radiance below a flat water–air surface, looking up at `cos_w` (> 0) to the vertical,
/// of a sky of isotropic radiance `sky` above it: `n² · T · sky` inside Snell's window (the
/// radiance law at a refracting interface; `T = 1 − R` the Fresnel transmittance, the same
/// both ways), 0 beyond the critical angle, where the surface reflects the water's light.
pub fn sky_below(n_water: f64, sky: f64, cos_w: f64) -> f64 {
    if !(cos_w > 0.0) {
        return 0.0;
    }
    n_water * n_water * (1.0 - reflectance_from_below(n_water, cos_w)) * sky
}

/// Unpolarised Fresnel reflectance of a flat water–air surface for light arriving from the
/// water at `cos_w` (> 0) to the vertical; 1 beyond the critical angle.
pub fn reflectance_from_below(n_water: f64, cos_w: f64) -> f64 {
    let sin_a2 = n_water * n_water * (1.0 - cos_w * cos_w).max(0.0);
    if sin_a2 >= 1.0 {
        return 1.0;
    }
    let cos_a = (1.0 - sin_a2).sqrt();
    1.0 - super::interface::fresnel_transmittance(n_water, 1.0, cos_w, cos_a)
}

/// The sky's radiance seen looking up at `cos_w` (> 0) to the vertical, per channel: `sky`
/// itself below an open surface, through Snell's window below a reflecting one.
fn sky_seen(sky: DVec3, window: Option<[f64; 3]>, cos_w: f64) -> DVec3 {
    match window {
        None => sky,
        Some(n) => DVec3::from_array([0, 1, 2].map(|c| sky_below(n[c], sky[c], cos_w))),
    }
}

/// A sky photon's direction in the water and weight: isotropic radiance, cosine-weighted
/// downward directions (in the air above a reflecting surface, then refracted into the water
/// with the Fresnel transmittance; the n² of the radiance is the window's narrower solid angle).
fn sky_photon(top: Top, c: usize, u1: f64, u2: f64) -> (DVec3, f64) {
    let phi = 2.0 * PI * u2;
    let (sin, w) = match top {
        Top::Open => (u1.sqrt(), 1.0),
        Top::Fresnel(n) => {
            let sin_w = u1.sqrt() / n[c];
            let cos_w = (1.0 - sin_w * sin_w).max(0.0).sqrt();
            (sin_w, 1.0 - reflectance_from_below(n[c], cos_w))
        }
    };
    let cos = (1.0 - sin * sin).max(0.0).sqrt();
    (DVec3::new(sin * phi.cos(), sin * phi.sin(), -cos), w)
}

/// Why a column cannot be solved.
#[derive(Debug, Clone, PartialEq)]
pub enum ColumnError {
    /// A channel without absorption: the light never dies, the walk does not converge.
    NoAbsorption { channel: usize },
    /// Not a positive finite depth.
    BadDepth(f64),
    /// A coefficient or a light that is negative or not finite.
    BadInput(String),
}

impl std::fmt::Display for ColumnError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColumnError::NoAbsorption { channel } => write!(
                f,
                "the water does not absorb in channel {} (σa = 0): light scattered in it never \
                 dies, so the column has no converged solution",
                ["R", "G", "B"][(*channel).min(2)]
            ),
            ColumnError::BadDepth(d) => {
                write!(
                    f,
                    "the column needs a seabed below the surface (depth {d} m)"
                )
            }
            ColumnError::BadInput(s) => write!(f, "{s}"),
        }
    }
}

/// Irradiance profiles of one channel at the planes `z_j = j·depth/NZ`, W/m² (horizontal
/// planes; E_0 scalar).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    pub e_d_direct: Vec<f64>,
    pub e_d_diffuse: Vec<f64>,
    pub e_u: Vec<f64>,
    pub e_0: Vec<f64>,
    /// Diffuse attenuation of E_d (total), 1/m.
    pub k_d: Vec<f64>,
    pub e_d_stderr: Vec<f64>,
    pub e_u_stderr: Vec<f64>,
}

impl Profile {
    /// Total downward irradiance at plane `j`.
    pub fn e_d(&self, j: usize) -> f64 {
        self.e_d_direct[j] + self.e_d_diffuse[j]
    }

    /// K_d at every plane from E_d at its neighbours (one-sided at the ends), planes `dz` apart.
    fn fill_k_d(&mut self, dz: f64) {
        self.k_d = (0..=NZ)
            .map(|j| {
                let (a, b) = (j.saturating_sub(1), (j + 1).min(NZ));
                let (ea, eb) = (self.e_d(a), self.e_d(b));
                if ea > 0.0 && eb > 0.0 && b > a {
                    -(eb / ea).ln() / ((b - a) as f64 * dz)
                } else {
                    0.0
                }
            })
            .collect();
    }
}

/// The solved column.
#[derive(Debug, Clone)]
pub struct Column {
    pub depth: f64,
    /// Unit horizontal direction towards the sun's azimuth (azimuth 0 of the table).
    pub sun_azimuth: DVec3,
    /// `L_m` per channel, index `(k · NMU + i) · NPHI + j`: layer k, polar bin i (from the nadir),
    /// azimuth bin j; W/(m²·sr).
    pub table: [Vec<f32>; 3],
    /// The sun's first-scattered light alone, same layout (`L_d = L_m + first`).
    pub first: [Vec<f32>; 3],
    /// Per layer and half-space (look up, look down): cumulative light × |cos θ| over the
    /// half's `NMU/2 × NPHI` bins, the channels summed (importance sampling of the camera
    /// ray's gather), last entry the total.
    cdf: Vec<[Vec<f64>; 2]>,
    pub profiles: [Profile; 3],
    /// Per channel, the radiance seen looking down within [`SEEN_CONE`] of the nadir in every
    /// layer, split by the number of events (scatterings in the water, reflections at the
    /// bottom) the light met (index `k · (ORDERS + 1) + n`, unnormalised): light going up
    /// that met `n` events, the last of them the first vertex of a camera path looking down
    /// from layer `k` ([`Column::share_seen_beyond`]).
    pub seen_orders: [Vec<f64>; 3],
    /// Share of the photons' weight lost to `MAX_EVENTS` (should be 0).
    pub truncated: f64,
    /// Photons of the channel that took the most rounds.
    pub photons: usize,
    /// The boundaries' radiances: the sky's (just below an open surface, above a reflecting
    /// one: [`Column::boundary`]), and the bottom's (`A·E_d(H)/π`), per channel.
    pub sky: DVec3,
    pub bottom: DVec3,
    /// The water's index under a reflecting surface ([`Top::Fresnel`]): the sky is seen
    /// through Snell's window.
    pub window: Option<[f64; 3]>,
    /// The water's attenuation per channel, 1/m.
    pub sigma_t: DVec3,
    /// Per layer, the open irradiance on the normals' grid ([`Column::irradiance_open`]).
    open: open::OpenLayers,
    /// Per layer, the normal-aware direction sampler's tables ([`Column::sample_open`]).
    samplers: open::SampleLayers,
    /// The water's phase function (the column's own, and the gather's control variate's).
    pub phase: PhaseFn,
    /// The open column's in-scattered light ([`Column::scattered_open`]): its quadrature,
    /// weights and tables, filled when first read.
    scatter: scatter::Tables,
    pub seconds: f64,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Order {
    /// The sun's unscattered beam (analytic, not tallied).
    Beam,
    /// Scattered once from the beam: traced by the renderer, tallied apart.
    First,
    /// Everything else: the table.
    Rest,
    /// Straight from a boundary (the sky's light coming down, the bottom's going up) to the
    /// first collision: analytic in [`Column::boundary`], not in the table (its tally would
    /// put the bottom's whole radiance, noise included, into every look at the seabed).
    Boundary,
}

#[derive(Clone, Copy)]
struct Photon {
    depth: f64,
    dir: DVec3,
    w: f64,
    order: Order,
    events: u32,
}

/// Tallies of one batch of one channel.
#[derive(Clone)]
struct Tally {
    table: Vec<f64>,
    first: Vec<f64>,
    /// Diffuse track length per layer (E_0), all orders.
    track: Vec<f64>,
    down: Vec<f64>,
    up: Vec<f64>,
    /// Track length going up within [`SEEN_CONE`] of the vertical, per layer and events met,
    /// index `k · (ORDERS + 1) + n` ([`Column::seen_orders`]).
    seen_ord: Vec<f64>,
    lost: f64,
    launched: f64,
}

impl Tally {
    fn new() -> Tally {
        Tally {
            table: vec![0.0; NZ * NMU * NPHI],
            first: vec![0.0; NZ * NMU * NPHI],
            track: vec![0.0; NZ],
            down: vec![0.0; NZ + 1],
            up: vec![0.0; NZ + 1],
            seen_ord: vec![0.0; NZ * (ORDERS + 1)],
            lost: 0.0,
            launched: 0.0,
        }
    }
}

/// Bin of a look direction: (cos θ bin, azimuth bin).
#[inline]
fn bin_of(look: DVec3, az: DVec3) -> (usize, usize) {
    let i = ((polar(look.z) / PI * NMU as f64) as usize).min(NMU - 1);
    let h = DVec3::new(look.x, look.y, 0.0);
    let c = h.dot(az);
    let s = (h.x * az.y - h.y * az.x).abs();
    let phi = s.atan2(c); // [0, π]
    let j = ((phi / PI * NPHI as f64) as usize).min(NPHI - 1);
    (i, j)
}

/// The bilinear weights [`Column::radiance`] reads the bins with for a look along `look`
/// (`az`: the sun's azimuth): the two polar bins about it and the two folded azimuth bins,
/// each with its weight (bin centres as nodes, held at the outer centres).
fn bin_weights(look: DVec3, az: DVec3) -> ([(usize, f64); 2], [(usize, f64); 2]) {
    let h = DVec3::new(look.x, look.y, 0.0);
    let c = h.dot(az);
    let s = (h.x * az.y - h.y * az.x).abs();
    let phi = if h.length_squared() > 0.0 {
        s.atan2(c)
    } else {
        0.0
    };
    let fp = (phi / PI * NPHI as f64 - 0.5).clamp(0.0, (NPHI - 1) as f64);
    let j0 = (fp as usize).min(NPHI - 1);
    let j1 = (j0 + 1).min(NPHI - 1);
    let tp = fp - j0 as f64;
    (polar_weights(look.z), [(j0, 1.0 - tp), (j1, tp)])
}

/// The polar half of [`bin_weights`], for a look of `cos θ = z`.
fn polar_weights(z: f64) -> [(usize, f64); 2] {
    let fm = (polar(z) / PI * NMU as f64 - 0.5).clamp(0.0, (NMU - 1) as f64);
    let i0 = (fm as usize).min(NMU - 2);
    let tm = fm - i0 as f64;
    [(i0, 1.0 - tm), (i0 + 1, tm)]
}

/// Angle of a look direction from the nadir, [0, π].
#[inline]
fn polar(z: f64) -> f64 {
    (-z.clamp(-1.0, 1.0)).acos()
}

/// cos θ (the look direction's z) at the lower edge of polar bin `i` (`i = NMU`: the zenith).
#[inline]
fn mu_edge(i: usize) -> f64 {
    static EDGES: std::sync::OnceLock<[f64; NMU + 1]> = std::sync::OnceLock::new();
    EDGES.get_or_init(|| std::array::from_fn(|i| -(i as f64 * PI / NMU as f64).cos()))[i]
}

/// Solid angle of one (folded) bin of polar bin `i`: both mirror halves.
#[inline]
fn bin_solid_angle(i: usize) -> f64 {
    (mu_edge(i + 1) - mu_edge(i)) * (PI / NPHI as f64) * 2.0
}

impl ColumnInput {
    fn check(&self) -> Result<(), ColumnError> {
        if !(self.depth.is_finite() && self.depth > 0.0) {
            return Err(ColumnError::BadDepth(self.depth));
        }
        for c in 0..3 {
            let vals = [
                self.sigma_a[c],
                self.sigma_s[c],
                self.ambient[c],
                self.bottom_albedo[c],
                self.sun.map_or(0.0, |s| s.irradiance[c]),
            ];
            if vals.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(ColumnError::BadInput(format!(
                    "a negative or non-finite coefficient or light in channel {c}"
                )));
            }
            if self.bottom_albedo[c] > 1.0 {
                return Err(ColumnError::BadInput(
                    "a bottom albedo above 1 creates light".into(),
                ));
            }
            if !(self.sigma_a[c] > 0.0) {
                return Err(ColumnError::NoAbsorption { channel: c });
            }
        }
        if let Top::Fresnel(n) = self.top
            && n.iter().any(|v| !(v.is_finite() && *v >= 1.0))
        {
            return Err(ColumnError::BadInput(
                "the water's index under a reflecting surface must be ≥ 1".into(),
            ));
        }
        if let Some(s) = &self.sun
            && !s.dirs.iter().all(|d| d.is_finite() && d.z < 0.0)
        {
            return Err(ColumnError::BadInput(
                "the sun must shine downwards in the water".into(),
            ));
        }
        Ok(())
    }
}

/// Solve the column.
pub fn solve(input: &ColumnInput) -> Result<Column, ColumnError> {
    solve_rounds(input, MAX_ROUNDS)
}

/// Solve the column in at most `max_rounds` rounds (1: a quick look, e.g. at the shares of
/// scattering orders, [`Column::share_seen_beyond`], whose noise is far below what they decide).
/// Water that scatters in no channel is solved exactly instead ([`clear`]).
pub fn solve_rounds(input: &ColumnInput, max_rounds: usize) -> Result<Column, ColumnError> {
    input.check()?;
    if input.sigma_s.iter().all(|s| *s == 0.0) {
        return Ok(clear::solve(input));
    }
    walk(input, max_rounds)
}

/// The 1D Monte Carlo of the module's method, in at most `max_rounds` rounds (on checked
/// input).
fn walk(input: &ColumnInput, max_rounds: usize) -> Result<Column, ColumnError> {
    let max_rounds = max_rounds.clamp(1, MAX_ROUNDS);
    let t0 = std::time::Instant::now();
    let az = input
        .sun
        .and_then(|s| DVec3::new(-s.dirs[1].x, -s.dirs[1].y, 0.0).try_normalize())
        .unwrap_or(DVec3::X);
    let dz = input.depth / NZ as f64;
    let per_batch = input.photons.div_ceil(BATCHES).max(2);
    let mut photons_max = 0;
    let mut table: [Vec<f32>; 3] = Default::default();
    let mut first: [Vec<f32>; 3] = Default::default();
    let mut profiles: [Profile; 3] = Default::default();
    let mut seen_orders: [Vec<f64>; 3] = Default::default();
    let mut lost = 0.0;
    let mut launched = 0.0;
    for c in 0..3 {
        // Rounds of BATCHES batches until E_d at the seabed is known to TARGET_STDERR (where
        // the channel keeps at least VISIBLE of the surface light), or MAX_ROUNDS.
        let (mu0, e0) = match input.sun {
            Some(s) => (-s.dirs[c].z, s.irradiance[c]),
            None => (1.0, 0.0),
        };
        let st = input.sigma_a[c] + input.sigma_s[c];
        let direct_bottom = e0 * mu0 * (-st * input.depth / mu0).exp();
        let surface = e0 * mu0 + PI * input.ambient[c];
        let mut sum = Tally::new();
        let mut per_plane_down: Vec<Vec<f64>> = vec![Vec::new(); NZ + 1];
        let mut per_plane_up: Vec<Vec<f64>> = vec![Vec::new(); NZ + 1];
        let mut round = 0;
        loop {
            let jobs: Vec<usize> = (round * BATCHES..(round + 1) * BATCHES).collect();
            let tallies: Vec<Tally> = jobs
                .par_iter()
                .map(|&b| run_batch(input, c, b, per_batch, az))
                .collect();
            for t in &tallies {
                for (a, b) in sum.table.iter_mut().zip(&t.table) {
                    *a += b;
                }
                for (a, b) in sum.first.iter_mut().zip(&t.first) {
                    *a += b;
                }
                for (a, b) in sum.track.iter_mut().zip(&t.track) {
                    *a += b;
                }
                for j in 0..=NZ {
                    sum.down[j] += t.down[j];
                    sum.up[j] += t.up[j];
                    per_plane_down[j].push(t.down[j]);
                    per_plane_up[j].push(t.up[j]);
                }
                for (a, b) in sum.seen_ord.iter_mut().zip(&t.seen_ord) {
                    *a += b;
                }
                sum.lost += t.lost;
                sum.launched += t.launched;
            }
            round += 1;
            let n = per_plane_down[NZ].len() as f64;
            let e_bottom = direct_bottom + sum.down[NZ] / n;
            let rel = stderr(&per_plane_down[NZ]) / e_bottom.max(1e-300);
            let visible = surface > 0.0 && e_bottom / surface >= VISIBLE;
            if round >= max_rounds || !visible || rel <= TARGET_STDERR {
                break;
            }
        }
        photons_max = photons_max.max(round * per_batch * BATCHES);
        lost += sum.lost;
        launched += sum.launched;
        // Tallies are already in W/m² × (number of batches) (each batch normalised to its
        // own photons); average the batches.
        let nb = per_plane_down[NZ].len() as f64;
        let domega = |idx: usize| bin_solid_angle((idx / NPHI) % NMU);
        table[c] = sum
            .table
            .iter()
            .enumerate()
            .map(|(i, &v)| (v / nb / (dz * domega(i))) as f32)
            .collect();
        first[c] = sum
            .first
            .iter()
            .enumerate()
            .map(|(i, &v)| (v / nb / (dz * domega(i))) as f32)
            .collect();
        let mut p = Profile::default();
        for j in 0..=NZ {
            let z = j as f64 * dz;
            let direct = e0 * mu0 * (-st * z / mu0).exp();
            p.e_d_direct.push(direct);
            p.e_d_diffuse.push(sum.down[j] / nb);
            p.e_u.push(sum.up[j] / nb);
            p.e_d_stderr.push(stderr(&per_plane_down[j]));
            p.e_u_stderr.push(stderr(&per_plane_up[j]));
            // Scalar irradiance: the layers' track lengths per unit volume around the plane,
            // plus the direct beam's E/μ0·μ0… (E_0 of a beam is its normal irradiance).
            let k = j.min(NZ - 1);
            let k2 = j.saturating_sub(1);
            let diffuse = 0.5 * (sum.track[k] + sum.track[k2]) / nb / dz;
            p.e_0.push(diffuse + e0 * (-st * z / mu0).exp());
        }
        // The Lambertian bottom reflects exactly A·E_d: the bottom plane's E_u from that
        // identity (the crossing tally adds the noise of the beam's sampled arrivals).
        p.e_u[NZ] = input.bottom_albedo[c] * p.e_d(NZ);
        p.e_u_stderr[NZ] = input.bottom_albedo[c] * p.e_d_stderr[NZ];
        p.fill_k_d(dz);
        seen_orders[c] = sum.seen_ord.iter().map(|v| v / nb).collect();
        profiles[c] = p;
    }
    for t in table.iter_mut().chain(first.iter_mut()) {
        pool_polar_rings(t);
    }
    let bottom =
        DVec3::from_array([0, 1, 2].map(|c| input.bottom_albedo[c] * profiles[c].e_d(NZ) / PI));
    let all: [Vec<f32>; 3] =
        [0, 1, 2].map(|c| table[c].iter().zip(&first[c]).map(|(a, b)| a + b).collect());
    let cdf = build_cdf(&all, input, bottom);
    Ok(Column {
        depth: input.depth,
        sun_azimuth: az,
        table,
        first,
        cdf,
        profiles,
        seen_orders,
        truncated: if launched > 0.0 { lost / launched } else { 0.0 },
        photons: photons_max,
        sky: DVec3::from_array(input.ambient),
        bottom,
        window: input.top.window(),
        sigma_t: DVec3::from_array([0, 1, 2].map(|c| input.sigma_a[c] + input.sigma_s[c])),
        open: open::empty_layers(),
        samplers: open::empty_samplers(),
        phase: input.phase.clone(),
        scatter: scatter::Tables::default(),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Polar rings within this many bins of the nadir or the zenith (22.5°) hold their azimuthal
/// mean in every azimuth bin: their bins are small (a 3.75° ring split 18 ways), so their
/// photons are few, and the azimuth hardly matters near the vertical.
const POLAR_POOL: usize = 6;

fn pool_polar_rings(t: &mut [f32]) {
    for k in 0..NZ {
        for i in (0..POLAR_POOL).chain(NMU - POLAR_POOL..NMU) {
            let row = &mut t[(k * NMU + i) * NPHI..(k * NMU + i + 1) * NPHI];
            let mean = row.iter().map(|v| *v as f64).sum::<f64>() / NPHI as f64;
            row.fill(mean as f32);
        }
    }
}

fn stderr(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (var / n).sqrt()
}

/// Per layer, the CDFs of the light × |cos θ| over the upper and the lower half of the bins,
/// the channels summed: the table's (`table`: `L_m` with the sun's first scattering) plus the
/// boundary's (the sky above, through Snell's window under a reflecting surface; `bottom`
/// below) seen through the water from the layer's centre.
fn build_cdf(table: &[Vec<f32>; 3], input: &ColumnInput, bottom: DVec3) -> Vec<[Vec<f64>; 2]> {
    let depth = input.depth;
    let sky = DVec3::from_array(input.ambient);
    let sky_at = |mu: f64| sky_seen(sky, input.top.window(), mu);
    let sigma_t = DVec3::from_array([0, 1, 2].map(|c| input.sigma_a[c] + input.sigma_s[c]));
    let half = NMU / 2 * NPHI;
    let dz = depth / NZ as f64;
    (0..NZ)
        .map(|k| {
            let z = (k as f64 + 0.5) * dz;
            [1, 0].map(|up| {
                let mut acc = 0.0;
                let mut out = Vec::with_capacity(half + 1);
                out.push(0.0);
                for b in 0..half {
                    let i = k * NMU * NPHI + up * half + b;
                    let mu_bin = up * NMU / 2 + b / NPHI;
                    let mu = 0.5 * (mu_edge(mu_bin) + mu_edge(mu_bin + 1)).abs();
                    let (to, lb) = if up == 1 {
                        (z, sky_at(mu))
                    } else {
                        (depth - z, bottom)
                    };
                    let through = lb * (-sigma_t * (to / mu.max(1e-3))).exp();
                    let l = DVec3::new(table[0][i] as f64, table[1][i] as f64, table[2][i] as f64)
                        + through;
                    acc += l.max(DVec3::ZERO).element_sum() * mu * bin_solid_angle(mu_bin);
                    out.push(acc);
                }
                out
            })
        })
        .collect()
}

/// One batch of one channel: its tallies in W/m² (normalised to the batch's photons).
fn run_batch(input: &ColumnInput, c: usize, batch: usize, n: usize, az: DVec3) -> Tally {
    let mut h0 = SplitMix64(input.seed ^ 0xC01A_0000);
    let mut h1 = SplitMix64(h0.next_u64() ^ (c as u64) << 32 ^ batch as u64);
    let mut rng = SplitMix64(h1.next_u64());
    let mut t = Tally::new();
    let h = input.depth;
    let dz = h / NZ as f64;
    let (sa, ss) = (input.sigma_a[c], input.sigma_s[c]);
    let st = sa + ss;
    let albedo_ss = if st > 0.0 { ss / st } else { 0.0 };
    let a_bottom = input.bottom_albedo[c];
    // The weight window's attenuation: σa, a lower bound of the diffuse attenuation
    // (K_d ≈ σa/μ̄ + b_b with μ̄ ≤ 1), so that the window never splits faster than the light
    // fades (an overestimate multiplies the photons exponentially with depth; measured: 5–30×
    // slower on the 33 m sky-lit scenes); the population thins by `e^(−(K_d − σa) z)` instead.
    let k = sa.clamp(0.0, 40.0 / h);
    let target = |depth: f64| (-k * depth).exp();
    // Horizontal fluxes of the two sources and the photons each gets.
    let f_sun = input.sun.map_or(0.0, |s| s.irradiance[c] * -s.dirs[c].z);
    let f_sky = PI * input.ambient[c];
    let total = f_sun + f_sky;
    if total <= 0.0 {
        return t;
    }
    let n_sun = if f_sun > 0.0 && f_sky > 0.0 {
        ((n as f64 * f_sun / total).round() as usize).clamp(1, n.saturating_sub(1).max(1))
    } else if f_sun > 0.0 {
        n
    } else {
        0
    };
    let n_sky = n - n_sun;
    let mut stack: Vec<Photon> = Vec::new();
    let budget = n * FLIGHT_BUDGET;
    let mut flights = 0usize;
    for p in 0..n {
        let (w0, start) = if p < n_sun {
            let s = input.sun.expect("sun photons only with a sun");
            (
                f_sun / n_sun as f64,
                Photon {
                    depth: 0.0,
                    dir: s.dirs[c],
                    w: 1.0,
                    order: Order::Beam,
                    events: 0,
                },
            )
        } else {
            let (dir, w) = sky_photon(input.top, c, rng.next_f64(), rng.next_f64());
            let w0 = f_sky / n_sky as f64;
            // The sky's light crosses the surface plane downwards.
            t.down[0] += w * w0;
            (
                w0,
                Photon {
                    depth: 0.0,
                    dir,
                    w,
                    order: Order::Boundary,
                    events: 0,
                },
            )
        };
        t.launched += w0;
        stack.push(start);
        while let Some(mut ph) = stack.pop() {
            loop {
                flights += 1;
                let dist = -(1.0 - rng.next_f64()).ln() / st;
                let mu = -ph.dir.z; // > 0 going down
                let mut end = ph.depth + mu * dist;
                let mut len = dist;
                let mut at_bottom = false;
                let mut at_top = false;
                if end >= h {
                    at_bottom = true;
                    len = (h - ph.depth) / mu;
                    end = h;
                } else if end <= 0.0 {
                    at_top = true;
                    len = -ph.depth / mu;
                    end = 0.0;
                }
                if ph.order != Order::Beam {
                    tally_track(&mut t, &ph, end, len, w0, dz, az);
                }
                if at_bottom {
                    // (The direct beam's arrival is analytic in E_d; its reflection is light
                    // of the table.)
                    ph.w *= a_bottom;
                    ph.depth = h;
                    t.up[NZ] += ph.w * w0;
                    let (u1, u2) = (rng.next_f64(), rng.next_f64());
                    let r = u1.sqrt();
                    let phi = 2.0 * PI * u2;
                    ph.dir = DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
                    ph.order = Order::Boundary;
                } else if at_top {
                    let Top::Fresnel(n) = input.top else {
                        break; // open top: the light leaves
                    };
                    // The surface's reflection: the share R(θ) comes back down mirrored (the
                    // rest leaves). Reflected light is the table's (not analytic, not the
                    // sun's first scattering, which the renderer traces in open water).
                    ph.w *= reflectance_from_below(n[c], ph.dir.z);
                    t.down[0] += ph.w * w0;
                    ph.depth = 0.0;
                    ph.dir.z = -ph.dir.z;
                    ph.order = Order::Rest;
                } else {
                    ph.depth = end;
                    ph.w *= albedo_ss;
                    let (u1, u2) = (rng.next_f64(), rng.next_f64());
                    ph.dir = input.phase.sample(ph.dir, u1, u2).0;
                    ph.order = match ph.order {
                        Order::Beam => Order::First,
                        _ => Order::Rest,
                    };
                }
                ph.events += 1;
                if ph.events >= MAX_EVENTS {
                    t.lost += ph.w * w0;
                    break;
                }
                // Weight window about the expected flux at this depth.
                let wt = target(ph.depth);
                if ph.w < 0.25 * wt {
                    let q = ph.w / wt;
                    if rng.next_f64() >= q {
                        break;
                    }
                    ph.w = wt;
                } else if ph.w > 4.0 * wt && flights < budget {
                    let copies = ((ph.w / wt).ceil() as usize).min(8);
                    ph.w /= copies as f64;
                    for _ in 1..copies {
                        stack.push(ph);
                    }
                }
                if ph.w <= 0.0 {
                    break;
                }
            }
        }
    }
    t
}

/// Tally one track from `ph.depth` to `end` (length `len`) into the layers, the table and
/// the plane crossings. `w0`: flux per photon.
fn tally_track(t: &mut Tally, ph: &Photon, end: f64, len: f64, w0: f64, dz: f64, az: DVec3) {
    let w = ph.w * w0;
    let (a, b) = (ph.depth.min(end), ph.depth.max(end));
    let mu = (-ph.dir.z).abs();
    let look = -ph.dir;
    let (bi, bj) = bin_of(look, az);
    let k0 = ((a / dz) as usize).min(NZ - 1);
    let k1 = ((b / dz) as usize).min(NZ - 1);
    for k in k0..=k1 {
        let lo = (k as f64 * dz).max(a);
        let hi = ((k + 1) as f64 * dz).min(b);
        let l = if mu > 1e-12 {
            ((hi - lo).max(0.0)) / mu
        } else {
            len
        };
        if l <= 0.0 {
            continue;
        }
        t.track[k] += w * l;
        if ph.dir.z > SEEN_CONE {
            t.seen_ord[k * (ORDERS + 1) + (ph.events as usize).min(ORDERS)] += w * l;
        }
        let idx = (k * NMU + bi) * NPHI + bj;
        match ph.order {
            Order::Rest => t.table[idx] += w * l,
            Order::First => t.first[idx] += w * l,
            _ => {}
        }
    }
    // Plane crossings: downward tracks cross planes in (start, end], upward in [end, start).
    if end > ph.depth {
        let j0 = (ph.depth / dz).floor() as usize + 1;
        let j1 = ((end / dz).floor() as usize).min(NZ);
        for j in j0..=j1 {
            if (j as f64 * dz) > ph.depth && (j as f64 * dz) <= end + 1e-12 {
                t.down[j] += w;
            }
        }
    } else if end < ph.depth {
        let j0 = (end / dz).ceil() as usize;
        let j1 = ((ph.depth / dz).ceil() as usize).min(NZ + 1);
        for j in j0..j1.min(NZ + 1) {
            if (j as f64 * dz) >= end - 1e-12 && (j as f64 * dz) < ph.depth {
                t.up[j] += w;
            }
        }
    }
}

impl Column {
    /// `L_m` per channel at depth `z` (m below the surface) looking along unit `look` (world,
    /// z up), trilinear in depth, cos θ and azimuth; W/(m²·sr). `with_first`: the whole
    /// diffuse light `L_d`, the sun's first scattering included.
    pub fn radiance(&self, z: f64, look: DVec3, with_first: bool) -> DVec3 {
        self.radiance_sum(z, look, with_first).max(DVec3::ZERO)
    }

    /// [`Column::radiance`] before its clamp at 0: linear in the layers' bins.
    pub fn radiance_sum(&self, z: f64, look: DVec3, with_first: bool) -> DVec3 {
        // Layer values stand at the layers' centres; in the outer half-layers they are
        // extrapolated linearly to the surface and the bottom (looking down, the light
        // scattered between a point and the bottom falls linearly to 0 at the bottom).
        let (polars, azimuths) = bin_weights(look, self.sun_azimuth);
        let mut out = DVec3::ZERO;
        for (k, wk) in self.depth_weights(z) {
            for (i, wi) in polars {
                for (j, wj) in azimuths {
                    let w = wk * wi * wj;
                    if w == 0.0 {
                        continue;
                    }
                    let idx = (k * NMU + i) * NPHI + j;
                    let mut v = DVec3::new(
                        self.table[0][idx] as f64,
                        self.table[1][idx] as f64,
                        self.table[2][idx] as f64,
                    );
                    if with_first {
                        v += DVec3::new(
                            self.first[0][idx] as f64,
                            self.first[1][idx] as f64,
                            self.first[2][idx] as f64,
                        );
                    }
                    out += w * v;
                }
            }
        }
        out
    }

    fn layer(&self, z: f64) -> usize {
        ((z / (self.depth / NZ as f64)) as usize).min(NZ - 1)
    }

    /// The two layers whose centres bracket depth `z`, with their linear weights (held at
    /// the outer layers' centres, no extrapolation: the weights are a mixture's).
    fn layers_at(&self, z: f64) -> [(usize, f64); 2] {
        let dz = self.depth / NZ as f64;
        let fz = (z / dz - 0.5).clamp(0.0, NZ as f64 - 1.0);
        let k0 = (fz as usize).min(NZ - 2);
        let t = (fz - k0 as f64).clamp(0.0, 1.0);
        [(k0, 1.0 - t), (k0 + 1, t)]
    }

    /// `L_m` (with the sun's first scattering) at depth `z` looking along `look`, constant
    /// over each angular bin and linear in depth between the layers' centres: nearly the function
    /// [`Column::sample`] draws directions in proportion to (times |cos θ|), so that a
    /// surface's next-event estimate of the column's light is nearly constant. (The bins
    /// hold the tallies' means over their solid angle: integrated over a hemisphere this and
    /// [`Column::radiance`]'s interpolation agree; sampled against the interpolation, the
    /// aureole's peak gave next-event estimates a 40 % relative spread.)
    pub fn radiance_binned(&self, z: f64, look: DVec3) -> DVec3 {
        self.binned_sum(z, look).max(DVec3::ZERO)
    }

    /// [`Column::radiance_binned`] before its clamp at 0: linear in the layers' bins.
    pub fn binned_sum(&self, z: f64, look: DVec3) -> DVec3 {
        let (i, j) = bin_of(look, self.sun_azimuth);
        // Linear in depth as [`Column::radiance`], extrapolated in the outer half-layers (the
        // light changes by e^(−K dz/2) there: 3.5 % for red at 12 m); the sampler's mixture
        // holds the outer layers' own bins, which are nearly proportional.
        let mut out = DVec3::ZERO;
        for (k, w) in self.depth_weights(z) {
            if w == 0.0 {
                continue;
            }
            let idx = (k * NMU + i) * NPHI + j;
            out += w * DVec3::new(
                (self.table[0][idx] + self.first[0][idx]) as f64,
                (self.table[1][idx] + self.first[1][idx]) as f64,
                (self.table[2][idx] + self.first[2][idx]) as f64,
            );
        }
        out
    }

    /// Sample a look direction at depth `z` in the upper (`up`) or lower half of the sphere,
    /// with density ∝ the whole diffuse light's luminance × |cos θ| (the table's, plus the
    /// sky's or the bottom's seen through the water): piecewise constant over the bins, the
    /// mixture of the two layers bracketing `z` by their weights, the function
    /// [`Column::radiance_binned`] reads. Returns (direction, density per sr), or `None` where
    /// that half is dark.
    pub fn sample(&self, z: f64, up: bool, u0: f64, u1: f64, u2: f64) -> Option<(DVec3, f64)> {
        self.sample_from(z, up, [u0, u1, u2])
    }

    fn sample_from(&self, z: f64, up: bool, u: [f64; 3]) -> Option<(DVec3, f64)> {
        let [u0, u1, u2] = u;
        let half = NMU / 2 * NPHI;
        // The layer: one of the two bracketing `z`, by its weight (`u0` is reused).
        let [(k0, w0), (k1, _)] = self.layers_at(z);
        let (k, u0) = if u0 < w0 {
            (k0, u0 / w0)
        } else {
            (k1, ((u0 - w0) / (1.0 - w0)).min(1.0 - f64::EPSILON))
        };
        let cdf = &self.cdf[k][if up { 0 } else { 1 }];
        let total = *cdf.last()?;
        if !(total > 0.0) {
            return None;
        }
        let x = u0 * total;
        let b = cdf
            .partition_point(|&v| v <= x)
            .saturating_sub(1)
            .min(half - 1);
        let (i, j) = (b / NPHI + if up { NMU / 2 } else { 0 }, b % NPHI);
        let cz = mu_edge(i) + u1 * (mu_edge(i + 1) - mu_edge(i));
        // Both mirror halves of the folded azimuth bin: the sign from the top bit of u2.
        let (u2, sign) = if u2 < 0.5 {
            (2.0 * u2, 1.0)
        } else {
            (2.0 * u2 - 1.0, -1.0)
        };
        let phi = sign * (j as f64 + u2) * PI / NPHI as f64;
        let sz = (1.0 - cz * cz).max(0.0).sqrt();
        let a = self.sun_azimuth;
        let perp = DVec3::new(-a.y, a.x, 0.0);
        let dir = (a * (sz * phi.cos()) + perp * (sz * phi.sin()) + DVec3::Z * cz).normalize();
        let p = self.pdf(z, up, dir);
        (p > 0.0).then_some((dir, p))
    }

    /// Density (per sr) of [`Column::sample`] (half `up`) at depth `z` for direction `look`.
    pub fn pdf(&self, z: f64, up: bool, look: DVec3) -> f64 {
        let (i, j) = bin_of(look, self.sun_azimuth);
        let in_up = i >= NMU / 2;
        if in_up != up {
            return 0.0;
        }
        let b = (i - if up { NMU / 2 } else { 0 }) * NPHI + j;
        self.layers_at(z)
            .iter()
            .filter(|(_, w)| *w > 0.0)
            .map(|&(k, w)| {
                let cdf = &self.cdf[k][if up { 0 } else { 1 }];
                let total = cdf.last().copied().unwrap_or(0.0);
                if total > 0.0 {
                    w * (cdf[b + 1] - cdf[b]) / total / bin_solid_angle(i)
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// Per channel, the share of the radiance seen looking down from depth `z` (within
    /// [`SEEN_CONE`] of the nadir) that met more than `bounces` events: what a path tracer
    /// ending paths after `bounces` scattering vertices loses of a down-looking camera's
    /// image there (its seabed and the water between). Close to the seabed it is the share of
    /// E_d there that met `bounces` events or more (the seabed's reflection is one more);
    /// higher up it grows, as the water's own light has met more events.
    pub fn share_seen_beyond(&self, z: f64, bounces: u32) -> [f64; 3] {
        // The layer holding `z` and its neighbours (a thin layer's cone holds few tracks).
        let k = self.layer(z.clamp(0.0, self.depth));
        let ks = k.saturating_sub(1)..(k + 2).min(NZ);
        let from = (bounces as usize + 1).min(ORDERS);
        [0, 1, 2].map(|c| {
            let o = &self.seen_orders[c][ks.start * (ORDERS + 1)..ks.end * (ORDERS + 1)];
            let total: f64 = o.iter().sum();
            let beyond: f64 = o
                .chunks(ORDERS + 1)
                .map(|l| l[from..].iter().sum::<f64>())
                .sum();
            if total > 0.0 {
                (beyond / total).clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
    }

    /// Whether channel `c` keeps at least [`VISIBLE`] of the surface's daylight at the bottom
    /// (darker channels are black in an image).
    pub fn visible_at_bottom(&self, c: usize) -> bool {
        let p = &self.profiles[c];
        let surface = p.e_d(0);
        surface > 0.0 && p.e_d(NZ) / surface >= VISIBLE
    }

    /// The smallest bounce limit losing at most `share` of the light seen looking down from
    /// every depth in `depths`, in every channel visible at the bottom
    /// ([`Column::share_seen_beyond`]); `None` beyond [`ORDERS`].
    pub fn bounces_for(&self, depths: &[f64], share: f64) -> Option<u32> {
        (1..ORDERS as u32 - 1).find(|&b| {
            depths.iter().all(|&z| {
                let s = self.share_seen_beyond(z, b);
                (0..3).all(|c| !self.visible_at_bottom(c) || s[c] <= share)
            })
        })
    }

    /// Share of the downward irradiance at the bottom that is diffuse, per channel.
    pub fn diffuse_share_at_bottom(&self) -> [f64; 3] {
        [0, 1, 2].map(|c| {
            let p = &self.profiles[c];
            let e = p.e_d(NZ);
            if e > 0.0 { p.e_d_diffuse[NZ] / e } else { 0.0 }
        })
    }

    /// Mean K_d over the column per channel, 1/m (from E_d at the surface and the bottom).
    pub fn mean_k_d(&self) -> [f64; 3] {
        [0, 1, 2].map(|c| {
            let p = &self.profiles[c];
            let (a, b) = (p.e_d(0), p.e_d(NZ));
            if a > 0.0 && b > 0.0 {
                (a / b).ln() / self.depth
            } else {
                0.0
            }
        })
    }

    /// The boundary radiance a ray from depth `z` along `look` reaches without a collision,
    /// before the water's transmittance: the sky looking up, the bottom looking down (0
    /// horizontally). Add it times the transmittance to the boundary to [`Column::radiance`]
    /// for the whole diffuse radiance of the column.
    pub fn boundary(&self, look: DVec3) -> DVec3 {
        if look.z > 0.0 {
            sky_seen(self.sky, self.window, look.z)
        } else if look.z < 0.0 {
            self.bottom
        } else {
            DVec3::ZERO
        }
    }

    /// Distance from depth `z` along `look` to the column's boundary (∞ horizontally).
    pub fn to_boundary(&self, z: f64, look: DVec3) -> f64 {
        if look.z > 0.0 {
            z.max(0.0) / look.z
        } else if look.z < 0.0 {
            (self.depth - z).max(0.0) / -look.z
        } else {
            f64::INFINITY
        }
    }

    /// Whether the column was solved exactly (clear water, [`clear`]) rather than by the walk:
    /// no photons, standard errors 0.
    pub fn is_exact(&self) -> bool {
        self.photons == 0
    }

    /// Depths of the profile planes, m.
    pub fn planes(&self) -> Vec<f64> {
        (0..=NZ)
            .map(|j| j as f64 * self.depth / NZ as f64)
            .collect()
    }
}

/// A reef site's column for the tests: 12 m of Jerlov IB (HG g = 0.92) under a sun, with the
/// sky's radiance `ambient` above the surface `top`, solved with `photons` per channel.
#[cfg(test)]
pub(crate) fn reef_site(ambient: [f64; 3], top: Top, photons: usize) -> ColumnInput {
    ColumnInput {
        depth: 12.0,
        sigma_a: [0.334, 0.0623, 0.0235],
        sigma_s: [0.045, 0.0536, 0.068],
        phase: PhaseFn::Hg { g: 0.92 },
        sun: Some(ColumnSun {
            dirs: [DVec3::new(0.33, -0.28, -0.9).normalize(); 3],
            irradiance: [500.0, 600.0, 550.0],
        }),
        ambient,
        bottom_albedo: [0.4, 0.38, 0.3],
        top,
        photons,
        seed: 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(sa: f64, ss: f64, g: f64, depth: f64, sun: bool, ambient: f64) -> ColumnInput {
        let el: f64 = 40f64.to_radians();
        ColumnInput {
            depth,
            sigma_a: [sa, sa * 0.5, sa * 0.8],
            sigma_s: [ss, ss, ss * 1.2],
            phase: PhaseFn::Hg { g },
            sun: sun.then(|| ColumnSun {
                // Each channel its own direction, as the sun refracts per channel (more than
                // water's dispersion, so that a mixed-up channel shows).
                dirs: [-1.1, -1.2, -1.3].map(|z| DVec3::new(el.cos(), 0.3, z).normalize()),
                irradiance: [500.0, 600.0, 550.0],
            }),
            ambient: [ambient; 3],
            bottom_albedo: [0.5, 0.3, 0.2],
            top: Top::Open,
            photons: 20_000,
            seed: 1,
        }
    }

    /// E₃, the third exponential integral, by quadrature: ∫₀¹ μ e^(−x/μ) dμ.
    fn e3(x: f64) -> f64 {
        let n = 20_000;
        (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                mu * (-x / mu).exp()
            })
            .sum::<f64>()
            / n as f64
    }

    /// Without scattering the profiles have closed forms: the sky's E_d(z) = 2πL·E₃(σa z), the
    /// beam's μ0 E0 e^(−σa z/μ0), and the bottom's E_u = A·E_d.
    #[test]
    fn absorbing_column_matches_closed_forms() {
        let mut inp = case(0.2, 0.0, 0.9, 6.0, true, 2.0);
        inp.photons = 200_000;
        let col = solve(&inp).unwrap();
        for c in 0..3 {
            let p = &col.profiles[c];
            for j in [NZ / 4, NZ / 2, NZ] {
                let z = col.planes()[j];
                let sky = 2.0 * PI * 2.0 * e3(inp.sigma_a[c] * z);
                let rel = (p.e_d_diffuse[j] - sky) / sky;
                assert!(
                    rel.abs() < 4.0 * p.e_d_stderr[j] / sky + 1e-3,
                    "c {c} z {z}: {rel}"
                );
                let mu0 = -inp.sun.unwrap().dirs[c].z;
                let beam = inp.sun.unwrap().irradiance[c] * mu0 * (-inp.sigma_a[c] * z / mu0).exp();
                assert!((p.e_d_direct[j] - beam).abs() < 1e-9 * beam);
            }
            let e_d = p.e_d(NZ);
            let want = inp.bottom_albedo[c] * e_d;
            assert!(
                (p.e_u[NZ] - want).abs() < 4.0 * p.e_u_stderr[NZ] + 1e-3 * want,
                "c {c}: {} vs {want}",
                p.e_u[NZ]
            );
            // Nothing scatters: the table holds only the sky and the bottom's light.
            assert!(col.table[c].iter().all(|v| v.is_finite() && *v >= 0.0));
        }
        // Looking straight up at the surface from 3 m: the sky through 3 m of water.
        inp.sun = None;
        inp.photons = 1_000_000;
        let col = solve(&inp).unwrap();
        // The sky's own light is the analytic boundary term; the table holds none here.
        assert!(col.radiance(3.0, DVec3::Z, false).max_element() < 1e-12);
        let l = col.boundary(DVec3::Z) * (-0.2f64 * col.to_boundary(3.0, DVec3::Z)).exp();
        // The table's top bin averages over cos θ ∈ [cos(π/NMU), 1] (its solid angle).
        let n = 1000;
        let lo = (PI / NMU as f64).cos();
        let want = (0..n)
            .map(|i| {
                let mu = 1.0 - (1.0 - lo) * (i as f64 + 0.5) / n as f64;
                2.0 * (-0.2f64 * 3.0 / mu).exp()
            })
            .sum::<f64>()
            / n as f64;
        assert!((l.x - want).abs() < 0.05 * want, "{l} vs {want}");
    }

    /// With scattering the bottom still reflects exactly A·E_d, and the diffuse light is
    /// positive and finite everywhere.
    #[test]
    fn scattering_column_is_consistent() {
        let col = solve(&case(0.05, 0.3, 0.92, 12.0, true, 0.5)).unwrap();
        for c in 0..3 {
            let p = &col.profiles[c];
            let want = col_albedo(c) * p.e_d(NZ);
            assert!(
                (p.e_u[NZ] - want).abs() < 5.0 * p.e_u_stderr[NZ] + 1e-9,
                "c {c}: {} vs {want}",
                p.e_u[NZ]
            );
            assert!(p.k_d.iter().all(|k| k.is_finite() && *k > 0.0));
            assert!(p.e_0.iter().all(|e| e.is_finite() && *e > 0.0));
        }
        assert_eq!(col.truncated, 0.0);
        fn col_albedo(c: usize) -> f64 {
            [0.5, 0.3, 0.2][c]
        }
    }

    /// The same input gives the same bytes on one thread and on several.
    #[test]
    fn bytes_do_not_depend_on_threads() {
        let inp = case(0.1, 0.4, 0.8, 8.0, true, 0.3);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| solve(&inp).unwrap());
        let many = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| solve(&inp).unwrap());
        assert_eq!(one.table, many.table);
        assert_eq!(one.profiles[1].e_u, many.profiles[1].e_u);
    }

    /// Importance sampling of the table: the sampled density is the one `pdf` reports, and
    /// integrates to one.
    #[test]
    fn table_sampling_matches_its_density() {
        let col = solve(&case(0.1, 0.4, 0.9, 8.0, true, 0.3)).unwrap();
        let z = 5.0;
        let n = 20_000;
        let mut sum = 0.0;
        let mut rng = SplitMix64(9);
        for _ in 0..n {
            let up = rng.next_f64() < 0.5;
            let (d, p) = col
                .sample(z, up, rng.next_f64(), rng.next_f64(), rng.next_f64())
                .unwrap();
            assert!((d.length() - 1.0).abs() < 1e-9);
            assert_eq!(d.z > 0.0, up);
            let q = col.pdf(z, up, d);
            assert_eq!(col.pdf(z, !up, d), 0.0);
            assert!((p - q).abs() < 1e-9 * p.max(1e-12), "{p} vs {q}");
            sum += 1.0 / p;
        }
        // E[1/p] over the sampled density is the solid angle of its support: a half, 2π.
        let support = sum / n as f64;
        assert!((support - 2.0 * PI).abs() < 0.05 * 2.0 * PI, "{support}");
    }

    /// Bad input is an explicit error, never a hang or NaN.
    /// A purely absorbing column under a reflecting surface: the Lambertian bottom's light
    /// goes up, the surface sends back `ρ = 2∫ μ R(μ) e^(−2σH/μ) dμ` of it (Fresnel, total
    /// beyond the critical angle), the bottom reflects that again: E_d at the bottom is the
    /// direct beam's over `1 − A ρ`, a geometric series (quadrature here, independent of the
    /// walk). The open top keeps the direct beam alone.
    #[test]
    fn reflecting_surface_returns_the_bottoms_light_as_a_geometric_series() {
        let mut input = case(0.08, 0.0, 0.9, 6.0, true, 0.0);
        input.bottom_albedo = [0.9, 0.6, 0.3];
        input.top = Top::Fresnel([1.331, 1.334, 1.338]);
        input.photons = 200_000;
        let col = solve(&input).unwrap();
        let open = solve(&ColumnInput {
            top: Top::Open,
            ..input.clone()
        })
        .unwrap();
        for c in 0..3 {
            let sa = input.sigma_a[c];
            let h = input.depth;
            let n = 200_000;
            let rho: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * mu
                        * reflectance_from_below([1.331, 1.334, 1.338][c], mu)
                        * (-2.0 * sa * h / mu).exp()
                        / n as f64
                })
                .sum();
            let p = &col.profiles[c];
            let direct = p.e_d_direct[NZ];
            let want = direct / (1.0 - input.bottom_albedo[c] * rho);
            let got = p.e_d(NZ);
            let err = p.e_d_stderr[NZ];
            eprintln!(
                "channel {c}: ρ {rho:.4}, E_d {got:.4} ± {err:.4}, series {want:.4}, open {:.4}",
                open.profiles[c].e_d(NZ)
            );
            assert!(
                (got - want).abs() < 3.0 * err + 1e-3 * want,
                "channel {c}: {got} vs {want}"
            );
            assert!(got > direct * (1.0 + 0.5 * input.bottom_albedo[c] * rho));
            assert!((open.profiles[c].e_d(NZ) - direct).abs() < 1e-9 * direct);
        }
    }

    /// Below a reflecting surface the sky comes in through Snell's window: with nothing
    /// scattering and a black bottom, `E_d(z) = 2π L ∫ T(μ_a) μ_a e^(−σa z/μ_w) dμ_a` over the
    /// air's directions (μ_w the refracted cosine), by quadrature, independent of the walk's
    /// sampling; the boundary seen looking up is `n² T L` inside the window and dark beyond it.
    #[test]
    fn the_sky_comes_in_through_snells_window() {
        let n = [1.331, 1.334, 1.338];
        let mut inp = case(0.2, 0.0, 0.9, 6.0, false, 2.0);
        inp.bottom_albedo = [0.0; 3];
        inp.top = Top::Fresnel(n);
        inp.photons = 200_000;
        let col = solve(&inp).unwrap();
        for c in 0..3 {
            let p = &col.profiles[c];
            for j in [0, NZ / 4, NZ / 2, NZ] {
                let z = col.planes()[j];
                let m = 20_000;
                let want: f64 = (0..m)
                    .map(|i| {
                        let mu_a = (i as f64 + 0.5) / m as f64;
                        let sin_w2 = (1.0 - mu_a * mu_a) / (n[c] * n[c]);
                        let mu_w = (1.0 - sin_w2).sqrt();
                        let t = 1.0 - reflectance_from_below(n[c], mu_w);
                        2.0 * PI * 2.0 * t * mu_a * (-inp.sigma_a[c] * z / mu_w).exp() / m as f64
                    })
                    .sum();
                let got = p.e_d_diffuse[j];
                assert!(
                    (got - want).abs() < 4.0 * p.e_d_stderr[j] + 1e-3 * want,
                    "c {c} z {z}: {got} vs {want}"
                );
            }
            // About 6.6 % of a uniform sky is reflected away at the surface.
            let t_hemi = p.e_d_diffuse[0] / (PI * 2.0);
            assert!((0.92..0.945).contains(&t_hemi), "c {c}: {t_hemi}");
        }
        let up = col.boundary(DVec3::Z);
        let want = 1.334f64.powi(2) * (1.0 - reflectance_from_below(1.334, 1.0)) * 2.0;
        assert!((up.y - want).abs() < 1e-12, "{up}");
        let c = (1.0f64 - 1.0 / (1.334 * 1.334)).sqrt(); // cosine of the critical angle
        assert!(
            col.boundary(DVec3::new((1.0f64 - 0.99 * c * c).sqrt(), 0.0, 0.99 * c))
                .y
                == 0.0
        );
        assert!(
            col.boundary(DVec3::new((1.0f64 - 1.01 * c * c).sqrt(), 0.0, 1.01 * c))
                .y
                > 0.0
        );
    }

    /// Clear water is solved by quadrature ([`clear`]); the walk estimates the same integrals.
    /// Under a reflecting surface with a sun and a sky over a bright bottom, the two agree on
    /// every profile within the walk's noise, and on the table (the light the surface returns)
    /// summed over each layer's upward bins.
    #[test]
    fn clear_water_is_solved_exactly_as_the_walk_estimates() {
        let mut inp = case(0.15, 0.0, 0.9, 8.0, true, 3.0);
        inp.bottom_albedo = [0.9, 0.7, 0.5];
        inp.top = Top::Fresnel([1.331, 1.334, 1.338]);
        inp.photons = 400_000;
        let exact = solve(&inp).unwrap();
        assert_eq!(exact.photons, 0, "clear water takes the exact solve");
        let walk = walk(&inp, MAX_ROUNDS).unwrap();
        for c in 0..3 {
            let (e, w) = (&exact.profiles[c], &walk.profiles[c]);
            for j in [0, NZ / 3, 2 * NZ / 3, NZ] {
                let close = |a: f64, b: f64, se: f64, what: &str| {
                    assert!(
                        (a - b).abs() < 4.0 * se + 2e-3 * b.abs(),
                        "c {c} plane {j} {what}: exact {a} walk {b} ± {se}"
                    )
                };
                close(e.e_d(j), w.e_d(j), w.e_d_stderr[j], "E_d");
                close(e.e_u[j], w.e_u[j], w.e_u_stderr[j], "E_u");
                assert_eq!(e.e_d_direct[j], w.e_d_direct[j]);
            }
            // E_0 (the walk's is a two-layer average: 1 %).
            for j in [NZ / 3, 2 * NZ / 3] {
                let (a, b) = (e.e_0[j], w.e_0[j]);
                assert!((a - b).abs() < 0.01 * b, "c {c} plane {j} E_0: {a} vs {b}");
            }
            // The table: upward bins of a layer, weighted by their solid angles.
            for k in [0, NZ / 2, NZ - 1] {
                let sum = |t: &[f32]| -> f64 {
                    (NMU / 2..NMU)
                        .map(|i| {
                            let row = &t[(k * NMU + i) * NPHI..(k * NMU + i + 1) * NPHI];
                            row.iter().map(|v| *v as f64).sum::<f64>() * bin_solid_angle(i)
                        })
                        .sum()
                };
                let (a, b) = (sum(&exact.table[c]), sum(&walk.table[c]));
                assert!(
                    a > 0.0 && (a - b).abs() < 0.03 * a,
                    "c {c} layer {k}: {a} vs {b}"
                );
            }
            // The scattering orders seen looking down: the same shares beyond one bounce.
            let (a, b) = (
                exact.share_seen_beyond(7.0, 1)[c],
                walk.share_seen_beyond(7.0, 1)[c],
            );
            assert!(
                a > 0.0 && (a - b).abs() < 0.1 * a + 1e-4,
                "c {c} seen: {a} vs {b}"
            );
        }
        assert!(
            exact.seconds < walk.seconds,
            "{} vs {}",
            exact.seconds,
            walk.seconds
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut inp = case(0.0, 0.3, 0.9, 10.0, true, 0.0);
        assert_eq!(
            solve(&inp).unwrap_err(),
            ColumnError::NoAbsorption { channel: 0 }
        );
        inp.sigma_a = [0.1; 3];
        inp.depth = 0.0;
        assert!(matches!(solve(&inp), Err(ColumnError::BadDepth(_))));
        inp.depth = f64::NAN;
        assert!(matches!(solve(&inp), Err(ColumnError::BadDepth(_))));
        inp.depth = 5.0;
        inp.sigma_s = [f64::NAN, 0.1, 0.1];
        assert!(matches!(solve(&inp), Err(ColumnError::BadInput(_))));
        // Nearly conservative water over a white bottom still ends.
        let mut inp = case(1e-6, 1.0, 0.9, 5.0, true, 0.1);
        inp.bottom_albedo = [1.0; 3];
        inp.photons = 2000;
        let col = solve(&inp).unwrap();
        assert!(col.table[0].iter().all(|v| v.is_finite()));
    }

    /// The table's directions ([`Column::sample`], which the camera ray's gather draws from)
    /// follow the light they estimate ([`Column::radiance_binned`] × cos θ): under a sun through 12 m of coastal water
    /// (g = 0.92, the aureole's peak in the table) the estimate of E_d's diffuse part at the
    /// bottom and half-way down matches the column's own crossing tallies, and its relative
    /// spread per sample stays small. (Sampling bins against the trilinear interpolation
    /// spread it 40 %: fireflies on every sunlit surface.)
    #[test]
    fn surface_sampling_follows_the_diffuse_light() {
        let col = solve(&reef_site([0.0, 2.0, 3.0], Top::Open, 200_000)).unwrap();
        // The irradiance on a level surface from the channels' summed light converges to E_d.
        let estimate = |z: f64| {
            let mut rng = SplitMix64(5);
            let n = 100_000;
            let (mut s, mut s2) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                let (w, p) = col
                    .sample(z, true, rng.next_f64(), rng.next_f64(), rng.next_f64())
                    .unwrap();
                let through = (-DVec3::new(0.379, 0.1159, 0.0915) * (z / w.z)).exp() * col.sky;
                let e = (col.radiance_binned(z, w) + through) * w.z / p;
                s += e;
                s2 += e * e;
            }
            let m = s / n as f64;
            let spread = (s2 / n as f64 - m * m).max(DVec3::ZERO).sqrt() / m;
            (m, spread)
        };
        for z in [11.95, 6.0] {
            let j = (z / 12.0 * NZ as f64).round() as usize;
            let (m, spread) = estimate(z);
            for c in 1..3 {
                let e_d = col.profiles[c].e_d_diffuse[j];
                assert!(
                    (m[c] / e_d - 1.0).abs() < 0.015,
                    "z {z} channel {c}: {} vs {e_d}",
                    m[c]
                );
                assert!(spread[c] < 0.12, "z {z} channel {c}: spread {}", spread[c]);
            }
        }
    }
}
