"""How result variables are encoded in NetCDF: CF-clean coordinates and compressed data.

* Coordinate variables carry no ``_FillValue`` (CF 2.5.1: a coordinate has no missing values).
* Data variables of at least :data:`COMPRESS_BYTES` are compressed (zlib with the shuffle
  filter, :data:`LEVEL`) in chunks along the sweep dimensions: a dask-computed variable in the
  chunks it is computed and written in (each chunk is compressed once), an in-memory one in
  chunks of at most :data:`CHUNK_BYTES` split along its leading (sweep) dimensions, its trailing
  dimension (q, stress levels, ...) kept whole where it fits.

A dask-computed variable is compressed only if a trial block shrinks enough, its chunks encoded
beside the computation (:mod:`roughcontact.writing`); a scene can turn compression off with
``[run] compress = false`` (the values are the same either way).

Used by :func:`roughcontact.store.write` for both its paths (xarray's ``to_netcdf`` and the
netCDF4 variables the block writer fills).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

#: data variables from this size on are compressed
COMPRESS_BYTES = 16 * 2**10
#: zlib level: 1 gains nearly all of the size at the least cost in write time
LEVEL = 1
#: largest chunk of an in-memory variable
CHUNK_BYTES = 2**20


def _compressed(var: xr.Variable, chunks: tuple[int, ...]) -> dict:
    return {"zlib": True, "shuffle": True, "complevel": LEVEL, "chunksizes": tuple(int(c) for c in chunks)}


def eager_chunks(shape: tuple[int, ...], itemsize: int, limit: int = CHUNK_BYTES) -> tuple[int, ...]:
    """Chunk sizes for an in-memory variable: the whole array, halved along its leading dimensions
    (the outermost first) until a chunk is at most ``limit`` bytes."""
    chunks = list(shape)
    for axis in range(len(shape)):
        while math.prod(chunks) * itemsize > limit and chunks[axis] > 1:
            chunks[axis] = math.ceil(chunks[axis] / 2)
    return tuple(max(c, 1) for c in chunks)


def encoding(ds: xr.Dataset, compress: bool = True) -> dict[str, dict]:
    """``to_netcdf`` encodings of the in-memory variables of ``ds`` (``compress``: large ones compressed)."""
    out: dict[str, dict] = {}
    for name, var in ds.variables.items():
        if name in ds.coords:
            out[name] = {"_FillValue": None}
        elif compress and var.ndim and var.nbytes >= COMPRESS_BYTES and var.dtype.kind in "fiuc":
            out[name] = _compressed(var, eager_chunks(var.shape, var.dtype.itemsize))
    return out


def lazy_variable(ds: xr.Dataset, name: str, compress: bool = True) -> dict:
    """``netCDF4.Dataset.createVariable`` keywords of a dask-backed variable: no fill value on a
    coordinate, NaN on floating-point data, compression in the variable's dask chunks."""
    var = ds[name].variable
    if name in ds.coords:
        return {"fill_value": False}
    kw = {"fill_value": np.nan if np.issubdtype(var.dtype, np.floating) else None}
    if compress and var.ndim and var.nbytes >= COMPRESS_BYTES:
        kw.update(_compressed(var, tuple(max(c) for c in var.chunks)))
    return kw
