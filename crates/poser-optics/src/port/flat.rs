//! The flat port ([`FlatPort`]): parallel glass layers, possibly tilted; the scalar
//! q-equation (`Slabs`, shared with the on-axis cylinder) and its double-double refinement.

use super::PortRay;
use super::housing::{
    Face, Housing, HousingMesh, HousingShell, MESH_SEGMENTS, Part, Shape, TaggedMesh, basis,
    border_directions, border_rays, field_directions, revolve, z_to,
};
use crate::NoSolution;
use crate::interface::{fresnel_transmittance, refract};
use crate::lanes::Lane;
use crate::project::Projector;
use crate::reference::{Dd, V3};
use crate::types::{Camera, Pose};
use glam::DVec3;

/// Largest number of glass layers of a flat port.
pub const MAX_LAYERS: usize = 4;

/// Flat port with one or more parallel glass layers (possibly tilted).
#[derive(Debug, Clone, Copy)]
pub struct FlatPort {
    pub normal: DVec3,
    pub distance: f64,
    pub(super) layers: [(f64, f64); MAX_LAYERS],
    pub(super) n_layers: usize,
    pub n_air: f64,
    pub n_water: f64,
    pub(super) total_thickness: f64,
    /// The q-equation's per-port constants.
    pub(super) slabs: Slabs,
    /// The same in double-double, for refining ill-conditioned roots.
    pub(super) dd: FlatDd,
}

/// One Newton or Halley step of the q-equation in ratio form: the step, whether it is
/// Halley's, and the slope G′(t) as a fraction (numerator, denominator > 0).
#[derive(Debug, Clone, Copy)]
pub(super) struct Step {
    pub(super) dt: f64,
    pub(super) halley: bool,
    pub(super) slope: (f64, f64),
}

/// The flat port's answer N + t·P⊥ carries a relative error of about κ·c·ε in its slope,
/// where κ = 1/(t·G′(t)) = r/(q·F′(q)) is the condition number of the root (the relative
/// change of q per relative change of r, which amplifies f64 rounding in G) and
/// c = (|N_z| + |t·P⊥_z|)/|N_z + t·P⊥_z| the cancellation in the direction's z (1 for an
/// untilted port). A pixel at distance ρ from the principal point then moves by ≈ 2κ·c·ε·ρ
/// (measured on the test ports), so where κ·c exceeds this bound (< 1e-9 px out to 1e5 px)
/// the answer is refined in double-double ([`FlatPort::refine`]): near grazing with no
/// camera-side gap, or deep behind a tilted port. κ·c ≈ 1 on ordinary points.
pub(super) const REFINE_AT: f64 = 16.0;

/// Scalar q-equation for parallel layers (`docs/optics.md` §1.3) with every per-port constant
/// precomputed once: the camera-side gap (index `na`), up to [`MAX_LAYERS`] glass layers, and
/// the water (index `nw`), whose depth D is the only per-point parameter besides r.
///
/// `F(q) = gap·q + Σᵢ tᵢ·na·q/√(nᵢ² + (nᵢ² − na²)q²) + D·na·q/√(nw² + (nw² − na²)q²) − r`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Slabs {
    pub(super) na: f64,
    pub(super) gap: f64,
    pub(super) n: usize,
    /// Per glass layer: tᵢ·na, nᵢ², nᵢ² − na².
    pub(super) tna: [f64; MAX_LAYERS],
    pub(super) n2: [f64; MAX_LAYERS],
    pub(super) k: [f64; MAX_LAYERS],
    /// Water: na, nw, nw², nw² − na².
    pub(super) nw: f64,
    pub(super) nw2: f64,
    pub(super) kw: f64,
    /// Every index ≥ na: F is concave and increasing (no bracket needed).
    pub(super) concave: bool,
    /// gap + Σ tᵢ·na/nᵢ (paraxial optical length of the port, camera-medium units).
    pub(super) parax: f64,
    /// (gap·nw/na + Σ tᵢ·nw/nᵢ): the port in paraxial water units (first guess of tan θw).
    pub(super) water_units: f64,
    /// Σ tᵢ·na/√(nᵢ² − na²) when every nᵢ > na (the layers' asymptote as q → ∞), else ∞.
    pub(super) asym: f64,
    /// na/√(nw² − na²): the limit of tan θw as q → ∞ (∞ when nw ≤ na).
    pub(super) tw_inf: f64,
    /// Largest q at which every term is defined (q < n/√(na²−n²) for layers with n < na),
    /// ignoring the water.
    pub(super) q_max_layers: f64,
}

impl Slabs {
    pub(super) fn new(na: f64, gap: f64, layers: &[(f64, f64)], nw: f64) -> Slabs {
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
    pub(super) fn term2(tna: f64, n2: f64, k: f64, q: f64) -> (f64, f64, f64) {
        let g = n2 + k * q * q;
        let inv = 1.0 / g.sqrt();
        let inv2 = inv * inv;
        let v = tna * q * inv;
        let dv = tna * n2 * inv2 * inv;
        (v, dv, -3.0 * k * q * dv * inv2)
    }

    /// F, F′ and F″ at q for water depth `depth`.
    #[inline(always)]
    pub(super) fn eval2(&self, q: f64, r: f64, depth: f64) -> (f64, f64, f64) {
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
    pub(super) fn eval2_ratio<T: Lane>(&self, t: T, r2: T, depth: T) -> (T, T, T) {
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
    pub(super) fn halley_parts<T: Lane>(f: T, df: T, d2f: T) -> (T, T, T::Mask) {
        let halley = (f * d2f).abs().lt(df * 1.5 * df);
        (
            T::select(halley, f * -2.0 * df, -f),
            T::select(halley, df * 2.0 * df - f * d2f, df),
            halley,
        )
    }

    /// [`Slabs::halley_parts`] as a [`Step`].
    #[inline(always)]
    pub(super) fn halley_step(f: f64, df: f64, d2f: f64) -> Step {
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
    pub(super) fn one_layer_parts<T: Lane>(
        &self,
        t: T,
        r2: T,
        depth: T,
    ) -> (T, T, T::Mask, (T, T)) {
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
    pub(super) fn step_one_layer(&self, t: f64, r2: f64, depth: f64) -> Step {
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
    pub(super) fn solve_ratio(&self, r2: f64, depth: f64) -> Result<f64, NoSolution> {
        self.solve_ratio_counted(r2, depth).map(|(t, _, _)| t)
    }

    /// [`Slabs::solve_ratio`], the number of evaluations of F it took (0 off the fast path),
    /// and the slope G′ at the last evaluation as (numerator, denominator > 0) ((∞, 1) off
    /// the fast path: the bracketed solver does not refine).
    #[inline(always)]
    pub(super) fn solve_ratio_counted(
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
    pub(super) fn eval(&self, q: f64, r: f64, depth: f64) -> (f64, f64) {
        let (f, df, _) = self.eval2(q, r, depth);
        (f, df)
    }

    /// Some layer is optically thinner than the camera medium: F → ∞ at q_max.
    /// Safeguarded Newton on [lo, hi].
    #[cold]
    pub(super) fn solve_bracketed(&self, r: f64, depth: f64) -> Result<f64, NoSolution> {
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
    pub(super) fn refine(&self, p: DVec3, t: f64, slope: (f64, f64)) -> DVec3 {
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
    pub(super) fn refine_in(&self, p: DVec3, t: f64, slope: (f64, f64)) -> DVec3 {
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
pub(super) struct FlatDd {
    /// The unit normal.
    pub(super) normal: V3,
    pub(super) gap: Dd,
    /// Inner-face distance plus every layer's thickness: the water depth is N·P − offset.
    pub(super) offset: Dd,
    /// Per glass layer: t·na, n², n² − na².
    pub(super) layers: [(Dd, Dd, Dd); MAX_LAYERS],
    /// Water: na, nw², nw² − na².
    pub(super) water: (Dd, Dd, Dd),
}

impl FlatDd {
    pub(super) fn new(
        normal: DVec3,
        distance: f64,
        layers: &[(f64, f64)],
        na: f64,
        nw: f64,
    ) -> FlatDd {
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

/// Why a flat port has no housing covering the field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HousingError {
    /// The distance or the (first layer's) thickness is not positive.
    NotPositive,
    /// A ray of the field of view leaves `degrees` from the normal (cosine below 0.1).
    FieldTooWide { degrees: f64 },
}

impl std::fmt::Display for HousingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HousingError::NotPositive => {
                write!(f, "the flat port needs a positive distance and thickness")
            }
            HousingError::FieldTooWide { degrees } => write!(
                f,
                "the field of view reaches {degrees:.1}° from the flat port's normal; the port \
                 cannot cover it"
            ),
        }
    }
}

/// A flat port's housing: the glass slab's six faces (`thickness`: the first layer) and the
/// black walls behind it. The slab's half-width covers the field of view's straight rays
/// 1.5 times over; five walls (back and four sides, from the inner face back to `d + t`
/// behind the pupil) close the air pocket, so rays the glass reflects back into the housing
/// end there instead of escaping to the ambient light (a real housing is dark inside).
pub fn housing(
    cam: &Camera,
    normal: DVec3,
    distance: f64,
    thickness: f64,
) -> Result<Housing, HousingError> {
    let n = normal.normalize();
    if !(distance > 0.0) || !(thickness > 0.0) {
        return Err(HousingError::NotPositive);
    }
    let mut max_tan: f64 = 0.0;
    for r in border_rays(cam) {
        let c = r.dot(n);
        if c < 0.1 {
            return Err(HousingError::FieldTooWide {
                degrees: c.clamp(-1.0, 1.0).acos().to_degrees(),
            });
        }
        max_tan = max_tan.max((1.0 - c * c).sqrt() / c);
    }
    let (d, t) = (distance, thickness);
    let half = 1.5 * (d + t) * max_tan + 2.0 * t;
    let (e1, e2) = basis(n);
    let rect = |centre, shift, x, y, normal| Shape::Rectangle {
        centre,
        shift,
        x,
        y,
        normal,
    };
    let sides = [(e1, e2), (-e1, -e2), (e2, -e1), (-e2, e1)];
    let mut parts = vec![
        // Inner face, normal towards the camera: interior (behind the normal) is glass.
        Part::new(
            Face::Inner { glass_inside: true },
            rect(n * d, None, (e2, half), (e1, half), -n),
        )
        .labelled("port", "inner face (air | glass)"),
        // Outer face, normal towards the water.
        Part::new(
            Face::Outer,
            rect(n * (d + t), None, (e1, half), (e2, half), n),
        )
        .labelled("port", "outer face (glass | water)"),
    ];
    // Four edge faces, normals outward: local x = other (half), y = n (t/2), z = axis.
    for (axis, other) in sides {
        parts.push(Part::new(
            Face::Outer,
            rect(
                n * (d + 0.5 * t),
                Some((axis, half)),
                (other, half),
                (n, 0.5 * t),
                axis,
            ),
        ));
    }
    let back = d + t;
    parts.push(
        Part::new(
            Face::Wall,
            rect(-n * back, None, (e1, half), (e2, half), -n),
        )
        .labelled("housing", "black walls behind the port"),
    );
    for (axis, other) in sides {
        parts.push(Part::new(
            Face::Wall,
            rect(
                n * (0.5 * (d - back)),
                Some((axis, half)),
                (other, half),
                (n, 0.5 * (d + back)),
                axis,
            ),
        ));
    }
    Ok(Housing {
        parts,
        clearance: d,
        extent: ((d + t).powi(2) + 2.0 * half * half).sqrt(),
    })
}

/// A flat port's closed housing for a mesh renderer ([`HousingShell`]): a box whose front is
/// the glass's outer face (`normal·x = distance + thickness`), wide enough that every ray of
/// the field of view (tilted at most 80° from the normal) crosses it with a margin of 10 % of
/// the span + 2 thicknesses + 1 mm, and whose back lies half the span + 2 cm behind the pupil;
/// the inner face is one rectangle of the same size at `distance`. Flat faces: no normals.
pub fn housing_shell(cam: &Camera, normal: DVec3, distance: f64, thickness: f64) -> HousingShell {
    let n = normal.normalize();
    // (e2, −e1): the orientation the Blender builder used when it built this shell itself.
    let (e1, e2) = basis(n);
    let (u, v) = (e2, -e1);
    let (d, t) = (distance, thickness);
    // Extents where the field meets the plane two thicknesses beyond the glass.
    let reach = d + 2.0 * t;
    let max_tilt = 80f64.to_radians();
    let (mut a0, mut a1, mut b0, mut b1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for ray in field_directions(cam, 8) {
        let mut ray = ray;
        if ray.dot(n) < max_tilt.cos() {
            let side = (ray - ray.dot(n) * n).normalize_or(u);
            ray = max_tilt.cos() * n + max_tilt.sin() * side;
        }
        let p = ray * (reach / ray.dot(n));
        (a0, a1) = (a0.min(p.dot(u)), a1.max(p.dot(u)));
        (b0, b1) = (b0.min(p.dot(v)), b1.max(p.dot(v)));
    }
    let span = (a1 - a0).max(b1 - b0);
    let margin = 0.1 * span + 2.0 * t + 1e-3;
    let (a0, a1, b0, b1) = (a0 - margin, a1 + margin, b0 - margin, b1 + margin);
    let back = -(0.5 * span + 0.02);
    let ring =
        |h: f64| [(a0, b0), (a1, b0), (a1, b1), (a0, b1)].map(|(a, b)| a * u + b * v + h * n);
    let mut shell = TaggedMesh {
        positions: [ring(d + t), ring(back)].concat(),
        ..TaggedMesh::default()
    };
    // u × v = n: the front ring counter-clockwise seen from the water.
    shell.push(vec![0, 1, 2, 3], Face::Outer);
    shell.push(vec![4, 7, 6, 5], Face::Wall);
    for i in 0..4 {
        let j = (i + 1) % 4;
        shell.push(vec![i, i + 4, j + 4, j], Face::Wall);
    }
    let mut inner = TaggedMesh {
        positions: ring(d).to_vec(),
        ..TaggedMesh::default()
    };
    inner.push(vec![0, 3, 2, 1], Face::Inner { glass_inside: true });
    HousingShell { shell, inner }
}

/// A flat port's glass as a disc, for display: the radius the field of view needs (where the
/// sensor corners' rays leave the glass by exact refraction in water of index `n_water`, else
/// the straight rays to the outer face; + 10 %), the glass's whole thickness.
pub fn housing_mesh(cam: &Camera, normal: DVec3, distance: f64, n_water: f64) -> HousingMesh {
    let t = cam.port.total_thickness();
    let n = normal.normalize();
    let exact = Projector::for_camera(cam, 1, n_water)
        .ok()
        .map(|pr| {
            let (w, h) = (cam.width as f64, cam.height as f64);
            [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
                .iter()
                .filter_map(|&(u, v)| pr.camera_ray(u, v).ok())
                .map(|r| (r.origin - n * n.dot(r.origin)).length())
                .fold(0.0, f64::max)
        })
        .filter(|r| *r > 0.0);
    let straight = border_directions(cam)
        .iter()
        .filter(|d| d.dot(n) > 1e-3)
        .map(|d| {
            let p = *d * ((distance + t) / d.dot(n));
            (p - n * n.dot(p)).length()
        })
        .fold(0.0, f64::max);
    let r = 1.1 * exact.unwrap_or(straight).max(0.5 * (distance + t));
    revolve(
        &[(0.0, 0.0), (r, 0.0), (r, t), (0.0, t)],
        false,
        MESH_SEGMENTS,
    )
    .transformed(&Pose {
        rotation: z_to(n),
        translation: n * distance,
    })
}
