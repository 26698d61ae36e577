"""Figure of the modulus stage's dma source: the DMA sweeps shifted onto the master curve at T_ref
(left) and the shift factors a_T(T) with the fitted WLF law (right)."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.viscoelastic import prony_modulus, wlf_log10_shift


def figure_master_curve(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["modulus"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11.0, 4.5))
    T_pts = ds["dma_temperature"].values
    temps = ds["shift_T"].values
    cmap = plt.get_cmap("coolwarm")
    shade = lambda T: cmap((T - temps.min()) / max(np.ptp(temps), 1e-9))  # noqa: E731
    w = ds["dma_reduced_omega"].values
    for T in temps:
        mine = np.isclose(T_pts, T)
        c = shade(T)
        left.loglog(w[mine], ds["dma_storage_modulus"].values[mine], "o", ms=3.5, color=c, label=f"{T - 273.15:.1f} °C")
        left.loglog(w[mine], ds["dma_loss_modulus"].values[mine], "^", ms=3.5, mfc="none", color=c)
    grid = np.geomspace(w.min() / 3, w.max() * 3, 400)  # the fitted spectrum, just beyond the data
    Ep, Epp = prony_modulus(grid, float(ds["relaxed_modulus"]), ds["relaxation_strength"].values,
                            ds["relaxation_time"].values)
    left.loglog(grid, Ep, "k-", lw=1.2, label="E' master curve (fitted spectrum)")
    left.loglog(grid, Epp, "k--", lw=1.2, label="E'' master curve")
    T_ref = float(ds["reference_temperature"])
    left.set_xlabel(f"reduced angular frequency omega a_T (rad/s), T_ref = {T_ref - 273.15:.4g} °C")
    left.set_ylabel("E' (circles), E'' (triangles) / b_T (Pa)")
    left.legend(fontsize=7, ncol=2)
    left.grid(True, which="major", alpha=0.3)
    C1, C2 = float(ds["wlf_C1"]), float(ds["wlf_C2"])
    T_line = np.linspace(temps.min() - 5, temps.max() + 5, 200)
    T_line = T_line[C2 + T_line - T_ref > 1.0]
    right.plot(temps - 273.15, ds["sweep_log10_aT"].values, "o", color="C3", label="shift of each sweep")
    right.plot(T_line - 273.15, wlf_log10_shift(T_line, T_ref, C1, C2), "k-",
               label=f"WLF: C1 = {C1:.4g}, C2 = {C2:.4g} K")
    right.axvline(T_ref - 273.15, color="0.6", lw=0.8, ls=":")
    right.set_xlabel("temperature (°C)")
    right.set_ylabel("log10 a_T")
    right.legend(fontsize=8)
    right.grid(True, alpha=0.3)
    kk = ds["sweep_kk_deviation"].values
    fig.suptitle(f"Master curve from {temps.size} DMA sweeps (Kramers-Kronig deviation of E' at most "
                 f"{100 * kk.max():.2g} % rms)", fontsize=10)
    fig.tight_layout()
    return fig
