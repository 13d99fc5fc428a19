//! Phase functions: Henyey–Greenstein and Fournier–Forand (evaluation, sampling, backscatter).
//!
//! | function | parameters | notes |
//! |---|---|---|
//! | [`hg_eval`], [`hg_sample`], [`hg_backscatter`] | asymmetry g ∈ (−1, 1) | Henyey & Greenstein 1941; per steradian, ∫p dΩ = 1 |
//! | [`ff_eval`], [`FfTable`], [`ff_backscatter`] | particle index n > 1 relative to water, Junge slope 3 < μ ≤ 5 | Mobley, Sundman & Boss, Appl. Opt. 41(6):1035 (2002) |
//!
//! Angles are scattering angles θ from the forward direction; `cos θ` is returned by samplers.

use std::f64::consts::PI;

/// Henyey–Greenstein phase function (1/sr) at `cos_theta`.
pub fn hg_eval(g: f64, cos_theta: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * d * d.sqrt())
}

/// Sample cos θ from Henyey–Greenstein with a uniform `u` ∈ [0, 1).
pub fn hg_sample(g: f64, u: f64) -> f64 {
    if g.abs() < 1e-6 {
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

/// Tabulated inverse CDF of Fournier–Forand for sampling (the θ → 0 peak is integrable but
/// sharp, so the table is log-spaced in θ from 1e-6 rad to π).
#[derive(Debug, Clone)]
pub struct FfTable {
    theta: Vec<f64>,
    cdf: Vec<f64>,
}

impl FfTable {
    const N: usize = 2048;
    pub fn new(n: f64, mu: f64) -> FfTable {
        let (lo, hi) = (1e-6f64.ln(), PI.ln());
        let mut theta = vec![0.0];
        theta
            .extend((0..Self::N).map(|i| (lo + (hi - lo) * i as f64 / (Self::N - 1) as f64).exp()));
        let mut cdf = vec![0.0; theta.len()];
        // Below 1e-6 rad the integrand 2π p sinθ ~ θ^(1-μ+... ) is handled by the first
        // trapezoid; trapezoid on a log grid elsewhere, renormalised to 1.
        let f = |t: f64| {
            if t <= 0.0 {
                0.0
            } else {
                2.0 * PI * ff_eval(n, mu, t) * t.sin()
            }
        };
        for i in 1..theta.len() {
            let (a, b) = (theta[i - 1], theta[i]);
            let m = 0.5 * (a + b);
            cdf[i] = cdf[i - 1] + (b - a) * (f(a) + 4.0 * f(m) + f(b)) / 6.0;
        }
        let total = *cdf.last().unwrap();
        for c in &mut cdf {
            *c /= total;
        }
        FfTable { theta, cdf }
    }
    /// Sample cos θ with a uniform `u` ∈ [0, 1).
    pub fn sample(&self, u: f64) -> f64 {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .clamp(1, self.cdf.len() - 1);
        let (c0, c1) = (self.cdf[i - 1], self.cdf[i]);
        let w = if c1 > c0 {
            ((u - c0) / (c1 - c0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (self.theta[i - 1] + w * (self.theta[i] - self.theta[i - 1])).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_backscatter_values() {
        // optics.md §3.4, printed to 1e-4.
        for (g, b) in [(0.8, 0.0507), (0.85, 0.0361), (0.9, 0.0229), (0.95, 0.0109)] {
            assert!((hg_backscatter(g) - b).abs() < 1e-4, "g={g}");
        }
    }

    #[test]
    fn ff_backscatter_values() {
        // optics.md §3.4 [verified numerically], printed to 4 significant digits.
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
    fn ff_table_integrates_to_one_and_backscatter_matches() {
        // The CDF at 90° must equal 1 − B (table resolution: 1e-3).
        let (n, mu) = (1.10, 3.5835);
        let t = FfTable::new(n, mu);
        let k = t.theta.partition_point(|&x| x < 0.5 * PI);
        let back = 1.0 - t.cdf[k];
        assert!((back - ff_backscatter(n, mu)).abs() < 1e-3, "{back}");
        let c = t.sample(0.999_999);
        assert!((-1.0..=1.0).contains(&c));
    }
}
