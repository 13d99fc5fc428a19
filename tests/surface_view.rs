//! A drone's camera above the water looks through the sea surface (`[camera.port] type =
//! "none"` above the crests of a modelled surface). The native renderer's camera rays refract
//! at the flat or wavy surface, and the ground truth solves for the pixel of each target
//! through the same surface (`optics::surface`). Rendered disk centroids (`poser compare
//! --backends native`) must land on the truth; the waves must move the truth by more than the
//! agreement, so a renderer that ignored them would fail. The other backends and observations
//! mode refuse such a camera with a clear error. (Full tier: the renders take a minute.)

use std::process::Command;

const SCENE: &str = "scenarios/lessons/uav_through_waves.toml";

fn poser(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run poser")
}

/// The test geometry: 8 m above the sea, 0.6 m disks (large enough to measure).
fn sets(extra: &[&str]) -> Vec<String> {
    let mut v = vec![
        "network.poses.0.position=[0, 0, 8]".to_string(),
        "targets.0.diameter=\"0.6 m\"".to_string(),
    ];
    v.extend(extra.iter().map(|s| s.to_string()));
    v
}

fn with_sets<'a>(args: &[&'a str], sets: &'a [String]) -> Vec<&'a str> {
    let mut a: Vec<&str> = args.to_vec();
    for s in sets {
        a.push("--set");
        a.push(s);
    }
    a
}

/// (measured, expected, RMS px) of the native render's disks against the truth.
fn compare(extra: &[&str], samples: &str) -> (u64, u64, f64) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cmp");
    let s = sets(extra);
    let o = poser(&with_sets(
        &[
            "compare",
            SCENE,
            "--backends",
            "native",
            "--samples",
            samples,
            "-o",
            out.to_str().unwrap(),
        ],
        &s,
    ));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let b = &j["backends"][0];
    (
        b["targets_measured"].as_u64().unwrap(),
        b["targets_expected"].as_u64().unwrap(),
        b["target_rms_px"].as_f64().unwrap_or(f64::NAN),
    )
}

/// Truth pixels (id → (u, v)) of the scene with `extra` settings.
fn truth(extra: &[&str]) -> std::collections::HashMap<String, (f64, f64)> {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("truth");
    let s = sets(extra);
    let o = poser(&with_sets(
        &["truth", SCENE, "-o", out.to_str().unwrap()],
        &s,
    ));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("points.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (i, u, v) = (col("id"), col("u"), col("v"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[i].to_string(),
                (f[u].parse().unwrap(), f[v].parse().unwrap()),
            )
        })
        .collect()
}

#[test]
fn the_native_render_through_the_surface_lands_on_the_truth() {
    // Sunlit flat sea: the disks land on the truth to a tenth of a pixel (measured 0.07).
    let (m, e, rms) = compare(&["site.surface=\"flat\""], "8");
    assert_eq!(m, e);
    assert!(m >= 10, "{m} disks measured");
    assert!(rms < 0.2, "flat sea, sunlit: RMS {rms} px");
    // Under waves the sun's caustics speckle the plates; light the scene from the sky alone to
    // measure the geometry. Through a flat sea the disks (about 20 px in radius) are ellipses
    // and are located by their edges: 0.066 px at 32 spp, all 12. Through 5 cm waves their
    // outlines are no ellipses (poser::compare::ELLIPSE_MISFIT), so their exact outlines are
    // fitted, shifted (`sectors::outline_edge`): 0.063 px, all 12. (By their area centroids,
    // which the sky light focused by the waves pulls, they had read 0.32 px, 10 of 12; before
    // the edge fit flat and wavy were both centroids, 0.20–0.33 px.)
    let sky = [
        "sun.irradiance=0.000001",
        "lights=[{type=\"ambient\", radiance=30}]",
    ];
    let (mf, _, flat) = compare(&[&["site.surface=\"flat\""][..], &sky[..]].concat(), "32");
    let (mw, _, waves) = compare(
        &[&["site.wave_height=\"0.05 m\""][..], &sky[..]].concat(),
        "32",
    );
    assert!(mf >= 10 && mw >= 10, "{mf} {mw} disks measured");
    assert!(
        flat < 0.15 && waves < 0.15,
        "flat {flat} px, waves {waves} px"
    );
    // The waves move the truth itself far more than that (1.6 px RMS here).
    let a = truth(&["site.surface=\"flat\""]);
    let b = truth(&["site.wave_height=\"0.05 m\""]);
    let d: Vec<f64> = a
        .iter()
        .filter_map(|(k, p)| b.get(k).map(|q| (p.0 - q.0).hypot(p.1 - q.1)))
        .collect();
    assert!(d.len() >= 10);
    let moved = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    assert!(
        moved > 1.0 && moved > 3.0 * waves,
        "moved {moved} px, agreement {waves} px"
    );
}

#[test]
fn backends_and_modes_that_cannot_look_through_the_surface_refuse() {
    let tmp = tempfile::tempdir().unwrap();
    for backend in ["mitsuba", "blender"] {
        let out = tmp.path().join(backend);
        let o = poser(&[
            "compile",
            SCENE,
            "--backend",
            backend,
            "-o",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{backend}: {err}");
        assert!(
            err.contains("looking through the sea") && err.contains("--backend native"),
            "{err}"
        );
        assert!(!out.exists(), "{backend} wrote output");
    }
    let out = tmp.path().join("ev");
    let o = poser(&["evaluate", SCENE, "-o", out.to_str().unwrap(), "--quiet"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("above the sea surface") && err.contains("--mode"),
        "{err}"
    );
    // A camera in a housing above the water is still an error with the drone hint.
    let o = poser(&["validate", SCENE, "--set", "camera.port={type = \"dome\"}"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("E0402") && err.contains("[camera.port] type"),
        "{err}"
    );
}
