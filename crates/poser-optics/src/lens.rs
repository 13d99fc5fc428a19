//! Lens models: camera-frame ray direction ↔ pixel.
//!
//! | model | mapping of the angle θ from the optical axis to the normalised radius r |
//! |---|---|
//! | `rectilinear` | r = tan θ (pinhole), then Brown–Conrady distortion (OpenCV k1, k2, k3, p1, p2) |
//! | `fisheye_equidistant` | r = θ, then the same Brown polynomial on the normalised coordinates |
//! | `fisheye_equisolid` | r = 2 sin(θ/2), then the same Brown polynomial |
//!
//! Pixel = (fx·x_d + cx, fy·y_d + cy) with no +0.5 term (pixel centres are at +0.5, as in
//! OpenCV/COLMAP). The inverse distortion is a 2-D Newton iteration with the analytic Jacobian,
//! converged to 1e-15 in normalised units; where it does not converge (folded distortion far
//! outside the calibrated field) the result is [`NoSolution::OutsideLensField`].

use super::NoSolution;
use super::types::{Camera, Distortion, LensModel};
use glam::DVec3;

/// The intrinsic part of a camera (everything before the port).
#[derive(Debug, Clone, Copy)]
pub struct Lens {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub model: LensModel,
    pub distortion: Distortion,
    distorted: bool,
    /// Largest r² (undistorted, normalised) where the radial distortion r·(1 + k1 r² + k2 r⁴ +
    /// k3 r⁶) is still increasing; beyond it the image folds back and points are
    /// [`NoSolution::OutsideLensField`].
    pub r2_max: f64,
}

impl Lens {
    pub fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        model: LensModel,
        distortion: Distortion,
    ) -> Lens {
        let r2_max = Self::fold_r2(&distortion);
        Lens {
            fx,
            fy,
            cx,
            cy,
            model,
            distortion,
            distorted: !distortion.is_zero(),
            r2_max,
        }
    }

    /// First s = r² > 0 where d/dr[r(1 + k1 s + k2 s² + k3 s³)] = 1 + 3k1 s + 5k2 s² + 7k3 s³
    /// vanishes (∞ if never, searched up to s = 1e8).
    fn fold_r2(d: &Distortion) -> f64 {
        let g = |s: f64| 1.0 + s * (3.0 * d.k1 + s * (5.0 * d.k2 + s * 7.0 * d.k3));
        let mut prev = 0.0;
        let mut s = 1e-6;
        while s <= 1e8 {
            if g(s) <= 0.0 {
                let (mut a, mut b) = (prev, s);
                for _ in 0..200 {
                    let m = 0.5 * (a + b);
                    if g(m) > 0.0 { a = m } else { b = m }
                }
                return a;
            }
            prev = s;
            s *= 1.05;
        }
        f64::INFINITY
    }

    pub fn from_camera(c: &Camera) -> Lens {
        Lens::new(c.fx, c.fy, c.cx, c.cy, c.lens, c.distortion)
    }

    /// Brown–Conrady distortion of normalised coordinates (OpenCV convention).
    #[inline(always)]
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        if !self.distorted {
            return (x, y);
        }
        let Distortion { k1, k2, k3, p1, p2 } = self.distortion;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        (
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        )
    }

    /// Inverse of [`Lens::distort`]: Newton with the analytic Jacobian from (xd, yd).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        if !self.distorted {
            return Some((xd, yd));
        }
        let Distortion { k1, k2, k3, p1, p2 } = self.distortion;
        let (mut x, mut y) = (xd, yd);
        let scale = 1.0 + xd.abs() + yd.abs();
        for _ in 0..60 {
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
            let dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2); // d radial / d r2
            let fx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
            let fy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
            let j11 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
            let j12 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
            let j21 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
            let j22 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
            let det = j11 * j22 - j12 * j21;
            if !(det.abs() > 1e-300) || !det.is_finite() {
                return None;
            }
            let dx = (j22 * fx - j12 * fy) / det;
            let dy = (j11 * fy - j21 * fx) / det;
            x -= dx;
            y -= dy;
            if !(x.is_finite() && y.is_finite()) {
                return None;
            }
            if dx.abs() + dy.abs() <= 1e-16 * scale {
                let (ex, ey) = self.distort(x, y);
                return ((ex - xd).abs() + (ey - yd).abs() <= 1e-13 * scale).then_some((x, y));
            }
        }
        let (ex, ey) = self.distort(x, y);
        ((ex - xd).abs() + (ey - yd).abs() <= 1e-13 * scale).then_some((x, y))
    }

    /// Camera-frame direction (any length) → pixel.
    #[inline]
    pub fn project(&self, d: DVec3) -> Result<[f64; 2], NoSolution> {
        let (x, y) = match self.model {
            LensModel::Rectilinear => {
                if !(d.z > 0.0) {
                    return Err(NoSolution::BehindCamera);
                }
                let iz = 1.0 / d.z;
                (d.x * iz, d.y * iz)
            }
            LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
                let rho = d.x.hypot(d.y);
                if rho == 0.0 {
                    if d.z > 0.0 {
                        (0.0, 0.0)
                    } else {
                        return Err(NoSolution::BehindCamera);
                    }
                } else {
                    let theta = rho.atan2(d.z);
                    let r = if self.model == LensModel::FisheyeEquidistant {
                        theta
                    } else {
                        2.0 * (0.5 * theta).sin()
                    };
                    (r * d.x / rho, r * d.y / rho)
                }
            }
        };
        if x * x + y * y > self.r2_max {
            return Err(NoSolution::OutsideLensField);
        }
        let (xd, yd) = self.distort(x, y);
        let u = self.fx * xd + self.cx;
        let v = self.fy * yd + self.cy;
        if u.is_finite() && v.is_finite() {
            Ok([u, v])
        } else {
            Err(NoSolution::OutsideLensField)
        }
    }

    /// Pixel → unit camera-frame direction.
    #[inline]
    pub fn unproject(&self, u: f64, v: f64) -> Result<DVec3, NoSolution> {
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        let (x, y) = self.undistort(xd, yd).ok_or(NoSolution::OutsideLensField)?;
        if x * x + y * y > self.r2_max {
            return Err(NoSolution::OutsideLensField);
        }
        let d = match self.model {
            LensModel::Rectilinear => DVec3::new(x, y, 1.0),
            LensModel::FisheyeEquidistant | LensModel::FisheyeEquisolid => {
                let r = x.hypot(y);
                if r == 0.0 {
                    return Ok(DVec3::Z);
                }
                let theta = if self.model == LensModel::FisheyeEquidistant {
                    r
                } else {
                    if r > 2.0 {
                        return Err(NoSolution::OutsideLensField);
                    }
                    2.0 * (0.5 * r).asin()
                };
                if theta >= std::f64::consts::PI {
                    return Err(NoSolution::OutsideLensField);
                }
                let s = theta.sin() / r;
                DVec3::new(s * x, s * y, theta.cos())
            }
        };
        if !d.is_finite() {
            return Err(NoSolution::OutsideLensField);
        }
        Ok(d.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(model: LensModel, dist: Distortion) -> Lens {
        Lens::new(1000.0, 1000.0, 640.0, 480.0, model, dist)
    }

    #[test]
    fn pinhole_matches_formula() {
        let l = lens(LensModel::Rectilinear, Distortion::default());
        let p = l.project(DVec3::new(0.1, -0.2, 2.0)).unwrap();
        assert_eq!(p, [640.0 + 50.0, 480.0 - 100.0]);
        assert_eq!(
            l.project(DVec3::new(0.0, 0.0, -1.0)),
            Err(NoSolution::BehindCamera)
        );
        assert_eq!(
            l.project(DVec3::new(1.0, 0.0, 0.0)),
            Err(NoSolution::BehindCamera)
        );
    }

    #[test]
    fn round_trips_all_models_with_distortion() {
        // Distorted round trip to 1e-9 px over a grid (Newton converges to 1e-16 normalised).
        let dist = Distortion {
            k1: -0.12,
            k2: 0.03,
            k3: -0.002,
            p1: 4e-4,
            p2: -3e-4,
        };
        for model in [
            LensModel::Rectilinear,
            LensModel::FisheyeEquidistant,
            LensModel::FisheyeEquisolid,
        ] {
            for d in [Distortion::default(), dist] {
                let l = lens(model, d);
                for i in 0..=16 {
                    for j in 0..=12 {
                        let (u, v) = (i as f64 * 80.0, j as f64 * 80.0);
                        let ray = l.unproject(u, v).unwrap();
                        assert!((ray.length() - 1.0).abs() < 1e-15);
                        let p = l.project(ray).unwrap();
                        assert!(
                            (p[0] - u).abs() < 1e-9 && (p[1] - v).abs() < 1e-9,
                            "{model:?} {u},{v}: {p:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn folded_distortion_is_outside_the_field() {
        // k1 < 0: r(1 + k1 r²) peaks at r² = −1/(3 k1); beyond it the image folds back.
        let l = lens(
            LensModel::Rectilinear,
            Distortion {
                k1: -0.1,
                ..Distortion::default()
            },
        );
        assert!((l.r2_max - 1.0 / 0.3).abs() < 1e-9);
        assert_eq!(
            l.project(DVec3::new(2.0, 0.0, 1.0)),
            Err(NoSolution::OutsideLensField)
        );
        assert!(l.project(DVec3::new(1.5, 0.0, 1.0)).is_ok());
        // Pixels beyond the fold radius have no ray.
        assert!(l.unproject(640.0 + 1000.0 * 1.3, 480.0).is_err());
    }

    #[test]
    fn fisheye_sees_beyond_90_degrees() {
        let l = lens(LensModel::FisheyeEquidistant, Distortion::default());
        let p = l.project(DVec3::new(1.0, 0.0, -0.1)).unwrap();
        let theta = 1f64.atan2(-0.1);
        assert!((p[0] - (640.0 + 1000.0 * theta)).abs() < 1e-9);
        assert_eq!(
            l.project(DVec3::new(0.0, 0.0, -1.0)),
            Err(NoSolution::BehindCamera)
        );
        let q = lens(LensModel::FisheyeEquisolid, Distortion::default());
        assert_eq!(
            q.unproject(640.0 + 2100.0, 480.0),
            Err(NoSolution::OutsideLensField)
        );
    }
}
