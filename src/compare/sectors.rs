//! Sub-pixel location of targets by fitting the exact image of their printed edges to the
//! pixels around them: a checkerboard's inner corners and a Siemens star's centre (straight
//! edges through one point), and a large disk's outline (an ellipse, or the exact outline
//! where waves bend it).
//!
//! | item | value | meaning |
//! |---|---|---|
//! | model | `I = D + g·(p − q) + c(p)·(Δ + h·(p − q))` | `c(p)`: the share of pixel `p`'s square on the sectors of one colour (outside the disk) |
//! | corner | [`checker_corner`]: `q` (2) and the two edges' angles, fitted | window: the pixels within `half` px of the prediction; it must hold no other corner |
//! | star | [`star_centre`]: `q` (2) fitted, the sector edges' image directions given | window: an annulus, from where the sectors are resolved to inside the star's rim |
//! | disk | [`disk_edge`]: an ellipse's centre `q` (2) and shape (3), fitted | window: the pixels within `band` px of the expected outline; outliers trimmed twice |
//! | disk bent out of an ellipse (waves) | [`outline_edge`]: the exact outline polygon's shift (2), fitted | as the disk's |
//! | linear parameters | `D`, `g` (2), `Δ`, `h` (2) | solved by least squares at every step (variable projection) |
//! | fit | Levenberg–Marquardt, numerical derivatives ([`levenberg_marquardt`]) | |
//! | pixel filter | a box over the pixel's square | what poser asks of every backend; a symmetric filter does not move `q` |
//!
//! Near an inner corner the printed board is two straight edges crossing at the corner, and a
//! Siemens star is `2·spokes` sectors meeting at its centre; the projection keeps the edges
//! straight over the window (a port bends them only over many pixels). A box-filtered pixel
//! then holds the dark level `D`, plus the contrast `Δ` times `c(p)`, the area of its square
//! on the light sectors, which is exact by clipping the square with the sectors' half-planes.
//! Shading varies across the window: `g` carries it on the dark sectors, `h` the extra on the
//! light ones (a multiplicative gradient, to first order). The fitted `q` is the projected
//! point itself, with no centroid to correct: unlike a disk's, these targets' images are
//! points of the projection.
//!
//! Gradient methods (OpenCV's `cornerSubPix`: the point where the window's gradients point
//! away from) weight the edges by the blur of their pixels, which on slanted edges moves the
//! answer by 0.04–0.07 px; the fitted model has no such bias (tested to 0.005 px).

use super::detect::{Gray, Miss};

/// Signed distances are `n·(p − q)`, `n = (cos a, sin a)`; the area of the unit square at
/// `(x, y)` on the side where both of the given half-planes are positive.
fn clipped_area(x: f64, y: f64, planes: &[([f64; 2], f64)]) -> f64 {
    let square = vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
    polygon_area(&clip(square, planes))
}

/// The polygon `poly` clipped to where every half-plane `n·p ≥ c` of `planes` holds
/// (Sutherland–Hodgman: exact for a convex clip region, whatever the polygon); empty when
/// less than a triangle is left.
fn clip(mut poly: Vec<[f64; 2]>, planes: &[([f64; 2], f64)]) -> Vec<[f64; 2]> {
    for &(n, c) in planes {
        let s = |p: [f64; 2]| n[0] * p[0] + n[1] * p[1] - c;
        let mut out = Vec::with_capacity(poly.len() + 2);
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
            return Vec::new();
        }
    }
    poly
}

/// The area of the polygon `p` (shoelace; 0 for fewer than three points).
fn polygon_area(p: &[[f64; 2]]) -> f64 {
    let mut a2 = 0.0;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        a2 += a[0] * b[1] - b[0] * a[1];
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

/// A corner's or a star's contrast must be this many times the residuals' spread (per pixel:
/// their windows are small, and a noisy one gives no sure point).
const PIXEL_CONTRAST: f64 = 3.0;

/// Linear parameters' count: `D`, `g` (2), `Δ`, `h` (2).
const LINEAR: usize = 6;

impl Window {
    /// The pixels whose centres lie between `inner` and `outer` px of `centre`;
    /// [`Miss::NearBorder`] when that square leaves the image.
    fn annulus(img: &Gray, centre: [f64; 2], inner: f64, outer: f64) -> Result<Window, Miss> {
        let (x0, x1) = (
            (centre[0] - outer).floor() as i64,
            (centre[0] + outer).ceil() as i64,
        );
        let (y0, y1) = (
            (centre[1] - outer).floor() as i64,
            (centre[1] + outer).ceil() as i64,
        );
        if !(outer >= 2.0) || x0 < 0 || y0 < 0 || x1 >= img.width as i64 || y1 >= img.height as i64
        {
            return Err(Miss::NearBorder);
        }
        let mut win = Window {
            at: Vec::new(),
            value: Vec::new(),
        };
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                let r = (cx - centre[0]).hypot(cy - centre[1]);
                if r >= inner && r <= outer {
                    win.at.push((x as f64, y as f64));
                    win.value
                        .push(img.data[y as usize * img.width + x as usize] as f64);
                }
            }
        }
        Ok(win)
    }

    /// Residuals of the model with coverage `cover(x, y)` and shading about `q`, with the
    /// linear parameters solved for (returned too); `None` when they are not determined.
    fn residuals(
        &self,
        q: [f64; 2],
        cover: impl Fn(f64, f64) -> f64,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let mut rows = Vec::with_capacity(self.at.len() * LINEAR);
        for &(x, y) in &self.at {
            let c = cover(x, y);
            let (dx, dy) = (x + 0.5 - q[0], y + 0.5 - q[1]);
            rows.extend_from_slice(&[1.0, dx, dy, c, c * dx, c * dy]);
        }
        let lin = normal_solve(&rows, &self.value, LINEAR, 1e-12)?;
        let r = (0..self.value.len())
            .map(|i| {
                let row = &rows[i * LINEAR..(i + 1) * LINEAR];
                self.value[i] - row.iter().zip(&lin).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect();
        Some((r, lin))
    }

    /// Whether the fit at `q` found the pattern: its contrast (from [`Window::residuals`]'
    /// linear parameters) more than `ratio` times the residuals' robust spread, `q` within
    /// `reach` px of `predicted`.
    fn found(
        &self,
        fit: Option<(Vec<f64>, Vec<f64>)>,
        q: [f64; 2],
        predicted: [f64; 2],
        reach: f64,
        ratio: f64,
    ) -> bool {
        let Some((r, lin)) = fit else {
            return false;
        };
        // The residuals' spread as 1.4826 times their median absolute value (their standard
        // deviation for Gaussian noise): a rendered image's noise has a heavy tail of bright
        // pixels (rare light paths) that would inflate an RMS far beyond the typical pixel's.
        // At least a millionth of the level: a flat window fits any edge exactly.
        let spread = robust_spread(&r);
        lin[3].abs() > ratio * spread.max(1e-6 * lin[0].abs())
            && (q[0] - predicted[0]).hypot(q[1] - predicted[1]) <= reach
    }
}

/// 1.4826 times the median absolute value of `r` (the standard deviation of Gaussian noise);
/// infinite when `r` is empty.
fn robust_spread(r: &[f64]) -> f64 {
    let mut a: Vec<f64> = r.iter().map(|v| v.abs()).collect();
    a.sort_by(f64::total_cmp);
    1.4826 * a.get(a.len() / 2).copied().unwrap_or(f64::INFINITY)
}

/// Minimise the sum of squares of `residuals(p)` from `p0` by Levenberg–Marquardt with
/// central-difference derivatives (steps `steps`); stops when a step moves every parameter by
/// less than 10⁻⁷ or none lowers the cost. `None` when the residuals are not defined at `p0`.
fn levenberg_marquardt<const N: usize>(
    p0: [f64; N],
    steps: [f64; N],
    residuals: impl Fn(&[f64; N]) -> Option<Vec<f64>>,
) -> Option<[f64; N]> {
    let sse = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut p = p0;
    let mut r = residuals(&p)?;
    let mut cost = sse(&r);
    let mut damping = 1e-3;
    for _ in 0..100 {
        let m = r.len();
        let mut jac = vec![0.0; m * N];
        for k in 0..N {
            let (mut hi, mut lo) = (p, p);
            hi[k] += steps[k];
            lo[k] -= steps[k];
            let (rh, rl) = (residuals(&hi)?, residuals(&lo)?);
            for i in 0..m {
                // d(residual)/d(param); the step solves J δ = −r.
                jac[i * N + k] = (rh[i] - rl[i]) / (2.0 * steps[k]);
            }
        }
        let neg_r: Vec<f64> = r.iter().map(|v| -v).collect();
        let mut improved = false;
        for _ in 0..12 {
            let Some(delta) = normal_solve(&jac, &neg_r, N, damping) else {
                damping *= 10.0;
                continue;
            };
            let trial: [f64; N] = std::array::from_fn(|k| p[k] + delta[k]);
            if let Some(rt) = residuals(&trial) {
                let ct = sse(&rt);
                if ct < cost {
                    p = trial;
                    r = rt;
                    cost = ct;
                    damping = (damping * 0.3).max(1e-9);
                    improved = true;
                    if delta.iter().all(|d| d.abs() < 1e-7) {
                        return Some(p);
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
    Some(p)
}

/// Sub-pixel position (pixel centres at +0.5) of a checkerboard's inner corner expected at
/// `predicted`, its two edges running along the image directions `dirs` there (from the
/// projected neighbouring corners; they need not be exact). The window holds the pixels whose
/// centres lie within `half` px of the prediction, and must hold no other corner.
/// [`Miss::NearBorder`] when it leaves the image, [`Miss::NoContrast`] when the fit finds no
/// corner there (no contrast, parallel edges, or `q` more than half the window from the
/// prediction).
pub fn checker_corner(
    img: &Gray,
    predicted: [f64; 2],
    dirs: [[f64; 2]; 2],
    half: f64,
) -> Result<[f64; 2], Miss> {
    let win = Window::annulus(img, predicted, 0.0, half)?;
    // An edge along direction d has its normal at d's angle + 90°.
    let normal = |d: [f64; 2]| d[1].atan2(d[0]) + std::f64::consts::FRAC_PI_2;
    let fit = |p: &[f64; 4]| {
        let q = [p[0], p[1]];
        win.residuals(q, |x, y| coverage(x, y, q, p[2], p[3]))
    };
    let p0 = [predicted[0], predicted[1], normal(dirs[0]), normal(dirs[1])];
    let p = levenberg_marquardt(p0, [1e-4, 1e-4, 1e-5, 1e-5], |p| fit(p).map(|f| f.0))
        .ok_or(Miss::NoContrast)?;
    let q = [p[0], p[1]];
    if !win.found(fit(&p), q, predicted, 0.5 * half, PIXEL_CONTRAST)
        || !((p[2] - p[3]).sin().abs() > 0.2)
    {
        return Err(Miss::NoContrast);
    }
    Ok(q)
}

/// The share of the pixel square at `(x, y)` on a star's light sectors: those between the
/// edges `dirs[2k]` and `dirs[2k + 1]` (image directions from the centre `q`, in order of
/// increasing angle, each sector under 180°).
fn star_coverage(x: f64, y: f64, q: [f64; 2], dirs: &[[f64; 2]]) -> f64 {
    let corners = [[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
    let n = dirs.len();
    let mut sum = 0.0;
    for k in (0..n).step_by(2) {
        let (a, b) = (dirs[k], dirs[(k + 1) % n]);
        // Inside: left of a (a × (p − q) ≥ 0) and right of b (b × (p − q) ≤ 0). The normals
        // n·p ≥ c: n = (−a_y, a_x) for a, (b_y, −b_x) for b.
        let na = [-a[1], a[0]];
        let nb = [b[1], -b[0]];
        let ca = na[0] * q[0] + na[1] * q[1];
        let cb = nb[0] * q[0] + nb[1] * q[1];
        let outside = |n: [f64; 2], c: f64| corners.iter().all(|p| n[0] * p[0] + n[1] * p[1] < c);
        if outside(na, ca) || outside(nb, cb) {
            continue;
        }
        sum += clipped_area(x, y, &[(na, ca), (nb, cb)]);
    }
    sum
}

/// Sub-pixel position (pixel centres at +0.5) of a Siemens star's centre expected at
/// `predicted`: its sector edges run from the centre along the image directions `dirs` (in
/// order of increasing angle, light sectors from `dirs[2k]` to `dirs[2k + 1]`, from the
/// exact projection of the spokes). Fitted over the annulus from `inner` px (inside it the
/// sectors are narrower than the pixels) to `outer` px (inside the star's rim).
/// [`Miss::NearBorder`] when the annulus leaves the image, [`Miss::NoContrast`] when the fit
/// finds no star (no contrast, or the centre more than `inner` px from the prediction).
pub fn star_centre(
    img: &Gray,
    predicted: [f64; 2],
    dirs: &[[f64; 2]],
    inner: f64,
    outer: f64,
) -> Result<[f64; 2], Miss> {
    let win = Window::annulus(img, predicted, inner, outer)?;
    if dirs.len() < 4 || dirs.len() % 2 != 0 || win.at.len() < 16 {
        return Err(Miss::NoContrast);
    }
    let fit = |p: &[f64; 2]| win.residuals(*p, |x, y| star_coverage(x, y, *p, dirs));
    let q = levenberg_marquardt(predicted, [1e-4, 1e-4], |p| fit(p).map(|f| f.0))
        .ok_or(Miss::NoContrast)?;
    if !win.found(fit(&q), q, predicted, inner, PIXEL_CONTRAST) {
        return Err(Miss::NoContrast);
    }
    Ok(q)
}

/// The share of the pixel square at `(x, y)` outside the ellipse `(p − q)ᵀ m (p − q) ≤ 1`
/// (`m` = `[m₁₁, m₁₂, m₂₂]`), its edge taken as straight across the pixel: the tangent at the
/// first-order signed distance of the pixel's centre (exact for a straight edge; for an edge
/// of curvature radius ρ px the area is off by under 1/(8ρ) of the pixel, alike all round).
fn ellipse_outside(x: f64, y: f64, q: [f64; 2], m: [f64; 3]) -> f64 {
    let (cx, cy) = (x + 0.5, y + 0.5);
    let Some((dist, n)) = ellipse_distance([cx, cy], q, m) else {
        return 0.0;
    };
    if dist >= 0.75 {
        return 1.0;
    }
    if dist <= -0.75 {
        return 0.0;
    }
    clipped_area(x, y, &[(n, n[0] * cx + n[1] * cy - dist)])
}

/// The first-order signed distance (px, positive outside) from `p` to the ellipse
/// `(x − q)ᵀ m (x − q) = 1`, and the unit outward normal there; `None` at the centre.
fn ellipse_distance(p: [f64; 2], q: [f64; 2], m: [f64; 3]) -> Option<(f64, [f64; 2])> {
    let d = [p[0] - q[0], p[1] - q[1]];
    let md = [m[0] * d[0] + m[1] * d[1], m[1] * d[0] + m[2] * d[1]];
    let s2 = d[0] * md[0] + d[1] * md[1];
    if !(s2 > 1e-300) {
        return None;
    }
    let s = s2.sqrt();
    // ∇√(dᵀ m d) = m d / s; the distance to the level 1 is (s − 1) / |∇|.
    let g = [md[0] / s, md[1] / s];
    let gl = g[0].hypot(g[1]);
    Some(((s - 1.0) / gl, [g[0] / gl, g[1] / gl]))
}

/// The ellipse with the area centroid and second moments of the polygon `p`: its centre `q`
/// and `m` of `(x − q)ᵀ m (x − q) ≤ 1` (a filled ellipse's covariance is `m⁻¹/4`). `None`
/// for a degenerate polygon.
pub fn moment_ellipse(p: &[[f64; 2]]) -> Option<([f64; 2], [f64; 3])> {
    let q = super::detect::polygon_centroid(p)?;
    let (mut a, mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let j = (i + 1) % p.len();
        let (x0, y0) = (p[i][0] - q[0], p[i][1] - q[1]);
        let (x1, y1) = (p[j][0] - q[0], p[j][1] - q[1]);
        let c = x0 * y1 - x1 * y0;
        a += 0.5 * c;
        xx += c * (x0 * x0 + x0 * x1 + x1 * x1) / 12.0;
        yy += c * (y0 * y0 + y0 * y1 + y1 * y1) / 12.0;
        xy += c * (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) / 24.0;
    }
    let (sxx, sxy, syy) = (xx / a, xy / a, yy / a);
    let det = 4.0 * (sxx * syy - sxy * sxy);
    (a.abs() > 1e-12 && det > 1e-300 && det.is_finite())
        .then(|| (q, [syy / det, -sxy / det, sxx / det]))
}

/// The largest distance (px, first order) of the points `p` from the ellipse `(x − q)ᵀ m
/// (x − q) = 1`: how far an outline is from the ellipse [`disk_edge`] fits.
pub fn ellipse_misfit(p: &[[f64; 2]], q: [f64; 2], m: [f64; 3]) -> f64 {
    p.iter()
        .map(|&p| ellipse_distance(p, q, m).map_or(f64::INFINITY, |(d, _)| d.abs()))
        .fold(
            0.0,
            |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
        )
}

/// Sub-pixel area centroid (pixel centres at +0.5) of a disk's image whose exact outline is
/// expected along the polygon `outline`, found by fitting an ellipse's edge to the pixels
/// within `band` px of it: centre (2) and shape (3) by Levenberg–Marquardt, the dark inside and
/// light outside levels each a plane ([`Window::residuals`]). The edge is where the printed
/// contrast is, so light that is smooth across it, the water's veil of backscatter and the
/// glow of forward scatter that pull an area centroid, leaves it in place. Meant for disks of
/// many pixels (the ellipse is a perspective view of a circle; a port's bending of it over the
/// disk is second order). [`Miss::NearBorder`] when the band leaves the image,
/// [`Miss::NoContrast`] when the fit finds no edge (no contrast, or a centre more than `band`
/// px from the outline's).
pub fn disk_edge(img: &Gray, outline: &[[f64; 2]], band: f64) -> Result<[f64; 2], Miss> {
    let (q0, m0) = moment_ellipse(outline).ok_or(Miss::NoContrast)?;
    // The shape's parameters in units of m0's scale, so that all five are of order 1.
    let scale = m0[0].abs().max(m0[2].abs());
    let shape = |p: &[f64; 5]| [p[2] * scale, p[3] * scale, p[4] * scale];
    let p = edge_fit(
        img,
        outline,
        q0,
        band,
        |x, y| ellipse_distance([x, y], q0, m0).map(|(d, _)| d),
        [q0[0], q0[1], m0[0] / scale, m0[1] / scale, m0[2] / scale],
        [1e-4, 1e-4, 1e-6, 1e-6, 1e-6],
        |x, y, p| ellipse_outside(x, y, [p[0], p[1]], shape(p)),
    )?;
    if !(p[2] * p[4] > p[3] * p[3]) {
        return Err(Miss::NoContrast);
    }
    Ok([p[0], p[1]])
}

/// [`disk_edge`] for a disk whose exact outline is no ellipse (seen through waves, which bend
/// it by pixels): the outline polygon itself, shifted, fitted to the pixels within `band` px
/// of it (only the shift, 2 parameters; the shape is the truth's). Returns the shifted
/// polygon's area centroid, comparable with the exact one. `outline` must be a simple polygon
/// fine enough that its chords follow the edge (256 points around a disk of tens of pixels).
pub fn outline_edge(img: &Gray, outline: &[[f64; 2]], band: f64) -> Result<[f64; 2], Miss> {
    let q0 = super::detect::polygon_centroid(outline).ok_or(Miss::NoContrast)?;
    let p = edge_fit(
        img,
        outline,
        q0,
        band,
        |x, y| polygon_distance([x, y], outline),
        [0.0, 0.0],
        [1e-4, 1e-4],
        |x, y, t| polygon_outside(x - t[0], y - t[1], outline),
    )?;
    Ok([q0[0] + p[0], q0[1] + p[1]])
}

/// The fit shared by [`disk_edge`] and [`outline_edge`]: the pixels whose centres lie within
/// `band` px of the expected edge (`distance(x, y)`, signed, of a pixel centre), the model's
/// parameters from `p0` (first two: the centre, or the shift, in px; `steps` for the
/// derivatives) and the share of each pixel outside the disk, `outside(x, y, p)` (the pixel
/// square's corner), fitted by Levenberg–Marquardt with the levels linear
/// ([`Window::residuals`] about `centre`), then twice again without the pixels more than 4
/// robust spreads off (a render's rare bright pixels would pull a least-squares edge).
#[allow(clippy::too_many_arguments)]
fn edge_fit<const N: usize>(
    img: &Gray,
    outline: &[[f64; 2]],
    centre: [f64; 2],
    band: f64,
    distance: impl Fn(f64, f64) -> Option<f64>,
    p0: [f64; N],
    steps: [f64; N],
    outside: impl Fn(f64, f64, &[f64; N]) -> f64,
) -> Result<[f64; N], Miss> {
    let reach = outline
        .iter()
        .map(|p| (p[0] - centre[0]).hypot(p[1] - centre[1]))
        .fold(0.0, f64::max)
        + band;
    let mut win = Window::annulus(img, centre, 0.0, reach)?;
    let keep: Vec<bool> = win
        .at
        .iter()
        .map(|&(x, y)| distance(x + 0.5, y + 0.5).is_some_and(|d| d.abs() <= band))
        .collect();
    let mut k = keep.iter();
    win.at.retain(|_| *k.next().unwrap_or(&false));
    let mut k = keep.iter();
    win.value.retain(|_| *k.next().unwrap_or(&false));
    if win.at.len() < 32 {
        return Err(Miss::NoContrast);
    }
    let fit = |win: &Window, p: &[f64; N]| win.residuals(centre, |x, y| outside(x, y, p));
    let mut p = p0;
    for round in 0..3 {
        p = levenberg_marquardt(p, steps, |p| fit(&win, p).map(|f| f.0)).ok_or(Miss::NoContrast)?;
        if round == 2 {
            break;
        }
        let r = fit(&win, &p).ok_or(Miss::NoContrast)?.0;
        let limit = 4.0 * robust_spread(&r);
        let mut keep = r.iter().map(|v| v.abs() <= limit);
        win.at.retain(|_| keep.next().unwrap_or(false));
        let mut keep = r.iter().map(|v| v.abs() <= limit);
        win.value.retain(|_| keep.next().unwrap_or(false));
        if win.at.len() < 32 {
            return Err(Miss::NoContrast);
        }
    }
    // The contrast is fitted from thousands of pixels: found when it stands 10 standard
    // errors (about 2·spread/√n, half the pixels on either side) above zero, however noisy
    // each pixel is; and the centre (or shift) within `band` px of where it was expected.
    let ratio = 20.0 / (win.at.len() as f64).sqrt();
    let moved = [p[0] - p0[0], p[1] - p0[1]];
    if !win.found(fit(&win, &p), moved, [0.0, 0.0], band, ratio) {
        return Err(Miss::NoContrast);
    }
    Ok(p)
}

/// The signed distance (px, positive outside) from `p` to the polygon `poly`: the distance
/// to its nearest edge, negative inside (by the crossing rule).
fn polygon_distance(p: [f64; 2], poly: &[[f64; 2]]) -> Option<f64> {
    if poly.len() < 3 {
        return None;
    }
    let mut best = f64::INFINITY;
    let mut inside = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let l2 = ex * ex + ey * ey;
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((p[0] - a[0] - t * ex).hypot(p[1] - a[1] - t * ey));
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
        {
            inside = !inside;
        }
    }
    Some(if inside { -best } else { best })
}

/// The share of the unit pixel square at `(x, y)` outside the simple polygon `poly`: exact, by
/// clipping the polygon with the square's four sides (Sutherland–Hodgman; the square is
/// convex, so a concave polygon's clipped area is right too). Pixels whose centre is more than
/// 0.75 px from the edge are wholly in or out.
fn polygon_outside(x: f64, y: f64, poly: &[[f64; 2]]) -> f64 {
    let Some(d) = polygon_distance([x + 0.5, y + 0.5], poly) else {
        return 0.0;
    };
    if d >= 0.75 {
        return 1.0;
    }
    if d <= -0.75 {
        return 0.0;
    }
    let square = [
        ([1.0, 0.0], x),
        ([-1.0, 0.0], -(x + 1.0)),
        ([0.0, 1.0], y),
        ([0.0, -1.0], -(y + 1.0)),
    ];
    (1.0 - polygon_area(&clip(poly.to_vec(), &square))).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w` × `h` image box-filtered by `s` × `s` supersampling of `level(x − c)`.
    fn supersample(
        (w, h): (usize, usize),
        c: [f64; 2],
        s: usize,
        level: impl Fn(f64, f64) -> f64,
    ) -> Vec<f32> {
        let mut img = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for j in 0..s {
                    for i in 0..s {
                        let px = x as f64 + (i as f64 + 0.5) / s as f64 - c[0];
                        let py = y as f64 + (j as f64 + 0.5) / s as f64 - c[1];
                        sum += level(px, py);
                    }
                }
                img[y * w + x] = (sum / (s * s) as f64) as f32;
            }
        }
        img
    }

    /// A checkerboard corner at `c`, its edges along `e1`, `e2`, box-filtered by 64 × 64
    /// supersampling, levels `dark` and `light` times `1 + shade·(x − c)`.
    fn corner_raster(
        size: (usize, usize),
        c: [f64; 2],
        e: [[f64; 2]; 2],
        shade: [f64; 2],
    ) -> Vec<f32> {
        let (dark, light) = (0.05, 0.9);
        supersample(size, c, 64, |px, py| {
            // Signed distances to the two edges (their normals: e rotated 90°).
            let u = -e[0][1] * px + e[0][0] * py;
            let v = -e[1][1] * px + e[1][0] * py;
            let level = if (u > 0.0) == (v > 0.0) { light } else { dark };
            level * (1.0 + shade[0] * px + shade[1] * py)
        })
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

    /// A Siemens star of `spokes` spokes centred at `c`, seen through the linear map `m` (a
    /// perspective view, locally), box-filtered by 32 × 32 supersampling; and its edges' image
    /// directions, light sectors first.
    fn star_raster(
        size: (usize, usize),
        c: [f64; 2],
        spokes: usize,
        m: [[f64; 2]; 2],
    ) -> (Vec<f32>, Vec<[f64; 2]>) {
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let inv = [
            [m[1][1] / det, -m[0][1] / det],
            [-m[1][0] / det, m[0][0] / det],
        ];
        let sector = std::f64::consts::PI / spokes as f64;
        let img = supersample(size, c, 32, |px, py| {
            let (u, v) = (
                inv[0][0] * px + inv[0][1] * py,
                inv[1][0] * px + inv[1][1] * py,
            );
            let a = v.atan2(u).rem_euclid(std::f64::consts::TAU);
            if ((a / sector).floor() as u64).is_multiple_of(2) {
                0.9
            } else {
                0.05
            }
        });
        let dirs = (0..2 * spokes)
            .map(|k| {
                let a = k as f64 * sector;
                let (u, v) = (a.cos(), a.sin());
                let d = [m[0][0] * u + m[0][1] * v, m[1][0] * u + m[1][1] * v];
                let n = d[0].hypot(d[1]);
                [d[0] / n, d[1] / n]
            })
            .collect();
        (img, dirs)
    }

    #[test]
    fn finds_a_siemens_stars_centre_to_a_hundredth_of_a_pixel() {
        // Seen square on, and obliquely (foreshortened and sheared); predicted 1.5 px off.
        for m in [[[1.0, 0.0], [0.0, 1.0]], [[0.95, 0.12], [-0.05, 0.7]]] {
            let c = [40.37, 39.81];
            let (data, dirs) = star_raster((80, 80), c, 12, m);
            let g = Gray {
                width: 80,
                height: 80,
                data: &data,
            };
            let q = star_centre(&g, [c[0] + 1.2, c[1] - 0.9], &dirs, 6.0, 24.0).unwrap();
            assert!(
                (q[0] - c[0]).abs() < 0.01 && (q[1] - c[1]).abs() < 0.01,
                "{m:?}: {q:?}"
            );
        }
        // A blank window has no star.
        let flat = vec![0.5f32; 80 * 80];
        let g = Gray {
            width: 80,
            height: 80,
            data: &flat,
        };
        let (_, dirs) = star_raster((4, 4), [2.0, 2.0], 12, [[1.0, 0.0], [0.0, 1.0]]);
        assert_eq!(
            star_centre(&g, [40.0, 40.0], &dirs, 6.0, 24.0),
            Err(Miss::NoContrast)
        );
    }

    /// An ellipse centred at `c` (semi-axes `a`, `b`, the first at `angle`), dark `0.05` in
    /// light `0.9`, box-filtered by 16 × 16 supersampling, plus `veil(x − c)` everywhere.
    fn ellipse_raster(
        size: (usize, usize),
        c: [f64; 2],
        (a, b, angle): (f64, f64, f64),
        veil: impl Fn(f64, f64) -> f64,
    ) -> Vec<f32> {
        let (ca, sa) = (angle.cos(), angle.sin());
        supersample(size, c, 16, |px, py| {
            let (u, v) = (ca * px + sa * py, -sa * px + ca * py);
            let inside = (u / a).powi(2) + (v / b).powi(2) < 1.0;
            (if inside { 0.05 } else { 0.9 }) + veil(px, py)
        })
    }

    /// The outline of that ellipse, 64 points.
    fn ellipse_outline(c: [f64; 2], (a, b, angle): (f64, f64, f64)) -> Vec<[f64; 2]> {
        (0..64)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 64.0;
                let (u, v) = (a * t.cos(), b * t.sin());
                [
                    c[0] + angle.cos() * u - angle.sin() * v,
                    c[1] + angle.sin() * u + angle.cos() * v,
                ]
            })
            .collect()
    }

    #[test]
    fn a_disks_edge_locates_it_under_a_veil_that_pulls_its_centroid() {
        // An oblique disk 60 × 42 px across, under a veil of backscatter that rises from 0.1
        // to 0.5 across it (the light scattered towards the camera in front of a lamp).
        let c = [60.37, 55.81];
        let shape = (30.0, 21.0, 0.4);
        let veil = |x: f64, _y: f64| 0.3 + 0.004 * x;
        let data = ellipse_raster((120, 112), c, shape, veil);
        let g = Gray {
            width: 120,
            height: 112,
            data: &data,
        };
        // Expected from a slightly wrong outline (1 px off, 3 % too large), as a port's
        // bending or a pose error would give.
        let guess: Vec<[f64; 2]> = ellipse_outline([c[0] + 0.8, c[1] - 0.6], shape)
            .iter()
            .map(|p| [c[0] + 1.03 * (p[0] - c[0]), c[1] + 1.03 * (p[1] - c[1])])
            .collect();
        let q = disk_edge(&g, &guess, 5.0).unwrap();
        assert!(
            (q[0] - c[0]).abs() < 0.01 && (q[1] - c[1]).abs() < 0.01,
            "edge: {q:?}"
        );
        // The area centroid of the darkness is pulled by the veil (0.69 px).
        let m = super::super::detect::disk_centroid(&g, c, 36.0, 0.05 / 0.9).unwrap();
        assert!((m[0] - c[0]).abs() > 0.5, "centroid: {m:?}");
        // A blank window has no disk.
        let flat = vec![0.5f32; 120 * 112];
        let g = Gray {
            width: 120,
            height: 112,
            data: &flat,
        };
        assert_eq!(disk_edge(&g, &guess, 5.0), Err(Miss::NoContrast));
    }

    #[test]
    fn a_disk_bent_by_waves_is_located_by_its_exact_outline() {
        // A disk's outline bent out of any ellipse (radius 16 px, ±2.4 px and ±1.3 px waves
        // around it), under a veil, drawn 0.37, −0.61 px from where its exact outline (64
        // points) says.
        let r = |t: f64| 16.0 * (1.0 + 0.15 * (3.0 * t).sin() + 0.08 * (5.0 * t + 1.0).cos());
        let (c, shift) = ([40.2, 38.7], [0.37, -0.61]);
        let veil = |x: f64, y: f64| 0.3 + 0.004 * x - 0.002 * y;
        let data = supersample((80, 78), [c[0] + shift[0], c[1] + shift[1]], 16, |x, y| {
            let inside = x.hypot(y) < r(y.atan2(x));
            (if inside { 0.05 } else { 0.9 }) + veil(x, y)
        });
        let g = Gray {
            width: 80,
            height: 78,
            data: &data,
        };
        let outline: Vec<[f64; 2]> = (0..64)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 64.0;
                [c[0] + r(t) * t.cos(), c[1] + r(t) * t.sin()]
            })
            .collect();
        let (q0, m0) = moment_ellipse(&outline).unwrap();
        assert!(ellipse_misfit(&outline, q0, m0) > 1.0, "not an ellipse");
        let want = super::super::detect::polygon_centroid(&outline).unwrap();
        let q = outline_edge(&g, &outline, 4.0).unwrap();
        assert!(
            (q[0] - want[0] - shift[0]).abs() < 0.01 && (q[1] - want[1] - shift[1]).abs() < 0.01,
            "{q:?} for {want:?} + {shift:?}"
        );
        // The polygon's coverage of a pixel is exact: a square half inside a straight edge.
        let square = [[0.5, -5.0], [9.0, -5.0], [9.0, 5.0], [0.5, 5.0]];
        assert!((polygon_outside(0.0, 0.0, &square) - 0.5).abs() < 1e-12);
        // A blank window has no disk.
        let flat = vec![0.5f32; 80 * 78];
        let g = Gray {
            width: 80,
            height: 78,
            data: &flat,
        };
        assert_eq!(outline_edge(&g, &outline, 4.0), Err(Miss::NoContrast));
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
