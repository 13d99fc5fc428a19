//! The camera after the lens: turns the linear radiance image a backend rendered into the 8-bit
//! file a camera writes — exposure, photon shot noise, read noise, full-well and ADC clipping,
//! white balance, tone curve, JPEG/PNG — and reports what it did (`docs/sensor.md` gives the
//! model, units and sources). The linear EXR stays the physical truth; this stage only reads it.
//!
//! | step | function | formula |
//! |---|---|---|
//! | exposure | [`expose`] | `k_c = QE_c · τ · t · A · π/(4N²) · λ_c/(h c)` e⁻ per W/(m²·sr); auto: `t` puts the metered value at `target` × full scale |
//! | white balance | [`expose`] | grey world: `g_c = min(max(m) / m_c, 8)` on channel means `m_c` of `k_c L_c` (gains ≥ 1) |
//! | shot noise | [`capture`] | `e ~ Poisson(k_c L_c)` (exact below [`POISSON_EXACT_BELOW`] e⁻, else `N(μ, μ)`) |
//! | full well, read noise, ADC | [`capture`] | `DN = round(min(e, FW)·G + N(0, σ_r²)·G + black)` clamped to `[0, 2^bits − 1]`, `G = (2^bits − 1 − black)/FW · ISO/ISO_base` |
//! | develop | [`develop`] | `x_c = g_c (DN − black)/(2^bits − 1 − black)`, clipped to [0, 1], tone curve, 8 bits |
//! | render noise | [`render_noise`] | `k_c √var_c` against `√(μ + σ_r²)` e⁻ per pixel and channel |
//!
//! Deterministic: every image row has its own SplitMix64 stream seeded from the image seed
//! ([`image_seed`]: render seed, pose, camera) and the row, so the bytes do not depend on the
//! number of threads.

pub mod exif;
pub mod files;

use crate::model::{Meter, Rgb, Sensor, SensorExposure, SensorFormat, ToneCurve, WhiteBalance};
use crate::rng::SplitMix64;
use rayon::prelude::*;
use serde::Serialize;

/// Planck constant, J·s, and the speed of light, m/s (SI 2019 exact values).
const PLANCK: f64 = 6.626_070_15e-34;
const LIGHT_SPEED: f64 = 299_792_458.0;
/// Below this mean (e⁻) shot noise is drawn from the exact Poisson law; at and above it from
/// the Gaussian of the same mean and variance (skewness 1/√μ ≤ 0.125 is all that differs).
pub const POISSON_EXACT_BELOW: f64 = 64.0;
/// Largest automatic (grey-world) white-balance gain: cameras limit their automatic range, and
/// deep water, which has lost its red, would otherwise multiply the red noise fifty-fold.
pub const GREY_WORLD_MAX_GAIN: f64 = 8.0;
/// Rec. 709 / sRGB luminance weights (IEC 61966-2-1), for average metering.
const LUMA: Rgb = [0.2126, 0.7152, 0.0722];

/// The linear RGB image the sensor takes (the media layer's one type).
pub use crate::image::Linear;

/// The exposure and white balance chosen for one image.
#[derive(Debug, Clone, Serialize)]
pub struct Exposure {
    /// `"auto"` or `"manual"`.
    pub mode: &'static str,
    /// Exposure time, s.
    pub shutter: f64,
    pub f_number: f64,
    pub iso: f64,
    /// Pixel pitch used for the photon count, m.
    pub pixel_pitch: f64,
    /// Mean electrons per unit radiance (W/(m²·sr)) per channel: `k_c`.
    pub electrons_per_radiance: Rgb,
    /// ADC conversion gain, DN per e⁻.
    pub dn_per_electron: f64,
    /// Electrons that fill the ADC range above the black level at this ISO.
    pub full_scale_electrons: f64,
    /// White-balance gains applied to the developed image.
    pub white_balance_gains: Rgb,
    /// What auto exposure did, when it could not meter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// Electrons per unit radiance and per second of exposure, per channel, for a pixel of pitch
/// `pitch` (m): `QE_c · τ · A · π/(4N²) · λ_c/(h c)` (on-axis image-plane irradiance of a
/// lens of f-number N; photons per joule at the channel wavelength).
pub fn electrons_per_radiance_second(s: &Sensor, pitch: f64) -> Rgb {
    let geom = s.transmittance * pitch * pitch * std::f64::consts::PI / (4.0 * s.f_number.powi(2));
    let mut k = [0.0; 3];
    for (c, k) in k.iter_mut().enumerate() {
        let lambda = crate::model::CHANNEL_WAVELENGTHS_NM[c] * 1e-9;
        *k = s.quantum_efficiency[c] * geom * lambda / (PLANCK * LIGHT_SPEED);
    }
    k
}

/// ADC maximum code, `2^bits − 1`.
pub fn dn_max(s: &Sensor) -> f64 {
    ((1u32 << s.bits) - 1) as f64
}

/// Conversion gain, DN per electron: the full well fills the range above the black level at
/// the base ISO; the analogue gain scales with ISO.
pub fn dn_per_electron(s: &Sensor) -> f64 {
    (dn_max(s) - s.black_level as f64) / s.full_well * s.iso / s.base_iso
}

fn finite_radiance(x: f32) -> f64 {
    if x.is_finite() && x > 0.0 {
        x as f64
    } else {
        0.0
    }
}

/// The value at fraction `p` of the sorted values (nearest rank), or `None` when empty.
pub fn percentile(mut v: Vec<f64>, p: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let n = v.len();
    let i = ((p * n as f64).ceil() as usize).clamp(1, n) - 1;
    let (_, x, _) = v.select_nth_unstable_by(i, |a, b| a.total_cmp(b));
    Some(*x)
}

/// Choose the exposure and white balance for `img` (pixels of pitch `pitch`, m).
pub fn expose(s: &Sensor, img: &Linear, pitch: f64) -> Exposure {
    let k1 = electrons_per_radiance_second(s, pitch);
    let g = dn_per_electron(s);
    let full_scale = (dn_max(s) - s.black_level as f64) / g;
    // Grey world on the expected raw signal (ratios do not depend on the shutter time).
    let wb = match s.white_balance {
        WhiteBalance::None => [1.0; 3],
        WhiteBalance::Fixed(gains) => gains,
        WhiteBalance::GreyWorld => {
            let mut m = [0.0f64; 3];
            for p in &img.rgb {
                for c in 0..3 {
                    m[c] += k1[c] * finite_radiance(p[c]);
                }
            }
            let top = m.iter().cloned().fold(0.0, f64::max);
            m.map(|mc| {
                if mc > 0.0 {
                    (top / mc).min(GREY_WORLD_MAX_GAIN)
                } else {
                    1.0
                }
            })
        }
    };
    let (mode, shutter, note) = match s.exposure {
        SensorExposure::Manual => ("manual", s.shutter, None),
        SensorExposure::Auto {
            meter,
            percentile: p,
            target,
        } => {
            let level = target * full_scale.min(s.full_well);
            let metered = match meter {
                Meter::Highlights => percentile(
                    img.rgb
                        .iter()
                        .map(|px| {
                            (0..3)
                                .map(|c| wb[c] * k1[c] * finite_radiance(px[c]))
                                .fold(0.0, f64::max)
                        })
                        .collect(),
                    p,
                ),
                Meter::Average => {
                    let n = img.rgb.len().max(1) as f64;
                    Some(
                        img.rgb
                            .iter()
                            .map(|px| {
                                (0..3)
                                    .map(|c| LUMA[c] * wb[c] * k1[c] * finite_radiance(px[c]))
                                    .sum::<f64>()
                            })
                            .sum::<f64>()
                            / n,
                    )
                }
            };
            match metered {
                Some(m) if m > 0.0 && (level / m).is_finite() => ("auto", level / m, None),
                _ => (
                    "auto",
                    s.shutter,
                    Some(
                        "the image is black where it was metered: the manual shutter was used"
                            .into(),
                    ),
                ),
            }
        }
    };
    Exposure {
        mode,
        shutter,
        f_number: s.f_number,
        iso: s.iso,
        pixel_pitch: pitch,
        electrons_per_radiance: k1.map(|k| k * shutter),
        dn_per_electron: g,
        full_scale_electrons: full_scale,
        white_balance_gains: wb,
        note,
    }
}

/// The seed of one image's sensor noise: the render seed, the rig pose and the camera.
pub fn image_seed(render_seed: u64, pose: usize, camera: usize) -> u64 {
    let mut h = SplitMix64(render_seed ^ 0x5E_4503_0A15_E000).next_u64();
    for k in [pose as u64, camera as u64] {
        h = SplitMix64(h ^ k.wrapping_mul(0x9E37_79B9_7F4A_7C15)).next_u64();
    }
    h
}

/// Gaussian and Poisson variates from one SplitMix64 stream.
pub struct Noise {
    stream: SplitMix64,
    spare: Option<f64>,
}

impl Noise {
    pub fn new(seed: u64, row: u64) -> Noise {
        let s = SplitMix64(seed ^ row.wrapping_mul(0xD1B5_4A32_D192_ED03)).next_u64();
        Noise {
            stream: SplitMix64(s),
            spare: None,
        }
    }

    /// Standard normal (Box–Muller, both values used).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (z, spare) = self.stream.normal_pair();
        self.spare = Some(spare);
        z
    }

    /// A Poisson count of mean `mu` (exact below [`POISSON_EXACT_BELOW`], Gaussian above).
    pub fn poisson(&mut self, mu: f64) -> f64 {
        if mu.is_nan() || mu <= 0.0 {
            return 0.0;
        }
        if mu < POISSON_EXACT_BELOW {
            // Knuth: multiply uniforms until the product drops below e^-μ.
            let l = (-mu).exp();
            let mut k = 0.0;
            let mut p = self.stream.next_f64();
            while p > l {
                k += 1.0;
                p *= self.stream.next_f64();
            }
            k
        } else {
            (mu + mu.sqrt() * self.normal()).max(0.0)
        }
    }
}

/// The raw frame: ADC codes per pixel and channel, and what clipped.
#[derive(Debug, Clone)]
pub struct Raw {
    pub width: u32,
    pub height: u32,
    pub dn: Vec<[u16; 3]>,
    /// Share of pixels with a channel at full well or at the ADC's maximum code.
    pub clipped_fraction: f64,
}

/// Expose the sensor to `img` for `e` and digitise (shot noise, full well, read noise, ADC),
/// with the noise of image seed `seed`.
pub fn capture(s: &Sensor, e: &Exposure, img: &Linear, seed: u64) -> Raw {
    let (w, h) = (img.width as usize, img.height as usize);
    let top = dn_max(s);
    let black = s.black_level as f64;
    let g = e.dn_per_electron;
    let rows: Vec<(Vec<[u16; 3]>, usize)> = (0..h)
        .into_par_iter()
        .map(|j| {
            let mut noise = Noise::new(seed, j as u64);
            let mut clipped = 0;
            let row = (0..w)
                .map(|i| {
                    let px = img.rgb[j * w + i];
                    let mut out = [0u16; 3];
                    let mut clip = false;
                    for c in 0..3 {
                        let mu = e.electrons_per_radiance[c] * finite_radiance(px[c]);
                        let mut el = if s.noise { noise.poisson(mu) } else { mu };
                        if el >= s.full_well {
                            el = s.full_well;
                            clip = true;
                        }
                        if s.noise && s.read_noise > 0.0 {
                            el += s.read_noise * noise.normal();
                        }
                        let dn = (el * g + black).round();
                        if dn >= top {
                            clip = true;
                        }
                        out[c] = dn.clamp(0.0, top) as u16;
                    }
                    clipped += clip as usize;
                    out
                })
                .collect();
            (row, clipped)
        })
        .collect();
    let mut dn = Vec::with_capacity(w * h);
    let mut clipped = 0;
    for (r, c) in rows {
        dn.extend(r);
        clipped += c;
    }
    Raw {
        width: img.width,
        height: img.height,
        dn,
        clipped_fraction: clipped as f64 / (w * h).max(1) as f64,
    }
}

/// The tone curve from linear [0, 1] to the encoded [0, 1].
pub fn tone(curve: ToneCurve, x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    match curve {
        ToneCurve::Linear => x,
        ToneCurve::Gamma(g) => x.powf(1.0 / g),
        ToneCurve::Srgb => {
            if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            }
        }
    }
}

/// Develop a raw frame: black level, white balance, clip, tone curve, 8 bits (RGB8, rows).
pub fn develop(s: &Sensor, e: &Exposure, raw: &Raw) -> Vec<u8> {
    let black = s.black_level as f64;
    let range = dn_max(s) - black;
    let wb = e.white_balance_gains;
    // One table per channel: every raw code maps to one 8-bit value.
    let lut: Vec<Vec<u8>> = (0..3)
        .map(|c| {
            (0..=dn_max(s) as u32)
                .map(|dn| {
                    let x = wb[c] * (dn as f64 - black).max(0.0) / range;
                    (tone(s.tone, x) * 255.0).round().clamp(0.0, 255.0) as u8
                })
                .collect()
        })
        .collect();
    raw.dn
        .iter()
        .flat_map(|p| [0, 1, 2].map(|c| lut[c][p[c] as usize]))
        .collect()
}

/// Encode 8-bit RGB as the sensor's file format, with `exif` (an [`exif::block`], or empty for
/// none) as the JPEG's APP1 `Exif` segment or the PNG's `eXIf` chunk.
pub fn encode(
    s: &Sensor,
    width: u32,
    height: u32,
    rgb8: &[u8],
    exif: &[u8],
) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    fn write(
        mut enc: impl ImageEncoder,
        exif: &[u8],
        rgb8: &[u8],
        (width, height): (u32, u32),
    ) -> image::ImageResult<()> {
        if !exif.is_empty() {
            enc.set_exif_metadata(exif.to_vec())
                .map_err(image::ImageError::Unsupported)?;
        }
        enc.write_image(rgb8, width, height, image::ExtendedColorType::Rgb8)
    }
    let mut out = Vec::new();
    match s.format {
        SensorFormat::Jpeg(q) => write(
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, q),
            exif,
            rgb8,
            (width, height),
        )
        .map_err(|e| format!("JPEG encoding: {e}"))?,
        SensorFormat::Png => write(
            image::codecs::png::PngEncoder::new(&mut out),
            exif,
            rgb8,
            (width, height),
        )
        .map_err(|e| format!("PNG encoding: {e}"))?,
    }
    Ok(out)
}

/// File extension of the sensor's format.
pub fn extension(s: &Sensor) -> &'static str {
    match s.format {
        SensorFormat::Jpeg(_) => "jpg",
        SensorFormat::Png => "png",
    }
}

/// Render (Monte Carlo) noise against the sensor's own noise, over every pixel and channel
/// with signal below the full well.
#[derive(Debug, Clone, Serialize)]
pub struct RenderNoise {
    /// Pixel-channel values compared.
    pub count: usize,
    /// Relative standard error of the rendered radiance, `√var / L`: median and 95th
    /// percentile.
    pub relative_median: f64,
    pub relative_p95: f64,
    /// Render noise in electrons at this exposure, `k √var`: median and 95th percentile.
    pub electrons_median: f64,
    pub electrons_p95: f64,
    /// The sensor's own temporal noise `√(μ + σ_read²)`, e⁻, and relative to the signal:
    /// medians.
    pub sensor_electrons_median: f64,
    pub sensor_relative_median: f64,
    /// Render noise / sensor noise per pixel and channel: median and 95th percentile.
    pub ratio_median: f64,
    pub ratio_p95: f64,
    /// `√(Σ render variance / Σ sensor variance)` in electrons over the same values: unbiased
    /// where the median is not (with few samples, path-tracing noise is heavy-tailed and most
    /// pixels have not yet met their rare bright paths, so the median ratio reads low).
    pub ratio_rms: f64,
    /// Samples per pixel for the larger of the median and RMS ratios to reach 1 (variance falls as 1/spp), when
    /// the samples used are known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples_needed: Option<u64>,
}

/// Compare the render's per-pixel variance of the mean (`variance`, same layout as `img`)
/// with the sensor noise at exposure `e`. `samples`: samples per pixel of the render.
pub fn render_noise(
    s: &Sensor,
    e: &Exposure,
    img: &Linear,
    variance: &[[f32; 3]],
    samples: Option<u32>,
) -> Option<RenderNoise> {
    let (mut rel, mut el, mut sen, mut senrel, mut ratio) =
        (vec![], vec![], vec![], vec![], vec![]);
    let (mut sum_r, mut sum_s) = (0.0, 0.0);
    for (px, var) in img.rgb.iter().zip(variance) {
        for c in 0..3 {
            let l = finite_radiance(px[c]);
            let v = if var[c].is_finite() {
                var[c].max(0.0) as f64
            } else {
                continue;
            };
            let k = e.electrons_per_radiance[c];
            let mu = k * l;
            if mu.is_nan() || mu <= 0.0 || mu >= s.full_well {
                continue;
            }
            let sigma_s = (mu + s.read_noise * s.read_noise).sqrt();
            let sigma_r = k * v.sqrt();
            rel.push(v.sqrt() / l);
            el.push(sigma_r);
            sen.push(sigma_s);
            senrel.push(sigma_s / mu);
            ratio.push(sigma_r / sigma_s);
            sum_r += sigma_r * sigma_r;
            sum_s += sigma_s * sigma_s;
        }
    }
    let count = rel.len();
    let ratio_median = percentile(ratio.clone(), 0.5)?;
    let ratio_rms = (sum_r / sum_s).sqrt();
    let worst = ratio_median.max(ratio_rms);
    Some(RenderNoise {
        count,
        relative_median: percentile(rel.clone(), 0.5)?,
        relative_p95: percentile(rel, 0.95)?,
        electrons_median: percentile(el.clone(), 0.5)?,
        electrons_p95: percentile(el, 0.95)?,
        sensor_electrons_median: percentile(sen, 0.5)?,
        sensor_relative_median: percentile(senrel, 0.5)?,
        ratio_median,
        ratio_p95: percentile(ratio, 0.95)?,
        ratio_rms,
        samples_needed: samples.map(|n| (n as f64 * (worst * worst).max(1.0)).ceil() as u64),
    })
}
