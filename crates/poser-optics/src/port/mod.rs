//! Housing ports: exact backward (camera ray → ray in water) and forward (point in water →
//! camera ray) refraction, per channel indices (n_air, n_glass, n_water).
//!
//! | port | parameters (camera frame, metres) | forward solver |
//! |---|---|---|
//! | [`FlatPort`] (`flat.rs`) | unit normal N (camera → water), inner-face distance d ≥ 0, glass layers (thickness, index)… | Halley on the scalar q-equation in ratio form t = q/r, from the water-unit guess (≤ 2 evaluations on ordinary points; no bracket needed when every n ≥ n_air; safeguarded Newton–bisection otherwise) |
//! | [`DomePort`] (`dome.rs`) | centre C (|C| < R₁), inner radius R₁, thickness t | Halley on the exact moment equation in the plane (O, C, P) from the first-order guess; bracketed secant/Illinois inside ±asin(|C|/R₁) as fallback; pinhole when centred |
//! | [`CylinderPort`] (`cylinder.rs`) | axis point, unit axis, inner radius, thickness | on its axis: the flat q-equation in the meridional plane; off it: 2-D Newton (skew rays) from two starts, then continuation in the decentring |
//!
//! Each type's file also builds its housing: [`housing`] (the exact glass surfaces and black
//! walls, what Mitsuba renders), [`housing_shell`] (the same as closed polygon meshes, what
//! Cycles renders) and [`housing_mesh`] (the glass shell as triangles, what the glTF export
//! shows), with the typed [`HousingError`]s; shared types in `port/housing.rs`.
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

pub mod cylinder;
pub mod dome;
pub mod flat;
mod housing;

pub use cylinder::CylinderPort;
pub use dome::DomePort;
pub use flat::{FlatPort, MAX_LAYERS};
use flat::{REFINE_AT, Slabs};
pub use housing::{
    Face, Housing, HousingError, HousingMesh, HousingShell, MESH_SEGMENTS, Part, Shape, TaggedMesh,
    basis, housing, housing_mesh, housing_shell, revolve, z_to,
};

use super::NoSolution;
use super::types::Port;
#[cfg(test)]
use glam::DVec2;
use glam::DVec3;

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
    use crate::cases::cases;

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
