//! `poser import`: scenes written for other renderers → one poser scene file (TOML) and its
//! assets. A second front end in front of the first: it writes scene *text*, which the scene
//! front end ([`crate::scene`]) then loads and validates like any hand-written scene.
//!
//! | module | reads | writes |
//! |---|---|---|
//! | [`mitsuba`] | Mitsuba 3 XML (quick-xml; no DOCTYPE, no entities; `include`, `default`, `ref`) | cameras, poses, objects, lights, water |
//! | [`blender`] | Blender `.blend` files, read by the pinned `bpy` with scripts off (`backends/blender/read_blend.py`) | cameras, rig, poses, objects, lights, water |
//! | [`meshes`] | Wavefront OBJ, PLY (ASCII and binary) | glTF 2.0 binary (`.glb`) assets |
//! | [`verify`] | the source rendered by Mitsuba, the imported scene rendered natively | the per-channel and per-region differences (`poser import --verify`) |
//!
//! Whatever the poser format cannot express is dropped with a [`Note`] naming the element, its
//! file, line and column, and a hint; the notes go to the terminal and, as comments, to the top
//! of the scene file. Nothing is written outside the scene file's folder and `--assets`, and
//! every file is written whole (temporary file, then rename).

pub mod blender;
pub mod meshes;
pub mod mitsuba;
pub mod verify;

use crate::scene::format::types as F;
use glam::{DMat3, DMat4, DVec3, EulerRot};
use std::path::{Path, PathBuf};
use toml::{Table, Value};

/// Something the importer dropped or changed, with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Note {
    /// `file:line:column` of the element, when it has one.
    pub location: Option<String>,
    pub message: String,
    pub help: Option<String>,
}

impl Note {
    pub fn new(location: Option<String>, message: impl Into<String>) -> Note {
        Note {
            location,
            message: message.into(),
            help: None,
        }
    }

    pub fn help(mut self, h: impl Into<String>) -> Note {
        self.help = Some(h.into());
        self
    }

    /// `file:line:col: message` and an indented `help:` line, as the terminal shows it.
    pub fn render(&self) -> String {
        let mut s = match &self.location {
            Some(l) => format!("{l}: {}", self.message),
            None => self.message.clone(),
        };
        if let Some(h) = &self.help {
            s.push_str(&format!("\n  help: {h}"));
        }
        s
    }
}

/// An import's result: the scene file's text, its assets (paths relative to the assets
/// folder) and the notes.
#[derive(Debug, Clone, Default)]
pub struct Imported {
    pub toml: String,
    pub assets: Vec<(String, Vec<u8>)>,
    pub notes: Vec<Note>,
}

/// The scene file's text: a header naming the `sources` and listing the notes as comments,
/// then the tables.
pub(crate) fn finish(
    t: &Table,
    sources: &str,
    notes: Vec<Note>,
    assets: Vec<(String, Vec<u8>)>,
) -> Result<Imported, String> {
    let body = toml::to_string(t).map_err(|e| format!("writing the scene: {e}"))?;
    let mut head = format!(
        "# Imported by `poser import` from {sources}.\n# Check it with `poser validate` and `poser explain`; what was not imported:\n"
    );
    if notes.is_empty() {
        head.push_str("#   (nothing)\n");
    }
    for n in &notes {
        for l in n.render().lines() {
            head.push_str("#   ");
            head.push_str(l);
            head.push('\n');
        }
    }
    Ok(Imported {
        toml: format!("{head}\n{body}"),
        assets,
        notes,
    })
}

/// Rotations about x, y, z (x first, as the scene format composes them) of an orthonormal
/// frame.
/// `m`'s linear part split into column lengths and an orthonormal frame (`None` when the
/// columns are not orthogonal: a shear), with a flag for a mirror.
pub(crate) fn decompose(m: &DMat4) -> (DVec3, DMat3, bool, bool) {
    let c = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let len = DVec3::new(c[0].length(), c[1].length(), c[2].length());
    let u = [0, 1, 2].map(|i| c[i] / len[i]);
    let mirror = u[0].cross(u[1]).dot(u[2]) < 0.0;
    let z = u[0].cross(u[1]);
    let sheared =
        u[0].dot(u[1]).abs() > 1e-9 || u[0].dot(u[2]).abs() > 1e-9 || u[1].dot(u[2]).abs() > 1e-9;
    (len, DMat3::from_cols(u[0], u[1], z), mirror, sheared)
}

/// The catalogue glass whose green index is nearest `n`, with that index, when it is within
/// [`GLASS_MATCH`]: what an imported glass object is made of.
pub(crate) fn catalogue_glass_near(n: f64) -> Option<(&'static str, f64)> {
    crate::optics::glass::CATALOGUE
        .iter()
        .filter_map(|g| {
            crate::optics::glass::catalogue_ior(g, crate::model::CHANNEL_WAVELENGTHS_NM[1])
                .map(|n_g| (*g, n_g))
        })
        .min_by(|a, b| (a.1 - n).abs().total_cmp(&(b.1 - n).abs()))
        .filter(|(_, n_g)| (n_g - n).abs() <= GLASS_MATCH)
}

/// How far, in index, an imported glass may be from a catalogue glass's (green) to be
/// imported as it (Mitsuba's named glasses, `bk7` and `acrylic glass`, go by their names).
pub(crate) const GLASS_MATCH: f64 = 0.02;

pub(crate) fn euler_xyz(r: DMat3) -> [f64; 3] {
    let (z, y, x) = r.to_euler(EulerRot::ZYX);
    [x, y, z].map(|a| a + 0.0)
}

/// An explicit `[network]` of the given world_from_rig poses (rotation, position).
pub(crate) fn explicit_network(poses: impl IntoIterator<Item = (DMat3, DVec3)>) -> Value {
    let ps = poses
        .into_iter()
        .map(|(rot, pos)| {
            let mut p = Table::new();
            p.insert(F::PoseTable::position.into(), arr(pos.to_array()));
            p.insert(F::PoseTable::rotation.into(), arr(euler_xyz(rot)));
            Value::Table(p)
        })
        .collect();
    let mut net = Table::new();
    net.insert(F::Network::kind.into(), Value::String("explicit".into()));
    net.insert(F::Network::poses.into(), Value::Array(ps));
    Value::Table(net)
}

/// The `[sun]` table of a sun shining along `dir_air` with irradiance `e_air` (W/m² per
/// channel) above the water.
pub(crate) fn sun_table(dir_air: DVec3, e_air: [f64; 3]) -> Value {
    let elevation = (-dir_air.z).clamp(-1.0, 1.0).asin();
    let azimuth = (-dir_air.x).atan2(-dir_air.y);
    let mut st = Table::new();
    st.insert(F::Sun::elevation.into(), Value::Float(elevation));
    st.insert(
        F::Sun::azimuth.into(),
        Value::Float(azimuth.rem_euclid(std::f64::consts::TAU)),
    );
    st.insert(F::Sun::irradiance.into(), arr(e_air));
    Value::Table(st)
}

/// Numbers as a TOML array of floats (no negative zeros).
pub(crate) fn arr(v: impl IntoIterator<Item = f64>) -> Value {
    Value::Array(v.into_iter().map(|x| Value::Float(x + 0.0)).collect())
}

/// Sun direction and irradiance in water back to air through a flat surface of index `n` per
/// channel (the inverse of what the scene front end does: the direction refracts with the
/// reference channel's index `n[1]`, each channel's irradiance with its own Fresnel factor);
/// beyond the critical angle the sun comes out grazing.
pub(crate) fn unrefract(dir_w: DVec3, e_w: [f64; 3], n: [f64; 3]) -> (DVec3, [f64; 3]) {
    let d = dir_w.normalize();
    let h = DVec3::new(d.x, d.y, 0.0);
    let s_a = (h.length() * n[1]).min(1.0);
    let c_a = (1.0 - s_a * s_a).max(0.0).sqrt();
    let dir_a = if h.length() > 0.0 {
        h.normalize() * s_a - DVec3::Z * c_a
    } else {
        -DVec3::Z
    };
    let e = [0, 1, 2].map(|c| {
        let (_, f) = crate::optics::sun::refract_into_water(dir_a, n[c]);
        if f > 0.0 { e_w[c] / f } else { e_w[c] }
    });
    (dir_a, e)
}

/// A name that is safe as one file name component: ASCII letters, digits, `_`, `-`, `.`
/// (no leading dot), at most 64 characters; anything else becomes `_`.
pub fn safe_file_name(name: &str) -> String {
    let mut s: String = name
        .chars()
        .take(64)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    while s.starts_with('.') {
        s.replace_range(0..1, "_");
    }
    if s.is_empty() { "_".into() } else { s }
}

/// Write the scene file and its assets. `assets` is the folder the assets go to (created);
/// the scene names them relative to its own folder. Refuses asset names that are not a single
/// safe file name, so that nothing is written outside `assets`.
pub fn write(imported: &Imported, scene: &Path, assets: &Path) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    for (name, bytes) in &imported.assets {
        if name != &safe_file_name(name) {
            return Err(format!("asset name `{name}` is not a plain file name"));
        }
        let path = assets.join(name);
        crate::io::write_atomic(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    crate::io::write_atomic(scene, imported.toml.as_bytes())
        .map_err(|e| format!("{}: {e}", scene.display()))?;
    written.push(scene.to_path_buf());
    Ok(written)
}

/// `to` relative to the folder `from` (both absolute or both relative to the same place),
/// with `/` separators, as a scene file names its assets.
pub fn relative_path(from: &Path, to: &Path) -> String {
    let a: Vec<_> = from.components().collect();
    let b: Vec<_> = to.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = Vec::new();
    for _ in common..a.len() {
        parts.push("..".into());
    }
    for c in &b[common..] {
        parts.push(c.as_os_str().to_string_lossy().into_owned());
    }
    if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_stay_in_their_folder() {
        assert_eq!(safe_file_name("../../etc/passwd"), "_._.._etc_passwd");
        assert_eq!(safe_file_name(".hidden"), "_hidden");
        assert_eq!(safe_file_name(""), "_");
        assert_eq!(safe_file_name("mesh_01.glb"), "mesh_01.glb");
        assert!(safe_file_name(&"x".repeat(500)).len() <= 64);
    }

    #[test]
    fn relative_paths() {
        assert_eq!(
            relative_path(Path::new("/a/b"), Path::new("/a/b/assets")),
            "assets"
        );
        assert_eq!(
            relative_path(Path::new("/a/b"), Path::new("/a/c/d")),
            "../c/d"
        );
        assert_eq!(relative_path(Path::new("out"), Path::new("out")), ".");
    }
}
