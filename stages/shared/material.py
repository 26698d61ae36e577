"""The elastic solid (``[material]``), with an optional coating, its load (``[load]``) and E*,
derived here only."""

from __future__ import annotations

import numpy as np

from roughcontact.physics.contact import effective_modulus
from roughcontact.stage import Param, Section, UserError, Var, register_section

#: E*, stored by the stages whose results are read against it (p/E*)
E_STAR = Var("Pa", "effective modulus E*", attrs={
    "comment": "E* = E/(1 - nu^2) of the elastic solid (material.E, material.nu) on the rigid substrate"})

#: the scene keys E* is derived from
MATERIAL_KEYS = ("material.E", "material.nu")

#: the scene keys of a coating on the elastic solid (docs/coating.md): read by the stages that
#: take its E_eff(q) (contact, separation, stiffness) and by those that refuse it
COATING_KEYS = ("material.coating_thickness", "material.coating_E", "material.coating_nu")

def e_star(inp) -> float:
    """E* of the scene's solid on a rigid substrate (Pa), from ``[material]`` (seed eq 3); with a
    coating, that of the coated part's substrate (the layer enters through :func:`coating_layer`)."""
    return float(effective_modulus(inp["material.E"], inp["material.nu"]))


def coated(inp) -> bool:
    """Whether the scene coats the elastic solid (material.coating_thickness set, not "none")."""
    d = inp["material.coating_thickness"]
    return d is not None and not isinstance(d, str)


def coating_layer(inp) -> tuple[float, float, float, float, float] | None:
    """The coated solid as the kernels take it, (thickness, E_layer, nu_layer, E_sub, nu_sub) in SI
    (:data:`roughcontact.physics.layered.LAYER_FIELDS`), or None for a homogeneous half-space."""
    if not coated(inp):
        return None
    return (float(inp["material.coating_thickness"]), float(inp["material.coating_E"]),
            float(inp["material.coating_nu"]), float(inp["material.E"]), float(inp["material.nu"]))


def coating_attrs(inp) -> dict:
    """The result attribute that records a coating (none for a homogeneous solid: nothing added)."""
    layer = coating_layer(inp)
    if layer is None:
        return {}
    d, E, nu, E_sub, nu_sub = layer
    return {"coating": f"layer of thickness {d:.6g} m, E = {E:.6g} Pa, nu = {nu:.6g} on the elastic solid "
                       "(material.E, material.nu: its substrate; E_star is the substrate's); E_eff(q) of "
                       "physics/layered.py under the q integrals: G = (pi/4) int q^3 C E_eff^2 dq, eq 57 with "
                       "E_eff in the elastic energy (docs/coating.md)",
            "coating_thickness_m": d, "coating_E_Pa": E, "coating_nu": nu, "substrate_E_Pa": E_sub,
            "substrate_nu": nu_sub}


def refuse_coating(inp, what: str) -> None:
    """One-line UserError in a stage's check when the scene coats the solid and ``what`` (the
    stage's computation) does not take a coating into account."""
    if coated(inp):
        raise UserError(f"a coating is not supported by {what} (it takes a homogeneous solid); remove "
                        "material.coating_thickness or set it to \"none\" (docs/coating.md)",
                        key="material.coating_thickness")


def _check_material(values: dict, key: str) -> None:
    """A coating needs its thickness, E and nu together; the thickness is one value (sweep it with
    [variants]) or "none"."""
    d = values.get("coating_thickness")
    if isinstance(d, np.ndarray):
        raise UserError("one thickness (or \"none\"); compare thicknesses with [variants]",
                        key=f"{key}.coating_thickness")
    given = [k for k in ("coating_E", "coating_nu") if values.get(k) is not None]
    if d is None and given:
        raise UserError(f"{key}.{given[0]} needs the layer's thickness: set {key}.coating_thickness (e.g. \"10 um\")",
                        key=f"{key}.coating_thickness")
    if d is not None and not isinstance(d, str):
        for k in ("coating_E", "coating_nu"):
            if values.get(k) is None:
                raise UserError(f"a coating needs its {'Young modulus' if k == 'coating_E' else 'Poisson ratio'} "
                                f"as well: set {key}.{k}", key=f"{key}.{k}")


register_section(
    Section(
        "material",
        (
            Param("E", "quantity", "Pa", lo=0.0, lo_open=True, doc="Young's modulus of the elastic solid"),
            Param("nu", "quantity", "", lo=-1.0, hi=0.5, lo_open=True, doc="Poisson ratio, -1 < nu <= 0.5"),
            Param("coating_thickness", "quantities", "m", default=None, lo=0.0, lo_open=True, choices=("none",),
                  doc="thickness d of an elastic coating bonded to the solid (one value; E, nu are then its "
                      "substrate's): E_eff(q) enters G, A/A0, P(sigma), u and K (docs/coating.md). Default: none "
                      "(homogeneous); \"none\" switches a coating off (e.g. in a variant)"),
            Param("coating_E", "quantity", "Pa", default=None, lo=0.0, lo_open=True,
                  doc="Young's modulus of the coating"),
            Param("coating_nu", "quantity", "", default=None, lo=-1.0, hi=0.5, lo_open=True,
                  doc="Poisson ratio of the coating, -1 < nu <= 0.5"),
        ),
        doc="the elastic solid (the substrate is rigid), optionally coated",
        check=_check_material,
    )
)
register_section(
    Section(
        "load",
        (Param("p", "sweep", "Pa", lo=0.0, lo_open=True,
               doc="nominal pressure; a list or {from, to, num} is a sweep"),),
        doc="the nominal squeezing pressure",
    )
)
