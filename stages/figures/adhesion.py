"""Figures of the adhesion stage: seed Figs 1 (one rough surface) and 2 (two rough surfaces),
gamma_eff/Delta_gamma and A/A0 at zero load against the substrate's rms roughness."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import UserError

from .common import (
    DEFAULT_LEVEL,
    band_level,
    band_note,
    draw_band,
    eta_label,
    legend_outside,
    line_style,
    nominal,
    q_reference,
    style,
    wavenumber,
)

_ANGSTROM = 1e-10


def _per_model(ds):
    if "model" in ds.dims:
        return [(str(m), ds.sel(model=m)) for m in ds["model"].values]
    return [(str(ds["model"].values) if "model" in ds.coords else "", ds)]


def _curve(ax_a, ax_b, ds, label, kind, full=False, level=DEFAULT_LEVEL):
    """gamma_eff/Delta_gamma on ax_a and A/A0 on ax_b against the substrate hrms, closed at the
    vanishing hrms (a dotted line of the case's colour, its value in the legend) when the dataset
    has it. ``kind`` is the case (:data:`CASE_STYLES`) that sets colour, marker and line. With
    spectrum draws, the measured spectrum's curve and the band of the draws shaded."""
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
        label += f" (vanishes at {hv:.3f} Å)"
        order = np.argsort(np.append(h, hv), kind="stable")
        hp, gp, Ap = np.append(h, hv)[order], np.append(g, 0.0)[order], np.append(A, 0.0)[order]
        for ax in (ax_a, ax_b):
            ax.axvline(hv, color=style(kind)["color"], lw=0.8, ls=":")
    kw = dict(line_style(kind, hp.size, markers=10), label=label)
    ax_a.plot(hp, gp, **kw)
    ax_b.plot(hp, Ap, **kw)
    for ax, var, scale in ((ax_a, "gamma_eff_macroscopic", dg), (ax_b, "adhesive_contact_area_ratio", 1.0)):
        band = draw_band(draws[var], level)
        if band is not None:
            ax.fill_between(h, band[0] / scale, band[1] / scale, color=style(kind)["color"], alpha=0.22, lw=0)
    if full:
        ax_a.plot(h, ds["gamma_eff_full_contact"].values / dg, color=style(kind)["color"], linestyle=(0, (6, 2, 1, 2)),
                  linewidth=1.0, label="full contact")


def _axes(title):
    import matplotlib.pyplot as plt

    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(12.5, 4.2), layout="constrained")
    ax_a.set_ylabel("gamma_eff / Delta_gamma")
    ax_b.set_ylabel("A / A0 at zero load")
    for ax, tag in ((ax_a, "(a)"), (ax_b, "(b)")):
        ax.set_xlabel("rms roughness of the substrate (Å)")
        ax.set_title(tag, loc="left")
        ax.grid(alpha=0.3)
    ax_b.set_ylim(0, 1.02)
    fig.suptitle(title, fontsize=10)
    return fig, ax_a, ax_b


def _title(results, variant, what):
    qL, note = q_reference(results, variant), band_note(results, results[variant]["adhesion"])
    title = f"{what}: zero load, magnification from qL = {wavenumber(qL)} up to the surfaces' q1" if qL else what
    return title + (f"; {note}" if note else "")


def figure_one_surface(results):
    """Seed Fig 1: one rough surface, partial (solid) and full (dash-dot) contact theory."""
    variant = "substrate_only" if "substrate_only" in results else "base"
    ds = results[variant]["adhesion"]
    if "eta" in ds.dims:
        ds = ds.isel(eta=0)
    fig, ax_a, ax_b = _axes(_title(results, variant, "One rough surface (seed Fig. 1)"))
    for k, (label, d) in enumerate(_per_model(ds)):
        _curve(ax_a, ax_b, d, f"partial contact, {label} model" if label else "partial contact", "substrate only",
               full=(k == 0), level=band_level(results))
    top = float(ds["gamma_eff_full_contact"].max() / ds["delta_gamma"])
    ax_a.set_ylim(0, max(1.02, 1.05 * top))
    return legend_outside(fig, [ax_a], below=True)


def figure_two_surfaces(results):
    """Seed Fig 2: two rough surfaces (eta = 0, +1, -1), substrate-only for reference."""
    ds = results["base"]["adhesion"]
    fig, ax_a, ax_b = _axes(_title(results, "base", "Two rough surfaces (seed Fig. 2)"))
    for label, d in _per_model(ds):
        suffix = f" ({label})" if "model" in ds.dims else ""
        if "eta" in d.dims:
            for e in d["eta"].values:
                _curve(ax_a, ax_b, d.sel(eta=e), eta_label(e) + suffix, eta_label(e), level=band_level(results))
        else:
            _curve(ax_a, ax_b, d, f"pair{suffix}", "pair", level=band_level(results))
    if "substrate_only" in results:
        for label, d in _per_model(results["substrate_only"]["adhesion"]):
            _curve(ax_a, ax_b, d, "substrate only" + (f" ({label})" if "model" in ds.dims else ""), "substrate only")
    ax_a.set_ylim(0, 1.02 * max(1.0, float(ds["gamma_eff_macroscopic"].max() / ds["delta_gamma"])))
    return legend_outside(fig, [ax_a], below=True)
