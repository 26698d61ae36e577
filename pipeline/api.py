"""The Python API: load a scene, plan it, run it, open what it wrote (docs/api.md).

Everything here is also available at the top level of the package::

    import roughcontact as rc

    scene = rc.load_scene("default")                   # a built-in name, a TOML file or a dict
    for p in rc.plan(scene, "outputs/default"):        # what a run would do, and why
        print(p.label, p.status, p.reasons)
    results = rc.run(scene, "outputs/default", progress=False)
    area = results["base"]["contact"]["contact_area_ratio"]     # an xarray DataArray, SI units
    mem = rc.compute(scene, progress=False)            # the same, in memory: no file written or read
    rc.open_result("outputs/default/contact.nc")       # a result file, with its provenance
    rc.builtin_scenes()                                # {"default": Path(...), ...}

The library writes nothing to stdout; progress goes to one reporter (stderr, live bars on a
terminal; ``progress=False``: nothing). Bad input raises :class:`roughcontact.errors.UserError`
(one line naming the file and key), a failed numerical method
:class:`roughcontact.errors.ComputationError`; nothing half-written is left behind either way.
"""

from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import Iterable, Mapping

import xarray as xr

from . import engine, scene as scenes, store
from .engine import StagePlan
from .errors import UserError
from .progress import Reporter
from .results import StageResults
from .scene import Scene

__all__ = ["Results", "Scene", "StagePlan", "StageResults", "builtin_scenes", "compute", "load_scene", "open_result",
           "plan", "run"]


class Results(dict):
    """What :func:`run` returns: ``results[variant][stage]`` is a Dataset (``variant`` is
    ``"base"`` or a name of the scene's ``[variants]``), loaded into memory (one larger than
    256 MB opened lazily, with dask). ``outdir`` is where the files are;
    ``results[variant].path(stage)`` gives a stage's file."""

    def __init__(self, by_variant: Mapping[str, StageResults], outdir: Path):
        super().__init__(by_variant)
        self.outdir = Path(outdir)

    def __repr__(self) -> str:
        inner = "; ".join(f"{v}: {', '.join(r)}" for v, r in self.items())
        return f"Results({self.outdir}: {inner})"


def builtin_scenes() -> dict[str, Path]:
    """The built-in scenes by name (``default``, ``friction``, ...), with their TOML files."""
    return dict(sorted(scenes.builtin_scenes().items()))


def load_scene(source: str | Path | Mapping | Scene | None = None, *, preset: str | None = None) -> Scene:
    """A validated scene, every value in SI.

    Parameters
    ----------
    source
        A TOML file, the name of a built-in scene (:func:`builtin_scenes`), a dict with the
        layout of a scene file (relative paths are taken from the current folder), an already
        loaded :class:`Scene`, or None: the built-in default scene.
    preset
        ``"fast"``, ``"default"`` or ``"accurate"``: every resolution setting the scene does not
        set itself (as ``[numerics] preset`` or ``--preset``).
    """
    if not isinstance(source, (str, Path, Mapping, Scene, type(None))):
        raise TypeError(f"expected a scene: a TOML file, a built-in scene name, a dict or a Scene (or None for the "
                        f"default scene), got {type(source).__name__} {source!r:.60}")
    if isinstance(source, Scene):
        if preset is None:
            return source
        raw = copy.deepcopy(source.raw)
        raw.setdefault("numerics", {})["preset"] = preset
        return scenes.from_dict(raw, source.path)
    if isinstance(source, Mapping):
        raw = copy.deepcopy(dict(source))
        if preset is not None:
            raw.setdefault("numerics", {})["preset"] = preset
        return scenes.from_dict(raw)
    return scenes.load(source, preset=preset)


def _outdir(sc: Scene, outdir: str | Path | None) -> Path:
    if outdir is not None and (not isinstance(outdir, (str, Path)) or not str(outdir)):
        raise TypeError(f"outdir must be a folder path (str or pathlib.Path) or None, got {outdir!r:.60}")
    return Path(outdir) if outdir is not None else engine.default_outdir(sc)


def plan(scene: str | Path | Mapping | Scene | None = None, outdir: str | Path | None = None, *,
         preset: str | None = None, force: Iterable[str] = ()) -> list[StagePlan]:
    """What :func:`run` would do: per stage and variant, ``status`` (``"fresh"``, ``"stale"``,
    ``"missing"``), the ``reasons`` (the key, input file or upstream stage that changed) and
    the result's ``path``. ``outdir`` defaults to ``outputs/<scene name>``."""
    sc = load_scene(scene, preset=preset)
    return engine.plan(sc, _outdir(sc, outdir), force=force)


def run(scene: str | Path | Mapping | Scene | None = None, outdir: str | Path | None = None, *,
        preset: str | None = None, scheduler: str | None = None, progress: bool | Reporter = True,
        force: Iterable[str] = ()) -> Results:
    """Compute what the scene asks for, reusing every result that is up to date.

    Parameters
    ----------
    scene, preset
        As for :func:`load_scene`.
    outdir
        Where the result files go (default ``outputs/<scene name>``).
    scheduler
        ``"threads"`` (default), ``"processes"``, ``"synchronous"`` or the address of a
        dask.distributed scheduler (``"tcp://host:8786"``); overrides the scene's ``[run]``.
    progress
        True: one line per stage on stderr, and live bars on a terminal; False: nothing; or a
        :class:`roughcontact.progress.Reporter`.
    force
        Stage names to recompute even if fresh (``"all"``: every stage).

    Returns
    -------
    Results
        ``results[variant][stage]``: xarray Datasets with units, long names and provenance.
    """
    sc = load_scene(scene, preset=preset)
    out = _outdir(sc, outdir)
    report = progress if isinstance(progress, Reporter) else Reporter(sys.stderr if progress else None)
    return Results(engine.run(sc, out, force=force, report=report, scheduler=scheduler), out)


def compute(scene: str | Path | Mapping | Scene | None = None, outputs: str | Iterable[str] | None = None, *,
            preset: str | None = None, scheduler: str | None = None,
            progress: bool | Reporter = True) -> dict[str, dict[str, xr.Dataset]]:
    """Compute in memory what :func:`run` would compute, writing no file and reusing none.

    The same checks before anything computes (input files, cross-key checks, sizes: the results
    must fit in memory instead of on disk) and the same numbers as :func:`run`: both share the
    engine's plan, preflight, stage computations and stamping. Nothing is left behind.

    Parameters
    ----------
    scene, preset
        As for :func:`load_scene`.
    outputs
        Variable or stage names to compute (with the stages they need); default: the scene's
        ``[outputs] variables``.
    scheduler, progress
        As for :func:`run`.

    Returns
    -------
    dict
        ``results[variant][stage]``: xarray Datasets (loaded) with units, long names and
        provenance; ``variant`` is ``"base"`` or a name of the scene's ``[variants]``.
    """
    sc = load_scene(scene, preset=preset)
    report = progress if isinstance(progress, Reporter) else Reporter(sys.stderr if progress else None)
    return engine.compute(sc, outputs, report=report, scheduler=scheduler)


def open_result(path: str | Path) -> xr.Dataset:
    """A result file (of any stage) loaded into memory, with its attributes: units and long
    names on every variable, provenance (``parameters``, ``input_files``, ``git_commit``, ...)
    in ``attrs``. Any other NetCDF file (no ``stage_name``/``stage_key``: not a stage's result,
    so no provenance to rely on) is refused with a UserError; open it with ``xarray.open_dataset``."""
    if not isinstance(path, (str, Path)):
        raise TypeError(f"expected the path of a result file (str or pathlib.Path), got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise UserError("no such result file", file=str(path))
    attrs = store.read_attrs(path)
    if attrs is None:
        raise UserError("not a readable NetCDF file", file=str(path))
    if not {"stage_name", "stage_key"} <= set(attrs):
        raise UserError("not the result of a roughcontact stage (no stage_name or stage_key attribute, so no "
                        "provenance): open it with xarray.open_dataset", file=str(path))
    try:
        return store.open_result(path)
    except (OSError, ValueError) as exc:
        raise UserError(f"not a readable NetCDF file ({exc.__class__.__name__})", file=str(path)) from None
