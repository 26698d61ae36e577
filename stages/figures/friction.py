"""Figures of the friction stage: the PSDs (seed Fig. 6), mu(v) and A/A0(v) for substrate-only
vs both rough (seed Figs 8, 9) and for correlated roughness eta = 0, +1, -1 (seed Figs 10, 11)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .common import (
    band_level,
    band_note,
    draw_band,
    eta_label,
    legend_outside,
    line_style,
    line_with_band,
    nominal,
    q_reference,
    wavenumber,
)


def _first(da: xr.DataArray, keep: tuple[str, ...]) -> tuple[xr.DataArray, str]:
    """Reduce every dimension but ``keep`` (and the spectrum draws) to its first value; say which in a note."""
    notes = []
    for dim in list(da.dims):
        if dim not in keep and dim != "draw":
            value = da[dim].values[0]
            notes.append(f"{dim} = {value:.4g}" if dim != "T" else f"T = {value - 273.15:.4g} °C")
            da = da.isel({dim: 0})
    return da, ", ".join(notes)


def _curves(results, which: str, etas: tuple[float, ...] | None):
    """(label, DataArray over v, note, case) for substrate-only (if etas is None) and the pair's
    eta values; ``case`` names the style of :data:`CASE_STYLES`."""
    out = []
    base = results["base"]["friction"]
    if etas is None:
        if "substrate_only" in results:
            da, note = _first(results["substrate_only"]["friction"][which], ("v",))
            out.append(("substrate only", da, note, "substrate only"))
        etas = (0.0,)
    for eta in etas:
        da = base[which]
        case = eta_label(eta)
        if "eta" in da.dims:
            hits = np.flatnonzero(np.isclose(da["eta"].values, eta))
            if not hits.size:
                continue
            da = da.isel(eta=int(hits[0]))
            label = f"both rough, {case}" + (" (uncorrelated)" if eta == 0 else "")
        else:
            label, case = "as in the scene", "pair"
        da, note = _first(da, ("v",))
        out.append((label, da, note, case))
    return out


def _friction_figure(results, which, etas, title, ylabel, logy=False):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.8, 4.3), layout="constrained")
    notes = set()
    ax.set_xscale("log")
    for label, da, note, case in _curves(results, which, etas):
        line_with_band(ax, da["v"].values, da, band_level(results), label=label,
                       **line_style(case, da.sizes["v"], markers=15))
        notes |= {n for n in (note, band_note(results, da)) if n}
    qL = q_reference(results)
    if qL:
        notes.add(f"q from qL = {wavenumber(qL)}")
    ax.set_xlabel("sliding velocity v (m/s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title + (f"\n({'; '.join(sorted(notes))})" if notes else ""), fontsize=10)
    if logy:
        ax.set_yscale("log")
    else:
        ax.set_ylim(bottom=0)
    ax.grid(True, which="both" if logy else "major", alpha=0.3)
    return legend_outside(fig)


def figure_mu_substrate(results):
    """Seed Fig. 8; None (no figure) without a substrate_only variant to compare with."""
    if "friction" not in results.get("substrate_only", {}):
        return None
    return _friction_figure(results, "friction_coefficient", None,
                            "Friction: substrate only vs both rough (seed Fig. 8)", "friction coefficient mu")


def figure_area_substrate(results):
    """Seed Fig. 9; None (no figure) without a substrate_only variant to compare with."""
    if "friction" not in results.get("substrate_only", {}):
        return None
    return _friction_figure(results, "sliding_contact_area_ratio", None,
                            "Contact area while sliding (seed Fig. 9)", "A / A0", logy=True)


def figure_mu_eta(results):
    return _friction_figure(results, "friction_coefficient", (0.0, 1.0, -1.0),
                            "Friction for correlated roughness (seed Fig. 10)", "friction coefficient mu")


def figure_area_eta(results):
    return _friction_figure(results, "sliding_contact_area_ratio", (0.0, 1.0, -1.0),
                            "Contact area for correlated roughness (seed Fig. 11)", "A / A0", logy=True)


def figure_psds(results):
    import matplotlib.pyplot as plt

    psd = results["base"]["psd"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2), layout="constrained")
    for ax, name, title in ((axes[0], "solid", "(a) elastic solid (rubber)"), (axes[1], "substrate", "(b) substrate")):
        draws, note = _first(psd[f"psd_{name}"], ("q",))
        da = nominal(draws)
        q = da["q"].values
        C = da.values
        mask = C > 0
        band = draw_band(draws, band_level(results))
        if band is not None and np.any(mask):
            ax.fill_between(q[mask], band[0][mask], band[1][mask], color="C0", alpha=0.25, lw=0,
                            label=band_note(results, draws))
        if not np.any(mask):
            ax.text(0.5, 0.5, "smooth", transform=ax.transAxes, ha="center")
        else:
            ax.loglog(q[mask], C[mask], "-", color="C0", label="C(q)")
            H = da.attrs.get("H")
            if H is not None:
                q0 = float(da.attrs.get("q0", q[mask][0]))
                ref = C[mask][np.searchsorted(q[mask], q0)] if q0 >= q[mask][0] else C[mask][0]
                qq = q[mask][q[mask] >= q0]
                ax.loglog(qq, 3.0 * ref * (qq / q0) ** (-2.0 * (1.0 + H)), "--", color="C1",
                          label="slope -2(1+H), shifted up")
            hrms = float(np.sqrt(2 * np.pi * np.trapezoid(q * np.where(mask, C, 0.0), q)))
            ax.set_title(f"{title}: hrms = {hrms * 1e6:.3g} um" + (f" ({note})" if note else ""), fontsize=10)
        ax.set_xlabel("wavenumber q (1/m)")
        ax.set_ylabel("C(q) (m^4)")
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"Power spectral densities (seed Fig. 6); q grid from qL = {wavenumber(psd['q'].values[0])}",
                 fontsize=10)
    return legend_outside(fig, below=True)
