"""Figure of the friction stage's flash-temperature option: mu(v) with and without the flash
temperature (left) and the temperature rise of the contacts at the highest magnification (right)."""

from __future__ import annotations

import numpy as np


def _select(da, eta):
    """The curve over v for one eta (every other dimension at its first value) and a note."""
    notes = []
    if "eta" in da.dims:
        da = da.isel(eta=int(np.argmin(np.abs(da["eta"].values - eta))))
    for dim in [d for d in da.dims if d != "v"]:
        value = da[dim].values[0]
        notes.append(f"{dim} = {value - 273.15:.4g} °C" if dim == "T" else f"{dim} = {value:.4g}")
        da = da.isel({dim: 0})
    return da, ", ".join(notes)


def figure_flash(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["friction"]
    etas = ds["eta"].values if "eta" in ds.dims else [0.0]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(10.0, 4.3))
    notes = set()
    T0 = ds["T"] if "T" in ds.coords else None
    for k, eta in enumerate(etas):
        c = colors[k % len(colors)]
        label = f"eta = {eta:g}" if "eta" in ds.dims else "as in the scene"
        mu, note = _select(ds["friction_coefficient"], eta)
        iso, _ = _select(ds["friction_coefficient_isothermal"], eta)
        flash, _ = _select(ds["flash_temperature"], eta)
        notes.add(note)
        v = mu["v"].values
        left.semilogx(v, iso.values, "--", color=c, label=f"{label}, isothermal")
        left.semilogx(v, mu.values, "-", color=c, label=f"{label}, flash temperature")
        base = _select(T0.broadcast_like(ds["flash_temperature"]), eta)[0].values if T0 is not None else 0.0
        right.loglog(v, np.maximum(flash.values - base, 1e-6), "-", color=c, label=label)
        if "background_temperature_rise" in ds:
            rise, _ = _select(ds["background_temperature_rise"], eta)
            right.loglog(v, np.maximum(rise.values, 1e-6), ":", color=c, label=f"{label}, background")
    left.set_xlabel("sliding velocity v (m/s)")
    left.set_ylabel("friction coefficient mu")
    left.set_ylim(bottom=0)
    left.legend(fontsize=7)
    right.set_xlabel("sliding velocity v (m/s)")
    right.set_ylabel("temperature rise of the contacts at q1 (K)")
    right.set_ylim(bottom=1e-3)
    right.legend(fontsize=7)
    for ax in (left, right):
        ax.grid(True, which="major", alpha=0.3)
    if T0 is not None and T0.ndim == 0:
        notes.add(f"T = {float(T0) - 273.15:.4g} °C")
    note = "; ".join(sorted(n for n in notes if n))
    fig.suptitle("Flash temperature (Persson 2006)" + (f" ({note})" if note else ""), fontsize=10)
    fig.tight_layout()
    return fig
