"""Declarations of scene parameters and sections, and their validation.

A stage module declares the scene sections it owns (names, units, bounds, defaults);
the engine collects them into the scene schema. Values are converted to SI here, so
stages only ever see SI floats, numpy arrays, strings and paths.
"""

from __future__ import annotations

import difflib
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from .errors import UserError
from .machine import check_sweep_length
from .units import to_si

REQUIRED = object()


class _Missing:
    """A required key the scene does not give; fine unless a needed stage reads it."""

    def __repr__(self) -> str:
        return "<missing>"

    def __reduce__(self):  # one object, also after a round trip through pickle (the scene cache)
        return "MISSING"


MISSING = _Missing()

#: Parameter kinds:
#:   quantity  one number with units (``units`` is the SI target)
#:   sweep     a quantity, or a list / range of them (a list becomes a sweep dimension)
#:   quantities  a quantity or a list of them that is data, not a sweep (e.g. Prony terms)
#:   int, bool, str, choice, path (a file, resolved against the scene's folder)
#:   paths     one or more files (a string or a list of strings), each resolved like ``path``
#:   list      a list of strings; intlist: a list of whole numbers
#:   table     a table of names to numbers or strings (e.g. { eta = 0.0 })
KINDS = ("quantity", "sweep", "quantities", "int", "bool", "str", "choice", "path", "paths", "list", "intlist", "table")


@dataclass(frozen=True)
class Param:
    """One scene key.

    Parameters
    ----------
    name
        Key inside its section.
    kind
        One of :data:`KINDS`.
    units
        SI units of a quantity or sweep ("" for dimensionless).
    default
        Default value (in SI for quantities); :data:`REQUIRED` if the user must give it.
    lo, hi, lo_open, hi_open
        Bounds (SI); ``lo_open`` means ``value > lo`` is required rather than ``>=``.
    choices
        Allowed strings for ``choice``; also extra allowed strings for a sweep (e.g. ``"all"``).
    doc
        One-line description, shown in the scene reference.
    dim, presets, ladder
        Sweep dimension name; values per preset; coarse-to-fine values (see the attributes).
    """

    def value_in(self, preset: str):
        """This parameter's value when the user does not set it, under ``preset``."""
        return self.presets.get(preset, self.default) if preset != "default" else self.default

    name: str
    kind: str = "quantity"
    units: str = ""
    default: Any = REQUIRED
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    doc: str = ""
    #: name of the dimension a list-valued sweep becomes (``{section}`` is replaced by the
    #: section's name, e.g. ``hrms_{section}``); default: the key's name
    dim: str | None = None
    #: values of a resolution setting in the named presets other than "default" (whose value is
    #: ``default``), e.g. {"fast": 20, "accurate": 100}
    presets: Mapping[str, Any] = field(default_factory=dict)
    #: the setting's values from coarse to fine for ``roughcontact accuracy``; the last is the
    #: reference ("converged") value
    ladder: tuple = ()
    #: the quantity is a difference (e.g. WLF's C2, a temperature difference): offset units are read as
    #: differences ("51.6 degC" is 51.6 K), never as absolute values
    difference: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"unknown parameter kind {self.kind!r}")

    # -- validation ---------------------------------------------------------------------
    def convert(self, raw: Any, key: str, base_dir: Path | None):
        """Validate and convert ``raw`` (as read from TOML) to its SI value."""
        converter = _CONVERTERS.get(self.kind)
        if converter is None:
            raise AssertionError(self.kind)
        return converter(self, raw, key, base_dir)

    def _bounded(self, v: float, key: str) -> float:
        if isinstance(v, float) and not math.isfinite(v):
            raise UserError(f"{v} is not a finite number", key=key)
        u = f" {self.units}" if self.units else ""
        if isinstance(v, float) and v != 0.0 and abs(v) < sys.float_info.min:  # sub-normal: 1/v overflows to inf
            raise UserError(f"{v:g}{u} is below the smallest normal double ({sys.float_info.min:.3g}): its inverse "
                            "overflows to infinity, and so would the results; give a physical value", key=key)
        if self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo):
            raise UserError(f"must be {'>' if self.lo_open else '>='} {self.lo:g}{u}, got {v:g}{u}", key=key)
        if self.hi is not None and (v >= self.hi if self.hi_open else v > self.hi):
            raise UserError(f"must be {'<' if self.hi_open else '<='} {self.hi:g}{u}, got {v:g}{u}", key=key)
        return v


# -- one converter per parameter kind (Param.convert dispatches on ``kind``) -----------------
def _quantity(p: Param, raw: Any, key: str, base_dir: Path | None) -> float:
    return p._bounded(to_si(raw, p.units, key=key, difference=p.difference), key)


def _sweep(p: Param, raw: Any, key: str, base_dir: Path | None):
    """``sweep`` and ``quantities``: a quantity or a list / range of them, or one of ``choices``."""
    if isinstance(raw, str) and raw in p.choices:
        return raw
    values = parse_sweep(raw, p.units, key, difference=p.difference)
    for v in np.atleast_1d(values):
        p._bounded(float(v), key)
    # a sweep becomes a coordinate, which CF wants strictly monotonic: increasing, whatever
    # order the scene lists it in (results do not depend on the order)
    return np.sort(values) if p.kind == "sweep" and isinstance(values, np.ndarray) else values


def _int(p: Param, raw: Any, key: str, base_dir: Path | None) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int):
        raise UserError(f"expected a whole number, got {raw!r}", key=key)
    return int(p._bounded(raw, key))


def _bool(p: Param, raw: Any, key: str, base_dir: Path | None) -> bool:
    if not isinstance(raw, bool):
        raise UserError(f"expected true or false, got {raw!r}", key=key)
    return raw


def _str(p: Param, raw: Any, key: str, base_dir: Path | None) -> str:
    """``str`` and ``choice`` (one of ``choices``)."""
    if not isinstance(raw, str):
        raise UserError(f"expected a string, got {raw!r}", key=key)
    if p.kind == "choice" and raw not in p.choices:
        raise UserError(f"{raw!r} is not one of {', '.join(map(repr, p.choices))}{_did_you_mean(raw, p.choices)}",
                        key=key)
    return raw


def _list(p: Param, raw: Any, key: str, base_dir: Path | None) -> tuple[str, ...]:
    if isinstance(raw, str):
        raw = [raw]
    if not isinstance(raw, list) or not all(isinstance(x, str) for x in raw):
        raise UserError(f"expected a list of strings, got {raw!r}", key=key)
    return tuple(raw)


def _intlist(p: Param, raw: Any, key: str, base_dir: Path | None) -> tuple[int, ...]:
    if not isinstance(raw, list) or not all(isinstance(x, int) and not isinstance(x, bool) for x in raw):
        raise UserError(f"expected a list of whole numbers, got {raw!r}", key=key)
    for x in raw:
        p._bounded(x, key)
    return tuple(raw)


def _table(p: Param, raw: Any, key: str, base_dir: Path | None) -> dict:
    if not isinstance(raw, dict) or not all(isinstance(v, (int, float, str)) and not isinstance(v, bool)
                                            for v in raw.values()):
        raise UserError(f"expected a table of names to numbers or strings, e.g. {{ eta = 0.0 }}, got {raw!r}",
                        key=key)
    return dict(raw)


def _paths(p: Param, raw: Any, key: str, base_dir: Path | None) -> tuple[Path, ...]:
    items = [raw] if isinstance(raw, str) else raw
    if not isinstance(items, list) or not items or not all(isinstance(x, str) for x in items):
        raise UserError(f"expected a file path or a non-empty list of them, got {raw!r}", key=key)
    single = Param(p.name, "path")
    return tuple(single.convert(x, f"{key}[{i}]" if len(items) > 1 else key, base_dir) for i, x in enumerate(items))


def _path(p: Param, raw: Any, key: str, base_dir: Path | None) -> Path:
    if not isinstance(raw, str):
        raise UserError(f"expected a file path, got {raw!r}", key=key)
    path = Path(raw).expanduser()
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    if path.is_dir():
        raise UserError(f"{str(path)!r} is a folder, not a file: give the path of the file in it", key=key)
    if not path.is_file():
        what = "is not a regular file" if path.exists() else "does not exist"
        raise UserError(f"file {str(path)!r} {what}", key=key)
    return path.resolve()


_CONVERTERS: dict[str, Callable[[Param, Any, str, Path | None], Any]] = {
    "quantity": _quantity, "sweep": _sweep, "quantities": _sweep, "int": _int, "bool": _bool, "str": _str,
    "choice": _str, "path": _path, "paths": _paths, "list": _list, "intlist": _intlist, "table": _table,
}
assert set(_CONVERTERS) == set(KINDS)


def parse_sweep(raw: Any, units: str, key: str, *, difference: bool = False):
    """A sweep value: a quantity (-> float), a list of quantities (-> 1-D array), or a range
    table ``{from = "...", to = "...", num = N, spacing = "log"|"linear"}``; a table with
    ``values = [...]`` and ``unit = "..."`` gives a list of bare numbers in that unit.
    """
    if isinstance(raw, dict):
        allowed = {"from", "to", "num", "spacing", "values", "unit"}
        for k in raw:
            if k not in allowed:
                raise UserError(f"unknown key {k!r} in a sweep table{_did_you_mean(k, allowed)}", key=f"{key}.{k}")
        unit = raw.get("unit")
        if "values" in raw:
            if set(raw) - {"values", "unit"}:
                raise UserError("a sweep table has either 'values' or 'from'/'to'/'num', not both", key=key)
            return parse_sweep_list(raw["values"], units, key, unit, difference)
        missing = [k for k in ("from", "to", "num") if k not in raw]
        if missing:
            raise UserError(f"a range needs 'from', 'to' and 'num' (missing {', '.join(missing)})", key=key)
        lo = to_si(raw["from"], units, key=f"{key}.from", default_unit=unit, difference=difference)
        hi = to_si(raw["to"], units, key=f"{key}.to", default_unit=unit, difference=difference)
        num = raw["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise UserError(f"'num' must be a whole number >= 1, got {num!r}", key=f"{key}.num")
        check_sweep_length(num, f"{key}.num")
        spacing = raw.get("spacing", "log")
        if spacing == "log":
            if lo <= 0 or hi <= 0:
                raise UserError("a log range needs positive 'from' and 'to'", key=key)
            return np.geomspace(lo, hi, num)
        if spacing == "linear":
            return np.linspace(lo, hi, num)
        raise UserError(f"'spacing' must be 'log' or 'linear', got {spacing!r}", key=f"{key}.spacing")
    if isinstance(raw, list):
        return parse_sweep_list(raw, units, key, None, difference)
    return to_si(raw, units, key=key, difference=difference)


def parse_sweep_list(raw, units, key, unit, difference=False):
    if not isinstance(raw, list) or not raw:
        raise UserError("expected a non-empty list", key=key)
    values = np.array([to_si(v, units, key=f"{key}[{i}]", default_unit=unit, difference=difference)
                       for i, v in enumerate(raw)])
    if len(np.unique(values)) != len(values):
        raise UserError("a sweep list must not repeat a value", key=key)
    return values


@dataclass(frozen=True)
class Section:
    """A scene section (a TOML table) with its parameters.

    ``discriminator`` names a key (e.g. ``kind``) whose value selects one of ``variants``
    (extra parameters per kind); ``check`` validates relations between parameters and
    raises :class:`UserError` naming the key. ``optional`` sections may be absent (value None).
    """

    name: str
    params: tuple[Param, ...] = ()
    doc: str = ""
    optional: bool = False
    discriminator: str | None = None
    variants: Mapping[str, tuple[Param, ...]] = field(default_factory=dict)
    check: Callable[[dict, str], None] | None = None

    def sweep_dims(self, values: dict | None) -> dict[str, int]:
        """Sizes of the sweep dimensions that ``values`` (this section, converted) define."""
        if not values:
            return {}
        out = {}
        for p in self.params_for(values.get(self.discriminator) if self.discriminator else None):
            v = values.get(p.name)
            if p.kind == "sweep" and isinstance(v, np.ndarray) and v.ndim == 1:
                out[(p.dim or p.name).format(section=self.name)] = v.size
        return out

    def params_for(self, kind: str | None) -> tuple[Param, ...]:
        return self.params + tuple(self.variants.get(kind, ())) if kind is not None else self.params

    def convert(self, raw: Any, base_dir: Path | None, key: str | None = None, preset: str = "default") -> dict | None:
        key = key or self.name
        if raw is None:
            if self.optional:
                return None
            raw = {}
        if not isinstance(raw, dict):
            raise UserError(f"expected a table [{key}], got {raw!r}", key=key)
        kind = self._variant(raw, key)
        params = {p.name: p for p in self.params_for(kind)}
        out: dict[str, Any] = {}
        if kind is not None:
            out[self.discriminator] = kind
        for k in raw:
            if k != self.discriminator and k not in params:
                raise UserError(f"unknown key {k!r}{_did_you_mean(k, params)}", key=f"{key}.{k}")
        for name, p in params.items():
            if name in raw:
                out[name] = p.convert(raw[name], f"{key}.{name}", base_dir)
            elif p.default is not REQUIRED:
                out[name] = p.value_in(preset)
        missing = [n for n, p in params.items() if n not in out]
        if missing and self.discriminator is not None:
            raise UserError(f"missing required key(s): {', '.join(missing)}", key=key)
        for name in missing:  # an error only if a stage the scene needs reads it (engine.plan)
            out[name] = MISSING
        if self.check is not None and not missing:
            self.check(out, key)
        return out

    def _variant(self, raw: dict, key: str) -> str | None:
        """The value of the discriminator key (which variant's parameters apply); None without one."""
        if self.discriminator is None:
            return None
        if self.discriminator not in raw:
            raise UserError(f"needs '{self.discriminator}' (one of {', '.join(map(repr, self.variants))})", key=key)
        kind = raw[self.discriminator]
        if kind not in self.variants:
            raise UserError(
                f"{self.discriminator} = {kind!r} is not one of {', '.join(map(repr, self.variants))}"
                f"{_did_you_mean(str(kind), self.variants)}",
                key=f"{key}.{self.discriminator}",
            )
        return kind


def _did_you_mean(word: str, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


did_you_mean = _did_you_mean
