"""Figures of the adhesion stage: seed Figs 1 (one rough surface) and 2 (two rough surfaces),
gamma_eff/Delta_gamma and A/A0 at zero load against the substrate's rms roughness."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import UserError

from .common import DEFAULT_LEVEL, band_level, draw_band, nominal

_ANGSTROM = 1e-10


def _per_model(ds):
    if "model" in ds.dims:
        return [(str(m), ds.sel(model=m)) for m in ds["model"].values]
    return [(str(ds["model"].values) if "model" in ds.coords else "", ds)]


def _curve(ax_a, ax_b, ds, label, style, full=False, color=None, level=DEFAULT_LEVEL):
    """gamma_eff/Delta_gamma on ax_a and A/A0 on ax_b against the substrate hrms, closed at the
    vanishing hrms (marked by a dotted line) when the dataset has it; with spectrum draws, the
    measured spectrum's curve and the band of the draws shaded."""
    draws, ds = ds, nominal(ds)
    if "hrms_substrate" not in ds.dims:
        raise UserError("the adhesion figures need substrate.hrms as a sweep", key="substrate.hrms")
    h = ds["hrms_substrate"].values / _ANGSTROM
    dg = float(ds["delta_gamma"])
    g = ds["gamma_eff_macroscopic"].values / dg
    A = ds["adhesive_contact_area_ratio"].values
    hp, gp, Ap = h, g, A
    if "hrms_substrate_vanishing" in ds:  # the end of the attached branch, where both reach 0
        hv = float(ds["hrms_substrate_vanishing"]) / _ANGSTROM
        order = np.argsort(np.append(h, hv), kind="stable")
        hp, gp, Ap = np.append(h, hv)[order], np.append(g, 0.0)[order], np.append(A, 0.0)[order]
    (line,) = ax_a.plot(hp, gp, style, color=color, label=label, markersize=4, markevery=list(np.flatnonzero(np.isin(hp, h))))
    ax_b.plot(hp, Ap, style, color=line.get_color(), label=label, markersize=4, markevery=list(np.flatnonzero(np.isin(hp, h))))
    for ax, var, scale in ((ax_a, "gamma_eff_macroscopic", dg), (ax_b, "adhesive_contact_area_ratio", 1.0)):
        band = draw_band(draws[var], level)
        if band is not None:
            ax.fill_between(h, band[0] / scale, band[1] / scale, color=line.get_color(), alpha=0.22, lw=0)
    if full:
        ax_a.plot(h, ds["gamma_eff_full_contact"].values / dg, "-.", color=line.get_color(), label="full contact")
    if "hrms_substrate_vanishing" in ds:
        hv = float(ds["hrms_substrate_vanishing"]) / _ANGSTROM
        for ax in (ax_a, ax_b):
            ax.axvline(hv, color=line.get_color(), lw=0.8, ls=":")
        ax_b.annotate(f"{hv:.3f} Å", (hv, 0.02), rotation=90, va="bottom", ha="right", fontsize=8, color=line.get_color())


def _axes(title):
    import matplotlib.pyplot as plt

    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(10, 4.2))
    ax_a.set_ylabel("gamma_eff / Delta_gamma")
    ax_b.set_ylabel("A / A0 at zero load")
    for ax, tag in ((ax_a, "(a)"), (ax_b, "(b)")):
        ax.set_xlabel("rms roughness of the substrate (Å)")
        ax.set_title(tag, loc="left")
        ax.grid(alpha=0.3)
    ax_b.set_ylim(0, 1.02)
    fig.suptitle(title)
    return fig, ax_a, ax_b


def figure_one_surface(results):
    """Seed Fig 1: one rough surface, partial (solid) and full (dash-dot) contact theory."""
    variant = "substrate_only" if "substrate_only" in results else "base"
    ds = results[variant]["adhesion"]
    if "eta" in ds.dims:
        ds = ds.isel(eta=0)
    fig, ax_a, ax_b = _axes("One rough surface (seed Fig. 1)")
    for k, (label, d) in enumerate(_per_model(ds)):
        _curve(ax_a, ax_b, d, f"partial contact ({label})" if label else "partial contact", "-", full=(k == 0),
               level=band_level(results))
    top = float(ds["gamma_eff_full_contact"].max() / ds["delta_gamma"])
    ax_a.set_ylim(0, max(1.02, 1.05 * top))
    ax_a.legend(fontsize=8)
    fig.tight_layout()
    return fig


def figure_two_surfaces(results):
    """Seed Fig 2: two rough surfaces (eta = 0 solid, +1 dotted, -1 asterisks), substrate-only for reference."""
    ds = results["base"]["adhesion"]
    fig, ax_a, ax_b = _axes("Two rough surfaces (seed Fig. 2)")
    styles = {0.0: "-", 1.0: ":", -1.0: "*-"}
    for label, d in _per_model(ds):
        suffix = f" ({label})" if "model" in ds.dims else ""
        if "eta" in d.dims:
            for e in d["eta"].values:
                _curve(ax_a, ax_b, d.sel(eta=e), f"eta = {e:+g}{suffix}", styles.get(float(e), "--"),
                       level=band_level(results))
        else:
            _curve(ax_a, ax_b, d, f"pair{suffix}", "-", level=band_level(results))
    if "substrate_only" in results:
        for label, d in _per_model(results["substrate_only"]["adhesion"]):
            _curve(ax_a, ax_b, d, "substrate only" + (f" ({label})" if "model" in ds.dims else ""), "--", color="0.6")
    ax_a.set_ylim(0, 1.02 * max(1.0, float(ds["gamma_eff_macroscopic"].max() / ds["delta_gamma"])))
    ax_a.legend(fontsize=8)
    fig.tight_layout()
    return fig
