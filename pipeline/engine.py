"""Planning and running the stage graph for a scene.

For each scene (and each of its variants) the engine selects the stages that the requested
outputs need, computes each stage's content key, compares it with the key stored in the
existing result, and computes only what is missing or stale, upstream first.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

import numpy as np
import xarray as xr

from . import integrity, preflight, reuse, sizing, store
from .errors import UserError
from .progress import Reporter
from .results import StageResults
from .scene import Scene, units_of
from .schema import MISSING, did_you_mean
from .stage import Shape, Stage, StageInput, coords, producer_of, stages
from .units import display


@dataclass
class StagePlan:
    """What the engine will do with one stage of one scene variant."""

    stage: Stage
    variant: str
    path: Path
    key: str
    record: dict
    status: str  # "fresh" | "stale" | "missing"
    reasons: list[str] = field(default_factory=list)
    wanted: frozenset[str] = frozenset()
    params: dict = field(default_factory=dict)
    file_paths: dict = field(default_factory=dict)
    inputs: list[dict] = field(default_factory=list)
    scene_label: str = ""
    #: an identical result (same key) to put in place instead of computing: a kept result of
    #: the output folder or the result of an earlier stage of the run (see roughcontact.reuse)
    source: Path | None = None

    @property
    def label(self) -> str:
        return self.stage.name if self.variant == "base" else f"{self.stage.name} [{self.variant}]"


def needed_stages(scene: Scene, targets: Iterable[str]) -> list[Stage]:
    """Stages needed for ``targets`` (variables or stage names), upstream first."""
    registry = stages()
    order: list[Stage] = []
    seen: set[str] = set()

    def visit(st: Stage, trail: tuple[str, ...]):
        if st.name in trail:
            raise RuntimeError(f"stage cycle: {' -> '.join(trail + (st.name,))}")
        if st.name in seen:
            return
        for up in st.upstream_for(scene.values):
            visit(registry[up], trail + (st.name,))
        seen.add(st.name)
        order.append(st)

    for target in targets:
        visit(producer_of(target), ())
    return order


def result_path(outdir: Path, variant: str, stage: str) -> Path:
    return outdir / (f"{stage}.nc" if variant == "base" else f"variants/{variant}/{stage}.nc")


#: the folder named in the plans of a computation in memory (nothing is written there)
IN_MEMORY = Path("(in memory)")


def default_outdir(scene: Scene) -> Path:
    return Path("outputs") / scene.name


def plan(scene: Scene, outdir: Path, targets: Iterable[str] | None = None, force: Iterable[str] = (),
         verify: bool | None = None) -> list[StagePlan]:
    """Plan every needed stage of the scene and of each of its variants.

    A stored result with the right key is fresh if its data still match their checksum
    (:mod:`roughcontact.integrity`), checked for files up to ``integrity.VERIFY_LIMIT_BYTES``
    (``verify`` None), for every file (True) or for none (False).

    ``outdir`` None plans a computation in memory (:func:`compute`): every stage is to compute,
    nothing stored is looked at or reused, and each ``path`` only names the stage (under
    :data:`IN_MEMORY`)."""
    memory = outdir is None
    scene, outdir, targets, force = preflight.arguments(scene, IN_MEMORY if memory else outdir, targets, force)
    targets = tuple(targets) if targets is not None else scene.outputs
    for name in sorted(force - set(stages()) - {"all"}):
        raise UserError(f"no stage {name!r}{did_you_mean(name, sorted(stages()))}", key="--force")
    plans: list[StagePlan] = []
    earlier: dict[str, Path] = {}  # key -> where the run will have that result
    for variant, sc in (("base", scene), *scene.variants.items()):
        keys: dict[str, str] = {}
        for st in needed_stages(sc, targets):
            p = _plan_stage(sc, variant, st, outdir, keys, targets, force, verify, stored=not memory)
            keys[st.name] = p.key
            if not memory and p.status != "fresh" and not force & {st.name, "all"}:
                _find_identical(p, earlier, outdir)
            earlier.setdefault(p.key, p.path)
            plans.append(p)
    used = list(dict.fromkeys(p.stage.name for p in plans))
    for name in sorted(force - set(used) - {"all"}):
        raise UserError(f"the scene does not use stage {name!r} (it runs {', '.join(used)})", key="--force")
    return plans


def _find_identical(p: StagePlan, earlier: dict[str, Path], outdir: Path) -> None:
    """Where the run can take ``p``'s result from without computing it, said in its reasons."""
    if p.key in earlier:
        p.source = earlier[p.key]
        p.reasons.append(f"identical to {p.source}")
    elif (kept := reuse.stored(outdir, p.key)) is not None:
        p.source = kept
        p.reasons.append("an identical result of an earlier run is kept")


def _plan_stage(scene, variant, st, outdir, keys, targets, force, verify=None, stored=True) -> StagePlan:
    params = {name: st.section_view(name, scene.get(name)) for name in st.keys}
    absent = [name for name, value in params.items() if value is MISSING]
    if absent:
        raise UserError(f"missing required key (stage {st.name} needs it)", key=absent[0])
    file_paths, inputs = {}, []
    for f in st.files:
        value = _dotted(scene, f.param)
        if value is None:
            continue
        if isinstance(value, (list, tuple)):  # a `paths` parameter: several files, read one by one
            file_paths[f.param] = tuple(Path(v) for v in value)
            inputs += [reuse.input_entry(f"{f.param}[{i}]", v, scene.path, f.param) for i, v in enumerate(value)]
            continue
        file_paths[f.param] = Path(value)
        inputs.append(reuse.input_entry(f.param, value, scene.path, f.param))
    upstream = {up: keys[up] for up in st.upstream_for(scene.values)}
    wanted = frozenset(t for t in targets if t in st.outputs and st.outputs[t].optional)
    record = {
        "stage": st.name,
        "version": st.version,
        "parameters": reuse.key_parameters(params),  # file paths out: their hashes are the inputs
        "upstream": upstream,
        "inputs": {i["param"]: i["sha256"] for i in inputs},
        "optional_outputs": sorted(wanted),
    }
    key = store.content_key(record)
    record["paths"] = {i["param"]: i["path"] for i in inputs}  # for messages only: not part of the key
    path = result_path(outdir, variant, st.name)
    if not stored:  # computed in memory: nothing stored is looked at
        return StagePlan(st, variant, path, key, record, "missing", ["computed in memory"], wanted, params,
                         file_paths, inputs, scene.label)
    if path.exists() and not path.is_file():
        raise UserError(f"is not a file, but the result of stage {st.name} goes there: move it away", file=str(path))
    stored = store.read_attrs(path)
    if stored is None:
        status, reasons = "missing", ["no result yet" if not path.exists() else "existing file is unreadable"]
    elif stored.get("stage_key") == key and st.name not in force and "all" not in force:
        damage = integrity.damage(path, verify)
        status, reasons = ("stale", [damage]) if damage else ("fresh", [])
    else:
        status = "stale"
        reasons = _why_stale(stored, record) if stored.get("stage_key") != key else ["forced"]
    return StagePlan(st, variant, path, key, record, status, reasons, wanted, params, file_paths, inputs, scene.label)


def _dotted(scene: Scene, dotted: str):
    section, _, rest = dotted.partition(".")
    value = scene.values.get(section)
    for part in rest.split(".") if rest else ():
        if not isinstance(value, dict):
            return None
        value = value.get(part)
    return value


def _why_stale(stored: dict, record: dict) -> list[str]:
    import json

    reasons = []
    if stored.get("stage_version") != record["version"]:
        reasons.append(f"stage version {stored.get('stage_version')} -> {record['version']}")
    try:
        old_params = json.loads(stored.get("parameters", "{}"))
        old_up = json.loads(stored.get("upstream_keys", "{}"))
        old_inputs = {i["param"]: i["sha256"] for i in json.loads(stored.get("input_files", "[]"))}
        old_optional = json.loads(stored.get("optional_outputs", "[]"))
    except (ValueError, TypeError, KeyError):
        return ["stored provenance unreadable"]
    new_params = store.canonical(record["parameters"])
    for name in sorted(set(old_params) | set(new_params)):
        if old_params.get(name) != new_params.get(name):
            reasons.extend(_param_diff(name, old_params.get(name), new_params.get(name)))
    for name in sorted(set(old_up) | set(record["upstream"])):
        if old_up.get(name) != record["upstream"].get(name):
            reasons.append(f"upstream stage {name} changed")
    for name in sorted(set(old_inputs) | set(record["inputs"])):
        if old_inputs.get(name) != record["inputs"].get(name):
            shown = record.get("paths", {}).get(name)
            reasons.append(f"input file {name}{f' ({shown})' if shown else ''} changed (sha256)")
    if sorted(old_optional) != record["optional_outputs"]:
        reasons.append(f"optional outputs {old_optional} -> {record['optional_outputs']}")
    return reasons or ["key differs"]


def _param_diff(name, old, new) -> list[str]:
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new)):
            if old.get(k) != new.get(k):
                out.extend(_param_diff(f"{name}.{k}", old.get(k), new.get(k)))
        return out
    units = units_of(name)
    return [f"{name}: {_short(old, units)} -> {_short(new, units)}"]


def _short(value, units=None) -> str:
    text = display(value, units) if value is not None else "(not set)"
    return text if len(text) <= 60 else text[:57] + "..."


def _finish(ds: xr.Dataset, p: StagePlan) -> xr.Dataset:
    """Stamp the declared units and long names on every variable and coordinate, refuse what a
    stage labelled itself or did not declare, and add provenance."""
    st = p.stage
    declared = {**coords(), **st.coords, **st.outputs}
    undeclared = [v for v in ds.data_vars if v not in st.outputs]
    if undeclared:
        raise RuntimeError(f"stage {st.name} returned undeclared variable(s) {undeclared} (a bug in the stage)")
    for name in ds.variables:
        if name not in declared:
            raise RuntimeError(f"stage {st.name} returned coordinate {name!r} that nothing declares "
                               "(a bug in the stage)")
        stamp = declared[name].stamp()
        attrs = ds[name].attrs
        own = [a for a in ("units", "long_name", "standard_name") if a in attrs and attrs[a] != stamp.get(a)]
        if own and name in ds.data_vars:
            raise RuntimeError(f"stage {st.name} labels {name!r} itself ({', '.join(own)}); units and long names "
                               "are declared once, in its Var (a bug in the stage)")
        for a in ("units", "long_name", "standard_name"):
            attrs.pop(a, None)
        attrs.update(stamp)
    extra = dict(ds.attrs)
    ds.attrs = {**extra, **store.provenance_attrs(
        stage=st.name, version=st.version, key=p.key, parameters=p.record["parameters"], upstream=p.record["upstream"],
        inputs=p.inputs, optional=list(p.wanted), scene=p.scene_label, variant=p.variant)}
    return ds


#: results larger than this many bytes are handed downstream lazily (dask-backed), not loaded
LOAD_LIMIT_BYTES = preflight.LOAD_LIMIT_BYTES


def run(scene: Scene, outdir: Path, targets: Iterable[str] | None = None, force: Iterable[str] = (),
        report: Reporter | None = None, scheduler: str | None = None,
        open_results: bool = True, lock_timeout: float | None = None,
        verify: bool | None = None) -> dict[str, StageResults]:
    """Bring every needed stage up to date; return ``results[variant][stage]``.

    With ``open_results`` every result is opened before this returns (in memory if small, so that
    it outlives its file); False opens each only when first read (the command line reads none).

    ``scheduler`` overrides the scene's ``[run] scheduler`` ('threads', 'processes',
    'synchronous' or a dask.distributed address). Small results are returned in memory, large
    ones lazily. The run holds the output folder's lock (:mod:`roughcontact.preflight`); another
    run on the same folder waits for it (at most ``lock_timeout`` seconds, None: until it ends).
    ``verify``: check the checksums of reused results of every size (see :func:`plan`).
    """
    from .scheduling import scheduler as open_scheduler

    scene, outdir, targets, force = preflight.arguments(scene, outdir, targets, force)
    report = report or Reporter()
    # every check before anything is written, the output folder and its lock included: a refused
    # run leaves no trace (the plan is made again under the lock; checked again only if it changed)
    preflight.not_a_file(outdir)
    unlocked = plan(scene, outdir, targets, force, verify=False)
    checked = preflight.check(unlocked, {"base": scene, **scene.variants}, outdir)
    outdir = preflight.output_folder(outdir)
    scheduled = open_scheduler(scheduler or scene.get("run.scheduler"))
    with preflight.locked(outdir, report, lock_timeout), scheduled as compute_with:
        results = _run(scene, outdir, targets, force, report, compute_with, verify, (unlocked, checked))
    for by_stage in results.values() if open_results else ():
        by_stage.open_all()
    return results


def _plan_facts(plans: list[StagePlan]) -> list[tuple]:
    """What decides the preflight's verdict on a plan: per stage, its key, status and source."""
    return [(p.variant, p.stage.name, p.key, p.status, p.source) for p in plans]


def _prepared(scene, outdir, targets, force, report, verify=None, checked=None):
    """Plan the stages and run the preflight (every input file read, every check, every size)
    before anything computes or is written; the notes go to the reporter. ``outdir`` None: in
    memory (:func:`compute`). ``checked``: (plans, preflight verdict) of a check already made
    before the output folder was locked, reused when the plan has not changed since."""
    plans = plan(scene, outdir, targets, force, verify)
    scenes = {"base": scene, **scene.variants}
    if checked is not None and _plan_facts(checked[0]) == _plan_facts(plans):
        files, shapes = checked[1]
    else:
        files, shapes = preflight.check(plans, scenes, outdir)
    differing = set(_differing(plans, shapes))
    for note in notes(plans, shapes):  # on a terminal; `plan` prints them always, and so does `run` where they differ
        (report if note in differing else report.live)(f"note: {note}")
    return plans, scenes, files, shapes


def _differing(plans: list[StagePlan], shapes) -> list[str]:
    """The notes of a stage that differ between the scene and its variants (e.g. another
    reference wavenumber of zeta): what the user must know even off a terminal."""
    by_stage: dict[str, dict[str, str]] = {}
    for p in plans:
        shape = shapes.get((p.variant, p.stage.name))
        if shape is not None and shape.attrs.get("note"):
            by_stage.setdefault(p.stage.name, {})[p.label] = shape.attrs["note"]
    return [f"{label}: {note}" for per in by_stage.values() if len(set(per.values())) > 1
            for label, note in per.items()]


def _computed(p: StagePlan, scene: Scene, upstream, files: dict, shape: Shape, report: Reporter) -> xr.Dataset:
    """One stage's result for plan ``p``: its compute on its keys, files and upstream results,
    checked against its describe (:func:`conforms`), stamped with units and provenance (:func:`_finish`)."""
    from .scheduling import chunk_sweeps

    sweeps = scene.sweep_sizes()
    spanned = {d: n for d, n in shape.sizes.items() if d in sweeps}  # the preflight's: shape has the dims spanned
    chunks = sizing.stage_chunks(scene, p.stage, p.wanted, shape, spanned)
    inp = StageInput(
        params=p.params,
        upstream=chunk_sweeps(upstream, chunks),  # a sweep made upstream (eta, draw) splits this stage's work too
        files=files,
        wanted=p.wanted,
        chunks=chunks,
        stage=p.stage.name,
        shape=shape,
        reporter=report,
    )
    with xr.set_options(keep_attrs=False):  # a variable's units come from its declaration, never by inheritance
        computed = p.stage.compute(inp)
    conforms(computed, shape, p.label)
    return _finish(computed, p)


def _run(scene, outdir, targets, force, report, compute_with, verify=None, checked=None):
    from .scheduling import quiet_libraries

    store.clean_temporaries(outdir)
    plans, scenes, files, shapes = _prepared(scene, outdir, targets, force, report, verify, checked)
    for folder in {p.path.parent for p in plans}:
        store.clean_temporaries(folder)
    results = {v: StageResults(_open) for v in scenes}  # each result opened when first read
    handed: dict[tuple[str, str], xr.Dataset] = {}  # results computed in memory here, handed downstream as they are
    n = len(plans)
    for i, p in enumerate(plans, start=1):
        tag = f"[{i}/{n}] {p.label}"
        if p.status == "fresh":
            report(f"{tag}: up to date ({p.path})")
            results[p.variant].add(p.stage.name, p.path)
            continue
        if p.source is not None:
            reuse.place(p.source, p.path, outdir)
            report(f"{tag}: reused, not recomputed ({'; '.join(p.reasons)}) -> {p.path}")
            results[p.variant].add(p.stage.name, p.path)
            continue
        why = "; ".join(p.reasons)
        report.live(f"{tag}: computing ({why})")
        t0 = time.perf_counter()
        upstream = {up: handed[(p.variant, up)] if (p.variant, up) in handed else results[p.variant][up]
                    for up in p.record["upstream"]}
        shape = shapes[(p.variant, p.stage.name)]
        with quiet_libraries():  # dask's notes on chunks and graphs: the engine's business, not the user's
            ds = _computed(p, scenes[p.variant], upstream, files[i - 1], shape, report)
            reuse.retire(p.path, outdir)  # the result it replaces stays reusable under its key
            store.write(ds, p.path, compute_with=compute_with, progress=report,
                        compress=scenes[p.variant].get("run.compress"), keep_blocks=shape.keep_blocks,
                        costlier_with=shape.costlier_with)
        report.finish()
        results[p.variant].add(p.stage.name, p.path)
        if _in_memory(ds) and ds.nbytes <= LOAD_LIMIT_BYTES:  # handed downstream as compute() hands it, not re-read
            handed[(p.variant, p.stage.name)] = ds
        report(f"{tag}: computed in {time.perf_counter() - t0:.2f} s ({why}) -> {p.path}")
    reuse.prune(outdir, [p.path for p in plans])
    return results


def compute(scene: Scene, targets: Iterable[str] | None = None, report: Reporter | None = None,
            scheduler: str | None = None) -> dict[str, dict[str, xr.Dataset]]:
    """Every needed stage computed in memory: ``results[variant][stage]``, each Dataset loaded.

    The same plan, preflight (:func:`roughcontact.preflight.check`: input files, checks, sizes,
    with the results held in memory instead of on disk), stage computations and stamping as
    :func:`run`, so the same numbers; but nothing stored is reused and no file is written or
    removed. Upstream results are handed downstream as computed (loaded, as :func:`run` hands
    every result up to 256 MB)."""
    from .scheduling import scheduler as open_scheduler

    scene = preflight.arguments(scene, IN_MEMORY, targets, ())[0]
    report = report or Reporter()
    plans, scenes, files, shapes = _prepared(scene, None, targets, (), report)
    results: dict[str, dict[str, xr.Dataset]] = {v: {} for v in scenes}
    from .scheduling import quiet_libraries

    with open_scheduler(scheduler or scene.get("run.scheduler")) as compute_with, quiet_libraries():
        for i, p in enumerate(plans, start=1):
            report.live(f"[{i}/{len(plans)}] {p.label}: computing in memory")
            t0 = time.perf_counter()
            upstream = {up: results[p.variant][up] for up in p.record["upstream"]}
            ds = _computed(p, scenes[p.variant], upstream, files[i - 1], shapes[(p.variant, p.stage.name)], report)
            results[p.variant][p.stage.name] = _loaded(ds, compute_with)
            report(f"[{i}/{len(plans)}] {p.label}: computed in memory in {time.perf_counter() - t0:.2f} s")
    return results


def _in_memory(ds: xr.Dataset) -> bool:
    """Whether every variable of ``ds`` is in memory (none dask-backed)."""
    return not any(v.chunks is not None for v in ds.variables.values())


def _loaded(ds: xr.Dataset, compute_with) -> xr.Dataset:
    """``ds`` with its dask-backed variables computed by ``compute_with`` (what
    :func:`roughcontact.scheduling.scheduler` yields: a scheduler name, a process pool or a client)."""
    from concurrent.futures import Executor

    if _in_memory(ds):
        return ds
    if isinstance(compute_with, Executor):
        return ds.load(scheduler="processes", pool=compute_with)
    return ds.load(scheduler=compute_with)


def checked_notes(scene: Scene, plans: list[StagePlan], outdir: Path) -> list[str]:
    """Run every check a run would run first (raising what it would refuse) and return the notes."""
    return notes(plans, preflight.check(plans, {"base": scene, **scene.variants}, outdir)[1])


def notes(plans: list[StagePlan], shapes) -> list[str]:
    """The lines the stages' describe left for the user (their shapes' ``note``), e.g. the
    wavenumber zeta is measured against; ``plan`` and ``run`` print them."""
    out = []
    for p in plans:
        shape = shapes.get((p.variant, p.stage.name))
        note = shape.attrs.get("note") if shape is not None else None
        if note:
            out.append(f"{p.label}: {note}")
    return out


def conforms(ds: xr.Dataset, shape: Shape, label: str) -> None:
    """Refuse, as a bug in the stage, a computed result whose dimensions or small coordinates
    differ from what its ``describe`` said before anything computed (the preflight's checks and
    size estimates relied on it)."""
    for dim, size in shape.sizes.items():
        if dim in ds.sizes and ds.sizes[dim] != size and dim not in shape.approximate:
            raise RuntimeError(f"stage {label} computed {dim} of size {ds.sizes[dim]}, but its describe said {size} "
                               "(a bug in the stage)")
    for name, values in shape.coords.items():
        one_d = name in ds.coords and ds[name].ndim == 1 and ds.sizes.get(name) == len(values)
        if name not in shape.approximate and one_d:
            computed = ds[name].values
            if computed.dtype.kind in "fiu" and not np.allclose(computed, values, rtol=1e-12, atol=0.0, equal_nan=True):
                worst = float(np.nanmax(np.abs(computed - values) / np.abs(values)))
                raise RuntimeError(f"stage {label} computed coordinate {name} unlike its describe (largest relative "
                                   f"difference {worst:.3g}; a bug in the stage)")


def _open(path: Path) -> xr.Dataset:
    """A stored result: in memory if small, else opened lazily with the file's own chunking."""
    if path.stat().st_size <= LOAD_LIMIT_BYTES:
        return store.open_result(path)
    from .ncio import open_lazily

    return open_lazily(path)
