"""Checksums of stored results: an edited value or attribute is found when a result is reused.

Each result file carries a global attribute ``data_checksum``: a sha256 over (a) one 64-bit
sum per variable, the sum over its elements of a hash of (element index, value bits), and (b)
every attribute of the file (global and per variable) except the checksum itself. The per-
variable sums do not depend on the order in which blocks are added, so the engine sums the
blocks it computes as it writes them (:class:`Checksums`), and only the variables written in
one piece are read back (they are small).

Detected: any changed value of any variable or coordinate (a flipped bit, an edited number,
NaN for a number), a changed, added or removed attribute (``parameters`` with the stage key
kept, units, ...), a renamed, added or removed variable. Not detected: a deliberate forgery
that also recomputes the checksum with this module (it is a checksum, not a signature), or a
file checked only by its key because it is larger than ``VERIFY_LIMIT_BYTES`` and ``--verify``
was not asked for. Hashing runs at about the speed of reading the file (docs/reliability.md).
"""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np

from . import ncio

#: the global attribute holding the checksum, and the name of the algorithm in its value
ATTR = "data_checksum"
ALGORITHM = "sum64-sha256-v1"
#: files up to this size are verified whenever they are reused; larger ones with --verify
VERIFY_LIMIT_BYTES = 64 * 2**20

_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_CANONICAL_NAN = np.array([np.nan]).view(np.uint64)[0]


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser on uint64 arrays (wrapping arithmetic)."""
    x = (x ^ (x >> np.uint64(30))) * _M1
    x = (x ^ (x >> np.uint64(27))) * _M2
    return x ^ (x >> np.uint64(31))


def _bits(values: np.ndarray) -> np.ndarray:
    """Each element as 64 bits: floats as float64 (one NaN), integers as int64, others hashed."""
    kind = values.dtype.kind
    if kind == "f":
        a = np.ascontiguousarray(values, dtype=np.float64)
        return np.where(np.isnan(a), _CANONICAL_NAN, a.view(np.uint64))
    if kind in "iub":
        return np.ascontiguousarray(values, dtype=np.int64).view(np.uint64)
    flat = [int.from_bytes(hashlib.blake2b(str(v).encode(), digest_size=8).digest(), "little") for v in values.ravel()]
    return np.array(flat, dtype=np.uint64).reshape(values.shape)


def _salt(name: str) -> np.uint64:
    return np.uint64(int.from_bytes(hashlib.blake2b(name.encode(), digest_size=8).digest(), "little"))


def block_sum(name: str, values, start, shape) -> int:
    """The contribution of one block (``values`` at offset ``start`` in a variable of ``shape``)."""
    values = np.asarray(values)
    if values.size == 0:
        return 0
    strides = [math.prod(shape[d + 1:]) for d in range(len(shape))]
    index = np.zeros(values.shape, dtype=np.uint64)
    for d, (s0, n, stride) in enumerate(zip(start, values.shape, strides)):
        shape_d = [1] * values.ndim
        shape_d[d] = n
        index = index + (np.arange(s0, s0 + n, dtype=np.uint64) * np.uint64(stride)).reshape(shape_d)
    with np.errstate(over="ignore"):
        h = _mix(_bits(values) ^ _mix(index ^ _salt(name)))
    return int(h.sum(dtype=np.uint64))


class Checksums:
    """Per-variable sums of blocks, added in any order (``add(name, block, start)``)."""

    def __init__(self, shapes: dict):
        self.shapes = {str(k): tuple(int(n) for n in v) for k, v in shapes.items()}
        self.sums = {name: 0 for name in self.shapes}

    def add(self, name: str, values, start) -> None:
        self.sums[name] = (self.sums[name] + block_sum(name, values, start, self.shapes[name])) % 2**64


def _plain(value):
    """An attribute value as plain JSON-able Python (NaN and inf as text)."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value


def _variable_sum(var, name: str, rows: int = 2**21) -> int:
    """The sum of a variable read from an open netCDF4 file, in slabs along its first dimension."""
    shape = tuple(var.shape)
    if not shape:
        with ncio.locked():
            return block_sum(name, np.asarray(var[...]), (), ())
    step = max(1, rows // max(1, math.prod(shape[1:])))
    total = 0
    for i in range(0, shape[0], step):
        with ncio.locked():
            values = np.asarray(var[i:i + step])
        total = (total + block_sum(name, values, (i,) + (0,) * (len(shape) - 1), shape)) % 2**64
    return total


def _digest(nc, known: dict[str, int]) -> str:
    """The checksum of an open netCDF4 file; sums in ``known`` are taken as given."""
    h = hashlib.sha256(ALGORITHM.encode())
    with ncio.locked():
        nc.set_auto_maskandscale(False)
        names = sorted(nc.variables)
        attrs = {"": {a: _plain(nc.getncattr(a)) for a in nc.ncattrs() if a != ATTR}}
        attrs.update({n: {a: _plain(nc.variables[n].getncattr(a)) for a in nc.variables[n].ncattrs()} for n in names})
    for name in names:
        total = known[name] if name in known else _variable_sum(nc.variables[name], name)
        h.update(f"{name}:{total:016x};".encode())
    h.update(json.dumps(attrs, sort_keys=True, default=str).encode())
    return f"{ALGORITHM}:{h.hexdigest()}"


def stamp(path, known: dict[str, int] | None = None) -> str:
    """Compute the file's checksum (reading the variables whose sums are not ``known``) and
    store it as the global attribute :data:`ATTR`."""
    with ncio.dataset(path, "a") as nc:
        value = _digest(nc, known or {})
        with ncio.locked():
            nc.setncattr(ATTR, value)
    return value


def verify(path) -> bool | None:
    """Whether the file's data and attributes still match its checksum (None: it has none)."""
    with ncio.dataset(path, "r") as nc:
        with ncio.locked():
            stored = nc.getncattr(ATTR) if ATTR in nc.ncattrs() else None
        if stored is None:
            return None
        return _digest(nc, {}) == stored
