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
//! | a volume-only material on a mesh (Volume Absorption/Scatter/Coefficients, Principled Volume), or the world's volume | `[water]`; a mesh whose top is at z = 0 gives a flat sea surface; a box elsewhere moves the scene so that its top is at z = 0 |
//! | a box or sphere holding a volume (alone, or inside smooth clear glass) that no camera is inside or above | a filled object (`fill = { … }`, its index the surroundings' or the glass's IOR times it) |
//! | meshes with a Principled or Diffuse BSDF | `.glb` assets, albedo = base colour |
//! | an Image Texture (UV map, a still image) feeding the base colour | a textured `.glb` and its image as a PNG beside it |
//! | glass at a camera | a note with the `[camera.port]` to declare; without it `[camera.port] type = "none"` |
//! | a box mesh with a smooth, clear Glass or Refraction BSDF away from the cameras | a glass object (`shape = "box"`, `glass =` the catalogue glass nearest IOR × the water's index, Cycles' IOR being relative to the medium around it; within 0.02, noted); another glass mesh: a note, not imported |
//!
//! A file poser saved (`--save-blend`) carries poser's exact values as custom properties; the
//! reader uses each while it agrees with Blender's float32 value, so the round trip is exact.

use super::{
    Imported, Note, arr, euler_xyz, explicit_network, finish, meshes, safe_file_name, sun_table,
    unrefract,
};
use crate::backend::python;
use crate::scene::format::types as F;
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
    /// Glass boxes away from the cameras.
    #[serde(default)]
    glass: Vec<ReadGlass>,
    /// Glass (or poser's housing) at a camera: the housing port the scene should declare.
    #[serde(default)]
    port_glass: bool,
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

#[derive(Deserialize, Clone)]
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

#[derive(Deserialize, Clone)]
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
    /// The Image Texture that feeds the base colour, when poser can draw it (the PLY then has
    /// `u v` per vertex, v = 0 at the image's first row).
    #[serde(default)]
    texture: Option<ReadTexture>,
}

/// An image's pixels as the reader wrote them: `width` × `height` float32 RGB, Blender's first
/// row (the image's bottom) first; `encoding` "srgb" (an 8-bit sRGB image's bytes / 255) or
/// "linear".
#[derive(Deserialize)]
struct ReadTexture {
    file: String,
    name: String,
    width: u32,
    height: u32,
    encoding: String,
    wrap: String,
}

/// A smooth, clear glass box away from every camera, as the reader found it.
#[derive(Deserialize, Clone)]
struct ReadGlass {
    name: String,
    /// World matrix (row-major) of the cube [-1, 1]³ the box is (a box).
    #[serde(default)]
    cube: Option<[[f64; 4]; 4]>,
    /// World matrix (row-major) of the unit sphere the mesh lies on (a sphere).
    #[serde(default)]
    sphere: Option<[[f64; 4]; 4]>,
    /// The sphere mesh's vertex count (for the note).
    #[serde(default)]
    vertices: usize,
    /// The Glass BSDF's IOR: in Cycles the index relative to the medium around the glass
    /// (1 for a volume alone, whose faces do not refract).
    ior: f64,
    /// The volume inside it: a filled object (a tank, a jar), not glass.
    #[serde(default)]
    fill: Option<ReadWater>,
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
    let at = |element: &str| located(&shown, element);
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

    let mut t = Table::new();
    let name = if read.name.trim().is_empty() {
        blend
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "imported".into())
    } else {
        read.name.clone()
    };
    t.insert(F::Scene::name.into(), Value::String(name));
    t.insert(
        F::Scene::description.into(),
        Value::String(format!("imported from a Blender {} file", read.blender)),
    );

    // Cameras: [camera] is the first; a rig when there are more.
    let mut read = read;
    rename_cameras(&mut read.cameras, &shown, &mut notes);
    check_cameras(&read.cameras, &shown)?;
    camera_tables(&read, &mut t);

    // Water.
    // A Blender volume has no index: poser's seawater at 20 °C, 35 PSU, 550 nm stands in.
    let default_n = crate::optics::water::seawater_ior(20.0, 35.0, 0.0, 550.0);
    let n_water = read
        .water
        .as_ref()
        .and_then(|w| w.ior)
        .unwrap_or([default_n; 3]);
    let dz = box_offset(read.water.as_ref(), &shown, &mut notes);
    let poses: Vec<(DMat3, DVec3)> = read
        .poses
        .iter()
        .map(|p| {
            let (r, c) = frame_of(&mat(p));
            (r, c + DVec3::Z * dz)
        })
        .collect();
    let surface = match &read.water {
        Some(w) => water_tables(w, default_n, &poses, &shown, &mut notes, &mut t)?,
        None => false,
    };

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
        let kind = l.get(F::Light::kind).and_then(|v| v.as_str()).unwrap_or("");
        let lname = l
            .get(F::Light::name)
            .and_then(|v| v.as_str())
            .unwrap_or("light");
        if kind == "sun" {
            let in_water = read.water.is_some() && surface;
            if let Some(sun) = sun_of(l, lname, sun_done, in_water, n_water, &shown, &mut notes) {
                sun_done = true;
                t.insert(F::Scene::sun.into(), sun);
            }
            continue;
        }
        lights.push(light_table(l, lname, dz, &mut unique, &shown)?);
    }
    if !lights.is_empty() {
        t.insert(F::Scene::lights.into(), Value::Array(lights));
    }

    // Meshes → .glb assets.
    let mut objects = Vec::new();
    let mut assets_out = Vec::new();
    for m in &read.meshes {
        let at_object = format!("{shown}: object `{}`", m.name);
        let (files, more, o) = mesh_object(m, dz, &unique(&m.name), assets, work, &at_object)?;
        notes.extend(more);
        assets_out.extend(files);
        objects.push(o);
    }
    for g in &read.glass {
        let at_object = format!("{shown}: object `{}`", g.name);
        let in_water = read.water.is_some();
        match glass_object(g, dz, in_water.then_some(n_water[1]), &at_object) {
            Ok((o, note)) => {
                let mut o = o;
                o.insert(F::Object::name.into(), Value::String(unique(&g.name)));
                notes.extend(note);
                objects.push(Value::Table(o));
            }
            Err(note) => notes.push(note),
        }
    }
    if !objects.is_empty() {
        t.insert(F::Scene::objects.into(), Value::Array(objects));
    }

    // Network: one explicit pose per frame.
    t.insert(F::Scene::network.into(), explicit_network(poses));
    let mut r = Table::new();
    r.insert(
        F::Render::samples.into(),
        Value::Integer(read.render.samples.clamp(1, 1 << 20)),
    );
    r.insert(
        F::Render::bounces.into(),
        Value::Integer(read.render.bounces.clamp(1, 1024)),
    );
    t.insert(F::Scene::render.into(), Value::Table(r));
    finish(&t, &shown, notes, assets_out)
}

/// A note's location: `element` of the file shown as `shown`.
fn located(shown: &str, element: &str) -> Option<String> {
    Some(format!("{shown}: {element}"))
}

/// Every value finite.
fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Camera names become file names (`<camera>_img_0001.exr`): one safe component each; a
/// renamed camera is noted.
fn rename_cameras(cameras: &mut [ReadCamera], shown: &str, notes: &mut Vec<Note>) {
    for c in cameras {
        let safe = safe_file_name(&c.name).replace('.', "_");
        if safe != c.name {
            notes.push(Note::new(
                located(shown, &format!("camera `{}`", c.name)),
                format!("renamed `{safe}`: a camera's name is part of its images' file names"),
            ));
            c.name = safe;
        }
    }
}

/// At least one camera, each with a sane size and a finite positive focal length.
fn check_cameras(cameras: &[ReadCamera], shown: &str) -> Result<(), String> {
    if cameras.is_empty() {
        return Err(format!(
            "{shown}: no camera that poser can import\n  help: a poser scene needs a perspective camera"
        ));
    }
    for c in cameras {
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
        // poser's cameras have square pixels (one focal length in pixels): refused rather
        // than imported with one of the two, which would move every pixel off its ray.
        if (c.fy / c.fx - 1.0).abs() > 1e-9 {
            return Err(format!(
                "{shown}: camera `{}`: fx = {} px and fy = {} px differ (non-square pixels)\n  help: poser's cameras have square pixels: set the camera's `fy` equal to its `fx`",
                c.name, c.fx, c.fy
            ));
        }
    }
    Ok(())
}

/// A camera's intrinsics into `tab`: size, focal length (physical, with the thin lens, when
/// it has an f-number), principal point, lens model and distortion.
fn insert_intrinsics(c: &ReadCamera, tab: &mut Table) {
    tab.insert(F::Camera::width.into(), Value::Integer(c.width));
    tab.insert(F::Camera::height.into(), Value::Integer(c.height));
    match (c.focal_length, c.f_number) {
        (Some(fl), Some(n)) if fl > 0.0 && n > 0.0 => {
            // Depth of field: the thin lens needs a physical focal length.
            tab.insert(F::Camera::focal_length.into(), Value::Float(fl));
            tab.insert(F::Camera::pixel_pitch.into(), Value::Float(fl / c.fx));
            tab.insert(F::Camera::f_number.into(), Value::Float(n));
            if let Some(d) = c.focus_distance.filter(|d| *d > 0.0) {
                tab.insert(F::Camera::focus_distance.into(), Value::Float(d));
            }
        }
        _ => {
            tab.insert(F::Camera::fx.into(), Value::Float(c.fx));
        }
    }
    tab.insert(F::Camera::principal_point.into(), arr([c.cx, c.cy]));
    if c.lens != "rectilinear" {
        tab.insert(F::Camera::lens.into(), Value::String(c.lens.clone()));
    }
    if let Some(d) = &c.distortion {
        let mut dt = Table::new();
        for &k in F::DistortionTable::KEYS {
            if let Some(v) = d.get(k).filter(|v| **v != 0.0) {
                dt.insert(k.into(), Value::Float(*v));
            }
        }
        if !dt.is_empty() {
            tab.insert(F::Camera::distortion.into(), Value::Table(dt));
        }
    }
}

/// The `[camera]` table (the first camera) and, for several cameras, the `[rig]`.
fn camera_tables(read: &Read, t: &mut Table) {
    let c0 = &read.cameras[0];
    let mut cam = Table::new();
    insert_intrinsics(c0, &mut cam);
    if !read.port_glass {
        cam.insert(F::Camera::port.into(), no_port());
    }
    if read.cameras.len() > 1 {
        let mut cams = Vec::new();
        for c in &read.cameras {
            let (rot, pos) = frame_of(&mat(&c.rig_from_camera));
            let mut ct = Table::new();
            ct.insert(F::Camera::name.into(), Value::String(c.name.clone()));
            ct.insert(F::Camera::position.into(), arr(pos.to_array()));
            ct.insert(F::Camera::rotation.into(), arr(euler_xyz(rot)));
            insert_intrinsics(c, &mut ct);
            cams.push(Value::Table(ct));
        }
        let mut rt = Table::new();
        rt.insert(F::Rig::kind.into(), Value::String("multi".into()));
        rt.insert(F::Rig::cameras.into(), Value::Array(cams));
        t.insert(F::Scene::camera.into(), Value::Table(cam));
        t.insert(F::Scene::rig.into(), Value::Table(rt));
    } else {
        cam.insert(F::Camera::name.into(), Value::String(c0.name.clone()));
        t.insert(F::Scene::camera.into(), Value::Table(cam));
    }
}

/// A volume's coefficients and phase function as `[water]`'s keys (a filled object's `fill`
/// has the same): `absorption`, `scattering`, and `g`, or Fournier–Forand's `phase`,
/// `particle_index` and `junge_slope` (Cycles gives the backscatter fraction; poser the Junge
/// slope that yields it). `at` locates an error.
fn medium_table(w: &ReadWater, at: &str) -> Result<Table, String> {
    if !finite(&w.absorption) || !finite(&w.scattering) || !w.g.is_finite() {
        return Err(format!("{at}: the volume's coefficients are not finite"));
    }
    let mut wt = Table::new();
    wt.insert(F::Water::absorption.into(), arr(w.absorption));
    wt.insert(F::Water::scattering.into(), arr(w.scattering));
    match &w.ff {
        Some(ff) => {
            let mu = ff
                .mu
                .filter(|m| *m > 3.0 && *m <= 5.0)
                .or_else(|| junge_slope(ff.n, ff.backscatter));
            let Some(mu) = mu else {
                return Err(format!(
                    "{at}: no Junge slope in (3, 5] gives a Fournier–Forand backscatter fraction of {} with particle index {}",
                    ff.backscatter, ff.n
                ));
            };
            wt.insert(
                F::Water::phase.into(),
                Value::String("fournier_forand".into()),
            );
            wt.insert(F::Water::particle_index.into(), Value::Float(ff.n));
            wt.insert(F::Water::junge_slope.into(), Value::Float(mu));
        }
        None => {
            wt.insert(F::Water::g.into(), Value::Float(w.g.clamp(-0.999, 0.999)));
        }
    }
    Ok(wt)
}

/// The `[water]` and `[site]` tables of the volume `w` (`default_n`: the index written when it
/// has none). Returns whether the sea has a flat surface at z = 0.
fn water_tables(
    w: &ReadWater,
    default_n: f64,
    poses: &[(DMat3, DVec3)],
    shown: &str,
    notes: &mut Vec<Note>,
    t: &mut Table,
) -> Result<bool, String> {
    let mut wt = medium_table(w, &format!("{shown}: water"))?;
    match w.ior {
        Some(n) => {
            wt.insert(F::Water::ior.into(), arr(n));
        }
        None => {
            wt.insert(F::Water::ior.into(), Value::Float(default_n));
            notes.push(Note::new(
                located(shown, "water"),
                format!("a Blender volume has no refractive index; seawater's at 20 °C, 35 PSU and 550 nm ({default_n:.5}) is written"),
            ).help("set `water.ior`, or `temperature` and `salinity` instead"));
        }
    }
    t.insert(F::Scene::water.into(), Value::Table(wt));
    let surface = match w.surface.as_deref() {
        Some("waves") => {
            notes.push(
                Note::new(
                    located(shown, "water"),
                    "the wavy sea surface is imported flat",
                )
                .help("set `site.surface = \"waves\"` with its height and wavelength"),
            );
            true
        }
        Some(s) => s == "flat",
        None => w.top.is_some_and(|z| z.abs() < 1e-4),
    };
    let mut site = Table::new();
    site.insert(
        F::Site::surface.into(),
        Value::String(if surface { "flat" } else { "none" }.into()),
    );
    t.insert(F::Scene::site.into(), Value::Table(site));
    if surface && poses.iter().any(|(_, c)| c.z >= 0.0) {
        notes.push(
            Note::new(
                located(shown, "camera"),
                "a camera is at z ≥ 0 in water: poser's water lies below z = 0",
            )
            .help("move the scene down so that the cameras are below the water's top"),
        );
    }
    Ok(surface)
}

/// The `[sun]` table of sun light `l` (`lname`), above the water when it shines in water
/// under a flat surface (`in_water`, refracted with `n_water`). `None` for a sun without a
/// direction or irradiance, and, noted, for a second sun or one shining upwards.
fn sun_of(
    l: &serde_json::Map<String, serde_json::Value>,
    lname: &str,
    sun_done: bool,
    in_water: bool,
    n_water: [f64; 3],
    shown: &str,
    notes: &mut Vec<Note>,
) -> Option<Value> {
    let v3 = |k: &str| -> Option<[f64; 3]> {
        let a = l.get(k)?.as_array()?;
        Some([
            a.first()?.as_f64()?,
            a.get(1)?.as_f64()?,
            a.get(2)?.as_f64()?,
        ])
    };
    let (Some(dir), Some(e)) = (v3("direction"), v3("irradiance")) else {
        return None;
    };
    let dir = DVec3::from_array(dir).normalize_or_zero();
    if sun_done || dir.z >= 0.0 || !finite(&e) {
        notes.push(
            Note::new(
                located(shown, &format!("light `{lname}`")),
                if sun_done {
                    "a second sun is not imported"
                } else {
                    "a sun shining upwards is not imported"
                },
            )
            .help("poser has one sun, shining down"),
        );
        return None;
    }
    let (dir_air, e_air) = if in_water {
        // Cycles has no sea surface to refract at: its sun shines in the water.
        notes.push(Note::new(
            located(shown, &format!("light `{lname}`")),
            "the sun is read as shining in the water: elevation and irradiance are those above the flat surface that refracts it so",
        ));
        unrefract(dir, e, n_water)
    } else {
        (dir, e)
    };
    Some(sun_table(dir_air, e_air))
}

/// The `[[lights]]` table of light `l` (`lname`) as the reader wrote it: its name made unique,
/// a world-mounted light's position moved by `dz`; a value that is not finite is refused.
fn light_table(
    l: &serde_json::Map<String, serde_json::Value>,
    lname: &str,
    dz: f64,
    unique: &mut dyn FnMut(&str) -> String,
    shown: &str,
) -> Result<Value, String> {
    let world = l.get(F::Light::mount).and_then(|v| v.as_str()) == Some("world");
    let mut lt = Table::new();
    for (k, v) in l {
        let value = match v {
            serde_json::Value::String(s) if k == F::Light::name => Value::String(unique(s)),
            serde_json::Value::String(s) => Value::String(s.clone()),
            serde_json::Value::Number(n) => Value::Float(n.as_f64().unwrap_or(f64::NAN)),
            serde_json::Value::Array(a) => {
                let shift = if k == F::Light::position && world {
                    dz
                } else {
                    0.0
                };
                arr(a.iter().enumerate().map(|(i, x)| {
                    x.as_f64().unwrap_or(f64::NAN) + if i == 2 { shift } else { 0.0 }
                }))
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
    Ok(Value::Table(lt))
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

/// The offset along z that puts the top of a user's water box (not poser's own sea, which
/// says its surface) at z = 0, with its notes: poser's water lies below z = 0 and, lit by the
/// sun or a sky, ends there, as the box's top ends Cycles' volume.
fn box_offset(water: Option<&ReadWater>, shown: &str, notes: &mut Vec<Note>) -> f64 {
    let at = |element: &str| Some(format!("{shown}: {element}"));
    let user_box = water.filter(|w| w.surface.is_none()).and_then(|w| w.top);
    let dz = match user_box {
        Some(top) if top.is_finite() && top.abs() >= 1e-4 => -top,
        _ => 0.0,
    };
    if user_box.is_some() {
        notes.push(
            Note::new(
                at("water"),
                "the water box's sides and bottom are not imported: poser's water reaches \
                 without end sideways and downwards",
            )
            .help("make the box wide and deep enough that no light or view reaches its sides"),
        );
    }
    if dz != 0.0 {
        notes.push(
            Note::new(
                at("water"),
                format!(
                    "the scene is moved by {dz:+.6} m along z so that the water box's top is at \
                     z = 0: poser's water lies below z = 0 (and, lit by the sun, ends there as \
                     the box's top ends Cycles' volume)"
                ),
            )
            .help("every position in the scene file is the Blender one plus this offset"),
        );
    }
    dz
}

/// Mesh `m` (its PLY in `work`, moved by `dz` along z) as object `name`: its assets (a `.glb`,
/// textured with its image as a PNG beside it when the reader gave a texture and the mesh has
/// texture coordinates), the notes (located at `at`) and its `[[objects]]` entry.
#[allow(clippy::type_complexity)]
fn mesh_object(
    m: &ReadMesh,
    dz: f64,
    name: &str,
    assets: &str,
    work: &Path,
    at: &str,
) -> Result<(Vec<(String, Vec<u8>)>, Vec<Note>, Value), String> {
    let mut notes = Vec::new();
    let mut assets_out = Vec::new();
    let bytes =
        std::fs::read(work.join(safe_file_name(&m.ply))).map_err(|e| format!("{}: {e}", m.ply))?;
    let read_mesh = crate::geometry::meshfile::read_ply(&bytes, &m.ply)?;
    let (mut mesh, uv) = (read_mesh.mesh, read_mesh.uv);
    for p in &mut mesh.positions {
        p.z += dz;
    }
    let (mesh, uv) = (&mesh, &uv[..]);
    let file = safe_file_name(&format!("{name}.glb"));
    match &m.texture {
        Some(tex) if uv.len() == mesh.positions.len() => {
            let (image, png) = texture_png(tex, name, work)?;
            let wrap = match tex.wrap.as_str() {
                "clamp" => crate::geometry::meshfile::Wrap::Clamp,
                "mirror" => crate::geometry::meshfile::Wrap::Mirror,
                _ => crate::geometry::meshfile::Wrap::Repeat,
            };
            let t = meshes::MeshTexture {
                uv,
                image: &image,
                wrap,
            };
            assets_out.push((file.to_string(), meshes::glb_textured(mesh, Some(&t), name)));
            assets_out.push((image.clone(), png));
            notes.push(
                Note::new(
                    Some(at.to_string()),
                    format!(
                        "image texture `{}` is imported as the image texture of `{name}` \
                             ({assets}/{image}, sampled bilinearly at the mipmap level the \
                             cameras' sampling asks for)",
                        tex.name
                    ),
                )
                .help("docs/textures.md, \"Textured meshes\""),
            );
        }
        Some(tex) => {
            notes.push(Note::new(
                Some(at.to_string()),
                format!(
                    "image texture `{}`: the mesh has no texture coordinates; imported as \
                         its mean colour",
                    tex.name
                ),
            ));
            assets_out.push((file.to_string(), meshes::glb(mesh, name)));
        }
        None => assets_out.push((file.to_string(), meshes::glb(mesh, name))),
    }
    if m.albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
        notes.push(Note::new(
            Some(at.to_string()),
            format!(
                "albedo ({:.3}, {:.3}, {:.3}) clamped to [0, 1]",
                m.albedo[0], m.albedo[1], m.albedo[2]
            ),
        ));
    }
    let mut o = Table::new();
    o.insert(F::Object::name.into(), Value::String(name.to_string()));
    o.insert(F::Object::shape.into(), Value::String("mesh".into()));
    o.insert(
        F::Object::path.into(),
        Value::String(format!("{assets}/{file}")),
    );
    o.insert(
        F::Object::albedo.into(),
        arr(m.albedo.map(|a| a.clamp(0.0, 1.0))),
    );
    Ok((assets_out, notes, Value::Table(o)))
}

/// Glass box or sphere `g` (moved by `dz` along z) as a glass object (`shape = "box"` or
/// `"sphere"`, `glass = …`, no name yet) of the catalogue glass nearest its index, with a note
/// on the index (and, for a sphere, that its facets became the exact sphere); or the note
/// saying why it is not imported. Cycles' Glass IOR is the index relative to the medium
/// around the glass: in the water (`n_water`, the water's green index, when the scene has
/// water; the box's centre below z = 0) the glass's own index is
/// IOR × n_water, which is what poser's own files hold (n_glass / n_water).
fn glass_object(
    g: &ReadGlass,
    dz: f64,
    n_water: Option<f64>,
    at: &str,
) -> Result<(Table, Option<Note>), Note> {
    let here = || Some(at.to_string());
    let help = "poser imports boxes and spheres of a catalogue glass as glass objects \
                (docs/scenes.md, \"Glass objects\")";
    let help_fill = "poser imports a volume in a box or sphere that no camera is inside or above \
                     as a filled object (docs/scenes.md, \"Filled objects\")";
    let (what, help) = match g.fill {
        Some(_) => ("filled object", help_fill),
        None => ("glass object", help),
    };
    let Some(rows) = g.cube.or(g.sphere) else {
        return Err(Note::new(here(), format!("this {what} is not imported: no shape")).help(help));
    };
    let mut m = mat(&rows);
    m.w_axis.z += dz;
    // Blender holds the matrix in float32: columns orthogonal to 1e-6, not to f64's 1e-9.
    let (len, _, _, _) = super::decompose(&m);
    let u = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate().normalize_or_zero());
    let sheared = [(0, 1), (0, 2), (1, 2)]
        .iter()
        .any(|&(a, b)| u[a].dot(u[b]).abs() > 1e-6);
    let (frame, _) = frame_of(&m);
    let finite = m.to_cols_array().iter().all(|v| v.is_finite()) && g.ior.is_finite();
    if !finite || sheared || !(len.min_element() > 0.0) {
        return Err(Note::new(
            here(),
            format!("this {what} is not imported: its transform shears it"),
        )
        .help(help));
    }
    let ball = g.cube.is_none();
    // Float32 in Blender: one scale within 1e-5.
    if ball && len.max_element() - len.min_element() > 1e-5 * len.max_element() {
        return Err(Note::new(
            here(),
            format!(
                "this {what} is not imported: a sphere scaled unevenly ({:.4} × {:.4} × \
                 {:.4}), an ellipsoid",
                len.x, len.y, len.z
            ),
        )
        .help(help));
    }
    // Below the surface (z = 0) the medium around the glass is the water.
    let n_water = n_water.filter(|_| m.w_axis.z < 0.0);
    let n = g.ior * n_water.unwrap_or(1.0);
    let mut o = Table::new();
    let mut says = Vec::new();
    if ball {
        says.push(format!(
            "its mesh of {} vertices on a sphere is imported as the exact sphere",
            g.vertices
        ));
        o.insert(F::Object::shape.into(), Value::String("sphere".into()));
        o.insert(
            F::Object::radius.into(),
            Value::Float(len.element_sum() / 3.0),
        );
    } else {
        o.insert(F::Object::shape.into(), Value::String("box".into()));
        o.insert(F::Object::size.into(), arr((2.0 * len).to_array()));
        o.insert(F::Object::rotation.into(), arr(euler_xyz(frame)));
    }
    o.insert(
        F::Object::position.into(),
        arr(m.w_axis.truncate().to_array()),
    );
    if let Some(w) = &g.fill {
        let mut f = medium_table(w, at).map_err(|e| Note::new(None, e))?;
        let around = match n_water {
            Some(w) => format!("the water's ({w:.4})"),
            None => "the air's (1)".to_string(),
        };
        match w.ior {
            // poser's own file: the fill's index as poser wrote it.
            Some(ior) => {
                f.insert(F::FillTable::ior.into(), arr(ior));
            }
            None if g.ior == 1.0 => {
                says.push(format!(
                    "a volume alone on a {}: its faces do not refract, so its water's index is \
                     {around}",
                    if ball { "sphere" } else { "box" }
                ));
                f.insert(F::FillTable::ior.into(), Value::Float(n));
            }
            None => {
                says.push(format!(
                    "the Glass BSDF around its volume has IOR {:.4}, relative to {around}: its \
                     water's index is {n:.4}",
                    g.ior
                ));
                f.insert(F::FillTable::ior.into(), Value::Float(n));
            }
        }
        o.insert(F::Object::fill.into(), Value::Table(f));
        let note = (!says.is_empty()).then(|| Note::new(here(), says.join("; ")).help(help_fill));
        return Ok((o, note));
    }
    let relative = match n_water {
        Some(w) => format!(
            "Cycles' IOR {:.4} is the index relative to the water ({w:.4}): glass of index \
             {n:.4}",
            g.ior
        ),
        None => format!("glass of index {n:.4}"),
    };
    let Some((glass, n_g)) = super::catalogue_glass_near(n) else {
        return Err(Note::new(
            here(),
            format!(
                "this glass object is not imported: {relative}, which no catalogue glass has \
                 within {} ({})",
                super::GLASS_MATCH,
                crate::optics::glass::CATALOGUE.join(", ")
            ),
        )
        .help(help));
    };
    if (n_g - n).abs() > 1e-3 || n_water.is_some() {
        says.insert(
            0,
            format!("{relative}, imported as the catalogue glass {glass} ({n_g:.4} in green)"),
        );
    }
    o.insert(F::Object::glass.into(), Value::String(glass.to_string()));
    let note = (!says.is_empty()).then(|| Note::new(here(), says.join("; ")).help(help));
    Ok((o, note))
}

/// The PNG file (its asset name and bytes) of the texture the reader wrote for object `name`:
/// an 8-bit sRGB image keeps its bytes (an 8-bit PNG), any other image becomes a 16-bit sRGB
/// PNG of its linear values; rows turned so that the image's top is the first.
fn texture_png(tex: &ReadTexture, name: &str, work: &Path) -> Result<(String, Vec<u8>), String> {
    let side = crate::texture::mapped::MAX_TEXTURE_SIDE;
    let (w, h) = (tex.width, tex.height);
    if !(1..=side).contains(&w) || !(1..=side).contains(&h) {
        return Err(format!(
            "image texture `{}` is {w}×{h} pixels; poser's textures have 1 to {side} a side\n  \
             help: scale the image down",
            tex.name
        ));
    }
    let path = work.join(safe_file_name(&tex.file));
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if bytes.len() as u64 != 12 * w as u64 * h as u64 {
        return Err(format!(
            "image texture `{}`: the reader wrote {} bytes for {w}×{h} RGB pixels",
            tex.name,
            bytes.len()
        ));
    }
    let rgb: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let png = meshes::png_rgb(w, h, &rgb, tex.encoding == "srgb", true)
        .map_err(|e| format!("image texture `{}`: {e}", tex.name))?;
    Ok((safe_file_name(&format!("{name}-texture.png")), png))
}

/// `[camera.port] type = "none"`: no glass at the camera, no housing, said explicitly (poser's
/// default in water is a 10 mm flat port).
fn no_port() -> Value {
    let mut port = Table::new();
    port.insert(F::PortTable::kind.into(), Value::String("none".into()));
    Value::Table(port)
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

    /// A camera whose fx and fy differ is refused with its name (the format has one focal
    /// length; the importer once wrote an `fy` key that no scene reads).
    #[test]
    fn non_square_pixels_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let text = READ.replacen(r#""fy": 60.0, "cx": 32.0"#, r#""fy": 66.0, "cx": 32.0"#, 1);
        assert_ne!(text, READ);
        let read: Read = serde_json::from_str(&text).unwrap();
        let e = convert(read, Path::new("x.blend"), "x_assets", dir.path()).unwrap_err();
        assert!(
            e.contains("camera `left`") && e.contains("non-square") && e.contains("help:"),
            "{e}"
        );
    }

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

    /// A user's water box with its top at z = 3 m, a world light, a textured quad, no glass.
    #[test]
    fn a_user_water_box_moves_the_scene_and_a_texture_becomes_a_textured_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let work = dir.path();
        // Blender's first row (the image's bottom) is red, its top row blue.
        let rgb: Vec<f32> = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
            .iter()
            .flat_map(|c| c.iter().chain(c.iter()).copied())
            .collect();
        let raw: Vec<u8> = rgb.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(work.join("texture_0.f32"), raw).unwrap();
        std::fs::write(
            work.join("mesh_0.ply"),
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
             property double z\nproperty float u\nproperty float v\nelement face 1\n\
             property list uchar int vertex_indices\nend_header\n\
             0 0 1 0 1\n1 0 1 1 1\n1 1 1 1 0\n0 1 1 0 0\n4 0 1 2 3\n",
        )
        .unwrap();
        let read = READ
            .replace(
                r#""ff": {"n": 1.1, "backscatter": 0.02}, "ior": null, "top": 0.0"#,
                r#""ior": null, "top": 3.0"#,
            )
            .replace(
                r#""mount": "rig", "position": [0.1, 0.0, 0.0]"#,
                r#""mount": "world", "position": [0.1, 0.0, 2.0]"#,
            )
            .replace(
                r#""meshes": []"#,
                r#""meshes": [{"name": "quad", "ply": "mesh_0.ply", "albedo": [0.5, 0.5, 0.5],
                   "texture": {"file": "texture_0.f32", "name": "../img", "width": 2,
                   "height": 2, "encoding": "linear", "wrap": "mirror"}}]"#,
            );
        let again = read.clone();
        let read: Read = serde_json::from_str(&read).unwrap();
        let imp = convert(read, Path::new("x.blend"), "x_assets", work).unwrap();
        let names: Vec<&str> = imp.assets.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(names, ["quad.glb", "quad-texture.png"]);
        for (name, bytes) in &imp.assets {
            std::fs::write(work.join(name), bytes).unwrap();
        }
        // The scene moved down by 3 m: cameras, world lights and meshes; no housing.
        let path = work.join("x.toml");
        let text = imp.toml.replace("x_assets/", "");
        std::fs::write(&path, &text).unwrap();
        let m = crate::scene::load(&path, &[])
            .map_err(|e| e.render())
            .unwrap()
            .model;
        assert!(
            matches!(m.cameras[0].port, crate::model::Port::None),
            "{text}"
        );
        assert!((m.world_from_camera(0, 0).translation.z + 5.0).abs() < 1e-12);
        assert!(text.contains("position = [0.1, 0.0, -1.0]"), "{text}");
        assert!(text.contains("surface = \"none\""), "{text}");
        assert!(
            imp.notes
                .iter()
                .any(|n| n.message.contains("moved by -3.000000 m"))
        );
        let glb = crate::geometry::meshfile::load(&work.join("quad.glb"), &[]).unwrap();
        assert!(glb.mesh.positions.iter().all(|p| (p.z + 2.0).abs() < 1e-6));
        assert_eq!(
            glb.materials[0].wrap,
            crate::geometry::meshfile::Wrap::Mirror
        );
        // v = 0 is the image's first row: Blender's top row, blue.
        let png = image::open(work.join("quad-texture.png"))
            .unwrap()
            .to_rgb16();
        assert_eq!(png.get_pixel(0, 0).0, [0, 0, 65535]);
        assert_eq!(png.get_pixel(1, 1).0, [65535, 0, 0]);
        // A texture the mesh has no coordinates for stays its mean colour, noted.
        std::fs::write(
            work.join("mesh_0.ply"),
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n\
             property double z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        )
        .unwrap();
        let imp = convert(
            serde_json::from_str(&again).unwrap(),
            Path::new("x.blend"),
            "a",
            work,
        )
        .unwrap();
        assert_eq!(imp.assets.len(), 1);
        assert!(
            imp.notes
                .iter()
                .any(|n| n.message.contains("no texture coordinates"))
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

    /// A glass box's cube matrix becomes a glass object: its size, place and turn, and the
    /// catalogue glass its IOR means (relative to the water below z = 0, absolute above);
    /// a shear or an index no glass has is a note instead.
    #[test]
    fn a_glass_box_is_a_glass_object_of_the_glass_its_ior_means() {
        let n_pmma =
            crate::optics::glass::catalogue_ior("PMMA", crate::model::CHANNEL_WAVELENGTHS_NM[1])
                .unwrap();
        let r = DMat3::from_rotation_z(0.5);
        let cube = |at: DVec3, lin: DMat3| {
            DMat4::from_mat3_translation(lin, at)
                .transpose()
                .to_cols_array_2d()
        };
        let half = DMat3::from_diagonal(DVec3::new(0.5, 0.3, 0.2));
        let n_w = 1.34;
        let g = ReadGlass {
            name: "Block".into(),
            cube: Some(cube(DVec3::new(1.0, 2.0, -3.0), r * half)),
            sphere: None,
            vertices: 8,
            ior: n_pmma / n_w,
            fill: None,
        };
        let (o, note) = glass_object(&g, 0.0, Some(n_w), "x.blend: object `Block`").unwrap();
        assert_eq!(o["glass"].as_str(), Some("PMMA"));
        assert_eq!(o["shape"].as_str(), Some("box"));
        let f = |k: &str| -> Vec<f64> {
            o[k].as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_float().unwrap())
                .collect()
        };
        for (a, b) in f("size").iter().zip([1.0, 0.6, 0.4]) {
            assert!((a - b).abs() < 1e-12, "{:?}", f("size"));
        }
        assert_eq!(f("position"), [1.0, 2.0, -3.0]);
        assert!(
            (f("rotation")[2] - 0.5).abs() < 1e-12,
            "{:?}",
            f("rotation")
        );
        assert!(note.unwrap().message.contains("relative to the water"));
        // Moved up out of the water by the scene's offset: the IOR is the glass's own, and
        // 1.116 is no catalogue glass.
        let why = glass_object(&g, 5.0, Some(n_w), "at").unwrap_err();
        assert!(
            why.message.contains("no catalogue glass"),
            "{}",
            why.message
        );
        // In air the IOR is the index itself.
        let air = ReadGlass { ior: n_pmma, ..g };
        let (o, note) = glass_object(&air, 0.0, None, "at").unwrap();
        assert_eq!((o["glass"].as_str(), note.is_none()), (Some("PMMA"), true));
        // A sheared box is not a box.
        let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.3, 1.0, 0.0), DVec3::Z);
        let sheared = ReadGlass {
            cube: Some(cube(DVec3::new(0.0, 0.0, -3.0), shear)),
            ..air.clone()
        };
        let why = glass_object(&sheared, 0.0, None, "at").unwrap_err();
        assert!(why.message.contains("shears"), "{}", why.message);
        // A sphere: its radius and centre, the exact sphere noted; squashed, refused.
        let ball = ReadGlass {
            cube: None,
            sphere: Some(cube(DVec3::new(0.5, 0.0, -2.0), r * 0.25)),
            vertices: 482,
            ..air.clone()
        };
        let (o, note) = glass_object(&ball, 0.0, None, "at").unwrap();
        assert_eq!(o["shape"].as_str(), Some("sphere"));
        assert!((o["radius"].as_float().unwrap() - 0.25).abs() < 1e-12);
        assert!(note.unwrap().message.contains("482 vertices on a sphere"));
        let egg = ReadGlass {
            sphere: Some(cube(
                DVec3::ZERO,
                r * DMat3::from_diagonal(DVec3::new(0.2, 0.2, 0.1)),
            )),
            ..ball
        };
        let why = glass_object(&egg, 0.0, None, "at").unwrap_err();
        assert!(why.message.contains("scaled unevenly"), "{}", why.message);
    }
}
