//! A seabed's large-scale relief through given heights: the thin-plate spline, the smoothest
//! surface z = f(x, y) (least bending energy) that passes exactly through a few surveyed
//! points, such as a site's ground control points with their heights.
//!
//! | input | meaning |
//! |---|---|
//! | `points` | 3 to [`MAX_RELIEF_POINTS`] points `(x, y, z)`, not all on one line, no two at the same `(x, y)` |
//!
//! f(x, y) = a₀ + a₁x + a₂y + Σ wᵢ φ(|(x, y) − (xᵢ, yᵢ)|), φ(r) = r² ln r, with Σ wᵢ = Σ wᵢxᵢ =
//! Σ wᵢyᵢ = 0 (Duchon 1977; Bookstein 1989). Away from the points it continues as a plane
//! bent gently, never oscillating as a polynomial through the same points would. Solved in f64
//! on coordinates centred and scaled to their extent, by Gaussian elimination with partial
//! pivoting: a singular system (collinear or coincident points) is an explicit error.

use glam::DVec3;

/// The most points a relief takes: the solve is cubic and every vertex of the heightfield sums
/// one term per point.
pub const MAX_RELIEF_POINTS: usize = 200;

/// A thin-plate spline through the points, in the points' own coordinates.
#[derive(Clone, Debug)]
pub struct Relief {
    centre: [f64; 2],
    scale: f64,
    sites: Vec<[f64; 2]>,
    weights: Vec<f64>,
    affine: [f64; 3],
}

fn phi(r2: f64) -> f64 {
    if r2 > 0.0 { 0.5 * r2 * r2.ln() } else { 0.0 }
}

impl Relief {
    /// The spline through `points`, or why there is none.
    pub fn through(points: &[DVec3]) -> Result<Relief, String> {
        let n = points.len();
        if n < 3 {
            return Err(format!(
                "a relief needs at least 3 points (got {n}): two points fix no surface"
            ));
        }
        if n > MAX_RELIEF_POINTS {
            return Err(format!(
                "a relief takes at most {MAX_RELIEF_POINTS} points (got {n})"
            ));
        }
        if points.iter().any(|p| !p.is_finite()) {
            return Err("a relief point is not a finite number".into());
        }
        let cx = points.iter().map(|p| p.x).sum::<f64>() / n as f64;
        let cy = points.iter().map(|p| p.y).sum::<f64>() / n as f64;
        let scale = points
            .iter()
            .map(|p| (p.x - cx).abs().max((p.y - cy).abs()))
            .fold(0.0, f64::max);
        if !(scale > 0.0) {
            return Err("every relief point is at the same (x, y)".into());
        }
        let sites: Vec<[f64; 2]> = points
            .iter()
            .map(|p| [(p.x - cx) / scale, (p.y - cy) / scale])
            .collect();
        // Collinear sites leave the plane's tilt across their line undetermined.
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for s in &sites {
            sxx += s[0] * s[0];
            sxy += s[0] * s[1];
            syy += s[1] * s[1];
        }
        let (tr, det) = (sxx + syy, sxx * syy - sxy * sxy);
        let lmin = 0.5 * (tr - (tr * tr - 4.0 * det).max(0.0).sqrt());
        if lmin <= 1e-9 * tr {
            return Err("the relief points lie on one line: they fix no surface across it".into());
        }
        // [K P; Pᵀ 0] [w; a] = [z; 0]
        let m = n + 3;
        let mut a = vec![0.0; m * (m + 1)];
        let at = |i: usize, j: usize| i * (m + 1) + j;
        for i in 0..n {
            for j in 0..n {
                let (dx, dy) = (sites[i][0] - sites[j][0], sites[i][1] - sites[j][1]);
                a[at(i, j)] = phi(dx * dx + dy * dy);
            }
            let p = [1.0, sites[i][0], sites[i][1]];
            for k in 0..3 {
                a[at(i, n + k)] = p[k];
                a[at(n + k, i)] = p[k];
            }
            a[at(i, m)] = points[i].z;
        }
        // Gaussian elimination with partial pivoting.
        let norm = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for c in 0..m {
            let piv = (c..m)
                .max_by(|&r, &s| a[at(r, c)].abs().total_cmp(&a[at(s, c)].abs()))
                .unwrap_or(c);
            if !(a[at(piv, c)].abs() > 1e-12 * norm.max(1.0)) {
                return Err(
                    "two relief points share one (x, y): no surface passes through both".into(),
                );
            }
            if piv != c {
                for j in 0..=m {
                    a.swap(at(piv, j), at(c, j));
                }
            }
            for r in c + 1..m {
                let f = a[at(r, c)] / a[at(c, c)];
                if f != 0.0 {
                    for j in c..=m {
                        a[at(r, j)] -= f * a[at(c, j)];
                    }
                }
            }
        }
        let mut x = vec![0.0; m];
        for r in (0..m).rev() {
            let s: f64 = (r + 1..m).map(|j| a[at(r, j)] * x[j]).sum();
            x[r] = (a[at(r, m)] - s) / a[at(r, r)];
        }
        if x.iter().any(|v| !v.is_finite()) {
            return Err("the relief's spline has no finite solution".into());
        }
        Ok(Relief {
            centre: [cx, cy],
            scale,
            sites,
            weights: x[..n].to_vec(),
            affine: [x[n], x[n + 1], x[n + 2]],
        })
    }

    /// The height of the surface at `(x, y)`.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let (u, v) = (
            (x - self.centre[0]) / self.scale,
            (y - self.centre[1]) / self.scale,
        );
        let mut h = self.affine[0] + self.affine[1] * u + self.affine[2] * v;
        for (s, w) in self.sites.iter().zip(&self.weights) {
            let (dx, dy) = (u - s[0], v - s[1]);
            h += w * phi(dx * dx + dy * dy);
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_every_point_and_keeps_a_plane() {
        let pts: Vec<DVec3> = [
            (4.5941, 11.3973, 1.18725),
            (4.54517, 7.80379, 0.675317),
            (18.8122, 12.2859, 0.439436),
            (18.9168, 7.70553, -0.8059),
            (29.5393, 11.7936, 1.0371),
            (46.9181, 10.589, 2.2479),
        ]
        .iter()
        .map(|&(x, y, z)| DVec3::new(x, y, z))
        .collect();
        let r = Relief::through(&pts).unwrap();
        for p in &pts {
            assert!((r.height(p.x, p.y) - p.z).abs() < 1e-9, "{p}");
        }
        // Points on a plane give the plane, everywhere.
        let plane: Vec<DVec3> = pts
            .iter()
            .map(|p| DVec3::new(p.x, p.y, 0.3 + 0.02 * p.x - 0.1 * p.y))
            .collect();
        let r = Relief::through(&plane).unwrap();
        for (x, y) in [(0.0, 0.0), (55.0, 3.0), (20.0, 10.0)] {
            assert!((r.height(x, y) - (0.3 + 0.02 * x - 0.1 * y)).abs() < 1e-9);
        }
    }

    #[test]
    fn degenerate_points_are_refused() {
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        assert!(Relief::through(&[p(0., 0., 0.), p(1., 0., 1.)]).is_err());
        let line = [p(0., 0., 0.), p(1., 1., 1.), p(2., 2., 0.), p(3., 3., 5.)];
        assert!(Relief::through(&line).unwrap_err().contains("one line"));
        let twin = [p(0., 0., 0.), p(1., 0., 1.), p(0., 1., 0.), p(1., 0., 2.)];
        assert!(Relief::through(&twin).unwrap_err().contains("share"));
        assert!(Relief::through(&[p(0., 0., f64::NAN), p(1., 0., 0.), p(0., 1., 0.)]).is_err());
    }
}
