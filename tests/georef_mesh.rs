//! Georeferenced photogrammetric meshes (issue 36, "bring your own site"): a model written at
//! UTM coordinates with `offset` (or `offset_file`) is the model written locally, to 1e-9 m in
//! the world and 1e-6 px in the truth, textured or not; a Y-up file with `up_axis = "y"` (and a
//! glTF, Y-up by definition, with a georeferenced node translation read in f64) is the Z-up
//! one; a millimetre model at `scale = 0.001` is the metre model; far coordinates without an
//! offset are warned of with the offset to give; a malformed offset file is a located error;
//! `poser explain` prints the extent; Mitsuba and Cycles are given the same geometry.

use crate::support;
use glam::DVec3;
use poser::geometry::mesh::object_mesh;
use poser::model::Model;
use std::path::{Path, PathBuf};
use support::textured::poser_in;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A 4 × 4-cell heightfield of 1.2 m × 0.9 m with a relief of a few centimetres, its heights
/// decimals no binary fraction holds; `at` maps a local point (x, y, z) to the line written.
fn relief(at: impl Fn(f64, f64, f64) -> String) -> String {
    let mut s = String::from("# relief\n");
    for j in 0..5 {
        for i in 0..5 {
            let (x, y) = (-0.6 + 0.3 * i as f64, -0.45 + 0.225 * j as f64);
            let z = 0.0123 * ((i * 7 + j * 3) % 5) as f64 + 0.001;
            s += &format!("v {}\n", at(x, y, z));
        }
    }
    for j in 0..4 {
        for i in 0..4 {
            let k = 1 + i + 5 * j;
            s += &format!("f {} {} {} {}\n", k, k + 1, k + 6, k + 5);
        }
    }
    s
}

/// UTM-like shift used throughout.
const E: f64 = 500_000.0;
const N: f64 = 4_200_000.0;
const H: f64 = -12.0;

/// The scene: the textured test site's camera and sun, the relief as object `relief` and
/// `extra` (more `[[objects]]` keys for it), three GCPs dropped onto it.
fn scene(dir: &Path, relief_path: &str, extra: &str) -> PathBuf {
    let text = format!(
        r#"name = "georef"

[site]
depth = "10 m"
surface = "none"

[sun]
elevation = "60 deg"
azimuth = "120 deg"
irradiance = 1000

[camera]
width = 120
height = 90
sensor_width = "36 mm"
focal_length = "26 mm"

[[objects]]
name = "relief"
shape = "mesh"
path = "{relief_path}"
position = [0.1, -0.05, -5.0]
rotation = [0, 0, "20 deg"]
{extra}

[[targets]]
name = "gcp"
type = "points_file"
file = "gcps.csv"
surface = "seabed"
diameter = "4 cm"

[network]
type = "explicit"
speed = "0.2 m/s"

[[network.poses]]
position = [0.1, 0.0, -3.8]
look_at = [0.1, 0.0, -5.0]
up = [0.0, 1.0, 0.0]
"#
    );
    std::fs::write(
        dir.join("gcps.csv"),
        "A 0.013 0.021 -3\nB -0.31 0.17 -3\nC 0.27 -0.2 -3\n",
    )
    .unwrap();
    let p = dir.join(format!("{}.toml", relief_path.replace(['.', '/'], "_")));
    std::fs::write(&p, text).unwrap();
    p
}

fn load(path: &Path) -> Model {
    match poser::scene::load(path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

/// Largest distance between the world vertices of object 0 of two models.
fn vertex_gap(a: &Model, b: &Model) -> f64 {
    let (ma, mb) = (
        object_mesh(&a.objects[0], Path::new(".")).unwrap(),
        object_mesh(&b.objects[0], Path::new(".")).unwrap(),
    );
    assert_eq!(ma.triangles, mb.triangles);
    assert_eq!(ma.positions.len(), mb.positions.len());
    ma.positions
        .iter()
        .zip(&mb.positions)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

/// Largest gap between the dropped GCPs of two models (m) and between their pixels (px).
fn truth_gap(a: &Model, b: &Model) -> (f64, f64) {
    let (pa, pb) = (a.projector(0, 1).unwrap(), b.projector(0, 1).unwrap());
    let (mut dm, mut dpx) = (0.0f64, 0.0f64);
    assert_eq!(a.targets.len(), 3);
    for (ta, tb) in a.targets.iter().zip(&b.targets) {
        let (p, q) = (ta.pose.translation, tb.pose.translation);
        // Dropped onto the relief, not onto the nominal seabed.
        assert!(p.z > -5.01 && p.z < -4.9, "{p}");
        dm = dm.max(p.distance(q));
        let (u, v) = (
            pa.project_world(0, p).unwrap(),
            pb.project_world(0, q).unwrap(),
        );
        dpx = dpx.max((u[0] - v[0]).hypot(u[1] - v[1]));
    }
    (dm, dpx)
}

#[test]
fn a_utm_model_with_its_offset_is_the_local_model() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("local.obj"),
        relief(|x, y, z| format!("{x} {y} {z}")),
    )
    .unwrap();
    // Written as a photogrammetry package writes UTM: easting, northing to the millimetre
    // and beyond, in text.
    std::fs::write(
        d.join("utm.obj"),
        relief(|x, y, z| format!("{:.6} {:.6} {:.6}", E + x, N + y, H + z)),
    )
    .unwrap();
    std::fs::write(d.join("utm.xyz"), "EPSG:32633 500000, 4200000, -12\n").unwrap();
    let local = load(&scene(d, "local.obj", ""));
    let utm = load(&scene(d, "utm.obj", "offset = [500000, 4200000, -12]"));
    let side = load(&scene(d, "utm.obj", "offset_file = \"utm.xyz\""));
    for m in [&utm, &side] {
        let gap = vertex_gap(&local, m);
        let (dm, dpx) = truth_gap(&local, m);
        eprintln!("UTM − local: vertices {gap:.2e} m, GCPs {dm:.2e} m, {dpx:.2e} px");
        assert!(gap < 1e-9 && dm < 1e-9 && dpx < 1e-6, "{gap} {dm} {dpx}");
    }
    // Without the offset subtracted in f64 first, f32 vertices (a PLY for Mitsuba or Cycles)
    // would be 0.5 m apart at this northing.
    assert_eq!(
        (N as f32 + 0.1) - N as f32,
        0.0,
        "f32 cannot hold 0.1 m at 4 200 000 m"
    );
}

#[test]
fn a_textured_utm_site_is_the_local_site_in_the_truth_and_the_texture() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let src = root().join("tests/textures/mesh");
    for f in ["site.mtl", "reef.png", "site.obj"] {
        std::fs::copy(src.join(f), d.join(f)).unwrap();
    }
    let obj = std::fs::read_to_string(src.join("site.obj")).unwrap();
    let utm: String = obj
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(r) => {
                let c: Vec<f64> = r.split_whitespace().map(|w| w.parse().unwrap()).collect();
                format!("v {:.6} {:.6} {:.6}\n", E + c[0], N + c[1], H + c[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(d.join("utm.obj"), utm).unwrap();
    let local = load(&scene(d, "site.obj", ""));
    let far = load(&scene(d, "utm.obj", "offset = [500000, 4200000, -12]"));
    assert!(matches!(
        far.objects[0].shape,
        poser::model::Shape::Mesh { textured: true, .. }
    ));
    let (dm, dpx) = truth_gap(&local, &far);
    assert!(dm < 1e-9 && dpx < 1e-6, "{dm} {dpx}");
    // The textured geometry (what the renderers draw and sample the image on).
    let (ba, bb) = (
        poser::texture::Textured::of_model(&local).unwrap(),
        poser::texture::Textured::of_model(&far).unwrap(),
    );
    for (x, y) in [(0.0, 0.0), (-0.31, 0.2), (0.3, -0.2), (0.758, 0.189)] {
        let ray = poser::geometry::Ray {
            origin: DVec3::new(x, y, -4.0),
            dir: DVec3::new(0.0, 0.0, -1.0),
        };
        let (ha, hb) = (
            ba.intersect(&ray, f64::INFINITY).unwrap(),
            bb.intersect(&ray, f64::INFINITY).unwrap(),
        );
        assert!((ha.t - hb.t).abs() < 1e-9, "{} {}", ha.t, hb.t);
        assert_eq!(ba.mapped_albedo(&ha), bb.mapped_albedo(&hb));
    }
}

/// A Y-up file: poser's (x, y, z) written as (x, z, −y).
fn y_up(x: f64, y: f64, z: f64) -> String {
    format!("{x} {z} {}", -y)
}

#[test]
fn a_y_up_file_with_up_axis_y_and_a_gltf_are_the_z_up_model() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("z.obj"), relief(|x, y, z| format!("{x} {y} {z}"))).unwrap();
    std::fs::write(d.join("y.obj"), relief(y_up)).unwrap();
    let z = load(&scene(d, "z.obj", ""));
    let y = load(&scene(d, "y.obj", "up_axis = \"y\""));
    assert_eq!(vertex_gap(&z, &y), 0.0);
    let (dm, dpx) = truth_gap(&z, &y);
    assert!(dm < 1e-12 && dpx < 1e-9, "{dm} {dpx}");
    // Unturned, the relief stands on its edge: 0.9 m tall.
    let wrong = load(&scene(d, "y.obj", ""));
    let b = object_mesh(&wrong.objects[0], d).unwrap().bounds().unwrap();
    assert!(b.1.z - b.0.z > 0.5, "{b:?}");

    // The same relief as glTF (Y up by definition), its vertices local in f32 and its node
    // translated to UTM (northing along −z in glTF's axes), read in f64.
    let ascii = relief(|x, y, z| format!("{x} {y} {z}"));
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let mut idx: Vec<u16> = Vec::new();
    for l in ascii.lines() {
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.first() {
            Some(&"v") => {
                let c: Vec<f64> = w[1..].iter().map(|s| s.parse().unwrap()).collect();
                pos.push([c[0] as f32, c[2] as f32, -c[1] as f32]);
            }
            Some(&"f") => {
                let k: Vec<u16> = w[1..]
                    .iter()
                    .map(|s| s.parse::<u16>().unwrap() - 1)
                    .collect();
                idx.extend([k[0], k[1], k[2], k[0], k[2], k[3]]);
            }
            _ => {}
        }
    }
    let mut bin: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let npos = bin.len();
    bin.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(d.join("relief.bin"), &bin).unwrap();
    let (lo, hi) = pos
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        });
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0, "translation": [500000.37, -11.63, -4200000.37]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
        "buffers": [{{"byteLength": {}, "uri": "relief.bin"}}],
        "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {npos}}},
                        {{"buffer": 0, "byteOffset": {npos}, "byteLength": {}}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3", "min": {lo:?}, "max": {hi:?}}},
          {{"bufferView": 1, "componentType": 5123, "count": {}, "type": "SCALAR"}}]}}"#,
        bin.len(),
        bin.len() - npos,
        pos.len(),
        idx.len()
    );
    std::fs::write(d.join("relief.gltf"), gltf).unwrap();
    // The offset is in the file's axes: glTF's (easting, height, −northing). Read in f32, the
    // node's northing would be rounded to 0.5 m.
    let g = load(&scene(
        d,
        "relief.gltf",
        "offset = [500000.37, -11.63, -4200000.37]",
    ));
    // The OBJ's faces are quads, fanned as the glTF's index list is: the same triangles; the
    // glTF's vertices are f32 (1e-8 m here).
    let gap = vertex_gap(&z, &g);
    eprintln!("glTF (f32 vertices, f64 node) − OBJ: {gap:.2e} m");
    assert!(gap < 1e-7, "{gap}");
}

#[test]
fn a_millimetre_model_at_scale_0_001_is_the_metre_model() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("m.obj"), relief(|x, y, z| format!("{x} {y} {z}"))).unwrap();
    std::fs::write(
        d.join("mm.obj"),
        relief(|x, y, z| format!("{} {} {}", (E + x) * 1e3, (N + y) * 1e3, (H + z) * 1e3)),
    )
    .unwrap();
    let m = load(&scene(d, "m.obj", ""));
    let mm = load(&scene(
        d,
        "mm.obj",
        "scale = 0.001\noffset = [500000000, 4200000000, -12000]",
    ));
    let gap = vertex_gap(&m, &mm);
    let (dm, dpx) = truth_gap(&m, &mm);
    assert!(gap < 1e-9 && dm < 1e-9 && dpx < 1e-6, "{gap} {dm} {dpx}");
}

#[test]
fn far_coordinates_without_an_offset_are_warned_of_with_the_offset_to_give() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("utm.obj"),
        relief(|x, y, z| format!("{:.6} {:.6} {:.6}", E + x, N + y, H + z)),
    )
    .unwrap();
    let p = scene(d, "utm.obj", "");
    let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(ok, "{text}");
    for want in [
        "warning[W0296]: the mesh's vertices are up to 4230 km from its origin",
        "utm_obj.toml:21:8",
        "help: add `offset = [500000, 4200000, -12]`",
    ] {
        assert!(text.contains(want), "`{want}` not in\n{text}");
    }
    // Given an offset, or a small model: no warning.
    let p = scene(d, "utm.obj", "offset = [500000, 4200000, -12]");
    let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(ok && !text.contains("W0296"), "{text}");
    std::fs::write(
        d.join("local.obj"),
        relief(|x, y, z| format!("{x} {y} {z}")),
    )
    .unwrap();
    let p = scene(d, "local.obj", "");
    let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(ok && !text.contains("W0296"), "{text}");
    // `poser explain` gives the extent after the offset: 1.2 m × 0.9 m, 4.9 cm of relief.
    let p = scene(d, "utm.obj", "offset = [500000, 4200000, -12]");
    let (ok, text) = poser_in(&["explain", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(ok, "{text}");
    assert!(
        text.contains("mesh `relief`: extent 1.200 × 0.900 × 0.049 m (x × y × z after offset, up axis and scale)"),
        "{text}"
    );
}

#[test]
fn a_malformed_offset_file_is_a_located_error() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("m.obj"), relief(|x, y, z| format!("{x} {y} {z}"))).unwrap();
    for (file, wants) in [
        (
            "# shift\n500000 4200000 abc\n",
            &[
                "error[E0297]",
                "m.xyz:2:16: `abc` is not a finite number",
                "help: an offset file holds three numbers",
            ][..],
        ),
        (
            "500000 4200000\n",
            &["m.xyz:1:8: 2 number(s) where an offset needs three"][..],
        ),
        ("1 2 3 4\n", &["m.xyz:1:7: a fourth number `4`"][..]),
    ] {
        std::fs::write(d.join("m.xyz"), file).unwrap();
        let p = scene(d, "m.obj", "offset_file = \"m.xyz\"");
        let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
        assert!(!ok, "{file}: accepted\n{text}");
        for w in wants {
            assert!(text.contains(w), "{file}: `{w}` not in\n{text}");
        }
    }
    let p = scene(d, "m.obj", "offset_file = \"gone.xyz\"");
    let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(
        !ok && text.contains("E0297") && text.contains("gone.xyz"),
        "{text}"
    );
    let p = scene(d, "m.obj", "offset_file = \"m.xyz\"\noffset = [1, 2, 3]");
    let (ok, text) = poser_in(&["validate", p.file_name().unwrap().to_str().unwrap()], d);
    assert!(!ok && text.contains("E0298"), "{text}");
}

#[test]
fn mitsuba_and_cycles_are_given_the_local_geometry() {
    // The relief's vertices are binary fractions: UTM − offset gives them back exactly, so the
    // files written for Mitsuba (world frame) and Cycles (object frame) are the same bytes.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let exact = |x: f64, y: f64, z: f64| {
        let r = |v: f64| (v * 1024.0).round() / 1024.0;
        (r(x), r(y), r(z))
    };
    std::fs::write(
        d.join("local.obj"),
        relief(|x, y, z| {
            let (x, y, z) = exact(x, y, z);
            format!("{x} {y} {z}")
        }),
    )
    .unwrap();
    std::fs::write(
        d.join("utm.obj"),
        relief(|x, y, z| {
            let (x, y, z) = exact(x, y, z);
            format!("{} {} {}", E + x, N + y, H + z)
        }),
    )
    .unwrap();
    let local = load(&scene(d, "local.obj", ""));
    let utm = load(&scene(d, "utm.obj", "offset = [500000, 4200000, -12]"));
    for (backend, file) in [
        ("mitsuba", "meshes/000-relief.ply"),
        ("blender", "assets/object_0.ply"),
    ] {
        let b = poser::backend::Backend::parse(backend).unwrap();
        let (oa, ob) = (
            d.join(format!("{backend}-a")),
            d.join(format!("{backend}-b")),
        );
        b.compile(&local, &oa).unwrap();
        b.compile(&utm, &ob).unwrap();
        let (fa, fb) = (
            std::fs::read(oa.join(file)).unwrap(),
            std::fs::read(ob.join(file)).unwrap(),
        );
        assert!(fa == fb, "{backend}: `{file}` differs");
    }
}
