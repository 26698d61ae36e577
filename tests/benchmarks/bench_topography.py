"""Benchmark: PSD of a 4096 x 4096 map, and PSD + cross-spectrum of a pair, against
SurfaceTopography's ``power_spectrum_from_area`` on the same map, in one run.

Run: ``python tests/benchmarks/bench_topography.py [n] [--smoke]`` (needs SurfaceTopography; about 1 GB
of RAM at n = 4096). ``--smoke``: n = 128 (seconds, for CI).
Each timing is the best of ``REPEAT`` runs; peak memory is measured per task in a fresh child
process (``ru_maxrss`` minus the child's RSS once the maps are loaded), in map sizes (8 n^2 bytes).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import sys
import time
from pathlib import Path
from queue import Empty

import numpy as np
from _bench import SMOKE, positional  # noqa: E402

REPEAT = 2
_CACHE = f"/tmp/bench_topography_{os.getpid()}_h{{}}.npy"  # one pair per run: two runs may overlap
_L = 1e-4


def _maps(n):
    from roughcontact.scenes.data.synthetic import self_affine, synthesize

    rng = np.random.default_rng(0)
    L = _L
    psd = lambda q: self_affine(q, 0.8, 2 * np.pi / L * 4, 1e-36)  # noqa: E731
    h1 = synthesize(psd, n, n, L, L, rng)
    h2 = 0.8 * h1 + 0.5 * synthesize(psd, n, n, L, L, rng)
    return h1, h2, L


def _task(name, n, queue):
    from roughcontact.physics.estimators import binned_spectra_area, log_bin_edges

    h1, h2, L = np.load(_CACHE.format(1)), np.load(_CACHE.format(2)), _L
    edges = log_bin_edges(2 * np.pi / L, np.pi * n / L, 20)
    if name == "surfacetopography":
        from SurfaceTopography import Topography

        topo = Topography(h1, (L, L), periodic=True, unit="m")
        run = lambda: topo.power_spectrum_from_area(collocation=edges, reliable=False)  # noqa: E731
    elif name == "psd":
        run = lambda: binned_spectra_area(h1, L, L, edges, np.pi * n / L)  # noqa: E731
    elif name == "psd+cross":
        run = lambda: binned_spectra_area(h1, L, L, edges, np.pi * n / L, h2)  # noqa: E731
    else:  # the whole stage path for one non-periodic map: checks, plane detrend, radial Hann window, PSD
        from roughcontact.physics.estimators import binned_spectra_area as spectra
        from roughcontact.readers import Topography
        from roughcontact.stages.shared.maps import prepare_map, process_map

        topo = Topography(Path("bench"), h1, (L, L), False, "m", "bench", "0")
        spec = {"analysis": "area", "hurst": 0.5}

        def run():
            p = process_map(prepare_map("substrate", spec, topo, 0), spec)
            return spectra(p["h"], p["sizes"][0], p["sizes"][1], edges, p["q_max"])
    before = _rss_now()
    best = np.inf
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    result = None
    if name == "surfacetopography":
        result = np.ma.filled(np.ma.asarray(out[1], dtype=float), np.nan) / (2 * np.pi) ** 2
    else:
        result = out["C11"]
    queue.put((name, best, peak - before, result))


def _rss_now():
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def _result_of(process, queue, name):
    """The task's result, or an error as soon as the task's process dies without one (an import
    error in the child would otherwise leave this waiting forever)."""
    while True:
        try:
            return queue.get(timeout=1.0)
        except Empty:
            if not process.is_alive():
                raise SystemExit(f"benchmark task {name!r} died (exit code {process.exitcode})") from None


def main(n=4096):
    h1, h2, _ = _maps(n)
    np.save(_CACHE.format(1), h1)
    np.save(_CACHE.format(2), h2)
    del h1, h2
    ctx = mp.get_context("fork")
    results = {}
    for name in ("surfacetopography", "psd", "psd+cross", "stage (plane+hann+psd)"):
        q = ctx.Queue()
        p = ctx.Process(target=_task, args=(name, n, q))
        p.start()
        results[name] = _result_of(p, q, name)
        p.join()
    for i in (1, 2):
        Path(_CACHE.format(i)).unlink()
    map_bytes = 8 * n * n
    ref = results["surfacetopography"][1]
    print(f"map {n} x {n} (one map = {map_bytes / 2**20:.0f} MiB), best of {REPEAT}")
    print(f"{'task':24s} {'time (s)':>9s} {'ratio to ST':>12s} {'peak extra RSS (map sizes)':>28s}")
    for name, best, mem, _ in results.values():
        print(f"{name:24s} {best:9.2f} {best / ref:12.2f} {mem / map_bytes:28.2f}")
    from roughcontact.physics.estimators import log_bin_edges

    edges = log_bin_edges(2 * np.pi / _L, np.pi * n / _L, 20)
    a, b = results["psd"][3], results["surfacetopography"][3]
    # ST also averages the corner modes beyond the Nyquist circle; compare the bins inside it
    ok = np.isfinite(a) & np.isfinite(b) & (edges[1:] <= np.pi * n / _L)
    print(f"max relative difference of the binned PSD vs SurfaceTopography / (2 pi)^2: "
          f"{np.max(np.abs(a[ok] / b[ok] - 1)):.2e} over {ok.sum()} bins")


if __name__ == "__main__":
    args = positional(sys.argv[1:])
    main(int(args[0]) if args else 4096 if not SMOKE else 128)
