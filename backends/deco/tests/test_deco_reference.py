"""The 60 m trimix dive (tests/in/trimix_dive.toml) against an independent ZHL-16C + GF planner.

`$POSER_BIN dive tests/in/trimix_dive.toml --json` (default target/release/poser) plans the dive:
TX15/55 in twin 12 l, EAN32 travel to 30 m, EAN50 from 21 m and O₂ from 5 m, GF 30/75, sea
water. The descent and the time at 60 m are the scene's (read from the JSON); the ascent is
planned again by backends/deco/zhl16c_reference.py, written from Bühlmann's coefficients, the
Schreiner equation and Baker's gradient factors, not from poser's code. The runtimes must agree
within 1 min, and poser must call the dive "OK, decompression planned".
"""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
POSER = Path(os.environ.get("POSER_BIN", ROOT / "target" / "release" / "poser"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import zhl16c_reference as ref  # noqa: E402

SCENE = ROOT / "tests" / "in" / "trimix_dive.toml"
TX = (0.15, 0.55)
EAN32 = (0.32, 0.0)


def switch_depth_travel(env, gas, po2=1.4, end_limit=30.0):
    """The deepest whole metre within the pO₂ limit and the END limit (O₂ narcotic)."""
    mod = (po2 / gas[0] - env.surface) / env.per_m
    end = (env.p(end_limit) / (1.0 - gas[1]) - env.surface) / env.per_m
    return float(int(min(mod, end)))


def switch_depth_deco(env, o2, po2=1.6):
    return float(int((po2 / o2 - env.surface) / env.per_m))


def test_trimix_dive_runtime_matches_an_independent_planner():
    out = subprocess.run(
        [str(POSER), "dive", str(SCENE), "--json"], check=True, capture_output=True, text=True
    ).stdout
    r = json.loads(out)
    assert r["verdict"]["ok"] and r["verdict"]["deco_planned"], r["verdict"]["problems"]
    dive = r["dive"]
    depth = dive["max_depth"]
    env = ref.Env(1.013, 1030.0)
    sw = switch_depth_travel(env, EAN32)
    assert sw == 30.0
    rate = depth / dive["descent_time"]  # m/s, the scene's descent rate
    segments = [
        (0.0, sw, sw / rate / 60.0, EAN32),
        (sw, depth, (depth - sw) / rate / 60.0, TX),
        (depth, depth, dive["bottom_time"] / 60.0, TX),
    ]
    gases = [(0.32, 0.0, sw), (0.5, 0.0, switch_depth_deco(env, 0.5)), (1.0, 0.0, switch_depth_deco(env, 1.0))]
    runtime, stops, _ = ref.plan(env, segments, gases, 0.30, 0.75)
    poser_min = dive["runtime"] / 60.0
    print(f"poser {poser_min:.2f} min, independent {runtime:.2f} min, stops {stops}")
    assert abs(runtime - poser_min) <= 1.0 + 1e-6
    # The same first stop and last stop.
    assert stops[0][0] == dive["stops"][0]["depth"]
    assert stops[-1][0] == dive["stops"][-1]["depth"] == 3.0
