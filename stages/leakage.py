"""Stage ``leakage``: the leak rate of a static seal over (p, eta) by the critical-junction theory
and by the effective-medium (Bruggeman) theory, with the pressure at which each says the seal
closes (the non-contact area stops percolating).

Kernels: :mod:`roughcontact.physics.leakage` (on Persson's A(zeta) and the separation u_bar(zeta)
of the roughness above each magnification, eq 57's kernels). Scene: ``[leakage]`` (liquid,
pressure drop, seal size, percolation threshold). Figure: :mod:`roughcontact.stages.figures.interface`.
See docs/interface.md.
"""

from __future__ import annotations

import xarray as xr

from roughcontact.physics.effective_medium import BRUGGEMAN_AREA
from roughcontact.physics.leakage import PERCOLATION_AREA, leak_rate, leakage_kernel, sealing_pressure
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Shape,
    Stage,
    StageInput,
    Var,
    register,
    register_params,
    register_section,
)

from .figures.interface import figure_leakage
from .separation import check_separation, theory_attrs
from .shared.magnification import area_correction
from .shared.material import COATING_KEYS, MATERIAL_KEYS, e_star, refuse_coating
from .stiffness import SEPARATION_KEYS, separation_settings

register_section(
    Section(
        "leakage",
        (
            Param("viscosity", "quantity", "Pa*s", lo=0.0, lo_open=True, doc="dynamic viscosity of the liquid (> 0)"),
            Param("pressure_drop", "quantity", "Pa", lo=0.0, lo_open=True,
                  doc="pressure difference across the seal (> 0), with units"),
            Param("seal_width", "quantity", "m", lo=0.0, lo_open=True,
                  doc="width W of the seal across the flow, e.g. an O-ring's circumference (> 0)"),
            Param("seal_length", "quantity", "m", lo=0.0, lo_open=True,
                  doc="length L of the seal along the flow, the nominal contact's width (> 0); Q ~ W/L"),
            Param("percolation_area", "quantity", "", default=PERCOLATION_AREA, lo=0.0, hi=1.0, lo_open=True,
                  hi_open=True, doc="A/A0 at which the non-contact area stops percolating (critical junction; "
                                    "0.42: Dapp et al. 2012)"),
        ),
        doc="the seal and the liquid of the leakage stage",
    )
)
register_params(
    "numerics",
    Param("leakage_bins_per_decade", "int", default=20, lo=2, hi=400, presets={"fast": 10, "accurate": 40},
          ladder=(5, 10, 20, 40, 80), doc="logarithmic bins per decade of the gap u in P(u) (effective medium)"),
    Param("leakage_points_per_decade", "int", default=20, lo=1, presets={"fast": 10, "accurate": 40},
          ladder=(5, 10, 20, 40, 80), doc="magnifications 1 + delta per decade of delta at which P(u) is resolved"),
)

SEAL_KEYS = ("leakage.viscosity", "leakage.pressure_drop", "leakage.seal_width", "leakage.seal_length")
NUMERICS = ("numerics.leakage_bins_per_decade", "numerics.leakage_points_per_decade")


def leakage_settings(inp: StageInput, q_top: float) -> dict:
    """The keywords of :func:`roughcontact.physics.leakage.leakage_kernel` from the scene, on the
    band [qL, q_top]."""
    settings = separation_settings(inp)
    alpha, refinement = settings.pop("alpha"), settings.pop("refinement")
    correction, gamma = area_correction(inp)
    return dict(E_star=e_star(inp), alpha=alpha, refinement=refinement, numerics=settings,
                area=float(inp["leakage.percolation_area"]), q_top=q_top, correction=correction, gamma=gamma,
                bins_per_decade=inp["numerics.leakage_bins_per_decade"],
                points_per_decade=inp["numerics.leakage_points_per_decade"])


def leakage_theory_attrs(inp: StageInput, kw: dict) -> dict:
    """Which theory the leak rates used: the contact-area theory of A(zeta)/A0 (``contact_correction``,
    ``contact_gamma``), the separation law (:func:`roughcontact.stages.separation.theory_attrs`) and
    the gap distribution of the effective medium."""
    return {**theory_attrs(inp, {"alpha": kw["alpha"], "refinement": kw["refinement"]}),
            "contact_correction": kw["correction"], "contact_gamma": "none" if kw["gamma"] is None else kw["gamma"],
            "gap_distribution": GAP_DISTRIBUTION}


#: what the effective medium's P(u) is (docs/interface.md)
GAP_DISTRIBUTION = ("Almqvist et al. 2011 reflected normals of the finer roughness's width, each with the mean gap "
                    "that conserves the volume A u_bar: the mean of P(u) is the mean separation u_bar")


def seal_parameters(inp: StageInput) -> tuple[float, float, float, float]:
    """(dp (Pa), mu (Pa s), W (m), L (m)): the trailing arguments of
    :func:`roughcontact.physics.leakage.leak_rate`, Q = (W/L) sigma dp / (12 mu)."""
    return tuple(float(inp[k]) for k in ("leakage.pressure_drop", "leakage.viscosity", "leakage.seal_width",
                                         "leakage.seal_length"))


def check_leakage(inp: StageInput) -> None:
    """The separation law's checks, and no coating (the seal theories take a homogeneous solid)."""
    check_separation(inp)
    refuse_coating(inp, "the leakage stage")


def compute_leakage(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q, C = psd["q"], psd["psd_combined"]
    kw = leakage_settings(inp, float(q[-1]))
    zeta_c, u1, s_cj, s_emt = xr.apply_ufunc(
        leakage_kernel, q, C, inp.sweep("p", inp["load.p"]), kwargs=kw, input_core_dims=[["q"], ["q"], []],
        output_core_dims=[[]] * 4, dask="parallelized", output_dtypes=[float] * 4,
    )
    ds = xr.Dataset({"critical_magnification": zeta_c, "critical_gap": u1, "flow_factor_critical_junction": s_cj,
                     "flow_factor_effective_medium": s_emt})
    for method, area in (("critical_junction", kw["area"]), ("effective_medium", BRUGGEMAN_AREA)):
        ds[f"sealing_pressure_{method}"] = xr.apply_ufunc(
            sealing_pressure, q, C, kw["E_star"], area, None, kw["correction"], kw["gamma"],
            input_core_dims=[["q"], ["q"], [], [], [], [], []])
        ds[f"leak_rate_{method}"] = xr.apply_ufunc(leak_rate, ds[f"flow_factor_{method}"], *seal_parameters(inp),
                                                   dask="parallelized", output_dtypes=[float])
    ds["critical_magnification"].attrs = {
        "nan_reason": "NaN where A(q_max)/A0 >= leakage.percolation_area: the non-contact area does not percolate "
                      "at any magnification (the seal is closed; critical_gap and the leak rate are 0)"}
    width, length = seal_parameters(inp)[2:]
    ds.attrs.update({"leakage_percolation_area": kw["area"], "leakage_bruggeman_area": BRUGGEMAN_AREA,
                     "leakage_aspect_ratio": width / length, **leakage_theory_attrs(inp, kw)})
    if "p" in ds.dims:
        ds = ds.transpose(..., "p")
    return ds


def describe_leakage(inp: StageInput) -> Shape:
    """No dimension of its own; working memory per (p, eta) point: the gap distribution's
    distribution function on (magnifications x gap bins), about 15 decades of zeta - 1 by 10
    decades of u, a few float64 temporaries. The sealing pressures do not span p."""
    magnifications = 15 * int(inp["numerics.leakage_points_per_decade"]) + 2
    bins = 10 * int(inp["numerics.leakage_bins_per_decade"]) + 3
    return Shape(work={"temporaries": 4, "magnification": magnifications, "gap_bin": bins},
                 lacks={"sealing_pressure_critical_junction": ("p",), "sealing_pressure_effective_medium": ("p",)})


FLOW = "Q = (W/L) sigma dp / (12 mu), sigma = "
register(
    Stage(
        name="leakage",
        version="2",
        compute=compute_leakage,
        check=check_leakage,
        needs=("psd",),
        reads=(*MATERIAL_KEYS, "load.p", *SEPARATION_KEYS, *SEAL_KEYS, "leakage.percolation_area", *NUMERICS,
               *COATING_KEYS),
        outputs={
            "leak_rate_critical_junction": Var("m^3/s", "leak rate, critical-junction theory", tolerance=1e-4,
                                               attrs={"formula": FLOW + "u1^3",
                                                      "comment": "leak rate of the seal (Persson & Yang 2008)"}),
            "leak_rate_effective_medium": Var("m^3/s", "leak rate, effective-medium theory",
                                              attrs={"formula": FLOW + "Bruggeman",
                                                     "comment": "leak rate of the seal (Lorenz & Persson 2010); "
                                                                + GAP_DISTRIBUTION}),
            "flow_factor_critical_junction": Var("m^3", "flow factor u1^3 of the critical junction",
                                                 comment="effective flow factor"),
            "flow_factor_effective_medium": Var("m^3", "Bruggeman's 2D effective flow factor sigma"),
            "critical_magnification": Var("1", "critical magnification zeta_c",
                                          comment="magnification at which the non-contact area "
                                                  "percolates, A(zeta_c)/A0 = leakage.percolation_area"),
            "critical_gap": Var("m", "critical gap u1(zeta_c)",
                                comment="separation of the critical constriction"),
            "sealing_pressure_critical_junction": Var("Pa", "sealing pressure, critical-junction theory",
                                                      comment="nominal pressure above which the "
                                                              "critical-junction theory has no open path "
                                                              "(A(q_max)/A0 = percolation_area)"),
            "sealing_pressure_effective_medium": Var("Pa", "sealing pressure, effective-medium theory",
                                                     comment="nominal pressure above which Bruggeman's "
                                                             "medium does not conduct (A(q_max)/A0 = 1/2)"),
        },
        figures=(Figure("leakage", "leak rate of the seal against the contact pressure", ("leakage",),
                        figure_leakage),),
        doc="Leak rate of a seal over (p, eta): critical-junction and effective-medium theories.",
        describe=describe_leakage,
    )
)
