"""Chunking and scheduling: how a result's blocks are cut and where they are computed.

* :func:`auto_chunks` picks dask chunk sizes for a scene's sweep dimensions so that one chunk's
  working memory stays near a budget (explicit sizes from the scene win).
* :func:`scheduler` turns the scene's / command line's scheduler setting into something dask
  can compute with: 'threads', 'processes', 'synchronous' or a dask.distributed client.
* :func:`computed_blocks` computes the blocks of a result on that scheduler, a bounded number
  in flight (a sweep never has to fit in memory), and hands them to the writer of this process
  (:mod:`roughcontact.writing`), computing the next ones meanwhile: no worker ever writes to the file.
* :func:`quiet_libraries`: dask's warnings about chunks and graphs (the engine's choices, nothing
  the user can act on) kept out of the user's output.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import warnings
from typing import Iterator, Mapping

import xarray as xr

from .errors import UserError


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


def resources(compute_with) -> tuple[object, object, int]:
    """``(client, pool, workers)`` of what :func:`scheduler` yields: the distributed Client or None,
    the process pool or None, and how many blocks can be computed at once."""
    from concurrent.futures import Executor

    import dask

    pool = compute_with if isinstance(compute_with, Executor) else None
    client = compute_with if not isinstance(compute_with, str) and pool is None else None
    workers = len(client.scheduler_info()["workers"]) if client is not None else (dask.system.CPU_COUNT or 2)
    return client, pool, workers


def computed_blocks(tasks, compute_with, in_flight: int | None = None, one_by_one: bool = False, finish=None):
    """Yield ``(idx, values)`` for every ``(idx, task)`` of ``tasks`` (a task: the list of dask objects
    of one block; ``tasks`` is read lazily).

    ``one_by_one``: every block computed on its own graph, several at a time, yielded as each
    finishes (:class:`roughcontact.writing.KeptBlocks`: long blocks, each kept as it arrives).
    Otherwise ``in_flight`` blocks at a time are computed together (work they share is done once)
    and yielded in order, ``finish(idx, values)`` (if given) applied to each in threads, what it
    returns yielded instead of the values; the next batch is computed in the background while the
    caller handles the blocks of this one (writing overlaps computing)."""
    client, pool, workers = resources(compute_with)
    if one_by_one:
        return _as_completed(dict(tasks), compute_with, client, pool, workers)
    if in_flight is None:
        in_flight = max(2, 2 * workers)
    return _ahead(_in_batches(tasks, compute_with, client, pool, in_flight, finish, workers))


def _in_batches(tasks, compute_with, client, pool, in_flight: int, finish=None, workers: int = 2):
    """Yield the list of ``(idx, values)`` of every ``in_flight`` blocks of ``tasks``, computed
    together (then ``finish``-ed, in ``workers`` threads)."""
    import dask

    todo = iter(tasks)
    threads = None
    try:
        while batch := list(itertools.islice(todo, in_flight)):
            work = [task for _, task in batch]
            if client is not None:
                results = client.gather(client.compute(work))
            elif pool is not None:
                results = dask.compute(*work, scheduler="processes", pool=pool)
            else:
                results = dask.compute(*work, scheduler=compute_with)
            indices = [idx for idx, _ in batch]
            if finish is not None:
                if threads is None:
                    from concurrent.futures import ThreadPoolExecutor

                    threads = ThreadPoolExecutor(max(1, workers), thread_name_prefix="roughcontact-finish")
                results = list(threads.map(finish, indices, results))
            yield list(zip(indices, results, strict=True))
    finally:
        if threads is not None:
            threads.shutdown(wait=False, cancel_futures=True)


def _ahead(batches):
    """Yield the items of the batches of the generator ``batches``, the next batch made in a
    background thread meanwhile (never more than that one: two batches in memory at most). When
    the caller stops (an error, an interrupt), no batch is started after the one being made
    (which finishes on its own, its values dropped)."""
    import queue
    import threading

    ready: queue.Queue = queue.Queue()
    turn = threading.Semaphore(1)  # the producer may make one batch beyond the caller's
    stop = threading.Event()

    def make():
        try:
            while True:
                turn.acquire()
                if stop.is_set():
                    return
                batch = next(batches, None)
                ready.put((batch, None))
                if batch is None:
                    return
        except BaseException as exc:  # handed to the caller, raised there
            ready.put((None, exc))

    thread = threading.Thread(target=make, name="roughcontact-batches", daemon=True)
    thread.start()
    try:
        while True:
            batch, error = ready.get()
            if error is not None:
                raise error
            if batch is None:
                return
            turn.release()
            yield from batch
    finally:
        stop.set()
        turn.release()
