"""What the stages' figures share: one style per case (colour, marker, line) across every figure,
the magnification a figure plots and its reference wavenumber, and legends kept off the data.

The cases of the seed's comparisons are the substrate alone and the pair with eta = 0, +1, -1;
:data:`CASE_STYLES` gives each its colour, marker and line, the same in every figure. Any other
single coherence (or a measured eta(q)) is drawn as :data:`OTHER_STYLE`; a sweep of more than a
few coherences is summarised (a colour map and the three seed cases) rather than drawn curve by
curve.
"""

from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np

from roughcontact.physics.uncertainty import quantiles
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
#: what the thin lines around a shaded band are (titles say it)
EDGES = "edged in its colour"
#: probability content of the shaded bands when the scene computes no bands stage
DEFAULT_LEVEL = 0.9


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


def line_style(case: "str | Case", npoints: int, markers: int = 12) -> dict:
    """Keyword arguments of ``Axes.plot`` for a case (its label or a :class:`Case`): its style,
    markers on about ``markers`` points."""
    out = style(case) if isinstance(case, str) else dict(case.style)
    out.update(markevery=max(1, npoints // markers), markersize=4)
    return out


def curve_cases(results, stage: str) -> list[Case]:
    """The curves of a seed-style comparison figure: the ``substrate_only`` variant if the scene
    has it, then one per coherence of the base scene (the seed's eta = -1, 0, +1 alone, or the
    nearest values, when it sweeps more than :data:`MAX_CURVES`), or one for the pair, then the
    same for every other variant with this stage (labelled 'variant name: case', open markers)."""
    out = []
    if "substrate_only" in results and stage in results["substrate_only"]:
        out.append(Case("substrate only", results["substrate_only"][stage], style("substrate only")))
    out += _variant_cases(results["base"], stage, "")
    for variant, res in results.items():
        if variant not in ("base", "substrate_only") and stage in res:
            out += _variant_cases(res, stage, variant.replace("_", " ") + ": ")
    return out


def _variant_cases(res, stage: str, prefix: str) -> list[Case]:
    """The cases of one variant's result (see :func:`curve_cases`); a variant other than the base
    keeps its case's colour and marker, drawn open."""
    ds = res[stage]
    if "eta" in ds.dims:
        cases = [(eta_label(e), ds.sel(eta=e)) for e in selected_etas(ds["eta"].values)]
    else:
        cases = [(case_of(res), ds)]
    out = []
    for case, d in cases:
        s = style(case)
        if prefix:
            s["markerfacecolor"] = "white"
        out.append(Case(prefix + case, d, s))
    return out


def case_of(res) -> str:
    """The case of a variant's results without an eta dimension: 'pair, measured eta(q)', the
    one constant coherence ('eta = 0'), 'substrate only' (or 'solid only') when one surface
    alone is rough, or 'pair'."""
    attrs = res["psd"]["psd_combined"].attrs if "psd" in res else {}
    if attrs.get("coherence") == "measured":
        return "pair, measured eta(q)"
    if attrs.get("coherence") == "none":  # one rough surface: the seed's 'substrate only' case
        rough = list(json.loads(res["psd"].attrs.get("surface_bands", "{}")))
        return f"{rough[0]} only" if len(rough) == 1 else "pair"
    return eta_label(attrs["eta"]) if attrs.get("coherence") == "constant" and "eta" in attrs else "pair"


def selected_etas(values) -> list[float]:
    """All coherences of a short sweep; of a long one, the values nearest -1, 0 and +1."""
    values = np.atleast_1d(values)
    if values.size <= MAX_CURVES:
        return [float(v) for v in values]
    picks = [float(values[int(np.argmin(np.abs(values - target)))]) for target in (0.0, 1.0, -1.0)]
    return list(dict.fromkeys(picks))


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


def scope_text(results, zeta: float | None) -> str:
    """:func:`zeta_text` of the base scene, and of every variant whose q grid starts elsewhere (its
    own surfaces set its qL, e.g. a substrate_only variant whose substrate starts above the
    solid): 'zeta = 4 (q up to 4e8 1/m, qL = 1e8 1/m); substrate only: other qL, zeta = 4 (q up
    to 8e8 1/m, qL = 2e8 1/m)'. The same zeta then reaches different wavenumbers: the figure says so."""
    qL = q_reference(results)
    text = zeta_text(zeta, qL)
    for variant in results:
        other = q_reference(results, variant) if variant != "base" else None
        if other and qL and not np.isclose(other, qL, rtol=1e-9):
            text += f";\n{variant.replace('_', ' ')}: other qL, {zeta_text(zeta, other)}"
    return text


def reduce_dims(ds, keep: tuple[str, ...], var: str | None = None):
    """``ds`` with every dimension of ``var`` (default: of ``ds``) but ``keep``, ``eta`` and the
    spectrum draws reduced to its middle value, and a note saying which values the figure shows (e.g.
    'hrms_substrate = 1.05e-09')."""
    notes = []
    dims = ds[var].dims if var is not None else ds.dims
    for dim in [d for d in dims if d not in keep and d not in ("eta", "draw")]:
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
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            if label not in labels and not label.startswith("_"):
                handles.append(h)
                labels.append(label)
    if handles:
        if below:
            fig.legend(handles, labels, loc="outside lower center", fontsize=8, ncol=min(len(handles), 4))
        else:
            fig.legend(handles, labels, loc="outside right upper", fontsize=8)
    return fig


def band_level(results) -> float:
    """The level of the scene's uncertainty bands (its bands stage's, else :data:`DEFAULT_LEVEL`)."""
    for variant in results.values():
        if "bands" in variant:
            return float(variant["bands"].attrs.get("level", DEFAULT_LEVEL))
    return DEFAULT_LEVEL


def nominal(obj):
    """A Dataset or DataArray at draw 0 (the measured spectrum) if it has spectrum draws."""
    return obj.isel(draw=0, drop=True) if "draw" in obj.dims else obj


def draw_band(da, level: float):
    """(lower, upper) quantiles over the draws 1..N of ``da`` (arrays over its other dimensions),
    or None without draws."""
    if "draw" not in da.dims:
        return None
    values = da.isel(draw=slice(1, None)).transpose(..., "draw").values
    q = quantiles(values, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return q[..., 0], q[..., 1]


def band_on(x0, xs, ys, level: float):
    """Quantiles over draws 1..N of curves (xs[d], ys[d]) read at the abscissae ``x0`` (each
    draw has its own abscissae, e.g. an adaptive stress grid)."""
    curves = np.stack([np.interp(x0, x, y, left=0.0, right=0.0) for x, y in zip(xs[1:], ys[1:], strict=True)], axis=-1)
    q = quantiles(curves, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return q[..., 0], q[..., 1]


def line_with_band(ax, x, da, level: float, *, across=False, **style):
    """Plot ``da`` at draw 0 against ``x`` and shade its band over the draws in the line's colour.

    ``da`` is a DataArray over one dimension (and ``draw``); ``across``: the values go on the
    horizontal axis (``x`` is then the vertical coordinate). Returns the line."""
    y = np.atleast_1d(nominal(da).values)
    line, = ax.plot(y, x, **style) if across else ax.plot(x, y, **style)
    band = draw_band(da, level)
    if band is not None:
        shade(ax, x, band[0], band[1], line.get_color(), across=across)
    return line


def shade(ax, x, lo, hi, color, across=False, alpha=0.18, edge=0.6):
    """A band from ``lo`` to ``hi`` over ``x``: a light fill in ``color`` edged by thin lines of
    the same colour, so that where two bands overlap (their fills mix into a third shade) each
    band's edges still say whose it is. ``across``: the band spans the horizontal axis."""
    fill = ax.fill_betweenx if across else ax.fill_between
    fill(x, lo, hi, color=color, alpha=alpha, lw=0)
    for limit in (lo, hi):
        ax.plot(*((limit, x) if across else (x, limit)), color=color, lw=edge, alpha=0.8, label="_band edge")


def band_note(results, ds) -> str:
    """A legend/title note on the shaded bands ('' without draws)."""
    if "draw" not in ds.dims:
        return ""
    return f"shaded: {band_level(results):.0%} band over {ds.sizes['draw'] - 1} spectrum draws, {EDGES}"
