//! `poser bench render` end to end: the speed-against-error report a user regenerates with one
//! command (its JSON, plot and the README's block), on real renders. The native run is in the
//! plain tier; the run with all three backends is in the full tier (`tests/bench_render_backends.rs`).

use crate::support::bench::{bench, poser};
use poser::bench::render::{README_BEGIN, TARGETS};

#[test]
fn native_curve_reaches_both_targets_and_the_readme_block_is_regenerated() {
    let (_dir, report) = bench("clear_strobe", "native");
    assert_eq!(report.scenes.len(), 1);
    let sc = &report.scenes[0];
    assert_eq!(
        (sc.scene.as_str(), sc.width, sc.height),
        ("clear_strobe", 48, 36)
    );
    let c = &sc.curves[0];
    assert_eq!((c.backend.as_str(), c.error.as_deref()), ("native", None));
    // The error falls with the samples at least as a Monte Carlo estimate's does (∝ spp^-½:
    // 4× the samples halve it; 1.5 allows for the reference's own noise), and at most about as
    // fast as a stratified one can on a smooth pixel (∝ spp^-1: 4×). The default Sobol sampler
    // stratifies a pixel's samples: measured 3.49× on this scene; independent samples gave
    // 1.5–2.7× (the bound before Sobol became the default).
    let p = &c.points;
    assert_eq!(p.iter().map(|p| p.spp).collect::<Vec<_>>(), [1, 4]);
    let ratio = p[0].rmse / p[1].rmse;
    assert!((1.5..4.5).contains(&ratio), "RMSE 1 → 4 spp fell {ratio}×");
    // Each target has its spp and time; the smaller target costs more.
    assert_eq!(c.to_target.len(), TARGETS.len());
    let (a, b) = (&c.to_target[0], &c.to_target[1]);
    assert_eq!((a.rmse, b.rmse), (TARGETS[0], TARGETS[1]));
    assert!(b.spp > a.spp && b.seconds > a.seconds && a.seconds >= a.render_seconds);
    // 0.05 vs 0.02 is (5/2)² = 6.25× the samples on the same ∝ spp^-½ law.
    assert!((b.spp / a.spp - 6.25).abs() < 1e-9, "{} {}", a.spp, b.spp);
    assert!(c.core_us_per_path > 0.0 && c.core_us_per_path.is_finite());
    assert!(c.reference_means.iter().all(|&m| m > 0.0));
}

#[test]
fn a_readme_without_the_markers_is_refused_before_any_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let readme = dir.path().join("README.md");
    std::fs::write(&readme, "# no markers here\n").unwrap();
    let json = dir.path().join("render.json");
    let out = poser()
        .args(["bench", "render", "--quick", "--backends", "native"])
        .args(["--only", "clear_strobe", "--readme"])
        .arg(&readme)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("README.md") && err.contains(README_BEGIN),
        "{err}"
    );
    assert!(
        !err.contains("bench render: clear_strobe"),
        "rendered first: {err}"
    );
    assert!(!json.exists());
    assert_eq!(
        std::fs::read_to_string(&readme).unwrap(),
        "# no markers here\n"
    );
}

/// A scene the water column lights is timed twice by native: with the column (the scene's
/// default) and by brute force (`native_traced`); the column's error counts its bias, the
/// difference of the two references' means, so its times are those of a noise target
/// √(e² − b²) on its own curve, and a target under the bias is never reached.
#[test]
fn the_column_is_timed_with_its_bias_against_the_brute_force() {
    use poser::bench::render::{Bias, TRACED, spp_to};
    let (_dir, report) = bench("coral_self_occlusion", "native");
    let sc = &report.scenes[0];
    let names: Vec<&str> = sc.curves.iter().map(|c| c.backend.as_str()).collect();
    assert_eq!(names, ["native", TRACED]);
    let (column, traced) = (&sc.curves[0], &sc.curves[1]);
    assert_eq!(
        (column.daylight.as_str(), traced.daylight.as_str()),
        ("column", "traced")
    );
    assert!(column.error.is_none() && traced.error.is_none());
    let bias = column.bias.expect("the column's bias");
    // (The report went through JSON: equal to its last bit or two.)
    let again = Bias::between(column, traced).unwrap();
    for c in 0..3 {
        assert!(
            (again.relative[c] - bias.relative[c]).abs() < 1e-12,
            "{bias:?}"
        );
        assert!((again.se[c] - bias.se[c]).abs() < 1e-12, "{bias:?}");
    }
    assert!(bias.se.iter().all(|&s| s > 0.0 && s < 0.1), "{bias:?}");
    let b = bias.rms();
    for &t in &TARGETS {
        match column.at(t) {
            Some(x) => {
                let (spp, _) = spp_to(&column.points, (t * t - b * b).sqrt()).unwrap();
                assert!((x.spp - spp).abs() <= 1e-9 * spp, "{t}: {} vs {spp}", x.spp);
            }
            None => assert!(t <= b, "{t} not reached with a bias of {b}"),
        }
    }
    // The summary names the estimator and gives the brute force's times beside it.
    let row = report
        .summary()
        .lines()
        .find(|l| l.starts_with("| `coral_self_occlusion` |"))
        .unwrap()
        .to_string();
    assert!(
        row.contains("| column |") && row.contains(&bias.text()),
        "{row}"
    );
}
