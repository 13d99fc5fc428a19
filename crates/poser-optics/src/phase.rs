//! Phase functions: Henyey–Greenstein and Fournier–Forand (evaluation, sampling, backscatter).
//!
//! | function | parameters | notes |
//! |---|---|---|
//! | [`hg_eval`], [`hg_sample`], [`hg_backscatter`] | asymmetry g ∈ (−1, 1) | Henyey & Greenstein 1941; per steradian, ∫p dΩ = 1 |
//! | [`ff_eval`], [`ff_cdf`], [`ff_backscatter`] | particle index n > 1 relative to water, Junge slope 3 < μ ≤ 5 | Fournier & Forand 1994; closed forms of Mobley, Sundman & Boss, Appl. Opt. 41(6):1035 (2002) |
//!
//! This is the only implementation of the phase physics: the native medium and the Mitsuba
//! emitter call these functions (and tabulate FF from [`ff_cdf`] in their own layouts).
//!
//! Angles are scattering angles θ from the forward direction; `cos θ` is returned by samplers.

use glam::DVec3;
use std::f64::consts::PI;

/// Henyey–Greenstein phase function (1/sr) at `cos_theta`.
pub fn hg_eval(g: f64, cos_theta: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * d * d.sqrt())
}

/// Sample cos θ from Henyey–Greenstein with a uniform `u` ∈ [0, 1).
pub fn hg_sample(g: f64, u: f64) -> f64 {
    // Below |g| = 1e-4 the closed form cancels badly; HG is isotropic to that accuracy.
    if g.abs() < 1e-4 {
        return (1.0 - 2.0 * u).clamp(-1.0, 1.0);
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// Backscatter fraction of Henyey–Greenstein with asymmetry g.
pub fn hg_backscatter(g: f64) -> f64 {
    if g.abs() < 1e-9 {
        0.5
    } else {
        (1.0 - g) / (2.0 * g) * ((1.0 + g) / (1.0 + g * g).sqrt() - 1.0)
    }
}

fn ff_delta(n: f64, theta: f64) -> f64 {
    let s = (0.5 * theta).sin();
    4.0 * s * s / (3.0 * (n - 1.0) * (n - 1.0))
}

/// Fournier–Forand phase function (1/sr) at scattering angle `theta` (rad, > 0).
pub fn ff_eval(n: f64, mu: f64, theta: f64) -> f64 {
    let nu = (3.0 - mu) / 2.0;
    let d = ff_delta(n, theta);
    let d180 = ff_delta(n, PI);
    let dn = d.powf(nu);
    let s2 = (0.5 * theta).sin().powi(2);
    let a = 1.0 / (4.0 * PI * (1.0 - d).powi(2) * dn)
        * (nu * (1.0 - d) - (1.0 - dn) + (d * (1.0 - dn) - nu * (1.0 - d)) / s2);
    let d180n = d180.powf(nu);
    let c = theta.cos();
    a + (1.0 - d180n) / (16.0 * PI * (d180 - 1.0) * d180n) * (3.0 * c * c - 1.0)
}

/// Backscatter fraction of Fournier–Forand with relative index `n` and Junge slope `mu`.
pub fn ff_backscatter(n: f64, mu: f64) -> f64 {
    let nu = (3.0 - mu) / 2.0;
    let d90 = ff_delta(n, 0.5 * PI);
    1.0 - (1.0 - d90.powf(nu + 1.0) - 0.5 * (1.0 - d90.powf(nu))) / ((1.0 - d90) * d90.powf(nu))
}

/// Fournier–Forand cumulative distribution: the fraction of the scattered light within angle
/// θ of the forward direction (Fournier & Jonasz 1999; Mobley, Sundman & Boss 2002). The
/// backends tabulate FF from it: the native medium (`poser::backend::native::medium`) and
/// Mitsuba's `tabphase` (`poser::backend::mitsuba::view::ff_table`).
pub fn ff_cdf(n: f64, mu: f64, theta: f64) -> f64 {
    let nu = (3.0 - mu) / 2.0;
    let k = 3.0 * (n - 1.0) * (n - 1.0);
    let s2 = (theta / 2.0).sin().powi(2);
    let d = 4.0 / k * s2;
    let d180 = 4.0 / k;
    let first = if d <= 0.0 {
        0.0
    } else {
        (1.0 - d.powf(nu + 1.0) - (1.0 - d.powf(nu)) * s2) / ((1.0 - d) * d.powf(nu))
    };
    let second = (1.0 - d180.powf(nu)) / (8.0 * (d180 - 1.0) * d180.powf(nu))
        * theta.cos()
        * theta.sin().powi(2);
    first + second
}

/// Number of bins of the tabulated Fournier–Forand phase function.
pub const FF_BINS: usize = 2048;

/// A phase function ready for rendering: HG in closed form, or any phase function as a table in
/// cos θ (evaluation and sampling use the same table, so sample weights are exact). Shared by
/// the native renderer and the water-column solver ([`crate::column`]).
#[derive(Debug, Clone)]
pub enum PhaseFn {
    Hg {
        g: f64,
    },
    /// Table: bin k spans θ ∈ `[theta[k], theta[k+1]]` (μ decreasing); `cdf[k]` is the mass of
    /// bins < k; density `dens[k]` per steradian inside bin k.
    Tab {
        mu: Vec<f64>,
        cdf: Vec<f64>,
        dens: Vec<f64>,
    },
}

impl PhaseFn {
    /// Density per steradian at `cos θ`.
    pub fn eval(&self, cos: f64) -> f64 {
        match self {
            PhaseFn::Hg { g } => hg_eval(*g, cos),
            PhaseFn::Tab { mu, dens, .. } => {
                // mu is decreasing; find bin k with mu[k] >= cos >= mu[k+1].
                let k = mu
                    .partition_point(|&m| m > cos)
                    .saturating_sub(1)
                    .min(dens.len() - 1);
                dens[k]
            }
        }
    }

    /// Sample `cos θ` from a uniform number.
    pub fn sample_cos(&self, u: f64) -> f64 {
        match self {
            PhaseFn::Hg { g } => hg_sample(*g, u),
            PhaseFn::Tab { mu, cdf, .. } => {
                let k = cdf
                    .partition_point(|&c| c <= u)
                    .saturating_sub(1)
                    .min(mu.len() - 2);
                let mass = cdf[k + 1] - cdf[k];
                let f = if mass > 0.0 {
                    ((u - cdf[k]) / mass).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                mu[k] + (mu[k + 1] - mu[k]) * f
            }
        }
    }

    /// The uniform number that [`PhaseFn::sample_cos`] maps to `cos` (its inverse): the
    /// phase function's probability between two cosines is the difference of their values.
    pub fn u_of_cos(&self, cos: f64) -> f64 {
        let c = cos.clamp(-1.0, 1.0);
        match self {
            PhaseFn::Hg { g } => {
                let g = *g;
                if g.abs() < 1e-4 {
                    return (1.0 - c) / 2.0;
                }
                let s = (1.0 + g * g - 2.0 * g * c).max(0.0).sqrt();
                if s <= 0.0 {
                    return 1.0;
                }
                (((1.0 - g * g) / s - (1.0 - g)) / (2.0 * g)).clamp(0.0, 1.0)
            }
            PhaseFn::Tab { mu, cdf, .. } => {
                let k = mu
                    .partition_point(|&m| m > c)
                    .saturating_sub(1)
                    .min(mu.len() - 2);
                let span = mu[k + 1] - mu[k];
                let f = if span != 0.0 {
                    ((c - mu[k]) / span).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                cdf[k] + (cdf[k + 1] - cdf[k]) * f
            }
        }
    }

    /// Sample a new propagation direction around `d`; returns (direction, density).
    pub fn sample(&self, d: DVec3, u1: f64, u2: f64) -> (DVec3, f64) {
        let c = self.sample_cos(u1);
        let s = (1.0 - c * c).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let (t, b) = d.any_orthonormal_pair();
        let w = (t * (s * phi.cos()) + b * (s * phi.sin()) + d * c).normalize();
        (w, self.eval(c))
    }
}

/// Fournier–Forand as a [`PhaseFn::Tab`] of [`FF_BINS`] bins (particle index `n`, Junge slope
/// `mu_slope`).
pub fn ff_table(n: f64, mu_slope: f64) -> PhaseFn {
    // θ edges: 0, then log-spaced from 1e-5 rad to π.
    let mut theta = vec![0.0];
    let (lo, hi) = (1e-5f64.ln(), PI.ln());
    for k in 0..FF_BINS {
        theta.push((lo + (hi - lo) * k as f64 / (FF_BINS - 1) as f64).exp());
    }
    *theta.last_mut().unwrap() = PI;
    let mu: Vec<f64> = theta.iter().map(|t| t.cos()).collect();
    let mut f: Vec<f64> = theta.iter().map(|&t| ff_cdf(n, mu_slope, t)).collect();
    // Monotone and normalised (F(π) = 1 analytically; guard rounding).
    for k in 1..f.len() {
        f[k] = f[k].max(f[k - 1]);
    }
    let total = *f.last().unwrap();
    for v in &mut f {
        *v /= total;
    }
    let dens = (0..FF_BINS)
        .map(|k| {
            let dmu = mu[k] - mu[k + 1];
            if dmu > 0.0 {
                (f[k + 1] - f[k]) / (2.0 * PI * dmu)
            } else {
                0.0
            }
        })
        .collect();
    PhaseFn::Tab { mu, cdf: f, dens }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_backscatter_values() {
        // docs/optics.md §3.4, printed to 1e-4.
        for (g, b) in [(0.8, 0.0507), (0.85, 0.0361), (0.9, 0.0229), (0.95, 0.0109)] {
            assert!((hg_backscatter(g) - b).abs() < 1e-4, "g={g}");
        }
    }

    #[test]
    fn ff_backscatter_values() {
        // docs/optics.md §3.4, printed to 4 significant digits.
        for (n, mu, b) in [
            (1.10, 3.5835, 0.018313),
            (1.05, 3.5, 0.00572),
            (1.15, 3.7, 0.0397),
        ] {
            let got = ff_backscatter(n, mu);
            assert!((got / b - 1.0).abs() < 2e-3, "n={n} mu={mu}: {got}");
        }
    }

    #[test]
    fn hg_sampling_matches_backscatter_and_mean() {
        // Stratified u: mean cos θ → g and P(cos<0) → B, to 1e-3 with 100k strata.
        let g = 0.9;
        let n = 100_000;
        let (mut mean, mut back) = (0.0, 0.0);
        for i in 0..n {
            let c = hg_sample(g, (i as f64 + 0.5) / n as f64);
            mean += c;
            if c < 0.0 {
                back += 1.0;
            }
        }
        assert!((mean / n as f64 - g).abs() < 1e-3);
        assert!((back / n as f64 - hg_backscatter(g)).abs() < 1e-3);
    }

    #[test]
    fn ff_cdf_reproduces_petzold_backscatter() {
        // n = 1.10, μ = 3.5835 → B = 0.018313 (Mobley, Sundman & Boss 2002; docs/optics.md).
        let b = 1.0 - ff_cdf(1.10, 3.5835, PI / 2.0);
        assert!((b - 0.018313).abs() < 2e-6, "{b}");
        assert!((b - ff_backscatter(1.10, 3.5835)).abs() < 1e-9, "{b}");
        assert!(ff_cdf(1.10, 3.5835, 0.0).abs() < 1e-12);
        assert!((ff_cdf(1.10, 3.5835, PI) - 1.0).abs() < 1e-12);
        let b = 1.0 - ff_cdf(1.15, 3.7, PI / 2.0);
        assert!((b - 0.0397).abs() < 1e-4, "{b}");
    }
}
