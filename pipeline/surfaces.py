"""Measured surfaces: :class:`Topography` (a height map or line scan in metres, as the readers
hand it to the stages) and :func:`read_topography`, which reads one in any of the instrument
formats of the SurfaceTopography package (x3p, sdf, sur, opd, plu, datx, Gwyddion, Bruker/DI,
text matrices, npy, NetCDF, ...). The measurements of a contact.engineering container
(:mod:`roughcontact.containers`) are Topography objects too.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneWarning, UserError
from .header_units import length_units


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
        Where ``unit`` comes from: ``"file"``, ``"header"`` (a text file's column header) or ``"scene"``.
    filled
        The points that were undefined in the file and filled by :func:`fill_undefined` (a
        boolean array of the shape of ``heights``), or None when none was filled.
    fill_method
        How they were filled, in words (None when none was).
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
    filled: np.ndarray | None = None
    fill_method: str | None = None

    @property
    def dim(self) -> int:
        return self.heights.ndim


#: the ways of filling undefined heights (``fill_undefined`` of a measured surface): "none" keeps them
#: (the stages refuse them), "harmonic" is SurfaceTopography's ``interpolate_undefined_data("harmonic")``
FILL_METHODS = ("none", "harmonic")
#: above this fraction of filled heights the reader warns (the PSD at short wavelengths comes out lower by about
#: the fraction, beyond its statistical error: docs/topography.md, "Missing data")
FILL_WARN_FRACTION = 0.01
FILL_DESCRIPTION = {
    "harmonic": "SurfaceTopography interpolate_undefined_data('harmonic'): the undefined heights solve the discrete "
                "Laplace equation (each the mean of its 2 or 4 nearest neighbours), the defined heights around them as "
                "boundary values; one sparse direct solve",
}


def fill_undefined(heights: np.ndarray, sizes, periodic: bool, method: str | None):
    """Heights with their undefined (NaN) points filled by SurfaceTopography, and the mask of
    the points filled (None if none was, or ``method`` is None / "none").

    ``method`` "harmonic": :meth:`SurfaceTopography.UniformTopographyInterface.interpolate_undefined_data`,
    which solves the discrete Laplace equation for the undefined points with the defined ones as
    boundary values (so each filled height is the mean of its nearest neighbours: smooth, with no
    roughness of its own). A hole with no defined neighbour cannot be filled (ValueError).
    """
    bad = np.isnan(heights)
    if method in (None, "none") or not bad.any():
        return heights, None
    if method not in FILL_METHODS:
        raise ValueError(f"unknown fill method {method!r}; one of {', '.join(FILL_METHODS)}")
    if bad.all():
        raise ValueError("every height is undefined: nothing to interpolate from")
    from SurfaceTopography import Topography as STTopography, UniformLineScan

    masked = np.ma.masked_array(np.where(bad, 0.0, heights), mask=bad)
    sizes = tuple(sizes) if sizes is not None else tuple(float(n) for n in heights.shape)
    cls = UniformLineScan if heights.ndim == 1 else STTopography
    topo = cls(masked, sizes[0] if heights.ndim == 1 else sizes, periodic=periodic)
    filled = np.ma.filled(np.ma.asarray(topo.interpolate_undefined_data(method).heights(), dtype=float), np.nan)
    if np.isnan(filled).any() or not np.all(np.isfinite(filled)):
        raise ValueError("the interpolation left undefined points (a region of undefined points with no defined "
                         "neighbour)")
    return filled, bad


def _filled(heights, sizes, periodic, fill, path, key):
    """:func:`fill_undefined` for the reader: errors name the file and ``key.fill_undefined``;
    a warning when more than :data:`FILL_WARN_FRACTION` of the heights were filled."""
    try:
        heights, filled = fill_undefined(heights, sizes, periodic, fill)
    except ValueError as exc:
        raise UserError(f"cannot fill the undefined heights ({exc})", file=str(path),
                        key=f"{key}.fill_undefined") from None
    if filled is not None and filled.mean() > FILL_WARN_FRACTION:
        warnings.warn(SceneWarning(
            f"{path}:{key}.fill_undefined: {filled.mean():.1%} of the heights were undefined and are filled; the fill "
            "has no roughness of its own, so at wavelengths shorter than the holes the PSD comes out lower by about "
            "that fraction, more than its statistical error (docs/topography.md); crop the map to a better measured "
            "part if that matters"), stacklevel=3)
    return heights, filled


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


def read_topography(path: Path, *, key: str = "surface", height_unit: str | None = None,
                    fill: str | None = None) -> Topography:
    """Read a height map or line scan with SurfaceTopography (default channel).

    Heights and sizes are converted to metres with the file's unit, or, for a file that does
    not say its unit (npy, bare text), with ``height_unit`` from the scene section ``key``
    (errors name ``key.height_unit``). Undefined heights (masked by the reader, or NaN) are
    NaN, or, with ``fill`` = "harmonic" (the scene's ``key.fill_undefined``), filled by
    :func:`fill_undefined` (``filled`` records where). Errors (unknown format, corrupt or
    truncated file, non-uniform data, no unit) are :class:`UserError` naming the file.
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
            raise UserError(f"a non-uniformly sampled line scan ({len(topo.positions())} points at uneven spacing): "
                            "the spectra here are computed on uniform grids; resample it on a uniform grid",
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
        raise UserError(f"corrupt or truncated file ({exc.__class__.__name__}: {str(exc)[:160]})",
                        file=str(path)) from None
    except Exception as exc:  # readers of binary formats raise all sorts of errors on damaged files
        raise UserError(f"cannot read the topography ({exc.__class__.__name__}: {str(exc)[:160]})",
                        file=str(path)) from None
    if np.ma.isMaskedArray(heights):
        heights = heights.astype(float).filled(np.nan)
    else:
        heights = np.array(heights, dtype=float)  # own copy (readers may hand out memory maps)
    if heights.size == 0:
        raise UserError("the file holds no height data", file=str(path))
    sizes_out = tuple(float(s) for s in np.atleast_1d(sizes)) if sizes is not None else None
    # the file's unit, else a text header's ("# x [um]  h [nm]"), else the scene's
    unit, source, factor, size_factor = length_units(path, unit, height_unit, key)
    heights *= factor
    sizes_out = tuple(s * size_factor for s in sizes_out) if sizes_out is not None else None
    heights, filled = _filled(heights, sizes_out, periodic, fill, path, key)
    return Topography(
        path=path, heights=heights, physical_sizes=sizes_out, periodic=periodic, unit=unit,
        format=type(reader).__name__.removesuffix("Reader"), channel=str(getattr(channel, "name", channel.index)),
        metadata=info, unit_source=source, filled=filled,
        fill_method=f"{fill}: {FILL_DESCRIPTION[fill]}" if filled is not None else None,
    )
