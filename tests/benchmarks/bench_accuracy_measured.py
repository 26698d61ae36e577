"""Benchmark: the q-grid error of a scene with measured spectra at fixed magnifications.

For each points_per_decade, the largest error (docs/accuracy.md's measure, floor 1e-6 of the
largest value) of A/A0 and u at each magnification, against a run at a much finer grid:

    python tests/benchmarks/bench_accuracy_measured.py [SCENE] [REFERENCE_PPD] [--smoke]

(defaults: topography, 1600). docs/accuracy.md quotes its output. --smoke: reference 100 points
per decade against 25 (seconds, for CI).
"""

import sys
import tempfile
from pathlib import Path

import numpy as np
from _bench import SMOKE, positional

from roughcontact import engine, scene as scenes
from roughcontact.accuracy import with_settings

ZETAS = [1.0, 1.05, 1.2, 1.6, 2.5, 4.0, 8.0, 16.0, 32.0, 64.0, 127.0]
TARGETS = ("contact_area_ratio", "mean_separation")


def run(sc, settings):
    with tempfile.TemporaryDirectory() as d:
        res = engine.run(with_settings(sc, {**settings, "contact.zeta": ZETAS}), Path(d), targets=TARGETS,
                         report=engine.Reporter(None))["base"]
        return {v: res[s][v].transpose("zeta", ...).values
                for s, v in (("contact", TARGETS[0]), ("separation", TARGETS[1]))}


def main(name="topography", reference=1600, ppds=(50, 200, 400)):
    sc = scenes.load(name)
    ref = run(sc, {"numerics.points_per_decade": reference})
    print(f"scene {name}; reference {reference} points per decade; zeta = {ZETAS}")
    for ppd in ppds:
        res = run(sc, {"numerics.points_per_decade": ppd})
        for var in TARGETS:
            a, b = res[var].reshape(len(ZETAS), -1), ref[var].reshape(len(ZETAS), -1)
            e = np.abs(a - b) / np.maximum(np.abs(b), 1e-6 * np.abs(b).max())
            per = np.nanmax(e, axis=1)
            print(f"ppd {ppd:4d} {var:20s} zeta < 8: {per[np.array(ZETAS) < 8].max():.2g}  "
                  f"zeta >= 16: {per[np.array(ZETAS) >= 16].max():.2g}  per zeta {[f'{x:.1g}' for x in per]}")


if __name__ == "__main__":
    args = positional(sys.argv[1:])
    name = args[0] if args else "topography"
    if SMOKE:
        main(name, 100, (25,))
    else:
        main(name, int(args[1]) if len(args) > 1 else 1600)
