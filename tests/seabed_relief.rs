//! A seabed through surveyed heights (`relief_file`, `relief_origin`): the generated seabed
//! passes through the listed points wherever the seabed object is placed, a GCP list printed
//! with `surface = "seabed"` lands on those heights, and points that fix no surface are a
//! located error. The shipped Moorea lesson scene keeps its GCPs' 3 m of relief.

use glam::DVec3;
use poser::model::{Model, Shape};
use std::path::Path;

const BASE: &str = r#"
[site]
depth = "10 m"

[water]
jerlov = "IB"

[camera]
width = 160
height = 120
focal_length = "8 mm"
pixel_pitch = "40 µm"

[camera.port]
type = "dome"

[network]
type = "explicit"

[[network.poses]]
position = [0, 0, -5]
look_at = [0, 0, -10]
up = [0, 1, 0]
"#;

/// Five points with 1.5 m of relief, in a frame whose origin `relief_origin` moves.
const POINTS: &str = "A 0 0 0.2\nB 6 1 1.1\nC 1 5 -0.4\nD 7 6 0.6\nE 3.5 3 1.5\n";

fn load_in(dir: &Path, scene: &str, points: &str) -> Result<Model, String> {
    std::fs::write(dir.join("pts.txt"), points).unwrap();
    let p = dir.join("scene.toml");
    std::fs::write(&p, format!("{BASE}{scene}")).unwrap();
    poser::scene::load(&p, &[])
        .map(|l| l.model)
        .map_err(|f| f.render())
}

/// Height of the seabed mesh at world (x, y) (the targets left out): the triangle straight
/// below a vertical ray.
fn height_at(m: &Model, x: f64, y: f64) -> f64 {
    let mut objects_only = m.clone();
    objects_only.targets.clear();
    let bvh = poser::geometry::Bvh::of_model(&objects_only).unwrap();
    let ray = poser::geometry::Ray {
        origin: DVec3::new(x, y, 0.0),
        dir: DVec3::NEG_Z,
    };
    bvh.intersect(&ray, f64::INFINITY)
        .map(|h| -h.t)
        .expect("the ray meets the seabed")
}

#[test]
fn the_seabed_passes_through_the_points_wherever_it_is_placed() {
    let tmp = tempfile::tempdir().unwrap();
    // The seabed is turned 90° and moved; the points' frame is moved elsewhere. With no
    // roughness the mesh is the spline, sampled every 5 cm.
    let m = load_in(
        tmp.path(),
        r#"
[[objects]]
name = "reef"
shape = "seabed"
width = "12 m"
length = "10 m"
roughness = 0
resolution = "0.05 m"
position = [1, -2, -10.5]
rotation = [0, 0, "90 deg"]
relief_file = "pts.txt"
relief_origin = [-3, -4, -10]

[[targets]]
name = "gcp"
type = "points_file"
file = "pts.txt"
position = [-3, -4, -10]
surface = "seabed"
"#,
        POINTS,
    )
    .unwrap();
    let Shape::Seabed { relief, .. } = &m.objects[0].shape else {
        panic!("not a seabed")
    };
    assert_eq!(relief.len(), 5);
    for line in POINTS.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let (x, y, z) = (
            f[1].parse::<f64>().unwrap() - 3.0,
            f[2].parse::<f64>().unwrap() - 4.0,
            f[3].parse::<f64>().unwrap() - 10.0,
        );
        let h = height_at(&m, x, y);
        assert!((h - z).abs() < 2e-3, "{}: mesh at {h}, surveyed {z}", f[0]);
        // The printed disk stands on it, 1 mm up.
        let t = m
            .targets
            .iter()
            .find(|t| t.name == format!("gcp/{}", f[0]))
            .unwrap();
        let w = t.points[0].world;
        assert!((w.truncate() - glam::DVec2::new(x, y)).length() < 2e-3);
        assert!(
            (w.z - z - 1e-3).abs() < 2e-3,
            "{}: disk at {}, surveyed {z}",
            f[0],
            w.z
        );
    }
    // Without the relief the same seabed is flat at its position.
    let flat = load_in(
        tmp.path(),
        r#"
[[objects]]
name = "reef"
shape = "seabed"
width = "12 m"
length = "10 m"
roughness = 0
position = [1, -2, -10.5]
"#,
        POINTS,
    )
    .unwrap();
    assert!((height_at(&flat, 0.5, 1.0) + 10.5).abs() < 1e-9);
}

#[test]
fn points_that_fix_no_surface_are_a_located_error() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = r#"
[[objects]]
shape = "seabed"
relief_file = "pts.txt"
"#;
    for (points, why) in [
        ("A 0 0 0\nB 1 1 1\nC 2 2 0\n", "one line"),
        ("A 0 0 0\nB 1 0 1\n", "at least 3"),
        ("A 0 0 0\nB 1 0 1\nC 0 1 0\nD 1 0 2\n", "share one (x, y)"),
    ] {
        let e = load_in(tmp.path(), scene, points).unwrap_err();
        assert!(e.contains("E0302") && e.contains(why), "{points}: {e}");
        assert!(e.contains("scene.toml:") && e.contains("help:"), "{e}");
    }
    // A relief on a shape that has none is an unknown key there, not silently ignored.
    let e = load_in(
        tmp.path(),
        "[[objects]]\nshape = \"box\"\nrelief_file = \"pts.txt\"\n",
        POINTS,
    )
    .unwrap_err();
    assert!(e.contains("relief_file"), "{e}");
}

#[test]
fn the_moorea_scene_keeps_its_gcps_surveyed_heights() {
    let m = poser::scene::load(Path::new("scenarios/sites/moorea.toml"), &[])
        .map(|l| l.model)
        .unwrap_or_else(|f| panic!("{}", f.render()));
    let text = std::fs::read_to_string("scenarios/sites/assets/moorea_gcps.txt").unwrap();
    let pts = poser::points::parse(&text).unwrap();
    assert_eq!(pts.len(), 8);
    let origin = DVec3::new(-27.5, -10.0, -12.0);
    let mut zs = vec![];
    for p in &pts {
        let want = origin + p.p;
        let t = m
            .targets
            .iter()
            .find(|t| t.name == format!("gcp/{}", p.id))
            .unwrap();
        let w = t.points[0].world;
        // Dropped onto the reef: the spline's height plus the 12 cm RMS rough relief.
        assert!((w.truncate() - want.truncate()).length() < 2e-3);
        assert!(
            (w.z - want.z).abs() < 0.4,
            "gcp/{}: {} for {}",
            p.id,
            w.z,
            want.z
        );
        zs.push(w.z);
    }
    let span =
        zs.iter().cloned().fold(f64::MIN, f64::max) - zs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 2.5, "the GCPs span {span} m of height");
}
