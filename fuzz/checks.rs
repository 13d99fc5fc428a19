//! What each fuzz target checks, shared by the libFuzzer targets (`fuzz/fuzz_targets/`,
//! nightly) and the stable replay of the corpus (`tests/fuzz_replay.rs`).
//!
//! | target | input | property |
//! |---|---|---|
//! | `scene` | a scene file's bytes | load + validate + resolve never panics; a failure always carries an error diagnostic with a file:line:col location |
//! | `compile` | a scene file's bytes | a scene that loads compiles to Mitsuba XML and to the Blender script without a panic, writing only inside the output folder |
//! | `project_csv` | a `poser project` points file | parsing never panics; every parsed point projects through a flat-port camera to a finite pixel or an explicit no-solution |
//! | `import` | a kind byte, then a Mitsuba 3 XML scene, an OBJ or PLY mesh a fixed scene names, or the `.glb` mesh asset of an imported scene | `poser import` never panics; what it imports is written only into its output folder, and the scene it wrote loads or fails with located errors, never a panic |
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A private working folder for this thread (scene files are read from a path, so that
/// includes and meshes resolve relative to it; the replay runs targets on parallel threads).
fn workdir() -> PathBuf {
    thread_local! {
        static DIR: tempfile::TempDir = tempfile::tempdir().expect("temporary folder");
    }
    DIR.with(|d| d.path().to_path_buf())
}

fn scene_file(data: &[u8]) -> PathBuf {
    let p = workdir().join("scene.toml");
    std::fs::write(&p, data).expect("write the scene");
    p
}

/// Load, validate and resolve arbitrary bytes as a scene.
pub fn scene(data: &[u8]) {
    scene_at(&scene_file(data));
}

/// [`scene`] on a scene file where it lies (the replay runs the committed corpus in place, so
/// that its includes resolve).
pub fn scene_at(p: &Path) {
    match poser::scene::load(p, &[]) {
        Ok(_) => {}
        Err(f) => {
            assert!(f.errors().next().is_some(), "a failure without an error");
            for d in f.errors() {
                assert!(!d.rendered.is_empty(), "{} has no text", d.code);
            }
        }
    }
}

/// Every file under `dir`, recursively.
fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                files_under(&p, out);
            } else {
                out.push(p);
            }
        }
    }
}

/// Compile a scene that loads to both file backends; nothing may land outside the output
/// folder (the working folder holds only the scene file and the output).
pub fn compile(data: &[u8]) {
    compile_at(&scene_file(data));
}

/// [`compile`] on a scene file where it lies.
pub fn compile_at(p: &Path) {
    let Ok(loaded) = poser::scene::load(p, &[]) else {
        return;
    };
    for backend in [
        poser::backend::Backend::Mitsuba,
        poser::backend::Backend::Blender,
    ] {
        let out = workdir().join("out");
        let _ = std::fs::remove_dir_all(&out);
        let _ = backend.compile(&loaded.model, &out);
        let mut all = Vec::new();
        files_under(&workdir(), &mut all);
        for f in all {
            assert!(
                f.as_path() == p || f.starts_with(&out),
                "{} wrote {} outside its output folder",
                backend.name(),
                f.display()
            );
        }
        let _ = std::fs::remove_dir_all(&out);
    }
}

/// Parse a points file and project what it holds through a tilted flat port.
pub fn project_csv(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(points) = poser::points::parse_points(&text, "points.csv") else {
        return;
    };
    static PROJECTOR: std::sync::OnceLock<poser::optics::project::Projector> =
        std::sync::OnceLock::new();
    let pr = PROJECTOR.get_or_init(|| {
        let camera = poser::optics::types::Camera {
            name: "c".into(),
            width: 1200,
            height: 800,
            pixel_pitch: 4e-6,
            focal_length: 4e-3,
            fx: 1000.0,
            fy: 1000.0,
            cx: 600.0,
            cy: 400.0,
            lens: poser::optics::types::LensModel::Rectilinear,
            distortion: Default::default(),
            focus_distance: None,
            f_number: None,
            port: poser::optics::types::Port::Flat {
                normal: glam::DVec3::new(0.05, -0.02, 1.0).normalize(),
                distance: 0.03,
                thickness: 0.015,
                glass: poser::optics::types::Glass {
                    name: "custom".into(),
                    ior: [1.51, 1.52, 1.53],
                },
                outer_layers: vec![],
            },
            rig_from_camera: poser::optics::types::Pose::IDENTITY,
        };
        poser::optics::project::Projector::for_camera(&camera, 1, 1.34).expect("projector")
    });
    let ps: Vec<glam::DVec3> = points.iter().map(|p| p.1).collect();
    let mut many = vec![Err(poser::optics::NoSolution::NoConvergence); ps.len()];
    pr.project_camera_many_unbounded(&ps, &mut many);
    for (p, m) in ps.iter().zip(&many) {
        let one = pr.project_camera_unbounded(*p);
        if let Ok(px) = one {
            assert!(px[0].is_finite() && px[1].is_finite(), "{p:?} → {px:?}");
        }
        if let Ok(px) = m {
            assert!(
                px[0].is_finite() && px[1].is_finite(),
                "batch {p:?} → {px:?}"
            );
        }
    }
}

/// The fixed Mitsuba scene of the mesh kinds of [`import`]: one camera and one mesh file.
fn import_scene(kind: &str, file: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <shape type="{kind}"><string name="filename" value="{file}"/></shape>
</scene>
"#
    )
}

/// A one-rectangle OBJ (the mesh whose `.glb` the glTF kind replaces).
const QUAD_OBJ: &[u8] = b"v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n";

/// `poser import` on fuzzed input. The first byte picks what the rest is (modulo 4):
///
/// | kind | the rest of the input |
/// |---|---|
/// | 0 | a Mitsuba 3 XML scene file |
/// | 1 | an OBJ mesh, named by a fixed scene (`<shape type="obj">`) |
/// | 2 | a PLY mesh (ASCII or binary), named the same way |
/// | 3 | a glTF binary (`.glb`) standing in for the mesh asset the importer wrote for a one-rectangle OBJ |
///
/// The import must not panic. What it imports is written (scene file and assets) only below
/// its output folder, and the scene file it wrote is read by the scene front end, which must
/// load it or fail with error diagnostics, never panic.
pub fn import(data: &[u8]) {
    let Some((&kind, body)) = data.split_first() else {
        return;
    };
    let dir = workdir().join("import");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("import folder");
    let xml = dir.join("scene.xml");
    let write = |p: &Path, b: &[u8]| std::fs::write(p, b).expect("write an input");
    match kind % 4 {
        0 => write(&xml, body),
        1 => {
            write(&dir.join("mesh.obj"), body);
            write(&xml, import_scene("obj", "mesh.obj").as_bytes());
        }
        2 => {
            write(&dir.join("mesh.ply"), body);
            write(&xml, import_scene("ply", "mesh.ply").as_bytes());
        }
        _ => {
            write(&dir.join("mesh.obj"), QUAD_OBJ);
            write(&xml, import_scene("obj", "mesh.obj").as_bytes());
        }
    }
    let Ok(imported) = poser::import::mitsuba::import(std::slice::from_ref(&xml), "assets") else {
        assert!(kind % 4 != 3, "the one-rectangle scene did not import");
        return;
    };
    let out = dir.join("out");
    let scene = out.join("scene.toml");
    let written = poser::import::write(&imported, &scene, &out.join("assets"))
        .expect("an import's files are written");
    let mut all = Vec::new();
    files_under(&dir, &mut all);
    for f in &all {
        assert!(
            f.starts_with(&out) || f.parent() == Some(dir.as_path()),
            "import wrote {} outside its output folder",
            f.display()
        );
    }
    if kind % 4 == 3 {
        let glbs: Vec<&PathBuf> = written
            .iter()
            .filter(|p| p.extension().is_some_and(|e| e == "glb"))
            .collect();
        assert!(!glbs.is_empty(), "the one-rectangle scene wrote no mesh");
        for g in glbs {
            write(g, body);
        }
    }
    scene_at(&scene);
}
