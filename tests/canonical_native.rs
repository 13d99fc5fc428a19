//! The canonical scenes of `tests/canonical/` rendered by the native backend and checked
//! against the exact truth (target positions) and the analytic radiance oracle
//! (`support::canonical`). The same checks for Mitsuba and Cycles are in `cross_backend.rs`.

use crate::support;
use poser::model::LightKind;
use support::canonical::*;

#[test]
fn native_geometry() {
    geometry("native");
}

#[test]
fn native_radiometry_strobe() {
    radiometry("native", "absorbing_strobe");
}

#[test]
fn native_radiometry_sun() {
    radiometry("native", "sun_seabed");
}

#[test]
fn analytic_reference_matches_a_hand_computation_on_the_axis() {
    // The oracle against the closed form worked out by hand for absorbing_strobe's principal
    // point, whose ray meets the flat port and the patch at normal incidence: water path
    // s = 1 m − (10 + 8) mm, the spot 0.6708 m away at cosθ = 0.6/0.6708, Fresnel at normal
    // incidence on both faces of the N-BK7 slab, n² law into the air behind the port.
    let m = load("absorbing_strobe");
    let cam = &m.cameras[0];
    let poser::model::Port::Flat {
        distance,
        thickness,
        glass,
        ..
    } = &cam.port
    else {
        panic!("absorbing_strobe has a flat port")
    };
    let w = m.water.as_ref().unwrap();
    let LightKind::Spot { intensity, .. } = &m.lights[0].kind else {
        panic!("one spot")
    };
    let rho = m.objects[0].material.albedo;
    for c in 0..3 {
        let (ng, nw) = (glass.ior[c], w.ior[c]);
        let r = |a: f64, b: f64| ((a - b) / (a + b)).powi(2);
        let t = (1.0 - r(1.0, ng)) * (1.0 - r(ng, nw));
        let s = 1.0 - distance - thickness;
        let dl = (0.3f64 * 0.3 + 0.6 * 0.6).sqrt();
        let e = intensity[c] * (0.6 / dl) / (dl * dl) * (-w.absorption[c] * dl).exp();
        let want = rho[c] / std::f64::consts::PI * e * (-w.absorption[c] * s).exp() * t / (nw * nw);
        let got = analytic(&m, cam.cx, cam.cy, c);
        eprintln!("channel {c}: oracle {got:.6e}, by hand {want:.6e}");
        assert!(
            (got / want - 1.0).abs() < 1e-6,
            "channel {c}: {got} vs {want}"
        );
    }
    // The oracle refuses what it cannot model: scattering water.
    assert!(poser::compare::analytic::applies(&load("scattering_backscatter")).is_err());
    assert!(poser::compare::analytic::applies(&m).is_ok());
}
