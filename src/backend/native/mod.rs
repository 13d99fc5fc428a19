//! The native renderer: poser's own CPU path tracer (default backend, no Python).
//!
//! `render(model, out, opts)` renders every selected rig pose with every camera and writes, per
//! image (names from [`Model::image_name`]):
//!
//! | file | content |
//! |---|---|
//! | `OUT/<image>.exr` | linear RGB radiance (float32), Mitsuba's radiometric conventions |
//! | `OUT/<image>.png` | sRGB preview of `render.exposure × radiance` |
//! | `OUT/<image>.variance.exr` | variance of each pixel's Monte Carlo mean per channel (render noise, [`Image::variance`]); when the scene has a `[sensor]` |
//! | `OUT/<image>.denoised.exr`, `OUT/<image>.denoised.variance.exr` | with `render.denoise = "illumination"`: the render and its variance through [`denoise::illumination`] (the PNG preview is made from it) |
//! | `OUT/<image>.noise.json` | with a noise target (`render.noise`): the samples each pixel took and the noise it achieved ([`adaptive::Report`]) |
//! | `OUT/<image>.depth.exr` | camera-frame z of the first surface hit through each pixel centre, m (0: none); when `render.outputs` has `"depth"` |
//! | `OUT/render-manifest.json` | the finished images and the SHA-256 of their files, for `--resume` ([`resume`]) |
//!
//! Parallel over image rows with rayon; every pixel sample has its own counter-based random
//! stream ([`sampler::Sampler`]), so the bytes do not depend on the number of threads. With
//! `needs.per_channel_passes`, each channel is rendered with its own camera rays (dispersion).

pub mod adaptive;
pub mod camera;
pub mod caustics;
pub mod denoise;
pub mod footprint;
pub mod integrator;
pub mod lights;
pub mod medium;
pub mod resume;
pub mod sampler;
pub mod scene;

use crate::backend::{RenderOptions, RenderReport};
use crate::model::Model;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use sampler::Sampler;
use std::path::Path;
use std::time::Instant;

/// One rendered image: linear RGB radiance (row-major, row 0 at the top) and depth.
#[derive(Debug, Clone)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
    /// Variance of each pixel's Monte Carlo mean per channel (the sample variance of its
    /// samples / their number; 0 with one sample): the render noise the sensor stage reports.
    pub variance: Vec<[f32; 3]>,
    /// Mean albedo of the first surface hit by each pixel's samples (0 where they see only
    /// water); filled when the denoiser needs it, else empty.
    pub albedo: Vec<[f32; 3]>,
    /// With a noise target (`render.noise`): the samples taken and the noise achieved.
    pub noise: Option<adaptive::Report>,
}

/// At least one sample per pixel: 0 is an error, never one sample in silence (a scene's
/// `samples = 0` is E0220 and the command line refuses `--samples 0`; this guards the library,
/// the Python module's `Scene.render(samples=0)` included).
fn checked_samples(samples: u32) -> Result<u32, String> {
    if samples == 0 {
        return Err("0 samples per pixel: at least one is needed (e.g. samples = 16)".into());
    }
    Ok(samples)
}

/// Render one image in memory (rig pose `pose`, camera `cam`; `samples` per pixel, else the
/// scene's): the linear radiance `poser render` writes as `<image>.exr`, before any
/// denoising. What the Python module's `Scene.render` returns.
pub fn render_one(
    model: &Model,
    pose: usize,
    cam: usize,
    samples: Option<u32>,
) -> Result<Image, String> {
    if pose >= model.poses.len() {
        return Err(format!(
            "pose {pose} is out of range (the network has {} poses)",
            model.poses.len()
        ));
    }
    if cam >= model.cameras.len() {
        return Err(format!(
            "camera index {cam} is out of range (the rig has {} cameras)",
            model.cameras.len()
        ));
    }
    // The entry point of the Python module, which reaches the renderer without `Backend`:
    // the same validation first.
    model.validate().map_err(|e| e.to_string())?;
    let samples = checked_samples(samples.unwrap_or(model.render.samples))?;
    let scene = scene::Scene::build(model)?;
    render_image(model, &scene, pose, cam, samples, None)
}

/// Render one image (rig pose `pose`, camera `cam`) with `samples` per pixel.
pub fn render_image(
    model: &Model,
    scene: &scene::Scene,
    pose: usize,
    cam: usize,
    samples: u32,
    progress: Option<&Progress>,
) -> Result<Image, String> {
    let camera = &model.cameras[cam];
    // A crop renders its rectangle alone, each pixel with the whole image's random numbers.
    let (x0, y0, w, h) = crate::model::Crop::region(model.render.crop, camera);
    let world_from_rig = &model.poses[pose].world_from_rig;
    let cam_pos = model.world_from_camera(pose, cam).translation;
    let medium = medium::Medium::new(model, cam_pos);
    let lights = lights::Lights::at_pose(model, world_from_rig);
    let passes: Vec<usize> = if model.needs.per_channel_passes {
        vec![0, 1, 2]
    } else {
        vec![1]
    };
    let rays: Vec<camera::CameraRays> = passes
        .iter()
        .map(|&c| camera::CameraRays::new(model, pose, cam, c))
        .collect::<Result<_, _>>()?;
    let px = Pixels {
        model,
        scene,
        integ: integrator::Integrator::new(scene, model, medium, lights),
        rays,
        passes,
        image_id: (pose * model.cameras.len() + cam) as u64,
        full_width: camera.width,
        origin: (x0, y0),
        width: w,
        want_albedo: model.render.denoise_radius.is_some(),
    };
    let spp = samples.max(1);
    let cam_from_world = model.world_from_camera(pose, cam).inverse();
    let target = model
        .render
        .noise
        .map(|t| (t.relative, t.max_samples_for(spp)));
    // With a noise target: every pixel's pilot, then how many fresh samples each one takes.
    let mut measure = adaptive::Measure::Relative;
    let counts: Vec<[u32; 3]> = match target {
        None => Vec::new(),
        Some((relative, max)) => {
            let pilot = px.pilot(h, spp);
            if model.render.noise.is_some_and(|t| t.against_sensor) {
                measure = sensor_measure(model, camera, w, h, &pilot)?;
            }
            let npass = px.rays.len();
            let rv: Vec<[f64; 3]> = pilot
                .iter()
                .map(|&(m, v)| {
                    let mut out = [0.0; 3];
                    for (k, o) in out.iter_mut().enumerate().take(npass) {
                        *o = measure.squared(m, v, px.channel_of(k));
                    }
                    out
                })
                .collect();
            adaptive::plan(w as usize, h as usize, &rv, spp, relative, max)
        }
    };
    let rows: Vec<PixelRow> = (0..h)
        .into_par_iter()
        .map(|j| {
            let row = px.row(j, spp, &counts, target.is_some(), &measure, &cam_from_world);
            if let Some(pb) = progress {
                pb.inc(1);
            }
            row
        })
        .collect();
    let mut rgb = Vec::with_capacity((w * h) as usize);
    let mut depth = Vec::with_capacity((w * h) as usize);
    let mut variance = Vec::with_capacity((w * h) as usize);
    let mut albedo = Vec::new();
    let mut per_pixel = Vec::new();
    for (r, d, v, a, n) in rows {
        albedo.extend(a);
        per_pixel.extend(n);
        rgb.extend(r);
        depth.extend(d);
        variance.extend(v);
    }
    Ok(Image {
        width: w,
        height: h,
        rgb,
        depth,
        variance,
        albedo,
        noise: target
            .map(|(relative, max)| adaptive::Report::new(relative, spp, max, &measure, &per_pixel)),
    })
}

/// One row of an image: radiance, depth, variance of the mean, first-hit albedo (when
/// denoising) and, with a noise target, each pixel's (samples, relative noise).
type PixelRow = (
    Vec<[f32; 3]>,
    Vec<f32>,
    Vec<[f32; 3]>,
    Vec<[f32; 3]>,
    Vec<(u32, f32)>,
);

/// The noise measure of `render.noise = "sensor"`: the pilot image exposed by the scene's
/// sensor gives the electrons per unit of radiance.
fn sensor_measure(
    model: &Model,
    camera: &crate::model::Camera,
    w: u32,
    h: u32,
    pilot: &[(DVec3, DVec3)],
) -> Result<adaptive::Measure, String> {
    let sensor = model.sensor.as_ref().ok_or_else(|| {
        "render.noise = \"sensor\" needs a sensor: add a [sensor] table or pass --sensor"
            .to_string()
    })?;
    let linear = crate::sensor::Linear {
        width: w,
        height: h,
        rgb: pilot
            .iter()
            .map(|(m, _)| [m.x as f32, m.y as f32, m.z as f32])
            .collect(),
    };
    // The camera's own pitch: a crop's pixels are the whole image's.
    let pitch = camera.pixel_pitch;
    let e = crate::sensor::expose(sensor, &linear, pitch);
    Ok(adaptive::Measure::Sensor {
        electrons_per_radiance: e.electrons_per_radiance,
        read_noise: sensor.read_noise,
        full_well: sensor.full_well,
    })
}

/// What sampling one image's pixels needs: the rays of each pass (one, or one per channel),
/// the integrator, and the image's place in the random streams.
struct Pixels<'a> {
    model: &'a Model,
    scene: &'a scene::Scene,
    integ: integrator::Integrator<'a>,
    rays: Vec<camera::CameraRays>,
    /// The channel of each pass's indices.
    passes: Vec<usize>,
    image_id: u64,
    /// The whole image's width (a pixel's place in the random streams).
    full_width: u32,
    /// The rendered rectangle's top-left pixel in the whole image, and its width.
    origin: (u32, u32),
    width: u32,
    want_albedo: bool,
}

impl Pixels<'_> {
    /// The channel pass `k` stands for (`None`: a single RGB pass).
    fn channel_of(&self, k: usize) -> Option<usize> {
        (self.passes.len() > 1).then_some(self.passes[k])
    }

    /// `n` samples of pixel (i, j) of the rendered rectangle, pass `k`, from stream index
    /// `from` on: their mean and the variance of that mean; the first-hit albedo is added to
    /// `alb`.
    fn run(&self, i: u32, j: u32, k: usize, from: u32, n: u32, alb: &mut DVec3) -> (DVec3, DVec3) {
        let (model, scene, integ) = (self.model, self.scene, &self.integ);
        let (seed, kind) = (model.render.seed, model.render.sampler);
        let r = &self.rays[k];
        // The pixel in the whole image.
        let (i, j) = (i + self.origin.0, j + self.origin.1);
        let spread = footprint::PixelSpread::of(model, scene, r, i, j);
        let pixel = j as u64 * self.full_width as u64 + i as u64;
        let (mut acc, mut acc2) = (DVec3::ZERO, DVec3::ZERO);
        for s in from as u64..(from + n) as u64 {
            let mut rng = Sampler::for_sample(kind, seed, self.image_id, k, pixel, from, s);
            let (du, dv) = rng.next2();
            if let Some((o, d, wgt)) = r.ray(i as f64 + du, j as f64 + dv) {
                if self.want_albedo && k == 0 {
                    let ray = scene::Ray { origin: o, dir: d };
                    if let Some(hit) = scene.intersect(&ray, f64::INFINITY) {
                        *alb += integ.albedo(&hit);
                    }
                }
                let v = integ.li_spread(o, d, spread.map(|s| s.shifted(du, dv)), &mut rng) * wgt;
                if v.is_finite() {
                    acc += v;
                    acc2 += v * v;
                }
            }
        }
        let nf = n as f64;
        acc /= nf;
        // Unbiased sample variance of the samples, over n: that of their mean.
        let v_mean = if n > 1 {
            ((acc2 / nf - acc * acc) * (nf / (nf - 1.0)) / nf).max(DVec3::ZERO)
        } else {
            DVec3::ZERO
        };
        (acc, v_mean)
    }

    /// Each pixel's pilot (`spp` samples) mean and variance of the mean, row by row
    /// (per-channel passes: each channel from its own pass).
    fn pilot(&self, h: u32, spp: u32) -> Vec<(DVec3, DVec3)> {
        let (w, npass) = (self.width, self.rays.len());
        (0..h)
            .into_par_iter()
            .flat_map_iter(|j| {
                (0..w).map(move |i| {
                    let (mut m, mut v) = (DVec3::ZERO, DVec3::ZERO);
                    for k in 0..npass {
                        let (pm, pv) = self.run(i, j, k, 0, spp, &mut DVec3::default());
                        match self.channel_of(k) {
                            None => (m, v) = (pm, pv),
                            Some(c) => (m[c], v[c]) = (pm[c], pv[c]),
                        }
                    }
                    (m, v)
                })
            })
            .collect()
    }

    /// Row `j`: every pixel's samples (`counts` per pixel and pass with a noise target, else
    /// `spp`), its depth through the pixel centre and, with a target, its noise by `measure`.
    fn row(
        &self,
        j: u32,
        spp: u32,
        counts: &[[u32; 3]],
        targeted: bool,
        measure: &adaptive::Measure,
        cam_from_world: &crate::model::Pose,
    ) -> PixelRow {
        let (w, want_albedo, rays) = (self.width, self.want_albedo, &self.rays);
        let mut row = Vec::with_capacity(w as usize);
        let mut drow = Vec::with_capacity(w as usize);
        let mut vrow = Vec::with_capacity(w as usize);
        let mut arow = Vec::with_capacity(if want_albedo { w as usize } else { 0 });
        let mut nrow = Vec::with_capacity(if targeted { w as usize } else { 0 });
        for i in 0..w {
            let mut alb = DVec3::ZERO;
            let mut alb_n = 0u32;
            let pixel = j as usize * w as usize + i as usize;
            let mut sum = DVec3::ZERO;
            let mut var = DVec3::ZERO;
            let mut taken = 0u32;
            for k in 0..rays.len() {
                let channel = self.channel_of(k);
                // With a noise target the pilot (stream indices 0..spp) is dropped and the
                // pixel's fresh samples follow it, so that their number does not depend on
                // the samples averaged (unbiased).
                let (from, n) = match counts.get(pixel) {
                    Some(c) => (spp, c[k]),
                    None => (0, spp),
                };
                let (acc, v_mean) = self.run(i, j, k, from, n, &mut alb);
                if k == 0 {
                    alb_n = n;
                }
                taken += n;
                match channel {
                    None => {
                        sum = acc;
                        var = v_mean;
                    }
                    Some(c) => {
                        sum[c] = acc[c];
                        var[c] = v_mean[c];
                    }
                }
            }
            if targeted {
                let rel = measure.squared(sum, var, None).sqrt();
                nrow.push((taken / rays.len() as u32, rel as f32));
            }
            row.push([sum.x as f32, sum.y as f32, sum.z as f32]);
            vrow.push([var.x as f32, var.y as f32, var.z as f32]);
            if want_albedo {
                let a = alb / alb_n.max(1) as f64;
                arow.push([a.x as f32, a.y as f32, a.z as f32]);
            }
            // Depth through the pixel centre (green channel rays).
            let r = &rays[if self.passes.len() == 1 { 0 } else { 1 }];
            let (x, y) = (i + self.origin.0, j + self.origin.1);
            let z = r
                .ray(x as f64 + 0.5, y as f64 + 0.5)
                .and_then(|(o, d, _)| {
                    self.scene
                        .intersect(&scene::Ray { origin: o, dir: d }, f64::INFINITY)
                })
                .map_or(0.0, |hit| cam_from_world.transform_point(hit.point).z);
            drow.push(z as f32);
        }
        (row, drow, vrow, arow, nrow)
    }
}

/// Linear float RGB → OpenEXR bytes on disk (atomic).
pub fn write_exr(path: &Path, width: u32, height: u32, data: &[[f32; 3]]) -> Result<(), String> {
    let flat: Vec<f32> = data.iter().flat_map(|p| *p).collect();
    let img = image::Rgb32FImage::from_raw(width, height, flat)
        .ok_or_else(|| format!("{}: image buffer has the wrong size", path.display()))?;
    crate::io::write_atomic_with(path, |tmp| {
        image::DynamicImage::ImageRgb32F(img)
            .save_with_format(tmp, image::ImageFormat::OpenExr)
            .map_err(|e| format!("{}: {e}", path.display()))
    })
}

use crate::image::srgb8 as srgb;

/// PNG preview (sRGB of `exposure × radiance`), atomic.
pub fn write_png(path: &Path, img: &Image, exposure: f64) -> Result<(), String> {
    let bytes: Vec<u8> = img
        .rgb
        .iter()
        .flat_map(|p| p.map(|c| srgb(exposure * c as f64)))
        .collect();
    let buf = image::RgbImage::from_raw(img.width, img.height, bytes)
        .ok_or_else(|| format!("{}: image buffer has the wrong size", path.display()))?;
    crate::io::write_atomic_with(path, |tmp| {
        buf.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| format!("{}: {e}", path.display()))
    })
}

/// Render the model (see the module documentation for the outputs).
pub fn render(model: &Model, out: &Path, opts: &RenderOptions) -> Result<RenderReport, String> {
    let start = Instant::now();
    if model.cameras.is_empty() {
        return Err("the scene has no camera".into());
    }
    let poses = opts.pose_indices(model.poses.len());
    if poses.is_empty() {
        return Err("no rig pose to render".into());
    }
    let samples = checked_samples(opts.samples.unwrap_or(model.render.samples))?;
    let scene = scene::Scene::build(model)?;
    // A baked texture coarser than wanted loses detail in these images: warn here, where it is
    // rendered (Mitsuba and Cycles warn when they compile; `poser explain` lists it as a plan).
    for (o, b) in model.objects.iter().zip(&scene.bvh.textures) {
        if let Some(b) = b.as_ref().filter(|b| b.coarsened()) {
            eprintln!("warning: object `{}`: texture {}", o.name, b.summary());
        }
    }
    let rows = |c: &crate::model::Camera| crate::model::Crop::region(model.render.crop, c).3 as u64;
    let rows_total: u64 = poses.len() as u64 * model.cameras.iter().map(rows).sum::<u64>();
    let pb = opts
        .progress
        .then(|| Progress::new(true, "rendering", "rows", rows_total));
    let want_depth = model.render.outputs.iter().any(|o| o == "depth");
    let mut report = RenderReport::default();
    let mut manifest = resume::Manifest::open(out, &resume::fingerprint(model, samples));
    let mut resumed = 0usize;
    // With a noise target: (images, Σ mean samples, Σ median achieved, at-target shares).
    let mut noise_sum = (0usize, 0.0f64, 0.0f64, 0.0f64);
    if opts.resume {
        // What a killed run was writing when it stopped (whole files are renamed into place).
        crate::io::remove_stale_temporaries(out);
    }
    for &p in &poses {
        for c in 0..model.cameras.len() {
            let name = model.image_name(p, c);
            let exr = out.join(format!("{name}.exr"));
            if opts.resume && manifest.is_done(out, &name) {
                if let Some(pb) = &pb {
                    pb.inc(rows(&model.cameras[c]));
                }
                report.images.push(exr);
                resumed += 1;
                continue;
            }
            let img = render_image(model, &scene, p, c, samples, pb.as_ref())?;
            write_exr(&exr, img.width, img.height, &img.rgb)?;
            let mut files = vec![exr.clone()];
            if model.sensor.is_some() {
                let path = out.join(format!("{name}.variance.exr"));
                write_exr(&path, img.width, img.height, &img.variance)?;
                files.push(path);
            }
            let png = out.join(format!("{name}.png"));
            if let Some(sigma) = model.render.denoise_radius {
                let (rgb, variance) = denoise::illumination(
                    img.width as usize,
                    img.height as usize,
                    &img.rgb,
                    &img.variance,
                    &img.albedo,
                    &img.depth,
                    sigma,
                );
                let path = out.join(format!("{name}.denoised.exr"));
                write_exr(&path, img.width, img.height, &rgb)?;
                files.push(path);
                let path = out.join(format!("{name}.denoised.variance.exr"));
                write_exr(&path, img.width, img.height, &variance)?;
                files.push(path);
                let filtered = Image {
                    rgb,
                    variance,
                    ..img.clone()
                };
                write_png(&png, &filtered, model.render.exposure)?;
            } else {
                write_png(&png, &img, model.render.exposure)?;
            }
            files.push(png);
            if let Some(noise) = &img.noise {
                noise_sum.0 += 1;
                noise_sum.1 += noise.samples.mean;
                noise_sum.2 += noise.achieved.median;
                noise_sum.3 += noise.share_at_target;
                let path = out.join(format!("{name}.noise.json"));
                let json = serde_json::to_vec_pretty(noise).map_err(|e| e.to_string())?;
                crate::io::write_atomic(&path, &json)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                files.push(path);
            }
            if want_depth {
                let d: Vec<[f32; 3]> = img.depth.iter().map(|&z| [z, z, z]).collect();
                let path = out.join(format!("{name}.depth.exr"));
                write_exr(&path, img.width, img.height, &d)?;
                files.push(path);
            }
            manifest.record(out, &name, &files)?;
            report.images.push(exr);
        }
    }
    if let Some(pb) = pb {
        pb.finish();
    }
    if opts.resume {
        eprintln!(
            "resume: {resumed} of {} image(s) were already finished",
            report.images.len()
        );
    }
    if let (Some(t), (n @ 1.., taken, achieved, share)) = (model.render.noise, noise_sum) {
        let k = n as f64;
        eprintln!(
            "noise target {}: {n} image(s), {:.0} samples per pixel on average after a pilot of \
             {samples}, median achieved {:.3} ({:.0} % of the pixels at or below the \
             target); each image's <image>.noise.json has the details",
            if t.against_sensor {
                "render noise ≤ sensor noise".to_string()
            } else {
                format!("{} %", crate::scene::diag::num(100.0 * t.relative))
            },
            taken / k,
            achieved / k,
            100.0 * share / k,
        );
    }
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}
