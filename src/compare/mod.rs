//! Cross-backend agreement: locate targets in rendered images, compare them with the exact
//! ground truth and with each other, and write the `poser compare` report.

pub mod analytic;
pub mod detect;
pub mod report;
pub mod sectors;

use std::path::Path;

/// A linear RGB float image as read from an EXR.
pub struct LinearImage {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB triples, row 0 at the top.
    pub rgb: Vec<[f32; 3]>,
}

impl LinearImage {
    /// Read an EXR ([`crate::image::read_exr`], the one reader).
    pub fn read(path: &Path) -> Result<Self, String> {
        let img = crate::image::read_exr(path)?;
        Ok(LinearImage {
            width: img.width as usize,
            height: img.height as usize,
            rgb: img.rgb,
        })
    }
    /// One channel as a flat vector.
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.rgb.iter().map(|p| p[c]).collect()
    }
    /// Mean per channel.
    pub fn mean(&self) -> [f64; 3] {
        channel_means(self.rgb.as_flattened())
    }
}

/// Per-channel means of interleaved RGB values.
pub fn channel_means(rgb: &[f32]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for px in rgb.chunks_exact(3) {
        for c in 0..3 {
            m[c] += px[c] as f64;
        }
    }
    m.map(|v| v / (rgb.len() / 3).max(1) as f64)
}

use crate::backend::{Backend, RenderOptions};
use crate::model::{Model, TargetKind};
use crate::optics::project::Projector;
use crate::optics::surface::SeaInterface;
use glam::DVec3;
use report::{BackendResult, PairResult, Report};
use std::time::Instant;

/// A printed dark disk whose image can be located: centre, normal (world), radius, and the
/// radius around the centre that is guaranteed white (m).
#[derive(Debug, Clone)]
pub struct Disk {
    pub id: String,
    pub center: DVec3,
    pub normal: DVec3,
    pub radius: f64,
    /// Half-size of the white region around the disk, m: a square cell along the target's
    /// x/y axes (`x_axis` given) or a circle (`x_axis` `None`).
    pub clear_radius: f64,
    pub x_axis: Option<DVec3>,
}

/// Every locatable disk of the model's targets (circle grids, coded targets' centre dots,
/// scale-bar ends).
pub fn disks(model: &Model) -> Vec<Disk> {
    let mut out = Vec::new();
    for t in &model.targets {
        let (radius, clear) = match t.kind {
            // Half the spacing: the outer disks are that close to the board's edge.
            TargetKind::CircleGrid {
                spacing, diameter, ..
            } => (diameter / 2.0, spacing / 2.0),
            TargetKind::Coded { diameter, .. } => (diameter / 2.0, 0.8 * diameter),
            TargetKind::Disk { diameter } => (diameter / 2.0, diameter),
            TargetKind::ScaleBar {
                width, diameter, ..
            } => (diameter / 2.0, width / 2.0),
            _ => continue,
        };
        let normal = t.pose.rotation.z_axis;
        let x_axis =
            matches!(t.kind, TargetKind::CircleGrid { .. }).then_some(t.pose.rotation.x_axis);
        for p in &t.points {
            out.push(Disk {
                id: p.id.clone(),
                center: p.world,
                normal,
                radius,
                clear_radius: clear,
                x_axis,
            });
        }
    }
    out
}

/// The exact projection into image `pose`: from the air through the sea surface when one is
/// given, else through the port.
fn projection<'a>(
    proj: &'a Projector,
    surface: Option<&'a SeaInterface>,
    pose: usize,
) -> impl Fn(DVec3) -> Result<[f64; 2], crate::optics::NoSolution> + 'a {
    move |p: DVec3| match surface {
        Some(s) => crate::optics::surface::project_through(proj, s, pose, p),
        None => proj.project_world(pose, p),
    }
}

/// Whether a window of radius `r` px around `c` stays a pixel inside the image.
fn fits(proj: &Projector, c: [f64; 2], r: f64) -> bool {
    c[0] - r >= 1.0
        && c[1] - r >= 1.0
        && c[0] + r <= proj.width - 1.0
        && c[1] + r <= proj.height - 1.0
}

/// A checkerboard's inner corner: where it is and the board's axes and square, from which
/// its edges' directions and a window free of other corners follow.
#[derive(Debug, Clone)]
pub struct Corner {
    pub id: String,
    pub world: DVec3,
    pub x_axis: DVec3,
    pub y_axis: DVec3,
    pub square: f64,
}

/// Every inner corner of the model's checkerboards.
pub fn corners(model: &Model) -> Vec<Corner> {
    let mut out = Vec::new();
    for t in &model.targets {
        let TargetKind::Checkerboard { square, .. } = t.kind else {
            continue;
        };
        for p in &t.points {
            out.push(Corner {
                id: p.id.clone(),
                world: p.world,
                x_axis: t.pose.rotation.x_axis,
                y_axis: t.pose.rotation.y_axis,
                square,
            });
        }
    }
    out
}

/// Where a corner should appear in image `pose`: its exact projection, the image directions
/// of its two edges, and the window's radius (0.45 of the nearest projected neighbour at one
/// square, so that no other corner or edge end falls inside); `None` when the board faces away
/// or the window is under 3 px or leaves the image.
pub fn expected_corner(
    proj: &Projector,
    surface: Option<&SeaInterface>,
    pose: usize,
    c: &Corner,
) -> Option<([f64; 2], [[f64; 2]; 2], f64)> {
    let project = projection(proj, surface, pose);
    let cam = proj.world_from_camera(pose).translation;
    if c.x_axis.cross(c.y_axis).dot(cam - c.world) <= 0.0 {
        return None;
    }
    let q = project(c.world).ok()?;
    let mut nearest = f64::INFINITY;
    let mut dirs = [[0.0; 2]; 2];
    for (k, axis) in [c.x_axis, c.y_axis].into_iter().enumerate() {
        let a = project(c.world + c.square * axis).ok()?;
        let b = project(c.world - c.square * axis).ok()?;
        let (da, db) = (
            (a[0] - q[0]).hypot(a[1] - q[1]),
            (b[0] - q[0]).hypot(b[1] - q[1]),
        );
        nearest = nearest.min(da).min(db);
        let d = [a[0] - b[0], a[1] - b[1]];
        let n = d[0].hypot(d[1]);
        if !(n > 0.0) {
            return None;
        }
        dirs[k] = [d[0] / n, d[1] / n];
    }
    let half = 0.45 * nearest;
    if !(half >= 3.0) || !fits(proj, q, half) {
        return None;
    }
    Some((q, dirs, half))
}

/// A Siemens star: its centre, axes, radius and spokes.
#[derive(Debug, Clone)]
pub struct Star {
    pub id: String,
    pub centre: DVec3,
    pub x_axis: DVec3,
    pub y_axis: DVec3,
    pub radius: f64,
    pub spokes: u32,
}

/// Every Siemens star of the model.
pub fn stars(model: &Model) -> Vec<Star> {
    model
        .targets
        .iter()
        .filter_map(|t| match t.kind {
            TargetKind::SiemensStar { diameter, spokes } if spokes >= 2 => Some(Star {
                id: t.points.first()?.id.clone(),
                centre: t.points.first()?.world,
                x_axis: t.pose.rotation.x_axis,
                y_axis: t.pose.rotation.y_axis,
                radius: diameter / 2.0,
                spokes,
            }),
            _ => None,
        })
        .collect()
}

/// Where a star's centre should appear in image `pose`: its exact projection, its sector
/// edges' image directions (in order of increasing angle, each sector from an even-numbered
/// edge to the next of one colour), and the annulus to fit over: from where a sector is
/// 2.5 px wide to 0.85 of the rim's nearest image radius. `None` when it faces away, or the
/// annulus is narrow or leaves the image.
pub fn expected_star(
    proj: &Projector,
    surface: Option<&SeaInterface>,
    pose: usize,
    s: &Star,
) -> Option<([f64; 2], Vec<[f64; 2]>, f64, f64)> {
    let project = projection(proj, surface, pose);
    let cam = proj.world_from_camera(pose).translation;
    if s.x_axis.cross(s.y_axis).dot(cam - s.centre) <= 0.0 {
        return None;
    }
    let q = project(s.centre).ok()?;
    let n = 2 * s.spokes as usize;
    let (mut dirs, mut rim) = (Vec::with_capacity(n), f64::INFINITY);
    for k in 0..n {
        let a = k as f64 * std::f64::consts::PI / s.spokes as f64;
        let along = a.cos() * s.x_axis + a.sin() * s.y_axis;
        let near = project(s.centre + 0.25 * s.radius * along).ok()?;
        let edge = project(s.centre + s.radius * along).ok()?;
        rim = rim.min((edge[0] - q[0]).hypot(edge[1] - q[1]));
        let d = [near[0] - q[0], near[1] - q[1]];
        let len = d[0].hypot(d[1]);
        if !(len > 0.0) {
            return None;
        }
        dirs.push([d[0] / len, d[1] / len]);
    }
    // The image may show the star mirrored (angles decreasing): reverse, which keeps each
    // sector's pair of edges (even to odd) together.
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    if cross(dirs[0], dirs[1]) < 0.0 {
        dirs.reverse();
    }
    let narrowest = (0..n)
        .map(|k| cross(dirs[k], dirs[(k + 1) % n]).clamp(-1.0, 1.0).asin())
        .fold(f64::INFINITY, f64::min);
    if !(narrowest > 0.0) {
        return None;
    }
    let (inner, outer) = ((2.5 / narrowest).max(3.0), 0.85 * rim);
    if !(outer >= inner + 4.0) || !fits(proj, q, outer) {
        return None;
    }
    Some((q, dirs, inner, outer))
}

/// Where a disk should appear in image (pose, cam): expected image centroid and the
/// half-size of the window that [`detect::disk_centroid`] measures it in, or `None` when it is
/// not (fully) visible or too small/crowded for that window.
pub fn expected_disk(
    proj: &Projector,
    surface: Option<&SeaInterface>,
    pose: usize,
    d: &Disk,
) -> Option<([f64; 2], f64)> {
    let v = disk_view(proj, surface, pose, d)?;
    v.window.map(|half| (v.centroid, half))
}

/// A disk's expected image ([`disk_view`]) and how it is measured.
pub struct DiskView {
    /// The area centroid of the exactly projected outline.
    pub centroid: [f64; 2],
    /// The outline's largest distance from the centroid along x or y, px.
    pub radius: f64,
    /// The exactly projected outline, 256 points.
    pub outline: Vec<[f64; 2]>,
    /// The half-size of [`detect::disk_centroid`]'s window, when the white surround holds
    /// one.
    pub window: Option<f64>,
    /// The band of [`sectors::disk_edge`] (px either side of the outline), when the disk is
    /// [`EDGE_FIT_PX`] or more in radius and its surround holds the band.
    pub band: Option<f64>,
    /// Whether the outline is an ellipse within [`ELLIPSE_MISFIT`] of its radius: fitted as
    /// one ([`sectors::disk_edge`]); else (through waves) as itself, shifted
    /// ([`sectors::outline_edge`]).
    pub elliptic: bool,
    /// Points that must be seen for the disk to be measured (world, pixel): its centre and
    /// eight points on the edge of its white surround ([`seen`]), which a half-buried disk's
    /// surround fails.
    pub probes: Vec<(DVec3, [f64; 2])>,
}

impl DiskView {
    /// The half-size of the square around the centroid that its measurement reads.
    pub fn half(&self) -> f64 {
        match (self.band, self.window) {
            (Some(band), _) => self.radius + band + 1.0,
            (None, Some(half)) => half,
            (None, None) => 0.0,
        }
    }
}

/// A disk's exact image in image `pose` and how it can be measured; `None` when it is not
/// (fully) visible, faces away, or is too small or crowded for either measurement.
pub fn disk_view(
    proj: &Projector,
    surface: Option<&SeaInterface>,
    pose: usize,
    d: &Disk,
) -> Option<DiskView> {
    let project = projection(proj, surface, pose);
    let c = detect::expected_centroid(d.center, d.normal, d.radius, |p| project(p).ok())?;
    // Facing the camera?
    let cam = proj.world_from_camera(pose).translation;
    if d.normal.dot(cam - d.center) <= 0.0 {
        return None;
    }
    // Chebyshev (max-norm) distances from the centroid: the disk's outline must stay inside
    // the centroid window's border ring, the white surround's outline outside the window.
    // Sampled outlines handle anisotropic magnification (cylinder ports, oblique views).
    let cheb = |p: [f64; 2]| (p[0] - c[0]).abs().max((p[1] - c[1]).abs());
    let a = d
        .x_axis
        .unwrap_or_else(|| d.normal.any_orthonormal_vector());
    let b = d.normal.cross(a);
    const N: usize = 256;
    let mut r_disk: f64 = 0.0;
    let mut r_clear = f64::INFINITY;
    // The edge fit's room: the white gap between the outline and the surround's edge along
    // each radius, and the disk's own smallest radius (its inside band).
    let (mut gap, mut r_min) = (f64::INFINITY, f64::INFINITY);
    let mut outline = Vec::with_capacity(N);
    let mut probes = vec![(d.center, project(d.center).ok()?)];
    for k in 0..N {
        let t = std::f64::consts::TAU * k as f64 / N as f64;
        let (ct, st) = (t.cos(), t.sin());
        let p = project(d.center + d.radius * (ct * a + st * b)).ok()?;
        r_disk = r_disk.max(cheb(p));
        r_min = r_min.min((p[0] - c[0]).hypot(p[1] - c[1]));
        outline.push(p);
        // Square cell: scale the direction onto the square's boundary.
        let s = if d.x_axis.is_some() {
            1.0 / ct.abs().max(st.abs())
        } else {
            1.0
        };
        let rim = d.center + d.clear_radius * s * (ct * a + st * b);
        let q = project(rim).ok()?;
        r_clear = r_clear.min(cheb(q));
        if k % (N / 8) == 0 {
            probes.push((rim, q));
        }
        gap = gap.min((q[0] - p[0]).hypot(q[1] - p[1]));
    }
    // 1.5 px of safety from the edge of the white surround (partly covered edge pixels).
    let half = (r_clear - 1.5).min(r_disk + 5.0);
    let window = (r_disk >= 1.5 && half >= r_disk + 2.0).then_some(half);
    // The edge fit's ellipse must be the outline's shape: not through waves, which bend one
    // disk's outline out of any ellipse (then the outline itself is fitted).
    let elliptic = sectors::moment_ellipse(&outline)
        .is_some_and(|(q, m)| sectors::ellipse_misfit(&outline, q, m) <= ELLIPSE_MISFIT * r_disk);
    let band = (gap - 1.5).min(5.0);
    let band = (r_disk >= EDGE_FIT_PX && band >= 2.0 && r_min >= band + 1.0).then_some(band);
    let v = DiskView {
        centroid: c,
        radius: r_disk,
        outline,
        window,
        band,
        elliptic,
        probes,
    };
    (v.half() > 0.0 && fits(proj, c, v.half())).then_some(v)
}

/// Whether every probe (world point, its pixel) of a target on a face of normal `normal` is
/// seen in image `pose`: the camera on the printed side and the water path clear of `scene`
/// (the ground truth's test, [`crate::truth::unobstructed`]). A disk half buried in the
/// seabed's relief, or a corner behind an object, is not measured.
pub fn seen(
    scene: &crate::geometry::Bvh,
    proj: &Projector,
    surface: Option<&SeaInterface>,
    pose: usize,
    normal: DVec3,
    probes: &[(DVec3, [f64; 2])],
) -> bool {
    probes.iter().all(|&(w, uv)| {
        crate::truth::unobstructed(proj, surface, pose, w, normal, uv, |a, b| {
            scene.occluded(a, b)
        })
    })
}

/// How far a disk's exact outline (256 points) may depart from its moment ellipse, as a share
/// of its radius, for [`sectors::disk_edge`]. A perspective view of a circle is an ellipse;
/// a 64-point polygon departs from it by about 0.08 % (its chords' sagitta: 0.02 px at 25 px,
/// 0.057 px at 69 px, calibration_flat's and archaeology's disks), 256 points by a sixteenth
/// of that, a port's bending of one disk by less; 5 cm waves bend a disk's outline by 9–30 %
/// (uav_through_waves), which [`sectors::outline_edge`] fits as it is.
pub const ELLIPSE_MISFIT: f64 = 0.01;

/// The image radius (px) from which a disk is located by its edge ([`sectors::disk_edge`]),
/// not by the area centroid of its darkness ([`detect::disk_centroid`]).
pub const EDGE_FIT_PX: f64 = 12.0;

/// Measure a disk in `gray` (pixel coordinates shifted by `origin`, a crop's corner): by its
/// edge where [`DiskView::band`] allows, else by its centroid.
fn measure_disk(
    gray: &detect::Gray,
    v: &DiskView,
    origin: [f64; 2],
    dark: f64,
) -> Option<[f64; 2]> {
    let local = [v.centroid[0] - origin[0], v.centroid[1] - origin[1]];
    match (v.band, v.window) {
        (Some(band), _) => {
            let outline: Vec<[f64; 2]> = v
                .outline
                .iter()
                .map(|p| [p[0] - origin[0], p[1] - origin[1]])
                .collect();
            if v.elliptic {
                sectors::disk_edge(gray, &outline, band).ok()
            } else {
                sectors::outline_edge(gray, &outline, band).ok()
            }
        }
        (None, Some(half)) => detect::disk_centroid(gray, local, half, dark).ok(),
        (None, None) => None,
    }
}

/// Which measurable points a [`target_crop`] gathers (`All`: stars' centres too).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Points {
    Disks,
    Corners,
    All,
}

/// The rectangle of image (`pose`, camera 0) around the measurable points (`which`) nearest
/// its centre, at most `max_side` px on a side: the point nearest the centre, then the next
/// nearest to it while their windows still fit, with a 2 px margin. A crop render there
/// (`render.crop`) measures targets at the full image size for a small share of its cost
/// (`poser compare --crop targets`). `None` when no such point can be measured in that image.
pub fn target_crop(
    model: &Model,
    scene: &crate::geometry::Bvh,
    pose: usize,
    max_side: u32,
    which: Points,
) -> Result<Option<crate::model::Crop>, String> {
    let proj = model.projector(0, 1)?;
    let surface = model
        .above_surface(pose, 0)
        .then(|| model.sea_interface(1))
        .flatten();
    let sf = surface.as_ref();
    let seen = |normal, probes: &[(DVec3, [f64; 2])]| seen(scene, &proj, sf, pose, normal, probes);
    let mut windows: Vec<([f64; 2], f64)> = Vec::new();
    if which != Points::Corners {
        windows.extend(disks(model).iter().filter_map(|d| {
            let v = disk_view(&proj, sf, pose, d)?;
            seen(d.normal, &v.probes).then(|| (v.centroid, v.half()))
        }));
    }
    if which != Points::Disks {
        windows.extend(corners(model).iter().filter_map(|c| {
            let (q, _, half) = expected_corner(&proj, sf, pose, c)?;
            seen(c.x_axis.cross(c.y_axis), &[(c.world, q)]).then_some((q, half))
        }));
    }
    if which == Points::All {
        windows.extend(stars(model).iter().filter_map(|s| {
            let (q, _, _, outer) = expected_star(&proj, sf, pose, s)?;
            seen(s.x_axis.cross(s.y_axis), &[(s.centre, q)]).then_some((q, outer))
        }));
    }
    let centre = [proj.width / 2.0, proj.height / 2.0];
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let Some(first) = windows
        .iter()
        .min_by(|a, b| dist(a.0, centre).total_cmp(&dist(b.0, centre)))
        .copied()
    else {
        return Ok(None);
    };
    windows.sort_by(|a, b| dist(a.0, first.0).total_cmp(&dist(b.0, first.0)));
    let (w, h) = (proj.width, proj.height);
    // Pixel bounds [x0, x1) × [y0, y1) of a window, with the margin, inside the image.
    let bounds = |(c, half): ([f64; 2], f64)| {
        [
            (c[0] - half - 2.0).floor().max(0.0),
            (c[1] - half - 2.0).floor().max(0.0),
            (c[0] + half + 3.0).ceil().min(w),
            (c[1] + half + 3.0).ceil().min(h),
        ]
    };
    let mut b = bounds(first);
    for &win in &windows[1..] {
        let n = bounds(win);
        let grown = [
            b[0].min(n[0]),
            b[1].min(n[1]),
            b[2].max(n[2]),
            b[3].max(n[3]),
        ];
        if grown[2] - grown[0] > max_side as f64 || grown[3] - grown[1] > max_side as f64 {
            continue;
        }
        b = grown;
    }
    Ok(Some(crate::model::Crop {
        x: b[0] as u32,
        y: b[1] as u32,
        width: (b[2] - b[0]) as u32,
        height: (b[3] - b[1]) as u32,
    }))
}

/// Measured disks: (id, image name, measured − expected in px), and how many were expected.
pub type Measured = (Vec<(String, String, [f64; 2])>, usize);

/// One disk expected in one image: where the exact truth puts its centre and where the image
/// shows it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TargetResidual {
    /// The point's id, as [`Disk::id`] or [`Corner::id`] (`dots/0`: a grid's first disk).
    pub id: String,
    /// `disk` (located by its area centroid), `corner` (a checkerboard's) or `star` (a Siemens
    /// star's centre; both by a fitted model, [`sectors`]).
    pub kind: &'static str,
    /// The image's name.
    pub image: String,
    /// The exact centre, px, pixel centres at +0.5 (COLMAP's convention).
    pub truth: [f64; 2],
    /// Measured − truth, px; `None` where no disk was found.
    pub offset: Option<[f64; 2]>,
}

/// Measure every visible disk in the rendered images of `dir` in the G channel: returns
/// (id, image name, measured − expected in px) for each disk found, and how many were expected.
pub fn measure_targets(model: &Model, dir: &Path) -> Result<Measured, String> {
    measure_targets_in_channel(model, dir, 1)
}

/// [`measure_targets`] in channel `channel` (0 = R, 1 = G, 2 = B) against that channel's
/// exact projection (with dispersion, each channel's indices place the disks differently).
pub fn measure_targets_in_channel(
    model: &Model,
    dir: &Path,
    channel: usize,
) -> Result<Measured, String> {
    let all = target_residuals(model, dir, channel)?;
    let expected = all.len();
    let found = all
        .into_iter()
        .filter_map(|r| r.offset.map(|o| (r.id, r.image, o)))
        .collect();
    Ok((found, expected))
}

/// Every disk, checkerboard corner and Siemens star centre expected in the rendered images of
/// `dir`, found or not, in channel `channel` against that channel's exact projection, in the
/// order of the cameras, poses, disks, stars and corners. Images of a crop (`render.crop`) hold the points whose window lies
/// inside the rectangle.
pub fn target_residuals(
    model: &Model,
    dir: &Path,
    channel: usize,
) -> Result<Vec<TargetResidual>, String> {
    let (disks, corners, stars) = (disks(model), corners(model), stars(model));
    let scene = crate::geometry::Bvh::of_model(model)?;
    let dark = crate::geometry::targets::BLACK / crate::geometry::targets::WHITE;
    // The rendered rectangle's origin in the whole image (a crop's corner, else 0).
    let (x0, y0) = model
        .render
        .crop
        .map_or((0.0, 0.0), |k| (k.x as f64, k.y as f64));
    let mut out = Vec::new();
    for cam in 0..model.cameras.len() {
        let proj = model.projector(cam, channel)?;
        for pose in 0..model.poses.len() {
            let name = model.image_name(pose, cam);
            let path = dir.join(format!("{name}.exr"));
            if !path.exists() {
                continue;
            }
            let img = LinearImage::read(&path)?;
            let g = img.channel(channel);
            let gray = detect::Gray {
                width: img.width,
                height: img.height,
                data: &g,
            };
            let surface = model
                .above_surface(pose, cam)
                .then(|| model.sea_interface(channel))
                .flatten();
            // A window inside the rendered pixels (always, without a crop: the expectation
            // checked the whole image).
            let inside = |local: [f64; 2], half: f64| {
                model.render.crop.is_none()
                    || (local[0] - half >= 1.0
                        && local[1] - half >= 1.0
                        && local[0] + half <= img.width as f64 - 1.0
                        && local[1] + half <= img.height as f64 - 1.0)
            };
            let seen = |normal, probes: &[(DVec3, [f64; 2])]| {
                seen(&scene, &proj, surface.as_ref(), pose, normal, probes)
            };
            let mut push = |id: &str, kind, truth: [f64; 2], found: Option<[f64; 2]>| {
                out.push(TargetResidual {
                    id: id.to_string(),
                    kind,
                    image: name.clone(),
                    truth,
                    offset: found.map(|m| [m[0] - (truth[0] - x0), m[1] - (truth[1] - y0)]),
                });
            };
            for d in &disks {
                let Some(v) = disk_view(&proj, surface.as_ref(), pose, d) else {
                    continue;
                };
                let local = [v.centroid[0] - x0, v.centroid[1] - y0];
                if inside(local, v.half()) && seen(d.normal, &v.probes) {
                    let found = measure_disk(&gray, &v, [x0, y0], dark);
                    push(&d.id, "disk", v.centroid, found);
                }
            }
            for s in &stars {
                let Some((c, dirs, inner, outer)) = expected_star(&proj, surface.as_ref(), pose, s)
                else {
                    continue;
                };
                let local = [c[0] - x0, c[1] - y0];
                if inside(local, outer) && seen(s.x_axis.cross(s.y_axis), &[(s.centre, c)]) {
                    let found = sectors::star_centre(&gray, local, &dirs, inner, outer).ok();
                    push(&s.id, "star", c, found);
                }
            }
            for k in &corners {
                let Some((c, dirs, half)) = expected_corner(&proj, surface.as_ref(), pose, k)
                else {
                    continue;
                };
                let local = [c[0] - x0, c[1] - y0];
                if inside(local, half) && seen(k.x_axis.cross(k.y_axis), &[(k.world, c)]) {
                    let found = sectors::checker_corner(&gray, local, dirs, half).ok();
                    push(&k.id, "corner", c, found);
                }
            }
        }
    }
    Ok(out)
}

/// Render with each backend and compare; writes `report.md`, `report.json`, `report.svg` (the
/// chart) and difference images into `out`. A backend that fails is reported as failed (its
/// error in the report); the caller decides the exit status.
pub fn run(
    model: &Model,
    backends: &[Backend],
    out: &Path,
    opts: &RenderOptions,
) -> Result<Report, String> {
    let analytic_ok = analytic::applies(model);
    let mut report = Report {
        scene: model.source.clone(),
        samples: opts.samples.unwrap_or(model.render.samples),
        analytic: Some(analytic_ok.clone().map(|_| {
            "the first image's central window (a quarter of its width and height) against \
             the closed-form radiance of the lit Lambertian patch"
                .to_string()
        })),
        ..Default::default()
    };
    for b in backends {
        let dir = out.join(b.name());
        let t0 = Instant::now();
        let mut r = BackendResult {
            backend: b.name().to_string(),
            ..Default::default()
        };
        match b.render(model, &dir, opts) {
            Err(e) => r.error = Some(e),
            Ok(rep) => {
                r.seconds = t0.elapsed().as_secs_f64();
                r.images = rep.images.len();
                r.targets = target_residuals(model, &dir, 1)?;
                r.targets_expected = r.targets.len();
                let d2: Vec<f64> = r
                    .targets
                    .iter()
                    .filter_map(|t| t.offset.map(|d| d[0] * d[0] + d[1] * d[1]))
                    .collect();
                r.targets_measured = d2.len();
                if !d2.is_empty() {
                    r.target_rms_px = Some((d2.iter().sum::<f64>() / d2.len() as f64).sqrt());
                    r.target_max_px = Some(d2.iter().cloned().fold(0.0, f64::max).sqrt());
                }
                let mut sum = [0.0; 3];
                let mut n = 0usize;
                for img in &rep.images {
                    let im = LinearImage::read(img)?;
                    let m = im.mean();
                    for c in 0..3 {
                        sum[c] += m[c];
                    }
                    n += 1;
                }
                r.mean_rgb = sum.map(|s| s / n.max(1) as f64);
                let first = dir.join(format!("{}.exr", model.image_name(0, 0)));
                if analytic_ok.is_ok() && first.exists() {
                    r.analytic_rel =
                        Some(analytic::window_error(model, &LinearImage::read(&first)?)?);
                }
            }
        }
        report.backends.push(r);
    }
    let ok: Vec<&BackendResult> = report
        .backends
        .iter()
        .filter(|b| b.error.is_none())
        .collect();
    for i in 0..ok.len() {
        for j in i + 1..ok.len() {
            report.pairs.push(compare_pair(
                model,
                out,
                &ok[i].backend,
                &ok[j].backend,
                ok[i].mean_rgb,
                ok[j].mean_rgb,
            )?);
        }
    }
    crate::io::write_atomic(&out.join("report.md"), report.to_markdown().as_bytes())
        .map_err(|e| e.to_string())?;
    let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    crate::io::write_atomic(&out.join("report.json"), json.as_bytes())
        .map_err(|e| e.to_string())?;
    let svg = report.plot_svg()?;
    crate::io::write_atomic(&out.join("report.svg"), svg.as_bytes()).map_err(|e| e.to_string())?;
    Ok(report)
}

/// `(b − a)/a` per channel (0 where `a` is 0): how two backends' image means differ.
pub fn rel_diff(ma: [f64; 3], mb: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|c| {
        if ma[c] > 0.0 {
            (mb[c] - ma[c]) / ma[c]
        } else {
            0.0
        }
    })
}

fn compare_pair(
    model: &Model,
    out: &Path,
    a: &str,
    b: &str,
    ma: [f64; 3],
    mb: [f64; 3],
) -> Result<PairResult, String> {
    let mut pr = PairResult {
        a: a.into(),
        b: b.into(),
        ..Default::default()
    };
    pr.mean_rel_diff = rel_diff(ma, mb);
    let mut rms_sum = 0.0;
    let mut n = 0;
    for cam in 0..model.cameras.len() {
        for pose in 0..model.poses.len() {
            let name = model.image_name(pose, cam);
            let (pa, pb) = (
                out.join(a).join(format!("{name}.exr")),
                out.join(b).join(format!("{name}.exr")),
            );
            if !(pa.exists() && pb.exists()) {
                continue;
            }
            let (ia, ib) = (LinearImage::read(&pa)?, LinearImage::read(&pb)?);
            if (ia.width, ia.height) != (ib.width, ib.height) {
                return Err(format!("{name}: {a} and {b} images differ in size"));
            }
            let lum = |p: &[f32; 3]| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0;
            let mean_a = ia.rgb.iter().map(lum).sum::<f64>() / ia.rgb.len() as f64;
            let diffs: Vec<f64> = ia
                .rgb
                .iter()
                .zip(&ib.rgb)
                .map(|(x, y)| lum(y) - lum(x))
                .collect();
            let rms = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
            if mean_a > 0.0 {
                rms_sum += rms / mean_a;
                n += 1;
            }
            // |b − a| scaled so that 10 % of a's mean is white.
            let scale = if mean_a > 0.0 {
                255.0 / (0.1 * mean_a)
            } else {
                0.0
            };
            let img = image::GrayImage::from_fn(ia.width as u32, ia.height as u32, |x, y| {
                let d = diffs[y as usize * ia.width + x as usize].abs() * scale;
                image::Luma([d.min(255.0) as u8])
            });
            let p = out.join(format!("diff_{a}_{b}_{name}.png"));
            crate::io::write_atomic_with(&p, |t| img.save(t).map_err(|e| e.to_string()))?;
            pr.diff_images
                .push(p.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    pr.rms_rel_diff = if n > 0 { rms_sum / n as f64 } else { 0.0 };
    Ok(pr)
}
