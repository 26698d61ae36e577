"""Stage ``friction``: hysteretic rubber friction mu(v) and the relative contact area A/A0(v)
while sliding, for an elastic (viscoelastic) solid and a hard substrate that may both be rough.

Kernels: :mod:`roughcontact.physics.friction` (docs/theory.md, section "Friction"; seed eqs 29-32 for
one rough surface, 61-62 for two, with the combined PSD C(q, eta) of eq 52, and the seed's
misprints in eqs 30 and 32/62 corrected). Figures: :mod:`roughcontact.stages.figures.friction`
(seed Figs 6, 8-11).

The nominal pressure sigma0 is the scene's ``load.p`` (a list is a sweep); Poisson's ratio is
``material.nu``; the temperature(s) are the modulus stage's ``modulus.T``.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from roughcontact.physics.friction import (
    angular_integrals,
    contact_friction,
    contact_shear_gaussian,
    contact_shear_table,
    friction_kernel,
)
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Stage,
    StageInput,
    UserError,
    Var,
    register,
    register_params,
    register_section,
)

from .figures.flash import figure_flash
from .figures.friction import figure_area_eta, figure_area_substrate, figure_mu_eta, figure_mu_substrate, figure_psds
from .shared.flash import (
    FLASH_KEYS,
    FLASH_NUMERICS,
    FLASH_OUTPUTS,
    FLASH_PARAMS,
    check_flash,
    compute_flash,
    flash_attrs,
    temperature_law,
)
from .shared.magnification import CORRECTION_KEYS, area_correction
from .shared.material import COATING_KEYS, refuse_coating

# ----------------------------------------------------------------------------------------
# Scene section and numerics
# ----------------------------------------------------------------------------------------

#: velocities when the scene gives none: 1e-9 .. 1e3 m/s, 6 points per decade
DEFAULT_VELOCITIES = np.geomspace(1e-9, 1e3, 73)

#: keys of [friction] for the contact shear term mu_cont = tau_f(v a_T(T_c)) A/A0 / sigma0
SHEAR_PARAMS = (
    Param("shear", "choice", default="none", choices=("none", "gaussian", "table"),
          doc="contact shear term tau_f A/A0 / sigma0 added to mu: none, the Gaussian-in-log10-v law "
              "(shear_tau0, shear_v0, shear_c) or a table (shear_table_v, shear_table_tau)"),
    Param("shear_tau0", "quantity", "Pa", default=None, lo=0.0, doc="peak frictional shear stress tau_f0 (gaussian)"),
    Param("shear_v0", "quantity", "m/s", default=None, lo=0.0, lo_open=True,
          doc="velocity of the peak of tau_f at the modulus' T_ref (gaussian)"),
    Param("shear_c", "quantity", "", default=None, lo=0.0, lo_open=True,
          doc="width c of tau_f0 exp(-c log10(v a_T / v0)^2) (gaussian)"),
    Param("shear_table_v", "quantities", "m/s", default=None, lo=0.0, lo_open=True,
          doc="table of tau_f: increasing velocities at the modulus' T_ref"),
    Param("shear_table_tau", "quantities", "Pa", default=None, lo=0.0, doc="table of tau_f: the shear stresses"),
)
SHEAR_KEYS = tuple(f"friction.{p.name}" for p in SHEAR_PARAMS)
SHEAR_OUTPUTS = {
    "friction_coefficient_viscoelastic": Var("1", "viscoelastic (hysteretic) friction term", optional=True,
                                             comment="eq 61; with friction.shear it is the first of the "
                                                     "two terms of friction_coefficient"),
    "friction_coefficient_contact": Var("1", "contact shear term tau_f A/A0 / sigma0", optional=True),
    "contact_shear_stress": Var("Pa", "frictional shear stress tau_f of the contacts", optional=True,
                                comment="tau_f(v a_T(T_c)), T_c the contacts' temperature (the flash "
                                        "temperature with friction.flash, else modulus.T)"),
}


def _shear_law(inp):
    """tau_f as a function of the reduced velocity v a_T (m/s -> Pa), or None without the term; a
    UserError naming the key for missing or inconsistent parameters."""
    kind = inp["friction.shear"]
    if kind == "none":
        for name in SHEAR_OUTPUTS:
            if name in inp.wanted:
                raise UserError(f"{name} needs the contact shear term: set friction.shear", key="friction.shear")
        return None
    if kind == "gaussian":
        values = [inp[f"friction.shear_{n}"] for n in ("tau0", "v0", "c")]
        for n, value in zip(("tau0", "v0", "c"), values, strict=True):
            if value is None:
                raise UserError(f"shear = \"gaussian\" needs shear_{n}", key=f"friction.shear_{n}")
        return lambda w: contact_shear_gaussian(w, *values)
    v_tab, tau_tab = inp["friction.shear_table_v"], inp["friction.shear_table_tau"]
    if v_tab is None or tau_tab is None:
        raise UserError("shear = \"table\" needs shear_table_v and shear_table_tau", key="friction.shear_table_v")
    v_tab, tau_tab = np.atleast_1d(v_tab), np.atleast_1d(tau_tab)
    if v_tab.size != tau_tab.size or v_tab.size < 2 or np.any(np.diff(v_tab) <= 0):
        raise UserError("shear_table_v must list at least two increasing velocities, as many as shear_table_tau",
                        key="friction.shear_table_v")
    return lambda w: contact_shear_table(w, v_tab, tau_tab)


def _check(inp):
    """Cross-key errors of the flash temperature and of the contact shear term; no coating."""
    refuse_coating(inp, "the friction stage (a viscoelastic layer's E(omega) under the q integral of eq 61 is "
                        "not implemented)")
    check_flash(inp)
    _shear_law(inp)


def _contact_shear(inp, law, v, T_contact, mod, area, p):
    """tau_f at the contacts' temperature (v reduced with the modulus' a_T) and mu_cont."""
    shift = temperature_law(mod)
    tau = xr.apply_ufunc(lambda vv, T: law(vv * 10.0 ** shift(T)[0]), v, T_contact, dask="parallelized",
                         output_dtypes=[float])
    return tau, xr.apply_ufunc(contact_friction, tau, area, p, dask="parallelized", output_dtypes=[float])


register_section(
    Section(
        "friction",
        (
            Param("v", "sweep", "m/s", default=None, lo=0.0, lo_open=True, hi=1e6,
                  doc="sliding velocity; a list or {from, to, num} is a sweep (default 1e-9..1e3 m/s, 73 points)"),
            Param("correction", "choice", default="none", choices=("none", "yang_persson"),
                  doc="S(q) in mu: none (S = 1, the seed) or yang_persson (S = gamma + (1 - gamma) P^2)"),
            Param("gamma", "quantity", "", default=0.5, lo=0.0, hi=1.0, doc="gamma of the yang_persson correction"),
        ) + FLASH_PARAMS + SHEAR_PARAMS,
        doc="hysteretic friction of the elastic solid sliding on the substrate (nominal pressure: load.p)",
    )
)
register_params(
    "numerics",
    Param("friction_phi_nodes", "int", default=16, lo=2, presets={"fast": 8, "accurate": 24},
          ladder=(6, 8, 10, 12, 16, 20, 24, 32, 64), doc="Gauss-Legendre nodes of the friction angular integrals"),
    Param("friction_segment_nodes", "int", default=12, lo=2, presets={"fast": 6, "accurate": 16},
          ladder=(4, 4, 6, 8, 12, 12, 16, 16, 24),
          doc="Gauss-Legendre nodes per q segment of the friction integral (integrated in the variable G)"),
    *FLASH_NUMERICS,
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------


def _attrs(grid, needed_hi: float, n_phi: int, n_seg: int, S_text: str, nu: float) -> dict:
    """What the result records about its numerics and the modulus range it used."""
    return {
        "angular_quadrature": f"Gauss-Legendre, {n_phi} nodes on [0, pi/2]",
        "q_quadrature": ("G: piecewise power law on the psd stage's q grid; mu: in the variable G, "
                         f"{n_seg} Gauss-Legendre nodes per q segment "
                         "(roughcontact.physics.quadrature.running_weighted_integral)"),
        "area_factor": S_text,
        "poisson_ratio": nu,
        "omega_needed_max": needed_hi,
        "modulus_omega_range": f"{grid[0]:.6g} {grid[-1]:.6g} rad/s",
        "modulus_extrapolated": ("yes: frequencies above the modulus grid use E' constant, E'' ~ 1/omega"
                                 if needed_hi > grid[-1] else "no (above); below the grid E'' ~ omega"),
        "equations": ("docs/theory.md, section 'Friction' (seed eqs 29-32, 61-62 with the eq 30 and eq 32/62 misprints "
                      "corrected)"),
    }


def _shear_text(inp) -> str:
    """What the result records about the contact shear term."""
    if inp["friction.shear"] == "gaussian":
        law = (f"tau_f = {inp['friction.shear_tau0']:.6g} Pa exp(-{inp['friction.shear_c']:.6g} "
               f"log10(v a_T / {inp['friction.shear_v0']:.6g} m/s)^2)")
    else:
        law = "tau_f from the table shear_table_v, shear_table_tau (linear in log10 v a_T, end values outside)"
    return (f"friction_coefficient = viscoelastic term + tau_f A/A0 / sigma0, {law}, a_T of the modulus read at the "
            "contacts' temperature (flash temperature or modulus.T); docs/theory.md, section 'Contact shear term'")


def compute_friction(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    mod = inp.upstream["modulus"]
    q = psd["q"]
    grid = mod["omega"].values
    ratios = np.diff(np.log(grid))
    if grid.size < 4 or np.ptp(ratios) > 1e-6 * np.abs(ratios).max():
        raise UserError("the modulus stage's omega grid must be geometric with at least 4 points", key="modulus")
    nu = float(inp["material.nu"])
    n_phi = int(inp["numerics.friction_phi_nodes"])
    n_seg = int(inp["numerics.friction_segment_nodes"])
    correction, gamma = inp["friction.correction"], float(inp["friction.gamma"])
    v_values = inp["friction.v"] if inp["friction.v"] is not None else DEFAULT_VELOCITIES
    v = inp.sweep("v", v_values)
    p = inp.sweep("p", inp["load.p"])

    A, B = xr.apply_ufunc(
        angular_integrals, q, v, mod["omega"], mod["storage_modulus"], mod["loss_modulus"], n_phi,
        input_core_dims=[["q"], [], ["omega"], ["omega"], ["omega"], []],
        output_core_dims=[["q"], ["q"]], dask="parallelized", output_dtypes=[float, float],
    )
    extras = bool({"sliding_G", "friction_density"} & inp.wanted)
    outputs = xr.apply_ufunc(
        friction_kernel, q, psd["psd_combined"], A, B, p, nu, correction, gamma, extras, n_seg, *area_correction(inp),
        input_core_dims=[["q"], ["q"], ["q"], ["q"], [], [], [], [], [], [], [], []],
        output_core_dims=[[], []] + ([["q"], ["q"]] if extras else []),
        dask="parallelized", output_dtypes=[float] * (4 if extras else 2),
    )
    mu, area = outputs[0], outputs[1]
    thermal = check_flash(inp)
    flash = compute_flash(inp, q, psd["psd_combined"], v, p, mod, nu, thermal, n_phi, n_seg, correction, gamma,
                          area_correction(inp)) if thermal is not None else {}
    T_contact = mod["T"]
    if flash:
        if "friction_coefficient_isothermal" in inp.wanted:
            flash["friction_coefficient_isothermal"] = mu
        mu, area = flash.pop("friction_coefficient"), flash.pop("sliding_contact_area_ratio")
        T_contact = flash["flash_temperature"] if "flash_temperature" in inp.wanted else flash.pop("flash_temperature")
    law = _shear_law(inp)
    shear = {}
    if law is not None:
        tau, mu_cont = _contact_shear(inp, law, v, T_contact, mod, area, p)
        shear = {"friction_coefficient_viscoelastic": mu, "friction_coefficient_contact": mu_cont,
                 "contact_shear_stress": tau}
        shear = {name: value for name, value in shear.items() if name in inp.wanted}
        mu = mu + mu_cont
    S_text = "S = 1" if correction == "none" else f"S = {gamma:g} + {1 - gamma:g} P^2"
    mu.attrs = {"formula": "mu = 2/((1-nu^2) sigma0) int dq q^3 C P S int_0^(pi/2) cos(phi) E''(q v cos phi) dphi, "
                           f"{S_text}" + ("; plus the contact shear term tau_f(v a_T(T_c)) A/A0 / sigma0"
                                          if law is not None else "")}
    last = ("v",) if v.ndim else ()
    name, area_gamma = area_correction(inp)
    area.attrs = {"area_correction": name, **({"area_correction_gamma": area_gamma} if area_gamma else {})}
    mu.attrs.update(area.attrs)
    ds = xr.Dataset({"friction_coefficient": mu.transpose(..., *last),
                     "sliding_contact_area_ratio": area.transpose(..., *last)})
    for name, index in (("sliding_G", 2), ("friction_density", 3)):
        if name in inp.wanted:
            ds[name] = outputs[index].transpose(..., *last, "q")
    for name, value in {**flash, **shear}.items():
        ds[name] = value.transpose(..., *last, "q") if "q" in value.dims else value.transpose(..., *last)
    for sweep in (v, p):
        if sweep.ndim == 0:
            ds = ds.assign_coords({sweep.name: sweep})
    needed_hi = float(q.values[-1] * np.max(v_values))
    if needed_hi > grid[-1]:
        warnings.warn(f"friction needs the modulus up to omega = q1 v_max = {needed_hi:.3g} rad/s, beyond the modulus "
                      f"grid ({grid[-1]:.3g} rad/s): extrapolated with E' constant, E'' ~ 1/omega; "
                      "raise modulus.omega_max if that is not the glassy plateau", UserWarning, stacklevel=2)
    ds.attrs = _attrs(grid, needed_hi, n_phi, n_seg, S_text, nu)
    ds.attrs["contact_correction"] = area.attrs["area_correction"]  # the A/A0 theory (contact.correction)
    if thermal is not None:
        ds.attrs.update(flash_attrs(inp, thermal))
    if law is not None:
        ds.attrs["contact_shear"] = _shear_text(inp)
    return ds


STAGE = register(
    Stage(
        name="friction",
        version="4",
        compute=compute_friction,
        needs=("modulus", "psd"),
        check=_check,
        reads=(*CORRECTION_KEYS, "load.p", "material.nu", "friction.v", "friction.correction", "friction.gamma",
                "numerics.friction_phi_nodes", "numerics.friction_segment_nodes") + FLASH_KEYS + SHEAR_KEYS
              + COATING_KEYS,
        outputs={
            "friction_coefficient": Var("1", "friction coefficient mu", tolerance=1e-4,
                                        comment="eq 61, plus the contact shear term with friction.shear"),
            "sliding_contact_area_ratio": Var("1", "relative contact area A/A0, sliding", tolerance=1e-4,
                                              comment="A/A0 = P(q1) while sliding; eqs 31, 62"),
            "sliding_G": Var("1", "G(q, v) while sliding", optional=True,
                             comment="G(q; v) of eq 62 (corrected: |E|^2, upper limit q), sigma0^2 "
                                     "absorbed"),
            "friction_density": Var("1", "contribution to mu per unit ln q, d mu / d ln q", optional=True),
            **FLASH_OUTPUTS,
            **SHEAR_OUTPUTS,
        },
        figures=(
            Figure("fig6_psds", "C(q) of the two surfaces (seed Fig. 6)", ("psd", "friction"), figure_psds),
            Figure("fig8_friction_substrate_only", "mu(v): substrate only vs both rough (seed Fig. 8)",
                   ("friction",), figure_mu_substrate),
            Figure("fig9_area_substrate_only", "A/A0(v): substrate only vs both rough (seed Fig. 9)",
                   ("friction",), figure_area_substrate),
            Figure("fig10_friction_eta", "mu(v) for eta = 0, +1, -1 (seed Fig. 10)", ("friction",), figure_mu_eta),
            Figure("fig11_area_eta", "A/A0(v) for eta = 0, +1, -1 (seed Fig. 11)", ("friction",), figure_area_eta),
            Figure("flash_temperature", "mu(v) with and without flash temperature, and T_q at q1", ("friction",),
                   figure_flash, outputs=("flash_temperature",)),
        ),
        doc="mu(v, eta, T, p) and A/A0(v, ...) of hysteretic rubber friction (eqs 61-62, corrected).",
    )
)
