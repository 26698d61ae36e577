"""roughcontact accuracy: an error measure that means something for every output (relative to the
output's scale, with a stated floor), the ladder and preset bookkeeping, and a table that says
what it holds (issue 14)."""

import io

import numpy as np
import pytest
import xarray as xr
from conftest import make_scene

from roughcontact import scene as scenes
from roughcontact.accuracy import FLOOR, MEASURE, measure, scaled_error
from roughcontact.cli import main
from roughcontact.progress import Reporter


def _da(values, p=None):
    p = np.geomspace(1e6, 1e9, len(values)) if p is None else p
    return xr.DataArray(np.asarray(values, dtype=float), dims=("p",), coords={"p": p})


def test_values_far_below_the_outputs_scale_do_not_dominate():
    # a separation that is 1e-26 m at full contact: a relative error of 1 there is rounding, not an error
    ref = _da([1e-8, 3e-9, 1e-26])
    res = _da([1e-8, 3e-9, 2e-26])
    assert scaled_error(res, ref) == pytest.approx(1e-26 / (FLOOR * 1e-8))
    # above the floor the measure is the relative error
    assert scaled_error(_da([1.0, 1.001e-3]), _da([1.0, 1e-3])) == pytest.approx(1e-3)
    # and below it, the error in units of the floor (FLOOR times the largest value)
    assert scaled_error(_da([1.0, 2e-7]), _da([1.0, 1e-7])) == pytest.approx(1e-7 / FLOOR)


def test_a_point_finite_in_one_and_not_the_other_is_an_infinite_error():
    assert scaled_error(_da([1.0, np.nan]), _da([1.0, 2.0])) == np.inf
    assert scaled_error(_da([0.0, 0.0]), _da([0.0, 0.0])) == 0.0


def test_a_reference_on_another_grid_is_interpolated_in_log_coordinates():
    p_ref = np.geomspace(1e6, 1e9, 301)
    p = np.geomspace(1e6, 1e9, 7)
    law = lambda x: 3e-9 * (x / 1e6) ** -0.8  # noqa: E731  (its log is linear in log p: interpolation is exact)
    ref = xr.DataArray(np.log(law(p_ref)), dims=("p",), coords={"p": p_ref})
    res = xr.DataArray(np.log(law(p)), dims=("p",), coords={"p": p})
    assert scaled_error(res, ref) < 1e-12


def test_the_table_states_its_measure_and_reuses_runs_of_equal_settings(tmp_path, capsys):
    raw = make_scene(solid=None, interface={"eta": 0.0}, contact={"zeta": [4.0]},
                     load={"p": {"from": "1 MPa", "to": "10 GPa", "num": 5}})
    raw["numerics"] = {"points_per_decade": 20}  # explicit: every preset runs at 20, i.e. one rung
    sc = scenes.from_dict(raw)
    stream = io.StringIO()
    ds = measure(sc, tmp_path / "acc", report=Reporter(stream, bars=False))
    lines = stream.getvalue().splitlines()
    assert list(ds["stage"].values) == ["contact"]
    assert ds["rung_error"].attrs["error_measure"] == MEASURE and ds["rung_error"].attrs["error_floor"] == FLOOR
    assert float(ds["rung_error"].sel(stage="contact").isel(rung=-1)) == 0.0  # the reference against itself
    # a self-affine spectrum is integrated exactly: every rung agrees to rounding
    assert float(ds["rung_error"].max()) < 1e-12
    ladder = ds["rung_settings"].sel(stage="contact").values
    rung20 = int(np.flatnonzero(["points_per_decade=20" in s for s in ladder])[0])
    times = ds["preset_time"].sel(stage="contact").values
    assert np.all(times == ds["rung_time"].sel(stage="contact", rung=rung20).values)  # reused, not rerun
    assert any("(= rung" in line and "meets its target" in line for line in lines)
    assert list(ds["output"].values) == ["contact_area_ratio"]
    assert (tmp_path / "acc" / "accuracy.png").is_file()
    assert main(["show", str(tmp_path / "acc" / "accuracy.nc")]) == 0
    out = capsys.readouterr().out
    assert "roughcontact accuracy table" in out and "stage ?" not in out and "error measure" in out


def test_a_scene_without_measured_outputs_is_told_so_and_nothing_is_written(tmp_path):
    from roughcontact.errors import UserError

    sc = scenes.from_dict(make_scene(outputs={"variables": ["psd_combined"]}))
    with pytest.raises(UserError, match="none of this scene's stages \\(psd\\)"):
        measure(sc, tmp_path / "acc", report=Reporter(None))
    assert not (tmp_path / "acc").exists()
