"""Every built-in scene's figures say what they plot and can be read (issue 14).

Each scene is run at the fast preset and each of its figures drawn as ``roughcontact plot``
draws it; the checks read the matplotlib objects:

* a figure over a magnification names it in a title, and the curves drawn are the data at that
  zeta (not at another one); every figure of a q integral names qL, the reference of zeta;
* legends lie off every plotted line and off the titles; tick labels do not overlap;
* each case (substrate only, eta = 0, +1, -1) has one colour and marker in every figure, and no
  label says "eta = +0";
* no figure is blank: it has a title, every axes with data has both axis labels, and the PNG
  written (as ``roughcontact plot`` writes it) read back through matplotlib is not one colour.

Every built-in scene is covered (a test says so): the CI runs a representative subset (the
default, friction, topography, seal, elastoplastic and coating scenes; large_sweep and interface_bem at reduced sizes);
the others, and large_sweep and interface_bem at their full sizes, are marked slow.
"""

from __future__ import annotations

import io
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from conftest import make_scene  # noqa: E402

from roughcontact import engine, scene as scenes, store  # noqa: E402
from roughcontact.cli import main, scene_figures  # noqa: E402
from roughcontact.stages.figures.common import CASE_STYLES, at_zeta, case_of, nominal, reduce_dims  # noqa: E402

FAST = ["default", "friction", "topography", "seal", "elastoplastic", "fit", "coating"]
SLOW = ["separation", "adhesion", "bem", "bem_topography", "large_sweep", "container", "dma_flash", "validation",
        "interface_bem"]
#: scenes the CI runs at reduced sizes (their full runs are in SLOW): dotted key -> value
REDUCED = {
    "large_sweep": {"load.p.num": 30, "substrate.hrms.num": 3},
    "interface_bem": {"bem.grid": 64, "bem.realizations": 1, "load.p.num": 3},
    "elastoplastic_bem": {"bem.grid": 32, "bem.pixels_per_wavelength": 3.2, "bem.realizations": 2, "load.p.num": 5},
    "coating_bem": {"bem.grid": 64, "bem.pixels_per_wavelength": 2, "bem.realizations": 2},  # zeta = 32 as the scene
}
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
    case = "eta = 0" if "eta" in ds.dims and 0.0 in ds["eta"].values else case_of(results["base"])
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


def _check_labels(name, fig):
    """A title, and both axis labels on every axes that draws data (colour bars excepted)."""
    assert _titles(fig).strip(), f"{name}: no title"
    fig.canvas.draw()
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    for ax in axes:
        if not (_data_lines(ax) or ax.images or ax.collections):
            continue
        box = ax.get_position()
        # a label may be shared: the x label by the panels of one column, the y label by one row
        column = [a for a in axes if np.isclose(a.get_position().x0, box.x0, atol=0.02)]
        row = [a for a in axes if np.isclose(a.get_position().y0, box.y0, atol=0.02)]
        assert any(a.get_xlabel() for a in column), f"{name}: an axes without an x label"
        assert any(a.get_ylabel() for a in row), f"{name}: an axes without a y label"


def _check_png(name, path):
    """The PNG as written, read back: an image that is not one colour."""
    image = matplotlib.image.imread(path)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100, f"{name}: {image.shape}"
    assert np.ptp(image[..., :3]) > 0.5, f"{name}: a blank PNG"


def _reduced(name):
    """The built-in scene ``name`` as a dict, at the reduced sizes of :data:`REDUCED`."""
    import tomllib

    raw = tomllib.loads(scenes.resolve(name).read_text())
    for dotted, value in REDUCED[name].items():
        *path, key = dotted.split(".")
        table = raw
        for part in path:
            table = table[part]
        table[key] = value
    return raw


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
            _check_labels(f"{name}/{f.name}", fig)
            _check_zeta(f.name, fig, results)
            _check_cases(f"{name}/{f.name}", fig, seen)
            if f.name.startswith(OVER_Q):
                assert "qL = " in _titles(fig), f"{name}/{f.name}: qL not named"
            store.write_figure(fig, tmp_path / f"{f.name}.png")  # as `plot` writes it
        finally:
            plt.close(fig)
        _check_png(f"{name}/{f.name}", tmp_path / f"{f.name}.png")
        drawn.append(f.name)
    assert drawn
    assert all(len(styles) == 1 for styles in seen.values()), seen
    return drawn


def test_every_builtin_scene_is_plotted_by_a_test():
    assert set(scenes.builtin_scenes()) <= set(FAST) | set(SLOW) | set(REDUCED)


@pytest.mark.parametrize("name", sorted(REDUCED))
def test_builtin_scene_figures_reduced(name, tmp_path):
    if name in ("interface_bem", "elastoplastic_bem", "coating_bem"):
        pytest.importorskip("tamaas", reason="the BEM needs the optional extra roughcontact[bem]")
    _render(name, tmp_path, _reduced(name))


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
    raw = _reduced("large_sweep")
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


def test_plot_draws_the_interface_figures_and_announces_no_skipped_figure(tmp_path, capsys):
    """`plot seal` stopped with an internal error before drawing stiffness, conductance and
    leakage (issue 26); its one rough surface is the substrate, and the curve says so."""
    out = tmp_path / "seal"
    assert main(["plot", "seal", "--preset", "fast", "--outdir", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "skipped" not in text and "internal error" not in text
    for name in ("stiffness", "conductance", "leakage", "fig3_contact_area", "fig5_separation"):
        _check_png(name, out / "figures" / f"{name}.png")
    sc = scenes.load("seal", preset="fast")
    results = engine.run(sc, out, report=engine.Reporter(None))
    for f in scene_figures(sc)[0]:
        fig = f.make(results)
        if fig is None:  # nothing to draw for this scene (the coating figures of a homogeneous solid)
            continue
        labels = [line.get_label() for ax in fig.axes for line in ax.get_lines()]
        assert not any(label.startswith("pair") for label in labels), (f.name, labels)
        assert any(label.startswith("substrate only") for label in labels), (f.name, labels)
        plt.close(fig)


def test_a_comparison_without_its_variant_is_not_drawn(tmp_path):
    """fig8/fig9 compare with the substrate_only variant; a scene without it (dma_flash) gets no
    figure titled 'substrate only vs both rough' without that curve, and `plot` says it quietly."""
    import tomllib

    from roughcontact.stages.figures.friction import figure_area_substrate, figure_mu_substrate

    raw = tomllib.loads(scenes.resolve("friction").read_text())
    raw["friction"]["v"]["num"] = 5
    raw["numerics"]["preset"] = "fast"
    variants = raw.pop("variants")
    sc = scenes.from_dict(raw, scenes.resolve("friction"))
    results = engine.run(sc, tmp_path / "out", report=engine.Reporter(None))
    assert figure_mu_substrate(results) is None and figure_area_substrate(results) is None
    raw["variants"] = variants
    results = engine.run(scenes.from_dict(raw), tmp_path / "out", report=engine.Reporter(None))
    for make in (figure_mu_substrate, figure_area_substrate):
        fig = make(results)
        assert "substrate only" in [line.get_label() for line in fig.axes[0].get_lines()]
        plt.close(fig)


def test_variants_at_another_reference_wavenumber_are_named(tmp_path):
    """A solid PSD file from 1e8 1/m (extended as a power law) on a substrate from 2e8 1/m: the
    base's qL is 1e8, the substrate_only variant's 2e8, so one zeta reaches twice the wavenumber
    there. The figures over zeta say so, each variant with its own q range (issue 26)."""
    q = np.logspace(8, np.log10(4e10), 60)
    data = tmp_path / "solid_psd.txt"
    data.write_text("# q [1/m]  C [m^4]\n" + "\n".join(f"{x:.6e} {1e-38 * (x / 1e8) ** -3.6:.6e}" for x in q))
    raw = make_scene(solid={"kind": "psd_file", "path": str(data), "extend": "power_law"},
                     interface={"eta": 0.0}, outputs={"variables": ["contact_area_ratio", "mean_separation"]},
                     variants={"substrate_only": {"solid": {"kind": "smooth"}},
                               "stiffer": {"material": {"E": "100 GPa"}}})
    sc = scenes.from_dict(raw)
    log = io.StringIO()  # off a terminal, as in a log file: run says so too
    results = engine.run(sc, tmp_path / "out", report=engine.Reporter(log))
    said = [line for line in log.getvalue().splitlines() if line.startswith("note: psd")]
    assert any("qL = 1e8 1/m" in line for line in said) and any("qL = 2e8 1/m" in line for line in said), said
    assert float(results["base"]["contact"]["qL"]) == pytest.approx(1e8)
    assert float(results["substrate_only"]["contact"]["qL"]) == pytest.approx(2e8)
    for f in scene_figures(sc)[0]:
        if f.name.startswith(("fig3", "fig5")):
            fig = f.make(results)
            titles = _titles(fig)
            assert "zeta = 4 (q up to 4e8 1/m, qL = 1e8 1/m)" in titles, titles
            assert "substrate only: other qL, zeta = 4 (q up to 8e8 1/m, qL = 2e8 1/m)" in titles, titles
            assert "stiffer: other qL" not in titles  # its qL is the base's
            # every variant is drawn (container's `uncorrelated` was left out of Figs 3 and 5)
            labels = [line.get_label() for line in fig.axes[0].get_lines()]
            assert {"substrate only", "eta = 0", "stiffer: eta = 0"} <= set(labels), labels
            plt.close(fig)
