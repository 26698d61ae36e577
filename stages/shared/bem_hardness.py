"""The surface hardness in the ``bem`` stage: with ``contact.yield_stress`` the elastic and plastic
contact areas, from the saturated BEM (the local pressure bounded by the hardness;
:func:`roughcontact.physics.bem_cg.saturated_areas`, with a coating the layered surface
compliance) on the same map pairs, and from the theory with the absorbing wall at sigma_Y
(:func:`roughcontact.physics.plasticity.elastoplastic_areas`) at the BEM's magnification; the
optional outputs' metadata and the preflight check that asks for the hardness.

Not a stage (it registers nothing). See docs/bem.md and docs/plasticity.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.bem_cg import NoConvergence, saturated_areas
from roughcontact.physics.layered import surface_compliance
from roughcontact.physics.plasticity import elastoplastic_areas
from roughcontact.stage import StageInput, UserError, Var

from .bem_solve import map_pairs
from .material import coating_layer

#: elastoplastic outputs (contact.yield_stress): per realization, and over (p, eta)
PLASTIC_REALIZATIONS = ("bem_elastic_contact_area_ratio", "bem_plastic_contact_area_ratio")
PLASTIC = (*PLASTIC_REALIZATIONS, *(f"{n}_{s}" for n in PLASTIC_REALIZATIONS for s in ("mean", "std")),
           "theory_elastic_contact_area_ratio", "theory_plastic_contact_area_ratio")


def check_hardness(inp: StageInput) -> None:
    """A penetration hardness when the scene asks for an elastoplastic output."""
    asked = sorted(set(PLASTIC) & inp.wanted)
    if asked and inp["contact.yield_stress"] is None:
        raise UserError(f"{asked[0]} needs a penetration hardness: set [contact] yield_stress (e.g. \"1.5 GPa\")",
                        key="contact.yield_stress")


def with_hardness(inp, ds, band, q, C1, C2, E_star, p_values, eta_values, G_pe) -> xr.Dataset:
    """The elastic and plastic contact area with the surface hardness contact.yield_stress:
    the saturated BEM (pressure bounded by sigma_Y; physics/bem_cg.py) on the same map pairs,
    and the theory's (two absorbing walls, physics/plasticity.py) at the BEM's magnification."""
    Y = float(inp["contact.yield_stress"])
    R = band["R"]
    layer = coating_layer(inp)
    compliance = None if layer is None else (lambda k: surface_compliance(k, *layer))
    shape = (p_values.size, eta_values.size, R)
    el, pl = np.empty(shape), np.empty(shape)
    tick = inp.progress("BEM elastoplastic solves",
                        total=p_values.size * (1 if band["maps"] is not None else R * eta_values.size), unit="solve")
    for j, r, h1, h2 in map_pairs(band, q, C1, C2, eta_values):
        try:
            res = saturated_areas(h1 - h2, band["dx"], E_star, p_values, Y, compliance=compliance,
                                  tolerance=inp["numerics.bem_tolerance"], progress=tick)
        except NoConvergence as exc:
            raise UserError(f"the saturated BEM did not converge ({exc}); use a larger numerics.bem_tolerance",
                            key="numerics.bem_tolerance") from None
        el[:, j, r], pl[:, j, r] = res["elastic_area"], res["plastic_area"]
    attrs = {"yield_stress_Pa": Y, "bem_solver": "roughcontact.physics.bem_cg, Polonsky-Keer with the pressure "
             "bounded by yield_stress (Kato's saturated contact)"
             + ("" if layer is None else ", the coated solid's surface compliance 2 / (q E_eff(q))")}
    dims = ("p", "eta", "realization")
    t_el, t_pl = elastoplastic_areas(p_values[:, None], np.asarray(G_pe)[None, :], Y)
    values = {"bem_elastic_contact_area_ratio": el, "bem_plastic_contact_area_ratio": pl}
    for name, a in values.items():
        out = {name: (dims, a), f"{name}_mean": (dims[:2], a.mean(axis=-1)),
               f"{name}_std": (dims[:2], a.std(axis=-1, ddof=1 if R > 1 else 0))}
        for k, v in out.items():
            if k in inp.wanted:
                ds[k] = xr.Variable(*v, attrs=attrs)
    for k, v in (("theory_elastic_contact_area_ratio", t_el), ("theory_plastic_contact_area_ratio", t_pl)):
        if k in inp.wanted:
            ds[k] = xr.Variable(("p", "eta"), v, attrs={"yield_stress_Pa": Y})
    return ds


_THEORY = "at the BEM's magnification bem_zeta"
_HARD = "with the penetration hardness contact.yield_stress"
#: the elastoplastic outputs' metadata (the bem stage's optional outputs)
PLASTIC_VARS = {
    "bem_elastic_contact_area_ratio": Var("1", "elastic contact area A_el/A0, BEM", optional=True, attrs={
        "comment": f"saturated BEM {_HARD}: fraction of pixels with 0 < p < yield_stress, per realization"}),
    "bem_plastic_contact_area_ratio": Var("1", "plastic contact area A_pl/A0, BEM", optional=True, attrs={
        "comment": f"saturated BEM {_HARD}: fraction of pixels at p = yield_stress, per realization"}),
    "bem_elastic_contact_area_ratio_mean": Var("1", "BEM A_el/A0, mean over realizations", optional=True),
    "bem_elastic_contact_area_ratio_std": Var("1", "BEM A_el/A0, std over realizations", optional=True),
    "bem_plastic_contact_area_ratio_mean": Var("1", "BEM A_pl/A0, mean over realizations", optional=True),
    "bem_plastic_contact_area_ratio_std": Var("1", "BEM A_pl/A0, std over realizations", optional=True),
    "theory_elastic_contact_area_ratio": Var("1", "elastic contact area A_el/A0, theory", optional=True, attrs={
        "comment": f"Persson's theory {_HARD} (docs/plasticity.md) {_THEORY}"}),
    "theory_plastic_contact_area_ratio": Var("1", "plastic contact area A_pl/A0, theory", optional=True, attrs={
        "comment": f"Persson's theory {_HARD} (docs/plasticity.md) {_THEORY}"}),
}
