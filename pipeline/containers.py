"""Reading contact.engineering containers (the engine's reader ``"container"``).

A container is a ZIP file holding one or more surfaces, each with several measurements (raw
instrument files of several scales) and their metadata (``index.json`` or ``meta.yml``: sizes,
units, height scale, detrending, instrument and its reliability parameters). It is what
https://contact.engineering exports and publishes. The container is read through
SurfaceTopography's own container reader (:func:`SurfaceTopography.Container.open_container`),
which applies each measurement's metadata pipeline (height scale, filling undefined data,
detrending); this module hands the stages the measurements' heights and sizes in metres, their
reliability cutoffs (SurfaceTopography's ``short_reliability_cutoff``: tip radius or lateral
resolution) in metres, and what to record about each. Every problem is a one-line
:class:`~roughcontact.errors.UserError` naming the container and the measurement.
"""

from __future__ import annotations

import re
import warnings
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneWarning, UserError
from .surfaces import FILL_DESCRIPTION, Topography
from .units import array_to_si


@dataclass
class Container:
    """The measurements of one surface of a container, in SI.

    Attributes
    ----------
    path
        The container file.
    surface
        The surface's name in the container.
    measurements
        One :class:`roughcontact.surfaces.Topography` per measurement (heights and sizes in m,
        the container's metadata pipeline applied); its ``metadata`` holds ``measurement``
        (name), ``datafile``, ``detrend_mode``, ``reliability_cutoff_m`` (None if the metadata
        gives no instrument parameters) and ``reliability_cutoff_source``.
    left_out
        The measurements not read, each a dict with ``measurement``, ``datafile`` and ``reason``
        (non-uniformly sampled line scans: the spectra here need uniform grids).
    """

    path: Path
    surface: str
    measurements: list = field(default_factory=list)
    left_out: list = field(default_factory=list)


def _fail(path: Path, key: str, message: str) -> UserError:
    return UserError(message, file=str(path), key=f"{key}.container")


def _open(path: Path, key: str, surface: str | None):
    """The container reader and the index of the surface to read."""
    try:
        from SurfaceTopography.Container import open_container
    except ImportError as exc:
        raise _fail(path, key, f"reading containers needs the SurfaceTopography package ({exc}); install it with: "
                               "pip install 'roughcontact[topography]'") from None
    if not path.is_file():
        raise _fail(path, key, "file does not exist")
    if not zipfile.is_zipfile(path):
        raise _fail(path, key, "not a contact.engineering container (not a ZIP file)")
    try:
        reader = open_container(str(path))
    except Exception as exc:  # the readers raise assorted errors on foreign ZIP files
        text = " ".join(str(exc).split())
        why = ("it holds neither index.json nor meta.yml" if "neither" in text or "meta.yml" in text
               else f"{exc.__class__.__name__}: {text[:160]}")
        raise _fail(path, key, f"not a readable contact.engineering container ({why})") from None
    names = [str(reader.container(i).info.get("name", f"surface {i}")) for i in range(reader.nb_containers)]
    if not names:
        raise _fail(path, key, "the container holds no surface")
    if surface is None:
        if len(names) > 1:
            raise UserError(f"the container holds {len(names)} surfaces ({', '.join(map(repr, names))}); "
                            f"choose one with {key}.surface", file=str(path), key=f"{key}.surface")
        return reader, 0, names[0]
    if surface not in names:
        raise UserError(f"no surface {surface!r} in the container (it holds {', '.join(map(repr, names))})",
                        file=str(path), key=f"{key}.surface")
    return reader, names.index(surface), surface


def _cutoff(topo, factor: float):
    """SurfaceTopography's reliability cutoff (m) and what sets it, from the instrument metadata."""
    params = ((topo.info or {}).get("instrument") or {}).get("parameters") or {}
    length = topo.short_reliability_cutoff()
    if length is None:
        return None, "none in the metadata (Nyquist)" if not params else "not determined from the metadata (Nyquist)"
    kind = "tip radius" if "tip_radius" in params else "resolution"
    given = params.get("tip_radius") or params.get("resolution") or {}
    return float(length) * factor, (f"{kind} {given.get('value')} {given.get('unit')} "
                                    "(SurfaceTopography short_reliability_cutoff)")


class _NonUniform(Exception):
    """A measurement that is a non-uniformly sampled line scan (left out, not an error)."""


def _measurement(container, index: int, name: str, datafile: str, members: set, path: Path, key: str,
                 fill: str | None = None):
    """One measurement read and checked, as a :class:`roughcontact.surfaces.Topography` in metres.
    A non-uniformly sampled line scan raises :class:`_NonUniform` (the caller leaves it out);
    undefined heights are filled by SurfaceTopography's ``interpolate_undefined_data(fill)``
    when ``fill`` is "harmonic" (and the container's own metadata did not fill them)."""
    from SurfaceTopography.Exceptions import CannotDetectFileFormat, UnknownFileFormat

    where = f"measurement {name!r} (data file {datafile!r})"
    if datafile not in members:
        raise _fail(path, key, f"{where}: the data file is not in the archive")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)  # SurfaceTopography's notes (metadata and file disagree, ...)
        try:
            topo = container[index]
            heights = topo.heights()
        except (CannotDetectFileFormat, UnknownFileFormat) as exc:
            tried = ", ".join(re.findall(r"tried (\w+)Reader", str(exc))[:6]) or "all readers"
            raise _fail(path, key, f"{where}: unknown or unsupported file format (SurfaceTopography tried "
                                   f"{tried}, ...)") from None
        except Exception as exc:  # noqa: BLE001 - readers of damaged files raise all sorts of errors
            text = " ".join(str(exc).split())
            if "physical_sizes" in text:
                raise _fail(path, key, f"{where}: physical size unknown: neither the metadata ('size') nor the data "
                                       "file gives it") from None
            raise _fail(path, key, f"{where}: cannot read ({exc.__class__.__name__}: {text[:160]})") from None
    unit = topo.unit
    if not unit:
        raise _fail(path, key, f"{where}: no height unit: neither the metadata ('unit') nor the data file gives it; "
                               "add e.g. 'unit: um' to the measurement's metadata")
    if not getattr(topo, "is_uniform", True):
        raise _NonUniform(f"a non-uniformly sampled line scan ({len(topo.positions())} points at uneven spacing); "
                          "the spectra here are computed on uniform grids")
    filled, method = None, None
    if fill not in (None, "none") and np.ma.is_masked(heights):
        filled = np.ma.getmaskarray(heights)
        try:
            heights = topo.interpolate_undefined_data(fill).heights()
        except Exception as exc:  # noqa: BLE001 - a hole with no defined neighbour, ...
            raise UserError(f"{where}: cannot fill the undefined heights ({exc.__class__.__name__}: {str(exc)[:120]})",
                            file=str(path), key=f"{key}.fill_undefined") from None
        method = f"{fill}: {FILL_DESCRIPTION[fill]}"
    factor = float(array_to_si(np.array(1.0), str(unit), "m", key=f"{key}.container ({where}, unit)"))
    heights = np.ma.filled(np.ma.asarray(heights, dtype=float), np.nan) * factor
    try:
        cutoff, source = _cutoff(topo, factor)
    except Exception as exc:  # noqa: BLE001 - a malformed instrument entry
        raise _fail(path, key, f"{where}: cannot evaluate the reliability cutoff from the instrument metadata "
                               f"({exc.__class__.__name__}: {str(exc)[:120]})") from None
    info = topo.info or {}
    meta = {"measurement": name, "datafile": datafile, "unit": str(unit), "detrend_mode": info.get("detrend_mode"),
            "height_scale": info.get("height_scale"), "instrument": _plain(info.get("instrument")),
            "reliability_cutoff_m": cutoff, "reliability_cutoff_source": source,
            "notes": [str(w.message)[:200] for w in caught if issubclass(w.category, UserWarning)]}
    sizes = tuple(float(s) * factor for s in np.atleast_1d(topo.physical_sizes))
    return Topography(path=Path(f"{path}[{name}]"), heights=heights, physical_sizes=sizes,
                      periodic=bool(topo.is_periodic), unit=str(unit), format="contact.engineering container",
                      channel=str(info.get("data_source", 0)), metadata=meta, unit_source="container",
                      filled=filled, fill_method=method)


def _plain(value):
    """JSON-able copy of metadata (dates and other objects as strings)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value if isinstance(value, (str, int, float, bool)) or value is None else str(value)


def read_container(path: Path, *, key: str = "surface", surface: str | None = None,
                   fill: str | None = None) -> Container:
    """Read the measurements of one surface of a contact.engineering container.

    ``key`` is the scene section (errors name ``key.container``); ``surface`` picks a surface
    by name when the container holds several; ``fill`` ("harmonic", the scene's
    ``key.fill_undefined``) fills undefined heights. A container needs at least two
    measurements: it exists to merge several scales (one measurement is a plain
    ``kind = "topography"``). Non-uniformly sampled line scans are left out with a
    :class:`~roughcontact.errors.SceneWarning` naming them (``Container.left_out``); a
    container with nothing else is an error.
    """
    path = Path(path)
    reader, index, name = _open(path, key, surface)
    container = reader.container(index)
    members = reader.members(index)
    with zipfile.ZipFile(path) as z:
        in_archive = set(z.namelist())
    datafiles = [_datafile(m) for m in container.info.get("topographies", [])]
    labels = [m.name for m in members]
    if len(labels) < 2:
        only = f" (measurement {labels[0]!r}, data file {datafiles[0]!r})" if labels else ""
        raise _fail(path, key, f"surface {name!r} has {len(labels)} measurement(s){only}; a container is merged "
                               "from several measurements (scales): add measurements, or unzip the container and give "
                               "that file as kind = 'topography'")
    out = Container(path=path, surface=name)
    for i, (label, datafile) in enumerate(zip(labels, datafiles, strict=False)):
        try:
            out.measurements.append(_measurement(container, i, label, datafile, in_archive, path, key, fill))
        except _NonUniform as why:
            out.left_out.append({"measurement": label, "datafile": datafile, "reason": str(why)})
    if out.left_out:
        names = "; ".join(f"measurement {m['measurement']!r} (data file {m['datafile']!r}): {m['reason']}"
                          for m in out.left_out)
        if not out.measurements:
            raise _fail(path, key, f"no measurement can be used: {names}; resample them on uniform grids")
        warnings.warn(SceneWarning(f"{path}:{key}.container: left out {names}; the PSD is merged from the other "
                                   f"{len(out.measurements)} measurement(s) (recorded in the result)"), stacklevel=2)
    return out


def _datafile(meta) -> str:
    files = meta.get("datafile") or {}
    for k in ("original", "squeezed-netcdf"):
        if files.get(k):
            return str(files[k])
    return "?"
