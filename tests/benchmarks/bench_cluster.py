"""Benchmark: speed-up of the validation scene's BEM tasks on a dask.distributed LocalCluster of
1, 2 and 4 worker processes (one thread each).

    python tests/benchmarks/bench_cluster.py [--repeat 3] [--workers 1,2,4] [--baseline REV] [--smoke]

The built-in ``validation`` scene cut to a size that runs in a minute or two on one worker:
H 0.5 and 0.8, bandwidth 16, eta 0 and -1, 2 realizations, 64^2 and 128^2 grids (4 and 8 pixels
per wavelength), 10 loads: 16 BEM tasks of two sizes, and the deviation table. Each measurement
is a fresh process that starts its LocalCluster (not timed), then times ``engine.run`` into an
empty folder: the whole run and, inside it, the BEM tasks alone (first submitted to last
received). The cases are interleaved round by round (the machine is shared: a round's cases see
about the same load) and the speed-up is the median over rounds of t(1 worker) / t(n workers) of
the same round. ``--baseline REV`` adds the same runs of git revision REV of this repository
(exported and imported from a temporary folder, as bench_startup.py does): before and after in one
run. The load average is printed with every round.

--smoke: one run on a 2-worker LocalCluster on a tiny scene (32^2 grids): checks that the cluster
path completes (seconds; the numbers mean nothing).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from _bench import ROOT, SMOKE

HERE = Path(__file__).resolve()
SIZE = {"hurst": [0.5, 0.8], "bandwidth": [16], "pixels_per_wavelength": [4, 8], "realizations": 2, "max_grid": 128}
TINY = {"hurst": [0.8], "bandwidth": [8], "pixels_per_wavelength": [4], "realizations": 2, "max_grid": 32,
        "reduced_pressure": [0.05, 0.3]}


def scene_dict(smoke: bool) -> dict:
    """The built-in validation scene with the benchmark's size."""
    from roughcontact import scene as scenes

    raw = tomllib.loads(scenes.builtin_scenes()["validation"].read_text())
    raw["validation"].update(TINY if smoke else SIZE)
    raw["interface"]["eta"] = [0.0] if smoke else [0.0, -1.0]
    raw["name"] = "bench_cluster"
    return raw


def child(workers: int, outdir: str, smoke: bool) -> None:
    """One measurement (run in its own process): print {"run": s, "tasks": s, "solved": n} as JSON."""
    from distributed import LocalCluster

    import roughcontact.scheduling as scheduling
    from roughcontact import engine, scene as scenes

    marks = {}
    real = scheduling._as_completed

    def timed(*args, **kwargs):  # the BEM tasks: first submitted to last received
        marks["start"] = time.perf_counter()
        yield from real(*args, **kwargs)
        marks["end"] = time.perf_counter()

    scheduling._as_completed = timed
    sc = scenes.from_dict(scene_dict(smoke))
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        t0 = time.perf_counter()
        res = engine.run(sc, Path(outdir), report=engine.Reporter(None), scheduler=cluster.scheduler_address)
        wall = time.perf_counter() - t0
    area = res["base"]["validation_bem"]["validation_bem_contact_area_ratio"]
    print(json.dumps({"run": wall, "tasks": marks["end"] - marks["start"], "solved": int(area.notnull().sum())}))


def _measure(workers: int, outdir: Path, env: dict, smoke: bool) -> dict:
    cmd = [sys.executable, str(HERE), "--child", str(workers), str(outdir)] + (["--smoke"] if smoke else [])
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="rounds of interleaved runs")
    ap.add_argument("--workers", default="1,2,4", help="worker counts (processes, one thread each)")
    ap.add_argument("--baseline", metavar="REV", help="also run git revision REV (before/after in one run)")
    ap.add_argument("--smoke", action="store_true", help="one run of 2 workers on a tiny scene")
    ap.add_argument("--child", nargs=2, metavar=("WORKERS", "OUTDIR"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(int(args.child[0]), args.child[1], SMOKE)
    counts = [2] if SMOKE else sorted({int(w) for w in args.workers.split(",")} | {1})
    repeat = 1 if SMOKE else args.repeat
    with tempfile.TemporaryDirectory() as tmp:
        versions = {"now": dict(os.environ)}
        if args.baseline:
            from bench_startup import _baseline

            versions[args.baseline] = _baseline(args.baseline, Path(tmp))
        cases = [(v, w) for v in versions for w in counts]
        times = {case: [] for case in cases}
        for r in range(repeat):
            load = os.getloadavg()[0]
            order = cases[r % len(cases):] + cases[:r % len(cases)]  # a different case first each round
            for version, w in order:
                m = _measure(w, Path(tmp) / f"{version}-{w}-{r}", versions[version], SMOKE)
                times[(version, w)].append(m)
                print(f"round {r + 1} (load {load:.1f}) {version:>8} {w} worker(s): run {m['run']:6.1f} s, "
                      f"BEM tasks {m['tasks']:6.1f} s ({m['solved']} values)", flush=True)
        if SMOKE:
            return print("smoke: the 2-worker LocalCluster completed the tiny scene")
        print("\nspeed-up from 1 worker (median over rounds of the same round's ratio):")
        for version in versions:
            for w in counts[1:]:
                for part in ("tasks", "run"):
                    ratios = [a[part] / b[part] for a, b in zip(times[(version, 1)], times[(version, w)], strict=True)]
                    print(f"  {version:>8} 1 -> {w} workers, {'BEM tasks' if part == 'tasks' else 'whole run':9}: "
                          f"{statistics.median(ratios):.2f}x  (rounds {', '.join(f'{x:.2f}' for x in ratios)})")
        if args.baseline:
            for w in counts:
                ratios = [a["run"] / b["run"] for a, b in zip(times[(args.baseline, w)], times[("now", w)],
                                                              strict=True)]
                print(f"  {args.baseline} / now, {w} worker(s), whole run: {statistics.median(ratios):.2f}x")
    print(f"({os.cpu_count()} cores; load average now {os.getloadavg()[0]:.1f}; from {ROOT})")


if __name__ == "__main__":
    main()
