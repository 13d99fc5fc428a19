//! The port housings Cycles renders: each camera's [`crate::optics::port::housing_shell`]
//! (built by the port's own file, as Mitsuba's and the glTF export's housings are) written as
//! two binary PLY assets in the camera frame, read by `poser_blender.geometry.read_ply`.
//!
//! | asset | content |
//! |---|---|
//! | `assets/housing_{camera}.ply` | the closed shell: the glass's outer face (tag 1) and the opaque body (tag 2), normals into the water |
//! | `assets/port_inner_{camera}.ply` | the glass's air side (tag 0), normals towards the camera |
//!
//! The layout, one fixed form (the reader refuses any other): binary little-endian; vertices
//! `double x, y, z` and, on curved glass, `double nx, ny, nz` (unit shading normals);
//! faces `list uint uint vertex_indices` (polygons, counter-clockwise seen from the side the
//! normals face) and `uchar tag`. Glass spheres are written in it too (`data.rs`): their
//! exact normals make Cycles refract as at the true sphere.

use super::data::Asset;
use crate::model::Model;
use crate::optics::port::{Face, TaggedMesh, housing_shell};
use serde_json::{Value, json};

/// Per camera, `{"shell": path, "inner": path}` or `null` without a port; the PLY files go to
/// `assets`.
pub fn housings_json(model: &Model, assets: &mut Vec<Asset>) -> Vec<Value> {
    model
        .cameras
        .iter()
        .enumerate()
        .map(|(i, cam)| {
            let Some(h) = housing_shell(cam) else {
                return Value::Null;
            };
            let shell = format!("assets/housing_{i}.ply");
            let inner = format!("assets/port_inner_{i}.ply");
            assets.push(Asset {
                path: shell.clone(),
                bytes: ply_bytes(&h.shell),
            });
            assets.push(Asset {
                path: inner.clone(),
                bytes: ply_bytes(&h.inner),
            });
            json!({"shell": shell, "inner": inner})
        })
        .collect()
}

/// A face's tag in the PLY (the builder's `geometry.INNER`, `GLASS_OUTER`, `BODY`).
fn tag(face: Face) -> u8 {
    match face {
        Face::Inner { .. } => 0,
        Face::Outer => 1,
        Face::Wall => 2,
    }
}

/// `mesh` as a binary PLY of the module's layout.
pub fn ply_bytes(mesh: &TaggedMesh) -> Vec<u8> {
    let normals = mesh.normals.as_deref();
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\ncomment poser housing, camera frame (m)\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n{}\
         element face {}\nproperty list uint uint vertex_indices\nproperty uchar tag\n\
         end_header\n",
        mesh.positions.len(),
        if normals.is_some() {
            "property double nx\nproperty double ny\nproperty double nz\n"
        } else {
            ""
        },
        mesh.faces.len()
    )
    .into_bytes();
    for (k, p) in mesh.positions.iter().enumerate() {
        let n = normals.map(|n| n[k].to_array());
        for c in p.to_array().iter().chain(n.iter().flatten()) {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for (f, &t) in mesh.faces.iter().zip(&mesh.tags) {
        out.extend_from_slice(&(f.len() as u32).to_le_bytes());
        for i in f {
            out.extend_from_slice(&i.to_le_bytes());
        }
        out.push(tag(t));
    }
    out
}
