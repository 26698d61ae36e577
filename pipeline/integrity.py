"""Checksums of stored results: an edited value or attribute is found when a result is reused.

Each result file carries a global attribute ``data_checksum`` (JSON): the algorithm, the block
shape each variable was hashed in, and a sha256 over (a) per variable, the sum modulo 2^256 of
the sha256 of each block (its name, position and little-endian bytes), and (b) every attribute
of the file (global and per variable) except the checksum itself. The block sums do not depend
on the order of the blocks, so the engine hashes the blocks it computes as it writes them
(:class:`Checksums`, the dask chunks), the numeric variables written in one piece from the values
the store encoded for the file (:func:`block_sums`), and reads back only text variables.

Detected: any changed value of any variable or coordinate (a flipped bit, an edited number, NaN
for a number), a changed, added or removed attribute (``parameters`` with the stage key kept,
units, ...), a renamed, added or removed variable. Not detected: a deliberate forgery that
recomputes the checksum with this module (a checksum is not a signature); and a file larger than
:data:`VERIFY_LIMIT_BYTES` is checked only by its key unless ``--verify`` is asked for. Hashing
runs at about the speed of reading the file (docs/reliability.md).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from pathlib import Path
from typing import Mapping

import numpy as np

from . import ncio

#: the global attribute holding the checksum, and the name of the algorithm in its value
ATTR = "data_checksum"
ALGORITHM = "blocksum-sha256-v1"
#: files up to this size are verified whenever they are reused; larger ones with --verify
VERIFY_LIMIT_BYTES = 64 * 2**20
#: elements per block when a variable is hashed by reading it back
_BLOCK_ELEMENTS = 2**21


def block_digest(name: str, values, start) -> int:
    """sha256 of one block of variable ``name`` at offset ``start`` (as an integer)."""
    values = np.asarray(values)
    h = hashlib.sha256(f"{name}|{tuple(int(s) for s in start)}|{values.shape}|{values.dtype.kind}|".encode())
    if values.dtype.kind in "fiub":
        if values.dtype.byteorder == ">" or (values.dtype.byteorder == "=" and np.little_endian is False):
            values = values.astype(values.dtype.newbyteorder("<"))
        h.update(memoryview(np.ascontiguousarray(values)).cast("B"))
    else:  # strings and objects: their text
        h.update("\x1f".join(str(v) for v in values.ravel()).encode())
    return int.from_bytes(h.digest(), "big")


def _regular(chunks) -> tuple[int, ...] | None:
    """The block shape of a dask chunking where every chunk but the last along each dim is equal."""
    if any(any(c != cs[0] for c in cs[:-1]) or cs[-1] > cs[0] for cs in chunks):
        return None
    return tuple(int(cs[0]) for cs in chunks)


class Checksums:
    """Per-variable block sums of the dask variables written block by block (``add``), hashed in a
    background thread (hashlib releases the GIL) while the next blocks are computed and written."""

    def __init__(self, chunks: dict):
        self.blocks = {str(k): _regular(v) for k, v in chunks.items()}
        self.pending: dict[str, list] = {name: [] for name, block in self.blocks.items() if block is not None}
        self.pool = None
        self.queue: list = []
        self.waited = 0.0  # seconds the writer waited for the hashing (its cost on the critical path)

    def add(self, name: str, values, start) -> None:
        if name in self.pending:
            if self.pool is None:
                from concurrent.futures import ThreadPoolExecutor

                self.pool = ThreadPoolExecutor(1, thread_name_prefix="roughcontact-checksum")
            self.pending[name].append(self.pool.submit(block_digest, name, values, tuple(start)))
            self.queue.append(self.pending[name][-1])
            while len(self.queue) > 4:  # at most a few blocks wait for their hash (bounded memory)
                self._wait(self.queue.pop(0))

    def _wait(self, future) -> int:
        import time

        t0 = time.perf_counter()
        value = future.result()
        self.waited += time.perf_counter() - t0
        return value

    def known(self) -> dict[str, tuple[tuple[int, ...], int]]:
        """Block shape and block sum of each variable hashed while written (waits for the hashing)."""
        out = {name: (self.blocks[name], sum(self._wait(f) for f in futures) % 2**256)
               for name, futures in self.pending.items()}
        if self.pool is not None:
            self.pool.shutdown()
        return out


def _plain(value):
    """An attribute value as plain JSON-able Python (NaN and inf as text)."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value


def _default_block(shape) -> tuple[int, ...]:
    return (max(1, _BLOCK_ELEMENTS // max(1, math.prod(shape[1:]))),) + tuple(shape[1:]) if shape else ()


def _variable_sum(var, name: str, block) -> int:
    """The block sum of a variable on the grid of ``block``: read from an open netCDF4 file, or a
    numpy array."""
    shape = tuple(var.shape)
    total = 0
    # a block of another rank than the variable (a damaged checksum attribute) raises ValueError,
    # which damage() reports as damage
    for start in itertools.product(*(range(0, n, b) for n, b in zip(shape, block, strict=True))):
        region = tuple(slice(s, s + b) for s, b in zip(start, block, strict=True))
        with ncio.locked():
            values = np.asarray(var[region] if region else var[...])
        total = (total + block_digest(name, values, start)) % 2**256
    return total


def block_sums(variables: Mapping) -> dict[str, tuple[tuple[int, ...], int]]:
    """Block shape and block sum of each numeric variable (``{name: xarray.Variable}``) in memory,
    on the grid :func:`stamp` reads a variable back in: the same numbers as reading back the
    variable written with exactly these values. Text variables are left out (they are read back)."""
    out = {}
    for name, var in variables.items():
        values = np.asarray(var.values)
        if values.dtype.kind in "fiu":
            block = _default_block(values.shape)
            out[str(name)] = (block, _variable_sum(values, str(name), block))
    return out


def _digest(nc, blocks: dict, known: dict[str, int]) -> str:
    """sha256 over the variables' block sums and all attributes of an open netCDF4 file."""
    h = hashlib.sha256(ALGORITHM.encode())
    with ncio.locked():
        nc.set_auto_maskandscale(False)
        names = sorted(nc.variables)
        attrs = {"": {a: _plain(nc.getncattr(a)) for a in nc.ncattrs() if a != ATTR}}
        attrs.update({n: {a: _plain(nc.variables[n].getncattr(a)) for a in nc.variables[n].ncattrs()} for n in names})
    for name in names:
        if name not in blocks:
            return "variable not in the checksum: " + name
        total = known[name] if name in known else _variable_sum(nc.variables[name], name, tuple(blocks[name]))
        h.update(f"{name}:{tuple(blocks[name])}:{total:064x};".encode())
    h.update(json.dumps(attrs, sort_keys=True, default=str).encode())
    return h.hexdigest()


def stamp(path, known: dict[str, tuple[tuple[int, ...], int]] | None = None) -> None:
    """Compute the file's checksum (reading back the variables whose block sums are not
    ``known``) and store it as the global attribute :data:`ATTR`."""
    known = known or {}
    with ncio.dataset(path, "a") as nc:
        with ncio.locked():
            shapes = {name: tuple(v.shape) for name, v in nc.variables.items()}
        blocks = {name: list(known[name][0]) if name in known else list(_default_block(shape))
                  for name, shape in shapes.items()}
        digest = _digest(nc, blocks, {name: total for name, (_, total) in known.items()})
        value = json.dumps({"algorithm": ALGORITHM, "blocks": blocks, "sha256": digest}, separators=(",", ":"))
        with ncio.locked():
            nc.setncattr(ATTR, value)


def verify(path) -> bool | None:
    """Whether the file's data and attributes still match its checksum (None: it has none)."""
    with ncio.dataset(path, "r") as nc:
        with ncio.locked():
            stored = nc.getncattr(ATTR) if ATTR in nc.ncattrs() else None
        if stored is None:
            return None
        try:
            record = json.loads(stored)
            blocks, expected = dict(record["blocks"]), record["sha256"]
        except (ValueError, TypeError, KeyError):
            return False
        if record.get("algorithm") != ALGORITHM:
            return None
        return _digest(nc, blocks, {}) == expected


def damage(path: Path, check: bool | None = None) -> str | None:
    """Why a stored result whose key matches cannot be trusted (its checksum), or None. ``check``
    None: files up to :data:`VERIFY_LIMIT_BYTES` are verified; True: every file; False: none."""
    if check is False or check is None and Path(path).stat().st_size > VERIFY_LIMIT_BYTES:
        return None
    try:
        ok = verify(path)
    except (OSError, RuntimeError, ValueError):
        ok = False
    if ok is None:
        return "stored without a checksum (by an older roughcontact)"
    return None if ok else "stored data or attributes differ from their checksum (edited or damaged since written)"
