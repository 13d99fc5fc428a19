"""The 60 m trimix dive (tests/in/trimix_dive.toml) against Subsurface's own planner.

backends/deco/subsurface_planner.py is Subsurface's Bühlmann planner (core/planner.cpp `plan()`,
core/deco.cpp, commit f0dfae794b5b) ported line by line. First it must give Subsurface's own
regression answers (tests/testplan.cpp `testMetric`, `testImperial`) to the second; then it
plans poser's trimix dive with the same gases and the same descent and bottom, and poser's
runtime must be within 1 min of it. The one minute between them is named: with poser's two
differing details switched on in the port, it reproduces poser's stops to the second.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
POSER = Path(os.environ.get("POSER_BIN", ROOT / "target" / "release" / "poser"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import subsurface_planner as ss  # noqa: E402

TX15_45 = (150, 450)
EAN36 = (360, 0)
OXYGEN = (1000, 0)


def _testplan_prefs(imperial):
    """tests/testplan.cpp setupPrefs() + setupPlan(): GF 100/100, 30 ft/min, 10 ft/min last 6 m."""
    fast, last = round(30 * 304.8) // 60, round(10 * 304.8) // 60
    return ss.Prefs(ascrate75=fast, ascrate50=fast, ascratestops=fast, ascratelast6m=last,
                    last_stop=True, gflow=100, gfhigh=100, imperial=imperial)


def _testplan(imperial):
    dive = ss.Dive(1013, 10300)
    prefs = _testplan_prefs(imperial)
    step = 3048 if imperial else 3000
    bottom = round(260 * 304.8) if imperial else 79000
    drop = bottom * 60 // (round(75 * 304.8) if imperial else 23000)
    switches = [(dive.gas_mod(360, 1600, step), 1), (dive.gas_mod(1000, 1600, step), 2)]
    segments = [(drop, bottom, 0), (30 * 60 - drop, bottom, 0)]
    return ss.plan(dive, [TX15_45, EAN36, OXYGEN], segments, switches, prefs)


def test_port_gives_subsurfaces_testmetric_to_the_second():
    r = _testplan(imperial=False)
    assert r["runtime"] == 109 * 60  # testMetric: "expected run time of 109 minutes"
    assert [(d, c) for _, d, c in r["switches"]] == [(33000, 1), (6000, 2)]


def test_port_gives_subsurfaces_testimperial_to_the_second():
    r = _testplan(imperial=True)
    assert r["runtime"] == 111 * 60 - 2  # testImperial
    assert [(d, c) for _, d, c in r["switches"]] == [(33528, 1), (6096, 2)]


# The trimix dive as a Subsurface user enters it: cylinder 0 EAN32 (breathed from the surface),
# 1 TX15/55, 2 EAN50, 3 O₂; EAN32 "switch at" 30 m (the travel gas's depth in the scene),
# EAN50 at gas_mod(1.6 bar) = 21 m, O₂ at the 3 m stop as in poser (Subsurface's own default
# for O₂, gas_mod(1.6 bar) with its +0.1 rounding, is 6 m: reported too).
CYLINDERS = [(320, 0), (150, 550), (500, 0), (1000, 0)]


def _poser_dive():
    out = subprocess.run(
        [str(POSER), "dive", str(ROOT / "tests" / "in" / "trimix_dive.toml"), "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out)


def _subsurface(dive_json, o2_switch_mm=3000, **kw):
    d = dive_json["dive"]
    depth = round(d["max_depth"] * 1000)
    assert d["profile"][1] == [100.0, 30.0]  # EAN32 to 30 m, then the trimix
    down = round(d["descent_time"])
    travel = round(d["profile"][1][0])
    segments = [(travel, 30000, 0), (down - travel, depth, 1), (round(d["bottom_time"]), depth, 1)]
    env = ss.Dive(1013, 10300)
    switches = [(30000, 0), (env.gas_mod(500, 1600), 2), (o2_switch_mm, 3)]
    return ss.plan(env, CYLINDERS, segments, switches, **kw)


def test_trimix_dive_runtime_matches_subsurfaces_planner():
    r = _poser_dive()
    assert r["verdict"]["ok"] and r["verdict"]["deco_planned"], r["verdict"]["problems"]
    poser = r["dive"]["runtime"]
    sub = _subsurface(r)
    default_o2 = _subsurface(r, o2_switch_mm=ss.Dive(1013, 10300).gas_mod(1000, 1600))
    print(f"poser {poser:.0f} s, Subsurface {sub['runtime']} s (O2 at 6 m: {default_o2['runtime']} s)")
    print("Subsurface stops", sub["stops"])
    assert abs(sub["runtime"] - poser) <= 60 + 1e-6
    assert sub["runtime"] == 60 * 60 + 20  # 60:20, pinned: docs/planning.md quotes it
    assert default_o2["runtime"] == 57 * 60 + 20
    # The same first and last stop depths, and the same gases in the same order.
    assert sub["stops"][0][0] == 30000 and sub["stops"][-1] == (3000, 700)
    assert [c for _, _, c in sub["switches"]] == [0, 2, 3]


def test_the_minute_is_the_switch_hold_and_the_first_ascent_step():
    """With poser's switch hold (to the whole runtime minute) and without Subsurface's 2 s at
    the bottom depth before the ascent moves, the port plans poser's stops to the second."""
    r = _poser_dive()
    d = r["dive"]
    port = _subsurface(r, hold_to_minute=True, step_at_bottom=False)
    assert port["runtime"] == round(d["runtime"])
    mine = [(s["depth"], round(s["duration"])) for s in d["stops"]]
    assert [(dm / 1000.0, t) for dm, t in port["stops"]] == mine
    # Either detail alone leaves Subsurface's 60:20.
    for kw in ({"hold_to_minute": True}, {"step_at_bottom": False}):
        assert _subsurface(r, **kw)["runtime"] == 3620
