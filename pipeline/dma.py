"""Reading multi-temperature DMA frequency sweeps (the ``dma`` reader of :data:`roughcontact.readers.READERS`).

A DMA file is a table of moduli (read by the one reader :func:`roughcontact.moduli.read_moduli`,
like a master curve) with one row per measured point and columns temperature, frequency (cyclic
or angular), E' and E'' or tan delta, with units in the header
(``# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]``) or from the scene. Rows of one isothermal sweep are
consecutive; a new sweep starts where the temperature moves by more than a tolerance (instruments
log the measured temperature, which wanders by a few tenths of a kelvin). The reader hands the
stage SI arrays (K, rad/s, Pa) sorted by sweep and frequency, checked row by row: errors name the
file and the line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .errors import UserError
from .moduli import read_moduli


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


def _sweeps(T: np.ndarray, lines: np.ndarray, tolerance: float, path) -> np.ndarray:
    """Start index of each sweep: a new one where T leaves the first row's T by more than tolerance."""
    starts = [0]
    for i in range(1, T.size):
        if abs(T[i] - T[starts[-1]]) > tolerance:
            starts.append(i)
    bounds = np.append(starts, T.size)
    means = np.array([T[a:b].mean() for a, b in zip(bounds[:-1], bounds[1:], strict=True)])
    for j in range(1, means.size):
        close = np.flatnonzero(np.abs(means[:j] - means[j]) <= tolerance)
        if close.size:
            raise UserError(f"a second sweep at T = {means[j]:.6g} K (the sweep from line "
                            f"{lines[starts[close[0]]]} has "
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
             frequency: str = "auto", temperature_tolerance: float = 0.5,
             loss_from_tan_delta: Callable | None = None, sheet: str | None = None) -> DMASweeps:
    """Read multi-temperature frequency sweeps: a text table or spreadsheet (``sheet``) with columns
    ``columns`` = [T,
    frequency, E', E'' or tan delta], read and checked by :func:`roughcontact.moduli.read_moduli`
    (units, angular or cyclic frequency, ``loss_from_tan_delta``). Rows whose temperature stays
    within ``temperature_tolerance`` (K) of a sweep's first row belong to it."""
    table = read_moduli(path, key=key, columns=columns, temperature=True, temperature_unit=temperature_unit,
                        frequency_unit=frequency_unit, modulus_unit=modulus_unit, loss_column=loss_column,
                        frequency=frequency, loss_from_tan_delta=loss_from_tan_delta, sheet=sheet)
    T, omega = table.temperature, table.omega
    bounds = _sweeps(T, table.lines, temperature_tolerance, table.path)
    temperatures = np.array([T[a:b].mean() for a, b in zip(bounds[:-1], bounds[1:], strict=True)])
    order = _order(omega, bounds, table.lines, table.path, temperatures)
    sweep_of_row = np.repeat(np.arange(temperatures.size), np.diff(bounds))
    rank = np.empty(temperatures.size, dtype=int)
    rank[np.argsort(temperatures)] = np.arange(temperatures.size)
    return DMASweeps(path=table.path, temperatures=np.sort(temperatures), sweep=rank[sweep_of_row[order]],
                     omega=omega[order], storage=table.storage[order], loss=table.loss[order], lines=table.lines[order],
                     attrs=dict(table.attrs, sweeps=int(temperatures.size)))
