"""Figure of the separation stage: seed Fig. 5 (log10(p/E*) against the mean separation u)."""

from __future__ import annotations

import numpy as np

from .common import band_level, band_note, curve_cases, line_with_band, nominal

_STYLES = (dict(marker="o", markersize=3, linestyle="-", linewidth=0.8), dict(marker="*", markersize=5),
           dict(linestyle="-", linewidth=2), dict(linestyle=":", linewidth=2), dict(linestyle="--"),
           dict(linestyle="-."))


def figure_separation(results, zeta=4.0):
    """log10(p/E*) against u (seed Fig. 5) at zeta = 4 (nearest available magnification), with
    the small-pressure law u = u0 ln(beta E*/p) (eqs 58-60) as thin dashed lines."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    zeta_used, level, note = None, band_level(results), ""
    for i, ((label, draws), style) in enumerate(zip(curve_cases(results, "separation"), _STYLES)):
        if "zeta" in draws.dims:
            draws = draws.sel(zeta=zeta, method="nearest")
        note = note or band_note(results, draws)
        ds = nominal(draws)
        zeta_used = float(ds["zeta"])
        u = np.atleast_1d(ds["mean_separation"].values)
        p = np.atleast_1d(ds["p"].values) / float(ds["E_star"])
        label = label.replace("+0", "0")
        if np.all(u == 0):
            label += " (u = 0: no combined roughness)"
        if "marker" in style:
            style = dict(style, markevery=max(1, u.size // 25))
        line = line_with_band(ax, np.log10(p), draws["mean_separation"] * 1e9, level, across=True, label=label, **style)
        u0, beta = float(ds["separation_u0"]), float(ds["separation_beta"])
        if u0 > 0 and np.isfinite(beta):
            law = u0 * np.log(beta / p)
            keep = law > 0
            ax.plot(law[keep] * 1e9, np.log10(p[keep]), "--", color=line.get_color(), linewidth=0.7, alpha=0.7,
                    label="u0 ln(beta E*/p) (eqs 58-60)" if i == 0 else None)
    ax.set_xlabel("mean separation u (nm)")
    ax.set_ylabel("log10(p / E*)")
    ax.set_xlim(left=-0.03 * ax.get_xlim()[1])
    ax.set_title(f"Interfacial separation, zeta = {zeta_used:g} (seed Fig. 5)" + (f"\n{note}" if note else ""),
                 fontsize=10 if note else None)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
