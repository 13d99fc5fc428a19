//! The geometry of comparing a reconstruction with the truth: a 7-parameter similarity
//! (Umeyama 1991, least squares, via SVD), error statistics, and the low-order surface fitted
//! to height errors that shows a systematic "bowl".
//!
//! | item | meaning |
//! |---|---|
//! | [`Similarity`] | `truth ≈ s·R·x + t`, estimated by [`Similarity::estimate`] |
//! | [`AxisStats`] | RMS and max |error| in X, Y, Z (and 3D), and [`Robust`] figures of the height error |
//! | [`Robust`] | median, NMAD, LE90 and the share of outliers (Höhle & Höhle 2009): what RMS hides when a few points are far off |
//! | [`Bowl`] | `dz ≈ a + b·x + c·y + d·x² + e·x·y + f·y²` over the plot, and the share of the height-error variance it explains |

use glam::{DMat3, DVec3};
use nalgebra::{DMatrix, DVector, Matrix3};
use serde::Serialize;

/// A similarity transform `y = s·R·x + t`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Similarity {
    pub scale: f64,
    /// Row-major rotation.
    pub rotation: [[f64; 3]; 3],
    pub translation: [f64; 3],
}

impl Similarity {
    /// The identity: the reconstruction is already in the truth's frame (control points
    /// weighted in the adjustment).
    pub fn identity() -> Similarity {
        Similarity {
            scale: 1.0,
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.0; 3],
        }
    }

    /// Least-squares similarity taking `from[i]` onto `to[i]` (Umeyama 1991). `None` for fewer
    /// than three points or a degenerate (collinear) set.
    pub fn estimate(from: &[DVec3], to: &[DVec3]) -> Option<Similarity> {
        let n = from.len();
        if n < 3 || n != to.len() {
            return None;
        }
        let mf = from.iter().copied().sum::<DVec3>() / n as f64;
        let mt = to.iter().copied().sum::<DVec3>() / n as f64;
        let mut cov = Matrix3::<f64>::zeros();
        let mut var_f = 0.0;
        for (a, b) in from.iter().zip(to) {
            let (a, b) = (*a - mf, *b - mt);
            var_f += a.length_squared();
            for i in 0..3 {
                for j in 0..3 {
                    cov[(i, j)] += b[i] * a[j];
                }
            }
        }
        cov /= n as f64;
        var_f /= n as f64;
        if var_f <= 0.0 {
            return None;
        }
        let svd = cov.svd(true, true);
        let (u, vt) = (svd.u?, svd.v_t?);
        let mut sgn = Matrix3::<f64>::identity();
        if (u * vt).determinant() < 0.0 {
            sgn[(2, 2)] = -1.0;
        }
        let sv = svd.singular_values;
        // Collinear points: the second singular value vanishes.
        if sv[1] <= 1e-12 * sv[0].max(f64::MIN_POSITIVE) {
            return None;
        }
        let r = u * sgn * vt;
        let trace = sv[0] * sgn[(0, 0)] + sv[1] * sgn[(1, 1)] + sv[2] * sgn[(2, 2)];
        let s = trace / var_f;
        let rot = DMat3::from_cols(
            DVec3::new(r[(0, 0)], r[(1, 0)], r[(2, 0)]),
            DVec3::new(r[(0, 1)], r[(1, 1)], r[(2, 1)]),
            DVec3::new(r[(0, 2)], r[(1, 2)], r[(2, 2)]),
        );
        let t = mt - s * (rot * mf);
        Some(Similarity {
            scale: s,
            rotation: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
            translation: t.to_array(),
        })
    }

    fn mat(&self) -> DMat3 {
        let r = self.rotation;
        DMat3::from_cols(
            DVec3::new(r[0][0], r[1][0], r[2][0]),
            DVec3::new(r[0][1], r[1][1], r[2][1]),
            DVec3::new(r[0][2], r[1][2], r[2][2]),
        )
    }

    /// Apply to a point.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.scale * (self.mat() * p) + DVec3::from_array(self.translation)
    }
}

/// RMS and largest absolute error per axis and in 3D, m.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct AxisStats {
    pub count: usize,
    pub rms: [f64; 3],
    pub max: [f64; 3],
    pub rms_3d: f64,
    pub max_3d: f64,
    /// Robust figures of the Z errors.
    pub robust_z: Robust,
}

/// Robust accuracy figures of one error component, m (Höhle & Höhle 2009, "Accuracy
/// assessment of digital elevation models by means of robust statistical methods", ISPRS
/// J. 64(4)): they hold when a few points are far off, where RMS does not.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Robust {
    /// Median of the signed errors (the systematic shift).
    pub median: f64,
    /// Normalized median absolute deviation, `1.4826 · median(|e − median|)`: the σ of the
    /// errors' core (equal to σ for normally distributed errors).
    pub nmad: f64,
    /// The 90 % quantile of |e| ("linear error at 90 %").
    pub le90: f64,
    /// Share of errors beyond `median ± 3 · NMAD`.
    pub outliers: f64,
}

/// The `q`-quantile of sorted values (linear interpolation between order statistics).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x.fract());
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] + f * (sorted[j] - sorted[i])
}

impl Robust {
    /// Of finite `errors` (non-finite values are skipped); all zero for none.
    pub fn of(errors: impl IntoIterator<Item = f64>) -> Robust {
        let mut e: Vec<f64> = errors.into_iter().filter(|v| v.is_finite()).collect();
        if e.is_empty() {
            return Robust::default();
        }
        e.sort_by(f64::total_cmp);
        let median = quantile(&e, 0.5);
        let mut dev: Vec<f64> = e.iter().map(|v| (v - median).abs()).collect();
        dev.sort_by(f64::total_cmp);
        let nmad = 1.4826 * quantile(&dev, 0.5);
        let mut abs: Vec<f64> = e.iter().map(|v| v.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let outliers = dev.iter().filter(|&&d| d > 3.0 * nmad).count() as f64 / e.len() as f64;
        Robust {
            median,
            nmad,
            le90: quantile(&abs, 0.9),
            outliers,
        }
    }
}

impl AxisStats {
    pub fn of(errors: &[DVec3]) -> AxisStats {
        let n = errors.len();
        if n == 0 {
            return AxisStats::default();
        }
        let mut s = AxisStats {
            count: n,
            ..Default::default()
        };
        let mut sq = [0.0; 3];
        let mut sq3 = 0.0;
        for e in errors {
            for i in 0..3 {
                sq[i] += e[i] * e[i];
                s.max[i] = s.max[i].max(e[i].abs());
            }
            sq3 += e.length_squared();
            s.max_3d = s.max_3d.max(e.length());
        }
        s.rms = sq.map(|v| (v / n as f64).sqrt());
        s.rms_3d = (sq3 / n as f64).sqrt();
        s.robust_z = Robust::of(errors.iter().map(|e| e.z));
        s
    }
}

/// The quadratic surface fitted to height errors over the plot: the systematic part.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Bowl {
    /// Coefficients of `a + b·x' + c·y' + d·x'² + e·x'·y' + f·y'²`, with `x' = x − x₀`,
    /// `y' = y − y₀` in metres about the centroid `origin` of the points.
    pub coefficients: [f64; 6],
    pub origin: [f64; 2],
    /// Share of the height-error variance the surface explains (R², 0..1).
    pub explained: f64,
    /// RMS of the fitted surface and of what is left, m.
    pub rms_fit: f64,
    pub rms_residual: f64,
    /// Peak-to-peak of the fitted surface over the points, m.
    pub peak_to_peak: f64,
}

impl Bowl {
    /// Least-squares fit to `(x, y, dz)`; `None` with fewer than 12 points.
    pub fn fit(samples: &[(f64, f64, f64)]) -> Option<Bowl> {
        let n = samples.len();
        if n < 12 {
            return None;
        }
        let x0 = samples.iter().map(|s| s.0).sum::<f64>() / n as f64;
        let y0 = samples.iter().map(|s| s.1).sum::<f64>() / n as f64;
        let terms = |x: f64, y: f64| [1.0, x, y, x * x, x * y, y * y];
        let a = DMatrix::from_fn(n, 6, |i, j| terms(samples[i].0 - x0, samples[i].1 - y0)[j]);
        let b = DVector::from_fn(n, |i, _| samples[i].2);
        let sol = a.clone().svd(true, true).solve(&b, 1e-12).ok()?;
        let fitted = &a * &sol;
        let mean = b.mean();
        let var = b.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        let res = (&b - &fitted).iter().map(|v| v * v).sum::<f64>();
        let (lo, hi) = fitted
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        Some(Bowl {
            coefficients: [0, 1, 2, 3, 4, 5].map(|j| sol[j]),
            origin: [x0, y0],
            explained: if var > 0.0 {
                (1.0 - res / var).clamp(0.0, 1.0)
            } else {
                0.0
            },
            rms_fit: (fitted.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt(),
            rms_residual: (res / n as f64).sqrt(),
            peak_to_peak: hi - lo,
        })
    }

    /// The fitted height error at `(x, y)`.
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let (x, y) = (x - self.origin[0], y - self.origin[1]);
        let c = self.coefficients;
        c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn robust_figures_ignore_a_few_far_points_where_rms_does_not() {
        // 96 errors normally spread (σ = 1 mm, by the inverse CDF at stratified levels), plus
        // 4 points a metre off: RMS blows up, the robust figures keep the core.
        let inv = |p: f64| {
            // Acklam's rational approximation is overkill here: bisect erf.
            let (mut lo, mut hi) = (-10.0f64, 10.0f64);
            for _ in 0..200 {
                let m = 0.5 * (lo + hi);
                let cdf = 0.5 * (1.0 + libm_erf(m / 2f64.sqrt()));
                if cdf < p { lo = m } else { hi = m }
            }
            0.5 * (lo + hi)
        };
        let mut e: Vec<f64> = (0..96)
            .map(|i| 1e-3 * inv((i as f64 + 0.5) / 96.0))
            .collect();
        e.extend([1.0, -1.0, 1.2, 0.9]);
        let r = Robust::of(e.iter().copied());
        assert!(r.median.abs() < 1e-4, "median {}", r.median);
        assert!((r.nmad - 1e-3).abs() < 0.1e-3, "NMAD {}", r.nmad);
        // LE90 of |N(0, 1 mm)| is 1.645 mm; four outliers of 100 shift the quantile a little.
        assert!(r.le90 > 1.5e-3 && r.le90 < 2.0e-3, "LE90 {}", r.le90);
        assert!((r.outliers - 0.04).abs() < 0.011, "outliers {}", r.outliers);
        let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
        assert!(rms > 100.0 * r.nmad);
        // Empty and non-finite input: zeros, no NaN.
        let z = Robust::of([f64::NAN]);
        assert_eq!((z.median, z.nmad, z.le90, z.outliers), (0.0, 0.0, 0.0, 0.0));
    }

    /// erf by its Abramowitz–Stegun 7.1.26 approximation (|error| < 1.5e-7), for the test.
    fn libm_erf(x: f64) -> f64 {
        let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
        let y = 1.0
            - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736)
                * t
                + 0.254_829_592)
                * t
                * (-x * x).exp();
        y.copysign(x)
    }

    #[test]
    fn recovers_a_known_similarity() {
        let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 1.1);
        let from: Vec<DVec3> = (0..20)
            .map(|i| {
                let f = i as f64;
                DVec3::new(f.sin() * 3.0, (f * 0.7).cos() * 2.0, f * 0.1)
            })
            .collect();
        let to: Vec<DVec3> = from
            .iter()
            .map(|p| 1.7 * (q * *p) + DVec3::new(5.0, -2.0, 0.5))
            .collect();
        let s = Similarity::estimate(&from, &to).unwrap();
        assert!((s.scale - 1.7).abs() < 1e-12);
        for (a, b) in from.iter().zip(&to) {
            assert!((s.apply(*a) - *b).length() < 1e-10);
        }
    }

    #[test]
    fn collinear_points_have_no_similarity() {
        let from: Vec<DVec3> = (0..5).map(|i| DVec3::X * i as f64).collect();
        assert!(Similarity::estimate(&from, &from).is_none());
    }

    #[test]
    fn bowl_explains_a_quadratic_and_not_noise() {
        let mut rng = crate::rng::SplitMix64(3);
        let pts: Vec<(f64, f64, f64)> = (0..400)
            .map(|_| {
                let (x, y) = (rng.next_f64() * 10.0, rng.next_f64() * 4.0);
                (x, y, 0.01 * (x - 5.0).powi(2))
            })
            .collect();
        let b = Bowl::fit(&pts).unwrap();
        assert!(b.explained > 0.999_999, "{}", b.explained);
        assert!((b.peak_to_peak - 0.25).abs() < 0.01, "{}", b.peak_to_peak);
        let noise: Vec<(f64, f64, f64)> = (0..400)
            .map(|_| {
                (
                    rng.next_f64() * 10.0,
                    rng.next_f64() * 4.0,
                    super::super::observe::gauss(&mut rng),
                )
            })
            .collect();
        assert!(Bowl::fit(&noise).unwrap().explained < 0.1);
    }
}
