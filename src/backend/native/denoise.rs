//! The illumination denoiser (`render.denoise = "illumination"`): an explicit, optional filter
//! of the native render that keeps the texture and smooths the light.
//!
//! | step | what |
//! |---|---|
//! | demodulate | `A`: the mean first-hit albedo of each pixel's samples; the light on a pixel is estimated as a ratio, `E'_p = Σ_q w_pq L_q / Σ_q w_pq A_q` (pixels whose albedo is under [`MIN_ALBEDO`] in a channel, or that see only water, are filtered as radiance, `A = 1`) |
//! | weights | `w = exp(−d²/2σ²) · exp(−(Δz / z_p)² / 2τ²)`, `d` in pixels, `z` the pixel's depth, `τ` = [`DEPTH_TOLERANCE`]; only pixels of the same kind (surface or water) mix |
//! | remodulate | `L'_p = A_p E'_p` |
//! | noise | `var'_p = A_p² Σ_q w_pq² var_q / (Σ_q w_pq A_q)²` (the samples of different pixels are independent) |
//!
//! The ratio form (rather than averaging `L_q / A_q`) keeps a dark pixel's noise from being
//! multiplied by its bright neighbours' albedo: at the edge of a black target print a firefly
//! would otherwise be copied onto the white around it, 18× brighter.
//!
//! What it changes: the Monte Carlo noise of the light falls by about `1/(2√π σ)` (a Gaussian
//! of σ pixels averages about `4πσ²` of them); the albedo (the texture SIFT matches) is kept at
//! full resolution; shadow edges, caustics and the light's gradients are blurred by about σ;
//! light that does not scale with the albedo (backscatter in front of a surface) is smoothed
//! and redistributed by the albedo of each pixel. The `.exr` stays the unfiltered render.

/// Albedo below which a channel is not demodulated (its light is filtered as radiance).
pub const MIN_ALBEDO: f64 = 0.01;
/// Relative depth difference at which neighbours stop sharing light (σ of the range weight).
pub const DEPTH_TOLERANCE: f64 = 0.02;

/// Filter `rgb` (and its per-pixel `variance`) with the first-hit `albedo` and the camera-frame
/// `depth` (0: no surface) as guides; `sigma` in pixels. Returns the filtered image and its
/// variance.
pub fn illumination(
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    variance: &[[f32; 3]],
    albedo: &[[f32; 3]],
    depth: &[f32],
    sigma: f64,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    use rayon::prelude::*;
    let radius = (2.5 * sigma).ceil().max(1.0) as i64;
    let (w, h) = (width as i64, height as i64);
    let two_s2 = 2.0 * sigma * sigma;
    let two_t2 = 2.0 * DEPTH_TOLERANCE * DEPTH_TOLERANCE;
    // Per pixel and channel: the demodulation factor (1 for radiance-filtered channels).
    let factor = |i: usize, c: usize| -> f64 {
        let a = albedo[i][c] as f64;
        if depth[i] > 0.0 && a >= MIN_ALBEDO {
            a
        } else {
            1.0
        }
    };
    let kind = |i: usize, c: usize| -> bool { depth[i] > 0.0 && albedo[i][c] as f64 >= MIN_ALBEDO };
    type Rows = Vec<(Vec<[f32; 3]>, Vec<[f32; 3]>)>;
    // The spatial weights, once: the same `exp` of the same argument as per pair, so the
    // same bits; the range weight is computed once per pair and shared by the channels.
    let side = (2 * radius + 1) as usize;
    let spatial: Vec<f64> = (-radius..=radius)
        .flat_map(|dy| (-radius..=radius).map(move |dx| (dy, dx)))
        .map(|(dy, dx)| (-((dx * dx + dy * dy) as f64) / two_s2).exp())
        .collect();
    let rows: Rows = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut out = Vec::with_capacity(width);
            let mut var = Vec::with_capacity(width);
            for x in 0..w {
                let p = (y * w + x) as usize;
                let zp = depth[p] as f64;
                let kp = [kind(p, 0), kind(p, 1), kind(p, 2)];
                // Per channel: Σ w A, Σ w² var, Σ w L.
                let mut acc = [[0.0f64; 3]; 3];
                for dy in -radius..=radius {
                    let qy = y + dy;
                    if qy < 0 || qy >= h {
                        continue;
                    }
                    let row = (dy + radius) as usize * side;
                    for dx in -radius..=radius {
                        let qx = x + dx;
                        if qx < 0 || qx >= w {
                            continue;
                        }
                        let q = (qy * w + qx) as usize;
                        let ws = spatial[row + (dx + radius) as usize];
                        let mut range = None;
                        for c in 0..3 {
                            if kind(q, c) != kp[c] {
                                continue;
                            }
                            let mut wt = ws;
                            if kp[c] {
                                wt *= *range.get_or_insert_with(|| {
                                    let rel = (depth[q] as f64 - zp) / zp;
                                    (-(rel * rel) / two_t2).exp()
                                });
                            }
                            let [sa, sw2v, se] = &mut acc[c];
                            *se += wt * rgb[q][c] as f64;
                            *sw2v += wt * wt * variance[q][c] as f64;
                            *sa += wt * factor(q, c);
                        }
                    }
                }
                let mut o = [0f32; 3];
                let mut v = [0f32; 3];
                for c in 0..3 {
                    let [sa, sw2v, se] = acc[c];
                    let fp = factor(p, c);
                    // sa ≥ factor(p, c) > 0: the pixel itself always counts.
                    o[c] = (fp * se / sa) as f32;
                    v[c] = (fp * fp * sw2v / (sa * sa)) as f32;
                }
                out.push(o);
                var.push(v);
            }
            (out, var)
        })
        .collect();
    let mut rgb_out = Vec::with_capacity(width * height);
    let mut var_out = Vec::with_capacity(width * height);
    for (o, v) in rows {
        rgb_out.extend(o);
        var_out.extend(v);
    }
    (rgb_out, var_out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// A checker albedo (2-pixel squares) under a smooth light with 40 % noise: the filtered
    /// image keeps the checker (every pixel within 5 predicted σ of albedo × light), its noise
    /// falls to the predicted variance (about 6 %), and a depth step keeps the two sides'
    /// light apart.
    #[test]
    fn keeps_texture_and_cuts_noise() {
        let (w, h) = (64usize, 48usize);
        let mut rng = SplitMix64(3);
        let mut rgb = Vec::new();
        let mut var = Vec::new();
        let mut alb = Vec::new();
        let mut depth = Vec::new();
        let mut truth = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let a = if (x / 2 + y / 2) % 2 == 0 { 0.8 } else { 0.2 };
                // Light: smooth across the image, and a step at x = 32 where depth jumps.
                let light = if x < 32 { 1.0 + 0.005 * y as f64 } else { 3.0 };
                let z = if x < 32 { 2.0 } else { 1.0 };
                let t = a * light;
                let sd = 0.4 * t;
                let n = rng.normal_pair().0;
                rgb.push([(t + sd * n) as f32; 3]);
                var.push([(sd * sd) as f32; 3]);
                alb.push([a as f32; 3]);
                depth.push(z as f32);
                truth.push(t);
            }
        }
        let (out, v) = illumination(w, h, &rgb, &var, &alb, &depth, 2.0);
        let mut err2 = 0.0;
        let mut pred = 0.0;
        let mut n = 0.0;
        for y in 4..h - 4 {
            for x in 4..w - 4 {
                if (28..36).contains(&x) {
                    continue;
                }
                let i = y * w + x;
                let e = out[i][1] as f64 / truth[i] - 1.0;
                let sd = (v[i][1] as f64).sqrt() / truth[i];
                assert!(
                    e.abs() < 5.0 * sd,
                    "({x}, {y}): {} vs {}",
                    out[i][1],
                    truth[i]
                );
                err2 += e * e;
                pred += v[i][1] as f64 / (truth[i] * truth[i]);
                n += 1.0;
            }
        }
        let (rms, rms_pred) = ((err2 / n).sqrt(), (pred / n).sqrt());
        // 4πσ² ≈ 50 pixels averaged: 40 % → about 5.6 %.
        assert!(rms < 0.08, "{rms}");
        assert!(
            (rms / rms_pred - 1.0).abs() < 0.25,
            "{rms} vs predicted {rms_pred}"
        );
        // Beside the depth step the far side's light (3.0) does not leak in.
        let i = 20 * w + 31;
        let sd = (v[i][1] as f64).sqrt() / truth[i];
        assert!((out[i][1] as f64 / truth[i] - 1.0).abs() < 5.0 * sd);
        assert!(sd < 0.12, "{sd}");
    }
}
