//! The noise target (`render.noise`): how many samples each pixel takes, and what it achieved.
//!
//! | setting | meaning |
//! |---|---|
//! | `render.noise` | relative standard error of each pixel's mean that the sampling aims at |
//! | `render.samples` | the pilot: every pixel first takes this many samples to estimate its variance |
//! | `render.max_samples` | the most samples a pixel takes after the pilot (default 16 × `samples`) |
//!
//! Every pixel first renders a pilot of `samples` samples, which estimates the relative
//! standard error `r` of its mean, pooled over the 3×3 pilots around it ([`plan`]); the pixel
//! then takes `n = ⌈samples × (r / noise)²⌉` fresh samples, clamped to
//! `[samples, max_samples]`, and its value is their mean alone. The pilot is dropped because keeping it would make the number of
//! samples depend on the samples averaged, which biases the mean (a pixel that has not yet met
//! a rare bright path looks quiet and would stop early). The fresh samples are independent of
//! the pilot, so the mean is unbiased whatever `n` is. Nothing is clamped.
//!
//! Which channels count: every channel carrying at least [`RELEVANT`] of the pixel's
//! brightest channel (white balance can raise a weak channel eightfold in blue-green water; a
//! weaker one is below the sensor's floor anyway). A pixel whose channels are all zero stops
//! after the pilot.
//!
//! [`Report`] is what `<image>.noise.json` holds (`docs/native.md`).

use glam::DVec3;
use serde::Serialize;

/// A channel counts when its mean is at least this fraction of the pixel's brightest one.
pub const RELEVANT: f64 = 0.05;

/// The largest relative standard error over the pixel's relevant channels (0 when dark).
pub fn relative_error(mean: DVec3, var_of_mean: DVec3) -> f64 {
    let top = mean.max_element();
    if !(top > 0.0) {
        return 0.0;
    }
    (0..3)
        .filter(|&c| mean[c] >= RELEVANT * top)
        .map(|c| var_of_mean[c].max(0.0).sqrt() / mean[c])
        .fold(0.0, f64::max)
}

/// The squared relative standard error of a pilot's mean: over the relevant channels (see
/// [`relative_error`]), or of `channel` alone (per-channel dispersion passes).
pub fn relative_variance(mean: DVec3, var_of_mean: DVec3, channel: Option<usize>) -> f64 {
    match channel {
        None => relative_error(mean, var_of_mean).powi(2),
        Some(c) if mean[c] > 0.0 => var_of_mean[c].max(0.0) / (mean[c] * mean[c]),
        Some(_) => 0.0,
    }
}

/// What the noise target measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measure {
    /// The relative standard error of the pixel's mean ([`relative_variance`]).
    Relative,
    /// The render's noise against the sensor's at the exposure `electrons_per_radiance`
    /// (e⁻ per W/(m²·sr) per channel): `k_c² var_c / (k_c L_c + σ_r²)` is the squared ratio of
    /// the render's noise to the sensor's shot and read noise, in electrons. A channel at or
    /// above the full well clips, so its noise does not matter.
    Sensor {
        electrons_per_radiance: [f64; 3],
        read_noise: f64,
        full_well: f64,
    },
}

impl Measure {
    /// The squared measure of a mean `mean` whose variance is `var_of_mean`: the largest over
    /// the channels (see [`relative_variance`] for which count), or of `channel` alone.
    pub fn squared(&self, mean: DVec3, var_of_mean: DVec3, channel: Option<usize>) -> f64 {
        match *self {
            Measure::Relative => relative_variance(mean, var_of_mean, channel),
            Measure::Sensor {
                electrons_per_radiance: k,
                read_noise,
                full_well,
            } => {
                let q = |c: usize| {
                    let mu = k[c] * mean[c].max(0.0);
                    let v = k[c] * k[c] * var_of_mean[c].max(0.0);
                    if !(mu < full_well) || !v.is_finite() {
                        0.0
                    } else {
                        v / (mu + read_noise * read_noise).max(f64::MIN_POSITIVE)
                    }
                };
                match channel {
                    Some(c) => q(c),
                    None => (0..3).map(q).fold(0.0, f64::max),
                }
            }
        }
    }
}

/// Fresh samples after a pilot of `pilot` samples whose mean has the squared relative error
/// `rv`, to reach a relative standard error `target`: `⌈pilot × rv / target²⌉` in
/// `[pilot, max]`.
pub fn count(rv: f64, pilot: u32, target: f64, max: u32) -> u32 {
    let want = pilot as f64 * rv / (target * target);
    let hi = max.max(pilot);
    if want.is_finite() {
        (want.ceil().max(0.0) as u64).clamp(pilot as u64, hi as u64) as u32
    } else {
        hi
    }
}

/// Every pixel's fresh samples (per pass) from the pilots' squared relative errors `rv`
/// (`w × h`, row-major). A pilot of a few samples underestimates a heavy-tailed variance
/// more often than not (the rare bright path is missing), so each pixel uses the mean of
/// [`POOL`]×[`POOL`] pilots around it: nine times the samples for the estimate.
pub fn plan(
    w: usize,
    h: usize,
    rv: &[[f64; 3]],
    pilot: u32,
    target: f64,
    max: u32,
) -> Vec<[u32; 3]> {
    let half = (POOL / 2) as isize;
    (0..h * w)
        .map(|p| {
            let (i, j) = ((p % w) as isize, (p / w) as isize);
            let mut out = [0u32; 3];
            for (k, o) in out.iter_mut().enumerate() {
                let (mut sum, mut n) = (0.0, 0.0);
                for dj in -half..=half {
                    for di in -half..=half {
                        let (x, y) = (i + di, j + dj);
                        if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                            sum += rv[y as usize * w + x as usize][k];
                            n += 1.0;
                        }
                    }
                }
                *o = count(sum / n, pilot, target, max);
            }
            out
        })
        .collect()
}

/// Side of the square of pilots pooled per pixel.
pub const POOL: usize = 3;

/// Percentiles of a distribution (nearest rank).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Spread {
    pub mean: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

impl Spread {
    fn of(mut v: Vec<f64>) -> Spread {
        if v.is_empty() {
            return Spread {
                mean: 0.0,
                median: 0.0,
                p95: 0.0,
                max: 0.0,
            };
        }
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
        Spread {
            mean: v.iter().sum::<f64>() / v.len() as f64,
            median: at(0.5),
            p95: at(0.95),
            max: v[v.len() - 1],
        }
    }
}

/// What one image's adaptive sampling did: `<image>.noise.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Report {
    pub format: &'static str,
    /// `"relative standard error"` of a pixel's mean, or `"render noise / sensor noise"`
    /// (`render.noise = "sensor"`).
    pub measure: &'static str,
    /// The target of that measure.
    pub target: f64,
    /// With `"sensor"`: the sensor's electrons per unit radiance per channel at the exposure
    /// picked for the pilot image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub electrons_per_radiance: Option<[f64; 3]>,
    /// Samples of every pixel's pilot (dropped from the image).
    pub pilot_samples: u32,
    /// The most samples a pixel may take after its pilot.
    pub max_samples: u32,
    /// Samples each pixel took after its pilot.
    pub samples: Spread,
    /// The measure achieved per pixel (largest over its relevant channels, as the image's own
    /// samples estimate it); dark pixels count as 0.
    pub achieved: Spread,
    /// Share of pixels whose achieved error is at most the target.
    pub share_at_target: f64,
    /// Share of pixels that hit `max_samples` (their noise may stay above the target).
    pub share_capped: f64,
}

impl Report {
    /// From each pixel's (samples after the pilot, achieved relative error).
    pub fn new(
        target: f64,
        pilot: u32,
        max: u32,
        measure: &Measure,
        per_pixel: &[(u32, f32)],
    ) -> Report {
        let n = per_pixel.len().max(1) as f64;
        Report {
            format: "poser noise target 1",
            measure: match measure {
                Measure::Relative => "relative standard error",
                Measure::Sensor { .. } => "render noise / sensor noise",
            },
            target,
            electrons_per_radiance: match measure {
                Measure::Relative => None,
                Measure::Sensor {
                    electrons_per_radiance,
                    ..
                } => Some(*electrons_per_radiance),
            },
            pilot_samples: pilot,
            max_samples: max.max(pilot),
            samples: Spread::of(per_pixel.iter().map(|p| p.0 as f64).collect()),
            achieved: Spread::of(per_pixel.iter().map(|p| p.1 as f64).collect()),
            share_at_target: per_pixel.iter().filter(|p| p.1 as f64 <= target).count() as f64 / n,
            share_capped: per_pixel.iter().filter(|p| p.0 >= max.max(pilot)).count() as f64 / n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_scale_with_the_square_of_the_noise_ratio() {
        let m = DVec3::new(1.0, 1.0, 1.0);
        // Relative error 0.2 after 16 samples; target 0.05 → 16 × 16 = 256.
        let rv = relative_variance(m, DVec3::splat(0.04), None);
        assert!((rv - 0.04).abs() < 1e-12);
        assert_eq!(count(rv, 16, 0.05, 1024), 256);
        // Capped, and never below the pilot.
        assert_eq!(count(rv, 16, 0.05, 100), 100);
        assert_eq!(count(rv * 1e-6, 16, 0.05, 1024), 16);
        assert_eq!(count(f64::NAN, 16, 0.05, 1024), 1024);
        // Dark pixel: nothing to reach; a weak channel (< 5 %) does not count unless it is
        // the pass's own.
        assert_eq!(relative_variance(DVec3::ZERO, DVec3::ONE, None), 0.0);
        let weak = DVec3::new(0.01, 1.0, 1.0);
        let v = DVec3::new(1.0, 1e-6, 1e-6);
        assert!(relative_variance(weak, v, None) < 1e-5);
        assert!(relative_variance(weak, v, Some(0)) > 1.0);
        assert!(relative_error(DVec3::new(f64::NAN, 1.0, 1.0), DVec3::ZERO).is_finite());
    }

    #[test]
    fn the_sensor_measure_is_the_ratio_of_render_to_sensor_noise_in_electrons() {
        let m = Measure::Sensor {
            electrons_per_radiance: [100.0, 200.0, 50.0],
            read_noise: 3.0,
            full_well: 10_000.0,
        };
        // Green: 2 W/(m²·sr) → 400 e⁻, sensor variance 400 + 9; render σ 0.1 → 20 e⁻.
        let mean = DVec3::new(1.0, 2.0, 0.0);
        let var = DVec3::new(0.0, 0.01, 0.0);
        assert!((m.squared(mean, var, Some(1)) - 400.0 / 409.0).abs() < 1e-12);
        assert!((m.squared(mean, var, None) - 400.0 / 409.0).abs() < 1e-12);
        // A dark channel has the read noise as its floor; a clipped one does not count.
        let dark = m.squared(DVec3::ZERO, DVec3::new(0.0, 0.0, 0.01), Some(2));
        assert!((dark - 25.0 / 9.0).abs() < 1e-12);
        let clipped = m.squared(DVec3::splat(1e3), DVec3::splat(1.0), None);
        assert_eq!(clipped, 0.0);
    }

    #[test]
    fn plan_pools_the_pilots_around_each_pixel() {
        // One noisy pilot among quiet ones raises its neighbours' counts, by a ninth.
        let (w, h) = (5, 4);
        let mut rv = vec![[0.0; 3]; w * h];
        rv[2 * w + 2] = [0.09, 0.0, 0.0];
        let c = plan(w, h, &rv, 10, 0.1, 1000);
        assert_eq!(c[2 * w + 2][0], 10);
        assert_eq!(c[w + 1][0], 10);
        // 10 × (0.09 / 9) / 0.01 = 10: at the pilot; with target 0.05, 40.
        let c = plan(w, h, &rv, 10, 0.05, 1000);
        assert_eq!(c[2 * w + 2][0], 40);
        assert_eq!(c[w + 1][0], 40);
        assert_eq!(c[0][0], 10);
    }
}
