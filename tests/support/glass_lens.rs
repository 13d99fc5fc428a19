//! The glass-lens scenes (a glass ball or rod imaging an emitting square) and their exact
//! images, traced with every Fresnel branch: the reference the glass-sphere and glass-cylinder
//! tests hold each back end to.

use glam::DVec3;
use poser::model::Model;
use poser::optics::interface::{fresnel_transmittance, refract};

/// The glass solid between the camera and the square, centred at (0, 0, −1), radius 0.1 m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lens {
    /// A sphere.
    Ball,
    /// A cylinder 0.3 m long, its axis along x.
    Rod,
}

const CENTRE: DVec3 = DVec3::new(0.0, 0.0, -1.0);
const RADIUS: f64 = 0.1;
/// The rod's half-length, m.
const ROD_HALF: f64 = 0.15;
/// Centre and half side of the emitting square on the plane z = −2 (facing +z), m.
const SQUARE: (f64, f64, f64) = (0.1, 0.05, 0.05);

/// A camera in air 2 m above a 10 cm emitting square (radiance 1) at (0.1, 0.05, −2), seen
/// only through a 20 cm N-BK7 ball or rod 1 m down (a ball lens of 15 cm focal length: the
/// square shows as a small inverted image; a rod inverts it across its axis only), 200 × 150
/// px, 256 spp.
pub fn scene(lens: Lens) -> Model {
    let solid = match lens {
        Lens::Ball => "name = \"ball\"\nshape = \"sphere\"\nradius = \"0.1 m\"\n",
        Lens::Rod => {
            "name = \"rod\"\nshape = \"cylinder\"\nradius = \"0.1 m\"\nheight = \"0.3 m\"\n\
             rotation = [0.0, 1.5707963267948966, 0.0]\n"
        }
    };
    super::column::load_text(
        &format!(
            "name = \"glass lens\"\n[camera]\nwidth = 200\nheight = 150\n\
             sensor_width = \"36 mm\"\nfocal_length = \"50 mm\"\n\
             [[lights]]\nname = \"panel\"\ntype = \"area\"\nmount = \"world\"\n\
             position = [0.1, 0.05, -2.0]\naim = [0.0, 0.0, 1.0]\nwidth = 0.1\nheight = 0.1\n\
             radiance = 1.0\n\
             [[objects]]\n{solid}position = [0.0, 0.0, -1.0]\nglass = \"N-BK7\"\n\
             [network]\ntype = \"explicit\"\n[[network.poses]]\nposition = [0.0, 0.0, 0.0]\n\
             look_at = [0.0, 0.0, -2.0]\nup = [0.0, 1.0, 0.0]\n[render]\nsamples = 256\n\
             seed = 1\nbounces = 16\n"
        ),
        &[],
    )
}

/// The first hit of `o + t d` (t > 1e-9) on the lens: distance and outward unit normal.
fn hit(lens: Lens, o: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
    let first =
        |ts: [f64; 2], ok: &dyn Fn(f64) -> bool| ts.into_iter().find(|&t| t > 1e-9 && ok(t));
    let quadratic = |a: f64, b: f64, c: f64| {
        let disc = b * b - a * c;
        (disc >= 0.0 && a > 0.0).then(|| [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a])
    };
    let oc = o - CENTRE;
    match lens {
        Lens::Ball => {
            let t = first(
                quadratic(1.0, oc.dot(d), oc.length_squared() - RADIUS * RADIUS)?,
                &|_| true,
            )?;
            Some((t, (o + d * t - CENTRE) / RADIUS))
        }
        Lens::Rod => {
            // Axis along x: the side y² + z² = r², |x| ≤ half; the caps x = ±half.
            let side = quadratic(
                d.y * d.y + d.z * d.z,
                oc.y * d.y + oc.z * d.z,
                oc.y * oc.y + oc.z * oc.z - RADIUS * RADIUS,
            )
            .and_then(|ts| first(ts, &|t| (oc.x + t * d.x).abs() <= ROD_HALF))
            .map(|t| {
                let p = oc + d * t;
                (t, DVec3::new(0.0, p.y, p.z) / RADIUS)
            });
            let caps = [-1.0, 1.0].into_iter().filter_map(|s: f64| {
                let t = (s * ROD_HALF - oc.x) / d.x;
                let p = oc + d * t;
                (t > 1e-9 && p.y * p.y + p.z * p.z <= RADIUS * RADIUS)
                    .then_some((t, DVec3::new(s, 0.0, 0.0)))
            });
            side.into_iter()
                .chain(caps)
                .min_by(|a, b| a.0.total_cmp(&b.0))
        }
    }
}

/// Radiance along `o + t d` (unit `d`) in the `lens` scene by exact optics and every
/// Fresnel branch (reflected and refracted, weighted by the reflectance) down to `depth`
/// faces: independent of any renderer's Monte Carlo choice between them.
pub fn radiance(lens: Lens, o: DVec3, d: DVec3, inside: bool, n: f64, depth: u32) -> f64 {
    let Some((t, out)) = hit(lens, o, d) else {
        // Out of the ball: the square's front face, or nothing.
        if inside || d.z >= 0.0 {
            return 0.0;
        }
        let p = o + d * ((-2.0 - o.z) / d.z);
        let (x, y, half) = SQUARE;
        return f64::from(u8::from((p.x - x).abs() < half && (p.y - y).abs() < half));
    };
    if depth == 0 {
        return 0.0;
    }
    let p = o + d * t;
    let nf = if out.dot(d) < 0.0 { out } else { -out };
    let (n1, n2) = if inside { (n, 1.0) } else { (1.0, n) };
    let cos_i = -nf.dot(d);
    let reflect = (d + 2.0 * cos_i * nf).normalize();
    let (tr, through) = match refract(d, -nf, n1 / n2) {
        Some((t, cos_t)) => (fresnel_transmittance(n1, n2, cos_i, cos_t), t.normalize()),
        None => (0.0, d),
    };
    let mut l = (1.0 - tr) * radiance(lens, p + nf * 1e-9, reflect, inside, n, depth - 1);
    if tr > 0.0 {
        l += tr * radiance(lens, p - nf * 1e-9, through, !inside, n, depth - 1);
    }
    l
}

/// The exact G-channel image of `m` (the `lens` scene, camera 0 at pose 0): 16 × 16 rays per
/// pixel (a box filter), 8 faces deep, row-major.
pub fn exact_image(lens: Lens, m: &Model) -> Vec<f64> {
    let n = m.objects[0].material.glass.as_ref().unwrap().ior[1];
    let cam = &m.cameras[0];
    let camera_lens = poser::optics::lens::Lens::from_camera(cam);
    let pose = m.world_from_camera(0, 0);
    let k = 16;
    let mut out = Vec::with_capacity((cam.width * cam.height) as usize);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let mut l = 0.0;
            for j in 0..k {
                for i in 0..k {
                    let u = x as f64 + (i as f64 + 0.5) / k as f64;
                    let v = y as f64 + (j as f64 + 0.5) / k as f64;
                    let d = pose.rotation * camera_lens.unproject(u, v).unwrap();
                    l += radiance(lens, pose.translation, d.normalize(), false, n, 8);
                }
            }
            out.push(l / (k * k) as f64);
        }
    }
    out
}

/// The sum of an image's values (px × radiance) and their weighted centroid, px (pixel
/// centres at +0.5).
pub fn flux_centroid(values: &[f64], width: usize) -> (f64, [f64; 2]) {
    let (mut s, mut su, mut sv) = (0.0, 0.0, 0.0);
    for (i, &v) in values.iter().enumerate() {
        s += v;
        su += v * ((i % width) as f64 + 0.5);
        sv += v * ((i / width) as f64 + 0.5);
    }
    (s, [su / s, sv / s])
}
