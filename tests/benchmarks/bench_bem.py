"""Benchmark of the bem stage's contact solve: time per pressure and peak memory at 512^2 and
1024^2 (the bem scene's surfaces: H = 0.8, hrms = 1 nm each, eta = 0, 4 pixels per shortest
wavelength).

Run: python tests/benchmarks/bench_bem.py [grid ...] [--smoke]   (needs the [bem] extra: tamaas)
--smoke: one 32^2 grid (seconds, for CI).

Each grid runs in a fresh subprocess so that its peak resident set size (ru_maxrss) is its own;
the table also gives the RSS after imports, so the difference is what the solve needs.
"""

from __future__ import annotations

import json
import subprocess
import sys

from _bench import SMOKE, positional

CHILD = r"""
import json, resource, sys, time
import numpy as np
from roughcontact.physics.bem import solve_contact
from roughcontact.physics.synthesis import grid_band, synthesize_pair
from roughcontact.physics.spectra import self_affine_hrms_factor, self_affine_psd
import tamaas
n = {n}
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
qL, q0, q1, H = 2e8, 8e8, 4e10, 0.8
q = np.geomspace(qL, q1, 400)
C = self_affine_psd(q, H, qL, q0, q1, 1e-18 / self_affine_hrms_factor(H, qL, q0, q1))
E_star = 77.2e9 / (1 - 0.42**2)
L, dx, q_cut, zeta = grid_band(qL, q1, n, 4)
t0 = time.perf_counter()
h1, h2 = synthesize_pair(q, C, C, 0.0, n, q_cut, seed=1)
t_syn = time.perf_counter() - t0
rows = []
for rel in (1e-3, 1e-2, 1e-1):
    t0 = time.perf_counter()
    r = solve_contact(h1 - h2, dx, E_star, [rel * E_star], tolerance=1e-10)
    rows.append((rel, time.perf_counter() - t0, float(r["area"][0]), float(r["mean_gap"][0])))
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps(dict(n=n, zeta=zeta, synth=t_syn, rows=rows, base_mb=base / 1024, peak_mb=peak / 1024,
                      tamaas=tamaas.__version__)))
"""


def main(grids=(512, 1024)):
    print(f"{'grid':>6} {'zeta':>6} {'p/E*':>7} {'time/p (s)':>10} {'A/A0':>8} {'gap (nm)':>9} "
          f"{'synth (s)':>9} {'RSS base (MB)':>13} {'peak (MB)':>9}")
    for n in grids:
        out = subprocess.run([sys.executable, "-c", CHILD.format(n=int(n))],
                             capture_output=True, text=True, check=True)
        res = json.loads(out.stdout.strip().splitlines()[-1])
        for rel, t, area, gap in res["rows"]:
            print(f"{res['n']:>6} {res['zeta']:>6.0f} {rel:>7.0e} {t:>10.2f} {area:>8.4f} {gap * 1e9:>9.4f} "
                  f"{res['synth']:>9.3f} {res['base_mb']:>13.0f} {res['peak_mb']:>9.0f}")
    print(f"(tamaas {res['tamaas']}, PolonskyKeerRey, tolerance 1e-10; one core-share of a busy 2-core machine)")


if __name__ == "__main__":
    main(tuple(int(a) for a in positional(sys.argv[1:])) or ((512, 1024) if not SMOKE else (32,)))
