//! `poser bench evaluate`: the cost of `poser evaluate` in observations mode on the deformation
//! lessons, with the numbers each run produced. CPU time counts poser and the COLMAP process it
//! waits for (user + system), so it does not depend on how busy the machine is.
//!
//! | form | scenes |
//! |---|---|
//! | `--quick` | every `scenarios/lessons/*deformation*.toml` variant and `in_air.toml`, on the 10 × 5 m quick form |
//! | full | `flat_port_deformation.toml` as shipped: about 2500 images over 55 × 7 m |

use crate::evaluate::{Options, evaluate_observations};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// One measured evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub scene: String,
    pub form: &'static str,
    pub images: usize,
    pub points: usize,
    pub wall_s: f64,
    pub cpu_s: f64,
    pub reprojection_px: f64,
    pub focal_error_percent: f64,
    pub rms_z_mm: f64,
    pub bowl_mm: f64,
    pub bowl_share: f64,
}

/// CPU seconds (user + system) of this process and of its waited-for children.
pub fn cpu_seconds() -> f64 {
    rusage_seconds(libc::RUSAGE_SELF) + rusage_seconds(libc::RUSAGE_CHILDREN)
}

/// CPU seconds (user + system) of this process alone, every thread.
pub fn self_cpu_seconds() -> f64 {
    rusage_seconds(libc::RUSAGE_SELF)
}

/// User + system seconds of `who` (`RUSAGE_SELF`, `RUSAGE_CHILDREN`); 0 where unavailable.
fn rusage_seconds(who: libc::c_int) -> f64 {
    // SAFETY: getrusage only writes the struct we hand it.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(who, &mut u) } != 0 {
        return 0.0;
    }
    [u.ru_utime, u.ru_stime]
        .iter()
        .map(|t| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6)
        .sum()
}

const QUICK: [&str; 6] = [
    "in_air",
    "flat_port_deformation_pupil_1mm",
    "flat_port_deformation",
    "flat_port_deformation_pupil_10cm",
    "flat_port_deformation_obliques",
    "flat_port_deformation_dome",
];

/// Evaluate the lessons (quick forms, or the full flat-port lesson) found under `lessons`.
pub fn run(lessons: &Path, quick: bool) -> Result<Vec<Row>, String> {
    let (scenes, sets, form): (Vec<&str>, Vec<String>, &'static str) = if quick {
        (
            QUICK.to_vec(),
            vec!["network.length=10".into(), "network.width=5".into()],
            "quick",
        )
    } else {
        (vec!["flat_port_deformation"], vec![], "full")
    };
    let mut rows = Vec::new();
    for name in scenes {
        let path = lessons.join(format!("{name}.toml"));
        let model = crate::scene::load(&path, &sets)
            .map_err(|f| f.render())?
            .model;
        let (t0, c0) = (std::time::Instant::now(), cpu_seconds());
        let ev = evaluate_observations(&model, &Options::default(), &|_, _, _| {})?;
        let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        eprintln!("{name}: {cpu:.1} s CPU");
        rows.push(Row {
            scene: name.to_string(),
            form,
            images: ev.images,
            points: ev.points,
            wall_s: wall,
            cpu_s: cpu,
            reprojection_px: ev.reprojection_error,
            focal_error_percent: ev.focal_error_percent(),
            rms_z_mm: 1e3 * ev.tie_errors.rms[2],
            bowl_mm: ev.bowl.map_or(f64::NAN, |b| 1e3 * b.peak_to_peak),
            bowl_share: ev.bowl.map_or(f64::NAN, |b| b.explained),
        });
    }
    Ok(rows)
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scene | form | images | points | CPU | wall | reprojection | focal error | RMS Z | bowl | bowl share |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1} s | {:.1} s | {:.2} px | {:+.2} % | {:.2} mm | {:.1} mm | {:.0} % |",
            r.scene,
            r.form,
            r.images,
            r.points,
            r.cpu_s,
            r.wall_s,
            r.reprojection_px,
            r.focal_error_percent,
            r.rms_z_mm,
            r.bowl_mm,
            100.0 * r.bowl_share
        );
    }
    s
}
