//! Backward (pixel → water ray) then forward (point on that ray → pixel) must return the pixel.
use glam::DVec3;
use poser::model::{Distortion, LensModel};
use poser::optics::lens::Lens;
use poser::optics::port::{CylinderPort, DomePort, FlatPort, PortSolver};

fn lens() -> Lens {
    Lens::new(
        3200.0,
        3200.0,
        2784.0,
        2088.0,
        LensModel::Rectilinear,
        Distortion::default(),
    )
}

fn check(port: &PortSolver, lens: &Lens, u: f64, v: f64, dist: f64) -> f64 {
    let d = lens.unproject(u, v).unwrap();
    let ray = port.backward(d).unwrap();
    let p = ray.origin + ray.dir * dist;
    let dir = port.forward(p).unwrap();
    let px = lens.project(dir).unwrap();
    (px[0] - u).hypot(px[1] - v)
}

#[test]
fn flat_dome_cylinder_round_trip_grid() {
    let l = lens();
    let ports = [
        PortSolver::Flat(FlatPort::new(DVec3::Z, 0.05, &[(0.007, 1.473)], 1.003, 1.333).unwrap()),
        PortSolver::Flat(
            FlatPort::new(
                DVec3::new(0.1, -0.05, 1.0),
                0.02,
                &[(0.01, 1.5168)],
                1.0,
                1.34,
            )
            .unwrap(),
        ),
        PortSolver::Dome(
            DomePort::new(
                DVec3::new(0.00042007, 0.00366894, 0.0283927),
                0.05,
                0.007,
                1.003,
                1.473,
                1.333,
            )
            .unwrap(),
        ),
        PortSolver::Dome(
            DomePort::new(
                DVec3::new(0.002, -0.001, 0.0),
                0.1,
                0.007,
                1.0,
                1.523,
                1.333,
            )
            .unwrap(),
        ),
        PortSolver::Cylinder(
            CylinderPort::new(DVec3::ZERO, DVec3::Y, 0.06, 0.008, 1.0, 1.49, 1.34).unwrap(),
        ),
        PortSolver::Cylinder(
            CylinderPort::new(
                DVec3::new(0.004, 0.0, -0.003),
                DVec3::Y,
                0.06,
                0.008,
                1.0,
                1.49,
                1.34,
            )
            .unwrap(),
        ),
    ];
    for (k, port) in ports.iter().enumerate() {
        let mut worst: f64 = 0.0;
        for i in 0..=8 {
            for j in 0..=6 {
                let (u, v) = (
                    i as f64 * 5568.0 / 8.0 + 0.5,
                    j as f64 * 4176.0 / 6.0 + 0.25,
                );
                for dist in [0.3, 2.0, 100.0] {
                    worst = worst.max(check(port, &l, u, v, dist));
                }
            }
        }
        // Exactness target of the issue: 1e-9 px.
        assert!(worst < 1e-9, "port {k}: worst {worst} px");
    }
}
