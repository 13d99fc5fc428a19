//! The canonical scenes of `tests/canonical/` rendered by the native backend and checked
//! against the exact truth (target positions) and the analytic radiance oracle
//! (`support::canonical`). The same checks for Mitsuba and Cycles are in `cross_backend.rs`.

mod support;
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
fn analytic_reference_is_sane() {
    // The analytic model itself: a brighter strobe gives proportionally more radiance, and
    // the value is finite and positive at the image centre.
    let mut m = load("absorbing_strobe");
    let a = analytic(&m, 80.5, 60.5, 1);
    if let LightKind::Spot { intensity, .. } = &mut m.lights[0].kind {
        *intensity = intensity.map(|i| 2.0 * i);
    }
    let b = analytic(&m, 80.5, 60.5, 1);
    assert!(a.is_finite() && a > 0.0);
    assert!((b / a - 2.0).abs() < 1e-12);
}
