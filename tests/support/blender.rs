//! Presets of the Blender backend tests, from the one builder ([`super::model`]).
#![allow(dead_code)]

use super::model::Sensor;
use glam::DVec3;
use poser::model::*;

pub const W: u32 = 160;
pub const H: u32 = 120;
pub const FX: f64 = 150.0;

#[allow(unused_imports)]
pub use super::model::{ambient, glass, looking_down, plane};

pub fn camera(name: &str, port: Port) -> Camera {
    let sensor = Sensor {
        width: W,
        height: H,
        fx: FX,
        pitch: 4e-6,
        cx: 83.7,
        cy: 57.2,
    };
    super::model::camera(name, sensor, port)
}

/// A flat N-BK7 port 10 mm thick, 2 cm in front of the pupil.
pub fn flat_port() -> Port {
    super::model::flat_port(0.02, 0.01)
}

pub fn water(absorption: Rgb, scattering: Rgb) -> Water {
    super::model::water(
        [1.3310, 1.3340, 1.3390],
        absorption,
        scattering,
        Phase::HenyeyGreenstein { g: 0.8 },
    )
}

/// One camera at `position` looking down, the given lights and objects.
pub fn model(
    name: &str,
    cam: Camera,
    position: DVec3,
    water: Option<Water>,
    lights: Vec<Light>,
    objects: Vec<Object>,
) -> Model {
    let mut m = super::model::model(name, cam, water, super::model::nadir(position));
    m.description = "blender backend test".into();
    m.source = "tests/blender.toml".into();
    m.lights = lights;
    m.objects = objects;
    m.poses[0].name = "img_0001".into();
    m.needs = Needs::default();
    m
}

/// The render tests use the real `bpy`; without it they fail with the setup hint.
pub fn require_bpy() {
    if let Err(e) = poser::backend::python::require_module("bpy") {
        panic!("{e}");
    }
}
