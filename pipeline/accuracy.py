"""``roughcontact accuracy``: the error and cost of each stage's numerical resolution, measured.

For each stage of a scene with outputs that declare a ``tolerance``
(:class:`~roughcontact.stage.Var`), the stage (and what it needs upstream) is run on a ladder of
increasing resolutions: rung k sets every resolution setting the involved stages declare a
``ladder`` for to its k-th value (the last rung is the reference). The stage's own ladders set
the number of rungs (an upstream ladder that is longer stops there). Each preset (fast, default,
accurate) is measured the same way; a preset whose settings are those of a rung reuses that
rung's run.

The error of an output is measured against the output's own scale (docs/accuracy.md)::

    e = max over points |x - x_ref| / max(|x_ref|, FLOOR * max|x_ref|),   FLOOR = 1e-6

a relative error wherever the output is at least a millionth of its largest value, and the
error in units of that millionth below it (where, e.g., a separation of 1e-26 m at full contact
has no meaningful relative error). A stage's error is the worst over its main outputs. Wall
times are the median of a few forced runs (one for runs over :data:`REPEAT_BELOW` seconds);
progress goes through :class:`roughcontact.progress.Reporter` (bars on a terminal).
The table is written as NetCDF and drawn as error against wall time.
"""

from __future__ import annotations

import copy
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from . import engine, scene as scenes, store
from .errors import UserError
from .progress import SILENT, Reporter
from .scene import PRESETS, Scene
from .stage import Stage, sections
from .version import __version__

#: below this fraction of an output's largest value, errors are measured against the fraction
FLOOR = 1e-6
#: the measure, as the table and the docs state it
MEASURE = (f"max |x - x_ref| / max(|x_ref|, {FLOOR:g} max|x_ref|) over every point of each main output "
           "(x_ref: the finest rung); a stage's error is the worst of its outputs")
#: runs shorter than this (s) are repeated (three in all) and their median time kept
REPEAT_BELOW = 2.0


def resolution_params(stage_list: list[Stage]) -> dict[str, object]:
    """``{"section.key": Param}`` of the settings with a ladder among the given stages' params."""
    out = {}
    schema = sections()
    for st in stage_list:
        for dotted in st.keys:
            section, _, key = dotted.partition(".")
            if not key or section not in schema:
                continue
            for p in schema[section].params:
                if p.name == key and p.ladder:
                    out[dotted] = p
    return out


def with_settings(scene: Scene, settings: dict[str, object], preset: str | None = None) -> Scene:
    raw = copy.deepcopy(scene.raw)
    raw.pop("variants", None)
    for dotted, value in settings.items():
        section, _, key = dotted.partition(".")
        raw.setdefault(section, {})[key] = value
    if preset is not None:
        raw.setdefault("numerics", {})["preset"] = preset
    return scenes.from_dict(raw, scene.path)


def scaled_error(result: xr.DataArray, reference: xr.DataArray, floor: float = FLOOR) -> float:
    """The error of one output against its reference, relative to the output's scale (see the
    module docstring); the reference is interpolated (linearly in the log of positive
    coordinates) where the coordinates differ. inf if the two disagree on which points are finite."""
    a, b = result, reference
    for dim in a.dims:
        if dim in b.dims and (a.sizes[dim] != b.sizes[dim] or not np.allclose(a[dim], b[dim], rtol=1e-12)):
            b = _interp(b, dim, a[dim])
    a, b = xr.align(a, b, join="inner")
    av, bv = np.asarray(a.values, dtype=float), np.asarray(b.values, dtype=float)
    if not np.array_equal(np.isfinite(av), np.isfinite(bv)):
        return np.inf
    both = np.isfinite(av)
    if not np.any(both):
        return 0.0
    diff, size = np.abs(av - bv)[both], np.abs(bv)[both]
    scale = max(float(size.max()) * floor, np.finfo(float).tiny)
    return float(np.max(diff / np.maximum(size, scale)))


def output_errors(result: xr.Dataset, reference: xr.Dataset, names) -> dict[str, float]:
    """:func:`scaled_error` of each of ``names`` the results hold."""
    return {n: scaled_error(result[n], reference[n]) for n in names if n in result and n in reference}


def _interp(da: xr.DataArray, dim: str, target: xr.DataArray) -> xr.DataArray:
    src = da[dim].values
    if np.all(src > 0) and np.all(target.values > 0):
        logged = da.assign_coords({dim: np.log(src)})
        out = logged.interp({dim: np.log(target.values)})
        return out.assign_coords({dim: target.values})
    return da.interp({dim: target.values})


def _sweep_param(dotted: str):
    """The :class:`~roughcontact.schema.Param` of a dotted key, and the name of its dimension if
    it is a sweep (else None)."""
    section, _, key = dotted.partition(".")
    sec = sections().get(section)
    params = sec.params + tuple(p for ps in sec.variants.values() for p in ps) if sec is not None else ()
    p = next((p for p in params if p.name == key), None)
    return (p.dim or p.name).format(section=section) if p is not None and p.kind == "sweep" else None


def _fixed_sweeps(scene: Scene, needed: list[Stage], result: xr.Dataset) -> dict:
    """The sweeps whose values the resolution decides, fixed: a sweep key the measured stages read
    that the scene sets to a word (e.g. ``"all"``: every node of the q grid) and whose dimension
    the result has, set to the cheapest rung's values of that coordinate (``result``), so that
    every rung is computed and compared at the same points (the grids differ; interpolating the
    reference between its nodes would measure the interpolation). Else nothing."""
    out = {}
    for dotted in dict.fromkeys(k for st in needed for k in st.keys):
        dim = _sweep_param(dotted) if isinstance(scene.get(dotted), str) else None
        if dim is not None and dim in result.coords:
            out[dotted] = [float(v) for v in np.atleast_1d(result[dim].values)]
    return out


def _settings_of(sc: Scene, needed: list[Stage]) -> dict:
    """Every parameter the measured stages read, as resolved for ``sc`` (what decides a run)."""
    return {name: repr(sc.get(name)) for st in needed for name in st.keys}


def measure_stage(scene: Scene, st: Stage, workdir: Path, report: Reporter = SILENT) -> dict:
    outputs = tuple(st.measured)
    needed = engine.needed_stages(scene, outputs)
    params = resolution_params(needed)
    own = [p for k, p in params.items() if k in st.keys] or list(params.values())
    rungs = max((len(p.ladder) for p in own), default=0)  # the stage's own ladder sets the rungs
    if rungs < 2:
        return {}
    settings = [{k: p.ladder[min(i, len(p.ladder) - 1)] for k, p in params.items()} for i in range(rungs)]
    step = report.bar(f"accuracy of {st.name}: warm-up", total=1, unit="run")

    def timed(sc: Scene, tag: str):
        """The result and the median wall time of forced runs (three if a run is short)."""
        out, times = workdir / st.name / tag, []
        while len(times) < (3 if not times or times[0] < REPEAT_BELOW else 1):
            t0 = time.perf_counter()
            res = engine.run(sc, out, targets=outputs, force=("all",), report=engine.Reporter(None))
            times.append(time.perf_counter() - t0)
        step()
        return res["base"][st.name], float(np.median(times))

    try:
        # imports and caches, not measured (the cheapest rung)
        warm, _ = timed(with_settings(scene, settings[0]), "warm-up")
        fixed = _fixed_sweeps(scene, needed, warm)
        rung_scenes = [with_settings(scene, {**s, **fixed}) for s in settings]
        preset_scenes = {name: with_settings(scene, fixed, name) for name in PRESETS}
        keys = [_settings_of(sc, needed) for sc in rung_scenes]
        same = {name: next((i for i, k in enumerate(keys) if k == _settings_of(sc, needed)), None)
                for name, sc in preset_scenes.items()}
        step.close()  # the rungs and the presets that reuse none of them
        step = report.bar(f"accuracy of {st.name}: rungs and presets", unit="run",
                          total=rungs + sum(i is None for i in same.values()))
        runs = [timed(sc, f"rung {i}") for i, sc in enumerate(rung_scenes)]
        reference = runs[-1][0]
        errors = [output_errors(r, reference, outputs) for r, _ in runs]
        presets = {}
        for name, sc in preset_scenes.items():
            i = same[name]
            res, seconds = runs[i] if i is not None else timed(sc, name)
            presets[name] = (output_errors(res, reference, outputs), seconds, i)
    finally:
        step.close()
        report.finish()
    return {"settings": settings, "errors": errors, "times": [t for _, t in runs], "presets": presets,
            "tolerance": min(st.measured.values()), "outputs": [n for n in outputs if n in errors[0]]}


def measure(scene: Scene, outdir: Path, report: Reporter | None = None) -> xr.Dataset:
    """Measure every stage of the scene with outputs that declare a tolerance; write NetCDF + PNG. Progress
    (bars on a terminal) and the table go to ``report`` (default: a
    :class:`~roughcontact.progress.Reporter` on stderr)."""
    report = report if report is not None else Reporter()
    all_stages = engine.needed_stages(scene, scene.outputs)
    measured = {}
    with tempfile.TemporaryDirectory() as tmp:
        for st in all_stages:
            if not st.measured:
                continue
            report(f"accuracy: {st.name} ...")
            m = measure_stage(scene, st, Path(tmp), report)
            if m:
                measured[st.name] = m
                for name, (errs, secs, rung) in m["presets"].items():
                    worst = max(errs.values(), default=0.0)
                    met = "" if name != "default" else ("  meets its target" if worst <= m["tolerance"] else
                                                        f"  MISSES its target {m['tolerance']:g}")
                    report(f"  {st.name:12s} {name:9s} error {worst:9.2e}  time {secs:7.3f} s"
                           + (f" (= rung {rung})" if rung is not None else "") + met)
    if not measured:  # no table and no blank plot: say why
        names = ", ".join(st.name for st in all_stages)
        raise UserError(f"none of this scene's stages ({names}) has a numerical resolution whose error "
                        "roughcontact accuracy measures", key="outputs.variables")
    ds = _table(measured)
    ds.attrs.update(
        Conventions="CF-1.11",
        title="roughcontact accuracy table: error and cost of each stage's resolution",
        comment=f"error measure: {MEASURE}; times: median of forced runs (three when under {REPEAT_BELOW:g} s)",
        scene=scene.label,
        software_version=__version__,
        git_commit=store.git_commit(),
        date_created=store.utc_now(),
        history=f"{store.utc_now()}: roughcontact accuracy on {scene.label}",
    )
    outdir.mkdir(parents=True, exist_ok=True)
    store.write(ds, outdir / "accuracy.nc")
    from .accuracy_figure import figure

    fig = figure(ds)  # selects the Agg backend first
    import matplotlib.pyplot as plt

    try:
        store.write_figure(fig, outdir / "accuracy.png")
    finally:
        plt.close(fig)
    return ds


def _table(measured: dict) -> xr.Dataset:
    names = list(measured)
    rungs = max((len(m["errors"]) for m in measured.values()), default=0)
    err = np.full((len(names), rungs), np.nan)
    secs = np.full((len(names), rungs), np.nan)
    setting = np.full((len(names), rungs), "", dtype=object)
    outputs = [(n, o) for n in names for o in measured[n]["outputs"]]
    out_err = np.array([[measured[n]["presets"][p][0].get(o, np.nan) for p in PRESETS] for n, o in outputs])
    for i, n in enumerate(names):
        m = measured[n]
        err[i, : len(m["errors"])] = [max(e.values(), default=0.0) for e in m["errors"]]
        secs[i, : len(m["times"])] = m["times"]
        for j, s in enumerate(m["settings"]):
            setting[i, j] = ", ".join(f"{k}={v}" for k, v in s.items())
    perr = np.array([[max(measured[n]["presets"][p][0].values(), default=0.0) for p in PRESETS] for n in names])
    ptime = np.array([[measured[n]["presets"][p][1] for p in PRESETS] for n in names])
    tol = np.array([measured[n]["tolerance"] for n in names])
    error = {"units": "1", "error_measure": MEASURE, "error_floor": FLOOR}
    return xr.Dataset(
        {
            "rung_error": (("stage", "rung"), err, {**error, "long_name": "error of the rung against the finest rung"}),
            "rung_time": (("stage", "rung"), secs,
                          {"units": "s", "long_name": "median wall time of the stage and its upstream stages"}),
            "rung_settings": (("stage", "rung"), setting.astype(str),
                              {"units": "1", "long_name": "resolution settings of the rung"}),
            "preset_error": (("stage", "preset"), perr.reshape(len(names), len(PRESETS)),
                             {**error, "long_name": "error of the preset against the finest rung"}),
            "preset_time": (("stage", "preset"), ptime.reshape(len(names), len(PRESETS)),
                            {"units": "s", "long_name": "median wall time of the preset"}),
            "output_error": (("output", "preset"), out_err.reshape(len(outputs), len(PRESETS)),
                             {**error, "long_name": "error of each main output at each preset"}),
            "tolerance": (("stage",), tol, {"units": "1", "long_name": "target error of the default preset"}),
        },
        coords={
            "stage": ("stage", np.array(names, dtype=str), {"units": "1", "long_name": "stage"}),
            "rung": ("rung", np.arange(rungs), {"units": "1", "long_name": "resolution rung (last: reference)"}),
            "preset": ("preset", np.array(PRESETS, dtype=str), {"units": "1", "long_name": "resolution preset"}),
            "output": ("output", np.array([o for _, o in outputs], dtype=str),
                       {"units": "1", "long_name": "main output"}),
            "output_stage": ("output", np.array([n for n, _ in outputs], dtype=str),
                             {"units": "1", "long_name": "stage of the output"}),
        },
    )
