"""Figure of the fit stage: each fitted surface's measured bins with their error bars, the fitted
self-affine PSD over them, and the weighted residuals."""

from __future__ import annotations

import json

import numpy as np

SURFACE_COLOURS = {"substrate": "C0", "solid": "C3"}


def _label(ds, name: str) -> str:
    """The fitted parameters with their intervals, for the legend."""
    H = ds[f"hurst_fit_{name}"]
    h = ds[f"hrms_fit_{name}"]
    pct = round(100 * float(H.attrs["ci_level"]))
    text = f"{name} fit: H = {float(H):.3f} [{H.attrs['ci_low']:.3f}, {H.attrs['ci_high']:.3f}]"
    text += f", hrms = {float(h) * 1e9:.3g} nm [{h.attrs['ci_low'] * 1e9:.3g}, {h.attrs['ci_high'] * 1e9:.3g}]"
    q0 = ds[f"q0_fit_{name}"]
    text += f", q0 = {float(q0):.3g} 1/m" + ("" if "ci_low" in q0.attrs else " (no roll-off resolved)")
    return text + f" ({pct} % intervals)"


def figure_fit(results):
    """Measured bins (error bars: one standard error, where known), the fitted PSD drawn over the
    fitted band, and below the residuals (data - fit) / sigma in log C with the +-2 lines."""
    import matplotlib.pyplot as plt

    ds = results["base"]["fit"]
    names = [n for n in SURFACE_COLOURS if f"hurst_fit_{n}" in ds]
    if not names:
        return None
    fig, (ax, res) = plt.subplots(2, 1, figsize=(9.0, 6.4), sharex=True, height_ratios=(3, 1), layout="constrained")
    for name in names:
        colour = SURFACE_COLOURS[name]
        q = ds[f"q_fit_{name}"].values
        C, err = ds[f"psd_fit_data_{name}"].values, ds[f"psd_fit_data_error_{name}"].values
        known = np.isfinite(err).any()
        if known:  # bars of one standard error of ln C (the fit's weights), symmetric on the log axis
            factor = np.exp(err / C)
            ax.errorbar(q, C, yerr=(C - C / factor, C * factor - C), fmt="o", ms=3, color=colour, elinewidth=0.8,
                        capsize=0, label=f"{name}: measured bins (bars: C exp(+-s.e./C))")
        else:
            ax.loglog(q, C, "o", ms=3, color=colour, label=f"{name}: PSD file (no errors known)")
        band = json.loads(ds.attrs[f"fit_{name}"])["band_per_m"]
        grid = np.geomspace(band[0], band[1], 400)
        H, C0, q0 = (float(ds[f"{v}_fit_{name}"]) for v in ("hurst", "C0", "q0"))
        model = C0 * np.where(grid < q0, 1.0, (np.maximum(grid, q0) / q0) ** (-2 * (1 + H)))
        ax.loglog(grid, model, "-", color="k" if len(names) == 1 else colour, lw=1.4, label=_label(ds, name))
        res.semilogx(q, ds[f"fit_residual_{name}"].values, "o", ms=3, color=colour)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel("C(q) (m$^4$, Persson convention)")
    ax.set_title("Self-affine fits of the measured spectra\n(fitted in log C, the bias of few-mode bins removed: "
                 "those scatter below the fit)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    for y in (-2, 2):
        res.axhline(y, color="0.5", lw=0.8, ls="--")
    res.axhline(0, color="k", lw=0.6)
    res.set_ylabel("(data - fit) / s.e.\nin log C")
    res.set_xlabel("wavenumber q (1/m)")
    res.grid(True, which="both", alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", fontsize=8, ncol=1)
    return fig
