//! The one model builder of the integration tests: resolved models written in Rust, independent
//! of the scene front end. Every suite's presets ([`super::mitsuba`], [`super::blender`],
//! [`super::native`], [`super::plan`]) are built from these pieces.
//!
//! | item | default |
//! |---|---|
//! | [`model`] | one camera at one rig pose `img_0000`, no lights, objects or targets; site 10 m deep, no sea surface; [`render_settings`]`(16)`; needs: medium when the water attenuates, refraction when the camera has a port |
//! | [`camera`] | rectilinear, no distortion, pinhole, no port offset in the rig, from a [`Sensor`] |
//! | [`glass`] | N-BK7 per channel |
//! | [`water`] | constant indices, everywhere |
//! | [`plane`] | `plane(name, z, size, albedo)`: a horizontal square at height z, normal +z |
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use poser::model::*;

/// Sensor and intrinsics of a test camera.
#[derive(Debug, Clone, Copy)]
pub struct Sensor {
    pub width: u32,
    pub height: u32,
    /// Focal length in pixels (fx = fy).
    pub fx: f64,
    /// Pixel pitch, m.
    pub pitch: f64,
    pub cx: f64,
    pub cy: f64,
}

/// A rectilinear camera with `sensor` behind `port`, at the rig origin.
pub fn camera(name: &str, sensor: Sensor, port: Port) -> Camera {
    Camera {
        name: name.into(),
        width: sensor.width,
        height: sensor.height,
        pixel_pitch: sensor.pitch,
        focal_length: sensor.fx * sensor.pitch,
        fx: sensor.fx,
        fy: sensor.fx,
        cx: sensor.cx,
        cy: sensor.cy,
        lens: LensModel::Rectilinear,
        distortion: Distortion::default(),
        focus_distance: None,
        f_number: None,
        port,
        rig_from_camera: Pose::IDENTITY,
    }
}

/// Camera axes looking along world −z (down): x_cam = +x world, y_cam = −y world.
pub fn looking_down() -> DMat3 {
    DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z)
}

/// A rig pose looking down from `pos`.
pub fn nadir(pos: DVec3) -> Pose {
    Pose {
        rotation: looking_down(),
        translation: pos,
    }
}

/// N-BK7 at the R, G, B wavelengths.
pub fn glass() -> Glass {
    Glass {
        name: "N-BK7".into(),
        ior: [1.5145, 1.5185, 1.5253],
    }
}

/// An untilted flat N-BK7 port.
pub fn flat_port(distance: f64, thickness: f64) -> Port {
    Port::Flat {
        normal: DVec3::Z,
        distance,
        thickness,
        glass: glass(),
        outer_layers: vec![],
    }
}

/// Homogeneous water everywhere with constant indices `ior`.
pub fn water(ior: Rgb, absorption: Rgb, scattering: Rgb, phase: Phase) -> Water {
    Water {
        ior,
        ior_source: IorSource::Constant,
        absorption,
        scattering,
        jerlov: None,
        phase,
        extent: WaterExtent::Everywhere,
    }
}

/// A horizontal Lambertian square of side `size` at height `z`, normal +z.
pub fn plane(name: &str, z: f64, size: f64, albedo: Rgb) -> Object {
    Object {
        backdrop: false,
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
            albedo,
            pattern: None,
            variation: 0.0,
            texel: None,
            grid: None,
            glass: None,
            fill: None,
        },
    }
}

/// One rig pose.
pub fn pose(name: &str, world_from_rig: Pose) -> RigPose {
    RigPose {
        name: name.into(),
        world_from_rig,
        time: 0.0,
        strip: 0,
    }
}

/// `samples` per pixel, seed 7, 16 bounces, RGB only, exposure 1.
pub fn render_settings(samples: u32) -> RenderSettings {
    RenderSettings {
        samples,
        seed: 7,
        max_bounces: 16,
        dispersion: false,
        outputs: vec!["rgb".into()],
        exposure: 1.0,
        denoise_radius: None,
        noise: None,
        daylight: Default::default(),
        texture_filter: Default::default(),
        sampler: Default::default(),
        surface_from_below: Default::default(),
        crop: None,
    }
}

/// A minimal model: camera `cam` at rig pose `img_0000` = `world_from_rig` (see the module table).
pub fn model(name: &str, cam: Camera, water: Option<Water>, world_from_rig: Pose) -> Model {
    let refraction = !matches!(cam.port, Port::None);
    let medium = water
        .as_ref()
        .map(|w| w.extinction().iter().any(|&s| s > 0.0))
        .unwrap_or(false);
    Model {
        name: name.into(),
        description: String::new(),
        source: format!("{name}.toml"),
        water,
        site: Site {
            depth: 10.0,
            surface: SeaSurface::None,
            altitude: 0.0,
            seed: 0,
        },
        sun: None,
        cameras: vec![cam],
        lights: vec![],
        objects: vec![],
        targets: vec![],
        poses: vec![pose("img_0000", world_from_rig)],
        network: NetworkSummary::default(),
        diver: None,
        render: render_settings(16),
        sensor: None,
        lesson: None,
        needs: Needs {
            medium,
            refraction,
            ..Default::default()
        },
    }
}

/// A rig-mounted spot at `offset` (rig frame) pointing along the rig's +z, 60° half angle.
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

/// Uniform ambient radiance (a grey sky).
pub fn ambient(radiance: f64) -> Light {
    Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient {
            radiance: [radiance; 3],
        },
    }
}

/// A sun whose light propagates along `dir` in air and in the water (no refraction), with the
/// given irradiance above and below the surface.
pub fn sun_along(dir: DVec3, irradiance: Rgb, irradiance_water: Rgb) -> Sun {
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
