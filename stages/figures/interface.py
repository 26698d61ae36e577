"""Figures of the interface stages: contact stiffness, contact conductance, leak rate."""

from __future__ import annotations

import numpy as np

from .common import curve_cases, legend_outside, scope_text


def _top_zeta(da):
    """The variable at its largest magnification (the whole band) when it has a zeta dimension."""
    return da.isel(zeta=-1) if "zeta" in da.dims else da


def _zeta_title(results, stage) -> str:
    """The magnification drawn and its reference wavenumber (each variant's, if they differ)."""
    zeta = results["base"][stage]["zeta"].values if "zeta" in results["base"][stage].coords else None
    return scope_text(results, float(np.atleast_1d(zeta)[-1]) if zeta is not None else None)


def _kw(case) -> dict:
    """Colour and marker of a case (its line style is the figure's, per quantity), markers on
    about ten points."""
    s = case.style
    return dict(color=s["color"], marker=s["marker"], markersize=4, markevery=max(1, case.ds.sizes.get("p", 1) // 10),
                markerfacecolor=s.get("markerfacecolor", s["color"]))


def _infinite_note(values) -> str:
    return " (exact fit: infinite)" if np.all(np.isinf(values)) else ""


def figure_stiffness(results):
    """K = -dp/du against p/E* (log-log) per case at the largest magnification, and K u0/p -> 1."""
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.9), layout="constrained")
    for case in curve_cases(results, "stiffness"):
        ds = case.ds
        x = ds["p"].values / float(ds["E_star"])
        K, small = _top_zeta(ds["contact_stiffness"]).values, _top_zeta(ds["small_load_stiffness"]).values
        ax.loglog(x, K, "-", label=case.label + _infinite_note(K), **_kw(case))
        ax.loglog(x, small, ":", color=case.style["color"], linewidth=0.9)
        with np.errstate(divide="ignore", invalid="ignore"):
            ax2.loglog(x, K / small, "-", **_kw(case))
    ax.plot([], [], ":", color="0.3", linewidth=0.9, label="small-load limit p/u0 (dotted)")
    ax.set_xlabel("p / E*")
    ax.set_ylabel("K = -dp/du (Pa/m)")
    ax.set_title("contact stiffness (dotted: small-load limit p/u0)", fontsize=9)
    ax2.axhline(1.0, color="0.5", linewidth=0.8)
    ax2.set_xlabel("p / E*")
    ax2.set_ylabel("K u0 / p")
    ax2.set_title("approach to the small-load law p = beta E* exp(-u/u0)", fontsize=9)
    for a in (ax, ax2):
        a.grid(alpha=0.3)
    fig.suptitle(f"Normal contact stiffness per unit area at {_zeta_title(results, 'stiffness')}", fontsize=10)
    return legend_outside(fig, [ax], below=True)


def figure_conductance(results):
    """Thermal and electrical contact conductance per unit area against p, per case."""
    import matplotlib.pyplot as plt

    base = results["base"]["conductance"]
    kinds = [(name, label, unit) for name, label, unit in
             (("thermal_contact_conductance", "thermal contact conductance h", "W/(m^2 K)"),
              ("electrical_contact_conductance", "electrical contact conductance", "S/m^2")) if name in base]
    fig, axes = plt.subplots(1, len(kinds), figsize=(5.6 * len(kinds), 4.9), squeeze=False, layout="constrained")
    for ax, (name, title, unit) in zip(axes[0], kinds, strict=True):
        for case in curve_cases(results, "conductance"):
            y = _top_zeta(case.ds[name]).values
            p = case.ds["p"].values / 1e6
            if np.all(np.isinf(y)):  # nothing to draw on a log axis: say so in the legend
                ax.plot([], [], "-", label=case.label + _infinite_note(y), **_kw(case))
                continue
            ax.loglog(p, y, "-", label=case.label, **_kw(case))
        ax.set_xlabel("nominal pressure p (MPa)")
        ax.set_ylabel(f"{title} ({unit})")
        ax.set_title(title + " (Barber's analogy)", fontsize=9)
        ax.grid(alpha=0.3)
    fig.suptitle("Contact conductance per unit nominal area (no gas, no radiation) at "
                 f"{_zeta_title(results, 'conductance')}", fontsize=10)
    return legend_outside(fig, list(axes[0]), below=True)


def figure_leakage(results):
    """Leak rate against the nominal contact pressure (critical junction: solid; effective medium:
    dashed), with each theory's sealing pressure, and the critical magnification."""
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.5, 5.0), layout="constrained")
    for case in curve_cases(results, "leakage"):
        ds = case.ds
        p = ds["p"].values / 1e6
        for method, style in (("critical_junction", "-"), ("effective_medium", "--")):
            Q = ds[f"leak_rate_{method}"].values * 1e9 * 3600  # m^3/s -> uL/h
            shown = np.where(Q > 0, Q, np.nan)
            note = " (sealed at every load)" if np.all(Q == 0) else ""
            ax.loglog(p, shown, style, label=f"{case.label}, {method.replace('_', ' ')}{note}", **_kw(case))
            seal = float(ds[f"sealing_pressure_{method}"])
            if 0 < seal < p.max() * 1e6 * 10:
                ax.axvline(seal / 1e6, color=case.style["color"], linestyle=style, linewidth=0.7, alpha=0.6)
        ax2.loglog(p, ds["critical_magnification"].values, "-", label=case.label, **_kw(case))
    ax.set_xlabel("nominal contact pressure p (MPa)")
    ax.set_ylabel("leak rate Q (uL/h)")
    ax.set_title("leak rate (vertical lines: pressure at which the seal closes)", fontsize=9)
    ax2.set_xlabel("nominal contact pressure p (MPa)")
    ax2.set_ylabel("critical magnification zeta_c")
    ax2.set_title("magnification at which the open area stops percolating", fontsize=9)
    for a in (ax, ax2):
        a.grid(alpha=0.3, which="both")
    attrs = results["base"]["leakage"].attrs
    fig.suptitle(f"Seal leak rate (W/L = {attrs.get('leakage_aspect_ratio', float('nan')):.4g}, "
                 f"percolation at A/A0 = {attrs.get('leakage_percolation_area', float('nan')):.2f})", fontsize=10)
    return legend_outside(fig, [ax], below=True)
