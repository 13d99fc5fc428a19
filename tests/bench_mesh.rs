//! `poser bench mesh` (issue 36, "Scale") at a tiny size: the generated OBJ + MTL + JPEG site of
//! 20 000 triangles and a 256² texture is loaded whole, every stage is reported with its costs,
//! and the render shows the texture (its warm west and cool east where the camera sees them).
//! The CLI refuses the bench's own options on the other benches.

use crate::support::bench::poser;
use poser::bench::mesh::{Options, run, table};

#[test]
fn a_tiny_site_is_loaded_whole_and_rendered_with_its_texture() {
    let keep = tempfile::tempdir().unwrap();
    let opts = Options {
        triangles: 20_000,
        texture: 256,
        samples: 2,
        keep: Some(keep.path().to_path_buf()),
    };
    let r = run(&opts).unwrap();
    eprintln!("{}", table(&r));
    // The mesh as written, every triangle of it.
    assert_eq!((r.triangles_written, r.triangles_loaded), (20_000, 20_000));
    assert_eq!(r.vertices_written, 101 * 101);
    assert_eq!(r.vertices_loaded, 101 * 101);
    // Two checkerboards (two triangles each) beside the site's triangles, none degenerate.
    assert_eq!(r.triangles_in_bvh, 20_004);
    // The image decoded whole; its 15.6 mm texels are coarser than the GSD: level 0 is used.
    assert_eq!(
        (r.texels_loaded, r.texels_used, r.level),
        (65_536, 65_536, 0)
    );
    let names: Vec<&str> = r.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["write", "load", "bvh", "truth", "render"]);
    for s in &r.stages {
        assert!(s.wall_s.is_finite() && s.wall_s >= 0.0, "{s:?}");
        assert!(s.cpu_s.is_finite() && s.cpu_s >= 0.0, "{s:?}");
        assert!(s.peak_rss_bytes > 0 && s.rss_bytes > 0, "{s:?}");
        assert!(s.peak_rss_bytes >= s.rss_bytes, "{s:?}");
    }
    assert!((r.load_bvh_s - r.stages[1].wall_s - r.stages[2].wall_s).abs() < 1e-12);
    // The files are there, as a photogrammetry package writes them.
    for f in [
        "scene.toml",
        "site/model.obj",
        "site/model.mtl",
        "site/model.jpg",
    ] {
        assert!(keep.path().join(f).is_file(), "{f}");
    }
    assert!(keep.path().join("render/truth").is_dir());
    // Not black, and the texture is where it belongs: red over blue is far higher west of the
    // colour boundary than east of it, in the texture and in the render (which the water's
    // backscatter, the same on both sides, pulls towards 1).
    let c = &r.render;
    assert_eq!((c.width, c.height, c.samples), (640, 427, 2));
    assert!(c.mean.iter().all(|m| m.is_finite() && *m > 0.0), "{c:?}");
    assert!(c.texture_ratio > 10.0, "{c:?}");
    assert!(
        c.render_ratio > 3.0 && c.render_ratio <= c.texture_ratio * 1.2,
        "{c:?}"
    );
    // The JSON the CLI writes is this report.
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["stages"].as_array().unwrap().len(), 5);
}

#[test]
fn the_mesh_options_belong_to_the_mesh_bench() {
    let out = poser()
        .args(["bench", "projection", "--triangles", "10"])
        .output()
        .unwrap();
    // Each report has its own options (a clap subcommand each): the projection bench has no
    // `--triangles`, and clap says so, with the usage of `poser bench projection`.
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unexpected argument '--triangles'") && err.contains("poser bench projection"),
        "{err}"
    );
    // Bad sizes are errors, not panics.
    let out = poser()
        .args(["bench", "mesh", "--triangles", "1", "--texture", "64"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--triangles 1"));
}

/// `--site DIR` writes the site's three files alone, at the sizes asked for, and the same bytes
/// twice; it refuses the bench's own options.
#[test]
fn the_site_alone_is_written_with_site() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |dir: &std::path::Path| {
        let out = poser()
            .args([
                "bench",
                "mesh",
                "--triangles",
                "500",
                "--texture",
                "64",
                "--site",
            ])
            .arg(dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("500 triangles"));
    };
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    write(&a);
    write(&b);
    let mut names: Vec<String> = std::fs::read_dir(&a)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["model.jpg", "model.mtl", "model.obj"]);
    for n in &names {
        assert!(
            std::fs::read(a.join(n)).unwrap() == std::fs::read(b.join(n)).unwrap(),
            "{n}"
        );
    }
    let obj = std::fs::read_to_string(a.join("model.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 500);
    let out = poser()
        .args(["bench", "mesh", "--quick", "--site"])
        .arg(tmp.path().join("c"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(!tmp.path().join("c").exists());
}
