//! Whether an evaluation's numbers mean what they say: the checks that flag a degenerate block
//! before its figures are read as results. Both modes run them; `poser evaluate` prints them,
//! `report.md` and the lesson pages show them, and `--strict` turns them into an error.
//!
//! | code | flags | threshold |
//! |---|---|---|
//! | `registered` | images that dropped out: not seen to have tie points (observations mode) or not registered by COLMAP | fewer than [`MIN_REGISTERED`] of the images |
//! | `dropped` | images that dropped out, when at least [`MIN_REGISTERED`] are in: how many, their share and the first names | any image missing from the result |
//! | `focal` | a self-calibrated focal length the block does not determine: the focal probe ([`super::Evaluation::focal_sensitivity`]) or the adjustment's covariance ([`super::Evaluation::focal_sd`], [`super::Evaluation::focal_singular`]) | a probe rise below [`super::FOCAL_DETERMINED`], a singular normal matrix, or a standard deviation above [`super::FOCAL_SD_MAX`] per pixel |
//! | `focal_drift` | a self-calibrated focal length far from the nominal (in-water-equivalent) one | beyond ± [`super::FOCAL_DRIFT_MAX`] |
//! | `diverged` | tie points the adjustment ran off to a camera's centre (observations mode), left out of every figure | a point's reprojection error above 100 px and 100 × the median point's (`drop_diverged_points` in `backends/colmap/evaluate.py`) |
//! | `fit` | a camera model that does not fit the images | a mean reprojection error above [`MAX_REPROJECTION_PX`] |
//! | `outliers` | a height RMS driven by a few far points, not by the block | more than [`MAX_OUTLIERS`] of the tie points beyond 3 NMAD, and RMS Z over twice the NMAD |
//!
//! A network of parallel views (every image looking one way, at any height and heading: no
//! hand-held jitter) is named in the `focal` warning's help, since that is its usual cause.

use super::Evaluation;
use crate::model::Model;
use serde::Serialize;

/// Below this share of registered images a block is reported as degenerate.
pub const MIN_REGISTERED: f64 = 0.95;
/// Above this mean reprojection error, px, the camera model does not describe the images (the
/// simulated noise is 0.3 px; a flat port self-calibrated fits to about 0.5–0.7 px).
pub const MAX_REPROJECTION_PX: f64 = 2.0;
/// Above this share of outliers (beyond 3 NMAD) the RMS is not the block's accuracy.
pub const MAX_OUTLIERS: f64 = 0.02;

/// One health warning.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Warning {
    pub code: &'static str,
    pub message: String,
    pub help: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} [{}]\n  help: {}", self.message, self.code, self.help)
    }
}

/// Every pose of camera 0 looking the same way (the optical axis to 1 µrad; the heading may
/// turn, as between strips, and the height change): a network with no jitter. Scaling the
/// focal length and every depth (the world's vertical) by one factor then changes no image,
/// whatever the relief and the cameras' heights (a radial distortion's terms scale with it),
/// so self-calibration cannot separate focal length from height.
pub fn regular_network(model: &Model) -> bool {
    if model.poses.len() < 2 || model.cameras.is_empty() {
        return false;
    }
    let first = model.world_from_camera(0, 0);
    (1..model.poses.len()).all(|p| {
        let w = model.world_from_camera(p, 0);
        (w.rotation.z_axis - first.rotation.z_axis).length() < 1e-6
    })
}

/// The checks on a finished evaluation. `self_calibrated`: COLMAP refined the intrinsics (not
/// a calibrated rig), so the focal checks apply.
pub fn check(model: &Model, ev: &Evaluation, self_calibrated: bool) -> Vec<Warning> {
    checks(ev, self_calibrated, regular_network(model))
}

/// The first five names of `names`, and how many more.
fn first_names(names: &[String]) -> String {
    let shown: Vec<&str> = names.iter().take(5).map(String::as_str).collect();
    let more = names.len().saturating_sub(shown.len());
    if shown.is_empty() {
        return String::new();
    }
    format!(
        "{}{}",
        shown.join(", "),
        if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        }
    )
}

/// [`check`] with the network's regularity given (`regular`: [`regular_network`]).
pub fn checks(ev: &Evaluation, self_calibrated: bool, regular: bool) -> Vec<Warning> {
    let mut out = Vec::new();
    let share = ev.registered as f64 / ev.images.max(1) as f64;
    let lost = ev.images.saturating_sub(ev.registered);
    if share < MIN_REGISTERED {
        let names = first_names(&ev.dropped);
        out.push(Warning {
            code: "registered",
            message: format!(
                "only {} of {} images registered ({:.0} %); the figures describe that part of the \
                 block only{}",
                ev.registered,
                ev.images,
                100.0 * share,
                if names.is_empty() {
                    String::new()
                } else {
                    format!("; dropped: {names}")
                }
            ),
            help: "check that the strips cover the object (`poser plan` draws the footprints), \
                   raise the overlap, or texture the surfaces at the image's GSD"
                .into(),
        });
    } else if lost > 0 {
        let names = first_names(&ev.dropped);
        out.push(Warning {
            code: "dropped",
            message: format!(
                "{lost} of {} images ({:.1} %) dropped out of the result{}; the figures \
                 describe the other {}",
                ev.images,
                100.0 * lost as f64 / ev.images.max(1) as f64,
                if names.is_empty() {
                    String::new()
                } else {
                    format!(" ({names})")
                },
                ev.registered
            ),
            help: "look at where the dropped images are (report.json's `dropped`; `poser plan` \
                   draws the footprints): an image that sees too little of the object, or too \
                   little overlap with its neighbours, leaves the block"
                .into(),
        });
    }
    if self_calibrated {
        focal_checks(ev, regular, &mut out);
    }
    let diverged = ev.diverged_points();
    if diverged > 0 {
        out.push(Warning {
            code: "diverged",
            message: format!(
                "{diverged} tie point(s) diverged in the adjustment (a reprojection error above \
                 100 px and 100 times the median point's: run off to a camera's centre from \
                 their perturbed start) and were left out of every figure"
            ),
            help: "a block that lets points run off is weakly determined: read the focal \
                   checks, and add obliques, relief or control points"
                .into(),
        });
    }
    if ev.reprojection_error > MAX_REPROJECTION_PX {
        out.push(Warning {
            code: "fit",
            message: format!(
                "the camera model does not fit the images: mean reprojection error {:.2} px \
                 (above {MAX_REPROJECTION_PX} px)",
                ev.reprojection_error
            ),
            help: "a pinhole model held at fixed intrinsics cannot describe a flat port's \
                   projection (it is no central projection): let the adjustment calibrate the \
                   camera, or use a dome centred on the lens"
                .into(),
        });
    }
    let z = &ev.tie_errors;
    if z.count >= 20 && z.robust_z.outliers > MAX_OUTLIERS && z.rms[2] > 2.0 * z.robust_z.nmad {
        out.push(Warning {
            code: "outliers",
            message: format!(
                "RMS Z {:.2} mm is driven by {:.1} % of points beyond 3 NMAD; the core of the \
                 errors has median {:+.2} mm and NMAD {:.2} mm",
                1e3 * z.rms[2],
                100.0 * z.robust_z.outliers,
                1e3 * z.robust_z.median,
                1e3 * z.robust_z.nmad
            ),
            help: "read the robust figures (median, NMAD, LE90) as the block's accuracy; the \
                   outliers are listed in errors.csv"
                .into(),
        });
    }
    out
}

/// The `focal` warning (the block does not determine the focal length: the probe, or the
/// adjustment's covariance) and the `focal_drift` warning (the self-calibrated focal length far
/// from the nominal one).
fn focal_checks(ev: &Evaluation, regular: bool, out: &mut Vec<Warning>) {
    let mut evidence = Vec::new();
    if ev.focal_singular() {
        evidence.push(
            "the adjustment's normal matrix is singular (rank deficient) in the camera and the \
             poses, so some change of focal length and poses leaves every image as it is"
                .to_string(),
        );
    } else if let Some(sd) = ev.focal_sd()
        && sd > super::FOCAL_SD_MAX
    {
        evidence.push(format!(
            "the adjustment's covariance gives the focal length a standard deviation of {:.2} % \
             per pixel of image noise (above {:.0} %)",
            100.0 * sd,
            100.0 * super::FOCAL_SD_MAX
        ));
    }
    if let Some(sens) = ev.focal_sensitivity()
        && sens < super::FOCAL_DETERMINED
    {
        evidence.push(format!(
            "holding it 10 % off raises the reprojection error by {:.3} % (below {:.1} %)",
            100.0 * sens,
            100.0 * super::FOCAL_DETERMINED
        ));
    }
    if !evidence.is_empty() {
        out.push(Warning {
            code: "focal",
            message: format!(
                "the images do not determine the focal length: {}; focal length and height \
                 trade, so the focal error and the bowl are not measurements",
                evidence.join("; ")
            ),
            help: if regular {
                "every image looks the same way (parallel views, at any height: scaling the \
                 focal length and every depth by one factor changes no image, relief or not): \
                 give the diver's hand-held wobble (`network.jitter_rotation`), add obliques, \
                 or calibrate beforehand (`--rig`)"
                    .into()
            } else {
                "add obliques or views tilted more, or calibrate beforehand (`--rig`)".into()
            },
        });
    }
    if let Some(c) = ev
        .cameras
        .iter()
        .filter(|c| c.focal_error.abs() > super::FOCAL_DRIFT_MAX)
        .max_by(|a, b| a.focal_error.abs().total_cmp(&b.focal_error.abs()))
    {
        out.push(Warning {
            code: "focal_drift",
            message: format!(
                "camera `{}` self-calibrated to a focal length {:+.1} % off the nominal one \
                 ({:.1} px against {:.1} px in water, {:.1} px in air; beyond ±{:.0} %): the \
                 adjustment bent the block to fit a wrong camera",
                c.name,
                100.0 * c.focal_error,
                0.5 * (c.recovered[0] + c.recovered[1]),
                0.5 * (c.truth[0] + c.truth[1]),
                c.f_air,
                100.0 * super::FOCAL_DRIFT_MAX
            ),
            help: "a camera's focal length in water is about n_water × f behind a flat port and \
                   f behind a centred dome; one this far off says the block does not hold it: \
                   add obliques, relief or the diver's wobble, or calibrate beforehand (`--rig`)"
                .into(),
        });
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::evaluate::align::{AxisStats, Similarity};
    use crate::evaluate::colmap::CameraModel;
    use crate::evaluate::{CameraEval, Mode};

    /// A sound block as the flat port's quick form gives it (measured: 330 of 330 images,
    /// focal +1.02 %, probe rise 930 %, covariance 0.08 % per px).
    pub(crate) fn healthy() -> Evaluation {
        Evaluation {
            scene: "test".into(),
            mode: Mode::Observations,
            camera_model: CameraModel::Opencv,
            conventions: "",
            settings: serde_json::Value::Null,
            images: 330,
            registered: 330,
            points: 1414,
            observations: 10000,
            mean_track_length: 7.5,
            reprojection_error: 0.485,
            cameras: vec![CameraEval {
                name: "cam".into(),
                f_air: 3000.0,
                truth: [3992.6, 3992.6, 3000.0, 2000.0],
                distance: 1.2,
                recovered: [4033.5, 4033.0, 3000.0, 2000.0],
                extra: Vec::new(),
                focal_error: 0.0102,
            }],
            alignment: "all points".into(),
            alignment_count: 1414,
            gcp_sigma: None,
            similarity: Similarity::identity(),
            tie_errors: AxisStats::default(),
            check_errors: None,
            control_errors: None,
            camera_errors: AxisStats::default(),
            bowl: None,
            colmap: serde_json::json!({
                "focal_sensitivity": 9.3, "focal_sd": 0.00075, "focal_covariance": "ok"
            }),
            dropped: Vec::new(),
            warnings: Vec::new(),
            seconds: 1.0,
            point_errors: Vec::new(),
            centres: Vec::new(),
        }
    }

    fn codes(ev: &Evaluation, regular: bool) -> Vec<&'static str> {
        checks(ev, true, regular).iter().map(|w| w.code).collect()
    }

    #[test]
    fn a_sound_block_gives_no_warning() {
        assert_eq!(codes(&healthy(), false), Vec::<&str>::new());
        assert_eq!(healthy().focal_determined(), Some(true));
    }

    #[test]
    fn dropped_images_warn_with_their_count_share_and_names() {
        // One image of 330 out: a `dropped` warning naming it, with its share.
        let mut ev = healthy();
        ev.registered = 329;
        ev.dropped = vec!["img_0007".into()];
        let w = checks(&ev, true, false);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].code, "dropped");
        assert!(
            w[0].message.contains("1 of 330 images (0.3 %)") && w[0].message.contains("img_0007"),
            "{}",
            w[0].message
        );
        // 25 of 330 (the strips moved off the plot, measured): `registered`, with five names.
        ev.registered = 25;
        ev.dropped = (0..305).map(|k| format!("img_{k:04}")).collect();
        let w = checks(&ev, true, false);
        assert_eq!(w[0].code, "registered", "{w:?}");
        assert!(
            w[0].message
                .contains("only 25 of 330 images registered (8 %)")
                && w[0].message.contains("img_0004 and 300 more"),
            "{}",
            w[0].message
        );
        assert!(w[0].to_string().contains("\n  help: "));
    }

    #[test]
    fn diverged_points_warn_with_their_count() {
        // Measured: the Moorea plot with 20° obliques left one point at 1e149 px.
        let mut ev = healthy();
        ev.colmap["diverged_points"] = serde_json::json!(1);
        let w = checks(&ev, true, false);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].code, "diverged");
        assert!(
            w[0].message.starts_with("1 tie point(s) diverged"),
            "{}",
            w[0].message
        );
    }

    /// A network is regular when every view looks one way, whatever the heights: reef_strip as
    /// shipped (a diver's wobble) is not; flown without jitter it is; with its positions
    /// jittered (heights varying) but its views parallel it still is, since scaling the focal
    /// length and the world's vertical by one factor changes none of its images.
    #[test]
    fn parallel_views_make_a_regular_network_at_any_height() {
        let load = |sets: &[&str]| {
            let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
            crate::scene::load(std::path::Path::new("scenarios/reef_strip.toml"), &sets)
                .map_err(|f| f.render())
                .unwrap()
                .model
        };
        assert!(!regular_network(&load(&[])));
        assert!(regular_network(&load(&[
            "network.jitter_position=0",
            "network.jitter_rotation=0"
        ])));
        let heights = load(&["network.jitter_rotation=0"]);
        let z: Vec<f64> = (0..heights.poses.len())
            .map(|p| heights.world_from_camera(p, 0).translation.z)
            .collect();
        let spread =
            z.iter().cloned().fold(f64::MIN, f64::max) - z.iter().cloned().fold(f64::MAX, f64::min);
        assert!(spread > 0.05, "heights spread {spread} m");
        assert!(regular_network(&heights));
    }

    #[test]
    fn each_sign_of_an_undetermined_focal_length_warns() {
        // The dome flown without jitter (measured): singular normal matrix, probe −0.003 %,
        // focal +75 %: `focal`, naming the regular network, and `focal_drift`.
        let mut ev = healthy();
        ev.colmap = serde_json::json!({
            "focal_sensitivity": -2.8e-5, "focal_sd": null, "focal_covariance": "rank_deficient"
        });
        ev.cameras[0].focal_error = 0.752;
        let w = checks(&ev, true, true);
        assert_eq!(
            w.iter().map(|w| w.code).collect::<Vec<_>>(),
            ["focal", "focal_drift"]
        );
        assert!(w[0].message.contains("singular") && w[0].message.contains("-0.003 %"));
        assert!(w[0].help.contains("jitter_rotation"), "{}", w[0].help);
        assert!(w[1].message.contains("+75.2 %"), "{}", w[1].message);
        assert_eq!(ev.focal_determined(), Some(false));
        // The flat port flown without jitter (measured): the probe passes (24.8 %), the
        // covariance does not (8.9 % per px), and the focal length is −59.5 % off.
        ev.colmap = serde_json::json!({
            "focal_sensitivity": 0.248, "focal_sd": 0.0889, "focal_covariance": "ok"
        });
        ev.cameras[0].focal_error = -0.595;
        let w = checks(&ev, true, true);
        assert_eq!(
            w.iter().map(|w| w.code).collect::<Vec<_>>(),
            ["focal", "focal_drift"]
        );
        assert!(
            w[0].message.contains("8.89 % per pixel"),
            "{}",
            w[0].message
        );
        assert!(!w[0].message.contains("holding it"), "{}", w[0].message);
        // Each sign alone warns; the drift alone is its own warning.
        for (summary, drift, want) in [
            (
                serde_json::json!({"focal_sensitivity": 9.3, "focal_sd": 0.02}),
                0.01,
                vec!["focal"],
            ),
            (
                serde_json::json!({"focal_sensitivity": 0.001, "focal_sd": 0.0008}),
                0.01,
                vec!["focal"],
            ),
            (
                serde_json::json!({"focal_sensitivity": 9.3, "focal_sd": 0.0008}),
                -0.12,
                vec!["focal_drift"],
            ),
        ] {
            ev.colmap = summary.clone();
            ev.cameras[0].focal_error = drift;
            assert_eq!(codes(&ev, false), want, "{summary} {drift}");
        }
        // A calibrated rig is not probed: no focal warning whatever the numbers.
        assert!(checks(&ev, false, true).is_empty());
    }
}
