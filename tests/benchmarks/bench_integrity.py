"""What the checksums of stored results cost, on the built-in large_sweep scene (1e8 points,
807 MB contact.nc): one cold run, with the time spent hashing blocks (in a background thread),
the time the writer waited for that hashing (the cost on the critical path), and the time to
verify each file on reuse (read back and hash). Run it alone on the machine:

    python tests/benchmarks/bench_integrity.py [OUTDIR] [--smoke]

--smoke: the default scene instead (seconds, for CI).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from _bench import SMOKE, positional

from roughcontact import engine, integrity, scene as scenes

SCENE = "large_sweep" if not SMOKE else "default"


def main(outdir: Path) -> None:
    hashing = {"seconds": 0.0, "bytes": 0}
    real_digest = integrity.block_digest

    def timed(name, values, start):
        t0 = time.perf_counter()
        out = real_digest(name, values, start)
        hashing["seconds"] += time.perf_counter() - t0
        hashing["bytes"] += getattr(values, "nbytes", 0)
        return out

    waited = []
    real_known = integrity.Checksums.known

    def known(self):
        out = real_known(self)
        waited.append(self.waited)
        return out

    integrity.block_digest, integrity.Checksums.known = timed, known
    t0 = time.perf_counter()
    engine.run(scenes.load(SCENE), outdir, report=engine.Reporter(None), force="all")
    run = time.perf_counter() - t0
    integrity.block_digest, integrity.Checksums.known = real_digest, real_known
    print(f"{SCENE} cold run: {run:.2f} s")
    print(f"hashing while writing: {hashing['seconds']:.2f} s for {hashing['bytes'] / 1e6:.0f} MB "
          f"({hashing['bytes'] / 1e6 / max(hashing['seconds'], 1e-9):.0f} MB/s, background thread)")
    print(f"writer waited for the hashing: {sum(waited):.2f} s = {sum(waited) / run:.1%} of the run")
    for name in ("psd.nc", "contact.nc"):
        path = outdir / name
        t0 = time.perf_counter()
        ok = integrity.verify(path)
        print(f"verify {name} ({path.stat().st_size / 1e6:.1f} MB): {ok} in {time.perf_counter() - t0:.2f} s")


if __name__ == "__main__":
    args = positional(sys.argv[1:])
    if args:
        main(Path(args[0]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main(Path(tmp))
