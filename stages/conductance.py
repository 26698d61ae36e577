"""Stage ``conductance``: thermal and electrical contact conductance per unit nominal area of the
two rough solids, from the contact stiffness by Barber's analogy, over (p, zeta, eta).

Kernels: :func:`roughcontact.physics.interface.barber_conductance` and
:func:`~roughcontact.physics.interface.barber_resistance`. Scene: ``[conductance]`` with the
thermal conductivities and / or the electrical resistivities of both bodies. Figure:
:mod:`roughcontact.stages.figures.interface`. See docs/interface.md.
"""

from __future__ import annotations

import xarray as xr

from roughcontact.physics.interface import barber_conductance, barber_resistance
from roughcontact.stage import Figure, Param, Section, Stage, StageInput, UserError, Var, register, register_section

from .figures.interface import figure_conductance
from .shared.material import COATING_KEYS, MATERIAL_KEYS, e_star, refuse_coating

#: (scene key prefix, what it is, SI units) of the two transport properties
PROPERTIES = {"thermal": ("thermal_conductivity", "thermal conductivity", "W/(m*K)"),
              "electrical": ("resistivity", "electrical resistivity", "ohm*m")}

register_section(
    Section(
        "conductance",
        tuple(
            Param(f"{prefix}_{body}", "quantity", units, default=None, lo=0.0, lo_open=True,
                  doc=f"{what} of the {body} (> 0); give it for both bodies or for neither")
            for prefix, what, units in PROPERTIES.values() for body in ("substrate", "solid")
        ),
        doc="transport properties of the two bodies for the conductance stage (thermal, electrical or both)",
        optional=True,
    )
)

KEYS = tuple(f"conductance.{prefix}_{body}" for prefix, _, _ in PROPERTIES.values() for body in ("substrate", "solid"))


def _series(inp: StageInput, kind: str):
    """R = 1/kappa1 + 1/kappa2 (m K/W) or rho1 + rho2 (Ohm m), or None when the scene gives neither
    body's value; a UserError when it gives only one."""
    prefix = PROPERTIES[kind][0]
    values = {body: inp[f"conductance.{prefix}_{body}"] for body in ("substrate", "solid")}
    given = [body for body, v in values.items() if v is not None]
    if not given:
        return None
    if len(given) == 1:
        missing = next(body for body in values if body not in given)
        raise UserError(f"the {PROPERTIES[kind][1]} is given for the {given[0]} only; give it for the {missing} too",
                        key=f"conductance.{prefix}_{missing}")
    if kind == "thermal":
        return 1.0 / values["substrate"] + 1.0 / values["solid"]
    return values["substrate"] + values["solid"]


def check_conductance(inp: StageInput) -> None:
    """At least one of the two properties, for both bodies; no coating (Barber's analogy needs
    homogeneous bodies)."""
    refuse_coating(inp, "the conductance stage (Barber's analogy holds for homogeneous bodies)")
    if _series(inp, "thermal") is None and _series(inp, "electrical") is None:
        raise UserError("the conductance stage needs the thermal conductivities or the electrical resistivities of "
                        "both bodies (e.g. thermal_conductivity_substrate = \"50 W/(m*K)\")", key="conductance")


def compute_conductance(inp: StageInput) -> xr.Dataset:
    check_conductance(inp)
    up = inp.upstream["stiffness"]
    E_star = e_star(inp)
    K, D = up["contact_stiffness"], up["stiffness_length"]
    p = D["p"] if "p" in D.coords else xr.DataArray(float(inp["load.p"]))
    # which separation law (and contact theory) the stiffness it rests on used
    ds = xr.Dataset(attrs={k: v for k, v in up.attrs.items() if k.startswith(("separation_", "contact_"))})
    for kind, (conductance, resistance) in NAMES.items():
        R = _series(inp, kind)
        if R is None:
            continue
        ds[conductance] = xr.apply_ufunc(barber_conductance, K, E_star, R, dask="parallelized", output_dtypes=[float])
        ds[resistance] = xr.apply_ufunc(barber_resistance, p, D, E_star, R, dask="parallelized",
                                        output_dtypes=[float]).transpose(*D.dims)
        ds[conductance].attrs = {"formula": "2 K / (E* R), Barber's analogy", "R": R}
    return ds


NAMES = {"thermal": ("thermal_contact_conductance", "thermal_contact_resistance"),
         "electrical": ("electrical_contact_conductance", "electrical_contact_resistance")}
ASSUMPTIONS = ("heat / current only through the real contact (no gas, no radiation, no film or spot resistance), "
               "constant conductivities, small slopes (half-spaces); +inf where the contact stiffness is infinite "
               "(surfaces that fit exactly, e.g. identical surfaces with eta = 1): the matching resistance is "
               "exactly 0")

register(
    Stage(
        name="conductance",
        version="2",
        compute=compute_conductance,
        check=check_conductance,
        needs=("stiffness",),
        reads=(*MATERIAL_KEYS, *COATING_KEYS, "load.p", *KEYS),
        outputs={
            "thermal_contact_conductance": Var("W/(m^2*K)", "thermal contact conductance h",
                                               comment="per unit nominal area, h = 2 K / (E* (1/kappa1 + "
                                                       f"1/kappa2)); {ASSUMPTIONS}"),
            "thermal_contact_resistance": Var("m^2*K/W", "thermal contact resistance 1/h",
                                              comment="times the nominal area"),
            "electrical_contact_conductance": Var("S/m^2", "electrical contact conductance",
                                                  comment="per unit nominal area, 2 K / (E* (rho1 + rho2)); "
                                                          f"{ASSUMPTIONS}"),
            "electrical_contact_resistance": Var("ohm*m^2", "electrical contact resistance times nominal area"),
        },
        figures=(Figure("conductance", "thermal and electrical contact conductance against p", ("conductance",),
                        figure_conductance),),
        doc="Thermal and electrical contact conductance per unit area (Barber's analogy with the contact stiffness).",
    )
)
