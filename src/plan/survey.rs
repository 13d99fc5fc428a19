//! Survey plan metrics measured on the actual site: GSD through the port (exact projection,
//! [`crate::optics::project::Projector`]), footprint, forward overlap and side-lap achieved on
//! the seabed/meshes (rays cast into the native renderer's [`crate::geometry::Bvh`]),
//! the camera distance needed for a target GSD, and per-face coverage counts with occlusion.
//!
//! | metric | how |
//! |---|---|
//! | GSD | at the hit of the centre pixel's ray: 1 mm across in the camera's x, projected exactly |
//! | footprint | the four corner pixels' rays hit on the site; mean edge lengths |
//! | overlap | 64×48 pixel grid of image *i* cast to the site, re-projected into image *j* (on the sensor and not occluded) |
//! | side-lap | as overlap, with *j* the nearest pose of the next strip |
//! | coverage | per mesh face (or per cell of a seabed grid): images that see its centre (on the sensor, facing, not occluded) |
//!
//! Metrics use the first camera of the rig and the green channel. Without geometry in the scene
//! the nominal seabed plane z = −`site.depth` is the site.

use crate::geometry::mesh::TriMesh;
use crate::geometry::{Bvh, Ray};
use crate::model::Model;
use crate::optics::project::Projector;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// The site as something rays can hit.
pub struct Site {
    pub scene: Option<Bvh>,
    pub seabed_z: f64,
    /// Why the scene geometry is not used, if it is not.
    pub note: Option<String>,
}

impl Site {
    pub fn new(model: &Model) -> Site {
        let seabed_z = -model.site.depth;
        match Bvh::of_model(model) {
            Ok(s) if s.triangle_count() > 0 => Site {
                scene: Some(s),
                seabed_z,
                note: None,
            },
            Ok(_) => Site {
                scene: None,
                seabed_z,
                note: Some("no geometry in the scene: the nominal seabed plane is used".into()),
            },
            Err(e) => Site {
                scene: None,
                seabed_z,
                note: Some(format!(
                    "scene geometry unavailable ({e}): the nominal seabed plane is used"
                )),
            },
        }
    }

    /// First surface hit along `o + t·d`, t > 0.
    pub fn hit(&self, o: DVec3, d: DVec3) -> Option<DVec3> {
        match &self.scene {
            Some(s) => s
                .intersect(&Ray { origin: o, dir: d }, 1e4)
                .map(|h| h.point),
            None => {
                if d.z >= 0.0 {
                    return None;
                }
                let t = (self.seabed_z - o.z) / d.z;
                (t > 0.0).then(|| o + t * d)
            }
        }
    }

    /// Whether the segment between `a` and `b` is blocked.
    pub fn occluded(&self, a: DVec3, b: DVec3) -> bool {
        self.scene.as_ref().is_some_and(|s| s.occluded(a, b))
    }
}

/// Min / mean / max of a quantity.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Stats {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
    pub n: usize,
}

impl Stats {
    fn of(v: &[f64]) -> Option<Stats> {
        if v.is_empty() {
            return None;
        }
        let min = v.iter().cloned().fold(f64::INFINITY, f64::min);
        let max = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        Some(Stats {
            min,
            mean: v.iter().sum::<f64>() / v.len() as f64,
            max,
            n: v.len(),
        })
    }
}

/// Everything `poser plan` reports.
#[derive(Debug, Clone, Serialize)]
pub struct SurveyReport {
    pub images: usize,
    pub rig_poses: usize,
    pub cameras: usize,
    pub strips: u32,
    pub network: String,
    pub path_length: f64,
    pub speed: f64,
    /// Survey time, s.
    pub duration: f64,
    pub port: String,
    /// GSD through the port at the centre pixel's hit, m/px.
    pub gsd: Option<Stats>,
    /// Distance from the entrance pupil to the site along the centre ray, m.
    pub distance: Option<Stats>,
    /// GSD through the port ÷ GSD of the same lens in air at the same distance (flat ≈ 1/n).
    pub port_gsd_factor: Option<f64>,
    /// Footprint across (image x) and along (image y), m.
    pub footprint_across: Option<Stats>,
    pub footprint_along: Option<Stats>,
    /// Achieved forward overlap and side-lap, fractions.
    pub overlap: Option<Stats>,
    pub sidelap: Option<Stats>,
    pub nominal_overlap: Option<f64>,
    pub nominal_sidelap: Option<f64>,
    pub nominal_altitude: Option<f64>,
    /// Camera distance needed for target GSDs: (GSD m/px, distance m).
    pub distance_for_gsd: Vec<(f64, f64)>,
    pub notes: Vec<String>,
}

/// Exact GSD (m/px) at camera-frame point `p` (1 mm step along the camera's x).
fn gsd_at(proj: &Projector, p: DVec3) -> Option<f64> {
    let d = 1e-3;
    let a = proj.project_camera_unbounded(p).ok()?;
    let b = proj
        .project_camera_unbounded(p + DVec3::new(d, 0.0, 0.0))
        .ok()?;
    let du = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    (du > 0.0).then(|| d / du)
}

/// Distance along the optical axis giving `target` GSD (m/px), by fixed-point iteration on the
/// exact projection (GSD is nearly proportional to distance).
pub fn distance_for_gsd(proj: &Projector, target: f64) -> Option<f64> {
    let mut z = 1.0;
    for _ in 0..30 {
        let g = gsd_at(proj, DVec3::new(0.0, 0.0, z))?;
        let next = z * target / g;
        if (next - z).abs() < 1e-9 {
            return Some(next);
        }
        z = next;
    }
    Some(z)
}

fn sample_indices(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        (0..n).collect()
    } else {
        (0..max).map(|k| k * (n - 1) / (max - 1)).collect()
    }
}

/// Fraction of image `i`'s view of the site also seen by image `j`.
fn shared_fraction(proj: &Projector, site: &Site, i: usize, j: usize) -> Option<f64> {
    // 64 × 48 cells: a row is 2 % of the image, so the measure resolves the 2 % by which a
    // planned overlap may miss the requested one.
    let (nx, ny) = (64, 48);
    let (mut hit, mut seen) = (0usize, 0usize);
    let cj = proj.world_from_camera(j).translation;
    for a in 0..nx {
        for b in 0..ny {
            let u = (a as f64 + 0.5) / nx as f64 * proj.width;
            let v = (b as f64 + 0.5) / ny as f64 * proj.height;
            let Ok((o, d, _)) = proj.pixel_ray_world(i, u, v) else {
                continue;
            };
            let Some(p) = site.hit(o, d) else { continue };
            hit += 1;
            if proj.project_world(j, p).is_ok() && !site.occluded(p, cj) {
                seen += 1;
            }
        }
    }
    (hit > 0).then(|| seen as f64 / hit as f64)
}

/// Compute the survey report.
pub fn survey(model: &Model, site: &Site) -> Result<SurveyReport, String> {
    if model.cameras.is_empty() {
        return Err("the scene has no camera".into());
    }
    let proj = model.projector(0, 1)?;
    let cam = &model.cameras[0];
    let n = model.poses.len();
    let mut notes: Vec<String> = site.note.iter().cloned().collect();
    if model.cameras.len() > 1 {
        notes.push(format!(
            "metrics use camera `{}`; the rig has {} cameras",
            cam.name,
            model.cameras.len()
        ));
    }

    // GSD, distance and footprint at up to 400 poses.
    let idx = sample_indices(n, 400);
    let per: Vec<Option<PoseMetrics>> = idx
        .par_iter()
        .map(|&i| pose_metrics(&proj, site, cam, i))
        .collect();
    let ok: Vec<PoseMetrics> = per.into_iter().flatten().collect();
    if ok.len() < idx.len() {
        notes.push(format!(
            "{} of {} sampled images do not see the site at their centre or corners (footprint/GSD from the others)",
            idx.len() - ok.len(),
            idx.len()
        ));
    }
    let col = |k: usize| -> Vec<f64> { ok.iter().map(|t| [t.0, t.1, t.2, t.3, t.4][k]).collect() };

    // Forward pairs: consecutive poses of one strip; side pairs: nearest pose of the next strip.
    let (fwd, side) = strip_pairs(model);
    let pick = |pairs: &[(usize, usize)]| -> Vec<(usize, usize)> {
        sample_indices(pairs.len(), 200)
            .into_iter()
            .map(|k| pairs[k])
            .collect()
    };
    let frac = |pairs: Vec<(usize, usize)>| -> Vec<f64> {
        pairs
            .par_iter()
            .filter_map(|&(i, j)| shared_fraction(&proj, site, i, j))
            .collect()
    };
    let overlap = Stats::of(&frac(pick(&fwd)));
    let sidelap = Stats::of(&frac(pick(&side)));

    // What would restore the nominal overlaps on the real footprint.
    let fp_across = Stats::of(&col(3));
    let fp_along = Stats::of(&col(4));
    overlap_notes(model, (overlap, sidelap), (fp_across, fp_along), &mut notes);
    let distance_for_gsd = [0.25e-3, 0.5e-3, 1e-3, 2e-3]
        .iter()
        .filter_map(|&g| distance_for_gsd(&proj, g).map(|d| (g, d)))
        .collect();
    Ok(SurveyReport {
        images: n * model.cameras.len(),
        rig_poses: n,
        cameras: model.cameras.len(),
        strips: model.network.strips,
        network: model.network.kind.clone(),
        path_length: model.network.path_length,
        speed: model.network.speed,
        duration: model.network.duration,
        port: cam.port.kind_name().to_string(),
        gsd: Stats::of(&col(0)),
        distance: Stats::of(&col(1)),
        port_gsd_factor: Stats::of(&col(2)).map(|s| s.mean),
        footprint_across: fp_across,
        footprint_along: fp_along,
        overlap,
        sidelap,
        nominal_overlap: model.network.overlap_requested,
        nominal_sidelap: model.network.sidelap_requested,
        nominal_altitude: model.network.altitude,
        distance_for_gsd,
        notes,
    })
}

/// (GSD, distance, GSD factor of the port, footprint across, footprint along) of one pose.
type PoseMetrics = (f64, f64, f64, f64, f64);

/// The metrics of pose `i` where its centre ray meets the site, with the footprint of its four
/// corners; `None` when the centre or a corner misses the site.
fn pose_metrics(
    proj: &Projector,
    site: &Site,
    cam: &crate::model::Camera,
    i: usize,
) -> Option<PoseMetrics> {
    let (o, d, _) = proj
        .pixel_ray_world(i, proj.width / 2.0, proj.height / 2.0)
        .ok()?;
    let p = site.hit(o, d)?;
    let w = proj.world_from_camera(i);
    let pc = w.inverse().transform_point(p);
    let g = gsd_at(&proj, pc)?;
    let air = pc.z / cam.fx;
    let corners = [
        (0.0, 0.0),
        (proj.width, 0.0),
        (proj.width, proj.height),
        (0.0, proj.height),
    ];
    let mut hits = Vec::new();
    for (u, v) in corners {
        let (o, d, _) = proj.pixel_ray_world(i, u, v).ok()?;
        hits.push(site.hit(o, d)?);
    }
    let across = 0.5 * ((hits[1] - hits[0]).length() + (hits[2] - hits[3]).length());
    let along = 0.5 * ((hits[3] - hits[0]).length() + (hits[2] - hits[1]).length());
    Some((g, (p - w.translation).length(), g / air, across, along))
}

/// The image pairs whose overlaps are measured: forward pairs, consecutive poses (in time) of
/// one strip; side pairs, each pose with the nearest pose of the next strip.
#[allow(clippy::type_complexity)]
fn strip_pairs(model: &Model) -> (Vec<(usize, usize)>, Vec<(usize, usize)>) {
    let n = model.poses.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| model.poses[a].time.total_cmp(&model.poses[b].time));
    let fwd: Vec<(usize, usize)> = order
        .windows(2)
        .filter(|w| model.poses[w[0]].strip == model.poses[w[1]].strip)
        .map(|w| (w[0], w[1]))
        .collect();
    let pos = |i: usize| model.poses[i].world_from_rig.translation;
    let mut side: Vec<(usize, usize)> = Vec::new();
    for i in 0..n {
        let s = model.poses[i].strip;
        let best = (0..n)
            .filter(|&j| model.poses[j].strip == s + 1)
            .min_by(|&a, &b| {
                let da = (pos(a) - pos(i)).truncate().length();
                let db = (pos(b) - pos(i)).truncate().length();
                da.total_cmp(&db)
            });
        if let Some(j) = best {
            side.push((i, j));
        }
    }
    (fwd, side)
}

/// What would restore the nominal overlaps on the real footprint: the trigger spacing and the
/// strip spacing that give them, as notes.
fn overlap_notes(
    model: &Model,
    (overlap, sidelap): (Option<Stats>, Option<Stats>),
    (fp_across, fp_along): (Option<Stats>, Option<Stats>),
    notes: &mut Vec<String>,
) {
    let n = model.poses.len();
    if let (Some(o), Some(nom), Some(fp), Some(sp)) = (
        overlap,
        model.network.overlap_requested,
        fp_along,
        model.network.spacing,
    ) && o.mean < nom - 0.03
    {
        let need = (1.0 - nom) * fp.mean;
        if need < 0.98 * sp {
            notes.push(format!(
                "forward overlap {:.0} % is below the nominal {:.0} %: trigger every {need:.2} m \
                     instead of {sp:.2} m ({:.0} images instead of {})",
                o.mean * 100.0,
                nom * 100.0,
                (n as f64 * sp / need).ceil(),
                n
            ));
        } else {
            // The spacing already gives the nominal overlap on the mean footprint: what is
            // lost is lost to relief, the diver's wobble or occlusion, not to the trigger.
            notes.push(format!(
                "forward overlap {:.0} % is below the nominal {:.0} % although the trigger \
                     spacing ({sp:.2} m) matches the mean footprint: relief, wobble and \
                     occlusion take the rest; ask for more `overlap` to keep {:.0} %",
                o.mean * 100.0,
                nom * 100.0,
                nom * 100.0
            ));
        }
    }
    if let (Some(sl), Some(nom), Some(fp), Some(ss)) = (
        sidelap,
        model.network.sidelap_requested,
        fp_across,
        model.network.strip_spacing,
    ) && sl.mean < nom - 0.03
        && ss > 0.0
    {
        let need = (1.0 - nom) * fp.mean;
        let width = ss * (model.network.strips.max(1) - 1) as f64;
        notes.push(format!(
            "side-lap {:.0} % is below the nominal {:.0} %: strips {need:.2} m apart instead of \
                 {ss:.2} m ({} strips instead of {} over the same {width:.1} m)",
            sl.mean * 100.0,
            nom * 100.0,
            (width / need - 1e-9).ceil() as u64 + 1,
            model.network.strips
        ));
    }
}

// ------------------------------------------------------------------------------------------
// Coverage
// ------------------------------------------------------------------------------------------

/// Per-face image counts over the site's mesh.
#[derive(Debug, Clone)]
pub struct Coverage {
    pub mesh: TriMesh,
    /// Images seeing each face.
    pub counts: Vec<u32>,
    /// Whether the nominal seabed grid was used (no scene geometry).
    pub grid: bool,
    /// Faces actually evaluated (large meshes are evaluated per xy cell, see [`coverage`]).
    pub evaluated: usize,
}

/// Summary numbers of a coverage.
#[derive(Debug, Clone, Serialize)]
pub struct CoverageSummary {
    pub faces: usize,
    pub evaluated: usize,
    pub on_seabed_grid: bool,
    /// Area-weighted fractions of the site seen by 0, 1, 2, ≥ 3 images.
    pub unseen: f64,
    pub one: f64,
    pub two: f64,
    pub three_or_more: f64,
    pub max_count: u32,
}

/// Largest number of faces evaluated one by one; bigger meshes are evaluated per xy cell.
pub const MAX_EVALUATED: usize = 40_000;

/// How many images see each face of the site (face centre on the sensor, face turned towards
/// the camera, line of sight not blocked). Without geometry, a 0.25 m grid over the network's
/// area on the nominal seabed. Meshes over [`MAX_EVALUATED`] faces are binned into xy cells and
/// each cell's highest face stands for the cell.
pub fn coverage(model: &Model, site: &Site) -> Result<Coverage, String> {
    let proj = model.projector(0, 1)?;
    let base = std::path::Path::new(&model.source)
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let mut mesh = TriMesh::default();
    // Backdrop objects are scenery, not the site (their faces would swamp the counts).
    for o in model.objects.iter().filter(|o| !o.backdrop) {
        if let Ok(m) = crate::geometry::mesh::object_mesh(o, base) {
            mesh.append(&m);
        }
    }
    let grid = mesh.triangles.is_empty() || site.scene.is_none();
    if grid {
        mesh = seabed_grid(model);
    } else {
        mesh = refine(&mesh, 0.25, 4 * MAX_EVALUATED);
    }
    let nf = mesh.triangles.len();
    let centroid = |f: usize| {
        let [a, b, c] = mesh.triangles[f].map(|i| mesh.positions[i as usize]);
        (a + b + c) / 3.0
    };
    // Representatives: every face, or the highest face per xy cell.
    let mut rep: Vec<usize> = (0..nf).collect();
    let mut owner: Vec<usize> = (0..nf).collect();
    if nf > MAX_EVALUATED {
        let (lo, hi) = mesh.bounds().ok_or("empty mesh")?;
        let area = ((hi.x - lo.x) * (hi.y - lo.y)).max(1e-9);
        let cell = (area / MAX_EVALUATED as f64).sqrt();
        let nx = ((hi.x - lo.x) / cell).ceil().max(1.0) as usize;
        let ny = ((hi.y - lo.y) / cell).ceil().max(1.0) as usize;
        let mut best: Vec<Option<usize>> = vec![None; nx * ny];
        let cell_of = |p: DVec3| {
            let i = (((p.x - lo.x) / cell) as usize).min(nx - 1);
            let j = (((p.y - lo.y) / cell) as usize).min(ny - 1);
            j * nx + i
        };
        for f in 0..nf {
            let p = centroid(f);
            let c = cell_of(p);
            if best[c].is_none_or(|b| centroid(b).z < p.z) {
                best[c] = Some(f);
            }
        }
        rep = best.iter().flatten().copied().collect();
        for (f, o) in owner.iter_mut().enumerate() {
            *o = best[cell_of(centroid(f))].unwrap_or(f);
        }
    }
    let cams: Vec<DVec3> = (0..model.poses.len())
        .map(|i| proj.world_from_camera(i).translation)
        .collect();
    let cam_from_world: Vec<crate::model::Pose> = (0..model.poses.len())
        .map(|i| proj.world_from_camera(i).inverse())
        .collect();
    // Cheap cone test before the exact projection: the widest corner ray in water, +5 %.
    let mut tan2 = 0.0f64;
    for (u, v) in [
        (0.0, 0.0),
        (proj.width, 0.0),
        (proj.width, proj.height),
        (0.0, proj.height),
    ] {
        match proj.camera_ray(u, v) {
            Ok(r) if r.dir.z > 1e-6 => {
                tan2 = tan2.max((r.dir.x.powi(2) + r.dir.y.powi(2)) / r.dir.z.powi(2))
            }
            _ => tan2 = f64::INFINITY,
        }
    }
    let tan2 = tan2 * 1.1025;
    let counts_rep: Vec<u32> = rep
        .par_iter()
        .map(|&f| {
            let p = centroid(f);
            let nrm = mesh.face_normal(f);
            let mut k = 0u32;
            for (i, c) in cams.iter().enumerate() {
                let to_cam = *c - p;
                // A face seen from behind does not count (one-sided surfaces, as rendered).
                if nrm.dot(to_cam) <= 0.0 {
                    continue;
                }
                let pc = cam_from_world[i].transform_point(p);
                if pc.z <= 0.0 || (pc.x * pc.x + pc.y * pc.y) > tan2 * pc.z * pc.z {
                    continue;
                }
                if proj.project_world(i, p).is_err() {
                    continue;
                }
                if site.occluded(p + nrm * 1e-4, *c) {
                    continue;
                }
                k += 1;
            }
            k
        })
        .collect();
    let mut by_face = vec![0u32; nf];
    for (r, &f) in rep.iter().enumerate() {
        by_face[f] = counts_rep[r];
    }
    let counts = (0..nf).map(|f| by_face[owner[f]]).collect();
    Ok(Coverage {
        mesh,
        counts,
        grid,
        evaluated: rep.len(),
    })
}

/// Split triangles (1 → 4 at edge midpoints) until every edge is ≤ `max_edge` m or the mesh
/// would exceed `max_faces` faces, so that large flat faces get a useful coverage resolution.
pub fn refine(mesh: &TriMesh, max_edge: f64, max_faces: usize) -> TriMesh {
    let mut m = mesh.clone();
    loop {
        let long = |t: &[u32; 3], m: &TriMesh| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            (a - b).length().max((b - c).length()).max((c - a).length()) > max_edge
        };
        let n_long = m.triangles.iter().filter(|t| long(t, &m)).count();
        if n_long == 0 || m.triangles.len() + 3 * n_long > max_faces {
            return m;
        }
        let mut out = TriMesh {
            positions: m.positions.clone(),
            triangles: Vec::new(),
        };
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |i: u32, j: u32, out: &mut TriMesh| -> u32 {
            let key = (i.min(j), i.max(j));
            *mid.entry(key).or_insert_with(|| {
                let p = 0.5 * (out.positions[i as usize] + out.positions[j as usize]);
                out.positions.push(p);
                (out.positions.len() - 1) as u32
            })
        };
        for t in &m.triangles {
            if !long(t, &m) {
                out.triangles.push(*t);
                continue;
            }
            let [a, b, c] = *t;
            let ab = midpoint(a, b, &mut out);
            let bc = midpoint(b, c, &mut out);
            let ca = midpoint(c, a, &mut out);
            out.triangles
                .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        m = out;
    }
}

/// A 0.25 m grid on the nominal seabed over the network's area (path bounds + 3 m).
fn seabed_grid(model: &Model) -> TriMesh {
    let z = -model.site.depth;
    let pts: Vec<DVec3> = model
        .poses
        .iter()
        .map(|p| p.world_from_rig.translation)
        .collect();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in &pts {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let m = 3.0;
    let (x0, y0, x1, y1) = (lo.x - m, lo.y - m, hi.x + m, hi.y + m);
    let mut cell = 0.25;
    while ((x1 - x0) / cell) * ((y1 - y0) / cell) > MAX_EVALUATED as f64 / 2.0 {
        cell *= 1.5;
    }
    let nx = ((x1 - x0) / cell).ceil() as usize;
    let ny = ((y1 - y0) / cell).ceil() as usize;
    let mut mesh = TriMesh::default();
    for j in 0..=ny {
        for i in 0..=nx {
            mesh.positions
                .push(DVec3::new(x0 + i as f64 * cell, y0 + j as f64 * cell, z));
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            mesh.triangles
                .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            mesh.triangles
                .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    mesh
}

impl Coverage {
    pub fn summary(&self) -> CoverageSummary {
        let mut a = [0.0f64; 4];
        let mut total = 0.0;
        for (f, &c) in self.counts.iter().enumerate() {
            let [p, q, r] = self.mesh.triangles[f].map(|i| self.mesh.positions[i as usize]);
            let area = 0.5 * (q - p).cross(r - p).length();
            a[(c as usize).min(3)] += area;
            total += area;
        }
        let t = total.max(1e-300);
        CoverageSummary {
            faces: self.counts.len(),
            evaluated: self.evaluated,
            on_seabed_grid: self.grid,
            unseen: a[0] / t,
            one: a[1] / t,
            two: a[2] / t,
            three_or_more: a[3] / t,
            max_count: self.counts.iter().copied().max().unwrap_or(0),
        }
    }

    /// Colour of a count: red (0) → orange (1) → yellow (2) → green (≥ 3, brighter with more).
    pub fn colour(count: u32, max: u32) -> [u8; 3] {
        match count {
            0 => [200, 30, 30],
            1 => [240, 130, 30],
            2 => [240, 220, 40],
            _ => {
                let f = if max > 3 {
                    (count - 3) as f64 / (max - 3) as f64
                } else {
                    1.0
                };
                [
                    (40.0 * (1.0 - f)) as u8,
                    (150.0 + 80.0 * f) as u8,
                    (60.0 + 60.0 * f) as u8,
                ]
            }
        }
    }

    /// Binary PLY with per-face `red green blue` and `count`.
    pub fn ply(&self) -> Vec<u8> {
        let max = self.counts.iter().copied().max().unwrap_or(0);
        let mut out = format!(
            "ply\nformat binary_little_endian 1.0\ncomment poser coverage: images per face\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar int vertex_indices\nproperty uchar red\n\
             property uchar green\nproperty uchar blue\nproperty int count\nend_header\n",
            self.mesh.positions.len(),
            self.mesh.triangles.len()
        )
        .into_bytes();
        for p in &self.mesh.positions {
            for c in p.to_array() {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        for (t, &c) in self.mesh.triangles.iter().zip(&self.counts) {
            out.push(3);
            for i in t {
                out.extend_from_slice(&(*i as i32).to_le_bytes());
            }
            out.extend_from_slice(&Coverage::colour(c, max));
            out.extend_from_slice(&(c as i32).to_le_bytes());
        }
        out
    }

    /// Top-down map (xy, north up) of the counts: each pixel takes the highest face over it.
    pub fn map(&self, max_px: u32) -> image::RgbImage {
        let (lo, hi) = self.mesh.bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
        let (w_m, h_m) = ((hi.x - lo.x).max(1e-6), (hi.y - lo.y).max(1e-6));
        let s = max_px as f64 / w_m.max(h_m);
        let (w, h) = (
            ((w_m * s).ceil() as u32).max(1),
            ((h_m * s).ceil() as u32).max(1),
        );
        let max = self.counts.iter().copied().max().unwrap_or(0);
        let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
        let mut zbuf = vec![f64::NEG_INFINITY; (w * h) as usize];
        for (f, t) in self.mesh.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| self.mesh.positions[i as usize]);
            let to_px = |p: DVec3| ((p.x - lo.x) * s, (hi.y - p.y) * s);
            let (pa, pb, pc) = (to_px(a), to_px(b), to_px(c));
            let x0 = pa.0.min(pb.0).min(pc.0).floor().max(0.0) as u32;
            let x1 = (pa.0.max(pb.0).max(pc.0).ceil() as u32).min(w);
            let y0 = pa.1.min(pb.1).min(pc.1).floor().max(0.0) as u32;
            let y1 = (pa.1.max(pb.1).max(pc.1).ceil() as u32).min(h);
            let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pc.0 - pa.0) * (pb.1 - pa.1);
            if area.abs() < 1e-12 {
                continue;
            }
            let z = (a.z + b.z + c.z) / 3.0;
            let col = image::Rgb(Coverage::colour(self.counts[f], max));
            for y in y0..y1 {
                for x in x0..x1 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let w0 = (pb.0 - px) * (pc.1 - py) - (pc.0 - px) * (pb.1 - py);
                    let w1 = (pc.0 - px) * (pa.1 - py) - (pa.0 - px) * (pc.1 - py);
                    let w2 = (pa.0 - px) * (pb.1 - py) - (pb.0 - px) * (pa.1 - py);
                    let inside = (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0)
                        || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0);
                    let k = (y * w + x) as usize;
                    if inside && z > zbuf[k] {
                        zbuf[k] = z;
                        img.put_pixel(x, y, col);
                    }
                }
            }
        }
        img
    }
}
