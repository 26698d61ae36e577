"""Figure of the modulus stage: E'(f), E''(f) at each temperature (seed Fig. 7)."""

from __future__ import annotations

import numpy as np

from .common import legend_outside


def figure_modulus(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["modulus"]
    fig, ax = plt.subplots(figsize=(7.6, 4.3), layout="constrained")
    f = ds["omega"].values / (2.0 * np.pi)
    temps = np.atleast_1d(ds["T"].values)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, T in enumerate(temps):
        sel = ds.sel(T=T) if "T" in ds.dims else ds
        c = colors[k % len(colors)]
        label = f"T = {T - 273.15:.4g} °C"
        ax.loglog(f, sel["storage_modulus"].values, "-", color=c, label=f"E'  ({label})")
        ax.loglog(f, sel["loss_modulus"].values, "--", color=c, label=f"E'' ({label})")
    ax.set_xlabel("frequency f = omega / 2 pi (Hz)")
    ax.set_ylabel("modulus (Pa)")
    model = ds.attrs.get("model", "")
    ax.set_title(f"Viscoelastic modulus ({model}; cf. seed Fig. 7)")
    top = float(np.nanmax(ds["loss_modulus"].values))
    if top > 0:
        ax.set_ylim(bottom=max(ax.get_ylim()[0], 1e-3 * top))
    ax.grid(True, which="major", alpha=0.3)
    return legend_outside(fig)
