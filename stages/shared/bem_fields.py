"""The BEM's maps as optional outputs: the contact pressure and the gap of one realization at
chosen loads, stored by the ``bem`` stage (``bem_pressure_map``, ``bem_gap_map``) and the
``interface_bem`` stage (``exact_pressure_map``, ``exact_gap_map``) when the scene asks for them
in ``outputs.variables``.

Scene keys ``bem.field_p`` (the loads, each one of ``load.p``: the BEM solves there; default
every load) and ``bem.field_realization`` (which random pair; measured maps: 0). The maps add the
dimensions ``bem_field_p``, ``bem_x`` and ``bem_y`` (the map's pixels, positions i dx) to the
result; :func:`with_fields` adds them to the stage's :class:`Shape` in its describe, so that the
preflight sizes the maps (and refuses what the disk cannot hold) before any solve.
Figures: :mod:`roughcontact.stages.figures.bem_fields`.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable

import numpy as np
import xarray as xr

from roughcontact.stage import Param, Shape, StageInput, UserError, Var, readable, register_coords

from .maps import map_surfaces, measured_maps

FIELD_KEYS = ("bem.field_p", "bem.field_realization")
PARAMS = (
    Param("field_p", "quantities", "Pa", default=None, lo=0.0, lo_open=True,
          doc="loads at which the maps of outputs bem_pressure_map, bem_gap_map, exact_pressure_map and exact_gap_map "
              "are stored, each one of load.p (default: every load)"),
    Param("field_realization", "int", default=0, lo=0,
          doc="the random surface pair whose maps are stored (0 to bem.realizations - 1; measured maps: 0)"),
)
#: the dimensions the maps add: the loads, and the pixels along the map's two axes
FIELD_DIMS = ("bem_field_p", "bem_x", "bem_y")
register_coords(
    bem_field_p=Var("Pa", "nominal pressure of the map", comment="the loads bem.field_p"),
    bem_x=Var("m", "position on the map, first axis", comment="pixel i at i dx"),
    bem_y=Var("m", "position on the map, second axis", comment="pixel j at j dx"),
)
_WHICH = ("of one realization (bem.field_realization) at the loads bem.field_p, on the BEM's map "
          "(periodic, pixels bem_x, bem_y)")
#: per stage: (pressure map, gap map) output names and their declarations
MAPS = {
    "bem": {
        "bem_pressure_map": Var("Pa", "contact pressure map, BEM", optional=True,
                                comment=f"local contact pressure {_WHICH}; 0 out of contact"),
        "bem_gap_map": Var("m", "gap map, BEM", optional=True,
                           comment=f"local gap between the surfaces {_WHICH}; 0 in contact"),
    },
    "interface_bem": {
        "exact_pressure_map": Var("Pa", "contact pressure map, interface BEM", optional=True,
                                  comment=f"local contact pressure {_WHICH}; 0 out of contact"),
        "exact_gap_map": Var("m", "gap map, interface BEM", optional=True,
                             comment=f"local gap, the Reynolds flow's {_WHICH}; 0 in contact"),
    },
}


def asked(inp: StageInput) -> list[str]:
    """The map outputs of the stage the scene asks for."""
    return [name for name in MAPS[inp.stage] if name in inp.wanted]


def field_loads(inp: StageInput) -> np.ndarray:
    """Indices into ``load.p`` of the loads whose maps are stored; a UserError naming
    ``bem.field_p`` for a load the BEM does not solve at."""
    p = np.atleast_1d(np.asarray(inp["load.p"], dtype=float))
    chosen = inp["bem.field_p"]
    if chosen is None:
        return np.arange(p.size)
    out = []
    for value in np.atleast_1d(np.asarray(chosen, dtype=float)):
        hit = np.flatnonzero(np.isclose(p, value, rtol=1e-9, atol=0.0))
        if hit.size == 0:
            shown = ", ".join(readable(v, "Pa") for v in p[:8]) + (", ..." if p.size > 8 else "")
            raise UserError(f"{readable(float(value), 'Pa')} is not one of the loads load.p, where the BEM solves "
                            f"(choose among {shown})", key="bem.field_p")
        out.append(int(hit[0]))
    return np.array(list(dict.fromkeys(out)), dtype=int)


def field_realization(inp: StageInput, realizations: int) -> int:
    r = int(inp["bem.field_realization"])
    if r >= realizations:
        raise UserError(f"{r} is beyond the {realizations} realization(s) the BEM solves (0 to {realizations - 1}"
                        f"{'; measured maps are one' if realizations == 1 else ''})", key="bem.field_realization")
    return r


def with_fields(inp: StageInput, shape: Shape, others: Iterable[str] = ()) -> Shape:
    """``shape`` with the maps' dimensions when the scene asks for a map (else as it is): their
    sizes, the scene keys that set them, the stored maps as working memory, and every other
    output (``others`` and those ``shape.lacks`` names) as lacking them; the maps themselves lack
    the load and realization dimensions. Checks ``bem.field_p`` and ``bem.field_realization``."""
    maps = asked(inp)
    if not maps:
        return shape
    names = map_surfaces(inp)
    n = measured_maps(inp, names)["n"] if names else int(inp["bem.grid"])
    loads = field_loads(inp)
    field_realization(inp, shape.sizes.get("realization", 1))
    etas = inp.upstream["psd"].sizes.get("eta", 1) if "psd" in inp.upstream else 1
    lacks = {name: tuple(dict.fromkeys((*shape.lacks.get(name, ()), *FIELD_DIMS)))
             for name in (*shape.lacks, *others) if name not in MAPS[inp.stage]}
    lacks.update({name: ("p", "realization", "zeta", "bem_stress_level", "theory") for name in maps})
    work = dict(shape.work)
    # one solve's maps at every load (pressure and gap), and the maps kept
    work["values_per_pixel"] = work.get("values_per_pixel", 25) + 2 * np.size(inp["load.p"]) + 2 * loads.size * etas
    keys = {**shape.keys, "bem_field_p": "bem.field_p",
            **dict.fromkeys(("bem_x", "bem_y"), "bem.grid" if not names else "bem.surfaces")}
    return dataclasses.replace(shape, sizes={**shape.sizes, "bem_field_p": loads.size, "bem_x": n, "bem_y": n},
                               lacks=lacks, keys=keys, work=work)


class Fields:
    """The maps of the chosen realization, gathered solve by solve (over the loads asked, the
    coherences and the map's pixels), and put into the stage's result."""

    def __init__(self, inp: StageInput, band: dict, eta_count: int):
        self.names = asked(inp)
        self.loads = field_loads(inp) if self.names else np.array([], dtype=int)
        self.realization = field_realization(inp, band["R"]) if self.names else -1
        self.dx, n = band["dx"], band["n"]
        shape = (self.loads.size, eta_count, n, n) if self.names else (0, 0, 0, 0)
        self.pressure, self.gap = np.zeros(shape), np.zeros(shape)

    def wants(self, realization: int) -> bool:
        """Whether the solves of this realization keep their maps."""
        return bool(self.names) and realization == self.realization

    def keep(self, j: int, pressure_maps, gap_maps) -> None:
        """The maps of coherence index ``j``, over every load of ``load.p`` in its order."""
        self.pressure[:, j] = np.asarray(pressure_maps)[self.loads]
        self.gap[:, j] = np.asarray(gap_maps)[self.loads]

    def keep_solved(self, j: int, res: dict, order: np.ndarray) -> None:
        """The maps of a solve at the loads ``load.p[order]`` (increasing), for coherence index ``j``."""
        back = np.empty_like(order)
        back[order] = np.arange(order.size)
        self.keep(j, res["pressure"][back], res["gap"][back])

    def add_to(self, ds: xr.Dataset, p_values: np.ndarray) -> xr.Dataset:
        """``ds`` with the maps asked for (dimensions bem_field_p, eta, bem_x, bem_y)."""
        if not self.names:
            return ds
        n = self.pressure.shape[-1]
        ds = ds.assign_coords(bem_field_p=p_values[self.loads], bem_x=np.arange(n) * self.dx,
                              bem_y=np.arange(n) * self.dx)
        dims = ("bem_field_p", "eta", "bem_x", "bem_y")
        for name in self.names:
            ds[name] = (dims, self.pressure if name.endswith("_pressure_map") else self.gap)
        return ds


__all__ = ["FIELD_DIMS", "FIELD_KEYS", "Fields", "MAPS", "PARAMS", "asked", "field_loads", "with_fields"]
