"""Stage ``contact``: G(zeta), the relative contact area A/A0(p, zeta, eta) and, when asked
for, the stress distribution P(sigma; p, zeta, eta) and, with a penetration hardness
(``contact.yield_stress``), the elastic and plastic contact areas.

Kernels: :mod:`roughcontact.physics.contact` (seed eqs 16-19, 53) and
:mod:`roughcontact.physics.plasticity` (absorbing wall at sigma_Y). Figures:
:mod:`roughcontact.stages.figures.contact` (seed Figs 3 and 4; elastic and plastic areas).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import xarray as xr

from roughcontact.physics.contact import contact_area_ratio, persson_G, stress_distribution_adaptive
from roughcontact.physics.corrections import CORRECTIONS, corrected_G
from roughcontact.physics.plasticity import elastoplastic_areas
from roughcontact.stage import (
    Figure,
    Param,
    SceneWarning,
    Shape,
    Stage,
    StageInput,
    UserError,
    Var,
    register,
    register_params,
)

from .figures.coating import figure_coating_area, figure_coating_modulus
from .figures.contact import figure_contact_area, figure_elastoplastic_area, figure_stress_distribution
from .shared.grid import Q_REFERENCE
from .shared.magnification import CORRECTION_KEYS, area_correction, zeta_shape, zeta_values
from .shared.material import COATING_KEYS, E_STAR, MATERIAL_KEYS, coating_attrs, coating_layer, e_star

register_params(
    "numerics",
    Param("sigma_points", "int", default=401, lo=3, doc="nodes of the stress grid of P(sigma)"),
    Param("sigma_width", "quantity", "", default=8.0, lo=1.0,
          doc="the stress grid of each (p, zeta, eta) spans max(0, p - sigma_width sqrt(G)) .. "
              "p + sigma_width sqrt(G)"),
)


def compute_contact(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = e_star(inp)
    zeta = xr.DataArray(zeta_values(inp, q), dims=("zeta",))
    G = xr.apply_ufunc(
        persson_G, psd["q"], psd["psd_combined"], zeta * q[0], E_star, kwargs={"layer": coating_layer(inp)},
        input_core_dims=[["q"], ["q"], ["zeta"], []], output_core_dims=[["zeta"]],
        dask="parallelized", output_dtypes=[float],
    ).assign_coords(zeta=zeta)
    G = inp.shared(G)  # once, not for every few blocks of pressures
    p = inp.sweep("p", inp["load.p"])
    G_area = _corrected(inp, p, G)
    area = xr.apply_ufunc(contact_area_ratio, p, G_area, dask="parallelized", output_dtypes=[float])
    area.attrs = _correction_attrs(inp)
    ds = xr.Dataset({"G": G, "contact_area_ratio": area, "E_star": xr.DataArray(E_star), "qL": xr.DataArray(q[0])},
                    attrs=coating_attrs(inp))
    if "stress_distribution" in inp.wanted:
        level = xr.DataArray(np.linspace(0.0, 1.0, inp["numerics.sigma_points"]), dims=("stress_level",))
        dist, sigma, mass = xr.apply_ufunc(
            stress_distribution_adaptive, level, p, G_area, inp["numerics.sigma_width"],
            input_core_dims=[["stress_level"], [], [], []], output_core_dims=[["stress_level"], ["stress_level"], []],
            dask="parallelized", output_dtypes=[float, float, float],
        )
        ds["stress_distribution"] = dist
        ds["stress_distribution_mass"] = mass
        ds = ds.assign_coords(stress_level=level, sigma=sigma)
    if set(PLASTIC) & inp.wanted:
        areas = xr.apply_ufunc(elastoplastic_areas, p, G, inp["contact.yield_stress"], dask="parallelized",
                               output_core_dims=[[], []], output_dtypes=[float, float])
        for name, area in zip(PLASTIC, areas, strict=True):
            if name in inp.wanted:
                ds[name] = area
                ds[name].attrs = {"yield_stress_Pa": float(inp["contact.yield_stress"])}
    return ds


#: the outputs of elastoplastic contact (contact.yield_stress)
PLASTIC = ("elastic_contact_area_ratio", "plastic_contact_area_ratio")


def _corrected(inp: StageInput, p: xr.DataArray, G: xr.DataArray) -> xr.DataArray:
    """G of eq 19 and eq 16: eq 17's G, or the corrected theory's G_eff(p, zeta) (contact.correction)."""
    name, gamma = area_correction(inp)
    if name == "persson":
        return G
    return xr.apply_ufunc(corrected_G, p, G, name, gamma, dask="parallelized", output_dtypes=[float])


def _correction_attrs(inp: StageInput) -> dict:
    name, gamma = area_correction(inp)
    attrs = {"correction": name, "correction_description": CORRECTIONS[name]}
    if gamma is not None:
        attrs.update(correction_gamma=gamma, correction_method="dV = S(A/A0) dV_full solved exactly: "
                     "Phi(2 G_eff / p^2) = 2 G / p^2, A/A0 = erf(p / 2 sqrt G_eff), P(sigma) = eq 16 with G_eff")
    return attrs


def check_contact(inp: StageInput) -> None:
    """A correction's gamma that makes S(A/A0) <= 0 is refused; so are the elastoplastic areas
    without a yield stress or with a corrected theory (the absorbing wall at sigma_Y is solved
    for eq 17's G only). Pressures at or above the yield stress are warned about."""
    name, _ = area_correction(inp)
    yield_stress = inp["contact.yield_stress"]
    asked = sorted(set(PLASTIC) & inp.wanted)
    if asked and yield_stress is None:
        raise UserError(f"{asked[0]} needs a penetration hardness: set [contact] yield_stress (e.g. \"1.5 GPa\")",
                        key="contact.yield_stress")
    if yield_stress is None:
        return
    if name != "persson":
        raise UserError(f"contact.yield_stress works with contact.correction = \"persson\" only (the absorbing wall "
                        f"at sigma_Y is solved for eq 17's G), not \"{name}\"", key="contact.correction")
    p_max = float(np.max(np.asarray(inp["load.p"], dtype=float)))
    if p_max >= yield_stress:
        warnings.warn(SceneWarning(
            f"load.p reaches {p_max:.4g} Pa, at or above contact.yield_stress = {yield_stress:.4g} Pa: there the "
            "interface cannot carry the load (A_pl/A0 = 1, A_el/A0 = 0 are written; the solid yields as a whole)"),
            stacklevel=2)


def describe_contact(inp: StageInput) -> Shape:
    """The dimensions the stage adds (zeta, which must lie on the psd stage's q grid and see the
    rough surfaces, and the stress grid when P(sigma) is asked for) and
    its working memory per sweep point: a few float64 temporaries, times the stress grid when
    P(sigma) is asked for, times the q grid when zeta = "all". G does not span p, and nothing but
    P and its stress grid sigma spans the stress grid; zeta is computed whole."""
    zeta = zeta_shape(inp, inp.upstream["psd"])
    stress = "stress_distribution" in inp.wanted
    work = {"temporaries": 8 * (inp["numerics.sigma_points"] if stress else 2),
            **({"q": inp.upstream["psd"].sizes["q"]} if isinstance(inp["contact.zeta"], str) else {})}
    lacks = {"G": ("p", "stress_level"), "contact_area_ratio": ("stress_level",),
             **{name: ("stress_level",) for name in PLASTIC},
             "E_star": ("p", "zeta", "stress_level"), "qL": ("p", "zeta", "stress_level")}
    if not stress:
        return dataclasses.replace(zeta, work=work, lacks=lacks, coupled=("zeta",))
    lacks.update(stress_distribution_mass=("stress_level",), sigma=())  # written with P: its mass, its stress grid
    return dataclasses.replace(zeta, sizes={**zeta.sizes, "stress_level": inp["numerics.sigma_points"]},
                               keys={**zeta.keys, "stress_level": "numerics.sigma_points"}, work=work, lacks=lacks,
                               coupled=("zeta",))


STAGE = register(
    Stage(
        name="contact",
        version="3",  # contact.yield_stress (default none) adds optional outputs only
        compute=compute_contact,
        needs=("psd",),
        reads=(*MATERIAL_KEYS, *COATING_KEYS, "load.p", "contact.zeta", "numerics.sigma_points", "numerics.sigma_width",
                *CORRECTION_KEYS, "contact.yield_stress"),
        outputs={
            "G": Var("Pa^2", "Persson's G(zeta)",
                     comment="G = (pi/4) E*^2 int_qL^(zeta qL) q^3 C dq (eq 17)"),
            "contact_area_ratio": Var("1", "relative contact area A/A0", tolerance=1e-4,
                                      comment="A/A0 = erf(p / 2 sqrt G) (eq 19); with contact.correction, "
                                              "G -> G_eff (attribute 'correction')"),
            "E_star": E_STAR,
            "qL": Q_REFERENCE,
            "stress_distribution": Var("1/Pa", "stress distribution P(sigma)", optional=True,
                                       comment="P(sigma; p, zeta) of eq 16, on the stress grid sigma"),
            "stress_distribution_mass": Var(
                "1", "integral of P(sigma) over the stress grid", optional=True,
                comment="trapezoidal rule over the stored stress grid; stored with stress_distribution; "
                        "equals contact_area_ratio within 1e-3 (relative) "
                        "at numerics.sigma_points >= 401 and sigma_width >= 8 (the defaults); a coarser grid "
                        "shows here how much of the distribution it misses"),
            "elastic_contact_area_ratio": Var(
                "1", "elastic contact area A_el/A0", optional=True,
                comment="Persson's theory with absorbing walls at sigma = 0 and sigma = contact.yield_stress "
                        "(docs/plasticity.md): contact spots below the penetration hardness"),
            "plastic_contact_area_ratio": Var(
                "1", "plastic contact area A_pl/A0", optional=True,
                comment="contact spots at the penetration hardness (the flux through sigma = "
                        "contact.yield_stress accumulated over zeta); elastic load + yield_stress "
                        "A_pl/A0 = p (docs/plasticity.md)"),
        },
        coords={
            "sigma": Var("Pa", "local normal stress sigma",
                         comment="the stress at each node of the stress grid of every point"),
            "stress_level": Var("1", "node of the stress grid",
                                comment="sigma = lo + stress_level (hi - lo), lo = max(0, p - sigma_width "
                                        "sqrt(G)), hi = p + sigma_width sqrt(G) ([0, 2p] where G = 0)"),
        },
        figures=(
            Figure("fig3_contact_area", "A/A0 against p/E* (seed Fig. 3)", ("contact",), figure_contact_area),
            Figure("fig4_stress_distribution", "P(sigma) (seed Fig. 4)", ("contact",), figure_stress_distribution,
                   outputs=("stress_distribution",)),
            Figure("elastoplastic_area", "A_el/A0 and A_pl/A0 against p", ("contact",), figure_elastoplastic_area,
                   outputs=PLASTIC),
            Figure("coating_modulus", "coated solid: E_eff(q) and sqrt(G) against q", ("psd", "contact"),
                   figure_coating_modulus),
            Figure("coating_area", "coated solid: A/A0 against p for each coating thickness", ("contact",),
                   figure_coating_area),
        ),
        check=check_contact,
        describe=describe_contact,
        doc="G(zeta), A/A0(p, zeta, eta) and optionally P(sigma; p, zeta, eta).",
    )
)
