"""Stage ``stiffness``: the normal contact stiffness per unit nominal area K = -dp/du over
(p, zeta, eta), from the separation law of eq 57 differentiated analytically in p.

Kernels: :func:`roughcontact.physics.interface.stiffness_from_psd` (on the separation nodes of
:mod:`roughcontact.physics.separation`). Every pressure is independent (no finite differences
along p), so p is chunked like any sweep. Figure: :mod:`roughcontact.stages.figures.interface`.
See docs/interface.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.interface import stiffness_from_psd
from roughcontact.physics.separation import REFINEMENTS
from roughcontact.stage import Figure, Shape, Stage, StageInput, Var, register

from .figures.interface import figure_stiffness
from .separation import check_separation, separation_variant, theory_attrs
from .shared.magnification import CORRECTION_KEYS, zeta_values
from .shared.material import COATING_KEYS, E_STAR, MATERIAL_KEYS, coating_attrs, coating_layer, e_star

#: the scene keys of eq 57 and its quadrature (declared by the separation stage); refinement
#: "contact" takes the variant (and its gamma as alpha) from contact.correction
SEPARATION_KEYS = ("separation.alpha", "separation.refinement", "numerics.separation_panels_per_decade",
                   "numerics.separation_gauss_points", "numerics.separation_depth", *CORRECTION_KEYS)


def separation_settings(inp: StageInput) -> dict:
    """The separation law's parameters (alpha, refinement: "contact" resolved to the contact
    correction's variant) and quadrature, as kernel keywords."""
    alpha, refinement = separation_variant(inp)
    return {"alpha": alpha, "refinement": refinement,
            "panels_per_decade": inp["numerics.separation_panels_per_decade"],
            "order": inp["numerics.separation_gauss_points"], "depth": float(inp["numerics.separation_depth"])}


def compute_stiffness(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = e_star(inp)
    zetas = zeta_values(inp, q)
    settings = separation_settings(inp)
    p = inp.sweep("p", inp["load.p"])
    D, K = xr.apply_ufunc(
        stiffness_from_psd, psd["q"], psd["psd_combined"], zetas * q[0], p,
        kwargs={"E_star": E_star, **settings, "layer": coating_layer(inp)},
        input_core_dims=[["q"], ["q"], ["zeta"], []], output_core_dims=[["zeta"], ["zeta"]],
        dask="parallelized", output_dtypes=[float, float],
        dask_gufunc_kwargs={"output_sizes": {"zeta": zetas.size}},
    )
    order = (..., "zeta", *(("p",) if "p" in K.dims else ()))
    zeta = xr.DataArray(zetas, dims=("zeta",))
    D = D.assign_coords(zeta=zeta).transpose(*order)
    K = K.assign_coords(zeta=zeta).transpose(*order)
    K.attrs = {"formula": "K = p / D, D = -du/dln p = sqrt(pi) alpha int q^2 C w exp(-(w p/E*)^2) dq",
               "alpha": settings["alpha"], "refinement": settings["refinement"],
               "refinement_description": REFINEMENTS[settings["refinement"]]}
    ds_attrs = {**theory_attrs(inp, settings), **coating_attrs(inp)}
    D.attrs = {"formula": "D = -p du/dp = (2 alpha/sqrt(pi)) int_0^(1/w) exp(-(p/(E* s))^2) ds/q(s) "
                          "(+ tail in closed form)"}
    u0 = inp.upstream["separation"]["separation_u0"]
    with np.errstate(divide="ignore"):
        small = xr.apply_ufunc(np.divide, p, u0, dask="parallelized", output_dtypes=[float])
    return xr.Dataset({"contact_stiffness": K, "stiffness_length": D, "small_load_stiffness": small.transpose(*order),
                       "E_star": xr.DataArray(E_star)}, attrs=ds_attrs)



def describe_stiffness(inp: StageInput) -> Shape:
    """Working memory per (p, eta) point: the Gaussian factor on every separation node (a few
    float64 temporaries), plus one value per magnification."""
    nq = inp.upstream["psd"].sizes["q"]
    nodes = (nq + inp["numerics.separation_depth"] * inp["numerics.separation_panels_per_decade"] + 2) \
        * inp["numerics.separation_gauss_points"]
    zetas = nq if isinstance(inp["contact.zeta"], str) else np.size(inp["contact.zeta"])
    return Shape(work={"values": int(4 * nodes + zetas)}, lacks={"E_star": ("p", "zeta")})


INFINITE = ("+inf where the interface adds no compliance: the surfaces fit exactly (combined PSD zero, e.g. "
            "identical surfaces with eta = 1) or exp(-(w p/E*)^2) underflows at every scale (full contact); "
            "stiffness_length is exactly 0 there")

register(
    Stage(
        name="stiffness",
        version="2",
        compute=compute_stiffness,
        check=check_separation,
        needs=("psd", "separation"),
        reads=(*MATERIAL_KEYS, *COATING_KEYS, "load.p", "contact.zeta", *SEPARATION_KEYS),
        outputs={
            "contact_stiffness": Var("Pa/m", "normal contact stiffness K = -dp/du",
                                     comment=f"per unit nominal area; {INFINITE}", tolerance=1e-4),
            "stiffness_length": Var("m", "stiffness length p/K = -du/d(ln p)",
                                    comment="the decay length of the separation law at p (-> u0 at small "
                                            "load)"),
            "small_load_stiffness": Var("Pa/m", "small-load contact stiffness p/u0",
                                        comment="small-load limit of the contact stiffness, u0 of eq 59; "
                                                "+inf where u0 = 0: the surfaces fit exactly (combined PSD "
                                                "zero, e.g. identical surfaces with eta = 1)"),
            "E_star": E_STAR,
        },
        figures=(Figure("stiffness", "contact stiffness K = -dp/du against p/E*, and K u0/p",
                        ("stiffness", "separation"), figure_stiffness),),
        doc="Normal contact stiffness per unit area K(p, zeta, eta) = -dp/du, analytic in p from eq 57.",
        describe=describe_stiffness,
    )
)
