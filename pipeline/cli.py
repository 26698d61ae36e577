"""Command line: ``roughcontact run|plan|show|plot|export|report|accuracy|scenes|reference``.

Exit codes: 0 ok, 1 failure or (for ``plan``) something would run, 2 user error, 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import json
import sys
import traceback
import warnings
from pathlib import Path

from .errors import ComputationError, SceneWarning, UserError
from .version import __version__


class _OnUse:
    """A module imported when one of its names is first used: ``roughcontact --help`` (and a
    mistyped command) answer without loading numpy, xarray and the stages."""

    def __init__(self, load):
        self._load = load

    def __getattr__(self, name):
        return getattr(self._load(), name)


def _engine():
    from . import engine

    return engine


def _scene():
    from . import scene

    return scene


def _store():
    from . import store

    return store


def _units():
    from . import units

    return units


engine, scenes, store, _unit_text = (_OnUse(f) for f in (_engine, _scene, _store, _units))


def units_of(key):
    return scenes.units_of(key)


def display(value, units):
    return _unit_text.display(value, units)


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="roughcontact", description="Persson contact mechanics for two rough surfaces.")
    ap.add_argument("--version", action="version", version=f"roughcontact {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)

    def scene_command(name, help_text):
        p = sub.add_parser(name, help=help_text)
        p.add_argument("scene", nargs="?",
                       help="scene file or built-in scene name (default: the built-in default scene)")
        p.add_argument("--outdir", type=Path, help="where results go (default: outputs/<scene name>)")
        p.add_argument("--preset", choices=("fast", "default", "accurate"),
                       help="resolution preset for every setting the scene does not set itself")
        return p

    run = scene_command("run", "compute what the scene asks for, reusing up-to-date results")
    run.add_argument("--force", action="append", default=[], metavar="STAGE",
                     help="recompute STAGE even if fresh ('all': every stage)")
    run.add_argument("--quiet", action="store_true", help="no progress bars: one line per stage")
    run.add_argument("--scheduler", help="threads (default), processes, synchronous, or a dask.distributed "
                                         "scheduler address tcp://host:port (overrides [run] scheduler)")
    plan = scene_command("plan", "say for each stage whether it is fresh, stale (and why) or missing; "
                                 "exit 1 if anything would run")
    for p in (run, plan):
        p.add_argument("--verify", action="store_true", default=None,
                       help="check the checksum of every reused result (default: of results up to 64 MiB)")
    plot = scene_command("plot", "draw the figures of the scene's stages as PNG (computing what is missing)")
    plot.add_argument("--quiet", action="store_true", help="no progress bars: one line per stage and per figure")
    plot.add_argument("--scheduler", help="as for run")
    _export_parser(scene_command("export", "write the scene's results as tidy tables (CSV or Excel) for "
                                           "spreadsheets and FE codes (computing what is missing)"))
    _report_parser(scene_command("report", "write one self-contained HTML page of the scene's results to send: "
                                           "figures, key numbers with units, accuracy, provenance, warnings "
                                           "(computing what is missing)"))
    scene_command("accuracy", "measure each stage's error and cost on a ladder of resolutions; NetCDF table + PNG")
    show = sub.add_parser("show", help="what is in a result file and where it came from")
    show.add_argument("file", type=Path)
    listing = sub.add_parser("scenes",
                             help="list the built-in scenes, or copy one (with its data files) to start your own")
    listing.add_argument("--copy", nargs=2, metavar=("NAME", "DIR"),
                         help="copy the built-in scene NAME and the data files it reads into folder DIR")
    ref = sub.add_parser("reference", help="print the scene-file reference (Markdown)")
    del ref
    return ap


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A SceneWarning as one line naming the keys; other warnings as Python prints them."""
    if issubclass(category, SceneWarning):
        print(f"roughcontact: warning: {message}", file=sys.stderr, flush=True)
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _main(args)


def _main(args) -> int:
    try:
        return _dispatch(args)
    except UserError as exc:
        print(f"roughcontact: error: {exc.format()}", file=sys.stderr)
        return exc.exit_code
    except ComputationError as exc:
        print(f"roughcontact: computation failed: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into head & co.
        return 0
    except KeyboardInterrupt:
        print("roughcontact: interrupted; nothing half-written is kept", file=sys.stderr)
        return 130  # 128 + SIGINT, as shells report a command stopped by Ctrl-C
    except Exception:  # an internal error: say so, with the traceback for the bug report
        traceback.print_exc()
        print("roughcontact: internal error (a bug: please report it with the traceback above)", file=sys.stderr)
        return 1


def _dispatch(args) -> int:
    if args.command == "scenes":
        if args.copy:
            written = scenes.copy_builtin(*args.copy)
            for path in written:
                print(f"copied {path}")
            print(f"run it with: roughcontact run {written[0]}")
            return 0
        for name, text in sorted(scenes.builtin_descriptions().items()):
            print(f"{name:16s} {text}")
        print(f"(scene files in {scenes.default_scene_path().parent}; to start your own, copy one with its data "
              "files: roughcontact scenes --copy NAME DIR)")
        return 0
    if args.command == "reference":
        print(scenes.reference())
        return 0
    from . import duckarrays

    duckarrays.install()  # this process is ours: xarray needs no dask.array or pint for numpy results
    if args.command == "show":
        return _show(args.file)
    sc = scenes.load(args.scene, preset=args.preset)
    try:
        return _scene_command(args, sc)
    except UserError as exc:  # errors about a scene key name the scene file too
        if exc.key == "run.scheduler" and getattr(args, "scheduler", None):  # the option's value, not the scene's
            raise UserError(exc.message, key="--scheduler") from None
        in_scene = exc.key and not exc.key.startswith("--")  # an option's error is not the scene file's
        raise (exc.located(file=str(sc.path)) if in_scene and sc.path else exc) from None


def _scene_command(args, sc) -> int:
    outdir = args.outdir or engine.default_outdir(sc)
    if args.command == "plan":
        plans = engine.plan(sc, outdir, verify=args.verify)
        notes = engine.checked_notes(sc, plans, outdir)  # what a run would refuse, before it runs
        for p in plans:
            why = f" ({'; '.join(p.reasons)})" if p.reasons else ""
            print(f"{p.label:28s} {p.status}{why}  {p.path}")
        for note in notes:
            print(f"note: {note}")
        return 1 if any(p.status != "fresh" for p in plans) else 0
    reporter = engine.Reporter(sys.stderr, bars=False if getattr(args, "quiet", False) else None)
    if args.command == "run":
        engine.run(sc, outdir, force=args.force, report=reporter, scheduler=args.scheduler, verify=args.verify,
                   open_results=False)
        print(f"results in {outdir}")
        return 0
    if args.command == "plot":
        return _plot(sc, outdir, reporter, args.scheduler)
    if args.command == "export":
        return _export(sc, outdir, reporter, args)
    if args.command == "report":
        from .report import write_report

        page = write_report(sc, outdir, args.output, force=args.force, report=reporter, scheduler=args.scheduler,
                            measure_accuracy=args.accuracy)
        print(f"report in {page}")
        return 0
    if args.command == "accuracy":
        from .accuracy import measure

        measure(sc, outdir / "accuracy", report=reporter)
        print(f"accuracy table and plot in {outdir / 'accuracy'}")
        return 0
    raise AssertionError(args.command)


def scene_figures(sc) -> tuple[list, list]:
    """The figures ``plot`` draws for a scene, and those it skips (:func:`roughcontact.figures.scene_figures`)."""
    from .figures import scene_figures as chosen

    return chosen(sc)


def _plot(sc, outdir: Path, reporter, scheduler=None) -> int:
    """Draw the scene's figures. A figure that needs an optional output the scene does not ask
    for, or that has nothing to show for this scene (a comparison without the variant it
    compares with), is not drawn and not announced as a problem: one closing line names them."""
    from .figures import use_agg

    plt = use_agg()
    figures, _ = scene_figures(sc)
    if not figures:
        raise UserError("none of the scene's stages draws a figure", key="outputs.variables")
    results = engine.run(sc, outdir, report=reporter, scheduler=scheduler)
    folder = outdir / "figures"
    folder.mkdir(parents=True, exist_ok=True)
    empty = []
    for f in figures:
        fig = f.make(results)
        target = folder / f"{f.name}.png"
        if fig is None:  # nothing to draw for this scene (e.g. no paired maps): no blank figure
            target.unlink(missing_ok=True)
            empty.append(f.name)
            continue
        try:
            store.write_figure(fig, target)
        finally:
            plt.close(fig)
        print(f"{f.title}: {target}")
    if empty:
        print(f"not drawn, nothing to show for this scene: {', '.join(empty)}")
    return 0


def _export_parser(p) -> None:
    p.add_argument("--format", default="csv", help="csv (default) or xlsx (needs pandas and openpyxl)")
    p.add_argument("--variables", nargs="+", metavar="NAME", help="only these variables (default: all)")
    p.add_argument("--quiet", action="store_true", help="no progress bars: one line per stage and per table")
    p.add_argument("--scheduler", help="as for run")


def _report_parser(p) -> None:
    p.add_argument("--output", type=Path, metavar="FILE", help="the page to write (default: <outdir>/report.html)")
    p.add_argument("--force", action="append", default=[], metavar="STAGE",
                   help="recompute STAGE even if fresh ('all': every stage, so that the page lists the warnings "
                        "of every computation)")
    p.add_argument("--accuracy", action="store_true",
                   help="measure the accuracy of the settings first (as roughcontact accuracy does: seconds to "
                        "minutes); without it the page shows a measurement already in <outdir>/accuracy")
    p.add_argument("--quiet", action="store_true", help="no progress bars: one line per stage")
    p.add_argument("--scheduler", help="as for run")


def _export(sc, outdir: Path, reporter, args) -> int:
    """``export``: the tables in <outdir>/tables, one line per file written."""
    from .export import export

    for path in export(sc, outdir, args.format, args.variables, report=reporter, scheduler=args.scheduler):
        print(path)
    return 0


def _show(path: Path) -> int:
    import xarray as xr

    if not path.is_file():
        raise UserError("no such file", file=str(path))
    try:
        ds = xr.open_dataset(path)
    except Exception as exc:
        raise UserError(f"not a readable NetCDF file ({exc.__class__.__name__})", file=str(path)) from None
    with ds:
        a = ds.attrs
        _show_header(path, a)
        print("dimensions: " + ", ".join(f"{d}={n}" for d, n in ds.sizes.items()))
        print("coordinates:")
        for name, v in ds.coords.items():
            print(f"  {name:24s} [{v.attrs.get('units', '?')}] {v.attrs.get('long_name', '')}")
        print("variables:")
        for name, v in ds.data_vars.items():
            units = v.attrs.get("units", "?")
            value = f" = {display(v.values.item(), units)}" if v.ndim == 0 and v.dtype.kind == "f" else ""
            print(f"  {name:24s} ({', '.join(v.dims)}) [{units}] {v.attrs.get('long_name', '')}{value}")
        for label, attr in (("parameters", "parameters"), ("upstream", "upstream_keys"),
                            ("input files", "input_files")):
            if attr in a:
                try:
                    value = json.loads(a[attr])
                except ValueError:
                    print(f"{label}: {a[attr]}")
                    continue
                print(f"{label}:")
                for line in _summarise(value):
                    print(f"  {line}")
        print(f"history: {a.get('history', '')}")
    return 0


def _show_header(path: Path, a) -> None:
    """What the file is: a stage's result (stage, version, key) or another roughcontact table."""
    made = f"roughcontact {a.get('software_version', '?')} (git {a.get('git_commit', '?')})"
    if "stage_name" in a:
        print(f"{path}: stage {a['stage_name']} v{a.get('stage_version', '?')}, {made}")
        print(f"created {a.get('date_created', '?')} from scene {a.get('scene', '?')} [{a.get('scene_variant', '?')}]")
        print(f"key {a.get('stage_key', '?')}")
    else:  # e.g. accuracy.nc: not a stage's result, so no stage key
        print(f"{path}: {a.get('title', 'a NetCDF file not written by a stage')}, {made}")
        print(f"created {a.get('date_created', '?')}" + (f" from scene {a['scene']}" if "scene" in a else ""))
        if "comment" in a:
            print(a["comment"])


def _summarise(value, prefix="") -> list[str]:
    """Readable lines for a provenance JSON value: quantities with units, long lists by their ends."""
    if isinstance(value, dict):
        out = []
        for k, v in value.items():
            out += _summarise(v, f"{prefix}{k}.") if isinstance(v, dict) else [f"{prefix}{k} = {_brief(v, prefix + k)}"]
        return out
    if isinstance(value, list) and value and isinstance(value[0], dict):
        return [", ".join(f"{k}={v}" for k, v in item.items()) for item in value]
    return [f"{prefix.rstrip('.')} = {_brief(value, prefix.rstrip('.'))}" if prefix else _brief(value)]


def _brief(v, key: str = "") -> str:
    return display(v, units_of(key) if key else None)


if __name__ == "__main__":
    sys.exit(main())
