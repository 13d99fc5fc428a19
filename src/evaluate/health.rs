//! Whether an evaluation's numbers mean what they say: the checks that flag a degenerate block
//! before its figures are read as results. Both modes run them; `poser evaluate` prints them,
//! `report.md` and the lesson pages show them, and `--strict` turns them into an error.
//!
//! | code | flags | threshold |
//! |---|---|---|
//! | `registered` | images that dropped out: not seen to have tie points (observations mode) or not registered by COLMAP | fewer than [`MIN_REGISTERED`] of the images |
//! | `focal` | a self-calibrated focal length the block does not determine ([`super::Evaluation::focal_sensitivity`]) | a rise below [`super::FOCAL_DETERMINED`] |
//! | `fit` | a camera model that does not fit the images | a mean reprojection error above [`MAX_REPROJECTION_PX`] |
//! | `outliers` | a height RMS driven by a few far points, not by the block | more than [`MAX_OUTLIERS`] of the tie points beyond 3 NMAD, and RMS Z over twice the NMAD |
//!
//! A perfectly regular network (every image at one height, looking one way: no hand-held
//! jitter) is named in the `focal` warning's help, since that is its usual cause.

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

/// Every pose of camera 0 at the same height and looking the same way (the optical axis to
/// 1 µrad; the heading may turn, as between strips), to 1 µm: a network with no jitter.
/// Self-calibration cannot then separate focal length from height.
pub fn regular_network(model: &Model) -> bool {
    if model.poses.len() < 2 || model.cameras.is_empty() {
        return false;
    }
    let first = model.world_from_camera(0, 0);
    (1..model.poses.len()).all(|p| {
        let w = model.world_from_camera(p, 0);
        (w.translation.z - first.translation.z).abs() < 1e-6
            && (w.rotation.z_axis - first.rotation.z_axis).length() < 1e-6
    })
}

/// The checks on a finished evaluation. `self_calibrated`: COLMAP refined the intrinsics (not
/// a calibrated rig), so the focal probe applies.
pub fn check(model: &Model, ev: &Evaluation, self_calibrated: bool) -> Vec<Warning> {
    let mut out = Vec::new();
    let share = ev.registered as f64 / ev.images.max(1) as f64;
    if share < MIN_REGISTERED {
        let names: Vec<&str> = ev.dropped.iter().take(5).map(String::as_str).collect();
        let more = ev.dropped.len().saturating_sub(names.len());
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
                    format!(
                        "; dropped: {}{}",
                        names.join(", "),
                        if more > 0 {
                            format!(" and {more} more")
                        } else {
                            String::new()
                        }
                    )
                }
            ),
            help: "check that the strips cover the object (`poser plan` draws the footprints), \
                   raise the overlap, or texture the surfaces at the image's GSD"
                .into(),
        });
    }
    if let Some(sens) = ev.focal_sensitivity().filter(|_| self_calibrated)
        && sens < super::FOCAL_DETERMINED
    {
        out.push(Warning {
            code: "focal",
            message: format!(
                "the images do not determine the focal length: holding it 10 % off raises the \
                 reprojection error by {:.3} % (below {:.1} %), so focal length and height trade \
                 and the focal error and the bowl are not measurements",
                100.0 * sens,
                100.0 * super::FOCAL_DETERMINED
            ),
            help: if regular_network(model) {
                "the network is perfectly regular (every image at one height, looking one way): \
                 give the diver's hand-held wobble (`network.jitter_position`, \
                 `jitter_rotation`), add obliques or relief, or calibrate beforehand (`--rig`)"
                    .into()
            } else {
                "add obliques, relief or a second height, or calibrate beforehand (`--rig`)".into()
            },
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
