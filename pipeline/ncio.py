"""netCDF/HDF5 use serialised within a process.

The netCDF-C and HDF5 libraries are not thread-safe, and xarray does not serialise writes to
different files: two runs in two threads of one Python process (different output folders)
crashed the interpreter (segmentation fault, bus error, "NetCDF: HDF error") in most rounds.
Every use of the libraries by roughcontact holds one process-wide reentrant lock, :data:`LOCK`:
writing a result (xarray's ``to_netcdf``, the block writes, variable definitions, checksums),
opening and loading a result, reading an input NetCDF file, and the reads of a result opened
lazily (xarray takes the lock passed at opening for each of them). The lock is held only around
calls into the library, never while dask computes, so a block being computed can read an
upstream file lazily (taking the lock itself).
"""

from __future__ import annotations

import contextlib
import threading
from typing import Iterator

#: the process-wide lock around the netCDF-C/HDF5 libraries (reentrant: nested use in one thread is fine)
LOCK = threading.RLock()


def locked():
    """``with locked(): ...`` around any call into netCDF4 or xarray's netCDF I/O."""
    return LOCK


@contextlib.contextmanager
def dataset(path, mode: str = "r") -> Iterator[object]:
    """A netCDF4.Dataset opened and closed under :data:`LOCK`; every call on it in between must
    also be made within ``with locked():``."""
    import netCDF4

    with LOCK:
        nc = netCDF4.Dataset(path, mode)
    try:
        yield nc
    finally:
        with LOCK:
            nc.close()


def open_lazily(path):
    """An xarray Dataset opened lazily (dask, the file's own chunks) whose later reads take :data:`LOCK`."""
    import xarray as xr

    with LOCK:
        return xr.open_dataset(path, chunks={}, lock=LOCK)
