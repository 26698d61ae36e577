"""Reading multi-temperature DMA frequency sweeps (the ``dma`` reader of :data:`roughcontact.readers.READERS`).

A DMA file is a text table (read by :func:`roughcontact.readers.read_table`) with one row per
measured point and columns temperature, frequency (cyclic or angular), E' and E'' or tan delta,
with units in the header (``# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]``) or from the scene. Rows of
one isothermal sweep are consecutive; a new sweep starts where the temperature moves by more than
a tolerance (instruments log the measured temperature, which wanders by a few tenths of a kelvin).
The reader hands the stage SI arrays (K, rad/s, Pa), checked row by row: errors name the file and
the line (:func:`roughcontact.readers.first_bad`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import UserError
from .readers import first_bad, read_table
from .units import array_to_si, to_si

_HEADER = "# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]"


@dataclass
class DMASweeps:
    """Isothermal frequency sweeps at two or more temperatures, in SI units.

    Attributes
    ----------
    path
        The file.
    temperatures
        Temperature of each sweep (K): the mean of its rows, increasing.
    sweep
        Index into ``temperatures`` of each point (rows sorted by sweep, then frequency).
    omega, storage, loss
        Angular frequency (rad/s, > 0), E' (Pa, > 0) and E'' (Pa, >= 0) of each point.
    lines
        Line of each point in the file.
    attrs
        What to record about the source.
    """

    path: Path
    temperatures: np.ndarray
    sweep: np.ndarray
    omega: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    lines: np.ndarray
    attrs: dict = field(default_factory=dict)


def _temperature_to_kelvin(raw: np.ndarray, unit: str, key: str) -> np.ndarray:
    """Temperatures in an affine unit (degC, degF, K) to K, through the one unit parser."""
    zero = to_si(f"0 {unit}", "K", key=key)
    return zero + (to_si(f"1 {unit}", "K", key=key) - zero) * np.asarray(raw, dtype=float)


def _units(table, cols, temperature_unit, frequency_unit, modulus_unit, tan, key):
    """(T, f, E', E'') units from the scene or else the header; a UserError naming the missing one."""
    units = table.units if table.units else [None] * table.data.shape[1]
    t_unit = temperature_unit or units[cols[0]]
    f_unit = frequency_unit or units[cols[1]]
    e_unit = modulus_unit or units[cols[2]]
    l_unit = None if tan else (modulus_unit or units[cols[3]] or e_unit)
    for missing, what, name in ((t_unit, "temperature", "temperature_unit"), (f_unit, "frequency", "frequency_unit"),
                                (e_unit and (l_unit or tan), "modulus", "modulus_unit")):
        if not missing:
            raise UserError(f"unit of the {what} column unknown: put it in the header ({_HEADER!r}) or set {key}.{name}",
                            file=str(table.path), key=f"{key}.{name}")
    return t_unit, f_unit, e_unit, l_unit


def _sweeps(T: np.ndarray, lines: np.ndarray, tolerance: float, path) -> np.ndarray:
    """Start index of each sweep: a new one where T leaves the first row's T by more than tolerance."""
    starts = [0]
    for i in range(1, T.size):
        if abs(T[i] - T[starts[-1]]) > tolerance:
            starts.append(i)
    bounds = np.append(starts, T.size)
    means = np.array([T[a:b].mean() for a, b in zip(bounds[:-1], bounds[1:])])
    for j in range(1, means.size):
        close = np.flatnonzero(np.abs(means[:j] - means[j]) <= tolerance)
        if close.size:
            raise UserError(f"a second sweep at T = {means[j]:.6g} K (the sweep from line {lines[starts[close[0]]]} has "
                            f"{means[close[0]]:.6g} K): merge them or raise the temperature tolerance",
                            file=str(path), key=f"line {lines[starts[j]]}")
    if means.size < 2:
        raise UserError(f"only one temperature ({means[0]:.6g} K, lines {lines[0]}-{lines[-1]}): a master curve needs "
                        "frequency sweeps at two or more temperatures", file=str(path), key=f"line {lines[0]}")
    return bounds


def _order(omega, bounds, lines, path, temperatures):
    """Row order: sweeps by temperature, each by frequency; a sweep must be monotonic in frequency
    (either direction) with at least 3 points."""
    order = []
    for j in np.argsort(temperatures):
        a, b = bounds[j], bounds[j + 1]
        if b - a < 3:
            raise UserError(f"the sweep at T = {temperatures[j]:.6g} K has {b - a} point(s); at least 3 frequencies "
                            "are needed", file=str(path), key=f"line {lines[a]}")
        step = np.diff(omega[a:b])
        if not (np.all(step > 0) or np.all(step < 0)):
            sign = np.sign(step[0]) if step[0] != 0 else 1.0
            bad = int(np.flatnonzero(np.sign(step) != sign)[0])
            raise UserError(f"frequencies not sorted within the sweep at T = {temperatures[j]:.6g} K "
                            f"({omega[a + bad]:.6g} then {omega[a + bad + 1]:.6g} rad/s)", file=str(path),
                            key=f"line {lines[a + bad + 1]}")
        rows = np.arange(a, b)
        order.append(rows if step[0] > 0 else rows[::-1])
    return np.concatenate(order)


def read_dma(path: Path, *, key: str = "modulus", columns=(0, 1, 2, 3), temperature_unit: str | None = None,
             frequency_unit: str | None = None, modulus_unit: str | None = None, loss_column: str = "loss_modulus",
             frequency: str = "auto", temperature_tolerance: float = 0.5) -> DMASweeps:
    """Read multi-temperature frequency sweeps: a text table with columns ``columns`` = [T,
    frequency, E', E'' or tan delta] (``loss_column`` says which). Units come from the scene
    (``temperature_unit``, ``frequency_unit``, ``modulus_unit``) or else the header; frequencies
    are angular or cyclic as ``frequency`` says ("auto": angular if the unit says rad). Rows whose
    temperature stays within ``temperature_tolerance`` (K) of a sweep's first row belong to it.
    ``key`` is the scene section (errors name ``key.frequency_unit``, ...)."""
    cols = tuple(columns)
    if len(cols) != 4:
        raise UserError(f"needs four column indices [T, frequency, E', E''], got {list(cols)}", key=f"{key}.columns")
    table = read_table(path)
    T_raw, f_raw, s_raw, l_raw = (table.column(i) for i in cols)
    tan = loss_column == "tan_delta"
    t_unit, f_unit, e_unit, l_unit = _units(table, cols, temperature_unit, frequency_unit, modulus_unit, tan, key)
    where = lambda i: f"line {table.lines[i]}"  # noqa: E731
    for raw, name in ((T_raw, "temperature"), (f_raw, "frequency"), (s_raw, "E'"), (l_raw, "tan delta" if tan else "E''")):
        first_bad(~np.isfinite(raw), lambda i: f"{name} is NaN or infinite", table.path, where)
    T = _temperature_to_kelvin(T_raw, t_unit, f"{key}.temperature_unit")
    angular = frequency == "angular" or frequency == "auto" and re.search(r"rad", f_unit) is not None
    omega = array_to_si(f_raw, f_unit, "1/s", key=f"{key}.frequency_unit") * (1.0 if angular else 2.0 * np.pi)
    storage = array_to_si(s_raw, e_unit, "Pa", key=f"{key}.modulus_unit")
    loss = storage * l_raw if tan else array_to_si(l_raw, l_unit, "Pa", key=f"{key}.modulus_unit")
    first_bad(T <= 0, lambda i: f"temperature {T_raw[i]:g} {t_unit} is not above absolute zero", table.path, where)
    first_bad(omega <= 0, lambda i: f"frequency must be positive, got {f_raw[i]:g}", table.path, where)
    first_bad(storage <= 0, lambda i: f"storage modulus E' must be positive, got {s_raw[i]:g}", table.path, where)
    loss_name = "tan delta" if tan else "loss modulus E''"
    first_bad(l_raw < 0 if tan else loss < 0, lambda i: f"{loss_name} must be >= 0, got {l_raw[i]:g}", table.path, where)
    bounds = _sweeps(T, table.lines, temperature_tolerance, table.path)
    temperatures = np.array([T[a:b].mean() for a, b in zip(bounds[:-1], bounds[1:])])
    order = _order(omega, bounds, table.lines, table.path, temperatures)
    sweep_of_row = np.repeat(np.arange(temperatures.size), np.diff(bounds))
    rank = np.empty(temperatures.size, dtype=int)
    rank[np.argsort(temperatures)] = np.arange(temperatures.size)
    kind = "angular" if angular else "cyclic: omega = 2 pi f"
    return DMASweeps(path=table.path, temperatures=np.sort(temperatures), sweep=rank[sweep_of_row[order]],
                     omega=omega[order], storage=storage[order], loss=loss[order], lines=table.lines[order],
                     attrs={"source_file": str(path), "frequency_column": f"{f_unit} ({kind})",
                            "temperature_column": t_unit, "sweeps": int(temperatures.size)})
