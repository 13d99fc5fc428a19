//! The hard-case table of the port solvers: the benchmark camera and, for a flat port, a
//! decentred dome and an on-axis cylinder, seeded point sets of ordinary and grazing rays.
//! One table, shared by the optics' own tests (fast paths taken, SIMD lanes used), the
//! integration tests and `poser bench projection` (`poser::bench::projection`, which
//! re-exports it).

use crate::lens::Lens;
use crate::port::{CylinderPort, DomePort, FlatPort, PortSolver};
use crate::rng::SplitMix64;
use crate::types::{Distortion, LensModel};
use glam::DVec3;

/// The benchmark camera: 5568×4176, f = 3200 px (as in Refractive COLMAP's tests).
pub fn bench_lens() -> Lens {
    Lens::new(
        3200.0,
        3200.0,
        2784.0,
        2088.0,
        LensModel::Rectilinear,
        Distortion::default(),
    )
}

/// A benchmark case: a port, its exact-reference function, and point sets.
pub struct Case {
    pub name: &'static str,
    pub port: PortSolver,
    pub ordinary: Vec<DVec3>,
    pub grazing: Vec<DVec3>,
}

fn points_from_rays(port: &PortSolver, rays: impl Iterator<Item = (DVec3, f64)>) -> Vec<DVec3> {
    rays.filter_map(|(d, s)| {
        port.backward(d.normalize())
            .ok()
            .map(|r| r.origin + r.dir * s)
    })
    .collect()
}

/// The three benchmark ports with `n` ordinary and `n` grazing points each.
pub fn cases(n: usize) -> Vec<Case> {
    let lens = bench_lens();
    let flat =
        PortSolver::Flat(FlatPort::new(DVec3::Z, 0.05, &[(0.007, 1.473)], 1.0, 1.333).unwrap());
    let dome = PortSolver::Dome(
        DomePort::new(
            DVec3::new(0.00042007, 0.00366894, 0.0283927),
            0.05,
            0.007,
            1.0,
            1.473,
            1.333,
        )
        .unwrap(),
    );
    let cyl = PortSolver::Cylinder(
        CylinderPort::new(DVec3::ZERO, DVec3::Y, 0.06, 0.008, 1.0, 1.473, 1.333).unwrap(),
    );
    let mut out = Vec::new();
    for (name, port, axis) in [
        ("flat", flat, DVec3::Z),
        ("dome", dome, DVec3::Z),
        ("cylinder", cyl, DVec3::Y),
    ] {
        let mut rng = SplitMix64(0x5EED ^ name.len() as u64);
        let ordinary: Vec<DVec3> = points_from_rays(
            &port,
            (0..n).map(|_| {
                let d = lens
                    .unproject(rng.next_f64() * 5568.0, rng.next_f64() * 4176.0)
                    .unwrap();
                (d, 0.3 * 100f64.powf(rng.next_f64()))
            }),
        );
        let grazing: Vec<DVec3> = points_from_rays(
            &port,
            (0..n).map(|_| {
                // 75°–88° off the port axis, in the image plane's direction (toward +x).
                let th = (75.0 + 13.0 * rng.next_f64()).to_radians();
                let ph = (rng.next_f64() - 0.5) * 0.6;
                let d = if axis == DVec3::Z {
                    DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
                } else {
                    // cylinder: toward the axis (y), seen from +z
                    DVec3::new(th.cos() * ph.sin(), th.sin(), th.cos() * ph.cos())
                };
                (d, 0.3 * 100f64.powf(rng.next_f64()))
            }),
        );
        out.push(Case {
            name,
            port,
            ordinary,
            grazing,
        });
    }
    out
}
