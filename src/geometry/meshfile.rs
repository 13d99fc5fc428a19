//! Mesh files with their colours: Wavefront OBJ with its MTL materials, PLY with per-vertex
//! colours, and glTF 2.0 with its base-colour textures. What a `shape = "mesh"` object reads
//! (and, geometry only, what `poser import` reads). Images are named here, not decoded: that is
//! [`crate::texture::mapped`]'s work.
//!
//! | format | geometry | colour |
//! |---|---|---|
//! | OBJ | `v`, `vt`, `f` (polygons fan-triangulated; `v`, `v/vt`, `v//vn`, `v/vt/vn`; negative indices count back from the last vertex) | `mtllib`, `usemtl`; MTL `newmtl`, `Kd`, `map_Kd` with `-clamp`, `-o`, `-s` (other options skipped) |
//! | PLY | `ascii`, `binary_little_endian`, `binary_big_endian`; vertex `x y z` and texture coordinates (`u v`, `s t`, `texture_u texture_v` or `texture_s texture_t`, taken as they are); face `vertex_indices`/`vertex_index` lists | vertex `red green blue` (or `r g b`): 8/16-bit values are sRGB, floats linear |
//! | glTF | every triangle primitive of the default scene, node transforms applied, +Y up turned into +Z up: `(x, y, z)_gltf → (x, −z, y)` | `baseColorFactor`, `baseColorTexture` (its `texCoord` set, sampler wrap, `KHR_texture_transform`), embedded (`.glb`, data URI) or external images |
//!
//! Texture coordinates follow poser's convention: v = 0 at the image's first stored row (glTF's
//! own; OBJ's v runs from the bottom row, so OBJ gives v = 1 − vt). OBJ and PLY coordinates are
//! returned as written; a mesh object's `offset` and `up_axis` are applied after reading
//! ([`super::mesh::georeferenced`]). Node transforms of a glTF are read from its JSON in f64
//! (the glTF crate's are f32, too coarse for a UTM translation).
//!
//! Every error names the file, and the line for OBJ and MTL. A file an OBJ, MTL or glTF names
//! (an MTL, an image, a buffer) must be a relative path that stays inside the scene's folder or
//! the mesh's own ([`side_file`]): a mesh from elsewhere cannot make poser read `/etc/passwd`.

use super::mesh::TriMesh;
use glam::{DMat4, DVec3};
use std::path::{Path, PathBuf};

/// Most vertices or faces accepted in one mesh file.
pub const MAX_ELEMENTS: usize = 50_000_000;

/// How texture coordinates outside [0, 1] wrap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    /// The image tiles (glTF's default and OBJ's without `-clamp on`).
    #[default]
    Repeat,
    /// Edge texels repeat outward.
    Clamp,
    /// The image tiles, every other copy mirrored.
    Mirror,
}

/// Where an image comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum ImageSource {
    /// A file (checked by [`side_file`]).
    File(PathBuf),
    /// Bytes embedded in the mesh file (a `.glb` buffer view or a data URI).
    Bytes(std::sync::Arc<Vec<u8>>),
}

/// An image a material names.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageRef {
    pub source: ImageSource,
    /// Who names it, for messages: `model.mtl:4`, `site.glb: image 0`.
    pub named_at: String,
}

impl ImageRef {
    /// `file` (named at `model.mtl:4`), for messages.
    pub fn shown(&self) -> String {
        match &self.source {
            ImageSource::File(p) => format!("`{}` (named at {})", p.display(), self.named_at),
            ImageSource::Bytes(_) => format!("the image embedded at {}", self.named_at),
        }
    }
}

/// One material of a mesh file.
#[derive(Debug, Clone, PartialEq)]
pub struct FileMaterial {
    pub name: String,
    /// Linear colour factor (MTL `Kd`, glTF `baseColorFactor`); `None`: the file gives none and
    /// the object's `albedo` is used.
    pub color: Option<[f64; 3]>,
    /// Base-colour image (MTL `map_Kd`, glTF `baseColorTexture`), multiplied by `color`.
    pub image: Option<ImageRef>,
    pub wrap: Wrap,
    /// The albedo is the mesh's per-vertex colours (PLY).
    pub vertex_colors: bool,
}

impl FileMaterial {
    fn plain(name: &str) -> FileMaterial {
        FileMaterial {
            name: name.to_string(),
            color: None,
            image: None,
            wrap: Wrap::Repeat,
            vertex_colors: false,
        }
    }
}

/// A mesh file read: geometry in the object frame (before scale and pose), texture coordinates
/// and colours per vertex, a material per triangle.
#[derive(Debug, Clone, Default)]
pub struct MeshFile {
    pub mesh: TriMesh,
    /// Per vertex, v = 0 at the image's first row; empty when the file has none.
    pub uv: Vec<[f32; 2]>,
    /// Per vertex, linear; empty when the file has none.
    pub colors: Vec<[f32; 3]>,
    /// Index into `materials`, per triangle.
    pub material: Vec<u32>,
    pub materials: Vec<FileMaterial>,
}

impl MeshFile {
    /// Whether any material takes its colour from an image or from vertex colours (what makes a
    /// mesh "textured" by default).
    pub fn has_texture(&self) -> bool {
        self.materials
            .iter()
            .any(|m| m.image.is_some() || m.vertex_colors)
    }
}

/// The mesh formats by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Gltf,
    Obj,
    Ply,
}

impl Format {
    /// The format of a file name, by its extension (case-insensitive).
    pub fn of(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_string_lossy().to_lowercase();
        match ext.as_str() {
            "glb" | "gltf" => Some(Format::Gltf),
            "obj" => Some(Format::Obj),
            "ply" => Some(Format::Ply),
            _ => None,
        }
    }
}

/// Read a mesh file (any [`Format`]) with its colours; `roots` are the folders its side files
/// (MTL, images, buffers) may be in, besides the mesh's own ([`side_file`]). The file is read
/// the front end's one way ([`crate::io::read::read_capped`], at most
/// [`MAX_MESH_BYTES`](crate::io::read::MAX_MESH_BYTES); the files it names at most
/// [`MAX_ASSET_BYTES`](crate::io::read::MAX_ASSET_BYTES)).
pub fn load(path: &Path, roots: &[PathBuf]) -> Result<MeshFile, String> {
    load_with(path, roots, true)
}

/// The triangles of a mesh file, without its colours: no MTL file or image is looked at (the
/// same triangles, vertices and order as [`load`]).
pub fn load_geometry(path: &Path, roots: &[PathBuf]) -> Result<TriMesh, String> {
    Ok(load_with(path, roots, false)?.mesh)
}

/// The bounds `(min, max)` of a mesh file's vertices as [`load_geometry`] reads them (glTF
/// turned to +Z up); `None` without vertices. An OBJ's `v` lines are scanned alone (its faces
/// are not parsed): what the scene's front end can afford on every load.
pub fn vertex_bounds(path: &Path) -> Result<Option<(DVec3, DVec3)>, String> {
    if Format::of(path) != Some(Format::Obj) {
        return Ok(load_geometry(path, &[])?.bounds());
    }
    let bytes = read_mesh(path)?;
    let text = text_of(&bytes, &path.display().to_string())?;
    use rayon::prelude::*;
    let merge = |a: Option<(DVec3, DVec3)>, b: Option<(DVec3, DVec3)>| match (a, b) {
        (Some((l0, h0)), Some((l1, h1))) => Some((l0.min(l1), h0.max(h1))),
        (a, b) => a.or(b),
    };
    // Pieces scanned in parallel; min and max are exact, so the result is the serial one.
    Ok(line_chunks(text)
        .par_iter()
        .map(|&(_, chunk)| {
            let mut out: Option<(DVec3, DVec3)> = None;
            for line in chunk.lines() {
                let line = line.trim_start();
                let Some(rest) = line.strip_prefix('v') else {
                    continue;
                };
                if !rest.starts_with(char::is_whitespace) {
                    continue;
                }
                let (c, n) = numbers::<3>(rest);
                if n == 3 && c.iter().all(|v| v.is_finite()) {
                    let p = DVec3::new(c[0], c[1], c[2]);
                    out = Some(out.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
                }
            }
            out
        })
        .reduce(|| None, merge))
}

/// Size of the pieces an OBJ's text is cut into for the scans run in parallel (fixed, so that
/// the pieces do not depend on the number of threads).
const CHUNK_BYTES: usize = 4 << 20;

/// `text` cut at line ends into pieces of about [`CHUNK_BYTES`], each with the number
/// (1-based, as `str::lines` counts) of its first line.
fn line_chunks(text: &str) -> Vec<(usize, &str)> {
    use rayon::prelude::*;
    let mut pieces = Vec::new();
    let mut start = 0;
    while start < text.len() {
        let mut end = (start + CHUNK_BYTES).min(text.len());
        if end < text.len() {
            end = match text.as_bytes()[end..].iter().position(|&c| c == b'\n') {
                Some(k) => end + k + 1,
                None => text.len(),
            };
        }
        pieces.push(&text[start..end]);
        start = end;
    }
    let newlines: Vec<usize> = pieces
        .par_iter()
        .map(|p| p.bytes().filter(|&b| b == b'\n').count())
        .collect();
    let mut line = 1;
    pieces
        .into_iter()
        .zip(newlines)
        .map(|(p, n)| {
            let first = line;
            line += n;
            (first, p)
        })
        .collect()
}

fn load_with(path: &Path, roots: &[PathBuf], colours: bool) -> Result<MeshFile, String> {
    let shown = path.display().to_string();
    let format = Format::of(path)
        .ok_or_else(|| format!("`{shown}`: not a mesh file (.glb, .gltf, .obj or .ply)"))?;
    let bytes = read_mesh(path)?;
    match format {
        Format::Gltf => read_gltf(&bytes, path, roots, colours),
        Format::Obj => {
            let text = text_of(&bytes, &shown)?;
            let obj = parse_obj(text, &shown)?;
            if colours {
                obj_materials(obj, path, roots)
            } else {
                Ok(MeshFile {
                    mesh: obj.mesh,
                    ..MeshFile::default()
                })
            }
        }
        Format::Ply => read_ply(&bytes, &shown),
    }
}

/// A file a scene reads, capped.
pub(crate) fn read(path: &Path) -> Result<Vec<u8>, String> {
    use crate::io::read::{MAX_ASSET_BYTES, read_capped};
    read_capped(path, MAX_ASSET_BYTES)
        .map_err(|r| format!("cannot read `{}`: {}", path.display(), r.reason()))
}

/// A mesh file a `mesh` object names, capped at
/// [`MAX_MESH_BYTES`](crate::io::read::MAX_MESH_BYTES).
pub(crate) fn read_mesh(path: &Path) -> Result<Vec<u8>, String> {
    use crate::io::read::{MAX_MESH_BYTES, read_capped};
    read_capped(path, MAX_MESH_BYTES)
        .map_err(|r| format!("cannot read `{}`: {}", path.display(), r.reason()))
}

fn text_of<'a>(bytes: &'a [u8], shown: &str) -> Result<&'a str, String> {
    // The common case in one pass each (UTF-8, then a memchr for NUL); the error's position
    // from `not_text`.
    if let Ok(text) = std::str::from_utf8(bytes)
        && !bytes.contains(&0)
    {
        return Ok(text);
    }
    if let Some((at, b)) = crate::io::read::not_text(bytes) {
        let line = 1 + bytes[..at].iter().filter(|&&c| c == b'\n').count();
        return Err(format!(
            "{shown}:{line}: not a text file (byte 0x{b:02x} at offset {at})"
        ));
    }
    Ok(std::str::from_utf8(bytes).unwrap_or(""))
}

/// The file `rel` named by the mesh (or MTL) file `by`: a relative path (a `\` is read as `/`,
/// as Windows exporters write them), resolved against `by`'s folder, that must exist and stay
/// inside that folder or one of `roots` once links and `..` are resolved. Returns the resolved
/// path, or why not.
pub fn side_file(by: &Path, rel: &str, roots: &[PathBuf]) -> Result<PathBuf, String> {
    let rel = rel.replace('\\', "/");
    let p = Path::new(&rel);
    let drive =
        rel.len() >= 2 && rel.as_bytes()[1] == b':' && rel.as_bytes()[0].is_ascii_alphabetic();
    if rel.is_empty() {
        return Err("an empty path".into());
    }
    if p.is_absolute() || p.has_root() || drive || rel.contains("://") {
        return Err(format!(
            "`{rel}` is an absolute path: a mesh may only name files beside it, by relative paths"
        ));
    }
    let dir = by.parent().unwrap_or(Path::new("."));
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let joined = dir.join(p);
    let canon = joined
        .canonicalize()
        .map_err(|e| format!("`{rel}` is missing ({})", crate::io::read::io_reason(&e)))?;
    let inside = std::iter::once(dir.to_path_buf())
        .chain(roots.iter().cloned())
        .filter_map(|r| r.canonicalize().ok())
        .any(|r| canon.starts_with(&r));
    if !inside {
        return Err(format!(
            "`{rel}` leaves the scene's folder: a mesh may only name files inside it"
        ));
    }
    let meta = std::fs::metadata(&canon).map_err(|e| {
        format!(
            "`{rel}` cannot be read ({})",
            crate::io::read::io_reason(&e)
        )
    })?;
    if !meta.is_file() {
        return Err(format!("`{rel}` is not a regular file"));
    }
    Ok(canon)
}

// ------------------------------------------------------------------------------------------
// OBJ and MTL
// ------------------------------------------------------------------------------------------

/// An OBJ file parsed, before its materials are looked up.
#[derive(Debug, Clone, Default)]
pub struct Obj {
    pub mesh: TriMesh,
    pub uv: Vec<[f32; 2]>,
    /// Index into `names`, per triangle.
    pub material: Vec<u32>,
    /// Material names in order of first `usemtl`, with the line of that first use; "" (line 0)
    /// for faces before any `usemtl`.
    pub names: Vec<(String, usize)>,
    /// `mtllib` files with their lines.
    pub mtllibs: Vec<(String, usize)>,
}

/// Parse OBJ text (`file` names it in messages). Faces with texture coordinates get one vertex
/// per distinct (position, texture coordinate) pair; without any, the positions are kept as
/// they are.
pub fn parse_obj(text: &str, file: &str) -> Result<Obj, String> {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut vts: Vec<[f32; 2]> = Vec::new();
    // Corners (position, texture coordinate or u32::MAX) of every triangle.
    let mut corners: Vec<[(u32, u32); 3]> = Vec::new();
    let mut tri_mat: Vec<u32> = Vec::new();
    let mut names: Vec<(String, usize)> = Vec::new();
    let mut current: Option<u32> = None;
    let mut mtllibs = Vec::new();
    let mut any_vt = false;
    let mut idx: Vec<(u32, u32)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let line = line.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        match key {
            "v" => {
                let (c, n) = numbers::<3>(rest);
                if n < 3 || c.iter().any(|x| !x.is_finite()) {
                    return Err(format!(
                        "{file}:{ln}: a vertex needs three finite numbers (got `{}`)",
                        clip(line)
                    ));
                }
                if positions.len() >= MAX_ELEMENTS {
                    return Err(format!("{file}:{ln}: more than {MAX_ELEMENTS} vertices"));
                }
                positions.push(DVec3::new(c[0], c[1], c[2]));
            }
            "vt" => {
                let (c, n) = numbers::<2>(rest);
                let c = &c[..n];
                if c.is_empty() || c.iter().any(|x| !x.is_finite()) {
                    return Err(format!(
                        "{file}:{ln}: a texture coordinate needs finite numbers (got `{}`)",
                        clip(line)
                    ));
                }
                if vts.len() >= MAX_ELEMENTS {
                    return Err(format!(
                        "{file}:{ln}: more than {MAX_ELEMENTS} texture coordinates"
                    ));
                }
                vts.push([c[0] as f32, c.get(1).copied().unwrap_or(0.0) as f32]);
            }
            "f" => {
                let (nv, nt) = (positions.len() as i64, vts.len() as i64);
                let index = |s: &str, n: i64, what: &str, many: &str| -> Result<u32, String> {
                    let k: i64 = s
                        .parse()
                        .map_err(|_| format!("{file}:{ln}: `{s}` is not a {what} index"))?;
                    let k = if k < 0 { n + k } else { k - 1 };
                    if k < 0 || k >= n {
                        return Err(format!(
                            "{file}:{ln}: {what} index {s} is out of range ({n} {many} so far)"
                        ));
                    }
                    Ok(k as u32)
                };
                idx.clear();
                for corner in rest.split_whitespace() {
                    // `v`, `v/vt`, `v//vn`, `v/vt/vn`: the first two fields.
                    let (vs, ts) = match corner.bytes().position(|b| b == b'/') {
                        Some(p) => {
                            let after = &corner[p + 1..];
                            let end = after.bytes().position(|b| b == b'/');
                            (&corner[..p], Some(&after[..end.unwrap_or(after.len())]))
                        }
                        None => (corner, None),
                    };
                    let v = index(vs, nv, "vertex", "vertices")?;
                    let t = match ts {
                        Some(s) if !s.is_empty() => {
                            any_vt = true;
                            index(s, nt, "texture coordinate", "texture coordinates")?
                        }
                        _ => u32::MAX,
                    };
                    idx.push((v, t));
                }
                if idx.len() < 3 {
                    return Err(format!("{file}:{ln}: a face needs three vertices"));
                }
                let m = *current.get_or_insert_with(|| {
                    names.push((String::new(), 0));
                    names.len() as u32 - 1
                });
                for k in 1..idx.len() - 1 {
                    corners.push([idx[0], idx[k], idx[k + 1]]);
                    tri_mat.push(m);
                }
                if corners.len() > MAX_ELEMENTS {
                    return Err(format!("{file}:{ln}: more than {MAX_ELEMENTS} triangles"));
                }
            }
            "usemtl" => {
                let name = rest.to_string();
                let k = match names.iter().position(|(n, _)| *n == name) {
                    Some(k) => k,
                    None => {
                        names.push((name, ln));
                        names.len() - 1
                    }
                };
                current = Some(k as u32);
            }
            "mtllib" if !rest.is_empty() => mtllibs.push((rest.to_string(), ln)),
            _ => {}
        }
    }
    if corners.is_empty() {
        return Err(format!("{file}: no faces"));
    }
    let mut mesh = TriMesh::default();
    let mut uv = Vec::new();
    if any_vt {
        // Sized for every position once, hashed cheaply (only looked up, never iterated).
        let mut remap: std::collections::HashMap<(u32, u32), u32, PairHash> =
            std::collections::HashMap::with_capacity_and_hasher(
                positions.len(),
                PairHash::default(),
            );
        for c in &corners {
            let tri = c.map(|(v, t)| {
                *remap.entry((v, t)).or_insert_with(|| {
                    mesh.positions.push(positions[v as usize]);
                    let q = vts.get(t as usize).copied().unwrap_or([0.0, 0.0]);
                    uv.push([q[0], 1.0 - q[1]]);
                    mesh.positions.len() as u32 - 1
                })
            });
            mesh.triangles.push(tri);
        }
    } else {
        mesh.positions = positions;
        mesh.triangles = corners.iter().map(|c| c.map(|(v, _)| v)).collect();
    }
    Ok(Obj {
        mesh,
        uv,
        material: tri_mat,
        names,
        mtllibs,
    })
}

/// Up to `N` whitespace-separated numbers of `rest` (a word that is not a number reads as NaN),
/// and how many there were.
fn numbers<const N: usize>(rest: &str) -> ([f64; N], usize) {
    let mut c = [f64::NAN; N];
    let mut n = 0;
    for w in rest.split_whitespace().take(N) {
        c[n] = w.parse().unwrap_or(f64::NAN);
        n += 1;
    }
    (c, n)
}

/// A multiply-rotate hash of the OBJ loader's (position, texture coordinate) pairs: SipHash's
/// resistance to chosen keys buys nothing for indices bounded by the file's own counts.
type PairHash = std::hash::BuildHasherDefault<PairHasher>;

#[derive(Default)]
struct PairHasher(u64);

impl std::hash::Hasher for PairHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

/// One `newmtl` of an MTL file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MtlEntry {
    pub name: String,
    pub kd: Option<[f64; 3]>,
    /// `map_Kd` file name as written, and its line.
    pub map_kd: Option<(String, usize)>,
    pub clamp: bool,
    /// `-o` and `-s` of `map_Kd`: vt' = vt · s + o.
    pub offset: [f64; 2],
    pub scale: [f64; 2],
}

/// Parse MTL text: every `newmtl` with its `Kd` and `map_Kd` (options `-clamp on|off`, `-o`,
/// `-s` read; `-blendu`, `-blendv`, `-bm`, `-boost`, `-cc`, `-imfchan`, `-mm`, `-t`, `-texres`
/// skipped with their values).
pub fn parse_mtl(text: &str, file: &str) -> Result<Vec<MtlEntry>, String> {
    let mut out: Vec<MtlEntry> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let line = line.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        let need = |out: &mut Vec<MtlEntry>| -> Result<(), String> {
            if out.is_empty() {
                Err(format!("{file}:{ln}: `{key}` before any `newmtl`"))
            } else {
                Ok(())
            }
        };
        match key {
            "newmtl" => out.push(MtlEntry {
                name: rest.to_string(),
                scale: [1.0, 1.0],
                ..Default::default()
            }),
            "Kd" => {
                need(&mut out)?;
                let c: Vec<f64> = rest
                    .split_whitespace()
                    .take(3)
                    .map(|s| s.parse().unwrap_or(f64::NAN))
                    .collect();
                if c.is_empty() || c.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Err(format!(
                        "{file}:{ln}: `Kd` needs one or three numbers ≥ 0 (got `{}`)",
                        clip(line)
                    ));
                }
                let c = [c[0], *c.get(1).unwrap_or(&c[0]), *c.get(2).unwrap_or(&c[0])];
                if let Some(m) = out.last_mut() {
                    m.kd = Some(c);
                }
            }
            "map_Kd" => {
                need(&mut out)?;
                let words: Vec<&str> = rest.split_whitespace().collect();
                let mut k = 0;
                let (mut clamp, mut offset, mut scale) = (false, [0.0, 0.0], [1.0, 1.0]);
                let numbers = |k: &mut usize, most: usize| -> Vec<f64> {
                    let mut v = Vec::new();
                    while v.len() < most
                        && let Some(x) = words.get(*k).and_then(|w| w.parse::<f64>().ok())
                    {
                        v.push(x);
                        *k += 1;
                    }
                    v
                };
                while k < words.len() && words[k].starts_with('-') && words.len() - k > 1 {
                    let opt = words[k];
                    k += 1;
                    match opt {
                        "-clamp" => {
                            clamp = words[k] == "on";
                            k += 1;
                        }
                        "-o" | "-s" => {
                            let v = numbers(&mut k, 3);
                            if v.is_empty() || v.iter().any(|x| !x.is_finite()) {
                                return Err(format!("{file}:{ln}: `{opt}` needs numbers"));
                            }
                            let pair = [
                                v[0],
                                *v.get(1).unwrap_or(&if opt == "-s" { 1.0 } else { 0.0 }),
                            ];
                            if opt == "-o" {
                                offset = pair;
                            } else {
                                scale = pair;
                            }
                        }
                        "-t" => {
                            numbers(&mut k, 3);
                        }
                        "-mm" => k += 2,
                        "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-imfchan"
                        | "-texres" | "-type" => k += 1,
                        _ => {
                            return Err(format!("{file}:{ln}: unknown `map_Kd` option `{opt}`"));
                        }
                    }
                }
                let name = words.get(k..).map(|w| w.join(" ")).unwrap_or_default();
                if name.is_empty() {
                    return Err(format!("{file}:{ln}: `map_Kd` names no file"));
                }
                if let Some(m) = out.last_mut() {
                    m.map_kd = Some((name, ln));
                    m.clamp = clamp;
                    m.offset = offset;
                    m.scale = scale;
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// The MTL files an OBJ names, parsed (each checked by [`side_file`]), as (file, entries).
pub fn obj_mtls(
    obj: &Obj,
    path: &Path,
    roots: &[PathBuf],
) -> Result<Vec<(PathBuf, Vec<MtlEntry>)>, String> {
    let shown = path.display().to_string();
    let mut out = Vec::new();
    for (lib, ln) in &obj.mtllibs {
        let p = side_file(path, lib, roots).map_err(|e| format!("{shown}:{ln}: `mtllib`: {e}"))?;
        let bytes = read(&p).map_err(|e| format!("{shown}:{ln}: {e}"))?;
        let mshown = p.display().to_string();
        let text = text_of(&bytes, &mshown)?;
        out.push((p.clone(), parse_mtl(text, &mshown)?));
    }
    Ok(out)
}

/// The images an OBJ's materials name, found from the `mtllib` lines of its first
/// [`EARLY_BYTES`] (where exporters write them), each with its wrap: what a loader may start
/// decoding while the faces are parsed. Only a hint: a library named later is missed, and an
/// error is an empty list (the full load reports it).
pub fn obj_images_early(path: &Path, roots: &[PathBuf]) -> Vec<(PathBuf, Wrap)> {
    use std::io::Read;
    let mut head = Vec::new();
    let read =
        std::fs::File::open(path).and_then(|f| f.take(EARLY_BYTES as u64).read_to_end(&mut head));
    if read.is_err() {
        return Vec::new();
    }
    // Whole lines only.
    let end = head.iter().rposition(|&b| b == b'\n').map_or(0, |k| k + 1);
    let Ok(text) = std::str::from_utf8(&head[..end]) else {
        return Vec::new();
    };
    let mut obj = Obj::default();
    for (i, line) in text.lines().enumerate() {
        if let Some(lib) = mtllib_of(line.trim_start()) {
            obj.mtllibs.push((lib.to_string(), i + 1));
        }
    }
    let Ok(mtls) = obj_mtls(&obj, path, roots) else {
        return Vec::new();
    };
    let mut out: Vec<(PathBuf, Wrap)> = Vec::new();
    for (mtl, entries) in &mtls {
        for e in entries {
            if let Some((file, _)) = &e.map_kd
                && let Ok(p) = side_file(mtl, file, roots)
            {
                let wrap = if e.clamp { Wrap::Clamp } else { Wrap::Repeat };
                if !out.contains(&(p.clone(), wrap)) {
                    out.push((p, wrap));
                }
            }
        }
    }
    out
}

/// The library an OBJ line (its leading space trimmed) names with `mtllib`, if it is one.
fn mtllib_of(line: &str) -> Option<&str> {
    line.strip_prefix("mtllib")
        .filter(|rest| rest.starts_with(char::is_whitespace))
        .map(str::trim)
        .filter(|lib| !lib.is_empty())
}

/// How much of an OBJ [`obj_images_early`] reads.
const EARLY_BYTES: usize = 64 << 10;

/// Turn a parsed OBJ into a [`MeshFile`]: look up every `usemtl` in its MTL files (a name not
/// defined there is an error at its line), apply `map_Kd`'s `-o`/`-s` to the texture
/// coordinates of the triangles that use it.
fn obj_materials(obj: Obj, path: &Path, roots: &[PathBuf]) -> Result<MeshFile, String> {
    let shown = path.display().to_string();
    let mtls = obj_mtls(&obj, path, roots)?;
    let mut materials = Vec::new();
    let mut transforms = Vec::new();
    for (name, ln) in &obj.names {
        if name.is_empty() {
            materials.push(FileMaterial::plain(""));
            transforms.push(None);
            continue;
        }
        let found = mtls
            .iter()
            .find_map(|(f, es)| es.iter().find(|e| e.name == *name).map(|e| (f, e)));
        let Some((mtl, e)) = found else {
            return Err(format!(
                "{shown}:{ln}: material `{name}` is not defined{}",
                if obj.mtllibs.is_empty() {
                    " (the file names no `mtllib`)".to_string()
                } else {
                    format!(
                        " in {}",
                        mtls.iter()
                            .map(|(f, _)| format!("`{}`", f.display()))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                }
            ));
        };
        let mshown = mtl.display().to_string();
        let image = match &e.map_kd {
            Some((file, mln)) => {
                let p = side_file(mtl, file, roots)
                    .map_err(|err| format!("{mshown}:{mln}: `map_Kd`: {err}"))?;
                Some(ImageRef {
                    source: ImageSource::File(p),
                    named_at: format!("{mshown}:{mln}"),
                })
            }
            None => None,
        };
        transforms.push(
            (e.map_kd.is_some() && (e.offset != [0.0, 0.0] || e.scale != [1.0, 1.0]))
                .then_some((e.offset, e.scale)),
        );
        materials.push(FileMaterial {
            name: name.clone(),
            color: e.kd,
            image,
            wrap: if e.clamp { Wrap::Clamp } else { Wrap::Repeat },
            vertex_colors: false,
        });
    }
    let Obj {
        mesh,
        mut uv,
        material,
        ..
    } = obj;
    if !uv.is_empty() && transforms.iter().any(Option::is_some) {
        // A vertex belongs to one material's triangles unless the file shares (v, vt) pairs
        // across materials; then the first triangle's material decides.
        let mut done = vec![false; uv.len()];
        for (t, &m) in mesh.triangles.iter().zip(&material) {
            if let Some((o, s)) = transforms[m as usize] {
                for &i in t {
                    let i = i as usize;
                    if !done[i] {
                        done[i] = true;
                        let u = uv[i][0] as f64 * s[0] + o[0];
                        let v = (1.0 - uv[i][1] as f64) * s[1] + o[1];
                        uv[i] = [u as f32, (1.0 - v) as f32];
                    }
                }
            }
        }
    }
    Ok(MeshFile {
        mesh,
        uv,
        colors: Vec::new(),
        material,
        materials,
    })
}

/// A line quoted in a message, cut at 60 characters.
fn clip(line: &str) -> String {
    let mut s: String = line.chars().take(60).collect();
    if line.chars().count() > 60 {
        s.push('…');
    }
    s
}

// ------------------------------------------------------------------------------------------
// PLY
// ------------------------------------------------------------------------------------------

#[derive(Clone, Copy, PartialEq)]
enum Enc {
    Ascii,
    Le,
    Be,
}

fn ty_size(t: &str) -> Option<usize> {
    Some(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return None,
    })
}

/// Full scale of an integer colour type (sRGB), or `None` for floats (linear).
fn color_scale(t: &str) -> Option<f64> {
    match t {
        "uchar" | "uint8" | "char" | "int8" => Some(255.0),
        "ushort" | "uint16" | "short" | "int16" => Some(65535.0),
        "uint" | "uint32" | "int" | "int32" => Some(u32::MAX as f64),
        _ => None,
    }
}

enum Prop {
    Scalar(String, String),
    List(String, String, String),
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
    enc: Enc,
    file: &'a str,
}

impl Cursor<'_> {
    fn word(&mut self) -> Result<&str, String> {
        while self.at < self.b.len() && self.b[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
        let start = self.at;
        while self.at < self.b.len() && !self.b[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
        if start == self.at {
            return Err(format!("{}: the PLY data ends early", self.file));
        }
        std::str::from_utf8(&self.b[start..self.at])
            .map_err(|_| format!("{}: the PLY data is not ASCII", self.file))
    }

    fn num(&mut self, ty: &str) -> Result<f64, String> {
        if self.enc == Enc::Ascii {
            let file = self.file;
            let w = self.word()?;
            return w
                .parse()
                .map_err(|_| format!("{file}: `{w}` is not a number"));
        }
        let n = ty_size(ty).ok_or_else(|| format!("{}: unknown PLY type `{ty}`", self.file))?;
        let s = self
            .b
            .get(self.at..self.at + n)
            .ok_or_else(|| format!("{}: the PLY data ends early", self.file))?;
        self.at += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(s);
        if self.enc == Enc::Be {
            a[..n].reverse();
        }
        Ok(match ty {
            "char" | "int8" => a[0] as i8 as f64,
            "uchar" | "uint8" => a[0] as f64,
            "short" | "int16" => i16::from_le_bytes([a[0], a[1]]) as f64,
            "ushort" | "uint16" => u16::from_le_bytes([a[0], a[1]]) as f64,
            "int" | "int32" => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            "uint" | "uint32" => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            "float" | "float32" => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            _ => f64::from_le_bytes(a),
        })
    }
}

/// The header of a PLY file: its encoding, its elements with their properties, and where the
/// body starts.
fn ply_header(bytes: &[u8], file: &str) -> Result<(Enc, Vec<Element>, usize), String> {
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| format!("{file}: not a PLY file (no `end_header`)"))?;
    let header = std::str::from_utf8(&bytes[..end])
        .map_err(|_| format!("{file}: the PLY header is not text"))?;
    let mut body = end + 10;
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    let mut lines = header.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err(format!("{file}: not a PLY file"));
    }
    let mut enc = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", f, _] => {
                enc = Some(match *f {
                    "ascii" => Enc::Ascii,
                    "binary_little_endian" => Enc::Le,
                    "binary_big_endian" => Enc::Be,
                    _ => return Err(format!("{file}: unknown PLY format `{f}`")),
                })
            }
            ["element", name, count] => {
                let count: usize = count
                    .parse()
                    .map_err(|_| format!("{file}: bad element count `{count}`"))?;
                // Every element takes at least one byte: a count beyond the file is a lie.
                if count > MAX_ELEMENTS || count > bytes.len() {
                    return Err(format!(
                        "{file}: element `{name}` claims {count} entries, more than the file can hold"
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", ct, it, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| format!("{file}: a property before any element"))?;
                e.props
                    .push(Prop::List(ct.to_string(), it.to_string(), name.to_string()));
            }
            ["property", ty, name] => {
                if ty_size(ty).is_none() {
                    return Err(format!("{file}: unknown PLY type `{ty}`"));
                }
                let e = elements
                    .last_mut()
                    .ok_or_else(|| format!("{file}: a property before any element"))?;
                e.props.push(Prop::Scalar(ty.to_string(), name.to_string()));
            }
            _ => {}
        }
    }
    let enc = enc.ok_or_else(|| format!("{file}: the PLY header has no format line"))?;
    Ok((enc, elements, body))
}

/// The colour channel a vertex property holds (0, 1, 2 for red, green, blue).
fn channel(name: &str) -> Option<usize> {
    match name {
        "red" | "r" | "diffuse_red" => Some(0),
        "green" | "g" | "diffuse_green" => Some(1),
        "blue" | "b" | "diffuse_blue" => Some(2),
        _ => None,
    }
}

/// The texture axis a vertex property holds (0: u, 1: v), under the names Mitsuba's PLY reader
/// takes (taken as they are: v = 0 at the image's first row, as Mitsuba's bitmap reads them).
fn uv_axis(name: &str) -> Option<usize> {
    match name {
        "u" | "s" | "texture_u" | "texture_s" => Some(0),
        "v" | "t" | "texture_v" | "texture_t" => Some(1),
        _ => None,
    }
}

/// Whether a `vertex` element has a scalar property for each of the `n` slots `slot` maps
/// property names to.
fn vertex_has(elements: &[Element], n: usize, slot: fn(&str) -> Option<usize>) -> bool {
    elements.iter().any(|e| {
        e.name == "vertex"
            && (0..n).all(|c| {
                e.props
                    .iter()
                    .any(|p| matches!(p, Prop::Scalar(_, name) if slot(name) == Some(c)))
            })
    })
}

/// Read a PLY file: its triangles (faces fan-triangulated) and, when the vertices have `red`,
/// `green`, `blue` (or `r`, `g`, `b`), their colours (integers as sRGB, floats as linear);
/// then the mesh has one material of vertex colours.
pub fn read_ply(bytes: &[u8], file: &str) -> Result<MeshFile, String> {
    let (enc, elements, body) = ply_header(bytes, file)?;
    let has_colors = vertex_has(&elements, 3, channel);
    let mut c = Cursor {
        b: bytes,
        at: body,
        enc,
        file,
    };
    let has_uv = vertex_has(&elements, 2, uv_axis);
    let mut m = TriMesh::default();
    let mut colors: Vec<[f32; 3]> = Vec::new();
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    for e in &elements {
        for k in 0..e.count {
            let mut xyz = [f64::NAN; 3];
            let mut rgb = [0.0f32; 3];
            let mut uv = [0.0f32; 2];
            for p in &e.props {
                match p {
                    Prop::Scalar(ty, name) => {
                        let v = c.num(ty)?;
                        if e.name == "vertex" {
                            match name.as_str() {
                                "x" => xyz[0] = v,
                                "y" => xyz[1] = v,
                                "z" => xyz[2] = v,
                                n if has_uv && uv_axis(n).is_some() => {
                                    if !v.is_finite() {
                                        return Err(format!(
                                            "{file}: vertex {k} has a texture coordinate that is not a number"
                                        ));
                                    }
                                    uv[uv_axis(n).unwrap_or(0)] = v as f32;
                                }
                                n => {
                                    if let Some(ch) = channel(n) {
                                        let lin = match color_scale(ty) {
                                            Some(full) => {
                                                srgb_to_linear((v / full).clamp(0.0, 1.0))
                                            }
                                            None if v.is_finite() => v.clamp(0.0, 1.0),
                                            None => {
                                                return Err(format!(
                                                    "{file}: vertex {k} has a colour that is not a number"
                                                ));
                                            }
                                        };
                                        rgb[ch] = lin as f32;
                                    }
                                }
                            }
                        }
                    }
                    Prop::List(ct, it, name) => {
                        let n = c.num(ct)?;
                        if !(0.0..=1024.0).contains(&n) {
                            return Err(format!("{file}: face {k} has {n} vertices"));
                        }
                        let mut idx = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            idx.push(c.num(it)?);
                        }
                        let is_face = e.name == "face"
                            && (name == "vertex_indices" || name == "vertex_index");
                        if is_face && idx.len() >= 3 {
                            let nv = m.positions.len() as f64;
                            if let Some(bad) = idx
                                .iter()
                                .find(|&&i| !(i >= 0.0 && i < nv && i.fract() == 0.0))
                            {
                                return Err(format!(
                                    "{file}: face {k} has vertex index {bad}, out of range ({nv} vertices)"
                                ));
                            }
                            for j in 1..idx.len() - 1 {
                                m.triangles
                                    .push([idx[0] as u32, idx[j] as u32, idx[j + 1] as u32]);
                            }
                        }
                    }
                }
            }
            if e.name == "vertex" {
                if xyz.iter().any(|v| !v.is_finite()) {
                    return Err(format!("{file}: vertex {k} has no finite x, y, z"));
                }
                m.positions.push(DVec3::from_array(xyz));
                if has_colors {
                    colors.push(rgb);
                }
                if has_uv {
                    uvs.push(uv);
                }
            }
        }
    }
    if m.triangles.is_empty() {
        return Err(format!("{file}: no faces"));
    }
    let n = m.triangles.len();
    let mut material = FileMaterial::plain("");
    material.vertex_colors = has_colors;
    Ok(MeshFile {
        mesh: m,
        uv: uvs,
        colors,
        material: vec![0; n],
        materials: vec![material],
    })
}

/// sRGB-encoded value in [0, 1] → linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

// ------------------------------------------------------------------------------------------
// glTF
// ------------------------------------------------------------------------------------------

/// A glTF file (`.gltf` text or `.glb`) parsed and validated, or why not. gltf-json 1.4.1's
/// validation reads a primitive's `POSITION` accessor before it checks that the accessor
/// exists, and panics on a file that names one it lacks (found by fuzzing `import`,
/// `docs/fuzzing.md`). Every accessor a primitive names is checked here first, so a malformed
/// file is an error, never a panic.
pub fn parse_gltf(bytes: &[u8]) -> Result<gltf::Gltf, String> {
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let json = document.into_json();
    let n = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let named = prim.attributes.values().chain(prim.indices.iter());
            if let Some(i) = named.map(|i| i.value()).find(|&i| i >= n) {
                return Err(format!(
                    "mesh {m}, primitive {p} names accessor {i}, and the file has {n} accessors"
                ));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf { document, blob })
}

/// Read a glTF 2.0 file (`bytes`, at `path`): every triangle primitive of the default scene
/// (or the first), node transforms applied, turned from +Y up into +Z up; with `colours`, each
/// glTF material one [`FileMaterial`] (a primitive without one takes the object's albedo) and
/// the texture coordinates its base-colour texture reads.
pub fn read_gltf(
    bytes: &[u8],
    path: &Path,
    roots: &[PathBuf],
    colours: bool,
) -> Result<MeshFile, String> {
    let shown = path.display().to_string();
    let gltf = parse_gltf(bytes).map_err(|e| format!("cannot read glTF `{shown}`: {e}"))?;
    let base = path.parent();
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob.clone())
        .map_err(|e| format!("cannot load the buffers of `{shown}`: {e}"))?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| format!("glTF `{shown}` has no scene"))?;
    let mut out = MeshFile::default();
    // glTF material index (None: the default material) → ours.
    let mut mat_of: Vec<(Option<usize>, u32)> = Vec::new();
    let exact = node_matrices(bytes);
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let local = match exact.get(node.index()) {
            Some(Some(m)) => *m,
            _ => DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from))),
        };
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            let mesh_name = mesh
                .name()
                .map(|n| format!("mesh `{n}`"))
                .unwrap_or_else(|| format!("mesh {}", mesh.index()));
            for (pi, prim) in mesh.primitives().enumerate() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let at = format!("{shown}: {mesh_name}, primitive {pi}");
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(pos) = reader.read_positions() else {
                    continue;
                };
                let base_index = out.mesh.positions.len() as u32;
                for (k, p) in pos.enumerate() {
                    if p.iter().any(|c| !c.is_finite()) {
                        return Err(format!("{at}: vertex {k} has a non-finite position"));
                    }
                    let p =
                        world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                    out.mesh.positions.push(DVec3::new(p.x, -p.z, p.y));
                }
                let nv = out.mesh.positions.len() as u32 - base_index;
                let idx: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..nv).collect(),
                };
                if let Some(&bad) = idx.iter().find(|&&i| i >= nv) {
                    return Err(format!(
                        "{at}: vertex index {bad} out of range ({nv} vertices)"
                    ));
                }
                // Material and texture coordinates (with colours only).
                let mi = if colours {
                    gltf_colours(
                        &prim,
                        &reader,
                        &buffers,
                        &mut out,
                        &mut mat_of,
                        base_index,
                        nv,
                        &at,
                        path,
                        roots,
                    )?
                } else {
                    0
                };
                let flip = world.determinant() < 0.0;
                for t in idx.chunks_exact(3) {
                    let tri = if flip {
                        [t[0], t[2], t[1]]
                    } else {
                        [t[0], t[1], t[2]]
                    };
                    out.mesh.triangles.push(tri.map(|i| i + base_index));
                    out.material.push(mi);
                }
                if out.mesh.triangles.len() > MAX_ELEMENTS {
                    return Err(format!("{shown}: more than {MAX_ELEMENTS} triangles"));
                }
            }
        }
        let kids: Vec<_> = node.children().collect();
        for k in kids.into_iter().rev() {
            stack.push((k, world));
        }
    }
    if out.mesh.triangles.is_empty() {
        return Err(format!("glTF `{shown}` contains no triangles"));
    }
    if !out.uv.is_empty() {
        out.uv.resize(out.mesh.positions.len(), [0.0; 2]);
    }
    Ok(out)
}

/// Every node's local transform read from the glTF's JSON in f64 (the glTF crate keeps them
/// in f32, which rounds a georeferenced translation such as 4 200 000.37 m to 0.5 m): per
/// node, `matrix`, or `translation · rotation · scale`; `None` for a node whose numbers are
/// not all there and finite (its f32 transform is used).
fn node_matrices(bytes: &[u8]) -> Vec<Option<DMat4>> {
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        match gltf::Glb::from_slice(bytes) {
            Ok(g) => return node_matrices_json(&g.json),
            Err(_) => return Vec::new(),
        }
    } else {
        bytes
    };
    node_matrices_json(json)
}

fn node_matrices_json(json: &[u8]) -> Vec<Option<DMat4>> {
    let Ok(v) = serde_json::from_slice::<serde_json::Value>(json) else {
        return Vec::new();
    };
    let numbers = |n: &serde_json::Value, key: &str, len: usize| -> Option<Option<Vec<f64>>> {
        match n.get(key) {
            None => Some(None),
            Some(a) => {
                let a = a.as_array()?;
                let v: Vec<f64> = a.iter().filter_map(serde_json::Value::as_f64).collect();
                (v.len() == len && a.len() == len && v.iter().all(|x| x.is_finite()))
                    .then_some(Some(v))
            }
        }
    };
    let nodes = v
        .get("nodes")
        .and_then(|n| n.as_array())
        .cloned()
        .unwrap_or_default();
    nodes
        .iter()
        .map(|n| {
            if let Some(m) = numbers(n, "matrix", 16)? {
                let mut a = [0.0; 16];
                a.copy_from_slice(&m);
                return Some(DMat4::from_cols_array(&a));
            }
            let t = numbers(n, "translation", 3)?.unwrap_or(vec![0.0; 3]);
            let r = numbers(n, "rotation", 4)?.unwrap_or(vec![0.0, 0.0, 0.0, 1.0]);
            let s = numbers(n, "scale", 3)?.unwrap_or(vec![1.0; 3]);
            let q = glam::DQuat::from_xyzw(r[0], r[1], r[2], r[3]);
            if !q.is_normalized() {
                return None;
            }
            Some(DMat4::from_scale_rotation_translation(
                DVec3::new(s[0], s[1], s[2]),
                q,
                DVec3::new(t[0], t[1], t[2]),
            ))
        })
        .collect()
}

/// The material of a glTF primitive (its index in `out.materials`, added when new) and the
/// texture coordinates its base-colour texture reads, appended to `out.uv` for the primitive's
/// `nv` vertices from `base_index`.
#[allow(clippy::too_many_arguments)]
fn gltf_colours<'a, 's, F>(
    prim: &gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    buffers: &[gltf::buffer::Data],
    out: &mut MeshFile,
    mat_of: &mut Vec<(Option<usize>, u32)>,
    base_index: u32,
    nv: u32,
    at: &str,
    path: &Path,
    roots: &[PathBuf],
) -> Result<u32, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let shown = path.display().to_string();
    let material = prim.material();
    let key = material.index();
    let mi = match mat_of.iter().find(|(k, _)| *k == key) {
        Some(&(_, m)) => m,
        None => {
            let m = gltf_material(&material, buffers, path, roots)
                .map_err(|e| format!("{shown}: {e}"))?;
            out.materials.push(m);
            let m = out.materials.len() as u32 - 1;
            mat_of.push((key, m));
            m
        }
    };
    let info = material.pbr_metallic_roughness().base_color_texture();
    if let Some(info) = &info {
        let transform = info.texture_transform();
        let set = transform
            .as_ref()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord());
        let tc = reader.read_tex_coords(set).ok_or_else(|| {
            format!("{at}: its base-colour texture reads TEXCOORD_{set}, which it does not have")
        })?;
        if out.uv.len() < base_index as usize {
            out.uv.resize(base_index as usize, [0.0; 2]);
        }
        let m = transform.map(|t| {
            let (s, c) = (t.rotation() as f64).sin_cos();
            let [ox, oy] = t.offset().map(f64::from);
            let [sx, sy] = t.scale().map(f64::from);
            // translation · rotation · scale, as the extension's GLSL writes it (its `mat3`s
            // are column-major: the rotation's rows are (cos, −sin) and (sin, cos)).
            [[c * sx, -s * sy, ox], [s * sx, c * sy, oy]]
        });
        let before = out.uv.len();
        for (k, q) in tc.into_f32().enumerate() {
            if q.iter().any(|c| !c.is_finite()) {
                return Err(format!(
                    "{at}: vertex {k} has a non-finite texture coordinate"
                ));
            }
            let q = match m {
                Some(m) => {
                    let (u, v) = (q[0] as f64, q[1] as f64);
                    [
                        (m[0][0] * u + m[0][1] * v + m[0][2]) as f32,
                        (m[1][0] * u + m[1][1] * v + m[1][2]) as f32,
                    ]
                }
                None => q,
            };
            out.uv.push(q);
        }
        if out.uv.len() - before != nv as usize {
            return Err(format!(
                "{at}: TEXCOORD_{set} has {} entries for {nv} vertices",
                out.uv.len() - before
            ));
        }
    } else if !out.uv.is_empty() {
        out.uv.resize(out.mesh.positions.len(), [0.0; 2]);
    }
    Ok(mi)
}

/// One glTF material as a [`FileMaterial`]: `baseColorFactor` (linear), `baseColorTexture`'s
/// image and sampler wrap (S's; T's when S and T differ is not modelled).
fn gltf_material(
    m: &gltf::Material,
    buffers: &[gltf::buffer::Data],
    path: &Path,
    roots: &[PathBuf],
) -> Result<FileMaterial, String> {
    let Some(index) = m.index() else {
        return Ok(FileMaterial::plain(""));
    };
    let name = m
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("material {index}"));
    let pbr = m.pbr_metallic_roughness();
    let f = pbr.base_color_factor();
    let mut out = FileMaterial::plain(&name);
    out.color = Some([f[0], f[1], f[2]].map(f64::from));
    if out
        .color
        .is_some_and(|c| c.iter().any(|x| !x.is_finite() || *x < 0.0))
    {
        return Err(format!(
            "material `{name}`: baseColorFactor is not a colour"
        ));
    }
    if let Some(info) = pbr.base_color_texture() {
        let tex = info.texture();
        out.wrap = match tex.sampler().wrap_s() {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        let img = tex.source();
        let named_at = format!("{}: image {}", path.display(), img.index());
        let source = match img.source() {
            gltf::image::Source::View { view, .. } => {
                let data = buffers
                    .get(view.buffer().index())
                    .ok_or_else(|| format!("{named_at}: its buffer is missing"))?;
                let bytes = data
                    .0
                    .get(view.offset()..view.offset() + view.length())
                    .ok_or_else(|| format!("{named_at}: its buffer view is out of range"))?;
                ImageSource::Bytes(std::sync::Arc::new(bytes.to_vec()))
            }
            gltf::image::Source::Uri { uri, .. } => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, b64) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| format!("{named_at}: a data URI that is not base64"))?;
                    use base64::Engine;
                    let bytes = base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| format!("{named_at}: bad base64 data: {e}"))?;
                    ImageSource::Bytes(std::sync::Arc::new(bytes))
                } else {
                    let rel = percent_decoded(uri);
                    ImageSource::File(
                        side_file(path, &rel, roots).map_err(|e| format!("{named_at}: {e}"))?,
                    )
                }
            }
        };
        out.image = Some(ImageRef { source, named_at });
    }
    Ok(out)
}

/// `%XX` escapes of a glTF URI decoded (as the glTF loader does); invalid escapes stay.
pub fn percent_decoded(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%'
            && i + 2 < b.len()
            && let Ok(v) =
                u8::from_str_radix(std::str::from_utf8(&b[i + 1..i + 3]).unwrap_or("x"), 16)
        {
            out.push(v);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

// ------------------------------------------------------------------------------------------
// Probing (the scene's front end)
// ------------------------------------------------------------------------------------------

/// What the scene's front end learns of a mesh file without reading its geometry: the files it
/// names (MTL files, images, buffers; each checked by [`side_file`]), the images whose headers
/// can be probed, and whether it carries colours of its own (an image texture or vertex
/// colours).
#[derive(Debug, Clone, Default)]
pub struct Probe {
    pub side_files: Vec<PathBuf>,
    pub images: Vec<ImageRef>,
    pub textured: bool,
}

/// Probe the mesh file `bytes` at `path` ([`Probe`]). Errors name the file and, for OBJ and MTL,
/// the line.
pub fn probe(bytes: &[u8], path: &Path, roots: &[PathBuf]) -> Result<Probe, String> {
    let shown = path.display().to_string();
    match Format::of(path) {
        Some(Format::Obj) => {
            let text = text_of(bytes, &shown)?;
            let mut obj = Obj::default();
            let mut used: Vec<(String, usize)> = Vec::new();
            // Pieces scanned in parallel, merged in the file's order.
            use rayon::prelude::*;
            let found: Vec<_> = line_chunks(text)
                .par_iter()
                .map(|&(first, chunk)| {
                    let (mut libs, mut uses) = (Vec::new(), Vec::<(String, usize)>::new());
                    for (i, line) in chunk.lines().enumerate() {
                        let line = line.trim_start();
                        if line.starts_with("mtllib") {
                            if let Some(lib) = mtllib_of(line) {
                                libs.push((lib.to_string(), first + i));
                            }
                        } else if let Some(rest) = line.strip_prefix("usemtl")
                            && rest.starts_with(char::is_whitespace)
                            && !uses.iter().any(|(n, _)| n == rest.trim())
                        {
                            uses.push((rest.trim().to_string(), first + i));
                        }
                    }
                    (libs, uses)
                })
                .collect();
            for (libs, uses) in found {
                obj.mtllibs.extend(libs);
                for (name, ln) in uses {
                    if !used.iter().any(|(n, _)| *n == name) {
                        used.push((name, ln));
                    }
                }
            }
            let mtls = obj_mtls(&obj, path, roots)?;
            let mut out = Probe::default();
            out.side_files.extend(mtls.iter().map(|(p, _)| p.clone()));
            for (name, ln) in &used {
                if !mtls
                    .iter()
                    .any(|(_, es)| es.iter().any(|e| e.name == *name))
                {
                    return Err(format!(
                        "{shown}:{ln}: material `{name}` is not defined in any `mtllib` file"
                    ));
                }
            }
            for (mtl, entries) in &mtls {
                let mshown = mtl.display().to_string();
                for e in entries {
                    if let Some((file, ln)) = &e.map_kd {
                        let p = side_file(mtl, file, roots)
                            .map_err(|err| format!("{mshown}:{ln}: `map_Kd`: {err}"))?;
                        out.side_files.push(p.clone());
                        out.images.push(ImageRef {
                            source: ImageSource::File(p),
                            named_at: format!("{mshown}:{ln}"),
                        });
                        out.textured = true;
                    }
                }
            }
            Ok(out)
        }
        Some(Format::Ply) => {
            let end = bytes
                .windows(10)
                .position(|w| w == b"end_header")
                .ok_or_else(|| format!("{shown}: not a PLY file (no `end_header`)"))?;
            let header = String::from_utf8_lossy(&bytes[..end]);
            let mut vertex = false;
            let mut found = [false; 3];
            for line in header.lines() {
                let w: Vec<&str> = line.split_whitespace().collect();
                match w.as_slice() {
                    ["element", name, _] => vertex = *name == "vertex",
                    ["property", _, name] if vertex => {
                        for (k, names) in [["red", "r"], ["green", "g"], ["blue", "b"]]
                            .iter()
                            .enumerate()
                        {
                            if names.contains(name) {
                                found[k] = true;
                            }
                        }
                    }
                    _ => {}
                }
            }
            Ok(Probe {
                textured: found.iter().all(|&f| f),
                ..Probe::default()
            })
        }
        Some(Format::Gltf) => {
            let g = parse_gltf(bytes)?;
            let mut out = Probe::default();
            for m in g.materials() {
                let Some(info) = m.pbr_metallic_roughness().base_color_texture() else {
                    continue;
                };
                out.textured = true;
                let img = info.texture().source();
                let named_at = format!("{shown}: image {}", img.index());
                match img.source() {
                    gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                        let p = side_file(path, &percent_decoded(uri), roots)
                            .map_err(|e| format!("{named_at}: {e}"))?;
                        out.images.push(ImageRef {
                            source: ImageSource::File(p),
                            named_at,
                        });
                    }
                    gltf::image::Source::View { view, .. }
                        if matches!(view.buffer().source(), gltf::buffer::Source::Bin) =>
                    {
                        if let Some(b) = g
                            .blob
                            .as_ref()
                            .and_then(|b| b.get(view.offset()..view.offset() + view.length()))
                        {
                            out.images.push(ImageRef {
                                source: ImageSource::Bytes(std::sync::Arc::new(b.to_vec())),
                                named_at,
                            });
                        }
                    }
                    // Data URIs and views of external buffers are checked when the mesh is
                    // read.
                    _ => {}
                }
            }
            Ok(out)
        }
        None => Err(format!("`{shown}` is not a .glb, .gltf, .obj or .ply file")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A primitive naming an accessor the file lacks is an error (gltf-json's own validation
    /// panics on it).
    #[test]
    fn a_gltf_naming_a_missing_accessor_is_an_error_not_a_panic() {
        let text = br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#;
        let e = parse_gltf(text).unwrap_err();
        assert!(e.contains("names accessor 0, and the file has 0"), "{e}");
        let e = read_gltf(text, Path::new("bad.gltf"), &[], false).unwrap_err();
        assert!(e.starts_with("cannot read glTF `bad.gltf`"), "{e}");
    }

    fn write(dir: &Path, name: &str, text: &[u8]) -> PathBuf {
        let p = dir.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }

    /// A 2 × 1 PNG.
    fn png() -> Vec<u8> {
        let mut out = Vec::new();
        image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
            .unwrap();
        out
    }

    const MTL: &str = "newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd -clamp on -s 2 2 1 -o 0.5 0 0 t.png\n\nnewmtl plain\nKd 0.2 0.3 0.4\n";

    fn obj_site(dir: &Path) -> PathBuf {
        write(dir, "t.png", &png());
        write(dir, "m.mtl", MTL.as_bytes());
        write(
            dir,
            "m.obj",
            b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
              usemtl tex\nf 1/1 2/2 3/3 4/4\nusemtl plain\nf -4 -3 -2\n",
        )
    }

    #[test]
    fn obj_with_mtl_reads_materials_uvs_and_negative_indices() {
        let dir = tempfile::tempdir().unwrap();
        let f = load(&obj_site(dir.path()), &[]).unwrap();
        assert_eq!(f.mesh.triangles.len(), 3);
        assert_eq!(f.material, vec![0, 0, 1]);
        assert_eq!(f.materials.len(), 2);
        let tex = &f.materials[0];
        assert_eq!(tex.color, Some([0.5; 3]));
        assert_eq!(tex.wrap, Wrap::Clamp);
        assert!(
            matches!(&tex.image, Some(ImageRef { source: ImageSource::File(p), named_at })
            if p.ends_with("t.png") && named_at.ends_with("m.mtl:3"))
        );
        assert_eq!(f.materials[1].color, Some([0.2, 0.3, 0.4]));
        assert!(f.materials[1].image.is_none());
        // vt (1, 1) → ·2 + (0.5, 0) = (2.5, 2) → v flipped: 1 − 2 = −1.
        let k = f
            .mesh
            .positions
            .iter()
            .position(|p| *p == DVec3::new(1.0, 1.0, 0.0))
            .unwrap();
        assert_eq!(f.uv[k], [2.5, -1.0]);
        // The plain face `f -4 -3 -2` uses the first three positions.
        let t = f.mesh.triangles[2].map(|i| f.mesh.positions[i as usize]);
        assert_eq!(t, [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0)]);
        assert!(f.has_texture());
        let p = probe(
            &std::fs::read(dir.path().join("m.obj")).unwrap(),
            &dir.path().join("m.obj"),
            &[],
        )
        .unwrap();
        assert!(p.textured);
        assert_eq!(p.side_files.len(), 2);
    }

    #[test]
    fn broken_obj_files_are_named_with_their_line() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let e = load(
            &write(d, "a.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
            &[],
        )
        .unwrap_err();
        assert!(
            e.contains("a.obj:4: vertex index 4 is out of range (3 vertices so far)"),
            "{e}"
        );
        let e = load(&write(d, "b.obj", b"v 0 0 0\nv nan 0 0\n"), &[]).unwrap_err();
        assert!(
            e.contains("b.obj:2: a vertex needs three finite numbers"),
            "{e}"
        );
        let e = load(&write(d, "c.obj", b"v 0 0 0\nvt 0 inf\n"), &[]).unwrap_err();
        assert!(
            e.contains("c.obj:2: a texture coordinate needs finite numbers"),
            "{e}"
        );
        let e = load(
            &write(
                d,
                "d.obj",
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            ),
            &[],
        )
        .unwrap_err();
        assert!(
            e.contains("d.obj:5: texture coordinate index 2 is out of range"),
            "{e}"
        );
        let e = load(
            &write(
                d,
                "e.obj",
                b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl nope\nf 1 2 3\n",
            ),
            &[],
        )
        .unwrap_err();
        assert!(e.contains("e.obj:1: `mtllib`: `m.mtl` is missing"), "{e}");
        write(d, "m.mtl", b"newmtl other\nKd 1 1 1\n");
        let e = load(&d.join("e.obj"), &[]).unwrap_err();
        assert!(
            e.contains("e.obj:5: material `nope` is not defined in"),
            "{e}"
        );
    }

    #[test]
    fn mtl_paths_may_not_leave_the_scene_or_be_missing() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene");
        write(dir.path(), "secret.png", &png());
        let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl a\nf 1/1 2/1 3/1\n";
        let roots = [scene.clone()];
        for (map, want) in [
            ("../../secret.png", "leaves the scene's folder"),
            ("/etc/passwd", "is an absolute path"),
            ("C:\\textures\\a.png", "is an absolute path"),
            ("missing.png", "is missing"),
        ] {
            let o = write(&scene, "site/m.obj", obj);
            write(
                &scene,
                "site/m.mtl",
                format!("newmtl a\nmap_Kd {map}\n").as_bytes(),
            );
            let e = load(&o, &roots).unwrap_err();
            assert!(
                e.contains("m.mtl:2: `map_Kd`:") && e.contains(want),
                "{map}: {e}"
            );
            let e = probe(obj, &o, &roots).unwrap_err();
            assert!(e.contains(want), "{map}: {e}");
        }
        // `..` that stays inside the scene's folder is fine.
        write(&scene, "textures/a.png", &png());
        let o = write(&scene, "site/m.obj", obj);
        write(
            &scene,
            "site/m.mtl",
            b"newmtl a\nmap_Kd ..\\textures\\a.png\n",
        );
        assert!(load(&o, &roots).is_ok());
        // An MTL file that climbs out is refused too.
        write(dir.path(), "out.mtl", b"newmtl a\n");
        let o = write(
            &scene,
            "site/n.obj",
            b"mtllib ../../out.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let e = load(&o, &roots).unwrap_err();
        assert!(
            e.contains("n.obj:1: `mtllib`:") && e.contains("leaves"),
            "{e}"
        );
    }

    #[test]
    fn ply_vertex_colours_are_srgb_bytes_or_linear_floats() {
        let head = |ty: &str| {
            format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty {ty} red\nproperty {ty} green\nproperty {ty} blue\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            )
        };
        let bytes = format!(
            "{}0 0 0 255 128 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 2\n",
            head("uchar")
        );
        let f = read_ply(bytes.as_bytes(), "c.ply").unwrap();
        assert!(f.materials[0].vertex_colors && f.has_texture());
        assert_eq!(f.colors[0][0], 1.0);
        assert!((f.colors[0][1] as f64 - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6);
        let bytes = format!(
            "{}0 0 0 0.5 0.25 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 2\n",
            head("float")
        );
        let f = read_ply(bytes.as_bytes(), "c.ply").unwrap();
        assert_eq!(f.colors[0], [0.5, 0.25, 0.0]);
        let bad = format!(
            "{}0 0 0 0 0 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 7\n",
            head("uchar")
        );
        let e = read_ply(bad.as_bytes(), "c.ply").unwrap_err();
        assert!(
            e.contains("c.ply: face 0 has vertex index 7, out of range"),
            "{e}"
        );
        let nan = format!(
            "{}0 0 0 0 0 0\nnan 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 2\n",
            head("uchar")
        );
        let e = read_ply(nan.as_bytes(), "c.ply").unwrap_err();
        assert!(e.contains("c.ply: vertex 1 has no finite x, y, z"), "{e}");
        let p = probe(bytes.as_bytes(), Path::new("c.ply"), &[]).unwrap();
        assert!(p.textured);
    }

    /// A glTF with one textured triangle: positions, TEXCOORD_0 and indices in a data-URI
    /// buffer; `extra` is merged into the texture info (e.g. a KHR_texture_transform).
    fn gltf(dir: &Path, positions: [[f32; 3]; 3], indices: [u16; 3], extra: &str) -> PathBuf {
        use base64::Engine;
        let mut bin = Vec::new();
        for p in positions {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for uv in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            for c in uv {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for i in indices {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 0]);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "nodes": [{{"mesh": 0}}],
            "meshes": [{{"name": "m", "primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}}]}}],
            "materials": [{{"name": "paint", "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "baseColorTexture": {{"index": 0{extra}}}}}}}],
            "textures": [{{"source": 0, "sampler": 0}}],
            "samplers": [{{"wrapS": 33648, "wrapT": 33648}}],
            "images": [{{"uri": "t%20x.png"}}],
            "extensionsUsed": ["KHR_texture_transform"],
            "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{b64}"}}],
            "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}, {{"buffer": 0, "byteOffset": 60, "byteLength": 6}}],
            "accessors": [
              {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
              {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}},
              {{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}}]}}"#,
            bin.len()
        );
        write(dir, "t x.png", &png());
        write(dir, "m.gltf", json.as_bytes())
    }

    #[test]
    fn gltf_reads_base_colour_texture_factor_and_transform() {
        let dir = tempfile::tempdir().unwrap();
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let p = gltf(
            dir.path(),
            tri,
            [0, 1, 2],
            r#", "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2], "rotation": 0}}"#,
        );
        let f = load(&p, &[]).unwrap();
        assert_eq!(f.materials.len(), 1);
        let m = &f.materials[0];
        assert_eq!(m.name, "paint");
        assert_eq!(m.color, Some([0.5, 0.25, 1.0]));
        assert_eq!(m.wrap, Wrap::Mirror);
        assert!(
            matches!(&m.image, Some(ImageRef { source: ImageSource::File(p), .. }) if p.ends_with("t x.png"))
        );
        // uv · 2 + (0.5, 0); glTF's v is already poser's.
        assert_eq!(f.uv, vec![[0.5, 0.0], [2.5, 0.0], [0.5, 2.0]]);
        // +Y up → +Z up.
        assert_eq!(f.mesh.positions[2], DVec3::new(0.0, 0.0, 1.0));
        let bad = gltf(dir.path(), tri, [0, 1, 5], "");
        let e = load(&bad, &[]).unwrap_err();
        assert!(
            e.contains("mesh `m`, primitive 0: vertex index 5 out of range"),
            "{e}"
        );
        // A quarter turn: (u, v) → (−v, u).
        let p = gltf(
            dir.path(),
            tri,
            [0, 1, 2],
            r#", "extensions": {"KHR_texture_transform": {"rotation": 1.5707963267948966}}"#,
        );
        let f = load(&p, &[]).unwrap();
        let r: Vec<[f32; 2]> =
            f.uv.iter()
                .map(|q| q.map(|x| (x * 1e6).round() / 1e6))
                .collect();
        assert_eq!(r, vec![[0.0, 0.0], [0.0, 1.0], [-1.0, 0.0]]);
        let nan = gltf(
            dir.path(),
            [[0.0, f32::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [0, 1, 2],
            "",
        );
        let e = load(&nan, &[]).unwrap_err();
        assert!(e.contains("vertex 0 has a non-finite position"), "{e}");
    }

    /// The prefetch finds the images a shipped OBJ names in its first lines; it misses a
    /// library named past its window and refuses one outside the roots (a hint only: the full
    /// load reports both).
    #[test]
    fn early_images_of_an_obj() {
        let dir = Path::new("scenarios/sites/assets/textured_bommie")
            .canonicalize()
            .unwrap();
        let found = obj_images_early(&dir.join("model.obj"), std::slice::from_ref(&dir));
        assert_eq!(found, [(dir.join("model.jpg"), Wrap::Repeat)]);
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path().canonicalize().unwrap();
        std::fs::write(root.join("m.mtl"), "newmtl a\nmap_Kd -clamp on t.png\n").unwrap();
        std::fs::write(root.join("t.png"), b"not read here").unwrap();
        let late = format!("{}mtllib m.mtl\n", "v 0 0 0\n".repeat(EARLY_BYTES / 8 + 1));
        std::fs::write(root.join("late.obj"), late).unwrap();
        std::fs::write(root.join("early.obj"), "mtllib m.mtl\nv 0 0 0\n").unwrap();
        std::fs::write(root.join("out.obj"), "mtllib ../m.mtl\n").unwrap();
        let roots = [root.clone()];
        assert_eq!(
            obj_images_early(&root.join("early.obj"), &roots),
            [(root.join("t.png"), Wrap::Clamp)]
        );
        assert!(obj_images_early(&root.join("late.obj"), &roots).is_empty());
        assert!(obj_images_early(&root.join("out.obj"), &roots).is_empty());
    }

    /// The parallel scans of an OBJ's text (vertex bounds, material lines) number lines as
    /// `str::lines` does, across the pieces they are cut into.
    #[test]
    fn line_chunks_keep_line_numbers() {
        let text: String = (0..1_000_000).map(|i| format!("v {i} 0 0\r\n")).collect();
        let chunks = line_chunks(&text);
        assert!(chunks.len() > 2);
        assert_eq!(chunks.iter().map(|c| c.1).collect::<String>(), text);
        for (first, c) in &chunks {
            let want = format!("v {} 0 0", first - 1);
            assert_eq!(c.lines().next().unwrap(), want);
        }
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("big.obj");
        std::fs::write(&p, &text).unwrap();
        let (lo, hi) = vertex_bounds(&p).unwrap().unwrap();
        assert_eq!((lo.x, hi.x), (0.0, 999_999.0));
    }
}
