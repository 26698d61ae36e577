"""Benchmark of the friction stage: mu(v) for 100 velocities x 4 surface cases.

The cases are those of the built-in ``friction`` scene: substrate only, and both rough with
eta = 0, +1, -1. For each pair (q points per decade, Gauss-Legendre nodes in phi) the script
times (CPU time, best of 5, one BLAS thread) the friction stage's kernels (angular integrals + q
integrals; the PSD and the modulus are computed once per q grid and not timed) and measures the
largest relative error of mu and of A/A0 over all velocities and cases against a converged run
(400 points per decade, 256 phi nodes, 24 nodes per q segment). It also measures the error left
by the modulus grid (numerics.modulus_points_per_decade) against the analytic box spectrum.

Run:  python tests/benchmarks/bench_friction.py  [--quick]  [--smoke]

--smoke: 5 velocities, a coarse reference and one setting per table (seconds, for CI).
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one thread: CPU times comparable between runs
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
from _bench import SMOKE, stage_result  # noqa: E402

from roughcontact import scene as scenes  # noqa: E402
from roughcontact.accuracy import with_settings  # noqa: E402
from roughcontact.physics import (
    friction as physics_friction,  # noqa: E402
    viscoelastic as ve,  # noqa: E402
)

REF = (400, 256) if not SMOKE else (20, 16)
PAIRS = [(ppd, n) for ppd in (10, 20, 30, 40, 50, 100) for n in (8, 12, 16, 24, 32, 48)]


def _inputs(ppd: int, modulus_ppd: int = 20):
    """q, C (4 cases, q), omega grid, E', E'' (omega), p, nu from the built-in scene, through the
    psd and modulus stages (their params read from the scene as the engine hands them)."""
    sc = with_settings(scenes.load("friction"), {"numerics.points_per_decade": ppd,
                                                 "numerics.modulus_points_per_decade": modulus_ppd})
    psd = stage_result("psd", sc)
    psd_only = stage_result("psd", sc, solid=None)
    C = np.vstack([psd_only["psd_combined"].values[None, :], psd["psd_combined"].values])  # (4, q)
    mod = stage_result("modulus", sc)
    return (psd["q"].values, C, mod["omega"].values, mod["storage_modulus"].values, mod["loss_modulus"].values,
            sc.get("load.p"), sc.get("material.nu"), sc.get("modulus"))


def run_case(ppd: int, n_phi: int, v: np.ndarray, modulus_ppd: int = 20, repeat: int = 5, chunk: int = 0,
             segment_nodes: int = 12):
    """mu, A/A0 (4 cases, v), best time of ``repeat`` runs (s), number of q nodes."""
    q, C, grid, Ep, Epp, p, nu, _ = _inputs(ppd, modulus_ppd)
    best = np.inf
    chunk = chunk or v.size
    for _ in range(repeat):
        t0 = time.process_time()
        mus, areas = [], []
        for i in range(0, v.size, chunk):
            A, B = physics_friction.angular_integrals(q, v[i:i + chunk], grid, Ep, Epp, n_phi)
            mu, area = physics_friction.friction_kernel(q, C[:, None, :], A[None], B[None], np.asarray(p), nu,
                                          segment_nodes=segment_nodes)
            mus.append(mu)
            areas.append(area)
        best = min(best, time.process_time() - t0)
    return np.concatenate(mus, axis=-1), np.concatenate(areas, axis=-1), best, q.size


def main(argv):
    quick = "--quick" in argv or SMOKE
    v = np.geomspace(1e-9, 1e3, 100 if not SMOKE else 5)
    pairs = PAIRS if not quick else [(10, 16), (20, 24), (50, 32)] if not SMOKE else [(10, 8)]
    repeat = 5 if not SMOKE else 1
    mu_ref, area_ref, t_ref, n_ref = run_case(*REF, v, repeat=1, chunk=5, segment_nodes=24)
    print(f"reference: {REF[0]} points/decade ({n_ref} q nodes), {REF[1]} phi nodes: {t_ref:.2f} s")
    print(f"mu range {mu_ref.min():.3g} .. {mu_ref.max():.3g}; A/A0 range {area_ref.min():.3g} .. {area_ref.max():.3g}")
    print()
    print("| q points/decade | q nodes | phi nodes | CPU time (s) | max rel. error mu | max rel. error A/A0 |")
    print("|---:|---:|---:|---:|---:|---:|")
    rows = []
    for ppd, n in pairs:
        mu, area, t, nq = run_case(ppd, n, v, repeat=repeat)
        e_mu = float(np.max(np.abs(mu / mu_ref - 1)))
        e_a = float(np.max(np.abs(area / area_ref - 1)))
        rows.append((ppd, n, t, e_mu, e_a))
        print(f"| {ppd} | {nq} | {n} | {t:.3f} | {e_mu:.2e} | {e_a:.2e} |", flush=True)
    ok = [r for r in rows if r[3] <= 1e-4 and r[4] <= 1e-4]
    if ok:
        best = min(ok, key=lambda r: r[2])
        print(f"\ncheapest pair with error <= 1e-4 (mu and A/A0): {best[0]} points/decade, {best[1]} phi nodes, "
              f"{best[2]:.3f} s")
    # error left by the number of Gauss-Legendre nodes per q segment of the mu integral
    print("\n| nodes per q segment (40 points/decade, 16 phi nodes) | time (s) | max rel. error mu (vs 48 nodes) |")
    print("|---:|---:|---:|")
    mu48 = run_case(40, 16, v, repeat=1, segment_nodes=48)[0]
    for m in (4, 6, 8, 12, 16) if not SMOKE else (4,):
        mu, _, t, _ = run_case(40, 16, v, repeat=repeat, segment_nodes=m)
        print(f"| {m} | {t:.3f} | {np.max(np.abs(mu / mu48 - 1)):.2e} |", flush=True)
    # error left by the modulus grid, at the reference q/phi resolution, against the analytic box
    print("\n| modulus points/decade | max rel. error of E' | of E'' | of mu (vs 80/decade) |")
    print("|---:|---:|---:|---:|")
    mu80 = run_case(100, 48, v, modulus_ppd=80, repeat=1)[0] if not quick else None
    for mppd in (10, 20, 40) if not SMOKE else (10,):
        q, C, grid, Ep, Epp, p, nu, spec = _inputs(50, mppd)
        w = np.geomspace(grid[0], grid[-1], 20001)
        aT = 10.0 ** ve.wlf_log10_shift(spec["T"], spec["T_ref"], spec["C1"], spec["C2"])
        ea, eb = ve.box_spectrum_modulus(w * aT, spec["E0"], spec["E_inf"], spec["tau1"], spec["tau2"])
        a, b = ve.modulus_at(w, grid, Ep, Epp)
        e_mu = "-" if quick else f"{np.max(np.abs(run_case(100, 48, v, modulus_ppd=mppd, repeat=1)[0] / mu80 - 1)):.2e}"
        print(f"| {mppd} | {np.max(np.abs(a / ea - 1)):.2e} | {np.max(np.abs(b / eb - 1)):.2e} | {e_mu} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
