"""Helpers shared by the stages' figures (not a stage: the name starts with an underscore)."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.uncertainty import quantiles

#: probability content of the shaded bands when the scene computes no bands stage
DEFAULT_LEVEL = 0.9


def curve_cases(results, stage: str):
    """(label, Dataset) per curve of a seed-style comparison figure: the ``substrate_only``
    variant first if the scene has it, then one curve per eta of the base scene (or one curve
    when eta is not a dimension). Spectrum draws (dimension ``draw``) are kept: see
    :func:`line_with_band`."""
    out = []
    if "substrate_only" in results and stage in results["substrate_only"]:
        out.append(("substrate only", results["substrate_only"][stage]))
    base = results["base"][stage]
    if "eta" in base.dims:
        out += [(f"eta = {e:+g}", base.sel(eta=e)) for e in base["eta"].values]
    else:
        out.append(("pair", base))
    return out


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
    curves = np.stack([np.interp(x0, x, y, left=0.0, right=0.0) for x, y in zip(xs[1:], ys[1:])], axis=-1)
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
        fill = ax.fill_betweenx if across else ax.fill_between
        fill(x, band[0], band[1], color=line.get_color(), alpha=0.22, lw=0)
    return line


def band_note(results, ds) -> str:
    """A legend/title note on the shaded bands ('' without draws)."""
    if "draw" not in ds.dims:
        return ""
    return f"shaded: {band_level(results):.0%} band over {ds.sizes['draw'] - 1} spectrum draws"
