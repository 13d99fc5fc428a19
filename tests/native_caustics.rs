//! Caustics under a wavy sea surface in the native renderer: energy conservation of the
//! caustic volume, caustic contrast against depth, a rendered seabed, determinism.

use crate::support;

use glam::DVec3;
use poser::backend::native::caustics::{CausticVolume, PLANES};
use poser::backend::native::{render_image, scene::Scene};
use poser::model::*;
use poser::optics::interface::{fresnel_transmittance, refract};
use poser::optics::sun::{direction_from, refract_into_water};
use poser::optics::waves::WaveField;
use support::native::*;

const N_WATER: f64 = 1.34;

fn sun_air() -> DVec3 {
    direction_from(70f64.to_radians(), 2.0)
}

/// Mean over one period of `T·(−d·N)/(T_flat·cos θa)`, computed independently of the volume
/// (fine grid over the period): what each plane's mean factor must equal.
fn expected_mean(f: &WaveField, d: DVec3) -> f64 {
    let cos_a = -d.z;
    let (_, ct0) = refract(d, -DVec3::Z, 1.0 / N_WATER).unwrap();
    let t0 = fresnel_transmittance(1.0, N_WATER, cos_a, ct0);
    let n = 400;
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (
                (i as f64 + 0.25) * f.period / n as f64,
                (j as f64 + 0.75) * f.period / n as f64,
            );
            let (gx, gy) = f.gradient(x, y);
            let nrm = DVec3::new(-gx, -gy, 1.0);
            let proj = -d.dot(nrm);
            if proj <= 0.0 {
                continue;
            }
            let nd = -nrm.normalize();
            let (_, ct) = refract(d, nd, 1.0 / N_WATER).unwrap();
            s += fresnel_transmittance(1.0, N_WATER, d.dot(nd), ct) * proj;
        }
    }
    s / (n * n) as f64 / (t0 * cos_a)
}

#[test]
fn caustic_volume_conserves_energy() {
    let f = WaveField::new(0.3, 4.0, 6.0, 0.0, 11);
    let d = sun_air();
    let v = CausticVolume::build(&f, d, N_WATER, -20.0);
    let want = expected_mean(&f, d);
    eprintln!(
        "expected plane mean (Fresnel difference) {want:.6}; build {:.2} s",
        v.build_seconds
    );
    // The Fresnel transmittance varies with the local slope (rms slope ≈ 0.1 here): the
    // mean differs from 1 by well under 1 %.
    assert!((want - 1.0).abs() < 0.01, "{want}");
    for k in 0..PLANES {
        let (mean, sd) = v.plane_stats(k);
        // f32 storage and summation of 262 144 cells: 1e-5 relative. The independent mean is
        // a 400² grid estimate of a smooth periodic integrand (≈ exact): 1e-4.
        assert!(
            (mean - want).abs() < 1e-4,
            "plane {k} z {:.2}: mean {mean} want {want} (sd {sd})",
            v.planes()[k]
        );
    }
}

#[test]
fn caustic_contrast_is_zero_when_flat_and_peaks_at_a_focal_depth() {
    let d = sun_air();
    let flat = CausticVolume::build(&WaveField::flat(16.0), d, N_WATER, -30.0);
    for k in 0..PLANES {
        let (mean, sd) = flat.plane_stats(k);
        // Uniform to f32 rounding (partition of unity of the splat).
        assert!(sd / mean < 1e-5, "flat plane {k}: contrast {}", sd / mean);
    }
    let f = WaveField::new(0.3, 4.0, 6.0, 0.0, 11);
    let v = CausticVolume::build(&f, d, N_WATER, -30.0);
    let c: Vec<f64> = (0..PLANES)
        .map(|k| {
            let (m, s) = v.plane_stats(k);
            s / m
        })
        .collect();
    // Focal depth of one sinusoid of amplitude a and wavenumber k: 1/(a·k²·(n−1)/n). The
    // peak component (a ≈ Hs/(2√2) ≈ 0.1 m, k = 2π/4 m) focuses at ≈ 15 m, but the short,
    // steep components of the spectrum's tail (down to λp/12) focus within a few metres: the
    // sum peaks at a few metres (measured: 2.5 m, contrast 1.2).
    for (k, ck) in c.iter().enumerate() {
        eprintln!("z {:7.2} m  contrast {ck:.4}", v.planes()[k]);
    }
    let (kmax, cmax) = c
        .iter()
        .enumerate()
        .fold((0, 0.0), |a, (k, &x)| if x > a.1 { (k, x) } else { a });
    eprintln!("max contrast {cmax:.3} at z = {:.2} m", v.planes()[kmax]);
    // Just below the troughs the irradiance is nearly uniform (the slopes have not had the
    // distance to focus): small contrast.
    assert!(c[0] < 0.5 * cmax, "top contrast {} vs max {cmax}", c[0]);
    // Rises to a maximum strictly inside the depth range …
    assert!(kmax > 0 && kmax < PLANES - 1, "max at plane {kmax}");
    assert!(cmax > 0.3, "max contrast {cmax}");
    // … monotonically up to it …
    for k in 1..=kmax {
        assert!(c[k] > c[k - 1], "not rising at plane {k}: {c:?}");
    }
    // … then falls (defocusing and the sun's disk blur), monotonically (measured: to 0.2 at
    // 30 m; smooth in depth, so no wiggle allowance).
    for k in kmax + 1..PLANES {
        assert!(c[k] < c[k - 1], "not falling at plane {k}: {c:?}");
    }
    assert!(
        c[PLANES - 1] < 0.5 * cmax,
        "deep contrast {} vs {cmax}",
        c[PLANES - 1]
    );
}

/// A sunlit sandy floor 4 m deep in clear water, camera 2.5 m above it looking down.
fn seabed(surface: SeaSurface) -> Model {
    let mut m = nadir_model(2.5);
    m.water.as_mut().unwrap().ior = [N_WATER; 3];
    let d = sun_air();
    let (dw, fac) = refract_into_water(d, N_WATER);
    m.sun = Some(Sun {
        elevation: 70f64.to_radians(),
        azimuth: 2.0,
        irradiance: [800.0; 3],
        direction_air: d,
        direction_water: dw,
        irradiance_water: [800.0 * fac; 3],
        from_time: None,
    });
    m.site.depth = 4.0;
    m.site.surface = surface;
    m.needs.caustics = matches!(surface, SeaSurface::Waves { .. });
    m.render.max_bounces = 1;
    m.poses[0].world_from_rig.translation.z -= 4.0;
    for o in &mut m.objects {
        o.pose.translation.z -= 4.0;
    }
    m
}

fn waves() -> SeaSurface {
    SeaSurface::Waves {
        height: 0.15,
        wavelength: 1.5,
        wind_speed: 6.0,
    }
}

fn stats(img: &[[f32; 3]]) -> (f64, f64) {
    let v: Vec<f64> = img.iter().map(|p| p[1] as f64).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    (mean, sd)
}

#[test]
fn rendered_seabed_shows_caustics_and_keeps_its_mean() {
    let flat = seabed(SeaSurface::Flat);
    let wavy = seabed(waves());
    let sf = Scene::build(&flat).unwrap();
    let sw = Scene::build(&wavy).unwrap();
    assert!(sf.caustics.is_none());
    let vol = sw.caustics.as_ref().expect("caustic volume");
    eprintln!("caustic volume built in {:.2} s", vol.build_seconds);
    let a = render_image(&flat, &sf, 0, 0, 4, None).unwrap();
    let b = render_image(&wavy, &sw, 0, 0, 4, None).unwrap();
    assert!(
        b.rgb
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0))
    );
    let (ma, sa) = stats(&a.rgb);
    let (mb, sb) = stats(&b.rgb);
    // What the footprint (3 m × 2.2 m, about 2 × 1.5 wavelengths) samples of the pattern:
    // the mean factor over the image's floor points.
    let cam = wavy.world_from_camera(0, 0);
    let c = &wavy.cameras[0];
    let mut fsum = 0.0;
    for j in 0..c.height {
        for i in 0..c.width {
            let dir = cam.transform_vector(DVec3::new(
                (i as f64 + 0.5 - c.cx) / c.fx,
                (j as f64 + 0.5 - c.cy) / c.fy,
                1.0,
            ));
            let t = (-4.0 - cam.translation.z) / dir.z;
            fsum += vol.factor(cam.translation + t * dir);
        }
    }
    let fmean = fsum / (c.width * c.height) as f64;
    eprintln!(
        "flat: mean {ma:.4} sd/mean {:.4}; waves: mean {mb:.4} sd/mean {:.4}; ratio {:.4}; \
         footprint mean factor {fmean:.4}",
        sa / ma,
        sb / mb,
        mb / ma
    );
    // A uniform floor under a flat surface is uniform (pixel noise of the 1-bounce estimate is
    // nil: direct light only, analytic transmittance).
    assert!(sa / ma < 0.02, "flat contrast {}", sa / ma);
    // Under waves: a bright/dark pattern.
    assert!(sb / mb > 0.15, "wavy contrast {}", sb / mb);
    // The image mean follows the pattern's mean over the footprint (to 1 %: pixel jitter of
    // 4 samples against pixel-centre factors) and stays within 5 % of the flat render (a
    // finite footprint samples a finite piece of the pattern).
    assert!(((mb / ma) - fmean).abs() < 0.01, "{} vs {fmean}", mb / ma);
    assert!((mb / ma - 1.0).abs() < 0.05, "ratio {}", mb / ma);
}

#[test]
fn caustics_are_deterministic() {
    let m = seabed(waves());
    let s1 = Scene::build(&m).unwrap();
    let s2 = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| Scene::build(&m).unwrap());
    let (v1, v2) = (s1.caustics.unwrap(), s2.caustics.unwrap());
    for k in 0..PLANES {
        let (p1, p2) = (v1.plane(k), v2.plane(k));
        assert!(
            p1.iter().zip(p2).all(|(a, b)| a.to_bits() == b.to_bits()),
            "plane {k} depends on threads"
        );
    }
    let scene = Scene::build(&m).unwrap();
    let a = render_image(&m, &scene, 0, 0, 2, None).unwrap();
    let b = render_image(&m, &scene, 0, 0, 2, None).unwrap();
    assert!(a.rgb == b.rgb);
    // A different site seed moves the waves; a different render seed (new noise) does not.
    let mut m2 = m.clone();
    m2.site.seed += 1;
    let v3 = Scene::build(&m2).unwrap().caustics.unwrap();
    assert!(v3.plane(PLANES / 2) != v1.plane(PLANES / 2));
    let mut m3 = m.clone();
    m3.render.seed += 1;
    let v4 = Scene::build(&m3).unwrap().caustics.unwrap();
    assert!(v4.plane(PLANES / 2) == v1.plane(PLANES / 2));
}

/// The teaching scene asks for caustics: it loads cleanly, the native renderer builds a caustic
/// volume reaching below its seabed, and Mitsuba refuses it with the clear error (not a crash,
/// not a silently flat sea).
#[test]
fn caustics_scenario_needs_caustics_and_mitsuba_refuses_it() {
    let loaded = poser::scene::load(std::path::Path::new("scenarios/caustics_shallow.toml"), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()));
    assert!(loaded.warnings.is_empty());
    let m = loaded.model;
    assert!(m.needs.caustics);
    assert!(matches!(m.site.surface, SeaSurface::Waves { .. }));
    // The caustic volume alone (the objects' textures, which building the whole scene
    // bakes, play no part in it).
    let mut bare = m.clone();
    bare.objects.clear();
    let scene = Scene::build(&bare).unwrap();
    let v = scene.caustics.as_ref().expect("caustic volume");
    let z = v.planes();
    assert!(*z.last().unwrap() < -m.site.depth && z[0] < 0.0);
    // The seabed plane (4 m) is lit by a visible pattern (contrast measured 1.12 at 4 m for
    // Hs 0.25 m, λp 4 m; > 0.3 leaves room for retuning the scene).
    let k = z
        .iter()
        .enumerate()
        .min_by(|a, b| {
            (a.1 + m.site.depth)
                .abs()
                .total_cmp(&(b.1 + m.site.depth).abs())
        })
        .unwrap()
        .0;
    let (mean, sd) = v.plane_stats(k);
    eprintln!(
        "seabed plane z {:.2}: mean {mean:.4}, contrast {:.3}; volume built in {:.2} s",
        z[k],
        sd / mean,
        v.build_seconds
    );
    assert!(sd / mean > 0.3 && (mean - 1.0).abs() < 0.01);
    let Err(e) = poser::backend::mitsuba::build(&m) else {
        panic!("Mitsuba must refuse waves");
    };
    assert!(
        e.contains("wavy sea surface") && e.contains("cannot be rendered"),
        "{e}"
    );
}
