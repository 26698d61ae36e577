"""Figure of the bem stage: theory against the exact BEM at the BEM's magnification."""

from __future__ import annotations

import numpy as np


def _label(d, eta, measured):
    label = (("measured maps" if measured else "pair") if np.isnan(eta)
             else f"eta = {eta:+g}".replace("+0", "0"))
    if np.all(np.asarray(d["bem_hrms_combined"].values) == 0):
        label += " (h1 = h2: full contact)"
    return label


def _decorate(fig, axes, ds, measured, zeta_bem, grid):
    axes[0].set_ylabel("A / A0")
    axes[0].set_ylim(top=1.3)
    axes[0].legend(fontsize=7)
    axes[0].set_title("contact area: theory (lines), BEM (points)", fontsize=9)
    axes[1].set_ylabel("mean separation u (nm)")
    axes[1].set_ylim(bottom=0)
    axes[1].set_title("mean separation" + (" (one measured pair)" if measured else
                                           " (error bars: spread over realizations)"), fontsize=9)
    axes[2].axhline(1.0, color="0.5", linewidth=0.8)
    axes[2].set_ylabel("theory / BEM")
    axes[2].set_title("ratios, same band on both sides", fontsize=9)
    axes[2].set_ylim(top=max(1.4, axes[2].get_ylim()[1] * 1.15))
    axes[2].legend(fontsize=7, ncol=2, loc="upper center")
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3)
    R = ds.sizes.get("realization", 1)
    source = ("the measured maps" if measured else
              f"{R} realization{'s' if R > 1 else ''}, seed {ds.attrs.get('bem_seed', '?')}")
    fig.suptitle(f"Theory vs BEM at zeta = {zeta_bem:.4g}: {grid}^2 map, {source}")
    fig.tight_layout()


def figure_bem_comparison(results):
    """Theory (lines) against BEM (markers, +- one standard deviation over realizations) at the
    BEM's magnification: A/A0 and mean separation against p/E*, and their theory/BEM ratios."""
    import matplotlib.pyplot as plt

    ds = results["base"]["bem"]
    E_star = float(ds["E_star"])
    measured = ds.attrs.get("bem_surfaces") == "measured"
    zeta_bem, grid = float(ds["bem_zeta"]), int(ds["bem_grid"])  # scalars, before eta/p are expanded
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.3))
    x = ds["p"].values / E_star
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        label = _label(d, eta, measured)
        color = f"C{k}"
        axes[0].loglog(x, d["theory_contact_area_ratio"], "-", color=color, label=f"theory, {label}")
        axes[0].errorbar(x, d["bem_contact_area_ratio_mean"], yerr=d["bem_contact_area_ratio_std"], fmt="o",
                         color=color, markersize=4, capsize=2, label=f"BEM, {label}")
        axes[1].semilogx(x, d["theory_mean_separation"] * 1e9, "-", color=color)
        axes[1].errorbar(x, d["bem_mean_gap_mean"] * 1e9, yerr=d["bem_mean_gap_std"] * 1e9, fmt="o",
                         color=color, markersize=4, capsize=2)
        for var, style, what in (("area_ratio_theory_to_bem", "o-", "A/A0"), ("separation_ratio_theory_to_bem", "s--", "u")):
            if np.any(np.isfinite(d[var].values)):
                axes[2].semilogx(x, d[var], style, color=color, markersize=4, label=f"{what}, {label}")
    _decorate(fig, axes, ds, measured, zeta_bem, grid)
    return fig
