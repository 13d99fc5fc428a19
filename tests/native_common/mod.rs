//! Shared builders for the native-renderer tests: small resolved models written in Rust.
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use poser::model::*;

/// A 160×120 nadir camera (no port, in the water) at height `h` above a Lambertian plane of
/// albedo 0.5 at z = 0; no lights; clear water of index 1.33 everywhere.
pub fn nadir_model(h: f64) -> Model {
    let (w, hh) = (160u32, 120u32);
    let f = 140.0;
    // Camera looking down (-z world): x right = +x world, y down = -y world, z forward = -z.
    let rot = DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z);
    Model {
        name: "test".into(),
        description: String::new(),
        source: "tests/inline.toml".into(),
        water: Some(Water {
            ior: [1.33; 3],
            ior_source: IorSource::Constant,
            absorption: [0.0; 3],
            scattering: [0.0; 3],
            jerlov: None,
            phase: Phase::HenyeyGreenstein { g: 0.9 },
            extent: WaterExtent::Everywhere,
        }),
        site: Site {
            depth: 10.0,
            surface: SeaSurface::None,
            altitude: 0.0,
        },
        sun: None,
        cameras: vec![Camera {
            name: "cam".into(),
            width: w,
            height: hh,
            pixel_pitch: 4e-6,
            focal_length: f * 4e-6,
            fx: f,
            fy: f,
            cx: w as f64 / 2.0,
            cy: hh as f64 / 2.0,
            lens: LensModel::Rectilinear,
            distortion: Distortion::default(),
            focus_distance: None,
            f_number: None,
            port: Port::None,
            rig_from_camera: Pose::IDENTITY,
        }],
        lights: vec![],
        objects: vec![Object {
            name: "floor".into(),
            shape: Shape::Plane {
                width: 20.0,
                height: 20.0,
            },
            pose: Pose::IDENTITY,
            scale: DVec3::ONE,
            material: Material {
                albedo: [0.5; 3],
                pattern: None,
                variation: 0.0,
                texel: None,
            },
        }],
        targets: vec![],
        poses: vec![RigPose {
            name: "img_0000".into(),
            world_from_rig: Pose {
                rotation: rot,
                translation: DVec3::new(0.0, 0.0, h),
            },
            time: 0.0,
            strip: 0,
        }],
        network: NetworkSummary::default(),
        diver: None,
        render: RenderSettings {
            samples: 16,
            seed: 7,
            max_bounces: 8,
            dispersion: false,
            outputs: vec!["rgb".into(), "depth".into()],
            exposure: 1.0,
        },
        needs: Needs::default(),
    }
}

/// A rig-mounted spot `offset` (rig frame) pointing forward (+z rig = down), 60° half angle.
pub fn rig_spot(offset: DVec3, intensity: f64) -> Light {
    Light {
        name: "strobe".into(),
        mount: Mount::Rig,
        kind: LightKind::Spot {
            position: offset,
            direction: DVec3::Z,
            half_angle: 60f64.to_radians(),
            intensity: [intensity; 3],
        },
    }
}

/// A sun whose light propagates along `dir` in air and in the water (no refraction), with the
/// given irradiance above and below the surface.
pub fn sun_along(dir: DVec3, irradiance: [f64; 3], irradiance_water: [f64; 3]) -> Sun {
    Sun {
        elevation: (-dir.z).asin(),
        azimuth: 0.0,
        irradiance,
        direction_air: dir,
        direction_water: dir,
        irradiance_water,
        from_time: None,
    }
}
