"""Write the example DMA file of the built-in `dma_flash` scene (seeded: reproducible).

    python -m roughcontact.scenes.data.make_dma

Synthetic frequency sweeps of a tread-like model rubber, not a measurement: a log-normal
relaxation spectrum (relaxed modulus 5 MPa, glassy modulus about 2 GPa, centred at tau = 1 ms at
-20 degC, 3 decades wide) shifted by the WLF law C1 = 12, C2 = 70 K about -20 degC, at 14
temperatures from -35 to 60 degC (5 K steps below 0 degC, 10 K above) and 13 frequencies from 0.1 to
100 Hz, with 1 % multiplicative noise on E' and E''. The instrument's habit of logging the measured
temperature is imitated by +-0.1 K of jitter on each row. `roughcontact run dma_flash` must give
the WLF constants back (C1 = 12, C2 = 70 K within a few per cent).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roughcontact.physics.viscoelastic import prony_modulus, wlf_log10_shift

OUT = Path(__file__).resolve().parent / "dma_example.txt"  # next to this maker
C1, C2, T_REF = 12.0, 70.0, 253.15
TAU = np.logspace(-12, 5, 52)
STRENGTH = 2e9 / 52 * 3.0 * np.exp(-0.5 * ((np.log10(TAU) + 3.0) / 3.0) ** 2)
E_RELAXED = 5e6


def main() -> None:
    rng = np.random.default_rng(20261123)
    temps = np.concatenate([np.arange(-35.0, 1.0, 5.0), np.arange(10.0, 61.0, 10.0)])
    freqs = np.logspace(-1, 2, 13)
    rows = ["# Synthetic DMA frequency sweeps (roughcontact.scenes.data.make_dma): log-normal spectrum, WLF C1 = 12,",
            "# C2 = 70 K about -20 degC, 1 % noise. Columns: temperature, frequency, E', E''.",
            "# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]"]
    for T in temps:
        aT = 10.0 ** wlf_log10_shift(T + 273.15, T_REF, C1, C2)
        Ep, Epp = prony_modulus(2 * np.pi * freqs * aT, E_RELAXED, STRENGTH, TAU)
        Ep = Ep * (1 + 0.01 * rng.standard_normal(freqs.size))
        Epp = Epp * (1 + 0.01 * rng.standard_normal(freqs.size))
        jitter = 0.1 * rng.uniform(-1, 1, freqs.size)
        rows += [f"{T + dT:7.2f}  {f:9.4g}  {a / 1e6:11.6g}  {b / 1e6:11.6g}"
                 for dT, f, a, b in zip(jitter, freqs, Ep, Epp, strict=True)]
    OUT.write_text("\n".join(rows) + "\n")
    print(f"wrote {OUT} ({temps.size} sweeps x {freqs.size} frequencies)")


if __name__ == "__main__":
    main()
