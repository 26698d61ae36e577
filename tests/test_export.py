"""`roughcontact export`: tidy CSV and Excel tables whose numbers are the NetCDF results' bit for
bit, with units in the header and provenance; bad input refused in one line before anything is
written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import make_scene

from roughcontact import store
from roughcontact.cli import main
from roughcontact.export import read_csv


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def _expected(ds: xr.Dataset, name: str, dims: list[str]) -> np.ndarray:
    """A result's variable as the tidy table holds it: over ``dims`` (the last fastest), flattened."""
    da = ds[name]
    if name in dims:  # a key column: the coordinate repeated over the table's other dimensions
        return np.meshgrid(*(ds[d].values for d in dims), indexing="ij")[dims.index(name)].ravel()
    return da.transpose(*dims).values.ravel()


def test_csv_tables_give_back_the_netcdf_numbers_bit_for_bit(tmp_path, write_scene, capsys):
    scene = write_scene(make_scene(outputs={"variables": ["contact_area_ratio", "mean_separation"]}))
    out = tmp_path / "out"
    assert main(["export", str(scene), "--outdir", str(out), "--quiet"]) == 0
    written = capsys.readouterr().out.split()
    assert written and all(p.endswith(".csv") for p in written)
    checked = set()
    for path in map(Path, written):
        meta, columns, units = read_csv(path)
        ds = store.open_result(path.parents[1] / f"{meta['stage_name']}.nc")
        assert meta["stage_key"] == ds.attrs["stage_key"] and meta["exported_from"].endswith(f"{meta['stage_name']}.nc")
        dims = [c for c in columns if c in ds.dims]
        rows = int(np.prod([ds.sizes[d] for d in dims]))
        for name, values in columns.items():
            assert units[name] == ds[name].attrs.get("units", "")  # units in the header row
            assert len(values) == rows
            assert _same_bits(values, _expected(ds, name, dims)), (path.name, name)
            checked.add((meta["stage_name"], name))
    for stage, name in [("contact", "contact_area_ratio"), ("contact", "p"), ("separation", "mean_separation"),
                        ("contact", "E_star"), ("psd", "psd_combined")]:
        assert (stage, name) in checked
    # every variable of every stage is in some table
    for stage in ("psd", "contact", "separation"):
        assert set(store.open_result(out / f"{stage}.nc").data_vars) <= {n for s, n in checked if s == stage}


def test_xlsx_workbook_per_stage_with_provenance_sheet_and_16_digit_numbers(tmp_path, write_scene, capsys):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("openpyxl")
    scene = write_scene(make_scene())
    out = tmp_path / "out"
    assert main(["export", str(scene), "--outdir", str(out), "--format", "xlsx", "--quiet",
                 "--variables", "contact_area_ratio"]) == 0
    assert capsys.readouterr().out.split() == [str(out / "tables" / "contact.xlsx")]  # psd has none of them
    sheets = pd.read_excel(out / "tables" / "contact.xlsx", sheet_name=None)
    assert list(sheets) == ["contact", "provenance"]
    table = sheets["contact"]
    assert list(table.columns) == ["eta [1]", "zeta [1]", "p [Pa]", "contact_area_ratio [1]"]
    ds = store.open_result(out / "contact.nc")
    dims = ["eta", "zeta", "p"]
    for head in table.columns:  # openpyxl writes 16 significant digits: the last bits of a double may go
        name = head.partition(" [")[0]
        np.testing.assert_allclose(table[head].to_numpy(), _expected(ds, name, dims), rtol=5e-16, atol=0)
    prov = dict(zip(sheets["provenance"]["attribute"], sheets["provenance"]["value"], strict=True))
    assert prov["stage_key"] == ds.attrs["stage_key"] and prov["stage_name"] == "contact"


def test_a_conductance_against_pressure_for_an_fe_code(tmp_path, capsys):
    """The seal scene's thermal contact conductance as one table over the load (per
    magnification): it rises with the pressure (more and larger contacts conduct)."""
    out = tmp_path / "seal"
    assert main(["export", "seal", "--preset", "fast", "--outdir", str(out), "--quiet",
                 "--variables", "thermal_contact_conductance"]) == 0
    (path,) = map(Path, capsys.readouterr().out.split())
    meta, columns, units = read_csv(path)
    assert meta["stage_name"] == "conductance"
    assert units == {"zeta": "1", "p": "Pa", "thermal_contact_conductance": "W/(m^2*K)"}  # per magnification
    for zeta in np.unique(columns["zeta"]):
        at = columns["zeta"] == zeta
        assert np.all(np.diff(columns["p"][at]) > 0) and np.all(np.diff(columns["thermal_contact_conductance"][at]) > 0)


@pytest.mark.parametrize("args, expected", [
    (["--format", "xls"], "--format: unknown table format 'xls'"),
    (["--variables", "contact_area_ration"], "--variables: 'contact_area_ration' is not among this scene's results"),
    (["--variables", "mean_separation"], "add a variable to outputs.variables"),
])
def test_bad_options_are_one_line_errors_before_anything_is_written(tmp_path, write_scene, capsys, args, expected):
    scene = write_scene(make_scene())
    out = tmp_path / "out"
    assert main(["export", str(scene), "--outdir", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert expected in err and err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("file_at", [".", "tables"])
def test_an_output_folder_that_is_a_file_is_refused_before_anything_is_written(tmp_path, write_scene, capsys,
                                                                                file_at):
    scene = write_scene(make_scene())
    out = tmp_path / "out"
    blocker = out / file_at if file_at != "." else out
    blocker.parent.mkdir(parents=True, exist_ok=True)
    blocker.write_text("not a folder")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    assert main(["export", str(scene), "--outdir", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(blocker) in err and "is not a folder" in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.rglob("*")) == before  # no result computed, no table
