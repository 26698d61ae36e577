"""Figures of the contact stage: seed Figs 3 (A/A0 against p/E*) and 4 (P(sigma))."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import UserError

from .common import band_level, band_note, band_on, curve_cases, line_with_band, nominal


def _cases(results):
    return curve_cases(results, "contact")


def _at_zeta(ds, zeta):
    return ds.sel(zeta=zeta, method="nearest") if "zeta" in ds.dims else ds


def figure_contact_area(results, zeta=4.0):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    ax.set_xscale("log")
    level, note = band_level(results), ""
    for (label, ds), marker in zip(_cases(results), "osx^dv"):
        ds = _at_zeta(ds, zeta)
        p = ds["p"].values / float(ds["E_star"])
        line_with_band(ax, p, ds["contact_area_ratio"], level, marker=marker, markersize=3, label=label)
        note = note or band_note(results, ds)
    ax.set_xlabel("p / E*")
    ax.set_ylabel("A / A0")
    ax.set_title(f"Relative contact area, zeta = {zeta:g} (seed Fig. 3)" + (f"\n{note}" if note else ""),
                 fontsize=10 if note else None)
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
    ref = nominal(_at_zeta(cases[0][1], zeta)["contact_area_ratio"])
    ref = ref.isel({d: 0 for d in ref.dims if d != "p"})
    picks = sorted({float(ref["p"][int(np.argmin(np.abs(ref.values - a)))]) for a in (0.1, 0.3, 0.6)})
    fig, axes = plt.subplots(1, len(picks), figsize=(4.2 * len(picks), 3.8), squeeze=False)
    for ax, p in zip(axes[0], picks):
        right = 0.0
        for (label, ds), style in zip(cases, ("-", "--", ":", "-.", "-", "--")):
            ds = _at_zeta(ds, zeta)
            draws = ds["stress_distribution"].sel(p=p, method="nearest")
            d, G = nominal(draws), float(nominal(ds["G"]))
            if G > 0:
                line, = ax.plot(d["sigma"].values / E_star, d.values * E_star, style, label=label)
                right = max(right, (p + 5.0 * np.sqrt(G)) / E_star)
                if "draw" in draws.dims:
                    lo, hi = band_on(d["sigma"].values, draws["sigma"].values, draws.values, band_level(results))
                    ax.fill_between(d["sigma"].values / E_star, lo * E_star, hi * E_star, color=line.get_color(),
                                    alpha=0.22, lw=0)
            else:
                ax.axvline(p / E_star, linestyle=style, color="0.3", label=f"{label} (full contact: delta)")
        ax.set_xlim(0, right or 2 * p / E_star)
        ax.set_xlabel("sigma / E*")
        ax.set_title(f"p / E* = {p / E_star:.3g}")
    axes[0][0].set_ylabel("P(sigma) E*")
    axes[0][-1].legend(fontsize=8)
    note = band_note(results, base)
    fig.suptitle(f"Stress distribution, zeta = {zeta:g} (seed Fig. 4)" + (f"\n{note}" if note else ""),
                 fontsize=10 if note else None)
    fig.tight_layout()
    return fig
