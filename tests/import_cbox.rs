//! A scene poser did not write: the Cornell box of Mitsuba's tutorials (`tests/import/cbox`,
//! see its README), imported with `poser import` and rendered by the native renderer, against
//! the original XML rendered by the real Mitsuba 3: image means per channel (the luminaire's
//! own pixels aside) within 2 % plus a noise allowance computed from the two images.

use std::path::Path;
use std::process::Command;

const RES: u32 = 64;
const SPP: u32 = 256;

/// Run a command; it must succeed.
fn run(cmd: &mut Command) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn exr_rgb(path: &Path) -> Vec<[f32; 3]> {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb32f();
    img.pixels().map(|p| p.0).collect()
}

#[test]
fn the_mitsuba_cornell_box_imports_and_renders_the_same_natively() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/import/cbox");
    let cbox = dir.path().join("cbox");
    std::fs::create_dir_all(cbox.join("meshes")).unwrap();
    for e in std::fs::read_dir(src.join("meshes")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, cbox.join("meshes").join(p.file_name().unwrap())).unwrap();
    }
    // The file as published, with its `res` default lowered for the test.
    let xml = std::fs::read_to_string(src.join("cbox.xml"))
        .unwrap()
        .replace(
            r#"<default name="res" value="256"/>"#,
            &format!(r#"<default name="res" value="{RES}"/>"#),
        );
    assert!(xml.contains(&format!("value=\"{RES}\"")));
    std::fs::write(cbox.join("cbox.xml"), &xml).unwrap();

    let scene = dir.path().join("cbox.toml");
    run(Command::new(env!("CARGO_BIN_EXE_poser"))
        .arg("import")
        .arg(cbox.join("cbox.xml"))
        .arg("-o")
        .arg(&scene));
    let model = poser::scene::load(&scene, &[]).unwrap().model;
    assert_eq!(
        model.objects.len(),
        7,
        "floor, ceiling, back, two walls, two boxes"
    );
    assert_eq!(model.lights.len(), 1, "the luminaire as an area light");
    assert_eq!(
        model.render.max_bounces, 7,
        "Mitsuba's max_depth 8 counts the camera vertex"
    );

    let native = dir.path().join("native");
    run(Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["render", "--quiet", "--samples", &SPP.to_string(), "-o"])
        .arg(&native)
        .arg(&scene));
    let a = exr_rgb(&native.join("img_0001.exr"));

    // The original, rendered by Mitsuba 3 (scalar_rgb).
    let script = dir.path().join("render.py");
    std::fs::write(
        &script,
        format!(
            "import sys, mitsuba as mi\nmi.set_variant('scalar_rgb')\n\
             s = mi.load_file(sys.argv[1], spp={SPP})\n\
             mi.util.write_bitmap(sys.argv[2], mi.render(s))\n"
        ),
    )
    .unwrap();
    let mi_exr = dir.path().join("mitsuba.exr");
    run(poser::backend::python::command(&script)
        .arg(cbox.join("cbox.xml"))
        .arg(&mi_exr));
    let b = exr_rgb(&mi_exr);
    assert_eq!(a.len(), b.len());
    assert_eq!(a.len(), (RES * RES) as usize);

    // Pixels that see the luminaire itself are left out: their antialiased edges differ
    // between any two renderers' pixel samples by far more than the light in the room does.
    let keep: Vec<usize> = (0..a.len())
        .filter(|&i| (0..3).all(|c| a[i][c].max(b[i][c]) < 1.0))
        .collect();
    assert!(keep.len() > a.len() * 9 / 10, "{} pixels kept", keep.len());
    let n = keep.len() as f64;
    for c in 0..3 {
        let ma = keep.iter().map(|&i| a[i][c] as f64).sum::<f64>() / n;
        let mb = keep.iter().map(|&i| b[i][c] as f64).sum::<f64>() / n;
        let rms = (keep
            .iter()
            .map(|&i| (a[i][c] as f64 - b[i][c] as f64).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let allowed = 0.02 + 3.0 * rms / mb / n.sqrt();
        let d = ma / mb - 1.0;
        eprintln!(
            "channel {c}: native {ma:.5}, mitsuba {mb:.5}: {:+.2} % (allowed {:.2} %)",
            100.0 * d,
            100.0 * allowed
        );
        assert!(mb > 0.001, "the Mitsuba image is dark");
        assert!(allowed < 0.05, "too noisy to decide: allowed {allowed}");
        assert!(d.abs() <= allowed, "channel {c}: {:+.2} %", 100.0 * d);
    }
}
