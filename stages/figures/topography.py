"""Figures of the topography stage: the measured PSDs and the measured coherence."""

from __future__ import annotations

import numpy as np


def _finish(fig, ax, ylabel, title):
    """Axis labels, title, grid and legend of a spectrum-like figure over q."""
    ax.set_xlabel("wavenumber q (1/m)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def figure_measured_psd(results):
    """The measured PSD bins of each surface with a band of two standard errors, and the psd
    stage's interpolation on its q grid when it has run."""
    import matplotlib.pyplot as plt

    ds = results["base"]["topography"]
    fig, ax = plt.subplots(figsize=(6.4, 4.6), constrained_layout=True)
    for name, colour in (("substrate", "C0"), ("solid", "C3")):
        var = f"psd_{name}_measured"
        if var not in ds:
            continue
        q, C, e = ds[f"q_{name}_measured"].values, ds[var].values, ds[f"{var}_error"].values
        ok = np.isfinite(C) & (C > 0)
        band = np.exp(2 * e[ok] / C[ok])  # +-2 s.e. in log space (the relative error is what matters on log axes)
        ax.fill_between(q[ok], C[ok] / band, C[ok] * band, color=colour, alpha=0.25, lw=0)
        ax.loglog(q[ok], C[ok], "o", color=colour, ms=2.5, label=f"{name}: measured bins (band: 2 s.e.)")
        if "psd" in results["base"]:
            p = results["base"]["psd"]
            grid = p[f"psd_{name}"].isel(draw=0) if "draw" in p[f"psd_{name}"].dims else p[f"psd_{name}"]
            ax.loglog(p["q"].values, grid.values, "-", color=colour, lw=0.8, label=f"{name}: on the psd stage's q grid")
    return _finish(fig, ax, "C(q) (m$^4$, Persson convention)", "Measured power spectral densities")


def figure_coherence(results):
    """The measured coherence eta(q) with a band of two standard errors (a note when the
    surfaces are not paired)."""
    import matplotlib.pyplot as plt

    ds = results["base"]["topography"]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), constrained_layout=True)
    if "coherence" not in ds:
        ax.text(0.5, 0.5, "no paired topographies: coherence not measured", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    q, eta, e = ds["q_substrate_measured"].values, ds["coherence"].values, ds["coherence_error"].values
    ok = np.isfinite(eta)
    ax.fill_between(q[ok], eta[ok] - 2 * e[ok], eta[ok] + 2 * e[ok], color="C2", alpha=0.25, lw=0, label="2 s.e.")
    ax.semilogx(q[ok], eta[ok], "o-", color="C2", ms=2.5, lw=1, label="eta(q) = Re C12 / sqrt(C11 C22)")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylim(-1.05, 1.05)
    return _finish(fig, ax, "coherence eta", "Measured coherence of the two surfaces")
