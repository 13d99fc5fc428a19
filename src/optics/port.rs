//! Housing ports: exact backward (camera ray → ray in water) and forward (point in water →
//! camera ray) refraction, per channel indices (n_air, n_glass, n_water).
//!
//! | port | parameters (camera frame, metres) | forward solver |
//! |---|---|---|
//! | [`FlatPort`] | unit normal N (camera → water), inner-face distance d ≥ 0, glass layers (thickness, index)… | Newton on the scalar q-equation from the paraxial guess (monotone, no bracket needed when every n ≥ n_air; safeguarded bisection otherwise) |
//! | [`DomePort`] | centre C (|C| < R₁), inner radius R₁, thickness t | 1-D secant in the plane (O, C, P) inside the guaranteed bracket ±asin(|C|/R₁); pinhole when centred |
//! | [`CylinderPort`] | axis point, unit axis, inner radius, thickness | on its axis: the flat q-equation in the meridional plane; off it: 2-D Newton (skew rays) |
//!
//! All ports share the conventions of Refractive COLMAP (`optics.md` §1.1). The backward
//! transmittance is the product of the unpolarised Fresnel transmittances of every interface
//! (no n² radiance factor; see render-conventions.md for that).
//!
//! Failure is explicit ([`NoSolution`]), never NaN: a point inside the housing or glass, behind
//! the camera, beyond the critical angle, a camera ray that misses the port or is totally
//! internally reflected, or (never seen, but guarded) a solver that does not converge.

use super::NoSolution;
use super::interface::{fresnel_transmittance, refract};
use crate::model::Port;
use glam::{DVec2, DVec3};

/// A ray leaving the port into the water (camera frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortRay {
    /// Where the ray leaves the outer surface of the port.
    pub origin: DVec3,
    /// Unit direction in the water.
    pub dir: DVec3,
    /// Product of the unpolarised Fresnel transmittances at every interface, in [0, 1].
    pub transmittance: f64,
}

/// Largest number of glass layers of a flat port.
pub const MAX_LAYERS: usize = 4;

/// Flat port with one or more parallel glass layers (possibly tilted).
#[derive(Debug, Clone, Copy)]
pub struct FlatPort {
    pub normal: DVec3,
    pub distance: f64,
    layers: [(f64, f64); MAX_LAYERS],
    n_layers: usize,
    pub n_air: f64,
    pub n_water: f64,
    total_thickness: f64,
    /// Σ tᵢ·na/nᵢ over the camera-side gap and the glass (the paraxial optical length).
    paraxial_port: f64,
    /// Every index ≥ n_air: F is concave and Newton from the left needs no bracket.
    concave: bool,
}

/// Scalar q-equation for parallel layers (`optics.md` §1.3): layers (thickness, index) with
/// the camera medium index `na`; the first layer is the camera-side gap.
#[derive(Debug, Clone, Copy)]
struct QSolve<'a> {
    na: f64,
    gap: f64,
    layers: &'a [(f64, f64)],
    water: (f64, f64),
}

impl QSolve<'_> {
    #[inline(always)]
    fn term(na: f64, t: f64, n: f64, q: f64) -> (f64, f64) {
        // t·na·q/√(n² + (n²−na²)q²) and its derivative t·na·n²/(…)^{3/2}
        let n2 = n * n;
        let g = n2 + (n2 - na * na) * q * q;
        let s = g.sqrt();
        let inv = 1.0 / s;
        let v = t * na * q * inv;
        (v, t * na * n2 * inv * inv * inv)
    }

    #[inline(always)]
    fn eval(&self, q: f64, r: f64) -> (f64, f64) {
        let mut f = self.gap * q - r;
        let mut df = self.gap;
        for &(t, n) in self.layers {
            let (v, d) = Self::term(self.na, t, n, q);
            f += v;
            df += d;
        }
        let (v, d) = Self::term(self.na, self.water.0, self.water.1, q);
        (f + v, df + d)
    }

    #[inline(always)]
    fn term2(na: f64, t: f64, n: f64, q: f64) -> (f64, f64, f64) {
        let n2 = n * n;
        let k = n2 - na * na;
        let g = n2 + k * q * q;
        let inv = 1.0 / g.sqrt();
        let inv2 = inv * inv;
        let v = t * na * q * inv;
        let dv = t * na * n2 * inv2 * inv;
        (v, dv, -3.0 * k * q * dv * inv2)
    }

    /// F, F′ and F″.
    #[inline(always)]
    fn eval2(&self, q: f64, r: f64) -> (f64, f64, f64) {
        let mut f = self.gap * q - r;
        let mut df = self.gap;
        let mut d2f = 0.0;
        for &(t, n) in self.layers {
            let (v, d, d2) = Self::term2(self.na, t, n, q);
            f += v;
            df += d;
            d2f += d2;
        }
        let (v, d, d2) = Self::term2(self.na, self.water.0, self.water.1, q);
        (f + v, df + d, d2f + d2)
    }

    /// Largest q at which every term is defined (q < n/√(na²−n²) for layers with n < na).
    fn q_max(&self) -> f64 {
        let mut m = f64::INFINITY;
        for &(t, n) in self.layers.iter().chain(std::iter::once(&self.water)) {
            if n < self.na && t > 0.0 {
                m = m.min(n / (self.na * self.na - n * n).sqrt());
            }
        }
        m
    }

    /// Solve F(q) = 0 for q ≥ 0 (q = tan of the camera-side angle). `q0` must satisfy F ≤ 0.
    #[inline]
    fn solve(&self, r: f64, q0: f64, concave: bool) -> Result<f64, NoSolution> {
        if concave {
            // Concave increasing F, F(q0) ≤ 0: Newton rises monotonically to the root.
            // If the camera-side gap is 0, F is bounded: check the asymptote first.
            if self.gap == 0.0 {
                let mut lim = 0.0;
                for &(t, n) in self.layers.iter().chain(std::iter::once(&self.water)) {
                    lim += if n > self.na {
                        t * self.na / (n * n - self.na * self.na).sqrt()
                    } else if t > 0.0 {
                        f64::INFINITY
                    } else {
                        0.0
                    };
                }
                if lim <= r {
                    return Err(NoSolution::BeyondCriticalAngle);
                }
            }
            // Halley iteration (cubic convergence) from the paraxial guess; steps of either
            // sign are allowed, q stays positive.
            let mut q = q0;
            for _ in 0..200 {
                let (f, df, d2f) = self.eval2(q, r);
                // Halley while its correction is mild; plain Newton (monotone from the left
                // for concave F) when F·F″ is comparable to F′² (far from the root).
                let dq = if (f * d2f).abs() < 0.5 * df * df {
                    -2.0 * f * df / (2.0 * df * df - f * d2f)
                } else {
                    -f / df
                };
                if !dq.is_finite() {
                    return Err(NoSolution::NoConvergence);
                }
                let next = q + dq;
                q = if next > 0.0 { next } else { 0.5 * q };
                if dq.abs() <= 1e-7 * q {
                    // Error after a Halley step ≈ K·dq³: < 1e-20 relative here.
                    return if q.is_finite() {
                        Ok(q)
                    } else {
                        Err(NoSolution::BeyondCriticalAngle)
                    };
                }
            }
            Err(NoSolution::NoConvergence)
        } else {
            // Some layer is optically thinner than the camera medium: F → ∞ at q_max.
            // Safeguarded Newton on [lo, hi].
            let (mut lo, mut hi): (f64, f64) = (0.0, self.q_max());
            let mut q = q0.min(0.5 * hi);
            for _ in 0..400 {
                let (f, df) = self.eval(q, r);
                if f.is_finite() && f <= 0.0 {
                    lo = lo.max(q);
                } else {
                    hi = hi.min(q);
                }
                let mut next = q - f / df;
                if !(next.is_finite() && next > lo && next < hi) {
                    next = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * lo + 1.0
                    };
                }
                if (next - q).abs() <= 1e-15 * next.abs() || hi - lo <= 1e-16 * hi {
                    return Ok(next);
                }
                q = next;
            }
            Err(NoSolution::NoConvergence)
        }
    }
}

impl FlatPort {
    /// A flat port with glass `layers` (thickness m, index) in order from the camera.
    pub fn new(
        normal: DVec3,
        distance: f64,
        layers: &[(f64, f64)],
        n_air: f64,
        n_water: f64,
    ) -> Result<FlatPort, String> {
        let n = normal
            .try_normalize()
            .ok_or("flat port normal must be a non-zero vector")?;
        if layers.len() > MAX_LAYERS {
            return Err(format!("a flat port has at most {MAX_LAYERS} glass layers"));
        }
        if !(distance >= 0.0 && distance.is_finite()) {
            return Err("flat port distance must be ≥ 0".into());
        }
        for &(t, ni) in layers {
            if !(t >= 0.0 && t.is_finite() && ni >= 1e-3 && ni.is_finite()) {
                return Err("flat port layers need thickness ≥ 0 and a positive index".into());
            }
        }
        if !(n_air > 0.0 && n_water > 0.0) {
            return Err("indices must be positive".into());
        }
        let mut arr = [(0.0, 1.0); MAX_LAYERS];
        arr[..layers.len()].copy_from_slice(layers);
        let total: f64 = layers.iter().map(|l| l.0).sum();
        let parax = distance + layers.iter().map(|&(t, ni)| t * n_air / ni).sum::<f64>();
        let concave = layers.iter().all(|&(_, ni)| ni >= n_air) && n_water >= n_air;
        Ok(FlatPort {
            normal: n,
            distance,
            layers: arr,
            n_layers: layers.len(),
            n_air,
            n_water,
            total_thickness: total,
            paraxial_port: parax,
            concave,
        })
    }

    pub fn layers(&self) -> &[(f64, f64)] {
        &self.layers[..self.n_layers]
    }

    /// Camera ray (unit, camera frame) → ray in water.
    #[inline]
    pub fn backward(&self, v: DVec3) -> Result<PortRay, NoSolution> {
        let nrm = self.normal;
        let c = nrm.dot(v);
        if !(c > 1e-300) {
            return Err(NoSolution::MissesPort);
        }
        let mut x = v * (self.distance / c);
        let mut dir = v;
        let mut n_prev = self.n_air;
        let mut cos_prev = c;
        let mut tr = 1.0;
        for &(t, ni) in self.layers() {
            let (d, ct) =
                refract(dir, nrm, n_prev / ni).ok_or(NoSolution::TotalInternalReflection)?;
            tr *= fresnel_transmittance(n_prev, ni, cos_prev, ct);
            x += d * (t / ct);
            dir = d;
            n_prev = ni;
            cos_prev = ct;
        }
        let (d, ct) =
            refract(dir, nrm, n_prev / self.n_water).ok_or(NoSolution::TotalInternalReflection)?;
        tr *= fresnel_transmittance(n_prev, self.n_water, cos_prev, ct);
        Ok(PortRay {
            origin: x,
            dir: d,
            transmittance: tr,
        })
    }

    /// Point in water (camera frame) → camera ray direction (not unit; z-scale arbitrary).
    #[inline]
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let nrm = self.normal;
        let a = nrm.dot(p);
        let depth = a - self.distance - self.total_thickness;
        if !(depth > 0.0) {
            return Err(if a <= 0.0 {
                NoSolution::BehindCamera
            } else if a <= self.distance {
                NoSolution::InsideHousing
            } else {
                NoSolution::InsideGlass
            });
        }
        let r = nrm.cross(p).length();
        if r == 0.0 {
            return Ok(nrm);
        }
        let perp = p - a * nrm;
        let qs = QSolve {
            na: self.n_air,
            gap: self.distance,
            layers: self.layers(),
            water: (depth, self.n_water),
        };
        // Paraxial guess r / Σ tᵢ na/nᵢ: F ≤ 0 there (each term ≤ tᵢ na q / nᵢ).
        let q0 = if self.concave {
            r / (self.paraxial_port + depth * self.n_air / self.n_water)
        } else {
            0.0
        };
        let q = qs.solve(r, q0, self.concave)?;
        Ok(nrm + perp * (q / r))
    }
}

/// Dome port: two concentric spheres about `center`.
#[derive(Debug, Clone, Copy)]
pub struct DomePort {
    pub center: DVec3,
    pub r1: f64,
    pub r2: f64,
    pub n_air: f64,
    pub n_glass: f64,
    pub n_water: f64,
    /// |C|; below `1e-13·R₁` the dome is treated as centred (pinhole; error < 1e-10 px).
    ecc: f64,
    /// tan(asin(|C|/R₁)): half-width of the guaranteed bracket on τ.
    bracket: f64,
}

/// Outcome of tracing one 2-D dome ray.
#[derive(Debug, Clone, Copy)]
struct DomeTrace {
    x2: DVec2,
    w2: DVec2,
}

impl DomePort {
    pub fn new(
        center: DVec3,
        inner_radius: f64,
        thickness: f64,
        n_air: f64,
        n_glass: f64,
        n_water: f64,
    ) -> Result<DomePort, String> {
        if !(inner_radius > 0.0
            && inner_radius.is_finite()
            && thickness >= 0.0
            && thickness.is_finite())
        {
            return Err("dome port needs inner radius > 0 and thickness ≥ 0".into());
        }
        if !center.is_finite() {
            return Err("dome centre must be finite".into());
        }
        let e = center.length();
        if e >= inner_radius {
            return Err(format!(
                "the camera's entrance pupil lies outside the dome (decentring {e} m ≥ inner radius {inner_radius} m)"
            ));
        }
        if !(n_air > 0.0 && n_glass > 0.0 && n_water > 0.0) {
            return Err("indices must be positive".into());
        }
        let s = e / inner_radius;
        // Widen slightly so the bound itself is never the root's own rounding victim.
        let bracket = (s / (1.0 - s * s).sqrt()) * (1.0 + 1e-6) + 1e-15;
        Ok(DomePort {
            center,
            r1: inner_radius,
            r2: inner_radius + thickness,
            n_air,
            n_glass,
            n_water,
            ecc: e,
            bracket,
        })
    }

    #[inline]
    fn is_centred(&self) -> bool {
        self.ecc <= 1e-13 * self.r1
    }

    /// Far intersection from inside a sphere: ray `o + s·w` (w unit), `oc = o − C`,
    /// `c0 = |oc|² − R²` (< 0). Stable root form.
    #[inline(always)]
    fn far_root(b: f64, c0: f64) -> f64 {
        let disc = (b * b - c0).max(0.0).sqrt();
        if b > 0.0 { -c0 / (b + disc) } else { disc - b }
    }

    /// Camera ray (unit, camera frame) → ray in water.
    #[inline]
    pub fn backward(&self, v: DVec3) -> Result<PortRay, NoSolution> {
        let c = self.center;
        // Inner sphere from the origin: oc = −C, c0 = |C|² − R₁².
        let b = -v.dot(c);
        let c0 = (self.ecc - self.r1) * (self.ecc + self.r1);
        let s = Self::far_root(b, c0);
        let x1 = v * s;
        let n1 = (x1 - c) / self.r1;
        let ci = n1.dot(v);
        let (w1, ct1) =
            refract(v, n1, self.n_air / self.n_glass).ok_or(NoSolution::TotalInternalReflection)?;
        let mut tr = fresnel_transmittance(self.n_air, self.n_glass, ci, ct1);
        // Outer sphere from X₁: oc = R₁·n₁, b = R₁ cosθt, c0 = R₁² − R₂².
        let b2 = self.r1 * w1.dot(n1);
        let c02 = (self.r1 - self.r2) * (self.r1 + self.r2);
        let s2 = Self::far_root(b2, c02);
        let x2 = x1 + w1 * s2;
        let n2 = (x2 - c) / self.r2;
        let ci2 = n2.dot(w1);
        let (w2, ct2) = refract(w1, n2, self.n_glass / self.n_water)
            .ok_or(NoSolution::TotalInternalReflection)?;
        tr *= fresnel_transmittance(self.n_glass, self.n_water, ci2, ct2);
        Ok(PortRay {
            origin: x2,
            dir: w2,
            transmittance: tr,
        })
    }

    /// Trace the 2-D ray of slope τ (direction ∝ (1, τ)) in the plane basis where C = (c1, c2).
    #[inline(always)]
    fn trace2(&self, tau: f64, c: DVec2) -> Option<DomeTrace> {
        let w = DVec2::new(1.0, tau) * (1.0 / (1.0 + tau * tau).sqrt());
        let b = -w.dot(c);
        let c0 = (self.ecc - self.r1) * (self.ecc + self.r1);
        let s = Self::far_root(b, c0);
        let x1 = w * s;
        let n1 = (x1 - c) * (1.0 / self.r1);
        let eta = self.n_air / self.n_glass;
        let ci = n1.dot(w);
        let st2 = eta * eta * (1.0 - ci * ci).max(0.0);
        if st2 > 1.0 {
            return None;
        }
        let ct = (1.0 - st2).sqrt();
        let w1 = w * eta + n1 * (ct - eta * ci);
        let b2 = self.r1 * ct;
        let c02 = (self.r1 - self.r2) * (self.r1 + self.r2);
        let s2 = Self::far_root(b2, c02);
        let x2 = x1 + w1 * s2;
        let n2 = (x2 - c) * (1.0 / self.r2);
        let eta2 = self.n_glass / self.n_water;
        let ci2 = n2.dot(w1);
        let st2b = eta2 * eta2 * (1.0 - ci2 * ci2).max(0.0);
        if st2b > 1.0 {
            return None;
        }
        let ct2 = (1.0 - st2b).sqrt();
        let w2 = w1 * eta2 + n2 * (ct2 - eta2 * ci2);
        Some(DomeTrace { x2, w2 })
    }

    /// Signed miss of the water ray with respect to P = (L, 0): w₂ × (P − X₂), and |P − X₂|.
    #[inline(always)]
    fn miss(&self, tau: f64, c: DVec2, l: f64) -> Option<(f64, f64)> {
        let t = self.trace2(tau, c)?;
        let d = DVec2::new(l - t.x2.x, -t.x2.y);
        Some((t.w2.perp_dot(d), d.length()))
    }

    /// Point in water (camera frame) → camera ray direction (not unit).
    #[inline]
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let pc = (p - self.center).length();
        if !(pc > self.r2) {
            return Err(if pc <= self.r1 {
                NoSolution::InsideHousing
            } else {
                NoSolution::InsideGlass
            });
        }
        if self.is_centred() {
            return Ok(p);
        }
        let l = p.length();
        let e1 = p / l;
        let cperp = self.center - self.center.dot(e1) * e1;
        let c2 = cperp.length();
        if !(c2 > 1e-300) {
            // P on the dome axis: normal incidence everywhere, undeviated.
            return Ok(p);
        }
        let e2 = cperp / c2;
        let c = DVec2::new(self.center.dot(e1), c2);
        let tau = self.solve_tau(c, l)?;
        Ok(e1 + e2 * tau)
    }

    fn solve_tau(&self, c: DVec2, l: f64) -> Result<f64, NoSolution> {
        let bound = self.bracket;
        // Secant from the pinhole guess, with a Newton-like second point (slope ≈ −|P − X₂|).
        let (m0, dist0) = self
            .miss(0.0, c, l)
            .ok_or(NoSolution::TotalInternalReflection)?;
        if m0 == 0.0 {
            return Ok(0.0);
        }
        let (mut x0, mut f0) = (0.0, m0);
        let mut x1 = (m0 / dist0).clamp(-bound, bound);
        let mut ok = true;
        for _ in 0..40 {
            let Some((f1, _)) = self.miss(x1, c, l) else {
                ok = false;
                break;
            };
            if f1 == 0.0 {
                return Ok(x1);
            }
            let den = f1 - f0;
            if den == 0.0 {
                break;
            }
            let x2 = x1 - f1 * (x1 - x0) / den;
            if !(x2.is_finite() && x2.abs() <= bound) {
                ok = false;
                break;
            }
            let step = (x2 - x1).abs();
            x0 = x1;
            f0 = f1;
            x1 = x2;
            if step <= 1e-12 * (1.0 + x1.abs()) {
                // Secant error after this step ≈ C·e₁·e₀ ≪ 1e-15.
                return Ok(x1);
            }
        }
        let _ = ok;
        // Fallback (never needed in the tests; kept for safety): Illinois on the bracket.
        self.illinois(c, l, bound)
    }

    fn illinois(&self, c: DVec2, l: f64, bound: f64) -> Result<f64, NoSolution> {
        let f = |t: f64| self.miss(t, c, l).map(|m| m.0);
        let (mut a, mut b) = (-bound, bound);
        let (mut fa, mut fb) = match (f(a), f(b)) {
            (Some(x), Some(y)) => (x, y),
            _ => {
                // Shrink towards the pinhole until both ends trace.
                let mut s = bound;
                loop {
                    s *= 0.5;
                    if s < 1e-18 {
                        return Err(NoSolution::TotalInternalReflection);
                    }
                    if let (Some(x), Some(y)) = (f(-s), f(s)) {
                        a = -s;
                        b = s;
                        break (x, y);
                    }
                }
            }
        };
        if fa * fb > 0.0 {
            return Err(NoSolution::NoConvergence);
        }
        let mut side = 0;
        for _ in 0..200 {
            let x = (a * fb - b * fa) / (fb - fa);
            let fx = f(x).ok_or(NoSolution::TotalInternalReflection)?;
            if fx == 0.0 || (b - a).abs() <= 1e-16 * (1.0 + x.abs()) {
                return Ok(x);
            }
            if fx * fb > 0.0 {
                b = x;
                fb = fx;
                if side == -1 {
                    fa *= 0.5;
                }
                side = -1;
            } else {
                a = x;
                fa = fx;
                if side == 1 {
                    fb *= 0.5;
                }
                side = 1;
            }
        }
        Ok(0.5 * (a + b))
    }
}

/// Cylindrical port: coaxial cylinders about a line.
#[derive(Debug, Clone, Copy)]
pub struct CylinderPort {
    pub axis_point: DVec3,
    pub axis: DVec3,
    pub r1: f64,
    pub r2: f64,
    pub n_air: f64,
    pub n_glass: f64,
    pub n_water: f64,
    /// The entrance pupil lies on the axis (within 1e-13·R₁): meridional q-equation.
    on_axis: bool,
}

impl CylinderPort {
    pub fn new(
        axis_point: DVec3,
        axis: DVec3,
        inner_radius: f64,
        thickness: f64,
        n_air: f64,
        n_glass: f64,
        n_water: f64,
    ) -> Result<CylinderPort, String> {
        let a = axis
            .try_normalize()
            .ok_or("cylinder axis must be a non-zero vector")?;
        if !(inner_radius > 0.0
            && inner_radius.is_finite()
            && thickness >= 0.0
            && thickness.is_finite())
        {
            return Err("cylinder port needs inner radius > 0 and thickness ≥ 0".into());
        }
        if !axis_point.is_finite() {
            return Err("cylinder axis point must be finite".into());
        }
        // Re-anchor the axis point at the foot of the perpendicular from the pupil.
        let a0 = axis_point - axis_point.dot(a) * a;
        let off = a0.length();
        if off >= inner_radius {
            return Err(format!(
                "the camera's entrance pupil lies outside the cylinder (offset {off} m ≥ inner radius {inner_radius} m)"
            ));
        }
        if !(n_air > 0.0 && n_glass > 0.0 && n_water > 0.0) {
            return Err("indices must be positive".into());
        }
        Ok(CylinderPort {
            axis_point: a0,
            axis: a,
            r1: inner_radius,
            r2: inner_radius + thickness,
            n_air,
            n_glass,
            n_water,
            on_axis: off <= 1e-13 * inner_radius,
        })
    }

    /// Far intersection of `o + s w` with the cylinder of radius `r` (o inside).
    #[inline(always)]
    fn hit(&self, o: DVec3, w: DVec3, r: f64) -> Option<(DVec3, DVec3)> {
        let a = self.axis;
        let op = (o - self.axis_point) - (o - self.axis_point).dot(a) * a;
        let wp = w - w.dot(a) * a;
        let qa = wp.length_squared();
        if !(qa > 1e-30) {
            return None;
        }
        let b = op.dot(wp);
        let c0 = op.length_squared() - r * r;
        let disc = (b * b - qa * c0).max(0.0).sqrt();
        let s = if b > 0.0 {
            -c0 / (b + disc)
        } else {
            (disc - b) / qa
        };
        let x = o + w * s;
        let n = (op + wp * s) / r;
        Some((x, n))
    }

    /// Camera ray (unit, camera frame) → ray in water.
    #[inline]
    pub fn backward(&self, v: DVec3) -> Result<PortRay, NoSolution> {
        let (x1, n1) = self
            .hit(DVec3::ZERO, v, self.r1)
            .ok_or(NoSolution::MissesPort)?;
        let ci = n1.dot(v);
        let (w1, ct1) =
            refract(v, n1, self.n_air / self.n_glass).ok_or(NoSolution::TotalInternalReflection)?;
        let mut tr = fresnel_transmittance(self.n_air, self.n_glass, ci, ct1);
        let (x2, n2) = self.hit(x1, w1, self.r2).ok_or(NoSolution::MissesPort)?;
        let ci2 = n2.dot(w1);
        let (w2, ct2) = refract(w1, n2, self.n_glass / self.n_water)
            .ok_or(NoSolution::TotalInternalReflection)?;
        tr *= fresnel_transmittance(self.n_glass, self.n_water, ci2, ct2);
        Ok(PortRay {
            origin: x2,
            dir: w2,
            transmittance: tr,
        })
    }

    /// Point in water (camera frame) → camera ray direction (not unit).
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let a = self.axis;
        let rel = p - self.axis_point;
        let rho_v = rel - rel.dot(a) * a;
        let rho = a.cross(rel).length();
        if !(rho > self.r2) {
            return Err(if rho <= self.r1 {
                NoSolution::InsideHousing
            } else {
                NoSolution::InsideGlass
            });
        }
        if self.on_axis {
            let z = a.dot(p);
            let e_rho = rho_v / rho;
            let r = z.abs();
            if r == 0.0 {
                return Ok(e_rho);
            }
            let depth = rho - self.r2;
            let layers = [(self.r2 - self.r1, self.n_glass)];
            let qs = QSolve {
                na: self.n_air,
                gap: self.r1,
                layers: &layers,
                water: (depth, self.n_water),
            };
            let concave = self.n_glass >= self.n_air && self.n_water >= self.n_air;
            let q0 = if concave {
                r / (self.r1
                    + (self.r2 - self.r1) * self.n_air / self.n_glass
                    + depth * self.n_air / self.n_water)
            } else {
                0.0
            };
            let q = qs.solve(r, q0, concave)?;
            return Ok(e_rho + a * (q * z.signum()));
        }
        self.forward_skew(p)
    }

    /// Off-axis cylinder: rays are skew; 2-D Newton with a central-difference Jacobian on the
    /// direction offset (α, β) ⊥ P̂, residual = the miss vector of P from the water ray.
    fn forward_skew(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        // Start from the solution of the same cylinder with the pupil moved onto its axis
        // (exact for zero offset), then from the pinhole direction.
        let centred = CylinderPort {
            axis_point: DVec3::ZERO,
            on_axis: true,
            ..*self
        };
        let mut last = NoSolution::NoConvergence;
        if let Ok(g) = centred.forward(p - self.axis_point) {
            match self.newton_skew(p, g.normalize()) {
                Ok(d) => return Ok(d),
                Err(e) => last = e,
            }
        }
        self.newton_skew(p, p.normalize()).map_err(|e| {
            if e == NoSolution::NoConvergence {
                last
            } else {
                e
            }
        })
    }

    fn newton_skew(&self, p: DVec3, e0: DVec3) -> Result<DVec3, NoSolution> {
        let l = p.length();
        let u1 = e0.any_orthonormal_vector();
        let u2 = e0.cross(u1);
        let resid = |x: DVec2| -> Result<DVec2, NoSolution> {
            let v = (e0 + u1 * x.x + u2 * x.y).normalize();
            let ray = self.backward(v)?;
            let d = p - ray.origin;
            let m = d - ray.dir * d.dot(ray.dir);
            Ok(DVec2::new(m.dot(u1), m.dot(u2)) / l)
        };
        let mut x = DVec2::ZERO;
        let mut f = resid(x)?;
        for _ in 0..60 {
            let h = 1e-7;
            let fx1 = resid(x + DVec2::new(h, 0.0))?;
            let fx0 = resid(x - DVec2::new(h, 0.0))?;
            let fy1 = resid(x + DVec2::new(0.0, h))?;
            let fy0 = resid(x - DVec2::new(0.0, h))?;
            let jx = (fx1 - fx0) / (2.0 * h);
            let jy = (fy1 - fy0) / (2.0 * h);
            let det = jx.x * jy.y - jy.x * jx.y;
            if !(det.abs() > 1e-300) {
                return Err(NoSolution::NoConvergence);
            }
            let step = DVec2::new(jy.y * f.x - jy.x * f.y, jx.x * f.y - jx.y * f.x) / det;
            // Backtrack on failure (TIR / miss) or growth of the residual.
            let mut lam = 1.0;
            let (nx, nf) = loop {
                let cand = x - step * lam;
                match resid(cand) {
                    Ok(fc) if fc.length() <= f.length() || lam < 1e-3 => break (cand, fc),
                    _ => {
                        lam *= 0.5;
                        if lam < 1e-12 {
                            return Err(NoSolution::NoConvergence);
                        }
                    }
                }
            };
            let moved = (nx - x).length();
            x = nx;
            f = nf;
            if moved <= 1e-15 * (1.0 + x.length()) || f.length() <= 1e-17 {
                break;
            }
        }
        // Accept only a genuine solution: the full 3-D miss of P by the water ray (not just
        // its part across e0) is within 1e-12 of the distance.
        let v = (e0 + u1 * x.x + u2 * x.y).normalize();
        let ray = self.backward(v)?;
        let d = p - ray.origin;
        let miss = (d - ray.dir * d.dot(ray.dir)).length();
        if !(f.length() <= 1e-12 && miss <= 1e-12 * l && d.dot(ray.dir) > 0.0) {
            return Err(NoSolution::NoConvergence);
        }
        Ok(v)
    }
}

/// The port of one camera for one channel, ready to trace.
#[derive(Debug, Clone, Copy)]
pub enum PortSolver {
    /// No housing: the camera sits in the medium; rays are straight.
    None,
    Flat(FlatPort),
    Dome(DomePort),
    Cylinder(CylinderPort),
}

impl PortSolver {
    /// Build the solver for `port` at `channel` (0 = R, 1 = G, 2 = B), with the camera-side
    /// medium of index `n_air` and water index `n_water` (indices relative to air).
    pub fn new(
        port: &Port,
        channel: usize,
        n_air: f64,
        n_water: f64,
    ) -> Result<PortSolver, String> {
        let ch = channel.min(2);
        Ok(match port {
            Port::None => PortSolver::None,
            Port::Flat {
                normal,
                distance,
                thickness,
                glass,
            } => PortSolver::Flat(FlatPort::new(
                *normal,
                *distance,
                &[(*thickness, glass.ior[ch])],
                n_air,
                n_water,
            )?),
            Port::Dome {
                center,
                inner_radius,
                thickness,
                glass,
            } => PortSolver::Dome(DomePort::new(
                *center,
                *inner_radius,
                *thickness,
                n_air,
                glass.ior[ch],
                n_water,
            )?),
            Port::Cylinder {
                axis_point,
                axis,
                inner_radius,
                thickness,
                glass,
            } => PortSolver::Cylinder(CylinderPort::new(
                *axis_point,
                *axis,
                *inner_radius,
                *thickness,
                n_air,
                glass.ior[ch],
                n_water,
            )?),
        })
    }

    /// Camera ray (unit, camera frame, from the pupil) → ray in water.
    #[inline]
    pub fn backward(&self, v: DVec3) -> Result<PortRay, NoSolution> {
        match self {
            PortSolver::None => Ok(PortRay {
                origin: DVec3::ZERO,
                dir: v,
                transmittance: 1.0,
            }),
            PortSolver::Flat(f) => f.backward(v),
            PortSolver::Dome(d) => d.backward(v),
            PortSolver::Cylinder(c) => c.backward(v),
        }
    }

    /// Point in water (camera frame) → camera ray direction (not unit).
    #[inline]
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        match self {
            PortSolver::None => {
                if p == DVec3::ZERO {
                    Err(NoSolution::InsideHousing)
                } else {
                    Ok(p)
                }
            }
            PortSolver::Flat(f) => f.forward(p),
            PortSolver::Dome(d) => d.forward(p),
            PortSolver::Cylinder(c) => c.forward(p),
        }
    }
}
