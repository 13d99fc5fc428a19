"""Subsurface's open-circuit Bühlmann planner, ported line by line to Python, for checking poser.

Ported from the Subsurface source (github.com/subsurface/subsurface, commit f0dfae794b5b,
2026-08-19), GPL-2.0 like Subsurface itself: this is a translation of its algorithm for a
test, with its integer units kept (depths in mm, pressures in mbar, times in s, gas fractions in
permille) so that its roundings happen where Subsurface's happen. It is *not* written from
poser's code (src/plan/deco.rs); it is the planner a Subsurface user would run. Each piece names
the Subsurface file and function it follows:

* `core/deco.cpp`: the ZHL-16C coefficients (compartment 1b) and the 1 s exposure factors
  (`buehlmann_N2_*`, `buehlmann_He_*`), `factor()`, `add_segment()` (Haldane steps at constant
  pressure, water vapour `WV_PRESSURE` 0.0627 bar, satmult = desatmult = 1), `clear_deco()`
  (tissues at (P_surf − 0.0627) × `N2_IN_AIR` 781 ‰, the GF-low anchor at P_surf + 1 bar),
  `tissue_tolerance_calc()` (Bühlmann mode: GF-low ceiling per tissue, the anchor
  `gf_low_pressure_this_dive` the deepest one seen, GF linear in pressure to GF high at the
  surface, solved in closed form), `deco_allowed_depth()` (smooth ceiling, no 3 m rounding in the
  planner).
* `core/dive.cpp`: `calculate_depth_to_mbarf()`/`depth_to_mbar()` (salinity × 0.981 / 100000
  mbar per mm, `lrint` to whole mbar), `rel_mbar_to_depth()`, `gas_mod()` (a MOD rounded to 3 m,
  with Subsurface's +0.1 "fudge to switch to O₂ at 6 m").
* `core/gas.cpp`: `fill_pressures()` (open circuit: inspired pressure × fraction).
* `core/interpolate.h`: `interpolate()` (depth at each second of an entered segment, lrint).
* `core/planner.cpp`: `create_dive_from_plan()` (a gas switch adds a sample at lasttime + 1 s),
  `tissue_at_end()` + `interpolate_transition()` (the entered profile in 1 s steps, each at the
  depth of the start of the second, on the gas breathed at its start), `analyze_gaslist()` and
  `sort_stops()` (stop levels every 3 m from `decostoplevels_metric`, plus the gas-switch depths),
  `ascent_velocity()` (four depth bands, all 9 m/min = 150 mm/s by default), `trial_ascent()`
  (the ascent to the next level in `base_timestep` 2 s steps at the depth of the start of each
  step; the smooth ceiling must never be below the next step's depth), `wait_until()` (binary
  search; stops end on multiples of the 60 s `timestep` of *runtime*), and `plan()` (Bühlmann
  branch: the 2 s ascent loop, the switch to the gas at a gas-change level with a
  `min_switch_duration` 60 s hold unless the new gas is O₂, the stop loop).
* `core/pref.cpp`: the defaults (GF 30/75, ascent 9 m/min in every band, descent 18 m/min,
  `last_stop` false (3 m), `min_switch_duration` 60 s, `switch_at_req_stop` false,
  `doo2breaks` false, `surface_segment` 0).
* `core/divecomputer.cpp`: `fixup_dc_duration()` (the runtime: the time of the last sample, here
  the arrival at the surface).

Left out, because the dives checked here do not use them: VPM-B, rebreathers (CCR/pSCR and
bailout), O₂ breaks, "switch only at required stops", imperial stop levels, gas accounting and
the recreational mode. Pure Python, no dependencies.
"""

import math

# core/deco.cpp
WV_PRESSURE = 0.0627  # bar
N2_IN_AIR = 781  # permille (core/gas.h), the initial tissue load in clear_deco()
LN2_OVER_60 = 1.155245301e-02  # factor(): ln(2)/60 as written there

N2_A = [1.1696, 1.0, 0.8618, 0.7562, 0.62, 0.5043, 0.441, 0.4,
        0.375, 0.35, 0.3295, 0.3065, 0.2835, 0.261, 0.248, 0.2327]
N2_B = [0.5578, 0.6514, 0.7222, 0.7825, 0.8126, 0.8434, 0.8693, 0.8910,
        0.9092, 0.9222, 0.9319, 0.9403, 0.9477, 0.9544, 0.9602, 0.9653]
N2_HT = [5.0, 8.0, 12.5, 18.5, 27.0, 38.3, 54.3, 77.0,
         109.0, 146.0, 187.0, 239.0, 305.0, 390.0, 498.0, 635.0]
N2_ONE_SECOND = [
    2.30782347297664E-003, 1.44301447809736E-003, 9.23769302935806E-004, 6.24261986779007E-004,
    4.27777107246730E-004, 3.01585140931371E-004, 2.12729727268379E-004, 1.50020603047807E-004,
    1.05980191127841E-004, 7.91232600646508E-005, 6.17759153688224E-005, 4.83354552742732E-005,
    3.78761777920511E-005, 2.96212356654113E-005, 2.31974277413727E-005, 1.81926738960225E-005,
]
HE_A = [1.6189, 1.383, 1.1919, 1.0458, 0.922, 0.8205, 0.7305, 0.6502,
        0.595, 0.5545, 0.5333, 0.5189, 0.5181, 0.5176, 0.5172, 0.5119]
HE_B = [0.4770, 0.5747, 0.6527, 0.7223, 0.7582, 0.7957, 0.8279, 0.8553,
        0.8757, 0.8903, 0.8997, 0.9073, 0.9122, 0.9171, 0.9217, 0.9267]
HE_HT = [1.88, 3.02, 4.72, 6.99, 10.21, 14.48, 20.53, 29.11,
         41.20, 55.19, 70.69, 90.34, 115.29, 147.42, 188.24, 240.03]
HE_ONE_SECOND = [
    6.12608039419837E-003, 3.81800836683133E-003, 2.44456078654209E-003, 1.65134647076792E-003,
    1.13084424730725E-003, 7.97503165599123E-004, 5.62552521860549E-004, 3.96776399429366E-004,
    2.80360036664540E-004, 2.09299583354805E-004, 1.63410794820518E-004, 1.27869320250551E-004,
    1.00198406028040E-004, 7.83611475491108E-005, 6.13689891868496E-005, 4.81280465299827E-005,
]

# core/planner.cpp
BASE_TIMESTEP = 2  # s
DECOSTOPLEVELS_METRIC = [0, 3000, 6000, 9000, 12000, 15000, 18000, 21000, 24000, 27000,
                         30000, 33000, 36000, 39000, 42000, 45000, 48000, 51000, 54000, 57000,
                         60000, 63000, 66000, 69000, 72000, 75000, 78000, 81000, 84000, 87000,
                         90000, 100000, 110000, 120000, 130000, 140000, 150000, 160000, 170000,
                         180000, 190000, 200000, 220000, 240000, 260000, 280000, 300000,
                         320000, 340000, 360000, 380000]
# decostoplevels_imperial: feet through the _ft literal (round(ft * 304.8))
DECOSTOPLEVELS_IMPERIAL = [int(math.floor(ft * 304.8 + 0.5)) for ft in (
    0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120, 130, 140, 150, 160, 170, 180, 190,
    200, 210, 220, 230, 240, 250, 260, 270, 280, 290, 300, 333, 367, 400, 433, 467, 500, 533, 567,
    600, 633, 667, 733, 800, 867, 933, 1000, 1067, 1133, 1200, 1267)]


def lrint(x):
    """C's lrint in the default rounding mode: to nearest, ties to even (as Python's round)."""
    return int(round(x))


class Prefs:
    """core/pref.cpp defaults for the planner (rates in mm/s, as Subsurface stores them)."""

    def __init__(self, **kw):
        self.ascrate75 = 9000 // 60
        self.ascrate50 = 9000 // 60
        self.ascratestops = 9000 // 60
        self.ascratelast6m = 9000 // 60
        self.descrate = 18000 // 60
        self.last_stop = False
        self.min_switch_duration = 60
        self.gflow = 30
        self.gfhigh = 75
        self.imperial = False  # prefs.units.length == FEET: stop levels every 10 ft
        for k, v in kw.items():
            if not hasattr(self, k):
                raise AttributeError(k)
            setattr(self, k, v)


class Dive:
    """The dive's environment: surface pressure (mbar) and salinity (g/10 l), core/dive.cpp."""

    def __init__(self, surface_mbar=1013, salinity=10300):
        self.surface_mbar = surface_mbar
        self.salinity = salinity

    def depth_to_mbarf(self, depth_mm):  # calculate_depth_to_mbarf()
        return self.surface_mbar + depth_mm * (self.salinity * 0.981 / 100000.0)

    def depth_to_mbar(self, depth_mm):
        return lrint(self.depth_to_mbarf(depth_mm))

    def depth_to_bar(self, depth_mm):
        return self.depth_to_mbar(depth_mm) / 1000.0

    def rel_mbar_to_depth(self, mbar):
        return lrint(mbar / (self.salinity * 0.981 / 100000.0))

    def mbar_to_depth(self, mbar):
        return self.rel_mbar_to_depth(mbar - self.surface_mbar)

    def gas_mod(self, o2_permille, po2_mbar, roundto_mm=3000):
        """gas_mod(): the MOD rounded to multiples of roundto, from .9 up (O₂ at 1.6 → 6 m)."""
        depth = float(self.mbar_to_depth(po2_mbar * 1000 // o2_permille))
        return int(depth / roundto_mm + 0.1) * roundto_mm


class DecoState:
    """struct deco_state: the parts the Bühlmann planner uses."""

    def __init__(self, surface_bar, gf_low, gf_high):
        # clear_deco()
        self.n2 = [(surface_bar - WV_PRESSURE) * N2_IN_AIR / 1000] * 16
        self.he = [0.0] * 16
        self.gf_low_pressure_this_dive = surface_bar + 1.0  # gf_low_position_min
        self.surface = surface_bar
        self.gf_low = gf_low
        self.gf_high = gf_high

    def copy(self):  # deco_state_cache::cache()/restore()
        c = DecoState.__new__(DecoState)
        c.__dict__ = dict(self.__dict__)
        c.n2 = list(self.n2)
        c.he = list(self.he)
        return c

    def add_segment(self, pressure_bar, gas, period_s):
        """add_segment() for open circuit: gas = (o2, he) in permille."""
        amb = pressure_bar - WV_PRESSURE
        o2, he = gas
        p_he = he / 1000.0 * amb  # fill_pressures()
        p_n2 = (1000 - o2 - he) / 1000.0 * amb
        for ci in range(16):
            if period_s == 1:  # factor()
                fn, fh = N2_ONE_SECOND[ci], HE_ONE_SECOND[ci]
            else:
                fn = 1.0 - math.exp(-period_s * LN2_OVER_60 / N2_HT[ci])
                fh = 1.0 - math.exp(-period_s * LN2_OVER_60 / HE_HT[ci])
            self.n2[ci] += (p_n2 - self.n2[ci]) * fn
            self.he[ci] += (p_he - self.he[ci]) * fh

    def tissue_tolerance(self):
        """tissue_tolerance_calc(), Bühlmann branch: the tolerated ambient pressure (bar)."""
        gf_low, gf_high, surface = self.gf_low, self.gf_high, self.surface
        a, b, sat = [], [], []
        lowest = 0.0
        for ci in range(16):
            s = self.n2[ci] + self.he[ci]
            ai = (N2_A[ci] * self.n2[ci] + HE_A[ci] * self.he[ci]) / s
            bi = (N2_B[ci] * self.n2[ci] + HE_B[ci] * self.he[ci]) / s
            a.append(ai)
            b.append(bi)
            sat.append(s)
            low = (bi * s - gf_low * ai * bi) / ((1.0 - bi) * gf_low + bi)
            if low > lowest:
                lowest = low
            if lowest > self.gf_low_pressure_this_dive:
                self.gf_low_pressure_this_dive = lowest
        ret = 0.0
        g = self.gf_low_pressure_this_dive
        for ci in range(16):
            ai, bi, s = a[ci], b[ci], sat[ci]
            if (surface / bi + ai - surface) * gf_high + surface < (g / bi + ai - g) * gf_low + g:
                tol = (-ai * bi * (gf_high * g - gf_low * surface)
                       - (1.0 - bi) * (gf_high - gf_low) * g * surface
                       + bi * (g - surface) * s) / (
                    -ai * bi * (gf_high - gf_low)
                    + (1.0 - bi) * (gf_low * g - gf_high * surface)
                    + bi * (g - surface))
            else:
                tol = ret
            if tol >= ret:
                ret = tol
        return ret


def deco_allowed_depth(tolerance_bar, surface_bar, dive):
    """deco_allowed_depth(..., smooth = true) in mm (last_deco_stop_in_mtr is 0)."""
    delta = tolerance_bar - surface_bar if tolerance_bar > surface_bar else 0.0
    return dive.rel_mbar_to_depth(lrint(delta * 1000))


def interpolate(a, b, part, whole):  # core/interpolate.h
    if whole:
        return lrint((a * (whole - part) + b * part) / whole)
    return (a + b) // 2


def ascent_velocity(depth_mm, avg_depth_mm, prefs):  # planner.cpp ascent_velocity()
    if depth_mm * 4 > avg_depth_mm * 3:
        return prefs.ascrate75
    if depth_mm * 2 > avg_depth_mm:
        return prefs.ascrate50
    if depth_mm > 6000:
        return prefs.ascratestops
    return prefs.ascratelast6m


def trial_ascent(ds, wait_time, trial_depth, stoplevel, avg_depth, gas, dive, prefs):
    """trial_ascent(), Bühlmann: True if the ascent from trial_depth to stoplevel is clear."""
    t = ds.copy()
    if wait_time:
        t.add_segment(dive.depth_to_bar(trial_depth), gas, wait_time)
    while trial_depth > stoplevel:
        deltad = ascent_velocity(trial_depth, avg_depth, prefs) * BASE_TIMESTEP
        if deltad > trial_depth:
            deltad = trial_depth
        t.add_segment(dive.depth_to_bar(trial_depth), gas, BASE_TIMESTEP)
        tol = t.tissue_tolerance()
        if deco_allowed_depth(tol, ds.surface, dive) > trial_depth - deltad:
            return False
        trial_depth -= deltad
    return True


def wait_until(ds, dive, clock, lo, leap, stepsize, depth, target, avg_depth, gas, prefs):
    """wait_until(): the runtime (s, a multiple of stepsize) from which the ascent is clear."""
    while True:
        if lo >= 48 * 3600:
            return 50 * 3600
        upper = lo + leap + stepsize - 1 - (lo + leap - 1) % stepsize
        if not trial_ascent(ds, upper - clock, depth, target, avg_depth, gas, dive, prefs):
            lo = upper
            continue
        if upper - lo <= stepsize:
            return upper
        leap //= 2


def plan(dive, cylinders, segments, switches, prefs=None, timestep=60, hold_to_minute=False,
         step_at_bottom=True):
    """plan(), Bühlmann open circuit.

    cylinders: [(o2 ‰, he ‰)], cylinder 0 breathed from the start.
    segments: the entered waypoints [(duration s, depth mm, cylinder)], as plan_add_segment().
    switches: the gases offered for the ascent [(depth mm, cylinder)], the time-0 entries the
    planner model makes from each cylinder's "switch at" depth.
    Returns a dict: runtime s, stops [(depth mm, s)], gas switches [(runtime s, depth mm, cyl)].

    Two switches that are *not* Subsurface, kept to name the difference from poser: with
    `hold_to_minute` the gas-switch hold lasts to the next whole runtime minute (at least
    `min_switch_duration`), as poser's; with `step_at_bottom=False` the ascent does not spend
    Subsurface's first 2 s step at the bottom depth (the ascent loop is a do-while, and when the
    bottom depth is itself a stop level, as 60 m is, its first step has deltad = 0).
    """
    prefs = prefs or Prefs()
    surface = dive.surface_mbar / 1000.0
    ds = DecoState(surface, prefs.gflow / 100.0, prefs.gfhigh / 100.0)

    # create_dive_from_plan(): the samples and gas-change events of the entered profile.
    samples = [(0, 0)]
    events = []
    lasttime, lastdepth, lastcyl = 0, 0, 0
    points = []  # the waypoints with cumulative times (add_to_end_of_diveplan)
    t = 0
    for dur, depth, cyl in segments:
        t += dur
        points.append((t, depth, cyl))
    for time, depth, cyl in points:
        if cyl != lastcyl:
            events.append((lasttime + 1, cyl))
            samples.append((lasttime + 1, lastdepth))
            lastcyl = cyl
        samples.append((time, depth))
        lastdepth, lasttime = depth, time

    def cyl_at(time):  # get_cylinderid_at_time()
        c = 0
        for et, ec in events:
            if et > time:
                break
            c = ec
        return c

    # average_max_depth() over the waypoints
    integral, last_d, last_t = 0, 0, 0
    for time, depth, _ in points:
        integral += (depth + last_d) * (time - last_t) // 2
        last_t, last_d = time, depth
    avg_depth = integral // last_t

    # tissue_at_end() + interpolate_transition()
    t0, prev = 0, None
    for time, depth in samples:
        gas = cylinders[cyl_at(t0)]
        d0 = prev if prev is not None else 0
        for j in range(t0, time):
            d = interpolate(d0, depth, j - t0, time - t0)
            ds.add_segment(dive.depth_to_bar(d), gas, 1)
        prev = depth
        t0 = time

    clock = previous = bottom_time = samples[-1][0]
    depth = samples[-1][1]
    current = cyl_at(bottom_time)

    levels = list(DECOSTOPLEVELS_IMPERIAL if prefs.imperial else DECOSTOPLEVELS_METRIC)
    levels[1] = 0 if prefs.last_stop else (3048 if prefs.imperial else 3000)  # m_or_ft(3, 10)

    # analyze_gaslist(): the gases at or above the current depth, shallowest first (stable)
    gaschanges = []
    best_first = None
    for sw_depth, cyl in switches:
        if sw_depth <= depth:
            i = 0
            while i < len(gaschanges) and not sw_depth < gaschanges[i][0]:
                i += 1
            gaschanges.insert(i, (sw_depth, cyl))
        elif best_first is None or sw_depth < best_first[0]:
            best_first = (sw_depth, cyl)

    stopidx = 0
    while stopidx < len(levels) and not levels[stopidx] > depth:
        stopidx += 1
    if stopidx > 0:
        stopidx -= 1
    stoplevels = sort_stops(levels, stopidx + 1, gaschanges)
    stopidx += len(gaschanges)
    gi = len(gaschanges) - 1

    if best_first is not None and best_first[1] != current:
        current = best_first[1]

    # The Bühlmann pass (is_final_plan is true at once).
    ds.tissue_tolerance()  # first_ceiling_pressure: moves the GF-low anchor at the bottom
    stopping = False
    last_min_switch = False
    laststoptime = timestep
    stops, gas_switches = [], []
    while True:
        while True:  # ascend to the next stop level
            deltad = ascent_velocity(depth, avg_depth, prefs) * BASE_TIMESTEP
            if depth - deltad < stoplevels[stopidx]:
                deltad = depth - stoplevels[stopidx]
            if step_at_bottom or deltad > 0 or depth != samples[-1][1]:
                ds.add_segment(dive.depth_to_bar(depth), cylinders[current], BASE_TIMESTEP)
                clock += BASE_TIMESTEP
            last_min_switch = False
            depth -= deltad
            if not (depth > 0 and depth > stoplevels[stopidx]):
                break
        if depth <= 0:
            break
        if gi >= 0 and stoplevels[stopidx] <= gaschanges[gi][0]:
            if current != gaschanges[gi][1]:
                stopping = True
                previous = clock
                current = gaschanges[gi][1]
                gas_switches.append((clock, depth, current))
                if not last_min_switch and cylinders[current][0] != 1000:
                    hold = prefs.min_switch_duration
                    if hold_to_minute:  # not Subsurface: poser's hold
                        hold = (clock // timestep + 1) * timestep - clock
                        while hold < prefs.min_switch_duration:
                            hold += timestep
                    ds.add_segment(dive.depth_to_bar(depth), cylinders[current], hold)
                    clock += hold
                    last_min_switch = True
            gi -= 1
        stopidx -= 1
        while True:
            if trial_ascent(ds, 0, depth, stoplevels[stopidx], avg_depth, cylinders[current],
                            dive, prefs):
                break
            if not stopping:
                previous = clock
                stopping = True
            new_clock = wait_until(ds, dive, clock, clock, laststoptime * 2 + 1, timestep, depth,
                                   stoplevels[stopidx], avg_depth, cylinders[current], prefs)
            laststoptime = new_clock - clock
            if laststoptime >= 48 * 3600 and depth >= 6000:
                raise RuntimeError("PLAN_ERROR_TIMEOUT")
            ds.add_segment(dive.depth_to_bar(depth), cylinders[current], laststoptime)
            last_min_switch = False
            clock += laststoptime
            break
        if stopping:
            stops.append((depth, clock - previous))
            previous = clock
            stopping = False
    return {"runtime": clock, "stops": stops, "switches": gas_switches,
            "bottom_time": bottom_time, "avg_depth": avg_depth}


def sort_stops(dstops, dnr, gstops):
    """sort_stops(): the deco levels dstops[:dnr] and the gas-change depths, ascending."""
    total = dnr + len(gstops)
    out = [0] * total
    if not gstops:
        return list(dstops[:dnr])
    i, gi, di = total - 1, len(gstops) - 1, dnr - 1
    while i >= 0:
        if dstops[di] > gstops[gi][0]:
            out[i] = dstops[di]
            di -= 1
        elif dstops[di] == gstops[gi][0]:
            out[i] = dstops[di]
            di -= 1
            gi -= 1
        else:
            out[i] = gstops[gi][0]
            gi -= 1
        i -= 1
        if di < 0:
            while gi >= 0:
                out[i] = gstops[gi][0]
                i -= 1
                gi -= 1
            break
        if gi < 0:
            while di >= 0:
                out[i] = dstops[di]
                i -= 1
                di -= 1
            break
    while i >= 0:
        out[i] = 0
        i -= 1
    return out
