//! Caustics from a wavy sea surface: the sun's irradiance in the water relative to a flat
//! surface, precomputed once per render as a "caustic volume" and applied as a factor on the
//! sun's next-event estimate ([`super::integrator`]).
//!
//! | item | value | meaning |
//! |---|---|---|
//! | surface | [`crate::optics::waves::WaveField`] | periodic (period `P = 4·λp`), seeded with `site.seed` |
//! | [`CELLS`] | 512 | histogram cells per period side (cell = `P/512`, 7.8 cm for λp = 10 m) |
//! | [`RAYS_PER_CELL_SIDE`] | 2 | sun rays per cell side (4 per cell, 1 048 576 rays per volume) |
//! | [`PLANES`] | 32 | horizontal planes from just below the lowest trough to below the deepest geometry |
//! | [`KERNEL_SIGMA_CELLS`] | 0.75 | std of the Gaussian smoothing kernel, cells (after a bilinear splat) |
//! | [`SUN_ANGULAR_RADIUS`] | 4.65 mrad | the sun's disk, as a depth-growing Gaussian blur (σ = depth·θw/(2 cos θw)) |
//! | cost | 1.6–3.1 s, 32 MiB (≈ 150 MiB peak) | measured (`build_seconds`) on 2 cores at load ≈ 7; see README |
//!
//! Method: a regular grid of sun rays (f64) is traced through the surface parametrised by its
//! horizontal coordinates: the ray at `(x, y)` enters at `(x, y, h(x, y))`, carries the flux
//! `E·(−d·N)·dx·dy` (`N = (−hx, −hy, 1)`, the unnormalised normal: the beam's projected area,
//! shadowing of one wave by another ignored), is refracted by vector Snell at the local normal
//! and weighted by the unpolarised Fresnel transmittance (index of the green channel). Where
//! it crosses each plane it is splatted bilinearly into a periodic 2-D histogram, which is then
//! blurred by a Gaussian (kernel + sun disk) with wrap-around. Each cell is divided by the flat
//! surface's horizontal irradiance `E·T_flat·cos θa`, so the factor is the irradiance relative
//! to the flat-surface `irradiance_water`: its mean over a plane is exactly
//! `mean(T·(−d·N))/(T_flat·cos θa)`, i.e. 1 up to the Fresnel difference (periodic surface:
//! the gradients average to 0). Between planes the factor is interpolated linearly in z and
//! bilinearly in x, y; above the top plane it blends to 1 at z = 0; below the last plane it is
//! the last plane's.
//!
//! Approximations (stated on purpose):
//! * A density estimate: biased (blurred by the kernel, [`KERNEL_SIGMA_CELLS`]) but
//!   consistent (the bias vanishes as `CELLS` and the ray count grow).
//! * The sun's *direction* in the water stays the flat-surface refracted direction; only its
//!   irradiance is modulated. Shadow rays and the water path length use that direction.
//! * One factor for all three channels (the caustic's dispersion is ignored); the surface is
//!   frozen (the same for every pose); the light is traced through geometry-free water (objects
//!   shadow it through the usual shadow ray, not through the volume).
//!
//! Deterministic: a regular ray grid, the seeded surface, per-plane accumulation in a fixed
//! order (planes in parallel, each by one thread); no NaN (rays with a non-finite or
//! non-positive weight are skipped).

// `!(x > y)` is deliberate: it rejects NaN as well as the failing comparison.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::model::{Model, SeaSurface};
use crate::optics::interface::{fresnel_transmittance, refract};
use crate::optics::waves::{WIND_DIRECTION, WaveField};
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

/// Histogram cells per period side.
pub const CELLS: usize = 512;
// Wrapping by bit mask in the splat needs a power of two.
const _: () = assert!(CELLS.is_power_of_two());

/// Sun rays per histogram cell side.
pub const RAYS_PER_CELL_SIDE: usize = 2;
/// Number of horizontal planes.
pub const PLANES: usize = 32;
/// Standard deviation of the smoothing kernel, in cells.
pub const KERNEL_SIGMA_CELLS: f64 = 0.75;
/// Angular radius of the sun seen from the ground, rad.
pub const SUN_ANGULAR_RADIUS: f64 = 4.65e-3;

/// The sun's irradiance below a wavy surface relative to a flat one, on a stack of planes.
#[derive(Debug, Clone)]
pub struct CausticVolume {
    period: f64,
    cells: usize,
    /// Plane heights (descending: `z[0]` is the top plane).
    z: Vec<f64>,
    /// Plane-major, row-major (y rows, x columns) factors.
    data: Vec<f32>,
    /// Wall-clock time of the precomputation, s (not part of any output).
    pub build_seconds: f64,
}

impl CausticVolume {
    /// The volume for a model whose sun shines through `site.surface = "waves"` into water,
    /// with planes down to `z_bottom`; `None` when there is nothing to do.
    pub fn for_model(model: &Model, z_bottom: f64) -> Option<CausticVolume> {
        let water = model.water.as_ref()?;
        let sun = model.sun.as_ref()?;
        let SeaSurface::Waves {
            height,
            wavelength,
            wind_speed,
        } = model.site.surface
        else {
            return None;
        };
        if !(sun.direction_air.z < 0.0) {
            return None;
        }
        let field = WaveField::new(
            height,
            wavelength,
            wind_speed,
            WIND_DIRECTION,
            model.site.seed,
        );
        Some(CausticVolume::build(
            &field,
            sun.direction_air,
            water.ior[1],
            z_bottom,
        ))
    }

    /// Trace the sun (propagating along `dir_air`, z < 0) through `field` into water of index
    /// `n_water` and bin the irradiance on planes from below the lowest trough to `z_bottom`.
    pub fn build(field: &WaveField, dir_air: DVec3, n_water: f64, z_bottom: f64) -> CausticVolume {
        let start = Instant::now();
        let d = dir_air.normalize_or(-DVec3::Z);
        let cos_a = (-d.z).max(1e-6);
        let eta = 1.0 / n_water;
        let (t_flat, cos_w) = match refract(d, -DVec3::Z, eta) {
            Some((_, ct)) => (fresnel_transmittance(1.0, n_water, cos_a, ct), ct),
            None => (1.0, 1.0),
        };
        let norm = 1.0 / (t_flat.max(1e-12) * cos_a * (RAYS_PER_CELL_SIDE as f64).powi(2));
        let period = field.period;
        let cells = CELLS;
        let m = cells * RAYS_PER_CELL_SIDE;
        let step = period / m as f64;
        let z_top = -field.max_abs_height() - 1e-3;
        let z_bottom = if z_bottom.is_finite() {
            z_bottom.min(z_top - 0.01)
        } else {
            z_top - 1.0
        };
        let z: Vec<f64> = (0..PLANES)
            .map(|k| z_top + (z_bottom - z_top) * k as f64 / (PLANES - 1) as f64)
            .collect();
        // Separable tables: cos/sin of kx·x_i and of ky·y_j + φ per component.
        let comps = &field.components;
        let coord = |i: usize| (i as f64 + 0.5) * step;
        let tab = |f: &dyn Fn(&crate::optics::waves::Component, f64) -> f64| -> Vec<(f64, f64)> {
            let mut v = Vec::with_capacity(comps.len() * m);
            for c in comps {
                for i in 0..m {
                    let a = f(c, coord(i));
                    v.push((a.cos(), a.sin()));
                }
            }
            v
        };
        let tx = tab(&|c, x| c.kx * x);
        let ty = tab(&|c, y| c.ky * y + c.phase);
        // Rays: (x0, y0, h, tx/tz, ty/tz, weight), row-major.
        let rays: Vec<[f64; 6]> = (0..m)
            .into_par_iter()
            .flat_map_iter(|j| {
                let (tx, ty) = (&tx, &ty);
                (0..m).filter_map(move |i| {
                    let (mut h, mut gx, mut gy) = (0.0, 0.0, 0.0);
                    for (ci, c) in comps.iter().enumerate() {
                        let (ca, sa) = tx[ci * m + i];
                        let (cb, sb) = ty[ci * m + j];
                        let cos = ca * cb - sa * sb;
                        let sin = sa * cb + ca * sb;
                        h += c.amplitude * cos;
                        gx -= c.amplitude * sin * c.kx;
                        gy -= c.amplitude * sin * c.ky;
                    }
                    let nrm = DVec3::new(-gx, -gy, 1.0);
                    let proj = -d.dot(nrm);
                    if !(proj > 0.0) {
                        return None; // the wave faces away from the sun
                    }
                    let n_down = -nrm.normalize();
                    let (t, ct) = refract(d, n_down, eta)?;
                    let tr = fresnel_transmittance(1.0, n_water, d.dot(n_down), ct);
                    let w = tr * proj * norm;
                    if !(t.z < 0.0) || !w.is_finite() || !h.is_finite() {
                        return None;
                    }
                    Some([coord(i), coord(j), h, t.x / t.z, t.y / t.z, w])
                })
            })
            .collect();
        let cell = period / cells as f64;
        let inv_cell = 1.0 / cell;
        let theta_w = SUN_ANGULAR_RADIUS / n_water;
        let data: Vec<f32> = z
            .par_iter()
            .flat_map_iter(|&zk| {
                let mut acc = vec![0.0f64; cells * cells];
                let mask = cells as i64 - 1; // CELLS is a power of two: `& mask` wraps
                for r in &rays {
                    let s = zk - r[2]; // ≤ 0: distance below the entry point, along z
                    let u = (r[0] + s * r[3]) * inv_cell - 0.5;
                    let v = (r[1] + s * r[4]) * inv_cell - 0.5;
                    let (uf, vf) = (u.floor(), v.floor());
                    let (fu, fv) = (u - uf, v - vf);
                    let (ui, vi) = (uf as i64, vf as i64);
                    let (i0, i1) = ((ui & mask) as usize, ((ui + 1) & mask) as usize);
                    let (j0, j1) = ((vi & mask) as usize, ((vi + 1) & mask) as usize);
                    let w = r[5];
                    acc[j0 * cells + i0] += w * (1.0 - fu) * (1.0 - fv);
                    acc[j0 * cells + i1] += w * fu * (1.0 - fv);
                    acc[j1 * cells + i0] += w * (1.0 - fu) * fv;
                    acc[j1 * cells + i1] += w * fu * fv;
                }
                let sun_sigma = 0.5 * (-zk).max(0.0) * theta_w / cos_w / cell;
                let sigma = KERNEL_SIGMA_CELLS.hypot(sun_sigma);
                blur(&mut acc, cells, sigma);
                acc.into_iter().map(|v| v as f32)
            })
            .collect();
        CausticVolume {
            period,
            cells,
            z,
            data,
            build_seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Plane heights, top first.
    pub fn planes(&self) -> &[f64] {
        &self.z
    }

    /// Period of the pattern in x and y, m.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// The factors of plane `k` (row-major, `cells × cells`).
    pub fn plane(&self, k: usize) -> &[f32] {
        let n = self.cells * self.cells;
        &self.data[k * n..(k + 1) * n]
    }

    /// (mean, standard deviation) of the factor over plane `k`.
    pub fn plane_stats(&self, k: usize) -> (f64, f64) {
        let p = self.plane(k);
        let n = p.len() as f64;
        let mean = p.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = p.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    }

    fn bilinear(&self, k: usize, x: f64, y: f64) -> f64 {
        let n = self.cells;
        let cell = self.period / n as f64;
        let u = (x / cell - 0.5).rem_euclid(n as f64);
        let v = (y / cell - 0.5).rem_euclid(n as f64);
        if !(u.is_finite() && v.is_finite()) {
            return 1.0;
        }
        let (i0, j0) = (u.floor() as usize % n, v.floor() as usize % n);
        let (fu, fv) = (u - u.floor(), v - v.floor());
        let (i1, j1) = ((i0 + 1) % n, (j0 + 1) % n);
        let p = self.plane(k);
        let g = |i: usize, j: usize| p[j * n + i] as f64;
        (g(i0, j0) * (1.0 - fu) + g(i1, j0) * fu) * (1.0 - fv)
            + (g(i0, j1) * (1.0 - fu) + g(i1, j1) * fu) * fv
    }

    /// The factor on the sun's flat-surface irradiance at `p` (≥ 0, finite).
    pub fn factor(&self, p: DVec3) -> f64 {
        let z = &self.z;
        let last = z.len() - 1;
        let f = if p.z >= 0.0 {
            1.0
        } else if p.z >= z[0] {
            let t = p.z / z[0];
            (1.0 - t) + t * self.bilinear(0, p.x, p.y)
        } else if p.z <= z[last] {
            self.bilinear(last, p.x, p.y)
        } else {
            let s = (z[0] - p.z) / (z[0] - z[last]) * last as f64;
            let k = (s.floor() as usize).min(last - 1);
            let t = s - k as f64;
            (1.0 - t) * self.bilinear(k, p.x, p.y) + t * self.bilinear(k + 1, p.x, p.y)
        };
        if f.is_finite() { f.max(0.0) } else { 1.0 }
    }
}

/// Separable periodic Gaussian blur of an `n × n` grid, std `sigma` cells (taps normalised to
/// sum 1, so the total is kept exactly up to rounding).
fn blur(a: &mut [f64], n: usize, sigma: f64) {
    let r = (3.0 * sigma).ceil().max(1.0) as usize;
    let r = r.min(n / 2);
    let mut taps: Vec<f64> = (0..=2 * r)
        .map(|i| {
            let x = i as f64 - r as f64;
            (-0.5 * x * x / (sigma * sigma)).exp()
        })
        .collect();
    let s: f64 = taps.iter().sum();
    taps.iter_mut().for_each(|t| *t /= s);
    // Rows: convolve a wrap-padded copy of each row.
    let mut pad = vec![0.0; n + 2 * r];
    for row in a.chunks_exact_mut(n) {
        for (k, p) in pad.iter_mut().enumerate() {
            *p = row[(k + n - r) % n];
        }
        for (i, out) in row.iter_mut().enumerate() {
            *out = taps.iter().zip(&pad[i..]).map(|(w, v)| w * v).sum();
        }
    }
    // Columns: each output row is a weighted sum of whole input rows (contiguous, vectorisable).
    let src = a.to_vec();
    for (j, out) in a.chunks_exact_mut(n).enumerate() {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (t, w) in taps.iter().enumerate() {
            let jj = (j + n + t - r) % n;
            for (o, v) in out.iter_mut().zip(&src[jj * n..(jj + 1) * n]) {
                *o += w * v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::sun::direction_from;

    #[test]
    fn flat_surface_gives_exactly_one() {
        let f = WaveField::flat(20.0);
        let d = direction_from(60f64.to_radians(), 1.0);
        let v = CausticVolume::build(&f, d, 1.34, -10.0);
        for k in [0, PLANES / 2, PLANES - 1] {
            let (mean, sd) = v.plane_stats(k);
            // Regular ray grid at twice the cell density + bilinear splat = a partition of
            // unity: uniform to f32 rounding.
            assert!(
                (mean - 1.0).abs() < 1e-6 && sd < 1e-5,
                "plane {k}: {mean} {sd}"
            );
        }
        assert!((v.factor(DVec3::new(3.3, -7.1, -4.0)) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn blur_keeps_the_total() {
        let n = 16;
        let mut a: Vec<f64> = (0..n * n).map(|i| ((i * 7919) % 13) as f64).collect();
        let s0: f64 = a.iter().sum();
        blur(&mut a, n, 1.3);
        let s1: f64 = a.iter().sum();
        assert!((s0 - s1).abs() < 1e-9 * s0);
        // A delta at the corner spreads symmetrically across the wrap, as a Gaussian.
        let mut d = vec![0.0; n * n];
        d[0] = 1.0;
        blur(&mut d, n, 1.0);
        let g = |i: usize, j: usize| d[j * n + i];
        assert!((g(1, 0) - g(n - 1, 0)).abs() < 1e-15 && (g(0, 2) - g(0, n - 2)).abs() < 1e-15);
        assert!((g(1, 0) / g(0, 0) - (-0.5f64).exp()).abs() < 1e-12);
        assert!((g(1, 1) - g(1, 0) * g(0, 1) / g(0, 0)).abs() < 1e-15);
    }
}
