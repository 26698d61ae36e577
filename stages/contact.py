"""Stage ``contact``: G(zeta), the relative contact area A/A0(p, zeta, eta) and, when asked
for, the stress distribution P(sigma; p, zeta, eta).

Kernels: :mod:`roughcontact.physics.contact` (seed eqs 16-19, 53). Figures:
:mod:`roughcontact.stages.figures.contact` (seed Figs 3 and 4).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from roughcontact.physics.contact import contact_area_ratio, persson_G, stress_distribution_adaptive
from roughcontact.physics.corrections import CORRECTIONS, corrected_G
from roughcontact.stage import Figure, Param, Preview, Stage, StageInput, Var, register, register_params

from .figures.contact import figure_contact_area, figure_stress_distribution
from .shared import CORRECTION_KEYS, E_STAR, MATERIAL_KEYS, area_correction, e_star, zeta_preview, zeta_values

register_params(
    "numerics",
    Param("sigma_points", "int", default=401, lo=3, doc="nodes of the stress grid of P(sigma)"),
    Param("sigma_width", "quantity", "", default=8.0, lo=1.0,
          doc="the stress grid of each (p, zeta, eta) spans max(0, p - sigma_width sqrt(G)) .. p + sigma_width sqrt(G)"),
)


def compute_contact(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = e_star(inp)
    zeta = xr.DataArray(zeta_values(inp, q), dims=("zeta",))
    G = xr.apply_ufunc(
        persson_G, psd["q"], psd["psd_combined"], zeta * q[0], E_star,
        input_core_dims=[["q"], ["q"], ["zeta"], []], output_core_dims=[["zeta"]],
        dask="parallelized", output_dtypes=[float],
    ).assign_coords(zeta=zeta)
    p = inp.sweep("p", inp["load.p"])
    G_area = _corrected(inp, p, G)
    area = xr.apply_ufunc(contact_area_ratio, p, G_area, dask="parallelized", output_dtypes=[float])
    area.attrs = _correction_attrs(inp)
    ds = xr.Dataset({"G": G, "contact_area_ratio": area, "E_star": xr.DataArray(E_star)})
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
    return ds


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


def validate_contact(inp: StageInput) -> Preview:
    """Before anything computes: the magnifications asked for lie on the psd stage's q grid;
    returns the sizes of the dimensions the stage adds (zeta, and the stress grid). A correction's
    gamma that makes S(A/A0) <= 0 is refused here too."""
    area_correction(inp)
    zeta = zeta_preview(inp, inp.upstream["psd"])
    if "stress_distribution" not in inp.wanted:
        return zeta
    return dataclasses.replace(zeta, sizes={**zeta.sizes, "stress_level": inp["numerics.sigma_points"]},
                               keys={**zeta.keys, "stress_level": "numerics.sigma_points"})


def _result_bytes(params, wanted, sizes) -> int:
    """G over everything but p; A/A0 (and the mass of P) over everything but the stress grid; P and
    sigma over everything (the engine adds the coordinates)."""
    full = int(np.prod(list(sizes.values()), dtype=float))
    area = full // sizes.get("stress_level", 1)
    stress = 2 * full + area if "stress_distribution" in wanted else 0
    return 8 * (area // sizes.get("p", 1) + area + stress)


def _point_bytes(params, wanted, upstream) -> int:
    """Working memory per sweep point: a few float64 temporaries, times the stress grid when
    P(sigma) is asked for, times the q grid when zeta = "all" adds a dimension of that size."""
    per = 8 * 4 * (params["numerics.sigma_points"] if "stress_distribution" in wanted else 2)
    if isinstance(params["contact.zeta"], str) and "psd" in upstream:
        per *= upstream["psd"].sizes["q"]
    return per


STAGE = register(
    Stage(
        name="contact",
        version="2",
        compute=compute_contact,
        requires=("psd",),
        params=(*MATERIAL_KEYS, "load.p", "contact.zeta", "numerics.sigma_points", "numerics.sigma_width",
                *CORRECTION_KEYS),
        outputs={
            "G": Var("Pa^2", "Persson's G(zeta) = (pi/4) E*^2 int_qL^(zeta qL) q^3 C dq (eq 17)"),
            "contact_area_ratio": Var("1", "relative contact area A/A0 = erf(p / 2 sqrt G) (eq 19; with "
                                              "contact.correction: G -> G_eff, attribute 'correction')"),
            "E_star": E_STAR,
            "stress_distribution": Var("1/Pa", "stress distribution P(sigma; p, zeta) (eq 16)", optional=True),
            "stress_distribution_mass": Var(
                "1", "integral of P(sigma) over the stored stress grid (trapezoidal rule)", optional=True,
                attrs={"comment": "stored with stress_distribution; equals contact_area_ratio within 1e-3 (relative) "
                                  "at numerics.sigma_points >= 401 and sigma_width >= 8 (the defaults); a coarser grid "
                                  "shows here how much of the distribution it misses"}),
        },
        coords={
            "sigma": Var("Pa", "local normal stress sigma at each node of the stress grid"),
            "stress_level": Var("1", "node of the stress grid: sigma = lo + stress_level (hi - lo), lo = max(0, p - "
                                     "sigma_width sqrt(G)), hi = p + sigma_width sqrt(G) ([0, 2p] where G = 0)"),
        },
        figures=(
            Figure("fig3_contact_area", "A/A0 against p/E* (seed Fig. 3)", ("contact",), figure_contact_area),
            Figure("fig4_stress_distribution", "P(sigma) (seed Fig. 4)", ("contact",), figure_stress_distribution,
                   outputs=("stress_distribution",)),
        ),
        doc="G(zeta), A/A0(p, zeta, eta) and optionally P(sigma; p, zeta, eta).",
        point_bytes=_point_bytes,
        validate=validate_contact,
        result_bytes=_result_bytes,
        unchunked=("zeta",),
        main_outputs=("contact_area_ratio",),
        tolerance=1e-4,
    )
)
