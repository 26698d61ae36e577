"""The one unit parser: quantities given as strings ("1 nm", "77.2 GPa", "2e8 1/m") -> SI floats.

Everything inside roughcontact is SI; this module is the only place that talks to pint, which
is imported, and its registry built, only when a quantity is parsed (a rerun whose scene is
unchanged takes its parsed values from :mod:`roughcontact.scenecache` and never does). Showing an
SI quantity ("77.2 GPa", "2e8 1/m": :func:`readable`) needs no pint: the SI unit strings the stages
declare are read by a small parser here (:func:`si_dimension`), pint only for anything else.
"""

from __future__ import annotations

import functools
import math
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


#: the SI symbols (and the named SI units) :func:`si_dimension` knows, as exponents of (m, kg, s, K, A, mol, cd)
_SI = {"m": (1, 0, 0, 0, 0, 0, 0), "kg": (0, 1, 0, 0, 0, 0, 0), "s": (0, 0, 1, 0, 0, 0, 0), "K": (0, 0, 0, 1, 0, 0, 0),
       "A": (0, 0, 0, 0, 1, 0, 0), "mol": (0, 0, 0, 0, 0, 1, 0), "cd": (0, 0, 0, 0, 0, 0, 1),
       "Pa": (-1, 1, -2, 0, 0, 0, 0), "N": (1, 1, -2, 0, 0, 0, 0), "J": (2, 1, -2, 0, 0, 0, 0),
       "W": (2, 1, -3, 0, 0, 0, 0), "Hz": (0, 0, -1, 0, 0, 0, 0), "C": (0, 0, 1, 0, 1, 0, 0),
       "V": (2, 1, -3, 0, -1, 0, 0), "ohm": (2, 1, -3, 0, -2, 0, 0), "S": (-2, -1, 3, 0, 2, 0, 0),
       "rad": (0,) * 7, "sr": (0,) * 7}
_TOKEN = re.compile(r"\s*(\*\*|[*/^()]|[A-Za-z]+|\d+(?:\.\d*)?|-\d+)")


def si_dimension(units: str) -> tuple[float, ...] | None:
    """The exponents of (m, kg, s, K, A, mol, cd) of an SI unit string ("Pa/m", "W/(m^2*K)",
    "1/m", "m^4"), or None when it holds anything but the symbols of :data:`_SI` (pint reads those).
    Products are written with ``*`` or a space, powers with ``^`` or ``**``; ``/`` divides by the
    next factor (a bracket or one symbol with its power), as pint reads it."""
    tokens, pos = [], 0
    while pos < len(units.rstrip()):
        m = _TOKEN.match(units, pos)
        if not m:
            return None
        tokens.append(m.group(1))
        pos = m.end()

    def product(i):  # factors up to a closing bracket or the end
        total = np.zeros(7)
        while i < len(tokens) and tokens[i] != ")":
            sign = 1.0
            if tokens[i] in "*/":
                sign = -1.0 if tokens[i] == "/" else 1.0
                i += 1
            dim, i = power(i)
            if dim is None:
                return None, i
            total += sign * dim
        return total, i

    def power(i):  # one factor with an optional exponent
        if i >= len(tokens):
            return None, i
        if tokens[i] == "(":
            dim, i = product(i + 1)
            if dim is None or i >= len(tokens):
                return None, i
            i += 1
        elif tokens[i] in _SI:
            dim, i = np.array(_SI[tokens[i]], dtype=float), i + 1
        elif tokens[i][0].isdigit():
            dim, i = np.zeros(7), i + 1
        else:
            return None, i
        if i < len(tokens) and tokens[i] in ("^", "**"):
            if i + 1 >= len(tokens) or not tokens[i + 1].lstrip("-")[:1].isdigit():
                return None, i
            dim, i = dim * float(tokens[i + 1]), i + 2
        return dim, i

    dim, end = product(0)
    return tuple(dim.tolist()) if dim is not None and end == len(tokens) else None


def is_dimensionless(units: str) -> bool:
    if units in ("", "1"):
        return True
    dim = si_dimension(units)
    return not any(dim) if dim is not None else _unit(units, None).dimensionless


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
        power = math.floor(math.log10(abs(value)) / 3) * 3  # as pint's to_compact chooses the prefix
        power = min(max(power, min(_PREFIXES)), max(_PREFIXES))
        return f"{number(value / 10.0**power if power > 0 else value * 10.0**-power, digits)} {_PREFIXES[power]}{units}"
    return f"{number(value, digits)} {units}"


#: the SI prefixes by power of ten (micro written u), as :func:`readable` prefixes the first unit
_PREFIXES = dict(zip(range(-30, 31, 3), "q r y z a f p n u m _ k M G T P E Z Y R Q".split(), strict=True))
_PREFIXES[0] = ""


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
