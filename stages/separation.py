"""Stage ``separation``: the mean interfacial separation u(p, zeta, eta) between the elastic
solid and the substrate (seed eq 57), and its small-pressure law p = beta E* exp(-u/u0)
(eqs 59-60).

Kernels: :mod:`roughcontact.physics.separation` (seed eqs 21-28 and 54-60, the numerics in
its module docstring). Figure: :mod:`roughcontact.stages.figures.separation` (seed Fig. 5).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from roughcontact.physics.separation import (
    EPSILON,
    REFINEMENTS,
    mean_separation,
    power_J,
    separation_moments,
    separation_node_count,
    separation_nodes,
    small_pressure_law,
)
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Shape,
    Stage,
    StageInput,
    UserError,
    Var,
    register,
    register_params,
    register_section,
)

from .figures.separation import figure_separation
from .shared.grid import Q_REFERENCE
from .shared.magnification import CORRECTION_KEYS, area_correction, zeta_shape, zeta_values
from .shared.material import COATING_KEYS, E_STAR, MATERIAL_KEYS, coating_attrs, coating_layer, e_star

register_section(
    Section(
        "separation",
        (
            Param("alpha", "quantity", "", default=0.45, lo=0.0, hi=1.0, lo_open=True,
                  doc="Persson's gamma in eq 57 (0 < alpha <= 1; ~0.4-0.5)"),
            Param("refinement", "choice", default="none", choices=(*REFINEMENTS, "contact"),
                  doc="'none' (eq 57), 'yang_persson' (alpha -> alpha + 3(1 - alpha) P^2), 'wang_mueser' "
                      "(alpha -> alpha - (2/3) P^2 + 5 (11/9 - alpha) P^4) or 'contact': the one of contact.correction "
                      "with its gamma as alpha (persson: 'none' with this alpha)"),
        ),
        doc="the mean interfacial separation stage",
    )
)
register_params(
    "numerics",
    Param("separation_panels_per_decade", "int", default=2, lo=1,
          presets={"fast": 1, "accurate": 4}, ladder=(1, 2, 2, 3, 4, 6, 8, 16, 16),
          doc="geometric panels per decade of s = 1/w in the separation integral"),
    Param("separation_gauss_points", "int", default=3, lo=1, hi=64,
          presets={"fast": 2, "accurate": 4}, ladder=(2, 2, 3, 3, 4, 4, 6, 10, 10),
          doc="Gauss-Legendre nodes per panel in the separation integral"),
    Param("separation_depth", "quantity", "", default=10.0, lo=1.0, hi=100.0,
          doc="decades of s below 1/w(q_max) resolved by panels (closed form below)"),
)

_NUMERICS = ("numerics.separation_panels_per_decade", "numerics.separation_gauss_points", "numerics.separation_depth")
_NODES = "separation_node"


def _checked_alpha(inp: StageInput) -> float:
    """alpha, after checking it and the pressures (the schema checks both; the kernels rely on them)."""
    alpha = float(inp["separation.alpha"])
    if not 0.0 < alpha <= 1.0:
        raise UserError(f"must be in (0, 1], got {alpha:g}", key="separation.alpha")
    if np.any(~(np.atleast_1d(np.asarray(inp["load.p"], dtype=float)) > 0)):
        raise UserError("pressures must be > 0", key="load.p")
    return alpha


def separation_variant(inp: StageInput) -> tuple[float, str]:
    """(alpha, refinement) of eq 57: the scene's, or with refinement "contact" the contact stage's
    correction (yang_persson, wang_mueser) with its gamma as alpha; persson keeps "none"."""
    alpha = _checked_alpha(inp)
    refinement = inp["separation.refinement"]
    if refinement != "contact":
        return alpha, refinement
    name, gamma = area_correction(inp)
    return (alpha, "none") if name == "persson" else (gamma, name)


def theory_attrs(inp: StageInput, settings: dict) -> dict:
    """The result's attributes that say which separation law was used: ``separation_refinement``
    (the variant of eq 57), ``separation_alpha``, ``contact_correction`` (whether eq 57 uses it) and,
    with refinement "contact", ``separation_refinement_source`` (the contact correction it came from)."""
    attrs = {"separation_refinement": settings["refinement"], "separation_alpha": settings["alpha"]}
    name = area_correction(inp)[0]
    if inp["separation.refinement"] == "contact":
        attrs["separation_refinement_source"] = f"contact: from contact.correction = {name}"
        attrs["contact_correction"] = name
    else:
        attrs["contact_correction"] = f"{name} (not used by eq 57: separation.refinement = {settings['refinement']})"
    return attrs


def check_separation(inp: StageInput) -> None:
    """With refinement "contact", the contact correction's gamma must be usable."""
    if inp["separation.refinement"] == "contact":
        area_correction(inp)


def describe_separation(inp: StageInput) -> Shape:
    """The magnifications (on the psd stage's q grid; computed whole) and the working memory per
    sweep point: the quadrature nodes and weights of each spectrum (about order x (q nodes + depth x
    panels per decade) each), shared by its pressures. The kernel's own temporaries do not grow
    with the block: it works through a few rows at a time (physics/separation.py, ``CHUNK``)."""
    panels = int(np.ceil(float(inp["numerics.separation_depth"]) * inp["numerics.separation_panels_per_decade"]))
    nodes = (int(inp.upstream["psd"].sizes["q"]) + panels + 1) * int(inp["numerics.separation_gauss_points"])
    pressures = max(int(np.size(inp["load.p"])), 1)
    return dataclasses.replace(zeta_shape(inp, inp.upstream["psd"]),
                               work={"node_arrays": 2, _NODES: nodes, "per_pressure": 1 / pressures},
                               coupled=("zeta",), lacks={"separation_u0": ("p",), "separation_beta": ("p",)})


def compute_separation(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = e_star(inp)
    alpha, refinement = separation_variant(inp)
    zetas = zeta_values(inp, q)
    zeta = xr.DataArray(zetas, dims=("zeta",))
    numerics = {"panels_per_decade": inp["numerics.separation_panels_per_decade"],
                "order": inp["numerics.separation_gauss_points"], "depth": float(inp["numerics.separation_depth"])}
    s, weight, count, s_upper, s_tail, q_tail = xr.apply_ufunc(
        separation_nodes, psd["q"], psd["psd_combined"], zetas * q[0], kwargs={**numerics, "layer": coating_layer(inp)},
        input_core_dims=[["q"], ["q"], ["zeta"]],
        output_core_dims=[[_NODES], [_NODES], ["zeta"], ["zeta"], ["zeta"], []],
        dask="parallelized", output_dtypes=[float, float, int, float, float, float],
        dask_gufunc_kwargs={"output_sizes": {_NODES: separation_node_count(q, zetas * q[0], **numerics),
                                             "zeta": zetas.size}},
    )
    M0, M1 = xr.apply_ufunc(
        separation_moments, s, weight, count, s_tail, q_tail,
        input_core_dims=[[_NODES], [_NODES], ["zeta"], ["zeta"], []],
        output_core_dims=[["zeta"], ["zeta"]], dask="parallelized", output_dtypes=[float, float],
    )
    u0, beta = xr.apply_ufunc(
        small_pressure_law, M0, M1, kwargs={"alpha": alpha, "refinement": refinement},
        output_core_dims=[["zeta"], ["zeta"]], input_core_dims=[["zeta"], ["zeta"]],
        dask="parallelized", output_dtypes=[float, float],
    )
    u = xr.apply_ufunc(
        mean_separation, inp.sweep("p", inp["load.p"]), s, weight, count, s_tail, q_tail,
        kwargs={"E_star": E_star, "alpha": alpha, "refinement": refinement},
        input_core_dims=[[], [_NODES], [_NODES], ["zeta"], ["zeta"], []],
        output_core_dims=[["zeta"]], dask="parallelized", output_dtypes=[float],
    )
    u = u.assign_coords(zeta=zeta).transpose(..., "zeta", *(("p",) if "p" in u.dims else ()))
    u.attrs = {
        "formula": "u = (sqrt(pi) alpha / 2) int_qL^(zeta qL) q^2 C w E1((w p / E*)^2) dq",
        "alpha": alpha,
        "refinement": refinement,
        "refinement_description": REFINEMENTS[refinement],
        "method": "s = 1/w substitution (q^2 C w dq = (2/pi) ds / q(s)), Gauss-Legendre panels; closed-form tail",
        "separation_panels_per_decade": numerics["panels_per_decade"],
        "separation_gauss_points": numerics["order"],
        "separation_depth": numerics["depth"],
    }
    u0 = u0.assign_coords(zeta=zeta)
    u0.attrs = {"formula": "u0 = sqrt(pi) alpha int q^2 C w dq", "alpha": alpha}
    beta = beta.assign_coords(zeta=zeta)
    beta.attrs = _beta_attrs(refinement)
    ds = xr.Dataset({"mean_separation": u, "separation_u0": u0, "separation_beta": beta,
                     "E_star": xr.DataArray(E_star), "qL": xr.DataArray(q[0])})
    ds.attrs.update({**theory_attrs(inp, {"alpha": alpha, "refinement": refinement}), "separation_epsilon": EPSILON,
                     **coating_attrs(inp)})
    return ds


def _beta_attrs(refinement: str) -> dict:
    extra = {"none": "", "yang_persson": " times exp(3 (1 - alpha) J2(0) / alpha), J2(0) = %.10f (Yang-Persson)"
             % float(power_J(0.0, 2)),
             "wang_mueser": " times exp(sum_k c_k Jk(0) / alpha), c_2 = -2/3, c_4 = 5 (11/9 - alpha), "
                            "J2(0) = %.10f, J4(0) = %.10f" % (float(power_J(0.0, 2)), float(power_J(0.0, 4)))}
    return {
        "formula": "beta = eps exp(-int q^2 C w ln w dq / int q^2 C w dq), eps = exp(-gamma_Euler/2)"
                   + extra[refinement],
        "epsilon": EPSILON,
        "sign_note": "eq 60 of the seed lost the minus sign in the exponent; restored here (docs/theory.md, "
                     "section 'Separation')",
        "nan_reason": "beta is NaN where the combined PSD is identically zero up to zeta qL (e.g. eta = 1 with "
                      "identical surfaces): then u = 0 and u0 = 0 at every pressure and p = beta E* exp(-u/u0) "
                      "has no meaning",
    }


STAGE = register(
    Stage(
        name="separation",
        version="3",
        compute=compute_separation,
        check=check_separation,
        describe=describe_separation,
        needs=("psd",),
        reads=(*MATERIAL_KEYS, "load.p", "contact.zeta", "separation.alpha", "separation.refinement", *_NUMERICS,
                *CORRECTION_KEYS, *COATING_KEYS),
        outputs={
            "mean_separation": Var("m", "mean interfacial separation u", comment="u(p), eq 57",
                                   tolerance=1e-4),
            "separation_u0": Var("m", "decay length u0 of the separation law",
                                 comment="of the small-pressure law p = beta E* exp(-u/u0); eq 59"),
            "separation_beta": Var("1", "prefactor beta of the separation law",
                                   comment="of the small-pressure law p = beta E* exp(-u/u0); eq 60"),
            "E_star": E_STAR,
            "qL": Q_REFERENCE,
        },
        figures=(Figure("fig5_separation", "log10(p/E*) against u (seed Fig. 5)", ("separation",), figure_separation),),
        doc="Mean interfacial separation u(p, zeta, eta) (eq 57) and its small-pressure law u0, beta (eqs 59-60).",
    )
)
