"""Everything the engine checks before any stage computes, and the lock on the output folder.

* :func:`output_folder` makes sure the output folder exists and can be written (a clear error
  for a file given as ``--outdir``, a read-only folder, ...).
* :func:`locked` holds a lock file (the maintained ``filelock`` library) in the output folder
  for the whole run: a second run on the same folder waits for the first (saying so) or, with a
  timeout, refuses with a clear message. Only a run that holds the lock removes temporaries, so
  a temporary is removed by its owner or, once no run holds the lock, as provably stale.
* :func:`check` reads every input file and runs every stage's ``check`` and ``describe``,
  upstream first, handing each the :class:`~roughcontact.stage.Shape` of its upstream results;
  then it estimates the size of every result and working array (:mod:`roughcontact.sizing`) and
  refuses what the machine cannot hold. All of this happens before anything is computed or
  written.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from pathlib import Path
from typing import Iterator

from . import sizing
from .errors import UserError
from .readers import READERS
from .stage import Shape, StageInput

#: the lock file every run holds in its output folder
LOCK_NAME = ".roughcontact.lock"
#: results above this many bytes are handed downstream lazily, in chunks (the engine's LOAD_LIMIT_BYTES)
LOAD_LIMIT_BYTES = 256 * 2**20


def arguments(scene, outdir, targets, force):
    """The Python API's arguments made what the engine expects, or a clear error: a scene file,
    built-in name or dict for a Scene, a string for a path, one name for a list of them."""
    from . import scene as scenes

    if isinstance(scene, (str, Path)):
        scene = scenes.load(scene)
    elif isinstance(scene, dict):
        scene = scenes.from_dict(scene)
    elif not isinstance(scene, scenes.Scene):
        raise TypeError(f"expected a Scene (or a scene file, built-in name or dict), got {type(scene).__name__}")
    if not isinstance(outdir, (str, Path)) or not str(outdir):
        raise TypeError(f"outdir must be a folder path (str or pathlib.Path), got {outdir!r}")
    if isinstance(targets, str):
        targets = (targets,)
    force = {force} if isinstance(force, str) else set(force or ())
    names = list(force) + (list(targets) if targets is not None else [])
    if not all(isinstance(name, str) for name in names):
        raise TypeError("force and targets take stage or variable names (a string or a list of strings)")
    return scene, Path(outdir), targets, force


def not_a_file(outdir) -> None:
    """A UserError if the output folder's path is taken by something that is not a folder."""
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise UserError("exists and is not a folder: give --outdir a folder (or a path that does not exist yet)",
                        file=str(outdir))


def output_folder(outdir) -> Path:
    """The output folder, created if needed; a UserError naming it if it cannot be used. The
    engine calls it only once every check has passed: a refused run creates no folder."""
    outdir = Path(outdir)
    not_a_file(outdir)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create the output folder ({exc.strerror or exc})", file=str(outdir)) from None
    if not os.access(outdir, os.W_OK | os.X_OK):
        raise UserError("the output folder is not writable (read-only or no permission)", file=str(outdir))
    return outdir


@contextlib.contextmanager
def locked(outdir: Path, report=None, timeout: float | None = None) -> Iterator[None]:
    """Hold the output folder's lock file. Another run holding it: say so and wait (at most
    ``timeout`` seconds; None waits until it ends), then a UserError if it is still held."""
    from filelock import FileLock, Timeout

    path = Path(outdir) / LOCK_NAME
    lock = FileLock(str(path))
    try:
        try:
            lock.acquire(timeout=0)
        except Timeout:
            if report is not None:
                report(f"waiting: another roughcontact run is writing to {outdir} (lock {path})")
            lock.acquire(timeout=-1 if timeout is None else timeout)
    except Timeout:
        raise UserError(f"another roughcontact run is writing to this folder (it holds {LOCK_NAME}); "
                        "run again when it has finished, or write elsewhere with --outdir", file=str(outdir)) from None
    except OSError as exc:
        raise UserError(f"cannot write to the output folder ({exc.strerror or exc})", file=str(outdir)) from None
    try:
        yield
    finally:
        lock.release()


def read_input(st, param: str, path, params):
    """One loaded input file of stage ``st``, or a list of them for a ``paths`` parameter."""
    spec = next(f for f in st.files if f.param == param)
    reader = READERS[spec.reader]
    options = dict(spec.options(params)) if spec.options is not None else {}
    return [reader(p, **options) for p in path] if isinstance(path, tuple) else reader(path, **options)


def stored_shape(path: Path) -> Shape:
    """The shape of a stored (fresh) result: its sizes and coordinate ranges, no data loaded."""
    import xarray as xr

    from . import ncio

    with ncio.locked(), xr.open_dataset(path) as ds:
        return Shape.of(ds)


@contextlib.contextmanager
def _in_variant(variant: str) -> Iterator[None]:
    """Say which variant a bad value belongs to."""
    try:
        yield
    except UserError as exc:
        if variant == "base":
            raise
        raise UserError(f"{exc.message} (variant {variant})", file=exc.file, key=exc.key) from None


def _stored(p) -> bool:
    """Whether the plan's result exists already: fresh, or to be taken from an identical one."""
    return p.status == "fresh" or getattr(p, "source", None) is not None


def _checked(p, files: dict) -> None:
    """Run the stage's ``check`` of one plan (its keys and files; no upstream shapes)."""
    if p.stage.check is not None:
        p.stage.check(StageInput(params=p.params, files=files, wanted=p.wanted, stage=p.stage.name))


def described(p, upstream: dict[str, Shape], files: dict) -> Shape:
    """Run the stage's ``describe`` for one plan (``upstream``: the shapes of its upstream
    results): the shape of the dimensions it adds (empty if it adds none)."""
    inp = StageInput(params=p.params, upstream=upstream, files=files, wanted=p.wanted, stage=p.stage.name)
    shape = p.stage.describe(inp) if p.stage.describe is not None else None
    return shape if shape is not None else Shape()


def check(plans, scenes: dict, outdir: Path) -> tuple[dict[int, dict], dict[tuple[str, str], Shape]]:
    """Everything that can be known before computing, before anything is computed or written:
    read the input files of every stage about to compute (a bad file is named first) and run
    every stage's ``check`` (its keys and files: a cause, such as two maps on different grids, is
    reported before its consequences downstream); then each stage's ``describe``, upstream first,
    with the shapes of its upstream results (of the stored file, or what the upstream
    ``describe`` gave), which refuses what does not fit them; then the sizes. Returns
    the loaded files per plan index and the shape of every result per (variant, stage), with
    the sweep dimensions it spans. A result put in place from an identical one (``p.source``,
    roughcontact.reuse) counts as stored; with nothing to compute, nothing is read at all (a
    rerun stays fast)."""
    files: dict[int, dict] = {}
    if all(_stored(p) for p in plans):
        return files, {}
    for i, p in enumerate(plans):
        if not _stored(p):
            with _in_variant(p.variant):
                files[i] = {param: read_input(p.stage, param, path, p.params) for param, path in p.file_paths.items()}
                _checked(p, files[i])
    shapes: dict[tuple[str, str], Shape] = {}
    stored: dict[tuple[str, str], int] = {}  # bytes of each result, estimated or on disk
    estimates = []
    planned: dict[Path, tuple[str, str]] = {}  # result path -> its (variant, stage)
    in_flight = max(2, 2 * (os.cpu_count() or 2))
    for i, p in enumerate(plans):
        here = (p.variant, p.stage.name)
        ups = tuple(p.record["upstream"])
        upstream = {up: shapes[(p.variant, up)] for up in ups if (p.variant, up) in shapes}
        planned_at = planned.get(p.path if p.status == "fresh" else p.source) if _stored(p) else None
        if _stored(p):
            where = p.path if p.status == "fresh" else p.source
            if planned_at is not None:  # identical to a result computed earlier in this run: its shape
                shapes[here], stored[here] = shapes[planned_at], stored[planned_at]
            else:
                shapes[here], stored[here] = stored_shape(where), where.stat().st_size
            planned[p.path] = here
            continue
        spanned = sizing.spanned_dims(scenes[p.variant], p.stage, [shapes.get((p.variant, up)) for up in ups])
        lazy = frozenset(d for up in ups if stored.get((p.variant, up), 0) > LOAD_LIMIT_BYTES
                         for d in shapes[(p.variant, up)].sizes)
        with _in_variant(p.variant):
            own = described(p, upstream, files[i])
        shape = dataclasses.replace(own, sizes={**spanned, **own.sizes})  # with the sweep dims it spans
        estimates.append(sizing.estimate(p, scenes[p.variant], spanned, own, in_flight, lazy))
        stored[here] = estimates[-1].result
        shapes[here] = shape
        planned[p.path] = here
    sizing.check(estimates, outdir)
    return files, shapes
