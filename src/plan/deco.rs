//! Decompression: Bühlmann ZHL-16C with gradient factors, as Subsurface computes it
//! (`core/deco.cpp`, `core/planner.cpp`; Bühlmann, *Tauchmedizin*; Baker, "Clearing up the confusion about deep stops" for the gradient factors).
//! Owns the tissue state, ceilings, no-decompression limits, and the ascent with stops.
//!
//! | parameter | unit | default | meaning |
//! |---|---|---|---|
//! | `gf_low`, `gf_high` | fraction | 0.30, 0.75 | gradient factors (Subsurface defaults) |
//! | `surface_pressure` | bar | 1.013 | ambient pressure at the surface (`1.013·e^(−h/7800 m)` at altitude) |
//! | `water_density` | kg/m³ | 1030 | sea water as Subsurface (1000 fresh); `ρ·0.981/10⁴` bar per m |
//! | `ascent_rate` | m/s | 0.15 (9 m/min) | rate of every ascent segment |
//! | `stop_step` | m | 3 | spacing of stop levels; the last stop is at 3 m |
//!
//! Model details followed from Subsurface: compartment 1 is the "1b" variant (5 min), water
//! vapour 0.0627 bar, initial tissues loaded with 78.1 % N₂ at the surface, a-/b-values of N₂
//! and He mixed by their tissue loads, the GF line interpolating the *tolerated tissue
//! pressure* linearly in ambient pressure between the surface (GF high) and the GF-low anchor
//! (the deepest GF-low ceiling seen so far, at least 1 bar below the surface), NDL found by
//! adding 60 s at depth until the ceiling leaves the surface, stops ending on whole runtime
//! minutes after a trial ascent in 2 s steps.

use serde::Serialize;

/// Water vapour pressure in the lungs, bar (Bühlmann, Rq = 1).
pub const WATER_VAPOUR: f64 = 0.0627;
/// N₂ fraction Subsurface uses for the initial (surface-saturated) tissue load.
pub const N2_IN_AIR_INITIAL: f64 = 0.781;
/// Standard atmosphere, bar (Subsurface's `depth_to_atm` divides by 1013.25 mbar).
pub const ATM: f64 = 1.01325;
/// Cap on NDL search (Subsurface's `MAX_PROFILE_DECO`), s.
pub const NDL_CAP: f64 = 7200.0;

/// ZHL-16C N₂ half-times (min), a (bar), b; compartment 1 is 1b.
const N2: [(f64, f64, f64); 16] = [
    (5.0, 1.1696, 0.5578),
    (8.0, 1.0000, 0.6514),
    (12.5, 0.8618, 0.7222),
    (18.5, 0.7562, 0.7825),
    (27.0, 0.6200, 0.8126),
    (38.3, 0.5043, 0.8434),
    (54.3, 0.4410, 0.8693),
    (77.0, 0.4000, 0.8910),
    (109.0, 0.3750, 0.9092),
    (146.0, 0.3500, 0.9222),
    (187.0, 0.3295, 0.9319),
    (239.0, 0.3065, 0.9403),
    (305.0, 0.2835, 0.9477),
    (390.0, 0.2610, 0.9544),
    (498.0, 0.2480, 0.9602),
    (635.0, 0.2327, 0.9653),
];
/// ZHL-16C He half-times (min), a (bar), b.
const HE: [(f64, f64, f64); 16] = [
    (1.88, 1.6189, 0.4770),
    (3.02, 1.3830, 0.5747),
    (4.72, 1.1919, 0.6527),
    (6.99, 1.0458, 0.7223),
    (10.21, 0.9220, 0.7582),
    (14.48, 0.8205, 0.7957),
    (20.53, 0.7305, 0.8279),
    (29.11, 0.6502, 0.8553),
    (41.20, 0.5950, 0.8757),
    (55.19, 0.5545, 0.8903),
    (70.69, 0.5333, 0.8997),
    (90.34, 0.5189, 0.9073),
    (115.29, 0.5181, 0.9122),
    (147.42, 0.5176, 0.9171),
    (188.24, 0.5172, 0.9217),
    (240.03, 0.5119, 0.9267),
];

/// A breathing gas (fractions).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Gas {
    pub o2: f64,
    pub he: f64,
}

impl Gas {
    /// Air: 20.9 % O₂, the rest narcotic N₂ (Subsurface's `O2_IN_AIR`, 209 ‰). poser's one
    /// definition of air: the default diver, a cylinder without a gas and `gas = "air"` all
    /// breathe this mix, so both spellings of the same dive give the same plan.
    pub const AIR: Gas = Gas { o2: 0.209, he: 0.0 };
    pub fn n2(&self) -> f64 {
        (1.0 - self.o2 - self.he).max(0.0)
    }
    /// Switch depth for a pO₂ limit as Subsurface's `gas_mod`: the MOD rounded to the nearest
    /// multiple of `round` m.
    pub fn switch_depth(&self, env: &Environment, po2_max: f64, round: f64) -> f64 {
        (self.mod_depth(env, po2_max) / round).round() * round
    }
    /// Maximum operating depth for a pO₂ limit (bar), given the environment.
    pub fn mod_depth(&self, env: &Environment, po2_max: f64) -> f64 {
        env.depth_at(po2_max / self.o2)
    }
    /// Fraction of the mix that is narcotic: N₂ and O₂ (everything but He). poser counts O₂
    /// as narcotic, as Subsurface's planner does by default and as GUE, TDI and IANTD teach:
    /// O₂ is at least as narcotic as N₂ by its lipid solubility, and counting it asks for
    /// more helium, never less — the conservative side.
    pub fn narcotic(&self) -> f64 {
        (1.0 - self.he).max(0.0)
    }
    /// Equivalent narcotic depth at `depth` m: the depth at which air is as narcotic as this
    /// gas is here (O₂ narcotic, see [`Gas::narcotic`]; air is all narcotic on that count), m.
    pub fn end(&self, env: &Environment, depth: f64) -> f64 {
        env.depth_at(env.pressure(depth) * self.narcotic()).max(0.0)
    }
}

/// Where the dive happens: surface pressure and water density.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Environment {
    /// Surface pressure, bar.
    pub surface_pressure: f64,
    /// Water density, kg/m³ (Subsurface: 1030 sea, 1000 fresh).
    pub water_density: f64,
}

impl Environment {
    pub const SEA: Environment = Environment {
        surface_pressure: 1.013,
        water_density: 1030.0,
    };
    pub const FRESH: Environment = Environment {
        surface_pressure: 1.013,
        water_density: 1000.0,
    };

    /// Sea or fresh water at an altitude (m) above sea level (Subsurface's barometric helper).
    pub fn new(salt_water: bool, altitude: f64) -> Environment {
        Environment {
            surface_pressure: 1.013 * (-altitude.max(0.0) / 7800.0).exp(),
            water_density: if salt_water { 1030.0 } else { 1000.0 },
        }
    }
    /// Bar per metre of water (Subsurface: salinity · 0.981 / 10⁵ in mbar/mm).
    pub fn bar_per_m(&self) -> f64 {
        self.water_density * 0.981e-4
    }
    /// Ambient pressure at `depth` m, bar.
    pub fn pressure(&self, depth: f64) -> f64 {
        self.surface_pressure + depth.max(0.0) * self.bar_per_m()
    }
    /// Depth at ambient pressure `p` bar (may be negative above the surface).
    pub fn depth_at(&self, p: f64) -> f64 {
        (p - self.surface_pressure) / self.bar_per_m()
    }
}

/// Gradient factors, fractions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GradientFactors {
    pub low: f64,
    pub high: f64,
}

impl GradientFactors {
    /// Subsurface's default planner/display GFs.
    pub const SUBSURFACE: GradientFactors = GradientFactors {
        low: 0.30,
        high: 0.75,
    };
    /// Pure Bühlmann.
    pub const NONE: GradientFactors = GradientFactors {
        low: 1.0,
        high: 1.0,
    };
}

/// Tissue loads of the 16 compartments plus the GF-low anchor of the dive so far.
#[derive(Debug, Clone, PartialEq)]
pub struct Tissues {
    pub n2: [f64; 16],
    pub he: [f64; 16],
    /// Deepest GF-low ceiling seen in this dive (ambient pressure, bar); starts at
    /// surface + 1 bar.
    pub gf_low_anchor: f64,
    pub env: Environment,
    pub gf: GradientFactors,
}

/// A stop of the ascent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stop {
    /// Depth, m.
    pub depth: f64,
    /// Duration, s.
    pub duration: f64,
}

/// An ascent to the surface as the planner would fly it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ascent {
    /// Mandatory stops, deepest first (empty: no decompression needed).
    pub stops: Vec<Stop>,
    /// Time to surface including travel, s.
    pub tts: f64,
    /// Path as (time from start of ascent, depth) points.
    pub path: Vec<(f64, f64)>,
    /// Gas switches as (time from start of ascent, depth, new gas).
    pub switches: Vec<(f64, f64, Gas)>,
}

/// How the ascent is flown (Subsurface planner preferences).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AscentPlan {
    /// Ascent rate deeper than 6 m, m/s.
    pub rate: f64,
    /// Ascent rate in the last 6 m, m/s.
    pub rate_last6: f64,
    /// Depth of the last stop, m (3, or 6 with Subsurface's `last_stop`).
    pub last_stop: f64,
    /// Deco gases and the depth (m) from which each may be breathed.
    pub deco_gases: Vec<(Gas, f64)>,
    /// Minimum time at a gas switch, s (Subsurface's `min_switch_duration`; not for O₂).
    pub switch_time: f64,
    /// Spacing of stop levels, m (3 m; 10 ft = 3.048 m in imperial plans).
    pub stop_step: f64,
}

impl AscentPlan {
    /// One rate, last stop 3 m, no deco gas.
    pub fn simple(rate: f64) -> AscentPlan {
        AscentPlan {
            rate,
            rate_last6: rate,
            last_stop: 3.0,
            deco_gases: vec![],
            switch_time: 60.0,
            stop_step: 3.0,
        }
    }
    fn rate_at(&self, depth: f64) -> f64 {
        if depth <= 6.0 + 1e-9 {
            self.rate_last6
        } else {
            self.rate
        }
    }
}

/// Result of a no-decompression-limit query.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", content = "seconds", rename_all = "snake_case")]
pub enum Ndl {
    /// Already in decompression (the ceiling is below the surface).
    InDeco,
    /// Time that can still be spent at this depth, s (1 s resolution).
    Limit(f64),
    /// Longer than the search cap ([`NDL_CAP`]), or too shallow to matter.
    Unlimited,
}

impl Ndl {
    /// The NDL in whole minutes as Subsurface displays it (60 s steps, floor).
    pub fn whole_minutes(&self) -> Option<u32> {
        match self {
            Ndl::Limit(s) => Some((s / 60.0).floor() as u32),
            Ndl::InDeco => Some(0),
            Ndl::Unlimited => None,
        }
    }
}

impl Tissues {
    /// Tissues saturated at the surface (Subsurface's `clear_deco`).
    pub fn surface(env: Environment, gf: GradientFactors) -> Tissues {
        let n2 = (env.surface_pressure - WATER_VAPOUR) * N2_IN_AIR_INITIAL;
        Tissues {
            n2: [n2; 16],
            he: [0.0; 16],
            gf_low_anchor: env.surface_pressure + 1.0,
            env,
            gf,
        }
    }

    /// Breathe `gas` at constant ambient pressure `p` (bar) for `dt` s (Haldane).
    pub fn expose_pressure(&mut self, p: f64, gas: Gas, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let pi = (p - WATER_VAPOUR).max(0.0);
        let pn2 = pi * gas.n2();
        let phe = pi * gas.he;
        for c in 0..16 {
            let kn = std::f64::consts::LN_2 / (N2[c].0 * 60.0);
            let kh = std::f64::consts::LN_2 / (HE[c].0 * 60.0);
            self.n2[c] += (pn2 - self.n2[c]) * (1.0 - (-kn * dt).exp());
            self.he[c] += (phe - self.he[c]) * (1.0 - (-kh * dt).exp());
        }
        self.update_anchor();
    }

    /// Breathe `gas` at `depth` m for `dt` s.
    pub fn expose(&mut self, depth: f64, gas: Gas, dt: f64) {
        self.expose_pressure(self.env.pressure(depth), gas, dt);
    }

    /// Travel linearly from `d0` to `d1` m in `dt` s, as constant steps of at most `step` s
    /// at the mid-step depth.
    pub fn travel(&mut self, d0: f64, d1: f64, gas: Gas, dt: f64, step: f64) {
        if dt <= 0.0 {
            return;
        }
        let n = (dt / step).ceil().max(1.0) as usize;
        let h = dt / n as f64;
        for i in 0..n {
            let f = (i as f64 + 0.5) / n as f64;
            self.expose(d0 + (d1 - d0) * f, gas, h);
        }
    }

    fn mixed_ab(&self, c: usize) -> (f64, f64, f64) {
        let total = self.n2[c] + self.he[c];
        if total <= 0.0 {
            return (N2[c].1, N2[c].2, 0.0);
        }
        let a = (N2[c].1 * self.n2[c] + HE[c].1 * self.he[c]) / total;
        let b = (N2[c].2 * self.n2[c] + HE[c].2 * self.he[c]) / total;
        (a, b, total)
    }

    fn update_anchor(&mut self) {
        let gl = self.gf.low;
        for c in 0..16 {
            let (a, b, p) = self.mixed_ab(c);
            // Ambient pressure at which this tissue sits exactly at GF low.
            let low = (b * p - gl * a * b) / ((1.0 - b) * gl + b);
            if low > self.gf_low_anchor {
                self.gf_low_anchor = low;
            }
        }
    }

    /// Tolerated ambient pressure (bar) of compartment `c` with the GF line.
    fn tolerated(&self, c: usize) -> f64 {
        let (a, b, p) = self.mixed_ab(c);
        let s = self.env.surface_pressure;
        let an = self.gf_low_anchor;
        // Tolerated tissue pressure at ambient P under a gradient factor g: P + g·(P/b + a − P).
        let allowed = |amb: f64, g: f64| amb + g * (amb / b + a - amb);
        let at_s = allowed(s, self.gf.high);
        let at_a = allowed(an, self.gf.low);
        if at_a > at_s && an > s {
            // Linear in ambient pressure between (s, at_s) and (an, at_a).
            s + (p - at_s) * (an - s) / (at_a - at_s)
        } else {
            // Degenerate GF line: plain Bühlmann at GF high.
            let g = self.gf.high;
            (p - g * a) / (g / b - g + 1.0)
        }
    }

    /// Ceiling as an ambient pressure, bar (the deepest over compartments).
    pub fn ceiling_pressure(&self) -> f64 {
        (0..16).map(|c| self.tolerated(c)).fold(0.0, f64::max)
    }

    /// Ceiling depth, m ("smooth", not rounded to stops); 0 when the surface is allowed.
    pub fn ceiling(&self) -> f64 {
        self.env.depth_at(self.ceiling_pressure()).max(0.0)
    }

    /// Whether the ceiling is below the surface.
    pub fn in_deco(&self) -> bool {
        self.ceiling_pressure() > self.env.surface_pressure
    }

    /// Index of the compartment setting the ceiling.
    pub fn leading_compartment(&self) -> usize {
        let mut best = (0, f64::MIN);
        for c in 0..16 {
            let t = self.tolerated(c);
            if t > best.1 {
                best = (c, t);
            }
        }
        best.0
    }

    /// No-decompression limit at `depth` on `gas`: time at that depth until a direct ascent is
    /// no longer allowed. Like Subsurface, 60 s steps; then refined to 1 s by bisection.
    /// Shallower than 3 m (or longer than [`NDL_CAP`]): [`Ndl::Unlimited`].
    pub fn ndl(&self, depth: f64, gas: Gas) -> Ndl {
        self.ndl_capped(depth, gas, NDL_CAP)
    }

    /// [`Tissues::ndl`] with a search cap of `cap` s instead of [`NDL_CAP`].
    pub fn ndl_capped(&self, depth: f64, gas: Gas, cap: f64) -> Ndl {
        if self.in_deco() {
            return Ndl::InDeco;
        }
        if depth < 3.0 {
            return Ndl::Unlimited;
        }
        let mut t = self.clone();
        let mut elapsed = 0.0;
        while elapsed < cap {
            let mut next = t.clone();
            next.expose(depth, gas, 60.0);
            if next.in_deco() {
                // Refine within this minute.
                let (mut lo, mut hi) = (0.0_f64, 60.0_f64);
                while hi - lo > 1.0 {
                    let mid = 0.5 * (lo + hi);
                    let mut probe = t.clone();
                    probe.expose(depth, gas, mid);
                    if probe.in_deco() {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Ndl::Limit(elapsed + lo.floor());
            }
            t = next;
            elapsed += 60.0;
        }
        Ndl::Unlimited
    }

    /// Check that ascending from `from` to `to` m never breaks the ceiling (2 s steps,
    /// Subsurface's `trial_ascent`). Returns the state after the ascent and its duration if
    /// it is clear.
    fn trial_ascent(
        &self,
        from: f64,
        to: f64,
        plan: &AscentPlan,
        gas: Gas,
    ) -> Option<(Tissues, f64)> {
        let mut t = self.clone();
        let mut d = from;
        let mut clock = 0.0;
        while d > to + 1e-9 {
            let rate = plan.rate_at(d);
            let step = (2.0 * rate).min(d - to);
            t.travel(d, d - step, gas, step / rate, 2.0);
            clock += step / rate;
            d -= step;
            if t.ceiling() > d + 1e-9 {
                return None;
            }
        }
        Some((t, clock))
    }

    /// Fly the ascent from `depth` to the surface at `rate` m/s on `gas`, with the stops the
    /// model requires (3 m levels, last stop at 3 m, stops ending on whole runtime minutes
    /// counted from `runtime` s). Consumes the state: afterwards it is the state at the surface.
    pub fn ascend(&mut self, depth: f64, rate: f64, gas: Gas, runtime: f64) -> Ascent {
        self.ascend_with(depth, gas, &AscentPlan::simple(rate), runtime)
    }

    /// [`Tissues::ascend`] with Subsurface planner options: a slower rate for the last 6 m, the
    /// last stop at 6 m, and deco gases switched to at their switch depths (the richest gas
    /// allowed at each level; a switch holds the diver at least `switch_time` at that level).
    pub fn ascend_with(
        &mut self,
        depth: f64,
        bottom_gas: Gas,
        plan: &AscentPlan,
        runtime: f64,
    ) -> Ascent {
        let step_m = plan.stop_step;
        let mut stops: Vec<Stop> = Vec::new();
        let mut path = vec![(0.0, depth)];
        let mut switches = Vec::new();
        let mut clock = 0.0;
        let mut d = depth;
        let mut gas = bottom_gas;
        let mut guard = 0;
        let mut hold = 0.0; // time still to spend at this level for a gas switch
        while d > 1e-9 {
            guard += 1;
            // Gas switch on arrival at a level.
            if let Some(better) = plan
                .deco_gases
                .iter()
                .filter(|(g, sw)| *sw + 1e-6 >= d && g.o2 > gas.o2)
                .max_by(|a, b| a.0.o2.total_cmp(&b.0.o2))
            {
                gas = better.0;
                switches.push((clock, d, gas));
                hold = if gas.o2 >= 0.999 {
                    0.0
                } else {
                    plan.switch_time
                };
            }
            // Next level: the 3 m multiple strictly above, or the surface from the last stop.
            let mut next = ((d - 1e-6) / step_m).floor() * step_m;
            if next < plan.last_stop - 1e-6 {
                next = 0.0;
            }
            let trial = if hold > 0.0 {
                None
            } else {
                self.trial_ascent(d, next, plan, gas)
            };
            match trial {
                Some((after, dt)) if guard < 100_000 => {
                    clock += dt;
                    *self = after;
                    d = next;
                    path.push((clock, d));
                }
                _ => {
                    // Wait at this level until the next whole runtime minute, then try again.
                    let now = runtime + clock;
                    let mut wait = (now / 60.0).floor() * 60.0 + 60.0 - now;
                    if wait < 1.0 {
                        wait += 60.0;
                    }
                    while wait + 1e-9 < hold {
                        wait += 60.0;
                    }
                    hold = 0.0;
                    self.expose(d, gas, wait);
                    clock += wait;
                    match stops.last_mut() {
                        Some(s) if (s.depth - d).abs() < 1e-6 => s.duration += wait,
                        _ => stops.push(Stop {
                            depth: d,
                            duration: wait,
                        }),
                    }
                    path.push((clock, d));
                    if clock > 48.0 * 3600.0 {
                        break; // cannot happen on breathable gases; keeps the loop finite
                    }
                }
            }
        }
        Ascent {
            stops,
            tts: clock,
            path,
            switches,
        }
    }

    /// Time to surface from `depth` (s) without changing this state.
    pub fn tts(&self, depth: f64, rate: f64, gas: Gas, runtime: f64) -> (f64, Option<Stop>) {
        let mut t = self.clone();
        let a = t.ascend(depth, rate, gas, runtime);
        (a.tts, a.stops.first().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pressure_per_metre_matches_subsurface() {
        // Subsurface: sea water (10300 g/10 l) gives 15 m → 2529 mbar (rounded).
        let p = Environment::SEA.pressure(15.0);
        assert!((p - 2.529).abs() < 0.0006, "{p}");
    }

    #[test]
    fn surface_tissues_are_clear() {
        let t = Tissues::surface(Environment::SEA, GradientFactors::SUBSURFACE);
        assert!(!t.in_deco());
        assert_eq!(t.ceiling(), 0.0);
    }
}
