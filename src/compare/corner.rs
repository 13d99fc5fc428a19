//! Sub-pixel location of a checkerboard's inner corners in rendered linear images, by fitting
//! the exact image of a corner to the pixels around it.
//!
//! | item | value | meaning |
//! |---|---|---|
//! | model | `I = D + g·(p − q) + c(p)·(Δ + h·(p − q))` | `c(p)`: the share of pixel `p`'s square on the squares of one colour |
//! | nonlinear parameters | `q` (2), the two edges' angles | fitted by Levenberg–Marquardt with numerical derivatives |
//! | linear parameters | `D`, `g` (2), `Δ`, `h` (2) | solved by least squares at every step (variable projection) |
//! | window | the pixels whose centres lie within `half` px of the prediction | it must hold no other corner |
//! | pixel filter | a box over the pixel's square | what poser asks of every backend; a symmetric filter does not move `q` |
//!
//! Near an inner corner the printed board is two straight edges crossing at the corner, and
//! the projection keeps them straight over a few pixels (a port bends them only over many).
//! A box-filtered pixel then holds the dark level `D`, plus the contrast `Δ` times `c(p)`, the
//! area of its square where the two edges' signed distances have the same sign, which is
//! exact by clipping the square with the two half-planes. Shading varies across the window:
//! `g` carries it on the dark squares, `h` the extra on the light ones (a multiplicative
//! gradient, to first order). The fitted `q` is the projected corner itself, with no centroid
//! to correct: unlike a disk's, a corner's image is a point of the projection.
//!
//! Gradient methods (OpenCV's `cornerSubPix`: the point where the window's gradients point
//! away from) weight the edges by the blur of their pixels, which on slanted edges moves the
//! answer by 0.04–0.07 px; the fitted model has no such bias (tested to 0.005 px).

use super::detect::{Gray, Miss};

/// Signed distances are `n·(p − q)`, `n = (cos a, sin a)`; the area of the unit square at
/// `(x, y)` on the side where both of the given half-planes are positive.
fn clipped_area(x: f64, y: f64, planes: &[([f64; 2], f64)]) -> f64 {
    let mut poly: Vec<[f64; 2]> = vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
    for &(n, c) in planes {
        let s = |p: [f64; 2]| n[0] * p[0] + n[1] * p[1] - c;
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (sa, sb) = (s(a), s(b));
            if sa >= 0.0 {
                out.push(a);
            }
            if (sa >= 0.0) != (sb >= 0.0) {
                let t = sa / (sa - sb);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        poly = out;
        if poly.len() < 3 {
            return 0.0;
        }
    }
    let mut a2 = 0.0;
    for i in 0..poly.len() {
        let (p, r) = (poly[i], poly[(i + 1) % poly.len()]);
        a2 += p[0] * r[1] - r[0] * p[1];
    }
    0.5 * a2.abs()
}

/// The share of the pixel square at `(x, y)` where the signed distances to the two edges
/// through `q` (angles `a1`, `a2` of their normals) have the same sign.
fn coverage(x: f64, y: f64, q: [f64; 2], a1: f64, a2: f64) -> f64 {
    let n1 = [a1.cos(), a1.sin()];
    let n2 = [a2.cos(), a2.sin()];
    let c1 = n1[0] * q[0] + n1[1] * q[1];
    let c2 = n2[0] * q[0] + n2[1] * q[1];
    let one = clipped_area(x, y, &[(n1, c1)]);
    let two = clipped_area(x, y, &[(n2, c2)]);
    let both = clipped_area(x, y, &[(n1, c1), (n2, c2)]);
    1.0 - one - two + 2.0 * both
}

/// Least squares of `a x = b` for a small dense system by Cholesky on the normal equations
/// (`rows` × `n`, row-major); `None` when singular.
fn normal_solve(rows: &[f64], b: &[f64], n: usize, damping: f64) -> Option<Vec<f64>> {
    let m = b.len();
    let mut ata = vec![0.0; n * n];
    let mut atb = vec![0.0; n];
    for r in 0..m {
        let row = &rows[r * n..(r + 1) * n];
        for i in 0..n {
            atb[i] += row[i] * b[r];
            for j in 0..=i {
                ata[i * n + j] += row[i] * row[j];
            }
        }
    }
    for i in 0..n {
        for j in 0..i {
            ata[j * n + i] = ata[i * n + j];
        }
        ata[i * n + i] *= 1.0 + damping;
    }
    cholesky_solve(&mut ata, &mut atb, n).then_some(atb)
}

/// Solve `A x = b` in place for a symmetric positive definite `A` (`n` × `n`); false when it
/// is not positive definite.
fn cholesky_solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > 1e-300) || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k * n + i] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    true
}

/// The window's pixels: their squares' corners `(x, y)` and values.
struct Window {
    at: Vec<(f64, f64)>,
    value: Vec<f64>,
}

/// Nonlinear parameters: `q` (2) and the two normals' angles.
type Params = [f64; 4];

/// Linear parameters' count: `D`, `g` (2), `Δ`, `h` (2).
const LINEAR: usize = 6;

impl Window {
    /// The linear design matrix at `p` (row-major, [`LINEAR`] columns).
    fn design(&self, p: &Params) -> Vec<f64> {
        let q = [p[0], p[1]];
        let mut rows = Vec::with_capacity(self.at.len() * LINEAR);
        for &(x, y) in &self.at {
            let c = coverage(x, y, q, p[2], p[3]);
            let (dx, dy) = (x + 0.5 - q[0], y + 0.5 - q[1]);
            rows.extend_from_slice(&[1.0, dx, dy, c, c * dx, c * dy]);
        }
        rows
    }

    /// Residuals at `p`, with the linear parameters solved for; `None` when they are not
    /// determined.
    fn residuals(&self, p: &Params) -> Option<(Vec<f64>, Vec<f64>)> {
        let rows = self.design(p);
        let lin = normal_solve(&rows, &self.value, LINEAR, 1e-12)?;
        let r = (0..self.value.len())
            .map(|i| {
                let row = &rows[i * LINEAR..(i + 1) * LINEAR];
                self.value[i] - row.iter().zip(&lin).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect();
        Some((r, lin))
    }
}

/// Sub-pixel position (pixel centres at +0.5) of a checkerboard's inner corner expected at
/// `predicted`, its two edges running along the image directions `dirs` there (from the
/// projected neighbouring corners; they need not be exact). The window holds the pixels whose
/// centres lie within `half` px of the prediction, and must hold no other corner.
/// [`Miss::NearBorder`] when it leaves the image, [`Miss::NoContrast`] when the fit finds no
/// corner there (no contrast, or `q` more than half the window from the prediction).
pub fn checker_corner(
    img: &Gray,
    predicted: [f64; 2],
    dirs: [[f64; 2]; 2],
    half: f64,
) -> Result<[f64; 2], Miss> {
    let (x0, x1) = (
        (predicted[0] - half).floor() as i64,
        (predicted[0] + half).ceil() as i64,
    );
    let (y0, y1) = (
        (predicted[1] - half).floor() as i64,
        (predicted[1] + half).ceil() as i64,
    );
    if !(half >= 2.0) || x0 < 0 || y0 < 0 || x1 >= img.width as i64 || y1 >= img.height as i64 {
        return Err(Miss::NearBorder);
    }
    let mut win = Window {
        at: Vec::new(),
        value: Vec::new(),
    };
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            if (cx - predicted[0]).hypot(cy - predicted[1]) <= half {
                win.at.push((x as f64, y as f64));
                win.value
                    .push(img.data[y as usize * img.width + x as usize] as f64);
            }
        }
    }
    // An edge along direction d has its normal at d's angle + 90°.
    let normal = |d: [f64; 2]| d[1].atan2(d[0]) + std::f64::consts::FRAC_PI_2;
    let mut p: Params = [predicted[0], predicted[1], normal(dirs[0]), normal(dirs[1])];
    let sse = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let (mut r, _) = win.residuals(&p).ok_or(Miss::NoContrast)?;
    let mut cost = sse(&r);
    let mut damping = 1e-3;
    let steps = [1e-4, 1e-4, 1e-5, 1e-5];
    for _ in 0..100 {
        // Numerical Jacobian of the residuals (central differences).
        let m = r.len();
        let mut jac = vec![0.0; m * 4];
        for k in 0..4 {
            let (mut hi, mut lo) = (p, p);
            hi[k] += steps[k];
            lo[k] -= steps[k];
            let (rh, _) = win.residuals(&hi).ok_or(Miss::NoContrast)?;
            let (rl, _) = win.residuals(&lo).ok_or(Miss::NoContrast)?;
            for i in 0..m {
                // d(residual)/d(param); the step solves J δ = −r.
                jac[i * 4 + k] = (rh[i] - rl[i]) / (2.0 * steps[k]);
            }
        }
        let neg_r: Vec<f64> = r.iter().map(|v| -v).collect();
        let mut improved = false;
        for _ in 0..12 {
            let Some(delta) = normal_solve(&jac, &neg_r, 4, damping) else {
                damping *= 10.0;
                continue;
            };
            let trial: Params = std::array::from_fn(|k| p[k] + delta[k]);
            if let Some((rt, _)) = win.residuals(&trial) {
                let ct = sse(&rt);
                if ct < cost {
                    let moved = (delta[0].hypot(delta[1]), delta[2].abs().max(delta[3].abs()));
                    p = trial;
                    r = rt;
                    cost = ct;
                    damping = (damping * 0.3).max(1e-9);
                    improved = true;
                    if moved.0 < 1e-7 && moved.1 < 1e-7 {
                        return accept(&win, p, predicted, half);
                    }
                    break;
                }
            }
            damping *= 10.0;
        }
        if !improved {
            break;
        }
    }
    accept(&win, p, predicted, half)
}

/// The fitted corner, if the fit found one: contrast well above the residuals, `q` within
/// half the window of the prediction, the two edges not parallel.
fn accept(win: &Window, p: Params, predicted: [f64; 2], half: f64) -> Result<[f64; 2], Miss> {
    let (r, lin) = win.residuals(&p).ok_or(Miss::NoContrast)?;
    let rms = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
    let contrast = lin[3].abs();
    let crossing = (p[2] - p[3]).sin().abs();
    let off = (p[0] - predicted[0]).hypot(p[1] - predicted[1]);
    if !(contrast > 3.0 * rms) || !(crossing > 0.2) || !(off <= 0.5 * half) {
        return Err(Miss::NoContrast);
    }
    Ok([p[0], p[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkerboard corner at `c`, its edges along `e1`, `e2`, box-filtered by 64 × 64
    /// supersampling, levels `dark` and `light` times `1 + shade·(x − c)`.
    fn corner_raster(
        (w, h): (usize, usize),
        c: [f64; 2],
        e: [[f64; 2]; 2],
        shade: [f64; 2],
    ) -> Vec<f32> {
        let s = 64;
        let (dark, light) = (0.05, 0.9);
        let mut img = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for j in 0..s {
                    for i in 0..s {
                        let px = x as f64 + (i as f64 + 0.5) / s as f64 - c[0];
                        let py = y as f64 + (j as f64 + 0.5) / s as f64 - c[1];
                        // Signed distances to the two edges (their normals: e rotated 90°).
                        let u = -e[0][1] * px + e[0][0] * py;
                        let v = -e[1][1] * px + e[1][0] * py;
                        let level = if (u > 0.0) == (v > 0.0) { light } else { dark };
                        sum += level * (1.0 + shade[0] * px + shade[1] * py);
                    }
                }
                img[y * w + x] = (sum / (s * s) as f64) as f32;
            }
        }
        img
    }

    fn unit(a: f64) -> [f64; 2] {
        [a.cos(), a.sin()]
    }

    #[test]
    fn the_area_of_a_clipped_square_is_exact() {
        // A diagonal through the centre halves the square; two perpendicular lines through
        // its centre leave a quarter.
        let n = [std::f64::consts::FRAC_1_SQRT_2; 2];
        let c = n[0] * 0.5 + n[1] * 0.5;
        assert!((clipped_area(0.0, 0.0, &[(n, c)]) - 0.5).abs() < 1e-15);
        let q = [0.5, 0.5];
        let quarter = clipped_area(0.0, 0.0, &[([1.0, 0.0], q[0]), ([0.0, 1.0], q[1])]);
        assert!((quarter - 0.25).abs() < 1e-15);
        // Same-sign share of perpendicular edges through the centre: two quarters.
        assert!((coverage(0.0, 0.0, q, 0.0, std::f64::consts::FRAC_PI_2) - 0.5).abs() < 1e-15);
        // A corner far away: the whole square on one side of both edges.
        let far = coverage(10.0, 10.0, q, 0.0, std::f64::consts::FRAC_PI_2);
        assert!((far - 1.0).abs() < 1e-15);
    }

    #[test]
    fn finds_a_checkerboard_corner_to_a_two_hundredth_of_a_pixel() {
        // Axis-aligned, slanted, sheared (a perspective view, locally), shaded across the
        // window; predicted 0.8 px off with edge directions 3° off.
        for (c, e, shade) in [
            (
                [20.3125, 17.75],
                [unit(0.0), unit(std::f64::consts::FRAC_PI_2)],
                [0.0, 0.0],
            ),
            (
                [19.62, 18.13],
                [unit(0.4), unit(0.4 + std::f64::consts::FRAC_PI_2)],
                [0.0, 0.0],
            ),
            ([20.91, 16.58], [unit(-0.3), unit(1.05)], [0.0, 0.0]),
            ([20.17, 17.42], [unit(0.2), unit(1.9)], [0.03, -0.02]),
        ] {
            let data = corner_raster((40, 34), c, e, shade);
            let g = Gray {
                width: 40,
                height: 34,
                data: &data,
            };
            let off = |d: [f64; 2]| {
                let a = d[1].atan2(d[0]) + 0.05;
                unit(a)
            };
            let m =
                checker_corner(&g, [c[0] - 0.8, c[1] + 0.6], [off(e[0]), off(e[1])], 6.0).unwrap();
            assert!(
                (m[0] - c[0]).abs() < 0.005 && (m[1] - c[1]).abs() < 0.005,
                "{c:?} edges {e:?} shade {shade:?}: {m:?}"
            );
        }
    }

    #[test]
    fn a_flat_window_or_one_off_the_image_has_no_corner() {
        let flat = vec![0.5f32; 40 * 34];
        let g = Gray {
            width: 40,
            height: 34,
            data: &flat,
        };
        let dirs = [unit(0.0), unit(std::f64::consts::FRAC_PI_2)];
        assert_eq!(
            checker_corner(&g, [20.0, 17.0], dirs, 6.0),
            Err(Miss::NoContrast)
        );
        assert_eq!(
            checker_corner(&g, [3.0, 17.0], dirs, 6.0),
            Err(Miss::NearBorder)
        );
    }

    #[test]
    fn noise_does_not_pull_a_corner_towards_its_prediction() {
        // Uniform noise of ±20 % of the contrast; 40 noisy images, each predicted 1 px up and
        // left. The mean error stays within 0.02 px.
        let c = [20.37, 17.21];
        let e = [unit(0.2), unit(1.8)];
        let clean = corner_raster((40, 34), c, e, [0.0, 0.0]);
        let mut st = 11u64;
        let (mut su, mut sv) = (0.0, 0.0);
        let n = 40;
        for _ in 0..n {
            let data: Vec<f32> = clean
                .iter()
                .map(|&v| {
                    st = st
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    let u = (st >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                    v + (0.17 * u) as f32
                })
                .collect();
            let g = Gray {
                width: 40,
                height: 34,
                data: &data,
            };
            let m = checker_corner(&g, [c[0] - 1.0, c[1] - 1.0], e, 6.0).unwrap();
            su += m[0] - c[0];
            sv += m[1] - c[1];
        }
        let (mu, mv) = (su / n as f64, sv / n as f64);
        assert!(
            mu.abs() < 0.02 && mv.abs() < 0.02,
            "mean error {mu:+.4}, {mv:+.4}"
        );
    }
}
