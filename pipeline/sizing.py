"""Sizes from the plan, before anything computes: will the results fit on the output disk and
the working arrays in memory?

For every stage about to compute, the estimate multiplies the sizes of the result's dimensions:
the scene's sweep dimensions the stage spans (from the keys it and its upstream stages read,
e.g. ``load.p``, ``interface.eta``, ``substrate.hrms``) and the dimensions it adds itself (from
the :class:`~roughcontact.stage.Shape` its ``describe`` returns, e.g. the q grid of
``numerics.points_per_decade`` or the stress grid of ``numerics.sigma_points``). One generic
place, from the shape's data:

* result bytes: 8 bytes per value of every output variable over the dimensions it spans (all,
  but those the shape's ``lacks`` names; stored uncompressed: an upper bound);
* working bytes: :func:`point_bytes` (8 bytes times the shape's ``work`` factors: the working
  memory per point of the sweep) times the points of one block of the computation (the chunk
  sizes along the dimensions the stage chunks, the whole length along the others and along the
  ones the shape says the computation ``coupled``) times the blocks in flight at once.

A scene whose results exceed the free space of the output disk, or one block of whose
computation exceeds the memory available, is refused with a :class:`~roughcontact.errors.UserError`
naming the keys that set the sizes; chunking (``[numerics] chunks``/``chunk_mb``) bounds the
working memory of sweeps, never a single point's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import UserError
from .machine import VALUE_BYTES, available_memory, free_disk, human


@dataclass
class Estimate:
    """The size of one stage's result and of one block of its computation."""

    label: str
    path: Path
    result: int
    working: int
    dims: dict  # dimension -> (size, scene key, size per block)
    parallel: int = 1  # blocks computed at once
    #: where the shape names the scene keys of its ``work`` factors: those, then the keys of the sweep
    #: dimensions a block is chunked along (what sets the working memory, named when a block does not fit)
    work_keys: tuple = ()
    work_text: str = ""  # the named work factors, e.g. "pixels 6.71e+07 (bem.grid)"

    def describe(self, per_block: bool = False) -> str:
        parts = []
        if per_block and self.work_text:  # what sets the working memory: the work factors, the chunked dimensions
            return "; ".join([self.work_text] + [f"{d} {b:g} ({k}) per block" for d, (n, k, b) in self.dims.items()
                                                 if k in self.work_keys and d not in self.work_text])
        for dim, (size, key, block) in sorted(self.dims.items(), key=lambda kv: -kv[1][0]):
            n = block if per_block else size
            parts.append(f"{dim} {n:g}" + (f" ({key})" if key else "")
                         + (" per block" if per_block and block < size else ""))
        return " x ".join(parts) or "no dimensions"

    def keys(self, per_block: bool = False) -> list[str]:
        """The scene keys of the dimensions longer than 1 (per block of the computation), longest first."""
        order = sorted(self.dims.values(), key=lambda v: -(v[2] if per_block else v[0]))
        return list(dict.fromkeys(key for size, key, block in order if key and (block if per_block else size) > 1))

    def memory_keys(self) -> list[str]:
        """The scene keys to reduce when one block does not fit in memory."""
        return list(dict.fromkeys(self.work_keys)) or self.keys(per_block=True)


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
    for dotted in st.keys:
        section, _, key = dotted.partition(".")
        sec, values = schema.get(section), scene.values.get(section)
        if sec is None or not isinstance(values, dict):
            continue
        for p in sec.params_for(values.get(sec.discriminator) if sec.discriminator else None):
            v = values.get(p.name)
            if (not key or p.name == key) and p.kind == "sweep" and isinstance(v, np.ndarray) and v.ndim == 1:
                out[(p.dim or p.name).format(section=section)] = int(v.size)
    return out


def spanned_dims(scene, st, upstream) -> dict[str, int]:
    """The scene's sweep dimensions a stage's result spans: those of the keys it reads and those
    its upstream results span (``upstream``: their shapes or datasets, None where unknown)."""
    sweeps = scene.sweep_sizes()
    out: dict[str, int] = {}
    for shape in upstream:
        out.update({d: n for d, n in (shape.sizes.items() if shape is not None else ()) if d in sweeps})
    return {**out, **own_sweep_dims(scene, st)}


def point_bytes(shape, outputs: int, sweeps) -> int:
    """Working memory of one point of the sweep (bytes): 8 bytes times the product of the
    shape's ``work`` factors, or, where the stage declares none, four temporaries of every output
    value over the dimensions the stage adds (those of ``shape`` that are not among the scene's
    ``sweeps``)."""
    if shape.work:
        return int(VALUE_BYTES * math.prod(shape.work.values()))
    return 4 * VALUE_BYTES * max(outputs, 1) * math.prod(int(n) for d, n in shape.sizes.items() if d not in sweeps)


def outputs_asked(st, wanted) -> list[str]:
    """The output variables the stage writes for a scene (optional ones only when asked for)."""
    return [name for name, var in st.outputs.items() if not var.optional or name in wanted]


def stage_chunks(scene, st, wanted, shape, spanned: dict[str, int]) -> dict[str, int]:
    """Chunk sizes for the sweep dimensions the stage's result spans (``spanned``:
    :func:`spanned_dims`): the scene's explicit ones, the others chosen so that a chunk's working
    memory (:func:`point_bytes` of the stage's shape) stays near chunk_mb; the dimensions the
    computation couples are never chunked. A sweep dimension the result does not span (the
    pressures, for the psd stage) takes no share of the budget."""
    from .scheduling import auto_chunks

    sizes = {d: n for d, n in scene.sweep_sizes().items() if d in spanned}
    per_point = point_bytes(shape, len(outputs_asked(st, wanted)), sizes)
    budget = scene.chunk_mb * 2**20 / max(per_point, 8)
    whole = [dim for dim in shape.coupled if dim in sizes]  # one chunk along these, whatever the scene says
    for dim in whole:
        budget /= sizes[dim]
    return auto_chunks({d: n for d, n in sizes.items() if d not in whole}, budget,
                       {d: n for d, n in scene.chunks.items() if d not in whole})


def result_bytes(st, wanted, sizes: dict[str, int], lacks) -> int:
    """Bytes of the stored result: every output asked for, and every other output or coordinate of
    the stage that ``lacks`` names (written with them; a coordinate over more than its own
    dimension, such as a stress grid per point), over the
    dimensions it spans (all of ``sizes`` but those ``lacks`` names), plus the 1-D coordinates and
    the scalars."""
    asked = outputs_asked(st, wanted)
    names = asked + [name for name in {**st.outputs, **st.coords} if name in lacks and name not in asked]
    values = sum(math.prod(n for d, n in sizes.items() if d not in lacks.get(name, ())) for name in names)
    return VALUE_BYTES * (values + sum(sizes.values()) + len(names))


def estimate(plan, scene, spanned: dict[str, int], own, in_flight: int, lazy: frozenset = frozenset()) -> Estimate:
    """The estimate for one stage plan: ``spanned`` are its sweep dimensions (its own and its
    upstream stages'), ``own`` the shape its describe returned (the dimensions it adds), ``lazy``
    the dimensions of upstream results too large to be loaded (they arrive in chunks)."""
    st = plan.stage
    keys = sweep_keys()
    own_sizes = {d: n for d, n in own.sizes.items() if d not in spanned}
    sizes = {**spanned, **own_sizes}
    result = result_bytes(st, plan.wanted, sizes, own.lacks)
    per_point = point_bytes(own, len(outputs_asked(st, plan.wanted)), spanned)
    chunked = (set(own_sweep_dims(scene, st)) | set(lazy)) - set(own.coupled) - set(own_sizes)
    chunks = stage_chunks(scene, st, plan.wanted, own, spanned)
    block = {d: (min(chunks.get(d, n), n) if d in chunked else n) for d, n in spanned.items()}
    blocks = math.prod(math.ceil(n / block[d]) for d, n in spanned.items())
    parallel = min(in_flight, blocks)
    working = per_point * math.prod(block.values()) * parallel
    dims = {d: (n, own.keys.get(d) or keys.get(d, ""), block.get(d, n)) for d, n in sizes.items()}
    named = {f: n for f, n in own.work.items() if f in own.keys and n > 1}
    text = " x ".join(f"{f} {n:.3g} ({own.keys[f]})" for f, n in named.items())
    work_keys = [own.keys[f] for f in named] + [dims[d][1] for d in spanned if named and dims[d][1] and d in chunked
                                                 and block[d] > 1]
    return Estimate(plan.label, plan.path, result, working, dims, parallel, tuple(work_keys), text)


def check(estimates: list[Estimate], outdir: Path | None) -> None:
    """Refuse a plan whose results exceed the output disk (``outdir`` None: the memory, where they
    are then held) or one of whose blocks exceeds memory."""
    memory = available_memory()
    for e in estimates:
        if e.working > memory:
            keys = e.memory_keys()
            raise UserError(
                f"stage {e.label} would need about {human(e.working)} of memory at once ("
                + f"{e.describe(per_block=True)}"
                + (f"; {e.parallel} blocks at a time" if e.parallel > 1 else "") + f") but this machine has "
                f"{human(memory)} available: reduce "
                f"{', '.join(keys) or 'the sizes'} (chunking bounds the memory of sweeps, not of a single point)",
                key=keys[0].split(" ")[0] if keys else None)
    total = sum(e.result for e in estimates)
    if outdir is None and total > memory:
        big = max(estimates, key=lambda e: e.result)
        keys = big.keys()
        raise UserError(
            f"the results would take about {human(total)} of memory ({big.label}: {human(big.result)}, "
            f"{big.describe()}) but this machine has {human(memory)} available: reduce "
            f"{', '.join(keys) or 'the sweeps'} or write them to files (run)",
            key=keys[0].split(" ")[0] if keys else None)
    if outdir is None:
        return
    free = free_disk(outdir)
    if total > free:
        big = max(estimates, key=lambda e: e.result)
        keys = big.keys()
        raise UserError(
            f"the results would take about {human(total)} on disk ({big.path.name}: {human(big.result)}, "
            f"{big.describe()}) but {outdir} has {human(free)} free: reduce {', '.join(keys) or 'the sweeps'} "
            "or write elsewhere (--outdir)", key=keys[0].split(" ")[0] if keys else None)
