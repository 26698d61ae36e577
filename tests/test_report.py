"""`roughcontact report`: one self-contained HTML page of a scene's results (figures embedded, key
numbers with units, provenance, accuracy, warnings, the scene), checked by parsing it and, where
Chromium is installed, by loading it in a real (headless) browser; bad input refused in one line
before anything is written."""

from __future__ import annotations

import base64
import os
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest
from conftest import cli_error_line, make_scene, toml_dumps

from roughcontact import store
from roughcontact.cli import main, scene_figures
from roughcontact.scene import load
from roughcontact.units import number
from roughcontact.version import __version__

PNG = b"\x89PNG\r\n\x1a\n"
OUTPUTS = {"variables": ["contact_area_ratio", "stress_distribution", "mean_separation"]}


class Page(HTMLParser):
    """What the tests read of a page: its images, its tables (header and body cells as text, and
    whether a header cell holds a unit), its text, and its links and scripts."""

    def __init__(self, text: str):
        super().__init__()
        self.images, self.tables, self.links, self.scripts, self.text = [], [], [], 0, []
        self._cell = None
        self._section = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section":
            self._section = a.get("id")
        elif tag == "img":
            self.images.append(a)
        elif tag == "table":
            self.tables.append({"section": self._section, "head": [], "rows": [], "units": []})
        elif tag == "tr" and self.tables:
            self.tables[-1]["rows"].append([])
        elif tag in ("th", "td") and self.tables:
            self._cell = [tag, ""]
        elif tag == "span" and self._cell is not None and a.get("class") == "unit" and self._cell[0] == "th":
            self.tables[-1]["units"].append(len(self.tables[-1]["head"]))
        elif tag in ("link", "iframe", "object", "embed") or tag == "a" and not a.get("href", "#").startswith("#"):
            self.links.append((tag, a))
        elif tag == "script":
            self.scripts += 1

    def handle_endtag(self, tag):
        if tag in ("th", "td") and self._cell is not None:
            kind, text = self._cell
            table = self.tables[-1]
            (table["head"] if kind == "th" else table["rows"][-1]).append(text.strip())
            self._cell = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell[1] += data


def _report(tmp_path, scene: Path, *extra) -> tuple[Path, str]:
    out = tmp_path / "out"
    assert main(["report", str(scene), "--outdir", str(out), "--quiet", *map(str, extra)]) == 0
    page = out / "report.html"
    return page, page.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def reported(tmp_path_factory):
    """A small two-surface scene with a substrate-only variant, reported once for the tests that read
    its page: (scene file, page file, page text)."""
    raw = make_scene(outputs=OUTPUTS, variants={"substrate_only": {"solid": {"kind": "smooth"}}},
                     description='Escaped? <script>alert("x")</script> & <b>bold</b>')
    folder = tmp_path_factory.mktemp("reported")
    scene = folder / "scene.toml"
    scene.write_text(toml_dumps(raw))
    page, text = _report(folder, scene)
    return scene, page, text


def test_page_is_self_contained_with_every_figure_embedded_as_png(reported):
    scene, _, text = reported
    page = Page(text)
    drawn, _ = scene_figures(load(str(scene)))
    # a declared figure may draw nothing for this scene (the coating's, on a homogeneous solid):
    # every image is one declared figure, each at most once, and the seed's three are there
    alts = [img.get("alt") for img in page.images]
    assert set(alts) <= {f.title for f in drawn} and len(set(alts)) == len(alts) >= 3, alts
    for img in page.images:
        src = img["src"]
        assert src.startswith("data:image/png;base64,"), src[:40]
        assert base64.b64decode(src.split(",", 1)[1], validate=True).startswith(PNG)
        assert img.get("alt")
    assert page.links == [] and page.scripts == 0  # nothing outside the page, nothing to run


def test_key_numbers_tables_carry_units_and_the_stored_values(reported):
    scene, page_file, text = reported
    page = Page(text)
    numbers = [t for t in page.tables if t["section"] == "numbers"]
    assert numbers
    for table in numbers:
        if "units" in table["head"]:  # a list: a units column, a unit in every row
            j = table["head"].index("units")
            assert all(r[j].startswith("[") and r[j].endswith("]") for r in table["rows"][1:])
        else:  # a table in full: a unit in every header cell
            assert table["units"] == list(range(len(table["head"]))), table["head"]
    # the effective modulus, a single value, as stored (4 digits) with its units
    ds = store.open_result(page_file.parent / "contact.nc")
    e_star = number(float(ds["E_star"]))
    assert any(r[:1] and "effective modulus" in r[0] and r[2] == e_star and r[3] == "[Pa]"
               for t in numbers for r in t["rows"])
    # the small-load law over the three coherences and two magnifications in full: 6 rows
    u0 = [t for t in numbers if any("separation_u0" in h for h in t["head"])]
    assert [len(t["rows"]) - 1 for t in u0] == [6, 2]  # the scene (eta x zeta), the variant (zeta)
    # a main output (declared tolerance) is marked
    assert "relative contact area A/A0main" in "".join(page.text)


def test_provenance_names_version_commit_and_every_results_content_key(reported):
    scene, page_file, text = reported
    assert __version__ in text and store.git_commit() in text
    assert store.file_sha256(scene) in text
    keys = [store.read_attrs(p)["stage_key"] for p in page_file.parent.rglob("*.nc")]
    assert len(keys) == 6 and all(k in text for k in keys)


def test_scene_and_every_text_are_escaped(reported):
    scene, _, text = reported
    assert "<script>" not in text and "<b>bold</b>" not in text
    page = Page(text)
    assert page.scripts == 0
    joined = "".join(page.text)
    assert 'Escaped? <script>alert("x")</script> & <b>bold</b>' in joined  # shown as text
    assert scene.read_text() in joined  # the scene file, verbatim


def test_accuracy_section_shows_settings_used_and_targets(reported):
    _, _, text = reported
    accuracy = [t for t in Page(text).tables if t["section"] == "accuracy"]
    settings = next(t for t in accuracy if t["head"][0] == "setting")
    rows = {r[0]: r for r in settings["rows"][1:]}
    assert rows["numerics.points_per_decade"][2:4] == ["20", "the scene"]  # the scene's own value
    assert rows["numerics.separation_gauss_points"][3] == "preset default"
    targets = next(t for t in accuracy if t["head"][0] == "stage")
    assert {r[0] for r in targets["rows"][1:]} == {"contact", "separation"}
    assert all(r[3] == "not measured" for r in targets["rows"][1:])


def test_warnings_of_the_run_are_on_the_page_and_results_are_reused(tmp_path, write_scene, capsys):
    raw = make_scene(outputs=OUTPUTS, contact={"yield_stress": "1 GPa"})  # load.p reaches 10 GPa
    scene = write_scene(raw)
    page, text = _report(tmp_path, scene)
    assert "roughcontact: warning: load.p reaches" in capsys.readouterr().err  # still shown on the terminal
    warned = "".join(Page(text).text)
    assert "load.p reaches 1e+10 Pa, at or above contact.yield_stress" in warned
    before = {p: p.stat().st_mtime_ns for p in page.parent.glob("*.nc")}
    _report(tmp_path, scene)
    assert {p: p.stat().st_mtime_ns for p in page.parent.glob("*.nc")} == before  # reused, not recomputed


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, write_scene, capsys):
    scene = write_scene(make_scene())
    out = tmp_path / "out"
    code, err = cli_error_line(capsys, "report", "no-such-scene", "--outdir", out)
    assert code == 2 and "no scene file 'no-such-scene'" in err and not out.exists()
    taken = tmp_path / "taken"
    taken.write_text("mine")
    code, err = cli_error_line(capsys, "report", scene, "--outdir", taken)
    assert code == 2 and str(taken) in err and "not a folder" in err and taken.read_text() == "mine"
    code, err = cli_error_line(capsys, "report", scene, "--outdir", out, "--output", taken / "report.html")
    assert code == 2 and str(taken) in err and not out.exists()
    (tmp_path / "folder").mkdir()
    code, err = cli_error_line(capsys, "report", scene, "--outdir", out, "--output", tmp_path / "folder")
    assert code == 2 and "is a folder" in err and not out.exists()


def test_a_page_that_cannot_be_written_keeps_the_old_one_and_no_temporary(tmp_path, write_scene, monkeypatch,
                                                                           capsys):
    scene = write_scene(make_scene())
    page, old = _report(tmp_path, scene)

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full_disk)
    code, err = cli_error_line(capsys, "report", scene, "--outdir", page.parent, "--quiet")
    assert code == 1 and "No space left on device" in err and str(page) in err
    assert page.read_text(encoding="utf-8") == old
    assert not [p for p in page.parent.iterdir() if p.name.startswith(store.TMP_PREFIX)]


# -- in a real browser ---------------------------------------------------------------------------

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
#: marks each image with whether the browser decoded it, once the page has loaded
PROBE = ('<script>window.addEventListener("load", function () { document.querySelectorAll("img").forEach('
         'function (i) { i.setAttribute("data-decoded", i.complete && i.naturalWidth > 0 ? "yes" : "no"); }); });'
         "</script>")


def _chromium(*args) -> subprocess.CompletedProcess:
    return subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                           "--virtual-time-budget=10000", *map(str, args)],
                          capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.skipif(CHROMIUM is None, reason="needs Chromium (the Debian package chromium), which CI does not "
                                             "install from the project's files")
def test_chromium_loads_the_page_decodes_every_image_and_draws_it(reported, tmp_path):
    from PIL import Image

    _, page, text = reported
    # the browser's own view of the images: the page with a probe that marks each decoded one
    probe = tmp_path / "probe.html"
    probe.write_text(text.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    dom = _chromium("--dump-dom", probe.as_uri())
    assert dom.returncode == 0, dom.stderr[-2000:]
    seen = Page(dom.stdout).images
    assert len(seen) == len(Page(text).images) >= 3
    assert [img.get("data-decoded") for img in seen] == ["yes"] * len(seen)
    # a broken image is told apart by the same probe
    broken = tmp_path / "broken.html"
    broken.write_text(f'<html><body><img src="data:image/png;base64,AAAA">{PROBE}</body></html>')
    assert Page(_chromium("--dump-dom", broken.as_uri()).stdout).images[0].get("data-decoded") == "no"
    # the page itself, drawn
    shot = tmp_path / "report.png"
    done = _chromium(f"--screenshot={shot}", "--window-size=1200,3000", page.as_uri())
    assert shot.is_file(), done.stderr[-2000:]
    with Image.open(shot) as im:
        colours = im.convert("RGB").getcolors(maxcolors=1 << 16)
        assert im.size == (1200, 3000)
        assert colours is None or len(colours) > 50  # text, tables and figures: far from one colour


@pytest.mark.slow
def test_report_accuracy_measures_and_shows_the_error_of_the_preset_used(tmp_path, write_scene):
    """(about 30 s: ``roughcontact accuracy`` runs each rung three times.)"""
    scene = write_scene(make_scene(outputs={"variables": ["contact_area_ratio", "mean_separation"]}))
    page, text = _report(tmp_path, scene, "--accuracy")
    table = store.open_result(page.parent / "accuracy" / "accuracy.nc")
    rows = {r[0]: r for t in Page(text).tables if t["section"] == "accuracy" and t["head"][0] == "stage"
            for r in t["rows"][1:]}
    for stage in ("contact", "separation"):
        error = float(table["preset_error"].sel(stage=stage, preset="default"))
        target = float(table["tolerance"].sel(stage=stage))
        assert rows[stage][3] == number(error)
        assert rows[stage][4] == ("meets it" if error <= target else "misses it")
