"""Benchmark: result files with and without compression, in one run.

    python tests/benchmarks/bench_compression.py [--scene large_sweep] [--repeat 1] [--smoke]

Runs the scene (every stage forced) with the compression of roughcontact.cf on, and with it
off (what the store wrote before), alternately, and prints for each the total size of the
result files and the best wall time of the run. The ratio is what compression costs and saves
on this machine, under its current load. --smoke: the default scene instead (seconds, for CI).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

from roughcontact import cf, engine, scene as scenes


def _run(sc, out: Path) -> tuple[float, int]:
    t0 = time.perf_counter()
    engine.run(sc, out, force=("all",), report=engine.Reporter(None))
    took = time.perf_counter() - t0
    size = sum(p.stat().st_size for p in out.rglob("*.nc") if ".results" not in p.parts)
    return took, size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="large_sweep")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--smoke", action="store_true", help="the default scene (seconds)")
    args = ap.parse_args()
    if args.smoke:
        args.scene = "default"
    sc = scenes.load(args.scene)
    threshold = cf.COMPRESS_BYTES
    best = {"compressed": (math.inf, 0), "uncompressed": (math.inf, 0)}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeat):
            for label, limit in (("uncompressed", math.inf), ("compressed", threshold)):
                cf.COMPRESS_BYTES = limit
                took, size = _run(sc, Path(tmp) / f"{label}{i}")
                best[label] = (min(best[label][0], took), size)
    cf.COMPRESS_BYTES = threshold
    print(f"scene {args.scene}: all stages forced, best of {args.repeat}")
    for label, (took, size) in best.items():
        print(f"{label:13s} {size / 2**20:9.1f} MiB  {took:7.2f} s")
    (tc, sc_), (tu, su) = best["compressed"], best["uncompressed"]
    print(f"compressed / uncompressed: size {sc_ / su:.2f}, time {tc / tu:.2f}")


if __name__ == "__main__":
    main()
