"""Tests of the interface_bem stage: theory against the exact leak rate (Reynolds flow through
the BEM's gap map) and the BEM's contact stiffness, on small synthesized maps (issue 17).

Needs tamaas (the bem extra). Facts asserted: the stage's exact flow factor is the Reynolds flow
of the solver's own gap map; the exact leak rate falls with load, is 0 at and above the
sealing load and positive below it; identical surfaces (eta = 1) seal at any load (zero flow,
infinite stiffness, sealing load 0); the contact area at the sealing load is near the 0.42 of
Dapp et al. (2012); the stiffness of the theory is within 25 % of the BEM's at small load and
the critical-junction leak rate within a factor of 3 of the exact one away from the threshold.
The larger comparison (256^2, 4 realizations, the example maps) is tests/benchmarks/bench_interface.py.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("tamaas")

from roughcontact.physics.bem import contact_pair  # noqa: E402
from roughcontact.physics.reynolds import flow_factors  # noqa: E402
from roughcontact.physics.synthesis import grid_band, synthesize_pair, white_noise_pair  # noqa: E402

E_STAR = 77.2e9 / (1 - 0.42**2)
SURFACE = {"kind": "self_affine", "H": 0.8, "qL": "2e8 1/m", "q0": "8e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}


def scene(grid=64, eta=(0.0, 1.0), pressures=(0.005, 0.02, 0.08)):
    return {
        "name": "interface-bem-test", "substrate": dict(SURFACE), "solid": dict(SURFACE),
        "interface": {"eta": list(eta)}, "material": {"E": "77.2 GPa", "nu": 0.42},
        "load": {"p": [f"{E_STAR * x!r} Pa" for x in pressures]},
        "leakage": {"viscosity": "1 mPa*s", "pressure_drop": "1 kPa", "seal_width": "1 mm", "seal_length": "1 mm"},
        "bem": {"grid": grid, "realizations": 1, "seed": 3, "pixels_per_wavelength": 4},
        "outputs": {"variables": ["exact_leak_rate"]}, "numerics": {"points_per_decade": 20},
    }


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    from roughcontact import engine, scene as scenes

    sc = scenes.from_dict(scene())
    return engine.run(sc, tmp_path_factory.mktemp("ibem"), report=engine.Reporter(None))["base"]


def test_exact_flow_is_the_reynolds_flow_of_the_solvers_gap(result):
    ds = result["interface_bem"]
    psd = result["psd"]
    q = psd["q"].values
    _, dx, q_cut, zeta = grid_band(q[0], q[-1], 64, 4)
    noise = white_noise_pair(64, 3, 0, band=zeta)
    h1, h2 = synthesize_pair(q, psd["psd_substrate"].values, psd["psd_solid"].values, 0.0, 64, q_cut, noise=noise)
    p = ds["p"].values
    res = contact_pair(h1, h2, dx, E_STAR, p, fields=True)
    expected = [np.mean(flow_factors(g)) for g in res["gap"]]
    np.testing.assert_allclose(ds["exact_flow_factor"].sel(eta=0.0).squeeze(), expected, rtol=1e-9)
    np.testing.assert_allclose(ds["exact_contact_area_ratio"].sel(eta=0.0).squeeze(), res["area"], rtol=1e-12)


def test_exact_leak_falls_with_load_and_stops_at_the_sealing_load(result):
    d = result["interface_bem"].sel(eta=0.0)
    Q = d["exact_leak_rate"].values
    assert np.all(Q > 0) and np.all(np.diff(Q) < 0)
    seal = float(d["exact_sealing_pressure"].squeeze())
    assert seal > d["p"].values.max()  # open at every load of the scene, closed above
    assert 0.3 < float(d["exact_percolation_area"].squeeze()) < 0.6  # Dapp et al. 2012: 0.42


def test_identical_surfaces_seal_at_any_load(result):
    d = result["interface_bem"].sel(eta=1.0)
    assert np.all(d["exact_flow_factor"] == 0) and np.all(d["exact_leak_rate"] == 0)
    assert np.all(np.isposinf(d["exact_stiffness"])) and np.all(np.isposinf(d["theory_stiffness"]))
    assert float(d["exact_sealing_pressure"].squeeze()) == 0.0
    assert float(d["theory_sealing_pressure_critical_junction"]) == 0.0
    assert np.all(d["theory_leak_rate_critical_junction"] == 0)


def test_theory_against_exact_within_the_expected_factors(result):
    d = result["interface_bem"].sel(eta=0.0)
    K = d["stiffness_ratio_theory_to_exact"].values
    assert 0.8 < K[0] < 1.25  # the separation theory at small load (Persson 2007; Almqvist et al. 2011)
    cj = d["leak_ratio_critical_junction_to_exact"].values
    assert 1 / 3 < cj[0] < 3  # critical junction away from the threshold (Dapp et al. 2012)
    assert np.all(np.isfinite(d["leak_ratio_effective_medium_to_exact"]))


def test_the_sealing_load_separates_open_from_closed(run_scene):
    """Loads on both sides of the BEM's sealing load: flow below it, none at or above it."""
    res = run_scene(scene(grid=32, eta=(0.0,), pressures=(0.01, 0.3, 0.9, 2.0)))["base"]["interface_bem"]
    seal = float(res["exact_sealing_pressure"].squeeze())
    p, Q = res["p"].values, res["exact_flow_factor"].squeeze().values
    assert np.any(p < seal) and np.any(p > seal)
    assert np.all(Q[p > seal] == 0) and np.all(Q[p < seal] > 0)
