"""Reading user input files (the engine's job; stages never open files).

* :func:`read_table` reads whitespace- or comma-separated numeric columns, with ``#``
  comments and an optional header naming the columns and their units, e.g.
  ``# q [1/m]   C [m^4]`` or ``q (1/m), C (m^4)``. Every data row keeps its line number
  so that a stage can name the offending line.
* :func:`read_netcdf` loads a NetCDF file into memory (with its attributes).
* :func:`read_spectrum` reads a measured PSD (a text table or a NetCDF file) and returns
  q and C in SI units, checked row by row (units from the scene or the header, finite
  values, C >= 0, q > 0 and strictly increasing), errors naming the file and line.
* :func:`read_master_curve` reads a measured viscoelastic master curve (frequency, E', E''
  or tan delta columns) and returns omega [rad/s], E' and E'' [Pa], checked the same way.
* :func:`read_topography` reads a measured surface (height map or line scan) in any of the
  instrument formats of the SurfaceTopography package (x3p, sdf, sur, opd, plu, datx,
  Gwyddion, Bruker/DI, text matrices, npy, NetCDF, ...).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from .containers import read_container
from .errors import UserError
from .ncio import locked

_UNIT_IN_HEADER = re.compile(r"^\s*([^\[\(]*?)\s*[\[\(]\s*([^\]\)]*)\s*[\]\)]\s*$")


@dataclass
class Table:
    """Numeric columns read from a text file.

    Attributes
    ----------
    path
        The file.
    data
        (rows, columns) float array.
    lines
        1-based line number in the file of each data row.
    names, units
        Column names and units from the header (None where the header gives none).
    header_line
        1-based line number of the header (None without one).
    """

    path: Path
    data: np.ndarray
    lines: np.ndarray
    names: list[str | None] = field(default_factory=list)
    units: list[str | None] = field(default_factory=list)
    header_line: int | None = None

    def column(self, index: int) -> np.ndarray:
        if not 0 <= index < self.data.shape[1]:
            raise UserError(
                f"column {index} requested but the file has {self.data.shape[1]} column(s)", file=str(self.path)
            )
        return self.data[:, index]


def _split(line: str) -> list[str]:
    return [t for t in re.split(r"[,;\s]+", line.strip()) if t]


def _parse_header(text: str) -> tuple[list[str | None], list[str | None]]:
    cells = [c for c in re.split(r",|;|\t|\s{2,}", text.strip()) if c.strip()]
    if len(cells) <= 1:
        # single spaces between "q [1/m] C [m^4]": split before each name followed by a bracket
        cells = re.findall(r"[^\s\[\(]+\s*[\[\(][^\]\)]*[\]\)]|[^\s\[\(]+", text.strip())
    names, units = [], []
    for c in cells:
        m = _UNIT_IN_HEADER.match(c)
        if m:
            names.append(m.group(1) or None)
            units.append(m.group(2).strip() or None)
        else:
            names.append(c.strip() or None)
            units.append(None)
    return names, units


def read_table(path: Path) -> Table:
    """Read a numeric text table. Errors name the file and the line."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise UserError(f"cannot read: {exc.strerror}", file=str(path)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise UserError("not a text file (is it binary or in another encoding?)", file=str(path)) from None
    rows, lines = [], []
    header: str | None = None
    header_line = None
    ncol = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith(("#", "%", "//")):
            body = stripped.lstrip("#%/ ").strip()
            if not rows and body and ("[" in body or "(" in body):
                header, header_line = body, number
            continue
        cells = _split(stripped)
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not rows and header is None:
                header, header_line = stripped, number
                continue
            raise UserError(f"not a number in {stripped[:60]!r}", file=str(path), key=f"line {number}") from None
        if ncol is None:
            ncol = len(values)
        elif len(values) != ncol:
            raise UserError(
                f"{len(values)} column(s) where earlier rows have {ncol}", file=str(path), key=f"line {number}"
            )
        rows.append(values)
        lines.append(number)
    if not rows:
        raise UserError("no data rows", file=str(path))
    names, units = _parse_header(header) if header else ([], [])
    if names and len(names) != ncol:
        names, units, header_line = [], [], None  # a header we cannot align with the columns names nothing
    return Table(path=path, data=np.array(rows, dtype=float), lines=np.array(lines), names=names, units=units,
                 header_line=header_line)


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
class Topography:
    """A measured surface as read from an instrument file.

    Attributes
    ----------
    path
        The file.
    heights
        Heights (m), ``(nx,)`` for a line scan or ``(nx, ny)`` for a map, x first (the layout
        of SurfaceTopography). Missing points (masked in the file) are NaN.
    physical_sizes
        Lengths of the scan along x (and y) (m); None when the file does not give them.
    periodic
        Whether the file says the data are periodic (simulations; measurements never are).
    unit
        The length unit the heights were given in (e.g. ``"um"``): the file's, or the scene's
        ``height_unit`` for a file that does not say.
    format, channel
        The reader (format) that recognised the file and the channel read (the default one).
    metadata
        The file's metadata (instrument, date, ...), as JSON-able values.
    unit_source
        Where ``unit`` comes from: ``"file"`` or ``"scene"``.
    """

    path: Path
    heights: np.ndarray
    physical_sizes: tuple[float, ...] | None
    periodic: bool
    unit: str | None
    format: str
    channel: str
    metadata: dict = field(default_factory=dict)
    unit_source: str = "file"

    @property
    def dim(self) -> int:
        return self.heights.ndim


def _npy_complete(path: Path) -> None:
    """SurfaceTopography pads a truncated .npy file with zeros; refuse it here instead."""
    try:
        np.load(path, mmap_mode="r", allow_pickle=False)  # maps the data: fails if the file is shorter
    except (ValueError, OSError, EOFError) as exc:
        raise UserError(f"truncated or corrupt .npy file ({str(exc)[:120]})", file=str(path)) from None


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, np.generic):
        return value.item()
    return str(value)


def _explain_by_suffix(path: Path) -> None:
    """When format detection failed for a file whose suffix names a format, open it with that
    format's reader and raise its error as "corrupt or truncated" (detection alone only says
    that no reader recognised the file)."""
    from SurfaceTopography import open_topography
    from SurfaceTopography.IO import readers

    suffix = path.suffix.lower().lstrip(".")
    formats = [r.format() for r in readers if suffix in r.file_extensions()]
    for fmt in formats[:1]:
        try:
            open_topography(str(path), format=fmt).topography()
        except Exception as exc:  # noqa: BLE001 - any reader error means the file is damaged
            raise UserError(f"corrupt or truncated {fmt} file ({exc.__class__.__name__}: {str(exc)[:160]})",
                            file=str(path)) from None


def read_topography(path: Path, *, key: str = "surface", height_unit: str | None = None) -> Topography:
    """Read a height map or line scan with SurfaceTopography (default channel).

    Heights and sizes are converted to metres with the file's unit, or, for a file that does
    not say its unit (npy, bare text), with ``height_unit`` from the scene section ``key``
    (errors name ``key.height_unit``). Errors (unknown format, corrupt or truncated file,
    non-uniform data, no unit) are :class:`UserError` naming the file.
    """
    path = Path(path)
    try:
        from SurfaceTopography import open_topography
        from SurfaceTopography.Exceptions import CannotDetectFileFormat, ReadFileError, UnknownFileFormat
    except ImportError as exc:
        raise UserError(
            f"reading topography files needs the SurfaceTopography package ({exc}); "
            "install it with: pip install 'roughcontact[topography]'", file=str(path)) from None
    if not path.is_file():
        raise UserError("file does not exist", file=str(path))
    if path.stat().st_size == 0:
        raise UserError("empty file", file=str(path))
    if path.suffix.lower() == ".npy":
        _npy_complete(path)
    try:
        reader = open_topography(str(path))
        channel = reader.default_channel
        sizes = channel.physical_sizes
        unit = channel.unit
        kwargs = {}
        if sizes is None or any(s is None for s in np.atleast_1d(sizes)):
            kwargs["physical_sizes"] = tuple(float(n) for n in channel.nb_grid_pts)  # pixels; the scene gives sizes
            sizes = None
        if unit is None:
            kwargs["unit"] = "m"  # placeholder; heights are kept as raw numbers (unit None below)
        topo = reader.topography(channel_index=channel.index, **kwargs)
        if not getattr(topo, "is_uniform", True):
            raise UserError("non-uniformly sampled line scans are not supported; resample them on a uniform grid",
                            file=str(path))
        heights = topo.heights()
        info = _jsonable(dict(getattr(topo, "info", {}) or {}))
        periodic = bool(topo.is_periodic)
    except UserError:
        raise
    except (CannotDetectFileFormat, UnknownFileFormat) as exc:
        _explain_by_suffix(path)  # a damaged file of a known format: say what its reader found
        tried = ", ".join(re.findall(r"tried (\w+)Reader", str(exc))) or "all readers"
        raise UserError(f"unknown or unsupported topography format (SurfaceTopography tried {tried})",
                        file=str(path)) from None
    except ReadFileError as exc:
        raise UserError(f"corrupt or truncated file ({exc.__class__.__name__}: {str(exc)[:160]})", file=str(path)) from None
    except Exception as exc:  # readers of binary formats raise all sorts of errors on damaged files
        raise UserError(f"cannot read the topography ({exc.__class__.__name__}: {str(exc)[:160]})", file=str(path)) from None
    if np.ma.isMaskedArray(heights):
        heights = heights.astype(float).filled(np.nan)
    else:
        heights = np.array(heights, dtype=float)  # own copy (readers may hand out memory maps)
    if heights.size == 0:
        raise UserError("the file holds no height data", file=str(path))
    sizes_out = tuple(float(s) for s in np.atleast_1d(sizes)) if sizes is not None else None
    source, unit_key = "file", f"unit {unit!r} in the file"
    if unit is None:
        if height_unit is None:
            raise UserError(f"the file does not say the unit of its heights; set {key}.height_unit (e.g. \"nm\")",
                            file=str(path), key=f"{key}.height_unit")
        unit, source, unit_key = height_unit, "scene", f"{key}.height_unit"
    from .units import array_to_si

    factor = float(array_to_si(np.array(1.0), unit, "m", key=unit_key))
    heights *= factor
    sizes_out = tuple(s * factor for s in sizes_out) if sizes_out is not None else None
    return Topography(
        path=path, heights=heights, physical_sizes=sizes_out, periodic=periodic, unit=unit,
        format=type(reader).__name__.removesuffix("Reader"), channel=str(getattr(channel, "name", channel.index)),
        metadata=info, unit_source=source,
    )


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


def first_bad(bad: np.ndarray, message, path: Path, where) -> None:
    """Raise a UserError naming the file and the row (``where(i)``) of the first True in ``bad``;
    ``message(i)`` says what is wrong there."""
    index = np.flatnonzero(bad)
    if index.size:
        raise UserError(message(index[0]), file=str(path), key=where(index[0]))


def read_spectrum(path: Path, *, key: str, convention: str, convention_units: dict, columns=(0, 1),
                  q_unit: str | None = None, value_unit: str | None = None, variable: str | None = None,
                  select: dict | None = None) -> Spectrum:
    """A measured PSD: a text table (columns [q, C]) or a NetCDF file (:func:`roughcontact.datafiles.netcdf_psd`,
    ``select``: one slice of a larger variable). Units from the scene (``q_unit``, ``value_unit``) or the file
    (header ``# q [1/m]  C [m^4]``, NetCDF ``units``), blamed on either; ``key``: the file's scene section."""
    from .datafiles import column_to_si, netcdf_psd

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


_MASTER_HEADER = "# f [Hz]  E' [MPa]  E'' [MPa]"


def read_master_curve(path: Path, *, key: str = "modulus", columns=(0, 1, 2), frequency_unit: str | None = None,
                      modulus_unit: str | None = None, loss_column: str = "loss_modulus",
                      frequency: str = "auto") -> MasterCurve:
    """Read a master curve: a text table with columns ``columns`` = [frequency, E', E'' or tan
    delta] (``loss_column`` says which). Units come from the scene (``frequency_unit``,
    ``modulus_unit``) or else from the header (``# f [Hz]  E' [MPa]  E'' [MPa]``); the frequency
    is angular or cyclic (omega = 2 pi f) as ``frequency`` says ("auto": angular if its unit
    says rad). ``key`` is the scene section (errors name ``key.frequency_unit``, ...)."""
    from .datafiles import column_to_si

    cols = tuple(columns)
    if len(cols) != 3:
        raise UserError(f"needs three column indices [frequency, E', E''], got {list(cols)}", key=f"{key}.columns")
    table = read_table(path)
    f_raw, s_raw, l_raw = (table.column(i) for i in cols)
    units = table.units if table.units else [None] * table.data.shape[1]
    f_unit, e_unit = frequency_unit or units[cols[0]], modulus_unit or units[cols[1]]
    tan = loss_column == "tan_delta"
    l_unit = None if tan else (units[cols[2]] if modulus_unit is None and units[cols[2]] is not None else e_unit)
    for missing, what, name in ((not f_unit, "the frequency column", "frequency_unit"),
                                (not e_unit or not l_unit and not tan, "the modulus columns", "modulus_unit")):
        if missing:
            raise UserError(f"unit of {what} unknown: put it in the header ({_MASTER_HEADER!r}) "
                            f"or set {key}.{name}", file=str(table.path), key=f"{key}.{name}")
    where = lambda i: f"line {table.lines[i]}"  # noqa: E731
    for raw, name in ((f_raw, "frequency"), (s_raw, "E'"), (l_raw, "tan delta" if tan else "E''")):
        first_bad(~np.isfinite(raw), lambda i: f"{name} is NaN or infinite", table.path, where)
    angular = frequency == "angular" or frequency == "auto" and re.search(r"rad", f_unit) is not None
    def si(raw, unit, target, name, what):  # a unit from the header is blamed on the header line
        return column_to_si(raw, unit, target, path=table.path, scene_key=f"{key}.{name}", what=what,
                            origin=None if {"frequency_unit": frequency_unit, "modulus_unit": modulus_unit}[name]
                            else f"line {table.header_line}")
    omega = si(f_raw, f_unit, "1/s", "frequency_unit", "the frequency") * (1.0 if angular else 2.0 * np.pi)
    storage = si(s_raw, e_unit, "Pa", "modulus_unit", "E'")
    first_bad(omega <= 0, lambda i: f"frequency must be positive, got {f_raw[i]:g}", table.path, where)
    first_bad(np.diff(omega) <= 0, lambda i: f"frequency is not strictly increasing ({f_raw[i]:g} then "
              f"{f_raw[i + 1]:g})", table.path, lambda i: where(i + 1))
    first_bad(storage <= 0, lambda i: f"storage modulus E' must be positive, got {s_raw[i]:g}", table.path, where)
    loss = storage * l_raw if tan else si(l_raw, l_unit, "Pa", "modulus_unit", "E''")
    loss_name = "tan delta" if tan else "loss modulus E''"
    first_bad(l_raw < 0 if tan else loss < 0, lambda i: f"{loss_name} must be >= 0, got {l_raw[i]:g}", table.path, where)
    if omega.size < 2:
        raise UserError("a master curve needs at least two data rows", file=str(table.path))
    kind = "angular" if angular else "cyclic: omega = 2 pi f"
    return MasterCurve(path=table.path, omega=omega, storage=storage, loss=loss,
                       attrs={"source_file": str(path), "frequency_column": f"{f_unit} ({kind})"})


READERS = {"table": read_table, "netcdf": read_netcdf, "auto": read_auto, "topography": read_topography, "spectrum": read_spectrum,
           "master_curve": read_master_curve, "dma": lambda path, **kw: __import__(f"{__package__}.dma", fromlist=["read_dma"]).read_dma(path, **kw), "container": read_container}
