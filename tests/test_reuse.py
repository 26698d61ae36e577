"""Content-addressed reuse: a result's key holds what the stage reads (file contents, never
paths), so a project folder can be copied or moved, an input edit makes exactly its downstream
stale, and results of presets, undone edits and identical variant stages are never computed twice."""

from __future__ import annotations

import io
import shutil

import numpy as np
import pytest
from conftest import make_scene, toml_dumps

from roughcontact import engine, scene as scenes
from roughcontact.cli import main
from roughcontact.scenes.data.synthetic import self_affine, synthesize

pytest.importorskip("SurfaceTopography")


def _project(folder):
    """A project folder: a scene with relative paths to a measured PSD (substrate) and a height
    map (solid), and a variant with a flat solid."""
    (folder / "maps").mkdir(parents=True)
    q = np.geomspace(1e5, 1e8, 40)
    (folder / "substrate_psd.txt").write_text(
        "# q [1/m]  C [m^4]\n" + "\n".join(f"{a:.10g} {1e-30 * (a / 1e5) ** -3.6:.10g}" for a in q) + "\n")
    rng = np.random.default_rng(3)
    h = synthesize(lambda k: self_affine(k, 0.8, 1e6, 1e-30), 64, 64, 20e-6, 20e-6, rng)
    np.save(folder / "maps" / "solid.npy", h * 1e9)
    raw = make_scene(
        substrate={"kind": "psd_file", "path": "substrate_psd.txt"},
        solid={"kind": "topography", "files": ["maps/solid.npy"], "height_unit": "nm", "size_x": "20 um",
               "periodic": True, "extend": "power_law"},
        interface={"eta": 0.0},
        material={"E": "10 MPa", "nu": 0.5},
        load={"p": {"from": "1 kPa", "to": "1 MPa", "num": 5}},
        contact={"zeta": [1.0]},
        numerics={"points_per_decade": 10},
        variants={"flat_solid": {"solid": {"kind": "smooth"}}},
    )
    path = folder / "scene.toml"
    path.write_text(toml_dumps(raw))
    return path


def _plans(scene_path, outdir):
    return {p.label: p for p in engine.plan(scenes.load(scene_path), outdir)}


def _run(scene_path, outdir, **kw):
    log = io.StringIO()
    engine.run(scenes.load(scene_path, preset=kw.pop("preset", None)), outdir, report=engine.Reporter(log), **kw)
    return log.getvalue()


def test_a_copied_project_is_fresh_and_an_edited_input_makes_exactly_its_downstream_stale(tmp_path, capsys):
    scene = _project(tmp_path / "project")
    _run(scene, tmp_path / "project" / "out")
    copy = tmp_path / "elsewhere" / "copy"
    shutil.copytree(tmp_path / "project", copy)
    shutil.rmtree(tmp_path / "project")  # a move: nothing of the old place is left
    plans = _plans(copy / "scene.toml", copy / "out")
    assert {p.status for p in plans.values()} == {"fresh"}, {k: p.reasons for k, p in plans.items()}
    assert main(["plan", str(copy / "scene.toml"), "--outdir", str(copy / "out")]) == 0
    assert "stale" not in capsys.readouterr().out

    h = np.load(copy / "maps" / "solid.npy")
    np.save(copy / "maps" / "solid.npy", 1.1 * h)
    plans = _plans(copy / "scene.toml", copy / "out")
    stale = {k for k, p in plans.items() if p.status != "fresh"}
    assert stale == {"topography", "psd", "contact"}
    assert plans["topography"].reasons == ["input file solid.files[0] (maps/solid.npy) changed (sha256)"]
    assert plans["psd"].reasons == ["upstream stage topography changed"]

    _run(copy / "scene.toml", copy / "out")
    text = (copy / "substrate_psd.txt").read_text()
    (copy / "substrate_psd.txt").write_text(text.replace("e-30", "e-29", 1))
    plans = _plans(copy / "scene.toml", copy / "out")
    stale = {k for k, p in plans.items() if p.status != "fresh"}
    assert stale == {"psd", "contact", "psd [flat_solid]", "contact [flat_solid]"}
    assert plans["psd"].reasons == ["input file substrate.path (substrate_psd.txt) changed (sha256)"]


def test_a_key_covers_only_what_the_stage_reads(tmp_path):
    scene = _project(tmp_path)
    _run(scene, tmp_path / "out")
    scene.write_text(scene.read_text().replace('extend = "power_law"', 'extend = "zero"'))
    plans = _plans(scene, tmp_path / "out")
    assert plans["topography"].status == "fresh"  # it reads the map keys, not how the psd stage extends
    assert plans["psd"].reasons == ["solid.extend: 'power_law' -> 'zero'"]
    assert plans["psd [flat_solid]"].status == "fresh"  # its solid is flat: the measured one's keys are not read


def test_switching_preset_and_back_computes_nothing(tmp_path, write_scene):
    scene = write_scene(make_scene(numerics=None))  # the preset sets the q grid's points per decade
    out = tmp_path / "out"
    first = _run(scene, out)
    assert first.count("computed in") == 2
    assert _run(scene, out, preset="fast").count("computed in") == 2
    plans = _plans(scene, out)
    assert all(p.status == "stale" and p.source is not None for p in plans.values())
    back = _run(scene, out)
    assert "computed in" not in back and back.count("reused") == 2
    assert {p.status for p in _plans(scene, out).values()} == {"fresh"}
    assert "computed in" not in _run(scene, out, preset="fast")  # and forth again


def test_identical_stages_of_variants_are_computed_once(tmp_path, write_scene):
    scene = write_scene(make_scene(variants={"softer": {"material": {"E": "7 GPa"}},
                                             "same": {"load": {"p": {"from": "1 MPa", "to": "10 GPa", "num": 9}}}}))
    out = tmp_path / "out"
    log = _run(scene, out)
    assert log.count("computed in") == 3  # psd once; contact of the base (shared by 'same') and of 'softer'
    res = engine.run(scenes.load(scene), out, report=engine.Reporter(None))
    assert res["softer"]["psd"].attrs["stage_key"] == res["base"]["psd"].attrs["stage_key"]
    np.testing.assert_array_equal(res["same"]["contact"]["contact_area_ratio"],
                                  res["base"]["contact"]["contact_area_ratio"])
    assert not np.allclose(res["softer"]["contact"]["contact_area_ratio"], res["base"]["contact"]["contact_area_ratio"])


def test_forcing_a_stage_recomputes_it_even_when_a_kept_result_matches(tmp_path, write_scene):
    scene = write_scene(make_scene())
    out = tmp_path / "out"
    _run(scene, out)
    log = _run(scene, out, force=["contact"])
    assert log.count("computed in") == 1 and "reused" not in log
