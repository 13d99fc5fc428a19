//! Models built in Rust for the Mitsuba backend tests (independent of the scene front end).
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use poser::model::*;

/// Camera looking along world -z (down) from `pos`: x_cam = +x world, y_cam = -y world.
pub fn nadir(pos: DVec3) -> Pose {
    Pose {
        rotation: DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z),
        translation: pos,
    }
}

pub fn glass() -> Glass {
    Glass {
        name: "N-BK7".into(),
        ior: [1.5145, 1.5185, 1.5253],
    }
}

pub fn flat_port(distance: f64) -> Port {
    Port::Flat {
        normal: DVec3::Z,
        distance,
        thickness: 0.012,
        glass: glass(),
    }
}

pub fn camera(name: &str, port: Port) -> Camera {
    let (w, h, fx) = (160u32, 120u32, 140.0);
    Camera {
        name: name.into(),
        width: w,
        height: h,
        pixel_pitch: 5e-6,
        focal_length: fx * 5e-6,
        fx,
        fy: fx,
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

pub fn water(absorption: Rgb, scattering: Rgb, phase: Phase) -> Water {
    Water {
        ior: [1.3310, 1.3339, 1.3390],
        ior_source: IorSource::Constant,
        absorption,
        scattering,
        jerlov: None,
        phase,
        extent: WaterExtent::Everywhere,
    }
}

pub fn render_settings(samples: u32) -> RenderSettings {
    RenderSettings {
        samples,
        seed: 7,
        max_bounces: 16,
        dispersion: false,
        outputs: vec!["rgb".into()],
        exposure: 1.0,
    }
}

/// A minimal model: one camera at `world_from_rig`, nothing else.
pub fn base(name: &str, cam: Camera, water: Option<Water>, world_from_rig: Pose) -> Model {
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
        },
        sun: None,
        cameras: vec![cam],
        lights: vec![],
        objects: vec![],
        targets: vec![],
        poses: vec![RigPose {
            name: "img_0000".into(),
            world_from_rig,
            time: 0.0,
            strip: 0,
        }],
        network: NetworkSummary::default(),
        diver: None,
        render: render_settings(16),
        needs: Needs {
            medium,
            refraction,
            ..Default::default()
        },
    }
}

pub fn plane(name: &str, z: f64, size: f64, albedo: Rgb) -> Object {
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
            albedo,
            pattern: None,
            variation: 0.0,
            texel: None,
        },
    }
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
            },
        },
        Object {
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
            },
        },
        Object {
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
            },
        },
    ];
    m.needs.sun_refraction = true;
    m
}
