"""Benchmark: speed-up of the validation scene's BEM tasks on a dask.distributed LocalCluster of
1, 2 and 4 worker processes (one thread each).

    python tests/benchmarks/bench_cluster.py [--repeat 3] [--workers 1,2,4] [--baseline REV] [--smoke]

The built-in ``validation`` scene cut to a size that runs in a minute or two on one worker:
H 0.5 and 0.8, bandwidth 16, eta 0 and -1, 2 realizations, 64^2 and 128^2 grids (4 and 8 pixels
per wavelength), 10 loads: 16 BEM tasks of two sizes, and the deviation table. Each run times
``engine.run`` into an empty folder: the whole run and, inside it, the BEM tasks alone (first
submitted to last received). One process per version of roughcontact starts, for each run, a
LocalCluster of that many workers alone on the machine, and has every worker import roughcontact
(not timed; the cluster is closed after the run); the runs are interleaved round by round, a
different worker count first each round (the machine is shared: a round's runs see about the same
load), and the speed-up is the median over rounds of t(1 worker) / t(n workers) of the same round.
``--keep-clusters`` starts the clusters of all worker counts first and keeps them for every run,
as this benchmark did before: their idle workers, nannies and schedulers then take CPU from the
two cores that the measured run needs (1.69-1.79x against 1.88-1.90x alone, docs/scale-out.md). ``--baseline REV``
then does the same with git revision REV of this repository (exported and imported from a
temporary folder, as bench_startup.py does): before and after in one run, the versions one after
the other. The load average is printed with every run.

On a shared machine the wall times follow the other jobs' load, which changes within a minute. So
the workers' CPU seconds are measured too (each worker's, over each run): their total says how much
work the tasks were (the same for any number of workers, unless work is duplicated), and the
largest says how the tasks were shared out. Since a task computes in one thread, the total CPU of
one worker over the makespan the n workers' CPU seconds allow on cores of their own estimates what
an otherwise idle machine would show (up to the scheduling gaps, which the wall times include): at
best with the work shared out evenly, and with the split observed, which on a loaded machine also
follows how much CPU each worker got (a worker that got less finished fewer tasks).

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


def child(counts: list[int], repeat: int, outdir: str, smoke: bool, keep: bool = False) -> None:
    """The measurements of one version (run in its own process): ``repeat`` rounds of one run on a
    LocalCluster of each worker count, the cases interleaved (a different one first each round);
    one JSON line per run. Each run has its cluster to itself, started and warmed up before it
    (not timed) and closed after it; ``keep``: the clusters of all counts started first and kept."""
    from contextlib import ExitStack

    from distributed import Client, LocalCluster

    import roughcontact.scheduling as scheduling
    from roughcontact import engine, scene as scenes

    def started(stack: ExitStack, workers: int):
        cluster = stack.enter_context(LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                   dashboard_address=None))
        client = stack.enter_context(Client(cluster, set_as_default=False))
        client.run(scheduling._worker_version)  # every worker imports roughcontact and its stages now
        return cluster, client

    marks = {}
    real = scheduling._as_completed

    def timed(*args, **kwargs):  # the BEM tasks: first submitted to last received
        marks["start"] = time.perf_counter()
        yield from real(*args, **kwargs)
        marks["end"] = time.perf_counter()

    scheduling._as_completed = timed
    sc = scenes.from_dict(scene_dict(smoke))
    with ExitStack() as kept:
        clusters = {w: started(kept, w) for w in counts} if keep else {}
        for r in range(repeat):
            for w in counts[r % len(counts):] + counts[:r % len(counts)]:
                with ExitStack() as own:
                    cluster, client = clusters[w] if keep else started(own, w)
                    load = os.getloadavg()[0]
                    cpu0 = client.run(_cpu)
                    t0 = time.perf_counter()
                    res = engine.run(sc, Path(outdir) / f"{w}-{r}", report=engine.Reporter(None),
                                     scheduler=cluster.scheduler_address)
                    wall = time.perf_counter() - t0
                    cpu = [c - cpu0[k] for k, c in client.run(_cpu).items()]
                area = res["base"]["validation_bem"]["validation_bem_contact_area_ratio"]
                print(json.dumps({"round": r, "workers": w, "run": wall, "tasks": marks["end"] - marks["start"],
                                  "solved": int(area.notnull().sum()), "load": load, "cpu": cpu}), flush=True)


def _cpu() -> float:
    """CPU seconds of this (worker) process so far."""
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def dedicated(cpu: list[float], cores: int) -> float:
    """The makespan the workers' CPU seconds ``cpu`` allow on ``cores`` cores of their own: the
    busiest worker's, or the work shared out over the cores if there are fewer cores than workers."""
    return max(max(cpu), sum(cpu) / min(cores, len(cpu)))


def _measure(version: str, counts: list[int], repeat: int, outdir: Path, env: dict, smoke: bool, keep: bool) -> dict:
    """{workers: [run of each round]} of one version, printed as they come."""
    cmd = [sys.executable, str(HERE), "--child", ",".join(map(str, counts)), str(repeat), str(outdir)]
    cmd += (["--smoke"] if smoke else []) + (["--keep-clusters"] if keep else [])
    runs: dict[int, list] = {w: [] for w in counts}
    with subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, text=True) as proc:
        for line in proc.stdout:
            m = json.loads(line)
            runs[m["workers"]].append(m)
            print(f"{version:>8} round {m['round'] + 1} (load {m['load']:.1f}) {m['workers']} worker(s): run "
                  f"{m['run']:6.1f} s, BEM tasks {m['tasks']:6.1f} s ({m['solved']} values); CPU s per worker "
                  f"{' '.join(f'{c:.1f}' for c in m['cpu'])}", flush=True)
    if proc.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed")
    return runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="rounds of interleaved runs")
    ap.add_argument("--workers", default="1,2,4", help="worker counts (processes, one thread each)")
    ap.add_argument("--baseline", metavar="REV", help="also run git revision REV (before/after in one run)")
    ap.add_argument("--baseline-repeat", type=int, default=None, help="rounds for REV (default --repeat)")
    ap.add_argument("--smoke", action="store_true", help="one run of 2 workers on a tiny scene")
    ap.add_argument("--keep-clusters", action="store_true",
                    help="start the clusters of all worker counts first and keep them (as before: sharing the cores)")
    ap.add_argument("--child", nargs=3, metavar=("WORKERS", "REPEAT", "OUTDIR"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child([int(w) for w in args.child[0].split(",")], int(args.child[1]), args.child[2], SMOKE,
                     args.keep_clusters)
    counts = [2] if SMOKE else sorted({int(w) for w in args.workers.split(",")} | {1})
    repeat = 1 if SMOKE else args.repeat
    with tempfile.TemporaryDirectory() as tmp:
        versions = {"now": (dict(os.environ), repeat)}
        if args.baseline:
            from bench_startup import _baseline

            versions[args.baseline] = (_baseline(args.baseline, Path(tmp)), args.baseline_repeat or repeat)
        times = {v: _measure(v, counts, n, Path(tmp) / v, env, SMOKE, args.keep_clusters)
                 for v, (env, n) in versions.items()}
    if SMOKE:
        return print("smoke: the 2-worker LocalCluster completed the tiny scene")
    print("\nspeed-up from 1 worker (median over rounds of the same round's ratio):")
    for version, runs in times.items():
        for w in counts[1:]:
            for part in ("tasks", "run"):
                ratios = [a[part] / b[part] for a, b in zip(runs[1], runs[w], strict=True)]
                print(f"  {version:>8} 1 -> {w} workers, {'BEM tasks' if part == 'tasks' else 'whole run':9}: "
                      f"{statistics.median(ratios):.2f}x  (rounds {', '.join(f'{x:.2f}' for x in ratios)})")
    cores = os.cpu_count() or 1
    print(f"\nfrom the workers' CPU seconds (a task computes in one thread): the work, and the speed-up the same runs "
          f"would give on {cores} cores of their own, at best (the work shared out evenly) and with the split "
          f"observed (the busiest worker's share; on a loaded machine it also follows the CPU each worker got)")
    for version, runs in times.items():
        for w in counts:
            total = statistics.median(sum(m["cpu"]) for m in runs[w])
            best = [sum(a["cpu"]) / (sum(b["cpu"]) / min(cores, w)) for a, b in zip(runs[1], runs[w], strict=True)]
            split = [sum(a["cpu"]) / dedicated(b["cpu"], cores) for a, b in zip(runs[1], runs[w], strict=True)]
            print(f"  {version:>8} {w} worker(s): {total:.1f} CPU s in all (median); speed-up from 1 worker on {cores} "
                  f"cores of their own: at best {statistics.median(best):.2f}x, with the observed split "
                  f"{statistics.median(split):.2f}x")
    if args.baseline:
        for w in counts:
            before = statistics.median(m["run"] for m in times[args.baseline][w])
            now = statistics.median(m["run"] for m in times["now"][w])
            print(f"  {args.baseline} / now, {w} worker(s), whole run (medians, not interleaved): {before / now:.2f}x")
    print(f"({os.cpu_count()} cores; load average now {os.getloadavg()[0]:.1f}; from {ROOT})")


if __name__ == "__main__":
    main()
