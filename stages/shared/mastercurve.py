"""The ``dma`` source of the ``modulus`` stage: multi-temperature DMA frequency sweeps (read in SI by
the engine's ``dma`` reader) shifted onto a master curve, the WLF law fitted to the shifts, a
causal (Prony) master curve and the Kramers-Kronig check. Kernels:
:mod:`roughcontact.physics.mastercurve`; docs/theory.md, section "Master curves from DMA data".

Not a stage of its own: :mod:`roughcontact.stages.modulus` declares the keys and outputs.
"""

from __future__ import annotations

import json
import warnings
from typing import NamedTuple

import numpy as np
import xarray as xr

from roughcontact.physics.mastercurve import build_master_curve, fit_prony, kramers_kronig_deviation, relaxation_times
from roughcontact.physics.viscoelastic import loss_modulus_from_tan_delta, prony_modulus
from roughcontact.stage import Param, Var

#: keys of ``[modulus] kind = "dma"``
DMA_PARAMS = (
    Param("sweeps", "path",
          doc="text/CSV file of DMA frequency sweeps: temperature, frequency, E', E'' (or tan delta)"),
    Param("columns", "intlist", default=(0, 1, 2, 3), lo=0, doc="0-based columns of T, frequency, E', E''/tan delta"),
    Param("loss_column", "choice", default="loss_modulus", choices=("loss_modulus", "tan_delta"),
          doc="what the fourth column holds"),
    Param("temperature_unit", "str", default=None, doc="unit of the temperature column (else from the header)"),
    Param("frequency_unit", "str", default=None, doc="unit of the frequency column (else from the header)"),
    Param("modulus_unit", "str", default=None, doc="unit of the modulus columns (else from the header)"),
    Param("frequency", "choice", default="auto", choices=("auto", "cyclic", "angular"),
          doc="cyclic f (omega = 2 pi f) or angular omega; auto: angular if the unit says rad, else cyclic"),
    Param("temperature_tolerance", "quantity", "K", default=0.5, lo=0.0, lo_open=True,
          doc="rows within this of a sweep's first temperature belong to the sweep"),
    Param("fit", "choice", default="wlf", choices=("wlf", "free"),
          doc="horizontal shifts: WLF fitted to the data (wlf) or one shift per sweep, then WLF fitted to them (free)"),
    Param("vertical_fit", "choice", default="none", choices=("none", "free"),
          doc="vertical shifts b_T: none or one per sweep"),
    Param("kk_tolerance", "quantity", "", default=0.05, lo=0.0, lo_open=True,
          doc="rms relative deviation of E' from its Kramers-Kronig reconstruction above which a sweep is flagged"),
    Param("spectrum_per_decade", "int", default=4, lo=1, doc="relaxation times per decade of the fitted spectrum"),
)

#: outputs of the dma source (optional: ask for any of them in outputs.variables)
DMA_OUTPUTS = {
    "sweep_log10_aT": Var("1", "log10 of the horizontal shift a_T of each DMA sweep to T_ref", optional=True),
    "sweep_log10_bT": Var("1", "log10 of the vertical shift b_T of each DMA sweep", optional=True),
    "sweep_shift_residual": Var("1", "rms of log10 E' and log10 E'' of each sweep about the shifted master curve "
                                     "(decades)", optional=True),
    "sweep_wlf_residual": Var("1", "log10 a_T of each sweep minus the fitted WLF law (decades)", optional=True),
    "sweep_kk_deviation": Var("1", "rms relative deviation of E' from its Kramers-Kronig reconstruction from E''",
                              optional=True),
    "relaxation_strength": Var("Pa", "moduli E_k of the fitted generalized Maxwell spectrum at T_ref", optional=True),
    "relaxed_modulus": Var("Pa", "relaxed modulus E0 of the fitted spectrum", optional=True),
    "spectrum_fit_residual": Var("1", "rms relative residual of E' and E'' about the fitted spectrum", optional=True),
    "dma_temperature": Var("K", "temperature of each DMA point", optional=True),
    "dma_reduced_omega": Var("rad/s", "reduced angular frequency omega a_T of each DMA point", optional=True),
    "dma_storage_modulus": Var("Pa", "E' of each DMA point divided by b_T", optional=True),
    "dma_loss_modulus": Var("Pa", "E'' of each DMA point divided by b_T", optional=True),
}

DMA_COORDS = {"relaxation_time": Var("s", "relaxation time tau_k of the fitted spectrum")}


class MasterCurve(NamedTuple):
    """The fitted master curve at T_ref and everything that reports on it (SI)."""

    T_ref: float
    C1: float
    C2: float
    temperatures: np.ndarray
    log10_aT: np.ndarray
    log10_bT: np.ndarray
    residual: np.ndarray
    wlf_residual: np.ndarray
    kk_deviation: np.ndarray
    E0: float
    moduli: np.ndarray
    times: np.ndarray
    fit_residual: float
    reduced_omega: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    point_T: np.ndarray


def master_curve(spec, data) -> MasterCurve:
    """Shift the sweeps of ``data`` (:class:`roughcontact.dma.DMASweeps`) to T_ref, fit the WLF law
    and the spectrum, run the Kramers-Kronig check and warn (naming the temperatures) where it fails."""
    T = data.temperatures
    T_ref = spec["T_ref"] if spec["T_ref"] is not None else float(T[np.argmin(np.abs(T - np.median(T)))])
    shifts = build_master_curve(T, data.sweep, data.omega, data.storage, data.loss, T_ref, spec["fit"],
                                spec["vertical_fit"] == "free")
    reduced = data.omega * 10.0 ** shifts.log10_aT[data.sweep]
    b = 10.0 ** shifts.log10_bT[data.sweep]
    storage, loss = data.storage / b, np.maximum(data.loss / b, 1e-12 * data.storage / b)
    times = relaxation_times(reduced, int(spec["spectrum_per_decade"]))
    E0, moduli, fit_residual = fit_prony(reduced, storage, loss, times)
    _, deviation = kramers_kronig_deviation(reduced, storage, loss, times, data.sweep)
    kk = np.array([np.sqrt(np.mean(deviation[data.sweep == j] ** 2)) for j in range(T.size)])
    bad = np.flatnonzero(kk > spec["kk_tolerance"])
    if bad.size:
        listed = ", ".join(f"{T[j] - 273.15:.4g} °C ({100 * kk[j]:.3g} %)" for j in bad)
        warnings.warn(f"{data.path}: E' does not follow from E'' by Kramers-Kronig within "
                      f"{100 * spec['kk_tolerance']:g} % (rms) at T = {listed}: the data there are not causal or do "
                      "not superpose", UserWarning, stacklevel=2)
    return MasterCurve(float(T_ref), shifts.C1, shifts.C2, T, shifts.log10_aT, shifts.log10_bT, shifts.residual,
                       shifts.wlf_residual, kk, E0, moduli, times, fit_residual, reduced, storage, loss,
                       T[data.sweep])


def model(curve: MasterCurve):
    """E(omega) at T_ref of the fitted spectrum, and the attributes saying what it is."""
    attrs = {"model_formula": "generalized Maxwell fitted to the DMA master curve (non-negative moduli): "
                              "E = E0 + sum_k E_k i w tau_k / (1 + i w tau_k)",
             "model_parameters": json.dumps({"E0": curve.E0, "terms": int(np.count_nonzero(curve.moduli))}),
             "wlf_fit": f"C1 = {curve.C1:.6g}, C2 = {curve.C2:.6g} K, T_ref = {curve.T_ref:.6g} K",
             "measured_reduced_omega_range": f"{curve.reduced_omega.min():.6g} {curve.reduced_omega.max():.6g} rad/s"}
    return (lambda w: prony_modulus(w, curve.E0, curve.moduli, curve.times)), attrs


def shift_spec(spec, curve: MasterCurve) -> dict:
    """The [modulus] values with the fitted temperature law in place of the scene's shift keys."""
    vertical = spec["vertical_fit"] == "free"
    return dict(spec, shift="wlf", C1=curve.C1, C2=curve.C2, T_ref=curve.T_ref, shift_T=curve.temperatures,
                shift_log10_aT=None, vertical_shift="table" if vertical else "none",
                shift_log10_bT=curve.log10_bT if vertical else None)


def dma_variables(curve: MasterCurve, wanted) -> dict:
    """The optional DMA outputs asked for (all of them once any is asked), as DataArrays."""
    if not set(DMA_OUTPUTS) & set(wanted):
        return {}
    per_sweep = {"sweep_log10_aT": curve.log10_aT, "sweep_log10_bT": curve.log10_bT,
                 "sweep_shift_residual": curve.residual, "sweep_wlf_residual": curve.wlf_residual,
                 "sweep_kk_deviation": curve.kk_deviation}
    out = {name: xr.DataArray(values, dims=("shift_T",), coords={"shift_T": curve.temperatures})
           for name, values in per_sweep.items()}
    out["relaxation_strength"] = xr.DataArray(curve.moduli, dims=("relaxation_time",),
                                              coords={"relaxation_time": curve.times})
    out["relaxed_modulus"] = xr.DataArray(curve.E0)
    out["spectrum_fit_residual"] = xr.DataArray(curve.fit_residual)
    for name, values in (("dma_temperature", curve.point_T), ("dma_reduced_omega", curve.reduced_omega),
                         ("dma_storage_modulus", curve.storage), ("dma_loss_modulus", curve.loss)):
        out[name] = xr.DataArray(values, dims=("dma_point",))
    return out


def dma_options(params) -> dict:
    """Reader options of the DMA file, from the [modulus] section."""
    spec = params["modulus"]
    return dict(key="modulus", columns=spec["columns"], temperature_unit=spec["temperature_unit"],
                frequency_unit=spec["frequency_unit"], modulus_unit=spec["modulus_unit"],
                loss_column=spec["loss_column"], frequency=spec["frequency"],
                temperature_tolerance=spec["temperature_tolerance"], loss_from_tan_delta=loss_modulus_from_tan_delta)
