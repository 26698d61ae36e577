"""Figure of the separation stage: seed Fig. 5 (log10(p/E*) against the mean separation u), at
the magnification the title names (the seed's zeta = 4 when the scene has it, else the largest)."""

from __future__ import annotations

import numpy as np

from .common import (
    at_zeta,
    band_level,
    band_note,
    curve_cases,
    legend_outside,
    line_style,
    line_with_band,
    nominal,
    pick_zeta,
    reduce_dims,
    scope_text,
)


def figure_separation(results):
    """log10(p/E*) against u (seed Fig. 5), one curve per case, with the small-pressure law
    u = u0 ln(beta E*/p) (eqs 58-60) as a black dotted line beside each case's curve, drawn over it."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.6, 4.6), layout="constrained")
    zeta = pick_zeta(results["base"]["separation"])
    notes, level = set(), band_level(results)
    for i, case in enumerate(curve_cases(results, "separation")):
        draws, note = reduce_dims(at_zeta(case.ds, zeta), ("p",), "mean_separation")
        notes |= {note, band_note(results, draws)}
        ds = nominal(draws)
        u = np.atleast_1d(ds["mean_separation"].values)
        p = np.atleast_1d(ds["p"].values) / float(ds["E_star"])
        label = case.label + (" (u = 0: no combined roughness)" if np.all(u == 0) else "")
        line_with_band(ax, np.log10(p), draws["mean_separation"] * 1e9, level, across=True, label=label,
                       **line_style(case, u.size))
        u0, beta = float(ds["separation_u0"]), float(ds["separation_beta"])
        if u0 > 0 and np.isfinite(beta):
            law = u0 * np.log(beta / p)
            keep = law > 0
            # on top of the curves, in a style no case has: it would hide under a dashed (substrate-only) curve
            ax.plot(law[keep] * 1e9, np.log10(p[keep]), color="k", linestyle=(0, (1.5, 2.5)), linewidth=1.0,
                    zorder=3, label="u0 ln(beta E*/p), eqs 58-60" if i == 0 else None)
    ax.set_xlabel("mean separation u (nm)")
    ax.set_ylabel("log10(p / E*)")
    ax.set_xlim(left=-0.03 * ax.get_xlim()[1])
    ax.grid(alpha=0.3)
    extra = "; ".join(sorted(n for n in notes if n))
    ax.set_title(f"Interfacial separation (seed Fig. 5) at\n{scope_text(results, zeta)}"
                 + (f"\n{extra}" if extra else ""), fontsize=10)
    return legend_outside(fig)
