//! `poser project` end to end: CSV in, CSV out, explicit statuses, usage errors.
use std::process::Command;

fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}
fn scene() -> String {
    format!(
        "{}/scenarios/calibration_flat.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn project_camera_frame_points_with_statuses() {
    let d = tempfile::tempdir().unwrap();
    let pts = d.path().join("p.csv");
    std::fs::write(
        &pts,
        "id,x,y,z\naxis,0,0,2\nside,0.3,-0.2,1.5\nbehind,0,0,-1\nglass,0,0,0.03\nfar,50,0,1\n",
    )
    .unwrap();
    let out = d.path().join("o.csv");
    let st = poser()
        .args(["project", &scene(), "--points"])
        .arg(&pts)
        .arg("-o")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(text.lines().next().unwrap(), "id,u,v,status");
    // On the axis of an untilted port: exactly the principal point (800, 600).
    assert_eq!(rows[0], vec!["axis", "800", "600", "ok"]);
    assert_eq!(rows[1][3], "ok");
    assert_eq!(rows[2], vec!["behind", "", "", "behind_camera"]);
    assert_eq!(rows[3], vec!["glass", "", "", "inside_glass"]);
    assert_eq!(rows[4][3], "off_sensor");
    assert!(rows[4][1].parse::<f64>().unwrap() > 1600.0);
    // The R and B channels differ (dispersion) for an off-axis point.
    let r = poser()
        .args(["project", &scene(), "--channel", "r", "--points"])
        .arg(&pts)
        .output()
        .unwrap();
    let b = poser()
        .args(["project", &scene(), "--channel", "b", "--points"])
        .arg(&pts)
        .output()
        .unwrap();
    let ur: f64 = String::from_utf8_lossy(&r.stdout)
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let ub: f64 = String::from_utf8_lossy(&b.stdout)
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!((ur - ub).abs() > 0.1, "R {ur} vs B {ub}");
}

#[test]
fn project_errors_are_clear() {
    let d = tempfile::tempdir().unwrap();
    let pts = d.path().join("p.csv");
    std::fs::write(&pts, "id,x,y,z\na,1,oops,2\n").unwrap();
    let o = poser()
        .args(["project", &scene(), "--points"])
        .arg(&pts)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("p.csv:2:") && err.contains("oops"), "{err}");
    std::fs::write(&pts, "id,x,y,z\na,1,1,2\n").unwrap();
    let o = poser()
        .args([
            "project",
            &scene(),
            "--frame",
            "world",
            "--pose",
            "999",
            "--points",
        ])
        .arg(&pts)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = poser()
        .args(["project", &scene(), "--camera", "nope", "--points"])
        .arg(&pts)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no such camera"));
}

#[test]
fn truth_command_writes_all_files() {
    let d = tempfile::tempdir().unwrap();
    let st = poser()
        .args(["truth", &scene(), "-o"])
        .arg(d.path())
        .status()
        .unwrap();
    assert!(st.success());
    for f in [
        "truth.json",
        "points.csv",
        "cameras.csv",
        "images.csv",
        "colmap/cameras.txt",
        "colmap/images.txt",
        "colmap/points3D.txt",
    ] {
        assert!(d.path().join(f).is_file(), "{f}");
    }
}
