//! Lesson kinds `dive` and `survey`: the survey planner and the dive planner on each variant,
//! as `poser plan` and `poser dive` run them (the library, not the command line), and for
//! `survey` also `poser evaluate` in observations mode aligned on the targets (GCPs). One
//! module for both kinds: the dive report is the same, `survey` adds the accuracy columns.
//!
//! | number | from |
//! |---|---|
//! | images, strips, path, survey time, GSD, camera distance | [`crate::plan::survey::survey`] (`poser plan`) |
//! | NDL run-out, stops, deco time, TTS, runtime, gas per cylinder, verdict, problems, remedies | [`crate::plan::dive::plan_dive`] (`poser dive`): the planner's own verdict, never re-derived here |
//! | dives needed | 1 when the planner's verdict is OK; else the planner's split ([`crate::plan::dive::max_strips`], [`crate::plan::dive::split`]): the fewest dives, a full cylinder each, repetitive tissues across its surface interval, every dive OK |
//! | contrast left | `exp(−c·r)` in green: the share of a target's contrast that survives the water path `r` (the plan's mean camera distance) at the water's extinction `c = a + b` (Duntley's contrast reduction) |
//! | view (`survey`) | the native renderer's image from the pose nearest the site's centre, at a twentieth of the camera's resolution and 32 samples per pixel (the camera's 8-bit file when the scene has a `[sensor]`, else the preview): a picture, not a number |
//! | accuracy (`survey`) | `poser evaluate` observations mode, its defaults but aligned on the target points (`--gcp`): RMS error of the tie points, 3D and per axis |
//! | rule of thumb | the first case's first bottom cylinder and SAC: minutes to empty and to the reserve at 15 m, 40 m and each case's depth, with poser's gas model, beside the ideal-gas rule `V·P / (SAC·(1 + d/10))` |

use super::Case;
use crate::evaluate::{self, Options};
use crate::plan::dive::{self, DiveConfig, DiveReport, Track};
use crate::plan::gas::{self, gas_label};
use crate::plan::survey::{self, Site};
use serde::Serialize;
use std::path::Path;

/// Depths of the rule-of-thumb table the exercise asks for, m (each case's depth is added).
pub const RULE_DEPTHS: [f64; 2] = [15.0, 40.0];

/// One cylinder as the dive used it.
#[derive(Debug, Clone, Serialize)]
pub struct CylinderRow {
    pub name: String,
    pub gas: String,
    /// Water volume, l; fill, bar.
    pub volume_l: f64,
    pub fill_bar: f64,
    /// Free gas at fill and breathed, l at 1 atm.
    pub start_l: f64,
    pub used_l: f64,
    pub end_bar: f64,
    pub reserve_ok: bool,
}

/// One dive of the planner's split.
#[derive(Debug, Clone, Serialize)]
pub struct SplitRow {
    pub first_strip: usize,
    pub last_strip: usize,
    pub survey_min: f64,
    pub runtime_min: f64,
    /// End pressure of the back gas, bar.
    pub end_bar: f64,
    pub safety_stop: bool,
}

/// `poser evaluate`'s answer (kind `survey`).
#[derive(Debug, Clone, Serialize)]
pub struct Accuracy {
    pub images: usize,
    pub registered: usize,
    pub points: usize,
    pub reprojection_px: f64,
    /// `gcp` (target points) or `all points` when the targets are too few.
    pub alignment: String,
    pub alignment_count: usize,
    /// Tie points after the alignment, mm.
    pub rms_3d_mm: f64,
    pub rms_xyz_mm: [f64; 3],
    pub focal_error_percent: f64,
    /// Scale of the similarity onto the truth, minus one, ppm: how far the block's own scale
    /// (the calibrated rig's baseline, or the gauge) is off.
    pub scale_error_ppm: f64,
    pub seconds: f64,
}

/// One variant's numbers and plot.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub label: String,
    /// `poser dive …` for this case alone.
    pub command: String,
    pub images: usize,
    pub strips: u32,
    pub path_m: f64,
    pub speed_m_s: f64,
    pub survey_min: f64,
    pub max_depth_m: f64,
    /// GSD at the centre ray's hit, mm/px, and the mean camera distance, m.
    pub gsd_mm: Option<f64>,
    pub distance_m: Option<f64>,
    /// `exp(−c·r)` in green at the mean camera distance.
    pub contrast_left: Option<f64>,
    pub gases: String,
    pub gf: String,
    /// Minutes into the survey at which the NDL runs out; `None`: it does not.
    pub ndl_runs_out_min: Option<f64>,
    /// Smallest NDL left while not in deco, min (`None`: unlimited throughout).
    pub min_ndl_min: Option<f64>,
    /// Mandatory stops as (depth m, min), their total, and the time to surface at the end of
    /// the bottom time, min.
    pub stops: Vec<(f64, f64)>,
    pub deco_min: f64,
    pub tts_min: f64,
    pub runtime_min: f64,
    pub cylinders: Vec<CylinderRow>,
    /// The planner's verdict.
    pub ok: bool,
    pub deco_required: bool,
    pub gas_ok: bool,
    pub problems: Vec<String>,
    pub advice: Vec<String>,
    pub suggestions: Vec<String>,
    /// Dives needed: 1 when `ok`, else the planner's split (`None`: no split fits).
    pub dives: Option<usize>,
    pub split: Vec<SplitRow>,
    pub surface_interval_min: f64,
    pub accuracy: Option<Accuracy>,
    pub seconds: f64,
    /// The rendered view (PNG, `survey`).
    #[serde(skip)]
    pub view_png: Vec<u8>,
    /// The dive profile (`poser dive --plot`).
    #[serde(skip)]
    pub profile_svg: String,
}

/// One line of the rule of thumb.
#[derive(Debug, Clone, Serialize)]
pub struct RuleRow {
    pub depth_m: f64,
    /// Ambient pressure, bar.
    pub ambient_bar: f64,
    /// Ideal-gas rule `V·P / (SAC·(1 + d/10))`, min.
    pub rule_min: f64,
    /// poser's gas model (real gas, the water's density): to empty and to the reserve, min.
    pub to_empty_min: f64,
    pub to_reserve_min: f64,
}

/// How long one cylinder lasts, by depth.
#[derive(Debug, Clone, Serialize)]
pub struct RuleOfThumb {
    pub cylinder: String,
    pub gas: String,
    pub volume_l: f64,
    pub fill_bar: f64,
    /// Free gas at fill, l (real gas).
    pub contents_l: f64,
    pub sac_lpm: f64,
    pub reserve_bar: f64,
    pub salt_water: bool,
    pub rows: Vec<RuleRow>,
}

/// Everything a `dive` or `survey` lesson measured.
#[derive(Debug, Clone, Serialize)]
pub struct Results {
    pub rows: Vec<Row>,
    pub rule_of_thumb: RuleOfThumb,
}

fn minutes(s: f64) -> f64 {
    s / 60.0
}

/// How long the first bottom cylinder of `cfg` lasts at `depths` at its SAC.
pub fn rule_of_thumb(cfg: &DiveConfig, depths: &[f64]) -> RuleOfThumb {
    let tank = &cfg.tanks[cfg.bottom_order()[0]];
    let env = cfg.env;
    let contents = gas::contents(tank.gas, tank.volume, tank.fill);
    let reserve = gas::contents(tank.gas, tank.volume, cfg.reserve_bar.min(tank.fill));
    let rows = depths
        .iter()
        .map(|&d| {
            let p = env.pressure(d);
            let per_min = gas::consumption(cfg.sac_lpm, p, 60.0);
            RuleRow {
                depth_m: d,
                ambient_bar: p,
                rule_min: tank.volume * tank.fill / (cfg.sac_lpm * (1.0 + d / 10.0)),
                to_empty_min: contents / per_min,
                to_reserve_min: (contents - reserve).max(0.0) / per_min,
            }
        })
        .collect();
    RuleOfThumb {
        cylinder: tank.name.clone(),
        gas: gas_label(tank.gas),
        volume_l: tank.volume,
        fill_bar: tank.fill,
        contents_l: contents,
        sac_lpm: cfg.sac_lpm,
        reserve_bar: cfg.reserve_bar,
        salt_water: env.water_density > 1010.0,
        rows,
    }
}

/// Plan, dive (and for `evaluate`, evaluate) every case.
pub fn run(
    cases: &[Case],
    out: &Path,
    evaluate: bool,
    full: bool,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Results, String> {
    let mut rows = Vec::new();
    let mut depths: Vec<f64> = RULE_DEPTHS.to_vec();
    for c in cases {
        let t0 = std::time::Instant::now();
        let m = &c.model;
        let err = |e: String| format!("variant `{}`: {e}", c.label);
        progress(&format!(
            "planning `{}` ({} images)",
            c.label,
            m.poses.len()
        ));
        let plan = survey::survey(m, &Site::new(m)).map_err(err)?;
        let report: DiveReport =
            dive::plan_dive(m, crate::plan::dive::PROFILE_SAMPLE_EVERY).map_err(err)?;
        let (cfg, d, v) = (&report.config, &report.dive, &report.verdict);
        // Dives needed: the planner's own split when one dive is not OK.
        let track = Track::from_model(m).map_err(err)?;
        let split = if v.ok {
            None
        } else {
            match dive::max_strips(cfg, &track) {
                0 => None,
                k => dive::split(cfg, &track, k, None),
            }
        };
        let dives = if v.ok {
            Some(1)
        } else {
            split.as_ref().map(|s| s.len())
        };
        let distance = plan.distance.map(|s| s.mean);
        let contrast_left = match (&m.water, distance) {
            (Some(w), Some(r)) => Some((-w.extinction()[1] * r).exp()),
            _ => None,
        };
        let accuracy = if evaluate {
            progress(&format!(
                "evaluating `{}` ({} images)",
                c.label,
                m.poses.len()
            ));
            let opts = Options {
                gcp: !m.targets.is_empty(),
                ..Options::default()
            };
            Some(accuracy(m, &opts, &out.join(&c.slug)).map_err(err)?)
        } else {
            None
        };
        let view_png = if evaluate {
            progress(&format!("rendering a view of `{}`", c.label));
            case_view(c, out, full).map_err(err)?
        } else {
            Vec::new()
        };
        let title = format!("{} — dive profile", c.label);
        let profile_svg = crate::plan::plot::svg(&report, &title)?;
        let depth = d.max_depth.round();
        if !depths.iter().any(|x| (x - depth).abs() < 0.5) {
            depths.push(depth);
        }
        rows.push(Row {
            label: c.label.clone(),
            command: c.command("dive"),
            images: plan.images,
            strips: plan.strips,
            path_m: plan.path_length,
            speed_m_s: plan.speed,
            survey_min: minutes(d.bottom_time),
            max_depth_m: d.max_depth,
            gsd_mm: plan.gsd.map(|s| 1e3 * s.mean),
            distance_m: distance,
            contrast_left,
            gases: gas_column(cfg),
            gf: format!("{:.0}/{:.0}", 100.0 * cfg.gf.low, 100.0 * cfg.gf.high),
            ndl_runs_out_min: d.deco_from.map(|t| minutes(t - d.descent_time)),
            min_ndl_min: d.min_ndl.map(minutes),
            stops: d
                .stops
                .iter()
                .map(|s| (s.depth, minutes(s.duration)))
                .collect(),
            // (`+ 0.0`: an empty sum is −0.0)
            deco_min: minutes(d.stops.iter().map(|s| s.duration).sum::<f64>() + 0.0),
            tts_min: minutes(d.tts_at_end),
            runtime_min: minutes(d.runtime),
            cylinders: cylinder_rows(cfg, d),
            ok: v.ok,
            deco_required: v.deco_required,
            gas_ok: v.gas_ok,
            problems: v.problems.clone(),
            advice: v.advice.clone(),
            suggestions: v.suggestions.iter().map(|s| s.text.clone()).collect(),
            dives,
            split: split_rows(&split.unwrap_or_default()),
            surface_interval_min: minutes(cfg.surface_interval),
            accuracy,
            seconds: t0.elapsed().as_secs_f64(),
            view_png,
            profile_svg,
        });
    }
    let first = cases
        .first()
        .ok_or("the lesson has no case to run")?
        .model
        .clone();
    let cfg = DiveConfig::from_model(&first)?;
    depths.sort_by(f64::total_cmp);
    Ok(Results {
        rows,
        rule_of_thumb: rule_of_thumb(&cfg, &depths),
    })
}

/// The gas column of a case: each cylinder's name, gas, volume and fill.
fn gas_column(cfg: &DiveConfig) -> String {
    let bottom_gases: Vec<String> = cfg
        .tanks
        .iter()
        .map(|t| {
            format!(
                "{}: {}, {:.0} l at {:.0} bar",
                t.name,
                gas_label(t.gas),
                t.volume,
                t.fill
            )
        })
        .collect();
    bottom_gases.join(" + ")
}

/// Each cylinder of a dive: its gas, contents, what was breathed and what is left.
fn cylinder_rows(cfg: &DiveConfig, d: &crate::plan::dive::DiveResult) -> Vec<CylinderRow> {
    d.gas
        .cylinders
        .iter()
        .zip(&cfg.tanks)
        .map(|(u, t)| CylinderRow {
            name: u.name.clone(),
            gas: u.gas.clone(),
            volume_l: t.volume,
            fill_bar: t.fill,
            start_l: u.start,
            used_l: u.used,
            end_bar: u.end_pressure,
            reserve_ok: u.reserve_ok,
        })
        .collect()
}

/// The dives of the planner's split: their strips, times, end pressure and safety stop.
fn split_rows(split: &[crate::plan::dive::SplitDive]) -> Vec<SplitRow> {
    split
        .iter()
        .map(|s| SplitRow {
            first_strip: s.first_strip,
            last_strip: s.last_strip,
            survey_min: minutes(s.dive.bottom_time),
            runtime_min: minutes(s.dive.runtime),
            end_bar: s.dive.gas.end_pressure,
            safety_stop: s.dive.safety_stop.is_some(),
        })
        .collect()
}

/// The rendered view of case `c` (into its folder under `out`): the quick or the full form's
/// scale and samples.
fn case_view(c: &Case, out: &Path, full: bool) -> Result<Vec<u8>, String> {
    let (scale, samples) = if full {
        (VIEW_SCALE, VIEW_SAMPLES)
    } else {
        (VIEW_SCALE_QUICK, VIEW_SAMPLES_QUICK)
    };
    view(&c.model, &out.join(&c.slug).join("view"), scale, samples)
}

/// `poser evaluate` (observations mode) on `m` with `opts`; its report is written into `dir`.
pub fn accuracy(m: &crate::model::Model, opts: &Options, dir: &Path) -> Result<Accuracy, String> {
    let ev = evaluate::evaluate_observations(m, opts, &|_, _, _| {})?;
    evaluate::report::write(&ev, dir)?;
    Ok(Accuracy {
        images: ev.images,
        registered: ev.registered,
        points: ev.points,
        reprojection_px: ev.reprojection_error,
        alignment: ev.alignment.clone(),
        alignment_count: ev.alignment_count,
        rms_3d_mm: 1e3 * ev.tie_errors.rms_3d,
        rms_xyz_mm: ev.tie_errors.rms.map(|x| 1e3 * x),
        focal_error_percent: ev.focal_error_percent(),
        scale_error_ppm: 1e6 * (ev.similarity.scale - 1.0),
        seconds: ev.seconds,
    })
}

/// Scale of the rendered view against the camera's resolution, and its samples per pixel in the
/// full form.
pub const VIEW_SCALE: f64 = 0.05;
pub const VIEW_SAMPLES: u32 = 32;
/// The quick form's views: half the scale and a quarter of the samples, a sixteenth of the
/// cost (a turbid variant's view, strobes random-walking 114 scatterings, took 30 s of CPU at
/// the full form's size; the views were three quarters of the archaeology lesson's quick form).
pub const VIEW_SCALE_QUICK: f64 = 0.025;
pub const VIEW_SAMPLES_QUICK: u32 = 8;

/// Render the pose nearest the site's centre (xy) with the native renderer at
/// `scale` of its resolution and `samples` per pixel into `dir` (through the scene's sensor, if
/// any); return the PNG.
pub fn view(
    model: &crate::model::Model,
    dir: &Path,
    scale: f64,
    samples: u32,
) -> Result<Vec<u8>, String> {
    use crate::backend::{Backend, RenderOptions};
    let centre = model
        .poses
        .iter()
        .map(|p| p.world_from_rig.translation)
        .fold(glam::DVec3::ZERO, |a, b| a + b)
        / model.poses.len().max(1) as f64;
    let pose = (0..model.poses.len())
        .min_by(|&a, &b| {
            let d = |i: usize| {
                let t = model.poses[i].world_from_rig.translation - centre;
                t.x.hypot(t.y)
            };
            d(a).total_cmp(&d(b))
        })
        .ok_or("the network has no poses")?;
    let mut small = model.clone().with_resolution_scale(scale);
    // The solved water column where it applies, as for the page's image ([`super::view`]):
    // a turbid variant's many-times-scattered daylight is what makes a traced preview slow.
    small.render.daylight = crate::model::Daylight::Auto;
    let opts = RenderOptions {
        samples: Some(samples),
        poses: Some(vec![pose]),
        progress: false,
        resume: false,
    };
    let steps = crate::pipeline::Steps {
        truth: false,
        camera: true,
    };
    crate::pipeline::run(&small, Backend::Native, dir, &opts, steps)?;
    // The camera's own file when the scene has a [sensor] (auto exposure, white balance),
    // else the renderer's preview.
    let png_in = |d: &Path| {
        std::fs::read_dir(d).ok().and_then(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .find(|p| p.extension().is_some_and(|x| x == "png"))
        })
    };
    let png = png_in(&dir.join("camera"))
        .or_else(|| png_in(dir))
        .ok_or_else(|| format!("{}: the renderer wrote no PNG", dir.display()))?;
    std::fs::read(&png).map_err(|e| format!("{}: {e}", png.display()))
}

/// `m:ss` of minutes.
pub fn mmss(min: f64) -> String {
    let s = (min * 60.0).max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

/// The verdict as the page shows it: the planner's words.
pub fn verdict_text(r: &Row) -> &'static str {
    if r.ok { "OK" } else { "NOT SAFE AS PLANNED" }
}

/// The lesson's section of the page (numbers, rule of thumb, per-case plots and the planner's
/// words); `survey` adds GSD, contrast and accuracy columns.
pub fn html(res: &Results, survey: bool) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    s.push_str(
        "<h2>The numbers</h2>\n<p>Each case is planned as <code>poser plan</code> and \
         <code>poser dive</code> plan it (Bühlmann ZHL-16C with gradient factors, gas cylinder \
         by cylinder). The verdict is the dive planner's: OK only within the NDL, every gas \
         breathable where it is breathed, the reserve in every cylinder and the rule of thirds \
         kept. <i>Dives needed</i> is the planner's split of the strips into the fewest dives \
         that are each OK, a full cylinder each, with repetitive-dive tissues across the \
         surface interval.</p>\n<table><tr><th>case</th><th>images</th><th>strips</th>\
         <th>path, m</th><th>survey, min</th><th>depth, m</th>",
    );
    if survey {
        s.push_str("<th>GSD, mm/px</th><th>contrast left</th>");
    }
    s.push_str(
        "<th>NDL runs out, min into the survey</th><th>stops</th><th>deco, min</th>\
         <th>TTS, min</th><th>gas</th><th>breathed, l</th><th>end, bar</th><th>verdict</th>\
         <th>dives needed</th>",
    );
    if survey {
        s.push_str("<th>accuracy RMS 3D, mm</th><th>X, Y, Z, mm</th>");
    }
    s.push_str("</tr>\n");
    for r in &res.rows {
        number_row(&mut s, r, survey);
    }
    s.push_str("</table>\n");
    if let Some(r) = res.rows.first() {
        let _ = write!(
            s,
            "<p class=\"small\">Gradient factors {}; surface interval between split dives {:.0} \
             min. Breathed and end pressure per cylinder, in the order of the gas column.",
            r.gf, r.surface_interval_min
        );
        if survey {
            s.push_str(
                " <i>Contrast left</i>: e<sup>−c·r</sup> in green, the share of a target's \
                 contrast that survives the water path r from the camera (the plan's mean \
                 distance) at the water's extinction c. \
                 <i>Accuracy</i>: <code>poser \
                 evaluate</code> in observations mode (exact refractive projections with 0.3 px \
                 noise, COLMAP's self-calibrating bundle adjustment with a camera model that \
                 ignores the port) aligned on the targets as GCPs; the RMS error of the tie \
                 points. Observations mode models the geometry, not the image: turbidity does \
                 not change its number — its cost is the contrast left and, when the camera \
                 must go closer to keep it, the images, the dives and the gas.",
            );
        }
        s.push_str("</p>\n");
    }
    rule_of_thumb_table(&mut s, &res.rule_of_thumb);
    s.push_str("<h2>The dives</h2>\n");
    for r in &res.rows {
        dive_section(&mut s, r);
    }
    s
}

/// One row of the numbers table: the case's plan, dive and (with `survey`) image columns.
fn number_row(s: &mut String, r: &Row, survey: bool) {
    use super::html::{escape, num};
    use std::fmt::Write as _;
    let k = super::slug(&r.label);
    let stops = if r.stops.is_empty() {
        "none".to_string()
    } else {
        r.stops
            .iter()
            .map(|(d, t)| format!("{d:.0} m {}", mmss(*t)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = write!(
        s,
        "<tr><td>{}</td>{}{}{}{}{}",
        escape(&r.label),
        num(&format!("{k}.images"), r.images.to_string()),
        num(&format!("{k}.strips"), r.strips.to_string()),
        num(&format!("{k}.path_m"), format!("{:.0}", r.path_m)),
        num(&format!("{k}.survey_min"), format!("{:.1}", r.survey_min)),
        num(&format!("{k}.max_depth_m"), format!("{:.1}", r.max_depth_m)),
    );
    if survey {
        let _ = write!(
            s,
            "{}{}",
            num(
                &format!("{k}.gsd_mm"),
                r.gsd_mm.map_or("–".into(), |g| format!("{g:.2}"))
            ),
            num(
                &format!("{k}.contrast_left"),
                r.contrast_left
                    .map_or("–".into(), |c| format!("{:.0} %", 100.0 * c))
            ),
        );
    }
    let cyl = |f: &dyn Fn(&CylinderRow) -> String| {
        r.cylinders.iter().map(f).collect::<Vec<_>>().join(" + ")
    };
    let _ = write!(
        s,
        "{}{}{}{}<td>{}</td>{}{}{}{}",
        num(
            &format!("{k}.ndl_runs_out_min"),
            r.ndl_runs_out_min
                .map_or("not reached".into(), |t| format!("{t:.1}"))
        ),
        num(&format!("{k}.stops"), escape(&stops)),
        num(&format!("{k}.deco_min"), format!("{:.1}", r.deco_min)),
        num(&format!("{k}.tts_min"), format!("{:.1}", r.tts_min)),
        escape(&r.gases),
        num(&format!("{k}.used_l"), cyl(&|c| format!("{:.0}", c.used_l))),
        num(
            &format!("{k}.end_bar"),
            cyl(&|c| format!("{:.0}", c.end_bar))
        ),
        num(&format!("{k}.verdict"), verdict_text(r).into()),
        num(
            &format!("{k}.dives"),
            r.dives.map_or("no split fits".into(), |n| n.to_string())
        ),
    );
    if survey {
        let a = r.accuracy.as_ref();
        let _ = write!(
            s,
            "{}{}",
            num(
                &format!("{k}.rms_3d_mm"),
                a.map_or("–".into(), |a| format!("{:.1}", a.rms_3d_mm))
            ),
            num(
                &format!("{k}.rms_xyz_mm"),
                a.map_or("–".into(), |a| format!(
                    "{:.1}, {:.1}, {:.1}",
                    a.rms_xyz_mm[0], a.rms_xyz_mm[1], a.rms_xyz_mm[2]
                ))
            ),
        );
    }
    s.push_str("</tr>\n");
}

/// The rule-of-thumb section: how long a cylinder lasts at each depth, by the rule and by
/// poser's gas model.
fn rule_of_thumb_table(s: &mut String, t: &RuleOfThumb) {
    use super::html::{escape, num};
    use std::fmt::Write as _;
    let _ = write!(
        s,
        "<h2>Rule of thumb: how long does a cylinder last?</h2>\n<p>{} l of {} at {:.0} bar \
         ({:.0} l of free gas, real gas), SAC {:.0} l/min, {} water. The rule of thumb \
         divides litres × bar by SAC × (1 + depth/10); poser's gas model counts the \
         compressibility of the gas and the water's density, and keeps a {:.0} bar reserve.\
         </p>\n<table><tr><th>depth, m</th><th>ambient, bar</th><th>rule of thumb, min</th>\
         <th>to empty, min</th><th>to the {:.0} bar reserve, min</th></tr>\n",
        t.volume_l,
        escape(&t.gas),
        t.fill_bar,
        t.contents_l,
        t.sac_lpm,
        if t.salt_water { "sea" } else { "fresh" },
        t.reserve_bar,
        t.reserve_bar
    );
    for r in &t.rows {
        let k = format!("rule_{:.0}m", r.depth_m);
        let _ = writeln!(
            s,
            "<tr>{}{}{}{}{}</tr>",
            num(&format!("{k}.depth_m"), format!("{:.0}", r.depth_m)),
            num(&format!("{k}.ambient_bar"), format!("{:.2}", r.ambient_bar)),
            num(&format!("{k}.rule_min"), format!("{:.1}", r.rule_min)),
            num(
                &format!("{k}.to_empty_min"),
                format!("{:.1}", r.to_empty_min)
            ),
            num(
                &format!("{k}.to_reserve_min"),
                format!("{:.1}", r.to_reserve_min)
            ),
        );
    }
    s.push_str("</table>\n");
}

/// One case's dive: its view, profile plot, verdict, problems, advice, remedies, split and
/// command.
fn dive_section(s: &mut String, r: &Row) {
    use super::html::{escape, svg};
    use std::fmt::Write as _;
    let _ = writeln!(s, "<h3>{}</h3>", escape(&r.label));
    if !r.view_png.is_empty() {
        let _ = writeln!(
            s,
            "<figure><img alt=\"rendered view, {}\" src=\"data:image/png;base64,{}\">\
             <figcaption>The view from the pose nearest the centre (native renderer, a \
             twentieth of the resolution, 32 samples per pixel).</figcaption></figure>",
            escape(&r.label),
            super::html::base64(&r.view_png)
        );
    }
    let _ = write!(
        s,
        "<figure>{svg}<figcaption>Depth, ceiling and NDL over the runtime \
         of the survey as one dive.</figcaption></figure>\n<p><b>Verdict: {v}</b> \
         ({runtime:.0} min runtime, GF {gf}, {gases}).</p>\n",
        svg = svg(&r.profile_svg),
        v = verdict_text(r),
        runtime = r.runtime_min,
        gf = escape(&r.gf),
        gases = escape(&r.gases),
    );
    for (title, list) in [
        ("Problems", &r.problems),
        ("Advice", &r.advice),
        ("What would fix it (the planner's remedies)", &r.suggestions),
    ] {
        if list.is_empty() {
            continue;
        }
        let _ = write!(s, "<p>{title}:</p><ul>");
        for p in list {
            let _ = write!(s, "<li>{}</li>", escape(p));
        }
        s.push_str("</ul>\n");
    }
    if !r.split.is_empty() {
        let _ = write!(
            s,
            "<p>Split into {} dives, {:.0} min apart:</p><ul>",
            r.split.len(),
            r.surface_interval_min
        );
        for p in &r.split {
            let _ = write!(
                s,
                "<li>strips {}–{}: {:.1} min of survey, {:.1} min runtime, {:.0} bar left{}\
                 </li>",
                p.first_strip,
                p.last_strip,
                p.survey_min,
                p.runtime_min,
                p.end_bar,
                if p.safety_stop {
                    ", 3 min safety stop at 5 m"
                } else {
                    ""
                }
            );
        }
        s.push_str("</ul>\n");
    }
    let _ = writeln!(
        s,
        "<p class=\"small\">This case alone: <code>{}</code></p>",
        escape(&r.command)
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lesson::{Options, cases};

    #[test]
    fn the_rule_of_thumb_follows_boyle_and_the_real_gas() {
        let m = crate::scene::load(Path::new("scenarios/paper_survey.toml"), &[])
            .unwrap()
            .model;
        let cfg = DiveConfig::from_model(&m).unwrap();
        let t = rule_of_thumb(&cfg, &RULE_DEPTHS);
        // 12 l × 200 bar / (20 l/min × 2.5) = 48 min at 15 m; 24 min at 40 m.
        assert!((t.rows[0].rule_min - 48.0).abs() < 1e-9, "{t:?}");
        assert!((t.rows[1].rule_min - 24.0).abs() < 1e-9, "{t:?}");
        for r in &t.rows {
            // Real gas holds less than the ideal 12 × 200 l; sea water adds pressure.
            assert!(r.to_empty_min < r.rule_min && r.to_empty_min > 0.85 * r.rule_min);
            assert!(r.to_reserve_min < r.to_empty_min * 0.8);
        }
        // Deeper, shorter: the ratio is the ratio of ambient pressures.
        let ratio = t.rows[0].to_empty_min / t.rows[1].to_empty_min;
        assert!((ratio - t.rows[1].ambient_bar / t.rows[0].ambient_bar).abs() < 1e-9);
    }

    #[test]
    fn the_scuba_survey_lesson_finds_the_deco_the_gas_and_the_fixes() {
        let (lesson, cs) = cases(
            Path::new("scenarios/lessons/scuba_survey.toml"),
            &Options::default(),
        )
        .unwrap();
        assert_eq!(lesson.kind, crate::model::LessonKind::Dive);
        let out = tempfile::tempdir().unwrap();
        let res = run(&cs, out.path(), false, false, &|_| {}).unwrap();
        let row = |l: &str| res.rows.iter().find(|r| r.label.starts_with(l)).unwrap();
        let planned = row("as planned");
        // ≈ 1100 m at 15 m in ≈ 104 min: decompression and not enough gas; never OK.
        assert!((1000.0..1200.0).contains(&planned.path_m), "{planned:?}");
        assert!((95.0..115.0).contains(&planned.survey_min));
        assert!(!planned.ok && planned.deco_required && !planned.gas_ok);
        assert!(planned.deco_min > 0.0 && planned.ndl_runs_out_min.is_some());
        assert!(planned.dives.is_some_and(|n| n >= 2));
        // EAN32 lengthens the NDL.
        let nitrox = row("EAN32");
        assert!(
            nitrox
                .ndl_runs_out_min
                .is_none_or(|t| t > planned.ndl_runs_out_min.unwrap() + 5.0),
            "{:?} vs {:?}",
            nitrox.ndl_runs_out_min,
            planned.ndl_runs_out_min
        );
        // Every split dive the planner proposes is itself within the rules.
        for r in &res.rows {
            assert_eq!(r.dives.is_some_and(|n| n > 1), !r.split.is_empty());
            assert!(
                r.ok == (r.problems.is_empty()),
                "{}: {:?}",
                r.label,
                r.problems
            );
            assert!(r.profile_svg.contains("<svg"));
        }
        let html = html(&res, false);
        assert!(html.contains("NOT SAFE AS PLANNED"));
        assert!(html.contains("data-key=\"rule_15m.rule_min\">48.0<"));
    }
}
