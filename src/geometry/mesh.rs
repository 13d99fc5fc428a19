//! Triangle meshes for every scene shape, shared by all backends: glTF import (with node
//! transforms), analytic primitives tessellated (plane, box, sphere, cylinder), the procedural
//! `Seabed` heightfield and `Boulders` field, object pose and scale, the material patterns
//! evaluated in the object frame, and a deterministic PLY writer (binary or ASCII).
//!
//! | shape | parameters (object frame, metres) | tessellation |
//! |---|---|---|
//! | `Mesh` | a glTF 2.0 (`.glb`/`.gltf`), OBJ or PLY file ([`super::meshfile`]) | glTF: every triangle primitive of the default scene, node transforms applied, then the object's `offset` subtracted in the file's axes and its up axis turned to +Z ([`georeferenced`]; glTF's +Y-up by default: `(x, y, z)_gltf → (x, -z, y)`; OBJ, PLY: +Z up by default) |
//! | `Plane` | `width` (x) × `height` (y), centred, normal +z | 2 triangles |
//! | `Box` | `size` (x, y, z), centred | 12 triangles, outward normals |
//! | `Sphere` | `radius`, centred | UV sphere, [`SPHERE_SEGMENTS`] × [`SPHERE_SEGMENTS`]/2 |
//! | `Cylinder` | `radius`, `height` along z, centred, capped | [`CYLINDER_SEGMENTS`] sides |
//! | `Seabed` | `width` (x) × `length` (y) heightfield, cell `resolution`, relief RMS `roughness`, `seed`, on the spline through `relief`'s heights ([`super::relief`]) | grid of ⌈width/resolution⌉ × ⌈length/resolution⌉ cells, ≤ [`MAX_SEABED_CELLS`] |
//! | `Boulders` | `count` rocks of mean radius `radius` in `width` × `length`, `seed` | subdivided icosahedra, radii 0.6–1.4 × `radius`, squashed, half buried at z = 0 |
//! | `Coral` | `growth` (branching or massive), colony `radius`, `seed` | a signed distance field polygonised by marching tetrahedra ([`super::coral`]) |
//!
//! Normals are geometric (flat per triangle, from the winding: counter-clockwise seen from the
//! outside). The object transform is `world = pose · (scale ⊙ local)`; a mirroring scale flips
//! the winding so that normals stay outward. Every procedural shape is a pure function of its
//! parameters and seed: the same scene gives the same bytes.

use crate::model::{Object, Pose, Shape, UpAxis};
use crate::noise::{hash_unit, mix64, value_noise3};
use glam::DVec3;
use std::path::Path;

/// Longitude segments of a tessellated sphere (latitude rings: half of it).
pub const SPHERE_SEGMENTS: u32 = 64;
/// Side segments of a tessellated cylinder.
pub const CYLINDER_SEGMENTS: u32 = 64;
/// Largest seabed grid (cells) accepted.
pub const MAX_SEABED_CELLS: u64 = 4_000_000;

/// An indexed triangle mesh (f64 positions).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    /// Vertex indices, counter-clockwise seen from the outside.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Append another mesh.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// This mesh with `world = pose · (scale ⊙ p)` applied to every vertex.
    pub fn transformed(&self, pose: &Pose, scale: DVec3) -> TriMesh {
        let positions = self
            .positions
            .iter()
            .map(|&p| pose.transform_point(p * scale))
            .collect();
        let mirror = (scale.x * scale.y * scale.z) < 0.0;
        let triangles = if mirror {
            self.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
        } else {
            self.triangles.clone()
        };
        TriMesh {
            positions,
            triangles,
        }
    }

    /// Two triangles per cell, counter-clockwise seen from +z, for a mesh whose vertices are a
    /// grid of `(nx + 1) × (ny + 1)` points pushed row by row (x fastest).
    pub fn triangulate_grid(&mut self, nx: u32, ny: u32) {
        let idx = |i: u32, j: u32| j * (nx + 1) + i;
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1));
                self.triangles.push([a, b, d]);
                self.triangles.push([a, d, c]);
            }
        }
    }

    /// The enclosed volume, m³ (divergence theorem): positive when the triangles face
    /// outwards: the check of a closed mesh's orientation.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Axis-aligned bounds `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Total surface area, m².
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Unit geometric normal of triangle `i` (zero for a degenerate triangle).
    pub fn face_normal(&self, i: usize) -> DVec3 {
        let [a, b, c] = self.triangles[i].map(|k| self.positions[k as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }
}

/// The mesh of an object in the **world frame** (pose and scale applied). `base_dir` resolves a
/// relative glTF path (the scene file's directory).
pub fn object_mesh(object: &Object, base_dir: &Path) -> Result<TriMesh, String> {
    let local = shape_mesh(&object.shape, base_dir)
        .map_err(|e| format!("object `{}`: {e}", object.name))?;
    Ok(local.transformed(&object.pose, object.scale))
}

/// The mesh of a shape in its own (object) frame, before scale and pose.
pub fn shape_mesh(shape: &Shape, base_dir: &Path) -> Result<TriMesh, String> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(format!("{name} must be a positive finite number (got {v})"))
        }
    };
    match *shape {
        Shape::Mesh {
            ref path,
            offset,
            up_axis,
            ..
        } => {
            let full = mesh_file_path(path, base_dir);
            let mut m = super::meshfile::load_geometry(&full, &[base_dir.to_path_buf()])?;
            georeferenced(&mut m, super::meshfile::Format::of(&full), offset, up_axis);
            Ok(m)
        }
        Shape::Plane { width, height } => {
            positive("plane width", width)?;
            positive("plane height", height)?;
            Ok(plane(width, height))
        }
        Shape::Box { size } => {
            positive("box size x", size.x)?;
            positive("box size y", size.y)?;
            positive("box size z", size.z)?;
            Ok(cuboid(size))
        }
        Shape::Sphere { radius } => {
            positive("sphere radius", radius)?;
            Ok(sphere(radius, SPHERE_SEGMENTS))
        }
        Shape::Cylinder { radius, height } => {
            positive("cylinder radius", radius)?;
            positive("cylinder height", height)?;
            Ok(cylinder(radius, height, CYLINDER_SEGMENTS))
        }
        Shape::Seabed {
            width,
            length,
            roughness,
            resolution,
            seed,
            ref relief,
        } => {
            positive("seabed width", width)?;
            positive("seabed length", length)?;
            positive("seabed resolution", resolution)?;
            if !(roughness.is_finite() && roughness >= 0.0) {
                return Err(format!("seabed roughness must be ≥ 0 (got {roughness})"));
            }
            let relief = if relief.is_empty() {
                None
            } else {
                Some(super::relief::Relief::through(relief)?)
            };
            seabed(width, length, roughness, resolution, seed, relief.as_ref())
        }
        Shape::Boulders {
            width,
            length,
            count,
            radius,
            seed,
        } => {
            positive("boulder field width", width)?;
            positive("boulder field length", length)?;
            positive("boulder radius", radius)?;
            Ok(boulders(width, length, count, radius, seed))
        }
        Shape::Coral {
            growth,
            radius,
            seed,
        } => {
            positive("coral radius", radius)?;
            let growth = match growth {
                crate::model::CoralGrowth::Branching => super::coral::Growth::Branching,
                crate::model::CoralGrowth::Massive => super::coral::Growth::Massive,
            };
            Ok(super::coral::coral(growth, radius, seed))
        }
    }
}

/// The file of a mesh shape's `path`, resolved against `base_dir` when relative.
pub fn mesh_file_path(path: &str, base_dir: &Path) -> std::path::PathBuf {
    let p = Path::new(path);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base_dir.join(p)
    }
}

/// A point as the reader of `format` returned it (glTF turned to +Z up) → in the file's own
/// axes, exactly (a permutation and a sign).
pub fn file_axes(q: DVec3, format: Option<super::meshfile::Format>) -> DVec3 {
    match format {
        Some(super::meshfile::Format::Gltf) => DVec3::new(q.x, q.z, -q.y),
        _ => q,
    }
}

/// A point in the file's own axes turned so that `up` points along +Z (exact).
pub fn up_turned(p: DVec3, up: UpAxis) -> DVec3 {
    match up {
        UpAxis::Z => p,
        UpAxis::Y => DVec3::new(p.x, -p.z, p.y),
    }
}

/// The up axis of a mesh file: `up` when given, else the format's own (glTF +Y, OBJ and PLY
/// +Z).
pub fn up_of(up: Option<UpAxis>, format: Option<super::meshfile::Format>) -> UpAxis {
    up.unwrap_or(match format {
        Some(super::meshfile::Format::Gltf) => UpAxis::Y,
        _ => UpAxis::Z,
    })
}

/// A mesh file's vertices (as [`super::meshfile`] read them, in f64) brought into the object
/// frame: in the file's own axes, `offset` subtracted (f64), then turned so that the file's
/// `up` axis is +Z. The object's scale and pose come after ([`TriMesh::transformed`]). A
/// turn is a rotation: the winding, hence the normals, stay outward.
pub fn georeferenced(
    m: &mut TriMesh,
    format: Option<super::meshfile::Format>,
    offset: DVec3,
    up: Option<UpAxis>,
) {
    let up = up_of(up, format);
    for p in &mut m.positions {
        *p = up_turned(file_axes(*p, format) - offset, up);
    }
}

// ------------------------------------------------------------------------------------------
// Primitives
// ------------------------------------------------------------------------------------------

/// Rectangle `width`×`height` in the xy plane, centred, normal +z.
pub fn plane(width: f64, height: f64) -> TriMesh {
    let (hx, hy) = (0.5 * width, 0.5 * height);
    TriMesh {
        positions: vec![
            DVec3::new(-hx, -hy, 0.0),
            DVec3::new(hx, -hy, 0.0),
            DVec3::new(hx, hy, 0.0),
            DVec3::new(-hx, hy, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Axis-aligned box of the given full size, centred, outward normals.
pub fn cuboid(size: DVec3) -> TriMesh {
    let h = 0.5 * size;
    let mut m = TriMesh::default();
    // Each face: (normal axis, sign); four corners counter-clockwise seen from outside.
    for axis in 0..3 {
        for sign in [-1.0f64, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f64, b: f64| {
                let mut p = [0.0; 3];
                p[axis] = sign * h[axis];
                p[u] = a * h[u];
                p[v] = b * h[v];
                DVec3::from_array(p)
            };
            let base = m.positions.len() as u32;
            m.positions.extend([
                corner(-1., -1.),
                corner(1., -1.),
                corner(1., 1.),
                corner(-1., 1.),
            ]);
            // (u, v, axis) is right-handed, so u×v = +axis: CCW for sign +, reversed for −.
            if sign > 0.0 {
                m.triangles
                    .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            } else {
                m.triangles
                    .extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]);
            }
        }
    }
    m
}

/// UV sphere with `seg` longitude segments and `seg/2` latitude rings.
pub fn sphere(radius: f64, seg: u32) -> TriMesh {
    let rings = (seg / 2).max(2);
    let seg = seg.max(3);
    let mut m = TriMesh::default();
    m.positions.push(DVec3::new(0.0, 0.0, radius));
    for r in 1..rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..seg {
            let ph = std::f64::consts::TAU * s as f64 / seg as f64;
            m.positions
                .push(radius * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    m.positions.push(DVec3::new(0.0, 0.0, -radius));
    let south = m.positions.len() as u32 - 1;
    let ring = |r: u32, s: u32| 1 + (r - 1) * seg + (s % seg);
    for s in 0..seg {
        m.triangles.push([0, ring(1, s), ring(1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..seg {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s),
                ring(r + 1, s + 1),
            );
            m.triangles.push([a, c, d]);
            m.triangles.push([a, d, b]);
        }
    }
    for s in 0..seg {
        m.triangles
            .push([south, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    m
}

/// Capped cylinder of `radius` along z, total `height`, centred.
pub fn cylinder(radius: f64, height: f64, seg: u32) -> TriMesh {
    let seg = seg.max(3);
    let h = 0.5 * height;
    let mut m = TriMesh::default();
    for s in 0..seg {
        let ph = std::f64::consts::TAU * s as f64 / seg as f64;
        let (x, y) = (radius * ph.cos(), radius * ph.sin());
        m.positions.push(DVec3::new(x, y, -h));
        m.positions.push(DVec3::new(x, y, h));
    }
    let top = m.positions.len() as u32;
    m.positions.push(DVec3::new(0.0, 0.0, h));
    m.positions.push(DVec3::new(0.0, 0.0, -h));
    let bottom = top + 1;
    for s in 0..seg {
        let (b0, t0) = (2 * s, 2 * s + 1);
        let (b1, t1) = (2 * ((s + 1) % seg), 2 * ((s + 1) % seg) + 1);
        m.triangles.push([b0, b1, t1]);
        m.triangles.push([b0, t1, t0]);
        m.triangles.push([top, t0, t1]);
        m.triangles.push([bottom, b1, b0]);
    }
    m
}

// ------------------------------------------------------------------------------------------
// Procedural shapes
// ------------------------------------------------------------------------------------------

/// Fractal heightfield: ⌈width/resolution⌉ × ⌈length/resolution⌉ cells on the xy plane,
/// heights of zero mean and RMS exactly `roughness`, added to `relief` (the surveyed heights'
/// spline) where there is one.
pub fn seabed(
    width: f64,
    length: f64,
    roughness: f64,
    resolution: f64,
    seed: u64,
    relief: Option<&super::relief::Relief>,
) -> Result<TriMesh, String> {
    let nx = (width / resolution).ceil().max(1.0);
    let ny = (length / resolution).ceil().max(1.0);
    if nx * ny > MAX_SEABED_CELLS as f64 {
        return Err(format!(
            "seabed of {width} m × {length} m at {resolution} m cells has {:.0} cells (the limit is \
             {MAX_SEABED_CELLS}); use a coarser resolution",
            nx * ny
        ));
    }
    let (nx, ny) = (nx as u32, ny as u32);
    // Octaves from a base wavelength of a quarter of the larger side down to two cells.
    let base = 0.25 * width.max(length);
    let height = |i: u32, j: u32| {
        let x = -0.5 * width + width * i as f64 / nx as f64;
        let y = -0.5 * length + length * j as f64 / ny as f64;
        let mut h = 0.0;
        let mut wl = base;
        let mut amp = 1.0;
        let mut octave = 0u64;
        while wl >= 2.0 * resolution || octave == 0 {
            let s = mix64(seed.wrapping_add(octave));
            h += amp * value_noise3(s, DVec3::new(x / wl, y / wl, 0.5));
            wl *= 0.5;
            amp *= 0.5;
            octave += 1;
            if octave > 24 {
                break;
            }
        }
        h
    };
    // Rows in parallel (a 20 × 7 m seabed at 1 cm is 1.4 M vertices of ten octaves each: a
    // second of one core); each vertex's height is a pure function of (i, j), and rayon's
    // `collect` keeps the rows' order, so the mesh is the same for any thread count.
    use rayon::prelude::*;
    let heights: Vec<f64> = (0..=ny)
        .into_par_iter()
        .flat_map_iter(|j| (0..=nx).map(move |i| height(i, j)))
        .collect();
    let n = heights.len() as f64;
    let mean = heights.iter().sum::<f64>() / n;
    let rms = (heights.iter().map(|h| (h - mean) * (h - mean)).sum::<f64>() / n).sqrt();
    let k = if rms > 0.0 { roughness / rms } else { 0.0 };
    let mut m = TriMesh::default();
    for j in 0..=ny {
        for i in 0..=nx {
            let x = -0.5 * width + width * i as f64 / nx as f64;
            let y = -0.5 * length + length * j as f64 / ny as f64;
            let mut h = (heights[(j * (nx + 1) + i) as usize] - mean) * k;
            if let Some(r) = relief {
                h += r.height(x, y);
            }
            m.positions.push(DVec3::new(x, y, h));
        }
    }
    m.triangulate_grid(nx, ny);
    Ok(m)
}

/// Icosahedron subdivided `levels` times, on the unit sphere.
fn icosphere(levels: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<DVec3> = [
        (-1., t, 0.),
        (1., t, 0.),
        (-1., -t, 0.),
        (1., -t, 0.),
        (0., -1., t),
        (0., 1., t),
        (0., -1., -t),
        (0., 1., -t),
        (t, 0., -1.),
        (t, 0., 1.),
        (-t, 0., -1.),
        (-t, 0., 1.),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut cache = std::collections::BTreeMap::new();
        let mut mid = |a: u32, b: u32, pos: &mut Vec<DVec3>| {
            let key = (a.min(b), a.max(b));
            *cache.entry(key).or_insert_with(|| {
                pos.push((pos[a as usize] + pos[b as usize]).normalize());
                pos.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = mid(a, b, &mut pos);
            let bc = mid(b, c, &mut pos);
            let ca = mid(c, a, &mut pos);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    TriMesh {
        positions: pos,
        triangles: tris,
    }
}

/// `count` lumpy rocks scattered uniformly in `width`×`length`, half buried at z = 0.
pub fn boulders(width: f64, length: f64, count: u32, radius: f64, seed: u64) -> TriMesh {
    let unit = icosphere(3);
    let mut m = TriMesh::default();
    for k in 0..count as i64 {
        let r = |slot: i64| hash_unit(seed, k, slot, 0x0B0D);
        let c = DVec3::new((r(0) - 0.5) * width, (r(1) - 0.5) * length, 0.0);
        let rad = radius * (0.6 + 0.8 * r(2));
        let squash = 0.5 + 0.3 * r(3);
        let (s, co) = (std::f64::consts::TAU * r(4)).sin_cos();
        let rock_seed = mix64(seed ^ mix64(k as u64));
        let mut rock = unit.clone();
        for p in &mut rock.positions {
            let bump = 1.0 + 0.25 * value_noise3(rock_seed, *p * 2.0);
            let q = *p * bump * rad;
            let q = DVec3::new(co * q.x - s * q.y, s * q.x + co * q.y, q.z * squash);
            *p = c + q;
        }
        m.append(&rock);
    }
    m
}

// ------------------------------------------------------------------------------------------
// glTF
// ------------------------------------------------------------------------------------------

/// Load every triangle primitive of a glTF 2.0 file (default scene, or the first), with node
/// transforms applied, converted from glTF's Y-up to poser's Z-up: the geometry of
/// [`super::meshfile::read_gltf`].
pub fn load_gltf(path: &Path) -> Result<TriMesh, String> {
    let bytes = super::meshfile::read_mesh(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(super::meshfile::read_gltf(&bytes, path, &[dir], false)?.mesh)
}

// ------------------------------------------------------------------------------------------
// PLY
// ------------------------------------------------------------------------------------------

/// PLY encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyFormat {
    BinaryLittleEndian,
    Ascii,
}

/// Encode a mesh as PLY: `float x, y, z` per vertex and `uchar`-counted `int` index lists.
/// Deterministic bytes (no timestamps; fixed number formatting).
pub fn ply_bytes(mesh: &TriMesh, format: PlyFormat) -> Vec<u8> {
    let fmt = match format {
        PlyFormat::BinaryLittleEndian => "binary_little_endian",
        PlyFormat::Ascii => "ascii",
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\ncomment poser mesh\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    match format {
        PlyFormat::BinaryLittleEndian => {
            out.reserve(mesh.positions.len() * 12 + mesh.triangles.len() * 13);
            for p in &mesh.positions {
                for c in p.to_array() {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
            for t in &mesh.triangles {
                out.push(3);
                for i in t {
                    out.extend_from_slice(&(*i as i32).to_le_bytes());
                }
            }
        }
        PlyFormat::Ascii => {
            use std::fmt::Write;
            let mut s = String::new();
            for p in &mesh.positions {
                let _ = writeln!(s, "{} {} {}", p.x as f32, p.y as f32, p.z as f32);
            }
            for t in &mesh.triangles {
                let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
            }
            out.extend_from_slice(s.as_bytes());
        }
    }
    out
}

/// Write a mesh as a PLY file atomically.
pub fn write_ply(path: &Path, mesh: &TriMesh, format: PlyFormat) -> Result<(), String> {
    crate::io::write_atomic(path, &ply_bytes(mesh, format))
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_primitives_have_outward_normals_and_right_volume() {
        let b = cuboid(DVec3::new(1.0, 2.0, 3.0));
        assert!((b.signed_volume() - 6.0).abs() < 1e-12);
        assert!((b.area() - 22.0).abs() < 1e-12);
        // Tessellated sphere/cylinder volumes fall short of the analytic ones by the chord error
        // (< 1 % at 64 segments: 1 - sin(2π/64)/(2π/64) ≈ 0.16 % per ring, summed ≈ 0.5 %).
        let s = sphere(1.0, SPHERE_SEGMENTS);
        let v = s.signed_volume() / (4.0 / 3.0 * std::f64::consts::PI);
        assert!(v > 0.99 && v < 1.0, "{v}");
        let c = cylinder(0.5, 2.0, CYLINDER_SEGMENTS);
        let v = c.signed_volume() / (std::f64::consts::PI * 0.25 * 2.0);
        assert!(v > 0.99 && v < 1.0, "{v}");
    }

    #[test]
    fn plane_faces_up_and_mirror_keeps_outward() {
        let p = plane(2.0, 1.0);
        assert_eq!(p.face_normal(0), DVec3::Z);
        let b = cuboid(DVec3::ONE).transformed(&Pose::IDENTITY, DVec3::new(-1.0, 1.0, 1.0));
        assert!(b.signed_volume() > 0.0);
    }

    #[test]
    fn seabed_is_deterministic_with_exact_rms() {
        let a = seabed(10.0, 6.0, 0.2, 0.1, 7, None).unwrap();
        let b = seabed(10.0, 6.0, 0.2, 0.1, 7, None).unwrap();
        let c = seabed(10.0, 6.0, 0.2, 0.1, 8, None).unwrap();
        assert_eq!(a, b);
        // Its rows are computed in parallel: the same mesh, bit for bit, on one thread.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let serial = one.install(|| seabed(10.0, 6.0, 0.2, 0.1, 7, None).unwrap());
        assert!(
            a.positions
                .iter()
                .zip(&serial.positions)
                .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits))
        );
        assert_eq!(a.triangles, serial.triangles);
        assert_ne!(a, c);
        let n = a.positions.len() as f64;
        let rms = (a.positions.iter().map(|p| p.z * p.z).sum::<f64>() / n).sqrt();
        assert!((rms - 0.2).abs() < 1e-9, "{rms}");
        assert_eq!(a.triangles.len(), 2 * 100 * 60);
        assert!(seabed(1e4, 1e4, 0.1, 0.001, 1, None).is_err());
    }

    #[test]
    fn boulders_lie_in_their_field() {
        let m = boulders(4.0, 3.0, 10, 0.2, 3);
        let (lo, hi) = m.bounds().unwrap();
        assert!(lo.x > -2.0 - 0.4 && hi.x < 2.0 + 0.4 && lo.y > -1.5 - 0.4 && hi.y < 1.5 + 0.4);
        assert!(hi.z > 0.0 && lo.z < 0.0);
        assert_eq!(m, boulders(4.0, 3.0, 10, 0.2, 3));
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn ply_header_and_sizes() {
        let m = cuboid(DVec3::ONE);
        let b = ply_bytes(&m, PlyFormat::BinaryLittleEndian);
        let s = String::from_utf8_lossy(&b);
        let end = s.find("end_header\n").unwrap() + "end_header\n".len();
        assert_eq!(b.len() - end, 24 * 12 + 12 * 13);
        assert!(s.starts_with("ply\nformat binary_little_endian 1.0\n"));
        let a = String::from_utf8(ply_bytes(&m, PlyFormat::Ascii)).unwrap();
        assert_eq!(a.lines().count(), 10 + 24 + 12);
        assert!(a.ends_with("3 20 22 23\n"));
    }
}
