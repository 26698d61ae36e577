"""Figures of the contact stage: seed Figs 3 (A/A0 against p/E*) and 4 (P(sigma)), at the
magnification the title names (the seed's zeta = 4 when the scene has it, else the largest)."""

from __future__ import annotations

import numpy as np

from roughcontact.stage import UserError

from .common import (
    CASE_STYLES,
    at_zeta,
    band_level,
    band_note,
    band_on,
    curve_cases,
    legend_outside,
    line_style,
    line_with_band,
    nominal,
    pick_zeta,
    q_reference,
    reduce_dims,
    scope_text,
    selected_etas,
    shade,
    zeta_text,
)


def _colour_map(ax, ds, E_star):
    """A/A0 over (p/E*, eta) of a long coherence sweep, as a colour map."""
    area = nominal(ds["contact_area_ratio"]).transpose("eta", "p")
    mesh = ax.pcolormesh(ds["p"].values / E_star, ds["eta"].values, area.values, shading="nearest",
                         cmap="viridis", vmin=0.0, vmax=1.0)
    ax.set_xscale("log")
    ax.set_xlabel("p / E*")
    ax.set_ylabel("coherence eta")
    ax.set_title(f"A / A0 over {ds.sizes['eta']} coherences", fontsize=9)
    ax.figure.colorbar(mesh, ax=ax, label="A / A0")


def figure_contact_area(results):
    """Seed Fig. 3: A/A0 against p/E*, one curve per case. A sweep of many coherences is shown as
    a colour map beside the seed's three cases; other sweep dimensions at their middle value."""
    import matplotlib.pyplot as plt

    base = results["base"]["contact"]
    zeta = pick_zeta(base)
    many = "eta" in base.dims and base.sizes["eta"] > len(selected_etas(base["eta"].values))
    fig, axes = plt.subplots(1, 2 if many else 1, figsize=(11.5 if many else 7.2, 4.4), layout="constrained",
                             squeeze=False)
    notes, level = set(), band_level(results)
    ax = axes[0][-1]
    ax.set_xscale("log")
    for case in curve_cases(results, "contact"):
        ds, note = reduce_dims(at_zeta(case.ds, zeta), ("p",), "contact_area_ratio")
        notes |= {note, band_note(results, ds)}
        p = np.atleast_1d(ds["p"].values) / float(nominal(ds["E_star"]))
        line_with_band(ax, p, ds["contact_area_ratio"], level, label=case.label, **line_style(case, p.size))
    ax.set_xlabel("p / E*")
    ax.set_ylabel("A / A0")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    if many:
        _colour_map(axes[0][0], reduce_dims(at_zeta(base, zeta), ("p",), "contact_area_ratio")[0],
                    float(nominal(base["E_star"])))
        ax.set_title("the seed's cases (nearest coherences)", fontsize=9)
    extra = "; ".join(sorted(n for n in notes if n))
    title = (f"Relative contact area (seed Fig. 3) at\n{scope_text(results, zeta)}"
             + (f"\n{extra}" if extra else ""))
    if many:
        fig.suptitle(title, fontsize=10)
    else:
        ax.set_title(title, fontsize=10)
    return legend_outside(fig, [ax], below=many)


def _pressures(reference, zeta):
    """Three pressures where the reference case's A/A0 is about 0.1, 0.3 and 0.6."""
    ref = nominal(reduce_dims(at_zeta(reference, zeta), ("p",), "contact_area_ratio")[0]["contact_area_ratio"])
    return sorted({float(ref["p"][int(np.argmin(np.abs(ref.values - a)))]) for a in (0.1, 0.3, 0.6)})


def figure_stress_distribution(results):
    """Seed Fig. 4: P(sigma) at three pressures (where the first case's A/A0 is about 0.1, 0.3
    and 0.6), one curve per case; a delta (no roughness: full contact) is a vertical line."""
    import matplotlib.pyplot as plt

    cases = curve_cases(results, "contact")
    base = results["base"]["contact"]
    if "stress_distribution" not in base:
        raise UserError("the scene does not ask for 'stress_distribution' (add it to outputs.variables)",
                        key="outputs.variables")
    zeta = pick_zeta(base)
    E_star = float(nominal(base["E_star"]))
    picks, level = _pressures(cases[0].ds, zeta), band_level(results)
    fig, axes = plt.subplots(1, len(picks), figsize=(3.6 * len(picks) + 2.2, 3.8), squeeze=False, layout="constrained")
    for ax, p in zip(axes[0], picks, strict=True):
        right = 0.0
        for case in cases:
            ds = reduce_dims(at_zeta(case.ds, zeta), ("p", "stress_level"), "stress_distribution")[0]
            draws = ds["stress_distribution"].sel(p=p, method="nearest")
            d, G = nominal(draws), float(nominal(ds["G"]))
            kw = dict(color=case.style["color"], linestyle=case.style["linestyle"])
            if G > 0:
                sigma = d["sigma"].values / E_star
                ax.plot(sigma, d.values * E_star, label=case.label, marker=case.style["marker"],
                        markevery=max(1, sigma.size // 10), markersize=4, **kw)
                right = max(right, (p + 5.0 * np.sqrt(G)) / E_star)
                if "draw" in draws.dims:
                    lo, hi = band_on(d["sigma"].values, draws["sigma"].values, draws.values, level)
                    shade(ax, sigma, lo * E_star, hi * E_star, kw["color"])
            else:
                ax.axvline(p / E_star, label=f"{case.label} (full contact: a delta at p)", **kw)
        ax.set_xlim(0, right or 2 * p / E_star)
        ax.set_xlabel("sigma / E*")
        ax.set_title(f"p / E* = {p / E_star:.3g}", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("P(sigma) E*")
    note = band_note(results, base)
    fig.suptitle(f"Stress distribution (seed Fig. 4) at {scope_text(results, zeta)}"
                 + (f"\n{note}" if note else ""), fontsize=10)
    return legend_outside(fig, list(axes[0]), below=True)



def _plastic_zetas(ds) -> list:
    """The magnifications of the elastoplastic figure: all of them up to three (the smallest,
    a middle one and the largest of more), or [None] without zeta."""
    if "zeta" not in ds.coords:
        return [None]
    values = np.atleast_1d(ds["zeta"].values)
    picks = values if values.size <= 3 else values[[0, values.size // 2, -1]]
    return [float(z) for z in picks]


def figure_elastoplastic_area(results):
    """A_el/A0 (solid) and A_pl/A0 (dashed) against p, one panel per magnification (up to three:
    Persson's picture of contact that looks elastic at low magnification and has yielded at
    high), one colour per case; beside them the elastic solid's A/A0 (eq 19, dotted) and the
    limit p / sigma_Y that A_pl reaches when every asperity has yielded."""
    import matplotlib.pyplot as plt

    base = results["base"]["contact"]
    Y = float(base["plastic_contact_area_ratio"].attrs["yield_stress_Pa"])
    zetas = _plastic_zetas(base)
    fig, axes = plt.subplots(1, len(zetas), figsize=(3.9 * len(zetas) + 1.0, 4.4), layout="constrained",
                             sharey=True, squeeze=False)
    notes, cases = set(), curve_cases(results, "contact")
    spare = iter(["C1", "C4", "C5", "C6", "C8", "C9"] * 3)  # other coherences: one colour each
    colours = [case.style["color"] if case.label in CASE_STYLES else next(spare) for case in cases]
    for ax, zeta in zip(axes[0], zetas, strict=True):
        p = None
        for i, case in enumerate(cases):
            ds, note = reduce_dims(at_zeta(case.ds, zeta), ("p",), "plastic_contact_area_ratio")
            notes.add(note)
            ds = nominal(ds)
            p = np.atleast_1d(ds["p"].values)
            colour = colours[i]
            ax.plot(p / 1e6, ds["elastic_contact_area_ratio"].values, color=colour, lw=1.8,
                    label=f"A_el / A0, {case.label}")
            ax.plot(p / 1e6, ds["plastic_contact_area_ratio"].values, color=colour, lw=1.8, ls="--",
                    label=f"A_pl / A0, {case.label}")
            ax.plot(p / 1e6, ds["contact_area_ratio"].values, color=colour, lw=0.9, ls=":",
                    label=f"A / A0 elastic solid (eq 19), {case.label}")
        ax.plot(p / 1e6, np.minimum(p / Y, 1.0), color="0.4", lw=1.0, ls="-.", label="p / sigma_Y (all yielded)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(1e-5, 1.5)
        ax.set_xlabel("nominal pressure p (MPa)")
        ax.grid(alpha=0.3, which="both", lw=0.4)
        ax.set_title(zeta_text(zeta, q_reference(results)).replace(" (q up", "\n(q up"), fontsize=9)
    axes[0][0].set_ylabel("relative contact area")
    extra = "; ".join(sorted(n for n in notes if n))
    fig.suptitle(f"Elastic (solid) and plastic (dashed) contact area, penetration hardness sigma_Y = "
                 f"{Y / 1e9:.3g} GPa" + (f"\n{extra}" if extra else ""), fontsize=10)
    return legend_outside(fig, list(axes[0]), below=True)
