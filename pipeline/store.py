"""The result store: one NetCDF file per stage, written atomically, with provenance.

Every file carries CF-style metadata (``Conventions``, ``history``, ``units`` and
``long_name`` on every variable and coordinate) and the provenance needed to decide
whether it can be reused: the stage's content key, its parameters, upstream keys and the
hashes of its input files.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import json
import os
import subprocess
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import xarray as xr

from . import __version__, cf

TMP_PREFIX = ".tmp-"


def canonical(value: Any):
    """A JSON-able, deterministic form of a parameter value (SI floats, lists, strings)."""
    if isinstance(value, Mapping):
        return {str(k): canonical(v) for k, v in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [canonical(v) for v in value]
    if isinstance(value, np.ndarray):
        return [canonical(v) for v in value.tolist()] if value.ndim else canonical(value.item())
    if isinstance(value, (np.floating, float)):
        return float(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, Path):
        return str(value)
    return value


def dumps(value: Any) -> str:
    return json.dumps(canonical(value), sort_keys=True, separators=(",", ":"))


def content_key(record: Mapping[str, Any]) -> str:
    """sha256 of the canonical JSON of a stage's identity (name, version, parameters,
    upstream keys, input file hashes, requested optional outputs)."""
    return hashlib.sha256(dumps(record).encode()).hexdigest()


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@functools.cache
def git_commit() -> str:
    """The commit of the running roughcontact: from git where the package runs from its checkout
    (an editable install; ``-dirty`` with uncommitted changes), else the one setuptools-scm
    recorded when the installed package was built."""
    here = Path(__file__).resolve().parent.parent
    try:
        top = subprocess.run(["git", "-C", str(here), "rev-parse", "--show-toplevel"], capture_output=True,
                             text=True, timeout=5)
        if top.returncode == 0 and Path(top.stdout.strip()).resolve() == here:
            head = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True,
                                  timeout=5).stdout.strip()
            dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                                   capture_output=True, text=True, timeout=5).stdout.strip()
            if head:
                return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        pass
    return built_commit()


def built_commit() -> str:
    """The commit the installed package was built from, as setuptools-scm recorded it, with
    ``-dirty`` if the tree had uncommitted changes."""
    import importlib

    built = importlib.import_module(f"{__package__}._version")  # written at build time, with __version__
    commit = getattr(built, "commit_id", None)
    if not commit:
        return "unknown (built without git metadata)"
    local = built.__version__.partition("+")[2].split(".")
    dirty = any(part.startswith("d") and part[1:].isdigit() for part in local)
    return commit.removeprefix("g") + ("-dirty" if dirty else "")  # git nodes are written g<hash>


def utc_now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def provenance_attrs(*, stage: str, version: str, key: str, parameters: Mapping, upstream: Mapping[str, str],
                     inputs: list[dict], optional: list[str], scene: str, variant: str) -> dict[str, str]:
    now = utc_now()
    return {
        "Conventions": "CF-1.11",
        "title": f"roughcontact stage '{stage}'",
        "institution": "roughcontact",
        "source": f"roughcontact {__version__}",
        "history": f"{now}: roughcontact {__version__} computed stage {stage} v{version} "
                   f"(scene {scene}, variant {variant}, key {key[:12]})",
        "software_version": __version__,
        "git_commit": git_commit(),
        "stage_name": stage,
        "stage_version": version,
        "stage_key": key,
        "parameters": dumps(parameters),
        "upstream_keys": dumps(upstream),
        "input_files": dumps(inputs),
        "optional_outputs": dumps(sorted(optional)),
        "scene": scene,
        "scene_variant": variant,
        "date_created": now,
    }


def _encodable(ds: xr.Dataset) -> xr.Dataset:
    """Attributes NetCDF can hold (str, numbers); None and booleans become strings."""
    def clean(attrs):
        return {k: (str(v) if v is None or isinstance(v, (bool, np.bool_)) else v) for k, v in attrs.items()}

    ds = ds.copy()
    ds.attrs = clean(ds.attrs)
    for name in ds.variables:
        ds[name].attrs = clean(ds[name].attrs)
    return ds


def write(ds: xr.Dataset, path: Path, compute_with="threads", progress=None, compress: bool = True) -> None:
    """Write ``ds`` to ``path`` atomically: a temporary file in the same folder, then a rename.

    Dask-backed variables are computed block by block by ``compute_with`` (a dask scheduler
    name or a distributed Client) and written from this process (:func:`pipeline.compute.write_blocks`),
    so a result never has to fit in memory (``progress``: a :class:`roughcontact.progress.Reporter`
    showing the blocks written; ``compress``: large variables zlib-compressed, :mod:`roughcontact.cf`). A crash or kill while writing leaves at most a
    ``.tmp-*`` file, which is never read as a result (and is removed by :func:`clean_temporaries`).
    """
    from .compute import dask_variables, write_blocks

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f"{TMP_PREFIX}{path.name}.", dir=path.parent)
    os.close(fd)
    os.chmod(tmp, new_file_mode())  # mkstemp makes it 0600; a result is a file like any other
    try:
        ds = _encodable(ds)
        lazy = dask_variables(ds)
        eager = ds.drop_vars(lazy)
        eager.to_netcdf(tmp, engine="netcdf4", encoding=cf.encoding(eager, compress))
        if lazy:
            _define(tmp, ds, lazy, compress)
            write_blocks(tmp, ds, lazy, compute_with, progress)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def new_file_mode() -> int:
    """The permissions the user's umask gives a new file (0644 under umask 022)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def _define(path, ds: xr.Dataset, names: list[str], compress: bool = True) -> None:
    """Declare the lazily computed variables in the file, with their attributes."""
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        for name in names:
            var = ds[name].variable
            for dim in var.dims:
                if dim not in nc.dimensions:
                    nc.createDimension(dim, ds.sizes[dim])
            target = nc.createVariable(name, var.dtype, var.dims, **cf.lazy_variable(ds, name, compress))
            target.setncatts(dict(var.attrs))
        coords = [n for n in names if n in ds.coords and n not in ds.dims]
        for name in ds.data_vars:
            extra = [c for c in coords if set(ds[c].dims) <= set(ds[name].dims)]
            if extra and name in nc.variables:
                nc.variables[name].setncattr("coordinates", " ".join(extra))


def clean_temporaries(folder: Path) -> None:
    """Remove temporaries that a killed run left behind."""
    if folder.is_dir():
        for leftover in folder.glob(f"{TMP_PREFIX}*"):
            leftover.unlink(missing_ok=True)


def read_attrs(path: Path) -> dict | None:
    """Global attributes of a stored result, or None if the file is missing or unreadable."""
    if not Path(path).is_file():
        return None
    import netCDF4  # directly: opening with xarray would import dask and pint for nothing

    try:
        with netCDF4.Dataset(path) as nc:
            return {k: nc.getncattr(k) for k in nc.ncattrs()}
    except Exception:  # a truncated or foreign file is simply not a valid result
        return None


def open_result(path: Path) -> xr.Dataset:
    """Load a stored result fully into memory (the file is closed afterwards)."""
    with xr.open_dataset(path) as ds:
        return ds.load()
