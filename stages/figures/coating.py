"""Figures of a coated solid (``[material] coating_thickness``): the surface modulus E_eff(q) with
the stress scale sqrt(G) it gives, and A/A0 against p, one curve per variant (coating thickness d,
the bare substrate, the bulk coating material). Drawn only when some variant has a coating."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.layered import modulus_weight
from roughcontact.stage import readable

from .common import legend_outside


def _solids(results) -> list[tuple[str, str, dict, object]]:
    """(variant, label, style, contact result) of every variant with a contact result, ordered from
    the stiffest homogeneous solid through the coatings (thin to thick) to the softer homogeneous ones;
    [] when no variant is coated."""
    rows = [(v, res["contact"]) for v, res in results.items() if "contact" in res]
    coated = [(v, ds) for v, ds in rows if "coating_thickness_m" in ds.attrs]
    if not coated:
        return []
    top = max(float(ds["E_star"]) for _, ds in coated)  # the coated parts' substrate E*
    cmap = __import__("matplotlib").colormaps["viridis"]
    coated.sort(key=lambda r: float(r[1].attrs["coating_thickness_m"]))
    out = []
    for i, (v, ds) in enumerate(coated):
        d = float(ds.attrs["coating_thickness_m"])
        colour = cmap(0.1 + 0.75 * i / max(len(coated) - 1, 1))
        out.append((v, f"coating d = {readable(d, 'm')}", dict(color=colour, lw=1.8, ls="-"), ds))
    plain = [(v, ds) for v, ds in rows if "coating_thickness_m" not in ds.attrs]
    for v, ds in sorted(plain, key=lambda r: -float(r[1]["E_star"])):
        E = float(ds["E_star"])
        stiff = E >= top * (1 - 1e-9)
        style = dict(color="0.15" if stiff else "0.55", lw=1.4, ls="--")
        row = (v, f"{_named(v)}no coating, E* = {readable(E, 'Pa')}", style, ds)
        if stiff:
            out.insert(0, row)
        else:
            out.append(row)
    return out


def _named(variant: str) -> str:
    """'bare steel: ' for a variant, '' for the base scene."""
    return "" if variant == "base" else f"{variant.replace('_', ' ')}: "


def _near_zero_eta(da):
    """``da`` at the coherence nearest 0 when it has an eta dimension, and a note saying which."""
    if "eta" not in da.dims:
        return da, ""
    eta = float(da["eta"].values[np.argmin(np.abs(da["eta"].values))])
    return da.sel(eta=eta), f"eta = {eta:g}"


def figure_coating_modulus(results):
    """(a) E_eff(q) of every coated variant against q (log-log), the bare substrate's and the coating's
    E* dotted, a dot at q = 1/d (the crossover), the q grid of the roughness shaded, wavelength 2 pi/q
    on the top axis; (b) sqrt(G(zeta)) against q = zeta qL, the stress scale of contact (A/A0 ~
    p / sqrt(pi G) at low load) of every variant."""
    import matplotlib.pyplot as plt

    solids = _solids(results)
    if not solids:
        return None
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11.0, 4.6), layout="constrained")
    q_grid = [float(results[v]["psd"]["q"].values[k]) for v, *_ in solids if "psd" in results[v] for k in (0, -1)]
    lo, hi = (min(q_grid), max(q_grid)) if q_grid else (None, None)
    coated = [(v, label, st, ds) for v, label, st, ds in solids if "coating_thickness_m" in ds.attrs]
    d_all = [float(ds.attrs["coating_thickness_m"]) for *_, ds in coated]
    q = np.geomspace(min([lo or np.inf] + [0.01 / d for d in d_all]),
                     max([hi or 0.0] + [100.0 / d for d in d_all]), 400)
    levels = {}
    for _, label, st, ds in coated:
        a = ds.attrs
        d, E_l, nu_l = float(a["coating_thickness_m"]), float(a["coating_E_Pa"]), float(a["coating_nu"])
        E_s = float(ds["E_star"])
        E_sub, nu_sub = float(a["substrate_E_Pa"]), float(a["substrate_nu"])
        layer = (d, E_l, nu_l, E_sub, nu_sub)
        ax.plot(q, E_s * modulus_weight(q, layer) / 1e9, label=label, **st)  # E_eff = E*_s (E_eff / E*_s)
        ax.plot([1 / d], [E_s * float(modulus_weight(1 / d, layer)) / 1e9], "o", color=st["color"], ms=5, label="_")
        levels[f"substrate E* = {readable(E_s, 'Pa')}"] = E_s
        E_top = E_s * float(modulus_weight(1e6 / d, layer))  # q d = 1e6: the coating's own E*
        levels[f"coating E* = {readable(E_top, 'Pa')}"] = E_top
    for (text, E), ls in zip(levels.items(), (":", "-."), strict=False):
        ax.axhline(E / 1e9, color="0.4", lw=0.9, ls=ls)
        ax.annotate(text, (q[0], E / 1e9), xytext=(4, 3), textcoords="offset points", fontsize=8, color="0.3")
    if lo is not None:
        ax.axvspan(lo, hi, color="0.9", zorder=0, label="q grid of the roughness")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(q[0], q[-1])
    ax.set_xlabel("wavenumber q (1/m)")
    ax.set_ylabel("surface modulus E_eff(q) (GPa)")
    ax.set_title("(a) E_eff(q) of the coated solid (dot: q = 1/d)", fontsize=9)
    top = ax.secondary_xaxis("top", functions=(lambda x: 2 * np.pi / np.maximum(x, 1e-300) * 1e6,
                                                lambda w: 2 * np.pi / np.maximum(w, 1e-300) * 1e6))
    top.set_xlabel("wavelength 2 pi / q (um)", fontsize=8)
    ax.grid(alpha=0.3, which="both", lw=0.4)
    notes = set()
    for _, label, st, ds in solids:
        G, note = _near_zero_eta(ds["G"])
        notes.add(note)
        qz = ds["zeta"].values * float(ds["qL"])
        bx.plot(qz, np.sqrt(np.maximum(G.values, 0.0)) / 1e6, label=label, **st,
                marker="o" if qz.size < 8 else None, ms=4)
    bx.set_xscale("log")
    bx.set_yscale("log")
    bx.set_xlabel("magnification q = zeta qL (1/m)")
    bx.set_ylabel("sqrt(G) (MPa)")
    bx.set_title("(b) stress scale sqrt(G(zeta)), G = (pi/4) int q^3 C E_eff^2 dq" +
                 (f" ({', '.join(sorted(n for n in notes if n))})" if any(notes) else ""), fontsize=9)
    bx.grid(alpha=0.3, which="both", lw=0.4)
    fig.suptitle("Coated solid: a soft coating lowers the modulus at wavelengths shorter than its thickness",
                 fontsize=10)
    return legend_outside(fig, [ax, bx], below=True)


def figure_coating_area(results):
    """A/A0 against p (log-log) at the largest magnification, one curve per variant: the bare
    substrate and the bulk coating material dashed, the coatings by thickness in between."""
    import matplotlib.pyplot as plt

    solids = _solids(results)
    if not solids:
        return None
    fig, ax = plt.subplots(figsize=(7.6, 4.8), layout="constrained")
    notes, zetas = set(), set()
    for _, label, st, ds in solids:
        zeta = float(ds["zeta"].values.max())
        zetas.add((zeta, float(ds["qL"])))
        area, note = _near_zero_eta(ds["contact_area_ratio"].sel(zeta=zeta))
        notes.add(note)
        p = np.atleast_1d(area["p"].values)
        ax.plot(p / 1e6, np.atleast_1d(area.transpose("p", ...).values), label=label, **st)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(top=1.5)
    ax.set_xlabel("nominal pressure p (MPa)")
    ax.set_ylabel("relative contact area A / A0")
    ax.grid(alpha=0.3, which="both", lw=0.4)
    scope = "; ".join(f"q up to {readable(z * qL, '1/m')}" for z, qL in sorted(zetas))
    extra = ", ".join(sorted(n for n in notes if n))
    ax.set_title(f"Contact area of the coated solid, {scope}" + (f", {extra}" if extra else ""), fontsize=9)
    return legend_outside(fig, [ax])
