//! `poser plan`: survey plan and achieved coverage.
use super::{CliError, SceneArgs};
use crate::plan::survey::{self, CoverageSummary, Site, Stats, SurveyReport};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Serialize)]
struct Output<'a> {
    survey: &'a SurveyReport,
    coverage: Option<CoverageSummary>,
}

fn mm(s: &Option<Stats>, scale: f64, unit: &str, digits: usize) -> String {
    match s {
        Some(s) => format!(
            "{:.d$} {unit} (min {:.d$}, max {:.d$})",
            s.mean * scale,
            s.min * scale,
            s.max * scale,
            d = digits
        ),
        None => "—".into(),
    }
}

fn pct(s: &Option<Stats>) -> String {
    match s {
        Some(s) => format!(
            "{:.0} % (min {:.0} %, max {:.0} %)",
            s.mean * 100.0,
            s.min * 100.0,
            s.max * 100.0
        ),
        None => "—".into(),
    }
}

fn text(model: &crate::model::Model, r: &SurveyReport, cov: Option<&CoverageSummary>) -> String {
    let mut o = String::new();
    let t = r.duration;
    let _ = writeln!(
        o,
        "Survey plan for '{}' ({} network)",
        model.name, r.network
    );
    let _ = writeln!(
        o,
        "  images        {} ({} rig poses × {} camera{}), {} strips",
        r.images,
        r.rig_poses,
        r.cameras,
        if r.cameras == 1 { "" } else { "s" },
        r.strips
    );
    let _ = writeln!(
        o,
        "  path          {:.0} m at {:.2} m/s → survey time {}:{:02} min",
        r.path_length,
        r.speed,
        (t / 60.0).floor() as u64,
        (t % 60.0).round() as u64
    );
    let _ = writeln!(
        o,
        "  GSD           {} through the {} port",
        mm(&r.gsd, 1e3, "mm/px", 3),
        r.port
    );
    if let Some(f) = r.port_gsd_factor {
        let _ = writeln!(
            o,
            "                × {f:.3} of the same lens in air at the same distance (flat port ≈ 1/n magnifies; dome ≈ 1)"
        );
    }
    let _ = writeln!(
        o,
        "  distance      {} to the site along the optical axis",
        mm(&r.distance, 1.0, "m", 2)
    );
    let _ = writeln!(
        o,
        "  footprint     {} across × {} along",
        mm(&r.footprint_across, 1.0, "m", 2),
        mm(&r.footprint_along, 1.0, "m", 2)
    );
    let nominal = |v: Option<f64>| {
        v.map(|v| format!(" (nominal {:.0} %)", v * 100.0))
            .unwrap_or_default()
    };
    let _ = writeln!(
        o,
        "  overlap       {}{} achieved on the site",
        pct(&r.overlap),
        nominal(r.nominal_overlap)
    );
    let _ = writeln!(
        o,
        "  side-lap      {}{} achieved on the site",
        pct(&r.sidelap),
        nominal(r.nominal_sidelap)
    );
    if !r.distance_for_gsd.is_empty() {
        let s: Vec<String> = r
            .distance_for_gsd
            .iter()
            .map(|(g, d)| format!("{:.2} mm/px → {d:.2} m", g * 1e3))
            .collect();
        let _ = writeln!(o, "  height for GSD {}", s.join(", "));
    }
    for n in &r.notes {
        let _ = writeln!(o, "  note: {n}");
    }
    if let Some(c) = cov {
        let _ = writeln!(
            o,
            "  coverage      {} faces{}: unseen {:.1} %, 1 image {:.1} %, 2 images {:.1} %, ≥ 3 images {:.1} % (max {})",
            c.faces,
            if c.on_seabed_grid {
                " of a seabed grid"
            } else {
                ""
            },
            c.unseen * 100.0,
            c.one * 100.0,
            c.two * 100.0,
            c.three_or_more * 100.0,
            c.max_count
        );
    }
    o
}

/// The arguments of `poser plan`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long)]
    pub json: bool,
    /// Also write the coverage map/mesh into this directory.
    #[arg(long)]
    pub coverage: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, json, coverage) = (&args.scene, args.json, args.coverage.as_deref());
    let model = super::load_model(scene)?;
    let site = Site::new(&model);
    let report = survey::survey(&model, &site).map_err(CliError::Failed)?;
    let mut cov_summary = None;
    if let Some(dir) = coverage {
        let cov = survey::coverage(&model, &site).map_err(CliError::Failed)?;
        let ply = dir.join("coverage.ply");
        crate::io::write_atomic(&ply, &cov.ply())
            .map_err(|e| CliError::Failed(format!("{}: {e}", ply.display())))?;
        let png = dir.join("coverage.png");
        let img = cov.map(1024);
        crate::io::write_atomic_with(&png, |p| {
            img.save_with_format(p, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })
        .map_err(CliError::Failed)?;
        cov_summary = Some(cov.summary());
        if !json {
            eprintln!("wrote {} and {}", ply.display(), png.display());
        }
    }
    if json {
        let s = serde_json::to_string_pretty(&Output {
            survey: &report,
            coverage: cov_summary,
        })
        .map_err(|e| CliError::Failed(e.to_string()))?;
        println!("{s}");
    } else {
        print!("{}", text(&model, &report, cov_summary.as_ref()));
    }
    Ok(())
}
