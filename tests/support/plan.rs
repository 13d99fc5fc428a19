//! Presets of the planning tests (divers, lawnmower networks, the paper's survey), from the one
//! builder ([`super::model`]).
#![allow(dead_code)]
use super::model::Sensor;
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
            o2: poser::plan::deco::Gas::AIR.o2,
            he: 0.0,
            role: CylinderRole::Bottom,
            switch_depth: None,
        }],
        gf_low: 0.3,
        gf_high: 0.75,
        reserve: 50e5,
        salt_water: true,
        po2_bottom: 1.4,
        po2_deco: 1.6,
        end_limit: DEFAULT_END_LIMIT,
        deco: DecoMode::None,
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
        overlap_requested: Some(0.8),
        sidelap_requested: Some(0.6),
        spacing: Some(step),
        strip_spacing: Some(spacing),
        strips,
    };
    (poses, summary)
}

/// A 4000×3000 camera, 16 mm lens, 4 µm pixels, behind a flat glass port.
pub fn camera() -> Camera {
    let (pitch, f) = (4e-6, 0.016);
    let sensor = Sensor {
        width: 4000,
        height: 3000,
        fx: f / pitch,
        pitch,
        cx: 2000.0,
        cy: 1500.0,
    };
    let port = Port::Flat {
        normal: DVec3::Z,
        distance: 0.02,
        thickness: 0.01,
        glass: Glass {
            name: "N-BK7".into(),
            ior: [1.514, 1.518, 1.527],
        },
        outer_layers: vec![],
    };
    let mut c = super::model::camera("cam", sensor, port);
    c.focal_length = f;
    c
}

/// The survey model: `poses` over a site `site_depth` deep with a flat sea surface, in
/// moderately turbid water.
pub fn model(
    poses: Vec<RigPose>,
    network: NetworkSummary,
    diver: Option<Diver>,
    site_depth: f64,
) -> Model {
    let water = super::model::water(
        [1.331, 1.334, 1.339],
        [0.3, 0.05, 0.02],
        [0.1, 0.1, 0.1],
        Phase::HenyeyGreenstein { g: 0.9 },
    );
    let mut m = super::model::model("test", camera(), Some(water), Pose::IDENTITY);
    m.source = "test.toml".into();
    m.site.depth = site_depth;
    m.site.surface = SeaSurface::Flat;
    m.poses = poses;
    m.network = network;
    m.diver = diver;
    m.render.seed = 1;
    m.render.max_bounces = 4;
    m.needs = Needs::default();
    m
}

/// The paper's survey: 20 strips of 52.6 m, 2 m apart (≈ 1090 m of path) at 15 m, 0.2 m/s.
pub fn paper_model(diver_: Option<Diver>) -> Model {
    let (poses, net) = lawnmower(20, 52.6, 2.0, 15.0, 0.2, 1.0);
    model(poses, net, diver_, 17.0)
}

/// A cylinder of `litres` water capacity filled to `bar` with O₂/He fractions `o2`, `he`.
pub fn cyl(name: &str, litres: f64, bar: f64, o2: f64, he: f64, role: CylinderRole) -> Cylinder {
    Cylinder {
        name: name.into(),
        volume: litres / 1e3,
        pressure: bar * 1e5,
        o2,
        he,
        role,
        switch_depth: None,
    }
}

/// One straight strip at `depth` swum for `minutes` at 0.2 m/s.
pub fn flat_dive(depth: f64, minutes: f64, diver: Diver) -> Model {
    let length = minutes * 60.0 * 0.2;
    let (poses, net) = lawnmower(1, length, 2.0, depth, 0.2, (length / 20.0).max(1.0));
    model(poses, net, Some(diver), depth + 2.0)
}

/// The gas breathed at each profile vertex and switch, from `dive.switches` and
/// `dive.profile` alone: (cylinder, depth) pairs, for checks independent of the simulator's
/// per-cylinder flags.
pub fn breathed(r: &poser::plan::dive::DiveReport) -> Vec<(usize, f64)> {
    let d = &r.dive;
    let at = |t: f64| {
        d.switches
            .iter()
            .rev()
            .find(|s| s.time <= t + 1e-6)
            .map(|s| s.cylinder)
            .unwrap_or(d.switches[0].cylinder)
    };
    let depth_at = |t: f64| {
        for w in d.profile.windows(2) {
            if t >= w[0].0 - 1e-9 && t <= w[1].0 + 1e-9 {
                let f = if w[1].0 > w[0].0 {
                    (t - w[0].0) / (w[1].0 - w[0].0)
                } else {
                    0.0
                };
                return w[0].1 + (w[1].1 - w[0].1) * f.clamp(0.0, 1.0);
            }
        }
        d.profile.last().unwrap().1
    };
    let mut out: Vec<(usize, f64)> = d.profile.iter().map(|&(t, depth)| (at(t), depth)).collect();
    // At a switch the new gas is breathed from that depth (and the old one up to it).
    for (k, s) in d.switches.iter().enumerate().skip(1) {
        let prev = d.switches[k - 1].cylinder;
        let depth = depth_at(s.time);
        out.push((s.cylinder, depth));
        out.push((prev, depth));
    }
    out
}
