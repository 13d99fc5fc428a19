//! The batch forward solvers ([`PortSolver::forward_many`]): the scalar solvers' fast paths
//! on [`LANES`] points at once in SIMD lanes ([`crate::lanes`]), AVX2 where the CPU
//! has it.
//!
//! | port | in lanes | handed back to the scalar solver |
//! |---|---|---|
//! | flat, cylinder on its axis | setup, first guess, Halley/Newton on the q-equation (ratio form), stopping rule | a bracketed port (some index below the camera medium's), beyond the critical angle, non-finite steps, no convergence in 12 steps |
//! | dome, decentred | setup, first-order guess, Halley/Newton on the moment equation, output direction | guess outside the bracket, total internal reflection, non-finite steps, no convergence in 16 steps |
//! | dome centred, cylinder off its axis, no port | — | every point |
//!
//! The steps themselves (`Slabs::eval2_ratio`, `halley_parts`, `one_layer_parts`,
//! `DomePort::guess`, `moment_step`) are the scalar solver's own functions, generic over
//! [`crate::lanes::Lane`]; the setup and stopping rule here repeat the scalar ones
//! operation for operation. So each point gets the same bits as [`PortSolver::forward`]
//! (tested), whichever instruction set runs it.

use super::{CylinderPort, DomePort, FlatPort, NoSolution, PortSolver, REFINE_AT, Slabs};
use crate::lanes::{M, V, W, has_avx2};
use glam::DVec3;
use std::ops::Not;

/// Points solved together by the batch solvers.
pub const LANES: usize = W;

type Out = Result<DVec3, NoSolution>;

/// The scalar solver for a lane that left the fast path, with [`PortSolver::forward`]'s
/// rule that a non-finite point has no solution.
#[inline(never)]
fn fallback(p: DVec3, forward: impl Fn(DVec3) -> Out) -> Out {
    #[cfg(test)]
    tests::FALLBACKS.with(|c| c.set(c.get() + 1));
    if p.is_finite() {
        forward(p)
    } else {
        Err(NoSolution::NoConvergence)
    }
}

/// Which build of the batch kernels runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Simd {
    /// The target's baseline instruction set (SSE2 on x86-64).
    Baseline,
    /// AVX2 (x86-64 only; falls back to the baseline where the CPU lacks it).
    Avx2,
}

impl Simd {
    /// The fastest build this CPU runs.
    pub fn detect() -> Simd {
        if has_avx2() {
            Simd::Avx2
        } else {
            Simd::Baseline
        }
    }

    /// `"avx2"` or `"baseline"`, for reports.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Baseline => "baseline",
            Simd::Avx2 => "avx2",
        }
    }
}

/// The points of `ps` (≤ [`W`]) in structure-of-arrays form; missing lanes are (0, 0, 1).
#[inline(always)]
fn soa(ps: &[DVec3]) -> (V, V, V) {
    let (mut x, mut y, mut z) = ([0.0; W], [0.0; W], [1.0; W]);
    for (l, p) in ps.iter().enumerate() {
        x[l] = p.x;
        y[l] = p.y;
        z[l] = p.z;
    }
    (V(x), V(y), V(z))
}

impl Slabs {
    /// [`Slabs::solve_ratio`] on [`W`] lanes (inactive lanes are ignored; they must hold
    /// finite r², D). Returns t and the lanes that converged on the fast path; the caller
    /// re-solves the others with the scalar solver. `N`: the number of glass layers. Also
    /// returns each lane's last slope G′ as (numerator, denominator).
    #[inline(always)]
    fn solve_ratio_v<const N: usize>(&self, r2: V, depth: V, active: M) -> (V, M, (V, V)) {
        // The plain concave path (no bracket, no critical-angle exit), as in solve_ratio.
        let asym = self.asym + depth * self.tw_inf;
        let zero = V::splat(0.0);
        let beyond = M::splat(self.gap == 0.0).and((asym * asym).le(r2));
        let active = active
            .and(M::splat(self.concave))
            .and(r2.gt(zero))
            .and(depth.gt(zero))
            .and(beyond.not());
        // First guess (see solve_ratio_counted).
        let big_a = depth + self.water_units;
        let lim = 0.9 * self.tw_inf * big_a;
        let ordinary = r2.lt(lim * lim);
        let mut t = self.nw / (self.na * self.na * big_a * big_a - self.kw * r2).sqrt();
        if !ordinary.or(active.not()).all() {
            let parax = 1.0 / (self.parax + depth * self.na / self.nw);
            let tg = if self.gap > 0.0 {
                let r = r2.sqrt();
                parax.max((r - asym) / (self.gap * r))
            } else {
                parax
            };
            t = ordinary.select(t, tg);
        }
        let mut done = active.not();
        let mut failed = M::splat(false);
        let (mut slope_num, mut slope_den) = (V::splat(1.0), V::splat(1.0));
        for _ in 0..12 {
            let (num, den, halley, slope) = if N == 1 {
                self.one_layer_parts(t, r2, depth)
            } else {
                let (f, df, d2f) = self.eval2_ratio(t, r2, depth);
                let (num, den, halley) = Self::halley_parts(f, df, d2f);
                (num, den, halley, (df, V::splat(1.0)))
            };
            let dt = num / den;
            let next = t + dt;
            let next = next.gt(zero).select(next, 0.5 * t);
            let tol = halley.select(V::splat(1e-5), V::splat(1e-8));
            let conv = dt.abs().le(tol * next);
            let bad = dt.finite().not();
            let live = done.not();
            t = live.select(next, t);
            slope_num = live.select(slope.0, slope_num);
            slope_den = live.select(slope.1, slope_den);
            failed = failed.or(live.and(bad));
            done = done.or(conv).or(bad);
            if done.all() {
                break;
            }
        }
        let ok = active.and(done).and(failed.not()).and(t.finite());
        (t, ok, (slope_num, slope_den))
    }
}

/// The flat port's batch kernel (`N` glass layers).
#[inline(always)]
fn flat_kernel<const N: usize>(port: &FlatPort, ps: &[DVec3], out: &mut [Out]) {
    let nrm = port.normal;
    for (pc, oc) in ps.chunks(W).zip(out.chunks_mut(W)) {
        let (x, y, z) = soa(pc);
        // a = N·P, depth, r² = |N × P|² (as FlatPort::forward).
        let a = x * nrm.x + y * nrm.y + z * nrm.z;
        let depth = a - port.distance - port.total_thickness;
        let cx = nrm.y * z - y * nrm.z;
        let cy = nrm.z * x - z * nrm.x;
        let cz = nrm.x * y - x * nrm.y;
        let r2 = cx * cx + cy * cy + cz * cz;
        let live = M::first(pc.len())
            .and(x.finite())
            .and(y.finite())
            .and(z.finite());
        // Inactive lanes get a harmless problem.
        let ok_in = live.and(depth.gt(V::splat(0.0))).and(r2.gt(V::splat(0.0)));
        let r2s = ok_in.select(r2, V::splat(1.0));
        let ds = ok_in.select(depth, V::splat(1.0));
        let (t, ok, slope) = port.slabs.solve_ratio_v::<N>(r2s, ds, ok_in);
        // FlatPort::forward's answer N + t·P⊥; lanes that need refining (κ·c > REFINE_AT)
        // go to the scalar solver, which refines them.
        let (px, py, pz) = (x - a * nrm.x, y - a * nrm.y, z - a * nrm.z);
        let (dx, dy, dz) = (nrm.x + px * t, nrm.y + py * t, nrm.z + pz * t);
        let c_num = nrm.z.abs() + (pz * t).abs();
        let refine = (c_num * slope.1).gt(REFINE_AT * t * slope.0 * dz.abs());
        let ok = ok.and(refine.not());
        for (l, (p, o)) in pc.iter().zip(oc.iter_mut()).enumerate() {
            *o = if ok.get(l) {
                Ok(DVec3::new(dx.0[l], dy.0[l], dz.0[l]))
            } else {
                fallback(*p, |p| port.forward(p))
            };
        }
    }
}

/// The on-axis cylinder's batch kernel (the flat q-equation in the meridional plane).
#[inline(always)]
fn cylinder_kernel(port: &CylinderPort, ps: &[DVec3], out: &mut [Out]) {
    let ax = port.axis;
    for (pc, oc) in ps.chunks(W).zip(out.chunks_mut(W)) {
        let mut r2 = [1.0; W];
        let mut depth = [1.0; W];
        let mut z = [0.0; W];
        let mut e_rho = [DVec3::ZERO; W];
        let mut active = [0u64; W];
        for (l, p) in pc.iter().enumerate() {
            let rel = *p - port.axis_point;
            let zl = ax.dot(*p);
            let rho_v = rel - rel.dot(ax) * ax;
            let rho = ax.cross(rel).length();
            let d = rho - port.r2;
            let ok = d > 0.0 && zl * zl > 0.0 && d.is_finite() && zl.is_finite();
            active[l] = (ok as u64).wrapping_neg();
            if ok {
                r2[l] = zl * zl;
                depth[l] = d;
                z[l] = zl;
                e_rho[l] = rho_v / rho;
            }
        }
        let (t, ok, _) = port.slabs.solve_ratio_v::<1>(V(r2), V(depth), M(active));
        for (l, (p, o)) in pc.iter().zip(oc.iter_mut()).enumerate() {
            *o = if ok.get(l) {
                Ok(e_rho[l] + ax * (t.0[l] * z[l]))
            } else {
                fallback(*p, |p| port.forward(p))
            };
        }
    }
}

/// The decentred dome's batch kernel: `DomePort::forward` with `DomePort::halley`, every
/// step in lanes.
#[inline(always)]
fn dome_kernel(port: &DomePort, ps: &[DVec3], out: &mut [Out]) {
    let c = port.center;
    let zero = V::splat(0.0);
    for (pc, oc) in ps.chunks(W).zip(out.chunks_mut(W)) {
        let (x, y, z) = soa(pc);
        let (dx, dy, dz) = (x - c.x, y - c.y, z - c.z);
        let dc = (dx * dx + dy * dy + dz * dz).sqrt();
        // DomePort::forward: C = (C·P/L, |C × P|/L) in the plane basis.
        let len = (x * x + y * y + z * z).sqrt();
        let (qx, qy, qz) = (c.y * z - y * c.z, c.z * x - z * c.x, c.x * y - x * c.y);
        let cl_x = (x * c.x + y * c.y + z * c.z) / len;
        let cl_y = (qx * qx + qy * qy + qz * qz).sqrt() / len;
        // P − C = (pc_x, pc_y); the guess (den, num) as in DomePort::halley_counted.
        let (pc_x, pc_y) = (len - cl_x, -cl_y);
        let (num, den) = port.guess((cl_x, cl_y), (pc_x, pc_y));
        let active = M::first(pc.len())
            .and(dc.gt(V::splat(port.r2)))
            .and(cl_y.gt(V::splat(1e-300)))
            .and(den.gt(zero))
            .and(num.abs().le(port.bracket * den));
        let s0 = 1.0 / (den * den + num * num).sqrt();
        let (mut ux, mut uy) = (den * s0, num * s0);
        let mut done = active.not();
        let mut failed = M::splat(false);
        for _ in 0..16 {
            let m = port.moment_step((cl_x, cl_y), (pc_x, pc_y), (ux, uy));
            let (step, halley, (vx, vy)) = (m.step, m.halley, m.v);
            let tol = halley.select(V::splat(5e-6), V::splat(1e-8));
            let conv = step.abs().le(tol);
            let bad = m.tir.or(step.finite().not());
            let live = done.not();
            // DomePort::unit_scale: the series where |step| ≤ 1e-3, else 1/|v|; a converged
            // lane keeps v as it is.
            let small = step.abs().le(V::splat(1e-3));
            let s2 = step * step;
            let mut scale = 1.0 - s2 * (0.5 - 0.375 * s2);
            let renorm = live.and(conv.or(bad).not());
            if !small.or(renorm.not()).all() {
                scale = small.select(scale, 1.0 / (vx * vx + vy * vy).sqrt());
            }
            let scale = conv.select(V::splat(1.0), scale);
            let take = live.and(bad.not());
            ux = take.select(vx * scale, ux);
            uy = take.select(vy * scale, uy);
            failed = failed.or(live.and(bad));
            done = done.or(conv).or(bad);
            if done.all() {
                break;
            }
        }
        let ok = active
            .and(done)
            .and(failed.not())
            .and(ux.gt(zero))
            .and(uy.abs().le(port.bracket * ux));
        // Output e₁·u₁ + e₂·u₂ with e₁ = P/L, e₂ = (C − e₁·c.x)/c.y.
        let (ex, ey, ez) = (x / len, y / len, z / len);
        let e2x = (c.x - ex * cl_x) / cl_y;
        let e2y = (c.y - ey * cl_x) / cl_y;
        let e2z = (c.z - ez * cl_x) / cl_y;
        let (ox, oy, oz) = (ex * ux + e2x * uy, ey * ux + e2y * uy, ez * ux + e2z * uy);
        for (l, (p, o)) in pc.iter().zip(oc.iter_mut()).enumerate() {
            *o = if ok.get(l) {
                Ok(DVec3::new(ox.0[l], oy.0[l], oz.0[l]))
            } else {
                fallback(*p, |p| port.forward(p))
            };
        }
    }
}

/// The AVX2 builds of the kernels (same code, wider vectors).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;

    #[target_feature(enable = "avx2")]
    pub fn flat<const N: usize>(port: &FlatPort, ps: &[DVec3], out: &mut [Out]) {
        flat_kernel::<N>(port, ps, out)
    }
    #[target_feature(enable = "avx2")]
    pub fn cylinder(port: &CylinderPort, ps: &[DVec3], out: &mut [Out]) {
        cylinder_kernel(port, ps, out)
    }
    #[target_feature(enable = "avx2")]
    pub fn dome(port: &DomePort, ps: &[DVec3], out: &mut [Out]) {
        dome_kernel(port, ps, out)
    }
}

/// Whether the AVX2 build may run: asked for and supported by this CPU.
#[inline]
fn use_avx2(simd: Simd) -> bool {
    simd == Simd::Avx2 && has_avx2()
}

impl FlatPort {
    /// [`FlatPort::forward`] for many points (`out[i]` for `ps[i]`; equal lengths), with
    /// [`PortSolver::forward`]'s rule for non-finite points.
    pub(super) fn forward_many_with(&self, simd: Simd, ps: &[DVec3], out: &mut [Out]) {
        assert_eq!(ps.len(), out.len(), "forward_many: one output per point");
        macro_rules! run {
            ($n:expr) => {{
                #[cfg(target_arch = "x86_64")]
                if use_avx2(simd) {
                    // SAFETY: the CPU supports AVX2 (use_avx2 checked it).
                    return unsafe { avx2::flat::<$n>(self, ps, out) };
                }
                let _ = simd;
                flat_kernel::<$n>(self, ps, out)
            }};
        }
        match self.slabs.n {
            0 => run!(0),
            1 => run!(1),
            2 => run!(2),
            3 => run!(3),
            _ => run!(4),
        }
    }
}

impl CylinderPort {
    /// [`CylinderPort::forward`] for many points (`out[i]` for `ps[i]`; equal lengths), with
    /// [`PortSolver::forward`]'s rule for non-finite points.
    pub(super) fn forward_many_with(&self, simd: Simd, ps: &[DVec3], out: &mut [Out]) {
        assert_eq!(ps.len(), out.len(), "forward_many: one output per point");
        if !self.on_axis {
            for (p, o) in ps.iter().zip(out.iter_mut()) {
                *o = fallback(*p, |p| self.forward(p));
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2(simd) {
            // SAFETY: the CPU supports AVX2 (use_avx2 checked it).
            return unsafe { avx2::cylinder(self, ps, out) };
        }
        let _ = simd;
        cylinder_kernel(self, ps, out)
    }
}

impl DomePort {
    /// [`DomePort::forward`] for many points (`out[i]` for `ps[i]`; equal lengths), with
    /// [`PortSolver::forward`]'s rule for non-finite points.
    pub(super) fn forward_many_with(&self, simd: Simd, ps: &[DVec3], out: &mut [Out]) {
        assert_eq!(ps.len(), out.len(), "forward_many: one output per point");
        if self.is_centred() {
            for (p, o) in ps.iter().zip(out.iter_mut()) {
                *o = fallback(*p, |p| self.forward(p));
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2(simd) {
            // SAFETY: the CPU supports AVX2 (use_avx2 checked it).
            return unsafe { avx2::dome(self, ps, out) };
        }
        let _ = simd;
        dome_kernel(self, ps, out)
    }
}

impl PortSolver {
    /// [`PortSolver::forward`] for many points at once (`out[i]` for `ps[i]`; the slices
    /// must have equal lengths): the same guess, iteration and stopping rule as the scalar
    /// call, bit for bit, on [`LANES`] points in SIMD lanes; anything off the fast path falls
    /// back to [`PortSolver::forward`].
    pub fn forward_many(&self, ps: &[DVec3], out: &mut [Out]) {
        self.forward_many_with(Simd::detect(), ps, out)
    }

    /// [`PortSolver::forward_many`] with a chosen build of the kernels (tests check that
    /// every build gives the scalar solver's bits).
    pub fn forward_many_with(&self, simd: Simd, ps: &[DVec3], out: &mut [Out]) {
        assert_eq!(ps.len(), out.len(), "forward_many: one output per point");
        match self {
            PortSolver::Flat(f) => f.forward_many_with(simd, ps, out),
            PortSolver::Dome(d) => d.forward_many_with(simd, ps, out),
            PortSolver::Cylinder(c) => c.forward_many_with(simd, ps, out),
            PortSolver::None => {
                for (p, o) in ps.iter().zip(out.iter_mut()) {
                    *o = self.forward(*p);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases::cases;
    use std::cell::Cell;

    thread_local! {
        /// Points the batch kernels handed to the scalar solver on this thread.
        pub(super) static FALLBACKS: Cell<usize> = const { Cell::new(0) };
    }

    #[test]
    fn the_lanes_solve_the_benchmark_points_themselves() {
        // Same bits either way (tests/optics_fast_path.rs), so only this notices a kernel
        // that hands everything to the scalar solver. Bounds: ordinary points never leave
        // the lanes; at grazing only the flat port's refined points do (measured 5 %).
        for c in cases(2000) {
            for (set, pts, bound) in [("ordinary", &c.ordinary, 0.0), ("grazing", &c.grazing, 0.1)]
            {
                for simd in [Simd::Baseline, Simd::Avx2] {
                    FALLBACKS.with(|f| f.set(0));
                    let mut out = vec![Err(NoSolution::NoConvergence); pts.len()];
                    c.port.forward_many_with(simd, pts, &mut out);
                    let n = FALLBACKS.with(|f| f.get());
                    assert!(
                        n as f64 <= bound * pts.len() as f64,
                        "{}/{set} ({simd:?}): {n} of {} points left the lanes",
                        c.name,
                        pts.len()
                    );
                    assert!(out.iter().all(|o| o.is_ok()));
                }
            }
        }
    }
}
