//! Oxygen toxicity of a dive: CNS % (central nervous system) and OTU (pulmonary), integrated
//! over the profile as the diver breathes it.
//!
//! **CNS %**: the fraction of the NOAA single-exposure limit used, summed over the dive
//! (NOAA Diving Manual, oxygen exposure limits table):
//!
//! | pO₂, bar | 0.6 | 0.7 | 0.8 | 0.9 | 1.0 | 1.1 | 1.2 | 1.3 | 1.4 | 1.5 | 1.6 |
//! |---|---|---|---|---|---|---|---|---|---|---|---|
//! | limit, min | 720 | 570 | 450 | 360 | 300 | 240 | 210 | 180 | 150 | 120 | 45 |
//!
//! The loading rate is 100 %/limit per minute. Between two rows the *rate* is interpolated
//! linearly (never less than interpolating the limit, since 1/t is convex). At or below
//! 0.5 bar there is no loading; from 0.5 to 0.6 bar the 0.6 bar row applies (the table has no
//! row there; Subsurface's fit gives ≈ 750 min at 0.55 bar, so this is the conservative side).
//! Above 1.6 bar the table ends; the rate is extrapolated by continuing the table's last step
//! geometrically (×120/45 per 0.1 bar: 17 min at 1.7 bar), which is steeper than a linear
//! extrapolation and within a few % of Subsurface's upper fit line. Such a pO₂ is a problem of
//! the plan in any case ([`PO2_TABLE_MAX`]).
//!
//! **OTU** (oxygen tolerance units, Lambertsen's UPTD as used for REPEX, Hamilton 1989):
//! `((pO₂ − 0.5) / 0.5)^0.83` per minute above 0.5 bar, none below. Over a linear ramp of pO₂
//! the exact integral is used. (Subsurface uses the exponent 5/6 in its approximation.)
//!
//! **Across surface intervals** (the dives of a split survey, the same day): CNS % halves every
//! 90 min at the surface (NOAA; Subsurface's `core/divelist.cpp` does the same) and does not
//! decay during a dive, so a dive ends at the CNS carried in plus its own. OTU is summed over
//! the day and held to REPEX's single-day limit, 850 OTU (Hamilton 1989).

use serde::Serialize;

/// NOAA single-exposure limits: (pO₂ bar, minutes).
pub const NOAA_CNS_LIMITS: [(f64, f64); 11] = [
    (0.6, 720.0),
    (0.7, 570.0),
    (0.8, 450.0),
    (0.9, 360.0),
    (1.0, 300.0),
    (1.1, 240.0),
    (1.2, 210.0),
    (1.3, 180.0),
    (1.4, 150.0),
    (1.5, 120.0),
    (1.6, 45.0),
];

/// pO₂ at or below which nothing loads, bar (both CNS and OTU).
pub const PO2_THRESHOLD: f64 = 0.5;
/// The highest pO₂ of the NOAA table, bar: beyond it the plan is a problem whatever the
/// diver's own limits.
pub const PO2_TABLE_MAX: f64 = 1.6;
/// The OTU exponent (Lambertsen / REPEX).
pub const OTU_EXPONENT: f64 = 0.83;
/// CNS % above which the report warns, and above which the plan is not safe.
pub const CNS_WARN: f64 = 80.0;
pub const CNS_LIMIT: f64 = 100.0;
/// OTU of one dive above which the report warns (a common single-dive planning figure; REPEX's
/// single-day limit is 850).
pub const OTU_WARN: f64 = 300.0;
/// REPEX's limit on the OTU of one day's dives (Hamilton 1989; also the NOAA Diving Manual).
pub const OTU_DAY_LIMIT: f64 = 850.0;
/// Half-time of CNS % at the surface between dives, s: 90 min.
pub const CNS_SURFACE_HALF_TIME: f64 = 90.0 * 60.0;

/// The CNS % left after `seconds` at the surface: halved every 90 min (a negative or
/// non-finite interval leaves it as it was).
pub fn cns_after_surface_interval(cns_percent: f64, seconds: f64) -> f64 {
    if !(seconds > 0.0) {
        return cns_percent;
    }
    cns_percent * 0.5_f64.powf(seconds / CNS_SURFACE_HALF_TIME)
}

/// CNS loading at a constant pO₂, % per minute.
pub fn cns_rate(po2: f64) -> f64 {
    if po2.is_nan() || po2 <= PO2_THRESHOLD {
        return 0.0;
    }
    let t = &NOAA_CNS_LIMITS;
    if po2 <= t[0].0 {
        return 100.0 / t[0].1;
    }
    if po2 > PO2_TABLE_MAX {
        let (p1, l1) = t[t.len() - 1];
        let (_, l0) = t[t.len() - 2];
        let step = l0 / l1;
        return 100.0 / l1 * step.powf((po2 - p1) / 0.1);
    }
    let i = t
        .windows(2)
        .position(|w| po2 <= w[1].0 + 1e-12)
        .unwrap_or(t.len() - 2);
    let ((p0, l0), (p1, l1)) = (t[i], t[i + 1]);
    let f = (po2 - p0) / (p1 - p0);
    100.0 * ((1.0 - f) / l0 + f / l1)
}

/// OTU per minute at a constant pO₂.
pub fn otu_rate(po2: f64) -> f64 {
    if po2.is_nan() || po2 <= PO2_THRESHOLD {
        0.0
    } else {
        ((po2 - PO2_THRESHOLD) / 0.5).powf(OTU_EXPONENT)
    }
}

/// CNS % and OTU, of a stretch or a whole dive.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Exposure {
    pub cns_percent: f64,
    pub otu: f64,
}

impl Exposure {
    /// A stretch of `seconds` over which pO₂ goes linearly from `po2_start` to `po2_end` bar.
    /// OTU: exact integral. CNS: midpoint rule on sub-steps of at most 0.005 bar, exact on each
    /// linear piece of the table when the pO₂ crosses a row on a sub-step boundary.
    pub fn segment(po2_start: f64, po2_end: f64, seconds: f64) -> Exposure {
        if !(seconds > 0.0) {
            return Exposure::default();
        }
        let minutes = seconds / 60.0;
        let dp = po2_end - po2_start;
        if dp.abs() < 1e-9 {
            let p = 0.5 * (po2_start + po2_end);
            return Exposure {
                cns_percent: cns_rate(p) * minutes,
                otu: otu_rate(p) * minutes,
            };
        }
        let x = |p: f64| ((p - PO2_THRESHOLD) / 0.5).max(0.0);
        let e1 = OTU_EXPONENT + 1.0;
        let otu = minutes / dp * 0.5 / e1 * (x(po2_end).powf(e1) - x(po2_start).powf(e1));
        let n = (dp.abs() / 0.005).ceil().max(1.0) as usize;
        let h = minutes / n as f64;
        let cns: f64 = (0..n)
            .map(|i| cns_rate(po2_start + dp * (i as f64 + 0.5) / n as f64) * h)
            .sum();
        Exposure {
            cns_percent: cns,
            otu,
        }
    }

    pub fn add(&mut self, other: Exposure) {
        self.cns_percent += other.cns_percent;
        self.otu += other.otu;
    }
}

/// The oxygen exposure of a simulated dive.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct OxygenExposure {
    /// CNS % at the end of the dive: the CNS carried in (`cns_carried`) plus the dive's own.
    pub cns_percent: f64,
    /// CNS % carried in from earlier dives of the day, decayed over the surface interval (0
    /// for a single dive).
    pub cns_carried: f64,
    /// OTU of the dive.
    pub otu: f64,
    /// Highest pO₂ breathed, bar, and where (runtime s, depth m).
    pub max_po2: f64,
    pub max_po2_time: f64,
    pub max_po2_depth: f64,
    /// Minutes breathed above 1.6 bar, where CNS is extrapolated beyond the NOAA table.
    pub minutes_above_table: f64,
}

impl OxygenExposure {
    /// Breathe a stretch of `seconds` from runtime `t` from depth `d0` (pO₂ `p0`) to `d1`
    /// (pO₂ `p1`).
    pub fn breathe(&mut self, t: f64, seconds: f64, (d0, p0): (f64, f64), (d1, p1): (f64, f64)) {
        let e = Exposure::segment(p0, p1, seconds);
        self.cns_percent += e.cns_percent;
        self.otu += e.otu;
        for (tt, d, p) in [(t, d0, p0), (t + seconds, d1, p1)] {
            if p > self.max_po2 {
                self.max_po2 = p;
                self.max_po2_time = tt;
                self.max_po2_depth = d;
            }
        }
        if p0.max(p1) > PO2_TABLE_MAX && seconds > 0.0 {
            let lo = p0.min(p1);
            let hi = p0.max(p1);
            let frac = if hi - lo < 1e-12 {
                1.0
            } else {
                ((hi - PO2_TABLE_MAX) / (hi - lo)).clamp(0.0, 1.0)
            };
            self.minutes_above_table += seconds / 60.0 * frac;
        }
    }

    /// Start this dive with `cns_percent` carried in from earlier dives (already decayed):
    /// CNS does not decay during a dive, so it adds to the dive's own.
    pub fn carry_in(&mut self, cns_percent: f64) {
        self.cns_percent += cns_percent - self.cns_carried;
        self.cns_carried = cns_percent;
    }

    /// CNS within 100 % and no pO₂ beyond the NOAA table.
    pub fn within_limits(&self) -> bool {
        self.cns_percent <= CNS_LIMIT && self.max_po2 <= PO2_TABLE_MAX + 1e-9
    }
}
