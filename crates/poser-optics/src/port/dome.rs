//! The dome port ([`DomePort`]): two concentric spheres, possibly decentred; Halley on the
//! moment equation, bracketed Illinois as fallback.

use super::PortRay;
use super::housing::{
    Face, Housing, HousingMesh, HousingShell, MESH_SEGMENTS, Part, Shape, TaggedMesh,
    border_directions, border_rays, field_directions, revolve,
};
use crate::NoSolution;
use crate::interface::{fresnel_transmittance, refract};
use crate::lanes::Lane;
use crate::types::{Camera, Pose};
use glam::{DMat3, DVec2, DVec3};

#[derive(Debug, Clone, Copy)]
pub struct DomePort {
    pub center: DVec3,
    pub r1: f64,
    pub r2: f64,
    pub n_air: f64,
    pub n_glass: f64,
    pub n_water: f64,
    /// |C|; below `1e-13·R₁` the dome is treated as centred (pinhole; error < 1e-10 px).
    pub(super) ecc: f64,
    /// tan(asin(|C|/R₁)): half-width of the guaranteed bracket on τ.
    pub(super) bracket: f64,
    /// Moment constants: the sines of the four refraction angles are `p·k[i]` for the signed
    /// distance p of the camera ray from C (k = 1/R₁, (na/ng)/R₁, (na/ng)/R₂, (na/nw)/R₂).
    pub(super) k: [f64; 4],
    /// na/nw: the water ray's moment about C is `na/nw` times the camera ray's.
    pub(super) kw: f64,
    /// dΘ/dp at p = 0 (Θ = total turning of the ray), for the first-order guess.
    pub(super) dtheta0: f64,
}

/// One step of [`DomePort::moment_step`].
pub(super) struct MomentStep<T: Lane> {
    pub(super) step: T,
    pub(super) halley: T::Mask,
    /// A refraction angle has no cosine: total internal reflection, or grazing a sphere.
    pub(super) tir: T::Mask,
    /// u turned by atan(step), not yet unit.
    pub(super) v: (T, T),
}

/// Outcome of tracing one 2-D dome ray.
#[derive(Debug, Clone, Copy)]
pub(super) struct DomeTrace {
    pub(super) x2: DVec2,
    pub(super) w2: DVec2,
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
        let r2 = inner_radius + thickness;
        let k = [
            1.0 / inner_radius,
            n_air / n_glass / inner_radius,
            n_air / n_glass / r2,
            n_air / n_water / r2,
        ];
        Ok(DomePort {
            k,
            kw: n_air / n_water,
            dtheta0: -k[0] + k[1] - k[2] + k[3],
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
    pub(super) fn is_centred(&self) -> bool {
        self.ecc <= 1e-13 * self.r1
    }

    /// Far intersection from inside a sphere: ray `o + s·w` (w unit), `oc = o − C`,
    /// `c0 = |oc|² − R²` (< 0). Stable root form.
    #[inline(always)]
    pub(super) fn far_root(b: f64, c0: f64) -> f64 {
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
    pub(super) fn trace2(&self, tau: f64, c: DVec2) -> Option<DomeTrace> {
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
    pub(super) fn miss(&self, tau: f64, c: DVec2, l: f64) -> Option<(f64, f64)> {
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
        // The plane (O, C, P): e₁ = P/L, e₂ along C's component ⊥ P, C = (c.x, c.y) there.
        // c.y = |C × P|/L needs no cancellation, and both √ run side by side.
        let l = p.length();
        let c = DVec2::new(self.center.dot(p) / l, self.center.cross(p).length() / l);
        if !(c.y > 1e-300) {
            // P on the dome axis: normal incidence everywhere, undeviated.
            return Ok(p);
        }
        // The basis is needed only for the answer, off the solver's critical path.
        let basis = || {
            let e1 = p / l;
            (e1, (self.center - e1 * c.x) / c.y)
        };
        if let Some(u) = self.halley(c, l) {
            let (e1, e2) = basis();
            return Ok(e1 * u.x + e2 * u.y);
        }
        let tau = self.solve_tau(c, l)?;
        let (e1, e2) = basis();
        Ok(e1 + e2 * tau)
    }

    /// Fast path: Halley's method on the moment equation, from a first-order guess. In the
    /// plane (O, C, P) with P = (L, 0) and C = c, a camera ray of unit direction u has the
    /// signed moment p = (O − C) × u about C. At a sphere centred on C, n·(X − C) × w is
    /// conserved (the normal is radial), so the glass and water rays have moments
    /// (na/ng)·p and (na/nw)·p, the sines of the four refraction angles are p·kᵢ, and the
    /// water ray is u turned by Θ(p) = −asin(p/R₁) + asin(p·na/(ng R₁)) −
    /// asin(p·na/(ng R₂)) + asin(p·na/(nw R₂)), exactly, with no intersection to compute. P lies on the water
    /// ray iff m = (P − C) × w − (na/nw)·p = 0. m, m′ and m″ with respect to the rotation
    /// angle of u are analytic. Returns the unit camera direction (u₁ along P, u₂ along
    /// C⊥), or `None` (then the bracketed solver decides).
    #[inline]
    pub(super) fn halley(&self, c: DVec2, l: f64) -> Option<DVec2> {
        self.halley_counted(c, l).map(|(u, _)| u)
    }

    /// [`DomePort::halley`] and the number of evaluations of m it took.
    #[inline(always)]
    pub(super) fn halley_counted(&self, c: DVec2, l: f64) -> Option<(DVec2, u32)> {
        let pc = DVec2::new(l - c.x, -c.y);
        let (num, den) = self.guess((c.x, c.y), (pc.x, pc.y));
        if !(den > 0.0 && num.abs() <= self.bracket * den) {
            return None;
        }
        let mut u = DVec2::new(den, num) * (1.0 / (den * den + num * num).sqrt());
        for evals in 1..=16 {
            let m = self.moment_step((c.x, c.y), (pc.x, pc.y), (u.x, u.y));
            let (step, halley) = (m.step, m.halley);
            if m.tir || !step.is_finite() {
                return None; // total internal reflection (or grazing a sphere)
            }
            // u turned by atan(step), not yet unit.
            let v = DVec2::new(m.v.0, m.v.1);
            if step.abs() <= if halley { 5e-6 } else { 1e-8 } {
                // Converged: v is the direction (|v| = 1 + O(step²) is irrelevant to it).
                // Inside the guaranteed bracket, in front of the camera.
                return (v.x > 0.0 && v.y.abs() <= self.bracket * v.x).then_some((v, evals));
            }
            u = v * Self::unit_scale(step, v);
        }
        None
    }

    /// The first-order guess (small angles, Θ ≈ Θ′(0)·p) as the slope num/den of the camera
    /// ray in the plane, C = `c`, P − C = `pc` (u = (den, num)/|(den, num)| needs no ÷).
    #[inline(always)]
    pub(super) fn guess<T: Lane>(&self, c: (T, T), pc: (T, T)) -> (T, T) {
        let k0 = self.dtheta0;
        (
            -c.1 * (pc.0 * k0 + 1.0 - self.kw),
            pc.0 * (T::splat(1.0) - c.0 * k0) + c.0 * self.kw,
        )
    }

    /// One Halley (or Newton) step on the moment equation from the unit camera direction
    /// `u`, on one value or on SIMD lanes ([`Lane`]) with the same operations.
    #[inline(always)]
    pub(super) fn moment_step<T: Lane>(&self, c: (T, T), pc: (T, T), u: (T, T)) -> MomentStep<T> {
        let (k, kw) = (self.k, self.kw);
        let one = T::splat(1.0);
        let p = c.1 * u.0 - c.0 * u.1;
        let s = [p * k[0], p * k[1], p * k[2], p * k[3]];
        let co2 = [
            one - s[0] * s[0],
            one - s[1] * s[1],
            one - s[2] * s[2],
            one - s[3] * s[3],
        ];
        let zero = T::splat(0.0);
        let tir = !T::all4([
            zero.lt(co2[0]),
            zero.lt(co2[1]),
            zero.lt(co2[2]),
            zero.lt(co2[3]),
        ]);
        let co = [co2[0].sqrt(), co2[1].sqrt(), co2[2].sqrt(), co2[3].sqrt()];
        // Rotation by Θ: conj(A₁)·B₁·conj(A₂)·B₂ with A, B = (cos, sin) of each angle.
        let z1 = (co[0] * co[1] + s[0] * s[1], co[0] * s[1] - s[0] * co[1]);
        let z2 = (co[2] * co[3] + s[2] * s[3], co[2] * s[3] - s[2] * co[3]);
        let z = (z1.0 * z2.0 - z1.1 * z2.1, z1.0 * z2.1 + z1.1 * z2.0);
        let w = (z.0 * u.0 - z.1 * u.1, z.0 * u.1 + z.1 * u.0);
        let cr = pc.0 * w.1 - pc.1 * w.0;
        let dt = pc.0 * w.0 + pc.1 * w.1;
        let m = cr - p * kw;
        // Θ′(p) = Σ ±kᵢ/cosᵢ and Θ″(p) = Σ ±kᵢ³ p/cosᵢ³.
        let inv = [one / co[0], one / co[1], one / co[2], one / co[3]];
        let th1 = inv[0] * -k[0] + inv[1] * k[1] - inv[2] * k[2] + inv[3] * k[3];
        let cube = |i: usize| inv[i] * (k[i] * k[i] * k[i]) * inv[i] * inv[i];
        let th2 = p * (-cube(0) + cube(1) - cube(2) + cube(3));
        let dp = -(c.0 * u.0 + c.1 * u.1); // p′; p″ = −p
        let g = th1 * dp + 1.0;
        let dm = dt * g - dp * kw;
        let d2m = -cr * g * g + dt * (th2 * dp * dp - th1 * p) + p * kw;
        // Halley (cubic, error constant ≈ 0.6 here: a step ≤ 5e-6 leaves ≲ 1e-16 rad);
        // Newton (error constant ≈ 0.1: a step ≤ 1e-8 leaves ≲ 1e-17) when far.
        let halley = (m * d2m).abs().lt(dm * 0.5 * dm);
        let step =
            T::select(halley, m * -2.0 * dm, -m) / T::select(halley, dm * 2.0 * dm - m * d2m, dm);
        MomentStep {
            step,
            halley,
            tir,
            v: (u.0 + -u.1 * step, u.1 + u.0 * step),
        }
    }

    /// 1/|v| for v = u + u⊥·step with |u| = 1, i.e. 1/√(1 + step²): by its series where
    /// |step| ≤ 1e-3 (the next term, 5·step⁶/16 ≤ 3e-19, is below half an ulp), which keeps
    /// a √ and a ÷ off the solver's critical path; else from v.
    #[inline(always)]
    pub(super) fn unit_scale(step: f64, v: DVec2) -> f64 {
        if step.abs() <= 1e-3 {
            let s2 = step * step;
            1.0 - s2 * (0.5 - 0.375 * s2)
        } else {
            1.0 / v.length()
        }
    }

    pub(super) fn solve_tau(&self, c: DVec2, l: f64) -> Result<f64, NoSolution> {
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

    pub(super) fn illinois(&self, c: DVec2, l: f64, bound: f64) -> Result<f64, NoSolution> {
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

/// Why a dome port has no housing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HousingError {
    /// The radius or the thickness is not positive.
    NotPositive,
    /// The entrance pupil lies `decentring` m from the centre, outside the inner sphere.
    PupilOutside { decentring: f64, inner_radius: f64 },
}

impl std::fmt::Display for HousingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HousingError::NotPositive => {
                write!(f, "the dome port needs a positive radius and thickness")
            }
            HousingError::PupilOutside {
                decentring,
                inner_radius,
            } => write!(
                f,
                "the dome's centre is {decentring:.4} m from the entrance pupil, outside its \
                 inner radius {inner_radius} m"
            ),
        }
    }
}

/// A dome port's housing: the inner and outer spheres (whole) and a black disk across the
/// inner sphere behind the pupil and the glass the field of view uses (its rim at the field
/// angle + 15°, 60°..170° from the axis). Without the disk, light the glass reflects back
/// into the housing would cross the spheres' back halves to the water and the sky.
pub fn housing(cam: &Camera, center: DVec3, r: f64, t: f64) -> Result<Housing, HousingError> {
    if !(r > 0.0) || !(t > 0.0) {
        return Err(HousingError::NotPositive);
    }
    if center.length() >= r {
        return Err(HousingError::PupilOutside {
            decentring: center.length(),
            inner_radius: r,
        });
    }
    let max_field = border_rays(cam)
        .iter()
        .map(|d| d.z.clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max);
    let alpha = (max_field + 15f64.to_radians()).clamp(60f64.to_radians(), 170f64.to_radians());
    let z_back = (center.z + r * alpha.cos()).min(0.0) - 0.01 * r;
    let rho = (r * r - (z_back - center.z).powi(2)).max(0.0).sqrt() * (1.0 - 1e-6);
    let parts = vec![
        Part::new(
            Face::Inner {
                glass_inside: false,
            },
            Shape::Sphere { center, radius: r },
        )
        .labelled("dome port", "inner sphere (air inside | glass)"),
        Part::new(
            Face::Outer,
            Shape::Sphere {
                center,
                radius: r + t,
            },
        )
        .labelled("dome port", "outer sphere (glass inside | water)"),
        Part::new(
            Face::Wall,
            Shape::Disk {
                centre: DVec3::new(center.x, center.y, z_back),
                normal: DVec3::Z,
                radius: rho,
            },
        )
        .labelled("housing", "black disk behind the dome"),
    ];
    Ok(Housing {
        parts,
        clearance: r - center.length(),
        extent: center.length() + r + t,
    })
}

/// Polar and azimuthal segments of [`housing_shell`]'s spherical caps: fine enough that
/// Cycles' smooth shading of the facets (with the sphere's exact normals) stays on the sphere.
const SHELL_RINGS: u32 = 96;
const SHELL_SEGMENTS: u32 = 384;

/// A dome port's closed housing for a mesh renderer ([`HousingShell`]): the outer sphere as a
/// cap about +z over the field of view seen from the pupil + 15° (at least 60°, at most 170°),
/// a cylindrical body from its rim back to behind the pupil (half the outer radius, at least
/// 2 cm), closed by a disk; the inner face is the inner sphere's cap of the same angle.
pub fn housing_shell(cam: &Camera, center: DVec3, r: f64, t: f64) -> HousingShell {
    let r_out = r + t;
    let field = field_directions(cam, 8)
        .iter()
        .map(|d| d.z.clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max);
    let alpha = (field + 15f64.to_radians())
        .max(60f64.to_radians())
        .min(170f64.to_radians());
    let (mut shell, rim) = sphere_cap(center, r_out, alpha, true, Face::Outer);
    let rim_z = center.z + r_out * alpha.cos();
    let rim_r = r_out * alpha.sin();
    let back_z = rim_z.min(0.0) - (0.5 * r_out).max(0.02);
    let base = shell.positions.len() as u32;
    let normals = shell.normals.get_or_insert_with(Vec::new);
    for j in 0..SHELL_SEGMENTS {
        let phi = std::f64::consts::TAU * j as f64 / SHELL_SEGMENTS as f64;
        let radial = DVec3::new(phi.cos(), phi.sin(), 0.0);
        shell
            .positions
            .push(DVec3::new(center.x, center.y, back_z) + rim_r * radial);
        normals.push(radial);
    }
    for j in 0..SHELL_SEGMENTS {
        let k = (j + 1) % SHELL_SEGMENTS;
        shell.push(
            vec![rim[j as usize], base + j, base + k, rim[k as usize]],
            Face::Wall,
        );
    }
    shell.push(
        (0..SHELL_SEGMENTS).rev().map(|j| base + j).collect(),
        Face::Wall,
    );
    let (inner, _) = sphere_cap(center, r, alpha, false, Face::Inner { glass_inside: true });
    HousingShell { shell, inner }
}

/// The cap of the sphere (`center`, `radius`) about +z, polar angle 0..`alpha`: the pole, then
/// [`SHELL_RINGS`] rings of [`SHELL_SEGMENTS`] vertices, each polygon tagged `tag`, with the
/// sphere's normals (outward, or inward and the polygons reversed). Also the last ring's
/// vertex indices (the rim).
fn sphere_cap(
    center: DVec3,
    radius: f64,
    alpha: f64,
    outward: bool,
    tag: Face,
) -> (TaggedMesh, Vec<u32>) {
    let (rings, seg) = (SHELL_RINGS, SHELL_SEGMENTS);
    let mut dirs = vec![DVec3::Z];
    for i in 1..=rings {
        let theta = alpha * i as f64 / rings as f64;
        for j in 0..seg {
            let phi = std::f64::consts::TAU * j as f64 / seg as f64;
            dirs.push(DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ));
        }
    }
    let sign = if outward { 1.0 } else { -1.0 };
    let mut m = TaggedMesh {
        positions: dirs.iter().map(|&d| center + radius * d).collect(),
        normals: Some(dirs.iter().map(|&d| sign * d).collect()),
        ..TaggedMesh::default()
    };
    let mut push = |mut f: Vec<u32>| {
        if !outward {
            f.reverse();
        }
        m.push(f, tag);
    };
    for j in 0..seg {
        push(vec![0, 1 + j, 1 + (j + 1) % seg]);
    }
    for i in 1..rings {
        let (r0, r1) = (1 + (i - 1) * seg, 1 + i * seg);
        for j in 0..seg {
            let k = (j + 1) % seg;
            push(vec![r0 + j, r1 + j, r1 + k, r0 + k]);
        }
    }
    let rim = (0..seg).map(|j| 1 + (rings - 1) * seg + j).collect();
    (m, rim)
}

/// A dome port's glass as a spherical cap shell, for display: the cap covers the field of
/// view seen from the dome's centre, + 10°; at least a hemisphere, at most 175°.
pub fn housing_mesh(cam: &Camera, center: DVec3, r: f64, t: f64) -> HousingMesh {
    let mut cap = std::f64::consts::FRAC_PI_2;
    for d in &border_directions(cam) {
        let b = d.dot(center);
        let disc = b * b - center.length_squared() + r * r;
        if disc >= 0.0 {
            let p = *d * (b + disc.sqrt()) - center;
            cap = cap.max(p.normalize().z.clamp(-1.0, 1.0).acos() + 10f64.to_radians());
        }
    }
    let cap = cap.min(175f64.to_radians());
    let k = 24;
    let mut profile = Vec::with_capacity(2 * k + 2);
    for i in 0..=k {
        let a = cap * i as f64 / k as f64;
        profile.push(((r + t) * a.sin(), (r + t) * a.cos()));
    }
    for i in (0..=k).rev() {
        let a = cap * i as f64 / k as f64;
        profile.push((r * a.sin(), r * a.cos()));
    }
    if let Some(p) = profile.first_mut() {
        p.0 = 0.0;
    }
    if let Some(p) = profile.last_mut() {
        p.0 = 0.0;
    }
    revolve(&profile, false, MESH_SEGMENTS).transformed(&Pose {
        rotation: DMat3::IDENTITY,
        translation: center,
    })
}
