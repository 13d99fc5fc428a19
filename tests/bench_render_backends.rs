//! `poser bench render` with all three backends (full tier): one curve each on the same image,
//! whose converged references agree.

use crate::support::bench::bench;
use poser::bench::render::TARGETS;

/// The three backends time the same image: one curve each, and their converged references
/// agree on the mean.
#[test]
fn every_backend_has_a_curve_on_the_same_image() {
    let (_dir, report) = bench("strobe_backscatter", "native,mitsuba,blender");
    let sc = &report.scenes[0];
    let names: Vec<&str> = sc.curves.iter().map(|c| c.backend.as_str()).collect();
    assert_eq!(names, ["native", "mitsuba", "blender"]);
    let native = sc.curves[0].reference_means;
    for c in &sc.curves {
        assert_eq!(c.error, None, "{}", c.backend);
        assert_eq!(c.to_target.len(), TARGETS.len(), "{}", c.backend);
        for (ch, (m, n)) in c.reference_means.iter().zip(native).enumerate() {
            let d = m / n - 1.0;
            assert!(d.abs() < 0.05, "{} channel {ch}: {d:+.3}", c.backend);
        }
    }
    let (wall, render) = sc.speedup(TARGETS[1]);
    assert!(wall.is_some() && render.is_some());
}
