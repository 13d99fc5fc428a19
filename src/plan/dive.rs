//! The dive of a survey: profile from the camera network, simulation of tissues and gas along
//! it, the ascent with the stops the model requires, and a verdict with computed remedies.
//!
//! | input (from [`crate::model::Diver`]) | unit | default when the scene has no diver |
//! |---|---|---|
//! | `speed` | m/s | the network's speed |
//! | `descent_rate` / `ascent_rate` | m/s | 18 / 9 m/min (Subsurface) |
//! | `sac` | m³/s (shown l/min) | 20 l/min |
//! | `cylinders` | — | one 12 l air cylinder at 200 bar |
//! | `gf_low` / `gf_high` | fraction | 0.30 / 0.75 (Subsurface's default) |
//! | `reserve` | Pa (shown bar) | 50 bar in every cylinder (poser's rule) |
//! | `po2_bottom` / `po2_deco` | bar | 1.4 / 1.6 (Subsurface) |
//! | `end_limit` | m | 30 (equivalent narcotic depth, O₂ counted as narcotic) |
//! | `salt_water` | — | true (1030 kg/m³ as Subsurface) |
//!
//! Gases as Subsurface's planner handles them: every cylinder keeps its own gas and contents.
//! Travel cylinders are breathed on the descent from the surface to their switch depth; then
//! stage cylinders, each down to its reserve, then the back gas; travel and deco cylinders
//! from their switch depth on the ascent (the richest allowed, a 1 min hold at a switch
//! except to O₂; within the NDL only travel gases, without a hold), and the ascent's stops are
//! computed on the gas breathed. Bailout cylinders are not breathed in the plan.
//! On the ascent too no cylinder is breathed below its reserve while another gas is left: a
//! stage or deco cylinder at its reserve hands over to the richest other deco gas allowed
//! there, else to the bottom cylinders (stages, then back gas), and the rest of the ascent is
//! planned again on the gas now breathed (longer stops, never above the ceiling).
//! Every gas is checked where it is breathed: pO₂ against its role's limit, and not hypoxic
//! at the surface. "In decompression" has one meaning everywhere (report, verdict, `.ssrf`):
//! the ceiling is below the surface.
//! Oxygen toxicity (CNS % against the NOAA limits, OTU) is summed in the same ≤ 1 s steps, each
//! a pO₂ ramp of the gas breathed ([`super::oxygen`]); CNS above 100 % or any pO₂ above the
//! table's 1.6 bar is a problem, CNS above 80 % or OTU above 300 advice.
//!
//! The profile: descent from the surface to the first pose at the descent rate, then the rig
//! poses in time order (depth = −z of the rig; linear between poses, which follows the terrain
//! when the network does), then the ascent at the ascent rate with mandatory stops, or — when
//! none are needed and the dive went deeper than 10 m — the recommended 3 min safety stop at
//! 5 m.

use super::deco::{AscentPlan, Environment, Gas, GradientFactors, Ndl, Stop, Tissues};
use super::gas::{
    self, BottomGas, CylinderUse, GasCheck, HYPOXIC, PROBLEM_SOLVING, SAC_FACTOR, Supply, Tank,
    bottom_gas, depth_limit, gas_label, hypoxic_limit,
};
use super::oxygen::{self, OxygenExposure};
use crate::model::{CylinderRole, DecoMode, Model};
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
    /// Every cylinder with its own gas.
    pub tanks: Vec<Tank>,
    /// The bottom cylinders (back gas and stages) pooled, for the gas rules and remedies.
    pub supply: Supply,
    /// Reserve at the surface in every cylinder, bar.
    pub reserve_bar: f64,
    /// pO₂ limits of bottom/stage and of deco gases, bar.
    pub po2_bottom: f64,
    pub po2_deco: f64,
    /// Deepest equivalent narcotic depth a named gas may have, m (O₂ counted as narcotic).
    pub end_limit: f64,
    /// Surface interval between split dives, s.
    pub surface_interval: f64,
    /// Whether decompression is planned and accepted (`diver.deco`).
    pub deco: DecoMode,
    /// Whether defaults were used because the scene has no diver.
    pub defaulted: bool,
}

impl DiveConfig {
    /// From the model's diver (or the defaults when the scene has none).
    pub fn from_model(model: &Model) -> Result<DiveConfig, String> {
        let env_of = |salt: bool| Environment::new(salt, model.site.altitude);
        match &model.diver {
            Some(d) => {
                for (name, v) in [
                    ("diver.speed", d.speed),
                    ("diver.descent_rate", d.descent_rate),
                    ("diver.ascent_rate", d.ascent_rate),
                    ("diver.sac", d.sac),
                    ("diver.po2_bottom", d.po2_bottom),
                    ("diver.po2_deco", d.po2_deco),
                    ("diver.end_limit", d.end_limit),
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
                let env = env_of(d.salt_water);
                let mut tanks = Vec::new();
                for c in &d.cylinders {
                    let gas = Gas { o2: c.o2, he: c.he };
                    if !(c.o2 > 0.0 && c.he >= 0.0 && c.o2 + c.he <= 1.0 + 1e-9) {
                        return Err(format!("cylinder '{}': impossible gas mix", c.name));
                    }
                    // Switch depths, rounded down to whole metres (toward safety): a deco gas
                    // at its MOD at the deco pO₂; a travel gas as deep as both its bottom pO₂
                    // and the END limit allow.
                    let sw = match c.role {
                        CylinderRole::Deco => Some(
                            c.switch_depth
                                .unwrap_or_else(|| depth_limit(gas.mod_depth(&env, d.po2_deco))),
                        ),
                        CylinderRole::Travel => Some(c.switch_depth.unwrap_or_else(|| {
                            depth_limit(gas.mod_depth(&env, d.po2_bottom).min(gas::end_depth(
                                &env,
                                gas,
                                d.end_limit,
                            )))
                        })),
                        _ => None,
                    };
                    tanks.push(Tank::new(
                        &c.name,
                        c.volume * 1e3,
                        c.pressure / 1e5,
                        gas,
                        c.role,
                        sw,
                        d.reserve / 1e5,
                    ));
                }
                let supply = pooled(&tanks, d.reserve / 1e5).ok_or_else(|| {
                    "the diver has no bottom cylinder: add one to plan the gas".to_string()
                })?;
                Ok(DiveConfig {
                    env,
                    gf: GradientFactors {
                        low: d.gf_low,
                        high: d.gf_high,
                    },
                    descent_rate: d.descent_rate,
                    ascent_rate: d.ascent_rate,
                    speed: d.speed,
                    sac_lpm: d.sac * 60_000.0,
                    tanks,
                    supply,
                    reserve_bar: d.reserve / 1e5,
                    po2_bottom: d.po2_bottom,
                    po2_deco: d.po2_deco,
                    end_limit: d.end_limit,
                    surface_interval: 3600.0,
                    deco: d.deco,
                    defaulted: false,
                })
            }
            None => {
                let tanks = vec![Tank::new(
                    "12 l",
                    12.0,
                    200.0,
                    Gas::AIR,
                    CylinderRole::Bottom,
                    None,
                    DEFAULT_RESERVE_BAR,
                )];
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
                    supply: pooled(&tanks, DEFAULT_RESERVE_BAR).expect("one cylinder"),
                    tanks,
                    reserve_bar: DEFAULT_RESERVE_BAR,
                    po2_bottom: 1.4,
                    po2_deco: 1.6,
                    end_limit: crate::model::DEFAULT_END_LIMIT,
                    surface_interval: 3600.0,
                    deco: DecoMode::None,
                    defaulted: true,
                })
            }
        }
    }

    /// The gas breathed first (the first stage, else the first back-gas cylinder).
    pub fn gas(&self) -> Gas {
        self.tanks[self.bottom_order()[0]].gas
    }

    /// Bottom cylinders in the order they are breathed: stages, then back gas.
    pub fn bottom_order(&self) -> Vec<usize> {
        let mut v: Vec<usize> = (0..self.tanks.len())
            .filter(|&i| self.tanks[i].role == CylinderRole::Stage)
            .collect();
        v.extend((0..self.tanks.len()).filter(|&i| self.tanks[i].role == CylinderRole::Bottom));
        v
    }

    /// pO₂ limit of a cylinder's role, bar: `po2_deco` for a deco gas, `po2_bottom` for
    /// every other (back gas, stage, travel, bailout).
    pub fn po2_limit(&self, tank: &Tank) -> f64 {
        if tank.role == CylinderRole::Deco {
            self.po2_deco
        } else {
            self.po2_bottom
        }
    }

    /// How a decompression ascent is flown: one rate, 3 m stops, the travel and deco
    /// cylinders' gases from their switch depths.
    pub fn ascent_plan(&self) -> AscentPlan {
        let mut plan = AscentPlan::simple(self.ascent_rate);
        plan.deco_gases = self
            .tanks
            .iter()
            .filter_map(|t| t.switch_depth.map(|d| (t.gas, d)))
            .collect();
        plan
    }

    /// How an ascent within the NDL is flown: direct, on the travel gases from their switch
    /// depths (a bottom gas hypoxic in the shallows must not be breathed there) without a
    /// hold at the switch; deco gases are not breathed.
    pub fn direct_plan(&self) -> AscentPlan {
        let mut plan = AscentPlan::simple(self.ascent_rate);
        plan.switch_time = 0.0;
        plan.deco_gases = self
            .tanks
            .iter()
            .filter(|t| t.role == CylinderRole::Travel)
            .filter_map(|t| t.switch_depth.map(|d| (t.gas, d)))
            .collect();
        plan
    }

    /// The travel cylinder breathed on the descent at `depth` m: of the travel gases whose
    /// switch depth is at or below `depth`, the one with the shallowest switch depth (the
    /// richest on a tie). `None` past every travel gas's switch depth: the bottom gas.
    pub fn descent_travel(&self, depth: f64) -> Option<usize> {
        (0..self.tanks.len())
            .filter(|&i| self.tanks[i].role == CylinderRole::Travel)
            .filter(|&i| {
                self.tanks[i]
                    .switch_depth
                    .is_some_and(|s| s + 1e-9 >= depth)
            })
            .min_by(|&a, &b| {
                let (ta, tb) = (&self.tanks[a], &self.tanks[b]);
                ta.switch_depth
                    .unwrap_or(0.0)
                    .total_cmp(&tb.switch_depth.unwrap_or(0.0))
                    .then(tb.gas.o2.total_cmp(&ta.gas.o2))
            })
    }

    /// The same diver with every bottom cylinder filled with `mix`.
    pub fn with_bottom_gas(&self, mix: Gas) -> DiveConfig {
        let mut c = self.clone();
        for t in &mut c.tanks {
            if t.bottom_phase() {
                *t = Tank::new(
                    &t.name,
                    t.volume,
                    t.fill,
                    mix,
                    t.role,
                    None,
                    self.reserve_bar,
                );
            }
        }
        c.supply = pooled(&c.tanks, self.reserve_bar).expect("bottom cylinder");
        c
    }
}

/// The reserve poser keeps in every cylinder when the scene has no diver, bar (poser's own
/// rule; Subsurface's planner keeps none outside its recreational mode).
pub const DEFAULT_RESERVE_BAR: f64 = 50.0;

fn pooled(tanks: &[Tank], reserve_bar: f64) -> Option<Supply> {
    // Back gas and stages: travel, deco and bailout cylinders keep their own gas.
    let cyl: Vec<(String, f64, f64, Gas)> = tanks
        .iter()
        .filter(|t| t.bottom_phase())
        .map(|t| (t.name.clone(), t.volume, t.fill, t.gas))
        .collect();
    Supply::new(&cyl, reserve_bar)
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
    /// No-decompression limit at this depth on the gas breathed.
    pub ndl: Option<Ndl>,
    /// Time to surface, s, and the first stop depth (m) if in deco.
    pub tts: f64,
    pub stop_depth: Option<f64>,
    /// Duration of that first stop, s.
    pub stop_time: Option<f64>,
    /// The ceiling is below the surface.
    pub in_deco: bool,
    /// Index of the cylinder breathed, and the pressure of every cylinder, bar.
    pub cylinder: usize,
    pub pressures: Vec<f64>,
    /// Pressure of the cylinder breathed, bar.
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

/// A change of the cylinder breathed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Switch {
    /// Runtime, s, and depth, m.
    pub time: f64,
    pub depth: f64,
    /// Index into the configuration's cylinders.
    pub cylinder: usize,
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
    /// Mandatory stops (empty when the ascent itself clears the ceiling).
    pub stops: Vec<Stop>,
    pub safety_stop: Option<Stop>,
    /// Smallest NDL seen while not in deco, s.
    pub min_ndl: Option<f64>,
    /// Runtime at which the ceiling first leaves the surface before the ascent, s: the end of
    /// the no-decompression time.
    pub deco_from: Option<f64>,
    /// Deepest ceiling of the dive, m, and the ceiling when the bottom time ends, m.
    pub max_ceiling: f64,
    pub ceiling_at_end: f64,
    /// Time to surface at the end of the bottom time, s.
    pub tts_at_end: f64,
    /// Most the ceiling was ever below the diver on the ascent, m (ceiling − depth, at every
    /// ≤ 1 s step; ≤ 0 when the ascent never breaks the ceiling).
    pub ascent_ceiling_excess: f64,
    /// Cylinder changes (the first entry is the cylinder breathed from the start).
    pub switches: Vec<Switch>,
    pub gas: GasCheck,
    /// Oxygen toxicity: CNS % and OTU of the dive (see [`super::oxygen`]).
    pub oxygen: OxygenExposure,
}

impl DiveResult {
    /// Decompression dive: the ceiling left the surface before the ascent began (whether or
    /// not the ascent needs a stop to clear it).
    pub fn deco_required(&self) -> bool {
        self.deco_from.is_some() || !self.stops.is_empty()
    }
    /// Within the NDL, the gas rules, every gas breathable where it is breathed, CNS within
    /// 100 % and no pO₂ beyond the NOAA table (1.6 bar).
    pub fn ok(&self) -> bool {
        !self.deco_required()
            && self.gas.ok()
            && self.gas.breathable()
            && self.oxygen.within_limits()
    }
}

/// Per-cylinder bookkeeping of a simulation.
struct Breathing<'a> {
    cfg: &'a DiveConfig,
    used: Vec<f64>,
    current: usize,
    max_po2: Vec<Option<(f64, f64)>>,
    min_po2: Vec<Option<(f64, f64)>>,
    switches: Vec<Switch>,
    reserve_reached_at: Option<f64>,
    empty_at: Option<f64>,
    /// Cylinders left on the ascent at their reserve: never taken again on this dive.
    exhausted: Vec<bool>,
    /// CNS % and OTU so far.
    oxygen: OxygenExposure,
    /// Where the ascent falls back when no travel or deco gas is left: the bottom cylinders
    /// (stages, then back gas).
    fallback: Vec<usize>,
}

impl Breathing<'_> {
    fn left(&self, i: usize) -> f64 {
        self.cfg.tanks[i].start - self.used[i]
    }
    fn gas(&self) -> Gas {
        self.cfg.tanks[self.current].gas
    }
    fn switch_to(&mut self, i: usize, t: f64, depth: f64) {
        if i != self.current {
            self.current = i;
            self.switches.push(Switch {
                time: t,
                depth,
                cylinder: i,
            });
            self.note_po2(depth, depth);
        }
    }
    /// Note the pO₂ of the gas breathed between `shallow` and `deep` m.
    fn note_po2(&mut self, shallow: f64, deep: f64) {
        let i = self.current;
        let o2 = self.cfg.tanks[i].gas.o2;
        let hi = self.cfg.env.pressure(deep) * o2;
        let lo = self.cfg.env.pressure(shallow) * o2;
        if self.max_po2[i].is_none_or(|m| hi > m.0) {
            self.max_po2[i] = Some((hi, deep));
        }
        if self.min_po2[i].is_none_or(|m| lo < m.0) {
            self.min_po2[i] = Some((lo, shallow));
        }
    }
    fn keeps(&self, i: usize, need: f64) -> bool {
        i != self.current
            && !self.exhausted[i]
            && self.left(i) - need * 1.0001 >= self.cfg.tanks[i].reserve
    }
    /// On the descent (`descent`: the step from `from` to `depth` m is before the first
    /// pose; a change is made, and noted, at `from`): the
    /// travel gas for this depth ([`DiveConfig::descent_travel`]) while there is one, then the
    /// bottom gas. On the bottom a travel gas is left for the bottom gas.
    fn pick_descent(&mut self, need: f64, t: f64, from: f64, depth: f64, descent: bool) {
        let c = self.current;
        let travel = if descent {
            self.cfg.descent_travel(depth)
        } else {
            None
        };
        match travel {
            Some(i) if i != c && self.keeps(i, need) => self.switch_to(i, t, from),
            None if self.cfg.tanks[c].role == CylinderRole::Travel => {
                let order = self.cfg.bottom_order();
                let next = order
                    .iter()
                    .copied()
                    .find(|&i| self.keeps(i, need))
                    .unwrap_or(order[0]);
                self.switch_to(next, t, from);
            }
            _ => {}
        }
    }
    /// On the bottom: before breathing `need` litres, move on from a cylinder that would drop
    /// below its reserve to the next bottom cylinder that keeps it (a travel gas on the
    /// descent: another travel gas allowed here first).
    fn pick_bottom(&mut self, need: f64, t: f64, depth: f64) {
        let c = self.current;
        let role = self.cfg.tanks[c].role;
        if !(role.is_bottom() || role == CylinderRole::Travel)
            || self.left(c) - need >= self.cfg.tanks[c].reserve
        {
            return;
        }
        let tanks = &self.cfg.tanks;
        let other_travel = (role == CylinderRole::Travel)
            .then(|| {
                (0..tanks.len()).find(|&i| {
                    tanks[i].role == CylinderRole::Travel
                        && tanks[i].switch_depth.is_some_and(|s| s + 1e-9 >= depth)
                        && self.keeps(i, need)
                })
            })
            .flatten();
        let next = other_travel.or_else(|| {
            self.cfg
                .bottom_order()
                .into_iter()
                .find(|&i| self.keeps(i, need))
        });
        if let Some(next) = next {
            self.switch_to(next, t, depth);
        }
    }
    /// On the ascent: before breathing `need` litres, move on from a cylinder that would drop
    /// below its reserve — to the richest travel or deco gas allowed at this depth that keeps
    /// its reserve (deco gases only when `deco`: the ascent breathes them), else to the first
    /// bottom cylinder (stages, then back gas) that keeps it. The cylinder left is marked
    /// exhausted. Returns whether the diver moved; with no cylinder above its reserve the
    /// diver stays on this one (and the verdict reports the reserve broken).
    fn pick_ascent(&mut self, need: f64, t: f64, depth: f64, deco: bool) -> bool {
        let c = self.current;
        if self.left(c) - need >= self.cfg.tanks[c].reserve {
            return false;
        }
        let tanks = &self.cfg.tanks;
        let richest_deco = (0..tanks.len())
            .filter(|&i| {
                (tanks[i].role == CylinderRole::Travel
                    || (deco && tanks[i].role == CylinderRole::Deco))
                    && tanks[i].switch_depth.is_some_and(|sw| sw + 1e-6 >= depth)
                    && self.keeps(i, need)
            })
            .max_by(|&a, &b| tanks[a].gas.o2.total_cmp(&tanks[b].gas.o2));
        let next =
            richest_deco.or_else(|| self.fallback.iter().copied().find(|&i| self.keeps(i, need)));
        match next {
            Some(n) => {
                self.exhausted[c] = true;
                self.switch_to(n, t, depth);
                true
            }
            None => false,
        }
    }
    /// The ascent's travel gases and (when `deco`) deco gases, without the cylinders left at
    /// their reserve or lost.
    fn ascent_gases(&self, deco: bool) -> Vec<(Gas, f64)> {
        self.cfg
            .tanks
            .iter()
            .enumerate()
            .filter(|(i, t)| !self.exhausted[*i] && (t.role == CylinderRole::Travel || deco))
            .filter_map(|(_, t)| t.switch_depth.map(|d| (t.gas, d)))
            .collect()
    }
    /// The travel or deco cylinder (not left at its reserve) holding `gas`.
    fn deco_tank(&self, gas: Gas) -> Option<usize> {
        self.cfg
            .tanks
            .iter()
            .enumerate()
            .position(|(i, k)| !self.exhausted[i] && k.role.switched() && k.gas == gas)
    }
    /// Breathe `litres` between `shallow` and `deep` m, ending at runtime `t`.
    fn breathe(&mut self, litres: f64, t: f64, shallow: f64, deep: f64) {
        let i = self.current;
        self.used[i] += litres;
        self.note_po2(shallow, deep);
        if self.reserve_reached_at.is_none() && self.left(i) < self.cfg.tanks[i].reserve {
            self.reserve_reached_at = Some(t);
        }
        if self.empty_at.is_none() && self.left(i) <= 0.0 {
            self.empty_at = Some(t);
        }
    }
    fn pressures(&self) -> Vec<f64> {
        (0..self.used.len())
            .map(|i| self.cfg.tanks[i].pressure_after(self.used[i]))
            .collect()
    }
}

impl<'a> Breathing<'a> {
    /// The state at the surface before a dive whose bottom starts at `d0` m: the travel gas
    /// for the shallows, else the first bottom cylinder.
    fn at_surface(cfg: &'a DiveConfig, d0: f64) -> Breathing<'a> {
        let first = cfg
            .descent_travel(0.0)
            .filter(|_| d0 > 0.0)
            .unwrap_or(cfg.bottom_order()[0]);
        let n_tanks = cfg.tanks.len();
        let mut b = Breathing {
            cfg,
            used: vec![0.0; n_tanks],
            current: first,
            max_po2: vec![None; n_tanks],
            min_po2: vec![None; n_tanks],
            switches: vec![Switch {
                time: 0.0,
                depth: 0.0,
                cylinder: first,
            }],
            reserve_reached_at: None,
            empty_at: None,
            exhausted: vec![false; n_tanks],
            oxygen: OxygenExposure::default(),
            fallback: cfg.bottom_order(),
        };
        b.note_po2(0.0, 0.0);
        b
    }

    /// The cylinders `lost` gone at runtime `t`, `depth` m: the bailout cylinders join the
    /// fallback, and when the gas breathed is lost the diver takes a bailout cylinder, else
    /// the first bottom cylinder left.
    fn lose(&mut self, lost: &[usize], t: f64, depth: f64) {
        for &i in lost {
            self.exhausted[i] = true;
        }
        let bailouts: Vec<usize> = (0..self.cfg.tanks.len())
            .filter(|&i| self.cfg.tanks[i].role == CylinderRole::Bailout && !self.exhausted[i])
            .collect();
        let exhausted = &self.exhausted;
        self.fallback.retain(|i| !exhausted[*i]);
        self.fallback.extend(bailouts.iter().copied());
        if self.exhausted[self.current]
            && let Some(&next) = bailouts.first().or(self.fallback.first())
        {
            self.switch_to(next, t, depth);
        }
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
    simulate_losing(cfg, track, tissues, sample_every, &[])
}

/// [`simulate`] with the cylinders `lost` gone at the end of the bottom time (the worst
/// moment: deepest, most gas loaded): the ascent is planned and flown on the others. When the
/// gas breathed is lost, the diver takes a bailout cylinder, else the first bottom cylinder
/// left; the bailout cylinders are then also where the ascent falls back.
pub fn simulate_losing(
    cfg: &DiveConfig,
    track: &Track,
    tissues: &mut Tissues,
    sample_every: Option<f64>,
    lost: &[usize],
) -> DiveResult {
    let env = cfg.env;
    let (mut profile, descent_time) = descent_and_bottom(cfg, track);
    let d0 = track.points.first().map(|p| p.1).unwrap_or(0.0);
    let bottom_end = descent_time + track.duration();
    let last_depth = track.points.last().map(|p| p.1).unwrap_or(0.0);
    let n_tanks = cfg.tanks.len();
    let mut b = Breathing::at_surface(cfg, d0);
    let mut deco_from: Option<f64> = None;
    let mut max_ceiling: f64 = 0.0;
    let mut rec = Recorder {
        every: sample_every,
        next: 0.0,
        samples: Vec::new(),
        plan: cfg.ascent_plan(),
        direct: cfg.direct_plan(),
    };

    rec.record(0.0, 0.0, tissues, &b);
    integrate(
        &env,
        cfg.sac_lpm,
        tissues,
        &mut b,
        &profile,
        Leg::Bottom {
            descent_end: descent_time,
        },
        &mut |t, d, ts, b| {
            let c = ts.ceiling();
            max_ceiling = max_ceiling.max(c);
            if c > 0.0 && deco_from.is_none() {
                deco_from = Some(t);
            }
            rec.record(t, d, ts, b);
        },
    );
    let used_bottom: f64 = (0..n_tanks)
        .filter(|&i| cfg.tanks[i].bottom_phase())
        .map(|i| b.used[i])
        .sum();
    let ceiling_at_end = tissues.ceiling();

    // The ascent the model requires, planned on a copy, then flown on the real state.
    // Within the NDL the ascent is direct (with a safety stop): deco gases are for
    // decompression, and a switch's hold is no decompression stop.
    let in_deco_ascent = deco_from.is_some();
    if !lost.is_empty() {
        b.lose(lost, bottom_end, last_depth);
    }
    let mut base = if in_deco_ascent {
        rec.plan.clone()
    } else {
        rec.direct.clone()
    };
    base.deco_gases = b.ascent_gases(in_deco_ascent);
    let base = &base;
    let max_depth = profile.iter().map(|p| p.1).fold(0.0, f64::max);
    let (ascent, mut asc, mut gas_changes, safety_stop) =
        plan_ascent(cfg, tissues, &b, base, (bottom_end, last_depth), max_depth);
    // Fly it. A cylinder reaching its reserve is left for the next gas (the docs' order:
    // every cylinder down to its reserve, then the next); when that changes the gas of a
    // planned ascent, the rest is planned again from there on the gas now breathed, without
    // the cylinders left, so the stops always match the gas breathed.
    let mut flown: Vec<(f64, f64)> = vec![(bottom_end, last_depth)];
    let mut replanned = false;
    let mut excess = f64::NEG_INFINITY;
    loop {
        let switch_at = |t: f64| {
            gas_changes
                .iter()
                .rev()
                .find(|c| c.0 <= t + 1e-9)
                .map(|c| c.1)
        };
        let cut = integrate(
            &env,
            cfg.sac_lpm,
            tissues,
            &mut b,
            &asc,
            Leg::Ascent {
                planned: &switch_at,
                deco: in_deco_ascent,
                replan: safety_stop.is_none(),
            },
            &mut |t, d, ts, b| {
                let c = ts.ceiling();
                max_ceiling = max_ceiling.max(c);
                excess = excess.max(c - d);
                rec.record(t, d, ts, b);
            },
        );
        let Some((t, d)) = cut else {
            flown.extend(asc.iter().skip(1));
            break;
        };
        flown.extend(asc.iter().skip(1).filter(|p| p.0 < t - 1e-9));
        flown.push((t, d));
        replanned = true;
        let mut again = base.clone();
        again.deco_gases = b.ascent_gases(in_deco_ascent);
        let a = tissues.clone().ascend_with(d, b.gas(), &again, t);
        asc = a.path.iter().map(|&(x, y)| (t + x, y)).collect();
        gas_changes = planned_changes(&a, t, &b);
    }
    let stops = if replanned {
        stops_of(&flown)
    } else {
        ascent.stops
    };
    let tts_at_end = flown.last().unwrap().0 - bottom_end;
    profile.extend(flown.into_iter().skip(1));
    let runtime = profile.last().unwrap().0;
    let samples = rec.samples;

    let min_ndl = min_ndl(&samples);
    let mean_depth = mean_depth(&profile, runtime);

    let gas = gas_check(cfg, &b, used_bottom, max_depth);
    DiveResult {
        profile,
        samples,
        descent_time,
        bottom_time: track.duration(),
        runtime,
        max_depth,
        mean_depth,
        stops,
        safety_stop,
        min_ndl,
        deco_from,
        max_ceiling,
        ceiling_at_end,
        tts_at_end,
        ascent_ceiling_excess: excess,
        switches: b.switches.clone(),
        gas,
        oxygen: b.oxygen,
    }
}

/// The ascent the model requires from `(bottom_end, last_depth)` (runtime s, m), planned on a
/// copy of `tissues` with `base`: the planned ascent, the path to fly, its gas changes as
/// (runtime, cylinder) and, for a direct ascent from 10 m or deeper, the safety stop at 5 m
/// (3 min) that then replaces the planned path.
#[allow(clippy::type_complexity)]
fn plan_ascent(
    cfg: &DiveConfig,
    tissues: &Tissues,
    b: &Breathing,
    base: &AscentPlan,
    (bottom_end, last_depth): (f64, f64),
    max_depth: f64,
) -> (
    super::deco::Ascent,
    Vec<(f64, f64)>,
    Vec<(f64, usize)>,
    Option<Stop>,
) {
    let mut planned = tissues.clone();
    let ascent = planned.ascend_with(last_depth, b.gas(), base, bottom_end);
    let mut asc: Vec<(f64, f64)> = ascent
        .path
        .iter()
        .map(|&(t, d)| (bottom_end + t, d))
        .collect();
    let mut gas_changes = planned_changes(&ascent, bottom_end, b);
    let mut safety_stop = None;
    if ascent.stops.is_empty() && max_depth >= 10.0 && last_depth > 5.0 {
        let t5 = bottom_end + (last_depth - 5.0) / cfg.ascent_rate;
        asc = vec![
            (bottom_end, last_depth),
            (t5, 5.0),
            (t5 + 180.0, 5.0),
            (t5 + 180.0 + 5.0 / cfg.ascent_rate, 0.0),
        ];
        // The travel gases from their switch depths (a vertex at each), as on any ascent.
        gas_changes = travel_changes(cfg, b, &mut asc);
        safety_stop = Some(Stop {
            depth: 5.0,
            duration: 180.0,
        });
    }
    (ascent, asc, gas_changes, safety_stop)
}

/// The shortest no-decompression limit of the samples, s.
fn min_ndl(samples: &[Sample]) -> Option<f64> {
    samples
        .iter()
        .filter_map(|s| match s.ndl {
            Some(Ndl::Limit(n)) => Some(n),
            _ => None,
        })
        .reduce(f64::min)
}

/// The descent and bottom vertices (runtime s, depth m) and the descent's duration; the
/// descent gets a vertex at each travel gas's switch depth, so that no step breathes a travel
/// gas past it.
fn descent_and_bottom(cfg: &DiveConfig, track: &Track) -> (Vec<(f64, f64)>, f64) {
    let d0 = track.points.first().map(|p| p.1).unwrap_or(0.0);
    let descent_time = d0 / cfg.descent_rate;
    let mut profile: Vec<(f64, f64)> = vec![(0.0, 0.0)];
    let mut cuts: Vec<f64> = cfg
        .tanks
        .iter()
        .filter(|t| t.role == CylinderRole::Travel)
        .filter_map(|t| t.switch_depth)
        .filter(|&s| s > 1e-9 && s < d0 - 1e-9)
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    for s in cuts {
        profile.push((s / cfg.descent_rate, s));
    }
    for p in &track.points {
        profile.push((descent_time + p.0, p.1));
    }
    let bottom_end = descent_time + track.duration();
    let last_depth = track.points.last().map(|p| p.1).unwrap_or(0.0);
    if track.tail > 0.0 {
        profile.push((bottom_end, last_depth));
    }
    (profile, descent_time)
}

/// The mean depth of a profile over `runtime` s (the area under it), m.
fn mean_depth(profile: &[(f64, f64)], runtime: f64) -> f64 {
    let mut area = 0.0;
    for w in profile.windows(2) {
        area += 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0);
    }
    if runtime > 0.0 { area / runtime } else { 0.0 }
}

/// A planned ascent's gas changes as (runtime, cylinder), the ascent starting at `t0` s.
fn planned_changes(a: &super::deco::Ascent, t0: f64, b: &Breathing) -> Vec<(f64, usize)> {
    a.switches
        .iter()
        .filter_map(|&(t, _, g)| b.deco_tank(g).map(|i| (t0 + t, i)))
        .collect()
}

/// The samples of a dive: every `every` s (none when `None`), the ceiling, NDL, time to
/// surface and pressures.
struct Recorder {
    every: Option<f64>,
    /// Runtime of the next sample, s.
    next: f64,
    samples: Vec<Sample>,
    /// The ascent plans of a dive in deco and within the NDL.
    plan: AscentPlan,
    direct: AscentPlan,
}

impl Recorder {
    /// Record a sample at runtime `t`, `depth` m, when one is due.
    fn record(&mut self, t: f64, depth: f64, tissues: &Tissues, b: &Breathing) {
        let Some(every) = self.every else { return };
        if t + 1e-9 < self.next {
            return;
        }
        self.next += every;
        let in_deco = tissues.in_deco();
        let mut probe = tissues.clone();
        // The time to surface on the gases still there (not the cylinders left at their reserve).
        let mut left = if in_deco {
            self.plan.clone()
        } else {
            self.direct.clone()
        };
        left.deco_gases = b.ascent_gases(in_deco);
        let asc = probe.ascend_with(depth, b.gas(), &left, t);
        let stop = asc.stops.first().copied();
        let pressures = b.pressures();
        self.samples.push(Sample {
            time: t,
            depth,
            ceiling: tissues.ceiling(),
            ndl: Some(tissues.ndl(depth, b.gas())),
            tts: asc.tts,
            // The first planned stop; in deco without one (the ascent itself clears the
            // ceiling), the ceiling rounded up to the 3 m level.
            stop_depth: stop
                .map(|s| s.depth)
                .or_else(|| in_deco.then(|| ((tissues.ceiling() / 3.0).ceil() * 3.0).max(3.0))),
            stop_time: stop.map(|s| s.duration),
            in_deco,
            cylinder: b.current,
            pressure: pressures[b.current],
            pressures,
        });
    }
}

/// How a stretch of the profile is breathed: the bottom (stages to their reserve, then
/// the back gas), or one leg of the ascent (the planned gas changes; a cylinder at its
/// reserve left for the next gas, and — when the stops depend on the gas, `replan` — the
/// leg cut there so that the rest of the ascent is planned again on the gas breathed).
enum Leg<'s> {
    /// The descent ends at `descent_end` s runtime.
    Bottom { descent_end: f64 },
    Ascent {
        planned: &'s dyn Fn(f64) -> Option<usize>,
        deco: bool,
        replan: bool,
    },
}

/// Integrate in ≤ 1 s steps. Returns where an ascent leg was cut (runtime s, depth m):
/// there the diver moved to another gas and the ascent must be planned again.
fn integrate(
    env: &Environment,
    sac: f64,
    tissues: &mut Tissues,
    b: &mut Breathing,
    vertices: &[(f64, f64)],
    leg: Leg,
    on_step: &mut dyn FnMut(f64, f64, &Tissues, &Breathing),
) -> Option<(f64, f64)> {
    for w in vertices.windows(2) {
        let ((t0, a), (t1, d1)) = (w[0], w[1]);
        let dt = t1 - t0;
        if dt <= 0.0 {
            continue;
        }
        let n = dt.ceil().max(1.0) as usize;
        let h = dt / n as f64;
        for i in 0..n {
            let f = (i as f64 + 0.5) / n as f64;
            let d = a + (d1 - a) * f;
            let p = env.pressure(d);
            let ts = t0 + i as f64 * h;
            let need = gas::consumption(sac, p, h);
            let ds = a + (d1 - a) * i as f64 / n as f64;
            match &leg {
                Leg::Bottom { descent_end } => {
                    let de = a + (d1 - a) * (i + 1) as f64 / n as f64;
                    b.pick_descent(need, ts, ds, de, ts + 1e-9 < *descent_end);
                    b.pick_bottom(need, ts, ds);
                }
                Leg::Ascent {
                    planned,
                    deco,
                    replan,
                } => {
                    if let Some(c) = planned(ts + 0.5 * h) {
                        b.switch_to(c, ts, ds);
                    }
                    let before = b.gas();
                    if b.pick_ascent(need, ts, ds, *deco) && *replan && b.gas() != before {
                        return Some((ts, ds));
                    }
                }
            }
            tissues.expose_pressure(p, b.gas(), h);
            let t = ts + h;
            let de = a + (d1 - a) * (i + 1) as f64 / n as f64;
            let o2 = b.gas().o2;
            b.oxygen.breathe(
                ts,
                h,
                (ds, env.pressure(ds) * o2),
                (de, env.pressure(de) * o2),
            );
            b.breathe(need, t, ds.min(de), ds.max(de));
            on_step(t, de, tissues, b);
        }
    }
    None
}

/// The travel-gas changes along an ascent `path` flown without the planner (the direct ascent
/// with its safety stop): where the path first reaches a travel gas's switch depth (a vertex
/// is inserted there), the diver takes the richest travel gas allowed there if it is richer
/// than the gas breathed. As (runtime s, cylinder).
fn travel_changes(
    cfg: &DiveConfig,
    b: &Breathing,
    path: &mut Vec<(f64, f64)>,
) -> Vec<(f64, usize)> {
    let travel: Vec<(usize, f64)> = (0..cfg.tanks.len())
        .filter(|&i| cfg.tanks[i].role == CylinderRole::Travel && !b.exhausted[i])
        .filter_map(|i| cfg.tanks[i].switch_depth.map(|s| (i, s)))
        .collect();
    let mut points: Vec<(f64, usize)> = Vec::new();
    for &(i, sw) in &travel {
        // First time the path is at or above the switch depth.
        let mut at = None;
        for k in 0..path.len() {
            let (t, d) = path[k];
            if d <= sw + 1e-9 {
                if k > 0 && path[k - 1].1 > sw + 1e-9 {
                    let (t0, d0) = path[k - 1];
                    let tc = t0 + (t - t0) * (d0 - sw) / (d0 - d);
                    if tc > t0 + 1e-9 && tc < t - 1e-9 {
                        path.insert(k, (tc, sw));
                    }
                    at = Some(tc.max(t0));
                } else {
                    at = Some(t);
                }
                break;
            }
        }
        if let Some(t) = at {
            points.push((t, i));
        }
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut o2 = b.gas().o2;
    let mut out = Vec::new();
    for (k, &(t, _)) in points.iter().enumerate() {
        // Every travel gas allowed by then; the richest, if richer than the gas breathed.
        if let Some(&(_, i)) = points[..=k]
            .iter()
            .max_by(|a, b| cfg.tanks[a.1].gas.o2.total_cmp(&cfg.tanks[b.1].gas.o2))
            && cfg.tanks[i].gas.o2 > o2
        {
            o2 = cfg.tanks[i].gas.o2;
            out.push((t, i));
        }
    }
    out
}

/// The stops of a flown ascent path: its level stretches below the surface, one per depth
/// (consecutive stretches at one depth merged).
fn stops_of(path: &[(f64, f64)]) -> Vec<Stop> {
    let mut stops: Vec<Stop> = Vec::new();
    for w in path.windows(2) {
        let ((t0, d0), (t1, d1)) = (w[0], w[1]);
        if t1 - t0 <= 1e-9 || (d1 - d0).abs() > 1e-6 || d0 <= 1e-6 {
            continue;
        }
        match stops.last_mut() {
            Some(s) if (s.depth - d0).abs() < 1e-6 => s.duration += t1 - t0,
            _ => stops.push(Stop {
                depth: d0,
                duration: t1 - t0,
            }),
        }
    }
    stops
}

fn gas_check(cfg: &DiveConfig, b: &Breathing, used_bottom: f64, max_depth: f64) -> GasCheck {
    let env = cfg.env;
    let bottom_idx: Vec<usize> = (0..cfg.tanks.len())
        .filter(|&i| cfg.tanks[i].bottom_phase())
        .collect();
    let used_phase: f64 = bottom_idx.iter().map(|&i| b.used[i]).sum();
    let used_ascent_bottom = used_phase - used_bottom;
    let start = cfg.supply.start;
    let min_gas = SAC_FACTOR
        * (gas::consumption(cfg.sac_lpm, env.pressure(max_depth), PROBLEM_SOLVING)
            + used_ascent_bottom);
    let at_end_of_bottom = start - used_bottom;
    // Hypoxic limit: 0.16 bar, or air's own pO₂ at an altitude site's surface.
    let hypoxic_limit = hypoxic_limit(&env);
    let cylinders: Vec<CylinderUse> = cfg
        .tanks
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let limit = cfg.po2_limit(t);
            let max = b.max_po2[i];
            let left = t.start - b.used[i];
            CylinderUse {
                name: t.name.clone(),
                gas: gas_label(t.gas),
                role: t.role,
                start: t.start,
                used: b.used[i],
                end_pressure: if left > 0.0 {
                    t.pressure_after(b.used[i])
                } else {
                    0.0
                },
                reserve_ok: left >= t.reserve - 1e-9,
                max_po2: max.map(|m| m.0),
                max_po2_depth: max.map(|m| m.1).unwrap_or(0.0),
                min_po2: b.min_po2[i].map(|m| m.0),
                min_po2_depth: b.min_po2[i].map(|m| m.1).unwrap_or(0.0),
                po2_limit: limit,
                mod_depth: t.gas.mod_depth(&env, limit),
                po2_ok: max.is_none_or(|m| m.0 <= limit + 1e-9),
                hypoxic: b.min_po2[i].is_some_and(|m| m.0 < hypoxic_limit),
            }
        })
        .collect();
    // The back gas breathed last tells the end pressure of the bottom supply.
    let last_bottom = b
        .switches
        .iter()
        .rev()
        .map(|s| s.cylinder)
        .find(|&i| cfg.tanks[i].bottom_phase())
        .unwrap_or(bottom_idx[0]);
    GasCheck {
        end_pressure: cylinders[last_bottom].end_pressure,
        reserve_ok: cylinders.iter().all(|c| c.reserve_ok),
        cylinders,
        used: used_phase,
        start,
        reserve_bar: cfg.reserve_bar,
        thirds_ok: used_phase <= start * 2.0 / 3.0,
        min_gas,
        min_gas_ok: at_end_of_bottom >= min_gas,
        at_end_of_bottom,
        reserve_reached_at: b.reserve_reached_at,
        empty_at: b.empty_at,
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
    /// No problem at all: the plan may be dived as it is.
    pub ok: bool,
    pub within_ndl: bool,
    pub deco_required: bool,
    /// OK as a planned-decompression dive (`diver.deco = "planned"`): the stops are the plan.
    pub deco_planned: bool,
    /// The decompression plan in words (stops, gases, runtime) when decompression is required.
    pub deco_plan: Option<String>,
    pub gas_ok: bool,
    /// Every gas within its pO₂ limit where it is breathed and none hypoxic at the surface.
    pub gases_ok: bool,
    pub problems: Vec<String>,
    /// Not failing the plan, but worth knowing (Subsurface's minimum gas, a thin NDL margin).
    pub advice: Vec<String>,
    pub suggestions: Vec<Suggestion>,
    /// The lost-gas plans ([`lost_gas_plans`]): each must hold for the verdict to be OK.
    pub lost_gas: Vec<LostGasPlan>,
}

/// A lost-gas plan: the ascent when cylinders are lost at the end of the bottom time.
#[derive(Debug, Clone, Serialize)]
pub struct LostGasPlan {
    /// What is lost: `deco` (a travel or deco gas) or `bottom` (every bottom cylinder: the
    /// bailout's plan).
    pub kind: String,
    /// Names of the cylinders lost.
    pub lost: Vec<String>,
    /// Runtime of this plan and the planned dive's, s.
    pub runtime: f64,
    pub planned_runtime: f64,
    /// Its stops.
    pub stops: Vec<Stop>,
    /// Every cylinder: (name, gas, litres breathed, bar left); the lost ones breathe nothing
    /// after the loss.
    pub cylinders: Vec<(String, String, f64, f64)>,
    /// CNS % and OTU of the whole dive with this ascent.
    pub cns_percent: f64,
    pub otu: f64,
    /// Whether it holds: no cylinder breathed empty (the reserve is what it may spend), every
    /// gas within its pO₂ limit and not hypoxic where breathed, CNS within 100 %, no pO₂
    /// beyond the NOAA table, the ceiling never above the diver.
    pub holds: bool,
    /// Why not, when it does not.
    pub faults: Vec<String>,
}

/// The lost-gas plans of a dive: for each travel or deco cylinder breathed on the ascent,
/// the ascent without it (on the back gas and the gases left); with bailout cylinders, the
/// ascent on them (and the travel and deco gases) after losing every bottom cylinder.
pub fn lost_gas_plans(cfg: &DiveConfig, track: &Track, dive: &DiveResult) -> Vec<LostGasPlan> {
    let ascent_start = dive.descent_time + dive.bottom_time;
    let breathed_up = |i: usize| {
        dive.switches
            .iter()
            .any(|s| s.cylinder == i && s.time >= ascent_start - 1e-6)
    };
    let mut cases: Vec<(String, Vec<usize>)> = (0..cfg.tanks.len())
        .filter(|&i| cfg.tanks[i].role.switched() && breathed_up(i))
        .map(|i| ("deco".to_string(), vec![i]))
        .collect();
    if cfg.tanks.iter().any(|t| t.role == CylinderRole::Bailout) {
        let bottom: Vec<usize> = (0..cfg.tanks.len())
            .filter(|&i| cfg.tanks[i].bottom_phase())
            .collect();
        cases.push(("bottom".to_string(), bottom));
    }
    cases
        .into_iter()
        .map(|(kind, lost)| {
            let mut t = Tissues::surface(cfg.env, cfg.gf);
            let r = simulate_losing(cfg, track, &mut t, None, &lost);
            let mut faults = Vec::new();
            for c in &r.gas.cylinders {
                if c.end_pressure <= 0.0 && c.used > 0.0 {
                    faults.push(format!("'{}' ({}) is breathed empty", c.name, c.gas));
                }
                if !c.po2_ok {
                    faults.push(format!(
                        "'{}' ({}) pO₂ {:.2} bar at {:.1} m",
                        c.name,
                        c.gas,
                        c.max_po2.unwrap_or(0.0),
                        c.max_po2_depth
                    ));
                }
                if c.hypoxic {
                    faults.push(format!(
                        "'{}' ({}) hypoxic at {:.1} m",
                        c.name, c.gas, c.min_po2_depth
                    ));
                }
            }
            if !r.oxygen.within_limits() {
                faults.push(format!(
                    "CNS {:.0} %, highest pO₂ {:.2} bar",
                    r.oxygen.cns_percent, r.oxygen.max_po2
                ));
            }
            if r.ascent_ceiling_excess > CEILING_TOLERANCE {
                faults.push(format!(
                    "the ascent breaks the ceiling by {:.2} m",
                    r.ascent_ceiling_excess
                ));
            }
            LostGasPlan {
                kind,
                lost: lost.iter().map(|&i| cfg.tanks[i].name.clone()).collect(),
                runtime: r.runtime,
                planned_runtime: dive.runtime,
                stops: r.stops.clone(),
                cylinders: r
                    .gas
                    .cylinders
                    .iter()
                    .map(|c| (c.name.clone(), c.gas.clone(), c.used, c.end_pressure))
                    .collect(),
                cns_percent: r.oxygen.cns_percent,
                otu: r.oxygen.otu,
                holds: faults.is_empty(),
                faults,
            }
        })
        .collect()
}

/// A lost-gas plan in one line.
pub fn lost_gas_line(p: &LostGasPlan) -> String {
    let stops: f64 = p.stops.iter().map(|s| s.duration).sum();
    let left: Vec<String> = p
        .cylinders
        .iter()
        .filter(|c| !p.lost.contains(&c.0))
        .map(|c| format!("'{}' {:.0} bar", c.0, c.3))
        .collect();
    format!(
        "{} lost at the end of the bottom time: runtime {} ({}{} against the plan), {} of stops; \
         left {}; CNS {:.1} %, OTU {:.0} → {}",
        p.lost
            .iter()
            .map(|n| format!("'{n}'"))
            .collect::<Vec<_>>()
            .join(", "),
        mmss(p.runtime),
        if p.runtime >= p.planned_runtime {
            "+"
        } else {
            "−"
        },
        mmss((p.runtime - p.planned_runtime).abs()),
        mmss(stops),
        left.join(", "),
        p.cns_percent,
        p.otu,
        if p.holds {
            "holds".to_string()
        } else {
            format!("DOES NOT HOLD ({})", p.faults.join("; "))
        }
    )
}

/// How far (m) the flown ascent may put the ceiling below the diver before a planned
/// decompression is NOT SAFE: 1 cm, the rounding of the 1 s steps against the planner's 2 s
/// trial ascents.
pub const CEILING_TOLERANCE: f64 = 0.01;

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

fn role_name(r: CylinderRole) -> &'static str {
    r.name()
}

fn mmss(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

/// Judge a dive and compute remedies.
pub fn verdict(cfg: &DiveConfig, track: &Track, dive: &DiveResult) -> Verdict {
    let mut problems = Vec::new();
    let mut advice = Vec::new();
    let deco = dive.deco_required();
    // Gases first: a gas that poisons or starves the diver outweighs everything else.
    gas_problems(cfg, dive, &mut problems);
    oxygen_findings(dive, &mut problems, &mut advice);
    let planned = cfg.deco == DecoMode::Planned;
    // With decompression planned, the stops are the plan, not a problem; everything else
    // still is. The plan in words, for the report, either way.
    let deco_lines = deco_lines(cfg, dive);
    let deco_plan = deco.then(|| deco_plan(cfg, dive, &deco_lines));
    if !planned {
        problems.extend(deco_lines);
    } else if deco && dive.ascent_ceiling_excess > CEILING_TOLERANCE {
        // The planner's own trial ascents keep the diver below the ceiling; the flown profile is
        // checked again, step by step, so that a planned dive is never OK above its ceiling.
        problems.push(format!(
            "the ascent breaks the ceiling by {:.2} m: the decompression plan does not hold",
            dive.ascent_ceiling_excess
        ));
    }
    let g = &dive.gas;
    supply_findings(cfg, g, &mut problems, &mut advice);
    narcosis_findings(cfg, dive, &mut problems, &mut advice);
    let mut suggestions = Vec::new();
    if !g.breathable() {
        // Every other remedy is moot while a gas is unfit: name the gas that would do.
        suggestions.push(Suggestion {
            kind: "gas".into(),
            text: gas_advice(&cfg.env, dive.max_depth, cfg.po2_bottom, cfg.end_limit),
            fixes_all: false,
        });
    } else if !problems.is_empty() {
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
    // Lost-gas plans: a decompression plan (or a bailout) is only as good as its fallback.
    // (Without `deco = "planned"` a dive that needs stops fails anyway: its deco gases are a
    // contingency, and their loss is planned only when decompression is.)
    let lost_gas = if (deco && planned) || cfg.tanks.iter().any(|t| t.role == CylinderRole::Bailout)
    {
        lost_gas_plans(cfg, track, dive)
    } else {
        Vec::new()
    };
    for p in lost_gas.iter().filter(|p| !p.holds) {
        problems.push(format!("lost-gas plan: {}", lost_gas_line(p)));
    }
    // The simulator's own rules (the NDL aside when decompression is planned) back the list.
    let rules_ok = if planned {
        dive.gas.ok() && dive.gas.breathable() && dive.oxygen.within_limits()
    } else {
        dive.ok()
    };
    if !rules_ok && problems.is_empty() {
        problems.push("the plan breaks a rule of the dive".into());
    }
    let ok = rules_ok && problems.is_empty();
    if ok {
        suggestions.clear();
    }
    Verdict {
        ok,
        within_ndl: !deco,
        deco_required: deco,
        deco_planned: ok && deco,
        deco_plan,
        lost_gas,
        gas_ok: g.ok(),
        gases_ok: g.breathable(),
        problems,
        advice,
        suggestions,
    }
}

/// The problems of the gases themselves: a pO₂ above a cylinder's limit, a hypoxic gas where
/// it is breathed.
fn gas_problems(cfg: &DiveConfig, dive: &DiveResult, problems: &mut Vec<String>) {
    for (i, c) in dive.gas.cylinders.iter().enumerate() {
        let role = role_name(cfg.tanks[i].role);
        if !c.po2_ok
            && let Some(p) = c.max_po2
        {
            problems.push(format!(
                "cylinder '{}' ({}, {role}): pO₂ {p:.2} bar at {:.1} m, above the {:.1} bar limit \
                 of a {role} gas (MOD {:.0} m){}",
                c.name,
                c.gas,
                c.max_po2_depth,
                c.po2_limit,
                depth_limit(c.mod_depth),
                if cfg.tanks[i].role.switched() {
                    format!(
                        "; its switch depth is {:.0} m",
                        depth_limit(cfg.tanks[i].switch_depth.unwrap_or(0.0))
                    )
                } else {
                    String::new()
                }
            ));
        }
        if c.hypoxic {
            let from = gas::breathable_from(&cfg.env, cfg.tanks[i].gas);
            problems.push(format!(
                "cylinder '{}' ({}, {role}): hypoxic where it is breathed — pO₂ {:.2} bar at \
                 {:.1} m, below {:.2} bar; it is breathable only from {:.0} m down{}",
                c.name,
                c.gas,
                c.min_po2.unwrap_or(0.0),
                c.min_po2_depth,
                hypoxic_limit(&cfg.env).min(HYPOXIC),
                from.ceil(),
                if cfg.tanks[i].role.is_bottom() {
                    format!(
                        ": carry a travel gas (`role = \"travel\"`) with a switch depth of at \
                         least {:.0} m",
                        from.ceil()
                    )
                } else {
                    String::new()
                }
            ));
        }
    }
}

/// Oxygen toxicity (CNS % against the NOAA limits, OTU against a single-dive figure).
fn oxygen_findings(dive: &DiveResult, problems: &mut Vec<String>, advice: &mut Vec<String>) {
    let ox = &dive.oxygen;
    // Beyond the table even within the diver's own limits (a cylinder above its own limit is
    // reported above already).
    if ox.max_po2 > oxygen::PO2_TABLE_MAX + 1e-9 && dive.gas.cylinders.iter().all(|c| c.po2_ok) {
        problems.push(format!(
            "pO₂ {:.2} bar at {:.1} m ({} runtime), beyond the 1.6 bar end of the NOAA oxygen \
             limits whatever the diver's own limits; {:.1} min breathed above it (CNS there \
             extrapolated steeply: ×2.7 per 0.1 bar)",
            ox.max_po2,
            ox.max_po2_depth,
            mmss(ox.max_po2_time),
            ox.minutes_above_table
        ));
    }
    if ox.cns_percent > oxygen::CNS_LIMIT {
        problems.push(format!(
            "CNS oxygen toxicity {:.1} %: above 100 % of the NOAA single-exposure limits \
             (highest pO₂ {:.2} bar at {:.1} m); breathe a leaner gas or shorten the exposure",
            ox.cns_percent, ox.max_po2, ox.max_po2_depth
        ));
    } else if ox.cns_percent > oxygen::CNS_WARN {
        advice.push(format!(
            "CNS oxygen toxicity {:.1} %: above the 80 % warning level of the NOAA \
             single-exposure limits (highest pO₂ {:.2} bar at {:.1} m); no repetitive dive \
             on oxygen-rich gas until it has come down (half-time 90 min)",
            ox.cns_percent, ox.max_po2, ox.max_po2_depth
        ));
    }
    if ox.otu > oxygen::OTU_WARN {
        advice.push(format!(
            "pulmonary oxygen exposure {:.0} OTU: above the {:.0} OTU single-dive planning \
             figure (REPEX: at most 850 OTU in one day)",
            ox.otu,
            oxygen::OTU_WARN
        ));
    }
}

/// The decompression obligation in words (none within the NDL).
fn deco_lines(cfg: &DiveConfig, dive: &DiveResult) -> Vec<String> {
    let deco = dive.deco_required();
    let mut deco_lines: Vec<String> = Vec::new();
    if deco && dive.stops.is_empty() {
        deco_lines.push(format!(
            "decompression dive: the ceiling leaves the surface at {} runtime ({} into the \
             survey; ceiling {:.1} m at the end of the bottom time) at GF {:.0}/{:.0}; the ascent \
             itself clears it without a stop, but the no-decompression limit is exceeded",
            mmss(dive.deco_from.unwrap_or(0.0)),
            mmss(dive.deco_from.unwrap_or(0.0) - dive.descent_time),
            dive.ceiling_at_end,
            cfg.gf.low * 100.0,
            cfg.gf.high * 100.0
        ));
    }
    if deco && !dive.stops.is_empty() {
        let total: f64 = dive.stops.iter().map(|s| s.duration).sum();
        let stops = dive
            .stops
            .iter()
            .map(|s| format!("{:.0} m {}", s.depth, mmss(s.duration)))
            .collect::<Vec<_>>()
            .join(", ");
        deco_lines.push(format!(
            "decompression obligation: the NDL runs out at {} runtime ({} into the survey); \
             {} of mandatory stops ({stops}) at GF {:.0}/{:.0}",
            mmss(dive.deco_from.unwrap_or(0.0)),
            mmss(dive.deco_from.unwrap_or(0.0) - dive.descent_time),
            mmss(total),
            cfg.gf.low * 100.0,
            cfg.gf.high * 100.0
        ));
    }
    deco_lines
}

/// The decompression plan in words: the obligation, the gas switches on the ascent, the
/// runtime.
fn deco_plan(cfg: &DiveConfig, dive: &DiveResult, deco_lines: &[String]) -> String {
    let switches: Vec<String> = dive
        .switches
        .iter()
        .skip(1)
        .filter(|s| s.time > dive.descent_time + dive.bottom_time - 1e-6)
        .map(|s| {
            format!(
                "{} at {:.0} m",
                gas_label(cfg.tanks[s.cylinder].gas),
                s.depth
            )
        })
        .collect();
    format!(
        "{}; gas switches on the ascent: {}; runtime {}",
        deco_lines.join("; "),
        if switches.is_empty() {
            "none".to_string()
        } else {
            switches.join(", ")
        },
        mmss(dive.runtime)
    )
}

/// The gas supply `g`: a cylinder short of its reserve, else the rule of thirds and the
/// minimum gas.
fn supply_findings(
    cfg: &DiveConfig,
    g: &GasCheck,
    problems: &mut Vec<String>,
    advice: &mut Vec<String>,
) {
    let bar = |l: f64| cfg.supply.pressure_after(cfg.supply.start - l);
    if !g.reserve_ok {
        let when = match (g.empty_at, g.reserve_reached_at) {
            (Some(e), _) => format!("; a cylinder is empty at {} runtime", mmss(e)),
            (None, Some(r)) => format!("; the reserve is reached at {} runtime", mmss(r)),
            _ => String::new(),
        };
        for (i, c) in g
            .cylinders
            .iter()
            .enumerate()
            .filter(|(_, c)| !c.reserve_ok)
        {
            let t = &cfg.tanks[i];
            problems.push(format!(
                "not enough gas in cylinder '{}' ({}, {}): {:.0} l breathed from it, it holds \
                 {:.0} l ({:.0} l above the {:.0} bar reserve), {:.0} bar left at the end{when}",
                c.name,
                c.gas,
                role_name(t.role),
                c.used,
                c.start,
                c.start - t.reserve,
                cfg.reserve_bar,
                c.end_pressure
            ));
        }
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
}

/// Narcosis: a breathed gas whose END at its deepest is beyond the limit (advice: the END
/// limit is a choice of the diver's agency, the pO₂ and hypoxic limits are physiology).
fn narcosis_findings(
    cfg: &DiveConfig,
    dive: &DiveResult,
    problems: &mut Vec<String>,
    advice: &mut Vec<String>,
) {
    for (i, c) in dive.gas.cylinders.iter().enumerate() {
        let t = &cfg.tanks[i];
        if c.max_po2.is_none() {
            continue;
        }
        let end = t.gas.end(&cfg.env, c.max_po2_depth);
        if end > cfg.end_limit + 1e-6 && t.role == CylinderRole::Travel {
            // A travel gas is chosen for the shallows: breathed past its END, its switch is
            // too deep, and switching shallower costs nothing.
            problems.push(format!(
                "travel gas '{}' ({}) is breathed to {:.1} m, where its END is {end:.1} m, deeper \
                 than the {:.0} m END limit (O₂ counted as narcotic); its switch depth is {:.0} m, \
                 at most {:.0} m keeps it within the limit",
                c.name,
                c.gas,
                c.max_po2_depth,
                depth_limit(cfg.end_limit),
                depth_limit(t.switch_depth.unwrap_or(0.0)),
                depth_limit(gas::end_depth(&cfg.env, t.gas, cfg.end_limit)),
            ));
        } else if end > cfg.end_limit + 1e-6 {
            let fit = bottom_gas(&cfg.env, c.max_po2_depth, cfg.po2_limit(t), cfg.end_limit)
                .map(|b| format!("; e.g. {}", bottom_gas_phrase(&b)))
                .unwrap_or_default();
            advice.push(format!(
                "narcosis: cylinder '{}' ({}) has an END of {end:.1} m at {:.1} m, deeper than \
                 the {:.0} m END limit (O₂ counted as narcotic){fit}",
                c.name,
                c.gas,
                c.max_po2_depth,
                depth_limit(cfg.end_limit),
            ));
        }
    }
}

/// A [`BottomGas`] in words: `TX19/44`, or `TX10/70 (a bottom gas: hypoxic at the surface,
/// breathed from 6 m down, EAN40 as travel gas above, a cylinder with role = "travel")`.
pub fn bottom_gas_phrase(b: &BottomGas) -> String {
    match b.travel {
        None => gas_label(b.gas),
        Some((travel, from)) => format!(
            "{} (a bottom gas: hypoxic at the surface, breathed from {from:.0} m down, {} as \
             travel gas above, a cylinder with `role = \"travel\"`)",
            gas_label(b.gas),
            gas_label(travel)
        ),
    }
}

/// The "breathable gases" advice for a bottom at `depth` m: what [`bottom_gas`] names there
/// under the pO₂ and END limits, in words. Never names a gas beyond either limit.
pub fn gas_advice(env: &super::deco::Environment, depth: f64, po2: f64, end_limit: f64) -> String {
    let rules = format!(
        "deco gases only from their switch depth; no gas below {HYPOXIC:.2} bar pO₂ at the surface"
    );
    match bottom_gas(env, depth, po2, end_limit) {
        Some(b) => {
            let he = if b.gas.he > 0.0 {
                format!(
                    " and at least {:.0} % He for an END within {:.0} m (O₂ counted as narcotic)",
                    b.gas.he * 100.0,
                    depth_limit(end_limit)
                )
            } else {
                String::new()
            };
            format!(
                "breathable gases: at {depth:.1} m a bottom gas may hold at most {:.0} % O₂ \
                 (pO₂ {po2:.1} bar){he}, e.g. {}; {rules}",
                b.gas.o2 * 100.0,
                bottom_gas_phrase(&b)
            )
        }
        None => format!(
            "breathable gases: no mix keeps pO₂ ≤ {po2:.1} bar and an END within {:.0} m at \
             {depth:.1} m; {rules}",
            depth_limit(end_limit)
        ),
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
        let best = max_strips(cfg, track);
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
                "faster swim: {v:.2} m/s instead of {:.3} m/s (×{hi:.2}, survey {} instead of {}) fits \
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

    // 5. Nitrox for the decompression part (gas quantity unchanged): only within the diver's
    // pO₂ limit at the deepest point and within the END limit (nitrox's END is its depth).
    if dive.deco_required() && dive.max_depth <= cfg.end_limit + 1e-9 {
        for o2 in [0.32, 0.36] {
            let mix = Gas { o2, he: 0.0 };
            let mod_m = mix.mod_depth(&cfg.env, cfg.po2_bottom);
            if mod_m < dive.max_depth {
                continue;
            }
            let c = cfg.with_bottom_gas(mix);
            let r = simulate_fresh(&c, track, None);
            if !r.deco_required() {
                out.push(Suggestion {
                    kind: "nitrox".into(),
                    text: format!(
                        "nitrox: EAN{:.0} (MOD {:.0} m at pO₂ {:.1}) keeps the whole survey within \
                         the NDL{}",
                        o2 * 100.0,
                        depth_limit(mod_m),
                        cfg.po2_bottom,
                        if r.gas.ok() {
                            ""
                        } else {
                            " — the gas quantity problem remains"
                        }
                    ),
                    fixes_all: r.gas.ok(),
                });
                break;
            }
        }
    }
    out
}

/// The largest number of strips, from the first, that one dive from clean tissues carries
/// within the NDL and the gas rules (0: not even one strip).
pub fn max_strips(cfg: &DiveConfig, track: &Track) -> usize {
    let n = track.strips().len();
    let fits = |k: usize| simulate_fresh(cfg, &track.strip_range(0, k), None).ok();
    (1..=n).rev().find(|&k| fits(k)).unwrap_or(0)
}

/// One dive of a split survey: strips `first..=last` (1-based) and the simulated dive, whose
/// `oxygen.cns_percent` includes the CNS carried in from the dives before it.
#[derive(Debug, Clone, Serialize)]
pub struct SplitDive {
    pub first_strip: usize,
    pub last_strip: usize,
    pub dive: DiveResult,
    /// OTU of the day up to the end of this dive (this dive's and every earlier one's).
    pub otu_day: f64,
}

/// Split the strips into the fewest dives (≤ `max_per_dive` strips each, as even as possible;
/// a full cylinder each; repetitive tissues across `cfg.surface_interval`) where every dive
/// is [`DiveResult::ok`] with the CNS carried over the surface intervals (halved every 90 min,
/// [`oxygen::cns_after_surface_interval`]) and the day's OTU within
/// [`oxygen::OTU_DAY_LIMIT`]. `None` when no split of up to six more dives fits.
/// `sample_every` as in [`simulate`].
pub fn split(
    cfg: &DiveConfig,
    track: &Track,
    max_per_dive: usize,
    sample_every: Option<f64>,
) -> Option<Vec<SplitDive>> {
    let n = track.strips().len();
    if max_per_dive == 0 || n == 0 {
        return None;
    }
    let first = n.div_ceil(max_per_dive);
    'count: for dives in first..=(first + 6).min(n) {
        let mut tissues = Tissues::surface(cfg.env, cfg.gf);
        let mut parts = Vec::new();
        let mut start = 0;
        let mut cns = 0.0; // CNS % at the start of the next dive
        let mut otu_day = 0.0;
        for i in 0..dives {
            let end = (n * (i + 1)).div_ceil(dives);
            let mut r = simulate(
                cfg,
                &track.strip_range(start, end),
                &mut tissues,
                sample_every,
            );
            r.oxygen.carry_in(cns);
            otu_day += r.oxygen.otu;
            if !r.ok() || otu_day > oxygen::OTU_DAY_LIMIT {
                continue 'count;
            }
            cns = oxygen::cns_after_surface_interval(r.oxygen.cns_percent, cfg.surface_interval);
            parts.push(SplitDive {
                first_strip: start + 1,
                last_strip: end,
                dive: r,
                otu_day,
            });
            tissues.expose(0.0, Gas::AIR, cfg.surface_interval);
            // New dive: a fresh GF-low anchor, as Subsurface starts each dive.
            tissues.gf_low_anchor = cfg.env.surface_pressure + 1.0;
            start = end;
        }
        return Some(parts);
    }
    None
}

/// The split of [`split`] as a remedy.
fn split_plan(cfg: &DiveConfig, track: &Track, max_per_dive: usize) -> Option<Suggestion> {
    let parts = split(cfg, track, max_per_dive, None)?;
    let text: Vec<String> = parts
        .iter()
        .map(|p| {
            format!(
                "strips {}–{} ({} survey, {:.0} bar left)",
                p.first_strip,
                p.last_strip,
                mmss(p.dive.bottom_time),
                p.dive.gas.end_pressure
            )
        })
        .collect();
    let cns: Vec<String> = parts
        .iter()
        .map(|p| format!("{:.0} %", p.dive.oxygen.cns_percent))
        .collect();
    Some(Suggestion {
        kind: "split_dives".into(),
        text: format!(
            "two or more dives: {} dives with {} surface intervals and a full cylinder each: {}; \
             CNS at the end of each dive {} (carried over the intervals, halved every 90 min), \
             OTU of the day {:.0}",
            parts.len(),
            mmss(cfg.surface_interval),
            text.join("; "),
            cns.join(", "),
            parts.last().map_or(0.0, |p| p.otu_day)
        ),
        fixes_all: true,
    })
}

/// Everything `poser dive` reports.
#[derive(Debug, Clone, Serialize)]
pub struct DiveReport {
    pub config: DiveConfig,
    pub dive: DiveResult,
    pub verdict: Verdict,
}

/// Sample interval of the exported and plotted dive profile, s (`poser dive`, the lessons,
/// the Python module's `Scene.dive`).
pub const PROFILE_SAMPLE_EVERY: f64 = 10.0;

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
