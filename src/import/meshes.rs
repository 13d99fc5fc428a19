//! Mesh files of imported scenes: Wavefront OBJ and PLY readers, and the glTF 2.0 binary
//! (`.glb`) writer the imported scene's `shape = "mesh"` objects point at.
//!
//! | format | read | limits |
//! |---|---|---|
//! | OBJ | `v` and `f` (polygons fan-triangulated; `v/vt/vn` and negative indices) | other statements ignored |
//! | PLY | `ascii`, `binary_little_endian`, `binary_big_endian`; vertex `x y z` (float or double, any other properties skipped); face `vertex_indices`/`vertex_index` lists | counts checked against the file's size before anything is allocated |
//! | GLB | written: one mesh, POSITION (f32) and u32 indices; glTF's +Y up (`(x, y, z)_poser → (x, z, −y)_gltf`, the inverse of the mesh loader's) | |

use crate::geometry::mesh::TriMesh;
use glam::DVec3;

/// Most vertices or faces accepted in one mesh file.
pub const MAX_ELEMENTS: usize = 50_000_000;

/// Read an OBJ file's triangles.
pub fn read_obj(text: &str, file: &str) -> Result<TriMesh, String> {
    let mut m = TriMesh::default();
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|s| s.parse().unwrap_or(f64::NAN)).collect();
                if c.len() < 3 || c.iter().any(|x| !x.is_finite()) {
                    return Err(format!(
                        "{file}:{}: a vertex needs three finite numbers",
                        i + 1
                    ));
                }
                if m.positions.len() >= MAX_ELEMENTS {
                    return Err(format!("{file}: more than {MAX_ELEMENTS} vertices"));
                }
                m.positions.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let n = m.positions.len() as i64;
                let idx: Vec<u32> = it
                    .map(|s| {
                        let k: i64 = s.split('/').next().unwrap_or("").parse().map_err(|_| {
                            format!("{file}:{}: `{s}` is not a vertex index", i + 1)
                        })?;
                        let k = if k < 0 { n + k } else { k - 1 };
                        if k < 0 || k >= n {
                            return Err(format!(
                                "{file}:{}: vertex index {s} is out of range ({n} vertices so far)",
                                i + 1
                            ));
                        }
                        Ok(k as u32)
                    })
                    .collect::<Result<_, String>>()?;
                if idx.len() < 3 {
                    return Err(format!("{file}:{}: a face needs three vertices", i + 1));
                }
                for k in 1..idx.len() - 1 {
                    m.triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
                if m.triangles.len() > MAX_ELEMENTS {
                    return Err(format!("{file}: more than {MAX_ELEMENTS} triangles"));
                }
            }
            _ => {}
        }
    }
    if m.triangles.is_empty() {
        return Err(format!("{file}: no faces"));
    }
    Ok(m)
}

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

/// Read a PLY file's triangles (faces fan-triangulated).
pub fn read_ply(bytes: &[u8], file: &str) -> Result<TriMesh, String> {
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
    let mut c = Cursor {
        b: bytes,
        at: body,
        enc,
        file,
    };
    let mut m = TriMesh::default();
    for e in &elements {
        for _ in 0..e.count {
            let mut xyz = [f64::NAN; 3];
            for p in &e.props {
                match p {
                    Prop::Scalar(ty, name) => {
                        let v = c.num(ty)?;
                        if e.name == "vertex" {
                            match name.as_str() {
                                "x" => xyz[0] = v,
                                "y" => xyz[1] = v,
                                "z" => xyz[2] = v,
                                _ => {}
                            }
                        }
                    }
                    Prop::List(ct, it, name) => {
                        let n = c.num(ct)?;
                        if !(0.0..=1024.0).contains(&n) {
                            return Err(format!("{file}: a face with {n} vertices"));
                        }
                        let mut idx = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            idx.push(c.num(it)?);
                        }
                        let is_face = e.name == "face"
                            && (name == "vertex_indices" || name == "vertex_index");
                        if is_face && idx.len() >= 3 {
                            let nv = m.positions.len() as f64;
                            if idx
                                .iter()
                                .any(|&k| !(k >= 0.0 && k < nv && k.fract() == 0.0))
                            {
                                return Err(format!("{file}: a face index is out of range"));
                            }
                            for k in 1..idx.len() - 1 {
                                m.triangles
                                    .push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
                            }
                        }
                    }
                }
            }
            if e.name == "vertex" {
                if xyz.iter().any(|v| !v.is_finite()) {
                    return Err(format!("{file}: a vertex without finite x, y, z"));
                }
                m.positions.push(DVec3::from_array(xyz));
            }
        }
    }
    if m.triangles.is_empty() {
        return Err(format!("{file}: no faces"));
    }
    Ok(m)
}

fn pad4(v: &mut Vec<u8>, with: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(with);
    }
}

/// A glTF 2.0 binary file holding `mesh` (poser's +Z-up frame turned into glTF's +Y-up).
pub fn glb(mesh: &TriMesh, name: &str) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &mesh.positions {
        let g = [p.x as f32, p.z as f32, -p.y as f32];
        for k in 0..3 {
            lo[k] = lo[k].min(g[k]);
            hi[k] = hi[k].max(g[k]);
            bin.extend_from_slice(&g[k].to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let idx_len = bin.len() - pos_len;
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": "poser import"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"name": name, "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": mesh.positions.len(),
             "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": mesh.triangles.len() * 3,
             "type": "SCALAR"}
        ]
    });
    let mut js = serde_json::to_vec(&json).unwrap_or_default();
    pad4(&mut js, b' ');
    pad4(&mut bin, 0);
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriMesh {
        TriMesh {
            positions: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 2.0, 0.0),
                DVec3::new(0.0, 2.0, 0.5),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn obj_faces_are_triangulated_with_negative_indices() {
        let m = read_obj(
            "# quad\nv 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0.5\nvn 0 0 1\nf 1//1 2//1 -2//1 -1//1\n",
            "q.obj",
        )
        .unwrap();
        assert_eq!(m, quad());
        assert!(
            read_obj("v 0 0 0\nf 1 2 3\n", "q.obj")
                .unwrap_err()
                .contains("q.obj:2")
        );
        assert!(read_obj("v 0 0 nan\n", "q.obj").is_err());
    }

    #[test]
    fn ply_ascii_and_binary_agree_with_poser_s_writer() {
        use crate::geometry::mesh::{PlyFormat, ply_bytes};
        let q = quad();
        for f in [PlyFormat::Ascii, PlyFormat::BinaryLittleEndian] {
            let m = read_ply(&ply_bytes(&q, f), "q.ply").unwrap();
            assert_eq!(m.triangles, q.triangles);
            for (a, b) in m.positions.iter().zip(&q.positions) {
                assert!((*a - *b).length() < 1e-6);
            }
        }
        let lie = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n";
        assert!(
            read_ply(lie, "x.ply")
                .unwrap_err()
                .contains("more than the file")
        );
        assert!(read_ply(b"not a ply", "x.ply").is_err());
    }

    #[test]
    fn glb_round_trips_through_the_mesh_loader() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("q.glb");
        std::fs::write(&p, glb(&quad(), "q")).unwrap();
        let m = crate::geometry::mesh::load_gltf(&p).unwrap();
        assert_eq!(m.triangles, quad().triangles);
        for (a, b) in m.positions.iter().zip(&quad().positions) {
            assert!((*a - *b).length() < 1e-6, "{a} {b}");
        }
    }
}
