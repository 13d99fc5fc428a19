//! Native renderer against analytic radiometry, thread-count determinism and finiteness.

use crate::support;

use glam::DVec3;
use poser::backend::RenderOptions;
use poser::backend::native::{render, render_image, scene::Scene};
use poser::model::*;
use support::native::*;

fn read_exr(path: &std::path::Path) -> Vec<f32> {
    image::open(path).unwrap().into_rgb32f().into_raw()
}

/// Lambertian floor lit by a spot in absorbing water: every pixel against
/// L = ρ/π · I·cosθ/r² · exp(-σa·r_light) · exp(-σa·r_cam).
#[test]
fn spot_on_lambertian_patch_in_absorbing_water_matches_analytic() {
    let h = 2.0;
    let mut m = nadir_model(h);
    m.water.as_mut().unwrap().absorption = [0.4, 0.1, 0.05];
    let light_off = DVec3::new(0.3, 0.0, 0.0); // rig frame: 0.3 m to the camera's right
    m.lights.push(rig_spot(light_off, 25.0));
    m.render.max_bounces = 1;
    let scene = Scene::build(&m).unwrap();
    let img = render_image(&m, &scene, 0, 0, 4, None).unwrap();
    let cam = m.world_from_camera(0, 0);
    let light = m.poses[0].world_from_rig.transform_point(light_off);
    let sa = DVec3::from_array(m.water.as_ref().unwrap().absorption);
    let c = &m.cameras[0];
    let mut ratios = [vec![], vec![], vec![]];
    for j in 20..100u32 {
        for i in 30..130u32 {
            // Pixel-centre ray to the plane z = 0.
            let d = cam.transform_vector(
                DVec3::new(
                    (i as f64 + 0.5 - c.cx) / c.fx,
                    (j as f64 + 0.5 - c.cy) / c.fy,
                    1.0,
                )
                .normalize(),
            );
            let t = -cam.translation.z / d.z;
            let p = cam.translation + t * d;
            let wl = light - p;
            let r = wl.length();
            let cos = wl.z / r;
            for ch in 0..3 {
                let e = 25.0 * cos / (r * r) * (-sa[ch] * r).exp();
                let l = 0.5 / std::f64::consts::PI * e * (-sa[ch] * t).exp();
                let px = img.rgb[(j * c.width + i) as usize][ch] as f64;
                ratios[ch].push(px / l);
            }
        }
    }
    for (ch, r) in ratios.iter().enumerate() {
        let n = r.len() as f64;
        let mean = r.iter().sum::<f64>() / n;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        // The only randomness is the pixel jitter (box filter over the pixel) against a
        // pixel-centre reference: its per-pixel spread `sd` is measured; the mean must agree to
        // 4 standard errors plus 1e-4 for the curvature of the integrand over a pixel and the
        // f32 storage.
        let tol = 4.0 * sd / n.sqrt() + 1e-4;
        eprintln!("channel {ch}: mean ratio {mean:.6}, per-pixel sd {sd:.2e}, tol {tol:.2e}");
        assert!(
            (mean - 1.0).abs() < tol,
            "channel {ch}: mean ratio {mean}, sd {sd}, tol {tol}"
        );
        assert!(sd < 0.02, "channel {ch}: per-pixel spread {sd}");
    }
}

#[test]
fn same_bytes_with_one_and_two_threads_and_no_nan() {
    let m = busy_model();
    let dirs: Vec<_> = [1usize, 2].iter().map(|&n| render_on(&m, n)).collect();
    for f in ["img_0000.exr", "img_0000.png", "img_0000.depth.exr"] {
        let a = std::fs::read(dirs[0].path().join(f)).unwrap();
        let b = std::fs::read(dirs[1].path().join(f)).unwrap();
        assert!(a == b, "{f} differs between 1 and 2 threads");
    }
    let px = read_exr(&dirs[0].path().join("img_0000.exr"));
    assert!(
        px.iter().all(|v| v.is_finite() && *v >= 0.0),
        "NaN, inf or negative pixel"
    );
    // Not black: the scene is lit by four kinds of light.
    let mean = px.iter().map(|&v| v as f64).sum::<f64>() / px.len() as f64;
    assert!(mean > 1e-4, "mean {mean}");
    let depth = read_exr(&dirs[0].path().join("img_0000.depth.exr"));
    // Depth at the centre: the floor is 1.5 m below the camera (boulders may be nearer).
    let c = (18 * 48 + 24) * 3;
    assert!(
        depth[c] > 0.5 && depth[c] <= 1.5 + 1e-4,
        "depth {}",
        depth[c]
    );
}

/// A circle grid seen through a flat port: measured disk centroids against the exact
/// refractive projection (poser::compare), with a tolerance from the measured Monte Carlo
/// noise of two independent renders.
#[test]
fn target_centroids_match_refractive_projection() {
    let mut m = nadir_model(1.2);
    m.cameras[0].port = Port::Flat {
        normal: DVec3::Z,
        distance: 0.03,
        thickness: 0.008,
        glass: Glass {
            name: "PMMA".into(),
            ior: [1.49; 3],
        },
        outer_layers: vec![],
    };
    m.lights.push(Light {
        name: "sky".into(),
        mount: Mount::World,
        kind: LightKind::Ambient { radiance: [1.0; 3] },
    });
    // Wide spacing: the detector's window (up to r_img + 4 px) must stay inside the printed
    // extent (spacing/2 beyond the outer disks), where the surround is uniformly white.
    let kind = TargetKind::CircleGrid {
        cols: 5,
        rows: 4,
        spacing: 0.12,
        diameter: 0.03,
    };
    let tilt = glam::DMat3::from_rotation_x(0.2) * glam::DMat3::from_rotation_z(0.3);
    let pose = Pose {
        rotation: tilt,
        translation: DVec3::new(0.02, -0.03, 0.0),
    };
    m.targets.push(Target {
        name: "grid".into(),
        points: poser::geometry::targets::points("grid", &kind, &pose),
        kind,
        pose,
    });
    // White backing board 2 mm behind the target, so that every disk's detection window (which
    // may reach past the printed extent) sees the same white surround.
    m.objects[0].shape = Shape::Plane {
        width: 1.0,
        height: 1.0,
    };
    m.objects[0].material.albedo = [poser::geometry::targets::WHITE; 3];
    m.objects[0].pose = pose.compose(&Pose {
        rotation: glam::DMat3::IDENTITY,
        translation: DVec3::new(0.0, 0.0, -0.002),
    });
    m.render.max_bounces = 1;
    m.render.samples = 64;
    let mut runs = Vec::new();
    for seed in [1u64, 2] {
        m.render.seed = seed;
        let dir = tempfile::tempdir().unwrap();
        render(&m, dir.path(), &RenderOptions::default()).unwrap();
        let (found, expected) = poser::compare::measure_targets(&m, dir.path()).unwrap();
        assert!(expected >= 15, "only {expected} disks expected in view");
        assert_eq!(found.len(), expected, "some disks were not found");
        runs.push(found);
    }
    let rms = |v: &[[f64; 2]]| {
        (v.iter().map(|d| d[0] * d[0] + d[1] * d[1]).sum::<f64>() / v.len() as f64).sqrt()
    };
    let err: Vec<[f64; 2]> = runs[0].iter().map(|r| r.2).collect();
    let diff: Vec<[f64; 2]> = runs[0]
        .iter()
        .zip(&runs[1])
        .map(|(a, b)| [a.2[0] - b.2[0], a.2[1] - b.2[1]])
        .collect();
    // Noise of one render's centroids = RMS of the two-seed difference / √2. The error must be
    // within 3σ of noise plus 0.01 px of systematic budget (docs/render-conventions.md §1.1; measured
    // Mitsuba/Cycles at ≤ 0.015 px RMS).
    let noise = rms(&diff) / 2f64.sqrt();
    let tol = 3.0 * noise + 0.01;
    let e = rms(&err);
    eprintln!("centroid RMS error {e:.4} px, noise {noise:.4} px, tolerance {tol:.4} px");
    assert!(e < tol, "centroid RMS error {e} px > {tol} px");
}

/// `poser render --scale`: a preview camera sees every point where the full camera does, at
/// the scaled pixel position (exactly, through the refractive port), for any scale.
#[test]
fn resolution_scale_keeps_every_ray_in_place() {
    let path =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/reef_strip.toml");
    let model = poser::scene::load(&path, &[]).unwrap().model;
    let full = model.projector(0, 1).unwrap();
    for scale in [0.25, 0.1, 0.333, 2.0] {
        let small_model = model.clone().with_resolution_scale(scale);
        let c0 = &model.cameras[0];
        let c1 = &small_model.cameras[0];
        assert_eq!(c1.width, (c0.width as f64 * scale).round() as u32);
        // Square pixels stay square: both axes scale by the width's ratio.
        let sx = c1.width as f64 / c0.width as f64;
        let sy = if c0.fx == c0.fy {
            sx
        } else {
            c1.height as f64 / c0.height as f64
        };
        assert_eq!(
            c1.fx == c1.fy,
            c0.fx == c0.fy,
            "scale {scale}: squareness kept"
        );
        let small = small_model.projector(0, 1).unwrap();
        let mut checked = 0;
        let cam = model.world_from_camera(0, 0);
        for k in 0..50 {
            // A fan of points 2 m in front of the camera, out to the image corners.
            let q = DVec3::new(-0.9 + 0.036 * k as f64, 0.6 - 0.024 * k as f64, 2.0);
            let p = cam.transform_point(q);
            if let Ok([u, v]) = full.project_world(0, p) {
                let [u1, v1] = small.project_world(0, p).unwrap();
                assert!((u1 - u * sx).abs() < 1e-6 && (v1 - v * sy).abs() < 1e-6);
                checked += 1;
            }
        }
        assert!(checked > 40, "{checked} points in view");
    }
}

/// Sunlit seabed in forward-scattering water (the typical survey): sampling surface bounces
/// from the mixture of the cosine lobe and the sun's aureole leaves the estimate unchanged and
/// cuts its variance. Measured (20 000 paths straight down, bounces = 2): the means agree well
/// within the noise (5.05 vs 4.89 ± 0.27) and the variance falls 14× (94 vs 1317).
#[test]
fn aureole_sampling_is_unbiased_and_cuts_sunlit_seabed_noise() {
    use poser::backend::native::{
        integrator::Integrator, lights::Lights, medium::Medium, sampler::Sampler,
    };
    let mut m = nadir_model(2.0);
    {
        let w = m.water.as_mut().unwrap();
        w.absorption = [0.05; 3];
        w.scattering = [0.3; 3];
        w.phase = Phase::HenyeyGreenstein { g: 0.92 };
    }
    let dir = DVec3::new(0.3, 0.1, -1.0).normalize();
    m.sun = Some(sun_along(dir, [800.0; 3], [600.0; 3]));
    m.render.max_bounces = 2;
    // These estimators trace daylight through the water (the column would replace them).
    m.render.daylight = poser::model::Daylight::Traced;
    // The sea ends at z = 0 under a sun: sink the floor and the camera 10 m.
    m.poses[0].world_from_rig.translation.z -= 10.0;
    for o in &mut m.objects {
        o.pose.translation.z -= 10.0;
    }
    let scene = Scene::build(&m).unwrap();
    let cam = m.world_from_camera(0, 0);
    let make = || {
        Integrator::new(
            &scene,
            &m,
            Medium::new(&m, cam.translation),
            Lights::at_pose(&m, &m.poses[0].world_from_rig),
        )
    };
    let guided = make();
    assert!(guided.aureole.is_some(), "sun + g = 0.92 water must guide");
    let mut plain = make();
    plain.aureole = None;
    let n = 20_000u64;
    let stats = |integ: &Integrator| {
        let v: Vec<f64> = (0..n)
            .map(|k| {
                let mut rng = Sampler::new(7, 0, 0, 0, k);
                integ.li(cam.translation, -DVec3::Z, &mut rng).y
            })
            .collect();
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, var)
    };
    let (mg, vg) = stats(&guided);
    let (mp, vp) = stats(&plain);
    let se = (vg / n as f64 + vp / n as f64).sqrt();
    eprintln!("guided {mg:.4} (var {vg:.4}), cosine {mp:.4} (var {vp:.4}), se {se:.4}");
    assert!((mg - mp).abs() < 4.0 * se, "biased: {mg} vs {mp} ± {se}");
    assert!(vg < 0.25 * vp, "no variance reduction: {vg} vs {vp}");
}

/// Sunlit, forward-scattering water seen from 2 m above a seabed 10 m deep: sun-aware distance
/// sampling along medium segments and no Russian roulette before `max_bounces` (what the
/// integrator does in sunlit water) leave the estimate unchanged and cut its variance.
/// Light scattered near the surface has crossed little water on its way down, so free-flight
/// vertices there (sampled with density `σt e^(−σt t)` from the seabed) carry large weights.
/// Measured (40 000 paths straight down): bounces = 2, 2.738 vs 2.712 ± 0.052 with the
/// variance 6.8× lower; bounces = 8, 32.6 vs 34.1 ± 1.2 with the variance 5.3× lower.
#[test]
fn sun_distance_sampling_and_roulette_policy_are_unbiased_and_cut_sunlit_water_noise() {
    use poser::backend::native::{
        integrator::{Integrator, ROULETTE_FROM},
        lights::Lights,
        medium::Medium,
        sampler::Sampler,
    };
    let mut m = nadir_model(2.0);
    {
        let w = m.water.as_mut().unwrap();
        w.absorption = [0.3, 0.06, 0.03];
        w.scattering = [0.3, 0.35, 0.5];
        w.phase = Phase::HenyeyGreenstein { g: 0.92 };
    }
    let dir = DVec3::new(0.3, 0.1, -1.0).normalize();
    m.sun = Some(sun_along(dir, [800.0; 3], [600.0; 3]));
    // These estimators trace daylight through the water (the column would replace them).
    m.render.daylight = poser::model::Daylight::Traced;
    m.poses[0].world_from_rig.translation.z -= 10.0;
    for o in &mut m.objects {
        o.pose.translation.z -= 10.0;
    }
    let scene = Scene::build(&m).unwrap();
    let cam = m.world_from_camera(0, 0);
    let models: Vec<_> = [2u32, 8]
        .iter()
        .map(|&b| {
            let mut mm = m.clone();
            mm.render.max_bounces = b;
            mm
        })
        .collect();
    let make = |bounces: u32| {
        let mm = &models[usize::from(bounces == 8)];
        Integrator::new(
            &scene,
            mm,
            Medium::new(mm, cam.translation),
            Lights::at_pose(mm, &mm.poses[0].world_from_rig),
        )
    };
    let n = 40_000u64;
    let stats = |integ: &Integrator| {
        let v: Vec<f64> = (0..n)
            .map(|k| {
                let mut rng = Sampler::new(11, 0, 0, 0, k);
                integ.li(cam.translation, -DVec3::Z, &mut rng).y
            })
            .collect();
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, var)
    };
    let agree = |a: (f64, f64), b: (f64, f64), what: &str| {
        let se = (a.1 / n as f64 + b.1 / n as f64).sqrt();
        eprintln!(
            "{what}: {:.4} (var {:.3}) vs {:.4} (var {:.3}), se {se:.4}",
            a.0, a.1, b.0, b.1
        );
        assert!((a.0 - b.0).abs() < 4.0 * se, "{what}: biased");
    };
    // Single scattering off the seabed: the sun-aware distance sample alone.
    let on = make(2);
    assert!(on.sun_sampling && on.roulette_from == 2);
    let mut off = make(2);
    off.sun_sampling = false;
    let (s_on, s_off) = (stats(&on), stats(&off));
    agree(s_on, s_off, "bounces 2, sun sampling on/off");
    assert!(
        s_on.1 < 0.5 * s_off.1,
        "no variance reduction: {s_on:?} vs {s_off:?}"
    );
    // Deep paths: roulette from depth 3 against none before max_bounces.
    let full = make(8);
    assert_eq!(full.roulette_from, 8);
    let mut rr = make(8);
    rr.roulette_from = ROULETTE_FROM;
    let (s_full, s_rr) = (stats(&full), stats(&rr));
    agree(s_full, s_rr, "bounces 8, roulette from max/3");
    assert!(
        s_full.1 < 0.5 * s_rr.1,
        "no variance reduction: {s_full:?} vs {s_rr:?}"
    );
}

/// `render.denoise = "illumination"` through the CLI, as a user runs it (`dome_orbit` ships
/// with it): the unfiltered EXR, the denoised EXR and its variance are written; the camera
/// image's sidecar names the denoised input; the denoised image keeps the mean within 3 % and
/// its propagated render noise is at most a third of the unfiltered one.
#[test]
fn illumination_denoiser_feeds_the_camera_and_keeps_the_mean() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["render", "scenarios/dome_orbit.toml", "-o"])
        .arg(out)
        .args([
            "--scale",
            "0.1",
            "--samples",
            "8",
            "--poses",
            "0",
            "--sensor",
            "--quiet",
            // Coarse textures: the bake at the scene's texel would be most of the test's time.
            "--set",
            "objects.0.pattern.texel=\"2 cm\"",
            "--set",
            "objects.1.pattern.texel=\"1 cm\"",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .unwrap();
    assert!(st.success());
    let raw = read_exr(&out.join("img_0001.exr"));
    let den = read_exr(&out.join("img_0001.denoised.exr"));
    let var_raw = read_exr(&out.join("img_0001.variance.exr"));
    let var_den = read_exr(&out.join("img_0001.denoised.variance.exr"));
    assert_eq!(raw.len(), den.len());
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let (m_raw, m_den) = (mean(&raw), mean(&den));
    assert!((m_den / m_raw - 1.0).abs() < 0.03, "{m_den} vs {m_raw}");
    assert!(den.iter().all(|x| x.is_finite() && *x >= 0.0));
    let (v_raw, v_den) = (mean(&var_raw), mean(&var_den));
    assert!(v_den < v_raw / 9.0, "variance {v_den} vs {v_raw}");
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("camera/img_0001.sensor.json")).unwrap())
            .unwrap();
    let input = side["input"].as_str().unwrap();
    assert!(input.ends_with("img_0001.denoised.exr"), "{input}");
}

#[test]
fn noise_target_against_the_sensor_aims_at_the_sensors_own_noise() {
    // A small-pixel sensor (full well 400 e⁻: at least 5 % shot noise at the top of its
    // range) so that the test stays cheap; `render.noise = "sensor"`.
    let mut m = busy_model();
    m.sensor = Some(Sensor {
        full_well: 400.0,
        ..Sensor::default()
    });
    m.render.noise = Some(NoiseTarget {
        relative: 1.0,
        max_samples: Some(2048),
        against_sensor: true,
    });
    let scene = Scene::build(&m).unwrap();
    let img = render_image(&m, &scene, 0, 0, 16, None).unwrap();
    let rep = img.noise.clone().expect("a noise report");
    eprintln!("{rep:?}");
    assert_eq!(rep.measure, "render noise / sensor noise");
    assert!(rep.electrons_per_radiance.is_some());
    assert!(
        rep.achieved.median > 0.6 && rep.achieved.median < 1.4,
        "{rep:?}"
    );
    assert!(rep.share_capped < 0.2, "{rep:?}");
    // Without a sensor the target has nothing to aim at: an error, not a panic.
    m.sensor = None;
    let e = render_image(&m, &scene, 0, 0, 16, None).unwrap_err();
    assert!(e.contains("needs a sensor"), "{e}");
}

/// `samples = 0` asked of the library (the Python module's `Scene.render(samples=0)`) is an
/// error, never one sample in silence.
#[test]
fn zero_samples_is_an_error_not_one_sample() {
    let m = busy_model();
    let e = match poser::backend::native::render_one(&m, 0, 0, Some(0)) {
        Ok(_) => panic!("0 samples rendered"),
        Err(e) => e,
    };
    assert!(e.contains("0 samples"), "{e}");
    assert!(poser::backend::native::render_one(&m, 0, 0, Some(1)).is_ok());
}

/// A textured seabed (fractal albedo, texels ~2.7 to a pixel's footprint) under a spot, one
/// bounce: the only randomness is where each sample lands in its pixel, so a pixel's variance is
/// the texture's (and the light's) variation over its footprint. Reading the texture averaged
/// over the footprint (`render.texture_filter = "footprint"`, the default) must cut that
/// variance and keep the image's mean per channel within 0.5 % of point lookups.
#[test]
fn footprint_texture_filter_cuts_pixel_variance_and_keeps_the_mean() {
    let mut m = nadir_model(2.0);
    m.water.as_mut().unwrap().absorption = [0.4, 0.1, 0.05];
    m.lights.push(rig_spot(DVec3::new(0.3, 0.0, 0.0), 25.0));
    m.render.max_bounces = 1;
    m.objects[0].material.pattern = Some(Pattern::Fbm {
        size: 0.1,
        smallest: 0.0,
        gain: 0.7,
        contrast: 0.45,
        seed: 11,
    });
    assert!(m.objects[0].material.is_baked());
    let scene = Scene::build(&m).unwrap();
    let b = scene.textures[0].as_ref().unwrap();
    assert!(b.mips.depth() >= 3, "a one-chart bake has its levels");
    let stats = |f: TextureFilter| {
        let mut m = m.clone();
        m.render.texture_filter = f;
        let img = render_image(&m, &scene, 0, 0, 16, None).unwrap();
        let n = img.rgb.len() as f64;
        let mut mean = [0.0; 3];
        let mut var = [0.0; 3];
        for (p, v) in img.rgb.iter().zip(&img.variance) {
            for c in 0..3 {
                mean[c] += p[c] as f64 / n;
                var[c] += v[c] as f64 / n;
            }
        }
        (mean, var)
    };
    let (mf, vf) = stats(TextureFilter::Footprint);
    let (mp, vp) = stats(TextureFilter::Point);
    eprintln!("footprint: mean {mf:?}, variance {vf:?}; point: mean {mp:?}, variance {vp:?}");
    for c in 0..3 {
        assert!(
            (mf[c] / mp[c] - 1.0).abs() < 0.005,
            "channel {c}: mean {} vs {}",
            mf[c],
            mp[c]
        );
        assert!(
            vf[c] < 0.25 * vp[c],
            "channel {c}: variance {} vs {}",
            vf[c],
            vp[c]
        );
    }
}
