"""What the stages' figures share: one style per case (colour, marker, line) across every figure,
the magnification a figure plots and its reference wavenumber, and legends kept off the data.

The cases of the seed's comparisons are the substrate alone and the pair with eta = 0, +1, -1;
:data:`CASE_STYLES` gives each its colour, marker and line, the same in every figure. Any other
single coherence (or a measured eta(q)) is drawn as :data:`OTHER_STYLE`; a sweep of more than a
few coherences is summarised (a colour map and the three seed cases) rather than drawn curve by
curve.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from roughcontact.stage import readable

#: colour, marker and line of each case, in every figure
CASE_STYLES = {
    "substrate only": dict(color="0.35", marker="s", linestyle="--"),
    "eta = 0": dict(color="C0", marker="o", linestyle="-"),
    "eta = +1": dict(color="C2", marker="^", linestyle=":"),
    "eta = -1": dict(color="C3", marker="v", linestyle="-."),
}
#: a pair with another coherence, or with the measured eta(q)
OTHER_STYLE = dict(color="C1", marker="D", linestyle="-")
#: sweeps of more coherences than this are summarised by a colour map and the seed's cases
MAX_CURVES = 5


class Case(NamedTuple):
    """One curve of a comparison figure: its legend label, its data and its style."""

    label: str
    ds: object
    style: dict


def eta_label(eta: float) -> str:
    """'eta = 0', 'eta = +1', 'eta = -0.5' (never 'eta = +0')."""
    eta = float(eta)
    return "eta = 0" if eta == 0 else f"eta = {eta:+.3g}"


def style(label: str) -> dict:
    """The style of a case label (see :data:`CASE_STYLES`)."""
    return dict(CASE_STYLES.get(label, OTHER_STYLE))


def line_style(label: str, npoints: int, markers: int = 12) -> dict:
    """Keyword arguments of ``Axes.plot`` for a case: its style, markers on about ``markers`` points."""
    out = style(label)
    out.update(markevery=max(1, npoints // markers), markersize=4)
    return out


def curve_cases(results, stage: str) -> list[Case]:
    """The curves of a seed-style comparison figure: the ``substrate_only`` variant if the scene
    has it, then one per coherence of the base scene (the seed's eta = -1, 0, +1 alone, or the
    nearest values, when it sweeps more than :data:`MAX_CURVES`), or one for the pair."""
    out = []
    if "substrate_only" in results and stage in results["substrate_only"]:
        out.append(Case("substrate only", results["substrate_only"][stage], style("substrate only")))
    base = results["base"][stage]
    if "eta" in base.dims:
        for e in selected_etas(base["eta"].values):
            out.append(Case(eta_label(e), base.sel(eta=e), style(eta_label(e))))
    else:
        label = "pair, measured eta(q)" if measured_pair(results) else "pair"
        out.append(Case(label, base, style(label)))
    return out


def selected_etas(values) -> list[float]:
    """All coherences of a short sweep; of a long one, the values nearest -1, 0 and +1."""
    values = np.atleast_1d(values)
    if values.size <= MAX_CURVES:
        return [float(v) for v in values]
    picks = [float(values[int(np.argmin(np.abs(values - target)))]) for target in (0.0, 1.0, -1.0)]
    return list(dict.fromkeys(picks))


def measured_pair(results) -> bool:
    """Whether the base scene's coherence is measured (eta(q) from paired maps)."""
    psd = results["base"].get("psd")
    return psd is not None and psd["psd_combined"].attrs.get("coherence") == "measured"


def pick_zeta(ds, prefer: float = 4.0) -> float | None:
    """The magnification a figure plots: the seed's ``prefer`` if the result has it, else the
    largest (the whole band); None when the result has no zeta."""
    if "zeta" not in ds.coords:
        return None
    values = np.atleast_1d(ds["zeta"].values)
    hit = values[np.isclose(values, prefer, rtol=1e-9)]
    return float(hit[0]) if hit.size else float(values.max())


def at_zeta(ds, zeta: float | None):
    """``ds`` at the magnification ``zeta`` (an exact node: see :func:`pick_zeta`)."""
    if zeta is None or "zeta" not in ds.dims:
        return ds
    return ds.isel(zeta=int(np.argmin(np.abs(ds["zeta"].values - zeta))))


def q_reference(results, variant: str = "base") -> float | None:
    """qL, the reference of zeta, of a variant's results (the lowest wavenumber of its q grid)."""
    res = results.get(variant, {})
    for stage in ("contact", "separation"):
        if stage in res and "qL" in res[stage]:
            return float(res[stage]["qL"])
    return float(res["psd"]["q"].values[0]) if "psd" in res else None


def wavenumber(q: float) -> str:
    """2e8 1/m as '2e8 1/m' (4 significant digits)."""
    return readable(q, "1/m")


def zeta_text(zeta: float | None, qL: float | None) -> str:
    """'zeta = 4 (q up to 8e8 1/m, qL = 2e8 1/m)': the magnification plotted and its reference."""
    if zeta is None:
        return f"qL = {wavenumber(qL)}" if qL else ""
    if qL is None:
        return f"zeta = {zeta:.4g}"
    return f"zeta = {zeta:.4g} (q up to {wavenumber(zeta * qL)}, qL = {wavenumber(qL)})"


def reduce_dims(ds, keep: tuple[str, ...], var: str | None = None):
    """``ds`` with every dimension of ``var`` (default: of ``ds``) but ``keep`` and ``eta``
    reduced to its middle value, and a note saying which values the figure shows (e.g.
    'hrms_substrate = 1.05e-09')."""
    notes = []
    dims = ds[var].dims if var is not None else ds.dims
    for dim in [d for d in dims if d not in keep and d != "eta"]:
        k = ds.sizes[dim] // 2
        value = ds[dim].values[k] if dim in ds.coords else k
        units = ds[dim].attrs.get("units", "") if dim in ds.coords else ""
        notes.append(f"{dim} = {readable(float(value), units)}" if isinstance(value, (float, np.floating))
                     else f"{dim} = {value}")
        ds = ds.isel({dim: k})
    return ds, ", ".join(notes)


def legend_outside(fig, axes=None, below: bool = False):
    """One legend for the figure, outside every axes (the figure must use layout="constrained"):
    right of them, or ``below`` them for a figure of several panels under one title; each label once."""
    handles, labels = [], []
    for ax in axes if axes is not None else fig.axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            if label not in labels and not label.startswith("_"):
                handles.append(h)
                labels.append(label)
    if handles:
        if below:
            fig.legend(handles, labels, loc="outside lower center", fontsize=8, ncol=min(len(handles), 4))
        else:
            fig.legend(handles, labels, loc="outside right upper", fontsize=8)
    return fig
