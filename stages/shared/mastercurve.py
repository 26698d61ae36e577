"""The ``dma`` source of the ``modulus`` stage: multi-temperature DMA frequency sweeps (read in SI by
the engine's ``dma`` reader) shifted onto a master curve, the WLF law fitted to the shifts, a
causal (Prony) master curve and the Kramers-Kronig check. Kernels:
:mod:`roughcontact.physics.mastercurve` and :mod:`roughcontact.physics.relaxation_spectrum`; docs/theory.md,
section "Master curves from DMA data".

Not a stage of its own: :mod:`roughcontact.stages.modulus` declares the keys and outputs.
"""

from __future__ import annotations

import json
import warnings
from typing import NamedTuple

import numpy as np
import xarray as xr

from roughcontact.physics.mastercurve import (
    SHIFT_LAWS,
    SHIFT_QUANTITIES,
    bin_sweeps,
    build_master_curve,
    overlap_shifts,
)
from roughcontact.physics.relaxation_spectrum import fit_prony, kramers_kronig_deviation, relaxation_times
from roughcontact.physics.viscoelastic import loss_modulus_from_tan_delta, prony_modulus
from roughcontact.stage import Param, UserError, Var

#: the keys of a table of moduli against frequency, the same for a measured master curve (``[modulus]
#: kind = "file"``) and DMA sweeps (``kind = "dma"``): declared once here
MODULI_TABLE_PARAMS = (
    Param("loss_column", "choice", default="loss_modulus", choices=("loss_modulus", "tan_delta"),
          doc="what the last column holds: E'' or tan delta"),
    Param("frequency_unit", "str", default=None, doc="unit of the frequency column (else from the header)"),
    Param("modulus_unit", "str", default=None, doc="unit of the modulus columns (else from the header)"),
    Param("frequency", "choice", default="auto", choices=("auto", "cyclic", "angular"),
          doc="cyclic f (omega = 2 pi f) or angular omega; auto: angular if the unit says rad, else cyclic"),
)

#: keys of ``[modulus] kind = "dma"``
DMA_PARAMS = (
    Param("sweeps", "path",
          doc="text/CSV/Excel file of DMA frequency sweeps: temperature, frequency, E', E'' (or tan delta)"),
    Param("columns", "intlist", default=(0, 1, 2, 3), lo=0, doc="0-based columns of T, frequency, E', E''/tan delta"),
    Param("column_names", "list", default=None,
          doc="the columns T, frequency, E', E''/tan delta by their names in the header (instead of columns)"),
    Param("sheet", "str", default=None, doc="Excel files: the sheet to read (default the first)"),
    Param("temperature_unit", "str", default=None, doc="unit of the temperature column (else from the header)"),
    *MODULI_TABLE_PARAMS,
    Param("temperature_tolerance", "quantity", "K", default=0.5, lo=0.0, lo_open=True,
          doc="rows within this of a sweep's first temperature belong to the sweep"),
    Param("fit", "choice", default="overlap", choices=("overlap", "wlf", "free"),
          doc="horizontal shifts: each sweep laid on its neighbour by their overlap, chained from T_ref, then WLF "
              "fitted to them (overlap); WLF fitted to all data (wlf); one shift per sweep by a global fit (free)"),
    Param("shift_law", "choice", default="wlf", choices=SHIFT_LAWS,
          doc="law fitted to the shifts: WLF, or WLF above T_g and Arrhenius below (continuous at T_g; "
              "with fit = overlap or free)"),
    Param("T_g", "quantity", "K", default=None, lo=0.0, lo_open=True,
          doc="shift_law = wlf_arrhenius: glass transition where the law turns Arrhenius (default: fitted as the "
              "breakpoint)"),
    Param("shift_on", "choice", default="storage", choices=SHIFT_QUANTITIES,
          doc="what the overlap shifts superpose: storage (E'), loss (E''), moduli (both), tan_delta, complex (|E*|)"),
    Param("min_overlap", "quantity", "", default=0.5, lo=0.0, lo_open=True,
          doc="least overlap of neighbouring sweeps in log10 frequency (decades) for the overlap shifts"),
    Param("no_overlap", "choice", default="warn", choices=("warn", "error"),
          doc="when a sweep's best shift leaves less than min_overlap with its neighbour: warn or refuse"),
    Param("bins_per_decade", "int", default=20, lo=2,
          doc="sweeps logged at more points are averaged in bins of this many per decade of frequency before the fit"),
    Param("vertical_fit", "choice", default="none", choices=("none", "free"),
          doc="vertical shifts b_T: none or one per sweep"),
    Param("kk_tolerance", "quantity", "", default=0.05, lo=0.0, lo_open=True,
          doc="rms relative deviation of E' from its Kramers-Kronig reconstruction above which a sweep is flagged"),
    Param("spectrum_per_decade", "int", default=4, lo=1, doc="relaxation times per decade of the fitted spectrum"),
)

#: outputs of the dma source (optional: ask for any of them in outputs.variables)
DMA_OUTPUTS = {
    "sweep_log10_aT": Var("1", "log10 a_T of each DMA sweep", optional=True,
                          comment="log10 of the horizontal shift a_T of each DMA sweep to T_ref"),
    "sweep_log10_bT": Var("1", "log10 of the vertical shift b_T of each DMA sweep", optional=True),
    "sweep_shift_residual": Var("1", "rms residual of each sweep (decades)", optional=True,
                                comment="rms of log10 E' and log10 E'' of each sweep about the shifted "
                                        "master curve"),
    "sweep_wlf_residual": Var("1", "WLF residual of log10 a_T (decades)", optional=True,
                              comment="log10 a_T of each sweep minus the fitted shift law (WLF or "
                                        "WLF-Arrhenius, shift_law)"),
    "sweep_overlap": Var("1", "overlap with the neighbour sweep (decades)", optional=True,
                         comment="overlap with the neighbour it was shifted onto: log10 frequency range "
                                 "both sweeps cover after the overlap shift; each sweep is laid on its "
                                 "neighbour nearer T_ref (NaN for the reference)"),
    "sweep_pair_misfit": Var("1", "misfit to the neighbour sweep (decades)", optional=True,
                             comment="rms distance to the neighbour it was shifted onto, in the overlap: "
                                     "rms of the log10 distance between the two curves of the shifted "
                                     "quantity (shift_on) over their overlap, at the overlap shift"),
    "sweep_kk_deviation": Var("1", "Kramers-Kronig deviation of E'", optional=True,
                              comment="rms relative deviation of E' from its Kramers-Kronig reconstruction "
                                      "from E''"),
    "relaxation_strength": Var("Pa", "relaxation strengths E_k", optional=True,
                               comment="moduli E_k of the fitted generalized Maxwell spectrum at T_ref"),
    "relaxed_modulus": Var("Pa", "relaxed modulus E0 of the fitted spectrum", optional=True),
    "spectrum_fit_residual": Var("1", "rms relative residual of the spectrum fit", optional=True,
                                 comment="rms relative residual of E' and E'' about the fitted spectrum"),
    "dma_temperature": Var("K", "temperature of each DMA point", optional=True,
                           comment="points of a sweep logged at more than bins_per_decade per decade are "
                                   "bin means (log10 E', log10 E'', log10 omega)"),
    "dma_reduced_omega": Var("rad/s", "reduced angular frequency omega a_T", optional=True,
                             comment="of each DMA point"),
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
    overlap: np.ndarray
    misfit: np.ndarray
    law: str = "wlf"
    T_g: float = float("nan")
    E_a: float = float("nan")


def _reference(spec, T) -> float:
    """T_ref of the master curve: the scene's, else the sweep temperature nearest the median."""
    return spec["T_ref"] if spec["T_ref"] is not None else float(T[np.argmin(np.abs(T - np.median(T)))])


def _check_law(spec, data) -> None:
    """shift_law = "wlf_arrhenius": fitted to overlap or free shifts, T_g below T_ref with sweeps on both
    sides (or enough sweeps to find it)."""
    if spec["shift_law"] != "wlf_arrhenius":
        return
    if spec["fit"] == "wlf":
        raise UserError("shift_law = \"wlf_arrhenius\" is fitted to the sweeps' shifts: set fit = \"overlap\" or "
                        "\"free\"", key="modulus.shift_law")
    if data is None:
        return
    T = data.temperatures
    T_ref = _reference(spec, T)
    if spec["T_g"] is None:
        if T.size < 5:
            raise UserError(f"fitting T_g as the breakpoint needs at least 5 temperatures, the file has {T.size}: "
                            "give modulus.T_g", key="modulus.shift_law")
        return
    Tg = spec["T_g"]
    if Tg > T_ref:
        raise UserError(f"T_g = {Tg:.6g} K is above T_ref = {T_ref:.6g} K: the WLF branch holds at T_ref "
                        "(a_T = 1 there); set T_ref above T_g", key="modulus.T_g")
    below, above = int(np.sum(T < Tg)), int(np.sum(T >= Tg))
    if below < 1 or above < 3:
        raise UserError(f"T_g = {Tg:.6g} K leaves {below} sweep(s) below it and {above} at or above: the Arrhenius "
                        "branch needs one, the WLF branch three", key="modulus.T_g")


def check_dma(spec, data) -> None:
    """Rules between the [modulus] keys and the DMA file: two temperatures give one relative shift,
    which cannot fix both WLF constants; the WLF-Arrhenius law's T_g and sweeps; with no_overlap = "error",
    neighbouring sweeps whose overlap does not fix their shift."""
    _check_law(spec, data)
    _overlap_refusal(spec, data)
    if data is None or data.temperatures.size > 2:
        return
    listed = " and ".join(f"{T - 273.15:.4g} °C" for T in data.temperatures)
    if spec["fit"] != "overlap":
        raise UserError(f"two temperatures ({listed}) give one relative shift, which cannot fix the two WLF constants "
                        f"C1 and C2: measure a third temperature, or set fit = \"overlap\" (C2 is then held at "
                        f"modulus.C2, {spec['C2']:g} K unless you set it, and only C1 is fitted)", key="modulus.fit")


def _binned(data, per_decade):
    """The sweeps averaged in bins of 1/per_decade decade (log10 moduli averaged), where a sweep has
    more points than bins: the fit's cost then does not grow with the file's rows."""
    logw = np.log10(data.omega)
    counts = np.bincount(data.sweep)
    spans = np.array([np.ptp(logw[data.sweep == j]) for j in range(counts.size)])
    if np.all(counts <= 1.5 * per_decade * spans + 2):
        return data.sweep, data.omega, data.storage, data.loss
    l2 = np.log10(np.maximum(data.loss, 1e-12 * data.storage))
    sweep, lw, (l1, l2), _ = bin_sweeps(data.sweep, logw, (np.log10(data.storage), l2), per_decade)
    return sweep, 10.0 ** lw, 10.0 ** l1, 10.0 ** l2


def _overlap_refusal(spec, data) -> None:
    """no_overlap = "error": the overlap shifts found in the preflight (from the file the stage's check
    has read), so the refusal comes before anything is written."""
    if spec["no_overlap"] != "error" or data is None or data.temperatures.size < 2:
        return
    T = data.temperatures
    sweep, omega, storage, loss = _binned(data, spec["bins_per_decade"])
    l1, l2 = np.log10(storage), np.log10(np.maximum(loss, 1e-12 * storage))
    j0 = int(np.argmin(np.abs(T - _reference(spec, T))))
    _, _, overlap, _, edge = overlap_shifts(np.log10(omega), l1, l2, sweep, T.size, j0, spec["shift_on"],
                                            spec["vertical_fit"] == "free", spec["min_overlap"])
    _warn_overlap(spec, data, overlap, edge, T)


def _warn_overlap(spec, data, overlap, at_edge, T) -> None:
    """Warn (or refuse, with no_overlap = "error") naming both temperatures of each pair whose best
    shift leaves less overlap than min_overlap."""
    j0 = int(np.nanargmin(np.where(np.isnan(overlap), 0.0, np.inf)))
    pairs = [(j, j - 1 if j > j0 else j + 1) for j in np.flatnonzero(at_edge)]
    if not pairs:
        return
    listed = "; ".join(f"{T[j] - 273.15:.4g} °C on {T[k] - 273.15:.4g} °C" for j, k in pairs)
    message = (f"the overlap of these neighbouring sweeps does not fix their shift on {spec['shift_on']} (the best "
               f"shift wants less than {spec['min_overlap']:g} decades of overlap, or a sign against the temperature "
               f"order, or the curves are flat there): "
               f"{listed}. Measure closer temperatures or wider frequency ranges, or shift on another quantity "
               "(shift_on: a flat E' on a glassy or rubbery plateau does not fix a shift; E'' or tan delta may)")
    if spec["no_overlap"] == "error":
        raise UserError(message, file=str(data.path), key="modulus.no_overlap")
    warnings.warn(f"{data.path}: {message}", UserWarning, stacklevel=3)


def master_curve(spec, data) -> MasterCurve:
    """Shift the sweeps of ``data`` (:class:`roughcontact.dma.DMASweeps`) to T_ref, fit the WLF law
    and the spectrum, run the Kramers-Kronig check and warn (naming the temperatures) where it fails."""
    T = data.temperatures
    T_ref = _reference(spec, T)
    sweep, omega, storage_raw, loss_raw = _binned(data, spec["bins_per_decade"])
    two = T.size == 2
    if two:
        warnings.warn(f"{data.path}: two temperatures give one relative shift: WLF C2 held at modulus.C2 = "
                      f"{spec['C2']:g} K and only C1 fitted; set modulus.C2 to your material's value, or measure a "
                      "third temperature", UserWarning, stacklevel=2)
    shifts = build_master_curve(T, sweep, omega, storage_raw, loss_raw, T_ref, spec["fit"],
                                spec["vertical_fit"] == "free", spec["shift_on"], spec["min_overlap"],
                                C2=spec["C2"] if two else None, law=spec["shift_law"], T_g=spec["T_g"])
    _warn_overlap(spec, data, shifts.overlap, shifts.at_edge, T)  # with no_overlap = "error" refused in check_dma
    reduced = omega * 10.0 ** shifts.log10_aT[sweep]
    b = 10.0 ** shifts.log10_bT[sweep]
    storage, loss = storage_raw / b, np.maximum(loss_raw / b, 1e-12 * storage_raw / b)
    times = relaxation_times(reduced, int(spec["spectrum_per_decade"]))
    E0, moduli, fit_residual = fit_prony(reduced, storage, loss, times)
    _, deviation = kramers_kronig_deviation(reduced, storage, loss, times, sweep)
    kk = np.array([np.sqrt(np.mean(deviation[sweep == j] ** 2)) for j in range(T.size)])
    bad = np.flatnonzero(kk > spec["kk_tolerance"])
    if bad.size:
        listed = ", ".join(f"{T[j] - 273.15:.4g} °C ({100 * kk[j]:.3g} %)" for j in bad)
        warnings.warn(f"{data.path}: E' does not follow from E'' by Kramers-Kronig within "
                      f"{100 * spec['kk_tolerance']:g} % (rms) at T = {listed}: the data there are not causal or do "
                      "not superpose", UserWarning, stacklevel=2)
    return MasterCurve(float(T_ref), shifts.C1, shifts.C2, T, shifts.log10_aT, shifts.log10_bT, shifts.residual,
                       shifts.wlf_residual, kk, E0, moduli, times, fit_residual, reduced, storage, loss,
                       T[sweep], shifts.overlap, shifts.misfit, shifts.law, shifts.T_g, shifts.E_a)


def model(curve: MasterCurve):
    """E(omega) at T_ref of the fitted spectrum, and the attributes saying what it is."""
    attrs = {"model_formula": "generalized Maxwell fitted to the DMA master curve (non-negative moduli): "
                              "E = E0 + sum_k E_k i w tau_k / (1 + i w tau_k)",
             "model_parameters": json.dumps({"E0": curve.E0, "terms": int(np.count_nonzero(curve.moduli))}),
             "wlf_fit": f"C1 = {curve.C1:.6g}, C2 = {curve.C2:.6g} K, T_ref = {curve.T_ref:.6g} K"
                        + (f"; Arrhenius below T_g = {curve.T_g:.6g} K with E_a = {curve.E_a / 1e3:.6g} kJ/mol"
                           if curve.law == "wlf_arrhenius" else ""),
             "measured_reduced_omega_range": f"{curve.reduced_omega.min():.6g} {curve.reduced_omega.max():.6g} rad/s"}
    return (lambda w: prony_modulus(w, curve.E0, curve.moduli, curve.times)), attrs


def shift_spec(spec, curve: MasterCurve) -> dict:
    """The [modulus] values with the fitted temperature law in place of the scene's shift keys."""
    vertical = spec["vertical_fit"] == "free"
    return dict(spec, shift=curve.law, C1=curve.C1, C2=curve.C2, T_ref=curve.T_ref, T_g=curve.T_g, E_a=curve.E_a,
                shift_T=curve.temperatures,
                shift_log10_aT=None, vertical_shift="table" if vertical else "none",
                shift_log10_bT=curve.log10_bT if vertical else None)


def dma_variables(curve: MasterCurve, wanted) -> dict:
    """The optional DMA outputs asked for (all of them once any is asked), as DataArrays."""
    if not set(DMA_OUTPUTS) & set(wanted):
        return {}
    per_sweep = {"sweep_log10_aT": curve.log10_aT, "sweep_log10_bT": curve.log10_bT,
                 "sweep_shift_residual": curve.residual, "sweep_wlf_residual": curve.wlf_residual,
                 "sweep_kk_deviation": curve.kk_deviation, "sweep_overlap": curve.overlap,
                 "sweep_pair_misfit": curve.misfit}
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
    return dict(key="modulus", columns=spec["column_names"] or spec["columns"], sheet=spec["sheet"],
                temperature_unit=spec["temperature_unit"],
                frequency_unit=spec["frequency_unit"], modulus_unit=spec["modulus_unit"],
                loss_column=spec["loss_column"], frequency=spec["frequency"],
                temperature_tolerance=spec["temperature_tolerance"], loss_from_tan_delta=loss_modulus_from_tan_delta)
