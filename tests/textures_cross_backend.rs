//! Baked textures look the same in every backend (issue 21): `tests/textures/seabed.toml` — a
//! sand-textured seabed heightfield, rock-textured boulders (triplanar charts, per-boulder
//! colour variation) and a coral-encrusted plane in water under the sun, 160×120, nadir through
//! a flat port — rendered by the native renderer, Mitsuba and Cycles.
//!
//! Checks, against the native image:
//! * image means per channel within [`MAX_MEAN_REL`] (the 2 %);
//! * the texture's spatial spectrum: the radially averaged power spectrum of the green channel
//!   (Hann window, mean removed) in octave bands from 1/64 to 1/2 cycle per pixel; each band's
//!   power within a factor [`MAX_BAND_RATIO`] of native's. Texture misplacement (a flipped or
//!   shifted V, another texel centre convention, nearest instead of bilinear filtering) changes
//!   the fine bands by far more. Monte Carlo noise adds power to the fine bands (Mitsuba's
//!   reflect-or-refract choice at the port's glass faces makes it the noisiest), so every
//!   backend renders twice with two seeds and its noise power, measured from the difference,
//!   is subtracted.
//! * the pixel-wise correlation of the green channels (each image's noise variance removed)
//!   ≥ [`MIN_CORRELATION`]: the same texture in the same place, not just the same statistics.

use poser::backend::RenderOptions;
use poser::compare::LinearImage;
use poser::model::Model;
use std::path::{Path, PathBuf};

/// The bound on image means.
const MAX_MEAN_REL: f64 = 0.02;
/// Bound on each octave band's texture power ratio to native's. Measured (128 spp × 2 seeds):
/// Mitsuba 0.977–1.012, Cycles 0.998–1.002.
const MAX_BAND_RATIO: f64 = 1.10;
/// Bound on the noise-corrected correlation of the green channels with native's. Measured
/// uncorrected: Cycles 0.9997, Mitsuba 0.9456 (its port-glass noise).
const MIN_CORRELATION: f64 = 0.95;

fn load() -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/textures/seabed.toml");
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

fn render(backend: &str, model: &Model, dir: &Path, samples: u32) -> LinearImage {
    let opts = RenderOptions {
        samples: Some(samples),
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::Backend::parse(backend)
        .and_then(|b| b.render(model, dir, &opts))
        .unwrap_or_else(|e| panic!("{backend}: {e}"));
    LinearImage::read(&dir.join(format!("{}.exr", model.image_name(0, 0)))).unwrap()
}

/// Discrete Fourier transform of a real row-major image, separable (rows, then columns);
/// returns |F|² per frequency (kx, ky) row-major.
fn power_spectrum(img: &[f64], w: usize, h: usize) -> Vec<f64> {
    let dft = |input: &[(f64, f64)], n: usize| -> Vec<(f64, f64)> {
        (0..n)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (i, &(a, b)) in input.iter().enumerate() {
                    let t = -std::f64::consts::TAU * ((k * i) % n) as f64 / n as f64;
                    let (s, c) = t.sin_cos();
                    re += a * c - b * s;
                    im += a * s + b * c;
                }
                (re, im)
            })
            .collect()
    };
    let mut rows = Vec::with_capacity(w * h);
    for y in 0..h {
        let r: Vec<(f64, f64)> = (0..w).map(|x| (img[y * w + x], 0.0)).collect();
        rows.extend(dft(&r, w));
    }
    let mut out = vec![0.0; w * h];
    for x in 0..w {
        let col: Vec<(f64, f64)> = (0..h).map(|y| rows[y * w + x]).collect();
        for (y, (re, im)) in dft(&col, h).into_iter().enumerate() {
            out[y * w + x] = re * re + im * im;
        }
    }
    out
}

/// Octave bands of radial frequency (cycles per pixel): [2^-(k+1), 2^-k) for k = 6 … 1.
const BANDS: usize = 6;

fn band_powers(img: &LinearImage) -> [f64; BANDS] {
    let (w, h) = (img.width, img.height);
    let g: Vec<f64> = img.rgb.iter().map(|p| p[1] as f64).collect();
    let mean = g.iter().sum::<f64>() / g.len() as f64;
    let hann = |i: usize, n: usize| {
        0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / n as f64).cos()
    };
    let win: Vec<f64> = (0..w * h)
        .map(|k| (g[k] - mean) * hann(k % w, w) * hann(k / w, h))
        .collect();
    let p = power_spectrum(&win, w, h);
    let mut bands = [0.0; BANDS];
    let mut counts = [0usize; BANDS];
    for ky in 0..h {
        for kx in 0..w {
            let fx = (if kx <= w / 2 { kx } else { w - kx }) as f64 / w as f64;
            let fy = (if ky <= h / 2 { ky } else { h - ky }) as f64 / h as f64;
            let f = fx.hypot(fy);
            if !(1.0 / 128.0..0.5).contains(&f) {
                continue;
            }
            let b = ((-f.log2()).floor() as usize - 1).min(BANDS - 1);
            bands[BANDS - 1 - b] += p[ky * w + kx];
            counts[BANDS - 1 - b] += 1;
        }
    }
    std::array::from_fn(|i| bands[i] / counts[i].max(1) as f64)
}

/// Correlation of the green channels, with each image's noise variance removed from its
/// variance (the correlation the noise-free images would have).
fn correlation(a: &LinearImage, b: &LinearImage, noise_a: f64, noise_b: f64) -> f64 {
    let ga: Vec<f64> = a.rgb.iter().map(|p| p[1] as f64).collect();
    let gb: Vec<f64> = b.rgb.iter().map(|p| p[1] as f64).collect();
    let n = ga.len() as f64;
    let (ma, mb) = (ga.iter().sum::<f64>() / n, gb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in ga.iter().zip(&gb) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    let n = n.max(1.0);
    (sab / n) / ((saa / n - noise_a) * (sbb / n - noise_b)).sqrt()
}

/// Renders of one backend with two seeds: their mean, and the spectrum of their Monte Carlo
/// noise (the difference of two independent renders has twice a render's noise power, the mean
/// half of it: noise of the mean = P(a − b) / 4).
struct Measured {
    mean_img: LinearImage,
    bands: [f64; BANDS],
    noise: [f64; BANDS],
    /// Variance of the green channel's Monte Carlo noise in `mean_img`.
    noise_var: f64,
}

fn measure(backend: &str, model: &Model, dir: &Path, samples: u32) -> Measured {
    let a = render(backend, model, &dir.join("a"), samples);
    let mut m2 = model.clone();
    m2.render.seed = model.render.seed.wrapping_add(1000);
    let b = render(backend, &m2, &dir.join("b"), samples);
    let combine = |f: &dyn Fn(f32, f32) -> f32| LinearImage {
        width: a.width,
        height: a.height,
        rgb: a
            .rgb
            .iter()
            .zip(&b.rgb)
            .map(|(p, q)| [0, 1, 2].map(|c| f(p[c], q[c])))
            .collect(),
    };
    let mean_img = combine(&|x, y| 0.5 * (x + y));
    let diff = combine(&|x, y| x - y);
    let noise = band_powers(&diff).map(|p| p / 4.0);
    let bands = band_powers(&mean_img);
    let g: Vec<f64> = diff.rgb.iter().map(|p| p[1] as f64).collect();
    let gm = g.iter().sum::<f64>() / g.len() as f64;
    let noise_var = g.iter().map(|x| (x - gm) * (x - gm)).sum::<f64>() / g.len() as f64 / 4.0;
    Measured {
        mean_img,
        bands,
        noise,
        noise_var,
    }
}

#[test]
fn textures_agree_across_backends() {
    let model = load();
    let tmp = tempfile::tempdir().unwrap();
    let native = measure("native", &model, &tmp.path().join("native"), 128);
    let reference_mean = native.mean_img.mean();
    eprintln!(
        "native: mean {reference_mean:.4?}, bands {:?}, noise {:?}",
        native.bands, native.noise
    );
    let mut failures = Vec::new();
    for backend in ["mitsuba", "blender"] {
        let m = measure(backend, &model, &tmp.path().join(backend), 128);
        let mean = m.mean_img.mean();
        for c in 0..3 {
            let rel = mean[c] / reference_mean[c] - 1.0;
            eprintln!("{backend}: mean channel {c} / native − 1 = {rel:+.4}");
            if rel.abs() > MAX_MEAN_REL {
                failures.push(format!("{backend} channel {c} mean {rel:+.4}"));
            }
        }
        for k in 0..BANDS {
            // Texture power: the band's power less the backend's own noise power.
            let ratio = (m.bands[k] - m.noise[k]) / (native.bands[k] - native.noise[k]);
            eprintln!(
                "{backend}: band [{:.4}, {:.4}) cycles/px texture power / native = {ratio:.3} \
                 (noise / texture: {:.3})",
                0.5f64.powi((BANDS - k) as i32 + 1),
                0.5f64.powi((BANDS - k) as i32),
                m.noise[k] / (m.bands[k] - m.noise[k])
            );
            if !(1.0 / MAX_BAND_RATIO..=MAX_BAND_RATIO).contains(&ratio) {
                failures.push(format!("{backend} band {k}: ratio {ratio:.3}"));
            }
        }
        let r = correlation(&native.mean_img, &m.mean_img, native.noise_var, m.noise_var);
        eprintln!("{backend}: correlation of green with native (noise removed) = {r:.4}");
        if r < MIN_CORRELATION {
            failures.push(format!("{backend} correlation {r:.4}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
