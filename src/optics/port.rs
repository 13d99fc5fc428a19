//! Housing ports: exact backward (camera ray → ray in water) and forward (point in water →
//! camera ray) refraction, per channel indices (n_air, n_glass, n_water).
//!
//! | port | parameters (camera frame, metres) | forward solver |
//! |---|---|---|
//! | [`FlatPort`] | unit normal N (camera → water), inner-face distance d ≥ 0, glass layers (thickness, index)… | Halley on the scalar q-equation in ratio form t = q/r, from the water-unit guess (≤ 2 evaluations on ordinary points; no bracket needed when every n ≥ n_air; safeguarded Newton–bisection otherwise) |
//! | [`DomePort`] | centre C (|C| < R₁), inner radius R₁, thickness t | Halley on the exact moment equation in the plane (O, C, P) from the first-order guess; bracketed secant/Illinois inside ±asin(|C|/R₁) as fallback; pinhole when centred |
//! | [`CylinderPort`] | axis point, unit axis, inner radius, thickness | on its axis: the flat q-equation in the meridional plane; off it: 2-D Newton (skew rays) from two starts, then continuation in the decentring |
//!
//! [`PortSolver::forward_many`] (in `port/batch.rs`) solves [`LANES`] points at a time in SIMD
//! lanes, AVX2 where the CPU has it: the same results bit for bit as [`PortSolver::forward`],
//! at 2.5–3.5 times its throughput.
//!
//! All ports share the conventions of Refractive COLMAP (`docs/optics.md` §1.1). The backward
//! transmittance is the product of the unpolarised Fresnel transmittances of every interface
//! (no n² radiance factor; see docs/render-conventions.md §3.4 for that).
//!
//! Failure is explicit ([`NoSolution`]), never NaN: a point inside the housing or glass, behind
//! the camera, beyond the critical angle, a camera ray that misses the port or is totally
//! internally reflected, or (never seen, but guarded) a solver that does not converge.

use super::NoSolution;
use super::interface::{fresnel_transmittance, refract};
use super::lanes::Lane;
use super::reference::{Dd, V3};
use super::types::Port;
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
    /// The q-equation's per-port constants.
    slabs: Slabs,
    /// The same in double-double, for refining ill-conditioned roots.
    dd: FlatDd,
}

/// One Newton or Halley step of the q-equation in ratio form: the step, whether it is
/// Halley's, and the slope G′(t) as a fraction (numerator, denominator > 0).
#[derive(Debug, Clone, Copy)]
struct Step {
    dt: f64,
    halley: bool,
    slope: (f64, f64),
}

/// The flat port's answer N + t·P⊥ carries a relative error of about κ·c·ε in its slope,
/// where κ = 1/(t·G′(t)) = r/(q·F′(q)) is the condition number of the root (the relative
/// change of q per relative change of r, which amplifies f64 rounding in G) and
/// c = (|N_z| + |t·P⊥_z|)/|N_z + t·P⊥_z| the cancellation in the direction's z (1 for an
/// untilted port). A pixel at distance ρ from the principal point then moves by ≈ 2κ·c·ε·ρ
/// (measured on the test ports), so where κ·c exceeds this bound (< 1e-9 px out to 1e5 px)
/// the answer is refined in double-double ([`FlatPort::refine`]): near grazing with no
/// camera-side gap, or deep behind a tilted port. κ·c ≈ 1 on ordinary points.
const REFINE_AT: f64 = 16.0;

/// Scalar q-equation for parallel layers (`docs/optics.md` §1.3) with every per-port constant
/// precomputed once: the camera-side gap (index `na`), up to [`MAX_LAYERS`] glass layers, and
/// the water (index `nw`), whose depth D is the only per-point parameter besides r.
///
/// `F(q) = gap·q + Σᵢ tᵢ·na·q/√(nᵢ² + (nᵢ² − na²)q²) + D·na·q/√(nw² + (nw² − na²)q²) − r`.
#[derive(Debug, Clone, Copy)]
struct Slabs {
    na: f64,
    gap: f64,
    n: usize,
    /// Per glass layer: tᵢ·na, nᵢ², nᵢ² − na².
    tna: [f64; MAX_LAYERS],
    n2: [f64; MAX_LAYERS],
    k: [f64; MAX_LAYERS],
    /// Water: na, nw, nw², nw² − na².
    nw: f64,
    nw2: f64,
    kw: f64,
    /// Every index ≥ na: F is concave and increasing (no bracket needed).
    concave: bool,
    /// gap + Σ tᵢ·na/nᵢ (paraxial optical length of the port, camera-medium units).
    parax: f64,
    /// (gap·nw/na + Σ tᵢ·nw/nᵢ): the port in paraxial water units (first guess of tan θw).
    water_units: f64,
    /// Σ tᵢ·na/√(nᵢ² − na²) when every nᵢ > na (the layers' asymptote as q → ∞), else ∞.
    asym: f64,
    /// na/√(nw² − na²): the limit of tan θw as q → ∞ (∞ when nw ≤ na).
    tw_inf: f64,
    /// Largest q at which every term is defined (q < n/√(na²−n²) for layers with n < na),
    /// ignoring the water.
    q_max_layers: f64,
}

impl Slabs {
    fn new(na: f64, gap: f64, layers: &[(f64, f64)], nw: f64) -> Slabs {
        let mut s = Slabs {
            na,
            gap,
            n: layers.len(),
            tna: [0.0; MAX_LAYERS],
            n2: [1.0; MAX_LAYERS],
            k: [0.0; MAX_LAYERS],
            nw,
            nw2: nw * nw,
            kw: nw * nw - na * na,
            concave: nw >= na && layers.iter().all(|&(_, n)| n >= na),
            parax: gap + layers.iter().map(|&(t, n)| t * na / n).sum::<f64>(),
            water_units: gap * nw / na + layers.iter().map(|&(t, n)| t * nw / n).sum::<f64>(),
            asym: 0.0,
            tw_inf: if nw > na {
                na / (nw * nw - na * na).sqrt()
            } else {
                f64::INFINITY
            },
            q_max_layers: f64::INFINITY,
        };
        for (i, &(t, n)) in layers.iter().enumerate() {
            s.tna[i] = t * na;
            s.n2[i] = n * n;
            s.k[i] = n * n - na * na;
            s.asym += if n > na {
                t * na / (n * n - na * na).sqrt()
            } else if t > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            if n < na && t > 0.0 {
                s.q_max_layers = s.q_max_layers.min(n / (na * na - n * n).sqrt());
            }
        }
        s
    }

    /// One term t·na·q/√(n² + k q²) with its first and second derivatives.
    #[inline(always)]
    fn term2(tna: f64, n2: f64, k: f64, q: f64) -> (f64, f64, f64) {
        let g = n2 + k * q * q;
        let inv = 1.0 / g.sqrt();
        let inv2 = inv * inv;
        let v = tna * q * inv;
        let dv = tna * n2 * inv2 * inv;
        (v, dv, -3.0 * k * q * dv * inv2)
    }

    /// F, F′ and F″ at q for water depth `depth`.
    #[inline(always)]
    fn eval2(&self, q: f64, r: f64, depth: f64) -> (f64, f64, f64) {
        let (mut f, mut df, mut d2f) = Self::term2(depth * self.na, self.nw2, self.kw, q);
        f += self.gap * q - r;
        df += self.gap;
        for i in 0..self.n {
            let (v, d, d2) = Self::term2(self.tna[i], self.n2[i], self.k[i], q);
            f += v;
            df += d;
            d2f += d2;
        }
        (f, df, d2f)
    }

    /// G(t) = F(r·t)/r, G′ = F′(q) and G″ = r·F″(q) at the ratio t = q/r, from r² only; on
    /// one value (`f64`) or on SIMD lanes ([`Lane`]), with the same operations either way.
    #[inline(always)]
    fn eval2_ratio<T: Lane>(&self, t: T, r2: T, depth: T) -> (T, T, T) {
        #[inline(always)]
        fn term<T: Lane>(tna: T, n2: f64, k: f64, t: T, r2: T) -> (T, T, T) {
            let kr2 = r2 * k;
            let g = kr2 * t * t + n2;
            let inv = T::splat(1.0) / g.sqrt();
            let inv2 = inv * inv;
            let dv = tna * n2 * inv2 * inv;
            (tna * t * inv, dv, kr2 * -3.0 * t * dv * inv2)
        }
        let (mut f, mut df, mut d2f) = term(depth * self.na, self.nw2, self.kw, t, r2);
        f = f + (t * self.gap - 1.0);
        df = df + self.gap;
        for i in 0..self.n {
            let (v, d, d2) = term(T::splat(self.tna[i]), self.n2[i], self.k[i], t, r2);
            f = f + v;
            df = df + d;
            d2f = d2f + d2;
        }
        (f, df, d2f)
    }

    /// The Halley step from G, G′, G″ while its denominator 2G′² − G·G″ stays above G′²/2
    /// (then the step is at most 4 Newton steps), else the Newton step, as (numerator,
    /// denominator, Halley?).
    #[inline(always)]
    fn halley_parts<T: Lane>(f: T, df: T, d2f: T) -> (T, T, T::Mask) {
        let halley = (f * d2f).abs().lt(df * 1.5 * df);
        (
            T::select(halley, f * -2.0 * df, -f),
            T::select(halley, df * 2.0 * df - f * d2f, df),
            halley,
        )
    }

    /// [`Slabs::halley_parts`] as a [`Step`].
    #[inline(always)]
    fn halley_step(f: f64, df: f64, d2f: f64) -> Step {
        let (num, den, halley) = Self::halley_parts(f, df, d2f);
        Step {
            dt: num / den,
            halley,
            slope: (df, 1.0),
        }
    }

    /// [`Slabs::halley_parts`] for exactly one glass layer with a single division: with
    /// s_g, s_w the two square roots and P = s_g·s_w, H₀ = G·P, H₁ = G′·P³ and H₂ = G″·P⁵ are
    /// polynomials in s_g, s_w, and the Halley step is −2H₀H₁P²/(2H₁² − H₀H₂) (Newton:
    /// −H₀P²/H₁). Returns (numerator, denominator, Halley?, slope G′ = H₁/P³).
    #[inline(always)]
    fn one_layer_parts<T: Lane>(&self, t: T, r2: T, depth: T) -> (T, T, T::Mask, (T, T)) {
        let (ag, n2g, kg) = (self.tna[0], self.n2[0], self.k[0]);
        let aw = depth * self.na;
        let (n2w, kw) = (self.nw2, self.kw);
        let tt = t * t;
        let a = (r2 * kg * tt + n2g).sqrt();
        let b = (r2 * kw * tt + n2w).sqrt();
        let p = a * b;
        let (a2, b2) = (a * a, b * b);
        let (a3, b3) = (a2 * a, b2 * b);
        let h0 = (t * self.gap - 1.0) * p + t * ag * b + aw * t * a;
        let h1 = p * self.gap * p * p + b3 * (ag * n2g) + aw * n2w * a3;
        let h2 = r2 * -3.0 * t * (b3 * (ag * kg * n2g) * b2 + aw * kw * n2w * a3 * a2);
        let p2 = p * p;
        let halley = (h0 * h2).abs().lt(h1 * 1.5 * h1);
        (
            T::select(halley, h0 * -2.0 * h1 * p2, -h0 * p2),
            T::select(halley, h1 * 2.0 * h1 - h0 * h2, h1),
            halley,
            (h1, p2 * p),
        )
    }

    /// [`Slabs::one_layer_parts`] as a [`Step`]; falls back to the per-term form if the
    /// polynomial form overflows (q ≳ 1e25).
    #[inline(always)]
    fn step_one_layer(&self, t: f64, r2: f64, depth: f64) -> Step {
        let (num, den, halley, slope) = self.one_layer_parts(t, r2, depth);
        let dt = num / den;
        if dt.is_finite() {
            Step { dt, halley, slope }
        } else {
            let (f, df, d2f) = self.eval2_ratio(t, r2, depth);
            Self::halley_step(f, df, d2f)
        }
    }

    /// Solve F(q) = 0 for the ratio t = q/r ≥ 0 (q = tan of the camera-side angle to the port
    /// normal, r = distance of the point from the port axis), given r² (> 0) and the water
    /// depth. Working with t needs no √ for r and keeps r → 0 exact (t → 1/F′(0)).
    #[inline]
    fn solve_ratio(&self, r2: f64, depth: f64) -> Result<f64, NoSolution> {
        self.solve_ratio_counted(r2, depth).map(|(t, _, _)| t)
    }

    /// [`Slabs::solve_ratio`], the number of evaluations of F it took (0 off the fast path),
    /// and the slope G′ at the last evaluation as (numerator, denominator > 0) ((∞, 1) off
    /// the fast path: the bracketed solver does not refine).
    #[inline(always)]
    fn solve_ratio_counted(
        &self,
        r2: f64,
        depth: f64,
    ) -> Result<(f64, u32, (f64, f64)), NoSolution> {
        if !self.concave {
            let r = r2.sqrt();
            return self
                .solve_bracketed(r, depth)
                .map(|q| (q / r, 0, (f64::INFINITY, 1.0)));
        }
        // F is bounded by its asymptote gap·q + Σ tᵢ Tᵢ + D·T_w: with no camera-side gap no
        // ray reaches points beyond it.
        let asym = self.asym + depth * self.tw_inf;
        if self.gap == 0.0 && asym * asym <= r2 {
            return Err(NoSolution::BeyondCriticalAngle);
        }
        // First guess. Ordinary points: the water dominates, so guess x = tan θw from the port
        // in paraxial water units, x = r/A with A = D + Σ tᵢ·nw/nᵢ, and map it exactly to
        // q = nw·x/√(na² − (nw² − na²)x²), i.e. t = nw/√(na²A² − (nw² − na²)r²) (exact for an
        // infinitely thin port). Near grazing (x close to its limit T_w): the larger of the
        // two lower bounds of the root, the paraxial q and the asymptote (r − Σ tᵢTᵢ − D·T_w)/gap.
        let big_a = depth + self.water_units;
        let lim = 0.9 * self.tw_inf * big_a;
        let t0 = if r2 < lim * lim {
            self.nw / (self.na * self.na * big_a * big_a - self.kw * r2).sqrt()
        } else {
            let parax = 1.0 / (self.parax + depth * self.na / self.nw);
            if self.gap > 0.0 {
                let r = r2.sqrt();
                parax.max((r - asym) / (self.gap * r))
            } else {
                parax
            }
        };
        // Halley (cubic; error constant < 0.4 on the benchmark sets, so a relative step
        // ≤ 1e-5 leaves an error ≲ 1e-15·q) while its denominator 2F′² − F·F″ stays above
        // F′²/2 (the step is then at most 4 Newton steps); plain Newton otherwise (far from
        // the root), where a step ≤ 1e-8 leaves ≲ 1e-16·q.
        let mut t = t0;
        for evals in 1..=200 {
            let Step { dt, halley, slope } = if self.n == 1 {
                self.step_one_layer(t, r2, depth)
            } else {
                let (f, df, d2f) = self.eval2_ratio(t, r2, depth);
                Self::halley_step(f, df, d2f)
            };
            if !dt.is_finite() {
                return Err(NoSolution::NoConvergence);
            }
            let next = t + dt;
            t = if next > 0.0 { next } else { 0.5 * t };
            if dt.abs() <= if halley { 1e-5 } else { 1e-8 } * t {
                return if t.is_finite() {
                    Ok((t, evals, slope))
                } else {
                    Err(NoSolution::BeyondCriticalAngle)
                };
            }
        }
        Err(NoSolution::NoConvergence)
    }

    /// F and F′ (for the bracketed solver).
    #[inline]
    fn eval(&self, q: f64, r: f64, depth: f64) -> (f64, f64) {
        let (f, df, _) = self.eval2(q, r, depth);
        (f, df)
    }

    /// Some layer is optically thinner than the camera medium: F → ∞ at q_max.
    /// Safeguarded Newton on [lo, hi].
    #[cold]
    fn solve_bracketed(&self, r: f64, depth: f64) -> Result<f64, NoSolution> {
        let mut hi = self.q_max_layers;
        if self.nw < self.na && depth > 0.0 {
            hi = hi.min(self.nw / (self.na * self.na - self.nw2).sqrt());
        }
        let mut lo: f64 = 0.0;
        let mut q = 0.0f64.min(0.5 * hi);
        for _ in 0..400 {
            let (f, df) = self.eval(q, r, depth);
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
        Ok(FlatPort {
            normal: n,
            distance,
            layers: arr,
            n_layers: layers.len(),
            n_air,
            n_water,
            total_thickness: total,
            slabs: Slabs::new(n_air, distance, layers, n_water),
            dd: FlatDd::new(n, distance, layers, n_air, n_water),
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
        // r² from the cross product (no cancellation near the axis).
        let r2 = nrm.cross(p).length_squared();
        if r2 == 0.0 {
            return Ok(nrm);
        }
        let perp = p - a * nrm;
        let (t, _, slope) = self.slabs.solve_ratio_counted(r2, depth)?;
        let d = nrm + perp * t;
        // κ·c > REFINE_AT, without a division.
        let c_num = nrm.z.abs() + (perp.z * t).abs();
        if c_num * slope.1 > REFINE_AT * t * slope.0 * d.z.abs() {
            return Ok(self.refine(p, t, slope));
        }
        Ok(d)
    }

    /// One Newton step on G(t) = F(r·t)/r evaluated in double-double from the exact inputs
    /// (P, the normal normalised in double-double, thicknesses and indices), with the
    /// solver's last slope G′; then N + t·P⊥ in double-double. For ill-conditioned roots
    /// ([`REFINE_AT`]), where f64 rounding in G and in the direction is amplified; the step
    /// leaves t to its own rounding (its error after the f64 solve, κ·ε, is squared).
    #[cold]
    #[inline(never)]
    fn refine(&self, p: DVec3, t: f64, slope: (f64, f64)) -> DVec3 {
        // Double-double products need a fused multiply-add: the instruction where the CPU
        // has it (same results, 3× faster than the library's emulation).
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "fma")]
            fn with_fma(port: &FlatPort, p: DVec3, t: f64, slope: (f64, f64)) -> DVec3 {
                port.refine_in(p, t, slope)
            }
            if std::arch::is_x86_feature_detected!("fma") {
                // SAFETY: the CPU has FMA (checked just above).
                return unsafe { with_fma(self, p, t, slope) };
            }
        }
        self.refine_in(p, t, slope)
    }

    #[inline(always)]
    fn refine_in(&self, p: DVec3, t: f64, slope: (f64, f64)) -> DVec3 {
        let k = &self.dd;
        let pp = V3::from(p);
        let a = k.normal.dot(pp);
        let c = k.normal.cross(pp);
        let rr = c.dot(c);
        let td = Dd::new(t);
        let tt = td * td * rr;
        let mut g = k.gap * td - Dd::ONE
            + (a - k.offset) * k.water.0 * td / (k.water.1 + k.water.2 * tt).sqrt();
        for &(tna, n2, kk) in &k.layers[..self.n_layers] {
            g = g + tna * td / (n2 + kk * tt).sqrt();
        }
        let step = g.to_f64() * slope.1 / slope.0;
        let td = if step.is_finite() && t - step > 0.0 {
            td - Dd::new(step)
        } else {
            td
        };
        let perp = pp.minus(k.normal.scale(a));
        let d = k.normal.plus(perp.scale(td));
        DVec3::new(d.x.to_f64(), d.y.to_f64(), d.z.to_f64())
    }
}

/// A flat port's constants in double-double, for [`FlatPort::refine`].
#[derive(Debug, Clone, Copy)]
struct FlatDd {
    /// The unit normal.
    normal: V3,
    gap: Dd,
    /// Inner-face distance plus every layer's thickness: the water depth is N·P − offset.
    offset: Dd,
    /// Per glass layer: t·na, n², n² − na².
    layers: [(Dd, Dd, Dd); MAX_LAYERS],
    /// Water: na, nw², nw² − na².
    water: (Dd, Dd, Dd),
}

impl FlatDd {
    fn new(normal: DVec3, distance: f64, layers: &[(f64, f64)], na: f64, nw: f64) -> FlatDd {
        let n0 = V3::from(normal);
        let nad = Dd::new(na);
        let na2 = nad * nad;
        let mut out = FlatDd {
            normal: n0.scale(Dd::ONE / n0.length()),
            gap: Dd::new(distance),
            offset: Dd::new(distance),
            layers: [(Dd::ZERO, Dd::ONE, Dd::ZERO); MAX_LAYERS],
            water: (
                nad,
                Dd::new(nw) * Dd::new(nw),
                Dd::new(nw) * Dd::new(nw) - na2,
            ),
        };
        for (slot, &(th, n)) in out.layers.iter_mut().zip(layers) {
            let n2 = Dd::new(n) * Dd::new(n);
            *slot = (Dd::new(th) * nad, n2, n2 - na2);
            out.offset = out.offset + Dd::new(th);
        }
        out
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
    /// Moment constants: the sines of the four refraction angles are `p·k[i]` for the signed
    /// distance p of the camera ray from C (k = 1/R₁, (na/ng)/R₁, (na/ng)/R₂, (na/nw)/R₂).
    k: [f64; 4],
    /// na/nw: the water ray's moment about C is `na/nw` times the camera ray's.
    kw: f64,
    /// dΘ/dp at p = 0 (Θ = total turning of the ray), for the first-order guess.
    dtheta0: f64,
}

/// One step of [`DomePort::moment_step`].
struct MomentStep<T: Lane> {
    step: T,
    halley: T::Mask,
    /// A refraction angle has no cosine: total internal reflection, or grazing a sphere.
    tir: T::Mask,
    /// u turned by atan(step), not yet unit.
    v: (T, T),
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
    fn halley(&self, c: DVec2, l: f64) -> Option<DVec2> {
        self.halley_counted(c, l).map(|(u, _)| u)
    }

    /// [`DomePort::halley`] and the number of evaluations of m it took.
    #[inline(always)]
    fn halley_counted(&self, c: DVec2, l: f64) -> Option<(DVec2, u32)> {
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
    fn guess<T: Lane>(&self, c: (T, T), pc: (T, T)) -> (T, T) {
        let k0 = self.dtheta0;
        (
            -c.1 * (pc.0 * k0 + 1.0 - self.kw),
            pc.0 * (T::splat(1.0) - c.0 * k0) + c.0 * self.kw,
        )
    }

    /// One Halley (or Newton) step on the moment equation from the unit camera direction
    /// `u`, on one value or on SIMD lanes ([`Lane`]) with the same operations.
    #[inline(always)]
    fn moment_step<T: Lane>(&self, c: (T, T), pc: (T, T), u: (T, T)) -> MomentStep<T> {
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
    fn unit_scale(step: f64, v: DVec2) -> f64 {
        if step.abs() <= 1e-3 {
            let s2 = step * step;
            1.0 - s2 * (0.5 - 0.375 * s2)
        } else {
            1.0 / v.length()
        }
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
    /// The meridional q-equation's constants (gap R₁, one glass layer).
    slabs: Slabs,
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
            slabs: Slabs::new(n_air, inner_radius, &[(thickness, n_glass)], n_water),
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
            if z == 0.0 {
                return Ok(e_rho);
            }
            let t = self.slabs.solve_ratio(z * z, rho - self.r2)?;
            return Ok(e_rho + a * (t * z));
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
        match self.newton_skew(p, p.normalize()) {
            Ok(d) => return Ok(d),
            Err(NoSolution::NoConvergence) => {}
            Err(e) => last = e,
        }
        // Both starts failed (a strongly decentred pupil, rays far from the sensor: Newton
        // diverges, or converges to the line's backward branch, which the acceptance test
        // rejects). Continuation in the decentring: move the pupil from the axis to its
        // place in 8 steps, keeping P fixed relative to the cylinder, each solve starting
        // from the previous one.
        self.continuation(p).map_err(|e| {
            if e == NoSolution::NoConvergence {
                last
            } else {
                e
            }
        })
    }

    #[cold]
    fn continuation(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let a0 = self.axis_point;
        let centred = CylinderPort {
            axis_point: DVec3::ZERO,
            on_axis: true,
            ..*self
        };
        let mut g = centred.forward(p - a0)?.normalize();
        const STEPS: u32 = 8;
        for k in 1..=STEPS {
            let lam = k as f64 / STEPS as f64;
            let port = CylinderPort {
                axis_point: a0 * lam,
                on_axis: false,
                ..*self
            };
            g = port.newton_skew(p - a0 * (1.0 - lam), g)?.normalize();
        }
        Ok(g)
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
// A flat port carries its constants twice (f64 and double-double, ≈ 0.6 KiB): solvers are
// built once per camera and channel and copied rarely, and boxing would cost `Copy`.
#[allow(clippy::large_enum_variant)]
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
                normal, distance, ..
            } => PortSolver::Flat(FlatPort::new(
                *normal,
                *distance,
                &port.flat_layers(ch),
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

    /// Point in water (camera frame) → camera ray direction (not unit). A non-finite point
    /// has no solution (`no_convergence`).
    #[inline]
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        if !p.is_finite() {
            return Err(NoSolution::NoConvergence);
        }
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

mod batch;
pub use batch::{LANES, Simd};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::projection::cases;

    /// Evaluations of the fast solver per point of the benchmark's sets (`None`: the point
    /// left the fast path), for the flat port and the on-axis cylinder (q-equation) and the
    /// decentred dome (moment equation).
    fn evaluations(port: &PortSolver, p: DVec3) -> Option<u32> {
        match port {
            PortSolver::Flat(f) => {
                let a = f.normal.dot(p);
                let depth = a - f.distance - f.total_thickness;
                let r2 = f.normal.cross(p).length_squared();
                f.slabs.solve_ratio_counted(r2, depth).ok().map(|x| x.1)
            }
            PortSolver::Cylinder(c) => {
                let z = c.axis.dot(p);
                let rho = c.axis.cross(p - c.axis_point).length();
                c.slabs
                    .solve_ratio_counted(z * z, rho - c.r2)
                    .ok()
                    .map(|x| x.1)
            }
            PortSolver::Dome(d) => {
                let l = p.length();
                let e1 = p / l;
                let cperp = d.center - d.center.dot(e1) * e1;
                let c = DVec2::new(d.center.dot(e1), cperp.length());
                d.halley_counted(c, l).map(|x| x.1)
            }
            PortSolver::None => None,
        }
    }

    #[test]
    fn fast_paths_are_taken_and_converge_in_few_evaluations() {
        // A regression here is a slowdown, not a wrong pixel: the fallbacks (bracketed
        // solvers) still give exact answers, so only this test notices a broken first guess
        // or stopping rule. Bounds: the evaluation counts measured on these sets (every port:
        // 2 on ordinary points, ≤ 4 on grazing ones).
        for c in cases(3000) {
            for (set, pts, bound) in [("ordinary", &c.ordinary, 2), ("grazing", &c.grazing, 4)] {
                let mut hist = [0usize; 8];
                for p in pts {
                    let n = evaluations(&c.port, *p)
                        .unwrap_or_else(|| panic!("{}/{set}: {p:?} left the fast path", c.name));
                    hist[(n as usize).min(7)] += 1;
                }
                let worst = hist.iter().rposition(|&k| k > 0).unwrap();
                assert!(
                    worst <= bound,
                    "{}/{set}: up to {worst} evaluations (histogram {hist:?})",
                    c.name
                );
                // On average the ordinary sets need no more than 2, the grazing ones ≤ 3.2.
                let mean = hist.iter().enumerate().map(|(i, k)| i * k).sum::<usize>() as f64
                    / pts.len() as f64;
                let mean_bound = if set == "ordinary" { 2.0 } else { 3.2 };
                assert!(
                    mean <= mean_bound,
                    "{}/{set}: mean {mean} evaluations",
                    c.name
                );
            }
        }
    }
}
