//! A housing's geometry in the camera frame (metres, f64), for the backends and the glTF
//! export to draw: [`Housing`] (the exact glass surfaces and the black housing walls, as
//! primitives: what Mitsuba renders), [`HousingShell`] (the same as closed polygon meshes with
//! shading normals: what Cycles renders) and [`HousingMesh`] (a triangle mesh of the glass
//! shell, what the glTF export shows). Each port type builds all three in its own file
//! ([`super::flat`], [`super::dome`], [`super::cylinder`]); [`housing`], [`housing_shell`] and
//! [`housing_mesh`] dispatch on the [`Port`].

use super::{cylinder, dome, flat};
use crate::lens::Lens;
use crate::types::{Camera, Port, Pose};
use glam::{DMat3, DVec3};

/// Which interface a part of a housing is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// Air (inside the housing) | glass. `glass_inside`: the part's interior (the side its
    /// normal points away from; a sphere's or a cylinder's inside) is the glass.
    Inner { glass_inside: bool },
    /// Glass (the part's interior) | the water outside.
    Outer,
    /// The housing's opaque body, black on both sides.
    Wall,
}

/// One primitive of a housing, camera frame. Directions are unit vectors; a half-extent is
/// the unit direction times a length, kept apart so that a backend maps the direction first
/// and scales after.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// The rectangle `centre + shift.0·shift.1 + a·x.0·x.1 + b·y.0·y.1`, |a|, |b| ≤ 1, with the
    /// unit `normal`.
    Rectangle {
        centre: DVec3,
        shift: Option<(DVec3, f64)>,
        x: (DVec3, f64),
        y: (DVec3, f64),
        normal: DVec3,
    },
    /// A disk of `radius` about `centre` with the unit `normal`.
    Disk {
        centre: DVec3,
        normal: DVec3,
        radius: f64,
    },
    /// A whole sphere.
    Sphere { center: DVec3, radius: f64 },
    /// A cylinder's side from `p0` to `p1` (closed by [`Shape::Disk`] parts).
    Cylinder { p0: DVec3, p1: DVec3, radius: f64 },
}

/// One part of a housing and, for some, a label `(kind, what)` for a comment ("`kind` of
/// camera: `what`").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Part {
    pub face: Face,
    pub shape: Shape,
    pub label: Option<(&'static str, &'static str)>,
}

impl Part {
    pub(super) fn new(face: Face, shape: Shape) -> Part {
        Part {
            face,
            shape,
            label: None,
        }
    }

    pub(super) fn labelled(self, kind: &'static str, what: &'static str) -> Part {
        Part {
            label: Some((kind, what)),
            ..self
        }
    }
}

/// A closed housing: the port's glass surfaces and the black walls behind them.
#[derive(Debug, Clone, PartialEq)]
pub struct Housing {
    pub parts: Vec<Part>,
    /// Distance from the entrance pupil to the nearest glass, m.
    pub clearance: f64,
    /// Radius about the entrance pupil that contains the whole housing, m.
    pub extent: f64,
}

/// Why a port cannot be given a housing that covers the camera's field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HousingError {
    Flat(flat::HousingError),
    Dome(dome::HousingError),
    Cylinder(cylinder::HousingError),
}

impl std::fmt::Display for HousingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HousingError::Flat(e) => e.fmt(f),
            HousingError::Dome(e) => e.fmt(f),
            HousingError::Cylinder(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for HousingError {}

/// The housing of `cam`'s port (`None` without a port).
pub fn housing(cam: &Camera) -> Result<Option<Housing>, HousingError> {
    Ok(Some(match &cam.port {
        Port::None => return Ok(None),
        Port::Flat {
            normal,
            distance,
            thickness,
            ..
        } => flat::housing(cam, *normal, *distance, *thickness).map_err(HousingError::Flat)?,
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => dome::housing(cam, *center, *inner_radius, *thickness).map_err(HousingError::Dome)?,
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => cylinder::housing(cam, *axis_point, *axis, *inner_radius, *thickness)
            .map_err(HousingError::Cylinder)?,
    }))
}

/// A polygon mesh with a [`Face`] per polygon, camera frame (metres).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TaggedMesh {
    pub positions: Vec<DVec3>,
    /// Unit shading normals per vertex (curved glass, shaded smooth), or `None` (flat faces).
    pub normals: Option<Vec<DVec3>>,
    /// Polygons of vertex indices, counter-clockwise seen from the side the normals face.
    pub faces: Vec<Vec<u32>>,
    /// What each polygon is.
    pub tags: Vec<Face>,
}

impl TaggedMesh {
    /// Append a polygon.
    pub(super) fn push(&mut self, face: Vec<u32>, tag: Face) {
        self.faces.push(face);
        self.tags.push(tag);
    }
}

/// A housing as a mesh renderer draws it (Cycles), camera frame. `shell` is closed around the
/// camera with its normals pointing into the water: the port glass's outer face
/// ([`Face::Outer`]) and the opaque body ([`Face::Wall`]), sized so that every ray of the
/// field of view leaves through the glass. `inner` is the glass's air side
/// ([`Face::Inner`]), normals towards the camera. Curved glass is finely tessellated and
/// carries its exact normals, for smooth shading.
#[derive(Debug, Clone, PartialEq)]
pub struct HousingShell {
    pub shell: TaggedMesh,
    pub inner: TaggedMesh,
}

/// The closed housing of `cam`'s port as polygon meshes (`None` without a port).
pub fn housing_shell(cam: &Camera) -> Option<HousingShell> {
    Some(match &cam.port {
        Port::None => return None,
        Port::Flat {
            normal,
            distance,
            thickness,
            ..
        } => flat::housing_shell(cam, *normal, *distance, *thickness),
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => dome::housing_shell(cam, *center, *inner_radius, *thickness),
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => cylinder::housing_shell(cam, *axis_point, *axis, *inner_radius, *thickness),
    })
}

/// An indexed triangle mesh, camera frame (f64 positions; triangles counter-clockwise seen
/// from outside).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HousingMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl HousingMesh {
    /// This mesh with `pose` applied to every vertex.
    pub fn transformed(&self, pose: &Pose) -> HousingMesh {
        HousingMesh {
            positions: self
                .positions
                .iter()
                .map(|&p| pose.transform_point(p))
                .collect(),
            triangles: self.triangles.clone(),
        }
    }
}

/// Segments of the meshes of revolution of [`housing_mesh`].
pub const MESH_SEGMENTS: u32 = 48;

/// The glass shell of `cam`'s port as a triangle mesh, for display (`None` without a port):
/// flat = a disc of the radius the field of view needs and the glass's thickness (`n_water`:
/// the G channel's water index, for the exact rays through the sensor corners); dome = a
/// spherical cap shell; cylinder = a tube shell.
pub fn housing_mesh(cam: &Camera, n_water: f64) -> Option<HousingMesh> {
    Some(match &cam.port {
        Port::None => return None,
        Port::Flat {
            normal, distance, ..
        } => flat::housing_mesh(cam, *normal, *distance, n_water),
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => dome::housing_mesh(cam, *center, *inner_radius, *thickness),
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => cylinder::housing_mesh(cam, *axis_point, *axis, *inner_radius, *thickness),
    })
}

/// The surface swept by a profile of `(ρ, z)` points (ρ ≥ 0; ρ = 0 is one vertex on the axis)
/// turned about the z axis in `seg` steps; `closed` joins the last point to the first.
pub fn revolve(profile: &[(f64, f64)], closed: bool, seg: u32) -> HousingMesh {
    let seg = seg.max(3);
    let mut m = HousingMesh::default();
    // First vertex index of each profile point and whether it is on the axis.
    let mut rings = Vec::with_capacity(profile.len());
    for &(r, z) in profile {
        let start = m.positions.len() as u32;
        if r == 0.0 {
            m.positions.push(DVec3::new(0.0, 0.0, z));
            rings.push((start, true));
        } else {
            for s in 0..seg {
                let a = std::f64::consts::TAU * s as f64 / seg as f64;
                m.positions.push(DVec3::new(r * a.cos(), r * a.sin(), z));
            }
            rings.push((start, false));
        }
    }
    let n = profile.len();
    let pairs = if closed { n } else { n.saturating_sub(1) };
    for k in 0..pairs {
        let (a, pa) = rings[k];
        let (b, pb) = rings[(k + 1) % n];
        let at = |base: u32, pole: bool, s: u32| if pole { base } else { base + s % seg };
        for s in 0..seg {
            let (a0, a1) = (at(a, pa, s), at(a, pa, s + 1));
            let (b0, b1) = (at(b, pb, s), at(b, pb, s + 1));
            match (pa, pb) {
                (true, true) => {}
                (true, false) => m.triangles.push([a0, b1, b0]),
                (false, true) => m.triangles.push([a0, a1, b0]),
                (false, false) => {
                    m.triangles.push([a0, a1, b1]);
                    m.triangles.push([a0, b1, b0]);
                }
            }
        }
    }
    m
}

/// Two unit vectors completing the unit `n` to a right-handed basis `(e1, e2, n)`.
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let e1 = a.cross(n).normalize();
    let e2 = n.cross(e1);
    (e1, e2)
}

/// A rotation taking +z to the unit vector `a` (its columns: a right-handed basis of the
/// plane normal to `a`, then `a`).
pub fn z_to(a: DVec3) -> DMat3 {
    let z = a.normalize();
    let helper = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = helper.cross(z).normalize();
    let y = z.cross(x);
    DMat3::from_cols(x, y, z)
}

/// Camera-frame rays through the image border (32 pixel-edge samples per side), unit length:
/// the field of view a housing must cover (pinhole model).
pub(super) fn border_rays(cam: &Camera) -> Vec<DVec3> {
    let (w, h) = (cam.width as f64, cam.height as f64);
    let n = 32;
    let mut pts = Vec::with_capacity(4 * n);
    for k in 0..n {
        let s = k as f64 / n as f64;
        pts.push((s * w, 0.0));
        pts.push((w, s * h));
        pts.push((w - s * w, h));
        pts.push((0.0, h - s * h));
    }
    pts.into_iter()
        .map(|(u, v)| DVec3::new((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0).normalize())
        .collect()
}

/// Unit directions of the field of view from the pupil, camera frame, through the lens model:
/// the image centre and `per_side + 1` points along each edge (the sizes of
/// [`housing_shell`]'s shells). Points outside a fisheye's field are left out.
pub(super) fn field_directions(cam: &Camera, per_side: usize) -> Vec<DVec3> {
    let (w, h) = (cam.width as f64, cam.height as f64);
    let mut pts = vec![(0.5 * w, 0.5 * h)];
    for i in 0..=per_side {
        let s = i as f64 / per_side.max(1) as f64;
        pts.extend([(s * w, 0.0), (s * w, h), (0.0, s * h), (w, s * h)]);
    }
    unproject_all(cam, pts)
}

/// Unit directions of the field of view's border (corners and edge midpoints) from the pupil,
/// camera frame, through the lens model (for the display meshes).
pub(super) fn border_directions(cam: &Camera) -> Vec<DVec3> {
    let (w, h) = (cam.width as f64, cam.height as f64);
    unproject_all(
        cam,
        [
            (0.0, 0.0),
            (w, 0.0),
            (0.0, h),
            (w, h),
            (0.5 * w, 0.0),
            (0.5 * w, h),
            (0.0, 0.5 * h),
            (w, 0.5 * h),
        ],
    )
}

/// The unit camera-frame directions of the pixel positions `pts` through `cam`'s lens model,
/// in their order; positions outside the lens's field are left out.
fn unproject_all(cam: &Camera, pts: impl IntoIterator<Item = (f64, f64)>) -> Vec<DVec3> {
    let lens = Lens::from_camera(cam);
    pts.into_iter()
        .filter_map(|(u, v)| lens.unproject(u, v).ok())
        .map(DVec3::normalize)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Distortion, Glass, LensModel};
    use std::collections::HashMap;

    /// A small wide camera (a 94° diagonal field), principal point off centre.
    fn camera(port: Port, lens: LensModel) -> Camera {
        Camera {
            name: "c".into(),
            width: 160,
            height: 120,
            pixel_pitch: 1e-5,
            focal_length: 7.5e-4,
            fx: 75.0,
            fy: 75.0,
            cx: 83.7,
            cy: 57.2,
            lens,
            distortion: Distortion::default(),
            focus_distance: None,
            f_number: None,
            port,
            rig_from_camera: Pose::IDENTITY,
        }
    }

    fn ports() -> Vec<Port> {
        let glass = Glass {
            name: "custom".into(),
            ior: [1.5; 3],
        };
        vec![
            Port::Flat {
                normal: DVec3::Z,
                distance: 0.02,
                thickness: 0.01,
                glass: glass.clone(),
                outer_layers: vec![],
            },
            Port::Flat {
                normal: DVec3::new(0.0, 0.1f64.sin(), 0.1f64.cos()),
                distance: 0.05,
                thickness: 0.012,
                glass: glass.clone(),
                outer_layers: vec![],
            },
            Port::Dome {
                center: DVec3::new(0.001, -0.002, 0.004),
                inner_radius: 0.1,
                thickness: 0.01,
                glass: glass.clone(),
            },
            Port::Cylinder {
                axis_point: DVec3::new(0.002, 0.0, 0.0),
                axis: DVec3::Y,
                inner_radius: 0.08,
                thickness: 0.008,
                glass,
            },
        ]
    }

    fn triangles(m: &TaggedMesh) -> impl Iterator<Item = ([DVec3; 3], Face)> + '_ {
        m.faces.iter().zip(&m.tags).flat_map(move |(f, &tag)| {
            (1..f.len() - 1).map(move |i| {
                let p = |k: usize| m.positions[f[k] as usize];
                ([p(0), p(i), p(i + 1)], tag)
            })
        })
    }

    /// Nearest hit of the ray (origin, `d`) on `m`: distance and face tag.
    fn first_hit(m: &TaggedMesh, d: DVec3) -> Option<(f64, Face)> {
        triangles(m)
            .filter_map(|([a, b, c], tag)| {
                // Möller–Trumbore.
                let (e1, e2) = (b - a, c - a);
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-18 {
                    return None;
                }
                let s = -a;
                let u = s.dot(p) / det;
                let q = s.cross(e1);
                let v = d.dot(q) / det;
                let t = e2.dot(q) / det;
                (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some((t, tag))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0))
    }

    #[test]
    fn shells_are_closed_outward_hold_the_pupil_and_pass_the_field_through_glass() {
        for lens in [LensModel::Rectilinear, LensModel::FisheyeEquidistant] {
            for port in ports() {
                let cam = camera(port, lens);
                let what = format!("{lens:?} {:?}", cam.port);
                let h = housing_shell(&cam).expect("a port has a shell");
                let shell = &h.shell;
                assert_eq!(shell.faces.len(), shell.tags.len());
                // Closed and consistently oriented: each directed edge has one reverse twin.
                let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
                for f in &shell.faces {
                    for i in 0..f.len() {
                        *edges.entry((f[i], f[(i + 1) % f.len()])).or_default() += 1;
                    }
                }
                for (&(a, b), &n) in &edges {
                    assert!(
                        n == 1 && edges.get(&(b, a)) == Some(&1),
                        "{what}: edge {a}-{b}"
                    );
                }
                // Outward (positive volume), and the pupil inside: the solid angle it sees
                // the shell under is 4π (Van Oosterom–Strackee per triangle).
                let (mut volume, mut omega) = (0.0, 0.0);
                for ([a, b, c], _) in triangles(shell) {
                    volume += a.dot(b.cross(c)) / 6.0;
                    let (la, lb, lc) = (a.length(), b.length(), c.length());
                    let num = a.dot(b.cross(c));
                    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
                    omega += 2.0 * num.atan2(den);
                }
                assert!(volume > 0.0, "{what}: normals point into the housing");
                let four_pi = 4.0 * std::f64::consts::PI;
                assert!(
                    (omega - four_pi).abs() < 1e-6 * four_pi,
                    "{what}: Ω = {omega}"
                );
                // Smooth normals: unit, and on the side the polygons face.
                if let Some(normals) = &shell.normals {
                    assert_eq!(normals.len(), shell.positions.len());
                    assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-12));
                }
                // The inner face looks at the pupil.
                for ([a, b, c], tag) in triangles(&h.inner) {
                    assert_eq!(tag, Face::Inner { glass_inside: true });
                    assert!((b - a).cross(c - a).dot(a) < 0.0, "{what}: inner face");
                }
                // Every ray of the field crosses the inner face, then leaves through the glass.
                for d in field_directions(&cam, 16) {
                    let (t_in, _) = first_hit(&h.inner, d).expect("the inner face is crossed");
                    let (t_out, tag) = first_hit(shell, d).expect("the shell is closed");
                    assert_eq!(
                        tag,
                        Face::Outer,
                        "{what}: the ray {d} meets the housing body"
                    );
                    assert!(
                        t_in < t_out,
                        "{what}: inner face at {t_in}, outer at {t_out}"
                    );
                }
            }
        }
    }
}
