"""The flash-temperature option of the ``friction`` stage: scene keys, the temperature law read from
the modulus stage's result, and the wrapper that runs the kernels of
:mod:`roughcontact.physics.flash` over the sweep (docs/theory.md, section "Flash temperature";
docs/friction.md).

Not a stage of its own: :mod:`roughcontact.stages.friction` declares the keys and the outputs
and calls :func:`compute_flash` when ``friction.flash = true``.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from roughcontact.physics.flash import background_march, flash_friction_kernel
from roughcontact.physics.viscoelastic import shift_factors
from roughcontact.stage import Param, SceneWarning, UserError, Var

#: keys of [friction] for the flash temperature (declared in the friction section)
FLASH_PARAMS = (
    Param("flash", "bool", default=False,
          doc="flash temperature (Persson 2006): the modulus at each scale is read at the temperature of the contacts"),
    Param("thermal_conductivity", "quantity", "W/(m*K)", default=None, lo=0.0, lo_open=True,
          doc="thermal conductivity of the rubber (needed with flash)"),
    Param("density", "quantity", "kg/m^3", default=None, lo=0.0, lo_open=True,
          doc="mass density of the rubber (needed with flash)"),
    Param("heat_capacity", "quantity", "J/(kg*K)", default=None, lo=0.0, lo_open=True,
          doc="specific heat capacity of the rubber (needed with flash)"),
    Param("background", "choice", default="none", choices=("none", "semi_infinite"),
          doc="background (cumulative) heating of the nominal contact: none, or the mean frictional heat flux "
              "into a semi-infinite rubber over the sliding time"),
    Param("sliding_distance", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="sliding distance of the background heating (sliding time = distance / v)"),
)

#: numerics of the flash temperature (registered in [numerics] by the friction stage)
FLASH_NUMERICS = (
    Param("flash_shift_step", "quantity", "", default=0.05, lo=0.0, lo_open=True,
          presets={"fast": 0.1, "accurate": 0.02},
          ladder=(0.4, 0.2, 0.1, 0.05, 0.05, 0.03, 0.02, 0.01, 0.005),
          doc="largest change of log10 a_T per q step of the flash-temperature march "
              "(finer sub-steps where it heats fast)"),
    Param("flash_time_nodes", "int", default=16, lo=3, presets={"fast": 10, "accurate": 24},
          doc="time nodes of the background-heating march (geometric over 6 decades of the sliding time)"),
)

FLASH_KEYS = tuple(f"friction.{p.name}" for p in FLASH_PARAMS) + tuple(f"numerics.{p.name}" for p in FLASH_NUMERICS)

#: outputs the friction stage writes with the flash temperature (when asked for in outputs.variables)
FLASH_OUTPUTS = {
    "friction_coefficient_isothermal": Var("1", "friction coefficient mu, isothermal", optional=True,
                                           comment="hysteretic friction coefficient without the flash "
                                                   "temperature; eq 61"),
    "flash_temperature": Var("K", "flash temperature T_q at q1", optional=True,
                             comment="temperature of the asperity contacts at the highest magnification"),
    "background_temperature_rise": Var("K", "background temperature rise", optional=True,
                                       comment="background (cumulative) temperature rise of the nominal "
                                               "contact at the end of sliding (semi-infinite rubber)"),
    "flash_temperature_profile": Var("K", "contact temperature T_q at magnification q", optional=True,
                                     comment="temperature T_q of the contacts observed at magnification q"),
    "frictional_heating": Var("W/m^2", "frictional heating per unit ln q", optional=True,
                              comment="heat released per unit nominal area and time per unit ln q, "
                                      "sigma0 v d mu / d ln q"),
}

#: a flash-temperature output asked for without friction.flash = true
NEEDS_FLASH = ("set friction.flash = true (and the rubber's thermal_conductivity, density, heat_capacity) "
               "to compute {name}")


def check_flash(inp) -> tuple[float, float, float] | None:
    """(lambda, D, effusivity) of the rubber when the flash temperature is on, else None; a
    UserError naming the missing key or the output that needs the option."""
    if not inp["friction.flash"]:
        for name in FLASH_OUTPUTS:
            if name in inp.wanted:
                raise UserError(NEEDS_FLASH.format(name=name), key="friction.flash")
        return None
    values = {}
    for name in ("thermal_conductivity", "density", "heat_capacity"):
        values[name] = inp[f"friction.{name}"]
        if values[name] is None:
            raise UserError(f"the flash temperature needs the rubber's {name.replace('_', ' ')}",
                            key=f"friction.{name}")
    if inp["friction.background"] != "none" and inp["friction.sliding_distance"] is None:
        raise UserError("background heating needs the sliding distance", key="friction.sliding_distance")
    if inp["friction.background"] == "none" and "background_temperature_rise" in inp.wanted:
        raise UserError("background_temperature_rise needs a background heating model", key="friction.background")
    lam, rho_c = values["thermal_conductivity"], values["density"] * values["heat_capacity"]
    return lam, lam / rho_c, float(np.sqrt(lam * rho_c))


def temperature_law(mod: xr.Dataset):
    """T -> (log10 a_T, b_T) of the modulus stage's result (its WLF constants, with the WLF-Arrhenius
    law T_g and E_a, shift table and vertical shift), with which E(omega, T) = b_T E(omega a_T, T_ref)."""
    horizontal = mod.attrs.get("horizontal_shift", "none")
    vertical = mod.attrs.get("vertical_shift", "none")
    T_ref = float(mod["reference_temperature"]) if "reference_temperature" in mod else None
    C1 = float(mod["wlf_C1"]) if "wlf_C1" in mod else 17.44
    C2 = float(mod["wlf_C2"]) if "wlf_C2" in mod else 51.6
    T_g = float(mod["glass_transition_temperature"]) if "glass_transition_temperature" in mod else None
    E_a = float(mod["arrhenius_activation_energy"]) if "arrhenius_activation_energy" in mod else None
    table_T = mod["shift_T"].values if "shift_T" in mod.coords else None
    log_aT = mod["shift_table_log10_aT"].values if "shift_table_log10_aT" in mod else None
    log_bT = mod["shift_table_log10_bT"].values if "shift_table_log10_bT" in mod else None

    def law(T):
        T = np.asarray(T, dtype=float)
        log_a, b = shift_factors(T.ravel(), T_ref, horizontal, vertical, C1, C2, table_T, log_aT, log_bT, T_g, E_a)
        return np.reshape(log_a, T.shape), np.reshape(b, T.shape)

    return law


def _kernel(q, C, v, T_s, grid, Ep, Epp, p, nu, *, law, thermal, n_phi, correction, gamma, n_seg, max_shift,
            background, distance, time_nodes, profile, area=("persson", None)):
    """Stage-side kernel: mu, A/A0, T at q1 (and the background rise, the T_q profile and the heat
    released over q) for one block of the sweep, with the modulus at E(omega, T) = b_T/b_Ts
    E_stored(omega a_T/a_Ts)."""
    lam, D, effusivity = thermal
    log_as, b_s = law(T_s)

    def shift(T):
        log_a, b = law(T)
        return 10.0 ** (log_a - log_as), b / b_s

    def run(T_start, with_profile):
        return flash_friction_kernel(q, C, v, T_start, grid, Ep, Epp, n_phi, p, nu, lam, D, shift, correction, gamma,
                                     n_seg, 1e-6, max_shift, with_profile, area)

    rise = np.zeros(np.broadcast_shapes(np.shape(v), np.shape(T_s), np.shape(p), np.shape(C)[:-1]))
    if background == "semi_infinite":
        times = np.concatenate([[0.0], np.geomspace(1e-6, 1.0, time_nodes - 1)])
        flux = lambda T: (lambda out: (out[0] * p * v, out))(run(T, False))  # noqa: E731
        rise, out = background_march(times, distance / v, flux, effusivity, T_s)
        if profile:
            out = run(T_s + rise, True)
    else:
        out = run(T_s, profile)
    return (out[0], out[1], out[2], np.broadcast_to(rise, np.shape(out[0]))) + tuple(out[3:])


def data_temperature_range(mod: xr.Dataset) -> tuple[float, float, str] | None:
    """(T_min, T_max, what) of the measurements behind the modulus' temperature law, in K: the DMA
    sweeps' temperatures (the WLF law or shifts fitted to them), or a given shift table's; None
    when the law is not tied to data (WLF with given constants, no shift)."""
    if mod.attrs.get("model") == "dma" and "sweep_temperature_range" in mod.attrs:
        lo, hi, _ = str(mod.attrs["sweep_temperature_range"]).split()
        return float(lo), float(hi), "DMA sweeps"
    if mod.attrs.get("model") == "dma":
        temps = mod["shift_T"].values if "shift_T" in mod.coords else (
            mod["dma_temperature"].values if "dma_temperature" in mod else None)
        what = "DMA sweeps"
    elif mod.attrs.get("horizontal_shift") == "table" and "shift_T" in mod.coords:
        temps, what = mod["shift_T"].values, "shift table"
    else:
        return None
    if temps is None or np.size(temps) == 0:
        return None
    return float(np.min(temps)), float(np.max(temps)), what


def _celsius(T: float) -> str:
    return f"{T - 273.15:.0f} degC"


def warn_outside_data(T_contact: xr.DataArray, v: xr.DataArray, mod: xr.Dataset, tolerance: float = 1.0) -> None:
    """A SceneWarning when the contacts' temperature leaves the temperature range of the data the
    modulus' temperature law was fitted to by more than ``tolerance`` K: the modulus there is
    extrapolated (WLF beyond the sweeps; a table's a_T held constant)."""
    data = data_temperature_range(mod)
    if data is None:
        return
    lo, hi, what = data
    T = np.asarray(T_contact.values, dtype=float)
    over, under = float(np.nanmax(T)) - hi, lo - float(np.nanmin(T))
    if max(over, under) <= tolerance:
        return
    outside = (T_contact > hi + tolerance) | (T_contact < lo - tolerance)
    other = [d for d in outside.dims if d != "v"]
    if "v" in outside.dims:
        hit = outside.any(other) if other else outside
        speed = f"from v = {float(v.where(hit, drop=True).min()):.3g} m/s on" if bool(hit.any()) else ""
    else:
        speed = f"at v = {float(v):.3g} m/s"
    if over >= under:
        extreme, side, end = float(np.nanmax(T)), f"{over:.0f} K above", "warmest"
    else:
        extreme, side, end = float(np.nanmin(T)), f"{under:.0f} K below", "coldest"
    if what == "DMA sweeps":
        law, fix = "the WLF law fitted to the sweeps, extrapolated beyond the data", "add sweeps at those temperatures"
    else:
        law, fix = "a_T held at the table's end value", "extend modulus.shift_T"
    warnings.warn(SceneWarning(
        f"friction.flash: the contacts leave the temperature range of the {what} ({_celsius(lo)} to "
        f"{_celsius(hi)}) {speed} and reach {_celsius(extreme)}, {side} the {end} one; there the modulus is "
        f"{law}: treat mu at those speeds as an extrapolation, or {fix}"), stacklevel=2)


def compute_flash(inp, q, C, v, p, mod, nu, thermal, n_phi, n_seg, correction, gamma, area=("persson", None)):
    """The friction with the flash temperature over the sweep: a dict of DataArrays (mu, A/A0 and
    the flash temperature always; the background rise and the profiles over q if asked)."""
    profile = bool({"flash_temperature_profile", "frictional_heating"} & inp.wanted)
    background = inp["friction.background"]
    kwargs = dict(law=temperature_law(mod), thermal=thermal, n_phi=n_phi, correction=correction, gamma=gamma,
                  n_seg=n_seg, max_shift=float(inp["numerics.flash_shift_step"]), background=background,
                  distance=inp["friction.sliding_distance"], time_nodes=int(inp["numerics.flash_time_nodes"]),
                  profile=profile, area=tuple(area))
    outputs = xr.apply_ufunc(
        _kernel, q, C, v, mod["T"], mod["omega"], mod["storage_modulus"], mod["loss_modulus"], p, nu, kwargs=kwargs,
        input_core_dims=[["q"], ["q"], [], [], ["omega"], ["omega"], ["omega"], [], []],
        output_core_dims=[[], [], [], []] + ([["q"], ["q"]] if profile else []),
        dask="parallelized", output_dtypes=[float] * (6 if profile else 4),
    )
    names = ["friction_coefficient", "sliding_contact_area_ratio", "flash_temperature", "background_temperature_rise",
             "flash_temperature_profile", "frictional_heating"]
    result = dict(zip(names, outputs, strict=False))
    warn_outside_data(result["flash_temperature"], v, mod)
    always = ("friction_coefficient", "sliding_contact_area_ratio", "flash_temperature")
    return {name: value for name, value in result.items() if name in always or name in inp.wanted}


def flash_attrs(inp, thermal) -> dict:
    """What the result records about the flash-temperature model."""
    lam, D, e = thermal
    background = inp["friction.background"]
    return {
        "flash_temperature_model": (
            "Persson (2006) flash temperature, heat released in the deformed layer (depth 1/q): "
            "dT/dq = 2 v q^2 C S B(q; T_q) Theta(pi D q / v) / ((1 - nu^2) lambda), Theta from x/2 (adiabatic layer) "
            "to 1/2 (steady spreading); T_q marched in q (trapezoid steps solved by the root finder), "
            "E read at (q v cos phi, T_q); "
            "docs/theory.md, section 'Flash temperature'"),
        "thermal_properties": f"lambda = {lam:.6g} W/(m K), D = {D:.6g} m^2/s, effusivity = {e:.6g} W s^0.5/(m^2 K)",
        "background_heating": ("none" if background == "none" else
                               f"semi-infinite rubber heated by mu sigma0 v for the sliding time "
                               f"{inp['friction.sliding_distance']:.6g} m / v (Duhamel integral marched in time)"),
    }
