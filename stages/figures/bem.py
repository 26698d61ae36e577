"""Figure of the bem stage: theory against the exact BEM at the BEM's magnification."""

from __future__ import annotations

import numpy as np


def _label(d, eta, measured):
    label = (("measured maps" if measured else "pair") if np.isnan(eta)
             else f"eta = {eta:+g}".replace("+0", "0"))
    if np.all(np.asarray(d["bem_hrms_combined"].values) == 0):
        label += " (h1 = h2: full contact)"
    return label


_STYLES = {"persson": "-", "yang_persson": "--", "wang_mueser": ":"}


def _decorate(fig, axes, ds, measured, zeta_bem, grid):
    axes[0].set_ylabel("A / A0")
    axes[0].set_ylim(top=1.3)
    axes[0].legend(fontsize=7)
    axes[0].set_title("contact area: theory (lines), BEM (points)", fontsize=9)
    axes[1].set_ylabel("mean separation u (nm)")
    axes[1].set_ylim(bottom=0)
    axes[1].set_title("mean separation" + (" (one measured pair)" if measured else
                                           " (error bars: spread over realizations)"), fontsize=9)
    axes[1].legend(fontsize=7)
    for ax, what in ((axes[2], "A/A0"), (axes[3], "u")):
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_ylabel(f"{what}: theory / BEM")
        ax.set_title(f"{what}: theory / BEM per variant, same band on both sides", fontsize=9)
        ax.set_ylim(0, max(1.5, min(ax.get_ylim()[1] * 1.1, 3.0)))
        ax.legend(fontsize=7, ncol=2, loc="lower center")
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3)
    R = ds.sizes.get("realization", 1)
    source = ("the measured maps" if measured else
              f"{R} realization{'s' if R > 1 else ''}, seed {ds.attrs.get('bem_seed', '?')}")
    fig.suptitle(f"Theory vs BEM at zeta = {zeta_bem:.4g}: {grid}^2 map, {source}; "
                 "lines: - eq 19/57, -- Yang-Persson, : Wang-Mueser")
    fig.tight_layout()


def _variant_lines(axes, x, d, color, label):
    """Every theory variant: A/A0 and u (lines), and the ratios to the BEM."""
    names = list(d["theory"].values) if "theory" in d.dims else []
    for name in names:
        v = d.sel(theory=name)
        style = _STYLES.get(str(name), "-.")
        first = name == names[0]
        axes[0].loglog(x, v["theory_variant_contact_area_ratio"], style, color=color,
                       label=f"theory, {label}" if first else None)
        axes[1].semilogx(x, v["theory_variant_mean_separation"] * 1e9, style, color=color,
                         label=str(name) if color == "C0" else None)
        for ax, var in ((axes[2], "area_ratio_variant_to_bem"), (axes[3], "separation_ratio_variant_to_bem")):
            if np.any(np.isfinite(v[var].values)):
                ax.semilogx(x, v[var], style, marker="o", color=color, markersize=3,
                            label=f"{name}, {label}" if color in ("C0", "C2") else None)
    if not names:  # results written before the variants existed
        axes[0].loglog(x, d["theory_contact_area_ratio"], "-", color=color, label=f"theory, {label}")
        axes[1].semilogx(x, d["theory_mean_separation"] * 1e9, "-", color=color)


def figure_bem_comparison(results):
    """Theory (lines: eq 19 / eq 57 and every correction) against BEM (markers, +- one standard
    deviation over realizations) at the BEM's magnification: A/A0 and mean separation against
    p/E*, and each variant's theory/BEM ratios."""
    import matplotlib.pyplot as plt

    ds = results["base"]["bem"]
    E_star = float(ds["E_star"])
    measured = ds.attrs.get("bem_surfaces") == "measured"
    zeta_bem, grid = float(ds["bem_zeta"]), int(ds["bem_grid"])  # scalars, before eta/p are expanded
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    fig, axes = plt.subplots(2, 2, figsize=(12.0, 8.5))
    axes = axes.ravel()
    x = ds["p"].values / E_star
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        label = _label(d, eta, measured)
        color = f"C{k}"
        _variant_lines(axes, x, d, color, label)
        axes[0].errorbar(x, d["bem_contact_area_ratio_mean"], yerr=d["bem_contact_area_ratio_std"], fmt="o",
                         color=color, markersize=4, capsize=2, label=f"BEM, {label}")
        axes[1].errorbar(x, d["bem_mean_gap_mean"] * 1e9, yerr=d["bem_mean_gap_std"] * 1e9, fmt="o",
                         color=color, markersize=4, capsize=2)
    _decorate(fig, axes, ds, measured, zeta_bem, grid)
    return fig


def reduced_pressure(ds):
    """p / (E* g) over (p, eta): g the BEM composite's rms slope (mean over realizations), the
    unit in which contact barely depends on the spectrum (docs/bem.md, "The separation ratio")."""
    g = ds["bem_rms_slope_combined"].mean("realization")
    with np.errstate(divide="ignore", invalid="ignore"):
        return ds["p"] / (ds["E_star"] * g)


def figure_bem_reduced_pressure(results):
    """Each variant's theory / BEM ratios of A/A0 and of the mean separation against the
    reduced pressure p / (E* g) (the rough pairs only)."""
    import matplotlib.pyplot as plt

    ds = results["base"]["bem"]
    measured = ds.attrs.get("bem_surfaces") == "measured"
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    x_all = reduced_pressure(ds)
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        if np.all(np.asarray(d["bem_hrms_combined"].values) == 0):
            continue  # h1 = h2: no roughness, no reduced pressure
        x = x_all.isel(eta=k).values
        label = _label(d, eta, measured)
        names = list(d["theory"].values) if "theory" in d.dims else []
        for name in names:
            v = d.sel(theory=name)
            style = _STYLES.get(str(name), "-.")
            for ax, var in ((axes[0], "area_ratio_variant_to_bem"), (axes[1], "separation_ratio_variant_to_bem")):
                ax.semilogx(x, v[var], style, marker="o", color=f"C{k}", markersize=3, label=f"{name}, {label}")
    for ax, what in ((axes[0], "A/A0"), (axes[1], "mean separation u")):
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_xlabel("p / (E* g), g = rms slope of the BEM composite")
        ax.set_ylabel(f"{what}: theory / BEM")
        ax.grid(alpha=0.3)
        ax.set_ylim(0, max(1.5, min(ax.get_ylim()[1], 3.0)))
    axes[1].legend(fontsize=7, ncol=2)
    fig.suptitle("Theory / BEM against the reduced pressure (- eq 19/57, -- Yang-Persson, : Wang-Mueser)")
    fig.tight_layout()
    return fig
