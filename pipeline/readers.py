"""Reading user input files (the engine's job; stages never open files): :data:`READERS`, the
readers a stage names in its ``FileInput``.

* :func:`~roughcontact.tables.read_table` (``table``) reads whitespace- or comma-separated
  numeric columns, with ``#`` comments and an optional header naming the columns and their
  units, e.g. ``# q [1/m]   C [m^4]`` or ``q (1/m), C (m^4)``. Every data row keeps its line
  number so that a reader can name the offending line.
* :func:`read_netcdf` loads a NetCDF file into memory (with its attributes).
* :func:`read_spectrum` reads a measured PSD (a text table or a NetCDF file) and returns
  q and C in SI units, checked row by row (units from the scene or the header, finite
  values, C >= 0, q > 0 and strictly increasing), errors naming the file and line.
* :func:`~roughcontact.moduli.read_master_curve` (``master_curve``) and
  :func:`~roughcontact.dma.read_dma` (``dma``) read a measured viscoelastic master curve or
  DMA sweeps ([T,] frequency, E', E'' or tan delta columns) through the one moduli reader
  :func:`~roughcontact.moduli.read_moduli`, and return omega [rad/s], E' and E'' [Pa], checked
  the same way.
* :func:`~roughcontact.surfaces.read_topography` reads a measured surface (height map or line
  scan) in any of the instrument formats of the SurfaceTopography package (x3p, sdf, sur, opd,
  plu, datx, Gwyddion, Bruker/DI, text matrices, npy, NetCDF, ...);
  :func:`~roughcontact.containers.read_container` the measurements of a contact.engineering
  container.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from .containers import read_container
from .datafiles import column_to_si, netcdf_psd
from .dma import read_dma
from .errors import UserError
from .moduli import read_master_curve
from .ncio import locked
from .surfaces import Topography, read_topography
from .tables import Table, first_bad, read_table

__all__ = ["READERS", "Spectrum", "Table", "Topography", "first_bad", "read_auto", "read_netcdf", "read_spectrum",
           "read_table", "read_topography"]


def read_netcdf(path: Path) -> xr.Dataset:
    """Load a NetCDF file fully into memory."""
    path = Path(path)
    try:
        with locked(), xr.open_dataset(path) as ds:
            return ds.load()
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot read as NetCDF ({exc.__class__.__name__}: {str(exc)[:120]})", file=str(path)) from None


def read_auto(path: Path):
    """NetCDF for ``.nc``/``.nc4``/``.netcdf`` files, a text table otherwise."""
    return read_netcdf(path) if Path(path).suffix.lower() in (".nc", ".nc4", ".netcdf", ".cdf") else read_table(path)


@dataclass
class Spectrum:
    """A measured PSD read from a file, in SI units.

    Attributes
    ----------
    path
        The file.
    q
        Wavenumbers (1/m), positive and strictly increasing.
    values
        The PSD in the SI unit of its convention (``convention_units[convention]``), >= 0.
    convention
        The file's PSD convention (a NetCDF variable's ``psd_convention`` attribute wins over
        the scene's).
    attrs
        What to record about the source (e.g. a NetCDF file's own provenance).
    """

    path: Path
    q: np.ndarray
    values: np.ndarray
    convention: str
    attrs: dict = field(default_factory=dict)


def read_spectrum(path: Path, *, key: str, convention: str, convention_units: dict, columns=(0, 1),
                  q_unit: str | None = None, value_unit: str | None = None, variable: str | None = None,
                  select: dict | None = None) -> Spectrum:
    """A measured PSD: a text table (columns [q, C]) or a NetCDF file (:func:`roughcontact.datafiles.netcdf_psd`,
    ``select``: one slice of a larger variable). Units from the scene (``q_unit``, ``value_unit``) or the file
    (header ``# q [1/m]  C [m^4]``, NetCDF ``units``), blamed on either; ``key``: the file's scene section."""
    path = Path(path)
    loaded = read_auto(path)
    attrs: dict = {}
    origin = {"q": None if q_unit else "file", "C": None if value_unit else "file"}
    if isinstance(loaded, xr.Dataset):
        q_raw, c_raw, file_q_unit, file_c_unit, psd_var = netcdf_psd(loaded, path, key, variable, select)
        q_unit, value_unit = q_unit or file_q_unit, value_unit or file_c_unit
        origin = {k: v and ("q.units" if k == "q" else f"{psd_var.name}.units") for k, v in origin.items()}
        convention = psd_var.attrs.get("psd_convention", convention)
        where = lambda i: f"index {i}"  # noqa: E731
        attrs["source_provenance"] = json.dumps({k: str(v) for k, v in loaded.attrs.items()})
    else:
        iq, ic = (tuple(columns) + (None, None))[:2]
        if iq is None or ic is None:
            raise UserError("needs two column indices [q, C]", key=f"{key}.columns")
        q_raw, c_raw = loaded.column(iq), loaded.column(ic)
        q_unit = q_unit or (loaded.units[iq] if loaded.units else None)
        value_unit = value_unit or (loaded.units[ic] if loaded.units else None)
        origin = {k: v and f"line {loaded.header_line}" for k, v in origin.items()}
        where = lambda i: f"line {loaded.lines[i]}"  # noqa: E731
    if (not q_unit or not value_unit) and getattr(loaded, "header_note", None):
        raise UserError(
            f"{loaded.header_note}, so it gives no units: name every column in it (e.g. '# q [1/m]  C [m^4]  "
            f"error [m^4]') or set {key}.q_unit and {key}.C_unit", file=str(path))
    if not q_unit or not value_unit:
        raise UserError(
            f"units of the {'q' if not q_unit else 'C'} column unknown: put them in the file's header "
            f"('# q [1/m]  C [m^4]') or set {key}.{'q_unit' if not q_unit else 'C_unit'}", file=str(path))
    q = column_to_si(q_raw, q_unit, "1/m", path=path, scene_key=f"{key}.q_unit", origin=origin["q"], what="q")
    values = column_to_si(c_raw, value_unit, convention_units[convention], path=path, scene_key=f"{key}.C_unit",
                          origin=origin["C"], what="the PSD")
    first_bad(~np.isfinite(q) | ~np.isfinite(values), lambda i: "NaN or infinite value", path, where)
    first_bad(values < 0, lambda i: f"negative PSD value {c_raw[i]:g}", path, where)
    first_bad(q <= 0, lambda i: f"wavenumber must be positive, got {q_raw[i]:g}", path, where)
    first_bad(np.diff(q) <= 0, lambda i: "q is not strictly increasing", path, lambda i: where(i + 1))
    if q.size < 2:
        raise UserError("needs at least two data rows", file=str(path))
    return Spectrum(path=path, q=q, values=values, convention=convention, attrs=attrs)


#: the readers a stage names in its FileInput
READERS = {"table": read_table, "netcdf": read_netcdf, "auto": read_auto, "topography": read_topography,
           "spectrum": read_spectrum, "master_curve": read_master_curve, "dma": read_dma, "container": read_container}
