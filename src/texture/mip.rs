//! Mip pyramids of texture images and the lookup filtered by a footprint: what lets the native
//! renderer read a texture averaged over the patch of surface a camera pixel sees, instead of
//! at one point per sample (docs/textures.md, "Filtering by the pixel's footprint").
//!
//! * Levels 1, 2, … are box averages of level 0 (exact area weights, so an odd side is
//!   resampled to ⌈n/2⌉ texels without shifting the mean), stored as f32 RGB premultiplied by a
//!   coverage weight, plus the coverage: texels outside every chart of an atlas (the black
//!   gaps between shelves) have coverage 0 and never bleed into a level.
//! * [`Pyramid::sample`]: the footprint `width` in level-0 texels picks the level
//!   `log2(width / √3)`, trilinear between the two nearest levels: a level's filter (its box,
//!   then the bilinear tent between its texels) has an RMS width of half its texel, the
//!   footprint's box `width / √12`, so that level blurs the texture as much as averaging it
//!   over the footprint does, no more. Where that is level 0 or finer, level 0's own bilinear
//!   lookup (exactly the point lookup).
//! * The level is capped ([`Pyramid::build`]'s `max_level`): an atlas of many charts keeps its
//!   filter within the charts' border of baked texels.

use crate::geometry::meshfile::Wrap;
use rayon::prelude::*;

/// One reduced level: premultiplied RGB and coverage per texel, row-major from row 0.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    width: u32,
    height: u32,
    texels: Vec<[f32; 4]>,
}

/// Levels 1… of an image (level 0 is the image itself, sampled by its owner).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pyramid {
    levels: Vec<Level>,
    wrap: Wrap,
}

/// Index of texel `i` on a side of `n` texels under `wrap`.
pub(crate) fn wrapped(wrap: Wrap, i: i64, n: u32) -> usize {
    let n = n as i64;
    (match wrap {
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Mirror => {
            let k = i.rem_euclid(2 * n);
            if k >= n { 2 * n - 1 - k } else { k }
        }
    }) as usize
}

/// Area weights of the input texels under each of `out` texels spanning `n` input texels:
/// output texel `i` covers input `[i·n/out, (i+1)·n/out)`; each list sums to 1.
fn weights(n: u32, out: u32) -> Vec<Vec<(usize, f32)>> {
    let s = n as f64 / out as f64;
    (0..out)
        .map(|i| {
            let (a, b) = (i as f64 * s, (i + 1) as f64 * s);
            let mut w = Vec::new();
            let mut k = a.floor() as u32;
            while (k as f64) < b && k < n {
                let lo = a.max(k as f64);
                let hi = b.min(k as f64 + 1.0);
                if hi > lo {
                    w.push((k as usize, ((hi - lo) / s) as f32));
                }
                k += 1;
            }
            w
        })
        .collect()
}

/// The next level of a `width × height` image whose texel (i, j) is `at(i, j)`.
fn reduce(width: u32, height: u32, at: impl Fn(usize, usize) -> [f32; 4] + Sync) -> Level {
    let (w, h) = (width.div_ceil(2).max(1), height.div_ceil(2).max(1));
    let (wx, wy) = (weights(width, w), weights(height, h));
    let mut texels = vec![[0f32; 4]; w as usize * h as usize];
    texels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                let mut s = [0f64; 4];
                for &(y, fy) in &wy[j] {
                    for &(x, fx) in &wx[i] {
                        let t = at(x, y);
                        let f = (fx * fy) as f64;
                        for c in 0..4 {
                            s[c] += f * t[c] as f64;
                        }
                    }
                }
                *out = s.map(|v| v as f32);
            }
        });
    Level {
        width: w,
        height: h,
        texels,
    }
}

impl Pyramid {
    /// The levels of a `width × height` image (texel (i, j) is `at(i, j)`: linear RGB and a
    /// coverage in [0, 1]), halving until one texel or `max_level` levels; `wrap` is how the
    /// lookup reads beyond the edges. Deterministic (fixed summation order).
    pub fn build(
        width: u32,
        height: u32,
        wrap: Wrap,
        max_level: u32,
        at: impl Fn(usize, usize) -> ([f64; 3], f64) + Sync,
    ) -> Pyramid {
        let mut levels: Vec<Level> = Vec::new();
        if width == 0 || height == 0 {
            return Pyramid { levels, wrap };
        }
        let first = |i: usize, j: usize| {
            let (c, a) = at(i, j);
            [
                (c[0] * a) as f32,
                (c[1] * a) as f32,
                (c[2] * a) as f32,
                a as f32,
            ]
        };
        let (mut w, mut h) = (width, height);
        while (levels.len() as u32) < max_level && (w > 1 || h > 1) {
            let next = match levels.last() {
                None => reduce(w, h, first),
                Some(l) => reduce(w, h, |i, j| l.texels[j * l.width as usize + i]),
            };
            (w, h) = (next.width, next.height);
            levels.push(next);
        }
        Pyramid { levels, wrap }
    }

    /// Number of reduced levels (0: the lookup is always level 0's).
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// Mean of level `l` (1…) per channel, coverage-weighted: `Σ a·rgb / Σ a`.
    pub fn level_mean(&self, l: usize) -> Option<[f64; 3]> {
        let lv = self.levels.get(l.checked_sub(1)?)?;
        let mut s = [0f64; 4];
        for t in &lv.texels {
            for c in 0..4 {
                s[c] += t[c] as f64;
            }
        }
        (s[3] > 0.0).then(|| [s[0] / s[3], s[1] / s[3], s[2] / s[3]])
    }

    /// Bilinear lookup in level `l` (1…): premultiplied colour over coverage; `None` where
    /// the four texels have no coverage.
    fn level_sample(&self, l: usize, u: f64, v: f64) -> Option<[f64; 3]> {
        let lv = &self.levels[l - 1];
        let wrap = self.wrap;
        let get = |i: i64, j: i64| {
            let t = lv.texels
                [wrapped(wrap, j, lv.height) * lv.width as usize + wrapped(wrap, i, lv.width)];
            [t[0] as f64, t[1] as f64, t[2] as f64, t[3] as f64]
        };
        let x = u * lv.width as f64 - 0.5;
        let y = v * lv.height as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let (fx, fy) = (x.floor(), y.floor());
        let (i, j) = (fx as i64, fy as i64);
        let (a, b) = (x - fx, y - fy);
        let (t00, t10, t01, t11) = (get(i, j), get(i + 1, j), get(i, j + 1), get(i + 1, j + 1));
        let m = [0, 1, 2, 3].map(|c| {
            (1.0 - b) * ((1.0 - a) * t00[c] + a * t10[c]) + b * ((1.0 - a) * t01[c] + a * t11[c])
        });
        (m[3] > 1e-6).then(|| [m[0] / m[3], m[1] / m[3], m[2] / m[3]])
    }

    /// The image averaged over a footprint `width` level-0 texels wide around (u, v):
    /// trilinear between the levels `⌊log2(width / √3)⌋` and the next (capped at the deepest
    /// level); `point(u, v)` (level 0's bilinear lookup) where that level is 0 or finer.
    pub fn sample(
        &self,
        u: f64,
        v: f64,
        width: f64,
        point: impl Fn(f64, f64) -> [f64; 3],
    ) -> [f64; 3] {
        let lod = (width / 3f64.sqrt()).log2();
        if !(lod > 0.0) || self.levels.is_empty() {
            return point(u, v);
        }
        let lod = lod.min(self.levels.len() as f64);
        let l0 = lod.floor() as usize;
        let f = lod - l0 as f64;
        let at = |l: usize| {
            if l == 0 {
                point(u, v)
            } else {
                self.level_sample(l, u, v).unwrap_or_else(|| point(u, v))
            }
        };
        let a = at(l0);
        if f <= 0.0 || l0 >= self.levels.len() {
            return a;
        }
        let b = at(l0 + 1);
        [0, 1, 2].map(|c| (1.0 - f) * a[c] + f * b[c])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `n × n` checker of single texels, 0.1 and 0.9.
    fn checker(i: usize, j: usize) -> [f64; 3] {
        [if (i + j) % 2 == 0 { 0.1 } else { 0.9 }; 3]
    }

    #[test]
    fn every_level_keeps_the_mean_of_level_zero() {
        // Odd and even sides: the area weights keep the mean exactly (to f32).
        for (w, h) in [(64, 64), (37, 21), (5, 1)] {
            let f = |i: usize, j: usize| {
                let x = crate::texture::unit(crate::texture::hash2(7, i as i64, j as i64));
                ([x, 0.5 * x, 1.0 - x], 1.0)
            };
            let p = Pyramid::build(w, h, Wrap::Clamp, 99, f);
            let mut m0 = [0f64; 3];
            for j in 0..h as usize {
                for i in 0..w as usize {
                    let c = f(i, j).0;
                    for k in 0..3 {
                        m0[k] += c[k] / (w * h) as f64;
                    }
                }
            }
            assert!(p.depth() >= 1);
            for l in 1..=p.depth() {
                let m = p.level_mean(l).unwrap();
                for k in 0..3 {
                    assert!(
                        (m[k] - m0[k]).abs() < 1e-5,
                        "{w}×{h} level {l}: {m:?} vs {m0:?}"
                    );
                }
            }
            assert_eq!(p.levels.last().map(|l| (l.width, l.height)), Some((1, 1)));
        }
    }

    #[test]
    fn a_wide_footprint_reads_the_mean_of_a_fine_checker() {
        let n = 64u32;
        let p = Pyramid::build(n, n, Wrap::Repeat, 99, |i, j| (checker(i, j), 1.0));
        let point = |u: f64, v: f64| {
            crate::texture::bilinear(n, n, u, v, |i, j| {
                checker(wrapped(Wrap::Repeat, i, n), wrapped(Wrap::Repeat, j, n))
            })
        };
        let (mut lo, mut hi) = (1.0f64, 0.0f64);
        for k in 0..200 {
            let u = crate::texture::unit(crate::texture::hash2(1, k, 0));
            let v = crate::texture::unit(crate::texture::hash2(2, k, 0));
            let pt = point(u, v)[0];
            (lo, hi) = (lo.min(pt), hi.max(pt));
            // Point lookups below a level: the same as without the pyramid.
            assert_eq!(p.sample(u, v, 0.5, point), point(u, v));
            assert_eq!(p.sample(u, v, 1.7, point), point(u, v));
            for width in [4.0, 8.0, 40.0] {
                let s = p.sample(u, v, width, point)[0];
                assert!((s - 0.5).abs() < 0.02, "width {width} at ({u}, {v}): {s}");
            }
        }
        assert!(
            hi - lo > 0.6,
            "point lookups of the checker vary: {lo}…{hi}"
        );
    }

    #[test]
    fn uncovered_texels_do_not_bleed() {
        // Left half a chart of albedo 0.6, right half an empty gap (black, coverage 0).
        let p = Pyramid::build(32, 32, Wrap::Clamp, 99, |i, _| {
            if i < 16 {
                ([0.6; 3], 1.0)
            } else {
                ([0.0; 3], 0.0)
            }
        });
        for width in [2.0, 4.0, 8.0] {
            let s = p.sample(15.5 / 32.0, 0.5, width, |_, _| [0.6; 3]);
            assert!((s[0] - 0.6).abs() < 1e-6, "width {width}: {s:?}");
        }
    }

    #[test]
    fn the_level_cap_holds() {
        let p = Pyramid::build(64, 64, Wrap::Clamp, 2, |i, j| (checker(i, j), 1.0));
        assert_eq!(p.depth(), 2);
        // At the cap a 64-texel footprint still reads level 2 (4-texel boxes of a 1-texel
        // checker: the mean).
        let s = p.sample(0.3, 0.7, 64.0, |_, _| [0.0; 3]);
        assert!((s[0] - 0.5).abs() < 1e-6, "{s:?}");
    }
}
