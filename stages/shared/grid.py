"""The wavenumber grid (``[grid]``, ``numerics.points_per_decade``) and its reference qL, the
lowest wavenumber of the grid against which every magnification zeta = q/qL is measured."""

from __future__ import annotations

import json

import numpy as np

from roughcontact.stage import Param, Section, Var, readable, register_params, register_section

from .surfaces import SURFACES, is_rough, surface_bands

#: qL, stored by the stages whose results are over zeta, so that every zeta has its reference
Q_REFERENCE = Var("1/m", "reference wavenumber qL", attrs={
    "comment": "the wavenumber the magnification zeta = q/qL is measured from: the lowest wavenumber of the q grid "
               "(grid.q_min, else the lowest wavenumber of the surfaces); roughness below qL is not counted"})


def reference_wavenumber(psd, bands) -> tuple[float | None, str]:
    """qL, the reference of zeta = q/qL and lowest wavenumber of the q grid, and where it comes
    from: ``grid.q_min``, else the lowest band edge of the rough surfaces (None if unknown yet)."""
    if psd["grid.q_min"]:
        return float(psd["grid.q_min"]), "grid.q_min"
    if not bands or len(bands) < sum(is_rough(psd[n]) for n in SURFACES):
        return None, "the lowest wavenumber of the surfaces"
    name = min(bands, key=lambda n: bands[n].lo)
    return bands[name].lo, f"the lowest wavenumber of the {name}, {bands[name].key}"


def wavenumber_text(q: float) -> str:
    """A wavenumber for a message, e.g. 2e8 1/m as '2e8'."""
    return readable(q, "1/m").removesuffix(" 1/m")


def scope_attrs(psd, topography, lo: float) -> dict:
    """What the psd stage tells the stages over zeta before they compute (its Shape's and its
    result's attributes): the reference of zeta as a note for the user, each rough surface's band
    (JSON), how the coherence enters and how many surfaces are rough. ``lo``: the grid's qL."""
    bands = surface_bands(psd, topography)
    source = reference_wavenumber(psd, bands)[1]
    eta, n_rough = psd["interface.eta"], sum(is_rough(psd[n]) for n in SURFACES)
    coherence = "measured" if isinstance(eta, str) else "swept" if np.size(eta) > 1 else "constant"
    return {"note": f"zeta = q/qL with qL = {wavenumber_text(lo)} 1/m ({source}; grid.q_min sets another system size)",
            "surface_bands": json.dumps({n: list(b) for n, b in bands.items()}), "q_reference_source": source,
            "coherence": coherence if n_rough == 2 else "none", "rough_surfaces": n_rough}


register_section(
    Section(
        "grid",
        (
            Param("q_min", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="lowest wavenumber of the q grid: qL = 2 pi/L, the system size and the reference of zeta = q/qL "
                      "(default: lowest of the surfaces; `plan` prints it)"),
            Param("q_max", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="highest wavenumber (default: highest of the surfaces)"),
        ),
        doc="the wavenumber grid shared by all stages",
    )
)


register_params(
    "numerics",
    Param("points_per_decade", "int", default=50, lo=2, presets={"fast": 20, "accurate": 100},
          ladder=(10, 14, 20, 35, 50, 70, 100, 200, 400), doc="q grid points per decade"),
    doc="resolution of the numerical methods",
)
