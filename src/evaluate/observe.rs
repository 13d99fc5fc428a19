//! Simulated image measurements for `poser evaluate`'s observations mode: tie points sampled
//! over the scene's surfaces, observed through the exact refractive projection wherever they
//! land on the sensor unblocked, with seeded Gaussian pixel noise.
//!
//! | item | meaning |
//! |---|---|
//! | [`sample_points`] | tie points, area-weighted over every object and target surface (`density` per m²), plus the targets' points as ground control |
//! | [`observe`] | per image, the points it sees: G-channel pixel on the sensor, not grazing, water path unblocked |
//! | [`add_noise`] | Gaussian pixel noise, one seeded stream per image (thread-count independent) |
//! | [`gauss`] | a standard normal deviate from [`SplitMix64`] (Box–Muller) |
//!
//! A point is *observed* by an image under the same rule as the ground truth of targets
//! ([`crate::truth`]): its projection lands on the sensor and nothing blocks the segment from
//! the point to where its ray leaves the port. A feature seen at more than
//! [`MAX_INCIDENCE_DEG`] from its surface normal is not matched by real software and is left out.

use crate::geometry::Bvh as Scene;
use crate::geometry::mesh::TriMesh;
use crate::model::Model;
use crate::optics::NoSolution;
use crate::optics::project::Projector;
use crate::rng::SplitMix64;
use glam::DVec3;
use rayon::prelude::*;

/// Largest angle between a surface normal and the line of sight at which a tie point is
/// still observed, degrees.
pub const MAX_INCIDENCE_DEG: f64 = 80.0;

/// Hard cap on sampled tie points (a density typo must not exhaust memory).
pub const MAX_POINTS: usize = 2_000_000;

/// What a 3D point is for the evaluation.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointKind {
    /// A tie point on a surface (matched texture).
    Tie,
    /// A target point (coded target, scale bar, …): ground control when `--gcp` is given.
    Target,
}

/// A 3D point of the simulated survey.
#[derive(Debug, Clone)]
pub struct SurveyPoint {
    pub world: DVec3,
    /// Unit normal of the surface it lies on.
    pub normal: DVec3,
    pub kind: PointKind,
    /// The object or target it lies on; for target points, `target/id`.
    pub label: String,
}

/// One image's observations: `(point index, u, v)`, pixel centres at +0.5.
#[derive(Debug, Clone)]
pub struct ImageObservations {
    pub pose: usize,
    pub camera: usize,
    pub name: String,
    pub points: Vec<(usize, [f64; 2])>,
}

/// A standard normal deviate ([`SplitMix64::normal`]).
pub fn gauss(rng: &mut SplitMix64) -> f64 {
    rng.normal()
}

/// Tie points sampled uniformly by area over `meshes` (`(label, world mesh)`), about `density`
/// per m², from `seed`; then every target point of the model.
pub fn sample_points(
    model: &Model,
    meshes: &[(String, TriMesh)],
    density: f64,
    seed: u64,
) -> Result<Vec<SurveyPoint>, String> {
    if !(density.is_finite() && density > 0.0) {
        return Err(format!(
            "--density {density}: expected a positive number of tie points per m²"
        ));
    }
    // Cumulative area over all triangles of all meshes.
    let mut cdf = Vec::new();
    let mut tris = Vec::new();
    let mut total = 0.0;
    for (mi, (_, m)) in meshes.iter().enumerate() {
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let area = 0.5 * (b - a).cross(c - a).length();
            if area.is_finite() && area > 0.0 {
                total += area;
                cdf.push(total);
                tris.push((mi, [a, b, c]));
            }
        }
    }
    let n = (density * total).round() as usize;
    if n > MAX_POINTS {
        return Err(format!(
            "--density {density} per m² over {total:.0} m² of surface asks for {n} tie points \
             (at most {MAX_POINTS})\n  help: lower --density"
        ));
    }
    let mut rng = SplitMix64(seed ^ 0x7E5E_A11C_0B5E_57ED);
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let x = rng.next_f64() * total;
        let k = cdf.partition_point(|&c| c <= x).min(tris.len() - 1);
        let (mi, [a, b, c]) = tris[k];
        let (mut r1, mut r2) = (rng.next_f64(), rng.next_f64());
        if r1 + r2 > 1.0 {
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        out.push(SurveyPoint {
            world: a + (b - a) * r1 + (c - a) * r2,
            normal: (b - a).cross(c - a).normalize(),
            kind: PointKind::Tie,
            label: meshes[mi].0.clone(),
        });
    }
    for t in &model.targets {
        for p in &t.points {
            out.push(SurveyPoint {
                world: p.world,
                normal: t.pose.rotation.z_axis,
                kind: PointKind::Target,
                // A points file's disk is its own target, already named `file/id`.
                label: if p.id == t.name || p.id.starts_with(&format!("{}/", t.name)) {
                    p.id.clone()
                } else {
                    format!("{}/{}", t.name, p.id)
                },
            });
        }
    }
    Ok(out)
}

/// Every image's observations of `points` (G channel), in image order (pose-major, then
/// camera). `progress` is called once per finished image.
pub fn observe(
    model: &Model,
    scene: &Scene,
    points: &[SurveyPoint],
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<ImageObservations>, String> {
    let projectors: Vec<Projector> = (0..model.cameras.len())
        .map(|ci| model.projector(ci, 1))
        .collect::<Result<_, _>>()?;
    let cos_max = MAX_INCIDENCE_DEG.to_radians().cos();
    let jobs: Vec<(usize, usize)> = (0..model.poses.len())
        .flat_map(|pi| (0..model.cameras.len()).map(move |ci| (pi, ci)))
        .collect();
    let images = jobs
        .par_iter()
        .map(|&(pi, ci)| {
            let pr = &projectors[ci];
            let wfc = model.world_from_camera(pi, ci);
            let cfw = wfc.inverse();
            let centre = wfc.translation;
            // Cheap cull: in front of the camera, inside a cone wider than any port's field.
            let cam = &model.cameras[ci];
            let half_diag =
                ((cam.width as f64 / cam.fx).powi(2) + (cam.height as f64 / cam.fy).powi(2)).sqrt()
                    * 0.5;
            let cone = (half_diag.atan() * 1.2 + 0.05).min(std::f64::consts::PI);
            let cos_cone = cone.cos();
            let axis = wfc.rotation.z_axis;
            let mut idx = Vec::new();
            let mut in_cam = Vec::new();
            for (k, p) in points.iter().enumerate() {
                let d = p.world - centre;
                let len = d.length();
                if len > 0.0 && d.dot(axis) > len * cos_cone {
                    idx.push(k);
                    in_cam.push(cfw.transform_point(p.world));
                }
            }
            let mut uv = vec![Err(NoSolution::NoConvergence); in_cam.len()];
            pr.project_camera_many(&in_cam, &mut uv);
            let mut seen = Vec::new();
            for (j, r) in uv.iter().enumerate() {
                let Ok(px) = r else { continue };
                let p = &points[idx[j]];
                let Ok((exit, _, _)) = pr.pixel_ray_world(pi, px[0], px[1]) else {
                    continue;
                };
                let sight = exit - p.world;
                let len = sight.length();
                if len <= 0.0 || p.normal.dot(sight).abs() < cos_max * len {
                    continue;
                }
                if p.kind == PointKind::Target && p.normal.dot(sight) <= 0.0 {
                    continue; // a printed target seen from behind
                }
                if scene.occluded(p.world, exit) {
                    continue;
                }
                seen.push((idx[j], *px));
            }
            progress();
            ImageObservations {
                pose: pi,
                camera: ci,
                name: model.image_name(pi, ci),
                points: seen,
            }
        })
        .collect();
    Ok(images)
}

/// Add Gaussian noise of `sigma` px to every observation; image `i`'s stream is seeded by
/// `(seed, i)`, so the result does not depend on the thread count.
pub fn add_noise(images: &mut [ImageObservations], sigma: f64, seed: u64) {
    if sigma <= 0.0 {
        return;
    }
    images.par_iter_mut().enumerate().for_each(|(i, im)| {
        let mut rng = SplitMix64(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x4015E);
        for (_, px) in &mut im.points {
            px[0] += sigma * gauss(&mut rng);
            px[1] += sigma * gauss(&mut rng);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_has_unit_variance_and_zero_mean() {
        let mut rng = SplitMix64(5);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| gauss(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.01, "variance {var}");
    }

    #[test]
    fn noise_is_seeded_per_image() {
        let mk = || {
            vec![
                ImageObservations {
                    pose: 0,
                    camera: 0,
                    name: "a".into(),
                    points: vec![(0, [10.0, 10.0]); 50],
                };
                3
            ]
        };
        let (mut a, mut b) = (mk(), mk());
        add_noise(&mut a, 0.3, 9);
        add_noise(&mut b, 0.3, 9);
        assert_eq!(a[2].points, b[2].points);
        assert_ne!(a[0].points, a[1].points, "images draw different noise");
        let d: Vec<f64> = a[0].points.iter().map(|p| p.1[0] - 10.0).collect();
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        assert!(rms > 0.15 && rms < 0.5, "rms {rms}");
    }
}
