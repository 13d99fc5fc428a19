//! Procedural noise shared by the generated geometry (seabeds, rocks, corals), the baked
//! textures and the renderer's seeds: the SplitMix64 hash, a floor that needs no libm call,
//! and trilinear value noise. Pure functions of their inputs, so a site is the same on every
//! machine and thread count.

use glam::DVec3;

/// `x.floor()`, the same value for every `x`, inlined: without SSE4.1 (`roundsd`, not in the
/// x86-64 baseline) `f64::floor` is a call into libm, a large share of a bake's time.
#[inline]
pub fn floor(x: f64) -> f64 {
    // Beyond 2^52 every f64 is an integer; NaN, ±∞ and ±0 are their own floor.
    if !(x.abs() < 4_503_599_627_370_496.0) || x == 0.0 {
        return x;
    }
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

/// SplitMix64 finaliser: a well-mixed 64-bit hash.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in [0, 1) from a hash of the inputs.
pub fn hash_unit(seed: u64, a: i64, b: i64, c: i64) -> f64 {
    let h = mix64(mix64(mix64(seed ^ (a as u64)) ^ (b as u64)) ^ (c as u64));
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[inline]
pub fn quintic(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Value noise in [-1, 1] on the integer lattice, trilinear with quintic fade.
pub fn value_noise3(seed: u64, p: DVec3) -> f64 {
    let fl = floor;
    let f = DVec3::new(fl(p.x), fl(p.y), fl(p.z));
    let (ix, iy, iz) = (f.x as i64, f.y as i64, f.z as i64);
    let d = p - f;
    let (u, v, w) = (quintic(d.x), quintic(d.y), quintic(d.z));
    let l = |a: i64, b: i64, c: i64| 2.0 * hash_unit(seed, ix + a, iy + b, iz + c) - 1.0;
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let x00 = lerp(l(0, 0, 0), l(1, 0, 0), u);
    let x10 = lerp(l(0, 1, 0), l(1, 1, 0), u);
    let x01 = lerp(l(0, 0, 1), l(1, 0, 1), u);
    let x11 = lerp(l(0, 1, 1), l(1, 1, 1), u);
    lerp(lerp(x00, x10, v), lerp(x01, x11, v), w)
}
