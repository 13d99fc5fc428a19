//! Textured photogrammetric meshes as scene objects (issue 36), in the native renderer:
//! `tests/textures/mesh.toml` (an OBJ + MTL + PNG site) resolves to a textured mesh whose image
//! is sampled at the mipmap level the survey's GSD asks for; the texture's printed disk is found
//! where the truth projects it; and hostile mesh files are refused with the file (and line)
//! named. The same scene in Mitsuba and Cycles: `tests/textured_mesh_backends.rs`.

use crate::support;
use poser::geometry::meshfile::Wrap;
use poser::model::Shape;
use poser::texture::mapped::Look;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

use support::textured::load;

#[test]
fn the_site_is_a_textured_mesh_sampled_at_the_gsd_level() {
    let model = load(&root().join("tests/textures/mesh.toml"));
    assert!(matches!(
        model.objects[0].shape,
        Shape::Mesh { textured: true, .. }
    ));
    let p = poser::texture::mapped::prepare_object(&model, 0)
        .unwrap()
        .unwrap();
    // Two materials: the texture (1.95 mm texels; the GSD of 13.8 mm wants ≤ 6.9 mm, so level
    // 1 of 3.9 mm) and the plain strip's `Kd`.
    let reef = &p.plan.materials[0];
    assert_eq!(
        (reef.size, reef.level, reef.level_size),
        ((512, 384), 1, (256, 192))
    );
    assert!((reef.texel0 - 1.0 / 512.0).abs() < 1e-9, "{}", reef.texel0);
    assert!((p.plan.wanted - 0.00692).abs() < 1e-4, "{}", p.plan.wanted);
    match &p.looks[0] {
        Look::Image(img) => {
            assert_eq!((img.width, img.height, img.wrap), (256, 192, Wrap::Repeat));
            // The disk's middle is black (0.03), the sRGB texels decoded to linear.
            let c = img.sample(160.0 / 512.0, 128.0 / 384.0);
            assert!((c[0] - 0.03).abs() < 0.01, "{c:?}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(p.looks[1], Look::Color(c) if c == [0.6, 0.5, 0.4]));
    // `poser explain` says so.
    let out = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["explain", "tests/textures/mesh.toml"])
        .current_dir(root())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for want in [
        "textured mesh `site`: 4 triangles, 8 vertices, 2 material(s); 49152 texels at the levels used",
        "512×384 texels of 1.95 mm; level 1 used (256×192, 3.91 mm texels); finest GSD 13.85 mm",
        "`plain` (2 triangles): one colour",
        "texel wanted: 6.92 mm, half the finest GSD",
    ] {
        assert!(text.contains(want), "`{want}` not in:\n{text}");
    }
}

#[test]
fn the_texture_disk_is_where_the_truth_projects_it_natively() {
    // The disk is 2.3 px in radius at the scene's 13.8 mm GSD, drawn from level 1.
    let model = load(&root().join("tests/textures/mesh.toml"));
    let tmp = tempfile::tempdir().unwrap();
    let opts = poser::backend::RenderOptions {
        samples: Some(64),
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::Backend::parse("native")
        .and_then(|b| b.render(&model, tmp.path(), &opts))
        .unwrap();
    let d = support::textured::disk_error(&model, tmp.path());
    eprintln!(
        "native: texture disk at ({:+.4}, {:+.4}) px from the truth",
        d[0], d[1]
    );
    assert!(d[0].hypot(d[1]) < 0.05, "{d:?}");
}

/// A scene folder with the test site's scene and `site/site.obj` (`obj`), `site/site.mtl`
/// (`mtl`) and the files `extra` (name, bytes).
fn site(obj: &str, mtl: &str, extra: &[(&str, Vec<u8>)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let scene = std::fs::read_to_string(root().join("tests/textures/mesh.toml"))
        .unwrap()
        .replace("mesh/site.obj", "site/site.obj");
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    std::fs::create_dir_all(dir.path().join("site")).unwrap();
    std::fs::write(dir.path().join("site/site.obj"), obj).unwrap();
    std::fs::write(dir.path().join("site/site.mtl"), mtl).unwrap();
    for (name, bytes) in extra {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    dir
}

const QUAD: &str = "mtllib site.mtl\nv -0.5 -0.4 0\nv 0.5 -0.4 0\nv 0.5 0.4 0\nv -0.5 0.4 0\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3 4/4\n";

/// A PNG whose header claims `w` × `h` pixels, with a little compressed data of zeros.
fn bomb_png(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let crc = |b: &[u8]| {
        let mut c = 0xFFFF_FFFFu32;
        for &x in b {
            c ^= x as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    };
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = kind.to_vec();
        c.extend_from_slice(data);
        out.extend_from_slice(&c);
        out.extend_from_slice(&crc(&c).to_be_bytes());
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    std::io::Write::write_all(&mut z, &vec![0u8; 1 << 20]).unwrap();
    chunk(b"IDAT", &z.finish().unwrap());
    chunk(b"IEND", &[]);
    out
}

#[test]
fn hostile_textures_are_refused_before_anything_is_decoded() {
    let png = std::fs::read(root().join("tests/textures/mesh/reef.png")).unwrap();
    /// MTL text, files beside it, what the message must say.
    type Case<'a> = (&'a str, Vec<(&'a str, Vec<u8>)>, &'a [&'a str]);
    let cases: Vec<Case> = vec![
        (
            "newmtl a\nmap_Kd bomb.png\n",
            vec![("site/bomb.png", bomb_png(100_000, 100_000))],
            &[
                "E0289",
                "claims 100000×100000 pixels",
                "site.mtl:2",
                "decompression bomb",
            ],
        ),
        (
            "newmtl a\nmap_Kd gone.jpg\n",
            vec![],
            &["E0289", "site.mtl:2: `map_Kd`: `gone.jpg` is missing"],
        ),
        (
            "newmtl a\nmap_Kd broken.png\n",
            vec![("site/broken.png", b"this is no image".to_vec())],
            &["E0289", "broken.png", "not a PNG, JPEG or OpenEXR image"],
        ),
        (
            "newmtl a\nmap_Kd ../../outside.png\n",
            vec![],
            &[
                "E0289",
                "site.mtl:2: `map_Kd`: `../../outside.png` leaves the scene's folder",
            ],
        ),
        (
            "newmtl a\nmap_Kd /etc/passwd\n",
            vec![],
            &[
                "E0289",
                "site.mtl:2: `map_Kd`: `/etc/passwd` is an absolute path",
            ],
        ),
    ];
    for (mtl, extra, wants) in cases {
        let dir = site(QUAD, mtl, &extra);
        // A file just outside the scene's folder, for the `..` case.
        std::fs::write(dir.path().parent().unwrap().join("outside.png"), &png).ok();
        let t0 = std::time::Instant::now();
        let (ok, text) = support::textured::poser_in(&["validate", "scene.toml"], dir.path());
        assert!(!ok, "{mtl}: accepted\n{text}");
        for w in wants {
            assert!(text.contains(w), "{mtl}: `{w}` not in\n{text}");
        }
        assert!(
            t0.elapsed().as_secs_f64() < 5.0,
            "{mtl}: took {:?}",
            t0.elapsed()
        );
    }
}

#[test]
fn hostile_geometry_is_refused_with_its_line() {
    let png = std::fs::read(root().join("tests/textures/mesh/reef.png")).unwrap();
    let mtl = "newmtl a\nmap_Kd reef.png\n";
    for (obj, want) in [
        (
            QUAD.replace("f 1/1 2/2 3/3 4/4", "f 1/1 2/2 9/3"),
            "site.obj:11: vertex index 9 is out of range (4 vertices so far)",
        ),
        (
            QUAD.replace("f 1/1 2/2 3/3 4/4", "f 1/1 2/2 3/-7"),
            "site.obj:11: texture coordinate index -7 is out of range",
        ),
        (
            QUAD.replace("v 0.5 0.4 0", "v 0.5 NaN 0"),
            "site.obj:4: a vertex needs three finite numbers (got `v 0.5 NaN 0`)",
        ),
        (
            QUAD.replace("usemtl a", "usemtl b"),
            "site.obj:10: material `b` is not defined",
        ),
    ] {
        let dir = site(&obj, mtl, &[("site/reef.png", png.clone())]);
        let (ok, text) = support::textured::poser_in(
            &[
                "render",
                "scene.toml",
                "--backend",
                "native",
                "--samples",
                "1",
                "--out",
                "r",
            ],
            dir.path(),
        );
        assert!(!ok, "{want}: rendered\n{text}");
        assert!(text.contains(want), "`{want}` not in\n{text}");
        assert!(!dir.path().join("r/img_0001.exr").exists());
    }
}

#[test]
fn a_vertex_coloured_ply_is_drawn_with_its_colours() {
    // A quad of four vertex colours (sRGB bytes): red, green, blue, white.
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
               element face 1\nproperty list uchar int vertex_indices\nend_header\n\
               -0.5 -0.4 0 255 0 0\n0.5 -0.4 0 0 255 0\n0.5 0.4 0 0 0 255\n-0.5 0.4 0 255 255 255\n\
               4 0 1 2 3\n";
    let dir = site("", "", &[("site/site.ply", ply.as_bytes().to_vec())]);
    let scene = std::fs::read_to_string(dir.path().join("scene.toml"))
        .unwrap()
        .replace("site/site.obj", "site/site.ply");
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    let model = load(&dir.path().join("scene.toml"));
    assert!(matches!(
        model.objects[0].shape,
        Shape::Mesh { textured: true, .. }
    ));
    let bvh = poser::texture::Textured::of_model(&model).unwrap();
    // Straight down onto the corner of the red vertex and the centre.
    let at = |x: f64, y: f64| {
        let h = bvh
            .intersect(
                &poser::geometry::Ray {
                    origin: glam::DVec3::new(x, y, -4.0),
                    dir: glam::DVec3::new(0.0, 0.0, -1.0),
                },
                f64::INFINITY,
            )
            .unwrap();
        bvh.mapped_albedo(&h).unwrap()
    };
    let c = at(-0.4999, -0.3999);
    assert!(c[0] > 0.99 && c[1] < 0.01 && c[2] < 0.01, "{c:?}");
    // The quad is fanned into (0, 1, 2) and (0, 2, 3): its centre is halfway from red to blue.
    let c = at(0.0, 0.0);
    assert!(
        (c[0] - 0.5).abs() < 1e-3 && c[1].abs() < 1e-3 && (c[2] - 0.5).abs() < 1e-3,
        "{c:?}"
    );
}
