//! Multi-layer flat ports written in a scene (`[camera.port] layers = […]`): the scene
//! resolves every layer in order, the exact projection refracts through each of them (checked
//! against Snell's law layer by layer, an oracle independent of the port solver), the
//! backends that cannot model them refuse by name, and the truth exports describe them.

use glam::DVec3;
use poser::backend::Backend;
use poser::model::{Model, Port};
use poser::optics::project::Projector;
use std::path::Path;

const BASE: &str = r#"
[site]
depth = "10 m"

[water]
jerlov = "IB"

[camera]
width = 400
height = 300
focal_length = "10 mm"
pixel_pitch = "20 µm"

[network]
type = "explicit"

[[network.poses]]
position = [0, 0, -3]
look_at = [0, 0, -10]
up = [0, 1, 0]

[camera.port]
type = "flat"
pupil_distance = "30 mm"
"#;

fn load(dir: &Path, port_keys: &str) -> Model {
    let path = dir.join("scene.toml");
    std::fs::write(&path, format!("{BASE}{port_keys}\n")).unwrap();
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

/// The ray leaving the port for pixel (u, v) by Snell's law at each parallel face of an
/// untilted flat port: lateral offset Σ tᵢ·tan θᵢ, direction with sin θ_w = sin θ₀ / n_w.
fn snell_ray(m: &Model, u: f64, v: f64, layers: &[(f64, f64)], n_w: f64) -> (DVec3, DVec3) {
    let c = &m.cameras[0];
    let d = DVec3::new((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0).normalize();
    let Port::Flat { distance, .. } = &c.port else {
        panic!("not flat")
    };
    let s0 = (d.x * d.x + d.y * d.y).sqrt();
    let radial = if s0 > 0.0 {
        DVec3::new(d.x / s0, d.y / s0, 0.0)
    } else {
        DVec3::X
    };
    let tan = |s: f64| s / (1.0 - s * s).sqrt();
    let mut lateral = distance * tan(s0);
    let mut z = *distance;
    for &(t, n) in layers {
        lateral += t * tan(s0 / n);
        z += t;
    }
    let sw = s0 / n_w;
    let dir = radial * sw + DVec3::Z * (1.0 - sw * sw).sqrt();
    (radial * lateral + DVec3::Z * z, dir)
}

#[test]
fn layers_resolve_in_order_and_refract_by_snell() {
    let tmp = tempfile::tempdir().unwrap();
    let m = load(
        tmp.path(),
        r#"layers = [{ thickness = "6 mm", material = "N-BK7" }, { thickness = "3 mm", ior = 1.77 }, { thickness = "2 mm", material = "PMMA" }]"#,
    );
    let port = &m.cameras[0].port;
    let Port::Flat {
        thickness,
        glass,
        outer_layers,
        ..
    } = port
    else {
        panic!("flat port expected, got {port:?}")
    };
    assert_eq!(*thickness, 0.006);
    assert_eq!(glass.name, "N-BK7");
    assert_eq!(outer_layers.len(), 2);
    assert_eq!(outer_layers[0].glass.ior, [1.77; 3]);
    assert_eq!(outer_layers[1].glass.name, "PMMA");
    assert!((port.total_thickness() - 0.011).abs() < 1e-15);
    assert_eq!(port.interfaces(), 4);

    let n_w = m.ambient_ior()[1];
    let layers = port.flat_layers(1);
    let pr = Projector::for_camera(&m.cameras[0], 1, n_w).unwrap();
    let mut worst: f64 = 0.0;
    for (u, v) in [
        (200.0, 150.0),
        (10.5, 20.5),
        (399.0, 299.0),
        (250.25, 30.0),
        (0.0, 150.0),
    ] {
        let ray = pr.camera_ray(u, v).unwrap();
        let (o, d) = snell_ray(&m, u, v, &layers, n_w);
        assert!(
            (ray.origin - o).length() < 1e-12,
            "origin at ({u}, {v}): {:?} vs {o:?}",
            ray.origin
        );
        assert!((ray.dir - d).length() < 1e-12, "direction at ({u}, {v})");
        // And back: a point 4 m along the ray projects onto the same pixel.
        let px = pr.project_camera(o + d * 4.0).unwrap();
        worst = worst.max((px[0] - u).hypot(px[1] - v));
    }
    assert!(worst < 1e-9, "round trip {worst} px");
}

#[test]
fn two_layers_of_one_glass_are_one_slab_and_a_different_glass_is_not() {
    let tmp = tempfile::tempdir().unwrap();
    let split = load(
        tmp.path(),
        r#"layers = [{ thickness = "4 mm", material = "N-BK7" }, { thickness = "6 mm", material = "N-BK7" }]"#,
    );
    let one = load(tmp.path(), r#"thickness = "10 mm""#);
    let sapphire = load(
        tmp.path(),
        r#"layers = [{ thickness = "4 mm", material = "N-BK7" }, { thickness = "6 mm", material = "sapphire" }]"#,
    );
    let n_w = one.ambient_ior()[1];
    let proj = |m: &Model| Projector::for_camera(&m.cameras[0], 1, n_w).unwrap();
    let (a, b, c) = (proj(&split), proj(&one), proj(&sapphire));
    let (mut same, mut differ): (f64, f64) = (0.0, f64::INFINITY);
    for p in [
        DVec3::new(0.4, 0.3, 3.0),
        DVec3::new(-0.5, 0.3, 2.0),
        DVec3::new(0.05, -0.02, 0.5),
    ] {
        let (pa, pb, pc) = (
            a.project_camera(p).unwrap(),
            b.project_camera(p).unwrap(),
            c.project_camera(p).unwrap(),
        );
        same = same.max((pa[0] - pb[0]).hypot(pa[1] - pb[1]));
        differ = differ.min((pc[0] - pb[0]).hypot(pc[1] - pb[1]));
    }
    assert!(same < 1e-9, "4 + 6 mm of N-BK7 vs 10 mm: {same} px");
    assert!(
        differ > 0.01,
        "a sapphire layer must move the image: {differ} px"
    );
}

#[test]
fn mitsuba_and_blender_refuse_and_native_does_not() {
    let tmp = tempfile::tempdir().unwrap();
    let m = load(
        tmp.path(),
        r#"layers = [{ thickness = "6 mm" }, { thickness = "2 mm", material = "sapphire" }]"#,
    );
    for b in [Backend::Mitsuba, Backend::Blender] {
        let err = b.compile(&m, &tmp.path().join(b.name())).unwrap_err();
        assert!(
            err.contains("multi-layer flat port") && err.contains("--backend native"),
            "{err}"
        );
        assert!(
            !tmp.path().join(b.name()).exists(),
            "{} wrote output",
            b.name()
        );
    }
    assert!(Backend::Native.refuse(&m).is_ok());
}

#[test]
fn truth_exports_describe_every_layer() {
    let tmp = tempfile::tempdir().unwrap();
    let m = load(
        tmp.path(),
        r#"layers = [{ thickness = "6 mm" }, { thickness = "2 mm", material = "sapphire" }]"#,
    );
    let out = tmp.path().join("truth");
    poser::truth::write(&m, &out).unwrap();
    let yml = std::fs::read_to_string(out.join("opencv/camera_1.yml")).unwrap();
    assert!(yml.contains("port_outer_layers: !!opencv-matrix"), "{yml}");
    assert!(yml.contains("rows: 1\n   cols: 4"), "{yml}");
    // Refractive COLMAP's FLATPORT has one layer: the export says why it leaves the port out
    // instead of writing a wrong one.
    let cams = std::fs::read_to_string(out.join("colmap/cameras.txt")).unwrap();
    assert!(cams.contains("FLATPORT has one glass layer"), "{cams}");
    if let Ok(r) = std::fs::read_to_string(out.join("colmap_refractive/cameras.txt")) {
        let data = r.lines().filter(|l| !l.starts_with('#'));
        assert!(data.clone().all(|l| !l.contains("FLATPORT")), "{r}");
    }
}
