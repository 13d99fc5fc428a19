//! `[[targets]] type = "points_file"`: a published test field or GCP list dropped into a scene
//! as it is. Ids are kept, the file's frame is placed by `position`/`rotation`, `surface =
//! "seabed"` lays each disk on the surface below it (checked against a tilted plane whose
//! height is known in closed form), the ground truth sees the disks, the native renderer
//! prints them, and a bad file is an error naming its line and column.

use glam::DVec3;
use poser::model::{Model, TargetKind};
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

[render]
samples = 16

[network]
type = "explicit"

[[network.poses]]
position = [0, 0, -7]
look_at = [0, 0, -10]
up = [0, 1, 0]

[[lights]]
type = "ambient"
radiance = 1.0
"#;

fn write(dir: &Path, scene: &str, points: &str) -> std::path::PathBuf {
    std::fs::write(dir.join("gcps.csv"), points).unwrap();
    let p = dir.join("scene.toml");
    std::fs::write(&p, format!("{BASE}{scene}")).unwrap();
    p
}

fn load(p: &Path) -> Model {
    match poser::scene::load(p, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

const POINTS: &str = "# a lab's GCP list\nid, x, y, z\nGCP1, 0.0, 0.0, 0.0\nGCP7, 0.6, -0.4, 0.0\nA-12, -0.5, 0.45, 0.0\n";

#[test]
fn given_points_keep_their_ids_in_the_targets_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let p = write(
        tmp.path(),
        r#"
[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
diameter = "8 cm"
position = [1, 2, -10]
rotation = [0, 0, "90 deg"]
"#,
        POINTS,
    );
    let m = load(&p);
    assert_eq!(m.targets.len(), 3);
    let t = &m.targets[1];
    assert_eq!(t.name, "gcp/GCP7");
    assert_eq!(t.points[0].id, "gcp/GCP7");
    assert!(matches!(t.kind, TargetKind::Disk { diameter } if (diameter - 0.08).abs() < 1e-12));
    // Rotated 90° about z: (0.6, -0.4) → (0.4, 0.6), then moved by the position.
    let want = DVec3::new(1.4, 2.6, -10.0);
    assert!(
        (t.points[0].world - want).length() < 1e-12,
        "{:?}",
        t.points[0].world
    );
    assert_eq!(m.targets[2].points[0].id, "gcp/A-12");
}

#[test]
fn seabed_points_lie_on_the_surface_below_them_facing_it() {
    let tmp = tempfile::tempdir().unwrap();
    // A plane tilted 10° about x, centred 10 m down: z = -10 + y·tan 10°, normal
    // (0, -sin 10°, cos 10°).
    let p = write(
        tmp.path(),
        r#"
[[objects]]
name = "slope"
shape = "plane"
width = "4 m"
height = "4 m"
position = [0, 0, -10]
rotation = ["10 deg", 0, 0]
albedo = 0.5

[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
surface = "seabed"
diameter = "10 cm"

[[targets]]
name = "lost"
type = "points_file"
file = "far.csv"
surface = "seabed"
"#,
        POINTS,
    );
    std::fs::write(tmp.path().join("far.csv"), "X 30 30 0\n").unwrap();
    let loaded = poser::scene::load(&p, &[]).unwrap_or_else(|f| panic!("{}", f.render()));
    // The far point is above no object: it lands on the nominal seabed, with a warning.
    assert!(
        loaded.warnings.iter().any(|w| w.code == "W0292"),
        "{}",
        loaded.render_warnings()
    );
    let m = loaded.model;
    let a = 10f64.to_radians();
    let n = DVec3::new(0.0, -a.sin(), a.cos());
    for t in m.targets.iter().filter(|t| t.name.starts_with("gcp/")) {
        let w = t.points[0].world;
        let on_plane = -10.0 + w.y * a.tan();
        // 1 mm above the surface along its normal.
        let lift = (w - DVec3::new(w.x, w.y, on_plane)).dot(n);
        assert!((lift - 1e-3).abs() < 1e-9, "{}: lift {lift}", t.name);
        assert!((t.pose.rotation.z_axis - n).length() < 1e-9, "{}", t.name);
    }
    let lost = m.targets.iter().find(|t| t.name == "lost/X").unwrap();
    assert!((lost.points[0].world.z - (-10.0 + 1e-3)).abs() < 1e-12);
}

#[test]
fn the_truth_sees_the_disks_and_the_native_renderer_prints_them() {
    let tmp = tempfile::tempdir().unwrap();
    let p = write(
        tmp.path(),
        r#"
[[objects]]
name = "floor"
shape = "plane"
width = "6 m"
height = "6 m"
position = [0, 0, -10]
albedo = 0.6

[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
surface = "seabed"
diameter = "25 cm"
"#,
        POINTS,
    );
    let out = tmp.path().join("out");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["render"])
        .arg(&p)
        .arg("-o")
        .arg(&out)
        .args(["--backend", "native"])
        .status()
        .unwrap();
    assert!(status.success());
    let csv = std::fs::read_to_string(out.join("truth/points.csv"))
        .or_else(|_| std::fs::read_to_string(out.join("points.csv")))
        .expect("truth points.csv");
    let mut seen = 0;
    let exr = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.ends_with(".exr") && !n.ends_with(".depth.exr")
        })
        .expect("an EXR image");
    let img = image::open(&exr).unwrap().into_rgb32f();
    let lum = |u: f64, v: f64| {
        let px = img.get_pixel(u as u32, v as u32);
        (px[0] + px[1] + px[2]) as f64
    };
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if !f[col("target")].starts_with("gcp") {
            continue;
        }
        seen += 1;
        let (u, v): (f64, f64) = (f[col("u")].parse().unwrap(), f[col("v")].parse().unwrap());
        // The disk (radius 0.125 m at 3 m with a 200 px focal length behind the dome: ≈ 8 px)
        // is dark against the white plate around it (which reaches ≈ 17 px out).
        let bx = |u: f64, v: f64| {
            let mut s = 0.0;
            for du in -1..=1 {
                for dv in -1..=1 {
                    s += lum(u + du as f64, v + dv as f64);
                }
            }
            s / 9.0
        };
        let centre = bx(u, v);
        let plate = [(12.0, 0.0), (-12.0, 0.0), (0.0, 12.0), (0.0, -12.0)]
            .iter()
            .map(|(a, b)| bx(u + a, v + b))
            .sum::<f64>()
            / 4.0;
        assert!(
            centre < 0.3 * plate,
            "disk at ({u}, {v}): {centre} vs plate {plate}"
        );
    }
    assert_eq!(seen, 3, "{csv}");
}

#[test]
fn a_bad_line_is_an_error_naming_file_line_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let p = write(
        tmp.path(),
        r#"
[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
"#,
        "id x y z\nP1 0 0 -10\nP2 0.5 O.5 -10\n",
    );
    let Err(err) = poser::scene::load(&p, &[]) else {
        panic!("a bad points file must be an error")
    };
    let text = err.render();
    assert!(
        text.contains("E0294") && text.contains("gcps.csv:3:8"),
        "{text}"
    );
    assert!(
        text.contains("scene.toml:"),
        "the error points at the `file` key: {text}"
    );
}
