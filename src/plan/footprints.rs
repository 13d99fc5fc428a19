//! The ground the camera network sees: each image's footprint on a horizontal plane (the
//! image border's exact rays through the port, met with the plane), and the share of a
//! rectangle on that plane that the footprints cover together. The front end warns with it
//! when a seabed lies mostly outside the network (`W0302`).

use crate::model::Model;
use crate::optics::project::Projector;
use glam::{DVec2, DVec3};

/// Points per image edge whose rays outline a footprint (a port bends the edges: more than the
/// corners keeps the outline within a few per cent of the curved one).
const PER_EDGE: usize = 4;
/// Sample points per side of the rectangle (64 × 64: a share to within about 2 %).
const GRID: usize = 64;
/// Images looked at, at most (a longer network is sampled evenly).
const MAX_VIEWS: usize = 4000;

/// One image's footprint: its outline on the plane and that outline's bounding box.
struct Footprint {
    outline: Vec<DVec2>,
    lo: DVec2,
    hi: DVec2,
}

impl Footprint {
    fn new(outline: Vec<DVec2>) -> Footprint {
        let lo = outline.iter().fold(DVec2::INFINITY, |a, p| a.min(*p));
        let hi = outline.iter().fold(DVec2::NEG_INFINITY, |a, p| a.max(*p));
        Footprint { outline, lo, hi }
    }
    /// Whether `p` is inside the outline (crossing number: the outline may be slightly
    /// concave where a port bends its edges).
    fn contains(&self, p: DVec2) -> bool {
        if p.x < self.lo.x || p.y < self.lo.y || p.x > self.hi.x || p.y > self.hi.y {
            return false;
        }
        let mut inside = false;
        let n = self.outline.len();
        for i in 0..n {
            let (a, b) = (self.outline[i], self.outline[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

/// What the network's images see of a rectangle on a horizontal plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    /// Share (0 to 1) of the rectangle inside at least one image's footprint.
    pub rect_seen: f64,
    /// Share (0 to 1) of the footprints' union that lies on the rectangle.
    pub on_rect: f64,
}

/// What the images see of the rectangle `corners` (four points on the horizontal plane
/// z = `corners[0].z`, in order around it), by the image border's rays through each camera's
/// port met with that plane: both shares are measured on a 64 × 64 grid (of the rectangle,
/// and of the footprints' bounding box). `None` when it cannot be measured: a border ray of
/// some image never meets the plane (it looks up or along it, or starts below it), so that
/// image's footprint is unbounded.
pub fn seen(model: &Model, corners: [DVec3; 4]) -> Option<Seen> {
    let prints = footprints(model, corners[0].z)?;
    let rect = Footprint::new(corners.iter().map(|c| c.truncate()).collect());
    let covered = |p: DVec2| prints.iter().any(|f| f.contains(p));
    let mut seen = 0usize;
    for p in grid(corners.map(|c| c.truncate())) {
        seen += covered(p) as usize;
    }
    let lo = prints.iter().fold(DVec2::INFINITY, |a, f| a.min(f.lo));
    let hi = prints.iter().fold(DVec2::NEG_INFINITY, |a, f| a.max(f.hi));
    let (mut union, mut on) = (0usize, 0usize);
    for p in grid([lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]) {
        if covered(p) {
            union += 1;
            on += rect.contains(p) as usize;
        }
    }
    Some(Seen {
        rect_seen: seen as f64 / (GRID * GRID) as f64,
        on_rect: if union == 0 {
            0.0
        } else {
            on as f64 / union as f64
        },
    })
}

/// Cell centres of a [`GRID`] × [`GRID`] grid over the quadrilateral `q` (bilinear in its
/// corners, in order around it).
fn grid(q: [DVec2; 4]) -> impl Iterator<Item = DVec2> {
    (0..GRID * GRID).map(move |k| {
        let (a, b) = (
            ((k / GRID) as f64 + 0.5) / GRID as f64,
            ((k % GRID) as f64 + 0.5) / GRID as f64,
        );
        q[0].lerp(q[1], a).lerp(q[3].lerp(q[2], a), b)
    })
}

/// Every image's footprint on the plane z = `z0` (`None`: one is unbounded).
fn footprints(model: &Model, z0: f64) -> Option<Vec<Footprint>> {
    let n = model.ambient_ior()[1];
    // The border rays of each camera, camera frame, once: edge by edge around the image.
    let mut rays = Vec::new();
    for cam in &model.cameras {
        let pr = Projector::for_camera(cam, 1, n).ok()?;
        let (w, h) = (cam.width as f64, cam.height as f64);
        let mut border = Vec::with_capacity(4 * PER_EDGE);
        for e in 0..4 {
            for k in 0..PER_EDGE {
                let f = k as f64 / PER_EDGE as f64;
                let (u, v) = [(f * w, 0.0), (w, f * h), (w - f * w, h), (0.0, h - f * h)][e];
                border.push(pr.camera_ray(u, v).ok()?);
            }
        }
        rays.push(border);
    }
    let step = model.poses.len().div_ceil(MAX_VIEWS).max(1);
    let mut prints = Vec::new();
    for pi in (0..model.poses.len()).step_by(step) {
        for (ci, border) in rays.iter().enumerate() {
            let w = model.world_from_camera(pi, ci);
            let mut outline = Vec::with_capacity(border.len());
            for r in border {
                let (o, d) = (w.transform_point(r.origin), w.transform_vector(r.dir));
                let t = (z0 - o.z) / d.z;
                if !(d.z < 0.0 && t > 0.0 && t.is_finite()) {
                    return None;
                }
                outline.push((o + d * t).truncate());
            }
            prints.push(Footprint::new(outline));
        }
    }
    (!prints.is_empty()).then_some(prints)
}
