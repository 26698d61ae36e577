"""The one unit parser: quantities given as strings ("1 nm", "77.2 GPa", "2e8 1/m") -> SI floats.

Everything inside roughcontact is SI; this module is the only place that talks to pint, which
is imported, and its registry built, only when a quantity is parsed (a rerun whose scene is
unchanged takes its parsed values from :mod:`roughcontact.scenecache` and never does).
"""

from __future__ import annotations

import functools
import re
from typing import TYPE_CHECKING

import numpy as np

from .errors import UserError

if TYPE_CHECKING:  # for the annotations only: pint is imported when a quantity is parsed
    import pint

_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


@functools.cache
def registry() -> "pint.UnitRegistry":
    import pint

    try:  # pint's own on-disk cache of its parsed definitions: a second start builds it in a fraction
        ureg = pint.UnitRegistry(cache_folder=":auto:")
    except OSError:  # no writable cache folder
        ureg = pint.UnitRegistry()
    ureg.define("angstrom_alias = angstrom = Å")
    return ureg


def _unit(text: str, key: str | None) -> "pint.Unit":
    try:
        return registry().Unit(text)
    except Exception as exc:  # pint raises several types for unparsable units
        raise UserError(f"cannot read unit {text!r} ({exc.__class__.__name__})", key=key) from None


def is_dimensionless(units: str) -> bool:
    return units in ("", "1") or _unit(units, None).dimensionless


def to_si(value, units: str, *, key: str | None = None, default_unit: str | None = None,
          difference: bool = False) -> float:
    """Convert a scalar quantity to a float in the SI ``units``.

    Parameters
    ----------
    value
        A number or a string ``"<number> <unit>"``. A bare number is accepted only when
        ``units`` is dimensionless or ``default_unit`` is given.
    units
        Target SI units, e.g. ``"m"``, ``"Pa"``, ``"1/m"``, ``"m^4"``, ``""``.
    key
        The scene key, for the error message.
    default_unit
        Unit of a bare number (e.g. from a ``unit =`` entry next to a list).
    difference
        The quantity is a difference (e.g. a temperature difference, WLF's C2): offset units
        are read as their differences ("51.6 degC" is 51.6 K, pint's ``delta_degC``), never
        as absolute temperatures (324.75 K).
    """
    if isinstance(value, bool):
        raise UserError(f"expected a quantity in {units or 'dimensionless'} units, got {value!r}", key=key)
    if isinstance(value, (int, float, np.number)):
        if default_unit is not None:
            return _convert(float(value), default_unit, units, key, difference)
        if is_dimensionless(units):
            return float(value)
        raise UserError(_no_units(value, units), key=key)
    if not isinstance(value, str):
        raise UserError(f"expected a number or a quantity string, got {type(value).__name__}", key=key)
    m = _NUMBER.match(value)
    if not m:
        raise UserError(f"cannot read quantity {value!r}; write e.g. \"1.5 {_example_unit(units)}\"", key=key)
    number, unit_text = float(m.group(1)), m.group(2)
    if not unit_text:
        if default_unit is not None:
            return _convert(number, default_unit, units, key, difference)
        if is_dimensionless(units):
            return number
        raise UserError(_no_units(value, units), key=key)
    return _convert(number, unit_text, units, key, difference)


def _as_difference(unit: pint.Unit) -> pint.Unit:
    """The unit of a difference: each offset unit (degC, degF) replaced by its delta unit."""
    from pint.util import UnitsContainer

    ureg = registry()
    parts = {(name if ureg.Quantity(1.0, name)._is_multiplicative else f"delta_{name}"): exp
             for name, exp in unit._units.items()}
    return ureg.Unit(UnitsContainer(parts))


def _convert(number: float, unit_text: str, units: str, key: str | None, difference: bool = False) -> float:
    ureg = registry()
    src = _unit(unit_text, key)
    if difference:
        src = _as_difference(src)
    dst = _unit(units, key) if units not in ("", "1") else ureg.dimensionless
    from pint import DimensionalityError

    try:
        return float(ureg.Quantity(number, src).to(dst).magnitude)
    except DimensionalityError:
        raise UserError(
            f"'{number:g} {unit_text}' is not convertible to {units or 'a dimensionless number'}", key=key
        ) from None


def array_to_si(values, unit_text: str, units: str, *, key: str | None = None) -> np.ndarray:
    """Convert an array given in ``unit_text`` to SI ``units`` (e.g. a file column)."""
    factor = _convert(1.0, unit_text, units, key) if unit_text else 1.0
    if unit_text and registry().Unit(unit_text).dimensionality and not _is_multiplicative(unit_text):
        raise UserError(f"offset unit {unit_text!r} is not allowed for a column", key=key)
    return np.asarray(values, dtype=float) * factor


def _is_multiplicative(unit_text: str) -> bool:
    return registry().Quantity(1.0, unit_text)._is_multiplicative


def _example_unit(units: str) -> str:
    return {"m": "nm", "Pa": "MPa", "1/m": "1/m", "m^4": "m^4", "J/m^2": "J/m^2", "K": "K", "m/s": "m/s"}.get(
        units, units or ""
    )


def _no_units(value, units: str) -> str:
    number = float(value) if not isinstance(value, str) else float(_NUMBER.match(value).group(1))
    return f"{value!r} has no units; write it with its unit, e.g. \"{readable(number, units)}\" if it is in {units}"


#: SI units shown with a prefix (77.2 GPa, 1 nm); others in powers of ten (2e8 1/m)
_PREFIXED = ("m", "Pa", "s", "J/m^2", "N", "W", "Hz")


def number(x: float, digits: int = 4) -> str:
    """A number at readable precision: 4 significant digits, powers of ten as 2e8 / 1.5e-10."""
    text = f"{x:.{digits}g}"
    mantissa, e, exponent = text.partition("e")
    return f"{mantissa}e{int(exponent)}" if e else text


def readable(value: float, units: str, digits: int = 4) -> str:
    """A quantity in SI ``units`` as a short string with units: (77.2e9, "Pa") -> "77.2 GPa",
    (1e-9, "m") -> "1 nm", (2e8, "1/m") -> "2e8 1/m", (0.42, "") -> "0.42"."""
    if is_dimensionless(units) or not np.isfinite(value):
        return f"{number(value, digits)} {units}".rstrip() if units not in ("", "1") else number(value, digits)
    if units in _PREFIXED and value != 0:
        q = registry().Quantity(value, units).to_compact()
        return f"{number(q.magnitude, digits)} {q.units:~}".replace("µ", "u").replace(" ** ", "^").replace(" / ", "/")
    return f"{number(value, digits)} {units}"


def display(value, units: str | None) -> str:
    """A parameter value for ``plan`` and ``show``: quantities with units at readable precision,
    long lists by their ends and length, anything else as JSON would show it."""
    if isinstance(value, (list, tuple)):
        items = [display(v, units) for v in value]
        if len(items) <= 4:
            return "[" + ", ".join(items) + "]"
        return f"[{items[0]}, {items[1]}, ..., {items[-1]}] ({len(items)} values)"
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool) and units is not None:
        return readable(float(value), units)
    return repr(value) if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else str(value)
