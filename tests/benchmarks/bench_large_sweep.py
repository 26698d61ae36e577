"""Benchmark: the large sweep against the machine's limit, as ratios measured in one run.

    python tests/benchmarks/bench_large_sweep.py [--repeat 3] [--p 1000] [--baseline REV] [--smoke]

The reference ("bare numpy") is what no pipeline can beat on this machine: scipy's erf over as
many float64 points as the sweep has, in blocks of 2**20, each block written as raw bytes to a
file that is fsynced at the end (the store fsyncs every result too). Against it, in the same
round, ``roughcontact run large_sweep`` (every stage computed, a fresh output folder), once
compressed (the default) and once with ``[run] compress = false``. Every case runs in a fresh
process; the time is that of the work (imports not counted), the memory the process's peak RSS.
The cases are interleaved, ``--repeat`` rounds; each round's times are divided by the bare run of
the same round and the median of these ratios is the number to read (the shared machine's load
moves a round's cases alike).

``--baseline REV`` adds both sweeps run by git revision REV of this repository (imported from
its files, as bench_startup.py does): before and after in one run. ``--p`` sets the number of
pressures (1000: 1e8 points). Targets (issue 27): compressed <= 2x the bare run, uncompressed
<= 1.5x, the peak memory independent of the size of the sweep.
--smoke: one round of a 1e5-point sweep (seconds, for CI).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve()


def _scene(p: int, hrms: int, compress: bool) -> dict:
    from roughcontact import scene as scenes

    raw = tomllib.loads(scenes.builtin_scenes()["large_sweep"].read_text())
    raw["load"]["p"]["num"] = p
    raw["substrate"]["hrms"]["num"] = hrms
    raw.setdefault("run", {})["compress"] = compress
    return raw


def _bare(points: int, folder: Path) -> dict:
    """erf over ``points`` values in blocks of 2**20, the raw bytes written and fsynced."""
    import numpy as np
    from scipy.special import erf

    block = 2**20
    t0 = time.perf_counter()
    with open(folder / "bare.bin", "wb") as fh:
        for start in range(0, points, block):
            x = np.linspace(start, start + block, min(block, points - start), endpoint=False) * (4.0 / points)
            fh.write(memoryview(erf(x)).cast("B"))
        os.fsync(fh.fileno())
    return {"time": time.perf_counter() - t0, "bytes": (folder / "bare.bin").stat().st_size}


def _sweep(raw: dict, folder: Path) -> dict:
    from roughcontact import engine, scene as scenes

    sc = scenes.from_dict(raw)
    t0 = time.perf_counter()
    res = engine.run(sc, folder / "out", force=("all",), report=engine.Reporter(None))
    took = time.perf_counter() - t0
    area = res["base"]["contact"]["contact_area_ratio"]
    size = sum(f.stat().st_size for f in (folder / "out").glob("*.nc"))
    return {"time": took, "bytes": size, "points": int(area.size)}


def _case(args) -> None:
    """Run one case in this process and print its time, size and peak memory as JSON."""
    with tempfile.TemporaryDirectory(dir=args.tmp) as tmp:
        if args.case == "bare":
            out = _bare(args.points, Path(tmp))
        else:
            out = _sweep(_scene(args.p, args.hrms, args.case == "compressed"), Path(tmp))
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))


def _spawn(case: str, args, env=None) -> dict:
    cmd = [sys.executable, str(HERE), "--case", case, "--p", str(args.p), "--hrms", str(args.hrms),
           "--points", str(args.points), "--tmp", str(args.tmp)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode:
        raise SystemExit(f"case {case} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--p", type=int, default=1000, help="pressures of the sweep (1000: 1e8 points)")
    ap.add_argument("--hrms", type=int, default=41, help="substrate roughness values of the sweep")
    ap.add_argument("--baseline", metavar="REV", help="also run both sweeps with git revision REV")
    ap.add_argument("--smoke", action="store_true", help="one round of a 1e5-point sweep (seconds)")
    ap.add_argument("--case", help=argparse.SUPPRESS)
    ap.add_argument("--points", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--tmp", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.case:
        return _case(args)
    if args.smoke:
        args.repeat, args.p, args.hrms = 1, 10, 4
    with tempfile.TemporaryDirectory() as folder:
        args.tmp = folder
        cases = {"compressed": None, "uncompressed": None}
        if args.baseline:
            sys.path.insert(0, str(HERE.parent))
            from bench_startup import _baseline

            env = _baseline(args.baseline, Path(folder))
            cases.update({f"compressed ({args.baseline})": env, f"uncompressed ({args.baseline})": env})
        ratios: dict[str, list[float]] = {c: [] for c in cases}
        seen: dict[str, list[dict]] = {c: [] for c in ["bare", *cases]}
        for _ in range(args.repeat):
            for case, env in cases.items():
                seen[case].append(_spawn(case.split()[0], args, env))
                args.points = args.points or seen[case][-1]["points"]  # the bare run: as many points
            seen["bare"].append(_spawn("bare", args))
            for case in cases:
                ratios[case].append(seen[case][-1]["time"] / seen["bare"][-1]["time"])
            print(f"round {len(seen['bare'])}: bare {seen['bare'][-1]['time']:.2f} s, "
                  + ", ".join(f"{c} {ratios[c][-1]:.2f}x" for c in cases), flush=True)
    bare = seen["bare"]
    print(f"large_sweep, {args.points:.3g} points, {args.repeat} interleaved rounds (medians)")
    print(f"{'bare numpy (erf + raw write)':32s} {statistics.median(r['time'] for r in bare):7.2f} s  "
          f"{bare[0]['bytes'] / 2**20:8.1f} MiB  peak {max(r['peak_mb'] for r in bare):6.0f} MB")
    for case in cases:
        runs = seen[case]
        print(f"{case:32s} {statistics.median(r['time'] for r in runs):7.2f} s  {runs[0]['bytes'] / 2**20:8.1f} MiB"
              f"  peak {max(r['peak_mb'] for r in runs):6.0f} MB  ratio to bare {statistics.median(ratios[case]):.2f}x"
              f"  (rounds {', '.join(f'{r:.2f}' for r in ratios[case])})")


if __name__ == "__main__":
    main()
