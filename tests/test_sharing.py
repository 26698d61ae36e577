"""Result files collaborators can use: readable as the umask says, CF-clean (compliance-checker
reports no error), compressed, and naming the software version and commit that made them."""

from __future__ import annotations

import os
import stat
import subprocess
from pathlib import Path

import netCDF4
import numpy as np
import pytest
from conftest import make_scene

import roughcontact
from roughcontact import engine, scene as scenes

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o027, 0o640), (0o002, 0o664)])
def test_a_result_file_has_the_mode_the_umask_gives(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        engine.run(scenes.from_dict(make_scene()), tmp_path / "out", report=engine.Reporter(None))
    finally:
        os.umask(old)
    for name in ("psd.nc", "contact.nc"):
        assert stat.S_IMODE((tmp_path / "out" / name).stat().st_mode) == mode


def test_the_default_scene_is_cf_clean_for_compliance_checker(tmp_path):
    pytest.importorskip("compliance_checker")
    from benchmarks.cf_report import cf_errors, result_files

    engine.run(scenes.load("default"), tmp_path / "out", report=engine.Reporter(None))
    files = result_files(tmp_path / "out")
    assert len(files) == 6
    found = {str(f.relative_to(tmp_path / "out")): cf_errors(f) for f in files}
    assert found == {name: [] for name in found}


def test_sweeps_are_stored_increasing_and_the_values_follow_them(tmp_path):
    raw = make_scene(interface={"eta": [0.0, 1.0, -1.0]}, load={"p": ["1 GPa", "10 MPa", "100 MPa"]})
    res = engine.run(scenes.from_dict(raw), tmp_path / "out", report=engine.Reporter(None))
    contact = res["base"]["contact"]
    assert list(contact["eta"].values) == [-1.0, 0.0, 1.0]
    assert np.all(np.diff(contact["p"].values) > 0)
    # eta = 1 with identical surfaces: the gap is flat, full contact at any load (eq 52)
    np.testing.assert_allclose(contact["contact_area_ratio"].sel(eta=1.0).values, 1.0)
    area = contact["contact_area_ratio"].sel(eta=-1.0, zeta=4.0).values
    assert np.all(np.diff(area) > 0)  # more load, more contact, in the stored order
    with netCDF4.Dataset(tmp_path / "out" / "contact.nc") as nc:
        for name in ("p", "eta", "zeta"):
            assert "_FillValue" not in nc.variables[name].ncattrs()


def test_large_variables_are_compressed_in_chunks_along_the_sweep(tmp_path):
    raw = make_scene(load={"p": {"from": "1 MPa", "to": "10 GPa", "num": 400}},
                     outputs={"variables": ["stress_distribution"]},
                     numerics={"points_per_decade": 20, "chunks": {"p": 100}})
    res = engine.run(scenes.from_dict(raw), tmp_path / "out", report=engine.Reporter(None))
    with netCDF4.Dataset(tmp_path / "out" / "contact.nc") as nc:
        var = nc.variables["stress_distribution"]
        assert var.filters()["zlib"] and var.filters()["shuffle"]
        chunks = dict(zip(var.dimensions, var.chunking(), strict=True))  # zlib: chunked, one size per dimension
        assert chunks["p"] == 100  # the chunks it was computed in
        assert chunks["stress_level"] == nc.dimensions["stress_level"].size
    assert np.isfinite(res["base"]["contact"]["stress_distribution"].values).all()


def test_provenance_names_the_version_and_the_commit(tmp_path):
    res = engine.run(scenes.from_dict(make_scene()), tmp_path / "out", report=engine.Reporter(None))
    attrs = res["base"]["psd"].attrs
    assert attrs["software_version"] == roughcontact.__version__ != "0+unbuilt"
    assert "unknown" not in attrs["git_commit"]
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    if head.returncode == 0:  # a checkout: the commit is the one checked out (full or abbreviated)
        assert head.stdout.strip().startswith(attrs["git_commit"].removesuffix("-dirty"))


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(scenes.builtin_scenes()))
def test_every_builtin_scene_is_cf_clean(tmp_path, name):
    pytest.importorskip("compliance_checker")
    from benchmarks.cf_report import cf_errors, result_files

    sc = scenes.load(name)
    if any(p.stage.name == "bem" for p in engine.plan(sc, tmp_path)):
        pytest.importorskip("tamaas")
    engine.run(sc, tmp_path / "out", report=engine.Reporter(None))
    found = {str(f.relative_to(tmp_path / "out")): cf_errors(f) for f in result_files(tmp_path / "out")}
    assert found and found == {name: [] for name in found}
