"""Stage ``modulus``: the complex Young's modulus E(omega, T) of the elastic solid (rubber).

The modulus comes from a model (box relaxation spectrum, generalized Maxwell / Prony series,
or a real constant for the elastic limit) or from a measured master curve at a reference
temperature (read in SI by the engine's ``master_curve`` reader), and is shifted to the
temperature(s) of the scene by the WLF equation or a table of shift factors,
E(omega, T) = b_T E(omega a_T, T_ref). Kernels: :mod:`roughcontact.physics.viscoelastic`
(docs/theory.md, section "Viscoelasticity"; the seed's Fig. 7 and eqs 29-32 use it). Figure:
:mod:`roughcontact.stages.figures.modulus`.

Storage: E is complex, NetCDF is not (portably). The stage stores the real and imaginary
parts as two real variables, ``storage_modulus`` (E') and ``loss_modulus`` (E''), on a
geometric grid of angular frequencies omega > 0; :func:`complex_modulus` rebuilds the complex
DataArray from a stored result, and :func:`roughcontact.physics.viscoelastic.modulus_at`
evaluates E', E'' at any frequency (log-log cubic interpolation inside the grid, the physical
asymptotes outside, and E(-omega) = conj E(omega)).
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import xarray as xr

from roughcontact.physics.viscoelastic import (
    MAX_LOG10_SHIFT,
    box_spectrum_modulus,
    elastic_modulus,
    frequency_grid,
    loss_modulus_from_tan_delta,
    master_curve_at,
    prony_modulus,
    shift_factors,
    worst_shift,
)
from roughcontact.stage import (
    Figure,
    FileInput,
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

from .figures.mastercurve import figure_master_curve
from .figures.modulus import figure_modulus
from .shared.mastercurve import (
    DMA_COORDS,
    DMA_OUTPUTS,
    DMA_PARAMS,
    MODULI_TABLE_PARAMS,
    check_dma,
    dma_options,
    dma_variables,
    master_curve,
    model as dma_model,
    shift_spec,
)


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
    Param("C2", "quantity", "K", default=51.6, lo=0.0, lo_open=True, difference=True,
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
    *MODULI_TABLE_PARAMS,
)


def _check_shift_table(values: dict, key: str, T: np.ndarray) -> None:
    """A shift table: both columns, as many values as temperatures, increasing, covering T."""
    shift = values["shift"]
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


def _check_modulus(values: dict, key: str) -> None:
    kind = values["kind"]
    if kind == "dma" and (values["shift"] != "none" or values["vertical_shift"] != "none"):
        which = "shift" if values["shift"] != "none" else "vertical_shift"
        raise UserError("the dma source fits its own temperature shifts: remove shift / vertical_shift "
                        "(see fit and vertical_fit)", key=f"{key}.{which}")
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
        raise UserError("give T_ref (the temperature of the model parameters or of the master curve)",
                        key=f"{key}.T_ref")
    if values["T"] is None:
        # no temperature dependence without a shift: T only labels the result
        values["T"] = values["T_ref"] if values["T_ref"] is not None else 293.15
    T = np.atleast_1d(values["T"])
    if shift == "wlf":
        if np.any(values["C2"] + T - values["T_ref"] <= 0):
            raise UserError(f"WLF is singular at T <= T_ref - C2 = {values['T_ref'] - values['C2']:g} K",
                            key=f"{key}.T")
    _check_shift_table(values, key, T)
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
        variants={"box": _BOX, "prony": _PRONY, "elastic": _ELASTIC, "file": _FILE, "dma": DMA_PARAMS},
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

_NO_SECTION = ("this scene needs the complex modulus: add a [modulus] section (kind = 'box', 'prony', 'elastic', "
               "'file' or 'dma')")


def _shift_factors(spec, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, str]:
    """a_T, b_T at the temperatures T and a sentence saying how; a shift beyond the physical
    range is a UserError naming modulus.T."""
    shift, vertical, T_ref = spec["shift"], spec["vertical_shift"], spec["T_ref"]
    log_aT, b_T = shift_factors(T, T_ref, shift, vertical, spec["C1"], spec["C2"], spec["shift_T"],
                                spec["shift_log10_aT"], spec["shift_log10_bT"], spec.get("T_g"), spec.get("E_a"))
    if shift in ("wlf", "wlf_arrhenius"):
        how = f"WLF: log10 a_T = -{spec['C1']:g} (T - {T_ref:g} K) / ({spec['C2']:g} K + T - {T_ref:g} K)"
        if shift == "wlf_arrhenius":
            how += (f" for T >= T_g = {spec['T_g']:.6g} K; below, Arrhenius: log10 a_T = log10 a_T(T_g) + "
                    f"E_a / (R ln 10) (1/T - 1/T_g) with E_a = {spec['E_a'] / 1e3:.6g} kJ/mol")
    elif shift == "table":
        how = "a_T from the scene's shift table (log10 a_T linear in T between entries)"
    else:
        how = "no horizontal shift (a_T = 1)"
    how += {"entropic": "; b_T = T / T_ref (entropic)", "table": "; b_T from the shift table",
            "none": "; no vertical shift (b_T = 1)"}[vertical]
    worst = worst_shift(log_aT)
    if worst is not None:
        raise UserError(
            f"the temperature shift at T = {np.atleast_1d(T)[worst]:.6g} K is a_T = 10^{log_aT.flat[worst]:.4g}, "
            "beyond "
            f"10^+-{MAX_LOG10_SHIFT}: relaxation times that large or small are outside the shift law's validity "
            f"(for WLF, T is too close to T_ref - C2 = {T_ref - spec['C2']:.6g} K); use temperatures nearer T_ref",
            key="modulus.T")
    return 10.0 ** log_aT, b_T, how


def _model(spec, curve):
    """E(omega) at T_ref of the scene's kind, as ``omega -> (E', E'')``, and attributes saying what it is."""
    kind = spec["kind"]
    if kind == "box":
        attrs = {"model_formula": "box spectrum: E = E0 + (E_inf - E0)/ln(tau2/tau1) [ln(1 + i w tau2) - "
                                  "ln(1 + i w tau1)], docs/theory.md, section 'Viscoelasticity'",
                 "model_parameters": json.dumps({k: spec[k] for k in ("E0", "E_inf", "tau1", "tau2")})}
        return lambda w: box_spectrum_modulus(w, spec["E0"], spec["E_inf"], spec["tau1"], spec["tau2"]), attrs
    if kind == "prony":
        Ek, tk = np.atleast_1d(spec["prony_E"]), np.atleast_1d(spec["prony_tau"])
        attrs = {"model_formula": "generalized Maxwell: E = E0 + sum_k E_k i w tau_k / (1 + i w tau_k)",
                 "model_parameters": json.dumps({"E0": spec["E0"], "prony_E": Ek.tolist(), "prony_tau": tk.tolist()})}
        return lambda w: prony_modulus(w, spec["E0"], Ek, tk), attrs
    if kind == "elastic":
        formula = {"model_formula": "elastic: E = E (real, frequency independent)"}
        return lambda w: elastic_modulus(w, spec["E"]), formula
    omega = curve.omega
    attrs = dict(
        curve.attrs,
        interpolation="log-log linear between the master curve's points (at T_ref, reduced frequency omega a_T)",
        measured_reduced_omega_range=f"{omega[0]:.6g} {omega[-1]:.6g} rad/s",
        extrapolation=(f"outside the measured reduced frequencies [{omega[0]:.4g}, {omega[-1]:.4g}] rad/s: "
                       "below, E' constant and E'' ~ omega (rubbery plateau); above, E' constant and "
                       "E'' ~ 1/omega (glassy plateau)"),
    )
    return lambda w: master_curve_at(w, curve.omega, curve.storage, curve.loss), attrs


def _times(spec) -> tuple[float, float] | None:
    """Shortest and longest relaxation times of a model (s)."""
    if spec["kind"] == "box":
        return spec["tau1"], spec["tau2"]
    if spec["kind"] == "prony":
        t = np.atleast_1d(spec["prony_tau"])
        return float(t.min()), float(t.max())
    return None


def check_modulus(inp: StageInput) -> None:
    """The [modulus] section and the temperature shift (the engine's reader has checked a
    master-curve file: units, NaNs, increasing frequency, moduli' signs)."""
    spec = inp["modulus"]
    if spec is None:
        raise UserError(_NO_SECTION, key="modulus")
    if spec["kind"] != "dma":  # the dma source's shifts are fitted in compute
        _shift_factors(spec, np.atleast_1d(np.asarray(spec["T"], dtype=float)))
    else:
        check_dma(spec, inp.files.get("modulus.sweeps"))


def compute_modulus(inp: StageInput) -> xr.Dataset:
    spec = inp["modulus"]
    if spec is None:
        raise UserError(_NO_SECTION, key="modulus")
    T = inp.sweep("T", spec["T"])
    extra = {}
    if spec["kind"] == "dma":
        fitted = master_curve(spec, inp.files["modulus.sweeps"])
        spec = shift_spec(spec, fitted)
        _check_wlf(spec)
        model, model_attrs = dma_model(fitted)
        T_data = fitted.temperatures  # the sweeps' range, read by the friction stage's flash temperature
        model_attrs = {**model_attrs, "sweep_temperature_range": f"{np.min(T_data):.6g} {np.max(T_data):.6g} K"}
        times, curve = (fitted.times[0], fitted.times[-1]), None
        extra = dma_variables(fitted, inp.wanted)
    else:
        curve = inp.files["modulus.path"] if spec["kind"] == "file" else None
        model, model_attrs = _model(spec, curve)
        times = _times(spec)
    aT_values, bT_values, how = _shift_factors(spec, np.atleast_1d(np.asarray(spec["T"], dtype=float)))
    grid = frequency_grid(aT_values, inp["numerics.modulus_points_per_decade"], times,
                          curve.omega if curve is not None else None, spec["omega_min"], spec["omega_max"])
    omega = xr.DataArray(grid, dims=("omega",))
    if T.ndim:  # a_T, b_T as DataArrays over the T sweep (scalars when T is one value)
        aT = xr.DataArray(aT_values, dims=("T",), coords={"T": T["T"]})
        bT = xr.DataArray(bT_values, dims=("T",), coords={"T": T["T"]})
    else:
        aT, bT = xr.DataArray(aT_values[0]), xr.DataArray(bT_values[0])
    outside = curve is not None and (grid[0] * aT_values.min() < curve.omega[0]
                                     or grid[-1] * aT_values.max() > curve.omega[-1])
    if outside:
        warnings.warn(
            f"{spec['path']}: the master curve covers omega = {curve.omega[0]:.3g}..{curve.omega[-1]:.3g} rad/s at "
            f"T_ref; E(omega, T) is extrapolated outside it (E' constant, E'' ~ omega below and ~ 1/omega above; "
            f"see the 'extrapolation' attribute)", UserWarning, stacklevel=2)

    def kernel(w):
        Ep, Epp = model(w)
        return np.asarray(Ep, dtype=float), np.asarray(Epp, dtype=float)

    Ep, Epp = xr.apply_ufunc(kernel, omega * aT, output_core_dims=[[], []], dask="parallelized",
                             output_dtypes=[float, float])
    Ep = (Ep * bT).transpose(..., "omega")
    Epp = (Epp * bT).transpose(..., "omega")
    ds = xr.Dataset({"storage_modulus": Ep, "loss_modulus": Epp, "loss_tangent": Epp / Ep,
                     "shift_factor": aT, "vertical_shift_factor": bT, **_law_variables(spec), **extra}
                    ).assign_coords(omega=omega)
    if T.ndim == 0:
        ds = ds.assign_coords(T=T)
    ds.attrs = {
        "model": spec["kind"], "temperature_shift": how, **model_attrs,
        "storage": "complex E stored as real variables storage_modulus (E') and loss_modulus (E''); "
                   "roughcontact.stages.modulus.complex_modulus(ds) rebuilds E = E' + i E''",
        "grid": "geometric omega grid; between nodes use roughcontact.physics.viscoelastic.modulus_at (cubic in "
                "log-log, physical asymptotes outside)",
        "T_ref": spec["T_ref"] if spec["T_ref"] is not None else "none",
        "horizontal_shift": spec["shift"], "vertical_shift": spec["vertical_shift"],
    }
    return ds


def _check_wlf(spec) -> None:
    """The fitted WLF law is finite at the scene's temperatures (T > T_ref - C2)."""
    T = np.atleast_1d(np.asarray(spec["T"], dtype=float))
    if spec["shift"] == "wlf_arrhenius":
        T = T[T >= spec["T_g"]]  # below T_g the Arrhenius branch holds (the fit keeps C2 > T_ref - T_g)
    if np.any(spec["C2"] + T - spec["T_ref"] <= 0):
        raise UserError(f"the WLF law fitted to the DMA sweeps is singular at T <= T_ref - C2 = "
                        f"{spec['T_ref'] - spec['C2']:.6g} K; use temperatures above it", key="modulus.T")


def _law_variables(spec) -> dict:
    """The temperature law as data (read back by the friction stage's flash temperature): WLF
    constants, reference temperature and the shift table."""
    out = {}
    if spec["T_ref"] is not None:
        out["reference_temperature"] = xr.DataArray(float(spec["T_ref"]))
    if spec["shift"] in ("wlf", "wlf_arrhenius"):
        out["wlf_C1"], out["wlf_C2"] = xr.DataArray(float(spec["C1"])), xr.DataArray(float(spec["C2"]))
    if spec["shift"] == "wlf_arrhenius":
        out["glass_transition_temperature"] = xr.DataArray(float(spec["T_g"]))
        out["arrhenius_activation_energy"] = xr.DataArray(float(spec["E_a"]))
    table = {"shift_table_log10_aT": spec["shift_log10_aT"] if spec["shift"] == "table" else None,
             "shift_table_log10_bT": spec["shift_log10_bT"] if spec["vertical_shift"] == "table" else None}
    for name, values in table.items():
        if values is not None:
            out[name] = xr.DataArray(np.atleast_1d(np.asarray(values, dtype=float)), dims=("shift_T",),
                                     coords={"shift_T": np.atleast_1d(np.asarray(spec["shift_T"], dtype=float))})
    return out


def _master_curve_options(params) -> dict:
    """Reader options of a measured master curve (kind file), from the [modulus] section."""
    spec = params["modulus"]
    return dict(key="modulus", columns=spec["columns"], frequency_unit=spec["frequency_unit"],
                modulus_unit=spec["modulus_unit"], loss_column=spec["loss_column"], frequency=spec["frequency"],
                loss_from_tan_delta=loss_modulus_from_tan_delta)


register(
    Stage(
        name="modulus",
        version="3",
        compute=compute_modulus,
        check=check_modulus,
        reads=("modulus", "numerics.modulus_points_per_decade"),
        files=(FileInput("modulus.path", reader="master_curve", options=_master_curve_options),
               FileInput("modulus.sweeps", reader="dma", options=dma_options)),
        outputs={
            "storage_modulus": Var("Pa", "storage modulus E' = Re E(omega, T)"),
            "loss_modulus": Var("Pa", "loss modulus E'' = Im E(omega, T)"),
            "loss_tangent": Var("1", "loss tangent tan delta = E''/E'"),
            "shift_factor": Var("1", "horizontal shift factor a_T",
                                comment="E(omega, T) = b_T E(omega a_T, T_ref)"),
            "vertical_shift_factor": Var("1", "vertical shift factor b_T"),
            "reference_temperature": Var("K", "reference temperature T_ref",
                                         comment="of the temperature shift"),
            "wlf_C1": Var("1", "WLF constant C1", comment="log10 a_T = -C1 (T - T_ref) / (C2 + T - T_ref)"),
            "wlf_C2": Var("K", "WLF constant C2"),
            "glass_transition_temperature": Var("K", "glass transition T_g of the WLF-Arrhenius law",
                                                comment="WLF above T_g, Arrhenius below (shift_law = "
                                                        "wlf_arrhenius)"),
            "arrhenius_activation_energy": Var("J/mol", "activation energy E_a below T_g",
                                               comment="log10 a_T = log10 a_T(T_g) + E_a / (R ln 10) "
                                                       "(1/T - 1/T_g) for T < T_g"),
            "shift_table_log10_aT": Var("1", "log10 a_T of the shift table"),
            "shift_table_log10_bT": Var("1", "log10 b_T of the shift table (vertical shift)"),
            **DMA_OUTPUTS,
        },
        coords={"shift_T": Var("K", "temperature of the shift table",
                               comment="for a dma modulus: the temperatures of the sweeps"), **DMA_COORDS},
        figures=(Figure("fig7_modulus", "E'(f), E''(f) (seed Fig. 7)", ("modulus",), figure_modulus),
                 Figure("dma_master_curve", "DMA sweeps shifted onto the master curve, and a_T(T)", ("modulus",),
                        figure_master_curve, outputs=("sweep_log10_aT",))),
        doc="Complex modulus E(omega, T) (model or measured master curve, WLF / table shift), stored as E' and E''.",
    )
)
