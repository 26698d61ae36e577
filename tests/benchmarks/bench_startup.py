"""Benchmark: how long the command line takes when there is nothing (or everything) to compute,
as ratios to ``python -c "import numpy, xarray"`` measured in the same run.

    python tests/benchmarks/bench_startup.py [--repeat 7] [--scene default] [--smoke]

Each command runs as a fresh process, the commands interleaved, ``--repeat`` times; the best
time of each is kept (the machine's noise only ever adds). Targets (issue 13): ``run`` and
``plan`` with every result fresh at most 1.5x the baseline; the cold scene (nothing stored) at
most 3x. "cold" keeps the parsed-scene cache (an unchanged scene); "cold, new scene" turns it
off (ROUGHCONTACT_CACHE=off), so that the scene is parsed and the unit registry built.
--smoke: one repeat (seconds, for CI).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _cli() -> list[str]:
    script = Path(sys.executable).with_name("roughcontact")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "roughcontact.cli"]


def _timed(cmd: list[str], env=None, expect=(0,)) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True)
    took = time.perf_counter() - t0
    if done.returncode not in expect:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr[-2000:]}")
    return took


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--scene", default="default")
    ap.add_argument("--smoke", action="store_true", help="one repeat (seconds)")
    args = ap.parse_args()
    if args.smoke:
        args.repeat = 1
    cli = _cli()
    off = dict(os.environ, ROUGHCONTACT_CACHE="off")
    with tempfile.TemporaryDirectory() as tmp:
        fresh = Path(tmp) / "fresh"
        subprocess.run([*cli, "run", args.scene, "--outdir", str(fresh), "--quiet"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cases = {
            "python -c 'import numpy, xarray'": lambda i: _timed([sys.executable, "-c", "import numpy, xarray"]),
            "roughcontact run (all fresh)": lambda i: _timed(
                [*cli, "run", args.scene, "--outdir", str(fresh), "--quiet"]),
            "roughcontact plan (all fresh)": lambda i: _timed([*cli, "plan", args.scene, "--outdir", str(fresh)]),
            "roughcontact run (cold)": lambda i: _timed(
                [*cli, "run", args.scene, "--outdir", f"{tmp}/cold{i}", "--quiet"]),
            "roughcontact run (cold, new scene)": lambda i: _timed(
                [*cli, "run", args.scene, "--outdir", f"{tmp}/new{i}", "--quiet"], env=off),
        }
        best = {name: float("inf") for name in cases}
        for i in range(args.repeat):
            for name, case in cases.items():
                best[name] = min(best[name], case(i))
            for folder in Path(tmp).glob("cold*"):
                shutil.rmtree(folder)
            for folder in Path(tmp).glob("new*"):
                shutil.rmtree(folder)
    base = best["python -c 'import numpy, xarray'"]
    print(f"scene {args.scene}, best of {args.repeat} runs each (interleaved)")
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        print("note: PYTHONDONTWRITEBYTECODE is set: roughcontact's modules are compiled at every start "
              "(an install compiles them once)")
    targets = {"roughcontact run (all fresh)": 1.5, "roughcontact plan (all fresh)": 1.5,
               "roughcontact run (cold)": 3.0}
    for name, seconds in best.items():
        target = f"  (target <= {targets[name]:g}x)" if name in targets else ""
        print(f"{name:38s} {seconds:6.3f} s  {seconds / base:5.2f}x{target}")


if __name__ == "__main__":
    main()
