"""The BEM's maps as optional outputs (issue 29 item 4): the contact pressure and gap maps of one
realization at chosen loads, stored by the ``bem`` and ``interface_bem`` stages, sized and checked
before any solve, and drawn (pressure map, contact patches, gap map with the percolating channel).

Facts asserted: a pressure map carries the load (its mean is the nominal pressure: force
balance); its contact fraction is the stage's own A/A0 of that load and realization, and the gap
map's mean its mean separation; identical surfaces (eta = 1) touch everywhere at the nominal
pressure with no gap; the interface stage's gap map gives, through the Reynolds solver, the flow
factor it stores, and it percolates exactly where that flow is not zero; the percolating cells
are whole open clusters, and there are some exactly when the map percolates.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import cli_error_line

from roughcontact import sizing
from roughcontact.physics.reynolds import flow_factors, percolates, percolating_cells

E_STAR = 77.2e9 / (1 - 0.42**2)
SURFACE = {"kind": "self_affine", "H": 0.8, "qL": "2e8 1/m", "q0": "8e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}
LOADS = (0.005, 0.03, 0.12)  # p / E*
MAPS = ["bem_pressure_map", "bem_gap_map", "exact_pressure_map", "exact_gap_map"]


def scene(grid=64, outputs=("bem_contact_area_ratio", "exact_leak_rate", *MAPS), **bem):
    """Two self-affine surfaces, eta 0 and 1, three loads; the BEM's band is zeta = grid / 4 (64: 16, 512: 128)."""
    return {
        "name": "bem-fields-test", "substrate": dict(SURFACE), "solid": dict(SURFACE),
        "interface": {"eta": [0.0, 1.0]}, "material": {"E": "77.2 GPa", "nu": 0.42},
        "load": {"p": [f"{E_STAR * x!r} Pa" for x in LOADS]}, "contact": {"zeta": [16.0, 128.0]},
        "leakage": {"viscosity": "1 mPa*s", "pressure_drop": "1 kPa", "seal_width": "1 mm", "seal_length": "1 mm"},
        "bem": {"grid": grid, "realizations": 2, "seed": 5, "pixels_per_wavelength": 4,
                "field_p": [f"{E_STAR * x!r} Pa" for x in LOADS[1:]], "field_realization": 1, **bem},
        "outputs": {"variables": list(outputs)}, "numerics": {"points_per_decade": 20},
    }


# -- the percolating cells (physics, no solver needed) ------------------------------------------

def test_percolating_cells_are_the_channel_and_not_the_pools():
    mask = np.zeros((8, 8), dtype=bool)
    mask[:, 3] = True  # a channel along the first index
    mask[5, 6] = True  # a pool
    channel = np.zeros_like(mask)
    channel[:, 3] = True
    assert np.array_equal(percolating_cells(mask, 0), channel)
    assert not percolating_cells(mask, 1).any()
    stair = np.eye(8, dtype=bool) | np.roll(np.eye(8, dtype=bool), 1, axis=1)  # a diagonal wrapping both ways
    assert np.array_equal(percolating_cells(stair, 0), stair) and np.array_equal(percolating_cells(stair, 1), stair)


@pytest.mark.parametrize("density", [0.3, 0.5, 0.6, 0.7])
def test_percolating_cells_are_whole_clusters_and_exist_exactly_when_the_map_percolates(density):
    rng = np.random.default_rng(int(density * 10))
    for _ in range(20):
        mask = rng.random((24, 24)) < density
        for axis in (0, 1):
            cells = percolating_cells(mask, axis)
            assert cells.any() == percolates(mask, axis)
            assert not (cells & ~mask).any()
            for a in (0, 1):  # closed under open neighbours: a cluster is in whole or not at all
                for shift in (1, -1):
                    assert not (cells & np.roll(mask & ~cells, shift, a)).any()


# -- the stages (need tamaas) -------------------------------------------------------------------

@pytest.fixture(scope="module")
def results(tmp_path_factory):
    pytest.importorskip("tamaas")
    from roughcontact import engine, scene as scenes

    out = tmp_path_factory.mktemp("fields")
    return engine.run(scenes.from_dict(scene()), out, report=engine.Reporter(None))["base"]


def test_maps_are_stored_at_the_chosen_loads_over_the_maps_pixels(results):
    ds = results["bem"]
    np.testing.assert_allclose(ds["bem_field_p"].values, E_STAR * np.array(LOADS[1:]), rtol=1e-12)
    assert ds["bem_pressure_map"].dims == ("bem_field_p", "eta", "bem_x", "bem_y")
    assert ds.sizes["bem_x"] == ds.sizes["bem_y"] == 64
    np.testing.assert_allclose(np.diff(ds["bem_x"].values), float(ds["bem_pixel_size"]), rtol=1e-12)
    assert ds["bem_pressure_map"].attrs["units"] == "Pa" and ds["bem_gap_map"].attrs["units"] == "m"


@pytest.mark.parametrize("stage, pressure, gap, area, mean_gap", [
    ("bem", "bem_pressure_map", "bem_gap_map", "bem_contact_area_ratio", "bem_mean_gap"),
    ("interface_bem", "exact_pressure_map", "exact_gap_map", "exact_contact_area_ratio", "exact_mean_gap")])
def test_a_map_carries_the_load_and_is_the_stages_own_solution(results, stage, pressure, gap, area, mean_gap):
    ds = results[stage].sel(eta=0.0)
    for p in ds["bem_field_p"].values:
        P = ds[pressure].sel(bem_field_p=p).values
        g = ds[gap].sel(bem_field_p=p).values
        assert np.all(P >= 0) and np.all(g >= 0)
        np.testing.assert_allclose(P.mean(), p, rtol=1e-8)  # force balance
        at = ds.sel(p=p, realization=1)
        assert np.count_nonzero(P > 0) / P.size == float(at[area])  # the stored realization's A/A0
        assert float(at[area]) != float(ds.sel(p=p, realization=0)[area])  # ... and not the other one's
        np.testing.assert_allclose(g.mean(), float(at[mean_gap]), rtol=1e-6)


def test_identical_surfaces_touch_everywhere_at_the_nominal_pressure(results):
    ds = results["bem"].sel(eta=1.0)
    for p in ds["bem_field_p"].values:
        np.testing.assert_allclose(ds["bem_pressure_map"].sel(bem_field_p=p), p, rtol=1e-12)
        assert np.all(ds["bem_gap_map"].sel(bem_field_p=p) == 0)


def test_the_interface_gap_map_is_the_one_the_flow_went_through(results):
    ds = results["interface_bem"].sel(eta=0.0)
    for p in ds["bem_field_p"].values:
        g = ds["exact_gap_map"].sel(bem_field_p=p).values
        flow = float(ds["exact_flow_factor"].sel(p=p, realization=1))
        np.testing.assert_allclose(np.mean(flow_factors(g)), flow, rtol=1e-9)
        assert (flow > 0) == (percolates(g > 0, 0) or percolates(g > 0, 1))


def test_the_figures_draw_the_maps(results, tmp_path):
    from PIL import Image

    from roughcontact.stages.figures.bem_fields import field_figures

    for stage in ("bem", "interface_bem"):
        for figure in field_figures(stage):
            fig = figure.make({"base": results})
            path = tmp_path / f"{figure.name}.png"
            fig.savefig(path, dpi=60)
            with Image.open(path) as im:
                assert len(im.convert("RGB").getcolors(1 << 20)) > 100  # maps, not an empty frame


# -- bad input, refused before anything is written -------------------------------------------------

def _refused(capsys, tmp_path, write_scene, raw, *expected):
    out = tmp_path / "out"
    code, err = cli_error_line(capsys, "run", write_scene(raw), "--outdir", out, "--quiet")
    assert code == 2 and all(text in err for text in expected), err
    assert not list(out.rglob("*.nc"))
    return err


def test_a_load_the_bem_does_not_solve_at_is_refused(tmp_path, write_scene, capsys):
    pytest.importorskip("tamaas")
    _refused(capsys, tmp_path, write_scene, scene(field_p=["1 GPa"]), "bem.field_p", "1 GPa",
             "is not one of the loads load.p")


def test_a_realization_beyond_those_solved_is_refused(tmp_path, write_scene, capsys):
    pytest.importorskip("tamaas")
    _refused(capsys, tmp_path, write_scene, scene(field_realization=2), "bem.field_realization",
             "beyond the 2 realization(s)")


def test_maps_too_large_for_the_disk_are_refused_before_any_solve(tmp_path, write_scene, capsys, monkeypatch):
    pytest.importorskip("tamaas")
    monkeypatch.setattr(sizing, "free_disk", lambda path: 4 * 2**20)  # 4 MiB free; the maps: 2 x 2 x 512^2 x 8 B
    outputs = ("bem_contact_area_ratio",)
    path = write_scene(scene(grid=512, outputs=outputs))
    assert cli_error_line(capsys, "plan", path, "--outdir", tmp_path / "out")[0] == 1  # fits: would run
    err = _refused(capsys, tmp_path, write_scene, scene(grid=512, outputs=(*outputs, "bem_gap_map")),
                   "bem.nc", "on disk")
    assert "bem.grid" in err or "bem.field_p" in err
