"""Viscoelastic modulus: the complex Young's modulus E(omega, T) of the elastic solid (rubber).

Physics: ``equations.md`` section 5 (the seed's Fig. 7 and eqs 29-32 use it). The modulus
comes from a model (box relaxation spectrum, generalized Maxwell / Prony series, or a real
constant for the elastic limit) or from a measured master curve at a reference temperature,
and is shifted to the temperature(s) of the scene by the WLF equation or a table of shift
factors:

    E(omega, T) = b_T E(omega a_T, T_ref).

Storage: E is complex, NetCDF is not (portably). The stage stores the real and imaginary
parts as two real variables, ``storage_modulus`` (E') and ``loss_modulus`` (E''), on a
geometric grid of angular frequencies omega > 0; :func:`complex_modulus` rebuilds the complex
DataArray from a stored result, and :func:`modulus_at` evaluates E', E'' at any frequency
(log-log cubic interpolation inside the grid, the physical asymptotes outside, and
E(-omega) = conj E(omega)).
"""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import xarray as xr

from roughcontact.stage import UserError
from roughcontact.stage import Param, Section
from roughcontact.stage import FileInput, Figure, Stage, StageInput, Var, register, register_params, register_section
from roughcontact.units import array_to_si

from roughcontact.physics.quadrature import loglog_interp

# ----------------------------------------------------------------------------------------
# Kernels (pure numpy)
# ----------------------------------------------------------------------------------------


def _half_log1p_sq(x):
    """0.5 ln(1 + x^2) without overflow for huge |x|."""
    x = np.abs(np.asarray(x, dtype=float))
    big = x > 1.0
    xs = np.where(big, x, 1.0)
    return np.where(big, np.log(xs) + 0.5 * np.log1p(1.0 / (xs * xs)), 0.5 * np.log1p(np.where(big, 0.0, x) ** 2))


def box_spectrum_modulus(omega, E0, E_inf, tau1, tau2):
    """Complex modulus of the box relaxation spectrum (Pa), equations.md section 5.

    E(omega) = E0 + (E_inf - E0) / ln(tau2/tau1) [ln(1 + i omega tau2) - ln(1 + i omega tau1)],

    a flat distribution of relaxation times in ln(tau) between tau1 and tau2. It goes from the
    rubbery modulus E0 (omega -> 0) to the glassy modulus E_inf (omega -> infinity); between
    1/tau2 and 1/tau1 the loss modulus is nearly flat, E'' ~ (pi/2) (E_inf - E0) / ln(tau2/tau1).

    Evaluated as E' = E0 + D [L(omega tau2) - L(omega tau1)], L(x) = 0.5 ln(1 + x^2), and
    E'' = D arctan(omega (tau2 - tau1) / (1 + omega^2 tau1 tau2)), D = (E_inf - E0)/ln(tau2/tau1):
    no overflow and no cancellation of the two arctangents at high frequency.

    Parameters
    ----------
    omega : array
        Angular frequency (rad/s); negative values give the complex conjugate.
    E0, E_inf : float
        Relaxed (rubbery) and unrelaxed (glassy) Young's moduli (Pa), E_inf > E0 > 0.
    tau1, tau2 : float
        Shortest and longest relaxation times (s), 0 < tau1 < tau2.

    Returns
    -------
    (E', E'') : arrays (Pa); E'' has the sign of omega.

    References
    ----------
    equations.md section 5; Tschoegl, The Phenomenological Theory of Linear Viscoelastic
    Behavior (1989), ch. 3 (box distribution).
    """
    omega = np.asarray(omega, dtype=float)
    D = (E_inf - E0) / np.log(tau2 / tau1)
    storage = E0 + D * (_half_log1p_sq(omega * tau2) - _half_log1p_sq(omega * tau1))
    with np.errstate(over="ignore"):
        loss = D * np.arctan(omega * (tau2 - tau1) / (1.0 + (omega * omega) * (tau1 * tau2)))
    return storage, loss


def prony_modulus(omega, E0, moduli, times):
    """Complex modulus of a generalized Maxwell model / Prony series (Pa).

    E(omega) = E0 + sum_k E_k i omega tau_k / (1 + i omega tau_k), i.e.
    E' = E0 + sum E_k x_k^2 / (1 + x_k^2), E'' = sum E_k x_k / (1 + x_k^2), x_k = omega tau_k.

    Parameters
    ----------
    omega : array
        Angular frequency (rad/s); negative values give the complex conjugate.
    E0 : float
        Equilibrium (relaxed) modulus (Pa).
    moduli, times : arrays (K,)
        Prony moduli E_k (Pa, > 0) and relaxation times tau_k (s, > 0).

    Returns
    -------
    (E', E'') : arrays (Pa), shape of ``omega``.

    References
    ----------
    equations.md section 5; Tschoegl (1989), ch. 3.
    """
    omega = np.asarray(omega, dtype=float)[..., None]
    moduli = np.asarray(moduli, dtype=float)
    x = omega * np.asarray(times, dtype=float)
    ax = np.abs(x)
    small = ax <= 1.0
    inv = np.where(small, 1.0, 1.0 / np.where(small, 1.0, x))
    xs = np.where(small, x, 0.0)
    sq = np.where(small, xs * xs / (1.0 + xs * xs), 1.0 / (1.0 + inv * inv))
    lin = np.where(small, xs / (1.0 + xs * xs), inv / (1.0 + inv * inv))
    return E0 + (moduli * sq).sum(-1), (moduli * lin).sum(-1)


def wlf_log10_shift(T, T_ref, C1, C2):
    """WLF horizontal shift log10 a_T = -C1 (T - T_ref) / (C2 + T - T_ref), equations.md section 5.

    E(omega, T) = E(omega a_T, T_ref): at higher temperature (a_T < 1) the same modulus is
    reached at higher frequency.

    Parameters
    ----------
    T, T_ref : float or array
        Temperature and reference temperature (K).
    C1 : float
        WLF constant (dimensionless; universal value 17.44 with T_ref = Tg).
    C2 : float
        WLF constant (K; universal value 51.6 K with T_ref = Tg). Needs C2 + T - T_ref > 0.

    References
    ----------
    Williams, Landel & Ferry, J. Am. Chem. Soc. 77, 3701 (1955).
    """
    dT = np.asarray(T, dtype=float) - T_ref
    return -C1 * dT / (C2 + dT)


def extrapolate_modulus(omega, omega_lo, omega_hi, storage_lo, loss_lo, storage_hi, loss_hi):
    """Physical asymptotes of a viscoelastic solid outside [omega_lo, omega_hi] (omega > 0).

    Below: rubbery plateau, E' = E'(omega_lo), E'' = E''(omega_lo) omega / omega_lo (E'' ~ omega);
    above: glassy plateau, E' = E'(omega_hi), E'' = E''(omega_hi) omega_hi / omega (E'' ~ 1/omega).
    These are the terminal behaviours of any solid with a bounded relaxation spectrum
    (equations.md section 5). Returns (E', E'', inside) where ``inside`` marks the points
    not extrapolated (their values are left to the caller: NaN here).
    """
    omega = np.asarray(omega, dtype=float)
    below = omega < omega_lo
    above = omega > omega_hi
    with np.errstate(divide="ignore", invalid="ignore"):
        storage = np.where(below, storage_lo, np.where(above, storage_hi, np.nan))
        loss = np.where(below, loss_lo * omega / omega_lo, np.where(above, loss_hi * omega_hi / np.where(above, omega, 1.0), np.nan))
    return storage, loss, ~(below | above)


def _gather(y, idx):
    nd = max(y.ndim, idx.ndim)
    y = y.reshape((1,) * (nd - y.ndim) + y.shape)
    idx = idx.reshape((1,) * (nd - idx.ndim) + idx.shape)
    return np.take_along_axis(y, idx, axis=-1)


def _uniform_cubic(y, s):
    """4-point Lagrange interpolation of ``y`` (..., n) on the uniform grid 0..n-1 at ``s`` (..., m).

    Fourth-order accurate (error ~ h^4 f''''/24); the stencil is shifted at the ends.
    """
    n = y.shape[-1]
    i = np.clip(np.floor(s).astype(np.intp), 1, n - 3)
    t = s - i
    w_m = -t * (t - 1.0) * (t - 2.0) / 6.0
    w_0 = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
    w_1 = -(t + 1.0) * t * (t - 2.0) / 2.0
    w_2 = (t + 1.0) * t * (t - 1.0) / 6.0
    return (w_m * _gather(y, i - 1) + w_0 * _gather(y, i) + w_1 * _gather(y, i + 1) + w_2 * _gather(y, i + 2))


def modulus_at(omega, omega_grid, storage, loss):
    """E'(omega), E''(omega) from values tabulated on a geometric frequency grid.

    Inside the grid: cubic (4-point Lagrange) interpolation of ln E' and ln E'' against
    ln omega (of E'' itself where it is not positive everywhere, e.g. 0 for an elastic solid);
    outside: the physical asymptotes of :func:`extrapolate_modulus`; negative frequencies:
    E(-omega) = conj E(omega).

    Parameters
    ----------
    omega : array (..., m)
        Angular frequencies (rad/s).
    omega_grid : array (n,)
        Geometric grid (rad/s), n >= 4, as stored by the modulus stage.
    storage, loss : arrays (..., n)
        E' > 0 and E'' >= 0 on the grid (Pa); leading axes broadcast against ``omega``'s.

    Returns
    -------
    (E', E'') : arrays (Pa), the broadcast shape.
    """
    grid = np.asarray(omega_grid, dtype=float)
    storage = np.asarray(storage, dtype=float)
    loss = np.asarray(loss, dtype=float)
    omega = np.asarray(omega, dtype=float)
    n = grid.size
    if n < 4:
        raise ValueError("modulus_at needs at least 4 grid frequencies")
    x0 = np.log(grid[0])
    h = np.log(grid[-1] / grid[0]) / (n - 1)
    a = np.abs(omega)
    with np.errstate(divide="ignore"):
        s = (np.log(a) - x0) / h
    sc = np.clip(s, 0.0, n - 1.0)
    positive = np.all(loss > 0, axis=-1, keepdims=True)
    log_loss = np.where(positive, np.log(np.where(loss > 0, loss, 1.0)), loss)
    Ep = np.exp(_uniform_cubic(np.log(storage), sc))
    raw = _uniform_cubic(log_loss, sc)
    Epp = np.where(positive, np.exp(np.where(positive, raw, 0.0)), np.maximum(raw, 0.0))
    eSp, eSpp, inside = extrapolate_modulus(a, grid[0], grid[-1], storage[..., :1], loss[..., :1],
                                            storage[..., -1:], loss[..., -1:])
    Ep = np.where(inside, Ep, eSp)
    Epp = np.where(inside, Epp, eSpp)
    return Ep, np.sign(omega) * Epp


def master_curve_at(omega, data_omega, data_storage, data_loss):
    """A measured master curve at reduced frequencies ``omega`` (rad/s): log-log linear between
    the data points, the physical asymptotes (:func:`extrapolate_modulus`) outside them."""
    omega = np.asarray(omega, dtype=float)
    Ep, Epp, inside = extrapolate_modulus(omega, data_omega[0], data_omega[-1], data_storage[0], data_loss[0],
                                          data_storage[-1], data_loss[-1])
    clipped = np.clip(omega, data_omega[0], data_omega[-1])
    Ep = np.where(inside, loglog_interp(clipped, data_omega, data_storage), Ep)
    Epp = np.where(inside, loglog_interp(clipped, data_omega, data_loss), Epp)
    return Ep, Epp


def complex_modulus(ds: xr.Dataset) -> xr.DataArray:
    """The complex modulus E = E' + i E'' (Pa) from a modulus-stage result (read side of the
    real/imaginary storage)."""
    E = ds["storage_modulus"] + 1j * ds["loss_modulus"]
    E.attrs = {"units": "Pa", "long_name": "complex Young's modulus E = E' + i E''"}
    return E


# ----------------------------------------------------------------------------------------
# Scene section
# ----------------------------------------------------------------------------------------

_COMMON = (
    Param("T", "sweep", "K", default=None, lo=0.0, lo_open=True,
          doc="temperature(s) of the solid (a list is a sweep); default T_ref, else 20 degC"),
    Param("T_ref", "quantity", "K", default=None, lo=0.0, lo_open=True,
          doc="reference temperature of the model parameters or of the measured master curve"),
    Param("shift", "choice", default="none", choices=("none", "wlf", "table"),
          doc="horizontal temperature shift a_T: none, WLF (C1, C2) or a table"),
    Param("C1", "quantity", "", default=17.44, lo=0.0, lo_open=True, doc="WLF C1 (universal 17.44 about Tg)"),
    Param("C2", "quantity", "K", default=51.6, lo=0.0, lo_open=True,
          doc="WLF C2, a temperature difference in K (universal 51.6 K about Tg)"),
    Param("shift_T", "quantities", "K", default=None, lo=0.0, lo_open=True, doc="shift table: temperatures"),
    Param("shift_log10_aT", "quantities", "", default=None, doc="shift table: log10 a_T at shift_T"),
    Param("vertical_shift", "choice", default="none", choices=("none", "entropic", "table"),
          doc="vertical shift b_T: none (1), entropic (T / T_ref) or the table's shift_log10_bT"),
    Param("shift_log10_bT", "quantities", "", default=None, doc="shift table: log10 b_T at shift_T"),
    Param("omega_min", "quantity", "rad/s", default=None, lo=0.0, lo_open=True,
          doc="lowest angular frequency of the stored grid (default: covers the spectrum at every T)"),
    Param("omega_max", "quantity", "rad/s", default=None, lo=0.0, lo_open=True,
          doc="highest angular frequency of the stored grid (default: covers the spectrum at every T)"),
)

_BOX = (
    Param("E0", "quantity", "Pa", lo=0.0, lo_open=True, doc="relaxed (rubbery, low-frequency) Young's modulus"),
    Param("E_inf", "quantity", "Pa", lo=0.0, lo_open=True, doc="unrelaxed (glassy, high-frequency) Young's modulus"),
    Param("tau1", "quantity", "s", lo=0.0, lo_open=True, doc="shortest relaxation time of the box (at T_ref)"),
    Param("tau2", "quantity", "s", lo=0.0, lo_open=True, doc="longest relaxation time of the box (at T_ref)"),
)
_PRONY = (
    Param("E0", "quantity", "Pa", lo=0.0, lo_open=True, doc="equilibrium (relaxed) Young's modulus"),
    Param("prony_E", "quantities", "Pa", lo=0.0, lo_open=True, doc="list of Prony moduli E_k"),
    Param("prony_tau", "quantities", "s", lo=0.0, lo_open=True, doc="list of relaxation times tau_k (at T_ref)"),
)
_ELASTIC = (Param("E", "quantity", "Pa", lo=0.0, lo_open=True, doc="real, frequency-independent Young's modulus"),)
_FILE = (
    Param("path", "path", doc="text/CSV master curve at T_ref: frequency, E' and E'' (or tan delta) columns"),
    Param("columns", "intlist", default=(0, 1, 2), lo=0, doc="0-based column indices of frequency, E', E''/tan delta"),
    Param("loss_column", "choice", default="loss_modulus", choices=("loss_modulus", "tan_delta"),
          doc="what the third column holds"),
    Param("frequency_unit", "str", default=None, doc="unit of the frequency column (else from the header)"),
    Param("modulus_unit", "str", default=None, doc="unit of the modulus columns (else from the header)"),
    Param("frequency", "choice", default="auto", choices=("auto", "cyclic", "angular"),
          doc="cyclic f (omega = 2 pi f) or angular omega; auto: angular if the unit says rad, else cyclic"),
)


def _check_modulus(values: dict, key: str) -> None:
    kind = values["kind"]
    if kind == "box":
        if not values["tau1"] < values["tau2"]:
            raise UserError(f"needs tau1 < tau2, got {values['tau1']:g} s and {values['tau2']:g} s", key=f"{key}.tau2")
        if not values["E_inf"] > values["E0"]:
            raise UserError(f"needs E_inf > E0, got {values['E_inf']:g} Pa and {values['E0']:g} Pa", key=f"{key}.E_inf")
    if kind == "prony":
        Ek, tk = np.atleast_1d(values["prony_E"]), np.atleast_1d(values["prony_tau"])
        if Ek.size != tk.size:
            raise UserError(f"prony_E has {Ek.size} value(s) but prony_tau has {tk.size}", key=f"{key}.prony_tau")
    shift = values["shift"]
    needs_ref = shift != "none" or values["vertical_shift"] != "none" or kind == "file"
    if needs_ref and values["T_ref"] is None:
        raise UserError("give T_ref (the temperature of the model parameters or of the master curve)", key=f"{key}.T_ref")
    if values["T"] is None:
        # no temperature dependence without a shift: T only labels the result
        values["T"] = values["T_ref"] if values["T_ref"] is not None else 293.15
    T = np.atleast_1d(values["T"])
    if shift == "wlf":
        if np.any(values["C2"] + T - values["T_ref"] <= 0):
            raise UserError(f"WLF is singular at T <= T_ref - C2 = {values['T_ref'] - values['C2']:g} K", key=f"{key}.T")
    table_needed = shift == "table" or values["vertical_shift"] == "table"
    if table_needed:
        name = "shift_log10_aT" if shift == "table" else "shift_log10_bT"
        if values["shift_T"] is None or values[name] is None:
            raise UserError(f"a shift table needs shift_T and {name}", key=f"{key}.shift_T")
        Ts = np.atleast_1d(values["shift_T"])
        for col in ("shift_log10_aT", "shift_log10_bT"):
            if values[col] is not None and np.atleast_1d(values[col]).size != Ts.size:
                raise UserError(f"{col} must have as many values as shift_T ({Ts.size})", key=f"{key}.{col}")
        if Ts.size < 2 or np.any(np.diff(Ts) <= 0):
            raise UserError("shift_T must list at least two increasing temperatures", key=f"{key}.shift_T")
        if np.any(T < Ts[0]) or np.any(T > Ts[-1]):
            raise UserError(f"temperature outside the shift table [{Ts[0]:g}, {Ts[-1]:g}] K", key=f"{key}.T")
    lo, hi = values["omega_min"], values["omega_max"]
    if lo is not None and hi is not None and not hi > 10.0 * lo:
        raise UserError("needs omega_max > 10 omega_min", key=f"{key}.omega_max")


register_section(
    Section(
        "modulus",
        _COMMON,
        doc="the complex modulus E(omega, T) of the elastic solid (for friction)",
        optional=True,
        discriminator="kind",
        variants={"box": _BOX, "prony": _PRONY, "elastic": _ELASTIC, "file": _FILE},
        check=_check_modulus,
    )
)
register_params(
    "numerics",
    Param("modulus_points_per_decade", "int", default=20, lo=4, presets={"fast": 10, "accurate": 40},
          ladder=(8, 10, 12, 16, 20, 24, 30, 40, 60),
          doc="points per decade of the stored E(omega) grid (cubic log-log interpolation between them)"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------

_HEADER_EXAMPLE = "# f [Hz]  E' [MPa]  E'' [MPa]"


def _shift_factors(spec, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, str]:
    shift, vertical = spec["shift"], spec["vertical_shift"]
    T_ref = spec["T_ref"]
    if shift == "wlf":
        log_aT = wlf_log10_shift(T, T_ref, spec["C1"], spec["C2"])
        how = f"WLF: log10 a_T = -{spec['C1']:g} (T - {T_ref:g} K) / ({spec['C2']:g} K + T - {T_ref:g} K)"
    elif shift == "table":
        log_aT = np.interp(T, np.atleast_1d(spec["shift_T"]), np.atleast_1d(spec["shift_log10_aT"]))
        how = "a_T from the scene's shift table (log10 a_T linear in T between entries)"
    else:
        log_aT = np.zeros_like(T)
        how = "no horizontal shift (a_T = 1)"
    if vertical == "entropic":
        b_T = T / T_ref
        how += "; b_T = T / T_ref (entropic)"
    elif vertical == "table":
        b_T = 10.0 ** np.interp(T, np.atleast_1d(spec["shift_T"]), np.atleast_1d(spec["shift_log10_bT"]))
        how += "; b_T from the shift table"
    else:
        b_T = np.ones_like(T)
        how += "; no vertical shift (b_T = 1)"
    log_aT = np.asarray(log_aT, dtype=float)
    if np.any(~np.isfinite(log_aT)) or np.any(np.abs(log_aT) > MAX_LOG10_SHIFT):
        worst = int(np.argmax(np.where(np.isfinite(log_aT), np.abs(log_aT), np.inf)))
        raise UserError(
            f"the temperature shift at T = {np.atleast_1d(T)[worst]:.6g} K is a_T = 10^{log_aT.flat[worst]:.4g}, beyond "
            f"10^+-{MAX_LOG10_SHIFT}: relaxation times that large or small are outside the shift law's validity "
            f"(for WLF, T is too close to T_ref - C2 = {T_ref - spec['C2']:.6g} K); use temperatures nearer T_ref",
            key="modulus.T")
    return 10.0 ** log_aT, b_T, how


#: largest |log10 a_T| accepted: beyond it (relaxation times shifted by more than 100 decades)
#: no shift law is physical, and the frequency grid would leave floating-point range
MAX_LOG10_SHIFT = 100


def _frequency_factor(unit: str, mode: str) -> float:
    """rad per unit of the frequency column: 2 pi for cyclic frequency, 1 for angular."""
    if mode == "angular":
        return 1.0
    if mode == "cyclic":
        return 2.0 * np.pi
    return 1.0 if re.search(r"rad", unit) else 2.0 * np.pi


def read_master_curve(spec: dict, table) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Validate a measured master curve (a :class:`pipeline.readers.Table`) and return SI
    (omega [rad/s], E' [Pa], E'' [Pa]) and attributes; errors name the file and line or key."""
    path = str(spec["path"])
    cols = tuple(spec["columns"])
    if len(cols) != 3:
        raise UserError(f"needs three column indices [frequency, E', E''], got {list(cols)}", key="modulus.columns")
    f_raw, s_raw, l_raw = (table.column(i) for i in cols)
    units = table.units if table.units else [None] * table.data.shape[1]
    f_unit = spec.get("frequency_unit") or units[cols[0]]
    e_unit = spec.get("modulus_unit") or units[cols[1]]
    tan = spec["loss_column"] == "tan_delta"
    l_unit = e_unit if not tan else None
    if not tan and spec.get("modulus_unit") is None and units[cols[2]] is not None:
        l_unit = units[cols[2]]
    if not f_unit:
        raise UserError(f"unit of the frequency column unknown: put it in the header ({_HEADER_EXAMPLE!r}) "
                        "or set modulus.frequency_unit", file=path, key="modulus.frequency_unit")
    if not e_unit or not l_unit and not tan:
        raise UserError(f"unit of the modulus columns unknown: put it in the header ({_HEADER_EXAMPLE!r}) "
                        "or set modulus.modulus_unit", file=path, key="modulus.modulus_unit")
    lines = table.lines
    for raw, name in ((f_raw, "frequency"), (s_raw, "E'"), (l_raw, "tan delta" if tan else "E''")):
        bad = np.flatnonzero(~np.isfinite(raw))
        if bad.size:
            raise UserError(f"{name} is NaN or infinite", file=path, key=f"line {lines[bad[0]]}")
    factor = _frequency_factor(f_unit, spec["frequency"])
    omega = array_to_si(f_raw, f_unit, "1/s", key="modulus.frequency_unit") * factor
    storage = array_to_si(s_raw, e_unit, "Pa", key="modulus.modulus_unit")
    bad = np.flatnonzero(omega <= 0)
    if bad.size:
        raise UserError(f"frequency must be positive, got {f_raw[bad[0]]:g}", file=path, key=f"line {lines[bad[0]]}")
    bad = np.flatnonzero(np.diff(omega) <= 0)
    if bad.size:
        raise UserError(f"frequency is not strictly increasing ({f_raw[bad[0]]:g} then {f_raw[bad[0] + 1]:g})",
                        file=path, key=f"line {lines[bad[0] + 1]}")
    bad = np.flatnonzero(storage <= 0)
    if bad.size:
        raise UserError(f"storage modulus E' must be positive, got {s_raw[bad[0]]:g}", file=path,
                        key=f"line {lines[bad[0]]}")
    if tan:
        bad = np.flatnonzero(l_raw < 0)
        if bad.size:
            raise UserError(f"tan delta must be >= 0, got {l_raw[bad[0]]:g}", file=path, key=f"line {lines[bad[0]]}")
        loss = storage * l_raw
    else:
        loss = array_to_si(l_raw, l_unit, "Pa", key="modulus.modulus_unit")
        bad = np.flatnonzero(loss < 0)
        if bad.size:
            raise UserError(f"loss modulus E'' must be >= 0, got {l_raw[bad[0]]:g}", file=path,
                            key=f"line {lines[bad[0]]}")
    if omega.size < 2:
        raise UserError("a master curve needs at least two data rows", file=path)
    attrs = {
        "source_file": path,
        "frequency_column": f"{f_unit} ({'angular' if factor == 1.0 else 'cyclic: omega = 2 pi f'})",
        "interpolation": "log-log linear between the master curve's points (at T_ref, reduced frequency omega a_T)",
        "measured_reduced_omega_range": f"{omega[0]:.6g} {omega[-1]:.6g} rad/s",
        "extrapolation": (f"outside the measured reduced frequencies [{omega[0]:.4g}, {omega[-1]:.4g}] rad/s: "
                          "below, E' constant and E'' ~ omega (rubbery plateau); above, E' constant and "
                          "E'' ~ 1/omega (glassy plateau)"),
    }
    return omega, storage, loss, attrs


def _time_range(spec) -> tuple[float, float] | None:
    kind = spec["kind"]
    if kind == "box":
        return spec["tau1"], spec["tau2"]
    if kind == "prony":
        t = np.atleast_1d(spec["prony_tau"])
        return float(t.min()), float(t.max())
    return None


def _omega_grid(spec, aT: np.ndarray, ppd: int, data_omega=None) -> np.ndarray:
    """Geometric grid of angular frequencies: by default it covers the relaxation spectrum
    (or the measured curve) at every temperature with 3 decades to spare, and at least
    [1e-6, 1e12] rad/s."""
    lo, hi = 1e-6, 1e12
    times = _time_range(spec)
    if times is not None:
        lo = min(lo, 1e-3 / (times[1] * aT.max()))
        hi = max(hi, 1e3 / (times[0] * aT.min()))
    if data_omega is not None:
        lo = min(lo, data_omega[0] / aT.max())
        hi = max(hi, data_omega[-1] / aT.min())
    lo = 10.0 ** np.floor(np.log10(lo))
    hi = 10.0 ** np.ceil(np.log10(hi))
    lo = spec["omega_min"] or lo
    hi = spec["omega_max"] or hi
    n = int(np.ceil(np.log10(hi / lo) * ppd)) + 1
    return np.geomspace(lo, hi, max(n, 4))


def validate_modulus(inp: StageInput) -> None:
    """Before anything computes: the [modulus] section, the temperature shift and a master-curve
    file's contents (non-increasing frequency, negative moduli, NaNs, units)."""
    spec = inp["modulus"]
    if spec is None:
        raise UserError("this scene needs the complex modulus: add a [modulus] section "
                        "(kind = 'box', 'prony', 'elastic' or 'file')", key="modulus")
    _shift_factors(spec, np.atleast_1d(np.asarray(spec["T"], dtype=float)))
    if spec["kind"] == "file":
        read_master_curve(spec, inp.files["modulus.path"])


def compute_modulus(inp: StageInput) -> xr.Dataset:
    spec = inp["modulus"]
    if spec is None:
        raise UserError("this scene needs the complex modulus: add a [modulus] section "
                        "(kind = 'box', 'prony', 'elastic' or 'file')", key="modulus")
    kind = spec["kind"]
    T = inp.sweep("T", spec["T"], "K", "temperature")
    T_values = np.atleast_1d(np.asarray(spec["T"], dtype=float))
    aT_values, bT_values, how = _shift_factors(spec, T_values)
    attrs: dict = {"model": kind, "temperature_shift": how}
    data = None
    if kind == "file":
        d_omega, d_storage, d_loss, file_attrs = read_master_curve(spec, inp.files["modulus.path"])
        attrs.update(file_attrs)
        data = (d_omega, d_storage, d_loss)
    grid = _omega_grid(spec, aT_values, inp["numerics.modulus_points_per_decade"], data[0] if data else None)
    omega = xr.DataArray(grid, dims=("omega",), attrs={"units": "rad/s", "long_name": "angular frequency"})
    # a_T, b_T as DataArrays over the T sweep (scalars when T is one value)
    if T.ndim:
        aT = xr.DataArray(aT_values, dims=("T",), coords={"T": T["T"]})
        bT = xr.DataArray(bT_values, dims=("T",), coords={"T": T["T"]})
    else:
        aT, bT = xr.DataArray(aT_values[0]), xr.DataArray(bT_values[0])
    reduced = omega * aT

    if kind == "box":
        model = lambda w: box_spectrum_modulus(w, spec["E0"], spec["E_inf"], spec["tau1"], spec["tau2"])  # noqa: E731
        attrs["model_formula"] = ("box spectrum: E = E0 + (E_inf - E0)/ln(tau2/tau1) [ln(1 + i w tau2) - ln(1 + i w tau1)], "
                                  "equations.md section 5")
        attrs["model_parameters"] = json.dumps({k: spec[k] for k in ("E0", "E_inf", "tau1", "tau2")})
    elif kind == "prony":
        Ek, tk = np.atleast_1d(spec["prony_E"]), np.atleast_1d(spec["prony_tau"])
        model = lambda w: prony_modulus(w, spec["E0"], Ek, tk)  # noqa: E731
        attrs["model_formula"] = "generalized Maxwell: E = E0 + sum_k E_k i w tau_k / (1 + i w tau_k)"
        attrs["model_parameters"] = json.dumps({"E0": spec["E0"], "prony_E": Ek.tolist(), "prony_tau": tk.tolist()})
    elif kind == "elastic":
        model = lambda w: (np.full(np.shape(w), spec["E"]), np.zeros(np.shape(w)))  # noqa: E731
        attrs["model_formula"] = "elastic: E = E (real, frequency independent)"
    else:
        model = lambda w: master_curve_at(w, *data)  # noqa: E731
        lo_r, hi_r = grid[0] * aT_values.min(), grid[-1] * aT_values.max()
        if lo_r < data[0][0] or hi_r > data[0][-1]:
            warnings.warn(
                f"{spec['path']}: the master curve covers omega = {data[0][0]:.3g}..{data[0][-1]:.3g} rad/s at T_ref; "
                f"E(omega, T) is extrapolated outside it (E' constant, E'' ~ omega below and ~ 1/omega above; "
                f"see the 'extrapolation' attribute)", UserWarning, stacklevel=2)

    def kernel(w):
        Ep, Epp = model(w)
        return np.asarray(Ep, dtype=float), np.asarray(Epp, dtype=float)

    Ep, Epp = xr.apply_ufunc(kernel, reduced, output_core_dims=[[], []], dask="parallelized",
                             output_dtypes=[float, float])
    Ep = (Ep * bT).transpose(..., "omega")
    Epp = (Epp * bT).transpose(..., "omega")
    Ep.attrs = {"units": "Pa", "long_name": "storage modulus E' = Re E(omega, T)"}
    Epp.attrs = {"units": "Pa", "long_name": "loss modulus E'' = Im E(omega, T)"}
    tan = Epp / Ep
    tan.attrs = {"units": "1", "long_name": "loss tangent tan delta = E''/E'"}
    aT.attrs = {"units": "1", "long_name": "horizontal shift factor a_T: E(omega, T) = b_T E(omega a_T, T_ref)"}
    bT.attrs = {"units": "1", "long_name": "vertical shift factor b_T"}
    ds = xr.Dataset({"storage_modulus": Ep, "loss_modulus": Epp, "loss_tangent": tan,
                     "shift_factor": aT, "vertical_shift_factor": bT})
    ds = ds.assign_coords(omega=omega)
    if T.ndim == 0:
        ds = ds.assign_coords(T=T)
    ds["omega"].attrs = {"units": "rad/s", "long_name": "angular frequency"}
    ds["T"].attrs = {"units": "K", "long_name": "temperature"}
    attrs.update(
        storage="complex E stored as real variables storage_modulus (E') and loss_modulus (E''); "
                "stages.modulus.complex_modulus(ds) rebuilds E = E' + i E''",
        grid="geometric omega grid; between nodes use stages.modulus.modulus_at (cubic in log-log, "
             "physical asymptotes outside)",
        T_ref=spec["T_ref"] if spec["T_ref"] is not None else "none",
    )
    ds.attrs = attrs
    return ds


# ----------------------------------------------------------------------------------------
# Figure (seed Fig. 7)
# ----------------------------------------------------------------------------------------


def figure_modulus(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["modulus"]
    fig, ax = plt.subplots(figsize=(5.8, 4.3))
    f = ds["omega"].values / (2.0 * np.pi)
    temps = np.atleast_1d(ds["T"].values)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, T in enumerate(temps):
        sel = ds.sel(T=T) if "T" in ds.dims else ds
        c = colors[k % len(colors)]
        label = f"T = {T - 273.15:.4g} °C"
        ax.loglog(f, sel["storage_modulus"].values, "-", color=c, label=f"E'  ({label})")
        ax.loglog(f, sel["loss_modulus"].values, "--", color=c, label=f"E'' ({label})")
    ax.set_xlabel("frequency f = omega / 2 pi (Hz)")
    ax.set_ylabel("modulus (Pa)")
    model = ds.attrs.get("model", "")
    ax.set_title(f"Viscoelastic modulus ({model}; cf. seed Fig. 7)")
    top = float(np.nanmax(ds["loss_modulus"].values))
    if top > 0:
        ax.set_ylim(bottom=max(ax.get_ylim()[0], 1e-3 * top))
    ax.legend(fontsize=8)
    ax.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    return fig


register(
    Stage(
        name="modulus",
        version="1",
        compute=compute_modulus,
        validate=validate_modulus,
        params=("modulus", "numerics.modulus_points_per_decade"),
        files=(FileInput("modulus.path", reader="table"),),
        outputs={
            "storage_modulus": Var("Pa", "storage modulus E' = Re E(omega, T)"),
            "loss_modulus": Var("Pa", "loss modulus E'' = Im E(omega, T)"),
            "loss_tangent": Var("1", "loss tangent tan delta"),
            "shift_factor": Var("1", "horizontal shift factor a_T"),
            "vertical_shift_factor": Var("1", "vertical shift factor b_T"),
        },
        coords={},
        figures=(Figure("fig7_modulus", "E'(f), E''(f) (seed Fig. 7)", ("modulus",), figure_modulus),),
        doc="Complex modulus E(omega, T) (model or measured master curve, WLF / table shift), stored as E' and E''.",
    )
)
