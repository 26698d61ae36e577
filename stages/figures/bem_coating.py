"""Figure of the exact check of coated solids (the ``bem`` stage with ``[material] coating_*`` in
several variants, e.g. the coating_bem scene): A/A0 of the theory with E_eff(q) and of the BEM with
the layered kernel, and their ratio, against the coating thickness d qL, a soft layer on a stiff
substrate and a stiff layer on a soft one side by side. Drawn only when some variant's bem result
is coated."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import readable


def _rows(results):
    """(case, d qL, bem result) of every coated variant, case "soft" (layer softer than the
    substrate) or "stiff"; and (E*, bem result) of the homogeneous variants (the half-spaces)."""
    coated, plain = [], []
    for res in results.values():
        ds = res.get("bem")
        if ds is None:
            continue
        if "coating_thickness_m" not in ds.attrs:
            plain.append((float(ds["E_star"]), ds))
            continue
        a = ds.attrs
        qL = 2 * np.pi / float(ds["bem_system_size"])
        case = "soft" if float(a["coating_E_Pa"]) < float(a["substrate_E_Pa"]) else "stiff"
        coated.append((case, float(a["coating_thickness_m"]) * qL, ds))
    return coated, plain


def _pressure_axis(da):
    """``da`` with a p dimension and no eta (the coherence nearest 0)."""
    if "eta" in da.dims:
        da = da.isel(eta=int(np.argmin(np.abs(da["eta"].values))))
    return da if "p" in da.dims else da.expand_dims("p")


def _half_space(plain, E_star):
    """The homogeneous variant of modulus E_star (Pa), or None."""
    hits = [ds for E, ds in plain if np.isclose(E, E_star, rtol=1e-6)]
    return hits[0] if hits else None


def figure_bem_coating(results):
    """Top: A/A0 against d qL, theory with E_eff(q) (lines) and the layered-kernel BEM (markers, +-
    one standard deviation over realizations), one colour per pressure; the two half-spaces the
    coating tends to (d -> 0: the substrate, d -> infinity: the layer) as short dashed (BEM) and
    dotted (theory) bars at the ends when the scene has them. Bottom: theory / BEM, error bars the
    standard error of the BEM's mean over realizations. Left: soft layer on a stiff substrate;
    right: stiff layer on a soft substrate."""
    import matplotlib.pyplot as plt

    coated, plain = _rows(results)
    if not coated:
        return None
    cases = [c for c in ("soft", "stiff") if any(r[0] == c for r in coated)]
    fig, axes = plt.subplots(2, len(cases), figsize=(5.6 * len(cases) + 1.0, 7.6), layout="constrained",
                             squeeze=False, sharex="col")
    colours = plt.colormaps["viridis"]
    zetas, grids, reps = set(), set(), set()
    labels = {}  # pressure -> colour
    for col, case in enumerate(cases):
        rows = sorted((r for r in coated if r[0] == case), key=lambda r: r[1])
        x = np.array([r[1] for r in rows])
        first = rows[0][2]
        a = first.attrs
        E_layer = float(a["coating_E_Pa"]) / (1 - float(a["coating_nu"]) ** 2)
        E_sub = float(first["E_star"])
        p = _pressure_axis(first["bem_contact_area_ratio_mean"])["p"].values
        top, bottom = axes[0, col], axes[1, col]
        for i, pi in enumerate(p):
            colour = colours(0.1 + 0.75 * i / max(len(p) - 1, 1))
            label = f"p = {readable(pi, 'Pa')}"
            get = {k: np.array([float(_pressure_axis(r[2][k]).isel(p=i)) for r in rows])
                   for k in ("theory_contact_area_ratio", "bem_contact_area_ratio_mean", "bem_contact_area_ratio_std",
                             "area_ratio_theory_to_bem")}
            R = np.array([r[2].sizes.get("realization", 1) for r in rows])
            theory, mean, std = (get[k] for k in ("theory_contact_area_ratio", "bem_contact_area_ratio_mean",
                                                  "bem_contact_area_ratio_std"))
            labels.setdefault(label, colour)
            top.plot(x, theory, "-", color=colour, lw=1.5, label="_")
            top.errorbar(x, mean, yerr=std, fmt="o", color=colour, ms=5, capsize=2, label="_")
            ratio = get["area_ratio_theory_to_bem"]
            bottom.errorbar(x, ratio, yerr=ratio * std / mean / np.sqrt(R), fmt="o-", color=colour, ms=5, capsize=2,
                            label="_")
            for E, where in ((E_sub, 0), (E_layer, 1)):
                ds = _half_space(plain, E)
                if ds is None:
                    continue
                span = (x[0] / 2.5, x[0] / 1.3) if where == 0 else (x[-1] * 1.3, x[-1] * 2.5)
                h_bem = float(_pressure_axis(ds["bem_contact_area_ratio_mean"]).isel(p=i))
                h_th = float(_pressure_axis(ds["theory_contact_area_ratio"]).isel(p=i))
                top.plot(span, [h_bem] * 2, "--", color=colour, lw=2.0, label="_")
                top.plot(span, [h_th] * 2, ":", color=colour, lw=2.0, label="_")
                bottom.plot(span, [h_th / h_bem] * 2, "--", color=colour, lw=2.0, label="_")
        for ds in (r[2] for r in rows):
            zetas.add(float(ds["bem_zeta"]))
            grids.add(int(ds["bem_grid"]))
            reps.add(ds.sizes.get("realization", 1))
        kind = ("soft layer on a stiff substrate" if case == "soft" else "stiff layer on a soft substrate")
        top.set_title(f"{kind}: E*_layer = {readable(E_layer, 'Pa')}, E*_substrate = {readable(E_sub, 'Pa')}",
                      fontsize=9)
        top.set_yscale("log")
        top.set_ylabel("relative contact area A / A0")
        bottom.axhline(1.0, color="0.5", lw=0.8)
        bottom.set_ylabel("A/A0: theory / BEM")
        bottom.set_xlabel("coating thickness d qL")
        bottom.set_title("dashed bars: the half-spaces (left: substrate, d -> 0; right: layer, d -> infinity)",
                         fontsize=8)
        for ax in (top, bottom):
            ax.set_xscale("log")
            ax.grid(alpha=0.3, which="both", lw=0.4)
    zeta = f"{min(zetas):.4g}" if len(zetas) == 1 else ", ".join(f"{z:.4g}" for z in sorted(zetas))
    n = "/".join(str(g) for g in sorted(grids))
    R = "/".join(str(r) for r in sorted(reps))
    fig.suptitle(f"Coated solids: theory with E_eff(q) vs BEM with the layered kernel at zeta = {zeta} ({n}^2 map, "
                 f"{R} realizations; error bars: +-1 s.d. of A/A0, standard error of the ratio)", fontsize=10)
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, marker="o", ms=5, lw=1.5, label=text) for text, c in labels.items()]
    handles += [Line2D([], [], color="0.3", lw=1.5, label="theory with E_eff(q) (top: line)"),
                Line2D([], [], color="0.3", marker="o", ls="none", label="BEM, layered kernel (top: markers)")]
    if plain:
        handles += [Line2D([], [], color="0.3", ls="--", lw=2.0, label="half-space: BEM (top), theory / BEM (bottom)"),
                    Line2D([], [], color="0.3", ls=":", lw=2.0, label="half-space: theory (top)")]
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=min(len(handles), 4))
    return fig
