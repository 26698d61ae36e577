"""Reading tables of a viscoelastic material's moduli: measured master curves (the
``master_curve`` reader, :func:`read_master_curve`) and multi-temperature DMA sweeps (the ``dma``
reader, :mod:`roughcontact.dma`).

Both are text tables (:func:`roughcontact.tables.read_table`) with columns [T,] frequency, E' and
E'' or tan delta, read by the one reader :func:`read_moduli`: units from the scene or else the
header (``# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]``) through the one unit parser, a bad unit blamed
on the scene key that set it or else on the file's header line, every value checked row by row,
each error one line naming the file and the line. The engine knows no physics: a tan delta column
becomes E'' through the function the stage passes (``loss_from_tan_delta``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .datafiles import column_to_si
from .errors import UserError
from .tables import first_bad, read_table
from .units import to_si

#: the columns of a moduli table, with their scene keys of units
_CELSIUS = {"C": "degC", "°C": "degC", "ºC": "degC", "F": "degF", "°F": "degF"}
_UNIT_KEYS = {"T": "temperature_unit", "frequency": "frequency_unit", "E'": "modulus_unit", "E''": "modulus_unit"}


@dataclass
class Moduli:
    """The rows of a moduli table in SI units, in file order.

    Attributes
    ----------
    path
        The file.
    temperature
        Temperature of each row (K, > 0); None for a table without a temperature column.
    omega, storage, loss
        Angular frequency (rad/s, > 0), E' (Pa, > 0) and E'' (Pa, >= 0) of each row.
    lines
        Line of each row in the file.
    attrs
        What to record about the source: ``source_file``, ``frequency_column`` (its unit and
        whether angular or cyclic) and, with a temperature column, ``temperature_column``.
    """

    path: Path
    temperature: np.ndarray | None
    omega: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    lines: np.ndarray
    attrs: dict = field(default_factory=dict)


def _kelvin(raw, unit: str, target: str, *, key: str) -> np.ndarray:
    """Temperatures in an affine unit (degC, degF, K) to K, through the one unit parser."""
    zero = to_si(f"0 {unit}", target, key=key)
    return zero + (to_si(f"1 {unit}", target, key=key) - zero) * np.asarray(raw, dtype=float)


def _units(table, columns: dict, scene: dict, tan: bool, key: str) -> dict:
    """The unit of each column (None for tan delta), from the scene (``scene``: unit key -> value)
    or else the header (E'' falls back on E'); a UserError naming the first unknown one."""
    header = dict(zip(columns, (table.units[c] if table.units else None for c in columns.values()), strict=True))
    units = {name: scene[_UNIT_KEYS[name]] or header[name] for name in columns}
    if units.get("T") is not None:  # instruments write C or °C for degrees Celsius (C alone is a coulomb)
        units["T"] = _CELSIUS.get(units["T"].strip(), units["T"])
    units["E''"] = None if tan else units["E''"] or units["E'"]
    example = "# T [degC]  f [Hz]  E' [MPa]  E'' [MPa]" if "T" in columns else "# f [Hz]  E' [MPa]  E'' [MPa]"
    for name, what in (("T", "temperature column"), ("frequency", "frequency column"), ("E'", "modulus columns")):
        if name in columns and not units[name]:
            raise UserError(f"unit of the {what} unknown: put it in the header ({example!r}) or set "
                            f"{key}.{_UNIT_KEYS[name]}", file=str(table.path), key=f"{key}.{_UNIT_KEYS[name]}")
    return units


def read_moduli(path: Path, *, key: str, columns, temperature: bool, temperature_unit: str | None = None,
                frequency_unit: str | None = None, modulus_unit: str | None = None,
                loss_column: str = "loss_modulus", frequency: str = "auto",
                loss_from_tan_delta: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                increasing: bool = False, sheet: str | None = None) -> Moduli:
    """Read a table of moduli: columns ``columns`` = [T (if ``temperature``), frequency, E', E''
    or tan delta], each a 0-based index or a name of the header (``loss_column`` says which; tan
    delta becomes E'' through ``loss_from_tan_delta(storage, tan_delta)``, which the stage passes). Units come from the
    scene (``temperature_unit``, ``frequency_unit``, ``modulus_unit``) or else the header; the
    frequency is angular or cyclic (omega = 2 pi f) as ``frequency`` says ("auto": angular if its
    unit says rad); ``increasing``: the frequency must increase strictly down the file. ``key``
    is the scene section (errors name ``key.frequency_unit``, ...); ``sheet``: of a spreadsheet."""
    names = (("T",) if temperature else ()) + ("frequency", "E'", "E''")
    if len(tuple(columns)) != len(names):
        raise UserError(f"needs {('three', 'four')[temperature]} columns [{', '.join(names)}], got "
                        f"{list(columns)}", key=f"{key}.columns")
    tan = loss_column == "tan_delta"
    if tan and loss_from_tan_delta is None:
        raise TypeError("loss_column 'tan_delta' needs loss_from_tan_delta(storage, tan_delta) from the stage")
    table = read_table(path, sheet=sheet)
    columns = dict(zip(names, (table.index(c) for c in columns), strict=True))
    raw = {name: table.column(index) for name, index in columns.items()}
    scene = {"temperature_unit": temperature_unit, "frequency_unit": frequency_unit, "modulus_unit": modulus_unit}
    units = _units(table, columns, scene, tan, key)
    where = lambda i: f"line {table.lines[i]}"  # noqa: E731
    for name, values in raw.items():
        label = {"T": "temperature", "E''": "tan delta" if tan else "E''"}.get(name, name)
        first_bad(~np.isfinite(values), lambda i, label=label: f"{label} is NaN or infinite", table.path, where)

    def si(name, target, what, convert=None):  # a unit from the header is blamed on the header line
        unit_key = _UNIT_KEYS[name]
        return column_to_si(raw[name], units[name], target, path=table.path, scene_key=f"{key}.{unit_key}", what=what,
                            origin=None if scene[unit_key] else f"line {table.header_line}", convert=convert)

    f_raw, s_raw, l_raw = raw["frequency"], raw["E'"], raw["E''"]
    T = si("T", "K", "the temperature", convert=_kelvin) if temperature else None
    angular = frequency == "angular" or frequency == "auto" and re.search(r"rad", units["frequency"]) is not None
    omega = si("frequency", "1/s", "the frequency") * (1.0 if angular else 2.0 * np.pi)
    storage = si("E'", "Pa", "E'")
    loss = loss_from_tan_delta(storage, l_raw) if tan else si("E''", "Pa", "E''")
    if temperature:
        first_bad(T <= 0, lambda i: f"temperature {raw['T'][i]:g} {units['T']} is not above absolute zero",
                  table.path, where)
    first_bad(omega <= 0, lambda i: f"frequency must be positive, got {f_raw[i]:g}", table.path, where)
    if increasing:
        first_bad(np.diff(omega) <= 0, lambda i: f"frequency is not strictly increasing ({f_raw[i]:g} then "
                  f"{f_raw[i + 1]:g})", table.path, lambda i: where(i + 1))
    first_bad(storage <= 0, lambda i: f"storage modulus E' must be positive, got {s_raw[i]:g}", table.path, where)
    loss_name = "tan delta" if tan else "loss modulus E''"
    first_bad(l_raw < 0 if tan else loss < 0, lambda i: f"{loss_name} must be >= 0, got {l_raw[i]:g}", table.path,
              where)
    kind = "angular" if angular else "cyclic: omega = 2 pi f"
    attrs = {"source_file": str(path), "frequency_column": f"{units['frequency']} ({kind})"}
    if temperature:
        attrs["temperature_column"] = units["T"]
    return Moduli(path=table.path, temperature=T, omega=omega, storage=storage, loss=loss, lines=table.lines,
                  attrs=attrs)


@dataclass
class MasterCurve:
    """A measured viscoelastic master curve at T_ref, in SI units: angular frequencies ``omega``
    (rad/s, positive, strictly increasing), ``storage`` E' (Pa, > 0) and ``loss`` E'' (Pa, >= 0),
    and ``attrs`` saying where they come from."""

    path: Path
    omega: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    attrs: dict = field(default_factory=dict)


def read_master_curve(path: Path, *, key: str = "modulus", columns=(0, 1, 2), frequency_unit: str | None = None,
                      modulus_unit: str | None = None, loss_column: str = "loss_modulus", frequency: str = "auto",
                      loss_from_tan_delta: Callable | None = None) -> MasterCurve:
    """Read a master curve: a text table with columns ``columns`` = [frequency, E', E'' or tan
    delta], the frequency strictly increasing, at least two rows (:func:`read_moduli` says the rest)."""
    table = read_moduli(path, key=key, columns=columns, temperature=False, frequency_unit=frequency_unit,
                        modulus_unit=modulus_unit, loss_column=loss_column, frequency=frequency,
                        loss_from_tan_delta=loss_from_tan_delta, increasing=True)
    if table.omega.size < 2:
        raise UserError("a master curve needs at least two data rows", file=str(table.path))
    return MasterCurve(path=table.path, omega=table.omega, storage=table.storage, loss=table.loss, attrs=table.attrs)
