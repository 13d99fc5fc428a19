//! Small hand-built models for the Blender backend tests (independent of the scene loader).
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use poser::model::*;

pub const W: u32 = 160;
pub const H: u32 = 120;
pub const FX: f64 = 150.0;

/// A rotation whose columns are the camera axes: looking along -z (down), x east, y south.
pub fn looking_down() -> DMat3 {
    DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z)
}

pub fn glass() -> Glass {
    Glass {
        name: "N-BK7".into(),
        ior: [1.5145, 1.5185, 1.5253],
    }
}

pub fn camera(name: &str, port: Port) -> Camera {
    Camera {
        name: name.into(),
        width: W,
        height: H,
        pixel_pitch: 4e-6,
        focal_length: FX * 4e-6,
        fx: FX,
        fy: FX,
        cx: 83.7,
        cy: 57.2,
        lens: LensModel::Rectilinear,
        distortion: Distortion::default(),
        focus_distance: None,
        f_number: None,
        port,
        rig_from_camera: Pose::IDENTITY,
    }
}

pub fn flat_port() -> Port {
    Port::Flat {
        normal: DVec3::Z,
        distance: 0.02,
        thickness: 0.01,
        glass: glass(),
    }
}

pub fn water(absorption: Rgb, scattering: Rgb) -> Water {
    Water {
        ior: [1.3310, 1.3340, 1.3390],
        ior_source: IorSource::Constant,
        absorption,
        scattering,
        jerlov: None,
        phase: Phase::HenyeyGreenstein { g: 0.8 },
        extent: WaterExtent::Everywhere,
    }
}

pub fn plane(name: &str, size: f64, z: f64, albedo: f64) -> Object {
    Object {
        name: name.into(),
        shape: Shape::Plane {
            width: size,
            height: size,
        },
        pose: Pose {
            rotation: DMat3::IDENTITY,
            translation: DVec3::new(0.0, 0.0, z),
        },
        scale: DVec3::ONE,
        material: Material {
            albedo: [albedo; 3],
            pattern: None,
            variation: 0.0,
            texel: None,
        },
    }
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
    Model {
        name: name.into(),
        description: "blender backend test".into(),
        source: "tests/blender.toml".into(),
        water,
        site: Site {
            depth: 10.0,
            surface: SeaSurface::None,
            altitude: 0.0,
        },
        sun: None,
        cameras: vec![cam],
        lights,
        objects,
        targets: vec![],
        poses: vec![RigPose {
            name: "img_0001".into(),
            world_from_rig: Pose {
                rotation: looking_down(),
                translation: position,
            },
            time: 0.0,
            strip: 0,
        }],
        network: NetworkSummary::default(),
        diver: None,
        render: RenderSettings {
            samples: 16,
            seed: 7,
            max_bounces: 16,
            dispersion: false,
            outputs: vec!["rgb".into()],
            exposure: 1.0,
        },
        needs: Needs::default(),
    }
}

pub fn ambient(radiance: f64) -> Light {
    Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient {
            radiance: [radiance; 3],
        },
    }
}

/// The render tests use the real `bpy`; without it they fail with the setup hint.
pub fn require_bpy() {
    if let Err(e) = poser::backend::python::require_module("bpy") {
        panic!("{e}");
    }
}
