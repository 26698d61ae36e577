"""Engine: only what is stale is recomputed; results are atomic, self-describing and carry their
provenance; chunked and unchunked sweeps agree."""

import json
import os

import numpy as np
import pytest
import xarray as xr
from conftest import make_scene

from roughcontact import engine, scene as scenes, store
from roughcontact.cli import main


def _plan(raw, outdir):
    return {p.label: p for p in engine.plan(scenes.from_dict(raw), outdir)}


def test_second_run_recomputes_nothing_and_changing_E_recomputes_only_contact(tmp_path):
    out = tmp_path / "out"
    raw = make_scene()
    engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    mtimes = {p: os.stat(p).st_mtime_ns for p in out.glob("*.nc")}
    plans = _plan(raw, out)
    assert {p.status for p in plans.values()} == {"fresh"}
    engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    assert {p: os.stat(p).st_mtime_ns for p in out.glob("*.nc")} == mtimes

    changed = make_scene(material={"E": "70 GPa"})
    plans = _plan(changed, out)
    assert plans["psd"].status == "fresh"
    assert plans["contact"].status == "stale"
    assert any("material.E" in r for r in plans["contact"].reasons)
    engine.run(scenes.from_dict(changed), out, report=engine.Reporter(None))
    assert os.stat(out / "psd.nc").st_mtime_ns == mtimes[out / "psd.nc"]
    assert os.stat(out / "contact.nc").st_mtime_ns != mtimes[out / "contact.nc"]


def test_changing_the_surface_makes_both_stages_stale_and_says_why(tmp_path):
    out = tmp_path / "out"
    engine.run(scenes.from_dict(make_scene()), out, report=engine.Reporter(None))
    plans = _plan(make_scene(substrate={"H": 0.7}), out)
    assert any(r.startswith("substrate.H") for r in plans["psd"].reasons)
    assert plans["contact"].reasons == ["upstream stage psd changed"]


def test_killed_write_leaves_nothing_taken_as_valid(tmp_path, monkeypatch):
    out = tmp_path / "out"
    raw = make_scene()
    real = store._write_in_memory  # the write of a result's in-memory variables (xarray's netCDF4 store)

    def dying(self, path, *args, **kwargs):
        real(self, path, *args, **kwargs)
        with open(path, "r+b") as fh:  # half-written file, then the process "dies"
            fh.truncate(100)
        raise KeyboardInterrupt

    monkeypatch.setattr(store, "_write_in_memory", dying)
    with pytest.raises(KeyboardInterrupt):
        engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    monkeypatch.undo()
    assert not (out / "psd.nc").exists()
    assert list(out.glob(".tmp-*")) == []
    assert {p.status for p in _plan(raw, out).values()} == {"missing"}


def test_truncated_result_file_is_not_reused(tmp_path):
    out = tmp_path / "out"
    raw = make_scene()
    engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    with open(out / "contact.nc", "r+b") as fh:
        fh.truncate(200)
    plans = _plan(raw, out)
    assert plans["contact"].status == "missing" and "unreadable" in plans["contact"].reasons[0]
    res = engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    assert res["base"]["contact"].attrs["stage_key"] == plans["contact"].key


def test_leftover_temporaries_are_cleaned(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".tmp-psd.nc.abc").write_bytes(b"partial")
    engine.run(scenes.from_dict(make_scene()), out, report=engine.Reporter(None))
    assert not list(out.glob(".tmp-*"))


def test_every_variable_and_coordinate_has_units_and_provenance_round_trips(tmp_path):
    out = tmp_path / "out"
    raw = make_scene(outputs={"variables": ["stress_distribution"]})
    res = engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    for stage in ("psd", "contact"):
        with xr.open_dataset(out / f"{stage}.nc") as ds:
            for name, var in ds.variables.items():
                assert var.attrs.get("units") is not None, name
                assert var.attrs.get("long_name"), name
            a = ds.attrs
            assert a["Conventions"] == "CF-1.11"
            assert a["stage_name"] == stage and a["stage_key"] == res["base"][stage].attrs["stage_key"]
            for key in ("history", "software_version", "git_commit", "stage_version", "date_created",
                        "parameters", "input_files", "upstream_keys"):
                assert key in a
            assert a["date_created"].endswith("Z")
            params = json.loads(a["parameters"])
            if stage == "contact":
                assert params["material.E"] == pytest.approx(77.2e9)
                assert json.loads(a["upstream_keys"])["psd"] == res["base"]["psd"].attrs["stage_key"]
            xr.testing.assert_identical(ds.load(), res["base"][stage])


def test_input_file_hash_is_part_of_the_key(tmp_path):
    q = np.geomspace(1e8, 1e11, 30)
    path = tmp_path / "psd.txt"
    path.write_text("# q [1/m] C [m^4]\n" + "\n".join(f"{a:.10g} {1e-36 * (a / 1e8) ** -3.6:.10g}" for a in q))
    raw = make_scene(substrate={"kind": "psd_file", "path": str(path)}, solid=None,
                     grid={"q_min": "2e8 1/m", "q_max": "4e10 1/m"})
    out = tmp_path / "out"
    engine.run(scenes.from_dict(raw), out, report=engine.Reporter(None))
    path.write_text(path.read_text().replace("1e+11", "1.1e+11"))
    plans = _plan(raw, out)
    assert plans["psd"].status == "stale"
    assert plans["psd"].reasons == [f"input file substrate.path ({path.resolve()}) changed (sha256)"]
    stored = json.loads(store.read_attrs(out / "psd.nc")["input_files"])
    assert stored[0]["path"] == str(path.resolve()) and len(stored[0]["sha256"]) == 64


def test_chunked_and_unchunked_sweeps_agree_exactly(tmp_path):
    raw = make_scene(load={"p": {"from": "1 MPa", "to": "10 GPa", "num": 50}},
                     outputs={"variables": ["stress_distribution"]})
    plain = engine.run(scenes.from_dict(raw), tmp_path / "a", report=engine.Reporter(None))
    chunked_raw = make_scene(load={"p": {"from": "1 MPa", "to": "10 GPa", "num": 50}},
                             outputs={"variables": ["stress_distribution"]},
                             numerics={"points_per_decade": 20, "chunks": {"p": 7, "eta": 1}})
    chunked = engine.run(scenes.from_dict(chunked_raw), tmp_path / "b", report=engine.Reporter(None))
    for stage in ("psd", "contact"):
        a, b = plain["base"][stage], chunked["base"][stage]
        for name in a.data_vars:
            np.testing.assert_array_equal(a[name].values, b[name].values)


def test_only_the_stages_the_outputs_need_are_planned(tmp_path):
    plans = _plan(make_scene(outputs={"variables": ["psd_combined"]}), tmp_path)
    assert list(plans) == ["psd"]


def test_cli_run_plan_show_and_exit_codes(tmp_path, capsys, write_scene):
    path = write_scene(make_scene())
    out = str(tmp_path / "out")
    assert main(["plan", str(path), "--outdir", out]) == 1
    assert main(["run", str(path), "--outdir", out, "--quiet"]) == 0
    assert main(["plan", str(path), "--outdir", out]) == 0
    capsys.readouterr()
    assert main(["show", f"{out}/contact.nc"]) == 0
    shown = capsys.readouterr().out
    assert "contact_area_ratio" in shown and "material.E" in shown
    assert main(["run", str(path), "--outdir", out, "--quiet", "--force", "contact"]) == 0
    assert main(["run", str(path), "--outdir", out, "--quiet", "--force", "nosuchstage"]) == 2


def test_a_bad_input_file_of_a_later_stage_writes_nothing_at_all(tmp_path, capsys, write_scene):
    """Validation runs for every stage before any computes: a master curve with a negative E''
    stops the run before psd (which does not need it) is written."""
    curve = tmp_path / "curve.txt"
    curve.write_text("# f [Hz]  E' [MPa]  E'' [MPa]\n1 5 0.1\n10 6 -0.3\n100 8 1\n")
    raw = scenes.load("friction").raw
    raw.pop("variants", None)
    raw["modulus"] = {"kind": "file", "path": str(curve), "T_ref": "20 degC", "T": "20 degC"}
    raw["friction"]["v"] = ["1e-3 m/s"]
    path = write_scene(raw)
    out = tmp_path / "out"
    assert main(["run", str(path), "--outdir", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "curve.txt" in err and "line 3" in err
    assert not out.exists() or not list(out.rglob("*.nc"))


def test_a_variable_several_stages_output_comes_from_the_cheapest():
    from roughcontact.stage import producer_of

    assert producer_of("E_star").name == "contact"  # not separation or bem, which need more upstream


def test_a_result_computed_in_the_run_is_handed_downstream_without_reading_its_file(tmp_path, monkeypatch):
    """Upstream results computed in memory go to the next stage as they are (issue 27: a small run
    reads none of its files back); one reused from a file is read from it; the numbers stay those of
    a run that reads every upstream result from its file (bit for bit)."""
    raw = make_scene()
    with monkeypatch.context() as m:  # as before: every upstream result read back from its file
        m.setattr(engine, "_in_memory", lambda ds: False)
        reread = engine.run(scenes.from_dict(raw), tmp_path / "reread", report=engine.Reporter(None))
    opened = []
    real = engine._open
    monkeypatch.setattr(engine, "_open", lambda path: opened.append(path.name) or real(path))
    handed = engine.run(scenes.from_dict(raw), tmp_path / "handed", report=engine.Reporter(None), force="all",
                        open_results=False)  # as the command line runs it
    assert opened == []
    for stage in handed["base"]:
        xr.testing.assert_identical(handed["base"][stage].drop_attrs(), reread["base"][stage].drop_attrs())
    opened.clear()
    (tmp_path / "handed" / "contact.nc").unlink()
    engine.run(scenes.from_dict(raw), tmp_path / "handed", report=engine.Reporter(None), open_results=False)
    assert opened == ["psd.nc"]  # contact recomputed from the psd result of the first run, read from its file
