//! Presets of the Mitsuba backend tests, from the one builder ([`super::model`]).
#![allow(dead_code)]

use super::model::Sensor;
use glam::{DMat3, DVec3};
use poser::model::*;

#[allow(unused_imports)]
pub use super::model::{glass, model as base, nadir, plane, render_settings};

/// The Mitsuba tests' sensor: 160×120, fx 140, principal point off centre.
pub const SENSOR: Sensor = Sensor {
    width: 160,
    height: 120,
    fx: 140.0,
    pitch: 5e-6,
    cx: 83.7,
    cy: 57.2,
};

/// An untilted flat N-BK7 port 12 mm thick at `distance`.
pub fn flat_port(distance: f64) -> Port {
    super::model::flat_port(distance, 0.012)
}

pub fn camera(name: &str, port: Port) -> Camera {
    super::model::camera(name, SENSOR, port)
}

pub fn water(absorption: Rgb, scattering: Rgb, phase: Phase) -> Water {
    super::model::water([1.3310, 1.3339, 1.3390], absorption, scattering, phase)
}

/// A rich model touching every emitter and port kind (for snapshots and stability).
pub fn showcase() -> Model {
    let mut m = base(
        "showcase",
        camera("left", flat_port(0.01)),
        Some(water(
            [0.4, 0.1, 0.05],
            [0.2, 0.3, 0.4],
            Phase::HenyeyGreenstein { g: 0.8 },
        )),
        nadir(DVec3::new(0.0, 0.0, -8.0)),
    );
    let mut right = camera(
        "right",
        Port::Dome {
            center: DVec3::new(0.0, 0.001, 0.0),
            inner_radius: 0.05,
            thickness: 0.008,
            glass: glass(),
        },
    );
    right.rig_from_camera = Pose {
        rotation: DMat3::IDENTITY,
        translation: DVec3::new(0.2, 0.0, 0.0),
    };
    m.cameras.push(right);
    m.poses.push(RigPose {
        name: "img_0001".into(),
        world_from_rig: nadir(DVec3::new(0.5, 0.0, -8.0)),
        time: 2.0,
        strip: 0,
    });
    m.site.surface = SeaSurface::Flat;
    m.sun = Some(Sun {
        elevation: 1.0,
        azimuth: 0.5,
        irradiance: [800.0, 900.0, 850.0],
        direction_air: DVec3::new(-0.25, -0.46, -0.85).normalize(),
        direction_water: DVec3::new(-0.19, -0.35, -0.92).normalize(),
        irradiance_water: [700.0, 780.0, 740.0],
        from_time: None,
    });
    m.lights = vec![
        Light {
            name: "strobe \"L\"".into(),
            mount: Mount::Rig,
            kind: LightKind::Spot {
                position: DVec3::new(-0.3, 0.0, 0.0),
                direction: DVec3::new(0.2, 0.0, 1.0),
                half_angle: 0.6,
                intensity: [50.0, 50.0, 50.0],
            },
        },
        Light {
            name: "lamp".into(),
            mount: Mount::World,
            kind: LightKind::Point {
                position: DVec3::new(1.0, 1.0, -9.0),
                intensity: [5.0, 4.0, 3.0],
            },
        },
        Light {
            name: "panel".into(),
            mount: Mount::World,
            kind: LightKind::Area {
                frame: Pose {
                    rotation: DMat3::IDENTITY,
                    translation: DVec3::new(0.0, 2.0, -9.5),
                },
                width: 0.5,
                height: 0.25,
                radiance: [10.0, 10.0, 10.0],
            },
        },
        Light {
            name: "sky".into(),
            mount: Mount::World,
            kind: LightKind::Ambient {
                radiance: [0.1, 0.2, 0.3],
            },
        },
    ];
    m.objects = vec![
        plane("seabed", -10.0, 20.0, [0.4, 0.35, 0.3]),
        Object {
            backdrop: false,
            name: "rock".into(),
            shape: Shape::Sphere { radius: 0.3 },
            pose: Pose {
                rotation: DMat3::IDENTITY,
                translation: DVec3::new(0.5, 0.2, -9.8),
            },
            scale: DVec3::ONE,
            material: Material {
                albedo: [0.2, 0.2, 0.2],
                pattern: None,
                variation: 0.0,
                texel: None,
                grid: None,
                glass: None,
                fill: None,
            },
        },
        Object {
            backdrop: false,
            name: "crate".into(),
            shape: Shape::Box {
                size: DVec3::new(0.4, 0.3, 0.2),
            },
            pose: Pose {
                rotation: DMat3::from_rotation_z(0.3),
                translation: DVec3::new(-0.5, 0.2, -9.9),
            },
            scale: DVec3::ONE,
            material: Material {
                albedo: [0.6, 0.5, 0.1],
                pattern: None,
                variation: 0.0,
                texel: None,
                grid: None,
                glass: None,
                fill: None,
            },
        },
        Object {
            backdrop: false,
            name: "pipe".into(),
            shape: Shape::Cylinder {
                radius: 0.1,
                height: 1.0,
            },
            pose: Pose {
                rotation: DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2),
                translation: DVec3::new(0.0, -0.5, -9.9),
            },
            scale: DVec3::ONE,
            material: Material {
                albedo: [0.3, 0.3, 0.3],
                pattern: None,
                variation: 0.0,
                texel: None,
                grid: None,
                glass: None,
                fill: None,
            },
        },
    ];
    m.needs.sun_refraction = true;
    m
}
