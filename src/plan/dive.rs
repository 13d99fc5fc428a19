//! The dive of a survey: profile from the camera network, simulation of tissues and gas along
//! it, the ascent with the stops the model requires, and a verdict with computed remedies.
//!
//! | input (from [`crate::model::Diver`]) | unit | default when the scene has no diver |
//! |---|---|---|
//! | `speed` | m/s | the network's speed |
//! | `descent_rate` / `ascent_rate` | m/s | 18 / 9 m/min (Subsurface) |
//! | `sac` | m³/s (shown l/min) | 20 l/min |
//! | `cylinders` | — | one 12 l air cylinder at 200 bar |
//! | `gf_low` / `gf_high` | fraction | 0.30 / 0.75 |
//! | `reserve` | Pa (shown bar) | 50 bar |
//! | `salt_water` | — | true (1030 kg/m³ as Subsurface) |
//!
//! The profile: descent from the surface to the first pose at the descent rate, then the rig
//! poses in time order (depth = −z of the rig; linear between poses, which follows the terrain
//! when the network does), then the ascent at the ascent rate with mandatory stops, or — when
//! none are needed and the dive went deeper than 10 m — the recommended 3 min safety stop at
//! 5 m.

use super::deco::{Environment, Gas, GradientFactors, Ndl, Stop, Tissues};
use super::gas::{self, GasCheck, PROBLEM_SOLVING, SAC_FACTOR, Supply};
use crate::model::Model;
use serde::Serialize;

/// Everything the simulation needs about the diver and the water.
#[derive(Debug, Clone, Serialize)]
pub struct DiveConfig {
    pub env: Environment,
    pub gf: GradientFactors,
    /// Descent and ascent rates, m/s.
    pub descent_rate: f64,
    pub ascent_rate: f64,
    /// Swim speed during the survey, m/s.
    pub speed: f64,
    /// Surface air consumption, l/min.
    pub sac_lpm: f64,
    pub supply: Supply,
    /// Reserve at the surface, bar.
    pub reserve_bar: f64,
    /// Surface interval between split dives, s.
    pub surface_interval: f64,
    /// Whether defaults were used because the scene has no diver.
    pub defaulted: bool,
}

impl DiveConfig {
    /// From the model's diver (or Subsurface's defaults when the scene has none).
    pub fn from_model(model: &Model) -> Result<DiveConfig, String> {
        let env_of = |salt: bool| Environment::new(salt, model.site.altitude);
        match &model.diver {
            Some(d) => {
                let cyl: Vec<(String, f64, f64, Gas)> = d
                    .cylinders
                    .iter()
                    .map(|c| {
                        (
                            c.name.clone(),
                            c.volume * 1e3,
                            c.pressure / 1e5,
                            Gas { o2: c.o2, he: c.he },
                        )
                    })
                    .collect();
                let supply = Supply::new(&cyl, d.reserve / 1e5).ok_or_else(|| {
                    "the diver has no cylinder: add one to plan the gas".to_string()
                })?;
                for (name, v) in [
                    ("diver.speed", d.speed),
                    ("diver.descent_rate", d.descent_rate),
                    ("diver.ascent_rate", d.ascent_rate),
                    ("diver.sac", d.sac),
                ] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(format!("{name} must be a positive number (got {v})"));
                    }
                }
                if !(d.gf_low > 0.0 && d.gf_low <= d.gf_high && d.gf_high <= 1.0) {
                    return Err(format!(
                        "gradient factors must satisfy 0 < low ≤ high ≤ 1 (got {}/{})",
                        d.gf_low, d.gf_high
                    ));
                }
                Ok(DiveConfig {
                    env: env_of(d.salt_water),
                    gf: GradientFactors {
                        low: d.gf_low,
                        high: d.gf_high,
                    },
                    descent_rate: d.descent_rate,
                    ascent_rate: d.ascent_rate,
                    speed: d.speed,
                    sac_lpm: d.sac * 60_000.0,
                    supply,
                    reserve_bar: d.reserve / 1e5,
                    surface_interval: 3600.0,
                    defaulted: false,
                })
            }
            None => {
                let cyl = vec![("12 l".to_string(), 12.0, 200.0, Gas::AIR)];
                Ok(DiveConfig {
                    env: env_of(true),
                    gf: GradientFactors::SUBSURFACE,
                    descent_rate: 18.0 / 60.0,
                    ascent_rate: 9.0 / 60.0,
                    speed: if model.network.speed > 0.0 {
                        model.network.speed
                    } else {
                        0.2
                    },
                    sac_lpm: 20.0,
                    supply: Supply::new(&cyl, 50.0).expect("one cylinder"),
                    reserve_bar: 50.0,
                    surface_interval: 3600.0,
                    defaulted: true,
                })
            }
        }
    }

    pub fn gas(&self) -> Gas {
        self.supply.gas
    }
}

/// The survey part of a dive: (time s, depth m, strip) from the first pose.
#[derive(Debug, Clone, Serialize)]
pub struct Track {
    pub points: Vec<(f64, f64, u32)>,
    /// Time spent after the last pose (the network's duration beyond it), s.
    pub tail: f64,
}

impl Track {
    /// From the model's rig poses (depth = −z), in time order.
    pub fn from_model(model: &Model) -> Result<Track, String> {
        if model.poses.is_empty() {
            return Err("the network has no poses: nothing to dive".into());
        }
        let mut pts: Vec<(f64, f64, u32)> = model
            .poses
            .iter()
            .map(|p| (p.time, -p.world_from_rig.translation.z, p.strip))
            .collect();
        if pts.iter().any(|p| !p.0.is_finite() || !p.1.is_finite()) {
            return Err("a pose has a non-finite time or position".into());
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let t0 = pts[0].0;
        for p in &mut pts {
            p.0 -= t0;
            p.1 = p.1.max(0.0);
        }
        let last = pts.last().unwrap().0;
        let tail = (model.network.duration - t0 - last).max(0.0);
        Ok(Track { points: pts, tail })
    }

    /// Survey (bottom) duration, s.
    pub fn duration(&self) -> f64 {
        self.points.last().map(|p| p.0).unwrap_or(0.0) + self.tail
    }

    pub fn strips(&self) -> Vec<u32> {
        let mut s: Vec<u32> = self.points.iter().map(|p| p.2).collect();
        s.sort_unstable();
        s.dedup();
        s
    }

    /// Only the poses of strips `from..to` (in the order of [`Track::strips`]), re-timed to
    /// start at 0.
    pub fn strip_range(&self, from: usize, to: usize) -> Track {
        let strips = self.strips();
        let keep: Vec<u32> = strips[from.min(strips.len())..to.min(strips.len())].to_vec();
        let mut pts: Vec<(f64, f64, u32)> = self
            .points
            .iter()
            .copied()
            .filter(|p| keep.contains(&p.2))
            .collect();
        if let Some(t0) = pts.first().map(|p| p.0) {
            for p in &mut pts {
                p.0 -= t0;
            }
        }
        let tail = if to >= strips.len() { self.tail } else { 0.0 };
        Track { points: pts, tail }
    }

    /// The same track swum `factor` times faster (times divided by `factor`).
    pub fn faster(&self, factor: f64) -> Track {
        Track {
            points: self
                .points
                .iter()
                .map(|p| (p.0 / factor, p.1, p.2))
                .collect(),
            tail: self.tail / factor,
        }
    }

    pub fn max_depth(&self) -> f64 {
        self.points.iter().map(|p| p.1).fold(0.0, f64::max)
    }
}

/// One sample of the simulated dive.
#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    /// Runtime, s.
    pub time: f64,
    pub depth: f64,
    /// Smooth ceiling, m.
    pub ceiling: f64,
    /// No-decompression limit at this depth (only on the bottom part).
    pub ndl: Option<Ndl>,
    /// Time to surface, s, and the first stop depth (m) if in deco.
    pub tts: f64,
    pub stop_depth: Option<f64>,
    /// Duration of that first stop, s.
    pub stop_time: Option<f64>,
    pub in_deco: bool,
    /// Cylinder pressure, bar.
    pub pressure: f64,
}

/// Phase of the dive a moment belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    Descent,
    Bottom,
    Ascent,
}

/// A simulated dive.
#[derive(Debug, Clone, Serialize)]
pub struct DiveResult {
    /// Profile as (runtime s, depth m) vertices.
    pub profile: Vec<(f64, f64)>,
    pub samples: Vec<Sample>,
    pub descent_time: f64,
    /// Survey time at depth, s.
    pub bottom_time: f64,
    /// Total runtime, s.
    pub runtime: f64,
    pub max_depth: f64,
    pub mean_depth: f64,
    /// Mandatory stops (empty within the NDL).
    pub stops: Vec<Stop>,
    pub safety_stop: Option<Stop>,
    /// Smallest NDL seen on the bottom while not in deco, s.
    pub min_ndl: Option<f64>,
    /// Runtime at which the ceiling first leaves the surface, s.
    pub deco_from: Option<f64>,
    /// Deepest ceiling of the dive, m.
    pub max_ceiling: f64,
    /// Time to surface at the end of the bottom time, s.
    pub tts_at_end: f64,
    pub gas: GasCheck,
}

impl DiveResult {
    pub fn deco_required(&self) -> bool {
        !self.stops.is_empty()
    }
    /// Within the NDL and the gas rules.
    pub fn ok(&self) -> bool {
        !self.deco_required() && self.gas.ok()
    }
}

/// Simulate a dive over `track` starting from `tissues` (surface state). `sample_every` s
/// (e.g. 10) fills [`DiveResult::samples`] with ceiling, NDL, TTS and pressure; `None` skips
/// the per-sample NDL/TTS work (for searches).
pub fn simulate(
    cfg: &DiveConfig,
    track: &Track,
    tissues: &mut Tissues,
    sample_every: Option<f64>,
) -> DiveResult {
    let gas_mix = cfg.gas();
    let env = cfg.env;
    // Descent and bottom vertices.
    let d0 = track.points.first().map(|p| p.1).unwrap_or(0.0);
    let descent_time = d0 / cfg.descent_rate;
    let mut profile: Vec<(f64, f64)> = vec![(0.0, 0.0)];
    for p in &track.points {
        profile.push((descent_time + p.0, p.1));
    }
    let bottom_end = descent_time + track.duration();
    let last_depth = track.points.last().map(|p| p.1).unwrap_or(0.0);
    if track.tail > 0.0 {
        profile.push((bottom_end, last_depth));
    }

    // Integrate the bottom part in ≤ 1 s steps.
    let mut used = 0.0;
    let mut min_ndl: Option<f64> = None;
    let mut deco_from: Option<f64> = None;
    let mut max_ceiling: f64 = 0.0;
    let mut samples = Vec::new();
    let mut next_sample = 0.0;
    let mut reserve_reached_at = None;
    let mut empty_at = None;
    let reserve_l = cfg.supply.reserve;
    let mut track_gas = |used: f64, t: f64| {
        if reserve_reached_at.is_none() && cfg.supply.start - used < reserve_l {
            reserve_reached_at = Some(t);
        }
        if empty_at.is_none() && cfg.supply.start - used <= 0.0 {
            empty_at = Some(t);
        }
    };
    let mut record =
        |t: f64, depth: f64, tissues: &Tissues, used: f64, phase: Phase, next: &mut f64| {
            let Some(every) = sample_every else { return };
            if t + 1e-9 < *next {
                return;
            }
            *next += every;
            let in_deco = tissues.in_deco();
            let (tts, stop) = tissues.tts(depth, cfg.ascent_rate, gas_mix, t);
            let _ = phase;
            let ndl = Some(tissues.ndl(depth, gas_mix));
            samples.push(Sample {
                time: t,
                depth,
                ceiling: tissues.ceiling(),
                ndl,
                tts,
                // The first planned stop; in deco without one (the ascent itself clears the
                // ceiling), the ceiling rounded up to the 3 m level.
                stop_depth: stop
                    .map(|s| s.depth)
                    .or_else(|| in_deco.then(|| ((tissues.ceiling() / 3.0).ceil() * 3.0).max(3.0))),
                stop_time: stop.map(|s| s.duration),
                in_deco,
                pressure: cfg.supply.pressure_after(used),
            });
        };

    let integrate = |tissues: &mut Tissues,
                     used: &mut f64,
                     vertices: &[(f64, f64)],
                     phase_of: &dyn Fn(f64) -> Phase,
                     on_step: &mut dyn FnMut(f64, f64, &Tissues, f64, Phase)| {
        for w in vertices.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            let dt = t1 - t0;
            if dt <= 0.0 {
                continue;
            }
            let n = dt.ceil().max(1.0) as usize;
            let h = dt / n as f64;
            for i in 0..n {
                let f = (i as f64 + 0.5) / n as f64;
                let d = a + (b - a) * f;
                let p = env.pressure(d);
                tissues.expose_pressure(p, gas_mix, h);
                *used += gas::consumption(cfg.sac_lpm, p, h);
                let t = t0 + (i + 1) as f64 * h;
                let de = a + (b - a) * (i + 1) as f64 / n as f64;
                on_step(t, de, tissues, *used, phase_of(t));
            }
        }
    };

    record(0.0, 0.0, tissues, 0.0, Phase::Descent, &mut next_sample);
    let phase_of = |t: f64| {
        if t <= descent_time + 1e-9 {
            Phase::Descent
        } else {
            Phase::Bottom
        }
    };
    integrate(
        tissues,
        &mut used,
        &profile,
        &phase_of,
        &mut |t, d, ts, u, ph| {
            track_gas(u, t);
            let c = ts.ceiling();
            max_ceiling = max_ceiling.max(c);
            if ph == Phase::Bottom && c > 0.0 && deco_from.is_none() {
                deco_from = Some(t);
            }
            record(t, d, ts, u, ph, &mut next_sample);
        },
    );
    let used_bottom = used;

    // The ascent the model requires, planned on a copy, then flown on the real state.
    let mut plan = tissues.clone();
    let ascent = plan.ascend(last_depth, cfg.ascent_rate, gas_mix, bottom_end);
    let mut asc: Vec<(f64, f64)> = ascent
        .path
        .iter()
        .map(|&(t, d)| (bottom_end + t, d))
        .collect();
    let max_depth = profile.iter().map(|p| p.1).fold(0.0, f64::max);
    let mut safety_stop = None;
    if ascent.stops.is_empty() && max_depth >= 10.0 && last_depth > 5.0 {
        let t5 = bottom_end + (last_depth - 5.0) / cfg.ascent_rate;
        asc = vec![
            (bottom_end, last_depth),
            (t5, 5.0),
            (t5 + 180.0, 5.0),
            (t5 + 180.0 + 5.0 / cfg.ascent_rate, 0.0),
        ];
        safety_stop = Some(Stop {
            depth: 5.0,
            duration: 180.0,
        });
    }
    let tts_at_end = asc.last().unwrap().0 - bottom_end;
    integrate(
        tissues,
        &mut used,
        &asc,
        &|_| Phase::Ascent,
        &mut |t, d, ts, u, ph| {
            track_gas(u, t);
            max_ceiling = max_ceiling.max(ts.ceiling());
            record(t, d, ts, u, ph, &mut next_sample);
        },
    );
    profile.extend(asc.into_iter().skip(1));
    let runtime = profile.last().unwrap().0;

    // NDL minimum from the samples when they were taken.
    for s in &samples {
        if let Some(Ndl::Limit(n)) = s.ndl {
            min_ndl = Some(min_ndl.map_or(n, |m: f64| m.min(n)));
        }
    }
    let mean_depth = {
        let mut area = 0.0;
        for w in profile.windows(2) {
            area += 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0);
        }
        if runtime > 0.0 { area / runtime } else { 0.0 }
    };

    let ascent_gas = used - used_bottom;
    let min_gas = SAC_FACTOR
        * (gas::consumption(cfg.sac_lpm, env.pressure(max_depth), PROBLEM_SOLVING) + ascent_gas);
    let at_end_of_bottom = cfg.supply.start - used_bottom;
    let gas = GasCheck {
        used,
        start: cfg.supply.start,
        end_pressure: if cfg.supply.start - used > 0.0 {
            cfg.supply.pressure_after(used)
        } else {
            0.0
        },
        reserve_bar: cfg.reserve_bar,
        reserve_ok: cfg.supply.start - used >= cfg.supply.reserve,
        thirds_ok: used <= cfg.supply.start * 2.0 / 3.0,
        min_gas,
        min_gas_ok: at_end_of_bottom >= min_gas,
        at_end_of_bottom,
        reserve_reached_at,
        empty_at,
    };
    DiveResult {
        profile,
        samples,
        descent_time,
        bottom_time: track.duration(),
        runtime,
        max_depth,
        mean_depth,
        stops: ascent.stops,
        safety_stop,
        min_ndl,
        deco_from,
        max_ceiling,
        tts_at_end,
        gas,
    }
}

/// Simulate one dive from clean tissues.
pub fn simulate_fresh(cfg: &DiveConfig, track: &Track, sample_every: Option<f64>) -> DiveResult {
    let mut t = Tissues::surface(cfg.env, cfg.gf);
    simulate(cfg, track, &mut t, sample_every)
}

/// A remedy with its computed numbers.
#[derive(Debug, Clone, Serialize)]
pub struct Suggestion {
    /// `bigger_cylinder`, `split_dives`, `max_strips`, `faster_swim`, `nitrox`.
    pub kind: String,
    pub text: String,
    /// Whether this remedy alone fixes both the deco and the gas problem.
    pub fixes_all: bool,
}

/// The verdict on a survey dive.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    pub within_ndl: bool,
    pub deco_required: bool,
    pub gas_ok: bool,
    pub problems: Vec<String>,
    /// Not failing the plan, but worth knowing (Subsurface's minimum gas, a thin NDL margin).
    pub advice: Vec<String>,
    pub suggestions: Vec<Suggestion>,
}

/// Standard back-gas configurations (l water volume, label) for the "bigger cylinder" remedy.
const CYLINDERS: [(f64, &str); 8] = [
    (10.0, "10 l"),
    (12.0, "12 l"),
    (15.0, "15 l"),
    (18.0, "18 l"),
    (20.0, "twin 10 l"),
    (24.0, "twin 12 l"),
    (30.0, "twin 15 l"),
    (36.0, "twin 18 l"),
];

fn mmss(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

/// Judge a dive and compute remedies.
pub fn verdict(cfg: &DiveConfig, track: &Track, dive: &DiveResult) -> Verdict {
    let mut problems = Vec::new();
    let mut advice = Vec::new();
    let deco = dive.deco_required();
    if deco {
        let total: f64 = dive.stops.iter().map(|s| s.duration).sum();
        let stops = dive
            .stops
            .iter()
            .map(|s| format!("{:.0} m {}", s.depth, mmss(s.duration)))
            .collect::<Vec<_>>()
            .join(", ");
        problems.push(format!(
            "decompression obligation: the NDL runs out at {} runtime ({} into the survey); \
             {} of mandatory stops ({stops}) at GF {:.0}/{:.0}",
            mmss(dive.deco_from.unwrap_or(0.0)),
            mmss(dive.deco_from.unwrap_or(0.0) - dive.descent_time),
            mmss(total),
            cfg.gf.low * 100.0,
            cfg.gf.high * 100.0
        ));
    }
    let g = &dive.gas;
    let bar = |l: f64| cfg.supply.pressure_after(cfg.supply.start - l);
    if !g.reserve_ok {
        let when = match (g.empty_at, g.reserve_reached_at) {
            (Some(e), _) => format!("the cylinders are empty at {} runtime", mmss(e)),
            (None, Some(r)) => format!("the reserve is reached at {} runtime", mmss(r)),
            _ => String::new(),
        };
        problems.push(format!(
            "not enough gas: the dive needs {:.0} l but {} hold {:.0} l ({:.0} l above the {:.0} bar reserve); {when}",
            g.used, cfg.supply.description, g.start, g.start - cfg.supply.reserve, cfg.reserve_bar
        ));
    } else {
        if !g.thirds_ok {
            problems.push(format!(
                "rule of thirds broken: {:.0} l used of {:.0} l (at most {:.0} l)",
                g.used,
                g.start,
                g.start * 2.0 / 3.0
            ));
        }
        if !g.min_gas_ok {
            advice.push(format!(
                "minimum gas not kept: {:.0} l ({:.0} bar) left at the end of the bottom time, \
                 {:.0} l ({:.0} bar) needed for an ascent with a problem (SAC×{SAC_FACTOR}, 4 min)",
                g.at_end_of_bottom,
                bar(g.at_end_of_bottom),
                g.min_gas,
                bar(g.min_gas)
            ));
        }
    }
    let mut suggestions = Vec::new();
    if !problems.is_empty() {
        suggestions = remedies(cfg, track, dive);
    }
    if let Some(n) = dive.min_ndl
        && !deco
        && n < 300.0
    {
        advice.push(format!(
            "the NDL margin is thin: {} left at the tightest point",
            mmss(n)
        ));
    }
    Verdict {
        within_ndl: !deco,
        deco_required: deco,
        gas_ok: g.ok(),
        problems,
        advice,
        suggestions,
    }
}

fn remedies(cfg: &DiveConfig, track: &Track, dive: &DiveResult) -> Vec<Suggestion> {
    let mut out = Vec::new();
    let g = &dive.gas;
    let gas_mix = cfg.gas();
    let fill = cfg.supply.fill;
    let per_l = gas::contents(gas_mix, 1.0, fill);
    let res_l = gas::contents(gas_mix, 1.0, cfg.reserve_bar.min(fill));
    let used_bottom = g.start - g.at_end_of_bottom;

    // 1. Bigger cylinder at the same fill pressure.
    if !g.ok() {
        let need = [
            g.used / (per_l - res_l).max(1e-9),
            g.used * 1.5 / per_l,
            (used_bottom + g.min_gas) / per_l,
        ]
        .into_iter()
        .fold(0.0, f64::max);
        let pick = CYLINDERS.iter().find(|c| c.0 >= need - 1e-9);
        let text = match pick {
            Some((v, name)) => format!(
                "bigger cylinder: the gas rules need ≥ {need:.1} l at {fill:.0} bar — a {name} \
                 ({v:.0} l) would do{}",
                if dive.deco_required() {
                    ", but it does not remove the decompression obligation"
                } else {
                    ""
                }
            ),
            None => format!(
                "bigger cylinder: the gas rules need ≥ {need:.1} l at {fill:.0} bar, more than a \
                 twin 18 l — no back-gas set carries this dive; shorten it"
            ),
        };
        out.push(Suggestion {
            kind: "bigger_cylinder".into(),
            text,
            fixes_all: pick.is_some() && !dive.deco_required(),
        });
    }

    let strips = track.strips();
    let n = strips.len();
    // 2. Max strips in one dive that fit the NDL and the gas.
    if n > 1 {
        let fits = |k: usize| simulate_fresh(cfg, &track.strip_range(0, k), None).ok();
        let mut best = 0;
        for k in (1..=n).rev() {
            if fits(k) {
                best = k;
                break;
            }
        }
        if best > 0 && best < n {
            let r = simulate_fresh(cfg, &track.strip_range(0, best), None);
            out.push(Suggestion {
                kind: "max_strips".into(),
                text: format!(
                    "fewer strips: at most {best} of the {n} strips fit one dive within the NDL and \
                     the gas rules ({} of survey, {:.0} bar left)",
                    mmss(r.bottom_time),
                    r.gas.end_pressure
                ),
                fixes_all: false,
            });
            // 3. Split into several dives with surface intervals (repetitive-dive tissues).
            if let Some(plan) = split_plan(cfg, track, best) {
                out.push(plan);
            }
        } else if best == 0 {
            out.push(Suggestion {
                kind: "max_strips".into(),
                text: "fewer strips: not even one strip fits one dive within the NDL and the gas \
                       rules — change depth, gas or cylinder"
                    .into(),
                fixes_all: false,
            });
        }
    }

    // 4. Faster swim: the speed factor at which the whole survey fits.
    let fits_at = |f: f64| simulate_fresh(cfg, &track.faster(f), None).ok();
    if fits_at(4.0) {
        let (mut lo, mut hi) = (1.0_f64, 4.0_f64);
        while hi - lo > 0.005 {
            let mid = 0.5 * (lo + hi);
            if fits_at(mid) { hi = mid } else { lo = mid }
        }
        let v = cfg.speed * hi;
        out.push(Suggestion {
            kind: "faster_swim".into(),
            text: format!(
                "faster swim: {v:.2} m/s instead of {:.2} m/s (×{hi:.2}, survey {} instead of {}) fits \
                 one dive{}",
                cfg.speed,
                mmss(track.duration() / hi),
                mmss(track.duration()),
                if v > 0.5 {
                    " — faster than a diver can swim steadily while photographing (≈ 0.5 m/s), not practical"
                } else {
                    "; keep exposures short enough against motion blur"
                }
            ),
            fixes_all: v <= 0.5,
        });
    } else {
        out.push(Suggestion {
            kind: "faster_swim".into(),
            text: "faster swim: even 4× the speed does not fit one dive".into(),
            fixes_all: false,
        });
    }

    // 5. Nitrox for the decompression part (gas quantity unchanged).
    if dive.deco_required() {
        for o2 in [0.32, 0.36] {
            let mix = Gas { o2, he: 0.0 };
            let mod_m = mix.mod_depth(&cfg.env, 1.4);
            if mod_m < dive.max_depth {
                continue;
            }
            let mut c = cfg.clone();
            c.supply.gas = mix;
            let r = simulate_fresh(&c, track, None);
            if !r.deco_required() {
                out.push(Suggestion {
                    kind: "nitrox".into(),
                    text: format!(
                        "nitrox: EAN{:.0} (MOD {mod_m:.0} m at pO₂ 1.4) keeps the whole survey within \
                         the NDL{}",
                        o2 * 100.0,
                        if r.gas.ok() { "" } else { " — the gas quantity problem remains" }
                    ),
                    fixes_all: r.gas.ok(),
                });
                break;
            }
        }
    }
    out
}

/// Split the strips into the fewest dives (≤ `max_per_dive` strips, repetitive tissues across
/// surface intervals) where every dive fits.
fn split_plan(cfg: &DiveConfig, track: &Track, max_per_dive: usize) -> Option<Suggestion> {
    let n = track.strips().len();
    let first = n.div_ceil(max_per_dive);
    for dives in first..=(first + 6).min(n) {
        let mut tissues = Tissues::surface(cfg.env, cfg.gf);
        let mut ok = true;
        let mut parts = Vec::new();
        let mut start = 0;
        for i in 0..dives {
            let end = (n * (i + 1)).div_ceil(dives);
            let r = simulate(cfg, &track.strip_range(start, end), &mut tissues, None);
            if !r.ok() {
                ok = false;
                break;
            }
            parts.push(format!(
                "strips {}–{} ({} survey, {:.0} bar left)",
                start + 1,
                end,
                mmss(r.bottom_time),
                r.gas.end_pressure
            ));
            tissues.expose(0.0, Gas::AIR, cfg.surface_interval);
            // New dive: a fresh GF-low anchor, as Subsurface starts each dive.
            tissues.gf_low_anchor = cfg.env.surface_pressure + 1.0;
            start = end;
        }
        if ok {
            return Some(Suggestion {
                kind: "split_dives".into(),
                text: format!(
                    "two or more dives: {dives} dives with {} surface intervals and a full cylinder \
                     each: {}",
                    mmss(cfg.surface_interval),
                    parts.join("; ")
                ),
                fixes_all: true,
            });
        }
    }
    None
}

/// Everything `poser dive` reports.
#[derive(Debug, Clone, Serialize)]
pub struct DiveReport {
    pub config: DiveConfig,
    pub dive: DiveResult,
    pub verdict: Verdict,
}

/// Plan the dive of a model's survey.
pub fn plan_dive(model: &Model, sample_every: f64) -> Result<DiveReport, String> {
    if model.water.is_none() {
        return Err("the scene has no water (a survey in air): there is no dive to plan".into());
    }
    let config = DiveConfig::from_model(model)?;
    let track = Track::from_model(model)?;
    let dive = simulate_fresh(&config, &track, Some(sample_every));
    let verdict = verdict(&config, &track, &dive);
    Ok(DiveReport {
        config,
        dive,
        verdict,
    })
}
