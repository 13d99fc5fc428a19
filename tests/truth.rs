//! Ground truth (`poser truth`, `truth::write`): every reported pixel is the exact refractive
//! image of its target point, hidden and back-facing points are left out, the COLMAP model is
//! consistent, and output is deterministic.
use glam::DVec3;
use poser::model::{Material, Model, Object, Pose, Shape};
use poser::optics::project::Projector;
use std::path::Path;

fn load(name: &str) -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

#[test]
fn every_observation_is_the_exact_refractive_image() {
    let model = load("calibration_flat.toml");
    let truth = poser::truth::compute(&model).unwrap();
    let p = Projector::new(&model, 0, 1).unwrap();
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
