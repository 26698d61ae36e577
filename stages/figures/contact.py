"""Figures of the contact stage: seed Figs 3 (A/A0 against p/E*) and 4 (P(sigma))."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import UserError

from .common import curve_cases


def _cases(results):
    return curve_cases(results, "contact")


def _at_zeta(ds, zeta):
    return ds.sel(zeta=zeta, method="nearest") if "zeta" in ds.dims else ds


def figure_contact_area(results, zeta=4.0):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for (label, ds), marker in zip(_cases(results), "osx^dv"):
        ds = _at_zeta(ds, zeta)
        p = ds["p"].values / float(ds["E_star"])
        ax.semilogx(p, ds["contact_area_ratio"].values, marker=marker, markersize=3, label=label)
    ax.set_xlabel("p / E*")
    ax.set_ylabel("A / A0")
    ax.set_title(f"Relative contact area, zeta = {zeta:g} (seed Fig. 3)")
    ax.set_ylim(0, 1.02)
    ax.legend()
    fig.tight_layout()
    return fig


def figure_stress_distribution(results, zeta=4.0):
    """Seed Fig. 4: P(sigma) at three pressures (where the reference curve's A/A0 is about
    0.1, 0.3 and 0.6), one curve per case; a delta (no roughness) is drawn as a vertical line."""
    import matplotlib.pyplot as plt

    cases = _cases(results)
    base = _at_zeta(results["base"]["contact"], zeta)
    if "stress_distribution" not in base:
        raise UserError("the scene does not ask for 'stress_distribution' (add it to outputs.variables)",
                        key="outputs.variables")
    E_star = float(base["E_star"])
    ref = _at_zeta(cases[0][1], zeta)["contact_area_ratio"]
    ref = ref.isel({d: 0 for d in ref.dims if d != "p"})
    picks = sorted({float(ref["p"][int(np.argmin(np.abs(ref.values - a)))]) for a in (0.1, 0.3, 0.6)})
    fig, axes = plt.subplots(1, len(picks), figsize=(4.2 * len(picks), 3.8), squeeze=False)
    for ax, p in zip(axes[0], picks):
        right = 0.0
        for (label, ds), style in zip(cases, ("-", "--", ":", "-.", "-", "--")):
            ds = _at_zeta(ds, zeta)
            d = ds["stress_distribution"].sel(p=p, method="nearest")
            G = float(ds["G"])
            if "p" in d["sigma"].dims:
                d = d.assign_coords(sigma=d["sigma"])
            if G > 0:
                line, = ax.plot(d["sigma"].values / E_star, d.values * E_star, style, label=label)
                right = max(right, (p + 5.0 * np.sqrt(G)) / E_star)
            else:
                ax.axvline(p / E_star, linestyle=style, color="0.3", label=f"{label} (full contact: delta)")
        ax.set_xlim(0, right or 2 * p / E_star)
        ax.set_xlabel("sigma / E*")
        ax.set_title(f"p / E* = {p / E_star:.3g}")
    axes[0][0].set_ylabel("P(sigma) E*")
    axes[0][-1].legend(fontsize=8)
    fig.suptitle(f"Stress distribution, zeta = {zeta:g} (seed Fig. 4)")
    fig.tight_layout()
    return fig
