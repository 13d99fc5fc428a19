//! Sub-pixel location of disk targets in rendered linear images, without perspective bias.
//!
//! A dark disk on a bright background is located by the area centroid of its "darkness"
//! `w = (B − I)/(B − D)` inside a window around its predicted position, where the background
//! B comes from the window's border (a plane fitted to it on windows of [`PLANE_WINDOW_PX`]
//! or more, so that a shading gradient does not pull the centroid; its median on smaller
//! ones) and D is the disk's printed level. With a box pixel
//! filter and a linear image, `w` is the fraction of each pixel covered by the disk, so the
//! weighted centroid is the centroid of the disk's *image*. That image centroid is not the
//! projection of the disk's centre (perspective and refraction shift it), so the truth to
//! compare with is [`expected_centroid`]: the area centroid of the exactly projected disk
//! outline. Both sides then measure the same quantity and no bias remains.
//!
//! The centroid sums the whole window, so light that is not the print's, smooth across the
//! disk but not flat (the veil of backscatter in front of a lamp, the glow of forward
//! scatter), pulls it. Disks [`crate::compare::EDGE_FIT_PX`] or more in radius are therefore
//! located by their edge instead ([`crate::compare::sectors::disk_edge`]).

use glam::DVec3;

/// A single-channel linear image, row-major, row 0 at the top.
pub struct Gray<'a> {
    pub width: usize,
    pub height: usize,
    pub data: &'a [f32],
}

impl Gray<'_> {
    fn at(&self, x: usize, y: usize) -> f64 {
        self.data[y * self.width + x] as f64
    }
}

/// Why a target could not be measured.
#[derive(Debug, Clone, PartialEq)]
pub enum Miss {
    /// The window around the prediction leaves the image.
    NearBorder,
    /// No contrast between disk and background (unlit, or not in the image).
    NoContrast,
}

/// Measured centroid (pixel coordinates, centres at +0.5) of a dark disk expected near
/// `predicted`, searching a square window of half-size `radius` px. `dark` is the disk's
/// printed reflectance relative to the background's (e.g. 0.05/0.9); the background level is
/// the median of the window border.
pub fn disk_centroid(
    img: &Gray,
    predicted: [f64; 2],
    radius: f64,
    dark: f64,
) -> Result<[f64; 2], Miss> {
    // A window this large or larger takes the white level as a plane fitted to its border
    // (rounded down: the ring stays inside `radius`, clear of the surround's edge); a smaller
    // one as the border's median (rounded up). A shading gradient's pull on the centroid grows
    // as the window's size to the fourth power over the disk's area, while the fitted slope
    // adds the border's noise: on the canonical scenes' 7–11 px windows the plane made
    // Mitsuba's dispersion check 0.039 → 0.053 px; on calibration_flat's 29 px windows at full
    // size the median left 0.11 px of strobe fall-off in every backend.
    let plane_fit = radius >= PLANE_WINDOW_PX;
    let r = if plane_fit {
        radius.floor()
    } else {
        radius.ceil()
    } as i64;
    let (px, py) = (predicted[0].floor() as i64, predicted[1].floor() as i64);
    let (x0, x1, y0, y1) = (px - r, px + r, py - r, py + r);
    if x0 < 0 || y0 < 0 || x1 >= img.width as i64 || y1 >= img.height as i64 {
        return Err(Miss::NearBorder);
    }
    // The background: a plane fitted to the window's border ring (the white surround), so
    // that a shading gradient across the window (a strobe's fall-off) does not pull the
    // centroid; a level taken as one number biased it by about 0.1 px on a 60 px window.
    let mut border = Vec::new();
    for x in x0..=x1 {
        border.push((x, y0));
        border.push((x, y1));
    }
    for y in y0 + 1..y1 {
        border.push((x0, y));
        border.push((x1, y));
    }
    let samples: Vec<[f64; 3]> = border
        .iter()
        .map(|&(x, y)| {
            [
                (x - px) as f64,
                (y - py) as f64,
                img.at(x as usize, y as usize),
            ]
        })
        .collect();
    let plane = if plane_fit {
        background_plane(&samples)
    } else {
        median_level(&samples).map(|m| [m, 0.0, 0.0])
    };
    let Some(plane) = plane else {
        return Err(Miss::NoContrast);
    };
    let bg = |x: i64, y: i64| plane[0] + plane[1] * (x - px) as f64 + plane[2] * (y - py) as f64;
    if !(plane.iter().all(|v| v.is_finite()) && bg(px, py) * (1.0 - dark) > 0.0) {
        return Err(Miss::NoContrast);
    }
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in y0 + 1..y1 {
        for x in x0 + 1..x1 {
            let b = bg(x, y);
            let depth = b * (1.0 - dark);
            if depth <= 0.0 {
                return Err(Miss::NoContrast);
            }
            let w = ((b - img.at(x as usize, y as usize)) / depth).clamp(-0.5, 1.5);
            sw += w;
            sx += w * (x as f64 + 0.5);
            sy += w * (y as f64 + 0.5);
        }
    }
    if sw < 0.5 {
        return Err(Miss::NoContrast);
    }
    Ok([sx / sw, sy / sw])
}

/// The median of border samples' values `[x, y, v]` (`None` without samples).
fn median_level(samples: &[[f64; 3]]) -> Option<f64> {
    let mut levels: Vec<f64> = samples.iter().map(|s| s[2]).collect();
    levels.sort_by(|a, b| a.total_cmp(b));
    levels.get(levels.len() / 2).copied()
}

/// The half-size (px) from which a window's white level is a fitted plane, not one number.
pub const PLANE_WINDOW_PX: f64 = 16.0;

/// The plane `v = a + b·x + c·y` through border samples `[x, y, v]`: `[a, b, c]`. Robust to
/// the few samples that are not the surround (a speck of noise, the card's edge where an outer
/// disk's window reaches it): starting from the median level, twice keep the samples within 4
/// median absolute deviations of the current plane and fit it again by least squares. `None`
/// when the samples do not determine it.
fn background_plane(samples: &[[f64; 3]]) -> Option<[f64; 3]> {
    let mut plane = [median_level(samples)?, 0.0, 0.0];
    for _ in 0..2 {
        let off = |s: &[f64; 3]| (s[2] - (plane[0] + plane[1] * s[0] + plane[2] * s[1])).abs();
        let mut dev: Vec<f64> = samples.iter().map(off).collect();
        dev.sort_by(|a, b| a.total_cmp(b));
        // A noise-free surround (MAD 0) keeps the samples on the plane, to rounding.
        let limit = (4.0 * dev[dev.len() / 2]).max(1e-9 * plane[0].abs());
        let mut m = glam::DMat3::ZERO;
        let mut r = DVec3::ZERO;
        for s in samples.iter().filter(|s| off(s) <= limit) {
            let u = DVec3::new(1.0, s[0], s[1]);
            m += glam::DMat3::from_cols(u * u.x, u * u.y, u * u.z);
            r += u * s[2];
        }
        if m.determinant().abs() < 1e-9 {
            return None;
        }
        let p = m.inverse() * r;
        plane = [p.x, p.y, p.z];
    }
    Some(plane)
}

/// Area centroid of the image of a disk of `radius` m centred at `center` with unit normal
/// `normal` (world), given the exact projection `project` (world point → pixel). `None` when
/// any outline point has no pixel.
pub fn expected_centroid(
    center: DVec3,
    normal: DVec3,
    radius: f64,
    project: impl Fn(DVec3) -> Option<[f64; 2]>,
) -> Option<[f64; 2]> {
    let n = normal.normalize();
    let a = n.any_orthonormal_vector();
    let b = n.cross(a);
    const N: usize = 512;
    let mut pts = Vec::with_capacity(N);
    for k in 0..N {
        let t = std::f64::consts::TAU * k as f64 / N as f64;
        pts.push(project(center + radius * (t.cos() * a + t.sin() * b))?);
    }
    polygon_centroid(&pts)
}

/// Area centroid of a simple polygon (shoelace).
pub fn polygon_centroid(p: &[[f64; 2]]) -> Option<[f64; 2]> {
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    let o = p.first()?;
    for i in 0..p.len() {
        let (x0, y0) = (p[i][0] - o[0], p[i][1] - o[1]);
        let j = (i + 1) % p.len();
        let (x1, y1) = (p[j][0] - o[0], p[j][1] - o[1]);
        let c = x0 * y1 - x1 * y0;
        a += c;
        cx += (x0 + x1) * c;
        cy += (y0 + y1) * c;
    }
    if a.abs() < 1e-300 {
        return None;
    }
    Some([o[0] + cx / (3.0 * a), o[1] + cy / (3.0 * a)])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Render a disk by exact supersampled coverage into a box-filtered image.
    fn raster(w: usize, h: usize, c: [f64; 2], r: f64, bg: f32, fg: f32) -> Vec<f32> {
        let s = 16;
        let mut img = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut inside = 0;
                for j in 0..s {
                    for i in 0..s {
                        let px = x as f64 + (i as f64 + 0.5) / s as f64;
                        let py = y as f64 + (j as f64 + 0.5) / s as f64;
                        if (px - c[0]).powi(2) + (py - c[1]).powi(2) < r * r {
                            inside += 1;
                        }
                    }
                }
                let f = inside as f32 / (s * s) as f32;
                img[y * w + x] = bg * (1.0 - f) + fg * f;
            }
        }
        img
    }

    #[test]
    fn finds_a_disk_to_a_hundredth_of_a_pixel() {
        let c = [31.37, 22.81];
        let data = raster(64, 48, c, 4.2, 0.9, 0.05);
        let g = Gray {
            width: 64,
            height: 48,
            data: &data,
        };
        let m = disk_centroid(&g, [30.0, 24.0], 9.0, 0.05 / 0.9).unwrap();
        assert!(
            (m[0] - c[0]).abs() < 0.01 && (m[1] - c[1]).abs() < 0.01,
            "{m:?}"
        );
    }

    #[test]
    fn a_shading_gradient_across_the_window_does_not_move_the_disk() {
        // A strobe's fall-off: the light changes by 1 % per pixel in x and 0.3 % in y across
        // the window (the disk's printed black and the white surround alike). A white level
        // taken as one number (the border's median) put this disk 2.17 px off in x and 0.65 px
        // in y on a 14 px window (the same sums in NumPy); the plane fitted to the border of
        // this 20 px window keeps it within 0.01 px. A speck on the border (a hot pixel) is
        // left out of the fit.
        let c = [40.37, 30.81];
        let (w, h) = (80, 60);
        let mut data = raster(w, h, c, 8.0, 0.9, 0.05);
        for y in 0..h {
            for x in 0..w {
                data[y * w + x] *= 1.0 + 0.01 * (x as f32 - 40.0) - 0.003 * (y as f32 - 30.0);
            }
        }
        let predicted = [40.0, 31.0];
        let (px, py) = (predicted[0] as usize, predicted[1] as usize);
        data[(py - 20) * w + px + 3] = 5.0;
        let g = Gray {
            width: w,
            height: h,
            data: &data,
        };
        let m = disk_centroid(&g, predicted, 20.0, 0.05 / 0.9).unwrap();
        assert!(
            (m[0] - c[0]).abs() < 0.01 && (m[1] - c[1]).abs() < 0.01,
            "{m:?} against {c:?}"
        );
    }

    #[test]
    fn reports_border_and_blank() {
        let data = vec![0.5f32; 32 * 32];
        let g = Gray {
            width: 32,
            height: 32,
            data: &data,
        };
        assert_eq!(
            disk_centroid(&g, [2.0, 2.0], 5.0, 0.1),
            Err(Miss::NearBorder)
        );
        assert_eq!(
            disk_centroid(&g, [16.0, 16.0], 5.0, 0.1),
            Err(Miss::NoContrast)
        );
    }

    #[test]
    fn oblique_disk_centroid_is_not_the_projected_centre() {
        // Pinhole f = 100 px, disk of radius 0.2 m at 1 m, tilted 60°: the image centroid
        // differs from the projection of the centre, and the polygon centroid captures it.
        let proj = |p: DVec3| Some([100.0 * p.x / p.z + 50.0, 100.0 * p.y / p.z + 50.0]);
        let c = DVec3::new(0.3, 0.0, 1.0);
        let n = DVec3::new(60f64.to_radians().sin(), 0.0, -60f64.to_radians().cos());
        let e = expected_centroid(c, n, 0.2, proj).unwrap();
        let pc = proj(c).unwrap();
        assert!((e[0] - pc[0]).abs() > 0.3, "{e:?} vs {pc:?}");
        assert!((e[1] - pc[1]).abs() < 1e-9);
        // A fronto-parallel disk's image centroid is the projected centre.
        let e2 = expected_centroid(DVec3::new(0.0, 0.0, 1.0), DVec3::Z, 0.2, proj).unwrap();
        assert!((e2[0] - 50.0).abs() < 1e-9 && (e2[1] - 50.0).abs() < 1e-9);
    }
}
