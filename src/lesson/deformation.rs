//! Lesson kind `deformation`: `poser evaluate` in observations mode (its defaults: `opencv`
//! model, 0.3 px noise, seed 1, aligned on all points) on each variant; each variant's full
//! evaluation report goes to `OUT/<variant>/`, the page gets the numbers and the plots.
//!
//! | column | from |
//! |---|---|
//! | images, points, reprojection | COLMAP's bundle adjustment |
//! | focal error | recovered focal length against the in-water-equivalent truth |
//! | RMS Z | tie-point height error after the similarity |
//! | NMAD Z | its robust spread (1.4826 × the median absolute deviation: what RMS would be without outliers) |
//! | maps | `deformation.png` on one colour scale for the whole page (the largest case's 99th percentile of \|dz\|), targets ringed |
//! | warnings | `poser evaluate`'s health checks (images dropped, focal length not determined, outlier-driven RMS), shown under the table |
//! | bowl, bowl share | the quadratic surface fitted to the height errors |

use super::Case;
use crate::evaluate::{self, Options};
use serde::Serialize;
use std::path::Path;

/// One variant's numbers and plots.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    pub command: String,
    pub images: usize,
    pub registered: usize,
    pub points: usize,
    pub reprojection_px: f64,
    pub focal_error_percent: f64,
    pub rms_z_mm: f64,
    pub nmad_z_mm: f64,
    pub bowl_mm: f64,
    pub bowl_share: f64,
    pub seconds: f64,
    /// `poser evaluate`'s health warnings, one line each.
    pub warnings: Vec<String>,
    /// The colour scale shared by every map of the page: ± this many mm.
    pub map_scale_mm: f64,
    /// This case's own range (the 99th percentile of |dz|), mm.
    pub own_scale_mm: f64,
    /// `deformation.png` of `poser evaluate`.
    #[serde(skip)]
    pub map_png: Vec<u8>,
    /// `profile.svg` of `poser evaluate`.
    #[serde(skip)]
    pub profile_svg: String,
}

/// Evaluate every case.
pub fn run(
    cases: &[Case],
    out: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Row>, String> {
    let mut evs = Vec::new();
    for c in cases {
        progress(&format!(
            "evaluating `{}` ({} images)",
            c.label,
            c.model.poses.len()
        ));
        let ev = evaluate::evaluate_observations(&c.model, &Options::default(), &|_, _, _| {})
            .map_err(|e| format!("variant `{}`: {e}", c.label))?;
        evaluate::report::write(&ev, &out.join(&c.slug))?;
        evs.push(ev);
    }
    // One colour scale for every map of the page, so that a bowl of millimetres and one of
    // decimetres do not look alike.
    let scale = evs
        .iter()
        .map(evaluate::report::color_scale)
        .fold(1e-6, f64::max);
    let mut rows = Vec::new();
    for (c, ev) in cases.iter().zip(evs) {
        rows.push(Row {
            label: c.label.clone(),
            command: c.command("evaluate"),
            images: ev.images,
            registered: ev.registered,
            points: ev.points,
            reprojection_px: ev.reprojection_error,
            focal_error_percent: ev.focal_error_percent(),
            rms_z_mm: 1e3 * ev.tie_errors.rms[2],
            nmad_z_mm: 1e3 * ev.tie_errors.robust_z.nmad,
            bowl_mm: ev.bowl.map_or(f64::NAN, |b| 1e3 * b.peak_to_peak),
            bowl_share: ev.bowl.map_or(f64::NAN, |b| b.explained),
            seconds: ev.seconds,
            warnings: ev.warnings.iter().map(|w| w.message.clone()).collect(),
            map_scale_mm: 1e3 * scale,
            own_scale_mm: 1e3 * evaluate::report::color_scale(&ev),
            map_png: evaluate::report::deformation_png_scaled(&ev, scale)?,
            profile_svg: evaluate::report::profile_svg(&ev)?,
        });
    }
    Ok(rows)
}
