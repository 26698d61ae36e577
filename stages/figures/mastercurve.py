"""Figure of the modulus stage's dma source: the DMA sweeps shifted onto the master curve at T_ref
(left) and the shift factors a_T(T) with the fitted WLF law (right)."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.viscoelastic import prony_modulus, wlf_arrhenius_log10_shift, wlf_log10_shift

from .common import legend_outside


def figure_master_curve(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["modulus"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11.0, 5.0), layout="constrained")
    T_pts = ds["dma_temperature"].values
    temps = ds["shift_T"].values
    cmap = plt.get_cmap("coolwarm")
    shade = lambda T: cmap((T - temps.min()) / max(np.ptp(temps), 1e-9))  # noqa: E731
    w = ds["dma_reduced_omega"].values
    for T in temps:
        mine = np.isclose(T_pts, T)
        c = shade(T)
        left.loglog(w[mine], ds["dma_storage_modulus"].values[mine], "o", ms=3.5, color=c)
        left.loglog(w[mine], ds["dma_loss_modulus"].values[mine], "^", ms=3.5, mfc="none", color=c)
    grid = np.geomspace(w.min() / 3, w.max() * 3, 400)  # the fitted spectrum, just beyond the data
    Ep, Epp = prony_modulus(grid, float(ds["relaxed_modulus"]), ds["relaxation_strength"].values,
                            ds["relaxation_time"].values)
    left.loglog(grid, Ep, "k-", lw=1.2, label="E' master curve (fitted spectrum)")
    left.loglog(grid, Epp, "k--", lw=1.2, label="E'' master curve")
    T_ref = float(ds["reference_temperature"])
    left.set_xlabel(f"reduced angular frequency omega a_T (rad/s), T_ref = {T_ref - 273.15:.4g} °C")
    left.set_ylabel("E' (circles), E'' (triangles) / b_T (Pa)")
    left.grid(True, which="major", alpha=0.3)
    scale = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(temps.min() - 273.15, temps.max() - 273.15))
    fig.colorbar(scale, ax=left, label="temperature of the sweep (°C)")  # a colour per sweep, not a legend entry
    C1, C2 = float(ds["wlf_C1"]), float(ds["wlf_C2"])
    T_line = np.linspace(temps.min() - 5, temps.max() + 5, 200)
    T_line = T_line[C2 + T_line - T_ref > 1.0]
    right.plot(temps - 273.15, ds["sweep_log10_aT"].values, "o", color="0.25", label="shift of each sweep")
    if "glass_transition_temperature" in ds:
        Tg, Ea = float(ds["glass_transition_temperature"]), float(ds["arrhenius_activation_energy"])
        T_line = np.linspace(temps.min() - 5, temps.max() + 5, 200)
        T_line = T_line[(T_line < Tg) | (C2 + T_line - T_ref > 1.0)]
        right.plot(T_line - 273.15, wlf_arrhenius_log10_shift(T_line, T_ref, C1, C2, Tg, Ea), "k-",
                   label=f"WLF: C1 = {C1:.4g}, C2 = {C2:.4g} K; Arrhenius below T_g = {Tg - 273.15:.4g} °C: "
                         f"E_a = {Ea / 1e3:.4g} kJ/mol")
        right.axvline(Tg - 273.15, color="0.6", lw=0.8, ls="--")
    else:
        right.plot(T_line - 273.15, wlf_log10_shift(T_line, T_ref, C1, C2), "k-",
                   label=f"WLF: C1 = {C1:.4g}, C2 = {C2:.4g} K")
    right.axvline(T_ref - 273.15, color="0.6", lw=0.8, ls=":")
    right.set_xlabel("temperature (°C)")
    right.set_ylabel("log10 a_T")
    right.grid(True, alpha=0.3)
    kk = ds["sweep_kk_deviation"].values
    fig.suptitle(f"Master curve from {temps.size} DMA sweeps (Kramers-Kronig deviation of E' at most "
                 f"{100 * kk.max():.2g} % rms)", fontsize=10)
    return legend_outside(fig, [left, right], below=True)
