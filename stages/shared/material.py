"""The elastic solid (``[material]``), its load (``[load]``) and E*, derived here only."""

from __future__ import annotations

from roughcontact.physics.contact import effective_modulus
from roughcontact.stage import Param, Section, Var, register_section

#: E*, stored by the stages whose results are read against it (p/E*)
E_STAR = Var("Pa", "effective modulus E*", attrs={
    "comment": "E* = E/(1 - nu^2) of the elastic solid (material.E, material.nu) on the rigid substrate"})

#: the scene keys E* is derived from
MATERIAL_KEYS = ("material.E", "material.nu")

def e_star(inp) -> float:
    """E* of the scene's solid on a rigid substrate (Pa), from ``[material]`` (seed eq 3)."""
    return float(effective_modulus(inp["material.E"], inp["material.nu"]))


register_section(
    Section(
        "material",
        (
            Param("E", "quantity", "Pa", lo=0.0, lo_open=True, doc="Young's modulus of the elastic solid"),
            Param("nu", "quantity", "", lo=-1.0, hi=0.5, lo_open=True, doc="Poisson ratio, -1 < nu <= 0.5"),
        ),
        doc="the elastic solid (the substrate is rigid)",
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
