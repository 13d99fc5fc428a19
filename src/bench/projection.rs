//! Speed against error of the forward-projection solvers (`poser bench projection`,
//! `benches/projection.rs`).
//!
//! For each port type, three solvers project the same points (camera frame → pixel):
//!
//! | solver | what |
//! |---|---|
//! | `poser` | [`PortSolver::forward`], one call per point: flat and on-axis cylinder: Halley on the q-equation (ratio form) from the water-unit guess; dome: Halley on the exact moment equation from the first-order guess (bracketed secant/Illinois as fallback); off-axis cylinder: 2-D Newton |
//! | `poser_batch` | [`PortSolver::forward_many`]: the same solvers on 8 points at a time in SIMD lanes, AVX2 where the CPU has it (same results bit for bit) |
//! | `colmap_gn` | Refractive COLMAP's `IterativeProjection`: Gauss–Newton on the pixel, residual = point on the back-projected water ray at distance \|P\| minus P, central-difference Jacobian (step max(1e-6, 1e-9·\|x\|) px), stop at \|Δ\|² < 1e-10 px², ≤ 100 iterations, 2×2 normal equations |
//! | `agrawal` (flat) | Agrawal et al. CVPR 2012: the 12th-degree polynomial in the radial hit x on the first interface (MERL `SolveForwardProjectionCase3`, K/L/M factoring of docs/optics.md §1.3), all roots by Aberth–Ehrlich on x/u, physical root = real root in [0, u] with the smallest trace residual |
//!
//! Errors are measured against [`super::reference`] (double-double, ≈ 32 digits) in pixels;
//! speed is points per second on one thread. Point sets: *ordinary* (pixels uniform over the
//! sensor, 0.3–30 m) and *grazing* (camera rays 75°–88° off the port axis, pixels up to
//! ≈ 1e5 px).

// `!(x > y)` is deliberate, as in the optics: it rejects NaN as well as the failing comparison.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::optics::NoSolution;
use crate::optics::lens::Lens;
use crate::optics::port::{FlatPort, PortSolver};
use crate::optics::reference;
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::time::Instant;

pub use crate::optics::cases::{Case, bench_lens, cases};

/// Exact (double-double) pixel of `p` through `port`; `None` where no solution.
pub fn reference_pixel(port: &PortSolver, lens: &Lens, p: DVec3) -> Option<[f64; 2]> {
    let dir = match port {
        PortSolver::None => reference::V3::from(p),
        PortSolver::Flat(f) => {
            reference::flat_forward(f.normal, f.distance, f.layers(), f.n_air, f.n_water, p)?
        }
        PortSolver::Dome(d) => {
            reference::dome_forward(d.center, d.r1, d.r2, d.n_air, d.n_glass, d.n_water, p)?
        }
        PortSolver::Cylinder(c) => {
            // On-axis only: the meridional plane is a flat port with N = e_ρ, d = R₁.
            let rel = p - c.axis_point;
            let rho = rel - rel.dot(c.axis) * c.axis;
            if c.axis_point != DVec3::ZERO || rho.length() == 0.0 {
                return None;
            }
            reference::flat_forward(
                rho,
                c.r1,
                &[(c.r2 - c.r1, c.n_glass)],
                c.n_air,
                c.n_water,
                p,
            )?
        }
    };
    if dir.z.hi <= 0.0 {
        return None;
    }
    Some(reference::pinhole(lens.fx, lens.fy, lens.cx, lens.cy, dir))
}

/// poser's solver.
#[inline]
pub fn poser_project(port: &PortSolver, lens: &Lens, p: DVec3) -> Result<[f64; 2], NoSolution> {
    lens.project(port.forward(p)?)
}

/// poser's batch solver ([`PortSolver::forward_many`], SIMD lanes) then the lens.
pub fn poser_project_many(
    port: &PortSolver,
    lens: &Lens,
    ps: &[DVec3],
    dirs: &mut [Result<DVec3, NoSolution>],
    out: &mut [Result<[f64; 2], NoSolution>],
) {
    port.forward_many(ps, dirs);
    for (d, o) in dirs.iter().zip(out.iter_mut()) {
        *o = d.and_then(|d| lens.project(d));
    }
}

/// Refractive COLMAP's Gauss–Newton `IterativeProjection`, transcribed in f64.
pub fn colmap_gn(port: &PortSolver, lens: &Lens, p: DVec3) -> Result<[f64; 2], NoSolution> {
    let dist = p.length();
    // Point on the back-projected water ray at distance |P| from the camera centre.
    let cam_from_img = |x: DVec2| -> Option<DVec3> {
        let d = lens.unproject(x.x, x.y).ok()?;
        let r = port.backward(d).ok()?;
        let b = r.origin.dot(r.dir);
        let c = r.origin.length_squared() - dist * dist;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let l1 = -b + disc.sqrt();
        let l2 = -b - disc.sqrt();
        let lam = if l1 >= 0.0 { l1 } else { l2 };
        Some(r.origin + r.dir * lam)
    };
    let x0 = lens.project(p)?;
    let mut x = DVec2::new(x0[0], x0[1]);
    for _ in 0..100 {
        let r0 = cam_from_img(x).ok_or(NoSolution::NoConvergence)? - p;
        let hx = (1e-9 * x.x.abs()).max(1e-6);
        let hy = (1e-9 * x.y.abs()).max(1e-6);
        let jx = (cam_from_img(x + DVec2::new(hx, 0.0)).ok_or(NoSolution::NoConvergence)?
            - cam_from_img(x - DVec2::new(hx, 0.0)).ok_or(NoSolution::NoConvergence)?)
            / (2.0 * hx);
        let jy = (cam_from_img(x + DVec2::new(0.0, hy)).ok_or(NoSolution::NoConvergence)?
            - cam_from_img(x - DVec2::new(0.0, hy)).ok_or(NoSolution::NoConvergence)?)
            / (2.0 * hy);
        // Normal equations JᵀJ Δ = −Jᵀ r.
        let (a, b, c) = (jx.dot(jx), jx.dot(jy), jy.dot(jy));
        let (g0, g1) = (-jx.dot(r0), -jy.dot(r0));
        let det = a * c - b * b;
        if !(det.abs() > 0.0) {
            return Err(NoSolution::NoConvergence);
        }
        let dx = DVec2::new((c * g0 - b * g1) / det, (a * g1 - b * g0) / det);
        x += dx;
        if !x.is_finite() {
            return Err(NoSolution::NoConvergence);
        }
        if dx.length_squared() < 1e-10 {
            break;
        }
    }
    Ok([x.x, x.y])
}

/// Agrawal et al.'s 12th-degree polynomial for air | glass | water (flat, untilted or tilted
/// via POR coordinates), roots by Aberth–Ehrlich.
pub fn agrawal(port: &FlatPort, lens: &Lens, p: DVec3) -> Result<[f64; 2], NoSolution> {
    let layers = port.layers();
    if layers.len() != 1 {
        return Err(NoSolution::NoConvergence);
    }
    let nrm = port.normal;
    let v = nrm.dot(p);
    let d = port.distance;
    let (t, ng) = layers[0];
    let d2 = d + t;
    if v <= d2 {
        return Err(NoSolution::InsideGlass);
    }
    let u = nrm.cross(p).length();
    if u == 0.0 {
        return lens.project(nrm);
    }
    let mu1 = ng / port.n_air;
    let mu2 = port.n_water / port.n_air;
    let a = mu1 * mu1 - 1.0;
    let b = mu2 * mu2 - 1.0;
    let (m1s, m2s) = (mu1 * mu1, mu2 * mu2);
    let d2s = d * d;
    let dd = (d - d2) * (d - d2);
    let dv = (d2 - v) * (d2 - v);
    let k = b * (u * u * a + d2s * m1s) - b * dd - a * dv + d2s * m2s * a;
    let l = d2s * m2s * (u * u * a + d2s * m1s) - d2s * m2s * dd - d2s * m1s * dv
        + d2s * m1s * u * u * b;
    let m = 2.0 * d2s * m1s * u * b + 2.0 * d2s * m2s * u * a;
    let d4 = d2s * d2s * m1s * m2s;
    let s = [
        a * a * b * b,
        -4.0 * u * a * a * b * b,
        4.0 * u * u * a * a * b * b + 2.0 * a * b * k,
        -2.0 * a * b * m - 4.0 * u * a * b * k,
        k * k + 2.0 * a * b * l - 4.0 * a * b * dd * dv + 4.0 * u * a * b * m,
        -2.0 * m * k - 4.0 * u * a * b * l - 4.0 * d4 * u * a * b,
        2.0 * k * l + m * m - 4.0 * dd * (d2s * m1s * b + d2s * m2s * a) * dv
            + 10.0 * d4 * u * u * a * b,
        -2.0 * m * l - 4.0 * d4 * u * k - 4.0 * d4 * u * u * u * a * b,
        l * l + 2.0 * d4 * u * u * k - 4.0 * d4 * dd * dv + 4.0 * d4 * u * m,
        -2.0 * d4 * u * u * m - 4.0 * d4 * u * l,
        4.0 * d4 * d4 * u * u + 2.0 * d4 * u * u * l,
        -4.0 * d4 * d4 * u * u * u,
        d4 * d4 * u * u * u * u,
    ];
    // Substitute x = u·y so the physical root lies in [0, 1].
    let mut c = [0.0; 13];
    for (i, si) in s.iter().enumerate() {
        c[i] = si * u.powi(12 - i as i32);
    }
    let roots = aberth(&c);
    let perp = (p - v * nrm) / u;
    let mut best: Option<(f64, DVec3)> = None;
    for z in roots {
        if z.y.abs() > 1e-6 * (1.0 + z.x.abs()) || !(z.x >= 0.0 && z.x <= 1.0) {
            continue;
        }
        let x = z.x * u;
        let dir = nrm * d + perp * x;
        // MERL-style check: trace and measure the miss of P.
        let Ok(ray) = port.backward(dir.normalize()) else {
            continue;
        };
        let miss = (p - ray.origin).cross(ray.dir).length();
        if best.is_none_or(|b| miss < b.0) {
            best = Some((miss, dir));
        }
    }
    let (_, dir) = best.ok_or(NoSolution::NoConvergence)?;
    lens.project(dir)
}

/// All complex roots of the polynomial with coefficients `c` (highest power first), by the
/// Aberth–Ehrlich simultaneous iteration. Returned as (re, im).
pub fn aberth(c: &[f64]) -> Vec<DVec2> {
    // Strip leading zeros.
    let first = c.iter().position(|x| *x != 0.0).unwrap_or(c.len());
    let c = &c[first..];
    let n = c.len().saturating_sub(1);
    if n == 0 {
        return Vec::new();
    }
    type C = (f64, f64);
    let mul = |a: C, b: C| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let den = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / den, (a.1 * b.0 - a.0 * b.1) / den)
    };
    let eval = |z: C| -> (C, C) {
        let mut p = (c[0], 0.0);
        let mut dp = (0.0, 0.0);
        for &ci in &c[1..] {
            dp = mul(dp, z);
            dp = (dp.0 + p.0, dp.1 + p.1);
            p = mul(p, z);
            p = (p.0 + ci, p.1);
        }
        (p, dp)
    };
    // Initial guesses on a circle of the Cauchy-bound radius (geometric mean scale).
    let scale = (c[n].abs() / c[0].abs()).powf(1.0 / n as f64).max(1e-300);
    let mut z: Vec<C> = (0..n)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64 + 0.4;
            (scale * a.cos(), scale * a.sin())
        })
        .collect();
    for _ in 0..500 {
        let mut moved = 0.0f64;
        for i in 0..n {
            let (p, dp) = eval(z[i]);
            if p == (0.0, 0.0) {
                continue;
            }
            let ratio = div(p, dp);
            let mut sum = (0.0, 0.0);
            for j in 0..n {
                if i != j {
                    let dz = (z[i].0 - z[j].0, z[i].1 - z[j].1);
                    let inv = div((1.0, 0.0), dz);
                    sum = (sum.0 + inv.0, sum.1 + inv.1);
                }
            }
            let den = (1.0 - mul(ratio, sum).0, -mul(ratio, sum).1);
            let w = div(ratio, den);
            if w.0.is_finite() && w.1.is_finite() {
                z[i] = (z[i].0 - w.0, z[i].1 - w.1);
                moved = moved.max(w.0.hypot(w.1) / (1.0 + z[i].0.hypot(z[i].1)));
            }
        }
        if moved < 1e-15 {
            break;
        }
    }
    z.into_iter().map(|(a, b)| DVec2::new(a, b)).collect()
}

/// CPU time consumed by the calling thread, s (immune to other processes on a shared
/// machine, unlike wall-clock time).
pub fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own; CLOCK_THREAD_CPUTIME_ID is valid
    // on Linux and the BSDs.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return f64::NAN;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// One row of the report.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub port: String,
    pub points: String,
    pub solver: String,
    pub n: usize,
    /// Points per second of thread CPU time, median pass (one core; robust to machine load).
    pub points_per_second: f64,
    /// Points per second of thread CPU time, fastest pass.
    pub points_per_second_best: f64,
    /// Points per second of wall-clock time (depends on the machine's load).
    pub points_per_second_wall: f64,
    pub median_error_px: f64,
    pub max_error_px: f64,
    /// Points the solver failed on (explicit error or non-finite) although a solution exists.
    pub failures: usize,
}

/// (points with a reference, median error, max error, failures) of `results` against `refs`.
fn error_stats(
    results: impl Iterator<Item = Result<[f64; 2], NoSolution>>,
    refs: &[Option<[f64; 2]>],
) -> (usize, f64, f64, usize) {
    let mut errs = Vec::new();
    let mut failures = 0;
    for (x, r) in results.zip(refs) {
        let Some(r) = r else { continue };
        match x {
            Ok(x) if x[0].is_finite() && x[1].is_finite() => {
                errs.push((x[0] - r[0]).hypot(x[1] - r[1]))
            }
            _ => failures += 1,
        }
    }
    errs.sort_by(f64::total_cmp);
    let median = errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN);
    let max = errs.last().copied().unwrap_or(f64::NAN);
    (errs.len(), median, max, failures)
}

/// Points per second of `pass`, which solves `n` points, over whole passes until `min_time`
/// of thread CPU time has elapsed: (median pass, fastest pass, wall clock over all passes).
/// The median pass is the headline figure: on a shared machine other processes only ever
/// slow a pass down (a VM's stolen time is counted as the thread's own), so the median is
/// robust to bursts of load, and the fastest pass shows the code on an undisturbed core.
fn time_passes(n: usize, min_time: f64, mut pass: impl FnMut()) -> (f64, f64, f64) {
    let t0 = Instant::now();
    let c0 = thread_cpu_seconds();
    let mut times = Vec::new();
    let mut last = c0;
    while last - c0 < min_time || times.len() < 3 {
        pass();
        let now = thread_cpu_seconds();
        times.push(now - last);
        last = now;
    }
    let wall = t0.elapsed().as_secs_f64();
    let count = (n * times.len()) as f64;
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    (n as f64 / median, n as f64 / times[0], count / wall)
}

/// One solver's errors and speed on one point set (see [`Row`]).
struct Measured {
    n: usize,
    pps: f64,
    pps_best: f64,
    pps_wall: f64,
    median: f64,
    max: f64,
    failures: usize,
}

impl Measured {
    /// From [`error_stats`] and [`time_passes`].
    fn new(
        (n, median, max, failures): (usize, f64, f64, usize),
        (pps, pps_best, pps_wall): (f64, f64, f64),
    ) -> Measured {
        Measured {
            n,
            pps,
            pps_best,
            pps_wall,
            median,
            max,
            failures,
        }
    }
}

/// Errors against `refs` and one-core speed of `solve` over `pts` (monomorphised per solver:
/// no dynamic dispatch in the timed loop).
fn measure<F: Fn(DVec3) -> Result<[f64; 2], NoSolution>>(
    pts: &[DVec3],
    refs: &[Option<[f64; 2]>],
    min_time: f64,
    solve: F,
) -> Measured {
    let errors = error_stats(pts.iter().map(|p| solve(*p)), refs);
    let speed = time_passes(pts.len(), min_time, || {
        for p in pts.iter() {
            std::hint::black_box(solve(std::hint::black_box(*p)).ok());
        }
    });
    Measured::new(errors, speed)
}

/// [`measure`] for the batch solver: errors per point, speed over whole passes.
fn measure_batch(
    port: &PortSolver,
    lens: &Lens,
    pts: &[DVec3],
    refs: &[Option<[f64; 2]>],
    min_time: f64,
) -> Measured {
    let mut dirs = vec![Err(NoSolution::NoConvergence); pts.len()];
    let mut out = vec![Err(NoSolution::NoConvergence); pts.len()];
    poser_project_many(port, lens, pts, &mut dirs, &mut out);
    let errors = error_stats(out.iter().cloned(), refs);
    let speed = time_passes(pts.len(), min_time, || {
        poser_project_many(
            port,
            lens,
            std::hint::black_box(pts),
            &mut dirs,
            std::hint::black_box(&mut out),
        );
    });
    Measured::new(errors, speed)
}

/// Run the whole comparison. `quick`: fewer points and shorter timing. The environment
/// variable `POSER_BENCH_FILTER` (a substring of `port/points/solver`, e.g. `dome/` or
/// `/poser`) restricts the rows, for profiling one solver under valgrind.
pub fn run(quick: bool) -> Vec<Row> {
    let filter = std::env::var("POSER_BENCH_FILTER").unwrap_or_default();
    let wanted = |port: &str, set: &str, solver: &str| {
        format!("{port}/{set}/{solver}").contains(filter.as_str())
    };
    let n = if quick { 1000 } else { 10000 };
    let min_time = if quick { 0.05 } else { 0.5 };
    let lens = bench_lens();
    let mut rows = Vec::new();
    for case in cases(n) {
        for (set, pts) in [("ordinary", &case.ordinary), ("grazing", &case.grazing)] {
            let want = |solver: &str| wanted(case.name, set, solver);
            if !(want("poser") || want("poser_batch") || want("colmap_gn") || want("agrawal")) {
                continue;
            }
            let refs: Vec<Option<[f64; 2]>> = pts
                .iter()
                .map(|p| reference_pixel(&case.port, &lens, *p))
                .collect();
            let port = case.port;
            let mut results = Vec::new();
            if want("poser") {
                results.push((
                    "poser",
                    measure(pts, &refs, min_time, |p| poser_project(&port, &lens, p)),
                ));
            }
            if want("poser_batch") {
                results.push((
                    "poser_batch",
                    measure_batch(&port, &lens, pts, &refs, min_time),
                ));
            }
            if want("colmap_gn") {
                results.push((
                    "colmap_gn",
                    measure(pts, &refs, min_time, |p| colmap_gn(&port, &lens, p)),
                ));
            }
            if let (PortSolver::Flat(f), true) = (case.port, want("agrawal")) {
                results.push((
                    "agrawal",
                    measure(pts, &refs, min_time, |p| agrawal(&f, &lens, p)),
                ));
            }
            for (name, m) in results {
                rows.push(Row {
                    port: case.name.into(),
                    points: set.into(),
                    solver: name.into(),
                    n: m.n,
                    points_per_second: m.pps,
                    points_per_second_best: m.pps_best,
                    points_per_second_wall: m.pps_wall,
                    median_error_px: m.median,
                    max_error_px: m.max,
                    failures: m.failures,
                });
            }
        }
    }
    rows
}

/// The report as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| port | points | solver | n | points/s (1 core, CPU time, median pass) | fastest pass | wall clock | median error px | max error px | failures |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.2} M | {:.2} M | {:.2} M | {:.1e} | {:.1e} | {} |\n",
            r.port,
            r.points,
            r.solver,
            r.n,
            r.points_per_second / 1e6,
            r.points_per_second_best / 1e6,
            r.points_per_second_wall / 1e6,
            r.median_error_px,
            r.max_error_px,
            r.failures
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrawal_and_colmap_agree_with_the_reference_on_ordinary_points() {
        // The competitors must be implemented faithfully: on ordinary points both reach
        // ≤ 1e-6 px (Refractive COLMAP's own round-trip tolerance).
        let lens = bench_lens();
        let cs = cases(50);
        for c in &cs {
            for p in c.ordinary.iter().take(20) {
                let Some(r) = reference_pixel(&c.port, &lens, *p) else {
                    continue;
                };
                let g = colmap_gn(&c.port, &lens, *p).unwrap();
                assert!(
                    (g[0] - r[0]).hypot(g[1] - r[1]) < 1e-6,
                    "{} GN {g:?} vs {r:?}",
                    c.name
                );
                if let PortSolver::Flat(f) = c.port {
                    let a = agrawal(&f, &lens, *p).unwrap();
                    assert!(
                        (a[0] - r[0]).hypot(a[1] - r[1]) < 1e-6,
                        "Agrawal {a:?} vs {r:?}"
                    );
                }
                let q = poser_project(&c.port, &lens, *p).unwrap();
                assert!((q[0] - r[0]).hypot(q[1] - r[1]) < 1e-9);
            }
        }
    }

    #[test]
    fn aberth_finds_known_roots() {
        // (x − 1)(x − 2)(x + 3) = x³ − 7x + 6
        let mut r: Vec<f64> = aberth(&[1.0, 0.0, -7.0, 6.0]).iter().map(|z| z.x).collect();
        r.sort_by(f64::total_cmp);
        for (a, b) in r.iter().zip([-3.0, 1.0, 2.0]) {
            assert!((a - b).abs() < 1e-12);
        }
    }
}
