"""Benchmark: how long the command line takes when there is nothing (or everything) to compute,
as ratios to ``python -c "import numpy, xarray"`` (the import floor) measured in the same run.

    python tests/benchmarks/bench_startup.py [--repeat 9] [--scene default] [--baseline REV] [--smoke]

Each command runs as a fresh process, the commands interleaved, ``--repeat`` times; each time is
divided by the floor's time of the same round and the median of these ratios is the number to
read (the shared machine's load moves a round's commands alike; the median times are shown too).
Targets: ``run`` and ``plan`` with every result fresh at most 1.5x the floor (issue 13); the cold
scene (a fresh output folder, the parsed scene cached) at most 2x (issue 27); ``--help`` well
below the floor (it loads no science stack). "cold, new scene" turns the parsed-scene cache off
(ROUGHCONTACT_CACHE=off), so that the scene is parsed and the unit registry built.

"xarray in use" is the floor of any program that builds one labelled array here: importing numpy
and xarray, then one DataArray with an index coordinate, which makes xarray import dask.array (and
with it scipy.sparse, scipy.fft, scipy.special) to ask whether the data is a dask array, and pint
to ask whether it is a pint quantity, when these are installed. The cold scene's ratio to it is
printed too: what the run itself costs above what xarray costs any user.

``--baseline REV`` adds, interleaved with the others, the cold scene and ``--help`` of the git
revision REV of this repository (its files exported to a temporary folder and imported from
there, with this interpreter and these libraries): before and after in one run.
--smoke: one repeat (seconds, for CI).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FLOOR = "python -c 'import numpy, xarray'"
COLD = "roughcontact run (cold)"
IN_USE = "xarray in use (one DataArray with an index)"
IN_USE_CODE = "import numpy, xarray; xarray.DataArray(numpy.zeros(2), dims='x', coords={'x': [0.0, 1.0]})"


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


def _baseline(rev: str, tmp: Path) -> dict:
    """The environment that imports roughcontact from revision ``rev`` (exported with git archive,
    laid out as the installed package: pipeline/ is roughcontact, physics/ and stages/ inside it)."""
    src = tmp / "baseline-src"
    src.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    package = tmp / "baseline" / "roughcontact"
    package.mkdir(parents=True)
    for entry in (src / "pipeline").iterdir():
        (package / entry.name).symlink_to(entry)
    for sub in ("physics", "stages"):
        (package / sub).symlink_to(src / sub)
    return dict(os.environ, PYTHONPATH=str(tmp / "baseline"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--scene", default="default")
    ap.add_argument("--baseline", metavar="REV", help="also time the cold scene and --help of git revision REV")
    ap.add_argument("--smoke", action="store_true", help="one repeat (seconds)")
    args = ap.parse_args()
    if args.smoke:
        args.repeat = 1
    cli = _cli()
    off = dict(os.environ, ROUGHCONTACT_CACHE="off")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        fresh = tmp / "fresh"
        subprocess.run([*cli, "run", args.scene, "--outdir", str(fresh), "--quiet"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cases = {
            FLOOR: lambda i: _timed([sys.executable, "-c", "import numpy, xarray"]),
            IN_USE: lambda i: _timed([sys.executable, "-c", IN_USE_CODE]),
            "roughcontact --help": lambda i: _timed([*cli, "--help"]),
            "roughcontact run (all fresh)": lambda i: _timed(
                [*cli, "run", args.scene, "--outdir", str(fresh), "--quiet"]),
            "roughcontact plan (all fresh)": lambda i: _timed([*cli, "plan", args.scene, "--outdir", str(fresh)]),
            COLD: lambda i: _timed([*cli, "run", args.scene, "--outdir", f"{tmp}/cold{i}", "--quiet"]),
            "roughcontact run (cold, new scene)": lambda i: _timed(
                [*cli, "run", args.scene, "--outdir", f"{tmp}/new{i}", "--quiet"], env=off),
        }
        if args.baseline:
            env = _baseline(args.baseline, tmp)
            old = [sys.executable, "-m", "roughcontact.cli"]
            subprocess.run([*old, "run", args.scene, "--outdir", f"{tmp}/warm-up", "--quiet"], env=env, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # its .pyc and parsed scene
            cases[f"roughcontact --help ({args.baseline})"] = lambda i: _timed([*old, "--help"], env=env)
            cases[f"{COLD} ({args.baseline})"] = lambda i: _timed(
                [*old, "run", args.scene, "--outdir", f"{tmp}/before{i}", "--quiet"], env=env)
        times = {name: [] for name in cases}
        for i in range(args.repeat):
            for name, case in cases.items():
                times[name].append(case(i))
            for pattern in ("cold*", "new*", "before*"):
                for out in tmp.glob(pattern):
                    shutil.rmtree(out)
    median = {name: statistics.median(t) for name, t in times.items()}
    ratio = {name: statistics.median(a / b for a, b in zip(t, times[FLOOR], strict=True)) for name, t in times.items()}
    print(f"scene {args.scene}, {args.repeat} interleaved rounds: median time, median of the rounds' ratios to the "
          "import floor")
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        print("note: PYTHONDONTWRITEBYTECODE is set: roughcontact's modules are compiled at every start "
              "(an install compiles them once)")
    targets = {"roughcontact run (all fresh)": 1.5, "roughcontact plan (all fresh)": 1.5, COLD: 2.0}
    for name, seconds in median.items():
        target = f"  (target <= {targets[name]:g}x)" if name in targets else ""
        per_round = ", ".join(f"{t / f:.2f}" for t, f in zip(times[name], times[FLOOR], strict=True))
        print(f"{name:48s} {seconds:6.3f} s  {ratio[name]:5.2f}x{target}  (per round: {per_round})")
    above = statistics.median(a / b for a, b in zip(times[COLD], times[IN_USE], strict=True))
    print(f"{COLD} / {IN_USE}: {above:.2f}x (median of the rounds' ratios)")


if __name__ == "__main__":
    main()
