"""Stage ``contact``: G(zeta), the relative contact area A/A0(p, zeta, eta) and, when asked
for, the stress distribution P(sigma; p, zeta, eta).

Kernels: :mod:`roughcontact.physics.contact` (seed eqs 16-19, 53). Figures:
:mod:`roughcontact.stages.figures.contact` (seed Figs 3 and 4).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.contact import contact_area_ratio, persson_G, stress_distribution_adaptive
from roughcontact.physics.corrections import CORRECTIONS, corrected_G
from roughcontact.stage import Figure, Param, Stage, StageInput, Var, register, register_params

from .figures.contact import figure_contact_area, figure_stress_distribution
from .shared import CORRECTION_KEYS, E_STAR, MATERIAL_KEYS, area_correction, e_star, zeta_values

register_params(
    "numerics",
    Param("sigma_points", "int", default=401, lo=3, doc="nodes of the stress grid of P(sigma)"),
    Param("sigma_width", "quantity", "", default=8.0, lo=1.0,
          doc="the stress grid of each (p, zeta, eta) reaches p + sigma_width sqrt(G)"),
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
        dist, sigma = xr.apply_ufunc(
            stress_distribution_adaptive, level, p, G_area, inp["numerics.sigma_width"],
            input_core_dims=[["stress_level"], [], [], []], output_core_dims=[["stress_level"], ["stress_level"]],
            dask="parallelized", output_dtypes=[float, float],
        )
        ds["stress_distribution"] = dist
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


def _point_bytes(params, wanted, upstream) -> int:
    """Working memory per sweep point: a few float64 temporaries, times the stress grid when
    P(sigma) is asked for, times the q grid when zeta = "all" adds a dimension of that size."""
    per = 8 * 4 * (params["numerics.sigma_points"] if "stress_distribution" in wanted else 2)
    if isinstance(params["contact.zeta"], str) and "psd" in upstream:
        per *= upstream["psd"].sizes["q"]
    return per


register(
    Stage(
        name="contact",
        version="1",
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
        },
        coords={
            "sigma": Var("Pa", "local normal stress sigma at each node of the stress grid"),
            "stress_level": Var("1", "node of the stress grid, sigma / (p + sigma_width sqrt(G))"),
        },
        figures=(
            Figure("fig3_contact_area", "A/A0 against p/E* (seed Fig. 3)", ("contact",), figure_contact_area),
            Figure("fig4_stress_distribution", "P(sigma) (seed Fig. 4)", ("contact",), figure_stress_distribution,
                   outputs=("stress_distribution",)),
        ),
        doc="G(zeta), A/A0(p, zeta, eta) and optionally P(sigma; p, zeta, eta).",
        point_bytes=_point_bytes,
        main_outputs=("contact_area_ratio",),
        tolerance=1e-4,
    )
)
