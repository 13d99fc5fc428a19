//! Mitsuba backend against analytic truth, rendering small images with the real `mitsuba`
//! package (variant `scalar_rgb`): target centroids through a flat port, and the radiance of a
//! Lambertian patch lit by a point light in absorbing water (Beer–Lambert × inverse square ×
//! Fresnel × n²).
//!
//! Each render is 160×120 at 16–32 spp (≈0.3–1 s). Tolerances are derived from the measured
//! Monte Carlo noise of each image and written next to each check.

use crate::support;
use glam::{DMat3, DVec3};
use poser::backend::{RenderOptions, mitsuba};
use poser::compare::LinearImage;
use poser::compare::detect::polygon_centroid;
use support::mitsuba::*;

use poser::model::*;

fn require_mitsuba() {
    if let Err(e) = poser::backend::python::require_module("mitsuba") {
        panic!("these tests render with the real Mitsuba 3: {e}");
    }
}

fn render(model: &Model, name: &str) -> (LinearImage, std::path::PathBuf) {
    require_mitsuba();
    let dir = tempfile::Builder::new()
        .prefix(name)
        .tempdir()
        .unwrap()
        .keep();
    let report = mitsuba::render(model, &dir, &RenderOptions::default()).unwrap();
    assert_eq!(report.images.len(), 1, "{:?}", report.images);
    let img = LinearImage::read(&report.images[0]).unwrap();
    (img, dir)
}

/// Camera looking along `dir` (world) from `pos`, OpenCV axes, with world z as "up" hint.
fn look(pos: DVec3, dir: DVec3) -> Pose {
    let z = dir.normalize();
    let x = z.cross(DVec3::Z).normalize();
    let y = z.cross(x);
    Pose {
        rotation: DMat3::from_cols(x, y, z),
        translation: pos,
    }
}

/// Unpolarised Fresnel transmittance from index n1 into n2 at incidence cosine `ci`.
fn fresnel_t(n1: f64, n2: f64, ci: f64) -> f64 {
    let s2t = (n1 / n2).powi(2) * (1.0 - ci * ci);
    if s2t >= 1.0 {
        return 0.0;
    }
    let ct = (1.0 - s2t).sqrt();
    let rs = ((n1 * ci - n2 * ct) / (n1 * ci + n2 * ct)).powi(2);
    let rp = ((n1 * ct - n2 * ci) / (n1 * ct + n2 * ci)).powi(2);
    1.0 - 0.5 * (rs + rp)
}

/// Refract unit `d` through a surface with unit normal `n` (pointing along the travel side),
/// from index n1 into n2.
fn refract(d: DVec3, n: DVec3, n1: f64, n2: f64) -> Option<DVec3> {
    let eta = n1 / n2;
    let ci = d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - ci * ci);
    (k >= 0.0).then(|| (eta * d + (ci.signum() * k.sqrt() - eta * ci) * n).normalize())
}

struct FlatPort {
    n: DVec3,
    d: f64,
    t: f64,
    ng: f64,
    nw: f64,
}

impl FlatPort {
    /// Exact forward projection of camera-frame point `x` (in the water) to the air-side
    /// direction at the pupil, by bisection on the sine of the air angle.
    fn air_direction(&self, x: DVec3) -> Option<DVec3> {
        let zx = x.dot(self.n);
        let radial = x - zx * self.n;
        let rho = radial.length();
        if rho < 1e-15 {
            return Some(self.n);
        }
        let e = radial / rho;
        let lateral = |s: f64| {
            let tan = |sn: f64| sn / (1.0 - sn * sn).sqrt();
            self.d * tan(s) + self.t * tan(s / self.ng) + (zx - self.d - self.t) * tan(s / self.nw)
        };
        let (mut lo, mut hi) = (0.0, (1.0f64).min(self.nw) - 1e-12);
        if lateral(hi) < rho {
            return None;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if lateral(mid) < rho {
                lo = mid
            } else {
                hi = mid
            }
        }
        let s = 0.5 * (lo + hi);
        Some((1.0 - s * s).sqrt() * self.n + s * e)
    }
}

fn pixel(cam: &Camera, d: DVec3) -> Option<[f64; 2]> {
    (d.z > 0.0).then(|| [cam.fx * d.x / d.z + cam.cx, cam.fy * d.y / d.z + cam.cy])
}

/// Clip a polygon to the half-plane `sign·(p[axis] - bound) ≤ 0` (Sutherland–Hodgman).
fn clip(poly: &[[f64; 2]], axis: usize, bound: f64, sign: f64) -> Vec<[f64; 2]> {
    let inside = |p: &[f64; 2]| sign * (p[axis] - bound) <= 0.0;
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ia, ib) = (inside(&a), inside(&b));
        if ia {
            out.push(a);
        }
        if ia != ib {
            let f = (bound - a[axis]) / (b[axis] - a[axis]);
            out.push([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
        }
    }
    out
}

fn area(poly: &[[f64; 2]]) -> f64 {
    let mut a = 0.0;
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        a += p[0] * q[1] - q[0] * p[1];
    }
    0.5 * a.abs()
}

/// What an intensity centroid with pixel-centre coordinates measures for a uniformly bright
/// shape with a box pixel filter: Σ coverage·centre / Σ coverage, the coverage of each pixel
/// computed exactly by clipping the projected outline. (This differs from the area centroid by
/// up to a few hundredths of a pixel for a 5 px shape, depending on its sub-pixel phase.)
fn pixelized_centroid(outline: &[[f64; 2]], near: [f64; 2], r: i64) -> [f64; 2] {
    let (px, py) = (near[0].floor() as i64, near[1].floor() as i64);
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in py - r..=py + r {
        for x in px - r..=px + r {
            let (x0, y0) = (x as f64, y as f64);
            let mut p = clip(outline, 0, x0, -1.0);
            p = clip(&p, 0, x0 + 1.0, 1.0);
            p = clip(&p, 1, y0, -1.0);
            p = clip(&p, 1, y0 + 1.0, 1.0);
            if p.len() >= 3 {
                let w = area(&p);
                sw += w;
                sx += w * (x0 + 0.5);
                sy += w * (y0 + 0.5);
            }
        }
    }
    [sx / sw, sy / sw]
}

/// Small emissive squares on black, seen through a tilted flat port at a general camera pose:
/// the intensity centroid of each square's image against the same centroid computed from its
/// exactly projected outline and exact pixel coverage (no perspective or pixelisation bias; a
/// black background leaves no background gradient to bias the centroid).
#[test]
fn flat_port_target_centroids_match_exact_projection() {
    let port_n = DVec3::new(0.05, -0.03, 1.0).normalize();
    let cam = camera(
        "cam",
        Port::Flat {
            normal: port_n,
            distance: 0.02,
            thickness: 0.012,
            glass: glass(),
            outer_layers: vec![],
        },
    );
    let pose = look(DVec3::new(0.1, -0.2, -5.0), DVec3::new(0.15, 0.1, -1.0));
    let mut m = base(
        "centroids",
        cam,
        Some(water(
            [0.0; 3],
            [0.0; 3],
            Phase::HenyeyGreenstein { g: 0.0 },
        )),
        pose,
    );
    m.needs.medium = false;
    m.render.samples = 32;
    let cam = m.cameras[0].clone();
    let fwd = pose.rotation.z_axis;
    let centre = pose.translation + 3.0 * fwd;
    // Frame facing the camera: x along the camera's x, z towards the camera.
    let facing = DMat3::from_cols(pose.rotation.x_axis, -pose.rotation.y_axis, -fwd);
    let half = 0.05;
    let offsets = [
        (0.0, 0.0),
        (0.8, 0.5),
        (-0.9, 0.4),
        (0.7, -0.55),
        (-0.75, -0.6),
        (0.95, 0.0),
        (0.0, 0.6),
    ];
    let mut squares = Vec::new();
    for (i, (a, b)) in offsets.iter().enumerate() {
        let c = centre + a * facing.x_axis + b * facing.y_axis;
        squares.push(c);
        m.lights.push(Light {
            name: format!("square{i}"),
            mount: Mount::World,
            kind: LightKind::Area {
                frame: Pose {
                    rotation: facing,
                    translation: c,
                },
                width: 2.0 * half,
                height: 2.0 * half,
                radiance: [1.0; 3],
            },
        });
    }
    let (img, dir) = render(&m, "mi-centroids");
    let port = FlatPort {
        n: port_n,
        d: 0.02,
        t: 0.012,
        ng: glass().ior[1],
        nw: m.water.as_ref().unwrap().ior[1],
    };
    let cam_from_world = pose.inverse();
    let project = |p: DVec3| {
        port.air_direction(cam_from_world.transform_point(p))
            .and_then(|d| pixel(&cam, d))
    };
    let mut errs = Vec::new();
    for c in &squares {
        // Outline: 4 edges × 128 points.
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        let mut outline = Vec::new();
        for k in 0..4 {
            let (a0, b0) = corners[k];
            let (a1, b1) = corners[(k + 1) % 4];
            for s in 0..128 {
                let f = s as f64 / 128.0;
                let (a, b) = (a0 + f * (a1 - a0), b0 + f * (b1 - b0));
                outline.push(
                    project(*c + half * (a * facing.x_axis + b * facing.y_axis)).expect("projects"),
                );
            }
        }
        let area_centroid = polygon_centroid(&outline).unwrap();
        let expect = pixelized_centroid(&outline, area_centroid, 10);
        // Intensity centroid (G channel) in a ±10 px window; the background is exactly 0.
        let (px, py) = (expect[0].floor() as i64, expect[1].floor() as i64);
        let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for y in py - 10..=py + 10 {
            for x in px - 10..=px + 10 {
                assert!(
                    x >= 0 && y >= 0 && (x as usize) < img.width && (y as usize) < img.height,
                    "window leaves the image"
                );
                let w = img.rgb[y as usize * img.width + x as usize][1] as f64;
                sw += w;
                sx += w * (x as f64 + 0.5);
                sy += w * (y as f64 + 0.5);
            }
        }
        assert!(
            sw > 1.0,
            "square at {c} not seen (images in {})",
            dir.display()
        );
        let got = [sx / sw, sy / sw];
        errs.push(((got[0] - expect[0]).powi(2) + (got[1] - expect[1]).powi(2)).sqrt());
    }
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    let max = errs.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "flat port centroids: rms {rms:.4} px, max {max:.4} px over {} squares",
        errs.len()
    );
    // Tolerance: at 32 spp the edge pixels of a ≈5 px square carry ≈ 1/√32 coverage noise,
    // which moves a centroid by ≈ 0.01–0.02 px (measured: see README-mitsuba.md); 0.05 px rms /
    // 0.1 px max leaves room for that noise while any convention error (half pixel, flipped
    // axis, wrong principal point, missing or wrong refraction) is ≥ 0.3 px.
    assert!(rms < 0.05, "rms {rms} px; errors {errs:?}");
    assert!(max < 0.1, "max {max} px; errors {errs:?}");
    let _ = std::fs::remove_dir_all(dir);
}

/// A Lambertian plane lit by a point light in absorbing water, seen through a flat port: every
/// pixel of a central window against E = I·cosθ/r²·exp(-σa·r), L = ρE/π, times the path's
/// attenuation exp(-σa·ℓ), the Fresnel transmittances of both port faces and (1/n_w)².
/// Rendered / analytic radiance of a Lambertian patch `h` m below a nadir camera behind a flat
/// port, lit by a point light, in purely absorbing water `sigma_a`: per channel (mean, standard
/// error of the mean) over a 60×40 px window.
fn patch_ratio(name: &str, sigma_a: Rgb, h: f64, samples: u32) -> [(f64, f64); 3] {
    let port_n = DVec3::Z;
    let (d, t) = (0.01, 0.012);
    let cam = camera(
        "cam",
        Port::Flat {
            normal: port_n,
            distance: d,
            thickness: t,
            glass: glass(),
            outer_layers: vec![],
        },
    );
    let pose = nadir(DVec3::new(0.0, 0.0, -5.0));
    let mut m = base(
        "patch",
        cam,
        Some(water(sigma_a, [0.0; 3], Phase::HenyeyGreenstein { g: 0.0 })),
        pose,
    );
    m.render.samples = samples;
    let rho = [0.5, 0.6, 0.7];
    let z_plane = -5.0 - h;
    m.objects.push(plane("patch", z_plane, 10.0, rho));
    let light_pos = DVec3::new(0.2 * h, 0.15 * h, -5.0 - 0.25 * h);
    let intensity = [40.0, 30.0, 20.0];
    m.lights.push(Light {
        name: "strobe".into(),
        mount: Mount::World,
        kind: LightKind::Point {
            position: light_pos,
            intensity,
        },
    });
    let cam = m.cameras[0].clone();
    let (img, dir) = render(&m, name);
    let (ng, nw) = (glass().ior[1], m.water.as_ref().unwrap().ior);
    let mut ratios = [Vec::new(), Vec::new(), Vec::new()];
    for j in 40..80 {
        for i in 55..115 {
            // Trace the pixel-centre ray: air → glass → water → plane z = z_plane.
            let dc = DVec3::new(
                (i as f64 + 0.5 - cam.cx) / cam.fx,
                (j as f64 + 0.5 - cam.cy) / cam.fy,
                1.0,
            )
            .normalize();
            let p1 = dc * (d / dc.z);
            let tg = fresnel_t(1.0, ng, dc.z);
            let dg = refract(dc, port_n, 1.0, ng).unwrap();
            let p2 = p1 + dg * (t / dg.z);
            for c in 0..3 {
                let dw = refract(dg, port_n, ng, nw[c]).unwrap();
                let tw = fresnel_t(ng, nw[c], dg.z);
                let w_p2 = pose.transform_point(p2);
                let w_dir = pose.transform_vector(dw);
                let s = (z_plane - w_p2.z) / w_dir.z;
                let hit = w_p2 + s * w_dir;
                let to_light = light_pos - hit;
                let r = to_light.length();
                let cos_l = to_light.z / r;
                let e = intensity[c] * cos_l / (r * r) * (-sigma_a[c] * r).exp();
                let l_water = rho[c] / std::f64::consts::PI * e * (-sigma_a[c] * s).exp();
                let expected = l_water * tw * tg / (nw[c] * nw[c]);
                let got = img.rgb[j * img.width + i][c] as f64;
                ratios[c].push(got / expected);
            }
        }
    }
    let _ = std::fs::remove_dir_all(dir);
    [0, 1, 2].map(|c| {
        let r = &ratios[c];
        let n = r.len() as f64;
        let mean = r.iter().sum::<f64>() / n;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        (mean, sd / n.sqrt())
    })
}

/// Tolerance of a patch ratio: 4 standard errors of the window mean (measured from the image's
/// own per-pixel scatter; the noise is Mitsuba's delta tracking of the absorbing water) plus
/// 0.3 % for what the analytic value leaves out (inter-reflections inside the glass,
/// R1·R2 ≈ 2e-4, and the pixel-area average of a smooth field taken at the centre).
fn assert_patch(label: &str, r: [(f64, f64); 3]) {
    for (c, (mean, se)) in r.into_iter().enumerate() {
        eprintln!("{label} channel {c}: rendered/analytic = {mean:.5} ± {se:.5}");
        let tol = 4.0 * se + 0.003;
        assert!(
            (mean - 1.0).abs() < tol,
            "{label} channel {c}: ratio {mean} ± {se} (tolerance {tol})"
        );
    }
}

#[test]
fn lambertian_patch_radiance_matches_beer_lambert_inverse_square() {
    assert_patch("patch", patch_ratio("mi-patch", [0.4, 0.1, 0.05], 2.0, 32));
}

/// Every Jerlov water type loads and renders, turbid coastal water included (σt > 1/m needs
/// an unbounded coefficient: a bare `<rgb>` is a [0, 1] reflectance in Mitsuba), and a water
/// as attenuating as each type (σa = its σt, no scattering, so the value is analytic) gives
/// the Beer–Lambert radiance. The patch distance is scaled so that σt·h ≤ 1.2: farther, the
/// free-flight sampling of Mitsuba's volpath leaves too few paths for a 32-spp check.
#[test]
fn every_jerlov_water_renders_with_beer_lambert_attenuation() {
    for ty in poser::optics::water::JERLOV_TYPES {
        let (a, b) = poser::optics::water::jerlov(ty).unwrap();
        let st = [0, 1, 2].map(|c| a[c] + b[c]);
        // The real water (absorbing and scattering, Fournier–Forand-free HG): it loads and
        // renders a finite, non-black image.
        let mut w = water(a, b, Phase::HenyeyGreenstein { g: 0.9 });
        w.jerlov = Some(ty.to_string());
        let mut m = base(
            "jerlov",
            camera("cam", flat_port(0.01)),
            Some(w),
            nadir(DVec3::new(0.0, 0.0, -5.0)),
        );
        m.render.samples = 4;
        m.objects.push(plane("seabed", -5.5, 10.0, [0.5; 3]));
        m.lights
            .push(support::model::rig_spot(DVec3::new(0.2, 0.0, 0.0), 50.0));
        let (img, dir) = render(&m, "mi-jerlov");
        let mean: f64 = img.rgb.iter().map(|p| p[1] as f64).sum::<f64>() / img.rgb.len() as f64;
        assert!(
            img.rgb.iter().all(|p| p.iter().all(|v| v.is_finite())) && mean > 0.0,
            "Jerlov {ty}: mean green {mean}"
        );
        let _ = std::fs::remove_dir_all(dir);
        // The attenuation, against Beer–Lambert.
        let smax = st.iter().cloned().fold(0.0, f64::max);
        let h = (1.2 / smax).min(2.0);
        assert_patch(
            &format!("Jerlov {ty} (σt {st:?}, h {h:.3} m)"),
            patch_ratio("mi-jerlov-patch", st, h, 32),
        );
    }
}

/// The flat port's housing is closed: with a black seabed, purely absorbing water and an
/// ambient light, the only light that can reach the camera is what the glass reflects back
/// into the housing, and the housing walls must absorb it. Without the walls those rays
/// escaped to the ambient light: 0.00091 (centre) to 0.0084 (corner) of the ambient radiance
/// 0.02 on calibration_flat; here ≈ 4.5 % of the ambient radiance.
#[test]
fn flat_port_housing_lets_no_ambient_light_in() {
    let mut m = base(
        "veil",
        camera("cam", flat_port(0.025)),
        Some(water(
            [0.35, 0.07, 0.03],
            [0.0; 3],
            Phase::HenyeyGreenstein { g: 0.0 },
        )),
        nadir(DVec3::new(0.0, 0.0, -2.0)),
    );
    m.render.samples = 16;
    m.objects.push(plane("seabed", -3.0, 40.0, [0.0; 3]));
    m.lights.push(support::model::ambient(1.0));
    let (img, dir) = render(&m, "mi-veil");
    let n = img.rgb.len() as f64;
    let mean = [0, 1, 2].map(|c| img.rgb.iter().map(|p| p[c] as f64).sum::<f64>() / n);
    let max = img
        .rgb
        .iter()
        .flat_map(|p| p.iter().map(|&v| v as f64))
        .fold(0.0, f64::max);
    eprintln!("veil: mean {mean:?}, max {max} (ambient radiance 1)");
    // Nothing but the veil can be non-zero: a black seabed, no scattering; the sea's sides
    // are ≥ 1000 m of water away. 1e-6 allows float noise only.
    assert!(
        max < 1e-6,
        "light leaks into the housing: mean {mean:?}, max {max}; images in {}",
        dir.display()
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// An area light neither blocks nor reflects light (native and Blender lights do neither):
/// a panel facing down 1 m above a Lambertian floor, a point light above the panel. The
/// camera above sees the floor through the panel's back, lit by the panel and by the point
/// light as if the panel were not there; the radiance matches the analytic value (point:
/// I·cos/r²; panel: L·∫cos·cos/r² dA, 60×60 quadrature) within the image's noise. With a
/// default (diffuse, opaque) BSDF the camera saw the panel's unlit back (0.0) there.
#[test]
fn area_light_casts_no_shadow_and_keeps_its_radiometry() {
    let mut m = base("panel", camera("cam", Port::None), None, nadir(DVec3::ZERO));
    m.render.samples = 64;
    let rho = [0.5, 0.5, 0.5];
    m.objects.push(plane("floor", -2.0, 20.0, rho));
    let (lp, li) = (DVec3::new(0.0, 0.0, -0.2), [1.0, 1.0, 1.0]);
    m.lights.push(Light {
        name: "lamp".into(),
        mount: Mount::World,
        kind: LightKind::Point {
            position: lp,
            intensity: li,
        },
    });
    let (half, lrad) = (0.3, [2.0, 1.5, 1.0]);
    m.lights.push(Light {
        name: "panel".into(),
        mount: Mount::World,
        kind: LightKind::Area {
            frame: Pose {
                rotation: DMat3::from_rotation_x(std::f64::consts::PI),
                translation: DVec3::new(0.0, 0.0, -1.0),
            },
            width: 2.0 * half,
            height: 2.0 * half,
            radiance: lrad,
        },
    });
    let cam = m.cameras[0].clone();
    let pose = m.poses[0].world_from_rig;
    let (img, dir) = render(&m, "mi-panel");
    let k = 60;
    let da = (2.0 * half / k as f64).powi(2);
    let mut ratios = [Vec::new(), Vec::new(), Vec::new()];
    for j in (30..90).step_by(3) {
        for i in (40..120).step_by(3) {
            let dc = DVec3::new(
                (i as f64 + 0.5 - cam.cx) / cam.fx,
                (j as f64 + 0.5 - cam.cy) / cam.fy,
                1.0,
            );
            let w = pose.transform_vector(dc);
            let hit = pose.translation + w * ((-2.0 - pose.translation.z) / w.z);
            let v = lp - hit;
            let e_point = v.z / v.length().powi(3);
            let mut g = 0.0;
            for a in 0..k {
                for b in 0..k {
                    let q = DVec3::new(
                        -half + (a as f64 + 0.5) * 2.0 * half / k as f64,
                        -half + (b as f64 + 0.5) * 2.0 * half / k as f64,
                        -1.0,
                    );
                    let u = q - hit;
                    g += u.z * u.z / u.length_squared().powi(2) * da;
                }
            }
            for c in 0..3 {
                let expected = rho[c] / std::f64::consts::PI * (li[c] * e_point + lrad[c] * g);
                ratios[c].push(img.rgb[j * img.width + i][c] as f64 / expected);
            }
        }
    }
    for (c, r) in ratios.iter().enumerate() {
        let n = r.len() as f64;
        let mean = r.iter().sum::<f64>() / n;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let (lo, hi) = r
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        eprintln!(
            "panel channel {c}: rendered/analytic = {mean:.5} ± {:.5}, min {lo:.3}, max {hi:.3}",
            sd / n.sqrt()
        );
        // Mean: 4 standard errors + 1 % (the pixel-area average of a field with the panel's
        // edge in it, taken at the pixel centre). Every pixel within 6 sd: a shadow or an
        // opaque panel shows as a block of outliers.
        assert!(
            (mean - 1.0).abs() < 4.0 * sd / n.sqrt() + 0.01,
            "channel {c}: ratio {mean}; images in {}",
            dir.display()
        );
        assert!(
            lo > 1.0 - 6.0 * sd.max(0.02),
            "channel {c}: a pixel at {lo} of the analytic value; images in {}",
            dir.display()
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// An installed binary (here: a copy outside the source tree, run from another directory)
/// renders with Mitsuba: the driver is embedded in the binary and written beside the compiled
/// scene, so nothing is read from the build tree's `backends/`.
#[test]
fn a_copied_binary_renders_with_mitsuba() {
    require_mitsuba();
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("poser");
    std::fs::copy(env!("CARGO_BIN_EXE_poser"), &bin).unwrap();
    let canon = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/canonical");
    for f in ["pinhole_air.toml", "common.toml"] {
        std::fs::copy(canon.join(f), tmp.path().join(f)).unwrap();
    }
    let python = poser::backend::python::interpreter();
    let run = || {
        std::process::Command::new(&bin)
            .current_dir(tmp.path())
            .env("POSER_PYTHON", &python)
            .env_remove("PYTHONPATH")
            .args([
                "render",
                "pinhole_air.toml",
                "--backend",
                "mitsuba",
                "-o",
                "out",
            ])
            .args(["--scale", "0.1", "--samples", "2", "--quiet"])
            .output()
    };
    // The copy's write handle can live on for a moment in a child that another test thread
    // forked meanwhile (until that child execs): "text file busy" (ETXTBSY, 26). Wait it out.
    let mut tries = 0;
    let out = loop {
        match run() {
            Err(e) if e.raw_os_error() == Some(26) && tries < 50 => {
                tries += 1;
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            r => break r.unwrap(),
        }
    };
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let out_dir = tmp.path().join("out");
    let driver =
        std::fs::read_to_string(out_dir.join("mitsuba").join(mitsuba::DRIVER_FILE)).unwrap();
    assert_eq!(driver, mitsuba::DRIVER_SOURCE);
    let exrs: Vec<_> = std::fs::read_dir(&out_dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "exr"))
        .collect();
    assert!(!exrs.is_empty(), "no image written: {err}");
}

/// A checkerboard target seen from above in air under ambient light: the printed pattern is
/// neither mirrored nor flipped (cell (0, 0) at the target's (-x, -y) corner is black, its
/// neighbours along x and y are white), and black/white levels are linear reflectances.
#[test]
fn target_texture_orientation_and_levels() {
    let mut m = base(
        "orient",
        camera("cam", Port::None),
        None,
        nadir(DVec3::new(0.0, 0.0, 1.0)),
    );
    m.render.samples = 8;
    m.lights.push(Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient { radiance: [1.0; 3] },
    });
    let kind = TargetKind::Checkerboard {
        cols: 4,
        rows: 3,
        square: 0.1,
    };
    m.targets.push(Target {
        name: "board".into(),
        kind,
        pose: Pose::IDENTITY,
        points: vec![],
    });
    let mut cam = m.cameras[0].clone();
    cam.rig_from_camera = Pose::IDENTITY;
    let (img, dir) = render(&m, "mi-orient");
    let cam_from_world = m.poses[0].world_from_rig.inverse();
    let at = |x: f64, y: f64| {
        // Mean over a 7×7 window (the cells are ≈ 14 px wide).
        let p = pixel(&cam, cam_from_world.transform_point(DVec3::new(x, y, 0.0))).unwrap();
        let mut s = 0.0;
        for dy in -3..=3i64 {
            for dx in -3..=3i64 {
                let (i, j) = ((p[0] as i64 + dx) as usize, (p[1] as i64 + dy) as usize);
                s += img.rgb[j * img.width + i][1] as f64;
            }
        }
        s / 49.0
    };
    // Pattern 0.4 × 0.3 m centred: cell (i, j) centre at (-0.15 + 0.1 i, -0.1 + 0.1 j).
    let (black, white) = (at(-0.15, -0.1), at(-0.05, -0.1));
    let up = at(-0.15, 0.0);
    eprintln!("cell (0,0) {black:.4}, (1,0) {white:.4}, (0,1) {up:.4}");
    // Ambient radiance 1 on a Lambertian print: L = ρ (the PNG stores ρ·255, so ±0.2 %
    // quantisation). The 7×7-window mean of 16 spp carries ≈ 1 % MIS noise (measured per-pixel
    // sd ≈ 8 % at 8 spp); 5 % still separates black (0.05) from white (0.9) by far, which is
    // what this test is about.
    assert!(
        (black - poser::geometry::targets::BLACK).abs() < 0.05 * poser::geometry::targets::WHITE,
        "cell (0,0) = {black}; {}",
        dir.display()
    );
    assert!(
        (white / poser::geometry::targets::WHITE - 1.0).abs() < 0.05,
        "cell (1,0) = {white}"
    );
    assert!(
        (up / poser::geometry::targets::WHITE - 1.0).abs() < 0.05,
        "cell (0,1) = {up}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// A Siemens star (a texture: its sectors are not simple geometry) under ambient light: the
/// printed sectors are neither mirrored nor flipped (sector 0, counter-clockwise from +x, is
/// black; the sector just clockwise of +x is white).
#[test]
fn textured_target_is_not_mirrored() {
    let mut m = base(
        "star",
        camera("cam", Port::None),
        None,
        nadir(DVec3::new(0.0, 0.0, 1.0)),
    );
    m.render.samples = 16;
    m.lights.push(Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient { radiance: [1.0; 3] },
    });
    let kind = TargetKind::SiemensStar {
        diameter: 0.6,
        spokes: 4,
    };
    m.targets.push(Target {
        name: "star".into(),
        kind,
        pose: Pose::IDENTITY,
        points: vec![],
    });
    let cam = m.cameras[0].clone();
    let (img, dir) = render(&m, "mi-star");
    let cam_from_world = m.poses[0].world_from_rig.inverse();
    let at = |a: f64| {
        let (x, y) = (0.2 * a.cos(), 0.2 * a.sin());
        let p = pixel(&cam, cam_from_world.transform_point(DVec3::new(x, y, 0.0))).unwrap();
        let mut s = 0.0;
        for dy in -1..=1i64 {
            for dx in -1..=1i64 {
                let (i, j) = ((p[0] as i64 + dx) as usize, (p[1] as i64 + dy) as usize);
                s += img.rgb[j * img.width + i][1] as f64;
            }
        }
        s / 9.0
    };
    // Sectors are π/4 wide: probe their middles, ±π/8 from +x.
    let (ccw, cw) = (
        at(std::f64::consts::PI / 8.0),
        at(-std::f64::consts::PI / 8.0),
    );
    eprintln!("star: sector 0 {ccw:.3}, sector 7 {cw:.3}");
    // Black 0.05 vs white 0.9: a 3×3 mean at 16 spp is within ±0.1 of either.
    assert!(
        ccw < 0.2 && cw > 0.7,
        "sector 0 = {ccw}, sector 7 = {cw} (mirrored?); {}",
        dir.display()
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `render.outputs = ["rgb", "depth"]`: Mitsuba writes `{image}.depth.exr` with the native
/// backend's definition (camera-frame z of the first surface through each pixel centre,
/// traced through the flat port; 0 where nothing is hit). A seabed and a sphere seen through a
/// tilted flat port in water: the two depth images agree to float32 precision.
#[test]
fn depth_output_matches_native_through_a_flat_port() {
    require_mitsuba();
    let port = Port::Flat {
        normal: DVec3::new(0.08, -0.05, 1.0).normalize(),
        distance: 0.02,
        thickness: 0.012,
        glass: glass(),
        outer_layers: vec![],
    };
    let mut m = base(
        "depth",
        camera("cam", port),
        Some(water(
            [0.2, 0.1, 0.05],
            [0.0; 3],
            Phase::HenyeyGreenstein { g: 0.0 },
        )),
        look(DVec3::new(0.0, 0.0, -5.0), DVec3::new(0.3, 0.2, -1.0)),
    );
    m.render.samples = 1;
    m.render.outputs = vec!["rgb".into(), "depth".into()];
    m.objects.push(plane("seabed", -7.0, 20.0, [0.5; 3]));
    let mut ball = plane("ball", 0.0, 1.0, [0.5; 3]);
    ball.shape = Shape::Sphere { radius: 0.4 };
    ball.pose.translation = DVec3::new(0.5, 0.3, -6.4);
    m.objects.push(ball);
    m.lights.push(support::model::ambient(1.0));
    let (_, mdir) = render(&m, "mi-depth");
    let ndir = tempfile::tempdir().unwrap();
    poser::backend::native::render(&m, ndir.path(), &RenderOptions::default()).unwrap();
    let name = m.image_name(0, 0);
    let zm = LinearImage::read(&mdir.join(format!("{name}.depth.exr"))).unwrap();
    let zn = LinearImage::read(&ndir.path().join(format!("{name}.depth.exr"))).unwrap();
    assert_eq!((zm.width, zm.height), (zn.width, zn.height));
    for (i, j) in [(0, 0), (159, 0), (0, 119), (159, 119), (80, 60)] {
        eprintln!(
            "depth at ({i}, {j}): mitsuba {:.5}, native {:.5}",
            zm.rgb[j * zm.width + i][0],
            zn.rgb[j * zn.width + i][0]
        );
    }
    let (mut coverage, mut zmin, mut zmax) = (0, f64::MAX, 0.0f64);
    let mut rel = Vec::new();
    for (a, b) in zm.rgb.iter().zip(&zn.rgb) {
        let (a, b) = (a[0] as f64, b[0] as f64);
        if (a > 0.0) != (b > 0.0) {
            coverage += 1;
        } else if a > 0.0 {
            rel.push((a - b).abs() / b);
            zmin = zmin.min(b);
            zmax = zmax.max(b);
        }
    }
    rel.sort_by(f64::total_cmp);
    let q = |f: f64| rel[((rel.len() - 1) as f64 * f) as usize];
    let edge = rel.iter().filter(|&&r| r > 1e-2).count();
    eprintln!(
        "depth: {} px hit in both (z {zmin:.3}…{zmax:.3} m); |Δz|/z median {:.2e}, 99 % {:.2e}; \
         {edge} px differ by > 1 % (silhouette), {coverage} px hit in one only",
        rel.len(),
        q(0.5),
        q(0.99)
    );
    assert!(
        rel.len() > zm.rgb.len() / 2 && zmax - zmin > 0.5,
        "the scene is not in view"
    );
    // Measured: median 5.4e-5 (the seabed: a ~0.025 px difference of ray position between the
    // two cameras on a depth gradient of 4 mm/px, float32 in Mitsuba), 99 % 4.2e-3 (the
    // sphere is analytic in Mitsuba, a UV-sphere mesh in native), 53 px (0.28 %) differ by
    // more than 1 %: pixel centres near the sphere's silhouette. Bounds: about twice these.
    assert!(
        q(0.5) < 1e-4,
        "median relative depth difference {}; in {}",
        q(0.5),
        mdir.display()
    );
    assert!(
        q(0.99) < 1e-2,
        "99 % relative depth difference {}; in {}",
        q(0.99),
        mdir.display()
    );
    assert!(
        edge + coverage <= zm.rgb.len() / 200,
        "{edge} + {coverage} pixels differ in what they hit; in {}",
        mdir.display()
    );
    let _ = std::fs::remove_dir_all(mdir);
}
