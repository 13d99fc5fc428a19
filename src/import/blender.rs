//! `poser import` of Blender scenes (`.blend`): the pinned `bpy` opens the file with script
//! auto-execution off and reads it (`backends/blender/read_blend.py`, embedded in the binary);
//! this module turns what it read into scene text and mesh assets.
//!
//! | Blender | poser |
//! |---|---|
//! | the cameras (scene camera first; those rigidly attached to it form a `multi` rig) | `[camera]`, `[rig]` |
//! | one pose per frame when the first camera moves, else one | `[network]` explicit poses |
//! | perspective camera: lens, sensor fit, shift, depth of field | `fx`, `principal_point`, `focal_length`, `f_number`, `focus_distance` |
//! | point, spot, area (W) and sun (W/m²) lights; the world's background | `[[lights]]` (W/sr, W/(m²·sr)), `[sun]`, an ambient light |
//! | a volume-only material on a mesh (Volume Absorption/Scatter/Coefficients, Principled Volume), or the world's volume | `[water]`; a mesh whose top is at z = 0 gives a flat sea surface |
//! | meshes with a Principled or Diffuse BSDF | `.glb` assets, albedo = base colour |
//! | glass at a camera | a note with the `[camera.port]` to declare |
//!
//! A file poser saved (`--save-blend`) carries poser's exact values as custom properties; the
//! reader uses each while it agrees with Blender's float32 value, so the round trip is exact.

use super::{
    Imported, Note, arr, euler_xyz, explicit_network, finish, meshes, safe_file_name, sun_table,
    unrefract,
};
use crate::backend::python;
use glam::{DMat3, DMat4, DVec3};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::Path;
use toml::{Table, Value};

/// The reader, run by the pinned interpreter.
pub const SCRIPT: &str = include_str!("../../backends/blender/read_blend.py");

#[derive(Deserialize)]
struct Read {
    name: String,
    blender: String,
    render: ReadRender,
    poses: Vec<[[f64; 4]; 4]>,
    cameras: Vec<ReadCamera>,
    lights: Vec<serde_json::Map<String, serde_json::Value>>,
    water: Option<ReadWater>,
    meshes: Vec<ReadMesh>,
    notes: Vec<ReadNote>,
}

#[derive(Deserialize)]
struct ReadRender {
    samples: i64,
    bounces: i64,
}

#[derive(Deserialize)]
struct ReadCamera {
    name: String,
    width: i64,
    height: i64,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    lens: String,
    distortion: Option<HashMap<String, f64>>,
    focal_length: Option<f64>,
    f_number: Option<f64>,
    focus_distance: Option<f64>,
    rig_from_camera: [[f64; 4]; 4],
}

#[derive(Deserialize)]
struct ReadWater {
    absorption: [f64; 3],
    scattering: [f64; 3],
    g: f64,
    /// Fournier–Forand: the particles' index `n`, the backscatter fraction, and the Junge
    /// slope `mu` when poser saved it.
    ff: Option<ReadFf>,
    ior: Option<[f64; 3]>,
    top: Option<f64>,
    surface: Option<String>,
}

#[derive(Deserialize)]
struct ReadFf {
    n: f64,
    backscatter: f64,
    mu: Option<f64>,
}

#[derive(Deserialize)]
struct ReadMesh {
    name: String,
    ply: String,
    albedo: [f64; 3],
}

#[derive(Deserialize)]
struct ReadNote {
    element: String,
    message: String,
    help: Option<String>,
}

/// Import `blend` (read by the pinned `bpy` in the scratch folder `work`); mesh assets are
/// named `assets/<name>.glb` in the scene.
pub fn import(blend: &Path, assets: &str, work: &Path) -> Result<Imported, String> {
    python::require_module("bpy")?;
    let req = serde_json::json!({
        "blend": std::path::absolute(blend).map_err(|e| format!("{}: {e}", blend.display()))?,
        "work": work,
    });
    let read: Read = python::run_json(work, "read_blend.py", SCRIPT, &req, "reading the .blend")?;
    convert(read, blend, assets, work)
}

/// What the reader found → scene text and assets (its PLY meshes are in `work`).
fn convert(read: Read, blend: &Path, assets: &str, work: &Path) -> Result<Imported, String> {
    let shown = blend.display().to_string();
    let at = |element: &str| Some(format!("{shown}: {element}"));
    let mut notes: Vec<Note> = read
        .notes
        .iter()
        .map(|n| {
            let note = Note::new(at(&n.element), n.message.clone());
            match &n.help {
                Some(h) => note.help(h.clone()),
                None => note,
            }
        })
        .collect();
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());

    let mut t = Table::new();
    let name = if read.name.trim().is_empty() {
        blend
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "imported".into())
    } else {
        read.name.clone()
    };
    t.insert("name".into(), Value::String(name));
    t.insert(
        "description".into(),
        Value::String(format!("imported from a Blender {} file", read.blender)),
    );

    // Cameras: [camera] is the first; a rig when there are more.
    // Camera names become file names (`<camera>_img_0001.exr`): one safe component each.
    let mut read = read;
    for c in &mut read.cameras {
        let safe = safe_file_name(&c.name).replace('.', "_");
        if safe != c.name {
            notes.push(Note::new(
                at(&format!("camera `{}`", c.name)),
                format!("renamed `{safe}`: a camera's name is part of its images' file names"),
            ));
            c.name = safe;
        }
    }
    let Some(c0) = read.cameras.first() else {
        return Err(format!(
            "{shown}: no camera that poser can import\n  help: a poser scene needs a perspective camera"
        ));
    };
    for c in &read.cameras {
        if !(1..=100_000).contains(&c.width) || !(1..=100_000).contains(&c.height) {
            return Err(format!(
                "{shown}: camera `{}`: {}×{} pixels",
                c.name, c.width, c.height
            ));
        }
        if !finite(&[c.fx, c.fy, c.cx, c.cy]) || c.fx <= 0.0 || c.fy <= 0.0 {
            return Err(format!(
                "{shown}: camera `{}`: no finite positive focal length",
                c.name
            ));
        }
    }
    let intrinsics = |c: &ReadCamera, tab: &mut Table| {
        tab.insert("width".into(), Value::Integer(c.width));
        tab.insert("height".into(), Value::Integer(c.height));
        match (c.focal_length, c.f_number) {
            (Some(fl), Some(n)) if fl > 0.0 && n > 0.0 => {
                // Depth of field: the thin lens needs a physical focal length.
                tab.insert("focal_length".into(), Value::Float(fl));
                tab.insert("pixel_pitch".into(), Value::Float(fl / c.fx));
                tab.insert("f_number".into(), Value::Float(n));
                if let Some(d) = c.focus_distance.filter(|d| *d > 0.0) {
                    tab.insert("focus_distance".into(), Value::Float(d));
                }
            }
            _ => {
                tab.insert("fx".into(), Value::Float(c.fx));
            }
        }
        if c.fy != c.fx {
            tab.insert("fy".into(), Value::Float(c.fy));
        }
        tab.insert("principal_point".into(), arr([c.cx, c.cy]));
        if c.lens != "rectilinear" {
            tab.insert("lens".into(), Value::String(c.lens.clone()));
        }
        if let Some(d) = &c.distortion {
            let mut dt = Table::new();
            for k in ["k1", "k2", "k3", "p1", "p2"] {
                if let Some(v) = d.get(k).filter(|v| **v != 0.0) {
                    dt.insert(k.into(), Value::Float(*v));
                }
            }
            if !dt.is_empty() {
                tab.insert("distortion".into(), Value::Table(dt));
            }
        }
    };
    let mut cam = Table::new();
    intrinsics(c0, &mut cam);
    if read.cameras.len() > 1 {
        let mut cams = Vec::new();
        for c in &read.cameras {
            let (rot, pos) = frame_of(&mat(&c.rig_from_camera));
            let mut ct = Table::new();
            ct.insert("name".into(), Value::String(c.name.clone()));
            ct.insert("position".into(), arr(pos.to_array()));
            ct.insert("rotation".into(), arr(euler_xyz(rot)));
            intrinsics(c, &mut ct);
            cams.push(Value::Table(ct));
        }
        let mut rt = Table::new();
        rt.insert("type".into(), Value::String("multi".into()));
        rt.insert("cameras".into(), Value::Array(cams));
        t.insert("camera".into(), Value::Table(cam));
        t.insert("rig".into(), Value::Table(rt));
    } else {
        cam.insert("name".into(), Value::String(c0.name.clone()));
        t.insert("camera".into(), Value::Table(cam));
    }

    // Water.
    let mut surface = false;
    // A Blender volume has no index: poser's seawater at 20 °C, 35 PSU, 550 nm stands in.
    let default_n = crate::optics::water::seawater_ior(20.0, 35.0, 0.0, 550.0);
    let n_water = read
        .water
        .as_ref()
        .and_then(|w| w.ior)
        .unwrap_or([default_n; 3]);
    let poses: Vec<(DMat3, DVec3)> = read.poses.iter().map(|p| frame_of(&mat(p))).collect();
    if let Some(w) = &read.water {
        if !finite(&w.absorption) || !finite(&w.scattering) || !w.g.is_finite() {
            return Err(format!("{shown}: the water's coefficients are not finite"));
        }
        let mut wt = Table::new();
        wt.insert("absorption".into(), arr(w.absorption));
        wt.insert("scattering".into(), arr(w.scattering));
        match &w.ff {
            Some(ff) => {
                // Cycles gives the backscatter fraction; poser the Junge slope that yields it.
                let mu = ff
                    .mu
                    .filter(|m| *m > 3.0 && *m <= 5.0)
                    .or_else(|| junge_slope(ff.n, ff.backscatter));
                let Some(mu) = mu else {
                    return Err(format!(
                        "{shown}: water: no Junge slope in (3, 5] gives a Fournier–Forand backscatter fraction of {} with particle index {}",
                        ff.backscatter, ff.n
                    ));
                };
                wt.insert("phase".into(), Value::String("fournier_forand".into()));
                wt.insert("particle_index".into(), Value::Float(ff.n));
                wt.insert("junge_slope".into(), Value::Float(mu));
            }
            None => {
                wt.insert("g".into(), Value::Float(w.g.clamp(-0.999, 0.999)));
            }
        }
        match w.ior {
            Some(n) => {
                wt.insert("ior".into(), arr(n));
            }
            None => {
                wt.insert("ior".into(), Value::Float(default_n));
                notes.push(Note::new(
                    at("water"),
                    format!("a Blender volume has no refractive index; seawater's at 20 °C, 35 PSU and 550 nm ({default_n:.5}) is written"),
                ).help("set `water.ior`, or `temperature` and `salinity` instead"));
            }
        }
        t.insert("water".into(), Value::Table(wt));
        surface = match w.surface.as_deref() {
            Some("waves") => {
                notes.push(
                    Note::new(at("water"), "the wavy sea surface is imported flat")
                        .help("set `site.surface = \"waves\"` with its height and wavelength"),
                );
                true
            }
            Some(s) => s == "flat",
            None => w.top.is_some_and(|z| z.abs() < 1e-4),
        };
        let mut site = Table::new();
        site.insert(
            "surface".into(),
            Value::String(if surface { "flat" } else { "none" }.into()),
        );
        t.insert("site".into(), Value::Table(site));
        if surface && poses.iter().any(|(_, c)| c.z >= 0.0) {
            notes.push(
                Note::new(
                    at("camera"),
                    "a camera is at z ≥ 0 in water: poser's water lies below z = 0",
                )
                .help("move the scene down so that the cameras are below the water's top"),
            );
        }
    }

    // Lights and the sun.
    let mut lights = Vec::new();
    let mut used: HashMap<String, usize> = HashMap::new();
    let mut unique = |n: &str| -> String {
        let c = used.entry(n.to_string()).or_insert(0);
        *c += 1;
        if *c == 1 {
            n.to_string()
        } else {
            format!("{n}_{c}")
        }
    };
    let mut sun_done = false;
    for l in &read.lights {
        let kind = l.get("type").and_then(|v| v.as_str()).unwrap_or("");
        let lname = l.get("name").and_then(|v| v.as_str()).unwrap_or("light");
        if kind == "sun" {
            let v3 = |k: &str| -> Option<[f64; 3]> {
                let a = l.get(k)?.as_array()?;
                Some([
                    a.first()?.as_f64()?,
                    a.get(1)?.as_f64()?,
                    a.get(2)?.as_f64()?,
                ])
            };
            let (Some(dir), Some(e)) = (v3("direction"), v3("irradiance")) else {
                continue;
            };
            let dir = DVec3::from_array(dir).normalize_or_zero();
            if sun_done || dir.z >= 0.0 || !finite(&e) {
                notes.push(
                    Note::new(
                        at(&format!("light `{lname}`")),
                        if sun_done {
                            "a second sun is not imported"
                        } else {
                            "a sun shining upwards is not imported"
                        },
                    )
                    .help("poser has one sun, shining down"),
                );
                continue;
            }
            sun_done = true;
            let (dir_air, e_air) = if read.water.is_some() && surface {
                // Cycles has no sea surface to refract at: its sun shines in the water.
                notes.push(Note::new(
                    at(&format!("light `{lname}`")),
                    "the sun is read as shining in the water: elevation and irradiance are those above the flat surface that refracts it so",
                ));
                unrefract(dir, e, n_water)
            } else {
                (dir, e)
            };
            t.insert("sun".into(), sun_table(dir_air, e_air));
            continue;
        }
        let mut lt = Table::new();
        for (k, v) in l {
            let value = match v {
                serde_json::Value::String(s) if k == "name" => Value::String(unique(s)),
                serde_json::Value::String(s) => Value::String(s.clone()),
                serde_json::Value::Number(n) => Value::Float(n.as_f64().unwrap_or(f64::NAN)),
                serde_json::Value::Array(a) => {
                    arr(a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)))
                }
                _ => continue,
            };
            let ok = match &value {
                Value::Float(x) => x.is_finite(),
                Value::Array(a) => a.iter().all(|x| x.as_float().is_some_and(f64::is_finite)),
                _ => true,
            };
            if !ok {
                return Err(format!("{shown}: light `{lname}`: `{k}` is not finite"));
            }
            lt.insert(k.clone(), value);
        }
        lights.push(Value::Table(lt));
    }
    if !lights.is_empty() {
        t.insert("lights".into(), Value::Array(lights));
    }

    // Meshes → .glb assets.
    let mut objects = Vec::new();
    let mut assets_out = Vec::new();
    for m in &read.meshes {
        let bytes = std::fs::read(work.join(safe_file_name(&m.ply)))
            .map_err(|e| format!("{}: {e}", m.ply))?;
        let mesh = meshes::read_ply(&bytes, &m.ply)?;
        let name = unique(&m.name);
        let file = safe_file_name(&format!("{name}.glb"));
        assets_out.push((file.clone(), meshes::glb(&mesh, &name)));
        if m.albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
            notes.push(Note::new(
                at(&format!("object `{}`", m.name)),
                format!(
                    "albedo ({:.3}, {:.3}, {:.3}) clamped to [0, 1]",
                    m.albedo[0], m.albedo[1], m.albedo[2]
                ),
            ));
        }
        let mut o = Table::new();
        o.insert("name".into(), Value::String(name));
        o.insert("shape".into(), Value::String("mesh".into()));
        o.insert("path".into(), Value::String(format!("{assets}/{file}")));
        o.insert("albedo".into(), arr(m.albedo.map(|a| a.clamp(0.0, 1.0))));
        objects.push(Value::Table(o));
    }
    if !objects.is_empty() {
        t.insert("objects".into(), Value::Array(objects));
    }

    // Network: one explicit pose per frame.
    t.insert("network".into(), explicit_network(poses));
    let mut r = Table::new();
    r.insert(
        "samples".into(),
        Value::Integer(read.render.samples.clamp(1, 1 << 20)),
    );
    r.insert(
        "bounces".into(),
        Value::Integer(read.render.bounces.clamp(1, 1024)),
    );
    t.insert("render".into(), Value::Table(r));
    finish(&t, &shown, notes, assets_out)
}

/// The Junge slope μ ∈ (3, 5] whose Fournier–Forand backscatter fraction is `b` for particle
/// index `n` (bisection; B falls as μ rises), or `None` outside the range.
fn junge_slope(n: f64, b: f64) -> Option<f64> {
    use crate::optics::phase::ff_backscatter;
    let (mut lo, mut hi) = (3.0 + 1e-9, 5.0);
    let (b_lo, b_hi) = (ff_backscatter(n, lo), ff_backscatter(n, hi));
    let (b_min, b_max) = (b_lo.min(b_hi), b_lo.max(b_hi));
    if n.is_nan() || n <= 1.0 || !(b_min..=b_max).contains(&b) {
        return None;
    }
    let rising = b_hi > b_lo;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (ff_backscatter(n, mid) < b) == rising {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

fn mat(rows: &[[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(rows).transpose()
}

/// A rigid transform's rotation (columns normalised and made orthogonal: Blender keeps
/// float32 matrices, which may carry a scale) and translation.
fn frame_of(m: &DMat4) -> (DMat3, DVec3) {
    let x = m.x_axis.truncate().normalize();
    let y0 = m.y_axis.truncate();
    let y = (y0 - x * x.dot(y0)).normalize();
    (DMat3::from_cols(x, y, x.cross(y)), m.w_axis.truncate())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reader's result as bpy writes it: two rigid cameras (one with a hostile name), two
    /// frames, a rig strobe, the sun in water under a flat sea, Fournier–Forand water.
    const READ: &str = r#"{
      "file": "x.blend", "name": "survey", "blender": "5.0.1",
      "render": {"samples": 64, "bounces": 4},
      "poses": [[[1,0,0,0],[0,-1,0,0],[0,0,-1,-2],[0,0,0,1]],
                [[1,0,0,0.5],[0,-1,0,0],[0,0,-1,-2],[0,0,0,1]]],
      "cameras": [
        {"name": "left", "width": 64, "height": 48, "fx": 60.0, "fy": 60.0, "cx": 32.0,
         "cy": 24.0, "lens": "rectilinear", "distortion": null, "focal_length": null,
         "f_number": null, "focus_distance": null,
         "rig_from_camera": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
        {"name": "../../right", "width": 64, "height": 48, "fx": 60.0, "fy": 60.0, "cx": 31.0,
         "cy": 24.0, "lens": "rectilinear", "distortion": {"k1": -0.1}, "focal_length": null,
         "f_number": null, "focus_distance": null,
         "rig_from_camera": [[1,0,0,0.3],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}],
      "lights": [
        {"name": "strobe", "type": "spot", "intensity": [2.0, 2.0, 2.0], "beam_angle": 1.5,
         "aim": [0.0, 0.0, 1.0], "mount": "rig", "position": [0.1, 0.0, 0.0]},
        {"name": "sun", "type": "sun", "direction": [0.3, 0.0, -0.9539392014169456],
         "irradiance": [500.0, 600.0, 700.0]}],
      "water": {"absorption": [0.3, 0.05, 0.02], "scattering": [0.1, 0.1, 0.1], "g": 0.0,
                "ff": {"n": 1.1, "backscatter": 0.02}, "ior": null, "top": 0.0},
      "meshes": [],
      "notes": [{"element": "text `go.py`", "message": "a script in the file was not run and is not imported", "help": null}]
    }"#;

    #[test]
    fn what_bpy_read_becomes_a_valid_scene() {
        let dir = tempfile::tempdir().unwrap();
        let read: Read = serde_json::from_str(READ).unwrap();
        let imp = convert(read, Path::new("x.blend"), "x_assets", dir.path()).unwrap();
        let path = dir.path().join("x.toml");
        std::fs::write(&path, &imp.toml).unwrap();
        let m = crate::scene::load(&path, &[])
            .map_err(|e| e.render())
            .unwrap()
            .model;
        assert_eq!(m.poses.len(), 2);
        assert_eq!(m.cameras.len(), 2);
        assert_eq!(m.cameras[1].name, "______right", "{}", imp.toml);
        assert_eq!(m.cameras[1].cx, 31.0);
        let w1 = m.world_from_camera(1, 1);
        assert!((w1.translation - DVec3::new(0.8, 0.0, -2.0)).length() < 1e-12);
        // The sun comes back as Cycles shone it in the water.
        let sun = m.sun.as_ref().unwrap();
        let want = DVec3::new(0.3, 0.0, -0.9539392014169456);
        assert!(
            (sun.direction_water - want).length() < 1e-9,
            "{:?}",
            sun.direction_water
        );
        for (c, e) in [500.0, 600.0, 700.0].iter().enumerate() {
            assert!(
                (sun.irradiance_water[c] / e - 1.0).abs() < 1e-9,
                "{:?}",
                sun.irradiance_water
            );
        }
        let w = m.water.as_ref().unwrap();
        match w.phase {
            crate::model::Phase::FournierForand { n, backscatter, .. } => {
                assert_eq!(n, 1.1);
                assert!((backscatter - 0.02).abs() < 1e-9);
            }
            _ => panic!("{:?}", w.phase),
        }
        assert!(imp.toml.contains("was not run"));
        assert!(
            imp.notes
                .iter()
                .any(|n| n.message.contains("no refractive index"))
        );
    }

    #[test]
    fn the_junge_slope_comes_back_from_the_backscatter_fraction() {
        let (n, mu) = (1.1, 3.6);
        let b = crate::optics::phase::ff_backscatter(n, mu);
        let back = junge_slope(n, b).unwrap();
        assert!((back - mu).abs() < 1e-9, "{back}");
        assert!(junge_slope(n, 0.9).is_none());
    }

    #[test]
    fn frames_drop_scale_and_keep_exact_rotations() {
        let r = DMat3::from_euler(glam::EulerRot::ZYX, 0.3, -0.2, 1.1);
        let m = DMat4::from_mat3_translation(r * 2.0, DVec3::new(1.0, 2.0, 3.0));
        let rows = m.transpose().to_cols_array_2d();
        let (back, t) = frame_of(&mat(&rows));
        assert!((back - r).to_cols_array().iter().all(|d| d.abs() < 1e-15));
        assert_eq!(t, DVec3::new(1.0, 2.0, 3.0));
    }
}
