//! Procedural corals: a branching colony (staghorn-like) and a massive one (brain-like dome),
//! each a pure function of its radius and seed, polygonised from a signed distance field into
//! one closed, consistently wound triangle mesh (every edge shared by exactly two triangles,
//! in opposite directions; normals outward).
//!
//! | growth | field (object frame, z up, cut flat at z = −[`BURIED`] · `radius`: the buried base) | grid cell |
//! |---|---|---|
//! | `branching` | union of capsules: a trunk of radius 0.1 `radius` rising 0.2 `radius`, then [`LEVELS`] − 1 levels of 2 or 3 children each (even odds), 20–45° off their parent and at least 15° above the horizontal, 0.7–0.9 × as long (at most 0.3 `radius`) and 0.75 × as thick | `radius` / [`BRANCHING_CELLS`] |
//! | `massive` | a dome: the ellipsoid of semi-axes (1, 1, 0.7) · `radius`, lumps of 6 % and meandering grooves of 1.5 % of `radius` (value noise), cut flat at the base | `radius` / [`MASSIVE_CELLS`] |
//!
//! The surface is the zero level of the field, polygonised by marching tetrahedra (six per
//! grid cube, the Kuhn split shared by neighbouring cubes, so the mesh has no cracks; vertices
//! on grid edges are shared). Each triangle is wound so that its normal points from the inside
//! corners of its tetrahedron to the outside ones. The colony stands on the object's xy plane:
//! z = 0 is where the substrate is; the part below it (the base) is buried.

use super::mesh::TriMesh;
use crate::noise::{mix64, value_noise3};
use glam::DVec3;
use std::collections::HashMap;

/// Branching levels (the trunk is level 1).
pub const LEVELS: u32 = 5;
/// Grid cells per `radius` of a branching colony.
pub const BRANCHING_CELLS: f64 = 64.0;
/// Grid cells per `radius` of a massive colony.
pub const MASSIVE_CELLS: f64 = 40.0;
/// Depth of the buried base, in units of `radius`.
pub const BURIED: f64 = 0.05;

/// The growth form of a coral colony.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Growth {
    Branching,
    Massive,
}

/// A branch: a capsule from `a` to `b` of radius `r`.
#[derive(Debug, Clone, Copy)]
struct Capsule {
    a: DVec3,
    b: DVec3,
    r: f64,
}

impl Capsule {
    fn distance(&self, p: DVec3) -> f64 {
        let ab = self.b - self.a;
        let t = ((p - self.a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        (p - (self.a + t * ab)).length() - self.r
    }
}

/// Uniform in [0, 1) from `seed` and a slot.
fn unit(seed: u64, slot: u64) -> f64 {
    (mix64(seed ^ mix64(slot)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The capsules of a branching colony of `radius`.
fn branches(radius: f64, seed: u64) -> Vec<Capsule> {
    let mut out = Vec::new();
    // (start, direction, length, radius, level, id)
    let mut stack = vec![(
        DVec3::new(0.0, 0.0, -BURIED * radius),
        DVec3::Z,
        0.2 * radius + BURIED * radius,
        0.1 * radius,
        1u32,
        1u64,
    )];
    while let Some((a, dir, len, r, level, id)) = stack.pop() {
        let b = a + dir * len;
        out.push(Capsule { a, b, r });
        if level >= LEVELS {
            continue;
        }
        let s = mix64(seed ^ mix64(id));
        let n = if unit(s, 0) < 0.5 { 3 } else { 2 };
        // A frame around the parent's direction.
        let u = if dir.z.abs() < 0.9 {
            dir.cross(DVec3::Z).normalize()
        } else {
            dir.cross(DVec3::X).normalize()
        };
        let v = dir.cross(u);
        let phase = std::f64::consts::TAU * unit(s, 1);
        for k in 0..n {
            let az = phase + std::f64::consts::TAU * (k as f64 + 0.3 * unit(s, 10 + k)) / n as f64;
            let tilt = (20.0 + 25.0 * unit(s, 20 + k)).to_radians();
            let mut d = dir * tilt.cos() + (u * az.cos() + v * az.sin()) * tilt.sin();
            // Corals grow towards the light: never below 15° above the horizontal.
            let min_z = 15f64.to_radians().sin();
            if d.z < min_z {
                let h = DVec3::new(d.x, d.y, 0.0).normalize_or_zero();
                d = h * min_z.acos().sin() + DVec3::Z * min_z;
            }
            let child_len = len.min(0.3 * radius) * (0.7 + 0.2 * unit(s, 30 + k));
            stack.push((b, d.normalize(), child_len, 0.75 * r, level + 1, id * 4 + k));
        }
    }
    out
}

/// The signed distance field of a massive colony (approximate distance, exact sign).
fn massive_field(radius: f64, seed: u64, p: DVec3) -> f64 {
    let axes = DVec3::new(1.0, 1.0, 0.7) * radius;
    let q = p / axes;
    let dome = (q.length() - 1.0) * 0.7 * radius;
    let s = p / radius;
    let lumps = 0.06 * radius * value_noise3(seed, s * 3.0);
    let grooves = 0.015 * radius * (1.0 - 2.0 * value_noise3(mix64(seed), s * 12.0).abs());
    let body = dome - lumps - grooves;
    body.max(-(p.z + BURIED * radius))
}

/// The mesh of a coral colony of `radius` (m) and `growth`, from `seed`.
pub fn coral(growth: Growth, radius: f64, seed: u64) -> TriMesh {
    match growth {
        Growth::Branching => {
            let caps = branches(radius, seed);
            let h = radius / BRANCHING_CELLS;
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for c in &caps {
                lo = lo.min(c.a.min(c.b) - DVec3::splat(c.r));
                hi = hi.max(c.a.max(c.b) + DVec3::splat(c.r));
            }
            let mut g = Grid::new(lo, hi, h);
            // Each capsule lowers the field in its own box only.
            for c in &caps {
                let (i0, _) = g.range(c.a.min(c.b) - DVec3::splat(c.r + 2.0 * h));
                let (_, j1) = g.range(c.a.max(c.b) + DVec3::splat(c.r + 2.0 * h));
                for z in i0[2]..=j1[2] {
                    for y in i0[1]..=j1[1] {
                        for x in i0[0]..=j1[0] {
                            let k = g.index(x, y, z);
                            let d = c.distance(g.point(x, y, z));
                            if d < g.values[k] {
                                g.values[k] = d;
                            }
                        }
                    }
                }
            }
            // Cut flat at the base, like the massive colony.
            for z in 0..g.n[2] {
                let cut = -(g.point(0, 0, z).z + BURIED * radius);
                for k in g.index(0, 0, z)..g.index(0, 0, z + 1) {
                    g.values[k] = g.values[k].max(cut);
                }
            }
            g.polygonise()
        }
        Growth::Massive => {
            let h = radius / MASSIVE_CELLS;
            let lo = DVec3::new(-1.2, -1.2, -BURIED - 0.1) * radius;
            let hi = DVec3::new(1.2, 1.2, 0.9) * radius;
            let mut g = Grid::new(lo, hi, h);
            for z in 0..g.n[2] {
                for y in 0..g.n[1] {
                    for x in 0..g.n[0] {
                        let k = g.index(x, y, z);
                        g.values[k] = massive_field(radius, seed, g.point(x, y, z));
                    }
                }
            }
            g.polygonise()
        }
    }
}

/// Field samples on a regular grid; outside the grid the field is positive.
struct Grid {
    origin: DVec3,
    h: f64,
    /// Nodes per axis.
    n: [usize; 3],
    values: Vec<f64>,
}

impl Grid {
    /// A grid covering `[lo, hi]` with a margin of two cells, every value "far outside".
    fn new(lo: DVec3, hi: DVec3, h: f64) -> Grid {
        let origin = lo - DVec3::splat(2.0 * h);
        let ext = hi - lo + DVec3::splat(4.0 * h);
        let n = [0, 1, 2].map(|i| (ext[i] / h).ceil() as usize + 1);
        Grid {
            origin,
            h,
            n,
            values: vec![f64::MAX; n[0] * n[1] * n[2]],
        }
    }

    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.n[1] + y) * self.n[0] + x
    }

    fn point(&self, x: usize, y: usize, z: usize) -> DVec3 {
        self.origin + self.h * DVec3::new(x as f64, y as f64, z as f64)
    }

    /// The grid nodes (clamped to the grid) just below and just above `p`, per axis.
    fn range(&self, p: DVec3) -> ([usize; 3], [usize; 3]) {
        let f = (p - self.origin) / self.h;
        let lo = [0, 1, 2].map(|i| (f[i].floor().max(0.0) as usize).min(self.n[i] - 1));
        let hi = [0, 1, 2].map(|i| (f[i].ceil().max(0.0) as usize).min(self.n[i] - 1));
        (lo, hi)
    }

    /// Marching tetrahedra over every cube (inside: value < 0).
    fn polygonise(&self) -> TriMesh {
        // The six tetrahedra of the Kuhn split: paths 0 → 7 through the cube corners (corner
        // bit 0 = +x, bit 1 = +y, bit 2 = +z).
        const TETS: [[usize; 4]; 6] = [
            [0, 1, 3, 7],
            [0, 1, 5, 7],
            [0, 2, 3, 7],
            [0, 2, 6, 7],
            [0, 4, 5, 7],
            [0, 4, 6, 7],
        ];
        let mut mesh = TriMesh::default();
        let mut shared: HashMap<(usize, usize), u32> = HashMap::new();
        let [nx, ny, nz] = self.n;
        for z in 0..nz - 1 {
            for y in 0..ny - 1 {
                for x in 0..nx - 1 {
                    let corner = |c: usize| (x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
                    let idx: [usize; 8] = std::array::from_fn(|c| {
                        let (a, b, d) = corner(c);
                        self.index(a, b, d)
                    });
                    let val: [f64; 8] = idx.map(|k| self.values[k]);
                    let inside = val.iter().filter(|v| **v < 0.0).count();
                    if inside == 0 || inside == 8 {
                        continue;
                    }
                    for t in TETS {
                        self.tetrahedron(t.map(|c| (idx[c], corner(c))), &mut mesh, &mut shared);
                    }
                }
            }
        }
        mesh
    }

    fn tetrahedron(
        &self,
        corners: [(usize, (usize, usize, usize)); 4],
        mesh: &mut TriMesh,
        shared: &mut HashMap<(usize, usize), u32>,
    ) {
        let pos = |c: (usize, (usize, usize, usize))| self.point(c.1.0, c.1.1, c.1.2);
        let (ins, outs): (Vec<_>, Vec<_>) = corners
            .iter()
            .copied()
            .partition(|c| self.values[c.0] < 0.0);
        if ins.is_empty() || outs.is_empty() {
            return;
        }
        let mut vertex = |i: (usize, (usize, usize, usize)), o: (usize, (usize, usize, usize))| {
            *shared.entry((i.0, o.0)).or_insert_with(|| {
                let (vi, vo) = (self.values[i.0], self.values[o.0]);
                let t = vi / (vi - vo);
                mesh.positions.push(pos(i) + t * (pos(o) - pos(i)));
                mesh.positions.len() as u32 - 1
            })
        };
        // The polygon's corners as (inside corner, outside corner) edges, in cyclic order.
        let edges: Vec<_> = match (ins.len(), outs.len()) {
            (1, 3) => outs.iter().map(|&o| (ins[0], o)).collect(),
            (3, 1) => ins.iter().map(|&i| (i, outs[0])).collect(),
            _ => vec![
                (ins[0], outs[0]),
                (ins[0], outs[1]),
                (ins[1], outs[1]),
                (ins[1], outs[0]),
            ],
        };
        let polygon: Vec<u32> = edges.iter().map(|&(i, o)| vertex(i, o)).collect();
        // Winding from the edges' midpoints (never degenerate, unlike the interpolated
        // corners when a value is nearly 0): outward, from the inside corners towards the
        // outside ones.
        let mid: Vec<DVec3> = edges
            .iter()
            .map(|&(i, o)| 0.5 * (pos(i) + pos(o)))
            .collect();
        let centre = |cs: &[(usize, (usize, usize, usize))]| {
            cs.iter().map(|&c| pos(c)).sum::<DVec3>() / cs.len() as f64
        };
        let out_dir = centre(&outs) - centre(&ins);
        for k in 1..polygon.len() - 1 {
            let mut t = [polygon[0], polygon[k], polygon[k + 1]];
            if (mid[k] - mid[0]).cross(mid[k + 1] - mid[0]).dot(out_dir) < 0.0 {
                t.swap(1, 2);
            }
            mesh.triangles.push(t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every directed edge has its reverse exactly once: closed and consistently wound.
    fn closed_and_consistent(m: &TriMesh) -> bool {
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
    }

    #[test]
    fn corals_are_deterministic_closed_and_outward() {
        for growth in [Growth::Branching, Growth::Massive] {
            let m = coral(growth, 0.3, 7);
            assert_eq!(m, coral(growth, 0.3, 7), "{growth:?}");
            assert_ne!(m, coral(growth, 0.3, 8), "{growth:?}");
            assert!(
                m.triangles.len() > 1000,
                "{growth:?}: {}",
                m.triangles.len()
            );
            assert!(closed_and_consistent(&m), "{growth:?}");
            assert!(m.signed_volume() > 0.0, "{growth:?}");
            let (lo, hi) = m.bounds().unwrap();
            assert!(
                lo.z < 0.0 && lo.z > -0.3 * (BURIED + 0.05),
                "{growth:?} {lo}"
            );
            assert!(
                hi.z > 0.15 && hi.x < 0.5 && lo.x > -0.5,
                "{growth:?} {lo} {hi}"
            );
        }
    }

    #[test]
    fn a_branching_colony_is_airier_than_a_massive_one() {
        let vol_per_area = |g| {
            let m = coral(g, 0.3, 3);
            m.signed_volume() / m.area()
        };
        // Thin branches: little volume for their surface.
        assert!(vol_per_area(Growth::Branching) < 0.5 * vol_per_area(Growth::Massive));
    }
}
