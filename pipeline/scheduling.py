"""Chunking, scheduling and the block writer.

* :func:`auto_chunks` picks dask chunk sizes for a scene's sweep dimensions so that one chunk's
  working memory stays near a budget (explicit sizes from the scene win).
* :func:`scheduler` turns the scene's / command line's scheduler setting into something dask
  can compute with: 'threads', 'processes', 'synchronous' or a dask.distributed client.
* :func:`write_blocks` fills the dask-backed variables of a NetCDF file block by block: the
  blocks are computed by the scheduler (on a cluster's workers, say) and written by *this*
  process only, a bounded number in flight, so a sweep never has to fit in memory and no worker
  ever writes to the file.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
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


def dask_variables(ds: xr.Dataset) -> list[str]:
    return [name for name, v in ds.variables.items() if v.chunks is not None]


def _region(offsets, idx) -> tuple[slice, ...]:
    """The slices of block ``idx`` (one index per dimension) given each dimension's chunk offsets."""
    return tuple(slice(int(o[i]), int(o[i + 1])) for o, i in zip(offsets, idx, strict=True))


def write_blocks(path, ds: xr.Dataset, names: list[str], compute_with, progress=None,
                 in_flight: int | None = None, checksums=None) -> None:
    """Compute the dask variables ``names`` of ``ds`` block by block and write them into the
    existing NetCDF file ``path`` (whose other variables are already written); ``progress`` (a
    :class:`roughcontact.progress.Reporter`) shows the blocks written.

    Variables with the same dimensions and chunks are computed together, so that work they share
    (an integral over q, say) is done once per block.
    """
    import dask  # imported here: a run with nothing to compute never needs it

    groups: dict[tuple, list[str]] = {}
    for name in names:
        var = ds[name].variable
        groups.setdefault((var.dims, var.chunks), []).append(name)
    total = sum(math.prod(len(c) for c in chunks) for (_, chunks) in groups)
    bar = progress.bar("writing", total, unit="block") if progress is not None else Tick()
    from concurrent.futures import Executor

    pool = compute_with if isinstance(compute_with, Executor) else None
    client = compute_with if not isinstance(compute_with, str) and pool is None else None
    if in_flight is None:
        workers = len(client.scheduler_info()["workers"]) if client is not None else (dask.system.CPU_COUNT or 2)
        in_flight = max(2, 2 * workers)
    with ncio.dataset(path, "a") as nc:  # every call into netCDF/HDF5 under the process-wide lock (ncio)
        for (_dims, chunks), group in groups.items():
            offsets = [np.concatenate([[0], np.cumsum(c)]) for c in chunks]
            with ncio.locked():
                targets = [nc.variables[name] for name in group]
            arrays = [ds[name].data for name in group]
            indices = itertools.product(*(range(len(c)) for c in chunks))
            while True:
                batch = list(itertools.islice(indices, in_flight))
                if not batch:
                    break
                tasks = [[a.blocks[idx] for a in arrays] for idx in batch]
                if client is not None:
                    futures = client.compute(tasks)
                    results = client.gather(futures)
                elif pool is not None:
                    results = dask.compute(*tasks, scheduler="processes", pool=pool)
                else:
                    results = dask.compute(*tasks, scheduler=compute_with)
                for idx, values in zip(batch, results, strict=True):
                    sl = _region(offsets, idx)
                    with ncio.locked():
                        for target, value in zip(targets, values, strict=True):
                            target[sl] = np.asarray(value)
                    if checksums is not None:
                        for name, value in zip(group, values, strict=True):
                            checksums.add(name, np.asarray(value), [s.start for s in sl])
                    bar()
