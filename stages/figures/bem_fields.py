"""Figures of the BEM's maps (optional outputs, stages/shared/bem_fields.py): the contact
pressure with the contact patches, and the gap with the channels through which a fluid crosses
the map (the open clusters that percolate, :func:`roughcontact.physics.reynolds.percolating_cells`).
Drawn for the ``bem`` and the ``interface_bem`` stage alike, at up to four of the loads stored,
for one coherence (eta = 0 where it was swept)."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.reynolds import percolating_cells
from roughcontact.stage import Figure, readable

from .common import eta_label

#: at most this many loads are drawn (evenly chosen among those stored)
LOADS = 4
_NAMES = {"bem": ("bem_pressure_map", "bem_gap_map"), "interface_bem": ("exact_pressure_map", "exact_gap_map")}


def _length_unit(side: float) -> tuple[float, str]:
    for scale, unit in ((1e-9, "nm"), (1e-6, "um"), (1e-3, "mm")):
        if side < 1000 * scale:
            return scale, unit
    return 1.0, "m"


def _pressure_unit(top: float) -> tuple[float, str]:
    for scale, unit in ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa")):
        if top >= scale:
            return scale, unit
    return 1.0, "Pa"


def _selected(ds, name):
    """The map over (bem_field_p, x, y) of one coherence and its label, and up to LOADS load indices."""
    da = ds[name]
    label = "measured maps"
    if "eta" in da.dims:
        etas = da["eta"].values
        k = int(np.flatnonzero(etas == 0.0)[0]) if np.any(etas == 0.0) else 0
        da = da.isel(eta=k)
        label = eta_label(float(etas[k])) if np.isfinite(etas[k]) else label
        if etas.size > 1:
            label += f" (of {etas.size} coherences stored)"
    elif "bem_surfaces" in ds.attrs and ds.attrs["bem_surfaces"] != "measured":
        label = "synthesized pair"
    loads = np.unique(np.linspace(0, da.sizes["bem_field_p"] - 1, min(LOADS, da.sizes["bem_field_p"])).round()
                      ).astype(int)
    return da, label, loads


def _extent(da):
    x, y = da["bem_x"].values, da["bem_y"].values
    dx = x[1] - x[0] if x.size > 1 else 1.0
    scale, unit = _length_unit(x.size * dx)
    return [0, y.size * dx / scale, x.size * dx / scale, 0], unit


def _title(ds, stage: str, what: str, label: str) -> str:
    realization = "" if ds.attrs.get("bem_surfaces") == "measured" else " (one realization)"
    return f"{stage}: {what}, {label}{realization}; map {ds.sizes.get('bem_x', '?')}^2 pixels"


def figure_pressure_maps(results, stage: str = "bem"):
    """Per load (rows): the contact pressure map and the contact patches (black: in contact)."""
    import matplotlib.pyplot as plt

    ds = results["base"][stage]
    name = _NAMES[stage][0]
    if name not in ds:
        return None
    da, label, loads = _selected(ds, name)
    extent, unit = _extent(da)
    fig, axes = plt.subplots(len(loads), 2, figsize=(9.6, 4.2 * len(loads)), layout="constrained", squeeze=False)
    for row, i in enumerate(loads):
        pressure = da.isel(bem_field_p=i).values
        p = float(da["bem_field_p"].values[i])
        scale, punit = _pressure_unit(float(pressure.max()))
        image = axes[row, 0].imshow(pressure / scale, cmap="viridis", extent=extent, interpolation="nearest")
        fig.colorbar(image, ax=axes[row, 0], label=f"contact pressure ({punit})", shrink=0.85)
        axes[row, 0].set_title(f"p = {readable(p, 'Pa')}: local pressure (mean {readable(pressure.mean(), 'Pa')})",
                               fontsize=9)
        contact = pressure > 0
        axes[row, 1].imshow(contact, cmap="gray_r", vmin=0, vmax=1, extent=extent, interpolation="nearest")
        axes[row, 1].set_title(f"contact patches (black): A/A0 = {contact.mean():.3g}", fontsize=9)
        for ax in axes[row]:
            ax.set_xlabel(f"y ({unit})")
            ax.set_ylabel(f"x ({unit})")
    fig.suptitle(_title(ds, stage, "contact pressure", label), fontsize=11)
    return fig


def figure_gap_maps(results, stage: str = "bem"):
    """Per load: the gap map, coloured where the open area percolates (the channels through which
    a fluid crosses the map), grey where it is trapped in pools, black in contact."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    ds = results["base"][stage]
    name = _NAMES[stage][1]
    if name not in ds:
        return None
    da, label, loads = _selected(ds, name)
    extent, unit = _extent(da)
    columns = min(2, len(loads))
    rows = -(-len(loads) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(4.8 * columns + 1.4, 4.6 * rows + 0.4), layout="constrained",
                             squeeze=False)
    for ax in axes.ravel()[len(loads):]:
        ax.set_visible(False)
    top = float(np.nanmax(da.isel(bem_field_p=loads).values)) or 1.0
    scale, gunit = _length_unit(top)
    classes = ListedColormap(["black", "0.72"])  # contact, trapped pools
    water = ListedColormap(plt.get_cmap("YlGnBu")(np.linspace(0.0, 0.8, 256)))  # no dark blue next to the black
    for ax, i in zip(axes.ravel(), loads, strict=False):
        gap = da.isel(bem_field_p=i).values
        p = float(da["bem_field_p"].values[i])
        open_cells = gap > 0
        along = [a for a in (0, 1) if open_cells.any() and percolates_along(open_cells, a)]
        channel = np.zeros_like(open_cells)
        for a in along:
            channel |= percolating_cells(open_cells, a)
        ax.imshow(np.where(open_cells, 1, 0), cmap=classes, vmin=0, vmax=1, extent=extent, interpolation="nearest")
        image = ax.imshow(np.ma.masked_where(~channel, gap / scale), cmap=water, vmin=0.0, vmax=top / scale,
                          extent=extent, interpolation="nearest")
        way = " and ".join("x" if a == 0 else "y" for a in along)
        ax.set_title(f"p = {readable(p, 'Pa')}, A/A0 = {1 - open_cells.mean():.3g}: "
                     + (f"open along {way}" if along else "sealed"), fontsize=9)
        ax.set_xlabel(f"y ({unit})")
        ax.set_ylabel(f"x ({unit})")
    fig.colorbar(image, ax=axes, label=f"gap in the percolating channel ({gunit})", shrink=0.6)
    fig.suptitle(_title(ds, stage, "gap", label) + "\ncolour: the percolating channel (the fluid's way across), "
                 "grey: trapped pools, black: contact", fontsize=10)
    return fig


def percolates_along(open_cells, axis) -> bool:
    return bool(percolating_cells(open_cells, axis).any())


def field_figures(stage: str) -> tuple[Figure, ...]:
    """The two figures of the maps of ``stage``, each drawn when the scene asks for its map."""
    pressure, gap = _NAMES[stage]
    return (
        Figure(f"{stage}_pressure_map", "BEM contact pressure map and contact patches", (stage,),
               lambda results: figure_pressure_maps(results, stage), outputs=(pressure,)),
        Figure(f"{stage}_gap_map", "BEM gap map and the percolating channel", (stage,),
               lambda results: figure_gap_maps(results, stage), outputs=(gap,)),
    )
