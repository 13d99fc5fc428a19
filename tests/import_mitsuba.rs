//! `poser import` of Mitsuba 3 XML: the round trip compile → import gives back the model's
//! poses, intrinsics, water and lights on every shipped scene Mitsuba can express, a scene
//! written by hand in Mitsuba's own style imports, and hostile files are refused without
//! writing anything.

use poser::model::Model;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

mod support;

fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}

/// The shipped scenes in `sub` (`scenarios` or `scenarios/lessons`).
fn scenes(sub: &str) -> Vec<PathBuf> {
    support::shipped_scenes()
        .into_iter()
        .filter(|p| p.parent().is_some_and(|d| d.ends_with(sub)))
        .collect()
}

/// Numbers of `a` and `b` (JSON of model parts) agree within `rel` relative (1e-12 absolute).
fn close(a: &Value, b: &Value, rel: f64, path: &str) -> Result<(), String> {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() <= 1e-12 + rel * x.abs().max(y.abs()) {
                Ok(())
            } else {
                Err(format!("{path}: {x} vs {y}"))
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .try_for_each(|(i, (p, q))| close(p, q, rel, &format!("{path}[{i}]"))),
        (Value::Object(x), Value::Object(y)) => x.iter().try_for_each(|(k, v)| match y.get(k) {
            Some(w) => close(v, w, rel, &format!("{path}.{k}")),
            None => Err(format!("{path}.{k} missing")),
        }),
        _ if a == b => Ok(()),
        _ => Err(format!("{path}: {a} vs {b}")),
    }
}

fn json<T: serde::Serialize>(v: &T) -> Value {
    serde_json::to_value(v).unwrap()
}

/// Compile `scene` for Mitsuba, import (up to `max_views` views) and compare. `Ok(None)` when
/// the Mitsuba backend refuses the scene or the comparison does not apply (with the reason).
fn round_trip(scene: &Path, dir: &Path, max_views: usize) -> Result<Option<String>, String> {
    let model: Model = poser::scene::load(scene, &[])
        .map_err(|e| e.render())?
        .model;
    let mi = dir.join("mi");
    let out = poser()
        .args(["compile", "--backend", "mitsuba", "-o"])
        .arg(&mi)
        .arg(scene)
        .output()
        .unwrap();
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr);
        return Ok(Some(format!(
            "refused by the Mitsuba backend: {}",
            why.trim()
        )));
    }
    let manifest: Value =
        serde_json::from_slice(&std::fs::read(mi.join("manifest.json")).unwrap()).unwrap();
    let views = manifest["views"].as_array().unwrap();
    // Every camera's view of up to `max_views` rig poses, spread over the network.
    let n_cams = model.cameras.len();
    let n_poses = views.len() / n_cams;
    let step = n_poses.div_ceil(max_views).max(1);
    let picked: Vec<&Value> = views
        .iter()
        .filter(|v| (v["pose"].as_u64().unwrap() as usize).is_multiple_of(step))
        .collect();
    let files: Vec<PathBuf> = picked
        .iter()
        .map(|v| {
            let passes = v["passes"].as_array().unwrap();
            let pass = passes
                .iter()
                .find(|p| p["channel"].is_null() || p["channel"] == 1)
                .unwrap();
            mi.join(pass["xml"].as_str().unwrap())
        })
        .collect();
    let toml = dir.join("imported.toml");
    let out = poser()
        .arg("import")
        .args(&files)
        .arg("-o")
        .arg(&toml)
        .output()
        .unwrap();
    if !out.status.success() {
        return Err(format!(
            "import failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let back = poser::scene::load(&toml, &[])
        .map_err(|e| e.render())?
        .model;

    // Poses: world_from_camera of every imported view (the imported rig's frame may differ).
    if back.poses.len() * n_cams != picked.len() || back.cameras.len() != n_cams {
        return Err(format!(
            "{} poses × {} cameras for {} views",
            back.poses.len(),
            back.cameras.len(),
            picked.len()
        ));
    }
    let index = |m: &Model, name: &str| m.cameras.iter().position(|c| c.name == name).unwrap();
    for (k, v) in picked.iter().enumerate() {
        let p = v["pose"].as_u64().unwrap() as usize;
        let name = v["camera"].as_str().unwrap();
        let (a, b) = (
            model.world_from_camera(p, index(&model, name)),
            back.world_from_camera(k / n_cams, if n_cams == 1 { 0 } else { index(&back, name) }),
        );
        let dr = (a.rotation - b.rotation)
            .to_cols_array()
            .iter()
            .map(|x| x.abs())
            .fold(0.0, f64::max);
        let dt = (a.translation - b.translation).length();
        if dr > 1e-9 || dt > 1e-9 {
            return Err(format!(
                "pose {p}, camera {name}: rotation off by {dr:e}, centre by {dt:e} m"
            ));
        }
    }
    // Intrinsics, camera by camera.
    for c in &model.cameras {
        let d = if n_cams == 1 {
            &back.cameras[0]
        } else {
            &back.cameras[index(&back, &c.name)]
        };
        if (c.width, c.height) != (d.width, d.height) {
            return Err("image size differs".into());
        }
        for (what, x, y) in [
            ("fx", c.fx, d.fx),
            ("fy", c.fy, d.fy),
            ("cx", c.cx, d.cx),
            ("cy", c.cy, d.cy),
        ] {
            if (x - y).abs() > 1e-12 * x.abs().max(1.0) {
                return Err(format!("{}: {what}: {x} vs {y}", c.name));
            }
        }
    }
    // Water.
    match (&model.water, &back.water) {
        (None, None) => {}
        (Some(w), Some(v)) => {
            close(
                &json(&w.absorption),
                &json(&v.absorption),
                1e-9,
                "absorption",
            )?;
            close(
                &json(&w.scattering),
                &json(&v.scattering),
                1e-9,
                "scattering",
            )?;
            if let (
                poser::model::Phase::HenyeyGreenstein { g },
                poser::model::Phase::HenyeyGreenstein { g: h },
            ) = (&w.phase, &v.phase)
                && (g - h).abs() > 1e-9
            {
                return Err(format!("g: {g} vs {h}"));
            }
        }
        _ => return Err("water present in one model only".into()),
    }
    // Lights, by name, in the world at the first imported pose (rig frames may differ).
    let p0 = picked[0]["pose"].as_u64().unwrap() as usize;
    let mut a: Vec<_> = model
        .lights
        .iter()
        .map(|l| {
            (
                l.name.clone(),
                json(&l.in_world(&model.poses[p0].world_from_rig)),
            )
        })
        .collect();
    let mut b: Vec<_> = back
        .lights
        .iter()
        .map(|l| {
            (
                l.name.clone(),
                json(&l.in_world(&back.poses[0].world_from_rig)),
            )
        })
        .collect();
    a.sort_by(|x, y| x.0.cmp(&y.0));
    b.sort_by(|x, y| x.0.cmp(&y.0));
    if a.iter().map(|x| &x.0).ne(b.iter().map(|x| &x.0)) {
        return Err(format!(
            "lights {:?} vs {:?}",
            a.iter().map(|x| &x.0).collect::<Vec<_>>(),
            b.iter().map(|x| &x.0).collect::<Vec<_>>()
        ));
    }
    for ((n, x), (_, y)) in a.iter().zip(&b) {
        close(x, y, 1e-9, &format!("light {n}"))?;
    }
    // The sun as Mitsuba sees it: its direction and irradiance in the water.
    match (&model.sun, &back.sun) {
        (None, None) => {}
        (Some(s), Some(t)) => {
            close(
                &json(&s.direction_water),
                &json(&t.direction_water),
                1e-9,
                "sun direction",
            )?;
            close(
                &json(&s.irradiance_water),
                &json(&t.irradiance_water),
                1e-9,
                "sun irradiance",
            )?;
        }
        _ => return Err("sun present in one model only".into()),
    }
    Ok(None)
}

/// Round-trip every scene of `sub`; returns the names done and the reasons for the others.
fn round_trip_all(sub: &str) -> (Vec<String>, Vec<String>) {
    let mut done = Vec::new();
    let mut skipped = Vec::new();
    for scene in scenes(sub) {
        let dir = tempfile::tempdir().unwrap();
        let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
        match round_trip(&scene, dir.path(), 6) {
            Ok(None) => done.push(name),
            Ok(Some(why)) => skipped.push(format!("{name}: {why}")),
            Err(e) => panic!("{name}: {e}"),
        }
    }
    eprintln!(
        "{sub}: round trip of {} scenes: {done:?}\nnot applicable:\n  {}",
        done.len(),
        skipped.join("\n  ")
    );
    (done, skipped)
}

#[test]
fn compile_then_import_gives_back_the_scenarios() {
    let (done, skipped) = round_trip_all("scenarios");
    // caustics_shallow: the wavy surface is refused by the Mitsuba backend.
    assert!(
        done.len() >= 5,
        "only {done:?}; not applicable: {skipped:?}"
    );
}

#[test]
fn compile_then_import_gives_back_the_lessons() {
    let (done, skipped) = round_trip_all("scenarios/lessons");
    // uav_through_waves: refused (a camera in the air); subsea_metrology: a two-camera rig.
    assert!(
        done.len() >= 12,
        "only {done:?}; not applicable: {skipped:?}"
    );
}

fn import(dir: &Path, files: &[&str]) -> std::process::Output {
    poser()
        .current_dir(dir)
        .arg("import")
        .args(files)
        .args(["-o", "out/scene.toml"])
        .output()
        .unwrap()
}

/// Every file under `dir`, relative.
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

const HAND_WRITTEN: &str = r#"<?xml version="1.0"?>
<scene version="3.0.0">
    <default name="res" value="120"/>
    <integrator type="volpath"><integer name="max_depth" value="6"/></integrator>
    <medium type="homogeneous" id="sea">
        <rgb name="sigma_t" value="0.2, 0.1, 0.05"/>
        <float name="albedo" value="0.5"/>
        <float name="scale" value="2"/>
        <phase type="hg"><float name="g" value="0.85"/></phase>
    </medium>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world">
            <lookat origin="1, 2, -3" target="1, 2, -6" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="160"/>
            <integer name="height" value="$res"/>
        </film>
        <ref id="sea" name="medium"/>
    </sensor>
    <bsdf type="twosided" id="sand">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.3"/></bsdf>
    </bsdf>
    <shape type="rectangle">
        <transform name="to_world"><scale x="5" y="3"/><translate z="-7"/></transform>
        <ref id="sand"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.5" y="0" z="-6.5"/>
        <float name="radius" value="0.25"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.3, 0.4"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.1"/><rotate z="1" angle="30"/><translate x="-1" z="-6"/></transform>
    </shape>
    <emitter type="point">
        <point name="position" value="0, 0, -5"/>
        <rgb name="intensity" value="5"/>
    </emitter>
    <emitter type="spot">
        <transform name="to_world"><lookat origin="0, 1, -4" target="0, 0, -7"/></transform>
        <float name="cutoff_angle" value="30"/>
        <float name="intensity" value="7"/>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.2, 0.3"/></emitter>
    <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
</scene>
"#;

#[test]
fn a_hand_written_scene_imports_with_located_notes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.xml"), HAND_WRITTEN).unwrap();
    let out = import(dir.path(), &["scene.xml"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // What was not imported is named with file:line:column and a help line.
    assert!(
        err.contains("scene.xml:33:9: a `roughplastic` BSDF is imported as diffuse"),
        "{err}"
    );
    assert!(
        err.contains("scene.xml:48:5: a `envmap` emitter is not imported"),
        "{err}"
    );
    assert!(err.contains("help:"), "{err}");
    let text = std::fs::read_to_string(dir.path().join("out/scene.toml")).unwrap();
    assert!(text.contains("roughplastic"), "the notes head the file");
    let m = poser::scene::load(&dir.path().join("out/scene.toml"), &[])
        .unwrap()
        .model;
    let c = &m.cameras[0];
    assert_eq!((c.width, c.height), (160, 120), "`$res` substituted");
    let fy = 60.0 / 20f64.to_radians().tan();
    assert!(
        (c.fx / fy - 1.0).abs() < 1e-12,
        "fov_axis y: {} vs {fy}",
        c.fx
    );
    let p = m.world_from_camera(0, 0);
    assert!((p.translation - glam::DVec3::new(1.0, 2.0, -3.0)).length() < 1e-12);
    assert!(
        (p.rotation.z_axis - glam::DVec3::NEG_Z).length() < 1e-12,
        "looks down"
    );
    // Mitsuba's `up` is image up: poser's y (down) is its opposite.
    assert!((p.rotation.y_axis - glam::DVec3::NEG_Y).length() < 1e-12);
    let w = m.water.as_ref().unwrap();
    for (ch, st) in [0.2, 0.1, 0.05].iter().enumerate() {
        assert!((w.scattering[ch] - st).abs() < 1e-12 && (w.absorption[ch] - st).abs() < 1e-12);
    }
    assert_eq!(m.render.max_bounces, 5);
    assert_eq!(m.objects.len(), 3);
    let plane = &m.objects[0];
    assert!(
        matches!(plane.shape, poser::model::Shape::Plane { width, height } if width == 10.0 && height == 6.0)
    );
    assert!(matches!(m.objects[1].shape, poser::model::Shape::Sphere { radius } if radius == 0.25));
    assert_eq!(m.objects[1].material.albedo, [0.2, 0.3, 0.4]);
    assert!(
        matches!(m.objects[2].shape, poser::model::Shape::Box { size } if (size - glam::DVec3::splat(0.2)).length() < 1e-12)
    );
    assert_eq!(
        m.objects[2].material.albedo, [0.5; 3],
        "Mitsuba's default BSDF"
    );
    let spot = m.lights.iter().find(|l| l.name == "spot").unwrap();
    match &spot.kind {
        poser::model::LightKind::Spot {
            half_angle,
            intensity,
            direction,
            ..
        } => {
            assert!((half_angle.to_degrees() - 30.0).abs() < 1e-9);
            assert_eq!(*intensity, [7.0; 3]);
            let want = glam::DVec3::new(0.0, -1.0, -3.0).normalize();
            assert!((*direction - want).length() < 1e-12);
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(
        m.lights.len(),
        3,
        "point, spot, ambient (the envmap is not imported)"
    );
}

#[test]
fn hostile_files_are_refused_and_nothing_leaves_the_output_folder() {
    let cases: [(&str, &str, &str); 5] = [
        (
            "entity.xml",
            "<?xml version=\"1.0\"?>\n<!DOCTYPE scene [<!ENTITY x SYSTEM \"file:///etc/passwd\">]>\n<scene version=\"3.0.0\">&x;</scene>\n",
            "document type declaration",
        ),
        (
            "include.xml",
            "<scene version=\"3.0.0\"><include filename=\"../outside.xml\"/></scene>\n",
            "leaves the scene's folder",
        ),
        (
            "absolute.xml",
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor><shape type=\"ply\"><string name=\"filename\" value=\"/etc/passwd\"/></shape></scene>\n",
            "absolute path",
        ),
        (
            "huge.xml",
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor><shape type=\"ply\"><string name=\"filename\" value=\"huge.ply\"/></shape></scene>\n",
            "more than the file can hold",
        ),
        (
            "entityattr.xml",
            "<scene version=\"3.0.0\"><sensor type=\"&secret;\"/></scene>\n",
            "only XML's own entities",
        ),
    ];
    for (name, xml, why) in cases {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("in");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(root.path().join("outside.xml"), "<scene/>").unwrap();
        std::fs::write(
            dir.join("huge.ply"),
            "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n",
        )
        .unwrap();
        std::fs::write(dir.join(name), xml).unwrap();
        let before = tree(root.path());
        let out = import(&dir, &[name]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(err.contains(why), "{name}: {err}");
        assert!(
            err.contains(name),
            "{name}: the message names the file: {err}"
        );
        assert_eq!(tree(root.path()), before, "{name}: nothing may be written");
    }
    // Names from the file become asset names only after sanitising.
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("in");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        dir.join("names.xml"),
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="45"/></sensor>
  <shape type="obj" id="../../../escaped"><string name="filename" value="m.obj"/></shape>
</scene>"#,
    )
    .unwrap();
    let out = import(&dir, &["names.xml"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let files = tree(root.path());
    assert!(
        files.iter().all(|f| f.starts_with("in/")),
        "written outside the input folder: {files:?}"
    );
    assert!(
        files
            .iter()
            .any(|f| f.starts_with("in/out/scene_assets/") && f.ends_with(".glb")),
        "{files:?}"
    );
}
