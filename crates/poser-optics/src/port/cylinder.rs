//! The cylinder port ([`CylinderPort`]): coaxial cylinders; the flat q-equation in the
//! meridional plane on its axis, 2-D Newton on skew rays off it.

use super::PortRay;
use super::flat::Slabs;
use super::housing::{
    Face, Housing, HousingMesh, HousingShell, MESH_SEGMENTS, Part, Shape, TaggedMesh, basis,
    border_directions, border_rays, field_directions, revolve, z_to,
};
use crate::NoSolution;
use crate::interface::{fresnel_transmittance, refract};
use crate::types::{Camera, Pose};
use glam::{DVec2, DVec3};

/// Cylindrical port: coaxial cylinders about a line.
#[derive(Debug, Clone, Copy)]
pub struct CylinderPort {
    pub axis_point: DVec3,
    pub axis: DVec3,
    pub r1: f64,
    pub r2: f64,
    pub n_air: f64,
    pub n_glass: f64,
    pub n_water: f64,
    /// The entrance pupil lies on the axis (within 1e-13·R₁): meridional q-equation.
    pub(super) on_axis: bool,
    /// The meridional q-equation's constants (gap R₁, one glass layer).
    pub(super) slabs: Slabs,
}

impl CylinderPort {
    pub fn new(
        axis_point: DVec3,
        axis: DVec3,
        inner_radius: f64,
        thickness: f64,
        n_air: f64,
        n_glass: f64,
        n_water: f64,
    ) -> Result<CylinderPort, String> {
        let a = axis
            .try_normalize()
            .ok_or("cylinder axis must be a non-zero vector")?;
        if !(inner_radius > 0.0
            && inner_radius.is_finite()
            && thickness >= 0.0
            && thickness.is_finite())
        {
            return Err("cylinder port needs inner radius > 0 and thickness ≥ 0".into());
        }
        if !axis_point.is_finite() {
            return Err("cylinder axis point must be finite".into());
        }
        // Re-anchor the axis point at the foot of the perpendicular from the pupil.
        let a0 = axis_point - axis_point.dot(a) * a;
        let off = a0.length();
        if off >= inner_radius {
            return Err(format!(
                "the camera's entrance pupil lies outside the cylinder (offset {off} m ≥ inner radius {inner_radius} m)"
            ));
        }
        if !(n_air > 0.0 && n_glass > 0.0 && n_water > 0.0) {
            return Err("indices must be positive".into());
        }
        Ok(CylinderPort {
            axis_point: a0,
            axis: a,
            r1: inner_radius,
            r2: inner_radius + thickness,
            n_air,
            n_glass,
            n_water,
            on_axis: off <= 1e-13 * inner_radius,
            slabs: Slabs::new(n_air, inner_radius, &[(thickness, n_glass)], n_water),
        })
    }

    /// Far intersection of `o + s w` with the cylinder of radius `r` (o inside).
    #[inline(always)]
    pub(super) fn hit(&self, o: DVec3, w: DVec3, r: f64) -> Option<(DVec3, DVec3)> {
        let a = self.axis;
        let op = (o - self.axis_point) - (o - self.axis_point).dot(a) * a;
        let wp = w - w.dot(a) * a;
        let qa = wp.length_squared();
        if !(qa > 1e-30) {
            return None;
        }
        let b = op.dot(wp);
        let c0 = op.length_squared() - r * r;
        let disc = (b * b - qa * c0).max(0.0).sqrt();
        let s = if b > 0.0 {
            -c0 / (b + disc)
        } else {
            (disc - b) / qa
        };
        let x = o + w * s;
        let n = (op + wp * s) / r;
        Some((x, n))
    }

    /// Camera ray (unit, camera frame) → ray in water.
    #[inline]
    pub fn backward(&self, v: DVec3) -> Result<PortRay, NoSolution> {
        let (x1, n1) = self
            .hit(DVec3::ZERO, v, self.r1)
            .ok_or(NoSolution::MissesPort)?;
        let ci = n1.dot(v);
        let (w1, ct1) =
            refract(v, n1, self.n_air / self.n_glass).ok_or(NoSolution::TotalInternalReflection)?;
        let mut tr = fresnel_transmittance(self.n_air, self.n_glass, ci, ct1);
        let (x2, n2) = self.hit(x1, w1, self.r2).ok_or(NoSolution::MissesPort)?;
        let ci2 = n2.dot(w1);
        let (w2, ct2) = refract(w1, n2, self.n_glass / self.n_water)
            .ok_or(NoSolution::TotalInternalReflection)?;
        tr *= fresnel_transmittance(self.n_glass, self.n_water, ci2, ct2);
        Ok(PortRay {
            origin: x2,
            dir: w2,
            transmittance: tr,
        })
    }

    /// Point in water (camera frame) → camera ray direction (not unit).
    pub fn forward(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let a = self.axis;
        let rel = p - self.axis_point;
        let rho_v = rel - rel.dot(a) * a;
        let rho = a.cross(rel).length();
        if !(rho > self.r2) {
            return Err(if rho <= self.r1 {
                NoSolution::InsideHousing
            } else {
                NoSolution::InsideGlass
            });
        }
        if self.on_axis {
            let z = a.dot(p);
            let e_rho = rho_v / rho;
            if z == 0.0 {
                return Ok(e_rho);
            }
            let t = self.slabs.solve_ratio(z * z, rho - self.r2)?;
            return Ok(e_rho + a * (t * z));
        }
        self.forward_skew(p)
    }

    /// Off-axis cylinder: rays are skew; 2-D Newton with a central-difference Jacobian on the
    /// direction offset (α, β) ⊥ P̂, residual = the miss vector of P from the water ray.
    pub(super) fn forward_skew(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        // Start from the solution of the same cylinder with the pupil moved onto its axis
        // (exact for zero offset), then from the pinhole direction.
        let centred = CylinderPort {
            axis_point: DVec3::ZERO,
            on_axis: true,
            ..*self
        };
        let mut last = NoSolution::NoConvergence;
        if let Ok(g) = centred.forward(p - self.axis_point) {
            match self.newton_skew(p, g.normalize()) {
                Ok(d) => return Ok(d),
                Err(e) => last = e,
            }
        }
        match self.newton_skew(p, p.normalize()) {
            Ok(d) => return Ok(d),
            Err(NoSolution::NoConvergence) => {}
            Err(e) => last = e,
        }
        // Both starts failed (a strongly decentred pupil, rays far from the sensor: Newton
        // diverges, or converges to the line's backward branch, which the acceptance test
        // rejects). Continuation in the decentring: move the pupil from the axis to its
        // place in 8 steps, keeping P fixed relative to the cylinder, each solve starting
        // from the previous one.
        self.continuation(p).map_err(|e| {
            if e == NoSolution::NoConvergence {
                last
            } else {
                e
            }
        })
    }

    #[cold]
    pub(super) fn continuation(&self, p: DVec3) -> Result<DVec3, NoSolution> {
        let a0 = self.axis_point;
        let centred = CylinderPort {
            axis_point: DVec3::ZERO,
            on_axis: true,
            ..*self
        };
        let mut g = centred.forward(p - a0)?.normalize();
        const STEPS: u32 = 8;
        for k in 1..=STEPS {
            let lam = k as f64 / STEPS as f64;
            let port = CylinderPort {
                axis_point: a0 * lam,
                on_axis: false,
                ..*self
            };
            g = port.newton_skew(p - a0 * (1.0 - lam), g)?.normalize();
        }
        Ok(g)
    }

    pub(super) fn newton_skew(&self, p: DVec3, e0: DVec3) -> Result<DVec3, NoSolution> {
        let l = p.length();
        let u1 = e0.any_orthonormal_vector();
        let u2 = e0.cross(u1);
        let resid = |x: DVec2| -> Result<DVec2, NoSolution> {
            let v = (e0 + u1 * x.x + u2 * x.y).normalize();
            let ray = self.backward(v)?;
            let d = p - ray.origin;
            let m = d - ray.dir * d.dot(ray.dir);
            Ok(DVec2::new(m.dot(u1), m.dot(u2)) / l)
        };
        let mut x = DVec2::ZERO;
        let mut f = resid(x)?;
        for _ in 0..60 {
            let h = 1e-7;
            let fx1 = resid(x + DVec2::new(h, 0.0))?;
            let fx0 = resid(x - DVec2::new(h, 0.0))?;
            let fy1 = resid(x + DVec2::new(0.0, h))?;
            let fy0 = resid(x - DVec2::new(0.0, h))?;
            let jx = (fx1 - fx0) / (2.0 * h);
            let jy = (fy1 - fy0) / (2.0 * h);
            let det = jx.x * jy.y - jy.x * jx.y;
            if !(det.abs() > 1e-300) {
                return Err(NoSolution::NoConvergence);
            }
            let step = DVec2::new(jy.y * f.x - jy.x * f.y, jx.x * f.y - jx.y * f.x) / det;
            // Backtrack on failure (TIR / miss) or growth of the residual.
            let mut lam = 1.0;
            let (nx, nf) = loop {
                let cand = x - step * lam;
                match resid(cand) {
                    Ok(fc) if fc.length() <= f.length() || lam < 1e-3 => break (cand, fc),
                    _ => {
                        lam *= 0.5;
                        if lam < 1e-12 {
                            return Err(NoSolution::NoConvergence);
                        }
                    }
                }
            };
            let moved = (nx - x).length();
            x = nx;
            f = nf;
            if moved <= 1e-15 * (1.0 + x.length()) || f.length() <= 1e-17 {
                break;
            }
        }
        // Accept only a genuine solution: the full 3-D miss of P by the water ray (not just
        // its part across e0) is within 1e-12 of the distance.
        let v = (e0 + u1 * x.x + u2 * x.y).normalize();
        let ray = self.backward(v)?;
        let d = p - ray.origin;
        let miss = (d - ray.dir * d.dot(ray.dir)).length();
        if !(f.length() <= 1e-12 && miss <= 1e-12 * l && d.dot(ray.dir) > 0.0) {
            return Err(NoSolution::NoConvergence);
        }
        Ok(v)
    }
}

/// Why a cylinder port has no housing covering the field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HousingError {
    /// The radius or the thickness is not positive.
    NotPositive,
    /// The entrance pupil lies `offset` m from the axis, outside the inner cylinder.
    PupilOutside { offset: f64, inner_radius: f64 },
    /// A ray of the field of view runs along the axis.
    AxisInView,
}

impl std::fmt::Display for HousingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HousingError::NotPositive => {
                write!(f, "the cylinder port needs a positive radius and thickness")
            }
            HousingError::PupilOutside {
                offset,
                inner_radius,
            } => write!(
                f,
                "the entrance pupil is {offset:.4} m from the cylinder axis, outside its inner \
                 radius {inner_radius} m"
            ),
            HousingError::AxisInView => write!(
                f,
                "the field of view contains the cylinder port's axis; the port cannot cover it"
            ),
        }
    }
}

/// A cylinder port's housing: the inner and outer cylinders, each closed by two disks, long
/// enough for 1.5 times the field of view's reach along the axis.
pub fn housing(
    cam: &Camera,
    axis_point: DVec3,
    axis: DVec3,
    r: f64,
    t: f64,
) -> Result<Housing, HousingError> {
    let u = axis.normalize();
    if !(r > 0.0) || !(t > 0.0) {
        return Err(HousingError::NotPositive);
    }
    // Pupil (origin) relative to the axis.
    let w = -axis_point - (-axis_point).dot(u) * u;
    if w.length() >= r {
        return Err(HousingError::PupilOutside {
            offset: w.length(),
            inner_radius: r,
        });
    }
    let mut max_axial: f64 = 0.0;
    for d in border_rays(cam) {
        let dp = d - d.dot(u) * u;
        let a = dp.length_squared();
        if a < 1e-6 {
            return Err(HousingError::AxisInView);
        }
        let b = 2.0 * w.dot(dp);
        let cc = w.length_squared() - r * r;
        let s = (-b + (b * b - 4.0 * a * cc).sqrt()) / (2.0 * a);
        max_axial = max_axial.max((s * d - axis_point).dot(u).abs());
    }
    let half_len = 1.5 * max_axial + 4.0 * t + 0.5 * r;
    let a0 = axis_point;
    let mut parts = Vec::new();
    for (radius, hl, face, label) in [
        (
            r,
            half_len,
            Face::Inner {
                glass_inside: false,
            },
            "inner (air inside | glass)",
        ),
        (
            r + t,
            half_len + t,
            Face::Outer,
            "outer (glass inside | water)",
        ),
    ] {
        parts.push(
            Part::new(
                face,
                Shape::Cylinder {
                    p0: a0 - u * hl,
                    p1: a0 + u * hl,
                    radius,
                },
            )
            .labelled("cylinder port", label),
        );
        for sign in [-1.0, 1.0] {
            parts.push(Part::new(
                face,
                Shape::Disk {
                    centre: a0 + u * (sign * hl),
                    normal: u * sign,
                    radius,
                },
            ));
        }
    }
    Ok(Housing {
        parts,
        clearance: r - w.length(),
        extent: axis_point.length() + (half_len + t).hypot(r + t),
    })
}

/// Segments of [`housing_shell`]'s tubes: fine enough that Cycles' smooth shading of the
/// facets (with the cylinder's exact normals) stays on the cylinder.
const SHELL_SEGMENTS: u32 = 512;

/// A cylinder port's closed housing for a mesh renderer ([`HousingShell`]): the outer tube
/// centred on the axis point nearest the pupil, long enough that the field of view (rays within
/// 80° of the axis) leaves through it with 30 % to spare + 2 outer radii, closed by two disks;
/// the inner face is the inner tube of the same length.
pub fn housing_shell(cam: &Camera, axis_point: DVec3, axis: DVec3, r: f64, t: f64) -> HousingShell {
    let a = axis.normalize();
    let r_out = r + t;
    let centre = axis_point + (-axis_point).dot(a) * a;
    let off = (-axis_point - (-axis_point).dot(a) * a).length();
    let cos_max = 10f64.to_radians().cos();
    let worst = field_directions(cam, 8)
        .iter()
        .map(|d| {
            let c = d.dot(a).abs().min(cos_max);
            c / (1.0 - c * c).sqrt()
        })
        .fold(0.0, f64::max);
    let half = (r_out + off) * worst * 1.3 + 2.0 * r_out;
    // (e2, −e1): the orientation the Blender builder used when it built this shell itself.
    let (e1, e2) = basis(a);
    let (u, v) = (e2, -e1);
    let seg = SHELL_SEGMENTS;
    let tube = |radius: f64, outward: bool, tag: Face| {
        let sign = if outward { 1.0 } else { -1.0 };
        let mut m = TaggedMesh::default();
        let mut normals = Vec::with_capacity(2 * seg as usize);
        for h in [-half, half] {
            for j in 0..seg {
                let phi = std::f64::consts::TAU * j as f64 / seg as f64;
                let radial = phi.cos() * u + phi.sin() * v;
                m.positions.push(centre + radius * radial + h * a);
                normals.push(sign * radial);
            }
        }
        m.normals = Some(normals);
        for j in 0..seg {
            let k = (j + 1) % seg;
            // Counter-clockwise seen from outside, for u × v = a.
            let mut f = vec![j, k, seg + k, seg + j];
            if !outward {
                f.reverse();
            }
            m.push(f, tag);
        }
        m
    };
    let mut shell = tube(r_out, true, Face::Outer);
    shell.push((0..seg).rev().collect(), Face::Wall);
    shell.push((0..seg).map(|j| seg + j).collect(), Face::Wall);
    let inner = tube(r, false, Face::Inner { glass_inside: true });
    HousingShell { shell, inner }
}

/// A cylinder port's glass as a tube shell, for display: the field of view's reach along the
/// axis on the inner cylinder, + 20 % (at least half the radius).
pub fn housing_mesh(cam: &Camera, axis_point: DVec3, axis: DVec3, r: f64, t: f64) -> HousingMesh {
    let u = axis.normalize();
    let w = -axis_point - (-axis_point).dot(u) * u;
    let mut reach: f64 = 0.0;
    for d in &border_directions(cam) {
        let dp = *d - d.dot(u) * u;
        let a = dp.length_squared();
        if a < 1e-9 {
            continue;
        }
        let bq = 2.0 * w.dot(dp);
        let c = w.length_squared() - r * r;
        let disc = bq * bq - 4.0 * a * c;
        if disc >= 0.0 {
            let s = (-bq + disc.sqrt()) / (2.0 * a);
            reach = reach.max((*d * s - axis_point).dot(u).abs());
        }
    }
    let l = (1.2 * reach).max(0.5 * r) + t;
    revolve(
        &[(r, -l), (r + t, -l), (r + t, l), (r, l)],
        true,
        MESH_SEGMENTS,
    )
    .transformed(&Pose {
        rotation: z_to(u),
        translation: axis_point,
    })
}
