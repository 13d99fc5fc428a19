//! Presets of the native-renderer tests, from the one builder ([`super::model`]).
#![allow(dead_code)]

use super::model::Sensor;
use glam::DVec3;
use poser::model::*;

#[allow(unused_imports)]
pub use super::model::{rig_spot, sun_along};

/// A 160×120 nadir camera (no port, in the water) at height `h` above a Lambertian plane of
/// albedo 0.5 at z = 0; no lights; clear water of index 1.33 everywhere.
pub fn nadir_model(h: f64) -> Model {
    let sensor = Sensor {
        width: 160,
        height: 120,
        fx: 140.0,
        pitch: 4e-6,
        cx: 80.0,
        cy: 60.0,
    };
    let water = super::model::water(
        [1.33; 3],
        [0.0; 3],
        [0.0; 3],
        Phase::HenyeyGreenstein { g: 0.9 },
    );
    let mut m = super::model::model(
        "test",
        super::model::camera("cam", sensor, Port::None),
        Some(water),
        super::model::nadir(DVec3::new(0.0, 0.0, h)),
    );
    m.source = "tests/inline.toml".into();
    m.objects = vec![super::model::plane("floor", 0.0, 20.0, [0.5; 3])];
    m.render.max_bounces = 8;
    m.render.outputs = vec!["rgb".into(), "depth".into()];
    m.needs = Needs::default();
    m
}
