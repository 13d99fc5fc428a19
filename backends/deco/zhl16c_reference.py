"""An independent Bühlmann ZHL-16C + gradient-factor decompression planner, for checking poser.

Written from the published model, not from poser's code: Bühlmann's ZHL-16C coefficients
(Bühlmann, Völlm, Nussberger, *Tauchmedizin*, 5th ed., 2002; compartment 1b), the Schreiner
equation for linear depth changes (Schreiner & Kelley 1971), and Erik Baker's gradient factors
("Clearing up the confusion about deep stops", 1998): the GF-low line anchored at the first stop,
GF rising linearly to GF high at the surface. Stops on 3 m levels in whole minutes, gas switches
at the richest gas allowed on arrival at a stop level, a 1 min hold at a switch (not to O₂).

Pure Python, no dependencies: `plan(...)` returns the ascent (stops and runtime).
"""

import math

WATER_VAPOUR = 0.0627  # bar, at 37 °C (Bühlmann, Rq = 1)
N2_IN_AIR = 0.7902  # the surface-saturated tissues breathe dry air's N2 (Bühlmann)

# (half-time min, a bar, b) for N2, then He: ZHL-16C, compartment 1b.
N2 = [
    (5.0, 1.1696, 0.5578), (8.0, 1.0, 0.6514), (12.5, 0.8618, 0.7222), (18.5, 0.7562, 0.7825),
    (27.0, 0.62, 0.8126), (38.3, 0.5043, 0.8434), (54.3, 0.441, 0.8693), (77.0, 0.4, 0.891),
    (109.0, 0.375, 0.9092), (146.0, 0.35, 0.9222), (187.0, 0.3295, 0.9319), (239.0, 0.3065, 0.9403),
    (305.0, 0.2835, 0.9477), (390.0, 0.261, 0.9544), (498.0, 0.248, 0.9602), (635.0, 0.2327, 0.9653),
]
HE = [
    (1.88, 1.6189, 0.477), (3.02, 1.383, 0.5747), (4.72, 1.1919, 0.6527), (6.99, 1.0458, 0.7223),
    (10.21, 0.922, 0.7582), (14.48, 0.8205, 0.7957), (20.53, 0.7305, 0.8279), (29.11, 0.6502, 0.8553),
    (41.2, 0.595, 0.8757), (55.19, 0.5545, 0.8903), (70.69, 0.5333, 0.8997), (90.34, 0.5189, 0.9073),
    (115.29, 0.5181, 0.9122), (147.42, 0.5176, 0.9171), (188.24, 0.5172, 0.9217), (240.03, 0.5119, 0.9267),
]


class Env:
    def __init__(self, surface=1.013, density=1030.0):
        self.surface = surface
        self.per_m = density * 9.81e-5  # bar per metre (g = 9.81)

    def p(self, depth):
        return self.surface + depth * self.per_m


class Tissues:
    def __init__(self, env):
        self.env = env
        p0 = (env.surface - WATER_VAPOUR) * N2_IN_AIR
        self.n2 = [p0] * 16
        self.he = [0.0] * 16

    def copy(self):
        t = Tissues(self.env)
        t.n2, t.he = list(self.n2), list(self.he)
        return t

    def segment(self, d0, d1, minutes, gas):
        """Schreiner: inspired pressure changing linearly from depth d0 to d1 over `minutes`."""
        if minutes <= 0:
            return
        fo2, fhe = gas
        fn2 = 1.0 - fo2 - fhe
        pi0 = self.env.p(d0) - WATER_VAPOUR
        rate = (self.env.p(d1) - self.env.p(d0)) / minutes
        for loads, table, f in ((self.n2, N2, fn2), (self.he, HE, fhe)):
            for c, (ht, _, _) in enumerate(table):
                k = math.log(2.0) / ht
                r = rate * f
                pa = pi0 * f
                loads[c] = pa + r * (minutes - 1.0 / k) - (pa - loads[c] - r / k) * math.exp(-k * minutes)

    def ceiling(self, gf):
        """Deepest tolerated ambient pressure (bar) over the compartments at gradient factor gf."""
        worst = 0.0
        for c in range(16):
            pn, ph = self.n2[c], self.he[c]
            p = pn + ph
            a = (N2[c][1] * pn + HE[c][1] * ph) / p
            b = (N2[c][2] * pn + HE[c][2] * ph) / p
            worst = max(worst, (p - a * gf) / (gf / b + 1.0 - gf))
        return worst


def plan(env, segments, gases, gf_low, gf_high, ascent_rate=9.0, switch_hold=1.0, last_stop=3.0):
    """Fly `segments` [(d0, d1, minutes, (fO2, fHe))], then ascend from the last depth.

    `gases`: [(fO2, fHe, switch depth m)] breathed on the ascent from their switch depth. Returns
    (runtime min, stops [(depth, minutes)], ascent gas switches [(depth, gas)])."""
    t = Tissues(env)
    runtime = 0.0
    for d0, d1, m, g in segments:
        t.segment(d0, d1, m, g)
        runtime += m
    depth = segments[-1][1]
    gas = segments[-1][3]

    def richest(d, current):
        ok = [(o, h) for (o, h, sw) in gases if sw >= d - 1e-9 and o > current[0]]
        return max(ok, default=None)

    def level_above(d):
        n = math.floor((d - 1e-9) / 3.0) * 3.0
        return 0.0 if n < last_stop - 1e-9 else n

    fs = None  # first stop depth: where the GF-low ceiling stops the ascent
    stops, switches = [], []
    hold = 0.0

    def gf_at(d):
        return gf_high + (gf_low - gf_high) * d / fs if fs > 0 else gf_high

    while depth > 1e-9:
        better = richest(depth, gas)
        if better is not None:
            gas = better
            switches.append((depth, gas))
            hold = 0.0 if gas[0] >= 0.999 else switch_hold
        nxt = level_above(depth)
        if fs is None:
            low = (t.ceiling(gf_low) - env.surface) / env.per_m
            if low > nxt + 1e-9:
                fs = depth
        clear = hold <= 1e-9
        if clear and fs is not None:
            probe = t.copy()
            probe.segment(depth, nxt, (depth - nxt) / ascent_rate, gas)
            clear = probe.ceiling(gf_at(nxt)) <= env.p(nxt) + 1e-9
        if clear:
            t.segment(depth, nxt, (depth - nxt) / ascent_rate, gas)
            runtime += (depth - nxt) / ascent_rate
            depth = nxt
            continue
        # A stop: to the next whole minute of runtime.
        wait = math.floor(runtime + 1e-9) + 1.0 - runtime
        if wait < 1.0 / 60.0:
            wait += 1.0
        t.segment(depth, depth, wait, gas)
        runtime += wait
        hold -= wait
        if stops and abs(stops[-1][0] - depth) < 1e-9:
            stops[-1] = (depth, stops[-1][1] + wait)
        else:
            stops.append((depth, wait))
    return runtime, stops, switches
