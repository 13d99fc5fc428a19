//! Cross-backend agreement (issue 7): the canonical scenes of `tests/canonical/`, one effect
//! each, rendered by Mitsuba and Cycles and checked against the exact truth and the analytic
//! radiometry (`support::canonical`; the native backend's runs are in `canonical_native.rs`),
//! and the backends against each other.
//!
//! Tolerance between backends in scattering water: ≤ 2 % on the image mean.

use crate::support;
use support::canonical::*;

#[test]
fn blender_geometry() {
    geometry("blender");
}

#[test]
fn blender_radiometry_strobe() {
    radiometry("blender", "absorbing_strobe");
}

#[test]
fn blender_radiometry_sun() {
    radiometry("blender", "sun_seabed");
}

#[test]
fn mitsuba_geometry() {
    geometry("mitsuba");
}

#[test]
fn mitsuba_radiometry_strobe() {
    radiometry("mitsuba", "absorbing_strobe");
}

#[test]
fn mitsuba_radiometry_sun() {
    radiometry("mitsuba", "sun_seabed");
}

/// Issue 7's target between backends in scattering water (image means, per channel).
const MAX_BETWEEN_BACKENDS: f64 = 0.02;

#[test]
fn backends_agree_in_scattering_water() {
    // Like for like: native traces the light through the water as Mitsuba and Cycles do,
    // whatever the native default for daylight is (this scene has only a strobe today).
    let mut model = load("scattering_backscatter");
    model.render.daylight = poser::model::Daylight::Traced;
    model.render.surface_from_below = poser::model::Underside::Open;
    let tmp = tempfile::tempdir().unwrap();
    let means: Vec<(&str, [f64; 3])> = ["native", "mitsuba", "blender"]
        .into_iter()
        .map(|b| (b, image_mean(b, &model, &tmp.path().join(b), 256)))
        .collect();
    // Every pair of distinct backends (native–Mitsuba, native–Cycles, Mitsuba–Cycles); no
    // backend is compared with itself.
    for (i, (a, ma)) in means.iter().enumerate() {
        for (b, mb) in &means[i + 1..] {
            for c in 0..3 {
                let rel = mb[c] / ma[c] - 1.0;
                eprintln!("scattering: {b} / {a} − 1, channel {c} = {rel:+.4}");
                assert!(
                    rel.abs() <= MAX_BETWEEN_BACKENDS,
                    "{b} vs {a} channel {c}: {rel:+.4}"
                );
            }
        }
    }
}

/// The bounce budgets mean the same thing in every backend: at `bounces = 1` (direct light and
/// single scattering only) behind a flat port, Mitsuba and Cycles must neither stop at the
/// port's two glass faces (a black image, as before the port's faces were added to their
/// budgets) nor add a second scattering event (Cycles was 21–43 % too bright when its
/// per-kind budgets were not one less than poser's). Scene: the render benchmark's
/// `strobe_backscatter` at 80×60. Measured at 128 spp: Cycles −0.2–0 %, Mitsuba −0.3–−0.2 %
/// of native; the check allows the same 2 % as above.
#[test]
fn single_scattering_behind_a_port_means_the_same_in_every_backend() {
    let model = poser::bench::render::bench_model(80, 60);
    assert_eq!(model.render.max_bounces, 1);
    let tmp = tempfile::tempdir().unwrap();
    let native = image_mean("native", &model, &tmp.path().join("native"), 128);
    for b in ["mitsuba", "blender"] {
        let m = image_mean(b, &model, &tmp.path().join(b), 128);
        for c in 0..3 {
            let rel = m[c] / native[c] - 1.0;
            eprintln!("bounces = 1: {b} / native − 1, channel {c} = {rel:+.4}");
            assert!(
                rel.abs() <= MAX_BETWEEN_BACKENDS,
                "{b} channel {c}: {rel:+.4}"
            );
        }
    }
}

/// An area light seen directly by a camera without a port, in water: Blender 5 makes a new
/// light invisible to camera rays, so Cycles rendered it black (0 against native's 0.46 in
/// green) until the builder set its camera visibility (AREA_SEEN in builder.py). Behind a port
/// the camera's rays reach it as transmission rays, which were always visible.
#[test]
fn an_area_light_seen_by_a_camera_without_a_port_is_seen_in_every_backend() {
    let model = support::column::load_text(
        r#"name = "area_seen"
[site]
depth = "10 m"
surface = "none"
[water]
ior = 1.34
absorption = [0.5, 0.1, 0.05]
scattering = 0.0
[camera]
width = 48
height = 36
sensor_width = "36 mm"
focal_length = "28 mm"
[camera.port]
type = "none"
[[lights]]
name = "panel"
type = "area"
mount = "world"
position = [0.0, 0.0, -9.0]
aim = [0.0, 0.0, 1.0]
width = "0.8 m"
height = "0.8 m"
radiance = 1.0
[network]
type = "explicit"
[[network.poses]]
position = [0.0, 0.0, -8.0]
look_at = [0.0, 0.0, -10.0]
up = [0.0, 1.0, 0.0]
[render]
samples = 16
seed = 1
"#,
        &[],
    );
    let tmp = tempfile::tempdir().unwrap();
    let native = image_mean("native", &model, &tmp.path().join("native"), 16);
    let cycles = image_mean("blender", &model, &tmp.path().join("blender"), 16);
    assert!(native[1] > 0.3, "{native:?}");
    for c in 0..3 {
        let rel = cycles[c] / native[c] - 1.0;
        assert!(rel.abs() < 0.01, "channel {c}: {cycles:?} vs {native:?}");
    }
}
