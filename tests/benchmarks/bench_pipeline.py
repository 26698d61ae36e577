"""Benchmark: the default scene cold (nothing stored) and warm (everything reused).

    python tests/benchmarks/bench_pipeline.py [--repeat 3] [--smoke]

Prints both times and their ratio, measured in one run; the warm run must recompute nothing.
--smoke: one repeat (seconds, for CI).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from roughcontact import engine, scene as scenes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scene", default=None, help="scene file or built-in name (default scene)")
    ap.add_argument("--smoke", action="store_true", help="one repeat (seconds)")
    args = ap.parse_args()
    if args.smoke:
        args.repeat = 1
    sc = scenes.load(args.scene)
    cold, warm = [], []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp)
            t0 = time.perf_counter()
            engine.run(sc, out, report=engine.Reporter(None))
            cold.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            engine.run(sc, out, report=engine.Reporter(None))
            warm.append(time.perf_counter() - t0)
            stale = [p.label for p in engine.plan(sc, out) if p.status != "fresh"]
            if stale:
                raise SystemExit(f"warm run left stages stale: {stale}")
    print(f"scene {sc.name}: {len(engine.plan(sc, Path(tempfile.gettempdir()) / 'none'))} stage runs")
    print(f"cold  best {min(cold):.3f} s  (runs: {', '.join(f'{t:.3f}' for t in cold)})")
    print(f"warm  best {min(warm):.3f} s  (runs: {', '.join(f'{t:.3f}' for t in warm)}), everything reused")
    print(f"cold / warm = {min(cold) / min(warm):.1f}")


if __name__ == "__main__":
    main()
