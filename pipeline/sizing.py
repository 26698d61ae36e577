"""Sizes from the plan, before anything computes: will the results fit on the output disk and
the working arrays in memory?

For every stage about to compute, the estimate multiplies the sizes of the result's dimensions:
the scene's sweep dimensions the stage spans (from the keys it and its upstream stages read,
e.g. ``load.p``, ``interface.eta``, ``substrate.hrms``) and the dimensions it adds itself (from
the :class:`~roughcontact.stage.Preview` its ``validate`` hook returns, e.g. the q grid of
``numerics.points_per_decade`` or the stress grid of ``numerics.sigma_points``).

* result bytes: the stage's ``result_bytes`` hook, or 8 bytes per output variable over every
  dimension (an upper bound; stored uncompressed);
* working bytes: the stage's ``point_bytes`` (its working memory per point of the sweep)
  times the points of one block of the computation (the chunk sizes along the dimensions the
  stage chunks, the whole length along the others) times the blocks in flight at once.

A scene whose results exceed the free space of the output disk, or one block of whose
computation exceeds the memory available, is refused with a :class:`~roughcontact.errors.UserError`
naming the keys that set the sizes; chunking (``[numerics] chunks``/``chunk_mb``) bounds the
working memory of sweeps, never a single point's.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import UserError

#: bytes per value of the results (float64)
VALUE_BYTES = 8


def available_memory() -> int:
    """Bytes of memory available to this process: MemAvailable, capped by a cgroup limit."""
    avail = None
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            avail = 2**40  # unknown: do not refuse on memory
    for limit_file, usage_file in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                                   ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                                    "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            limit = Path(limit_file).read_text().strip()
            used = int(Path(usage_file).read_text().strip())
        except (OSError, ValueError):
            continue
        if limit.isdigit() and int(limit) < 2**60:
            avail = min(avail, max(int(limit) - used, 0))
        break
    return int(avail)


def free_disk(path: Path) -> int:
    """Free bytes on the file system that holds ``path`` (or its nearest existing folder)."""
    path = Path(path).absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    try:
        return int(shutil.disk_usage(path).free)
    except OSError:
        return 2**62


def human(nbytes: float) -> str:
    """1.5 GB, 340 MB, 12 kB, ... (powers of 1000)."""
    for unit, scale in (("PB", 1e15), ("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{int(nbytes)} B"


def check_sweep_length(num: int, key: str) -> None:
    """Refuse a range whose values alone would take a quarter of the memory available."""
    need = num * VALUE_BYTES
    avail = available_memory()
    if need * 4 > avail:
        raise UserError(f"{num:.3g} values need {human(need)} just to be held, and every result over them far more; "
                        f"this machine has {human(avail)} of memory available: use fewer points", key=key)


@dataclass
class Estimate:
    """The size of one stage's result and of one block of its computation."""

    label: str
    path: Path
    result: int
    working: int
    dims: dict  # dimension -> (size, scene key, size per block)
    parallel: int = 1  # blocks computed at once

    def describe(self, per_block: bool = False) -> str:
        parts = []
        for dim, (size, key, block) in sorted(self.dims.items(), key=lambda kv: -kv[1][0]):
            n = block if per_block else size
            parts.append(f"{dim} {n:g}" + (f" ({key})" if key else "") + (" per block" if per_block and block < size else ""))
        return " x ".join(parts) or "no dimensions"

    def keys(self, per_block: bool = False) -> list[str]:
        """The scene keys of the dimensions longer than 1 (per block of the computation), longest first."""
        order = sorted(self.dims.values(), key=lambda v: -(v[2] if per_block else v[0]))
        return [key for size, key, block in order if key and (block if per_block else size) > 1]


def sweep_keys() -> dict[str, str]:
    """Sweep dimension -> the scene key that defines it (``hrms_substrate`` -> ``substrate.hrms``)."""
    from .stage import sections

    out = {}
    for name, section in sections().items():
        params = list(section.params) + [p for ps in section.variants.values() for p in ps]
        for p in params:
            if p.kind == "sweep":
                out[(p.dim or p.name).format(section=name)] = f"{name}.{p.name}"
    return out


def own_sweep_dims(scene, st) -> dict[str, int]:
    """The scene's sweep dimensions defined by the keys the stage itself reads."""
    from .stage import sections

    out: dict[str, int] = {}
    schema = sections()
    for dotted in st.params:
        section, _, key = dotted.partition(".")
        sec, values = schema.get(section), scene.values.get(section)
        if sec is None or not isinstance(values, dict):
            continue
        for p in sec.params_for(values.get(sec.discriminator) if sec.discriminator else None):
            v = values.get(p.name)
            if (not key or p.name == key) and p.kind == "sweep" and isinstance(v, np.ndarray) and v.ndim == 1:
                out[(p.dim or p.name).format(section=section)] = int(v.size)
    return out


def estimate(plan, scene, spanned: dict[str, int], own, upstream: dict, in_flight: int,
             lazy: frozenset = frozenset()) -> Estimate:
    """The estimate for one stage plan: ``spanned`` are its sweep dimensions (its own and its
    upstream stages'), ``own`` the Preview its validate returned (or None), ``upstream`` the
    previews of its upstream results, ``lazy`` the dimensions of upstream results too large to be
    loaded (they arrive in chunks)."""
    from .engine import stage_chunks

    st = plan.stage
    keys = sweep_keys()
    own_sizes = {d: n for d, n in (own.sizes.items() if own is not None else ()) if d not in spanned}
    n_vars = sum(1 for name, var in st.outputs.items() if not var.optional or name in plan.wanted)
    sizes = {**spanned, **own_sizes}
    if st.result_bytes is not None:
        result = int(st.result_bytes(plan.params, plan.wanted, sizes))
    else:
        result = VALUE_BYTES * max(n_vars, 1) * math.prod(sizes.values())
    result += VALUE_BYTES * (sum(sizes.values()) + n_vars)  # the coordinates, and scalars
    hooks_upstream = {**upstream, **({st.name: own} if own is not None else {})}
    if st.point_bytes is not None:
        per_point = int(st.point_bytes(plan.params, plan.wanted, hooks_upstream))
    else:
        per_point = 4 * VALUE_BYTES * max(n_vars, 1) * math.prod(own_sizes.values())
    chunked = (set(own_sweep_dims(scene, st)) | set(lazy)) - set(st.unchunked) - set(own_sizes)
    chunks = stage_chunks(scene, st, plan.params, plan.wanted, hooks_upstream)
    block = {d: (min(chunks.get(d, n), n) if d in chunked else n) for d, n in spanned.items()}
    blocks = math.prod(math.ceil(n / block[d]) for d, n in spanned.items())
    parallel = min(in_flight, blocks)
    working = per_point * math.prod(block.values()) * parallel
    own_keys = own.keys if own is not None else {}
    dims = {d: (n, own_keys.get(d) or keys.get(d, ""), block.get(d, n)) for d, n in sizes.items()}
    return Estimate(plan.label, plan.path, result, working, dims, parallel)


def check(estimates: list[Estimate], outdir: Path) -> None:
    """Refuse a plan whose results exceed the output disk or one of whose blocks exceeds memory."""
    memory = available_memory()
    for e in estimates:
        if e.working > memory:
            keys = e.keys(per_block=True)
            raise UserError(
                f"stage {e.label} would need about {human(e.working)} of memory at once ({e.describe(per_block=True)}"
                + (f"; {e.parallel} blocks at a time" if e.parallel > 1 else "") + f") but this machine has "
                f"{human(memory)} available: reduce "
                f"{', '.join(keys) or 'the sizes'} (chunking bounds the memory of sweeps, not of a single point)",
                key=keys[0].split(" ")[0] if keys else None)
    total = sum(e.result for e in estimates)
    free = free_disk(outdir)
    if total > free:
        big = max(estimates, key=lambda e: e.result)
        keys = big.keys()
        raise UserError(
            f"the results would take about {human(total)} on disk ({big.path.name}: {human(big.result)}, "
            f"{big.describe()}) but {outdir} has {human(free)} free: reduce {', '.join(keys) or 'the sweeps'} "
            "or write elsewhere (--outdir)", key=keys[0].split(" ")[0] if keys else None)
