"""Tests of the kernel-agnostic Polonsky-Keer contact solver (physics/bem_cg.py).

Facts checked: the same pressure field and contact area as Tamaas' solver on a half-space
surface (1e-8); Westergaard's sinusoidal contact (full contact exact, partial contact within
the grid's resolution); load balance, non-negative pressure, zero gap in contact and none
elsewhere (the contact conditions); the kernel as a parameter (a stiffer kernel is the same
problem with lower heights; array and function agree); the saturated (Kato) variant: pressure
bounded by the cap, plastic area at least p / sigma_Y, the elastic solution when the cap is out
of reach, and Tamaas' KatoSaturated where that solver converges.
"""

from __future__ import annotations

import numpy as np
import pytest
from reference_solutions import westergaard_contact_fraction, westergaard_full_contact_pressure

from roughcontact.physics.bem_cg import compliance_grid, half_space_compliance, saturated_areas, solve, wavenumbers
from roughcontact.physics.spectra import self_affine_psd
from roughcontact.physics.synthesis import synthesize_pair

Q = np.geomspace(1.0, 100.0, 201)
C_SHAPE = self_affine_psd(Q, 0.8, 1.0, 4.0, 100.0, 1.0)


def rough_map(n=64, hrms=1.0, seed=3):
    """A self-affine composite map in pixel units (dx = 1): rms height ``hrms`` pixels."""
    h1, h2 = synthesize_pair(Q, C_SHAPE, 0 * C_SHAPE, 0.0, n, n / 4, seed=seed)  # qL = 1, 4 pixels per wavelength
    h = h1 - h2
    return (h - h.mean()) * hrms / h.std()


def gap_and_contact(res, heights, pixel_size, compliance):
    """The gap recomputed from the pressure (independently of the solver's own gap)."""
    K = compliance_grid(compliance, heights.shape, pixel_size)
    u = np.fft.irfft2(K * np.fft.rfft2(res["pressure"]), s=heights.shape)
    return u - heights


def tamaas():
    tm = pytest.importorskip("tamaas")
    tm.set_log_level(tm.LogLevel.error)
    return tm


def tamaas_model(tm, n):
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(n), float(n)], [n, n])
    model.E, model.nu = 1.0, 0.0  # E* = 1, lengths in pixels
    return model


@pytest.mark.parametrize("p", [1e-3, 1e-2, 0.1])
def test_same_solution_as_tamaas_on_the_half_space(p):
    tm = tamaas()
    n = 64
    h = rough_map(n)
    model = tamaas_model(tm, n)
    tm.PolonskyKeerRey(model, np.ascontiguousarray(h), 1e-14).solve(p)
    ref = np.array(model.traction).reshape(n, n)
    res = solve(h, 1.0, half_space_compliance(1.0), p, tolerance=1e-14)
    assert np.linalg.norm(res["pressure"] - ref) / np.linalg.norm(ref) < 1e-8
    assert res["area"] == np.count_nonzero(ref > 0) / ref.size  # the same pixels in contact
    gap_ref = np.array(model.displacement).reshape(n, n) - h
    assert np.max(np.abs(res["gap"] - gap_ref)) < 1e-8 * h.std()


def test_si_units_are_the_reduced_solution_scaled():
    """Heights in m, pressure in Pa, E* in Pa: the pixel-unit solution times the scales."""
    n, dx, E = 32, 2e-7, 1.3e11
    h = rough_map(n)
    reduced = solve(h, 1.0, half_space_compliance(1.0), 0.02, tolerance=1e-13)
    si = solve(h * dx, dx, half_space_compliance(E), 0.02 * E, tolerance=1e-13)
    assert si["area"] == reduced["area"]
    np.testing.assert_allclose(si["pressure"], reduced["pressure"] * E, rtol=1e-8, atol=1e-10 * E)


def test_contact_conditions_and_load_balance():
    n = 64
    h = rough_map(n, seed=5)
    k = half_space_compliance(1.0)
    for p in (3e-3, 0.05, 0.3):
        res = solve(h, 1.0, k, p, tolerance=1e-13)
        pr = res["pressure"]
        assert abs(pr.mean() / p - 1) < 1e-12  # force balance
        assert pr.min() >= 0.0
        g = gap_and_contact(res, h, 1.0, k)
        g -= g[pr > 0].mean()
        assert np.max(np.abs(g[pr > 0])) < 1e-9 * h.std()  # zero gap in contact
        assert g[pr == 0].min() > -1e-9 * h.std()  # no interpenetration outside
        assert 0 < res["area"] < 1


def test_westergaard_full_contact_is_exact():
    """Above p* = pi E* h0 / lambda the sinusoid is flattened: p(x) = p + p* cos(2 pi x / lambda)."""
    n, lam, h0, E = 128, 1.0, 0.01, 2.0
    x = np.arange(n) / n * lam
    h = np.tile(h0 * np.cos(2 * np.pi * x / lam)[:, None], (1, 4))
    p_star = westergaard_full_contact_pressure(h0, lam, E)
    p = 1.5 * p_star
    res = solve(h, lam / n, half_space_compliance(E), p, tolerance=1e-14)
    assert res["area"] == 1.0
    np.testing.assert_allclose(res["pressure"][:, 0], p + p_star * np.cos(2 * np.pi * x / lam), rtol=0,
                               atol=1e-10 * p)


@pytest.mark.parametrize("ratio", [0.05, 0.3, 0.7])
def test_westergaard_partial_contact(ratio):
    """Contact width 2a / lambda = (2/pi) arcsin sqrt(p/p*) (Johnson eq 13.13), to the grid's half
    pixel per edge, and converging as the grid refines."""
    lam, h0, E = 1.0, 0.01, 1.0
    p = ratio * westergaard_full_contact_pressure(h0, lam, E)
    exact = westergaard_contact_fraction(ratio)
    errors = []
    for n in (256, 1024):
        x = np.arange(n) / n * lam
        h = np.tile(h0 * np.cos(2 * np.pi * x / lam)[:, None], (1, 2))
        res = solve(h, lam / n, half_space_compliance(E), p, tolerance=1e-13)
        errors.append(abs(res["area"] - exact))
        assert errors[-1] <= 2.0 / n
    assert errors[1] < errors[0] or errors[1] <= 1.0 / 1024


def test_the_kernel_is_a_parameter():
    """compliance / s with heights h is the problem with compliance and heights s h (linear
    elasticity); an array on the rfft2 grid is the same as the function; a q-dependent kernel
    (stiffer at long wavelengths, like a hard substrate under a soft coat) runs."""
    n, p = 64, 0.02
    h = rough_map(n, seed=11)
    k = half_space_compliance(1.0)
    stiff = solve(h, 1.0, lambda q: k(q) / 3.0, p, tolerance=1e-13)
    scaled = solve(3.0 * h, 1.0, k, p, tolerance=1e-13)
    assert stiff["area"] == scaled["area"]
    np.testing.assert_allclose(stiff["pressure"], scaled["pressure"], rtol=0, atol=1e-9 * p)
    as_array = solve(h, 1.0, compliance_grid(k, h.shape, 1.0), p, tolerance=1e-13)
    np.testing.assert_array_equal(as_array["pressure"] > 0, solve(h, 1.0, k, p, tolerance=1e-13)["pressure"] > 0)

    def coated(q):  # E_eff from 1 (q d >> 1) to 10 (q d << 1), d = 4 pixels
        return 2.0 / (q * (1.0 + 9.0 * np.exp(-q * 4.0)))

    soft = solve(h, 1.0, k, p, tolerance=1e-13)
    layered = solve(h, 1.0, coated, p, tolerance=1e-13)
    assert layered["area"] < soft["area"]  # a stiffer long-wavelength response: less contact
    g = gap_and_contact(layered, h, 1.0, coated)
    g -= g[layered["pressure"] > 0].mean()
    assert np.max(np.abs(g[layered["pressure"] > 0])) < 1e-9 * h.std()


def test_wavenumbers_and_bad_kernels():
    q = wavenumbers((8, 6), 0.5)
    assert q.shape == (8, 4) and q[0, 0] == 0 and np.isclose(q[1, 0], 2 * np.pi / 4.0)
    h = rough_map(16)
    with pytest.raises(ValueError, match="rfft2 shape"):
        solve(h, 1.0, np.ones((16, 16)), 0.1)
    with pytest.raises(ValueError, match=">= 0"):
        solve(h, 1.0, lambda q: -1.0 / q, 0.1)
    with pytest.raises(ValueError, match="pressure_cap"):
        solve(h, 1.0, half_space_compliance(1.0), 0.1, pressure_cap=0.05)


def test_saturated_contact_conditions():
    """0 <= p <= sigma_Y, mean p = p0; free contact: zero gap; capped: the surfaces overlap (g <= 0);
    elsewhere open; the capped area carries at most the load, A_pl sigma_Y <= p0."""
    n = 64
    h = rough_map(n, seed=5)
    k = half_space_compliance(1.0)
    for p, Y in ((0.01, 0.05), (0.1, 0.5), (0.05, 0.08)):
        res = solve(h, 1.0, k, p, pressure_cap=Y, tolerance=1e-13)
        pr = res["pressure"]
        assert abs(pr.mean() / p - 1) < 1e-12 and pr.min() >= 0 and pr.max() <= Y
        capped, free = pr >= Y, (pr > 0) & (pr < Y)
        assert capped.any() and res["plastic_area"] * Y <= p * (1 + 1e-12)
        g = gap_and_contact(res, h, 1.0, k)
        g -= g[free].mean()
        tol = 1e-9 * h.std()
        assert np.max(np.abs(g[free])) < tol
        assert g[capped].max() < tol and g[pr == 0].min() > -tol


def test_saturated_without_reach_is_elastic():
    n, p = 64, 0.02
    h = rough_map(n, seed=2)
    k = half_space_compliance(1.0)
    el = solve(h, 1.0, k, p, tolerance=1e-13)
    sat = solve(h, 1.0, k, p, pressure_cap=1.01 * el["pressure"].max(), tolerance=1e-13)
    assert sat["plastic_area"] == 0 and sat["area"] == el["area"]
    np.testing.assert_allclose(sat["pressure"], el["pressure"], rtol=0, atol=1e-9 * p)


@pytest.mark.parametrize("p", [1e-3, 2e-3, 4e-3])
def test_saturated_same_as_tamaas_kato(p):
    """Tamaas' KatoSaturated where it converges (here p / E* <= 4e-3 with hrms of one pixel; at
    larger loads it stalls, docs/bem.md): the same pressure field to 1e-8."""
    tm = tamaas()
    n = 64
    h = rough_map(n, seed=1)
    Y = 5 * p
    model = tamaas_model(tm, n)
    kato = tm.KatoSaturated(model, np.ascontiguousarray(h), 1e-12, Y)
    kato.solve(p)
    if kato.computeError() > 1e-10:
        pytest.skip(f"KatoSaturated did not converge (error {kato.computeError():.2g})")
    ref = np.array(model.traction).reshape(n, n)
    res = solve(h, 1.0, half_space_compliance(1.0), p, pressure_cap=Y, tolerance=1e-14)
    assert np.linalg.norm(res["pressure"] - ref) / np.linalg.norm(ref) < 1e-8
    assert res["area"] == np.count_nonzero(ref > 0) / ref.size
    assert res["plastic_area"] == np.count_nonzero(ref >= Y * (1 - 1e-12)) / ref.size


def test_saturated_areas_in_si_units_and_with_a_kernel():
    """saturated_areas (what the bem stage calls): SI heights and pressures, reduced internally;
    the half-space kernel given explicitly (converted to reduced units) gives the same areas; at
    p >= sigma_Y the map is all plastic; elastic + plastic = the contact fraction."""
    n, dx, E, Y = 64, 1e-6, 1e11, 1e9
    h = rough_map(n, seed=4) * dx * 0.3
    p = np.array([1e6, 3e7, 3e8, 2e9])
    default = saturated_areas(h, dx, E, p, Y, tolerance=1e-12)
    explicit = saturated_areas(h, dx, E, p, Y, compliance=half_space_compliance(E), tolerance=1e-12)
    for key in ("elastic_area", "plastic_area", "area"):
        np.testing.assert_allclose(explicit[key], default[key], rtol=0, atol=1.0 / h.size)
    np.testing.assert_array_equal(default["elastic_area"] + default["plastic_area"], default["area"])
    assert default["plastic_area"][-1] == 1.0 and default["elastic_area"][-1] == 0.0
    assert np.all(np.diff(default["plastic_area"]) > 0) and np.all(default["plastic_area"][:-1] * Y <= p[:-1])
