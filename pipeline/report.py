"""A report to send: ``roughcontact report`` writes one self-contained HTML page of a scene's results.

The page holds, with nothing outside it (no file, script, font or style sheet it links to):

* the warnings the run emitted and the notes the stages left on their results;
* the scene's figures, as ``plot`` draws them, embedded as base64 PNG;
* each stage's key numbers in tables with units, per variant. Which numbers are shown is decided
  by the shape of the stored result alone, as the export's tidy tables group it
  (:func:`roughcontact.export.tables`): its scalars (one value each) in full; a group of variables
  over few points (at most :data:`ROWS_IN_FULL` rows: e.g. the small-load law's u0 and beta per
  coherence) in full; a larger group by its coordinates' and variables' ranges. Labels and units
  are the stages' declarations (their :class:`~roughcontact.stage.Var`), and the outputs that
  ``roughcontact accuracy`` measures (a declared tolerance) are marked as main outputs;
* the accuracy of the settings used: the resolution settings the stages read with their ladder
  (:mod:`roughcontact.accuracy`), each stage's target error, and the error measured by
  ``roughcontact accuracy`` when its table is in the output folder (``--accuracy`` measures it);
* provenance: the software version and commit, the scene file's sha256, and per result its stage
  version, content key, creation date and input files with their sha256;
* the scene file itself.

It runs the scene as ``run`` does (reusing fresh results): every check is made before anything is
written, and the page is written to a temporary file beside it and renamed into place. The engine
knows no physics, and neither does the report: everything on the page is read from the stored
results and the stages' declarations.
"""

from __future__ import annotations

import base64
import html
import io
import json
import platform
import sys
import warnings
from pathlib import Path
from typing import Iterable

import numpy as np
import xarray as xr

from . import accuracy as accuracy_table, engine, store
from .errors import UserError
from .export import tables
from .figures import scene_figures, use_agg
from .stage import stages
from .units import number
from .version import __version__

#: a group of variables over at most this many points is shown whole; a larger one by its ranges
ROWS_IN_FULL = 12
#: variables with more values than this are not read for their ranges (a 1e8-point sweep)
RANGE_LIMIT = 10**7
#: resolution of the embedded figures (dots per inch)
DPI = 100

_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; margin: 0 auto;
       max-width: 1100px; padding: 1.5em 2em 4em; color: #1c1c1c; line-height: 1.4; }
h1 { font-size: 1.7em; margin-bottom: 0.2em; }
h2 { border-bottom: 2px solid #3a6ea5; padding-bottom: 0.15em; margin-top: 2em; }
h3 { margin: 1.5em 0 0.4em; }
h4 { margin: 1.1em 0 0.3em; color: #444; }
p.lead { color: #444; margin-top: 0; }
nav ol { columns: 2; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.92em; }
th, td { border: 1px solid #c9c9c9; padding: 0.25em 0.6em; vertical-align: top; }
th { background: #eef2f7; text-align: left; font-weight: 600; }
.date { white-space: nowrap; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tbody tr:nth-child(even) { background: #f8f8f8; }
.unit { color: #555; font-weight: normal; white-space: nowrap; }
.name { color: #666; font-size: 0.85em; font-family: ui-monospace, "DejaVu Sans Mono", monospace; }
.main { background: #3a6ea5; color: white; border-radius: 3px; padding: 0 0.35em; font-size: 0.78em;
        margin-left: 0.3em; }
code, pre { font-family: ui-monospace, "DejaVu Sans Mono", monospace; }
code.key { word-break: break-all; font-size: 0.85em; }
pre { background: #f5f5f5; border: 1px solid #ddd; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
figure { margin: 1em 0 2em; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-weight: 600; margin-top: 0.3em; }
ul.warnings li { background: #fff4d6; border-left: 4px solid #d19a00; padding: 0.3em 0.6em; margin: 0.3em 0;
                 list-style: none; }
ul.notes li { margin: 0.2em 0; }
.ok { color: #1d7a2e; font-weight: 600; }
.miss { color: #b3261e; font-weight: 600; }
.muted { color: #666; }
"""


def _e(text) -> str:
    """Text put into the page, escaped (quotes too: it may go into an attribute)."""
    return html.escape(str(text), quote=True)


def check_target(outdir: Path, target: Path) -> None:
    """The output folder and the page's path must be usable: a UserError naming the path before
    anything is computed or written."""
    from .preflight import not_a_file

    not_a_file(outdir)
    for where in target.parents:
        if where.exists() and not where.is_dir():
            raise UserError("exists and is not a folder: the report goes into a folder there "
                            "(give --outdir or --output a folder that is one)", file=str(where))
    if target.is_dir():
        raise UserError("is a folder: the report is a file (give --output a file name, e.g. report.html)",
                        file=str(target))


def write_report(scene, outdir: Path, output: Path | None = None, force: Iterable[str] = (), report=None,
                 scheduler: str | None = None, measure_accuracy: bool = False) -> Path:
    """Run ``scene`` into ``outdir`` as ``run`` does (reusing fresh results), draw its figures and
    write the page to ``output`` (default ``outdir/report.html``); return its path. With
    ``measure_accuracy`` the accuracy table is measured first (``roughcontact accuracy``)."""
    outdir = Path(outdir)
    target = Path(output) if output is not None else outdir / "report.html"
    check_target(outdir, target)
    with warnings.catch_warnings(record=True) as caught:
        results = engine.run(scene, outdir, force=force, report=report, scheduler=scheduler)
    for w in caught:  # shown as the run would have shown them, and kept for the page
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    if measure_accuracy:
        accuracy_table.measure(scene, outdir / "accuracy", report=report)
    page = render(scene, outdir, results, draw(scene, results), _warnings(caught))
    target.parent.mkdir(parents=True, exist_ok=True)
    store.write_file(page.encode("utf-8"), target, what="report")
    return target


def _warnings(caught) -> list[str]:
    """The run's warnings, each once, as one-line messages."""
    out = []
    for w in caught:
        text = str(w.message) if issubclass(w.category, UserWarning) else f"{w.category.__name__}: {w.message}"
        if text not in out:
            out.append(text)
    return out


def draw(scene, results) -> list[tuple[str, str, bytes]]:
    """The scene's figures as ``plot`` draws them: (name, title, PNG bytes); a figure with
    nothing to show for the scene is left out."""
    plt = use_agg()
    figures, _ = scene_figures(scene)
    out = []
    for f in figures:
        fig = f.make(results)
        if fig is None:
            continue
        try:
            buffer = io.BytesIO()
            fig.savefig(buffer, format="png", dpi=DPI)
        finally:
            plt.close(fig)
        out.append((f.name, f.title, buffer.getvalue()))
    return out


# -- the page ------------------------------------------------------------------------------------

def render(scene, outdir: Path, results, figures: list[tuple[str, str, bytes]], warned: list[str]) -> str:
    """The whole page as text."""
    sections = [
        ("warnings", "Warnings and notes", _warnings_html(warned, results)),
        ("figures", "Figures", _figures_html(figures)),
        ("numbers", "Key numbers", _numbers_html(results)),
        ("accuracy", "Accuracy of the settings used", _accuracy_html(scene, outdir)),
        ("provenance", "Provenance", _provenance_html(scene, outdir, results)),
        ("scene", "The scene", _scene_html(scene)),
    ]
    title = f"roughcontact report: {scene.name}"
    toc = "".join(f'<li><a href="#{key}">{_e(head)}</a></li>' for key, head, _ in sections)
    body = "".join(f'<section id="{key}"><h2>{_e(head)}</h2>{content}</section>' for key, head, content in sections)
    lead = _e(scene.description) if scene.description else ""
    made = f"written {_e(store.utc_now())} by roughcontact {_e(__version__)} (git {_e(store.git_commit())})"
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{_e(title)}</title><style>{_STYLE}</style></head><body>"
            f"<h1>{_e(title)}</h1><p class=\"lead\">{lead}</p><p class=\"muted\">{made}</p>"
            f"<nav><ol>{toc}</ol></nav>{body}</body></html>\n")


def _table(head: list[str], rows: list[list[str]], numeric: Iterable[int] = ()) -> str:
    """An HTML table from header cells and rows of cells (all already HTML); ``numeric``: the
    columns aligned as numbers."""
    numeric = set(numeric)
    cells = "".join(f"<th>{h}</th>" for h in head)
    body = "".join("<tr>" + "".join(f'<td class="num">{c}</td>' if j in numeric else f"<td>{c}</td>"
                                    for j, c in enumerate(r)) + "</tr>" for r in rows)
    return f"<table><thead><tr>{cells}</tr></thead><tbody>{body}</tbody></table>"


def _units(units: str) -> str:
    return f'<span class="unit">[{_e(units or "1")}]</span>'


def _value(x) -> str:
    """One value as the tables show it: 4 significant digits."""
    if isinstance(x, (bool, np.bool_)):
        return _e(str(bool(x)).lower())
    if isinstance(x, (int, np.integer)):
        return _e(str(int(x)))
    if isinstance(x, (float, np.floating)):
        return _e(number(float(x)))
    return _e(x)


def _warnings_html(warned: list[str], results) -> str:
    parts = []
    if warned:
        parts.append('<ul class="warnings">' + "".join(f"<li>{_e(w)}</li>" for w in warned) + "</ul>")
    else:
        parts.append("<p>The run emitted no warning.</p>")
    parts.append('<p class="muted">A result reused from an earlier run does not repeat the warnings of its '
                 "computation: <code>roughcontact report --force all</code> computes everything again.</p>")
    notes: dict[str, list[str]] = {}  # note -> the results that left it
    for variant, by_stage in results.items():
        for stage, ds in _each(by_stage):
            if ds.attrs.get("note"):
                notes.setdefault(str(ds.attrs["note"]), []).append(_label(variant, stage))
    if notes:
        parts.append("<h3>Notes of the stages</h3><ul class=\"notes\">"
                     + "".join(f"<li><b>{_e(', '.join(who))}</b>: {_e(n)}</li>" for n, who in notes.items()) + "</ul>")
    return "".join(parts)


def _figures_html(figures) -> str:
    if not figures:
        return "<p>None of the scene's stages draws a figure for this scene.</p>"
    out = []
    for name, title, png in figures:
        data = base64.b64encode(png).decode("ascii")
        out.append(f'<figure id="figure-{_e(name)}"><img src="data:image/png;base64,{data}" alt="{_e(title)}">'
                   f"<figcaption>{_e(title)} <span class=\"name\">({_e(name)})</span></figcaption></figure>")
    return "".join(out)


def _label(variant: str, stage: str) -> str:
    return stage if variant == "base" else f"{stage} [{variant}]"


def _each(by_stage):
    return ((stage, by_stage[stage]) for stage in by_stage)


def _numbers_html(results) -> str:
    declared = stages()
    out = ['<p class="muted">Per stage: its single values; the values over a few points of the scene\'s sweep in '
           "full; larger results by the range of their coordinates and values (the full tables: "
           "<code>roughcontact export</code>). <span class=\"main\">main</span> marks the outputs whose numerical "
           "error <code>roughcontact accuracy</code> measures. A single value an earlier stage of the same scene "
           "or variant already showed is not repeated.</p>"]
    for variant, by_stage in results.items():
        if len(results) > 1:
            out.append(f"<h3>{'The scene' if variant == 'base' else 'Variant ' + _e(variant)}</h3>")
        shown: dict[str, object] = {}  # single values shown for this variant
        for stage, ds in _each(by_stage):
            st = declared.get(stage)
            doc = f' <span class="muted">&mdash; {_e(st.doc)}</span>' if st is not None and st.doc else ""
            main = set(st.measured) if st is not None else set()
            out.append(f"<h4><code>{_e(_label(variant, stage))}</code>{doc}</h4>")
            out.append(_stage_numbers(ds, tables(ds, stage), main, shown))
    return "".join(out)


def _stage_numbers(ds: xr.Dataset, groups: list, main: set, shown: dict) -> str:
    """One result's tables (the export's tidy tables): its single values as a list, a group over
    few points in full, the larger groups together by ranges (each coordinate once)."""
    out, large = [], []
    for table in sorted(groups, key=lambda t: any(c in ds.dims for c in t.columns)):  # single values first
        dims = [c for c in table.columns if c in ds.dims]
        if not dims:
            out.append(_scalars_html(ds, table, main, shown))
        elif table.rows <= ROWS_IN_FULL:
            head = [_head(ds, n, table.units[n], main) for n in table.columns]
            rows = [[_value(c[i]) for c in table.columns.values()] for i in range(table.rows)]
            out.append(_table(head, rows, numeric=range(len(head))))
        else:
            large.append((table, dims))
    if large:
        out.append(_ranges_html(ds, large, main))
    return "".join(out)


def _scalars_html(ds: xr.Dataset, table, main: set, shown: dict) -> str:
    rows = []
    for name, column in table.columns.items():
        value = column[0]
        if name in shown and _same(shown[name], value):
            continue
        shown[name] = value
        rows.append([_e(ds[name].attrs.get("long_name", name)) + ('<span class="main">main</span>' if name in main
                                                                   else ""),
                     f'<span class="name">{_e(name)}</span>', _value(value), _units(table.units[name])])
    return _table(["quantity", "name", "value", "units"], rows, numeric=[2]) if rows else ""


def _same(a, b) -> bool:
    try:
        return bool(a == b) or bool(np.isnan(a) and np.isnan(b))
    except TypeError:
        return False


def _head(ds: xr.Dataset, name: str, units: str, main: set) -> str:
    """A column's header: the long name, its units and the variable's name."""
    long_name = ds[name].attrs.get("long_name", name) if name in ds.variables else name
    badge = '<span class="main">main</span>' if name in main else ""
    return f'{_e(long_name)} {_units(units)}{badge}<br><span class="name">{_e(name)}</span>'


def _ranges_html(ds: xr.Dataset, large: list, main: set) -> str:
    """The large groups by ranges: each coordinate (once) and each variable with its lowest and
    highest finite value."""
    rows, seen = [], set()
    coordinates = [d for _, dims in large for d in dims]
    names = list(dict.fromkeys(coordinates + [n for t, dims in large for n in t.columns if n not in dims]))
    units = {n: u for t, _ in large for n, u in t.units.items()}
    for name in names:
        if name in seen:
            continue
        seen.add(name)
        var = ds[name] if name in ds.variables else None
        long_name = var.attrs.get("long_name", name) if var is not None else name
        over = "coordinate" if name in coordinates else ", ".join(var.dims) if var is not None else ""
        lo, hi, count = _range(var, ds.sizes.get(name))
        badge = '<span class="main">main</span>' if name in main else ""
        rows.append([f"{_e(long_name)}{badge}", f'<span class="name">{_e(name)}</span>', _e(over), count, lo, hi,
                     _units(units.get(name, ""))])
    return _table(["quantity", "name", "over", "values", "lowest", "highest", "units"], rows, numeric=[3, 4, 5])


def _range(var: xr.DataArray | None, size: int | None) -> tuple[str, str, str]:
    """(lowest, highest, number of values) of a variable, as cells."""
    if var is None:  # a dimension without a coordinate: its index
        return "0", _e(str((size or 1) - 1)), _e(str(size))
    count = _e(f"{var.size:,}")
    if var.dtype.kind not in "fiu":  # labels (a coordinate of names): the first and the last
        flat = np.asarray(var.values).ravel() if var.size <= RANGE_LIMIT else np.array([])
        return (_e(flat[0]), _e(flat[-1]), count) if flat.size else ("", "", count)
    if var.size > RANGE_LIMIT:
        return '<span class="muted">not read</span>', "", count
    values = np.asarray(var.values, dtype=float)
    finite = values[np.isfinite(values)]
    if not finite.size:
        return "no finite value", "", count
    return _value(finite.min()), _value(finite.max()), count


def _accuracy_html(scene, outdir: Path) -> str:
    needed = engine.needed_stages(scene, scene.outputs)
    settings = accuracy_table.resolution_params(needed)
    out = [f"<p>Resolution preset: <b>{_e(scene.preset)}</b>. A setting the scene gives itself keeps its value at "
           "every preset.</p>"]
    if settings:
        rows = []
        for dotted, param in settings.items():
            section, _, key = dotted.partition(".")
            value = scene.get(dotted)
            given = isinstance(scene.raw.get(section), dict) and key in scene.raw[section]
            ladder = ", ".join(_value(v) for v in param.ladder)
            rows.append([f"<code>{_e(dotted)}</code>", _e(param.doc), _value(value) if value is not None else "-",
                         "the scene" if given else f"preset {_e(scene.preset)}", ladder])
        out.append("<h3>Resolution settings</h3>" + _table(
            ["setting", "what it resolves", "value used", "set by", "ladder, coarse to fine (last: the reference)"],
            rows, numeric=[2]))
    else:
        out.append("<p>None of the scene's stages has a resolution setting that <code>roughcontact accuracy</code> "
                   "ladders.</p>")
    out.append(_measured_html(scene, outdir, needed))
    return "".join(out)


def _measured_html(scene, outdir: Path, needed) -> str:
    """Each stage's target error and, from ``outdir/accuracy/accuracy.nc`` when it was measured for
    this scene, the error of the preset used."""
    targets = {st.name: st.measured for st in needed if st.measured}
    if not targets:
        return ""
    table = _accuracy_table(scene, outdir)
    rows = []
    for stage, outputs in targets.items():
        target = min(outputs.values())
        cells = [_e(stage), ", ".join(f'<span class="name">{_e(o)}</span>' for o in outputs), _value(target)]
        if table is not None and stage in table["stage"].values:
            err = float(table["preset_error"].sel(stage=stage, preset=scene.preset))
            verdict = '<span class="ok">meets it</span>' if err <= target else '<span class="miss">misses it</span>'
            cells += [_value(err), verdict]
        else:
            cells += ['<span class="muted">not measured</span>', ""]
        rows.append(cells)
    out = "<h3>Numerical error</h3>" + _table(
        ["stage", "main outputs", "target error (default preset)", f"measured error ({_e(scene.preset)} preset)",
         "against the target"], rows, numeric=[2, 3])
    measure = ("error = max |x - x_ref| / max(|x_ref|, 1e-6 max|x_ref|) over every point of each main output, x_ref "
               "the finest rung of the ladder")
    if table is None:
        out += (f'<p class="muted">{measure}. Not measured for this scene: <code>roughcontact accuracy</code> (or '
                "<code>roughcontact report --accuracy</code>) measures it and the report then shows it.</p>")
    else:
        stale = _stale_note(scene, outdir)
        out += (f'<p class="muted">{measure}; measured {_e(table.attrs.get("date_created", "?"))} by roughcontact '
                f'{_e(table.attrs.get("software_version", "?"))}.{stale}</p>')
    return out


def _accuracy_path(outdir: Path) -> Path:
    return Path(outdir) / "accuracy" / "accuracy.nc"


def _accuracy_table(scene, outdir: Path) -> xr.Dataset | None:
    """The accuracy table ``roughcontact accuracy`` left in the output folder for this scene, or None."""
    path = _accuracy_path(outdir)
    attrs = store.read_attrs(path)
    if attrs is None or attrs.get("scene") != scene.label:
        return None
    return store.open_result(path)


def _stale_note(scene, outdir: Path) -> str:
    path = _accuracy_path(outdir)
    scene_file = Path(scene.path) if scene.path is not None else None
    if scene_file is not None and scene_file.is_file() and scene_file.stat().st_mtime > path.stat().st_mtime:
        return (' <span class="miss">The scene file changed after the accuracy was measured: measure it again '
                "(report --accuracy).</span>")
    return ""


def _provenance_html(scene, outdir: Path, results) -> str:
    made = [["roughcontact", _e(__version__)], ["git commit", f'<code class="key">{_e(store.git_commit())}</code>'],
            ["written", _e(store.utc_now())], ["python", _e(f"{platform.python_version()} ({sys.platform})")],
            ["output folder", f"<code>{_e(outdir)}</code>"]]
    if scene.path is not None and Path(scene.path).is_file():
        made += [["scene file", f"<code>{_e(scene.path)}</code>"],
                 ["scene file sha256", f'<code class="key">{_e(store.file_sha256(Path(scene.path)))}</code>']]
    rows, files = [], []
    for variant, by_stage in results.items():
        for stage, ds in _each(by_stage):
            a = ds.attrs
            created = f'<span class="date">{_e(a.get("date_created", "?"))}</span>'
            rows.append([_e(_label(variant, stage)), _e(a.get("stage_version", "?")), created,
                         _e(a.get("software_version", "?")), f'<code class="key">{_e(a.get("git_commit", "?"))}</code>',
                         f'<code class="key">{_e(a.get("stage_key", "?"))}</code>'])
            for entry in _json(a.get("input_files", "[]")):
                files.append([_e(_label(variant, stage)), f"<code>{_e(entry.get('param', ''))}</code>",
                              f"<code>{_e(entry.get('path', ''))}</code>",
                              f'<code class="key">{_e(entry.get("sha256", ""))}</code>'])
    out = ["<h3>This report</h3>", _table(["", ""], made).replace("<thead><tr><th></th><th></th></tr></thead>", "")]
    out += ["<h3>The results</h3><p class=\"muted\">Each result's content key is a sha256 over its stage, version, "
            "the scene values it reads, its input files and its upstream results' keys: the same key, the same "
            "result.</p>",
            _table(["result", "stage version", "computed", "by roughcontact", "git commit", "content key"], rows)]
    if files:
        out += ["<h3>Input files</h3>", _table(["result", "scene key", "file", "sha256"], files)]
    return "".join(out)


def _json(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return []


def _scene_html(scene) -> str:
    if scene.path is not None and Path(scene.path).is_file():
        text = Path(scene.path).read_text(encoding="utf-8")
        return f"<p><code>{_e(scene.path)}</code></p><pre>{_e(text)}</pre>"
    return f"<p>Given as a dict (no file):</p><pre>{_e(json.dumps(scene.raw, indent=2, default=str))}</pre>"


__all__ = ["ROWS_IN_FULL", "check_target", "draw", "render", "write_report"]
