//! Calibration targets, scale bars and GSD targets: their 3D points and printed patterns.
//!
//! Every target lives in its own frame: printed face on z = 0, normal +z, centred on the
//! origin, extent `w × h` ([`extent`]) over x ∈ [-w/2, w/2], y ∈ [-h/2, h/2]. The printed
//! pattern is [`reflectance`] (0.05 black ink / 0.9 white paper); [`texture`] rasterises it
//! for backends that need an image: pixel column `i` ↔ x = -w/2 + (i+0.5)/ppm, row `j` ↔
//! y = h/2 - (j+0.5)/ppm (row 0 at +y), i.e. UV (0,0) is the (-x,-y) corner as in Blender and
//! Mitsuba.
//!
//! | kind | points (target frame) | extent |
//! |---|---|---|
//! | checkerboard | inner corners, row-major from (-x,-y) | `(cols+2)·square × (rows+2)·square` (one white square of margin) |
//! | circle_grid | disk centres, row-major from (-x,-y) | `cols·spacing × rows·spacing` |
//! | coded | centres of ring-coded disks on a near-square grid; ids = code numbers | `gc·spacing × gr·spacing` |
//! | scale_bar | the two disk centres at x = ∓length/2 | `(length + 2·diameter) × width` |
//! | siemens_star | the centre | `diameter × diameter` |
//! | test_object | disks at the 4 corners of every step's top face (z = step top) | `size × size` |
//! | disk | the centre; its id is the target's name | `2·diameter × 2·diameter` |

use crate::model::{Pose, TargetKind, TargetPoint};
use glam::DVec3;

/// Reflectance of black ink.
pub const BLACK: f64 = 0.05;
/// Reflectance of white paper.
pub const WHITE: f64 = 0.9;

/// Grid (cols, rows) used to lay out `count` coded targets.
pub fn coded_grid(count: u32) -> (u32, u32) {
    let cols = ((count as f64).sqrt().ceil() as u32).max(1);
    let rows = count.div_ceil(cols).max(1);
    (cols, rows)
}

/// Extent `(w, h)` of the target's printed face, m.
pub fn extent(kind: &TargetKind) -> (f64, f64) {
    match *kind {
        TargetKind::Checkerboard { cols, rows, square } => {
            ((cols + 2) as f64 * square, (rows + 2) as f64 * square)
        }
        TargetKind::CircleGrid {
            cols,
            rows,
            spacing,
            ..
        } => (cols as f64 * spacing, rows as f64 * spacing),
        TargetKind::Coded { count, spacing, .. } => {
            let (c, r) = coded_grid(count);
            (c as f64 * spacing, r as f64 * spacing)
        }
        TargetKind::ScaleBar {
            length,
            width,
            diameter,
        } => (length + 2.0 * diameter, width),
        TargetKind::SiemensStar { diameter, .. } => (diameter, diameter),
        TargetKind::Disk { diameter } => (2.0 * diameter, 2.0 * diameter),
        TargetKind::TestObject { size, .. } => (size, size),
    }
}

/// Top-face side and height of step `k` (0 = bottom) of a test object.
pub fn test_object_step(size: f64, levels: u32, step: f64, k: u32) -> (f64, f64) {
    let side = size * (levels - k) as f64 / levels as f64;
    (side, (k + 1) as f64 * step)
}

/// The target's known points in its own frame, with their ids (without the target name).
pub fn local_points(kind: &TargetKind) -> Vec<(String, DVec3)> {
    let mut out = Vec::new();
    match *kind {
        TargetKind::Checkerboard { cols, rows, square } => {
            let (w, h) = (cols as f64 * square, rows as f64 * square);
            for j in 1..rows {
                for i in 1..cols {
                    let p = DVec3::new(
                        -w / 2.0 + i as f64 * square,
                        -h / 2.0 + j as f64 * square,
                        0.0,
                    );
                    out.push((out.len().to_string(), p));
                }
            }
        }
        TargetKind::CircleGrid {
            cols,
            rows,
            spacing,
            ..
        } => {
            for (i, j, p) in grid(cols, rows, spacing) {
                let _ = (i, j);
                out.push((out.len().to_string(), p));
            }
        }
        TargetKind::Coded {
            count,
            spacing,
            first_code,
            ..
        } => {
            let (c, r) = coded_grid(count);
            for (k, (_, _, p)) in grid(c, r, spacing)
                .into_iter()
                .take(count as usize)
                .enumerate()
            {
                out.push(((first_code as u64 + k as u64).to_string(), p));
            }
        }
        TargetKind::ScaleBar { length, .. } => {
            out.push(("0".into(), DVec3::new(-length / 2.0, 0.0, 0.0)));
            out.push(("1".into(), DVec3::new(length / 2.0, 0.0, 0.0)));
        }
        TargetKind::SiemensStar { .. } => out.push(("0".into(), DVec3::ZERO)),
        // The id is the target's own name (see [`points`]).
        TargetKind::Disk { .. } => out.push((String::new(), DVec3::ZERO)),
        TargetKind::TestObject {
            size,
            levels,
            step,
            diameter,
        } => {
            for p in test_object_disks(size, levels, step, diameter) {
                out.push((out.len().to_string(), p));
            }
        }
    }
    out
}

/// The test object's disk centres, four corners per level, in `local_points`' order.
fn test_object_disks(
    size: f64,
    levels: u32,
    step: f64,
    diameter: f64,
) -> impl Iterator<Item = DVec3> {
    (0..levels).flat_map(move |k| {
        let (side, z) = test_object_step(size, levels, step, k);
        let a = (side / 2.0 - diameter).max(0.0);
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(sx, sy)| DVec3::new(sx * a, sy * a, z))
    })
}

/// Centres of a `cols × rows` grid of pitch `spacing`, centred, row-major from (-x,-y).
fn grid(cols: u32, rows: u32, spacing: f64) -> Vec<(u32, u32, DVec3)> {
    let mut v = Vec::new();
    for j in 0..rows {
        for i in 0..cols {
            v.push((i, j, centre(i, j, cols, rows, spacing)));
        }
    }
    v
}

/// Centre of disk (i, j) of a `cols × rows` grid of pitch `spacing`.
#[inline]
fn centre(i: u32, j: u32, cols: u32, rows: u32, spacing: f64) -> DVec3 {
    let x = (i as f64 - (cols as f64 - 1.0) / 2.0) * spacing;
    let y = (j as f64 - (rows as f64 - 1.0) / 2.0) * spacing;
    DVec3::new(x, y, 0.0)
}

/// The indices, among `n` centred at pitch `spacing`, whose centre may lie within `reach` of
/// `x` (one index of slack each side for rounding): [`reflectance`] tests those alone, with the
/// same arithmetic, instead of every disk of the grid at every texel. Every index when the
/// numbers do not allow the bound.
fn near(n: u32, spacing: f64, x: f64, reach: f64) -> std::ops::Range<u32> {
    let c0 = (n as f64 - 1.0) / 2.0;
    let (lo, hi) = (
        (x - reach) / spacing + c0 - 1.0,
        (x + reach) / spacing + c0 + 1.0,
    );
    if !(spacing > 0.0 && reach >= 0.0 && lo.is_finite() && hi.is_finite()) {
        return 0..n;
    }
    let lo = lo.floor().clamp(0.0, n as f64) as u32;
    let hi = (hi.ceil() + 1.0).clamp(0.0, n as f64) as u32;
    lo..hi.max(lo)
}

/// The target's points in the world: ids `"{name}/{id}"` (a disk's: `"{name}"`).
pub fn points(name: &str, kind: &TargetKind, world_from_target: &Pose) -> Vec<TargetPoint> {
    local_points(kind)
        .into_iter()
        .map(|(id, p)| TargetPoint {
            id: if id.is_empty() {
                name.to_string()
            } else {
                format!("{name}/{id}")
            },
            world: world_from_target.transform_point(p),
        })
        .collect()
}

/// Printed reflectance at (x, y) in the target frame (white outside the pattern).
pub fn reflectance(kind: &TargetKind, x: f64, y: f64) -> f64 {
    let dark = match *kind {
        TargetKind::Checkerboard { cols, rows, square } => {
            let (w, h) = (cols as f64 * square, rows as f64 * square);
            if x.abs() > w / 2.0 || y.abs() > h / 2.0 {
                false
            } else {
                let i = (((x + w / 2.0) / square).floor() as i64).clamp(0, cols as i64 - 1);
                let j = (((y + h / 2.0) / square).floor() as i64).clamp(0, rows as i64 - 1);
                (i + j) % 2 == 0
            }
        }
        TargetKind::CircleGrid {
            cols,
            rows,
            spacing,
            diameter,
        } => {
            let reach = diameter / 2.0;
            let (is, js) = (near(cols, spacing, x, reach), near(rows, spacing, y, reach));
            js.clone().any(|j| {
                is.clone().any(|i| {
                    let p = centre(i, j, cols, rows, spacing);
                    (x - p.x).hypot(y - p.y) <= diameter / 2.0
                })
            })
        }
        TargetKind::Coded {
            count,
            spacing,
            diameter,
            first_code,
        } => {
            let (c, r) = coded_grid(count);
            let mut dark = false;
            // Row-major, as `grid` lists them (a later disk or ring wins where they overlap);
            // beyond 1.25 diameters a disk leaves `dark` as it is.
            let reach = 1.25 * diameter;
            let (is, js) = (near(c, spacing, x, reach), near(r, spacing, y, reach));
            for (k, p) in js
                .flat_map(|j| {
                    is.clone()
                        .map(move |i| (j as u64 * c as u64 + i as u64, (i, j)))
                })
                .filter(|&(k, _)| k < count as u64)
                .map(|(k, (i, j))| (k, centre(i, j, c, r, spacing)))
            {
                let (dx, dy) = (x - p.x, y - p.y);
                let rr = dx.hypot(dy);
                if rr <= diameter / 2.0 {
                    dark = true;
                } else if rr >= 0.8 * diameter && rr <= 1.25 * diameter {
                    // 8-bit code ring: sector s is black when bit s of the code is set.
                    let code = (first_code as u64 + k) as u32;
                    let a = dy.atan2(dx).rem_euclid(std::f64::consts::TAU);
                    let s = ((a / std::f64::consts::TAU * 8.0).floor() as u32).min(7);
                    dark = (code >> s) & 1 == 1;
                }
            }
            dark
        }
        TargetKind::ScaleBar {
            length, diameter, ..
        } => {
            (x + length / 2.0).hypot(y) <= diameter / 2.0
                || (x - length / 2.0).hypot(y) <= diameter / 2.0
        }
        TargetKind::SiemensStar { diameter, spokes } => {
            let r = x.hypot(y);
            if r > diameter / 2.0 || spokes == 0 {
                false
            } else {
                let a = y.atan2(x).rem_euclid(std::f64::consts::TAU);
                let sector = (a / (std::f64::consts::PI / spokes as f64)).floor() as u64;
                sector.is_multiple_of(2)
            }
        }
        TargetKind::Disk { diameter } => x.hypot(y) <= diameter / 2.0,
        // `local_points`' disks, without building their ids at every point.
        TargetKind::TestObject {
            size,
            levels,
            step,
            diameter,
        } => test_object_disks(size, levels, step, diameter)
            .any(|p| (x - p.x).hypot(y - p.y) <= diameter / 2.0),
    };
    if dark { BLACK } else { WHITE }
}

/// Largest texture side, px (a 16k texture is already 768 MB of RGB8).
pub const MAX_TEXTURE_PX: u32 = 8192;

/// Rasterise the printed face at `px_per_m` pixels per metre (sampled at pixel centres, no
/// anti-aliasing); sides are clamped to [`MAX_TEXTURE_PX`] (the resolution drops accordingly).
pub fn texture(kind: &TargetKind, px_per_m: f64) -> image::RgbImage {
    let (w, h) = extent(kind);
    let ppm = if px_per_m.is_finite() && px_per_m > 0.0 {
        px_per_m
    } else {
        1000.0
    };
    let mut wpx = (w * ppm).round().max(1.0);
    let mut hpx = (h * ppm).round().max(1.0);
    let m = MAX_TEXTURE_PX as f64;
    if wpx > m || hpx > m {
        let s = m / wpx.max(hpx);
        wpx = (wpx * s).floor().max(1.0);
        hpx = (hpx * s).floor().max(1.0);
    }
    let (wpx, hpx) = (wpx as u32, hpx as u32);
    image::RgbImage::from_fn(wpx, hpx, |i, j| {
        let x = -w / 2.0 + (i as f64 + 0.5) * w / wpx as f64;
        let y = h / 2.0 - (j as f64 + 0.5) * h / hpx as f64;
        let v = (reflectance(kind, x, y) * 255.0).round() as u8;
        image::Rgb([v, v, v])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `reflectance` of the disk grids as it was before [`near`]: every disk at every point.
    fn every_disk(kind: &TargetKind, x: f64, y: f64) -> bool {
        match *kind {
            TargetKind::CircleGrid {
                cols,
                rows,
                spacing,
                diameter,
            } => grid(cols, rows, spacing)
                .iter()
                .any(|(_, _, p)| (x - p.x).hypot(y - p.y) <= diameter / 2.0),
            TargetKind::Coded {
                count,
                spacing,
                diameter,
                first_code,
            } => {
                let (c, r) = coded_grid(count);
                let mut dark = false;
                for (k, (_, _, p)) in grid(c, r, spacing)
                    .into_iter()
                    .take(count as usize)
                    .enumerate()
                {
                    let (dx, dy) = (x - p.x, y - p.y);
                    let rr = dx.hypot(dy);
                    if rr <= diameter / 2.0 {
                        dark = true;
                    } else if rr >= 0.8 * diameter && rr <= 1.25 * diameter {
                        let code = (first_code as u64 + k as u64) as u32;
                        let a = dy.atan2(dx).rem_euclid(std::f64::consts::TAU);
                        let s = ((a / std::f64::consts::TAU * 8.0).floor() as u32).min(7);
                        dark = (code >> s) & 1 == 1;
                    }
                }
                dark
            }
            TargetKind::TestObject { diameter, .. } => local_points(kind)
                .iter()
                .any(|(_, p)| (x - p.x).hypot(y - p.y) <= diameter / 2.0),
            _ => unreachable!(),
        }
    }

    #[test]
    fn disk_grids_test_only_the_near_disks_and_print_the_same() {
        let kinds = [
            TargetKind::CircleGrid {
                cols: 7,
                rows: 5,
                spacing: 0.03,
                diameter: 0.012,
            },
            // Overlapping disks, an even count, one column.
            TargetKind::CircleGrid {
                cols: 4,
                rows: 1,
                spacing: 0.01,
                diameter: 0.025,
            },
            TargetKind::Coded {
                count: 7,
                spacing: 0.05,
                diameter: 0.012,
                first_code: 3,
            },
            // Rings reaching into the next disk's (a later disk wins).
            TargetKind::Coded {
                count: 10,
                spacing: 0.02,
                diameter: 0.012,
                first_code: 200,
            },
            TargetKind::TestObject {
                size: 0.2,
                levels: 3,
                step: 0.02,
                diameter: 0.01,
            },
        ];
        for kind in &kinds {
            let (w, h) = extent(kind);
            let n = 301;
            let mut dark = 0;
            for j in 0..n {
                for i in 0..n {
                    let x = (i as f64 / (n - 1) as f64 - 0.5) * 1.2 * w;
                    let y = (j as f64 / (n - 1) as f64 - 0.5) * 1.2 * h;
                    let fast = reflectance(kind, x, y) == BLACK;
                    assert_eq!(fast, every_disk(kind, x, y), "{kind:?} at ({x}, {y})");
                    dark += fast as u32;
                }
            }
            assert!(dark > 100, "{kind:?}: {dark} dark samples");
        }
        // Exactly on a disk's edge, and not finite.
        let k = &kinds[0];
        let p = centre(2, 1, 7, 5, 0.03);
        for (x, y) in [
            (p.x + 0.006, p.y),
            (p.x, p.y - 0.006),
            (f64::NAN, 0.0),
            (f64::INFINITY, 0.0),
        ] {
            assert_eq!(
                reflectance(k, x, y) == BLACK,
                every_disk(k, x, y),
                "({x}, {y})"
            );
        }
    }

    #[test]
    fn checkerboard_corners_sit_on_square_boundaries() {
        let k = TargetKind::Checkerboard {
            cols: 9,
            rows: 6,
            square: 0.04,
        };
        let pts = local_points(&k);
        assert_eq!(pts.len(), 8 * 5);
        // First corner is one square in from the (-x,-y) corner of the 0.36 × 0.24 pattern.
        assert!((pts[0].1 - DVec3::new(-0.14, -0.08, 0.0)).length() < 1e-12);
        // Around a corner the four squares alternate black/white (probe 1 mm away).
        let c = pts[0].1;
        let e = 1e-3;
        let a = reflectance(&k, c.x - e, c.y - e);
        let b = reflectance(&k, c.x + e, c.y - e);
        assert_ne!(a, b);
        assert_eq!(a, reflectance(&k, c.x + e, c.y + e));
        assert_eq!(reflectance(&k, 10.0, 10.0), WHITE);
    }

    #[test]
    fn circle_grid_centres_are_black_between_is_white() {
        let k = TargetKind::CircleGrid {
            cols: 4,
            rows: 3,
            spacing: 0.05,
            diameter: 0.02,
        };
        let pts = local_points(&k);
        assert_eq!(pts.len(), 12);
        for (_, p) in &pts {
            assert_eq!(reflectance(&k, p.x, p.y), BLACK);
            assert_eq!(reflectance(&k, p.x + 0.025, p.y), WHITE);
        }
        assert_eq!(extent(&k), (0.2, 0.15000000000000002));
    }

    #[test]
    fn coded_ids_and_world_points() {
        let k = TargetKind::Coded {
            count: 5,
            spacing: 0.1,
            diameter: 0.01,
            first_code: 7,
        };
        let pose = Pose {
            rotation: glam::DMat3::IDENTITY,
            translation: DVec3::new(1.0, 2.0, -3.0),
        };
        let pts = points("field", &k, &pose);
        assert_eq!(pts.len(), 5);
        assert_eq!(pts[0].id, "field/7");
        assert_eq!(pts[4].id, "field/11");
        assert_eq!(coded_grid(5), (3, 2));
        assert!((pts[0].world - DVec3::new(0.9, 1.95, -3.0)).length() < 1e-12);
    }

    #[test]
    fn star_scale_bar_test_object() {
        let s = TargetKind::SiemensStar {
            diameter: 0.2,
            spokes: 16,
        };
        assert_eq!(local_points(&s).len(), 1);
        let dark = (0..64)
            .filter(|k| {
                let a = (*k as f64 + 0.5) / 64.0 * std::f64::consts::TAU;
                reflectance(&s, 0.05 * a.cos(), 0.05 * a.sin()) == BLACK
            })
            .count();
        assert_eq!(dark, 32, "half of the star is black");
        let b = TargetKind::ScaleBar {
            length: 1.0,
            width: 0.04,
            diameter: 0.02,
        };
        let p = local_points(&b);
        assert!((p[1].1 - p[0].1).length() - 1.0 < 1e-12);
        let t = TargetKind::TestObject {
            size: 0.5,
            levels: 3,
            step: 0.1,
            diameter: 0.02,
        };
        let p = local_points(&t);
        assert_eq!(p.len(), 12);
        assert!((p[11].1.z - 0.3).abs() < 1e-12);
    }

    #[test]
    fn texture_matches_reflectance() {
        let k = TargetKind::Checkerboard {
            cols: 4,
            rows: 3,
            square: 0.01,
        };
        let img = texture(&k, 1000.0);
        assert_eq!(img.dimensions(), (60, 50));
        // Pixel (15, 34) centre: x = -0.0145, y = -0.0095 → bottom-left square (black).
        assert_eq!(img.get_pixel(15, 34).0[0], (BLACK * 255.0).round() as u8);
        assert_eq!(img.get_pixel(0, 0).0[0], (WHITE * 255.0).round() as u8);
    }
}
