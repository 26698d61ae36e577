"""Figures of the bem stage: theory (eq 19 / eq 57 and its corrections) against the exact BEM at
the BEM's magnification, and the ratios against the reduced pressure p / (E* g).

Colour and marker are the case's (:data:`~.common.CASE_STYLES`); the line style is the theory
variant's (:data:`_STYLES`); one legend below the panels says both."""

from __future__ import annotations

import numpy as np

from .common import eta_label, legend_outside, style, wavenumber

#: line style of each theory variant
_STYLES = {"persson": "-", "yang_persson": "--", "wang_mueser": ":"}
_VARIANTS = {"persson": "eq 19 / eq 57", "yang_persson": "Yang-Persson", "wang_mueser": "Wang-Mueser"}


def _label(d, eta, measured):
    """(case, legend text) of one coherence of the BEM result."""
    case = ("pair, measured eta(q)" if measured else "pair") if np.isnan(eta) else eta_label(eta)
    full = np.all(np.asarray(d["bem_hrms_combined"].values) == 0)
    return case, case + (" (h1 = h2: full contact)" if full else "")


def _prepared(results):
    ds = results["base"]["bem"]
    measured = ds.attrs.get("bem_surfaces") == "measured"
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    return ds, measured


def _legend(fig, cases, variants, bem=True, spread=True):
    """One legend below the panels: a colour and marker per case, a line style per theory variant."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=s["color"], marker=s["marker"], linestyle="none", label=text) for text, s in cases]
    handles += [Line2D([], [], color="0.2", linestyle=_STYLES.get(v, "-."), label=f"theory: {_VARIANTS.get(v, v)}")
                for v in variants]
    if bem:
        handles.append(Line2D([], [], color="0.2", marker="o", linestyle="none", markerfacecolor="white",
                              label="BEM (+- 1 s.d. over realizations)" if spread else "BEM (one pair: no spread)"))
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=min(len(handles), 4))


def _variant_lines(axes, x, d, s):
    """Every theory variant: A/A0 and u (lines), and the ratios to the BEM (case markers)."""
    names = [str(n) for n in d["theory"].values] if "theory" in d.dims else []
    for name in names:
        v = d.sel(theory=name)
        line = _STYLES.get(name, "-.")
        axes[0].loglog(x, v["theory_variant_contact_area_ratio"], line, color=s["color"])
        axes[1].semilogx(x, v["theory_variant_mean_separation"] * 1e9, line, color=s["color"])
        for ax, var in ((axes[2], "area_ratio_variant_to_bem"), (axes[3], "separation_ratio_variant_to_bem")):
            if np.any(np.isfinite(v[var].values)):
                ax.semilogx(x, v[var], line, marker=s["marker"], color=s["color"], markersize=4)
    if not names:  # results written before the variants existed
        axes[0].loglog(x, d["theory_contact_area_ratio"], "-", color=s["color"])
        axes[1].semilogx(x, d["theory_mean_separation"] * 1e9, "-", color=s["color"])
    return names or ["persson"]


def _decorate(fig, axes, ds, measured, zeta_bem, grid, qL):
    axes[0].set_ylabel("A / A0")
    axes[0].set_title("contact area: theory (lines), BEM (open markers)", fontsize=9)
    axes[1].set_ylabel("mean separation u (nm)")
    axes[1].set_ylim(bottom=0)
    one = " (one measured pair)" if measured else " (one realization)"
    axes[1].set_title("mean separation" + (" (error bars: spread over realizations)"
                                           if ds.sizes.get("realization", 1) > 1 else one), fontsize=9)
    for ax, what in ((axes[2], "A/A0"), (axes[3], "u")):
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_ylabel(f"{what}: theory / BEM")
        ax.set_title(f"{what}: theory / BEM per variant, same band on both sides", fontsize=9)
        ax.set_ylim(0, max(1.5, min(ax.get_ylim()[1] * 1.1, 3.0)))
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3)
    R = ds.sizes.get("realization", 1)
    source = ("the measured maps" if measured else
              f"{R} realization{'s' if R > 1 else ''}, seed {ds.attrs.get('bem_seed', '?')}")
    band = f" (q up to {wavenumber(zeta_bem * qL)}, qL = {wavenumber(qL)})" if qL else ""
    fig.suptitle(f"Theory vs BEM at zeta = {zeta_bem:.4g}{band}: {grid}^2 map, {source}", fontsize=10)


def figure_bem_comparison(results):
    """Theory (lines: eq 19 / eq 57 and every correction) against BEM (markers, +- one standard
    deviation over realizations) at the BEM's magnification: A/A0 and mean separation against
    p/E*, and each variant's theory/BEM ratios."""
    import matplotlib.pyplot as plt

    raw = results["base"]["bem"]
    E_star = float(raw["E_star"])
    zeta_bem, grid = float(raw["bem_zeta"]), int(raw["bem_grid"])  # scalars, before eta/p are expanded
    ds, measured = _prepared(results)
    psd = results["base"].get("psd")
    qL = float(psd["q"].values[0]) if psd is not None else None
    fig, axes = plt.subplots(2, 2, figsize=(12.0, 8.8), layout="constrained")
    axes = axes.ravel()
    x = ds["p"].values / E_star
    cases, variants = [], []
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        case, text = _label(d, eta, measured)
        s = style(case)
        cases.append((text, s))
        variants = _variant_lines(axes, x, d, s)
        axes[0].errorbar(x, d["bem_contact_area_ratio_mean"], yerr=d["bem_contact_area_ratio_std"], fmt=s["marker"],
                         color=s["color"], markerfacecolor="white", markersize=5, capsize=2)
        axes[1].errorbar(x, d["bem_mean_gap_mean"] * 1e9, yerr=d["bem_mean_gap_std"] * 1e9, fmt=s["marker"],
                         color=s["color"], markerfacecolor="white", markersize=5, capsize=2)
    _decorate(fig, axes, ds, measured, zeta_bem, grid, qL)
    _legend(fig, cases, variants, spread=ds.sizes.get("realization", 1) > 1)
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

    ds, measured = _prepared(results)
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.8), layout="constrained")
    x_all = reduced_pressure(ds)
    cases, variants = [], []
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        if np.all(np.asarray(d["bem_hrms_combined"].values) == 0):
            continue  # h1 = h2: no roughness, no reduced pressure
        x = x_all.isel(eta=k).values
        case, text = _label(d, eta, measured)
        s = style(case)
        cases.append((text, s))
        variants = [str(n) for n in d["theory"].values] if "theory" in d.dims else []
        for name in variants:
            v = d.sel(theory=name)
            for ax, var in ((axes[0], "area_ratio_variant_to_bem"), (axes[1], "separation_ratio_variant_to_bem")):
                ax.semilogx(x, v[var], _STYLES.get(name, "-."), marker=s["marker"], color=s["color"], markersize=4)
    for ax, what in ((axes[0], "A/A0"), (axes[1], "mean separation u")):
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_xlabel("p / (E* g), g = rms slope of the BEM composite")
        ax.set_ylabel(f"{what}: theory / BEM")
        ax.grid(alpha=0.3)
        ax.set_ylim(0, max(1.5, min(ax.get_ylim()[1], 3.0)))
    zeta = float(results["base"]["bem"]["bem_zeta"])
    fig.suptitle(f"Theory / BEM against the reduced pressure, at zeta = {zeta:.4g}", fontsize=10)
    _legend(fig, cases, variants, bem=False)
    return fig


def figure_bem_elastoplastic(results):
    """Elastoplastic contact, theory (lines) against the saturated BEM (markers, +- one standard
    deviation over realizations) at the BEM's magnification: A_el/A0 (solid, open markers) and
    A_pl/A0 (dashed, filled markers; the case's marker and colour) against p / sigma_Y, with the
    limit p / sigma_Y of a fully yielded interface; beside them the theory / BEM ratios of A_el,
    A_pl and the total A_el + A_pl."""
    import matplotlib.pyplot as plt

    raw = results["base"]["bem"]
    zeta_bem, grid = float(raw["bem_zeta"]), int(raw["bem_grid"])
    ds, measured = _prepared(results)
    Y = float(ds["theory_plastic_contact_area_ratio"].attrs["yield_stress_Pa"])
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.9), layout="constrained")
    x = ds["p"].values / Y
    cases = []
    kinds = (("elastic", "-", "white"), ("plastic", "--", None))  # line style, marker face (None: filled)
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        case, text = _label(d, eta, measured)
        s = style(case)
        cases.append(text)
        totals = {"theory": 0.0, "bem": 0.0}
        for kind, line, face in kinds:
            marker = dict(marker=s["marker"], color=s["color"], markerfacecolor=face or s["color"])
            theory = d[f"theory_{kind}_contact_area_ratio"].values
            mean, std = d[f"bem_{kind}_contact_area_ratio_mean"].values, d[f"bem_{kind}_contact_area_ratio_std"].values
            axes[0].loglog(x, np.where(theory > 0, theory, np.nan), line, color=s["color"],
                           label=f"theory A_{kind[:2]}/A0, {text}")
            axes[0].errorbar(x, mean, yerr=std, linestyle="none", markersize=5, capsize=2,
                             label=f"BEM A_{kind[:2]}/A0, {text}", **marker)
            totals["theory"] = totals["theory"] + theory
            totals["bem"] = totals["bem"] + mean
            with np.errstate(divide="ignore", invalid="ignore"):
                axes[1].loglog(x, np.where(mean > 0, theory / mean, np.nan), line, markersize=4,
                               label=f"A_{kind[:2]}: theory / BEM, {text}", **marker)
        with np.errstate(divide="ignore", invalid="ignore"):
            axes[1].loglog(x, totals["theory"] / totals["bem"], ":", marker=s["marker"], color=s["color"], markersize=4,
                           markerfacecolor="white", markeredgecolor="0.5",
                           label=f"A_el + A_pl: theory / BEM, {text}")
    axes[0].loglog(x, np.minimum(x, 1.0), "-.", color="0.45", lw=1.0, label="p / sigma_Y (every spot yielded)")
    axes[0].axvline(1.0, color="0.6", lw=0.8)
    axes[0].set_ylim(max(1e-9, axes[0].get_ylim()[0]), 2.0)
    axes[0].set_ylabel("relative contact area")
    axes[0].set_title("elastic (solid line, open markers) and plastic (dashed, filled) area", fontsize=9)
    axes[1].axhline(1.0, color="0.5", lw=0.8)
    axes[1].set_ylabel("theory / BEM")
    axes[1].set_title("theory / BEM (p >= sigma_Y: both fully plastic)", fontsize=9)
    for ax in axes:
        ax.set_xlabel("p / sigma_Y")
        ax.grid(alpha=0.3, which="both", lw=0.4)
    R = ds.sizes.get("realization", 1)
    source = "the measured maps" if measured else f"{R} realization{'s' if R > 1 else ''}"
    fig.suptitle(f"Elastoplastic contact, sigma_Y = {Y / 1e9:.3g} GPa: theory vs saturated BEM at zeta = "
                 f"{zeta_bem:.4g} ({grid}^2 map, {source}; error bars: +- 1 s.d. over realizations)", fontsize=10)
    return legend_outside(fig, list(axes), below=True)
