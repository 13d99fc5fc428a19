//! A wavy sea surface: a deterministic, seeded, periodic height field `h(x, y)` (m, z up,
//! mean level z = 0) with its analytic gradient. Used by the native renderer's caustics
//! (`poser::backend::native::caustics`).
//!
//! | parameter | unit | default (scene) | meaning |
//! |---|---|---|---|
//! | `height` (`site.wave_height`) | m | 0.5 | significant wave height `Hs = 4·std(h)`, matched exactly |
//! | `wavelength` (`site.wave_length`) | m | 10 | peak wavelength `λp`: the peak of the frequency spectrum is at `ωp = √(g·2π/λp)` (deep water) |
//! | `wind_speed` (`site.wind_speed`) | m/s | 5 | sets the directional spread (Mitsuyasu); the spectrum's *shape* is Pierson–Moskowitz, its level is set by `height` |
//! | `wind_direction` | rad | 0 ([`WIND_DIRECTION`]) | direction the waves travel to, counter-clockwise from +x (east) |
//! | `seed` | – | `site.seed` | phases and directions; same seed → same surface |
//!
//! Model (a "linear random sea", frozen in time):
//!
//! * `h(x, y) = Σᵢ aᵢ·cos(kᵢ·(x, y) + φᵢ)` with [`COMPONENTS`] components.
//! * Frequencies `ωᵢ` are stratified (one jittered sample per bin) over
//!   `[`[`OMEGA_MIN`]`, `[`OMEGA_MAX`]`]·ωp`; amplitudes `aᵢ = √(2·S(ωᵢ)·Δω)` from the
//!   Pierson–Moskowitz shape `S(ω) ∝ ω⁻⁵·exp(−5/4·(ωp/ω)⁴)`, then all scaled by one factor so
//!   that `4·√(Σ aᵢ²/2) = Hs` exactly.
//! * Wavenumbers from deep-water dispersion `k = ω²/g`; directions drawn from the Mitsuyasu
//!   spreading `D(θ) ∝ cos^{2s}((θ − θw)/2)` with `s = 11.5·(ωp·U/g)^−2.5·(ω/ωp)^{5 or −2.5}`
//!   (clamped to [1, 80]): light wind → long-crested swell, strong wind → short-crested sea.
//! * Each wave vector is snapped to the lattice `2π·(m, n)/P` with period
//!   `P = `[`PERIOD_WAVELENGTHS`]`·λp`, so the field is exactly periodic in x and y with period
//!   `P` (components that land on the same lattice point add their energy). Periodicity lets
//!   the caustics be computed over one period and tiled.
//! * The field is bounded: `|h| ≤ Σ|aᵢ|` ([`WaveField::max_abs_height`]).

use crate::rng::SplitMix64;
use std::f64::consts::PI;

/// Standard gravity, m/s².
pub const G: f64 = 9.806_65;
/// Number of sinusoids before lattice merging.
pub const COMPONENTS: usize = 48;
/// Frequency band, in units of the peak frequency ωp (PM energy below 0.6 ωp is < 0.3 % of the peak density).
pub const OMEGA_MIN: f64 = 0.6;
pub const OMEGA_MAX: f64 = 3.5;
/// Period of the field in peak wavelengths.
pub const PERIOD_WAVELENGTHS: f64 = 4.0;
/// Default direction the waves travel towards (rad, counter-clockwise from +x).
pub const WIND_DIRECTION: f64 = 0.0;

/// One sinusoid `a·cos(kx·x + ky·y + φ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    pub kx: f64,
    pub ky: f64,
    pub amplitude: f64,
    pub phase: f64,
}

/// A periodic random sea surface.
#[derive(Debug, Clone, PartialEq)]
pub struct WaveField {
    pub components: Vec<Component>,
    /// Period in x and in y, m.
    pub period: f64,
    pub significant_height: f64,
    pub peak_wavelength: f64,
}

impl WaveField {
    /// The surface for significant height `height` (m, > 0), peak wavelength `wavelength`
    /// (m, > 0), wind speed `wind_speed` (m/s, ≥ 0), travelling towards `wind_direction` (rad).
    /// Non-positive or non-finite height/wavelength give a flat field (no components).
    pub fn new(
        height: f64,
        wavelength: f64,
        wind_speed: f64,
        wind_direction: f64,
        seed: u64,
    ) -> WaveField {
        let period = PERIOD_WAVELENGTHS * wavelength;
        let mut out = WaveField {
            components: Vec::new(),
            period,
            significant_height: height,
            peak_wavelength: wavelength,
        };
        if !(height > 0.0 && wavelength > 0.0 && height.is_finite() && wavelength.is_finite()) {
            return out;
        }
        let mut rng = SplitMix64(seed ^ 0x5EA5_0F7A_7E5F_u64);
        let wp = (G * 2.0 * PI / wavelength).sqrt();
        let s_peak = 11.5 * (wp * wind_speed.max(0.0) / G).max(1e-6).powf(-2.5);
        let dw = (OMEGA_MAX - OMEGA_MIN) * wp / COMPONENTS as f64;
        let dk = 2.0 * PI / period;
        // (m, n) → index into components
        let mut cells: Vec<((i64, i64), usize)> = Vec::new();
        for i in 0..COMPONENTS {
            let w = (OMEGA_MIN * wp) + (i as f64 + rng.next_f64()) * dw;
            let r = wp / w;
            let s_w = w.powi(-5) * (-1.25 * r.powi(4)).exp() * wp.powi(4);
            let s = (s_peak
                * if w < wp {
                    (w / wp).powi(5)
                } else {
                    (w / wp).powf(-2.5)
                })
            .clamp(1.0, 80.0);
            // Rejection sampling of the Mitsuyasu spread about the wind direction.
            let mut theta = 0.0;
            for _ in 0..1000 {
                let t = (2.0 * rng.next_f64() - 1.0) * PI;
                if rng.next_f64() <= (t / 2.0).cos().abs().powf(2.0 * s) {
                    theta = t;
                    break;
                }
            }
            let theta = theta + wind_direction;
            let k = w * w / G;
            let mut m = (k * theta.cos() / dk).round() as i64;
            let n = (k * theta.sin() / dk).round() as i64;
            if m == 0 && n == 0 {
                m = 1;
            }
            let energy = 2.0 * s_w * dw; // a²
            let phase = 2.0 * PI * rng.next_f64();
            match cells.iter().find(|(c, _)| *c == (m, n)) {
                Some(&(_, j)) => {
                    let c: &mut Component = &mut out.components[j];
                    c.amplitude = (c.amplitude * c.amplitude + energy).sqrt();
                }
                None => {
                    cells.push(((m, n), out.components.len()));
                    out.components.push(Component {
                        kx: m as f64 * dk,
                        ky: n as f64 * dk,
                        amplitude: energy.sqrt(),
                        phase,
                    });
                }
            }
        }
        // Scale to Hs: variance of a sum of distinct lattice sinusoids over a period = Σ a²/2.
        let var: f64 = out
            .components
            .iter()
            .map(|c| 0.5 * c.amplitude * c.amplitude)
            .sum();
        if var > 0.0 {
            let f = (height / 4.0) / var.sqrt();
            for c in &mut out.components {
                c.amplitude *= f;
            }
        }
        out
    }

    /// A surface with no waves (h ≡ 0).
    pub fn flat(period: f64) -> WaveField {
        WaveField {
            components: Vec::new(),
            period,
            significant_height: 0.0,
            peak_wavelength: period / PERIOD_WAVELENGTHS,
        }
    }

    /// Height `h(x, y)`, m.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.components
            .iter()
            .map(|c| c.amplitude * (c.kx * x + c.ky * y + c.phase).cos())
            .sum()
    }

    /// Gradient `(∂h/∂x, ∂h/∂y)`.
    pub fn gradient(&self, x: f64, y: f64) -> (f64, f64) {
        let mut g = (0.0, 0.0);
        for c in &self.components {
            let s = -c.amplitude * (c.kx * x + c.ky * y + c.phase).sin();
            g.0 += s * c.kx;
            g.1 += s * c.ky;
        }
        g
    }

    /// Height and gradient `(h, ∂h/∂x, ∂h/∂y)` in one pass (one sine and cosine per
    /// component).
    pub fn height_gradient(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let mut r = (0.0, 0.0, 0.0);
        for c in &self.components {
            let (s, co) = (c.kx * x + c.ky * y + c.phase).sin_cos();
            r.0 += c.amplitude * co;
            r.1 -= c.amplitude * s * c.kx;
            r.2 -= c.amplitude * s * c.ky;
        }
        r
    }

    /// Bound on |h|: `Σ|aᵢ|`.
    pub fn max_abs_height(&self) -> f64 {
        self.components.iter().map(|c| c.amplitude.abs()).sum()
    }

    /// Root-mean-square slope `√(Σ aᵢ²·|kᵢ|²/2)` (per axis pair, i.e. of |∇h|).
    pub fn rms_slope(&self) -> f64 {
        self.components
            .iter()
            .map(|c| 0.5 * c.amplitude * c.amplitude * (c.kx * c.kx + c.ky * c.ky))
            .sum::<f64>()
            .sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> WaveField {
        WaveField::new(0.5, 10.0, 5.0, 0.3, 42)
    }

    #[test]
    fn significant_height_matches() {
        // Sample one period on a grid finer than twice the largest lattice index (Nyquist),
        // so the grid mean of h² is the exact spatial variance up to rounding (1e-9 relative).
        for (hs, lam, u) in [(0.5, 10.0, 5.0), (0.2, 3.0, 12.0), (1.5, 40.0, 1.0)] {
            let f = WaveField::new(hs, lam, u, 0.0, 7);
            assert!(
                f.components.len() >= 10,
                "{} components",
                f.components.len()
            );
            let n = 256;
            let (mut s, mut s2) = (0.0, 0.0);
            for i in 0..n {
                for j in 0..n {
                    let h = f.height(
                        i as f64 * f.period / n as f64,
                        j as f64 * f.period / n as f64,
                    );
                    s += h;
                    s2 += h * h;
                }
            }
            let nn = (n * n) as f64;
            let mean = s / nn;
            let got = 4.0 * (s2 / nn - mean * mean).sqrt();
            assert!(mean.abs() < 1e-9 * hs, "mean {mean}");
            assert!((got - hs).abs() < 1e-9 * hs, "Hs {got} vs {hs}");
        }
    }

    #[test]
    fn periodic_bounded_and_seeded() {
        let f = field();
        let b = f.max_abs_height();
        // Bound: Σ|a| is finite and at most a few Hs for a few dozen components.
        assert!(b > 0.5 / 4.0 && b < 10.0 * 0.5, "bound {b}");
        for (x, y) in [(0.3, -1.7), (12.0, 5.5), (-33.0, 71.2)] {
            let h = f.height(x, y);
            assert!(h.abs() <= b);
            // Periodic to rounding of the phase (arguments up to ~100 rad: 1e-12 m).
            assert!((f.height(x + f.period, y) - h).abs() < 1e-11);
            assert!((f.height(x, y - f.period) - h).abs() < 1e-11);
        }
        assert_eq!(f, field());
        assert_ne!(f, WaveField::new(0.5, 10.0, 5.0, 0.3, 43));
        assert!(WaveField::new(0.0, 10.0, 5.0, 0.0, 1).components.is_empty());
        assert!(
            WaveField::new(f64::NAN, 10.0, 5.0, 0.0, 1)
                .components
                .is_empty()
        );
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let f = field();
        let e = 1e-5;
        for (x, y) in [(0.3, -1.7), (12.0, 5.5), (-3.0, 7.2), (25.0, 25.0)] {
            let (gx, gy) = f.gradient(x, y);
            let fx = (f.height(x + e, y) - f.height(x - e, y)) / (2.0 * e);
            let fy = (f.height(x, y + e) - f.height(x, y - e)) / (2.0 * e);
            // Central differences: error O(e²·h''') ≈ 1e-10 plus rounding 1e-16/e ≈ 1e-11.
            assert!((gx - fx).abs() < 1e-8, "{gx} vs {fx}");
            assert!((gy - fy).abs() < 1e-8, "{gy} vs {fy}");
        }
    }

    #[test]
    fn wind_narrows_or_widens_the_spread() {
        // Mitsuyasu: light wind (old swell) → narrow spread; mean |sin(direction)| weighted by
        // energy is smaller for U = 1 m/s than for U = 15 m/s.
        let spread = |u: f64| {
            let f = WaveField::new(0.5, 10.0, u, 0.0, 3);
            let (mut num, mut den) = (0.0, 0.0);
            for c in &f.components {
                let e = c.amplitude * c.amplitude;
                num += e * (c.ky.abs() / c.kx.hypot(c.ky));
                den += e;
            }
            num / den
        };
        let (calm, windy) = (spread(1.0), spread(15.0));
        assert!(calm < windy, "calm {calm} windy {windy}");
    }
}
