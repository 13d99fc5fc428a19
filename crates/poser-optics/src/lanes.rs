//! SIMD lanes for the batch port solvers: [`V`], [`W`] f64 values in lock step, and [`M`],
//! a mask of lanes, with element-wise IEEE operations only (+ − × ÷ √, compare, select).
//!
//! | item | meaning |
//! |---|---|
//! | [`W`] = 8 | lanes per group: two AVX2 registers, or four SSE2 ones, whose independent √/÷ chains overlap |
//! | [`V`] | `[f64; W]`; each operator is the scalar operator on every lane |
//! | [`M`] | a lane mask (all ones or zeros per lane, like a vector compare); `select`, `any`, `all` |
//! | [`Lane`] | what a port solver's formula needs of a number: implemented by `f64` and [`V`], so one generic formula serves one point and the lanes |
//! | [`has_avx2`] | whether the AVX2 builds run on this CPU (`POSER_SIMD=baseline` turns them off) |
//!
//! Nothing here is approximate: an element-wise √ or ÷ in a vector register is the correctly
//! rounded IEEE result, exactly as the scalar instruction, and Rust never fuses a multiply and
//! an add on its own. So a kernel written with [`V`] gives, lane by lane, the same bits as the
//! same formula on scalars. The kernels are `#[inline(always)]` generic code that each caller
//! compiles twice: for the portable baseline (SSE2 on x86-64) and, in a wrapper marked
//! `#[target_feature(enable = "avx2")]`, with AVX2, picked at run time by [`has_avx2`]. The
//! compiler turns the fixed-size loops below into vector instructions; no intrinsics.

// Index loops over the lanes are what the vectoriser turns into single instructions.
#![allow(clippy::needless_range_loop)]

use std::ops::{Add, Div, Mul, Neg, Not, Sub};

/// Lanes per group.
pub const W: usize = 8;

/// [`W`] f64 lanes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V(pub [f64; W]);

/// A mask: per lane all ones (set) or all zeros, like a vector compare's result, so masks
/// stay in vector registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct M(pub [u64; W]);

macro_rules! binop {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, b: V) -> V {
                let mut o = [0.0; W];
                for i in 0..W {
                    o[i] = self.0[i] $op b.0[i];
                }
                V(o)
            }
        }
        impl $tr<f64> for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, b: f64) -> V {
                let mut o = [0.0; W];
                for i in 0..W {
                    o[i] = self.0[i] $op b;
                }
                V(o)
            }
        }
        impl $tr<V> for f64 {
            type Output = V;
            #[inline(always)]
            fn $f(self, b: V) -> V {
                let mut o = [0.0; W];
                for i in 0..W {
                    o[i] = self $op b.0[i];
                }
                V(o)
            }
        }
    };
}
binop!(Add, add, +);
binop!(Sub, sub, -);
binop!(Mul, mul, *);
binop!(Div, div, /);

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        let mut o = [0.0; W];
        for i in 0..W {
            o[i] = -self.0[i];
        }
        V(o)
    }
}

macro_rules! cmp {
    ($f:ident, $op:tt) => {
        #[inline(always)]
        pub fn $f(self, b: V) -> M {
            let mut o = [0; W];
            for i in 0..W {
                o[i] = ((self.0[i] $op b.0[i]) as u64).wrapping_neg();
            }
            M(o)
        }
    };
}

impl V {
    #[inline(always)]
    pub fn splat(x: f64) -> V {
        V([x; W])
    }
    #[inline(always)]
    pub fn sqrt(self) -> V {
        let mut o = [0.0; W];
        for i in 0..W {
            o[i] = self.0[i].sqrt();
        }
        V(o)
    }
    #[inline(always)]
    pub fn abs(self) -> V {
        let mut o = [0.0; W];
        for i in 0..W {
            o[i] = self.0[i].abs();
        }
        V(o)
    }
    /// `f64::max` on every lane (a NaN lane takes the other value).
    #[inline(always)]
    pub fn max(self, b: V) -> V {
        let mut o = [0.0; W];
        for i in 0..W {
            o[i] = self.0[i].max(b.0[i]);
        }
        V(o)
    }
    /// Lanes whose value is finite.
    #[inline(always)]
    pub fn finite(self) -> M {
        // |x| < ∞ is false for ±∞ and NaN.
        self.abs().lt(V::splat(f64::INFINITY))
    }
    cmp!(lt, <);
    cmp!(le, <=);
    cmp!(gt, >);
}

impl M {
    #[inline(always)]
    pub fn splat(b: bool) -> M {
        M([(b as u64).wrapping_neg(); W])
    }
    /// Whether lane `l` is set.
    #[inline(always)]
    pub fn get(self, l: usize) -> bool {
        self.0[l] != 0
    }
    /// Lanes `0..n` set.
    #[inline(always)]
    pub fn first(n: usize) -> M {
        let mut o = [0; W];
        for (i, m) in o.iter_mut().enumerate() {
            *m = ((i < n) as u64).wrapping_neg();
        }
        M(o)
    }
    /// `a` where the mask is set, else `b`.
    #[inline(always)]
    pub fn select(self, a: V, b: V) -> V {
        let mut o = [0.0; W];
        for i in 0..W {
            let m = self.0[i];
            o[i] = f64::from_bits((a.0[i].to_bits() & m) | (b.0[i].to_bits() & !m));
        }
        V(o)
    }
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(0, |a, &m| a | m) != 0
    }
    #[inline(always)]
    pub fn all(self) -> bool {
        self.0.iter().fold(u64::MAX, |a, &m| a & m) != 0
    }
    #[inline(always)]
    pub fn and(self, b: M) -> M {
        let mut o = [0; W];
        for i in 0..W {
            o[i] = self.0[i] & b.0[i];
        }
        M(o)
    }
    #[inline(always)]
    pub fn or(self, b: M) -> M {
        let mut o = [0; W];
        for i in 0..W {
            o[i] = self.0[i] | b.0[i];
        }
        M(o)
    }
}

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        let mut o = [0; W];
        for i in 0..W {
            o[i] = !self.0[i];
        }
        M(o)
    }
}

/// What the port solvers' formulas need of a number, so that one generic formula serves
/// a single point (`f64`) and the SIMD lanes ([`V`]) with the same operations in the same
/// order, hence the same bits. Constants multiply on the right (`x * 2.0`, not `2.0 * x`:
/// the product is the same).
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
{
    /// `bool` for one value, [`M`] for lanes.
    type Mask: Copy + Not<Output = Self::Mask>;
    /// Set where all four masks are.
    fn all4(m: [Self::Mask; 4]) -> Self::Mask;
    fn splat(x: f64) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn lt(self, b: Self) -> Self::Mask;
    /// `a` where `m` is set, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

impl Lane for f64 {
    type Mask = bool;
    #[inline(always)]
    fn all4(m: [bool; 4]) -> bool {
        m[0] && m[1] && m[2] && m[3]
    }
    #[inline(always)]
    fn splat(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> f64 {
        f64::abs(self)
    }
    #[inline(always)]
    fn lt(self, b: f64) -> bool {
        self < b
    }
    #[inline(always)]
    fn select(m: bool, a: f64, b: f64) -> f64 {
        if m { a } else { b }
    }
}

impl Lane for V {
    type Mask = M;
    #[inline(always)]
    fn all4(m: [M; 4]) -> M {
        m[0].and(m[1]).and(m[2]).and(m[3])
    }
    #[inline(always)]
    fn splat(x: f64) -> V {
        V::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> V {
        V::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> V {
        V::abs(self)
    }
    #[inline(always)]
    fn lt(self, b: V) -> M {
        V::lt(self, b)
    }
    #[inline(always)]
    fn select(m: M, a: V, b: V) -> V {
        m.select(a, b)
    }
}

/// Whether the AVX2 builds of the batch kernels run here: the CPU has AVX2 (x86-64) and the
/// environment variable `POSER_SIMD` is not `baseline` (read once, then cached; for
/// measuring what the vectors gain, results are the same bits either way).
#[inline]
pub fn has_avx2() -> bool {
    static AVX2: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVX2.get_or_init(|| {
        let allowed = std::env::var("POSER_SIMD").map_or(true, |v| v != "baseline");
        #[cfg(target_arch = "x86_64")]
        {
            allowed && std::arch::is_x86_feature_detected!("avx2")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = allowed;
            false
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_are_the_scalar_operations_bit_for_bit() {
        let a = V([1.0, -2.5, 3.0e-300, 7.0, f64::INFINITY, 0.3, 1e300, -0.0]);
        let b = V([3.0, 0.1, 7.0, -0.0, 2.0, 0.7, 1e10, 5.0]);
        for i in 0..W {
            assert_eq!((a + b).0[i].to_bits(), (a.0[i] + b.0[i]).to_bits());
            assert_eq!((a * b).0[i].to_bits(), (a.0[i] * b.0[i]).to_bits());
            assert_eq!((a / b).0[i].to_bits(), (a.0[i] / b.0[i]).to_bits());
            assert_eq!((a - 2.0).0[i].to_bits(), (a.0[i] - 2.0).to_bits());
            assert_eq!(b.abs().sqrt().0[i].to_bits(), b.0[i].abs().sqrt().to_bits());
        }
        let m = a.lt(b);
        let set: Vec<bool> = (0..W).map(|l| m.get(l)).collect();
        assert_eq!(set, [true, true, true, false, false, true, false, true]);
        assert_eq!((m.select(a, b).0[1], m.select(a, b).0[3]), (-2.5, -0.0));
        assert!(m.any() && !m.all() && m.or(m.not()).all() && !m.and(m.not()).any());
        assert!(!a.finite().get(4) && a.finite().get(3));
        assert!(M::first(3).get(2) && !M::first(3).get(3));
    }
}
