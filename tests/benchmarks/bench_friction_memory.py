"""Benchmark: the friction kernels' memory traffic, 100 velocities x 4 cases (the built-in
``friction`` scene at its default numerics), alone and beside other allocations.

    python tests/benchmarks/bench_friction_memory.py [--rounds 5] [--baseline REV] [--smoke]

One call = the friction stage's two kernels (``angular_integrals`` over 100 v, then
``friction_kernel`` over 4 cases x 100 v); the PSD and the modulus are computed once, not timed.
Per call the script measures, for the thread that computes (``resource.RUSAGE_THREAD``): wall
time, CPU time in user and in system mode, and minor page faults (``ru_minflt``: memory the
process got fresh from the OS, zeroed page by page). Three conditions:

* ``alone``: nothing else in the process;
* ``beside``: another thread allocates, fills and frees arrays of 0.1-4 MB in a loop (as other
  stages' blocks do on the threads scheduler);
* ``dask worker``: glibc told to give freed memory back to the OS early
  (``MALLOC_TRIM_THRESHOLD_=65536``), as a dask.distributed nanny sets it for its workers.

Each (version, condition) runs in a fresh process, 7 calls after a warm-up, and reports medians;
the cases are interleaved round by round (a different one first each round) and the tables give
the medians over rounds. ``--baseline REV`` adds git revision REV of this repository (exported and
imported from a temporary folder, as bench_startup.py does): before and after in one run. On a
shared machine the wall times follow the load; CPU times and page faults barely do.

--smoke: one call alone, no baseline (seconds; the numbers mean nothing).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _bench import SMOKE

HERE = Path(__file__).resolve()
CONDITIONS = {"alone": {}, "beside": {}, "dask worker": {"MALLOC_TRIM_THRESHOLD_": "65536"}}


def child(condition: str, calls: int) -> None:
    """Measure ``calls`` calls in this process; print the medians as JSON."""
    import resource
    import threading
    import time

    import numpy as np
    from bench_friction import _inputs

    from roughcontact.physics.friction import angular_integrals, friction_kernel

    q, C, grid, Ep, Epp, p, nu, _ = _inputs(50)
    v = np.geomspace(1e-9, 1e3, 100)

    def kernels():
        A, B = angular_integrals(q, v, grid, Ep, Epp, 16)
        return friction_kernel(q, C[:, None, :], A[None], B[None], np.asarray(p), nu)

    stop = threading.Event()

    def allocate():  # another stage's blocks: arrays of 0.1-4 MB allocated, filled, freed
        rng = np.random.default_rng(0)
        while not stop.is_set():
            block = np.empty(int(rng.integers(12_500, 500_000)))
            block.fill(1.0)
            del block

    if condition == "beside":
        threading.Thread(target=allocate, daemon=True).start()
    kernels()  # warm-up: imports, first allocations
    rows = []
    for _ in range(calls):
        r0, t0 = resource.getrusage(resource.RUSAGE_THREAD), time.perf_counter()
        kernels()
        t, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_THREAD)
        rows.append({"wall": t, "user": r1.ru_utime - r0.ru_utime, "system": r1.ru_stime - r0.ru_stime,
                     "faults": r1.ru_minflt - r0.ru_minflt})
    stop.set()
    print(json.dumps({k: statistics.median(r[k] for r in rows) for k in rows[0]}))


def _measure(condition: str, env: dict, calls: int) -> dict:
    cmd = [sys.executable, str(HERE), "--child", condition, str(calls)]
    done = subprocess.run(cmd, env={**env, **CONDITIONS[condition]}, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5, help="rounds of interleaved measurements")
    ap.add_argument("--baseline", metavar="REV", help="also measure git revision REV (before/after in one run)")
    ap.add_argument("--smoke", action="store_true", help="one call alone")
    ap.add_argument("--child", nargs=2, metavar=("CONDITION", "CALLS"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.child[0], int(args.child[1]))
    rounds, calls = (1, 1) if SMOKE else (args.rounds, 7)
    conditions = ["alone"] if SMOKE else list(CONDITIONS)
    with tempfile.TemporaryDirectory() as tmp:
        versions = {"now": dict(os.environ)}
        if args.baseline and not SMOKE:
            from bench_startup import _baseline

            versions[args.baseline] = _baseline(args.baseline, Path(tmp))
        cases = [(v, c) for v in versions for c in conditions]
        got = {case: [] for case in cases}
        for r in range(rounds):
            for version, condition in cases[r % len(cases):] + cases[:r % len(cases)]:
                m = _measure(condition, versions[version], calls)
                got[(version, condition)].append(m)
                print(f"round {r + 1} (load {os.getloadavg()[0]:.1f}) {version:>8} {condition:>11}: wall "
                      f"{m['wall'] * 1e3:6.1f} ms, user {m['user'] * 1e3:5.1f} ms, system {m['system'] * 1e3:5.1f} ms, "
                      f"{m['faults']:6.0f} page faults", flush=True)
    print("\n| version | condition | wall (ms) | CPU user (ms) | CPU system (ms) | page faults | wall / now alone |")
    print("|---|---|---:|---:|---:|---:|---:|")
    ref = statistics.median(m["wall"] for m in got[("now", "alone")])
    for (version, condition), runs in got.items():
        med = {k: statistics.median(m[k] for m in runs) for k in runs[0]}
        print(f"| {version} | {condition} | {med['wall'] * 1e3:.1f} | {med['user'] * 1e3:.1f} | "
              f"{med['system'] * 1e3:.1f} | {med['faults']:.0f} | {med['wall'] / ref:.2f} |")
    print(f"(medians over {rounds} rounds of the per-process medians of {calls} calls; {os.cpu_count()} cores; "
          f"load average now {os.getloadavg()[0]:.1f})")


if __name__ == "__main__":
    main()
