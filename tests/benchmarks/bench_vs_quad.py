"""Benchmark: each stage at each preset against a straightforward scipy.integrate implementation
of the same equation, in one run.

    python tests/benchmarks/bench_vs_quad.py [--smoke]

For contact (eq 19 with G of eq 17), separation (eq 57) and friction (eqs 61-62) on the built-in
scenes (eta = 0), the stage computes a sweep of N = 100 pressures (x 2 magnifications) or
velocities at the fast, default and accurate presets (the whole pipeline run, best of 3). The
same equation is evaluated by adaptive scipy quadrature at scipy's default tolerance and at a
tight one (the reference) on 4 of the sweep's points; scipy's time is scaled to the N points of
the sweep (its cost is linear in them). Printed per stage and preset: the stage's time and error
on those points, scipy's time and error, and the ratios (speed: scipy / stage; error: stage /
scipy). --smoke: 10 sweep points, one run per preset, the fast preset only, 2 points for scipy
at tolerances 1e-6 and 1e-8 (seconds, for CI).
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np
from _bench import SMOKE
from reference_solutions import brute_force_mu, brute_force_u
from scipy.integrate import quad
from scipy.special import erf

from roughcontact import engine, scene as scenes
from roughcontact.physics.spectra import self_affine_hrms_factor

SCIPY_DEFAULT, TIGHT = (1.49e-8, 1e-11) if not SMOKE else (1e-6, 1e-8)
PRESETS, REPEAT = (("fast", "default", "accurate"), 3) if not SMOKE else (("fast",), 1)


def _stage(scene_name, preset, overrides, stage, variable):
    raw = scenes.load(scene_name).raw
    raw.pop("variants", None)
    for section, values in overrides.items():
        raw.setdefault(section, {}).update(values)
    raw.setdefault("numerics", {})["preset"] = preset
    sc = scenes.from_dict(raw)
    best = math.inf
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(REPEAT):
            t0 = time.perf_counter()
            res = engine.run(sc, Path(tmp), targets=[variable], force=("all",), report=engine.Reporter(None))
            best = min(best, time.perf_counter() - t0)
    return res["base"][stage][variable], best


def _timed(f, *args):
    t0 = time.perf_counter()
    out = f(*args)
    return out, time.perf_counter() - t0


# ---- the three equations by plain adaptive quadrature ----------------------------------------
H, QL, Q1, E_STAR = 0.8, 2e8, 4e10, 77.2e9 / (1 - 0.42**2)
C0_PAIR = 2 * 1e-18 / self_affine_hrms_factor(H, QL, QL, Q1)  # eta = 0, identical surfaces: C = 2 C1


def contact_quad(points, epsrel):
    out = []
    for pt in points:
        g = quad(lambda q: q**3 * C0_PAIR * (q / QL) ** (-2 - 2 * H), QL, pt["zeta"] * QL, epsabs=0, epsrel=epsrel)[0]
        out.append(erf(pt["p"] / (2 * math.sqrt(math.pi / 4 * E_STAR**2 * g))))
    return np.array(out)


def separation_quad(points, epsrel):
    return np.array([brute_force_u(pt["p"], pt["zeta"], C0_PAIR, epsrel=epsrel) for pt in points])


def friction_quad(points, rtol):
    sc = scenes.load("friction")
    v = sc.values
    return np.array([brute_force_mu(pt["v"], v["modulus"], [v["substrate"], v["solid"]], v["load"]["p"],
                                     v["material"]["nu"], rtol=rtol)[0] for pt in points])


N = 100 if not SMOKE else 10
SWEEP_P = {"load": {"p": {"from": "1e3 Pa", "to": "1e10 Pa", "num": N}}, "contact": {"zeta": [4.0, 200.0]}}
SWEEP_V = {"friction": {"v": {"from": "1e-6 m/s", "to": "1e2 m/s", "num": N}}}
PICK = [0, 33, 66, 99] if not SMOKE else [0, 9]

CASES = [
    ("contact", "default", "contact_area_ratio", contact_quad, SWEEP_P, 2 * N),
    ("separation", "default", "mean_separation", separation_quad, SWEEP_P, 2 * N),
    ("friction", "friction", "friction_coefficient", friction_quad, SWEEP_V, N),
]


def _points(da):
    """Four points of the sweep (eta = 0; both magnifications where there are two)."""
    dim = "p" if "p" in da.dims and da.sizes["p"] == N else "v"
    values = da[dim].values[PICK]
    zetas = da["zeta"].values if "zeta" in da.dims else [None]
    pts = [{dim: float(x), "eta": 0.0, **({"zeta": float(z)} if z is not None else {})} for x in values for z in zetas]
    return pts[:: max(1, len(pts) // 4)][:4 if not SMOKE else 2]


def main() -> None:
    print(f"{'stage':11s} {'preset':9s} {'stage s':>9s} {'stage err':>10s} {'scipy s':>9s} {'scipy err':>10s}"
          f" {'speed x':>8s} {'err ratio':>10s}   (N = {N} sweep points; scipy timed on 4, scaled)")
    for stage, scene_name, variable, brute, overrides, n_points in CASES:
        runs = {preset: _stage(scene_name, preset, overrides, stage, variable) for preset in PRESETS}
        points = _points(runs[PRESETS[-1] if SMOKE else "default"][0])
        reference, _ = _timed(brute, points, TIGHT)
        scipy_values, scipy_time = _timed(brute, points, SCIPY_DEFAULT)
        scipy_time *= n_points / len(points)
        scipy_err = float(np.max(np.abs(scipy_values / reference - 1)))
        for preset, (da, t) in runs.items():
            values = np.array([float(da.sel(**pt)) for pt in points])
            err = float(np.max(np.abs(values / reference - 1)))
            ratio = err / scipy_err if scipy_err > 0 else math.inf
            print(f"{stage:11s} {preset:9s} {t:9.3f} {err:10.2e} {scipy_time:9.3f} {scipy_err:10.2e}"
                  f" {scipy_time / t:8.1f} {ratio:10.2g}")


if __name__ == "__main__":
    main()
