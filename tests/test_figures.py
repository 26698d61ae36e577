"""Every built-in scene's figures say what they plot and can be read (issue 14).

Each scene is run at the fast preset and each of its figures drawn as ``roughcontact plot``
draws it; the checks read the matplotlib objects:

* a figure over a magnification names it in a title, and the curves drawn are the data at that
  zeta (not at another one); every figure of a q integral names qL, the reference of zeta;
* legends lie off every plotted line and off the titles; tick labels do not overlap;
* each case (substrate only, eta = 0, +1, -1) has one colour and marker in every figure, and no
  label says "eta = +0";
* no figure is blank.

The CI runs a representative subset (the default, friction and topography scenes and a small
large sweep); the others are marked slow.
"""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from roughcontact import engine, scene as scenes  # noqa: E402
from roughcontact.cli import scene_figures  # noqa: E402
from roughcontact.stages.figures.common import CASE_STYLES, at_zeta, nominal, reduce_dims  # noqa: E402

FAST = ["default", "friction", "topography"]
SLOW = ["separation", "adhesion", "bem", "bem_topography", "large_sweep", "container", "dma_flash", "validation"]
#: figures drawn from a q integral (they name qL)
OVER_Q = ("fig3", "fig4", "fig5", "bem_comparison", "fig1", "fig2", "fig6", "fig8", "fig9", "fig10", "fig11",
          "flash_temperature", "bands_contact_area", "bands_separation", "bands_stress")
ZETA = re.compile(r"zeta = ([0-9.eE+-]+)")


def _titles(fig) -> str:
    texts = [fig._suptitle.get_text()] if fig._suptitle is not None else []
    texts += [t.get_text() for ax in fig.axes for t in (ax.title, ax._left_title, ax._right_title)]
    return "\n".join(texts)


def _data_lines(ax):
    """Lines with finite data (not axhline/axvline helpers, which span the axes)."""
    out = []
    for line in ax.get_lines():
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        if x.size > 1 and np.any(np.isfinite(x) & np.isfinite(y)) and np.ptp(x[np.isfinite(x)]) > 0:
            out.append(line)
    return out


def _legend_boxes(fig, renderer):
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    return [leg.get_window_extent(renderer) for leg in legends]


def _check_layout(name, fig):
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legends = _legend_boxes(fig, renderer)
    drawn = 0
    for ax in fig.axes:
        for line in _data_lines(ax):
            drawn += 1
            box = line.get_window_extent(renderer)
            shown = box.intersection(box, ax.bbox)  # what is drawn is clipped to the axes
            for leg in legends:
                assert shown is None or not leg.overlaps(shown), f"{name}: legend over line {line.get_label()!r}"
        drawn += len(ax.images) + sum(len(c.get_paths()) > 0 for c in ax.collections)
        for axis in (ax.xaxis, ax.yaxis):
            boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
            for a, b in zip(boxes, boxes[1:], strict=False):
                assert not a.overlaps(b), f"{name}: tick labels overlap on {axis.axis_name}"
    titles = [t for t in ([fig._suptitle] if fig._suptitle else []) + [ax.title for ax in fig.axes] if t.get_text()]
    for t in titles:
        for leg in legends:
            assert not leg.overlaps(t.get_window_extent(renderer)), f"{name}: legend over the title"
    assert drawn > 0, f"{name}: a blank figure"


def _matches(values, ds_at, var, scale=1.0):
    # draw 0: the measured spectrum
    ref = np.atleast_1d(nominal(reduce_dims(ds_at, ("p",), var)[0][var]).values) * scale
    return ref.shape == values.shape and np.allclose(values, ref, rtol=1e-9, equal_nan=True)


def _check_zeta(name, fig, results):
    """The zeta in the title is the one whose data are drawn (Figs 3 and 5: first curve)."""
    found = ZETA.findall(_titles(fig))
    stage = {"fig3": "contact", "fig4": "contact", "fig5": "separation", "bem": "bem"}.get(name.split("_")[0])
    if stage is None:
        return
    assert found, f"{name}: no 'zeta = ...' in the titles"
    zeta = float(found[0])
    if stage == "bem":
        assert zeta == pytest.approx(float(results["base"]["bem"]["bem_zeta"]), rel=1e-3)
        return
    ds = results["base"][stage]
    zetas = np.atleast_1d(ds["zeta"].values)
    assert np.min(np.abs(zetas / zeta - 1)) < 1e-3, f"{name}: zeta = {zeta} is not a computed magnification"
    if name.startswith("fig4"):
        return
    case = "eta = 0" if "eta" in ds.dims and 0.0 in ds["eta"].values else "pair"
    line = next(ln for ax in fig.axes for ln in _data_lines(ax) if ln.get_label().startswith(case))
    data = ds.sel(eta=0.0) if case == "eta = 0" else ds
    x, y = (np.asarray(v, dtype=float) for v in line.get_data())
    var, values, scale = ("contact_area_ratio", y, 1.0) if stage == "contact" else ("mean_separation", x, 1e9)
    hits = [z for z in zetas if _matches(values, at_zeta(data, z), var, scale)]
    assert hits and np.isclose(hits[0], zeta, rtol=1e-3), f"{name}: drawn at zeta {hits}, titled zeta = {zeta}"


def _check_cases(name, fig, seen):
    for ax in fig.axes:
        for line in ax.get_lines():
            label = line.get_label()
            assert not re.search(r"eta = [+-]0(?![.\d])", label), f"{name}: {label!r}"
            case = next((c for c in CASE_STYLES if c in label), None)
            if case is None or line.get_marker() in ("None", "", None):
                continue
            style = (matplotlib.colors.to_hex(line.get_color()), line.get_marker())
            expected = (matplotlib.colors.to_hex(CASE_STYLES[case]["color"]), CASE_STYLES[case]["marker"])
            assert style == expected, f"{name}: {label!r} drawn as {style}, its case is {expected}"
            seen.setdefault(case, set()).add(style)


def _render(name, tmp_path, raw=None):
    sc = scenes.from_dict(raw, scenes.resolve(name)) if raw is not None else scenes.load(name, preset="fast")
    results = engine.run(sc, tmp_path / "out", report=engine.Reporter(None))
    figures, _ = scene_figures(sc)
    seen: dict[str, set] = {}
    drawn = []
    for f in figures:
        fig = f.make(results)
        if fig is None:
            continue
        try:
            _check_layout(f"{name}/{f.name}", fig)
            _check_zeta(f.name, fig, results)
            _check_cases(f"{name}/{f.name}", fig, seen)
            if f.name.startswith(OVER_Q):
                assert "qL = " in _titles(fig), f"{name}/{f.name}: qL not named"
        finally:
            plt.close(fig)
        drawn.append(f.name)
    assert drawn
    assert all(len(styles) == 1 for styles in seen.values()), seen
    return drawn


@pytest.mark.parametrize("name", FAST)
def test_builtin_scene_figures(name, tmp_path):
    _render(name, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_builtin_scene_figures_slow(name, tmp_path):
    _render(name, tmp_path)


def test_a_large_sweep_is_summarised(tmp_path):
    """large_sweep's dimensions (21 coherences, an hrms sweep, every zeta) on fewer points: a
    colour map and the seed's three cases, not one curve per point of the sweep."""
    import tomllib

    raw = tomllib.loads(scenes.resolve("large_sweep").read_text())
    raw["load"]["p"]["num"] = 30
    raw["substrate"]["hrms"]["num"] = 3
    assert _render("large_sweep", tmp_path, raw) == ["fig3_contact_area"]
    sc = scenes.from_dict(raw, scenes.resolve("large_sweep"))
    results = engine.run(sc, tmp_path / "out", report=engine.Reporter(None))
    fig = scene_figures(sc)[0][0].make(results)
    assert len(fig.axes[0].collections) == 1  # the colour map
    assert len(_data_lines(fig.axes[1])) == 3
    plt.close(fig)


def test_coherence_figure_is_not_drawn_for_one_map(tmp_path):
    from roughcontact.stages.figures.topography import figure_coherence

    raw = {"material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "0.1 MPa"},
           "substrate": {"kind": "topography", "files": ["data/substrate_map.npy"], "height_unit": "nm",
                         "size_x": "20 um", "periodic": True}}
    pytest.importorskip("SurfaceTopography")
    sc = scenes.from_dict(raw, scenes.resolve("topography"))
    results = engine.run(sc, tmp_path / "out", targets=("topography",), report=engine.Reporter(None))
    assert figure_coherence(results) is None
