//! Mesh files of imported scenes: Wavefront OBJ and PLY readers, and the glTF 2.0 binary
//! (`.glb`) writer the imported scene's `shape = "mesh"` objects point at.
//!
//! | format | read | limits |
//! |---|---|---|
//! | OBJ | `v` and `f` (polygons fan-triangulated; `v/vt/vn` and negative indices) | other statements ignored |
//! | PLY | `ascii`, `binary_little_endian`, `binary_big_endian`; vertex `x y z` (float or double, any other properties skipped); face `vertex_indices`/`vertex_index` lists | counts checked against the file's size before anything is allocated |
//! | PNG | written: an image texture's pixels (8-bit sRGB kept, linear values as 16-bit sRGB) | |
//! | GLB | written: one mesh, POSITION (f32) and u32 indices, and for an image texture TEXCOORD_0 and one material naming the image beside it; glTF's +Y up (`(x, y, z)_poser → (x, z, −y)_gltf`, the inverse of the mesh loader's) | |

use crate::geometry::mesh::TriMesh;

pub use crate::geometry::meshfile::MAX_ELEMENTS;

/// Read an OBJ file's triangles ([`crate::geometry::meshfile::parse_obj`]; materials and
/// texture coordinates are not imported).
pub fn read_obj(text: &str, file: &str) -> Result<TriMesh, String> {
    Ok(crate::geometry::meshfile::parse_obj(text, file)?.mesh)
}

/// Read a PLY file's triangles ([`crate::geometry::meshfile::read_ply`]; colours are not
/// imported).
pub fn read_ply(bytes: &[u8], file: &str) -> Result<TriMesh, String> {
    Ok(crate::geometry::meshfile::read_ply(bytes, file)?.mesh)
}

fn pad4(v: &mut Vec<u8>, with: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(with);
    }
}

/// An image texture for [`glb_textured`]: per-vertex texture coordinates (v = 0 at the
/// image's first row, glTF's and poser's convention), the image's file name beside the `.glb`
/// and its wrap.
pub struct MeshTexture<'a> {
    pub uv: &'a [[f32; 2]],
    pub image: &'a str,
    pub wrap: crate::geometry::meshfile::Wrap,
}

/// A glTF 2.0 binary file holding `mesh` (poser's +Z-up frame turned into glTF's +Y-up).
pub fn glb(mesh: &TriMesh, name: &str) -> Vec<u8> {
    glb_textured(mesh, None, name)
}

/// [`glb`] with, when `tex` is given, a `TEXCOORD_0` set and one material whose base colour is
/// the external image `tex.image` (factor 1).
pub fn glb_textured(mesh: &TriMesh, tex: Option<&MeshTexture>, name: &str) -> Vec<u8> {
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
    let mut json = serde_json::json!({
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
    if let Some(t) = tex.filter(|t| t.uv.len() == mesh.positions.len()) {
        use crate::geometry::meshfile::Wrap;
        let uv_at = bin.len();
        for q in t.uv {
            bin.extend_from_slice(&q[0].to_le_bytes());
            bin.extend_from_slice(&q[1].to_le_bytes());
        }
        let wrap = match t.wrap {
            Wrap::Repeat => 10497,
            Wrap::Clamp => 33071,
            Wrap::Mirror => 33648,
        };
        if let Some(v) = json["bufferViews"].as_array_mut() {
            v.push(serde_json::json!({"buffer": 0, "byteOffset": uv_at,
                "byteLength": bin.len() - uv_at, "target": 34962}));
        }
        if let Some(v) = json["accessors"].as_array_mut() {
            v.push(serde_json::json!({"bufferView": 2, "componentType": 5126,
                "count": t.uv.len(), "type": "VEC2"}));
        }
        json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
        json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = serde_json::json!(2);
        json["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
        json["materials"] = serde_json::json!([{"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "baseColorTexture": {"index": 0},
            "metallicFactor": 0.0}}]);
        json["textures"] = serde_json::json!([{"source": 0, "sampler": 0}]);
        json["samplers"] = serde_json::json!([{"wrapS": wrap, "wrapT": wrap}]);
        json["images"] = serde_json::json!([{"uri": t.image}]);
    }
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

/// A PNG of `width` × `height` RGB values (row-major; `bottom_up`: the first row is the
/// image's bottom, as Blender keeps images). `srgb_bytes`: the values are an 8-bit sRGB image's
/// bytes / 255, kept exactly in an 8-bit PNG; otherwise they are linear and become a 16-bit
/// sRGB-encoded PNG (clamped to [0, 1]; not a number becomes 0). Either way the mesh loader
/// decodes the PNG from sRGB back to the same linear values.
pub fn png_rgb(
    width: u32,
    height: u32,
    rgb: &[f32],
    srgb_bytes: bool,
    bottom_up: bool,
) -> Result<Vec<u8>, String> {
    let (w, h) = (width as usize, height as usize);
    if rgb.len() != 3 * w * h {
        return Err(format!(
            "{} values for {width}×{height} RGB pixels",
            rgb.len()
        ));
    }
    let row = |y: usize| {
        let src = if bottom_up { h - 1 - y } else { y };
        &rgb[3 * w * src..3 * w * (src + 1)]
    };
    let unit = |v: f32| {
        if v.is_finite() {
            v.clamp(0.0, 1.0) as f64
        } else {
            0.0
        }
    };
    let mut png = Vec::new();
    let mut out = std::io::Cursor::new(&mut png);
    let done = if srgb_bytes {
        let px: Vec<u8> = (0..h)
            .flat_map(|y| row(y).iter().map(|&v| (unit(v) * 255.0).round() as u8))
            .collect();
        image::RgbImage::from_raw(width, height, px)
            .map(|i| i.write_to(&mut out, image::ImageFormat::Png))
    } else {
        let px: Vec<u16> = (0..h)
            .flat_map(|y| {
                row(y).iter().map(|&v| {
                    let v = unit(v);
                    let e = if v <= 0.0031308 {
                        12.92 * v
                    } else {
                        1.055 * v.powf(1.0 / 2.4) - 0.055
                    };
                    (e * 65535.0).round() as u16
                })
            })
            .collect();
        image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_raw(width, height, px)
            .map(|i| i.write_to(&mut out, image::ImageFormat::Png))
    };
    match done {
        Some(Ok(())) => Ok(png),
        Some(Err(e)) => Err(format!("writing the PNG: {e}")),
        None => Err("writing the PNG: wrong buffer size".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

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
    fn png_keeps_srgb_bytes_and_encodes_linear_values() {
        // 2 × 1 pixels, stored bottom-up: one row, so the flip is the identity here; a 1 × 2
        // image checks it.
        let px = [10.0 / 255.0, 128.0 / 255.0, 1.0, 0.0, 0.5, 2.0];
        let png = png_rgb(2, 1, &px, true, true).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.as_raw(), &vec![10, 128, 255, 0, 128, 255]);
        let png = png_rgb(1, 2, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], true, true).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(
            img.as_raw(),
            &vec![255, 255, 255, 0, 0, 0],
            "the top row first"
        );
        // Linear 0.5 → sRGB 0.7354 in 16 bits, decoded back by the texture code.
        let png = png_rgb(1, 1, &[0.5, 0.0, f32::NAN], false, false).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb16();
        let back = crate::geometry::meshfile::srgb_to_linear(img.as_raw()[0] as f64 / 65535.0);
        assert!((back - 0.5).abs() < 1e-4, "{back}");
        assert_eq!(img.as_raw()[1..], [0, 0]);
        assert!(png_rgb(2, 2, &px, true, false).is_err());
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
