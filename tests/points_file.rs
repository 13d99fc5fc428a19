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
        // Four samples: the disks against their plates need no more (16 took most of the test).
        .args(["--backend", "native", "--samples", "4"])
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

/// One point-list parser: the same GCP file (a comment, a header naming the columns, rows
/// separated by tabs, blanks and commas) given to `poser project --points` and as a
/// `points_file` target gives the same points, ids and pixels.
#[test]
fn project_and_a_points_file_target_read_the_same_gcp_file() {
    let gcps = "# a lab's GCP list\nid\tx\ty\tz\nGCP1\t0.0\t0.0\t-10\nGCP7 0.6 -0.4 -10  # corner\nA-12, -0.5, 0.45, -10\n";
    let tmp = tempfile::tempdir().unwrap();
    let p = write(
        tmp.path(),
        r#"
[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
diameter = "5 cm"
"#,
        gcps,
    );
    let m = load(&p);
    let from_target: Vec<(String, DVec3)> = m
        .targets
        .iter()
        .map(|t| {
            let id = t.points[0].id.strip_prefix("gcp/").unwrap().to_string();
            (id, t.points[0].world)
        })
        .collect();
    let from_project = poser::points::parse_points(gcps, "gcps.csv").unwrap();
    assert_eq!(from_project, from_target);
    assert_eq!(from_project.len(), 3);
    // The command itself takes the file, and projects the target's points.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["project", "--frame", "world", "--pose", "0"])
        .arg(&p)
        .arg("--points")
        .arg(tmp.path().join("gcps.csv"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pr = m.projector(0, 1).unwrap();
    assert_eq!(
        stdout,
        poser::cli::project::project_csv(&pr, &from_target, Some(0))
    );
    assert!(
        stdout.lines().skip(1).all(|l| l.ends_with(",ok")),
        "{stdout}"
    );
}

/// The point-list parser on `poser project`'s CSV: quotes, header order, located errors.
#[test]
fn csv_point_lists_read_by_header_with_located_errors() {
    use poser::points::parse_points;
    let pts = parse_points("id,x,y,z\n\"a,1\",1,2,3\nb, 4 ,5,6\n", "f.csv").unwrap();
    assert_eq!(pts[0].0, "a,1");
    assert_eq!(pts[1].1, DVec3::new(4.0, 5.0, 6.0));
    let e = parse_points("id,x,y,z\na,1,2\n", "f.csv").unwrap_err();
    assert!(e.starts_with("f.csv:2:"), "{e}");
    let e = parse_points("id,x,y,z\na,1,zz,3\n", "f.csv").unwrap_err();
    assert!(
        e.starts_with("f.csv:2:5: `zz` is not a finite number"),
        "{e}"
    );
    assert!(
        parse_points("name,x,y\n", "f.csv")
            .unwrap_err()
            .contains("help:")
    );
    assert!(
        parse_points("", "f.csv")
            .unwrap_err()
            .contains("empty file")
    );
    assert!(parse_points("id,x,y,z\na,NaN,1,1\n", "f.csv").is_err());
    assert!(parse_points("id,x,y,z\n\"a,1,2,3\n", "f.csv").is_err());
    // Column order is taken from the header, extra columns are ignored.
    let p = parse_points("z,y,x,id,note\n3,2,1,p,x\n", "f.csv").unwrap();
    assert_eq!(p[0], ("p".into(), DVec3::new(1.0, 2.0, 3.0)));
    // A header only: no points (`poser project` writes its header alone).
    assert!(parse_points("id,x,y,z\n", "f.csv").unwrap().is_empty());
    // `#` inside an id is not a comment; spaces inside a comma-separated id are kept; a line
    // that mixes separators and a trailing comma are read.
    let p = parse_points("id,x,y,z\nGCP#2;4;5;6 # a note\n", "f.csv").unwrap();
    assert_eq!(p[0], ("GCP#2".into(), DVec3::new(4.0, 5.0, 6.0)));
    let p = parse_points("id,x,y,z\nGCP 1,1,2,3\nA1 0.5,1,2\nB,1,2,3,\n", "f.csv").unwrap();
    assert_eq!(p[0].0, "GCP 1");
    assert_eq!(p[1], ("A1".into(), DVec3::new(0.5, 1.0, 2.0)));
    assert_eq!(p[2].0, "B");
}

/// The point-list parser on published lists (`points_file`): blanks, commas, comments, an
/// optional header; errors with line and column.
#[test]
fn whitespace_csv_header_and_comments() {
    use poser::scene::points_file::parse;
    let t = "\u{feff}# test field\nid,x,y,z\nA1, 0.5, -1.25, -10\n\nB2\t1e-1 2 -9.5  # a note\n";
    let v = parse(t).unwrap();
    assert_eq!(v.len(), 2);
    assert_eq!(v[0].id, "A1");
    assert_eq!(v[0].p, DVec3::new(0.5, -1.25, -10.0));
    assert_eq!(v[1].p, DVec3::new(0.1, 2.0, -9.5));
    // No header at all; a header by position.
    assert_eq!(parse("7 1 2 3").unwrap()[0].id, "7");
    assert_eq!(
        parse("name east north up\nP 1 2 3").unwrap()[0].p,
        DVec3::new(1.0, 2.0, 3.0)
    );
}

#[test]
fn points_file_errors_name_line_and_column() {
    use poser::scene::points_file::parse;
    assert_eq!(
        parse("id x y z\nA 1 2 3\nB 1 zz 3\n").unwrap_err(),
        (
            3,
            5,
            "`zz` is not a finite number (column `y`, in metres)".into()
        )
    );
    assert_eq!(
        parse("A 1 2 3\nA 4 5 6").unwrap_err(),
        (2, 1, "the id `A` appears twice".into())
    );
    assert_eq!(parse("A 1 2 3 4").unwrap_err().1, 9);
    assert_eq!(parse("A 1 2").unwrap_err().0, 1);
    assert!(parse("# nothing\n\n").is_err());
    assert!(parse("id x y z\n").is_err());
    assert!(parse("A 1 2 inf").is_err());
    // A header is only the first data line: a later non-numeric line is an error.
    assert_eq!(parse("A 1 2 3\nid x y z").unwrap_err().0, 2);
}

#[test]
fn channel_names() {
    use poser::optics::project::parse_channel;
    assert_eq!(parse_channel("R"), Ok(0));
    assert_eq!(parse_channel("green"), Ok(1));
    assert_eq!(parse_channel("b"), Ok(2));
    assert!(parse_channel("x").is_err());
}
