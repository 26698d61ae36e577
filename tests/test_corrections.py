"""Contact-area corrections (docs/theory.md, "Contact-area corrections"): the variance ODE
dV = S(A/A0) dV_full solved exactly, against eq 19 (S = 1), an independent ODE integration, the
published small-load factors 1/sqrt(gamma), full contact, P(sigma)'s mass and moment,
monotonicity and the extremes; the stage applies the scene's choice to A/A0 and P(sigma)."""

import numpy as np
import pytest
import xarray as xr
from conftest import make_scene
from hypothesis import given, settings, strategies as st
from scipy import integrate
from scipy.special import erf

from roughcontact.physics.contact import contact_area_ratio, stress_distribution
from roughcontact.physics.corrections import (
    DEFAULT_GAMMA,
    check_gamma,
    corrected_area,
    corrected_G,
    reduced_variance,
    variance_factor,
    variance_function,
)

VARIANTS = [("yang_persson", 0.45), ("yang_persson", 0.42), ("wang_mueser", 5.0 / 9.0)]


def test_S_equal_one_reproduces_eq19():
    """yang_persson with gamma = 1 has S = 1 identically: the whole machinery (table, panels,
    root finder) must give back eq 19."""
    p = np.geomspace(1e3, 1e11, 400)
    G = np.geomspace(1e10, 1e22, 400)[:, None]
    A = contact_area_ratio(p, corrected_G(p, G, "yang_persson", 1.0))
    np.testing.assert_allclose(A, contact_area_ratio(p, G), rtol=1e-12, atol=1e-300)
    assert np.array_equal(corrected_G(p, G, "persson", None), np.broadcast_to(G, A.shape))


@pytest.mark.parametrize("correction, gamma", VARIANTS)
def test_exact_solution_matches_a_direct_ode_integration(correction, gamma):
    """Phi^-1 against scipy's adaptive integration of dv/dv_full = S(erf(1/sqrt(2 v)))."""
    for x0 in (0.02, 0.3, 0.8, 2.0):
        v_full = 0.5 / x0**2
        rhs = lambda t, v: variance_factor(erf(1 / np.sqrt(2 * max(v[0], 1e-300))), correction, gamma)  # noqa: E731
        ode = integrate.solve_ivp(rhs, [0.0, v_full], [0.0], rtol=1e-12, atol=1e-14).y[0, -1]
        assert float(reduced_variance(v_full, correction, gamma)) == pytest.approx(ode, rel=1e-9)


@pytest.mark.parametrize("correction, gamma", VARIANTS)
def test_small_load_factor_is_the_published_one(correction, gamma):
    """At small load S -> gamma everywhere, so V -> gamma V_full and A/A0 rises by 1/sqrt(gamma):
    1.49-1.54 (Yang-Persson, gamma 0.42-0.45) and 1.34 (Wang-Mueser, 5/9), inside the 1.3-1.7
    that exact numerics give over eq 19."""
    x0 = np.array([1e-7, 1e-5])
    ratio = corrected_area(x0, correction, gamma) / erf(x0)
    assert ratio == pytest.approx(1 / np.sqrt(gamma), rel=1e-6)
    assert np.all((1.3 < ratio) & (ratio < 1.7))


@pytest.mark.parametrize("correction, gamma", VARIANTS)
def test_full_contact_limits(correction, gamma):
    """S(1) = 1: nothing changes once the contact is full; no roughness (G = 0) is full contact."""
    assert float(variance_factor(1.0, correction, gamma)) == pytest.approx(1.0, abs=1e-15)
    x0 = np.array([4.0, 6.0, 30.0, np.inf])
    A = corrected_area(x0, correction, gamma)
    assert np.all(A >= erf(x0)) and np.all(A <= 1.0)
    assert A[-1] == 1.0 and A[1] == pytest.approx(1.0, abs=1e-15)
    assert float(corrected_G(1e6, 0.0, correction, gamma)) == 0.0
    assert float(contact_area_ratio(1e6, corrected_G(1e6, 0.0, correction, gamma))) == 1.0


@pytest.mark.parametrize("correction, gamma", VARIANTS)
@pytest.mark.parametrize("p, G", [(1e6, 1e14), (3e8, 4e16), (1e9, 1e16), (1e7, 1e18)])
def test_stress_distribution_integrates_to_the_corrected_area(correction, gamma, p, G):
    """eq 16 with G -> G_eff: its mass is the corrected A/A0 and its first moment is p."""
    Ge = float(corrected_G(p, G, correction, gamma))
    f = lambda s: float(stress_distribution(np.array([s]), p, Ge)[0])  # noqa: E731
    top = p + 40 * np.sqrt(Ge)
    mass = integrate.quad(f, 0, top, points=[p], limit=200, epsabs=0, epsrel=1e-11)[0]
    moment = integrate.quad(lambda s: s * f(s), 0, top, points=[p], limit=200, epsabs=0, epsrel=1e-11)[0]
    A = float(corrected_area(p / (2 * np.sqrt(G)), correction, gamma))
    assert mass == pytest.approx(A, rel=1e-8)
    assert moment == pytest.approx(p, rel=1e-8)
    A19 = float(contact_area_ratio(p, G))
    assert A > A19 if A19 < 0.99 else A >= A19


@pytest.mark.parametrize("correction, gamma", VARIANTS)
def test_area_rises_with_load_and_falls_with_roughness(correction, gamma):
    x0 = np.geomspace(1e-8, 10.0, 3000)
    A = corrected_area(x0, correction, gamma)
    assert np.all(np.diff(A) >= 0) and np.all(np.diff(A)[A[1:] < 1 - 1e-9] > 0)
    G = np.geomspace(1e12, 1e24, 500)
    A = contact_area_ratio(1e8, corrected_G(1e8, G, correction, gamma))
    assert np.all(np.diff(A) <= 0) and np.all(np.diff(A)[A[1:] < 1 - 1e-9] < 0)
    assert np.all(np.diff(variance_function(np.geomspace(1e-6, 1e20, 2000), correction, gamma)) > 0)


@settings(max_examples=60, deadline=None)
@given(log_p=st.floats(-12, 12), log_G=st.floats(-30, 40), which=st.sampled_from(range(len(VARIANTS))),
       gamma_shift=st.floats(-0.3, 0.4))
def test_extremes_are_finite_and_bounded(log_p, log_G, which, gamma_shift):
    correction, gamma = VARIANTS[which]
    gamma = gamma + gamma_shift
    p, G = 10.0**log_p, 10.0**log_G
    Ge = float(corrected_G(p, G, correction, gamma))
    A, A19 = float(contact_area_ratio(p, Ge)), float(contact_area_ratio(p, G))
    assert np.isfinite(Ge) and 0 <= Ge <= G
    assert A19 <= A <= 1.0
    assert A <= A19 / np.sqrt(0.5 * gamma) + 1e-300  # S >= S_min > gamma / 2 here: V >= S_min V_full


def test_bad_gamma_is_refused():
    with pytest.raises(ValueError, match="gamma"):
        check_gamma("yang_persson", 1.5)
    with pytest.raises(ValueError, match="S"):
        check_gamma("wang_mueser", 0.005)
    with pytest.raises(ValueError, match="unknown"):
        check_gamma("greenwood", 0.5)
    assert DEFAULT_GAMMA["wang_mueser"] == pytest.approx(5 / 9)


def test_stage_applies_the_scene_choice(run_scene):
    """contact.correction changes A/A0 and P(sigma) consistently; the default is eq 19."""
    base = dict(outputs={"variables": ["stress_distribution"]}, numerics={"sigma_points": 4001},
                load={"p": ["100 MPa", "2 GPa", "10 GPa"]}, contact={"zeta": [4.0, 200.0]}, interface={"eta": [0.0]})
    plain = run_scene(make_scene(**base))["base"]["contact"]
    assert plain["contact_area_ratio"].attrs["correction"] == "persson"
    p, G = xr.broadcast(plain["p"], plain["G"])
    np.testing.assert_allclose(plain["contact_area_ratio"].transpose(*p.dims), contact_area_ratio(p.values, G.values),
                               rtol=1e-14)
    for correction, gamma in (("yang_persson", None), ("wang_mueser", 0.6)):
        sc = make_scene(**{**base, "contact": {"zeta": [4.0, 200.0], "correction": correction,
                                                **({"gamma": gamma} if gamma else {})}})
        c = run_scene(sc, outdir=None)["base"]["contact"]
        g = DEFAULT_GAMMA[correction] if gamma is None else gamma
        assert c["contact_area_ratio"].attrs["correction_gamma"] == pytest.approx(g)
        x0 = c["p"] / (2 * np.sqrt(c["G"]))
        area = c["contact_area_ratio"].transpose(*x0.dims)
        np.testing.assert_allclose(area, corrected_area(x0.values, correction, g), rtol=1e-10)
        assert np.all(area >= plain["contact_area_ratio"].transpose(*x0.dims))
        d = c["stress_distribution"]
        mass = d.integrate("stress_level") * d["sigma"].isel(stress_level=-1)
        np.testing.assert_allclose(mass, c["contact_area_ratio"], rtol=2e-4)


def test_stage_refuses_a_gamma_that_makes_S_negative(run_scene):
    from roughcontact.stage import UserError

    with pytest.raises(UserError, match="contact.gamma"):
        run_scene(make_scene(contact={"zeta": [4.0], "correction": "wang_mueser", "gamma": 0.005}))
