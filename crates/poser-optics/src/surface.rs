//! The sea surface seen from the air: a camera above the water (a drone) looks through the
//! air–water interface, flat or wavy ([`WaveField`]). Pure math on world-frame rays.
//!
//! | item | meaning |
//! |---|---|
//! | [`SeaInterface::hit`] | first crossing of a downward air ray with `z = h(x, y)`: sphere tracing from the plane `z = max|h|` with steps `f/L` (`L = |d_z| + Σ|aᵢ||kᵢ|·|d_xy|` bounds the slope of `f = z − h` along the ray, so no step passes the first crossing), then Newton's method from 0.1 mm above it, to 1e-11 m |
//! | [`SeaInterface::refract_down`] | the ray in the water: vector Snell at the local normal `(−hx, −hy, 1)`, and the unpolarised Fresnel transmittance (air → water) |
//! | [`image_through`] | the pixel at which a camera in the air sees a point under the surface: Newton's method in pixel space on the water ray's miss distance, the Jacobian by central differences (1e-4 px), from a start pixel (the straight-line projection) |
//!
//! What is not modelled here: the light the surface reflects (sky glint), and rays that cross
//! the surface more than once (a wave crest between the camera and the point). With several
//! images of one point (strong waves focus the view as they focus the sun) Newton finds the
//! one nearest its start; no convergence is the explicit [`NoSolution::NoConvergence`].

use super::NoSolution;
use super::interface::{fresnel_transmittance, refract};
use super::waves::WaveField;
use glam::DVec3;

/// The air–water interface, for one colour channel.
#[derive(Debug, Clone, PartialEq)]
pub struct SeaInterface {
    pub field: WaveField,
    /// Index of the water (the air is 1).
    pub n_water: f64,
}

impl SeaInterface {
    /// A flat surface at z = 0.
    pub fn flat(n_water: f64) -> SeaInterface {
        SeaInterface {
            field: WaveField::flat(1.0),
            n_water,
        }
    }

    /// Whether `p` is above every crest.
    pub fn above(&self, p: DVec3) -> bool {
        p.z > self.field.max_abs_height()
    }

    /// First point where the ray `o + t·d` (`o` above every crest, `d` unit) meets the surface.
    pub fn hit(&self, o: DVec3, d: DVec3) -> Result<DVec3, NoSolution> {
        if !(d.z < 0.0) || !o.is_finite() || !d.is_finite() {
            return Err(NoSolution::MissesPort);
        }
        let f = |t: f64| {
            let p = o + t * d;
            p.z - self.field.height(p.x, p.y)
        };
        let h_max = self.field.max_abs_height();
        if h_max == 0.0 {
            return Ok(o + (o.z / -d.z) * d);
        }
        let (t0, t_end) = ((o.z - h_max) / -d.z, (o.z + h_max) / -d.z);
        // Sphere tracing: |f'| ≤ |d.z| + max|∇h|·|d_xy| (the gradient bound Σ|aᵢ|·|kᵢ|), so a
        // step of f/that bound never passes the first crossing; it closes in on it
        // geometrically (fast for the steep rays of a camera looking down).
        let slope_max: f64 = self
            .field
            .components
            .iter()
            .map(|c| c.amplitude.abs() * c.kx.hypot(c.ky))
            .sum();
        let lipschitz = -d.z + slope_max * d.x.hypot(d.y);
        let tol = 1e-11 * (1.0 + o.z.abs());
        let mut t = t0;
        for _ in 0..100_000 {
            let fv = f(t);
            if fv <= tol {
                return Ok(o + t * d);
            }
            if fv <= 1e-4 {
                // Within 0.1 mm of the crossing: finish with Newton's method.
                return self.polish(o, d, t, tol);
            }
            t += fv / lipschitz;
            if t > t_end + 1.0 {
                break;
            }
        }
        Err(NoSolution::NoConvergence)
    }

    /// Newton's method on `f(t) = z − h` from `t` (just above the first crossing).
    fn polish(&self, o: DVec3, d: DVec3, mut t: f64, tol: f64) -> Result<DVec3, NoSolution> {
        for _ in 0..20 {
            let p = o + t * d;
            let (h, hx, hy) = self.field.height_gradient(p.x, p.y);
            let fv = p.z - h;
            if fv.abs() <= tol {
                return Ok(p);
            }
            let df = d.z - hx * d.x - hy * d.y;
            if !(df < 0.0) {
                return Err(NoSolution::NoConvergence);
            }
            t -= fv / df;
        }
        Err(NoSolution::NoConvergence)
    }

    /// The ray in the water below the point where `o + t·d` meets the surface: (that point,
    /// unit direction in the water, Fresnel transmittance air → water).
    pub fn refract_down(&self, o: DVec3, d: DVec3) -> Result<(DVec3, DVec3, f64), NoSolution> {
        let s = self.hit(o, d)?;
        let (hx, hy) = self.field.gradient(s.x, s.y);
        // Normal pointing down, into the water (the transmission side).
        let n = -DVec3::new(-hx, -hy, 1.0).normalize();
        let cos_i = n.dot(d);
        if cos_i <= 0.0 {
            return Err(NoSolution::MissesPort); // grazing the back of a wave
        }
        let (t, cos_t) =
            refract(d, n, 1.0 / self.n_water).ok_or(NoSolution::TotalInternalReflection)?;
        let tr = fresnel_transmittance(1.0, self.n_water, cos_i, cos_t);
        Ok((s, t.normalize(), tr))
    }
}

/// The pixel at which a camera in the air sees the water point `p`: the (u, v) whose air ray
/// (`ray(u, v)` → world origin and unit direction) refracts through `iface` and passes through
/// `p`, on the branch that continues the flat surface's image. Homotopy: Newton on the flat
/// surface from `start`, then on the waves scaled from 0 to their full height in steps (halved
/// when Newton fails). Where that branch folds away (the point sits at a caustic of the view)
/// the remaining images are searched on a grid around the last one ([`images_through`]) and
/// the nearest is returned. `NoConvergence` when there is none.
pub fn image_through(
    iface: &SeaInterface,
    ray: &dyn Fn(f64, f64) -> Result<(DVec3, DVec3), NoSolution>,
    p: DVec3,
    start: [f64; 2],
) -> Result<[f64; 2], NoSolution> {
    let flat = SeaInterface {
        field: WaveField::flat(iface.field.period),
        n_water: iface.n_water,
    };
    let mut uv = newton(&flat, ray, p, start)?;
    if iface.field.components.is_empty() {
        return Ok(uv);
    }
    let scaled = |s: f64| SeaInterface {
        field: WaveField {
            components: iface
                .field
                .components
                .iter()
                .map(|c| super::waves::Component {
                    amplitude: c.amplitude * s,
                    ..*c
                })
                .collect(),
            ..iface.field.clone()
        },
        n_water: iface.n_water,
    };
    let (mut s, mut ds) = (0.0f64, 0.125f64);
    while s < 1.0 {
        let next = (s + ds).min(1.0);
        match newton(&scaled(next), ray, p, uv) {
            Ok(x) if (x[0] - uv[0]).hypot(x[1] - uv[1]) < 50.0 => {
                uv = x;
                s = next;
                ds = (ds * 1.5).min(0.25);
            }
            _ if ds > 1e-3 => ds *= 0.5,
            _ => {
                // The branch folds away: look for the other images near where it was.
                let all = images_through(iface, ray, p, uv, 40.0);
                return all.into_iter().next().ok_or(NoSolution::NoConvergence);
            }
        }
    }
    Ok(uv)
}

/// The pixel of world point `w` for projector `p` at pose `pi`, seen from the air through
/// the sea surface `iface`: [`image_through`] started from the straight-line projection, on
/// the sensor.
pub fn project_through(
    p: &super::project::Projector,
    iface: &SeaInterface,
    pi: usize,
    w: DVec3,
) -> Result<[f64; 2], NoSolution> {
    let start = p.project_world_unbounded(pi, w)?;
    let ray = |u: f64, v: f64| p.pixel_ray_world(pi, u, v).map(|(o, d, _)| (o, d));
    let uv = image_through(iface, &ray, w, start)?;
    if p.on_sensor(uv) {
        Ok(uv)
    } else {
        Err(NoSolution::OffSensor)
    }
}

/// Every image of `p` within `radius` px of `around` (a grid of 41 × 41 starts, Newton from
/// each local minimum of the miss), nearest to `around` first, duplicates (within 1e-6 px)
/// removed.
pub fn images_through(
    iface: &SeaInterface,
    ray: &dyn Fn(f64, f64) -> Result<(DVec3, DVec3), NoSolution>,
    p: DVec3,
    around: [f64; 2],
    radius: f64,
) -> Vec<[f64; 2]> {
    const N: i32 = 20;
    let step = radius / N as f64;
    let at = |i: i32, j: i32| [around[0] + i as f64 * step, around[1] + j as f64 * step];
    let miss = |x: [f64; 2]| -> f64 {
        ray(x[0], x[1])
            .and_then(|(o, d)| iface.refract_down(o, d))
            .map(|(s, w, _)| {
                let q = p - s;
                (q - q.dot(w) * w).length()
            })
            .unwrap_or(f64::INFINITY)
    };
    let grid: Vec<Vec<f64>> = (-N..=N)
        .map(|i| (-N..=N).map(|j| miss(at(i, j))).collect())
        .collect();
    let mut found: Vec<[f64; 2]> = Vec::new();
    for i in -N..=N {
        for j in -N..=N {
            let m = grid[(i + N) as usize][(j + N) as usize];
            if !m.is_finite() {
                continue;
            }
            let lower = (-1..=1).all(|a| {
                (-1..=1).all(|b| {
                    let (x, y) = (i + a, j + b);
                    (a == 0 && b == 0)
                        || !(-N..=N).contains(&x)
                        || !(-N..=N).contains(&y)
                        || grid[(x + N) as usize][(y + N) as usize] >= m
                })
            });
            if !lower {
                continue;
            }
            if let Ok(x) = newton(iface, ray, p, at(i, j))
                && !found
                    .iter()
                    .any(|f| (f[0] - x[0]).hypot(f[1] - x[1]) < 1e-6)
            {
                found.push(x);
            }
        }
    }
    let d = |x: &[f64; 2]| (x[0] - around[0]).hypot(x[1] - around[1]);
    found.sort_by(|a, b| d(a).total_cmp(&d(b)));
    found
}

/// Newton's method from `start` on the miss of the water ray at `p`: the miss must fall below
/// 1e-9 of the water path.
fn newton(
    iface: &SeaInterface,
    ray: &dyn Fn(f64, f64) -> Result<(DVec3, DVec3), NoSolution>,
    p: DVec3,
    start: [f64; 2],
) -> Result<[f64; 2], NoSolution> {
    // The plane through p across the first water ray, and a 2-D basis in it.
    let (o0, d0) = ray(start[0], start[1])?;
    let (_, w0, _) = iface.refract_down(o0, d0)?;
    let b1 = w0.any_orthonormal_vector();
    let b2 = w0.cross(b1);
    // Where the water ray from (u, v) crosses that plane, relative to p (in the basis), and
    // the water path length to it.
    let miss = |u: f64, v: f64| -> Result<([f64; 2], f64), NoSolution> {
        let (o, d) = ray(u, v)?;
        let (s, w, _) = iface.refract_down(o, d)?;
        let cos = w.dot(w0);
        if cos <= 1e-6 {
            return Err(NoSolution::NoConvergence);
        }
        let t = (p - s).dot(w0) / cos;
        if t <= 0.0 {
            return Err(NoSolution::BehindCamera);
        }
        let q = s + t * w - p;
        Ok(([q.dot(b1), q.dot(b2)], t))
    };
    let norm = |e: [f64; 2]| e[0].hypot(e[1]);
    let (mut u, mut v) = (start[0], start[1]);
    const H: f64 = 1e-4;
    for _ in 0..60 {
        let (e, len) = miss(u, v)?;
        if norm(e) <= 1e-9 * len {
            return Ok([u, v]);
        }
        let diff =
            |a: [f64; 2], b: [f64; 2]| [(a[0] - b[0]) / (2.0 * H), (a[1] - b[1]) / (2.0 * H)];
        let du = diff(miss(u + H, v)?.0, miss(u - H, v)?.0);
        let dv = diff(miss(u, v + H)?.0, miss(u, v - H)?.0);
        let det = du[0] * dv[1] - dv[0] * du[1];
        if !(det.abs() > 0.0) || !det.is_finite() {
            return Err(NoSolution::NoConvergence);
        }
        // Solve J·δ = −e.
        let su = -(e[0] * dv[1] - dv[0] * e[1]) / det;
        let sv = -(du[0] * e[1] - e[0] * du[1]) / det;
        // Damped: halve the step until the miss shrinks.
        let now = norm(e);
        let mut k = 1.0;
        loop {
            match miss(u + k * su, v + k * sv) {
                Ok((next, _)) if norm(next) < now => break,
                _ if k < 1e-6 => return Err(NoSolution::NoConvergence),
                _ => k *= 0.5,
            }
        }
        u += k * su;
        v += k * sv;
    }
    Err(NoSolution::NoConvergence)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pinhole in the air at `c` looking straight down, focal `f` px, principal point (cx, cy).
    fn pinhole(c: DVec3, f: f64) -> impl Fn(f64, f64) -> Result<(DVec3, DVec3), NoSolution> {
        move |u, v| {
            // Camera x = world x, camera y = world −y, camera z = world −z.
            let d = DVec3::new((u - 500.0) / f, -(v - 500.0) / f, -1.0).normalize();
            Ok((c, d))
        }
    }

    #[test]
    fn flat_surface_obeys_snell_and_the_apparent_depth() {
        let n = 1.34;
        let iface = SeaInterface::flat(n);
        let c = DVec3::new(0.0, 0.0, 10.0);
        let p = DVec3::new(3.0, -1.0, -4.0);
        let px = image_through(&iface, &pinhole(c, 1000.0), p, [800.0, 600.0]).unwrap();
        let (o, d) = pinhole(c, 1000.0)(px[0], px[1]).unwrap();
        let (s, w, t) = iface.refract_down(o, d).unwrap();
        assert!(s.z.abs() < 1e-12);
        // Snell: sin θ_air = n sin θ_water, in the plane of incidence.
        let sin_a = d.truncate().length();
        let sin_w = w.truncate().length();
        assert!((sin_a - n * sin_w).abs() < 1e-9, "{sin_a} {sin_w}");
        // The water ray passes through p.
        let q = p - s;
        assert!((q - q.dot(w) * w).length() < 1e-8);
        assert!(t > 0.9 && t < 1.0);
        // Nadir point: seen straight below, at the principal point.
        let px = image_through(
            &iface,
            &pinhole(c, 1000.0),
            DVec3::new(0.0, 0.0, -4.0),
            [510.0, 490.0],
        )
        .unwrap();
        assert!(
            (px[0] - 500.0).abs() < 1e-6 && (px[1] - 500.0).abs() < 1e-6,
            "{px:?}"
        );
    }

    #[test]
    fn waves_move_the_image_and_the_solution_is_exact() {
        let iface = SeaInterface {
            field: WaveField::new(0.3, 4.0, 5.0, 0.0, 9),
            n_water: 1.34,
        };
        let flat = SeaInterface::flat(1.34);
        let c = DVec3::new(0.0, 0.0, 20.0);
        let mut moved = 0.0f64;
        for i in 0..20 {
            let p = DVec3::new(-3.0 + 0.3 * i as f64, 1.0 - 0.1 * i as f64, -3.0);
            let a = image_through(&flat, &pinhole(c, 1000.0), p, [500.0, 500.0]).unwrap();
            let b = image_through(&iface, &pinhole(c, 1000.0), p, a).unwrap();
            let (o, d) = pinhole(c, 1000.0)(b[0], b[1]).unwrap();
            let (s, w, _) = iface.refract_down(o, d).unwrap();
            assert!((s.z - iface.field.height(s.x, s.y)).abs() < 1e-9);
            let q = p - s;
            assert!((q - q.dot(w) * w).length() < 1e-8);
            moved = moved.max((a[0] - b[0]).hypot(a[1] - b[1]));
        }
        assert!(
            moved > 1.0,
            "waves of 0.3 m move a point 3 m down by {moved} px"
        );
    }

    #[test]
    fn rays_that_never_reach_the_water_are_explicit() {
        let iface = SeaInterface::flat(1.34);
        assert_eq!(
            iface.hit(DVec3::new(0.0, 0.0, 5.0), DVec3::Z),
            Err(NoSolution::MissesPort)
        );
        assert!(
            iface
                .hit(DVec3::new(0.0, 0.0, 5.0), DVec3::new(f64::NAN, 0.0, -1.0))
                .is_err()
        );
    }
}
