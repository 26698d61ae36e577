"""What a data file says about itself: the units in its header or attributes, and which of a
NetCDF file's variables is the PSD.

* :func:`column_to_si` converts a column to SI and blames a bad unit on where it came from:
  the scene key the user set, or the file and its header line (``line 1``) or attribute
  (``q.units``), never a scene key the user did not set.
* :func:`netcdf_psd` picks the PSD in a NetCDF file: a 1-D variable over a ``q`` coordinate,
  or one slice of a variable with more dimensions (our own ``psd_combined`` over eta and q,
  say), chosen with ``select = { eta = 0.0 }`` in the scene.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .errors import UserError
from .units import array_to_si


def column_to_si(raw, unit: str, target: str, *, path, scene_key: str, origin: str | None, what: str,
                 convert=None) -> np.ndarray:
    """``raw`` given in ``unit`` as an array in the SI ``target`` units.

    ``origin`` None: the unit is the scene's ``scene_key``, errors name that key; else it is
    where the file gives the unit (``"line 1"``, ``"q.units"``), errors name the file and it.
    ``what`` names the column in the message ("column q"). ``convert(raw, unit, target, key=)``
    converts (default :func:`roughcontact.units.array_to_si`, multiplicative units only).
    """
    try:
        return (convert or array_to_si)(raw, unit, target, key=scene_key)
    except UserError as exc:
        if origin is None:
            raise
        raise UserError(f"the file gives {what} the unit {unit!r}: {exc.message}", file=str(path), key=origin) from None


def _values(coord) -> str:
    shown = ", ".join(f"{v:g}" if isinstance(v, (float, np.floating)) else str(v) for v in np.asarray(coord)[:8])
    return shown + (", ..." if np.size(coord) > 8 else "")


def _select(da: xr.DataArray, select: dict, path, key: str) -> xr.DataArray:
    """One slice of ``da``: each dimension of ``select`` at the given coordinate value."""
    for dim, value in select.items():
        if dim not in da.dims:
            raise UserError(f"{da.name} has no dimension {dim!r} (it has {', '.join(map(str, da.dims))})",
                            file=str(path), key=f"{key}.select.{dim}")
        coord = np.asarray(da[dim].values)
        if coord.dtype.kind in "fiu" and isinstance(value, (int, float)):
            hit = np.flatnonzero(np.isclose(coord.astype(float), float(value), rtol=1e-9, atol=1e-12))
        else:
            hit = np.flatnonzero(coord.astype(str) == str(value))
        if hit.size == 0:
            raise UserError(f"no {dim} = {value!r} in {da.name} (values: {_values(coord)})", file=str(path),
                            key=f"{key}.select.{dim}")
        da = da.isel({dim: int(hit[0])})
    return da


def netcdf_psd(ds: xr.Dataset, path, key: str, variable: str | None, select: dict | None):
    """The PSD of a NetCDF file as (q, values, q unit, values unit, the variable).

    The file needs a 1-D ``q`` coordinate; the PSD variable is ``variable`` or the only data
    variable over q alone, reduced to q by ``select``. Errors name the file and the scene key.
    """
    if "q" not in ds.variables or ds["q"].ndim != 1 or ds["q"].dims != ("q",):
        raise UserError("the NetCDF file has no 'q' coordinate (a 1-D variable q over dimension q, the wavenumbers)",
                        file=str(path))
    if variable is None:
        candidates = [str(v) for v in ds.data_vars if "q" in ds[v].dims and ds[v].ndim == 1 + len(select or {})]
        if len(candidates) != 1:
            over_q = [str(v) for v in ds.data_vars if "q" in ds[v].dims]
            raise UserError(f"cannot tell which variable is the PSD ({', '.join(over_q) or 'none over q'}); "
                            f"set {key}.variable", file=str(path))
        variable = candidates[0]
    if variable not in ds.data_vars:
        raise UserError(f"no variable {variable!r} in the file", file=str(path), key=f"{key}.variable")
    da = _select(ds[variable], dict(select or {}), path, key)
    extra = [d for d in da.dims if d != "q"]
    if extra or "q" not in da.dims:
        dim = extra[0] if extra else None
        choose = (f": choose one {dim} with {key}.select = {{ {dim} = ... }} (values in the file: "
                  f"{_values(da[dim].values) if dim in da.coords else f'{da.sizes[dim]} unlabelled'})") if dim else ""
        raise UserError(f"{variable} has dimensions ({', '.join(map(str, da.dims))}), a PSD has q alone{choose}",
                        file=str(path), key=f"{key}.select" if dim else f"{key}.variable")
    return ds["q"].values, da.values, ds["q"].attrs.get("units"), da.attrs.get("units"), da
