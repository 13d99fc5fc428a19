"""DISORT reference for `poser column`: the same plane-parallel water column, solved by PythonicDISORT.

`poser column SCENE -o DIR` writes DIR/column.json: the water column above the seabed (depth,
absorption and scattering per channel, Henyey-Greenstein phase function, the refracted sun's
beam and an isotropic sky just below the surface, a Lambertian bottom, a non-reflecting top)
and the Monte Carlo irradiance profiles it solved. This module solves the same problem with
the discrete-ordinates solver DISORT (the pure-Python port `PythonicDISORT.pydisort`, pinned in
backends/requirements.txt) so that backends/column/tests compare the two.

The mapping (each convention checked numerically by `--selftest` against closed forms):

| column.json | DISORT |
|---|---|
| `depth`, `sigma_a`, `sigma_s` | one layer: `tau = (sigma_a + sigma_s) * depth`, `omega = sigma_s / (sigma_a + sigma_s)`; a depth z is `tau = (sigma_a + sigma_s) * z` |
| `phase` HG `g` | Legendre coefficients `g**l`, delta-M with `f = g**NQuad` (the package's advice: `f_arr = Leg_coeffs_all[NLeg]`) |
| `mu0` (per channel), `sun_irradiance` E | `mu0` of the channel, `I0 = E`: DISORT's direct flux is `I0 * mu0 * exp(-tau / mu0)`, so `I0` is the irradiance on a plane normal to the beam |
| `ambient` L | `b_neg = L`: isotropic downward intensity at the top (Fourier mode 0); E_d(0) = pi * L |
| `bottom_albedo` A | `BDRF_Fourier_modes = [A]`: PythonicDISORT's reflected intensity is `rho/pi` times the incident flux, so a Lambertian bottom of albedo A is rho = A (not A/pi) |
| `top = "open"` | DISORT's top boundary does not reflect |

Outputs are energetic (plane) fluxes, W/m²: E_d_direct, E_d_diffuse, E_u, and the scalar
irradiance E_0 (the actinic fluxes plus the direct beam's `E * exp(-tau / mu0)`).

    python backends/column/disort_reference.py column.json   # DISORT vs the JSON at the bottom
    python backends/column/disort_reference.py --selftest    # the conventions against closed forms
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.special import expn

from PythonicDISORT import pydisort
from PythonicDISORT.subroutines import generate_diff_act_flux_funcs

# Streams (NQuad). Even 64 gives the fluxes of a g = 0.92 column to 1e-8 of 256 streams (the
# self-test compares); 128 costs a hundredth of a second.
NQUAD = 128
CHANNELS = ("R", "G", "B")


def disort_channel(case: dict, c: int, z, nquad: int = NQUAD) -> dict:
    """DISORT's profiles of channel `c` (0 = R) of a column.json dict at depths `z` (m, down).

    Returns numpy arrays E_d_direct, E_d_diffuse, E_u, E_0 (W/m²) the length of `z`.
    """
    depth = float(case["depth"])
    sa = float(case["sigma_a"][c])
    ss = float(case["sigma_s"][c])
    ext = sa + ss
    if not (depth > 0 and ext > 0 and sa >= 0 and ss >= 0):
        raise ValueError(f"no column to solve: depth {depth} m, sigma_a {sa}, sigma_s {ss} 1/m")
    omega = ss / ext
    phase = case.get("phase") or {"kind": "henyey_greenstein", "g": 0.0}
    if phase.get("kind") != "henyey_greenstein":
        raise NotImplementedError(f"phase {phase.get('kind')!r}: only Henyey-Greenstein is mapped")
    g = float(phase["g"])
    # NLeg = NQuad coefficients are used; one more is given so that f = g**NQuad is at hand.
    leg = g ** np.arange(nquad + 1)
    f = leg[nquad] if omega > 0 else 0.0

    mu0 = case.get("mu0")
    if isinstance(mu0, list):  # per channel: the sun refracts with each channel's index
        mu0 = mu0[c]
    e_sun = float(case["sun_irradiance"][c]) if mu0 is not None else 0.0
    if e_sun > 0:
        mu0 = float(mu0)
        i0 = e_sun  # direct flux I0*mu0*exp(-tau/mu0): I0 is normal to the beam
    else:
        mu0, i0, e_sun = 1.0, 0.0, 0.0
    ambient = float(case["ambient"][c])
    albedo = float(case["bottom_albedo"][c])

    tau_total = ext * depth
    z = np.atleast_1d(np.asarray(z, dtype=float))
    if np.any(z < -1e-9) or np.any(z > depth * (1 + 1e-9)):
        raise ValueError(f"depths {z.tolist()} are not all within the column [0, {depth}] m")
    tau = np.clip(ext * z, 0.0, tau_total)

    if i0 == 0 and ambient == 0:
        zero = np.zeros_like(tau)
        return {"E_d_direct": zero, "E_d_diffuse": zero, "E_u": zero, "E_0": zero}

    _mu, flux_up, flux_down, u0 = pydisort(
        tau_total,
        omega,
        nquad,
        leg[None, :],
        mu0,
        i0,
        0.0,
        NLeg=nquad,
        b_neg=ambient,
        only_flux=True,
        f_arr=f,
        BDRF_Fourier_modes=[albedo] if albedo > 0 else [],
    )
    e_diffuse, e_direct = flux_down(tau)
    e_u = flux_up(tau)
    act_up, act_down = generate_diff_act_flux_funcs(u0)
    e_0 = act_up(tau) + act_down(tau) + e_sun * np.exp(-tau / mu0)
    return {
        "E_d_direct": np.atleast_1d(e_direct) * np.ones_like(tau),
        "E_d_diffuse": np.atleast_1d(e_diffuse),
        "E_u": np.atleast_1d(e_u),
        "E_0": np.atleast_1d(e_0),
    }


def disort_profiles(case: dict, z, nquad: int = NQUAD) -> dict:
    """DISORT's profiles of every channel of a column.json dict, laid out like column.json."""
    out = {"z": [float(v) for v in np.atleast_1d(z)], "channels": []}
    for c, name in enumerate(CHANNELS[: len(case["sigma_a"])]):
        p = disort_channel(case, c, z, nquad)
        out["channels"].append({"name": name, **{k: v.tolist() for k, v in p.items()}})
    return out


def rel(a: float, b: float) -> float:
    """Relative difference of a to the reference b (0 when both are 0)."""
    if b == 0:
        return 0.0 if a == 0 else math.inf
    return (a - b) / b


# --- self-test --------------------------------------------------------------------------------


def _case(**kw) -> dict:
    base = {
        "depth": 10.0,
        "mu0": None,
        "sun_irradiance": [0.0],
        "ambient": [0.0],
        "bottom_albedo": [0.0],
        "phase": {"kind": "henyey_greenstein", "g": 0.92},
        "sigma_a": [0.2],
        "sigma_s": [0.0],
    }
    base.update(kw)
    return base


def selftest(out=sys.stdout) -> bool:
    """Checks the I0, b_neg and BDRF conventions against closed forms; prints the numbers."""
    ok = True

    def check(label: str, got, want, tol: float) -> None:
        nonlocal ok
        got, want = np.atleast_1d(got), np.atleast_1d(want)
        err = float(np.max(np.abs(got - want) / np.maximum(np.abs(want), 1e-300)))
        good = err <= tol
        ok &= good
        print(
            f"{'ok  ' if good else 'FAIL'} {label}: max rel err {err:.2e} (tol {tol:.0e});"
            f" got {np.array2string(got[-3:], precision=6)}"
            f" want {np.array2string(want[-3:], precision=6)}",
            file=out,
        )

    z = np.linspace(0.0, 10.0, 11)
    c = 0.2
    a = 0.5

    # 1. I0: a sun beam in a purely absorbing column, black bottom.
    e, mu0 = 800.0, 0.8
    p = disort_channel(_case(mu0=mu0, sun_irradiance=[e]), 0, z)
    check("sun, omega=0: E_d_direct = E*mu0*exp(-c z/mu0)", p["E_d_direct"],
          e * mu0 * np.exp(-c * z / mu0), 1e-10)
    check("sun, omega=0: E_d_diffuse = 0", p["E_d_diffuse"] + 1.0, np.ones_like(z), 1e-9)
    check("sun, omega=0: E_0 = E*exp(-c z/mu0)", p["E_0"], e * np.exp(-c * z / mu0), 1e-9)

    # 2. BDRF with the beam: a Lambertian bottom of albedo A, still no scattering.
    p = disort_channel(_case(mu0=mu0, sun_irradiance=[e], bottom_albedo=[a]), 0, z)
    e_bot = e * mu0 * math.exp(-c * 10.0 / mu0)
    check("sun, omega=0, A=0.5: E_u(bottom) = A*E_d(bottom)", p["E_u"][-1], a * e_bot, 1e-6)
    check("sun, omega=0, A=0.5: E_u(z) = 2*A*E_d(bottom)*E3(c (H-z))", p["E_u"],
          2 * a * e_bot * expn(3, c * (10.0 - z)), 1e-5)

    # 3. b_neg: an isotropic sky of radiance L, no sun, no scattering.
    radiance = 3.0
    p = disort_channel(_case(ambient=[radiance], bottom_albedo=[a]), 0, z)
    e_d = 2 * math.pi * radiance * expn(3, c * z)
    check("sky L, omega=0: E_d(z) = 2*pi*L*E3(c z)", p["E_d_diffuse"] + p["E_d_direct"], e_d, 1e-5)
    check("sky L, omega=0: E_d(0) = pi*L", p["E_d_diffuse"][0], math.pi * radiance, 1e-9)
    check("sky L, omega=0, A=0.5: E_u(bottom) = A*E_d(bottom)", p["E_u"][-1], a * e_d[-1], 1e-5)
    check("sky L, omega=0: E_0(z) = 2*pi*L*E2(c z) + E_u part", p["E_0"],
          2 * math.pi * radiance * expn(2, c * z)
          + 2 * a * e_d[-1] * expn(2, c * (10.0 - z)), 1e-3)

    # 4. With scattering: energy balance dE_net/dz = -sigma_a*E_0, and stream convergence.
    sa, ss = 0.05, 0.25
    case = _case(mu0=0.8, sun_irradiance=[1000.0], ambient=[20.0], bottom_albedo=[a],
                 sigma_a=[sa], sigma_s=[ss], depth=12.0)
    zf = np.linspace(0.0, 12.0, 2401)
    p = disort_channel(case, 0, zf)
    net = p["E_d_direct"] + p["E_d_diffuse"] - p["E_u"]
    absorbed = sa * np.trapz(p["E_0"], zf)
    check("scattering g=0.92: net(0) - net(H) = sigma_a * integral E_0 dz",
          net[0] - net[-1], absorbed, 1e-4)
    ref = disort_channel(case, 0, [12.0], nquad=256)
    for nq in (64, NQUAD):
        t0 = time.perf_counter()
        q = disort_channel(case, 0, [12.0], nquad=nq)
        dt = time.perf_counter() - t0
        for k in ("E_d_diffuse", "E_u"):
            check(f"scattering g=0.92: NQuad {nq} vs 256, {k}(bottom) ({dt:.2f} s)", q[k], ref[k],
                  2e-3 if nq == 64 else 5e-4)
    print("selftest", "passed" if ok else "FAILED", file=out)
    return ok


# --- command line -----------------------------------------------------------------------------


def compare(path: Path, profile: bool = False, out=sys.stdout) -> float:
    """Prints DISORT's and the JSON's E_d and E_u (at the bottom, or at every z) per channel.

    Returns the largest relative difference of E_d or E_u at the bottom.
    """
    case = json.loads(path.read_text())
    z = case["z"] if profile else [case["depth"]]
    ref = disort_profiles(case, z)
    print(f"{case.get('scene', path)}: depth {case['depth']} m, mu0 {case.get('mu0')}, "
          f"phase {case.get('phase')}, bottom albedo {case['bottom_albedo']}", file=out)
    print(f"{'ch':2} {'z':>7} {'E_d DISORT':>12} {'E_d json':>12} {'rel':>8} {'±se':>7} "
          f"{'E_u DISORT':>12} {'E_u json':>12} {'rel':>8} {'±se':>7}", file=out)
    worst = 0.0
    for ch, dch in zip(case["channels"], ref["channels"]):
        js = range(len(case["z"])) if profile else [len(case["z"]) - 1]
        for i, j in enumerate(js):
            ed = dch["E_d_direct"][i] + dch["E_d_diffuse"][i]
            eu = dch["E_u"][i]
            jd = ch["E_d_direct"][j] + ch["E_d_diffuse"][j]
            ju = ch["E_u"][j]
            rd, ru = rel(jd, ed), rel(ju, eu)
            sd = ch["E_d_stderr"][j] / jd if jd else 0.0
            su = ch["E_u_stderr"][j] / ju if ju else 0.0
            if j == len(case["z"]) - 1:
                worst = max(worst, abs(rd), abs(ru))
            print(f"{ch['name']:2} {case['z'][j]:7.2f} {ed:12.5g} {jd:12.5g} {rd:+8.2%} {sd:7.2%} "
                  f"{eu:12.5g} {ju:12.5g} {ru:+8.2%} {su:7.2%}", file=out)
    return worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("column_json", nargs="?", type=Path, help="a `poser column` output")
    ap.add_argument("--profile", action="store_true", help="every z of the JSON, not the bottom")
    ap.add_argument("--selftest", action="store_true", help="check the conventions and exit")
    args = ap.parse_args(argv)
    if args.selftest:
        return 0 if selftest() else 1
    if args.column_json is None:
        ap.error("give a column.json or --selftest")
    worst = compare(args.column_json, args.profile)
    print(f"largest relative difference of E_d or E_u at the bottom: {worst:.3%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
