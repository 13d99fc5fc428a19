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
fn native_sun_refracts_per_channel() {
    // sun_seabed with a strongly dispersive water (n = 1.25 / 1.34 / 1.45) and more red
    // absorption: refracted with green's index alone, red would arrive 4.6 % too bright and
    // blue 1.3 % too dark (computed below). The render must follow each channel's direction to
    // the 1 % of the canonical radiometry (measured: 0.00000 in every channel, the water
    // absorbing only).
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/canonical/sun_seabed.toml");
    // One pass per channel (`render.dispersion`): in one green pass the camera side (the n²
    // law behind the port) takes green's index too, which is not what is tested here.
    let sets = [
        "water.ior=[1.25, 1.34, 1.45]",
        "water.absorption=[0.5, 0.08, 0.03]",
        "render.dispersion=true",
    ]
    .map(String::from);
    let model = poser::scene::load(&path, &sets)
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let dirs = model.sun_directions_water().unwrap();
    let sun = model.sun.as_ref().unwrap();
    let w = model.water.as_ref().unwrap();
    // Snell per channel: sin θ_air = n_c sin θ_c, blue the steepest; green's is the model's.
    let sin_air = (1.0 - sun.direction_air.z.powi(2)).sqrt();
    for (c, (d, n)) in dirs.iter().zip(w.ior).enumerate() {
        let sin_c = (1.0 - d.z.powi(2)).sqrt();
        assert!((sin_air - n * sin_c).abs() < 1e-12, "channel {c}");
    }
    assert!(-dirs[2].z > -dirs[1].z && -dirs[1].z > -dirs[0].z);
    assert_eq!(dirs[1], sun.direction_water);
    // What green's direction for every channel would give on the seabed 5 m down: the
    // irradiance there is E cos θ e^(−σa · 5 m / cos θ).
    let e = |c: usize, mu: f64| mu * (-w.absorption[c] * 5.0 / mu).exp();
    let shift: Vec<f64> = (0..3)
        .map(|c| e(c, -dirs[1].z) / e(c, -dirs[c].z) - 1.0)
        .collect();
    eprintln!("one direction against per channel: {shift:+.4?}");
    assert!(shift[0] > 0.03 && shift[2] < -0.01, "{shift:?}");
    radiometry_of("native", &model, "sun_seabed, dispersive water");
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
