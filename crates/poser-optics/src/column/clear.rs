//! The column of water that does not scatter, solved exactly: in clear water (σs = 0 in every
//! channel) the column's light has closed forms up to one-dimensional integrals in the polar
//! cosine, so [`super::solve`] computes it by quadrature instead of flying photons (it
//! flew 2 M photons per channel per round for what is a handful of integrals: 0.5–1 s of a
//! render's start-up, and noise on what is exact).
//!
//! | quantity (channel `c`, attenuation `σ = σa`, depth `z`, bottom at `H`) | closed form |
//! |---|---|
//! | the sun's beam, `E_dir(z)` | `E0 μ0 e^(−σz/μ0)` |
//! | the sky's light through the water, `E_sky(z)` | `2π ∫₀¹ S(μ) e^(−σz/μ) μ dμ`, `S` the sky seen looking up ([`super::sky_seen`]: through Snell's window under a reflecting surface) |
//! | the surface's return of the bottom's light, `Q` | `2π ∫₀¹ R(μ) e^(−2σH/μ) μ dμ` (`R` the Fresnel reflectance from below, 1 beyond the critical angle; 0 under an open top) |
//! | the bottom's radiance, `L_b` | `A (E_dir(H) + E_sky(H)) / (π − A Q)`: the geometric series of bottom → surface → bottom, summed |
//! | the table (light looking up that the surface reflected), `L(z, μ)` | `L_b R(μ) e^(−σ(H + z)/μ)`, averaged over each layer (closed form in z) and polar bin (quadrature), the same in every azimuth |
//! | `E_u(z)` | `2π L_b ∫₀¹ e^(−σ(H − z)/μ) μ dμ` (`A·E_d(H)` at the bottom) |
//! | `E_0(z)` | the beam's `E0 e^(−σz/μ0)` plus `2π ∫₀¹` of the three radiances (sky, reflected, bottom) |
//! | scattering orders seen looking down | the bottom's light after `1, 3, 5, …` events (each surface return and bottom reflection one), `L_b,n = L_b,1 (A Q / π)^((n−1)/2)` |
//!
//! Quadrature: Simpson's rule, split at the critical angle (where `R` and `S` have a kink),
//! [`INTERVALS`] intervals for the profiles and [`BIN_INTERVALS`] per polar bin of the table:
//! relative error below 10⁻⁶ (the profiles' standard errors are 0). The walk's tallies estimate
//! exactly these integrals; `clear_water_is_solved_exactly_as_the_walk_estimates` compares
//! them.

use super::{
    Column, NMU, NPHI, NZ, ORDERS, Profile, SEEN_CONE, build_cdf, mu_edge, open, scatter, sky_seen,
};
use super::{ColumnInput, reflectance_from_below};
use glam::DVec3;
use std::f64::consts::PI;

/// Simpson intervals of an integral over [0, 1] in the polar cosine.
pub const INTERVALS: usize = 4096;
/// Simpson intervals per polar bin of the table.
pub const BIN_INTERVALS: usize = 64;

/// `∫ f` over [a, b] by Simpson's rule on `n` (even) intervals.
fn simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    if !(b > a) {
        return 0.0;
    }
    let n = n.max(2) & !1;
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// `∫ f` over [a, b] ⊂ [0, 1], split at the critical cosine `kink` when it lies inside; `n`
/// intervals per unit length (at least 8 per piece).
fn integrate(f: &impl Fn(f64) -> f64, a: f64, b: f64, kink: Option<f64>, n: usize) -> f64 {
    let pieces = match kink {
        Some(k) if k > a && k < b => vec![(a, k), (k, b)],
        _ => vec![(a, b)],
    };
    pieces
        .into_iter()
        .map(|(lo, hi)| simpson(f, lo, hi, (((hi - lo) * n as f64) as usize).max(8)))
        .sum()
}

/// One channel's closed forms (see the module table).
struct Channel {
    c: usize,
    sigma: f64,
    depth: f64,
    /// The water's index under a reflecting surface (`None`: an open top).
    n: Option<f64>,
    /// The sky's radiance above the surface (all channels, as [`sky_seen`] takes it).
    sky_l: DVec3,
    /// The critical cosine under a reflecting surface.
    kink: Option<f64>,
    /// The bottom's radiance (all orders) and its first order.
    l_b: f64,
    l_b1: f64,
    /// `A Q / π`: the share of the bottom's radiance that comes back to it.
    ratio: f64,
}

impl Channel {
    fn new(input: &ColumnInput, c: usize) -> Channel {
        let n = input.top.window().map(|n| n[c]);
        let mut ch = Channel {
            c,
            sigma: input.sigma_a[c],
            depth: input.depth,
            n,
            sky_l: DVec3::from_array(input.ambient),
            kink: n.map(|n| (1.0 - 1.0 / (n * n)).max(0.0).sqrt()),
            l_b: 0.0,
            l_b1: 0.0,
            ratio: 0.0,
        };
        let (sigma, depth) = (ch.sigma, ch.depth);
        let e_dir_h = input.sun.map_or(0.0, |s| {
            let mu0 = -s.dirs[c].z;
            s.irradiance[c] * mu0 * (-sigma * depth / mu0).exp()
        });
        let e_sky_h = ch.sky_irradiance(depth);
        let q = 2.0 * PI * ch.quad(&|mu| ch.reflect(mu) * (-2.0 * sigma * depth / mu).exp() * mu);
        let a = input.bottom_albedo[c];
        ch.ratio = a * q / PI;
        ch.l_b1 = a * (e_dir_h + e_sky_h) / PI;
        ch.l_b = ch.l_b1 / (1.0 - ch.ratio);
        ch
    }

    /// The surface's reflectance from below at cosine `mu` (0 under an open top).
    fn reflect(&self, mu: f64) -> f64 {
        self.n.map_or(0.0, |n| reflectance_from_below(n, mu))
    }

    /// The sky's radiance seen looking up at cosine `mu`.
    fn sky(&self, mu: f64) -> f64 {
        sky_seen(self.sky_l, self.n.map(|n| [n; 3]), mu)[self.c]
    }

    /// `∫₀¹ f(μ) dμ`, split at the critical cosine. (`f` is evaluated at μ > 0 only where
    /// it carries an `e^(−x/μ)`; at μ = 0 every integrand here is 0.)
    fn quad(&self, f: &impl Fn(f64) -> f64) -> f64 {
        let g = |mu: f64| if mu > 0.0 { f(mu) } else { 0.0 };
        integrate(&g, 0.0, 1.0, self.kink, INTERVALS)
    }

    fn sky_irradiance(&self, z: f64) -> f64 {
        2.0 * PI * self.quad(&|mu| self.sky(mu) * (-self.sigma * z / mu).exp() * mu)
    }

    /// The surface's return of the bottom's light at depth `z`, looking up at cosine `mu`.
    fn reflected(&self, z: f64, mu: f64) -> f64 {
        self.l_b * self.reflect(mu) * (-self.sigma * (self.depth + z) / mu).exp()
    }

    /// The bottom's radiance seen looking down at cosine `mu` from depth `z`.
    fn bottom_seen(&self, z: f64, mu: f64) -> f64 {
        self.l_b * (-self.sigma * (self.depth - z) / mu).exp()
    }

    /// `∫ e^(−σ(d0 + s z)/μ) dz` over the layer [z0, z1] (s = ±1), closed form.
    fn layer_integral(&self, d0: f64, s: f64, z0: f64, z1: f64, mu: f64) -> f64 {
        let k = self.sigma / mu;
        let (a, b) = ((-k * (d0 + s * z0)).exp(), (-k * (d0 + s * z1)).exp());
        (a - b) / (s * k)
    }
}

/// The column of non-scattering water (`input.sigma_s` all 0), exact.
pub(super) fn solve(input: &ColumnInput) -> Column {
    let t0 = std::time::Instant::now();
    let az = input
        .sun
        .and_then(|s| DVec3::new(-s.dirs[1].x, -s.dirs[1].y, 0.0).try_normalize())
        .unwrap_or(DVec3::X);
    let dz = input.depth / NZ as f64;
    let mut table: [Vec<f32>; 3] = Default::default();
    let mut profiles: [Profile; 3] = Default::default();
    let mut seen_orders: [Vec<f64>; 3] = Default::default();
    for c in 0..3 {
        let ch = Channel::new(input, c);
        let (e0, mu0) = match input.sun {
            Some(s) => (s.irradiance[c], -s.dirs[c].z),
            None => (0.0, 1.0),
        };
        let mut p = Profile::default();
        for j in 0..=NZ {
            let z = j as f64 * dz;
            let beam = (-ch.sigma * z / mu0).exp();
            let sky = ch.sky_irradiance(z);
            let refl = 2.0 * PI * ch.quad(&|mu| ch.reflected(z, mu) * mu);
            let up = 2.0 * PI * ch.quad(&|mu| ch.bottom_seen(z, mu) * mu);
            let scalar = 2.0
                * PI
                * ch.quad(&|mu| {
                    ch.sky(mu) * (-ch.sigma * z / mu).exp()
                        + ch.reflected(z, mu)
                        + ch.bottom_seen(z, mu)
                });
            p.e_d_direct.push(e0 * mu0 * beam);
            p.e_d_diffuse.push(sky + refl);
            p.e_u.push(up);
            p.e_0.push(scalar + e0 * beam);
            p.e_d_stderr.push(0.0);
            p.e_u_stderr.push(0.0);
        }
        // The Lambertian bottom reflects exactly A·E_d (as the walk's profiles say it).
        p.e_u[NZ] = input.bottom_albedo[c] * p.e_d(NZ);
        p.fill_k_d(dz);
        // The table: the reflected light looking up (polar bins from NMU/2), each bin's mean
        // over its layer and its cosines (the walk's track-length estimate of the same).
        let mut t = vec![0.0f32; NZ * NMU * NPHI];
        if ch.l_b > 0.0 && ch.kink.is_some() {
            for k in 0..NZ {
                let (z0, z1) = (k as f64 * dz, (k + 1) as f64 * dz);
                for i in NMU / 2..NMU {
                    let (a, b) = (mu_edge(i).max(0.0), mu_edge(i + 1));
                    let f = |mu: f64| {
                        if mu > 0.0 {
                            ch.l_b * ch.reflect(mu) * ch.layer_integral(ch.depth, 1.0, z0, z1, mu)
                        } else {
                            0.0
                        }
                    };
                    let per_mu = BIN_INTERVALS as f64 / (b - a);
                    let v = integrate(&f, a, b, ch.kink, per_mu as usize) / ((b - a) * dz);
                    t[(k * NMU + i) * NPHI..(k * NMU + i + 1) * NPHI].fill(v as f32);
                }
            }
        }
        table[c] = t;
        // The radiance seen looking down within the cone, by the events it met: the bottom's
        // light after 1, 3, 5, … events (each return by the surface is two more).
        let mut seen = vec![0.0; NZ * (ORDERS + 1)];
        for k in 0..NZ {
            let (z0, z1) = (k as f64 * dz, (k + 1) as f64 * dz);
            let per_unit = 2.0
                * PI
                * integrate(
                    &|mu: f64| ch.layer_integral(ch.depth, -1.0, z0, z1, mu),
                    SEEN_CONE,
                    1.0,
                    None,
                    INTERVALS,
                );
            let mut l_n = ch.l_b1;
            let mut n = 1;
            while n < ORDERS && l_n > 0.0 {
                seen[k * (ORDERS + 1) + n] = l_n * per_unit;
                l_n *= ch.ratio;
                n += 2;
            }
            // What is left of the series, in the last bin.
            if l_n > 0.0 {
                seen[k * (ORDERS + 1) + ORDERS] += l_n / (1.0 - ch.ratio) * per_unit;
            }
        }
        seen_orders[c] = seen;
        profiles[c] = p;
    }
    let bottom =
        DVec3::from_array([0, 1, 2].map(|c| input.bottom_albedo[c] * profiles[c].e_d(NZ) / PI));
    let cdf = build_cdf(&table, input, bottom);
    Column {
        depth: input.depth,
        sun_azimuth: az,
        first: [0, 1, 2].map(|c| vec![0.0; table[c].len()]),
        table,
        cdf,
        profiles,
        seen_orders,
        truncated: 0.0,
        photons: 0,
        sky: DVec3::from_array(input.ambient),
        bottom,
        window: input.top.window(),
        sigma_t: DVec3::from_array(input.sigma_a),
        open: open::empty_layers(),
        samplers: open::empty_samplers(),
        phase: input.phase.clone(),
        scatter: scatter::Tables::default(),
        seconds: t0.elapsed().as_secs_f64(),
    }
}
