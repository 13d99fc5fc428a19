//! `poser dive`: dive profile, decompression, gas; Subsurface export.
use super::{CliError, SceneArgs};
use crate::plan::dive::{DiveConfig, DiveReport, DiveResult, Verdict, plan_dive};
use crate::plan::gas::GasCheck;
use crate::plan::gas::depth_limit;
use crate::plan::oxygen::OxygenExposure;
use std::fmt::Write as _;
use std::path::PathBuf;

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
            "  (the scene has no [diver]: a 12 l air cylinder at 200 bar with poser's 50 bar \
             reserve; SAC 20 l/min, GF 30/75 and pO₂ 1.4/1.6 bar are Subsurface's planner defaults)"
        );
    }
    let _ = writeln!(
        o,
        "  survey      {} poses, {} strips, {:.0} m of path at {:.3} m/s → {} at depth",
        model.poses.len(),
        model.network.strips.max(1),
        model.network.path_length,
        c.speed,
        mmss(d.bottom_time)
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
    deco_lines(&mut o, c, d);
    let g = &d.gas;
    gas_lines(&mut o, c, g);
    oxygen_line(&mut o, &d.oxygen);
    for (k, p) in v.lost_gas.iter().enumerate() {
        let _ = writeln!(
            o,
            "  {}{}",
            if k == 0 {
                "lost gas    "
            } else {
                "            "
            },
            crate::plan::dive::lost_gas_line(p)
        );
    }
    verdict_line(&mut o, v, g);
    if v.deco_planned
        && let Some(plan) = &v.deco_plan
    {
        let _ = writeln!(o, "  ✓ {plan}");
    }
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

/// The decompression lines: the model and water, the NDL or where it runs out, the stops.
fn deco_lines(o: &mut String, c: &DiveConfig, d: &DiveResult) {
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
                "              NDL runs out at {} runtime (the ceiling leaves the surface); deepest ceiling {:.1} m",
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
}

/// The gas lines: SAC, reserve and pO₂ limits, one line per cylinder, the gas rules.
fn gas_lines(o: &mut String, c: &DiveConfig, g: &GasCheck) {
    let _ = writeln!(
        o,
        "  gas         SAC {:.0} l/min; {:.0} bar reserve in every cylinder; pO₂ limits {:.1} bar bottom, {:.1} bar deco",
        c.sac_lpm, g.reserve_bar, c.po2_bottom, c.po2_deco
    );
    for (t, u) in c.tanks.iter().zip(&g.cylinders) {
        let sw = depth_limit(t.switch_depth.unwrap_or(0.0));
        let role = match t.role {
            crate::model::CylinderRole::Deco => format!("deco from {sw:.0} m"),
            crate::model::CylinderRole::Travel => format!("travel to and from {sw:.0} m"),
            crate::model::CylinderRole::Bailout => "bailout, not breathed in the plan".into(),
            r => r.name().to_string(),
        };
        let mut flags = Vec::new();
        if !u.po2_ok {
            flags.push("pO₂ TOO HIGH");
        }
        if u.hypoxic {
            flags.push("HYPOXIC");
        }
        if !u.reserve_ok {
            flags.push("RESERVE BROKEN");
        }
        let _ = writeln!(
            o,
            "    '{}' {} ({role}, MOD {:.0} m): {:.1} l at {:.0} bar = {:.0} l, {:.0} l breathed, end {:.0} bar; max pO₂ {} → {}",
            u.name,
            u.gas,
            depth_limit(u.mod_depth),
            t.volume,
            t.fill,
            u.start,
            u.used,
            u.end_pressure,
            u.max_po2
                .map(|p| format!("{p:.2} bar"))
                .unwrap_or_else(|| "— (not breathed)".into()),
            if flags.is_empty() {
                "OK".to_string()
            } else {
                flags.join(", ")
            }
        );
    }
    let _ = writeln!(
        o,
        "              reserve {} · rule of thirds {} · Subsurface minimum gas {}",
        if g.reserve_ok { "kept" } else { "BROKEN" },
        if g.thirds_ok { "kept" } else { "BROKEN" },
        if g.min_gas_ok { "kept" } else { "not kept" }
    );
}

/// The oxygen line: CNS %, OTU and the highest pO₂, each with its flag.
fn oxygen_line(o: &mut String, ox: &OxygenExposure) {
    let cns_flag = if ox.cns_percent > crate::plan::oxygen::CNS_LIMIT {
        "NOT SAFE (> 100 %)"
    } else if ox.cns_percent > crate::plan::oxygen::CNS_WARN {
        "WARNING (> 80 %)"
    } else {
        "OK"
    };
    let otu_flag = if ox.otu > crate::plan::oxygen::OTU_WARN {
        "WARNING (> 300)"
    } else {
        "OK"
    };
    let _ = writeln!(
        o,
        "  oxygen      CNS {:.1} % → {cns_flag} · OTU {:.1} → {otu_flag} · max pO₂ {:.2} bar at {:.1} m{}",
        ox.cns_percent,
        ox.otu,
        ox.max_po2,
        ox.max_po2_depth,
        if ox.max_po2 > crate::plan::oxygen::PO2_TABLE_MAX + 1e-9 {
            " — BEYOND THE 1.6 bar NOAA TABLE"
        } else {
            ""
        }
    );
}

/// The verdict line: OK or not, the NDL or the decompression plan, the gases, the supply.
fn verdict_line(o: &mut String, v: &Verdict, g: &GasCheck) {
    let _ = writeln!(
        o,
        "\nVerdict: {} — {}, {}, {}",
        if v.deco_planned {
            "OK, decompression planned"
        } else if v.ok {
            "OK"
        } else {
            "NOT SAFE AS PLANNED"
        },
        if v.within_ndl {
            "within the NDL"
        } else if v.deco_planned {
            "the decompression plan holds"
        } else {
            "decompression required"
        },
        if v.gases_ok {
            "every gas breathable where breathed".to_string()
        } else {
            let bad: Vec<String> = g
                .cylinders
                .iter()
                .filter(|u| !u.po2_ok || u.hypoxic)
                .map(|u| format!("'{}' ({})", u.name, u.gas))
                .collect();
            format!("gas unfit to breathe in {}", bad.join(", "))
        },
        if v.gas_ok {
            "enough gas".to_string()
        } else {
            let short: Vec<String> = g
                .cylinders
                .iter()
                .filter(|u| !u.reserve_ok)
                .map(|u| format!("'{}' ({})", u.name, u.gas))
                .collect();
            if short.is_empty() {
                "not enough gas (rule of thirds)".to_string()
            } else {
                format!("not enough gas in {}", short.join(", "))
            }
        }
    );
}

/// The arguments of `poser dive`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Subsurface log to write (`.ssrf`).
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Plot of depth, ceiling and NDL over time (`.svg` or `.png`).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, out, plot, json) = (
        &args.scene,
        args.out.as_deref(),
        args.plot.as_deref(),
        args.json,
    );
    if let Some(path) = plot {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if ext != "svg" && ext != "png" {
            return Err(CliError::Usage(format!(
                "--plot {}: the plot is written as SVG or PNG (use a .svg or .png name)",
                path.display()
            )));
        }
    }
    let model = super::load_model(scene)?;
    let report =
        plan_dive(&model, crate::plan::dive::PROFILE_SAMPLE_EVERY).map_err(CliError::Failed)?;
    if let Some(path) = out {
        let bytes = crate::plan::ssrf::to_ssrf(&model, &report).map_err(CliError::Failed)?;
        crate::io::write_atomic(path, &bytes)
            .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = plot {
        let title = format!("{} — dive profile", model.name);
        let png = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        let bytes = if png {
            crate::plan::plot::png(&report, &title)
        } else {
            crate::plan::plot::svg(&report, &title).map(String::into_bytes)
        }
        .map_err(CliError::Failed)?;
        crate::io::write_atomic(path, &bytes)
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
