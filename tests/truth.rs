//! Ground truth (`poser truth`, `truth::write`): every reported pixel is the exact refractive
//! image of its target point, hidden and back-facing points are left out, the COLMAP model is
//! consistent, and output is deterministic.
use crate::support::scenario as load;
use glam::DVec3;
use poser::model::{Material, Object, Pose, Shape};
use std::path::Path;

#[test]
fn every_observation_is_the_exact_refractive_image() {
    let model = load("calibration_flat.toml");
    let truth = poser::truth::compute(&model).unwrap();
    let p = model.projector(0, 1).unwrap();
    let mut n = 0;
    for im in &truth.images {
        for o in &im.points {
            // Trace the reported pixel back into the water: the ray must pass through the point.
            let (origin, dir, _) = p.pixel_ray_world(im.pose_index, o.u, o.v).unwrap();
            let miss = (o.world - origin).cross(dir).length();
            // 1e-9 px at ~2300 px focal length and ~2 m is ≈ 1e-12 m; allow 1e-11 m.
            assert!(miss < 1e-11, "{} {}: ray misses by {miss} m", im.name, o.id);
            assert!(o.u >= 0.0 && o.u <= 1600.0 && o.v >= 0.0 && o.v <= 1200.0);
            n += 1;
        }
    }
    assert!(n > 50, "only {n} observations");
}

#[test]
fn occluded_and_back_facing_points_are_left_out() {
    let mut model = load("calibration_flat.toml");
    let before = poser::truth::compute(&model).unwrap();
    let count = |t: &poser::truth::Truth| t.images.iter().map(|i| i.points.len()).sum::<usize>();
    let n0 = count(&before);
    // A large opaque box between every camera and the targets.
    model.objects.push(Object {
        backdrop: false,
        name: "wall".into(),
        shape: Shape::Box {
            size: DVec3::new(10.0, 0.05, 10.0),
        },
        pose: Pose {
            rotation: glam::DMat3::IDENTITY,
            translation: DVec3::new(0.0, -0.5, -2.0),
        },
        scale: DVec3::ONE,
        material: Material {
            albedo: [0.5; 3],
            pattern: None,
            variation: 0.0,
            texel: None,
            grid: None,
            glass: None,
            fill: None,
        },
    });
    let cams: Vec<DVec3> = (0..model.poses.len())
        .map(|i| model.world_from_camera(i, 0).translation)
        .collect();
    assert!(
        cams.iter().all(|c| c.y < -0.5),
        "test premise: cameras on the −y side of the wall"
    );
    let blocked = poser::truth::compute(&model).unwrap();
    assert_eq!(
        count(&blocked),
        0,
        "a wall between cameras and targets hides everything (was {n0})"
    );
    model.objects.pop();
    // Turn the targets around: their printed faces now look away from the cameras.
    for t in &mut model.targets {
        t.pose.rotation *= glam::DMat3::from_rotation_x(std::f64::consts::PI);
    }
    let back = poser::truth::compute(&model).unwrap();
    assert_eq!(count(&back), 0);
}

#[test]
fn colmap_model_is_consistent_and_output_deterministic() {
    let model = load("calibration_flat.toml");
    let d1 = tempfile::tempdir().unwrap();
    let d2 = tempfile::tempdir().unwrap();
    poser::truth::write(&model, d1.path()).unwrap();
    poser::truth::write(&model, d2.path()).unwrap();
    for f in [
        "truth.json",
        "points.csv",
        "cameras.csv",
        "images.csv",
        "colmap/cameras.txt",
        "colmap/images.txt",
        "colmap/points3D.txt",
        "colmap/cameras.bin",
        "colmap/images.bin",
        "colmap/points3D.bin",
        "markers/markers.csv",
        "markers/gcp.csv",
    ] {
        let a = std::fs::read(d1.path().join(f)).unwrap();
        assert_eq!(
            a,
            std::fs::read(d2.path().join(f)).unwrap(),
            "{f} differs between runs"
        );
        assert!(!a.is_empty());
    }
    // images.txt: camera_from_world quaternion + translation must map the camera centre to 0.
    let text = std::fs::read_to_string(d1.path().join("colmap/images.txt")).unwrap();
    let data: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(data.len(), 2 * model.poses.len());
    let pts3d = std::fs::read_to_string(d1.path().join("colmap/points3D.txt")).unwrap();
    let n3d = pts3d.lines().filter(|l| !l.starts_with('#')).count();
    for (k, pair) in data.chunks(2).enumerate() {
        let f: Vec<f64> = pair[0]
            .split(' ')
            .take(8)
            .map(|x| x.parse().unwrap())
            .collect();
        let q = glam::DQuat::from_xyzw(f[2], f[3], f[4], f[1]);
        let t = DVec3::new(f[5], f[6], f[7]);
        let c = model.world_from_camera(k, 0).translation;
        assert!((q * c + t).length() < 1e-12, "image {k}");
        // Every 2-D point references a listed 3-D point.
        let obs: Vec<&str> = pair[1].split_whitespace().collect();
        assert_eq!(obs.len() % 3, 0);
        for o in obs.chunks(3) {
            let id: usize = o[2].parse().unwrap();
            assert!(id >= 1 && id <= n3d);
        }
    }
}

#[test]
fn without_a_port_colmap_pinhole_reprojects_the_truth() {
    // In air (no port), the COLMAP PINHOLE camera and pose reproduce every pixel.
    let mut model = load("calibration_flat.toml");
    model.water = None;
    for c in &mut model.cameras {
        c.port = poser::model::Port::None;
    }
    let truth = poser::truth::compute(&model).unwrap();
    let cam = &model.cameras[0];
    let mut n = 0;
    for im in &truth.images {
        let cfw = model.world_from_camera(im.pose_index, 0).inverse();
        for o in &im.points {
            let pc = cfw.transform_point(o.world);
            let (u, v) = (cam.fx * pc.x / pc.z + cam.cx, cam.fy * pc.y / pc.z + cam.cy);
            assert!((u - o.u).abs() < 1e-9 && (v - o.v).abs() < 1e-9);
            n += 1;
        }
    }
    assert!(n > 0);
}

/// A camera-frame ray traced the way Refractive COLMAP's `FlatPort::CamFromImg` and
/// `DomePort::CamFromImg` do (She et al., IROS 2024; pinhole camera): the test's own
/// implementation of the format's meaning, to read back what poser wrote.
fn refractive_colmap_ray(k: &[f64], model: &str, rp: &[f64], x: f64, y: f64) -> (DVec3, DVec3) {
    let refract = |n: DVec3, n1: f64, n2: f64, d: DVec3| {
        // Vector Snell with n along the transmission side.
        let n = if n.dot(d) < 0.0 { -n } else { n };
        let eta = n1 / n2;
        let c = n.dot(d);
        let s2 = eta * eta * (1.0 - c * c);
        eta * d + ((1.0 - s2).sqrt() - eta * c) * n
    };
    let mut dir = DVec3::new((x - k[2]) / k[0], (y - k[3]) / k[1], 1.0).normalize();
    let (na, ng, nw) = (rp[5], rp[6], rp[7]);
    match model {
        "FLATPORT" => {
            let n = DVec3::new(rp[0], rp[1], rp[2]);
            let o1 = dir * (rp[3] / n.dot(dir));
            dir = refract(n, na, ng, dir);
            let o2 = o1 + dir * ((rp[3] + rp[4] - n.dot(o1)) / n.dot(dir));
            (o2, refract(n, ng, nw, dir))
        }
        "DOMEPORT" => {
            let c = DVec3::new(rp[0], rp[1], rp[2]);
            let far = |o: DVec3, d: DVec3, r: f64| {
                let b = d.dot(o - c);
                let c0 = (o - c).length_squared() - r * r;
                o + d * (-b + (b * b - c0).sqrt())
            };
            let o1 = far(DVec3::ZERO, dir, rp[3]);
            dir = refract((o1 - c).normalize(), na, ng, dir);
            let o2 = far(o1, dir, rp[3] + rp[4]);
            (o2, refract((o2 - c).normalize(), ng, nw, dir))
        }
        m => panic!("unknown refractive model {m}"),
    }
}

/// Read a written COLMAP text model: cameras (model, params, refractive part), images
/// (camera_from_world, camera id, observations) and points.
#[allow(clippy::type_complexity)]
fn read_colmap(
    dir: &Path,
) -> (
    Vec<(String, Vec<f64>, Option<(String, Vec<f64>)>)>,
    Vec<(glam::DQuat, DVec3, usize, Vec<(f64, f64, usize)>)>,
    std::collections::HashMap<usize, DVec3>,
) {
    let data = |f: &str| -> Vec<String> {
        std::fs::read_to_string(dir.join(f))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(String::from)
            .collect()
    };
    let text = std::fs::read_to_string(dir.join("cameras.txt")).unwrap();
    let cams = read_cameras_text(&text)
        .unwrap_or_else(|e| panic!("the fork's reader refuses cameras.txt: {e}\n{text}"))
        .into_iter()
        .map(|c| (c.model, c.params, c.refrac))
        .collect();
    let lines = data("images.txt");
    let images = lines
        .chunks(2)
        .map(|pair| {
            let f: Vec<&str> = pair[0].split(' ').collect();
            let n: Vec<f64> = f[1..8].iter().map(|x| x.parse().unwrap()).collect();
            let obs = pair[1]
                .split_whitespace()
                .collect::<Vec<_>>()
                .chunks(3)
                .map(|o| {
                    (
                        o[0].parse().unwrap(),
                        o[1].parse().unwrap(),
                        o[2].parse().unwrap(),
                    )
                })
                .collect();
            (
                glam::DQuat::from_xyzw(n[1], n[2], n[3], n[0]),
                DVec3::new(n[4], n[5], n[6]),
                f[8].parse().unwrap(),
                obs,
            )
        })
        .collect();
    let points = data("points3D.txt")
        .iter()
        .map(|l| {
            let f: Vec<&str> = l.split(' ').collect();
            let v: Vec<f64> = f[1..4].iter().map(|x| x.parse().unwrap()).collect();
            (f[0].parse().unwrap(), DVec3::new(v[0], v[1], v[2]))
        })
        .collect();
    (cams, images, points)
}

/// One camera as the Refractive COLMAP fork (`colmap_underwater`) reads it.
#[derive(Debug)]
struct ForkCamera {
    id: u64,
    model: String,
    width: i64,
    height: i64,
    params: Vec<f64>,
    refrac: Option<(String, Vec<f64>)>,
}

/// A Rust port of the fork's `Reconstruction::ReadCamerasText`
/// (src/colmap/scene/reconstruction.cc): each line trimmed (`StringTrim`: space, `\n`, `\r`,
/// `\t`), empty and `#` lines skipped; the rest read with `std::getline(line_stream, item, ' ')`
/// word by word: ID, MODEL, WIDTH, HEIGHT, exactly the model's number of parameters, then — if
/// the stream is not at its end — the refraction model's name and every remaining word as its
/// parameters, whose count must be the model's (`VerifyRefracParams`). An unknown camera or
/// refraction model name throws there (`…DOES_NOT_EXIST_EXCEPTION`); here it is an `Err`.
/// Numbers must be whole words (`std::stold` would also take a numeric prefix: stricter).
fn read_cameras_text(text: &str) -> Result<Vec<ForkCamera>, String> {
    /// `std::getline(stream, item, ' ')` on a `std::stringstream`: reads up to the next
    /// single space (consumed) or the end (sets eof); at eof it fails and leaves `item` as it
    /// was, as the C++ does.
    struct Stream<'a> {
        rest: &'a str,
        eof: bool,
    }
    impl Stream<'_> {
        fn getline(&mut self, item: &mut String) {
            if self.eof {
                return;
            }
            match self.rest.find(' ') {
                Some(i) => {
                    *item = self.rest[..i].to_string();
                    self.rest = &self.rest[i + 1..];
                }
                None => {
                    *item = self.rest.to_string();
                    self.rest = "";
                    self.eof = true;
                }
            }
        }
    }
    // The fork's camera models (src/colmap/sensor/models.h): name → number of parameters.
    let camera_params = |name: &str| -> Option<usize> {
        Some(match name {
            "SIMPLE_PINHOLE" => 3,
            "PINHOLE" => 4,
            "SIMPLE_RADIAL" => 4,
            "RADIAL" => 5,
            "OPENCV" => 8,
            "OPENCV_FISHEYE" => 8,
            "FULL_OPENCV" => 12,
            "FOV" => 5,
            "SIMPLE_RADIAL_FISHEYE" => 4,
            "RADIAL_FISHEYE" => 5,
            "THIN_PRISM_FISHEYE" => 12,
            "METASHAPE_FISHEYE" => 8,
            _ => return None,
        })
    };
    // Its refraction models (src/colmap/sensor/models_refrac.h).
    let refrac_params = |name: &str| -> Option<usize> {
        match name {
            "FLATPORT" | "DOMEPORT" => Some(8),
            _ => None,
        }
    };
    let stold = |s: &str| -> Result<f64, String> {
        s.parse::<f64>()
            .map_err(|_| format!("std::stold(\"{s}\") throws"))
    };
    let mut out = Vec::new();
    for line in text.split('\n') {
        let line = line.trim_matches([' ', '\n', '\r', '\t']);
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut s = Stream {
            rest: line,
            eof: false,
        };
        let mut item = String::new();
        s.getline(&mut item);
        let id: u64 = item
            .parse()
            .map_err(|_| format!("std::stoul(\"{item}\") throws"))?;
        s.getline(&mut item);
        let model = item.clone();
        let n = camera_params(&model).ok_or(format!("camera model `{model}` does not exist"))?;
        s.getline(&mut item);
        let width: i64 = item
            .parse()
            .map_err(|_| format!("std::stoll(\"{item}\") throws"))?;
        s.getline(&mut item);
        let height: i64 = item
            .parse()
            .map_err(|_| format!("std::stoll(\"{item}\") throws"))?;
        let mut params = Vec::with_capacity(n);
        for _ in 0..n {
            s.getline(&mut item);
            params.push(stold(&item)?);
        }
        let more_params = !s.eof;
        s.getline(&mut item);
        let mut refrac = None;
        if more_params {
            let name = item.clone();
            let m = refrac_params(&name)
                .ok_or(format!("refractive camera model `{name}` does not exist"))?;
            let mut rp = Vec::with_capacity(m);
            while !s.eof {
                s.getline(&mut item);
                rp.push(stold(&item)?);
            }
            if rp.len() != m {
                return Err(format!(
                    "{name}: {} parameters, VerifyRefracParams wants {m}",
                    rp.len()
                ));
            }
            refrac = Some((name, rp));
        }
        out.push(ForkCamera {
            id,
            model,
            width,
            height,
            params,
            refrac,
        });
    }
    Ok(out)
}

/// calibration_flat behind its flat port, or behind a decentred dome (`port = "dome"`).
fn calibration_behind(port: &str) -> poser::model::Model {
    let mut model = load("calibration_flat.toml");
    if port == "dome" {
        let glass = model.cameras[0].port.glass().unwrap().clone();
        model.cameras[0].port = poser::model::Port::Dome {
            center: DVec3::new(0.003, -0.002, 0.004),
            inner_radius: 0.06,
            thickness: 0.008,
            glass,
        };
    }
    model
}

/// `colmap_refractive/cameras.txt` reads in the Refractive COLMAP fork: its reader (ported
/// above) takes the word after the camera parameters as the port model, so the port follows
/// them directly, and the port's eight parameters come back exactly: the normal (flat) or
/// centre (dome), the distance or inner radius, the glass thickness, and the G-channel
/// indices of air, glass and water. The header line is the fork's.
#[test]
fn refractive_cameras_txt_reads_in_the_fork_and_the_port_round_trips() {
    for port in ["flat", "dome"] {
        let model = calibration_behind(port);
        let truth = poser::truth::compute(&model).unwrap();
        let d = tempfile::tempdir().unwrap();
        poser::truth::write(&model, d.path()).unwrap();
        let text = std::fs::read_to_string(d.path().join("colmap_refractive/cameras.txt")).unwrap();
        assert!(
            text.lines().any(|l| l
                == "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[] OPTIONAL[REFRAC_MODEL REFRAC_PARAMS[]]"),
            "{text}"
        );
        assert!(text.contains("Pixel convention: COLMAP's"), "{text}");
        let cams = read_cameras_text(&text).unwrap_or_else(|e| panic!("{port}: {e}\n{text}"));
        assert_eq!(cams.len(), truth.cameras.len());
        let (c, t) = (&cams[0], &truth.cameras[0]);
        assert_eq!(c.id, 1);
        assert_eq!(c.model, "PINHOLE");
        assert_eq!((c.width, c.height), (t.width as i64, t.height as i64));
        assert_eq!(c.params, vec![t.fx, t.fy, t.cx, t.cy]);
        let (name, rp) = c.refrac.as_ref().expect("the port was not read");
        let glass = t.ior_glass.expect("a glass port")[1];
        let want = match &t.port {
            poser::model::Port::Flat {
                normal,
                distance,
                thickness,
                ..
            } => {
                assert_eq!(name, "FLATPORT");
                [normal.x, normal.y, normal.z, *distance, *thickness]
            }
            poser::model::Port::Dome {
                center,
                inner_radius,
                thickness,
                ..
            } => {
                assert_eq!(name, "DOMEPORT");
                [center.x, center.y, center.z, *inner_radius, *thickness]
            }
            p => panic!("{port}: unexpected port {p:?}"),
        };
        let mut want = want.to_vec();
        want.extend([t.ior_air[1], glass, t.ior_water[1]]);
        assert_eq!(rp, &want, "{port}: the port parameters do not round-trip");
        // The upstream export reads in the same reader, without a port.
        let up = std::fs::read_to_string(d.path().join("colmap/cameras.txt")).unwrap();
        let up = read_cameras_text(&up).unwrap();
        assert!(up.iter().all(|c| c.refrac.is_none()));
    }
}

/// The ported reader refuses what the fork refuses: an unknown port name where the port model
/// stands (the old `… REFRAC FLATPORT …` line) and a wrong number of port parameters.
#[test]
fn the_ported_fork_reader_refuses_what_the_fork_refuses() {
    let base = "1 PINHOLE 10 8 5 5 5 4";
    assert!(read_cameras_text(base).unwrap()[0].refrac.is_none());
    let e = read_cameras_text(&format!(
        "{base} REFRAC FLATPORT 0 0 1 0.01 0.005 1 1.5 1.33"
    ))
    .unwrap_err();
    assert!(e.contains("`REFRAC` does not exist"), "{e}");
    assert!(read_cameras_text(&format!("{base} FLATPORT 0 0 1 0.01 0.005 1 1.5")).is_err());
    assert!(read_cameras_text("1 PINHOLE 10 8 5  5 5 4").is_err());
    let ok =
        read_cameras_text(&format!("{base} DOMEPORT 0 0 0 0.05 0.005 1 1.5 1.33\r\n")).unwrap();
    assert_eq!(ok[0].refrac.as_ref().unwrap().1[3], 0.05);
}

/// `colmap_refractive/` is Refractive COLMAP's format: every observation, traced back through
/// the written camera and port by that format's own ray model, passes through its 3-D point;
/// for a flat and a decentred dome port. `colmap/` (upstream COLMAP) has no port model,
/// and its port-less camera misses the same observations by pixels.
#[test]
fn refractive_colmap_model_reprojects_every_observation() {
    for port in ["flat", "dome"] {
        let model = calibration_behind(port);
        let d = tempfile::tempdir().unwrap();
        poser::truth::write(&model, d.path()).unwrap();
        let (cams, images, points) = read_colmap(&d.path().join("colmap_refractive"));
        let (up_cams, _, _) = read_colmap(&d.path().join("colmap"));
        assert!(
            up_cams.iter().all(|c| c.2.is_none()),
            "upstream model has REFRAC"
        );
        let (name, k, refrac) = &cams[0];
        assert_eq!(name, "PINHOLE");
        let (rmodel, rp) = refrac.as_ref().expect("refractive camera");
        assert_eq!(
            rmodel,
            if port == "flat" {
                "FLATPORT"
            } else {
                "DOMEPORT"
            }
        );
        let mut n = 0;
        let mut upstream_px = 0.0f64;
        for (q, t, cam, obs) in &images {
            assert_eq!(*cam, 1);
            for &(x, y, pid) in obs {
                let pc = *q * points[&pid] + *t;
                let (o, dir) = refractive_colmap_ray(k, rmodel, rp, x, y);
                let miss = (pc - o).cross(dir).length();
                assert!(
                    miss < 1e-9,
                    "{port}: observation misses its point by {miss} m"
                );
                // Upstream pinhole reprojection of the same point.
                let (u, v) = (k[0] * pc.x / pc.z + k[2], k[1] * pc.y / pc.z + k[3]);
                upstream_px = upstream_px.max((u - x).hypot(v - y));
                n += 1;
            }
        }
        assert!(n > 50, "{port}: only {n} observations");
        if port == "flat" {
            assert!(
                upstream_px > 10.0,
                "flat port without its port: {upstream_px} px"
            );
        }
    }
}

/// The equisolid fisheye is exported as OPENCV_FISHEYE with fitted coefficients (it was
/// written with zeros, up to 5.7 px off): the exported model reprojects every observation to
/// within 0.01 px, in the COLMAP and the OpenCV files alike.
#[test]
fn equisolid_fisheye_export_reprojects_within_a_hundredth_of_a_pixel() {
    let mut model = load("calibration_flat.toml");
    model.water = None;
    for c in &mut model.cameras {
        c.port = poser::model::Port::None;
        c.lens = poser::model::LensModel::FisheyeEquisolid;
        // A 1.2 mm focal length on this sensor: ≈ 150° across the diagonal.
        c.fx *= 0.15;
        c.fy *= 0.15;
    }
    let d = tempfile::tempdir().unwrap();
    poser::truth::write(&model, d.path()).unwrap();
    let (cams, images, points) = read_colmap(&d.path().join("colmap"));
    let (name, p, _) = &cams[0];
    assert_eq!(name, "OPENCV_FISHEYE");
    assert!(p[4] != 0.0, "coefficients were not fitted: {p:?}");
    let fisheye = |pc: DVec3| {
        let r = pc.x.hypot(pc.y);
        let th = r.atan2(pc.z);
        let t2 = th * th;
        let td = th * (1.0 + t2 * (p[4] + t2 * (p[5] + t2 * (p[6] + t2 * p[7]))));
        (p[0] * td * pc.x / r + p[2], p[1] * td * pc.y / r + p[3])
    };
    let (mut n, mut worst, mut widest) = (0, 0.0f64, 0.0f64);
    for (q, t, _, obs) in &images {
        for &(x, y, pid) in obs {
            let pc = *q * points[&pid] + *t;
            let (u, v) = fisheye(pc);
            worst = worst.max((u - x).hypot(v - y));
            widest = widest.max(pc.x.hypot(pc.y).atan2(pc.z));
            n += 1;
        }
    }
    assert!(n > 50, "only {n} observations");
    assert!(
        widest > 0.5,
        "observations only near the centre ({widest} rad)"
    );
    assert!(worst < 0.01, "OPENCV_FISHEYE export is {worst} px off");
    // The OpenCV file carries the same coefficients.
    let yml = std::fs::read_to_string(d.path().join("opencv/camera_1.yml")).unwrap();
    assert!(yml.contains("distortion_model: \"fisheye\""), "{yml}");
    assert!(yml.contains(&format!("{:?}", p[4])), "{yml}");
}

/// `opencv/` uses OpenCV's pixel convention (centres at integers): every pixel and the
/// principal point are poser's − 0.5; poser's own files keep +0.5.
#[test]
fn opencv_files_use_opencv_pixel_convention() {
    let model = load("calibration_flat.toml");
    let truth = poser::truth::compute(&model).unwrap();
    let d = tempfile::tempdir().unwrap();
    poser::truth::write(&model, d.path()).unwrap();
    let yml = std::fs::read_to_string(d.path().join("opencv/camera_1.yml")).unwrap();
    assert!(yml.starts_with("%YAML:1.0\n"), "{yml}");
    let c = &model.cameras[0];
    let k = format!(
        "data: [ {:?}, 0.0, {:?}, 0.0, {:?}, {:?}, 0.0, 0.0, 1.0 ]",
        c.fx,
        c.cx - 0.5,
        c.fy,
        c.cy - 0.5
    );
    assert!(yml.contains(&k), "{yml}\nwants {k}");
    let csv = std::fs::read_to_string(d.path().join("opencv/points.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    let obs: Vec<_> = truth
        .images
        .iter()
        .flat_map(|im| im.points.iter())
        .collect();
    assert_eq!(rows.len(), obs.len());
    for (r, o) in rows.iter().zip(obs) {
        let (u, v): (f64, f64) = (r[4].parse().unwrap(), r[5].parse().unwrap());
        assert_eq!((u, v), (o.u - 0.5, o.v - 0.5));
    }
    let points_csv = std::fs::read_to_string(d.path().join("points.csv")).unwrap();
    let first = points_csv.lines().nth(1).unwrap();
    let u: f64 = first.split(',').nth(5).unwrap().parse().unwrap();
    assert_eq!(
        u,
        truth
            .images
            .iter()
            .flat_map(|i| &i.points)
            .next()
            .unwrap()
            .u
    );
}

/// A Rust port of the Refractive COLMAP fork's binary readers (its
/// src/colmap/scene/reconstruction.cc, `Reconstruction::ReadCamerasBinary`, `ReadImagesBinary`,
/// `ReadPoints3DBinary`; `ReadBinaryLittleEndian`): per camera u32 id, i32 model id, u64 width,
/// u64 height, the model's number of f64 parameters, then an i32 refraction model id
/// (`CameraRefracModelId`: −1 none, 0 FLATPORT, 1 DOMEPORT) and, unless −1, that model's number
/// of f64 parameters (eight for both). A short file, an unknown id or bytes left over are errors.
mod fork_binary {
    use glam::{DQuat, DVec3};
    use std::collections::HashMap;

    pub struct Reader<'a>(pub &'a [u8]);
    impl Reader<'_> {
        fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
            if self.0.len() < N {
                return Err("file ends inside a record".into());
            }
            let (a, b) = self.0.split_at(N);
            self.0 = b;
            Ok(a.try_into().unwrap())
        }
        pub fn u8(&mut self) -> Result<u8, String> {
            Ok(self.take::<1>()?[0])
        }
        pub fn u32(&mut self) -> Result<u32, String> {
            Ok(u32::from_le_bytes(self.take()?))
        }
        pub fn i32(&mut self) -> Result<i32, String> {
            Ok(i32::from_le_bytes(self.take()?))
        }
        pub fn u64(&mut self) -> Result<u64, String> {
            Ok(u64::from_le_bytes(self.take()?))
        }
        pub fn f64(&mut self) -> Result<f64, String> {
            Ok(f64::from_le_bytes(self.take()?))
        }
        pub fn end(&self) -> Result<(), String> {
            if self.0.is_empty() {
                Ok(())
            } else {
                Err(format!("{} bytes after the last record", self.0.len()))
            }
        }
    }

    /// The fork's camera models by id (src/colmap/sensor/models.h): name, parameters.
    fn camera_model(id: i32) -> Result<(&'static str, usize), String> {
        Ok(match id {
            0 => ("SIMPLE_PINHOLE", 3),
            1 => ("PINHOLE", 4),
            2 => ("SIMPLE_RADIAL", 4),
            3 => ("RADIAL", 5),
            4 => ("OPENCV", 8),
            5 => ("OPENCV_FISHEYE", 8),
            6 => ("FULL_OPENCV", 12),
            7 => ("FOV", 5),
            8 => ("SIMPLE_RADIAL_FISHEYE", 4),
            9 => ("RADIAL_FISHEYE", 5),
            10 => ("THIN_PRISM_FISHEYE", 12),
            _ => return Err(format!("camera model id {id} does not exist")),
        })
    }

    /// Its refraction models (src/colmap/sensor/models_refrac.h).
    fn refrac_model(id: i32) -> Result<Option<(&'static str, usize)>, String> {
        Ok(match id {
            -1 => None,
            0 => Some(("FLATPORT", 8)),
            1 => Some(("DOMEPORT", 8)),
            _ => return Err(format!("refractive model id {id} does not exist")),
        })
    }

    #[allow(clippy::type_complexity)]
    pub fn cameras(
        bytes: &[u8],
    ) -> Result<Vec<(u32, String, u64, u64, Vec<f64>, Option<(String, Vec<f64>)>)>, String> {
        let mut r = Reader(bytes);
        let n = r.u64()?;
        let mut out = Vec::new();
        for _ in 0..n {
            let id = r.u32()?;
            let (name, np) = camera_model(r.i32()?)?;
            let (w, h) = (r.u64()?, r.u64()?);
            let params = (0..np).map(|_| r.f64()).collect::<Result<Vec<_>, _>>()?;
            let refrac = match refrac_model(r.i32()?)? {
                None => None,
                Some((rn, rnp)) => Some((
                    rn.to_string(),
                    (0..rnp).map(|_| r.f64()).collect::<Result<Vec<_>, _>>()?,
                )),
            };
            out.push((id, name.to_string(), w, h, params, refrac));
        }
        r.end()?;
        Ok(out)
    }

    /// Images: (id, camera_from_world rotation (normalised, as the fork does) and translation,
    /// camera id, name, observations (x, y, point id)).
    #[allow(clippy::type_complexity)]
    pub fn images(
        bytes: &[u8],
    ) -> Result<Vec<(u32, DQuat, DVec3, u32, String, Vec<(f64, f64, u64)>)>, String> {
        let mut r = Reader(bytes);
        let n = r.u64()?;
        let mut out = Vec::new();
        for _ in 0..n {
            let id = r.u32()?;
            let (w, x, y, z) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
            let q = DQuat::from_xyzw(x, y, z, w).normalize();
            let t = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
            let cam = r.u32()?;
            let mut name = Vec::new();
            loop {
                match r.u8()? {
                    0 => break,
                    c => name.push(c),
                }
            }
            let k = r.u64()?;
            let obs = (0..k)
                .map(|_| Ok((r.f64()?, r.f64()?, r.u64()?)))
                .collect::<Result<Vec<_>, String>>()?;
            out.push((id, q, t, cam, String::from_utf8(name).unwrap(), obs));
        }
        r.end()?;
        Ok(out)
    }

    /// Points: id → position (colour, error and track read and checked for length).
    #[allow(clippy::type_complexity)]
    pub fn points(bytes: &[u8]) -> Result<HashMap<u64, (DVec3, Vec<(u32, u32)>)>, String> {
        let mut r = Reader(bytes);
        let n = r.u64()?;
        let mut out = HashMap::new();
        for _ in 0..n {
            let id = r.u64()?;
            let p = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
            for _ in 0..3 {
                r.u8()?;
            }
            r.f64()?;
            let k = r.u64()?;
            let track = (0..k)
                .map(|_| Ok((r.u32()?, r.u32()?)))
                .collect::<Result<Vec<_>, String>>()?;
            out.insert(id, (p, track));
        }
        r.end()?;
        Ok(out)
    }
}

/// `colmap_refractive/` also holds the fork's binary model, which the fork reads in preference
/// to the text. Read by the port of its binary readers above, it is the text model exactly
/// (cameras, ports, poses, observations, points), and every observation traced back through
/// the camera and port read from `cameras.bin` by the format's own ray model passes within
/// 1e-9 m of its point; for a flat and a decentred dome port. A camera without a port is
/// written with the refraction id −1 and nothing after it.
#[test]
fn refractive_colmap_binary_model_reads_in_the_fork_and_reprojects() {
    for port in ["flat", "dome", "none"] {
        let mut model = calibration_behind(if port == "dome" { "dome" } else { "flat" });
        if port == "none" {
            model.water = None;
            for c in &mut model.cameras {
                c.port = poser::model::Port::None;
            }
        }
        let d = tempfile::tempdir().unwrap();
        poser::truth::write(&model, d.path()).unwrap();
        let dir = d.path().join("colmap_refractive");
        let read = |f: &str| std::fs::read(dir.join(f)).unwrap();
        let cams =
            fork_binary::cameras(&read("cameras.bin")).unwrap_or_else(|e| panic!("{port}: {e}"));
        let images = fork_binary::images(&read("images.bin")).unwrap();
        let points = fork_binary::points(&read("points3D.bin")).unwrap();
        // The same model as the text.
        let (tcams, timages, tpoints) = read_colmap(&dir);
        assert_eq!(cams.len(), tcams.len());
        for (i, (c, t)) in cams.iter().zip(&tcams).enumerate() {
            assert_eq!(c.0 as usize, i + 1);
            assert_eq!((&c.1, &c.4, &c.5), (&t.0, &t.1, &t.2), "{port}: camera {i}");
        }
        assert_eq!(images.len(), timages.len());
        for (b, t) in images.iter().zip(&timages) {
            assert_eq!(b.3 as usize, t.2);
            let obs: Vec<(f64, f64, usize)> =
                b.5.iter().map(|&(x, y, p)| (x, y, p as usize)).collect();
            assert_eq!(obs, t.3);
            assert!((b.1.dot(t.0).abs() - 1.0).abs() < 1e-12 && (b.2 - t.1).length() == 0.0);
        }
        assert_eq!(points.len(), tpoints.len());
        for (id, (p, _)) in &points {
            assert_eq!(*p, tpoints[&(*id as usize)]);
        }
        let (name, k, refrac) = (&cams[0].1, &cams[0].4, &cams[0].5);
        assert_eq!(name, "PINHOLE");
        if port == "none" {
            assert!(refrac.is_none());
            let bytes = read("cameras.bin");
            // u64 count + u32 + i32 + 2 × u64 + 4 × f64 + i32 (−1) per camera.
            assert_eq!(bytes.len(), 8 + cams.len() * (4 + 4 + 16 + 32 + 4));
            assert_eq!(bytes[bytes.len() - 4..], (-1i32).to_le_bytes());
            continue;
        }
        let (rmodel, rp) = refrac.as_ref().expect("the port was not read");
        assert_eq!(
            rmodel,
            if port == "flat" {
                "FLATPORT"
            } else {
                "DOMEPORT"
            }
        );
        let mut n = 0;
        for (_, q, t, cam, _, obs) in &images {
            assert_eq!(*cam, 1);
            for &(x, y, pid) in obs {
                let pc = *q * points[&pid].0 + *t;
                let (o, dir) = refractive_colmap_ray(k, rmodel, rp, x, y);
                let miss = (pc - o).cross(dir).length();
                assert!(
                    miss < 1e-9,
                    "{port}: observation misses its point by {miss} m"
                );
                n += 1;
            }
        }
        assert!(n > 50, "{port}: only {n} observations");
    }
    // The ported reader refuses what the fork's would: a truncated file, an unknown
    // refraction id, and bytes after the last camera.
    let model = calibration_behind("flat");
    let d = tempfile::tempdir().unwrap();
    poser::truth::write(&model, d.path()).unwrap();
    let bytes = std::fs::read(d.path().join("colmap_refractive/cameras.bin")).unwrap();
    assert!(fork_binary::cameras(&bytes[..bytes.len() - 1]).is_err());
    let mut extra = bytes.clone();
    extra.push(0);
    assert!(fork_binary::cameras(&extra).is_err());
    let mut bad = bytes.clone();
    let at = 8 + 4 + 4 + 16 + 32; // the first camera's refraction id
    bad[at..at + 4].copy_from_slice(&7i32.to_le_bytes());
    assert!(fork_binary::cameras(&bad).is_err());
    // Upstream's cameras.bin has no refraction id: the fork's reader cannot take it.
    let up = std::fs::read(d.path().join("colmap/cameras.bin")).unwrap();
    assert!(fork_binary::cameras(&up).is_err());
}

/// `markers/markers.csv` is `points.csv` as marker rows: the same observations at the same
/// pixels, labelled by target point id and keyed by the image file a package loads; every label
/// is in `markers/gcp.csv` at its target point's position; an id that two targets share (two
/// coded targets with the same codes) is qualified by the target's name in both files.
#[test]
fn marker_files_are_the_truths_observations_with_their_gcp_reference() {
    fn file(files: &[(String, Vec<u8>)], name: &str) -> String {
        let (_, b) = files.iter().find(|(n, _)| n == name).unwrap();
        String::from_utf8(b.clone()).unwrap()
    }
    /// The rows after the column names (and, in the marker files, a `#` line before them).
    fn rows(text: &str, header: &str) -> Vec<Vec<String>> {
        let mut lines = text.lines();
        if !header.starts_with("image,") {
            let first = lines.next().unwrap();
            assert!(first.starts_with("# "), "{first}");
        }
        assert_eq!(lines.next().unwrap(), header);
        lines
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    }
    let mut model = load("calibration_flat.toml");
    for (sensor, ext) in [
        (None, "png"),
        (Some(poser::model::Sensor::default()), "jpg"),
    ] {
        model.sensor = sensor;
        let truth = poser::truth::compute(&model).unwrap();
        let files = poser::truth::files(&model, &truth).unwrap();
        let markers = file(&files, "markers/markers.csv");
        assert!(markers.lines().next().unwrap().contains("(0.5, 0.5)"));
        let m = rows(&markers, "marker,image,x,y");
        let p = rows(
            &file(&files, "points.csv"),
            "image,camera,pose,target,id,u,v,u_r,v_r,u_b,v_b,x,y,z,x_cam,y_cam,z_cam",
        );
        assert!(m.len() > 50);
        assert_eq!(m.len(), p.len());
        for (m, p) in m.iter().zip(&p) {
            // Ids are unique in this scene, so the label is the id.
            assert_eq!(
                (&m[0], &m[1], &m[2], &m[3]),
                (&p[4], &format!("{}.{ext}", p[0]), &p[5], &p[6])
            );
        }
        let gcp = rows(&file(&files, "markers/gcp.csv"), "label,x,y,z");
        let n: usize = model.targets.iter().map(|t| t.points.len()).sum();
        assert_eq!(gcp.len(), n);
        for t in &model.targets {
            for tp in &t.points {
                let row = gcp.iter().find(|r| r[0] == tp.id).unwrap();
                let xyz: Vec<f64> = row[1..].iter().map(|x| x.parse().unwrap()).collect();
                assert_eq!(xyz, tp.world.to_array().to_vec());
            }
        }
    }
    // Both targets become coded targets with codes 1..6: the ids clash.
    for t in &mut model.targets {
        t.kind = poser::model::TargetKind::Coded {
            count: 6,
            spacing: 0.05,
            diameter: 0.02,
            first_code: 1,
        };
        t.points = poser::geometry::targets::points(&t.name, &t.kind, &t.pose);
    }
    let truth = poser::truth::compute(&model).unwrap();
    let files = poser::truth::files(&model, &truth).unwrap();
    let gcp = rows(&file(&files, "markers/gcp.csv"), "label,x,y,z");
    let mut labels: Vec<&str> = gcp.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(labels.len(), 12);
    assert!(
        labels.contains(&"board/1") && labels.contains(&"dots/6"),
        "{labels:?}"
    );
    labels.sort();
    labels.dedup();
    assert_eq!(labels.len(), 12, "labels are unique");
    let m = rows(&file(&files, "markers/markers.csv"), "marker,image,x,y");
    assert!(!m.is_empty());
    assert!(m.iter().all(|r| labels.contains(&r[0].as_str())));
}
