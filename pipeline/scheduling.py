"""Chunking, scheduling and the block writer.

* :func:`auto_chunks` picks dask chunk sizes for a scene's sweep dimensions so that one chunk's
  working memory stays near a budget (explicit sizes from the scene win).
* :func:`scheduler` turns the scene's / command line's scheduler setting into something dask
  can compute with: 'threads', 'processes', 'synchronous' or a dask.distributed client.
* :func:`write_blocks` fills the dask-backed variables of a NetCDF file block by block: the
  blocks are computed by the scheduler (on a cluster's workers, say) and written by *this*
  process only, a bounded number in flight, so a sweep never has to fit in memory and no worker
  ever writes to the file.
* :class:`KeptBlocks`: for a stage whose blocks are long work (``Shape(keep_blocks=True)``, the
  validation's BEM tasks), every finished block is also saved in the output folder under the
  result's content key, as it arrives, so that a run that is killed resumes where it stopped.
* :func:`quiet_libraries`: dask's warnings about chunks and graphs (the engine's choices, nothing
  the user can act on) kept out of the user's output.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import tempfile
import warnings
from pathlib import Path
from typing import Iterator, Mapping

import numpy as np
import xarray as xr

from . import ncio
from .errors import UserError
from .progress import Tick


def auto_chunks(sizes: Mapping[str, int], budget_points: int,
                explicit: Mapping[str, int] | None = None) -> dict[str, int]:
    """Chunk sizes per sweep dimension: explicit ones as given; the others start whole and the
    largest is halved until the product of chunk sizes is within ``budget_points``."""
    explicit = dict(explicit or {})
    chunks = {d: (explicit[d] if explicit.get(d) else n) for d, n in sizes.items()}
    free = [d for d in sizes if not explicit.get(d)]
    budget_points = max(1, int(budget_points))
    while free and math.prod(chunks.values()) > budget_points:
        d = max(free, key=lambda k: chunks[k])
        if chunks[d] == 1:
            break
        chunks[d] = math.ceil(chunks[d] / 2)
    return {d: c for d, c in chunks.items() if c < sizes[d]}


def chunk_sweeps(upstream: Mapping[str, xr.Dataset], chunks: Mapping[str, int]) -> dict[str, xr.Dataset]:
    """Upstream results chunked along the sweep dimensions a stage chunks (``chunks``, from
    :func:`auto_chunks`): a sweep dimension made upstream (eta, spectrum draws) then splits the
    stage's work into blocks like the stage's own sweeps. Chunking never changes values."""
    out = {}
    for name, ds in upstream.items():
        dims = {d: int(c) for d, c in chunks.items() if d in ds.dims and c}
        out[name] = ds.chunk(dims) if dims else ds
    return out


@contextlib.contextmanager
def scheduler(setting: str) -> Iterator[object]:
    """Yield what :func:`write_blocks` computes with: a dask scheduler name, a process pool (one
    for the whole run: a pool per batch of blocks would start and import in new processes every
    time) or a distributed Client."""
    if setting == "processes":
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(os.cpu_count() or 2, mp_context=multiprocessing.get_context("spawn")) as pool:
            yield pool
        return
    if setting in ("threads", "synchronous", "sync"):
        yield setting
        return
    if "://" in setting or setting.count(":") == 1:
        try:
            from distributed import Client
        except ImportError:
            raise UserError("a scheduler address needs dask.distributed: pip install distributed",
                            key="run.scheduler") from None
        try:
            client = Client(setting, timeout="10s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise UserError(f"cannot reach the dask scheduler at {setting!r} ({exc})", key="run.scheduler") from None
        try:
            _check_workers(client, setting)
            yield client
        finally:
            client.close()
        return
    raise UserError(f"scheduler {setting!r}: use threads, processes, synchronous or a tcp:// address",
                    key="run.scheduler")


def _worker_version() -> str:
    """Run on each worker: the roughcontact version it can import (stages included)."""
    from roughcontact.stage import stages
    from roughcontact.version import __version__

    stages()
    return __version__


def _check_workers(client, address: str) -> None:
    from .version import __version__

    try:
        versions = client.run(_worker_version)
    except Exception as exc:  # deserialisation or import failures on the workers
        raise UserError(
            f"the workers of {address} cannot import roughcontact ({exc.__class__.__name__}); install the same "
            f"roughcontact ({__version__}) in the workers' environment", key="run.scheduler") from None
    if not versions:
        raise UserError(f"the dask cluster at {address} has no workers", key="run.scheduler")
    wrong = {w: v for w, v in versions.items() if v != __version__}
    if wrong:
        raise UserError(f"workers run roughcontact {sorted(set(wrong.values()))}, this client {__version__}",
                        key="run.scheduler")


@contextlib.contextmanager
def quiet_libraries() -> Iterator[None]:
    """Hide the warnings dask and dask.distributed give about how the work is cut up (a
    ``PerformanceWarning`` "Increasing number of chunks", "Sending large graph"): the engine
    chooses the chunks, so they say nothing the user can act on. Warnings of the physics
    (numpy's, the stages' own :class:`SceneWarning`) still show."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", module=r"(dask|distributed)(\..*)?$")
        warnings.filterwarnings("ignore", message=r"(Increasing number of chunks|Sending large graph)")
        yield


class KeptBlocks:
    """The finished blocks of one result being written, kept in ``folder`` (one ``.npz`` per
    block, named by the block's dimensions and index ranges, written atomically) so that a run
    that is killed resumes: the next run with the same content key reads them instead of
    computing them. The folder is the result's (:func:`roughcontact.store.kept_blocks_folder`),
    its name holds the key; the store removes it once the result is written."""

    def __init__(self, folder: Path, tmp_prefix: str = ".tmp-"):
        self.folder = Path(folder)
        self.tmp_prefix = tmp_prefix  # the store's: its clean-up removes what a kill leaves

    def _file(self, dims, region) -> Path:
        where = "_".join(f"{s.start}-{s.stop}" for s in region)
        return self.folder / f"{'.'.join(dims) or 'scalar'}@{where or '0'}.npz"

    def load(self, dims, names, region) -> list[np.ndarray] | None:
        """The block's values per variable of ``names``, or None if not kept (or unreadable)."""
        path = self._file(dims, region)
        if not path.is_file():
            return None
        shape = tuple(s.stop - s.start for s in region)
        try:
            with np.load(path, allow_pickle=False) as kept:
                values = [kept[name] for name in names]
        except (OSError, KeyError, ValueError, EOFError):
            return None
        return values if all(v.shape == shape for v in values) else None

    def save(self, dims, names, region, values) -> None:
        """Keep a block: a temporary in the folder, then a rename (a kill leaves no half block)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=self.tmp_prefix, suffix=".npz", dir=self.folder)
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **{name: np.asarray(v) for name, v in zip(names, values, strict=True)})
            os.replace(tmp, self._file(dims, region))
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise


def _compute_block(arrays: bytes) -> tuple:
    """Run on a worker: the pickled dask arrays of one block, computed together in this thread."""
    import pickle

    import dask

    return dask.compute(*pickle.loads(arrays), scheduler="synchronous")


def _as_completed(tasks: Mapping[tuple, list], compute_with, client, pool, workers: int):
    """Yield ``(idx, values)`` as each block of ``tasks`` (block index -> its dask arrays) finishes,
    computing every block on its own (its own graph): a few at a time, on the scene's scheduler."""
    import dask

    todo = iter(tasks.items())
    if client is not None:
        import cloudpickle
        from distributed import as_completed

        def submit(task):
            # A block is one task on the cluster: its arrays (their graph, 12 KB pickled for a
            # validation task) computed together by one worker thread, as on the threads
            # scheduler, so that work they share (the BEM solve behind a task's area, gap and
            # time) is done once, and no small input task ties a block to the worker that happened
            # to make it. (Wrapped in dask.delayed, each array was optimised on its own and the
            # shared solve ran once per array: three solves per validation task.)
            return client.submit(_compute_block, cloudpickle.dumps(list(task)), pure=False)

        window = as_completed(loop=client.loop)
        owner = {}
        for idx, task in itertools.islice(todo, 2 * workers):
            future = submit(task)
            owner[future.key] = idx
            window.add(future)
        for future in window:
            yield owner.pop(future.key), future.result()
            for idx, task in itertools.islice(todo, 1):
                nxt = submit(task)
                owner[nxt.key] = idx
                window.add(nxt)
        return
    if compute_with in ("synchronous", "sync") or workers <= 1:
        for idx, task in todo:
            yield idx, dask.compute(*task, scheduler="synchronous")
        return
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    if pool is not None:
        def one(task):
            return dask.compute(*task, scheduler="processes", pool=pool)
    else:  # threads: each block computed whole by one thread, several blocks at a time
        def one(task):
            return dask.compute(*task, scheduler="synchronous")
    executor = ThreadPoolExecutor(workers, thread_name_prefix="roughcontact-block")
    try:
        running = {executor.submit(one, task): idx for idx, task in itertools.islice(todo, workers)}
        while running:
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                idx = running.pop(future)
                yield idx, future.result()
                for nidx, task in itertools.islice(todo, 1):
                    running[executor.submit(one, task)] = nidx
    finally:  # interrupted: start nothing more (blocks already running finish on their own)
        executor.shutdown(wait=False, cancel_futures=True)


def dask_variables(ds: xr.Dataset) -> list[str]:
    return [name for name, v in ds.variables.items() if v.chunks is not None]


def _region(offsets, idx) -> tuple[slice, ...]:
    """The slices of block ``idx`` (one index per dimension) given each dimension's chunk offsets."""
    return tuple(slice(int(o[i]), int(o[i + 1])) for o, i in zip(offsets, idx, strict=True))


def _in_batches(indices, arrays, compute_with, client, pool, in_flight: int):
    """Yield ``(idx, values)`` for every block, ``in_flight`` blocks computed together (work they
    share is done once)."""
    import dask

    todo = iter(indices)
    while batch := list(itertools.islice(todo, in_flight)):
        tasks = [[a.blocks[idx] for a in arrays] for idx in batch]
        if client is not None:
            results = client.gather(client.compute(tasks))
        elif pool is not None:
            results = dask.compute(*tasks, scheduler="processes", pool=pool)
        else:
            results = dask.compute(*tasks, scheduler=compute_with)
        yield from zip(batch, results, strict=True)


def _groups(ds: xr.Dataset, names: list[str], keep: KeptBlocks | None) -> list[tuple]:
    """Per group of variables with the same dimensions and chunks: (dims, names, chunk offsets,
    block indices, {index: values} of the blocks ``keep`` holds)."""
    groups: dict[tuple, list[str]] = {}
    for name in names:
        var = ds[name].variable
        groups.setdefault((var.dims, var.chunks), []).append(name)
    out = []
    for (dims, chunks), group in groups.items():
        offsets = [np.concatenate([[0], np.cumsum(c)]) for c in chunks]
        indices = list(itertools.product(*(range(len(c)) for c in chunks)))
        kept = {}
        for idx in indices if keep is not None else ():
            values = keep.load(dims, group, _region(offsets, idx))
            if values is not None:
                kept[idx] = values
        out.append((dims, group, offsets, indices, kept))
    return out


def write_blocks(path, ds: xr.Dataset, names: list[str], compute_with, progress=None,
                 in_flight: int | None = None, checksums=None, keep: KeptBlocks | None = None) -> None:
    """Compute the dask variables ``names`` of ``ds`` block by block and write them into the
    existing NetCDF file ``path`` (whose other variables are already written); ``progress`` (a
    :class:`roughcontact.progress.Reporter`) shows the blocks written.

    Variables with the same dimensions and chunks are computed together, so that work they share
    (an integral over q, say) is done once per block.

    With ``keep`` (:class:`KeptBlocks`), the blocks it holds are written without computing them,
    and every other block is computed on its own and kept as soon as it finishes (then written),
    so that a run killed at any moment loses at most the blocks being computed.
    """
    import dask  # imported here: a run with nothing to compute never needs it

    plans = _groups(ds, names, keep)
    total = sum(len(p[3]) for p in plans)
    done_before = sum(len(p[4]) for p in plans)
    if progress is not None and done_before:
        progress.note(f"    {done_before} of {total} blocks kept from an interrupted run: computing the other "
                      f"{total - done_before}")
    bar = progress.bar("writing", total, unit="block", initial=done_before) if progress is not None else Tick()
    from concurrent.futures import Executor

    pool = compute_with if isinstance(compute_with, Executor) else None
    client = compute_with if not isinstance(compute_with, str) and pool is None else None
    workers = len(client.scheduler_info()["workers"]) if client is not None else (dask.system.CPU_COUNT or 2)
    if in_flight is None:
        in_flight = max(2, 2 * workers)
    with ncio.dataset(path, "a") as nc:  # every call into netCDF/HDF5 under the process-wide lock (ncio)
        for dims, group, offsets, indices, kept in plans:
            with ncio.locked():
                targets = [nc.variables[name] for name in group]
            arrays = [ds[name].data for name in group]
            if keep is None:
                arriving = _in_batches(indices, arrays, compute_with, client, pool, in_flight)
            else:
                tasks = {idx: [a.blocks[idx] for a in arrays] for idx in indices if idx not in kept}
                arriving = itertools.chain(kept.items(), _as_completed(tasks, compute_with, client, pool, workers))
            for idx, values in arriving:
                sl = _region(offsets, idx)
                if keep is not None and idx not in kept:
                    keep.save(dims, group, sl, values)
                with ncio.locked():
                    for target, value in zip(targets, values, strict=True):
                        target[sl] = np.asarray(value)
                if checksums is not None:
                    for name, value in zip(group, values, strict=True):
                        checksums.add(name, np.asarray(value), [s.start for s in sl])
                if idx not in kept:
                    bar()
