"""``roughcontact accuracy``: the error and cost of each stage's numerical resolution, measured.

For each stage of a scene that declares ``main_outputs``, the stage (and what it needs upstream)
is run on a ladder of increasing resolutions: rung k sets every resolution setting the involved
stages declare a ``ladder`` for to its k-th value (the last rung is the reference). Each rung's
error is the maximum relative error of the main outputs against the reference; each preset
(fast, default, accurate) is measured the same way. The table is written as NetCDF and drawn
as error against wall time.
"""

from __future__ import annotations

import copy
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from . import __version__, engine, scene as scenes, store
from .progress import SILENT, Reporter
from .scene import PRESETS, Scene
from .stage import Stage, sections


def resolution_params(stage_list: list[Stage]) -> dict[str, object]:
    """``{"section.key": Param}`` of the settings with a ladder among the given stages' params."""
    out = {}
    schema = sections()
    for st in stage_list:
        for dotted in st.params:
            section, _, key = dotted.partition(".")
            if not key or section not in schema:
                continue
            for p in schema[section].params:
                if p.name == key and p.ladder:
                    out[dotted] = p
    return out


def _with(scene: Scene, settings: dict[str, object], preset: str | None = None) -> Scene:
    raw = copy.deepcopy(scene.raw)
    raw.pop("variants", None)
    for dotted, value in settings.items():
        section, _, key = dotted.partition(".")
        raw.setdefault(section, {})[key] = value
    if preset is not None:
        raw.setdefault("numerics", {})["preset"] = preset
    return scenes.from_dict(raw, scene.path)


def relative_error(result: xr.Dataset, reference: xr.Dataset, names) -> float:
    """Max relative error of ``names`` (absolute where the reference is 0); the reference is
    interpolated (linearly in the log of positive coordinates) where the coordinates differ."""
    worst = 0.0
    for name in names:
        if name not in result and name not in reference:
            continue  # an output this scene does not ask for
        a, b = result[name], reference[name]
        for dim in a.dims:
            if dim in b.dims and (a.sizes[dim] != b.sizes[dim] or not np.allclose(a[dim], b[dim], rtol=1e-12)):
                b = _interp(b, dim, a[dim])
        a, b = xr.align(a, b, join="inner")
        av, bv = np.asarray(a.values, dtype=float), np.asarray(b.values, dtype=float)
        both = np.isfinite(av) & np.isfinite(bv)
        if not np.all(np.isfinite(av) == np.isfinite(bv)):
            return np.inf
        diff = np.abs(av - bv)[both]
        scale = np.abs(bv)[both]
        rel = np.where(scale > 0, diff / np.where(scale > 0, scale, 1.0), diff)
        worst = max(worst, float(rel.max()) if rel.size else 0.0)
    return worst


def _interp(da: xr.DataArray, dim: str, target: xr.DataArray) -> xr.DataArray:
    src = da[dim].values
    if np.all(src > 0) and np.all(target.values > 0):
        logged = da.assign_coords({dim: np.log(src)})
        out = logged.interp({dim: np.log(target.values)})
        return out.assign_coords({dim: target.values})
    return da.interp({dim: target.values})


def measure_stage(scene: Scene, st: Stage, workdir: Path, report: Reporter = SILENT) -> dict:
    needed = engine.needed_stages(scene, st.main_outputs)
    params = resolution_params(needed)
    rungs = max((len(p.ladder) for p in params.values()), default=0)
    if rungs < 2:
        return {}

    def timed(sc: Scene, tag: str, repeat: int = 2):
        """The result and the best wall time of ``repeat`` forced runs (imports and caches warm)."""
        out = workdir / st.name / tag
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            res = engine.run(sc, out, targets=st.main_outputs, force=("all",), report=engine.Reporter(None))
            best = min(best, time.perf_counter() - t0)
        return res["base"][st.name], best

    tick = report.bar(f"accuracy of {st.name}: warm-up, rungs and presets", total=1 + rungs + len(PRESETS), unit="run")
    timed(scene, "warm-up", repeat=1)
    tick()
    settings = [{k: p.ladder[min(i, len(p.ladder) - 1)] for k, p in params.items()} for i in range(rungs)]
    runs = []
    for i, s in enumerate(settings):
        runs.append(timed(_with(scene, s), f"rung{i}"))
        tick()
    reference = runs[-1][0]
    errors = [relative_error(r, reference, st.main_outputs) for r, _ in runs[:-1]]
    presets = {}
    for name in PRESETS:
        res, seconds = timed(_with(scene, {}, name), name)
        presets[name] = (relative_error(res, reference, st.main_outputs), seconds)
        tick()
    report.finish()
    return {
        "settings": settings,
        "errors": errors + [0.0],
        "times": [t for _, t in runs],  # best of two forced runs each
        "presets": presets,
        "tolerance": st.tolerance,
    }


def measure(scene: Scene, outdir: Path, report: Reporter | None = None) -> xr.Dataset:
    """Measure every stage of the scene that declares main outputs; write NetCDF + PNG. Progress
    and the table go to ``report`` (default: a :class:`~roughcontact.progress.Reporter` on stderr)."""
    report = report if report is not None else Reporter()
    all_stages = engine.needed_stages(scene, scene.outputs)
    measured = {}
    with tempfile.TemporaryDirectory() as tmp:
        for st in all_stages:
            if not st.main_outputs:
                continue
            report(f"accuracy: {st.name} ...")
            m = measure_stage(scene, st, Path(tmp), report)
            if m:
                measured[st.name] = m
                for name, (err, secs) in m["presets"].items():
                    report(f"  {st.name:12s} {name:9s} error {err:9.2e}  time {secs:7.3f} s")
    ds = _table(measured)
    ds.attrs.update(
        Conventions="CF-1.11",
        title="roughcontact accuracy: error and cost of each stage's resolution",
        scene=scene.label,
        software_version=__version__,
        git_commit=store.git_commit(),
        date_created=store.utc_now(),
        history=f"{store.utc_now()}: roughcontact accuracy on {scene.label}",
    )
    outdir.mkdir(parents=True, exist_ok=True)
    store.write(ds, outdir / "accuracy.nc")
    fig = figure(ds)
    tmp_png = outdir / f"{store.TMP_PREFIX}accuracy.png"
    fig.savefig(tmp_png, dpi=130)
    tmp_png.replace(outdir / "accuracy.png")
    return ds


def _table(measured: dict) -> xr.Dataset:
    names = list(measured)
    rungs = max((len(m["errors"]) for m in measured.values()), default=0)
    err = np.full((len(names), rungs), np.nan)
    secs = np.full((len(names), rungs), np.nan)
    setting = np.full((len(names), rungs), "", dtype=object)
    for i, n in enumerate(names):
        m = measured[n]
        err[i, : len(m["errors"])] = m["errors"]
        secs[i, : len(m["times"])] = m["times"]
        for j, s in enumerate(m["settings"]):
            setting[i, j] = ", ".join(f"{k}={v}" for k, v in s.items())
    perr = np.array([[measured[n]["presets"][p][0] for p in PRESETS] for n in names]).reshape(len(names), len(PRESETS))
    ptime = np.array([[measured[n]["presets"][p][1] for p in PRESETS] for n in names]).reshape(len(names), len(PRESETS))
    tol = np.array([measured[n]["tolerance"] for n in names])
    return xr.Dataset(
        {
            "rung_error": (("stage", "rung"), err, {"units": "1", "long_name": "max relative error of the main outputs against the finest rung"}),
            "rung_time": (("stage", "rung"), secs, {"units": "s", "long_name": "wall time of the stage and its upstream stages"}),
            "rung_settings": (("stage", "rung"), setting.astype(str), {"units": "1", "long_name": "resolution settings of the rung"}),
            "preset_error": (("stage", "preset"), perr, {"units": "1", "long_name": "max relative error of the preset against the finest rung"}),
            "preset_time": (("stage", "preset"), ptime, {"units": "s", "long_name": "wall time of the preset"}),
            "tolerance": (("stage",), tol, {"units": "1", "long_name": "target relative error of the default preset"}),
        },
        coords={
            "stage": ("stage", np.array(names, dtype=str), {"units": "1", "long_name": "stage"}),
            "rung": ("rung", np.arange(rungs), {"units": "1", "long_name": "resolution rung (last: reference)"}),
            "preset": ("preset", np.array(PRESETS, dtype=str), {"units": "1", "long_name": "resolution preset"}),
        },
    )


def figure(ds: xr.Dataset):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    markers = {"fast": "v", "default": "o", "accurate": "^"}
    for i, name in enumerate(ds["stage"].values):
        e = ds["rung_error"].isel(stage=i).values[:-1]
        t = ds["rung_time"].isel(stage=i).values[:-1]
        ok = np.isfinite(e) & np.isfinite(t)
        line, = ax.loglog(t[ok], np.maximum(e[ok], 1e-16), "-", marker=".", label=str(name))
        for j, preset in enumerate(ds["preset"].values):
            ax.loglog(float(ds["preset_time"][i, j]), max(float(ds["preset_error"][i, j]), 1e-16),
                      markers[str(preset)], color=line.get_color(), markersize=8, markerfacecolor="none")
        ax.axhline(float(ds["tolerance"][i]), color=line.get_color(), linestyle=":", linewidth=0.8)
    for preset, m in markers.items():
        ax.plot([], [], m, color="0.3", markerfacecolor="none", label=f"preset {preset}")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("max relative error vs finest rung")
    ax.set_title("Accuracy against cost (dotted: target of the default)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
