//! `poser dive`: dive profile, decompression, gas; Subsurface export.
use super::{CliError, SceneArgs};
use crate::plan::dive::{DiveReport, plan_dive};
use std::fmt::Write as _;
use std::path::Path;

/// Sample interval of the exported profile, s.
const SAMPLE_EVERY: f64 = 10.0;

fn mmss(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

/// Human-readable report.
pub fn text_report(model: &crate::model::Model, r: &DiveReport) -> String {
    let c = &r.config;
    let d = &r.dive;
    let v = &r.verdict;
    let mut o = String::new();
    let _ = writeln!(o, "Dive plan for '{}'", model.name);
    if c.defaulted {
        let _ = writeln!(
            o,
            "  (the scene has no [diver]: Subsurface's defaults are used — 12 l air at 200 bar, \
             SAC 20 l/min, GF 30/75, 50 bar reserve)"
        );
    }
    let _ = writeln!(
        o,
        "  survey      {} poses, {} strips, {:.0} m of path at {:.2} m/s",
        model.poses.len(),
        model.network.strips.max(1),
        model.network.path_length,
        c.speed
    );
    let _ = writeln!(
        o,
        "  profile     descent {} · survey {} · ascent {} · runtime {} · max {:.1} m · mean {:.1} m",
        mmss(d.descent_time),
        mmss(d.bottom_time),
        mmss(d.tts_at_end),
        mmss(d.runtime),
        d.max_depth,
        d.mean_depth
    );
    let _ = writeln!(
        o,
        "  deco        Bühlmann ZHL-16C, GF {:.0}/{:.0}, {} water ({:.0} kg/m³), surface {:.3} bar",
        c.gf.low * 100.0,
        c.gf.high * 100.0,
        if c.env.water_density > 1010.0 {
            "sea"
        } else {
            "fresh"
        },
        c.env.water_density,
        c.env.surface_pressure
    );
    match d.deco_from {
        Some(t) => {
            let _ = writeln!(
                o,
                "              NDL runs out at {} runtime; deepest ceiling {:.1} m",
                mmss(t),
                d.max_ceiling
            );
        }
        None => {
            let _ = writeln!(
                o,
                "              within the NDL (tightest margin {})",
                d.min_ndl.map(mmss).unwrap_or_else(|| "> 120 min".into())
            );
        }
    }
    if d.stops.is_empty() {
        if let Some(s) = d.safety_stop {
            let _ = writeln!(
                o,
                "  stops       safety stop {:.0} m for {}",
                s.depth,
                mmss(s.duration)
            );
        }
    } else {
        let stops: Vec<String> = d
            .stops
            .iter()
            .map(|s| format!("{:.0} m {}", s.depth, mmss(s.duration)))
            .collect();
        let _ = writeln!(o, "  stops       {} (mandatory)", stops.join(", "));
    }
    let g = &d.gas;
    let _ = writeln!(
        o,
        "  gas         {} = {:.0} l; SAC {:.0} l/min → {:.0} l needed; end {:.0} bar (reserve {:.0} bar)",
        c.supply.description, g.start, c.sac_lpm, g.used, g.end_pressure, g.reserve_bar
    );
    let _ = writeln!(
        o,
        "              reserve {} · rule of thirds {} · Subsurface minimum gas {}",
        if g.reserve_ok { "kept" } else { "BROKEN" },
        if g.thirds_ok { "kept" } else { "BROKEN" },
        if g.min_gas_ok { "kept" } else { "not kept" }
    );
    let ok = v.problems.is_empty();
    let _ = writeln!(
        o,
        "\nVerdict: {} — {}, {}",
        if ok { "OK" } else { "NOT SAFE AS PLANNED" },
        if v.within_ndl {
            "within the NDL"
        } else {
            "decompression required"
        },
        if v.gas_ok {
            "enough gas"
        } else {
            "not enough gas"
        }
    );
    for p in &v.problems {
        let _ = writeln!(o, "  ✗ {p}");
    }
    for a in &v.advice {
        let _ = writeln!(o, "  ! {a}");
    }
    if !v.suggestions.is_empty() {
        let _ = writeln!(o, "What would fix it:");
        for s in &v.suggestions {
            let _ = writeln!(o, "  {} {}", if s.fixes_all { "→" } else { "·" }, s.text);
        }
    }
    o
}

pub fn run(
    scene: &SceneArgs,
    out: Option<&Path>,
    plot: Option<&Path>,
    json: bool,
) -> Result<(), CliError> {
    if let Some(path) = plot {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if ext != "svg" {
            return Err(CliError::Usage(format!(
                "--plot {}: only SVG plots are written (use a .svg name)",
                path.display()
            )));
        }
    }
    let model = super::load_model(scene)?;
    let report = plan_dive(&model, SAMPLE_EVERY).map_err(CliError::Failed)?;
    if let Some(path) = out {
        let bytes = crate::plan::ssrf::to_ssrf(&model, &report).map_err(CliError::Failed)?;
        crate::io::write_atomic(path, &bytes)
            .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = plot {
        let svg = crate::plan::plot::svg(&report, &format!("{} — dive profile", model.name))
            .map_err(CliError::Failed)?;
        crate::io::write_atomic(path, svg.as_bytes())
            .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
    }
    if json {
        let s =
            serde_json::to_string_pretty(&report).map_err(|e| CliError::Failed(e.to_string()))?;
        println!("{s}");
    } else {
        print!("{}", text_report(&model, &report));
        if let Some(p) = out {
            println!("wrote {}", p.display());
        }
        if let Some(p) = plot {
            println!("wrote {}", p.display());
        }
    }
    Ok(())
}
