"""The Python API: the notebook example of docs/api.md runs as written and returns Datasets with
the expected variables; the library writes nothing to stdout; scenes come from files, names and
dicts; `import roughcontact` stays cheap."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import xarray as xr
from conftest import make_scene

import roughcontact as rc
from roughcontact.errors import UserError

ROOT = Path(__file__).resolve().parent.parent


def test_the_api_page_example_runs_and_returns_datasets(tmp_path, monkeypatch, capsys):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), flags=re.S)
    assert len(blocks) >= 4
    namespace: dict = {}
    exec(compile("\n".join(blocks), "docs/api.md", "exec"), namespace)
    printed = capsys.readouterr()
    assert "default" in printed.out and printed.err == ""  # progress=False: the library said nothing

    results = namespace["results"]
    assert set(results) == {"base", "substrate_only"}
    contact = results["base"]["contact"]
    assert isinstance(contact, xr.Dataset)
    assert {"contact_area_ratio", "stress_distribution", "E_star"} <= set(contact.data_vars)
    assert list(contact["eta"].values) == [-1.0, 0.0, 1.0]
    assert set(results["base"]) == {"psd", "contact", "separation"}
    # eta = +1 with identical surfaces: no gap roughness, full contact (eq 52)
    np.testing.assert_allclose(namespace["area"].sel(eta=1.0).values, 1.0)
    separation = namespace["separation"]
    assert separation.attrs["units"] == "m" and np.all(np.diff(separation.values, axis=separation.dims.index("p")) <= 0)
    assert namespace["ds"].attrs["stage_name"] == "contact"
    assert (tmp_path / "outputs" / "api-example" / "contact.nc").is_file()
    assert (tmp_path / "api-example.png").stat().st_size > 10_000
    # the eta sweep in memory: the area grows with the coherence at every load, to full contact at eta = +1
    by_eta = namespace["by_eta"]
    assert by_eta.sizes["eta"] == 11 and not (tmp_path / "outputs" / "eta-sweep").exists()
    assert np.all(np.diff(by_eta.transpose("p", "eta").values, axis=1) >= 0)  # A saturates at 1 at high loads
    assert np.all(np.diff(by_eta.sel(p=slice(None, 1e8)).transpose("p", "eta").values, axis=1) > 0)
    np.testing.assert_allclose(by_eta.sel(eta=1.0).values, 1.0)
    assert (tmp_path / "api-eta-sweep.png").stat().st_size > 10_000


def test_progress_goes_to_stderr_only(tmp_path, capsys):
    rc.run(make_scene(), tmp_path / "out")
    printed = capsys.readouterr()
    assert printed.out == ""
    assert printed.err.count("computed in") == 2  # not a terminal: one line per stage, no bars


def test_scenes_from_a_file_a_name_and_a_dict_agree(tmp_path, write_scene):
    raw = make_scene()
    from_file = rc.load_scene(write_scene(raw))
    from_dict = rc.load_scene(raw)
    assert from_file.values["material"] == from_dict.values["material"]
    assert rc.load_scene("friction").name == "friction" and rc.load_scene().name == "default"
    unset = make_scene(numerics=None)
    assert rc.load_scene(unset, preset="fast").values["numerics"]["points_per_decade"] == 20
    assert rc.load_scene(rc.load_scene(unset), preset="accurate").values["numerics"]["points_per_decade"] == 100
    plans = rc.plan(raw, tmp_path / "out")
    assert [(p.label, p.status) for p in plans] == [("psd", "missing"), ("contact", "missing")]
    res = rc.run(from_file, tmp_path / "out", progress=False)
    assert {p.status for p in rc.plan(raw, tmp_path / "out")} == {"fresh"}
    assert res.outdir == tmp_path / "out"
    xr.testing.assert_identical(rc.open_result(tmp_path / "out" / "contact.nc"), res["base"]["contact"])


def test_bad_input_raises_a_user_error_naming_the_key(tmp_path):
    with pytest.raises(UserError, match="material.nu"):
        rc.load_scene(make_scene(material={"nu": 0.7}))
    with pytest.raises(UserError, match="no such result file"):
        rc.open_result(tmp_path / "nothing.nc")


@pytest.mark.parametrize("call", [lambda out: rc.run(42, out, progress=False),
                                  lambda out: rc.run(["default"], out, progress=False),
                                  lambda out: rc.plan(3.5, out),
                                  lambda out: rc.load_scene(b"default"),
                                  lambda out: rc.run("default", 42, progress=False)],
                         ids=["run(42)", "run([...])", "plan(3.5)", "load_scene(bytes)", "outdir 42"])
def test_what_is_not_a_scene_is_a_type_error_and_writes_nothing(tmp_path, monkeypatch, call):
    """docs/reliability.md: anything else is a TypeError saying what is expected (not "no scene file '42'")."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError, match="expected a scene|outdir must be a folder path"):
        call(tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_open_result_refuses_a_netcdf_file_that_is_no_stage_result(tmp_path):
    xr.Dataset({"x": ("i", np.arange(3.0))}).to_netcdf(tmp_path / "foreign.nc")
    with pytest.raises(UserError, match="not the result of a roughcontact stage") as info:
        rc.open_result(tmp_path / "foreign.nc")
    assert str(tmp_path / "foreign.nc") in info.value.format()
    (tmp_path / "junk.nc").write_bytes(b"not a netcdf file")
    with pytest.raises(UserError, match="not a readable NetCDF file"):
        rc.open_result(tmp_path / "junk.nc")


def test_importing_the_package_imports_no_heavy_module():
    code = ("import sys, roughcontact; "
            "heavy = [m for m in ('xarray', 'dask', 'pint', 'matplotlib', 'netCDF4', 'scipy') if m in sys.modules]; "
            "print(heavy); roughcontact.load_scene; print('xarray' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "[]" and out[1] == "True"


def _bitwise_equal(a: xr.Dataset, b: xr.Dataset) -> list[str]:
    """The variables (and coordinates) of two results that differ in dtype, shape or any bit."""
    assert set(a.variables) == set(b.variables)
    differ = []
    for name in a.variables:
        x, y = a[name].values, b[name].values
        if x.dtype.kind == "O" or y.dtype.kind == "O":
            same = x.shape == y.shape and np.array_equal(x, y)
        else:
            same = x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        if not same or a[name].dims != b[name].dims or a[name].attrs != b[name].attrs:
            differ.append(name)
    return differ


@pytest.mark.parametrize("name", ["default", "friction", "topography"])
def test_compute_in_memory_gives_the_numbers_run_stores_bit_for_bit(name, tmp_path):
    """Every variable of every stage and variant: same dtype, dims, units and bits as the stored result."""
    scene = rc.load_scene(name, preset="fast")
    memory = rc.compute(scene, progress=False)
    stored = rc.run(scene, tmp_path / "out", progress=False)
    assert {v: set(r) for v, r in memory.items()} == {v: set(r) for v, r in stored.items()}
    for variant, by_stage in memory.items():
        for stage, ds in by_stage.items():
            assert _bitwise_equal(ds, stored[variant][stage]) == [], (variant, stage)
            assert ds.attrs["stage_key"] == stored[variant][stage].attrs["stage_key"]
            assert ds.attrs["parameters"] == stored[variant][stage].attrs["parameters"]


def test_compute_writes_nothing_and_reuses_nothing(tmp_path, monkeypatch, capsys):
    """A stored result with the same key, its numbers edited, is not read: compute recomputes;
    the output folder and the current folder are left exactly as they were."""
    monkeypatch.chdir(tmp_path)
    raw = make_scene()
    stored = rc.run(raw, progress=False)  # outputs/<name>: where compute would look if it looked
    path = stored["base"].path("contact")
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:  # same key, numbers changed: a reused file would show it
        nc.variables["contact_area_ratio"][:] = 0.5
    before = {p: (p.stat().st_mtime_ns, p.stat().st_size) for p in tmp_path.rglob("*")}
    memory = rc.compute(raw)
    after = {p: (p.stat().st_mtime_ns, p.stat().st_size) for p in tmp_path.rglob("*")}
    assert after == before
    assert capsys.readouterr().err.count("computed in memory") == 2  # both stages computed, none reused
    area = memory["base"]["contact"]["contact_area_ratio"]
    assert area.attrs["units"] == "1" and not np.any(area.values == 0.5)
    assert np.all((area.values > 0) & (area.values <= 1))


def test_compute_asks_for_outputs_and_refuses_what_run_refuses(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    only_psd = rc.compute(make_scene(), outputs="psd", progress=False)
    assert list(only_psd["base"]) == ["psd"] and "psd_combined" in only_psd["base"]["psd"]
    with pytest.raises(UserError, match="psd_combinedd.*did you mean"):
        rc.compute(make_scene(), outputs=["psd_combinedd"], progress=False)
    data = tmp_path / "psd.txt"  # read in the preflight: line 4 is out of order
    data.write_text("# q [1/m] C [m^4]\n1e8 1e-30\n1e9 1e-33\n5e8 1e-32\n")
    bad = make_scene(substrate={"kind": "psd_file", "path": str(data), "extend": "zero"}, solid=None,
                     grid={"q_min": "1e8 1/m", "q_max": "1e10 1/m"})
    with pytest.raises(UserError, match="strictly increasing") as compute_error:
        rc.compute(bad, progress=False)
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["psd.txt"]  # compute wrote nothing
    with pytest.raises(UserError) as run_error:
        rc.run(bad, tmp_path / "out", progress=False)
    assert str(compute_error.value) == str(run_error.value)  # the same check, the same words
