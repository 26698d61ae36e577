"""Cost of a DMA master curve against the rows of the file: 20 sweeps of 0.1-100 Hz logged at
n points each (1e3 to 1e6 rows in all), read by the dma reader and fitted by the modulus stage's
dma source (sweeps longer than bins_per_decade per decade are averaged in bins first).

    python tests/benchmarks/bench_mastercurve_rows.py [--smoke]

Prints seconds for reading and for fitting, and their ratio to the smallest file; asserts nothing.
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from _bench import SMOKE

from roughcontact.physics import viscoelastic as ve
from roughcontact.readers import READERS
from roughcontact.stage import REQUIRED
from roughcontact.stages.shared.mastercurve import DMA_PARAMS, master_curve

TAU = np.logspace(-8, 6, 43)
STRENGTH = 2e9 / 43 * 2.5 * np.exp(-0.5 * ((np.log10(TAU) + 1) / 3.0) ** 2)
#: the dma source's keys at their declared defaults (a key added later cannot break the benchmark), and ours
SPEC = {**{p.name: p.default for p in DMA_PARAMS if p.default is not REQUIRED},
        "T_ref": 273.15, "fit": "overlap", "shift_on": "moduli", "no_overlap": "warn", "C2": 51.6}


def write(path: Path, per_sweep: int) -> None:
    rng = np.random.default_rng(0)
    temps = np.arange(-30.0, 70.0, 5.0)
    f = np.logspace(-1, 2, per_sweep)
    with path.open("w") as out:
        out.write("# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]\n")
        for t in temps:
            aT = 10.0 ** ve.wlf_log10_shift(t + 273.15, 273.15, 10.0, 60.0)
            Ep, Epp = ve.prony_modulus(2 * np.pi * f * aT, 5e6, STRENGTH, TAU)
            noise = 1 + 0.01 * rng.standard_normal((2, f.size))
            block = np.column_stack([np.full(f.size, t), f, Ep * noise[0] / 1e6, Epp * noise[1] / 1e6])
            np.savetxt(out, block, fmt="%.6g")


def main() -> None:
    sizes = (50, 500) if SMOKE else (50, 500, 5000, 50000)
    print(f"{'rows':>9} {'read (s)':>9} {'fit (s)':>8} {'read/first':>10} {'fit/first':>9} {'C1':>7} {'C2 (K)':>7}")
    first = None
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            path = Path(tmp) / f"dma_{n}.txt"
            write(path, n)
            start = time.perf_counter()
            data = READERS["dma"](path)
            read = time.perf_counter() - start
            start = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                curve = master_curve(SPEC, data)
            fit = time.perf_counter() - start
            first = first or (read, fit)
            print(f"{20 * n:9d} {read:9.2f} {fit:8.2f} {read / first[0]:10.1f} {fit / first[1]:9.1f} "
                  f"{curve.C1:7.3f} {curve.C2:7.2f}")


if __name__ == "__main__":
    main()
