//! The sensor stage (`poser::sensor`, docs/sensor.md): its noise has the variance the model
//! predicts, it is deterministic at any thread count, exposure/white balance/clipping/tone do
//! what the documentation says, the sidecar carries what was applied, and the native renderer's
//! per-pixel variance agrees with the spread of independent renders.

use poser::model::*;
use poser::sensor::{self, Linear};
use std::path::Path;

/// A flat field where every channel's mean signal is `mu` electrons at exposure `e`.
fn flat(e: &sensor::Exposure, mu: f64, w: u32, h: u32) -> Linear {
    let l = [0, 1, 2].map(|c| (mu / e.electrons_per_radiance[c]) as f32);
    Linear {
        width: w,
        height: h,
        rgb: vec![l; (w * h) as usize],
    }
}

/// A sensor with a fine ADC (16 bits, black level 1024 DN, gain ≈ 4.3 DN/e⁻) so that
/// quantisation (1/(12 G²) ≈ 0.005 e⁻²) is negligible against the noise measured.
fn fine_sensor(read_noise: f64) -> Sensor {
    Sensor {
        bits: 16,
        black_level: 1024,
        read_noise,
        exposure: SensorExposure::Manual,
        ..Sensor::default()
    }
}

/// Mean and variance of the raw signal converted back to electrons, per image.
fn electron_stats(s: &Sensor, e: &sensor::Exposure, raw: &sensor::Raw) -> (f64, f64) {
    let g = e.dn_per_electron;
    let v: Vec<f64> = raw
        .dn
        .iter()
        .flat_map(|p| p.map(|d| (d as f64 - s.black_level as f64) / g))
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

#[test]
fn shot_noise_has_the_poisson_variance_within_5_percent() {
    // 512×512 pixels × 3 channels = 786 432 samples per level: the variance's relative
    // standard error is √(2/N) ≈ 0.16 %, so 5 % is 30 standard errors while half the noise
    // (a quarter of the variance) or a missing √ fails at once. Levels on both sides of the
    // exact-Poisson / Gaussian switch (64 e⁻).
    // The few-electron levels are taken at ISO 6400 (275 DN/e⁻), so that the ADC's rounding
    // of whole electrons (≤ 0.5/G e⁻) cannot bias the variance of a Poisson count.
    let dummy = Linear {
        width: 1,
        height: 1,
        rgb: vec![[1.0; 3]],
    };
    for (k, (mu, iso)) in [
        (5.0, 6400.0),
        (40.0, 6400.0),
        (500.0, 100.0),
        (5000.0, 100.0),
    ]
    .into_iter()
    .enumerate()
    {
        let s = Sensor {
            iso,
            ..fine_sensor(0.0)
        };
        let e = sensor::expose(&s, &dummy, 4e-6);
        let img = flat(&e, mu, 512, 512);
        let raw = sensor::capture(&s, &e, &img, 1000 + k as u64);
        let (mean, var) = electron_stats(&s, &e, &raw);
        let predicted = mu + 1.0 / (12.0 * e.dn_per_electron.powi(2));
        eprintln!(
            "shot noise μ = {mu} e⁻: variance / model = {:.4}",
            var / predicted
        );
        assert!(
            (mean - mu).abs() < 0.01 * mu + 0.05,
            "μ = {mu}: mean {mean}"
        );
        assert!(
            (var / predicted - 1.0).abs() < 0.05,
            "μ = {mu} e⁻: variance {var} e⁻², the model predicts {predicted}"
        );
    }
}

#[test]
fn read_noise_has_its_rms_within_5_percent_alone_and_with_shot_noise() {
    let s = fine_sensor(5.0);
    let dummy = Linear {
        width: 1,
        height: 1,
        rgb: vec![[1.0; 3]],
    };
    let e = sensor::expose(&s, &dummy, 4e-6);
    for (mu, seed) in [(0.0, 7u64), (2000.0, 8)] {
        let img = flat(&e, mu, 512, 512);
        let raw = sensor::capture(&s, &e, &img, seed);
        let (_, var) = electron_stats(&s, &e, &raw);
        let predicted = mu + 25.0 + 1.0 / (12.0 * e.dn_per_electron.powi(2));
        eprintln!(
            "read noise 5 e⁻ at μ = {mu} e⁻: std / model = {:.4}",
            (var / predicted).sqrt()
        );
        assert!(
            (var.sqrt() / predicted.sqrt() - 1.0).abs() < 0.05
                && (var / predicted - 1.0).abs() < 0.05,
            "μ = {mu}: std {} e⁻, predicted {}",
            var.sqrt(),
            predicted.sqrt()
        );
    }
}

#[test]
fn the_noise_scales_with_iso_gain_in_dn_but_not_in_electrons() {
    // At ISO 400 one electron is 4× the DN: the DN variance is 16× larger for the same μ.
    let mut s = fine_sensor(0.0);
    s.bits = 16;
    let dummy = Linear {
        width: 1,
        height: 1,
        rgb: vec![[1.0; 3]],
    };
    let e100 = sensor::expose(&s, &dummy, 4e-6);
    s.iso = 400.0;
    let e400 = sensor::expose(&s, &dummy, 4e-6);
    assert!((e400.dn_per_electron / e100.dn_per_electron - 4.0).abs() < 1e-12);
    assert!((e400.full_scale_electrons - s.full_well / 4.0).abs() < 1e-9);
    let img = flat(&e400, 1000.0, 256, 256);
    let raw = sensor::capture(&s, &e400, &img, 3);
    let (_, var) = electron_stats(&s, &e400, &raw);
    assert!((var / 1000.0 - 1.0).abs() < 0.05, "variance {var}");
}

fn textured(w: u32, h: u32) -> Linear {
    let rgb = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let t = 0.5 + 0.4 * (x * 0.3).sin() * (y * 0.2).cos();
            [0.2 * t, 1.0 * t, 0.6 * t]
        })
        .collect();
    Linear {
        width: w,
        height: h,
        rgb,
    }
}

fn camera_bytes(s: &Sensor, img: &Linear, seed: u64) -> Vec<u8> {
    let e = sensor::expose(s, img, 4e-6);
    let raw = sensor::capture(s, &e, img, seed);
    let rgb8 = sensor::develop(s, &e, &raw);
    sensor::encode(s, img.width, img.height, &rgb8, &[]).unwrap()
}

#[test]
fn the_camera_file_is_the_same_bytes_at_any_thread_count() {
    let img = textured(97, 61);
    for s in [
        Sensor::default(),
        Sensor {
            format: SensorFormat::Png,
            ..Sensor::default()
        },
    ] {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| camera_bytes(&s, &img, 42));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| camera_bytes(&s, &img, 42));
        assert_eq!(one, two, "bytes differ between 1 and 2 threads");
        assert_eq!(one, camera_bytes(&s, &img, 42), "bytes differ between runs");
        assert_ne!(one, camera_bytes(&s, &img, 43), "the seed changes nothing");
    }
    // Seeds differ between images and between cameras.
    let a = sensor::image_seed(0, 0, 0);
    assert_ne!(a, sensor::image_seed(0, 1, 0));
    assert_ne!(a, sensor::image_seed(0, 0, 1));
    assert_ne!(a, sensor::image_seed(1, 0, 0));
}

fn noiseless() -> Sensor {
    Sensor {
        noise: false,
        exposure: SensorExposure::Manual,
        white_balance: WhiteBalance::None,
        tone: ToneCurve::Linear,
        format: SensorFormat::Png,
        ..Sensor::default()
    }
}

#[test]
fn quantisation_clipping_and_tone_curves() {
    let s = noiseless();
    let dummy = Linear {
        width: 1,
        height: 1,
        rgb: vec![[1.0; 3]],
    };
    let e = sensor::expose(&s, &dummy, 4e-6);
    let g = e.dn_per_electron;
    // 40 % of the full well at base ISO: 40 % of the ADC range above black.
    let img = flat(&e, 0.4 * s.full_well, 4, 4);
    let raw = sensor::capture(&s, &e, &img, 0);
    let half = (0.4 * s.full_well * g + s.black_level as f64).round() as u16;
    assert!(raw.dn.iter().all(|p| *p == [half; 3]));
    assert_eq!(raw.clipped_fraction, 0.0);
    let x = (half as f64 - s.black_level as f64) / (4095.0 - s.black_level as f64);
    let lin = sensor::develop(&s, &e, &raw);
    assert!(
        lin.iter().all(|&v| v == (x * 255.0).round() as u8),
        "{}",
        lin[0]
    );
    let srgb = sensor::develop(
        &Sensor {
            tone: ToneCurve::Srgb,
            ..s.clone()
        },
        &e,
        &raw,
    );
    // IEC 61966-2-1 at 0.4: 1.055·0.4^(1/2.4) − 0.055 = 0.6652 → 170.
    assert!((x - 0.4).abs() < 1e-3);
    assert_eq!(srgb[0], 170);
    let gamma = sensor::develop(
        &Sensor {
            tone: ToneCurve::Gamma(2.2),
            ..s.clone()
        },
        &e,
        &raw,
    );
    assert_eq!(gamma[0], (x.powf(1.0 / 2.2) * 255.0).round() as u8);
    // Twice the full well: every pixel saturates at the ADC maximum and reads white.
    let img = flat(&e, 2.0 * s.full_well, 4, 4);
    let raw = sensor::capture(&s, &e, &img, 0);
    assert_eq!(raw.clipped_fraction, 1.0);
    assert!(raw.dn.iter().all(|p| *p == [4095; 3]));
    assert!(sensor::develop(&s, &e, &raw).iter().all(|&v| v == 255));
    // ISO 800 saturates the ADC at 1/8 of the full well.
    let s8 = Sensor {
        iso: 800.0,
        ..s.clone()
    };
    let e8 = sensor::expose(&s8, &dummy, 4e-6);
    let raw = sensor::capture(&s8, &e8, &flat(&e8, 0.2 * s.full_well, 4, 4), 0);
    assert_eq!(raw.clipped_fraction, 1.0);
    // Negative or non-finite radiance reads as black (black level), never NaN.
    let bad = Linear {
        width: 2,
        height: 1,
        rgb: vec![[f32::NAN, -1.0, f32::INFINITY], [0.0; 3]],
    };
    let raw = sensor::capture(&s, &e, &bad, 0);
    assert!(raw.dn.iter().all(|p| *p == [s.black_level as u16; 3]));
}

#[test]
fn white_balance_grey_world_fixed_and_capped() {
    let s = Sensor {
        white_balance: WhiteBalance::GreyWorld,
        ..noiseless()
    };
    let k1 = sensor::electrons_per_radiance_second(&s, 4e-6);
    // Raw channel means in the ratio 1 : 4 : 2 → gains 4, 1, 2 (the largest channel keeps 1).
    let img = Linear {
        width: 2,
        height: 1,
        rgb: vec![
            [
                (0.5 / k1[0]) as f32,
                (2.0 / k1[1]) as f32,
                (1.0 / k1[2]) as f32,
            ],
            [
                (1.5 / k1[0]) as f32,
                (6.0 / k1[1]) as f32,
                (3.0 / k1[2]) as f32,
            ],
        ],
    };
    let e = sensor::expose(&s, &img, 4e-6);
    for (g, want) in e.white_balance_gains.iter().zip([4.0, 1.0, 2.0]) {
        assert!((g - want).abs() < 1e-4, "{:?}", e.white_balance_gains);
    }
    // A red channel at 1/50 of green: the automatic gain stops at the documented limit.
    let deep = Linear {
        width: 1,
        height: 1,
        rgb: vec![[
            (0.02 / k1[0]) as f32,
            (1.0 / k1[1]) as f32,
            (1.0 / k1[2]) as f32,
        ]],
    };
    let e = sensor::expose(&s, &deep, 4e-6);
    assert_eq!(e.white_balance_gains[0], sensor::GREY_WORLD_MAX_GAIN);
    let fixed = Sensor {
        white_balance: WhiteBalance::Fixed([2.0, 1.0, 1.5]),
        ..s.clone()
    };
    assert_eq!(
        sensor::expose(&fixed, &deep, 4e-6).white_balance_gains,
        [2.0, 1.0, 1.5]
    );
    // The gain multiplies the developed value: 1000 DN above black reads 1000/4031 in green,
    // twice that in red, 1.5 times in blue.
    let e = sensor::expose(&fixed, &deep, 4e-6);
    let raw = sensor::Raw {
        width: 1,
        height: 1,
        dn: vec![[1064; 3]],
        clipped_fraction: 0.0,
    };
    let out = sensor::develop(&fixed, &e, &raw);
    let x = 1000.0 / 4031.0;
    assert_eq!(
        out,
        [2.0 * x, x, 1.5 * x].map(|v: f64| (v * 255.0).round() as u8)
    );
}

#[test]
fn auto_exposure_puts_the_metered_value_at_the_target() {
    let img = textured(64, 48);
    let pitch = 4e-6;
    // Highlights: the 99th percentile of the brightest white-balanced channel at 85 %.
    let s = Sensor {
        white_balance: WhiteBalance::None,
        ..noiseless()
    };
    let s = Sensor {
        exposure: SensorExposure::Auto {
            meter: Meter::Highlights,
            percentile: 0.99,
            target: 0.85,
        },
        ..s
    };
    let e = sensor::expose(&s, &img, pitch);
    assert_eq!(e.mode, "auto");
    let brightest: Vec<f64> = img
        .rgb
        .iter()
        .map(|p| {
            (0..3)
                .map(|c| e.electrons_per_radiance[c] * p[c] as f64)
                .fold(0.0, f64::max)
        })
        .collect();
    let p99 = sensor::percentile(brightest.clone(), 0.99).unwrap();
    assert!((p99 / (0.85 * s.full_well) - 1.0).abs() < 1e-9, "{p99}");
    let above = brightest.iter().filter(|&&v| v > p99).count() as f64 / brightest.len() as f64;
    assert!(above <= 0.01, "{above}");
    // The shutter time is the one the photon count implies.
    let k1 = sensor::electrons_per_radiance_second(&s, pitch);
    assert!((e.electrons_per_radiance[1] / (k1[1] * e.shutter) - 1.0).abs() < 1e-12);
    // Average: the mean luminance at 18 %.
    let sa = Sensor {
        exposure: SensorExposure::Auto {
            meter: Meter::Average,
            percentile: 0.99,
            target: 0.18,
        },
        ..s.clone()
    };
    let e = sensor::expose(&sa, &img, pitch);
    let luma = [0.2126, 0.7152, 0.0722];
    let mean = img
        .rgb
        .iter()
        .map(|p| {
            (0..3)
                .map(|c| luma[c] * e.electrons_per_radiance[c] * p[c] as f64)
                .sum::<f64>()
        })
        .sum::<f64>()
        / img.rgb.len() as f64;
    assert!((mean / (0.18 * sa.full_well) - 1.0).abs() < 1e-9, "{mean}");
    // A black image cannot be metered: the manual shutter is used and said so.
    let black = Linear {
        width: 2,
        height: 2,
        rgb: vec![[0.0; 3]; 4],
    };
    let e = sensor::expose(&s, &black, pitch);
    assert_eq!(e.shutter, s.shutter);
    assert!(e.note.is_some());
}

#[test]
fn photon_count_follows_the_camera_equation() {
    // 1 W/(m²·sr) at 550 nm, f/8, 4 µm pixels, τ = 0.9, QE 0.55, 10 ms:
    // E = π·τ·L/(4N²) = 0.01104 W/m²; energy per pixel = E·A·t = 1.767e-15 J;
    // photons = energy·λ/(hc) = 4891; electrons = 0.55 × that = 2690.
    let s = Sensor::default();
    let k = sensor::electrons_per_radiance_second(&s, 4e-6);
    let expect = 0.55 * 0.9 * 16e-12 * std::f64::consts::PI / (4.0 * 64.0) * 0.01 * 550e-9
        / (6.626_070_15e-34 * 299_792_458.0);
    assert!((k[1] * 0.01 / expect - 1.0).abs() < 1e-12);
    assert!((k[1] * 0.01 - 2690.0).abs() < 2.0, "{}", k[1] * 0.01);
}

#[test]
fn the_sidecar_records_what_was_applied() {
    let dir = tempfile::tempdir().unwrap();
    let img = textured(32, 24);
    let var = Linear {
        width: 32,
        height: 24,
        rgb: img
            .rgb
            .iter()
            .map(|p| p.map(|x| (0.05 * x).powi(2)))
            .collect(),
    };
    let s = Sensor::default();
    // The scene's camera with 4 µm pixels, 32 × 24 of them.
    let mut cam = crate::support::scenario("calibration_flat.toml").cameras[0].clone();
    (cam.width, cam.height, cam.pixel_pitch) = (32, 24, 4e-6);
    (cam.fx, cam.fy) = (cam.focal_length / 4e-6, cam.focal_length / 4e-6);
    let done = sensor::files::process(
        &s,
        &img,
        Path::new("in.exr"),
        Some(&var),
        Some(16),
        &cam,
        99,
        dir.path(),
        "img_0001",
    )
    .unwrap();
    assert!(dir.path().join("img_0001.jpg").is_file());
    let decoded = image::open(dir.path().join("img_0001.jpg")).unwrap();
    assert_eq!((decoded.width(), decoded.height()), (32, 24));
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("img_0001.sensor.json")).unwrap(),
    )
    .unwrap();
    for key in [
        "/sensor/full_well",
        "/sensor/read_noise",
        "/sensor/quantum_efficiency",
        "/sensor/bits",
        "/sensor/tone/curve",
        "/exposure/shutter",
        "/exposure/f_number",
        "/exposure/iso",
        "/exposure/electrons_per_radiance",
        "/exposure/dn_per_electron",
        "/exposure/white_balance_gains",
        "/seed",
        "/clipped_fraction",
        "/render_noise/relative_median",
        "/render_noise/relative_p95",
        "/render_noise/electrons_median",
        "/render_noise/sensor_electrons_median",
        "/render_noise/ratio_median",
        "/render_noise/ratio_p95",
        "/render_noise/ratio_rms",
        "/render_noise/samples_needed",
        "/pixel_convention",
    ] {
        assert!(json.pointer(key).is_some(), "sidecar lacks {key}: {json:#}");
    }
    assert_eq!(json["seed"], 99);
    // 5 % relative render noise everywhere.
    let rn = done.sidecar.render_noise.unwrap();
    assert!((rn.relative_median - 0.05).abs() < 1e-6);
    // Render noise 5 % of a signal of thousands of electrons is far above its shot noise.
    assert!(rn.ratio_median > 1.0 && done.warning.is_some());
    assert!(rn.ratio_rms > 1.0);
    let worst = rn.ratio_median.max(rn.ratio_rms);
    let n = rn.samples_needed.unwrap() as f64;
    assert!((n / (16.0 * worst.powi(2)) - 1.0).abs() < 0.01);
}

// ---- the native renderer's variance, and the CLI -------------------------------------------

fn poser(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn render_with_a_sensor_writes_camera_images_and_sidecars_and_without_one_nothing_more() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain");
    let cam = dir.path().join("cam");
    // calibration_flat has no [sensor]; --sensor (and any `sensor.` override) turns it on.
    let base = [
        "render",
        "scenarios/calibration_flat.toml",
        "--scale",
        "0.03",
        "--samples",
        "4",
        "--poses",
        "0",
        "--quiet",
    ];
    let o = poser(&[&base[..], &["-o", plain.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!plain.join("camera").exists());
    assert!(!plain.join("img_0001.variance.exr").exists());
    let o = poser(
        &[
            &base[..],
            &[
                "-o",
                cam.to_str().unwrap(),
                "--sensor",
                "--set",
                "sensor.format=\"png\"",
                "--set",
                "sensor.iso=400",
            ],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    // The linear truth and its preview are the same bytes with or without the sensor stage.
    for f in ["img_0001.exr", "img_0001.png"] {
        assert_eq!(
            std::fs::read(plain.join(f)).unwrap(),
            std::fs::read(cam.join(f)).unwrap(),
            "{f} changed"
        );
    }
    assert!(cam.join("img_0001.variance.exr").is_file());
    let png = image::open(cam.join("camera/img_0001.png")).unwrap();
    let preview = image::open(plain.join("img_0001.png")).unwrap();
    assert_eq!(
        (png.width(), png.height()),
        (preview.width(), preview.height())
    );
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(cam.join("camera/img_0001.sensor.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["sensor"]["iso"], 400.0);
    assert!(json["render_noise"]["ratio_median"].as_f64().unwrap() > 0.0);
    assert!(err.contains("sensor: 1 camera image"), "{err}");
    // The standalone command makes the same image from the same EXR.
    let again = dir.path().join("again.png");
    let o = poser(&[
        "sensor",
        "scenarios/calibration_flat.toml",
        "--set",
        "sensor.format=\"png\"",
        "--set",
        "sensor.iso=400",
        cam.join("img_0001.exr").to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(&again).unwrap(),
        std::fs::read(cam.join("camera/img_0001.png")).unwrap()
    );
    assert!(dir.path().join("again.sensor.json").is_file());
}

// ---- EXIF -----------------------------------------------------------------------------------

/// The EXIF fields of an image file, read back with an independent reader (kamadak-exif).
fn exif_of(path: &Path) -> exif::Exif {
    let f = std::fs::File::open(path).unwrap();
    exif::Reader::new()
        .read_from_container(&mut std::io::BufReader::new(f))
        .unwrap_or_else(|e| panic!("{}: no EXIF ({e})", path.display()))
}

fn exif_f64(x: &exif::Exif, tag: exif::Tag) -> f64 {
    let f = x
        .get_field(tag, exif::In::PRIMARY)
        .unwrap_or_else(|| panic!("no {tag}"));
    match &f.value {
        exif::Value::Rational(v) => v[0].to_f64(),
        v => v.get_uint(0).unwrap_or_else(|| panic!("{tag}: {v:?}")) as f64,
    }
}

fn exif_str(x: &exif::Exif, tag: exif::Tag) -> String {
    let f = x
        .get_field(tag, exif::In::PRIMARY)
        .unwrap_or_else(|| panic!("no {tag}"));
    match &f.value {
        exif::Value::Ascii(v) => String::from_utf8_lossy(&v[0]).into_owned(),
        v => panic!("{tag}: {v:?}"),
    }
}

#[test]
fn camera_images_carry_the_lens_and_sensor_in_exif_jpeg_and_png() {
    // A 48 × 36 native render of calibration_flat (8 mm lens, 1600 × 1200 pixels of 3.45 µm):
    // the JPEG from `poser render --sensor`, the PNG from `poser sensor` on the same EXR.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = poser(&[
        "render",
        "scenarios/calibration_flat.toml",
        "--scale",
        "0.03",
        "--samples",
        "1",
        "--poses",
        "0",
        "--quiet",
        "--sensor",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = dir.path().join("again.png");
    let o = poser(&[
        "sensor",
        "scenarios/calibration_flat.toml",
        out.join("img_0001.exr").to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The scene's lens and sensor, at full resolution.
    let cam = crate::support::scenario("calibration_flat.toml").cameras[0].clone();
    let f_mm = cam.focal_length * 1e3;
    let sensor_mm = [
        cam.width as f64 * cam.pixel_pitch * 1e3,
        cam.height as f64 * cam.pixel_pitch * 1e3,
    ];
    let f35 = f_mm * 36f64.hypot(24.0) / sensor_mm[0].hypot(sensor_mm[1]);
    assert!((f_mm - 8.0).abs() < 1e-9 && (sensor_mm[0] - 5.52).abs() < 1e-9);
    for file in [out.join("camera/img_0001.jpg"), png] {
        let x = exif_of(&file);
        let img = image::open(&file).unwrap();
        let (w, h) = (img.width(), img.height());
        assert_eq!(exif_str(&x, exif::Tag::Make), "poser");
        assert_eq!(exif_str(&x, exif::Tag::Model), "poser camera");
        assert_eq!(
            exif_str(&x, exif::Tag::Software),
            format!("poser {}", env!("CARGO_PKG_VERSION"))
        );
        let focal = exif_f64(&x, exif::Tag::FocalLength);
        assert!(
            (focal / f_mm - 1.0).abs() < 1e-6,
            "{file:?}: FocalLength {focal}"
        );
        // 8 mm on a 5.52 × 4.14 mm sensor (diagonal 6.9 mm): 50.2 mm equivalent, written 50.
        let eq = exif_f64(&x, exif::Tag::FocalLengthIn35mmFilm);
        assert_eq!(eq, f35.round(), "{file:?}: 35 mm equivalent {eq} for {f35}");
        assert_eq!(exif_f64(&x, exif::Tag::FocalPlaneResolutionUnit), 3.0);
        // Pixels per cm × the sensor's size in cm = the image's pixels: the sensor is the
        // scene's, whatever the preview scale.
        for (k, tag) in [
            exif::Tag::FocalPlaneXResolution,
            exif::Tag::FocalPlaneYResolution,
        ]
        .into_iter()
        .enumerate()
        {
            let ppcm = exif_f64(&x, tag);
            let px = [w, h][k] as f64;
            assert!(
                (ppcm * sensor_mm[k] / 10.0 / px - 1.0).abs() < 0.02,
                "{file:?}: {tag} {ppcm} px/cm on {} mm for {px} px",
                sensor_mm[k]
            );
        }
        // Across, where the width sets the scale exactly: FocalLength × pixels per mm = fx.
        let fx = f_mm * exif_f64(&x, exif::Tag::FocalPlaneXResolution) / 10.0;
        let fx_true = cam.fx * w as f64 / cam.width as f64;
        assert!(
            (fx / fx_true - 1.0).abs() < 1e-6,
            "{fx} px against {fx_true}"
        );
        assert_eq!(exif_f64(&x, exif::Tag::PixelXDimension), w as f64);
        assert_eq!(exif_f64(&x, exif::Tag::PixelYDimension), h as f64);
        assert!(
            x.get_field(exif::Tag::DateTime, exif::In::PRIMARY)
                .is_none()
        );
    }
}
