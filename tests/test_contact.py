"""Contact stage: eq 19 against an independent G, eq 20 at small load, the stress distribution's
normalisation and load balance, scaling, ordering in eta, and the extremes."""

import numpy as np
import pytest
from conftest import SURFACE, make_scene
from hypothesis import given, settings, strategies as st
from reference_solutions import contact_area_ratio as area_eq19, self_affine_C0, self_affine_G
from scipy import integrate

from roughcontact.physics.contact import contact_area_ratio, effective_modulus, stress_distribution

E, NU = 77.2e9, 0.42
E_STAR = E / (1 - NU**2)


def _analytic_G(zeta, hrms, H=0.8, qL=2e8, q1=4e10):
    """G for the seed's eq 63 PSD (q0 = qL), from the closed form of the integral."""
    return self_affine_G(zeta, self_affine_C0(hrms, H, qL, qL, q1), H, qL, E_STAR)


def test_area_equals_eq19_with_independent_G(run_scene):
    res = run_scene(make_scene(solid=None, interface=None))["base"]["contact"]
    for zeta in (4.0, 200.0):
        G = _analytic_G(zeta, 1e-9)
        assert float(res["G"].sel(zeta=zeta)) == pytest.approx(G, rel=1e-10)
        p = res["p"].values
        assert np.allclose(res["contact_area_ratio"].sel(zeta=zeta).values, area_eq19(p, G), rtol=1e-10)


def test_area_tends_to_eq20_at_small_load():
    G = 1e18
    p = np.array([1e3, 1e4, 1e5, 1e6])
    ratio = contact_area_ratio(p, G) / (p / np.sqrt(np.pi * G))
    assert np.all(np.diff(np.abs(ratio - 1)) > 0)  # the error grows with p
    assert ratio[0] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("p, G", [(1e6, 1e14), (3e8, 4e16), (1e9, 1e16), (1.0, 1e-2)])
def test_stress_distribution_integrates_to_area_and_balances_the_load(p, G):
    f = lambda s: float(stress_distribution(np.array([s]), p, G)[0])  # noqa: E731
    top = p + 40 * np.sqrt(G)
    mass = integrate.quad(f, 0, top, points=[p], limit=200, epsabs=0, epsrel=1e-11)[0]
    moment = integrate.quad(lambda s: s * f(s), 0, top, points=[p], limit=200, epsabs=0, epsrel=1e-11)[0]
    assert mass == pytest.approx(float(contact_area_ratio(p, G)), rel=1e-8)
    assert moment == pytest.approx(p, rel=1e-8)


def test_stage_stress_distribution_on_its_grid(run_scene):
    raw = make_scene(outputs={"variables": ["stress_distribution"]}, numerics={"sigma_points": 4001},
                     load={"p": ["2 GPa", "5 GPa", "10 GPa"]}, contact={"zeta": [4.0]}, interface={"eta": [0.0, -1.0]})
    c = run_scene(raw)["base"]["contact"]
    d = c["stress_distribution"]
    span = d["sigma"].isel(stress_level=-1)  # sigma = stress_level * span
    mass = d.integrate("stress_level") * span
    moment = (d * d["sigma"]).integrate("stress_level") * span
    assert np.allclose((mass / c["contact_area_ratio"]).values, 1.0, rtol=1e-5)
    assert np.allclose((moment / c["p"]).values, 1.0, rtol=1e-5)
    assert float(d.min()) >= 0.0


def test_scaling_of_the_psd_rescales_the_pressure(run_scene, tmp_path):
    lam = 3.7
    p = np.geomspace(1e6, 1e10, 7)
    base = run_scene(make_scene(solid=None, load={"p": [f"{v} Pa" for v in p]}), outdir=tmp_path / "a")
    scaled_surface = dict(SURFACE, hrms=f"{lam} nm")
    scaled = run_scene(make_scene(solid=None, substrate=scaled_surface, load={"p": [f"{v * lam} Pa" for v in p]}),
                       outdir=tmp_path / "b")
    a = base["base"]["contact"]["contact_area_ratio"].values
    b = scaled["base"]["contact"]["contact_area_ratio"].values
    assert np.allclose(a, b, rtol=1e-10)


def test_area_ordering_in_eta_and_monotonic_in_load_and_magnification(run_scene):
    raw = make_scene()
    raw["variants"] = {"substrate_only": {"solid": {"kind": "smooth"}}}
    res = run_scene(raw)
    pair = res["base"]["contact"]["contact_area_ratio"]
    ref = res["substrate_only"]["contact"]["contact_area_ratio"]
    assert np.all(pair.sel(eta=1.0) == 1.0)
    assert np.all(ref > pair.sel(eta=0.0))
    assert np.all(pair.sel(eta=0.0) > pair.sel(eta=-1.0))
    assert np.all(pair.diff("p") >= 0)
    assert np.all(pair.sel(eta=0.0).diff("zeta") < 0)


@given(p=st.floats(1e-12, 1e3), g=st.floats(0, 1e12), zeta_scale=st.floats(1e-20, 1e20))
@settings(max_examples=200, deadline=None)
def test_area_is_bounded_for_extreme_pressures(p, g, zeta_scale):
    # p/E* from 1e-12 to 1e3, G over 32 decades and 0
    a = contact_area_ratio(p * E_STAR, g * zeta_scale * E_STAR**2)
    assert np.isfinite(a) and 0.0 <= a <= 1.0


@given(p=st.floats(1e-12, 1e3), g=st.floats(1e-30, 1e6))
@settings(max_examples=200, deadline=None)
def test_stress_distribution_is_finite_and_non_negative(p, g):
    sigma = np.linspace(0, (p + 10 * np.sqrt(g)) * E_STAR, 64)
    d = stress_distribution(sigma, p * E_STAR, g * E_STAR**2)
    assert np.all(np.isfinite(d)) and np.all(d >= 0)


def test_no_roughness_gives_a_unit_delta_at_p():
    sigma = np.linspace(0, 10, 101)
    d = stress_distribution(sigma, 3.0, 0.0)
    assert np.trapezoid(d, sigma) == pytest.approx(1.0)
    assert sigma[np.argmax(d)] == pytest.approx(3.0)
    assert contact_area_ratio(3.0, 0.0) == 1.0


def test_effective_modulus():
    assert effective_modulus(E, NU) == pytest.approx(93.74e9, rel=1e-3)
