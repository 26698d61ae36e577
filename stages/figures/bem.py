"""Figure of the bem stage: theory against the exact BEM at the BEM's magnification."""

from __future__ import annotations

import numpy as np

from .common import eta_label, style, wavenumber


def _label(d, eta, measured):
    label = ("pair, measured eta(q)" if measured else "pair") if np.isnan(eta) else eta_label(eta)
    full = np.all(np.asarray(d["bem_hrms_combined"].values) == 0)
    return label, label + (" (h1 = h2: full contact)" if full else "")


def _legend(fig, cases):
    """One legend below the panels: a colour per case, and what lines and markers mean."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=s["color"], marker=s["marker"], linestyle="-", label=text) for text, s in cases]
    handles += [Line2D([], [], color="0.2", linestyle="-", label="theory"),
                Line2D([], [], color="0.2", marker="o", linestyle="none", label="BEM (+- 1 s.d.)"),
                Line2D([], [], color="0.2", marker="o", linestyle="-", label="ratio A/A0"),
                Line2D([], [], color="0.2", marker="o", markerfacecolor="white", linestyle="--", label="ratio u")]
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=min(len(handles), 8))


def _decorate(fig, axes, ds, measured, zeta_bem, grid, qL):
    axes[0].set_ylabel("A / A0")
    axes[0].set_title("contact area: theory (lines), BEM (points)", fontsize=9)
    axes[1].set_ylabel("mean separation u (nm)")
    axes[1].set_ylim(bottom=0)
    axes[1].set_title("mean separation" + (" (one measured pair)" if measured else
                                           " (error bars: spread over realizations)"), fontsize=9)
    axes[2].axhline(1.0, color="0.5", linewidth=0.8)
    axes[2].set_ylabel("theory / BEM")
    axes[2].set_title("ratios, same band on both sides", fontsize=9)
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3)
    R = ds.sizes.get("realization", 1)
    source = ("the measured maps" if measured else
              f"{R} realization{'s' if R > 1 else ''}, seed {ds.attrs.get('bem_seed', '?')}")
    band = f" (q up to {wavenumber(zeta_bem * qL)}, qL = {wavenumber(qL)})" if qL else ""
    fig.suptitle(f"Theory vs BEM at zeta = {zeta_bem:.4g}{band}: {grid}^2 map, {source}", fontsize=10)


def figure_bem_comparison(results):
    """Theory (lines) against BEM (markers, +- one standard deviation over realizations) at the
    BEM's magnification: A/A0 and mean separation against p/E*, and their theory/BEM ratios."""
    import matplotlib.pyplot as plt

    ds = results["base"]["bem"]
    E_star = float(ds["E_star"])
    measured = ds.attrs.get("bem_surfaces") == "measured"
    zeta_bem, grid = float(ds["bem_zeta"]), int(ds["bem_grid"])  # scalars, before eta/p are expanded
    psd = results["base"].get("psd")
    qL = float(psd["q"].values[0]) if psd is not None else None
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    fig, axes = plt.subplots(1, 3, figsize=(15.0, 4.3), layout="constrained")
    x = ds["p"].values / E_star
    cases = []
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        case, text = _label(d, eta, measured)
        s = style(case)
        cases.append((text, s))
        color = s["color"]
        axes[0].loglog(x, d["theory_contact_area_ratio"], "-", color=color)
        axes[0].errorbar(x, d["bem_contact_area_ratio_mean"], yerr=d["bem_contact_area_ratio_std"], fmt=s["marker"],
                         color=color, markersize=4, capsize=2)
        axes[1].semilogx(x, d["theory_mean_separation"] * 1e9, "-", color=color)
        axes[1].errorbar(x, d["bem_mean_gap_mean"] * 1e9, yerr=d["bem_mean_gap_std"] * 1e9, fmt=s["marker"],
                         color=color, markersize=4, capsize=2)
        for var, face, line in (("area_ratio_theory_to_bem", color, "-"), ("separation_ratio_theory_to_bem", "white", "--")):
            if np.any(np.isfinite(d[var].values)):
                axes[2].semilogx(x, d[var], marker=s["marker"], linestyle=line, color=color, markerfacecolor=face,
                                 markersize=5)
    _decorate(fig, axes, ds, measured, zeta_bem, grid, qL)
    _legend(fig, cases)
    return fig
