//! Models built in Rust for the planning tests (independent of the scene format).
#![allow(dead_code)]
use glam::{DMat3, DVec3};
use poser::model::*;

pub fn diver(cyl_l: f64, fill_bar: f64) -> Diver {
    Diver {
        speed: 0.2,
        descent_rate: 18.0 / 60.0,
        ascent_rate: 9.0 / 60.0,
        sac: 20.0 / 60_000.0,
        cylinders: vec![Cylinder {
            name: "back".into(),
            volume: cyl_l / 1e3,
            pressure: fill_bar * 1e5,
            o2: 0.21,
            he: 0.0,
        }],
        gf_low: 0.3,
        gf_high: 0.75,
        reserve: 50e5,
        salt_water: true,
    }
}

/// A nadir lawnmower: `strips` strips of `length` m, `spacing` m apart, camera at `depth`,
/// exposures every `step` m, swum at `speed`.
pub fn lawnmower(
    strips: u32,
    length: f64,
    spacing: f64,
    depth: f64,
    speed: f64,
    step: f64,
) -> (Vec<RigPose>, NetworkSummary) {
    let mut poses = Vec::new();
    let mut path = Vec::new();
    let mut dist = 0.0;
    let rot = DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z);
    for s in 0..strips {
        let x = s as f64 * spacing;
        let (y0, y1) = if s % 2 == 0 {
            (0.0, length)
        } else {
            (length, 0.0)
        };
        if s > 0 {
            dist += spacing;
        }
        let n = (length / step).round() as usize;
        for i in 0..=n {
            let y = y0 + (y1 - y0) * i as f64 / n as f64;
            let p = DVec3::new(x, y, -depth);
            if i == 0 || i == n {
                path.push(p);
            }
            poses.push(RigPose {
                name: format!("img_{:05}", poses.len()),
                world_from_rig: Pose {
                    rotation: rot,
                    translation: p,
                },
                time: (dist + length * i as f64 / n as f64) / speed,
                strip: s,
            });
        }
        dist += length;
    }
    let summary = NetworkSummary {
        kind: "lawnmower".into(),
        path,
        path_length: dist,
        speed,
        duration: dist / speed,
        altitude: Some(2.0),
        overlap: Some(0.8),
        sidelap: Some(0.6),
        spacing: Some(step),
        strip_spacing: Some(spacing),
        strips,
    };
    (poses, summary)
}

pub fn camera() -> Camera {
    let (w, h, pitch, f) = (4000u32, 3000u32, 4e-6, 0.016);
    Camera {
        name: "cam".into(),
        width: w,
        height: h,
        pixel_pitch: pitch,
        focal_length: f,
        fx: f / pitch,
        fy: f / pitch,
        cx: w as f64 / 2.0,
        cy: h as f64 / 2.0,
        lens: LensModel::Rectilinear,
        distortion: Distortion::default(),
        focus_distance: None,
        f_number: None,
        port: Port::Flat {
            normal: DVec3::Z,
            distance: 0.02,
            thickness: 0.01,
            glass: Glass {
                name: "N-BK7".into(),
                ior: [1.514, 1.518, 1.527],
            },
        },
        rig_from_camera: Pose::IDENTITY,
    }
}

pub fn model(
    poses: Vec<RigPose>,
    network: NetworkSummary,
    diver: Option<Diver>,
    site_depth: f64,
) -> Model {
    Model {
        name: "test".into(),
        description: String::new(),
        source: "test.toml".into(),
        water: Some(Water {
            ior: [1.331, 1.334, 1.339],
            ior_source: IorSource::Constant,
            absorption: [0.3, 0.05, 0.02],
            scattering: [0.1, 0.1, 0.1],
            jerlov: None,
            phase: Phase::HenyeyGreenstein { g: 0.9 },
            extent: WaterExtent::Everywhere,
        }),
        site: Site {
            depth: site_depth,
            surface: SeaSurface::Flat,
            altitude: 0.0,
        },
        sun: None,
        cameras: vec![camera()],
        lights: vec![],
        objects: vec![],
        targets: vec![],
        poses,
        network,
        diver,
        render: RenderSettings {
            samples: 16,
            seed: 1,
            max_bounces: 4,
            dispersion: false,
            outputs: vec!["rgb".into()],
            exposure: 1.0,
        },
        sensor: None,
        needs: Needs::default(),
    }
}

/// The paper's survey: 20 strips of 52.6 m, 2 m apart (≈ 1090 m of path) at 15 m, 0.2 m/s.
pub fn paper_model(diver_: Option<Diver>) -> Model {
    let (poses, net) = lawnmower(20, 52.6, 2.0, 15.0, 0.2, 1.0);
    model(poses, net, diver_, 17.0)
}
