"""The result store: one NetCDF file per stage, written atomically, with provenance.

Every file carries CF-style metadata (``Conventions``, ``history``, ``units`` and
``long_name`` on every variable and coordinate) and the provenance needed to decide
whether it can be reused: the stage's content key, its parameters, upstream keys and the
hashes of its input files.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import functools
import hashlib
import json
import os
import socket
import subprocess
import tempfile
from pathlib import Path
from typing import Any, BinaryIO, Callable, Mapping

import numpy as np
import xarray as xr

from . import cf, integrity, ncio
from .errors import OutputError
from .version import __version__

TMP_PREFIX = ".tmp-"
#: folder (beside a result) of the finished blocks of results being written
#: (:class:`roughcontact.writing.KeptBlocks`)
BLOCKS = ".blocks"


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


def kept_blocks_folder(path: Path, key: str) -> Path:
    """Where the finished blocks of the result ``path`` with content key ``key`` are kept while it
    is written (a killed run resumes from them)."""
    return Path(path).parent / BLOCKS / f"{Path(path).name}.{key[:20]}"


def _forget_blocks(path: Path, keep: Path | None = None) -> None:
    """Remove the kept blocks of ``path`` under every key but ``keep``'s (and an empty folder)."""
    import shutil

    folder = Path(path).parent / BLOCKS
    if not folder.is_dir():
        return
    for old in folder.glob(f"{Path(path).name}.*"):
        if old != keep:
            shutil.rmtree(old, ignore_errors=True)
    with contextlib.suppress(OSError):
        folder.rmdir()  # only if empty


def write(ds: xr.Dataset, path: Path, compute_with="threads", progress=None, compress: bool = True,
          keep_blocks: bool = False, costlier_with: tuple[str, ...] = ()) -> None:
    """Write ``ds`` to ``path`` atomically: a temporary file in the same folder, then a rename.

    Dask-backed variables are computed block by block by ``compute_with`` (a dask scheduler
    name or a distributed Client) and written from this process (:func:`roughcontact.writing.write_blocks`),
    so a result never has to fit in memory (``progress``: a :class:`roughcontact.progress.Reporter`
    showing the blocks written; ``compress``: large variables zlib-compressed where it pays, :mod:`roughcontact.cf`).
    A crash or kill while writing leaves at most a
    ``.tmp-*`` file, which is never read as a result (and is removed by :func:`clean_temporaries`).
    The file gets a checksum of its data and attributes (:mod:`roughcontact.integrity`). A file
    that cannot be written (full disk, no permission) is an :class:`OutputError` naming it, raised
    after its temporary is removed.

    With ``keep_blocks`` (a stage whose blocks are long work, ``Shape(keep_blocks=True)``) every
    finished block is also kept in :func:`kept_blocks_folder` (named by the result's content key)
    until the result is in place: a run that is killed or fails resumes from them, computing only
    the blocks not kept. Kept blocks of the same result under another key (an older scene) are
    removed when it is written. ``costlier_with``: the dimensions along which a block's work grows
    with the coordinate (``Shape.costlier_with``): those blocks are computed first.
    """
    from .writing import KeptBlocks, dask_variables, write_blocks

    path = Path(path)
    key = ds.attrs.get("stage_key")
    keep = KeptBlocks(kept_blocks_folder(path, key), TMP_PREFIX) if keep_blocks and key else None
    _forget_blocks(path, keep.folder if keep is not None else None)
    if keep is not None:
        clean_temporaries(keep.folder)  # a block being saved when a run was killed
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f"{TMP_PREFIX}{path.name}.{_owner()}.", dir=path.parent)
        os.close(fd)
        os.chmod(tmp, new_file_mode())  # mkstemp makes it 0600; a result is a file like any other
        ds = _encodable(ds)
        lazy = dask_variables(ds)
        eager = ds.drop_vars(lazy)
        with ncio.locked():
            written = _write_in_memory(eager, tmp, cf.encoding(eager, compress))
        sums = integrity.Checksums({name: ds[name].variable.chunks for name in lazy})
        if lazy:
            write_blocks(tmp, ds, lazy, compute_with, progress, checksums=sums, keep=keep, compress=compress,
                         costlier_with=costlier_with)
        integrity.stamp(tmp, {**written, **sums.known()})
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        if keep is not None:
            _forget_blocks(path)
    except BaseException as exc:
        why = _why(exc, path) if _is_write_failure(exc) else None  # the free space before the temporary goes
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        if why is not None:
            raise OutputError(f"cannot write this result ({why}); nothing of it was kept", file=str(path)) from None
        raise


def _write_in_memory(ds: xr.Dataset, path, encoding: dict) -> dict[str, tuple[tuple[int, ...], int]]:
    """``ds.to_netcdf(path, engine="netcdf4", encoding=encoding)`` for a dataset without dask
    variables, through the same xarray encoder and netCDF4 store, but with :data:`ncio.LOCK` as the
    store's lock: ``to_netcdf`` asks dask which scheduler runs (to choose its lock), and dask
    imports dask.distributed to answer (0.1-0.2 s of a small run's start).

    Returns the block sums (:func:`roughcontact.integrity.block_sums`) of the numeric variables,
    hashed from the values exactly as the store writes them (encoded by the store itself, in
    memory) instead of read back from the file: reading back a compressed variable meant
    decompressing it just after compressing it."""
    from xarray.backends import NetCDF4DataStore

    target = NetCDF4DataStore.open(str(path), mode="w", format="NETCDF4", lock=ncio.LOCK)
    sums: dict[str, tuple[tuple[int, ...], int]] = {}

    def hashed(variables, attributes):  # xarray's encoder hook: look, change nothing (the store encodes them)
        sums.update(integrity.block_sums(target.encode(variables, attributes)[0]))
        return variables, attributes

    try:
        ds.dump_to_store(target, encoding=encoding, encoder=hashed)
    finally:
        target.close()
    return sums


def write_figure(fig, path: Path, dpi: int = 130) -> None:
    """Save a matplotlib figure as PNG at ``path`` whole or not at all (see :func:`write_file`).
    The caller closes the figure."""
    write_file(lambda fh: fig.savefig(fh, format="png", dpi=dpi), path, what="figure")


def write_file(content: bytes | Callable[[BinaryIO], object], path: Path, what: str = "file") -> None:
    """Write a file whole or not at all: into a temporary beside it (named by host and process, so
    :func:`clean_temporaries` never removes a live writer's), synced, then renamed over ``path``.

    ``content`` is the bytes, or a function that writes them to the binary file handle it is given
    (a figure, a table, a spreadsheet). A file that cannot be written (full disk, no permission)
    is an :class:`OutputError` naming it (``what``: "report", "figure", "table", ...), and nothing
    of it is kept; an interruption keeps nothing either."""
    path = Path(path)
    tmp = path.with_name(f"{TMP_PREFIX}{path.name}.{_owner()}")
    try:
        with open(tmp, "wb") as fh:
            if callable(content):
                content(fh)
            else:
                fh.write(content)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, new_file_mode())
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write this {what} ({exc.strerror or exc}); nothing of it was kept",
                          file=str(path)) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def new_file_mode() -> int:
    """The permissions the user's umask gives a new file (0644 under umask 022)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def _owner() -> str:
    """Who writes a temporary: host and process id (a temporary of a live process is never removed)."""
    return f"{socket.gethostname().replace('.', '_')}-{os.getpid()}"


def _is_write_failure(exc: BaseException) -> bool:
    """An OSError, or the netCDF library's error, while writing (not a stage's error)."""
    return isinstance(exc, OSError) or isinstance(exc, RuntimeError) and str(exc).startswith(("NetCDF:", "HDF"))


def _why(exc: BaseException, path: Path) -> str:
    """The reason, with the free space of the disk when it is (nearly) full."""
    import shutil

    text = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
    try:
        free = shutil.disk_usage(path.parent if path.parent.exists() else Path.cwd()).free
    except OSError:
        return text
    return f"{text}; the disk had {free / 1e6:.3g} MB free when it failed" if free < 2**30 else text


def clean_temporaries(folder: Path) -> None:
    """Remove temporaries that a killed run left behind. Called only while holding the output
    folder's lock (:func:`roughcontact.preflight.locked`): no other run writes there then, so a
    temporary is stale, unless its name says that a live process of this host owns it."""
    if folder.is_dir():
        for leftover in folder.glob(f"{TMP_PREFIX}*"):
            if not _owner_alive(leftover.name):
                leftover.unlink(missing_ok=True)


def _owner_alive(name: str) -> bool:
    """Whether the temporary ``name`` belongs to another live process of this host."""
    host, _, pid = (name.split(".")[-2] if name.count(".") >= 3 else "").rpartition("-")
    if host != socket.gethostname().replace(".", "_") or not pid.isdigit() or int(pid) == os.getpid():
        return False
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


def read_attrs(path: Path) -> dict | None:
    """Global attributes of a stored result, or None if the file is missing or unreadable."""
    if not Path(path).is_file():
        return None
    try:  # with netCDF4 directly: opening with xarray would import dask and pint for nothing
        with ncio.dataset(path) as nc, ncio.locked():
            return {k: nc.getncattr(k) for k in nc.ncattrs()}
    except Exception:  # a truncated or foreign file is simply not a valid result
        return None


def open_result(path: Path) -> xr.Dataset:
    """Load a stored result fully into memory (the file is closed afterwards)."""
    with ncio.locked(), xr.open_dataset(path) as ds:
        return ds.load()
