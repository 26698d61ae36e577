"""Figure of the interface_bem stage: leak rate and contact stiffness, theory against the exact
(BEM gap + Reynolds) results, and their ratios."""

from __future__ import annotations

import numpy as np

from .common import eta_label, style


def _cases(ds):
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    for k, eta in enumerate(ds["eta"].values):
        case = "measured maps" if np.isnan(eta) else eta_label(eta)
        d = ds.isel(eta=k)
        full = np.all(d["exact_contact_area_ratio"].values == 1.0)
        yield style(case)["color"], case + (" (h1 = h2: full contact, no flow)" if full else ""), d


def _positive(values):
    values = np.asarray(values, dtype=float)
    return np.where((values > 0) & np.isfinite(values), values, np.nan)


def figure_interface_bem(results):
    """Leak rate (theory: lines; exact: points with the spread over realizations) and stiffness
    against p/E*, theory/exact ratios, and the loads at which each says the seal closes."""
    import matplotlib.pyplot as plt

    ds = results["base"]["interface_bem"]
    E_star = float(ds["E_star"])
    fig, axes = plt.subplots(1, 3, figsize=(15.0, 5.4), layout="constrained")
    cases = []
    for c, label, d in _cases(ds):  # the legend is one for all panels: see _legend
        x = d["p"].values / E_star
        cases.append((c, label))
        axes[0].loglog(x, _positive(d["theory_leak_rate_critical_junction"]), "-", color=c)
        axes[0].loglog(x, _positive(d["theory_leak_rate_effective_medium"]), "--", color=c)
        scale = d["exact_leak_rate"] / d["exact_flow_factor_mean"]
        axes[0].errorbar(x, _positive(d["exact_leak_rate"]), yerr=np.nan_to_num(d["exact_flow_factor_std"] * scale),
                         fmt="o", color=c, markersize=4, capsize=2)
        seal = np.nanmean(d["exact_sealing_pressure"].values) / E_star
        for value, dash in ((seal, ":"), (float(d["theory_sealing_pressure_critical_junction"]) / E_star, "-")):
            if np.isfinite(value) and value > 0:
                axes[0].axvline(value, color=c, linestyle=dash, linewidth=0.8, alpha=0.6)
        axes[1].loglog(x, _positive(d["theory_stiffness"]), "-", color=c)
        axes[1].errorbar(x, _positive(d["exact_stiffness_mean"]), yerr=np.nan_to_num(d["exact_stiffness_std"]),
                         fmt="s", color=c, markersize=4, capsize=2)
        for var, fmt in (("leak_ratio_critical_junction_to_exact", "o-"),
                         ("leak_ratio_effective_medium_to_exact", "^--"), ("stiffness_ratio_theory_to_exact", "s:")):
            axes[2].loglog(x, _positive(d[var]), fmt, color=c, markersize=4)
    axes[0].set_ylabel("leak rate Q (m^3/s)")
    axes[0].set_title("leak rate (vertical: sealing load, exact dotted, CJ solid)", fontsize=9)
    axes[1].set_ylabel("K = -dp/du (Pa/m)")
    axes[1].set_title("contact stiffness", fontsize=9)
    axes[2].axhline(1.0, color="0.4", linewidth=0.8)
    for level in (1 / 3, 3.0):
        axes[2].axhline(level, color="0.7", linewidth=0.6, linestyle="--")
    axes[2].set_ylabel("theory / exact")
    axes[2].set_title("ratios (grey dashed: factor 3)", fontsize=9)
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3, which="both")
    _legend(fig, cases)
    fig.suptitle(f"Theory vs exact on the BEM's gap: zeta = {ds.attrs.get('bem_zeta', float('nan')):.4g}, "
                 f"{ds.attrs.get('bem_grid', '?')}^2 {ds.attrs.get('bem_surfaces', '')} map(s)")
    return fig


def _legend(fig, cases):
    """One legend below the panels: a colour per case, a line style or marker per quantity."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, linewidth=6, label=label) for c, label in cases]
    handles += [Line2D([], [], color="0.2", linestyle=ls, marker=m, markersize=4, label=text) for ls, m, text in (
        ("-", "", "theory: critical junction (ratio: o-)"), ("--", "", "theory: effective medium (ratio: ^--)"),
        ("none", "o", "exact leak rate, BEM gap + Reynolds (+- 1 s.d.)"), ("-", "", "theory stiffness"),
        ("none", "s", "BEM stiffness (+- 1 s.d.)"), (":", "s", "stiffness: theory / BEM"))]
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=4)
