//! The hard cases of the refractive projection, each a named test (issue 3, "Exactness and
//! stability"). Reference pixels come from `optics::reference` (double-double, ≈ 32 digits),
//! so "exact" means within 1e-9 px of the f64-input exact answer.
use glam::DVec3;
use poser::model::{Distortion, LensModel};
use poser::optics::NoSolution;
use poser::optics::lens::Lens;
use poser::optics::port::{CylinderPort, DomePort, FlatPort, PortSolver};
use poser::optics::reference;

const F: f64 = 3200.0;
const CX: f64 = 2784.0;
const CY: f64 = 2088.0;
/// The exactness target.
const EXACT_PX: f64 = 1e-9;

fn lens() -> Lens {
    Lens::new(F, F, CX, CY, LensModel::Rectilinear, Distortion::default())
}
fn flat(n: DVec3, d: f64, t: f64) -> FlatPort {
    FlatPort::new(n, d, &[(t, 1.473)], 1.003, 1.333).unwrap()
}
fn px(port: &PortSolver, p: DVec3) -> Result<[f64; 2], NoSolution> {
    lens().project(port.forward(p)?)
}
fn flat_ref(n: DVec3, d: f64, t: f64, p: DVec3) -> [f64; 2] {
    let dir = reference::flat_forward(n, d, &[(t, 1.473)], 1.003, 1.333, p).unwrap();
    reference::pinhole(F, F, CX, CY, dir)
}
fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[test]
fn flat_point_on_axis_is_the_principal_point() {
    let port = PortSolver::Flat(flat(DVec3::Z, 0.05, 0.007));
    assert_eq!(px(&port, DVec3::new(0.0, 0.0, 2.0)).unwrap(), [CX, CY]);
}

#[test]
fn flat_point_1e9_m_off_axis_matches_reference_and_paraxial_limit() {
    let (d, t) = (0.05, 0.007);
    let port = PortSolver::Flat(flat(DVec3::Z, d, t));
    let p = DVec3::new(1e-9, -1e-9, 2.0);
    let got = px(&port, p).unwrap();
    assert!(dist(got, flat_ref(DVec3::Z, d, t, p)) < EXACT_PX);
    // Paraxial: ρ = f r / (d + t na/ng + D na/nw); second-order terms are ~1e-18 here.
    let depth = 2.0 - d - t;
    let want = F * 1e-9 / (d + t * 1.003 / 1.473 + depth * 1.003 / 1.333);
    assert!(
        ((got[0] - CX) - want).abs() < 1e-12,
        "{} vs {want}",
        got[0] - CX
    );
}

#[test]
fn flat_grazing_incidence_pixel_runs_to_1e5() {
    // A camera ray at u = 1e5 px (89.9° in air) refracts to ≈ 48.6° in water (θw ≤ asin(na/nw)).
    let (d, t) = (0.05, 0.007);
    let port = PortSolver::Flat(flat(DVec3::Z, d, t));
    let l = lens();
    let ray = port.backward(l.unproject(1e5, CY).unwrap()).unwrap();
    let cos_w = ray.dir.z;
    assert!(cos_w.acos() < (1.003f64 / 1.333).asin());
    for s in [0.01, 1.0, 100.0] {
        let p = ray.origin + ray.dir * s;
        let got = px(&port, p).unwrap();
        let want = flat_ref(DVec3::Z, d, t, p);
        // Relative 1e-14 of a 1e5 px coordinate is 1e-9 px.
        assert!(dist(got, want) < EXACT_PX, "s={s}: {got:?} vs {want:?}");
        assert!((got[0] - 1e5).abs() < 1e-6, "round trip {}", got[0]);
    }
    // The Projector rejects it as off the sensor (5568 px wide) with an explicit reason.
    assert!(got_offsensor());
}

fn got_offsensor() -> bool {
    use poser::model::{Camera, Glass, Port, Pose};
    let cam = Camera {
        name: "c".into(),
        width: 5568,
        height: 4176,
        pixel_pitch: 4e-6,
        focal_length: F * 4e-6,
        fx: F,
        fy: F,
        cx: CX,
        cy: CY,
        lens: LensModel::Rectilinear,
        distortion: Distortion::default(),
        focus_distance: None,
        f_number: None,
        port: Port::Flat {
            normal: DVec3::Z,
            distance: 0.05,
            thickness: 0.007,
            glass: Glass {
                name: "custom".into(),
                ior: [1.473; 3],
            },
            outer_layers: vec![],
        },
        rig_from_camera: Pose::IDENTITY,
    };
    let p = poser::optics::project::Projector::for_camera(&cam, 1, 1.333).unwrap();
    let ray = p.camera_ray(1e5, CY).unwrap();
    p.project_camera(ray.origin + ray.dir) == Err(NoSolution::OffSensor)
        && p.project_camera_unbounded(ray.origin + ray.dir).is_ok()
}

#[test]
fn flat_point_1mm_outside_the_glass_and_inside_it() {
    let (d, t) = (0.05, 0.007);
    let port = PortSolver::Flat(flat(DVec3::Z, d, t));
    for x in [0.0, 0.001, 0.05, 0.5] {
        let p = DVec3::new(x, 0.3 * x, d + t + 1e-3);
        let got = px(&port, p).unwrap();
        assert!(dist(got, flat_ref(DVec3::Z, d, t, p)) < EXACT_PX, "x={x}");
    }
    assert_eq!(
        px(&port, DVec3::new(0.1, 0.0, d + t - 1e-3)),
        Err(NoSolution::InsideGlass)
    );
    assert_eq!(
        px(&port, DVec3::new(0.1, 0.0, d + t)),
        Err(NoSolution::InsideGlass)
    );
    assert_eq!(
        px(&port, DVec3::new(0.1, 0.0, d * 0.5)),
        Err(NoSolution::InsideHousing)
    );
    assert_eq!(
        px(&port, DVec3::new(0.1, 0.0, -1.0)),
        Err(NoSolution::BehindCamera)
    );
}

#[test]
fn points_100m_away_all_ports() {
    let (d, t) = (0.05, 0.007);
    let fport = PortSolver::Flat(flat(DVec3::Z, d, t));
    let c = DVec3::new(0.00042007, 0.00366894, 0.0283927);
    let dport = PortSolver::Dome(DomePort::new(c, 0.05, 0.007, 1.003, 1.473, 1.333).unwrap());
    for p in [
        DVec3::new(30.0, -20.0, 100.0),
        DVec3::new(0.0, 1e-7, 100.0),
        DVec3::new(-57.0, 0.0, 82.0),
    ] {
        let got = px(&fport, p).unwrap();
        assert!(dist(got, flat_ref(DVec3::Z, d, t, p)) < EXACT_PX, "{p}");
        let got = px(&dport, p).unwrap();
        let want = reference::pinhole(
            F,
            F,
            CX,
            CY,
            reference::dome_forward(c, 0.05, 0.057, 1.003, 1.473, 1.333, p).unwrap(),
        );
        assert!(dist(got, want) < EXACT_PX, "dome {p}: {got:?} {want:?}");
    }
}

#[test]
fn centred_dome_equals_the_pinhole_exactly() {
    let port = PortSolver::Dome(DomePort::new(DVec3::ZERO, 0.1, 0.007, 1.0, 1.523, 1.333).unwrap());
    let l = lens();
    for p in [
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-2.0, 1.0, 0.5),
        DVec3::new(0.0, 0.0, 3.0),
    ] {
        assert_eq!(px(&port, p).unwrap(), l.project(p).unwrap());
    }
    // And the backward ray is undeviated (normal incidence on both spheres).
    let v = l.unproject(100.0, 4000.0).unwrap();
    let r = port.backward(v).unwrap();
    assert!((r.dir - v).length() < 1e-15);
    assert!((r.origin.length() - 0.107).abs() < 1e-15);
}

#[test]
fn dome_decentred_by_1e9_m() {
    let c = DVec3::new(1e-9, 0.0, 0.0);
    let port = PortSolver::Dome(DomePort::new(c, 0.05, 0.007, 1.003, 1.473, 1.333).unwrap());
    let l = lens();
    for p in [
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(0.0, 0.5, 0.7),
        DVec3::new(1e-6, 0.0, 2.0),
    ] {
        let got = px(&port, p).unwrap();
        let want = reference::pinhole(
            F,
            F,
            CX,
            CY,
            reference::dome_forward(c, 0.05, 0.057, 1.003, 1.473, 1.333, p).unwrap(),
        );
        assert!(dist(got, want) < EXACT_PX, "{p}: {got:?} vs {want:?}");
        // Continuity with the centred dome: moves by O(e/R) only (docs/optics.md §1.4: ~5e-6 px).
        assert!(dist(got, l.project(p).unwrap()) < 1e-4);
    }
}

#[test]
fn dome_strongly_decentred_matches_reference() {
    for c in [
        DVec3::new(0.00042007, 0.00366894, 0.0283927),
        DVec3::new(0.0342007, 0.0366894, 0.0083927),
    ] {
        let r1 = if c.length() > 0.04 { 0.1 } else { 0.05 };
        let port = PortSolver::Dome(DomePort::new(c, r1, 0.007, 1.003, 1.473, 1.333).unwrap());
        for p in [
            DVec3::new(0.3, -0.2, 1.0),
            DVec3::new(-1.0, 0.4, 0.9),
            DVec3::new(0.01, 0.02, 0.3),
        ] {
            let got = px(&port, p).unwrap();
            let dir = reference::dome_forward(c, r1, r1 + 0.007, 1.003, 1.473, 1.333, p).unwrap();
            let want = reference::pinhole(F, F, CX, CY, dir);
            assert!(dist(got, want) < EXACT_PX, "{c} {p}: {got:?} vs {want:?}");
        }
    }
}

#[test]
fn dome_points_inside_are_rejected() {
    let c = DVec3::new(0.002, 0.0, 0.001);
    let port = PortSolver::Dome(DomePort::new(c, 0.05, 0.007, 1.0, 1.473, 1.333).unwrap());
    assert_eq!(
        port.forward(DVec3::new(0.0, 0.0, 0.04)),
        Err(NoSolution::InsideHousing)
    );
    assert_eq!(
        port.forward(DVec3::new(0.0, 0.0, 0.055)),
        Err(NoSolution::InsideGlass)
    );
    assert!(port.forward(DVec3::new(0.0, 0.0, 0.059)).is_ok());
    assert!(DomePort::new(DVec3::new(0.06, 0.0, 0.0), 0.05, 0.007, 1.0, 1.5, 1.33).is_err());
}

#[test]
fn glass_thickness_to_zero() {
    for t in [0.0, 1e-9, 1e-6] {
        let port = PortSolver::Flat(flat(DVec3::Z, 0.05, t));
        let l = lens();
        for p in [DVec3::new(0.4, 0.3, 1.0), DVec3::new(-3.0, 0.1, 1.0)] {
            let got = px(&port, p).unwrap();
            assert!(
                dist(got, flat_ref(DVec3::Z, 0.05, t, p)) < EXACT_PX,
                "t={t}"
            );
            let ray = port.backward(l.unproject(got[0], got[1]).unwrap()).unwrap();
            let miss = (p - ray.origin).cross(ray.dir).length();
            assert!(miss < 1e-12, "t={t}: ray misses P by {miss} m");
        }
        // A zero-thickness dome is also fine.
        let dport = PortSolver::Dome(
            DomePort::new(DVec3::new(0.001, 0.0, 0.0), 0.05, t, 1.0, 1.5, 1.33).unwrap(),
        );
        assert!(px(&dport, DVec3::new(0.2, 0.1, 1.0)).is_ok());
    }
}

#[test]
fn tilted_flat_ports() {
    let n = DVec3::new(0.1, -0.05, 1.0);
    let (d, t) = (0.05, 0.007);
    let port = PortSolver::Flat(flat(n, d, t));
    // On the port axis: undeviated, projects to pinhole(N) (docs/optics.md §1.3; (740, 430) for f = 1000).
    let on_axis = n.normalize() * 2.0;
    let got = px(&port, on_axis).unwrap();
    assert!(dist(got, lens().project(n).unwrap()) < 1e-12);
    let l1000 = Lens::new(
        1000.0,
        1000.0,
        640.0,
        480.0,
        LensModel::Rectilinear,
        Distortion::default(),
    );
    let p1000 = l1000.project(port.forward(on_axis).unwrap()).unwrap();
    assert!(dist(p1000, [740.0, 430.0]) < 1e-9);
    for p in [
        DVec3::new(0.5, 0.2, 1.5),
        DVec3::new(-1.0, -0.7, 2.0),
        DVec3::new(1e-9, 0.0, 2.0),
    ] {
        let got = px(&port, p).unwrap();
        assert!(dist(got, flat_ref(n, d, t, p)) < EXACT_PX, "{p}");
    }
    // A point whose solution ray has v_z ≤ 0 (far to the side of a strongly tilted port) is
    // explicitly not imageable.
    let steep = PortSolver::Flat(flat(DVec3::new(1.0, 0.0, 0.3), d, t));
    assert_eq!(
        px(&steep, DVec3::new(5.0, 0.0, -1.2)),
        Err(NoSolution::BehindCamera)
    );
}

#[test]
fn multilayer_flat_port() {
    let layers = [(0.004, 1.5168), (0.001, 1.40), (0.006, 1.77)];
    let port = PortSolver::Flat(FlatPort::new(DVec3::Z, 0.03, &layers, 1.0, 1.34).unwrap());
    for p in [DVec3::new(0.5, 0.2, 1.5), DVec3::new(2.0, -0.7, 0.8)] {
        let got = px(&port, p).unwrap();
        let want = reference::pinhole(
            F,
            F,
            CX,
            CY,
            reference::flat_forward(DVec3::Z, 0.03, &layers, 1.0, 1.34, p).unwrap(),
        );
        assert!(dist(got, want) < EXACT_PX);
    }
}

#[test]
fn cylinder_with_the_camera_off_its_axis() {
    let port = PortSolver::Cylinder(
        CylinderPort::new(
            DVec3::new(0.01, 0.0, -0.005),
            DVec3::Y,
            0.06,
            0.008,
            1.0,
            1.49,
            1.34,
        )
        .unwrap(),
    );
    let l = lens();
    for (u, v) in [(10.0, 10.0), (CX, CY), (5000.0, 300.0), (2000.0, 4100.0)] {
        let ray = port.backward(l.unproject(u, v).unwrap()).unwrap();
        for s in [0.05, 1.0, 50.0] {
            let got = px(&port, ray.origin + ray.dir * s).unwrap();
            assert!(dist(got, [u, v]) < EXACT_PX, "({u},{v}) s={s}: {got:?}");
        }
    }
    // Consistency (docs/optics.md §1.5): a point in the symmetry plane of a decentred cylinder
    // projects like a dome with the same offset.
    let off = DVec3::new(0.003, 0.0, 0.0);
    let cyl = PortSolver::Cylinder(
        CylinderPort::new(off, DVec3::Y, 0.05, 0.007, 1.003, 1.473, 1.333).unwrap(),
    );
    let dome = PortSolver::Dome(DomePort::new(off, 0.05, 0.007, 1.003, 1.473, 1.333).unwrap());
    let p = DVec3::new(0.4, 0.0, 1.2);
    assert!(dist(px(&cyl, p).unwrap(), px(&dome, p).unwrap()) < EXACT_PX);
}

#[test]
fn cylinder_on_axis_meridional_q_equation() {
    let port = PortSolver::Cylinder(
        CylinderPort::new(DVec3::ZERO, DVec3::Y, 0.06, 0.008, 1.0, 1.49, 1.34).unwrap(),
    );
    // Equivalent flat port in the meridional plane: N = e_ρ, d = R, D = ρ − R − t.
    let p = DVec3::new(0.3, 0.5, 1.0);
    let e_rho = DVec3::new(0.3, 0.0, 1.0).normalize();
    let dir = reference::flat_forward(e_rho, 0.06, &[(0.008, 1.49)], 1.0, 1.34, p).unwrap();
    let want = reference::pinhole(F, F, CX, CY, dir);
    assert!(dist(px(&port, p).unwrap(), want) < EXACT_PX);
    // A point on the axis line itself is inside the housing.
    assert_eq!(
        port.forward(DVec3::new(0.0, 2.0, 0.0)),
        Err(NoSolution::InsideHousing)
    );
    // A camera ray along the axis never leaves the port.
    assert_eq!(port.backward(DVec3::Y), Err(NoSolution::MissesPort));
}

#[test]
fn total_internal_reflection_where_the_geometry_allows_it() {
    // A liquid-filled housing (n = 1.333) looking through glass into air (n = 1): beyond the
    // critical angle asin(1/1.333) = 48.6° the camera ray is totally reflected.
    let port = FlatPort::new(DVec3::Z, 0.02, &[(0.005, 1.5)], 1.333, 1.0).unwrap();
    let inside = DVec3::new(40f64.to_radians().sin(), 0.0, 40f64.to_radians().cos());
    let beyond = DVec3::new(50f64.to_radians().sin(), 0.0, 50f64.to_radians().cos());
    assert!(port.backward(inside).is_ok());
    assert_eq!(
        port.backward(beyond),
        Err(NoSolution::TotalInternalReflection)
    );
    // Forward still finds every point (its camera ray is inside the critical cone), exactly.
    let port_s = PortSolver::Flat(port);
    for p in [
        DVec3::new(5.0, 1.0, 1.0),
        DVec3::new(0.2, 0.0, 1.0),
        DVec3::new(100.0, 0.0, 0.03),
    ] {
        let dir = port_s.forward(p).unwrap();
        let sin_a = dir.normalize().cross(DVec3::Z).length();
        assert!(sin_a < 1.0 / 1.333 + 1e-12);
        let want = reference::pinhole(
            F,
            F,
            CX,
            CY,
            reference::flat_forward(DVec3::Z, 0.02, &[(0.005, 1.5)], 1.333, 1.0, p).unwrap(),
        );
        assert!(dist(lens().project(dir).unwrap(), want) < EXACT_PX, "{p}");
    }
    // A dome whose glass is optically thinner than the housing medium: TIR at the inner
    // surface for strongly oblique rays of a decentred dome.
    let dome = DomePort::new(DVec3::new(0.04, 0.0, 0.0), 0.05, 0.005, 1.45, 1.0, 1.333).unwrap();
    let v = DVec3::new(-0.2, 0.0, 1.0).normalize();
    assert_eq!(dome.backward(v), Err(NoSolution::TotalInternalReflection));
}

#[test]
fn flat_port_with_zero_gap_beyond_critical_angle() {
    // Pupil on the glass (d = 0): the visible cone in water is bounded, points outside it have
    // no pixel.
    let port = PortSolver::Flat(flat(DVec3::Z, 0.0, 0.007));
    assert_eq!(
        port.forward(DVec3::new(10.0, 0.0, 1.0)),
        Err(NoSolution::BeyondCriticalAngle)
    );
    assert!(port.forward(DVec3::new(1.0, 0.0, 1.0)).is_ok());
}

#[test]
fn non_finite_inputs_never_produce_nan() {
    let ports = [
        PortSolver::Flat(flat(DVec3::Z, 0.05, 0.007)),
        PortSolver::Dome(
            DomePort::new(DVec3::new(0.001, 0.002, 0.0), 0.05, 0.007, 1.0, 1.5, 1.33).unwrap(),
        ),
        PortSolver::Cylinder(
            CylinderPort::new(
                DVec3::new(0.01, 0.0, 0.0),
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
    let l = lens();
    for port in &ports {
        for p in [
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::new(f64::INFINITY, 0.0, 1.0),
            DVec3::new(1e300, 1e300, 1e300),
            DVec3::new(1e-300, 0.0, 1.0),
            DVec3::ZERO,
        ] {
            if let Ok(d) = port.forward(p)
                && let Ok(px) = l.project(d)
            {
                {
                    assert!(px[0].is_finite() && px[1].is_finite(), "{p}");
                }
            }
        }
        for (u, v) in [(f64::NAN, 0.0), (1e300, 0.0), (-1e12, 5.0)] {
            if let Ok(d) = l.unproject(u, v)
                && let Ok(r) = port.backward(d)
            {
                {
                    assert!(
                        r.origin.is_finite() && r.dir.is_finite() && r.transmittance.is_finite()
                    );
                }
            }
        }
    }
}

#[test]
fn chromatic_projection_per_channel() {
    // Flat BK7 port in sea water: R and B land apart off-axis, coincide on the axis.
    use poser::optics::{glass, water};
    let wl = poser::model::CHANNEL_WAVELENGTHS_NM;
    let ng = wl.map(|l| glass::catalogue_ior("N-BK7", l).unwrap());
    let nw = wl.map(|l| water::seawater_ior(15.0, 35.0, 10.0, l));
    let ports: Vec<PortSolver> = (0..3)
        .map(|c| {
            PortSolver::Flat(FlatPort::new(DVec3::Z, 0.03, &[(0.01, ng[c])], 1.0, nw[c]).unwrap())
        })
        .collect();
    let p = DVec3::new(0.8, 0.5, 1.0);
    let px: Vec<[f64; 2]> = ports
        .iter()
        .map(|port| lens().project(port.forward(p).unwrap()).unwrap())
        .collect();
    // Blue sees a higher water index: a flat port magnifies by ≈ n_water, so blue lands
    // farther from the centre than green, green farther than red.
    assert!(px[2][0] > px[1][0] && px[1][0] > px[0][0]);
    assert!(dist(px[0], px[2]) > 1.0);
    let on_axis = DVec3::new(0.0, 0.0, 1.0);
    assert_eq!(px_of(&ports[0], on_axis), px_of(&ports[2], on_axis));
}

fn px_of(port: &PortSolver, p: DVec3) -> [f64; 2] {
    lens().project(port.forward(p).unwrap()).unwrap()
}

#[test]
fn lateral_colour_at_the_corners() {
    use poser::model::{Camera, Glass, Port, Pose};
    let mut cam = Camera {
        name: "c".into(),
        width: 4000,
        height: 3000,
        pixel_pitch: 4e-6,
        focal_length: 0.012,
        fx: 3000.0,
        fy: 3000.0,
        cx: 2000.0,
        cy: 1500.0,
        lens: LensModel::Rectilinear,
        distortion: Distortion::default(),
        focus_distance: None,
        f_number: None,
        port: Port::Flat {
            normal: DVec3::Z,
            distance: 0.03,
            thickness: 0.01,
            glass: Glass {
                name: "N-BK7".into(),
                ior: [1.51452, 1.518522, 1.52532],
            },
            outer_layers: vec![],
        },
        rig_from_camera: Pose::IDENTITY,
    };
    let water = [1.3377, 1.3408, 1.3459];
    let flat = poser::optics::lateral_color_px(&cam, water);
    // Flat port: several pixels at the corners of a 4000 px sensor (≈ (nB−nR)/n · tan² shift).
    assert!(flat > 2.0 && flat < 100.0, "{flat}");
    cam.port = Port::Dome {
        center: DVec3::ZERO,
        inner_radius: 0.1,
        thickness: 0.01,
        glass: Glass {
            name: "N-BK7".into(),
            ior: [1.51452, 1.518522, 1.52532],
        },
    };
    // A centred dome has no lateral colour at all.
    assert_eq!(poser::optics::lateral_color_px(&cam, water), 0.0);
    cam.port = Port::None;
    assert_eq!(poser::optics::lateral_color_px(&cam, water), 0.0);
}

#[test]
fn tilted_flat_port_ray_89_98_degrees_off_its_normal() {
    // Found by the million-case property test: a fisheye ray almost parallel to a tilted port
    // (cos = 2.2e-4) needs q ≈ 4000; the solver must switch from Halley to monotone Newton
    // far from the root instead of giving up.
    let l = Lens::new(
        395.3125,
        395.3125,
        635.7477672351733,
        673.7670935898929,
        LensModel::FisheyeEquisolid,
        Distortion::default(),
    );
    let n = DVec3::new(0.22104378626465523, -0.0808534024916798, 0.9719065653957194);
    let port =
        PortSolver::Flat(FlatPort::new(n, 0.04464238403980347, &[(0.0, 1.3)], 1.0, 1.32).unwrap());
    for (u, v, s) in [(142.0, 637.0, 100.0), (142.0, 643.0, 27.825594022071257)] {
        let ray = port.backward(l.unproject(u, v).unwrap()).unwrap();
        let p = ray.origin + ray.dir * s;
        let got = l.project(port.forward(p).unwrap()).unwrap();
        assert!(dist(got, [u, v]) < EXACT_PX, "({u},{v}): {got:?}");
    }
}
