//! High-precision references for the projection solvers: double-double arithmetic (≈ 32
//! significant digits, no long double) and forward projection through flat and dome ports
//! solved in it. Used by the tests and by `poser bench projection` to measure the error of the
//! f64 solvers; far too slow for production use.
//!
//! The reference answers the question "what is the exact pixel for these f64 inputs", so every
//! input is taken as exact and only the arithmetic is extended.

use glam::DVec3;

/// A double-double number `hi + lo` with |lo| ≤ ulp(hi)/2.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Dd {
    pub hi: f64,
    pub lo: f64,
}

#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

#[inline]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

impl Dd {
    pub const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };
    pub const ONE: Dd = Dd { hi: 1.0, lo: 0.0 };
    #[inline(always)]
    pub fn new(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }
    #[inline(always)]
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
    #[inline(always)]
    pub fn plus(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let (s, e) = quick_two_sum(s, e + t);
        let (hi, lo) = quick_two_sum(s, e + f);
        Dd { hi, lo }
    }
    #[inline(always)]
    pub fn negate(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
    #[inline(always)]
    pub fn minus(self, o: Dd) -> Dd {
        self.plus(o.negate())
    }
    #[inline(always)]
    pub fn times(self, o: Dd) -> Dd {
        let p = self.hi * o.hi;
        let e = self.hi.mul_add(o.hi, -p);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }
    #[inline(always)]
    pub fn over(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.minus(o.times(Dd::new(q1)));
        let q2 = r.hi / o.hi;
        let r = r.minus(o.times(Dd::new(q2)));
        let q3 = r.hi / o.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        Dd { hi, lo }.plus(Dd::new(q3))
    }
    #[inline(always)]
    pub fn sqrt(self) -> Dd {
        if self.hi <= 0.0 {
            return Dd::ZERO;
        }
        let x = 1.0 / self.hi.sqrt();
        let ax = Dd::new(self.hi * x);
        // Karp's trick: sqrt(a) ≈ a·x + (a − (a·x)²)·x/2
        let diff = self.minus(ax.times(ax));
        ax.plus(Dd::new(diff.hi * x * 0.5))
    }
    #[inline(always)]
    pub fn abs(self) -> Dd {
        if self.hi < 0.0 { self.negate() } else { self }
    }
}

impl std::ops::Add for Dd {
    type Output = Dd;
    #[inline(always)]
    fn add(self, o: Dd) -> Dd {
        Dd::plus(self, o)
    }
}
impl std::ops::Sub for Dd {
    type Output = Dd;
    #[inline(always)]
    fn sub(self, o: Dd) -> Dd {
        Dd::minus(self, o)
    }
}
impl std::ops::Mul for Dd {
    type Output = Dd;
    #[inline(always)]
    fn mul(self, o: Dd) -> Dd {
        Dd::times(self, o)
    }
}
impl std::ops::Div for Dd {
    type Output = Dd;
    #[inline(always)]
    fn div(self, o: Dd) -> Dd {
        Dd::over(self, o)
    }
}

/// A 3-vector of double-doubles.
#[derive(Debug, Clone, Copy)]
pub struct V3 {
    pub x: Dd,
    pub y: Dd,
    pub z: Dd,
}

impl V3 {
    #[inline(always)]
    pub fn from(v: DVec3) -> V3 {
        V3 {
            x: Dd::new(v.x),
            y: Dd::new(v.y),
            z: Dd::new(v.z),
        }
    }
    #[inline(always)]
    pub fn dot(self, o: V3) -> Dd {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    pub fn cross(self, o: V3) -> V3 {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
    #[inline(always)]
    pub fn scale(self, s: Dd) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub fn plus(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    #[inline(always)]
    pub fn minus(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    #[inline(always)]
    pub fn length(self) -> Dd {
        self.dot(self).sqrt()
    }
}

/// Pinhole pixel of a camera-frame direction, in double-double.
pub fn pinhole(fx: f64, fy: f64, cx: f64, cy: f64, d: V3) -> [f64; 2] {
    [
        (Dd::new(fx) * d.x / d.z + Dd::new(cx)).to_f64(),
        (Dd::new(fy) * d.y / d.z + Dd::new(cy)).to_f64(),
    ]
}

/// Reference forward projection through a flat port (normal need not be unit: it is
/// normalised in double-double), layers `(thickness, index)`; `None` where no solution.
/// Newton on the q-equation in double-double to |Δq| ≤ 1e-28·q.
pub fn flat_forward(
    normal: DVec3,
    distance: f64,
    layers: &[(f64, f64)],
    na: f64,
    nw: f64,
    p: DVec3,
) -> Option<V3> {
    let n0 = V3::from(normal);
    let nrm = n0.scale(Dd::ONE / n0.length());
    let pp = V3::from(p);
    let a = nrm.dot(pp);
    let mut depth = a - Dd::new(distance);
    for l in layers {
        depth = depth - Dd::new(l.0);
    }
    if depth.hi <= 0.0 {
        return None;
    }
    let r = nrm.cross(pp).length();
    if r.hi == 0.0 {
        return Some(nrm);
    }
    let perp = pp.minus(nrm.scale(a));
    let na_d = Dd::new(na);
    let mut all: Vec<(Dd, Dd)> = layers
        .iter()
        .map(|l| (Dd::new(l.0), Dd::new(l.1)))
        .collect();
    all.push((depth, Dd::new(nw)));
    let eval = |q: Dd| -> (Dd, Dd) {
        let mut f = Dd::new(distance) * q - r;
        let mut df = Dd::new(distance);
        for &(t, n) in &all {
            let n2 = n * n;
            let g = n2 + (n2 - na_d * na_d) * q * q;
            let s = g.sqrt();
            f = f + t * na_d * q / s;
            df = df + t * na_d * n2 / (g * s);
        }
        (f, df)
    };
    // Safeguarded Newton in double-double on [lo, hi]; hi is the first pole (a layer thinner
    // than the camera medium) or grows geometrically.
    let mut hi_b = f64::INFINITY;
    for &(t, n) in &all {
        if n.hi < na && t.hi > 0.0 {
            hi_b = hi_b.min(n.hi / (na * na - n.hi * n.hi).sqrt());
        }
    }
    let mut lo = Dd::ZERO;
    let mut hi = if hi_b.is_finite() {
        Dd::new(hi_b)
    } else {
        Dd::new(1.0)
    };
    if !hi_b.is_finite() {
        while eval(hi).0.hi <= 0.0 {
            hi = hi * Dd::new(2.0);
            if hi.hi > 1e300 {
                return None;
            }
        }
    }
    let mut q = (lo + hi) * Dd::new(0.5);
    for _ in 0..400 {
        let (f, df) = eval(q);
        if f.hi <= 0.0 {
            lo = q;
        } else {
            hi = q;
        }
        let mut next = q - f / df;
        if !(next.hi.is_finite() && next.hi > lo.hi && next.hi < hi.hi) {
            next = (lo + hi) * Dd::new(0.5);
        }
        let step = (next - q).abs();
        q = next;
        if step.hi <= 1e-30 * q.hi.abs() {
            break;
        }
    }
    if !q.hi.is_finite() || q.hi <= 0.0 {
        return None;
    }
    Some(nrm.plus(perp.scale(q / r)))
}

/// Reference forward projection through a dome (sphere centre `c`, radii r1 < r2); the root
/// is bracketed by ±asin(|C|/R₁) and refined by bisection in double-double to 1e-30.
pub fn dome_forward(c: DVec3, r1: f64, r2: f64, na: f64, ng: f64, nw: f64, p: DVec3) -> Option<V3> {
    let pp = V3::from(p);
    let cc = V3::from(c);
    if (pp.minus(cc)).length().hi <= r2 {
        return None;
    }
    let l = pp.length();
    let e1 = pp.scale(Dd::ONE / l);
    let cpar = cc.dot(e1);
    let cperp = cc.minus(e1.scale(cpar));
    let c2 = cperp.length();
    if c2.hi == 0.0 {
        return Some(pp);
    }
    let e2 = cperp.scale(Dd::ONE / c2);
    let (c1, c2) = (cpar, c2);
    let r1d = Dd::new(r1);
    let r2d = Dd::new(r2);
    let refr = |w: (Dd, Dd), n: (Dd, Dd), eta: Dd| -> Option<(Dd, Dd)> {
        let ci = w.0 * n.0 + w.1 * n.1;
        let s2 = eta * eta * (Dd::ONE - ci * ci);
        if s2.hi > 1.0 {
            return None;
        }
        let ct = (Dd::ONE - s2).sqrt();
        let k = ct - eta * ci;
        Some((eta * w.0 + k * n.0, eta * w.1 + k * n.1))
    };
    let far = |o: (Dd, Dd), w: (Dd, Dd), r: Dd| -> Dd {
        let oc = (o.0 - c1, o.1 - c2);
        let b = w.0 * oc.0 + w.1 * oc.1;
        let c0 = oc.0 * oc.0 + oc.1 * oc.1 - r * r;
        let disc = (b * b - c0).sqrt();
        if b.hi > 0.0 {
            c0.negate() / (b + disc)
        } else {
            disc - b
        }
    };
    let miss = |tau: Dd| -> Option<Dd> {
        let inv = Dd::ONE / (Dd::ONE + tau * tau).sqrt();
        let w = (inv, tau * inv);
        let s = far((Dd::ZERO, Dd::ZERO), w, r1d);
        let x1 = (w.0 * s, w.1 * s);
        let n1 = ((x1.0 - c1) / r1d, (x1.1 - c2) / r1d);
        let w1 = refr(w, n1, Dd::new(na) / Dd::new(ng))?;
        let s2 = far(x1, w1, r2d);
        let x2 = (x1.0 + w1.0 * s2, x1.1 + w1.1 * s2);
        let n2 = ((x2.0 - c1) / r2d, (x2.1 - c2) / r2d);
        let w2 = refr(w1, n2, Dd::new(ng) / Dd::new(nw))?;
        Some(w2.0 * (Dd::ZERO - x2.1) - w2.1 * (l - x2.0))
    };
    let e = cc.length().hi;
    let s = e / r1;
    let bound = s / (1.0 - s * s).sqrt() * (1.0 + 1e-6) + 1e-15;
    let (mut a, mut b) = (Dd::new(-bound), Dd::new(bound));
    let mut fa = miss(a)?;
    let fb = miss(b)?;
    if (fa.hi > 0.0) == (fb.hi > 0.0) {
        return None;
    }
    for _ in 0..110 {
        let m = (a + b) * Dd::new(0.5);
        let fm = miss(m)?;
        if fm.hi == 0.0 {
            a = m;
            b = m;
            break;
        }
        if (fm.hi > 0.0) == (fa.hi > 0.0) {
            a = m;
            fa = fm;
        } else {
            b = m;
        }
        if (b - a).hi <= 1e-31 {
            break;
        }
    }
    let tau = (a + b) * Dd::new(0.5);
    Some(e1.plus(e2.scale(tau)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dd_arithmetic_is_double_double() {
        let third = Dd::ONE / Dd::new(3.0);
        let back = third * Dd::new(3.0) - Dd::ONE;
        assert!(back.to_f64().abs() < 1e-31);
        let s2 = Dd::new(2.0).sqrt();
        assert!((s2 * s2 - Dd::new(2.0)).to_f64().abs() < 1e-31);
        // 1 + 1e-20 survives.
        let x = Dd::ONE + Dd::new(1e-20);
        assert_eq!((x - Dd::ONE).to_f64(), 1e-20);
    }
}
