"""`poser column` against DISORT: the water column's irradiance at the seabed, independently.

Each case writes a scene (a flat sea, one Jerlov water, a 200 m × 200 m seabed plane of albedo
0.5, a sun with a black sky or a sky without a sun), runs `$POSER_BIN column scene.toml -o out`
(default target/release/poser) and solves the column that out/column.json describes with
PythonicDISORT (backends/column/disort_reference.py). E_d (direct + diffuse) and E_u at the
bottom must agree within 1 % per channel, with the Monte Carlo's own standard error below 0.5 %.

Channels that keep less than 0.1 % of the surface's light at the seabed (red at 30 m, blue in
coastal water at 30 m: ten stops below the surface, black in an image) are solved with one round
of photons (crates/poser-optics/src/column.rs, VISIBLE): there the column must agree within 1 % or three of
its own standard errors, whichever is larger.
"""

import json
import math
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
POSER = Path(os.environ.get("POSER_BIN", ROOT / "target" / "release" / "poser"))

TOLERANCE = 0.01  # DISORT vs the column, relative, per channel
STDERR_MAX = 0.005  # the column's own relative standard error at the bottom (the solver aims at 0.2 %; a heavy-tailed channel stops at 16 rounds)
VISIBLE = 1e-3  # share of the surface's downward light below which a channel is "dark"
ALBEDO = 0.5
SUN_IRRADIANCE = 1000.0  # W/m², normal to the sun, above the surface
SKY_RADIANCE = 30.0  # W/(m² sr), the ambient light of the sky-only case

SCENE = """\
name = "{name}"
description = "poser column vs DISORT, the irradiance at the seabed: {title}"

[site]
depth = "{depth} m"
surface = "flat"

[water]
jerlov = "{jerlov}"
phase = "hg"
g = {g}

{light}
[[objects]]
name = "seabed"
shape = "plane"
width = "200 m"
height = "200 m"
position = [0.0, 0.0, -{depth}]
albedo = {albedo}

[camera]
width = 64
height = 48
focal_length = "16 mm"

[network]
type = "explicit"

[[network.poses]]
position = [0.0, 0.0, -{camera_depth}]

# Like for like: DISORT's top boundary lets the light coming up leave, and its sky is an
# isotropic radiance just below the surface; poser's default surface reflects from below
# (Fresnel, Snell's window), which crates/poser-optics/src/column.rs checks against closed forms instead.
[render]
surface_from_below = "open"
"""

SUN = """\
[sun]
elevation = "{elevation} deg"
azimuth = "180 deg"
irradiance = {irradiance}
"""

SKY = """\
[[lights]]
type = "ambient"
radiance = {radiance}
"""

# (water, depth m, HG g, light): "sun" is a sun beam under a black sky at that elevation,
# "sky" an ambient sky without a sun.
CASES = [
    ("IB", 5.0, 0.92, "sun", 60),
    ("IB", 12.0, 0.92, "sun", 60),
    ("IB", 30.0, 0.92, "sun", 60),
    ("3C", 5.0, 0.92, "sun", 60),
    ("3C", 12.0, 0.92, "sun", 60),
    ("3C", 30.0, 0.92, "sun", 60),
    ("IB", 12.0, 0.7, "sun", 45),
    ("3C", 12.0, 0.7, "sun", 45),
    ("IB", 12.0, 0.92, "sky", None),
]


def case_id(case) -> str:
    jerlov, depth, g, light, elevation = case
    sun = f"sun{elevation}" if light == "sun" else "sky_only"
    return f"{jerlov}-{depth:g}m-g{g}-{sun}"


def scene_text(case) -> str:
    jerlov, depth, g, light, elevation = case
    if light == "sun":
        lit = SUN.format(elevation=elevation, irradiance=SUN_IRRADIANCE)
    else:
        lit = SKY.format(radiance=SKY_RADIANCE)
    return SCENE.format(
        name="column_" + case_id(case).replace("-", "_").replace(".", "p"),
        title=case_id(case),
        depth=depth,
        jerlov=jerlov,
        g=g,
        light=lit,
        albedo=ALBEDO,
        camera_depth=depth - 2.0,
    )


def run_column(tmp_path: Path, case) -> dict:
    assert POSER.exists(), f"{POSER} is missing: run `cargo build --release` (test.sh does)"
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text(case))
    out = tmp_path / "out"
    r = subprocess.run(
        [str(POSER), "column", str(scene), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    if r.returncode != 0:
        pytest.fail(
            f"`poser column {scene} -o {out}` exited with {r.returncode} "
            f"(is the `column` command built into {POSER}?)\n"
            f"stdout:\n{r.stdout}\nstderr:\n{r.stderr}",
            pytrace=False,
        )
    column = out / "column.json"
    assert column.exists(), f"`poser column` succeeded but wrote no {column}"
    return json.loads(column.read_text())


def test_disort_reference_conventions(reference):
    """The reference itself: DISORT's I0, b_neg and BDRF conventions against closed forms."""
    assert reference.selftest(), "the DISORT reference's self-test failed (see the output)"


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_column_matches_disort_at_the_seabed(tmp_path, reference, case):
    jerlov, depth, g, light, elevation = case
    col = run_column(tmp_path, case)

    # The column is the scene's: its depth, its phase function, its seabed, an open top.
    assert col["depth"] == pytest.approx(depth)
    assert col["z"][-1] == pytest.approx(depth), "the last profile depth is not the bottom"
    assert col["top"] == "open"
    assert col["phase"]["kind"] == "henyey_greenstein"
    assert col["phase"]["g"] == pytest.approx(g)
    assert col["bottom_albedo"] == pytest.approx([ALBEDO] * 3)
    assert [ch["name"] for ch in col["channels"]] == ["R", "G", "B"]
    if light == "sun":
        # Refracted by a flat sea (n ≈ 1.34): cos of the zenith angle in the water, per
        # channel (each refracts with its own index; blue, bent most, the steepest).
        s = math.cos(math.radians(elevation)) / 1.34
        assert col["mu0"] == pytest.approx([math.sqrt(1 - s * s)] * 3, abs=0.005)
        assert col["mu0"][0] <= col["mu0"][1] <= col["mu0"][2]
        assert all(e > 0 for e in col["sun_irradiance"])
        assert col["ambient"] == pytest.approx([0.0] * 3), "a black sky was asked for"
    else:
        assert col["mu0"] is None, "no sun was asked for"
        assert col["sun_irradiance"] == pytest.approx([0.0] * 3)
        assert all(a > 0 for a in col["ambient"])

    ref = reference.disort_profiles(col, [col["depth"]])
    failures = []
    for ch, dch in zip(col["channels"], ref["channels"]):
        surface = ch["E_d_direct"][0] + ch["E_d_diffuse"][0]
        ed_mc = ch["E_d_direct"][-1] + ch["E_d_diffuse"][-1]
        dark = ed_mc < VISIBLE * surface
        eu_mc = ch["E_u"][-1]
        ed = dch["E_d_direct"][0] + dch["E_d_diffuse"][0]
        eu = dch["E_u"][0]
        for what, mc, want, se in (
            ("E_d", ed_mc, ed, ch["E_d_stderr"][-1]),
            ("E_u", eu_mc, eu, ch["E_u_stderr"][-1]),
        ):
            line = (
                f"{ch['name']} {what}(bottom): column {mc:.6g} ± {se:.3g}, DISORT {want:.6g}, "
                f"relative difference {reference.rel(mc, want):+.3%}, "
                f"relative stderr {se / mc if mc else math.inf:.3%}"
            )
            if not want > 0:
                failures.append(f"{line} (DISORT has no light there)")
            elif abs(mc - want) > max(TOLERANCE * want, 3.0 * se if dark else 0.0):
                failures.append(f"{line}: more than {TOLERANCE:.0%} apart")
            if not dark and not (mc > 0 and se < STDERR_MAX * mc):
                failures.append(f"{line}: stderr not below {STDERR_MAX:.1%}")
    if failures:
        pytest.fail(
            f"{case_id(case)} (sigma_a {col['sigma_a']}, sigma_s {col['sigma_s']}, "
            f"mu0 {col['mu0']}):\n  " + "\n  ".join(failures),
            pytrace=False,
        )
