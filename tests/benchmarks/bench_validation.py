"""Benchmark of the validation's BEM tasks: the time of one solve at 512^2 and 1024^2 at three
reduced pressures, and the speedup of a small validation scene from one to two workers of a
dask.distributed LocalCluster (the same tasks, the same results).

Run: python tests/benchmarks/bench_validation.py [--skip-solves] [--skip-cluster] [--smoke]
(needs tamaas, distributed). --smoke: one 64^2 solve per pressure and a 32^2 scene on the cluster.

Wall and CPU seconds are both printed: on a shared machine the wall time of a solve is its CPU
time divided by the share of a core it got.
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _bench import SMOKE

from roughcontact import engine, scene as scenes
from roughcontact.physics.validation import bem_task

KW = dict(qL=2e8, rolloffs=(4.0, 2.0), hrms=(1e-9, 0.5e-9), E_star=77.2e9 / (1 - 0.42**2))
SCENE = {
    "name": "bench_validation",
    "interface": {"eta": [0.0, -1.0]},
    "material": {"E": "77.2 GPa", "nu": 0.42},
    "validation": {"hurst": [0.5, 0.8], "bandwidth": [16], "reduced_pressure": {"from": 0.003, "to": 0.5, "num": 6},
                   "pixels_per_wavelength": [8], "realizations": 2, "max_grid": 256},
    "outputs": {"variables": ["validation_bem_contact_area_ratio"]},
}
if SMOKE:
    SCENE["validation"].update(hurst=[0.8], realizations=1, max_grid=32, pixels_per_wavelength=[2])


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def solves(grids=(512, 1024), zeta=64) -> None:
    print(f"{'grid':>6} {'p/(E* g)':>9} {'A/A0':>7} {'wall (s)':>9} {'cpu (s)':>8}")
    for n in grids:
        for p in (0.01, 0.1, 0.5):  # one cold solve each
            t0, c0 = time.perf_counter(), _cpu()
            res = bem_task(0.5, zeta, 0.0, 0, n / zeta, np.array([p]), **KW)
            print(f"{n:>6} {p:>9.2g} {res[0, 0]:>7.4f} {time.perf_counter() - t0:>9.2f} {_cpu() - c0:>8.2f}",
                  flush=True)


def cluster() -> None:
    from distributed import LocalCluster

    walls = {}
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as c:
                t0 = time.perf_counter()
                res = engine.run(scenes.from_dict(SCENE), Path(tmp) / str(workers), report=engine.Reporter(None),
                                 scheduler=c.scheduler_address)["base"]["validation_bem"]
                walls[workers] = time.perf_counter() - t0
            tasks = res["validation_bem_contact_area_ratio"].size // 6
            print(f"{workers} worker(s): {walls[workers]:.1f} s for {tasks} "
                  f"tasks ({'128^2' if not SMOKE else '32^2'}, 6 loads each)", flush=True)
    print(f"speedup 1 -> 2 workers: {walls[1] / walls[2]:.2f}")


if __name__ == "__main__":
    if "--skip-solves" not in sys.argv:
        solves() if not SMOKE else solves((64,), zeta=16)
    if "--skip-cluster" not in sys.argv:
        cluster()
