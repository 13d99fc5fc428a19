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

/// A busy scene for the native renderer's sampling tests: water in a box about the camera
/// (Fournier–Forand), a flat sea surface, a checkered plane and a boulder field, a rig spot, an
/// area light, a sky and the sun; 48×36 px, 8 spp.
pub fn busy_model() -> Model {
    let mut m = nadir_model(1.5);
    {
        let w = m.water.as_mut().unwrap();
        w.absorption = [0.3, 0.08, 0.05];
        w.scattering = [0.2, 0.25, 0.3];
        w.phase = Phase::FournierForand {
            n: 1.10,
            mu: 3.5835,
            backscatter: 0.0183,
        };
        w.extent = WaterExtent::BoxAroundCamera {
            half_size: DVec3::splat(3.0),
        };
    }
    m.site.surface = SeaSurface::Flat;
    m.site.depth = 5.0;
    m.poses[0].world_from_rig.translation.z = -3.5;
    m.objects[0].pose.translation.z = -5.0;
    m.objects[0].material.pattern = Some(Pattern::Checker {
        size: 0.2,
        contrast: 0.3,
    });
    m.objects.push(Object {
        backdrop: false,
        name: "rock".into(),
        shape: Shape::Boulders {
            width: 2.0,
            length: 2.0,
            count: 6,
            radius: 0.3,
            seed: 2,
        },
        pose: Pose {
            rotation: glam::DMat3::IDENTITY,
            translation: DVec3::new(0.0, 0.0, -5.0),
        },
        scale: DVec3::ONE,
        material: Material {
            albedo: [0.6, 0.5, 0.4],
            pattern: Some(Pattern::Noise {
                size: 0.1,
                amount: 0.5,
                seed: 3,
            }),
            variation: 0.0,
            texel: None,
            grid: None,
            glass: None,
            fill: None,
        },
    });
    m.lights.push(rig_spot(DVec3::new(0.25, 0.0, 0.0), 10.0));
    m.lights.push(Light {
        name: "panel".into(),
        mount: Mount::World,
        kind: LightKind::Area {
            frame: Pose {
                rotation: glam::DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z),
                translation: DVec3::new(0.5, 0.5, -3.0),
            },
            width: 0.4,
            height: 0.4,
            radiance: [5.0; 3],
        },
    });
    m.lights.push(Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient {
            radiance: [0.05, 0.07, 0.1],
        },
    });
    let dir = DVec3::new(0.3, 0.1, -1.0).normalize();
    m.sun = Some(sun_along(dir, [500.0; 3], [400.0, 420.0, 430.0]));
    m.cameras[0].width = 48;
    m.cameras[0].height = 36;
    m.cameras[0].cx = 24.0;
    m.cameras[0].cy = 18.0;
    m.cameras[0].fx = 40.0;
    m.cameras[0].fy = 40.0;
    m.render.samples = 8;
    m
}

/// `render` into a temporary folder on a pool of `threads` threads.
pub fn render_on(m: &Model, threads: usize) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        poser::backend::native::render(m, dir.path(), &poser::backend::RenderOptions::default())
    })
    .unwrap();
    dir
}
