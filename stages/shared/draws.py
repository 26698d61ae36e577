"""Spectrum draws for the uncertainty bands (``[bands]``): ``draws = N`` becomes the sweep
dimension draw = 0..N that every downstream stage carries."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import Param, Section, UserError, register_section


def _check_bands(values: dict, key: str) -> None:
    """``draws = N`` becomes the sweep dimension draw = 0..N (0: the measured spectrum)."""
    n = values.get("draws")
    if isinstance(n, np.ndarray) or float(n) != int(n):
        raise UserError(f"expected a whole number of draws, got {n!r}", key=f"{key}.draws")
    values["draws"] = np.arange(int(n) + 1, dtype=float) if int(n) > 0 else 0.0


register_section(
    Section(
        "bands",
        (
            Param("draws", "sweep", "", default=0, lo=0, hi=100000, dim="draw",
                  doc="spectra drawn within the measured PSDs' statistical band (0: none); a sweep dimension "
                      "'draw' = 0..N that every downstream stage carries (0 = the measured spectrum)"),
            Param("level", "quantity", "", default=0.9, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
                  doc="probability content of the bands (quantiles (1 - level)/2, 0.5, (1 + level)/2 of the draws)"),
            Param("seed", "int", default=0, lo=0,
                  doc="random seed of the draws (draw d uses the stream (seed, surface, d))"),
        ),
        doc="uncertainty bands: predictions from spectra drawn within the measured spectra's statistical band",
        check=_check_bands,
    )
)
