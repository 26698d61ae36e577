"""Elastoplastic contact (issue 28): the absorbing wall at the penetration hardness sigma_Y.

Physical facts checked: sigma_Y -> infinity is the elastic theory (eqs 16, 19) to 1e-10; G >> sigma_Y^2
puts the whole load on plastic spots (A_pl -> p / sigma_Y); the two exact forms (sine series, images)
agree where both converge, and the kernels stay finite and bounded for G / sigma_Y^2 from 1e-30 to
1e30; P(sigma) integrates to A_el and, with the plastic spots at sigma_Y, carries p (load balance);
areas are monotonic in p and G; the stage's option changes nothing by default and refuses bad input
before anything is written."""

import numpy as np
import pytest
from conftest import make_scene
from hypothesis import given, settings, strategies as st
from reference_solutions import contact_area_ratio as area_eq19
from scipy import integrate
from scipy.special import erf

from roughcontact.cli import main
from roughcontact.physics import plasticity as pl
from roughcontact.physics.contact import stress_distribution
from roughcontact.stage import UserError

Y = 1.2e9  # a mild steel's penetration hardness (Pa)


# --- limits -------------------------------------------------------------------------------------

@pytest.mark.parametrize("ratio", [1e-8, 1e-4, 0.1, 1.0, 10.0])
def test_infinite_hardness_is_the_elastic_theory(ratio):
    """sigma_Y -> infinity (here 1e6 p and more than 1e3 sqrt G): A_el = erf(p / 2 sqrt G) (eq 19) to
    1e-10 relative, A_pl = 0, P(sigma) = eq 16, the elastic spots carry all the load."""
    p = 1e6
    G = (p / ratio) ** 2
    big = 1e6 * p * max(1.0, 1.0 / ratio)
    exact = area_eq19(p, G)
    assert pl.elastic_area_ratio(p, G, big) == pytest.approx(exact, rel=1e-10)
    assert pl.plastic_area_ratio(p, G, big) < 1e-100
    assert pl.elastic_load(p, G, big) == pytest.approx(p, rel=1e-10)
    sigma = np.linspace(0.0, p + 10 * np.sqrt(G), 201)
    np.testing.assert_allclose(pl.elastoplastic_stress_distribution(sigma, p, G, big),
                               stress_distribution(sigma, p, G), rtol=1e-10, atol=1e-300)


@pytest.mark.parametrize("p_over_Y", [1e-6, 1e-3, 0.2, 0.5, 0.9])
def test_hardness_far_below_the_roughness_stress_puts_the_load_on_plastic_spots(p_over_Y):
    """sigma_Y << sqrt(G) (p < sigma_Y): A_pl -> p / sigma_Y, A_el -> 0, both as exp(-pi^2 G / sigma_Y^2)
    (the slowest mode of the sine series)."""
    p = p_over_Y * Y
    for tau in (0.5, 1.0, 3.0, 1e4):
        bound = 2.0 * np.exp(-np.pi**2 * tau) * 1.001 + 1e-14  # the first term of the series for p << sigma_Y
        assert abs(pl.plastic_area_ratio(p, tau * Y**2, Y) * Y / p - 1.0) <= bound
        assert pl.elastic_area_ratio(p, tau * Y**2, Y) <= 4 / np.pi * np.exp(-np.pi**2 * tau) * 1.000001


def test_no_roughness_and_overload():
    """G = 0: full elastic contact; p >= sigma_Y: every spot plastic (A_pl = 1, A_el = 0)."""
    assert pl.elastic_area_ratio(0.3 * Y, 0.0, Y) == 1.0 and pl.plastic_area_ratio(0.3 * Y, 0.0, Y) == 0.0
    for p in (Y, 3 * Y):
        assert pl.elastic_area_ratio(p, 1e16, Y) == 0.0 and pl.plastic_area_ratio(p, 1e16, Y) == 1.0
    assert pl.elastic_area_ratio(0.0, 1e16, Y) == 0.0 and pl.plastic_area_ratio(0.0, 1e16, Y) == 0.0


def test_elastic_area_is_symmetric_about_half_the_hardness():
    """An exact property of the two-wall problem: A_el(p) = A_el(sigma_Y - p) (the walls are alike)."""
    p = np.linspace(0.01, 0.49, 25) * Y
    for tau in (1e-4, 0.05, 0.3, 2.0):
        np.testing.assert_allclose(pl.elastic_area_ratio(p, tau * Y**2, Y),
                                   pl.elastic_area_ratio(Y - p, tau * Y**2, Y), rtol=1e-12)


# --- the two forms and their convergence -------------------------------------------------------

@pytest.mark.parametrize("tau", [0.002, 0.01, 0.02, 0.05, 0.1])
def test_series_and_images_agree(tau, monkeypatch):
    """Two exact forms of the same solution, sine series and images, each given terms enough (60 terms,
    m = -4 .. 4) over tau = 0.002 .. 0.1, agree to 1e-13: the formulas (and so the switch) are right.
    That the kernels' own numbers of terms are converged is the next test's business."""
    monkeypatch.setattr(pl, "_N", np.arange(1, 61.0))
    monkeypatch.setattr(pl, "_M", np.arange(-4, 5.0))
    p = np.array([1e-6, 0.01, 0.3, 0.5, 0.77, 0.999]) * Y
    G, Yv = np.full_like(p, tau * Y**2), np.full_like(p, Y)
    # rounding floors: 1e-16 of an area, 1e-15 sigma_Y of a load (the images' charges lie at 2 m sigma_Y)
    for series, images, scale, floor in [(pl._elastic_area_series, pl._elastic_area_images, 1.0, 4e-16),
                                         (pl._plastic_area_series, pl._plastic_area_images, p / Y, 4e-16),
                                         (pl._elastic_load_series, pl._elastic_load_images, p, 1e-15 * Y)]:
        np.testing.assert_array_less(np.abs(series(p, G, Yv, 60) - images(p, G, Yv)), 1e-13 * scale + floor)


def test_more_terms_change_nothing(monkeypatch):
    """The fixed numbers of terms are converged: doubling them changes nothing beyond rounding."""
    p = np.linspace(0.001, 0.999, 37) * Y
    taus = (1e-30, 1e-3, 0.01, 0.02, 0.05, 0.1, 0.3, 1.0, 1e3, 1e30)
    before = [(pl.elastic_area_ratio(p, t * Y**2, Y), pl.plastic_area_ratio(p, t * Y**2, Y)) for t in taus]
    monkeypatch.setattr(pl, "_N", np.arange(1, 2 * pl.SERIES_TERMS + 1.0))
    monkeypatch.setattr(pl, "_M", np.arange(-2 * pl.IMAGE_PAIRS, 2 * pl.IMAGE_PAIRS + 1.0))
    for t, (a_el, a_pl) in zip(taus, before, strict=True):
        np.testing.assert_allclose(pl.elastic_area_ratio(p, t * Y**2, Y), a_el, rtol=1e-14, atol=1e-16)
        np.testing.assert_allclose(pl.plastic_area_ratio(p, t * Y**2, Y), a_pl, rtol=1e-14, atol=1e-16)


@settings(max_examples=60, deadline=None)
@given(log_tau=st.floats(-30.0, 30.0), p_over_Y=st.floats(0.0, 1.0))
def test_extremes_are_finite_and_bounded(log_tau, p_over_Y):
    """G / sigma_Y^2 from 1e-30 to 1e30 and any p in [0, sigma_Y]: finite, 0 <= A_el, 0 <= A_pl <= p / sigma_Y,
    A_el + A_pl <= 1, and the load balance holds."""
    p, G = p_over_Y * Y, 10.0**log_tau * Y**2
    a_el, a_pl = float(pl.elastic_area_ratio(p, G, Y)), float(pl.plastic_area_ratio(p, G, Y))
    assert np.isfinite(a_el) and np.isfinite(a_pl)
    assert -1e-15 <= a_el <= 1.0 + 1e-15
    assert -1e-15 <= a_pl <= min(1.0, p / Y) * (1 + 1e-12) + 1e-15
    assert a_el + a_pl <= 1.0 + 1e-12
    if 0 < p < Y:
        assert abs(float(pl.load_residual(p, G, Y))) < 1e-12 + 1e-14 * Y / p  # rounding of loads at 1e-16 sigma_Y


@settings(max_examples=25, deadline=None)
@given(log_tau=st.sampled_from([-30.0, -20.0, 20.0, 30.0]), p_over_Y=st.floats(1e-9, 1.0 - 1e-6))
def test_extreme_ends_have_their_limits(log_tau, p_over_Y):
    """At the far ends the two limits hold exactly: tiny G (sqrt G <= 1e-10 sigma_Y, far from the wall at
    sigma_Y): A_el = eq 19 (1 unless p ~ sqrt G), A_pl = 0; huge G: A_el = 0, A_pl = p / sigma_Y."""
    p, G = p_over_Y * Y, 10.0**log_tau * Y**2
    if log_tau > 0:
        assert pl.elastic_area_ratio(p, G, Y) == 0.0
        assert pl.plastic_area_ratio(p, G, Y) == pytest.approx(p / Y, rel=1e-15)
    else:
        assert pl.elastic_area_ratio(p, G, Y) == pytest.approx(area_eq19(p, G), rel=1e-12)
        assert pl.plastic_area_ratio(p, G, Y) == pytest.approx(0.0, abs=1e-300)


# --- load balance and monotonicity -------------------------------------------------------------

@pytest.mark.parametrize("p_over_Y", [0.05, 0.4, 0.8])
@pytest.mark.parametrize("tau", [1e-3, 0.02, 0.2, 0.6, 3.0])
def test_stress_distribution_integrates_to_the_elastic_area_and_the_load_balances(p_over_Y, tau):
    """By adaptive quadrature of P(sigma) on (0, sigma_Y): its mass is A_el/A0 and its first moment plus
    sigma_Y A_pl/A0 is p (the plastic spots carry exactly sigma_Y), to 1e-9."""
    p, G = p_over_Y * Y, tau * Y**2

    def P(s):
        return float(pl.elastoplastic_stress_distribution(np.array([s]), p, G, Y)[0])

    points = [p] if tau < 0.1 else None
    mass = integrate.quad(P, 0.0, Y, points=points, epsabs=0, epsrel=1e-12, limit=200)[0]
    moment = integrate.quad(lambda s: s * P(s), 0.0, Y, points=points, epsabs=0, epsrel=1e-12, limit=200)[0]
    assert mass == pytest.approx(float(pl.elastic_area_ratio(p, G, Y)), rel=1e-9, abs=1e-15)
    assert moment + Y * float(pl.plastic_area_ratio(p, G, Y)) == pytest.approx(p, rel=1e-9)
    assert moment == pytest.approx(float(pl.elastic_load(p, G, Y)), rel=1e-9, abs=1e-6)


def test_areas_are_monotonic_in_pressure_and_magnification():
    """More load: more plastic area and more total contact; more roughness (G): less elastic and
    more plastic area. The elastic area grows with p up to sigma_Y / 2."""
    p = np.linspace(0.0, 0.999, 400) * Y
    for tau in (1e-4, 0.01, 0.1, 0.3, 1.0, 5.0):
        a_el, a_pl = pl.elastic_area_ratio(p, tau * Y**2, Y), pl.plastic_area_ratio(p, tau * Y**2, Y)
        assert np.all(np.diff(a_pl) >= -1e-15) and np.all(np.diff(a_el + a_pl) >= -1e-15)
        half = p <= Y / 2
        assert np.all(np.diff(a_el[half]) >= -1e-15)
    G = np.geomspace(1e-6, 1e2, 300) * Y**2
    for p_over_Y in (0.01, 0.3, 0.9):
        a_el, a_pl = pl.elastic_area_ratio(p_over_Y * Y, G, Y), pl.plastic_area_ratio(p_over_Y * Y, G, Y)
        assert np.all(np.diff(a_el) <= 1e-15) and np.all(np.diff(a_pl) >= -1e-15)


def test_kernel_refuses_a_hardness_that_is_not_positive():
    for bad in (0.0, -1e9):
        with pytest.raises(ValueError, match="sigma_Y must be > 0"):
            pl.elastic_area_ratio(1e6, 1e16, bad)


# --- the contact stage ------------------------------------------------------------------------

PLASTIC = ["contact_area_ratio", "elastic_contact_area_ratio", "plastic_contact_area_ratio"]


def test_stage_option_is_off_by_default_and_changes_no_default_result(run_scene, tmp_path):
    """The yield stress adds A_el and A_pl; the elastic A/A0 (what every other stage reads) is unchanged,
    and A_el, A_pl are the kernel's on the stage's G (the combined spectrum of the two rough surfaces)."""
    plain = run_scene(make_scene(), outdir=tmp_path / "a")["base"]["contact"]
    assert "elastic_contact_area_ratio" not in plain
    res = run_scene(make_scene(contact={"zeta": [4.0, 200.0], "yield_stress": "20 GPa"},
                               outputs={"variables": PLASTIC}), outdir=tmp_path / "b")["base"]["contact"]
    np.testing.assert_array_equal(res["contact_area_ratio"].values, plain["contact_area_ratio"].values)
    p, G = res["p"], res["G"]
    np.testing.assert_allclose(res["elastic_contact_area_ratio"].transpose(*G.dims, "p").values,
                               pl.elastic_area_ratio(p.values, G.values[..., None], 20e9), rtol=1e-14)
    a_pl = res["plastic_contact_area_ratio"]
    assert a_pl.attrs["units"] == "1" and "comment" in a_pl.attrs
    # eta = -1 (anti-correlated: the largest combined spectrum) yields most, eta = +1 (identical: none) least
    top = a_pl.sel(zeta=4.0, p=p.values[4])
    assert float(top.sel(eta=-1.0)) > float(top.sel(eta=0.0)) > float(top.sel(eta=1.0)) == 0.0


def test_stage_refuses_plastic_outputs_without_a_yield_stress_or_with_a_correction(run_scene, tmp_path):
    with pytest.raises(UserError, match="contact.yield_stress"):
        run_scene(make_scene(outputs={"variables": PLASTIC}), outdir=tmp_path / "a")
    with pytest.raises(UserError, match="persson"):
        run_scene(make_scene(contact={"zeta": [4.0], "yield_stress": "1 GPa", "correction": "wang_mueser"},
                             outputs={"variables": PLASTIC}), outdir=tmp_path / "b")
    assert not any((tmp_path / "a").rglob("*.nc")) and not any((tmp_path / "b").rglob("*.nc"))


@pytest.mark.parametrize("value", ["0 GPa", "-1 GPa"])
def test_a_yield_stress_that_is_not_positive_is_one_line_and_writes_nothing(tmp_path, capsys, write_scene, value):
    path = write_scene(make_scene(contact={"zeta": [4.0], "yield_stress": value}, outputs={"variables": PLASTIC}))
    out = tmp_path / "out"
    code = main(["run", str(path), "--outdir", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert str(path) in err and "contact.yield_stress: must be > 0" in err
    assert not out.exists() or not any(out.rglob("*.nc"))


def test_pressure_above_the_hardness_is_warned_about(run_scene, tmp_path):
    with pytest.warns(UserWarning, match="at or above contact.yield_stress"):
        res = run_scene(make_scene(contact={"zeta": [4.0], "yield_stress": "2 GPa"}, outputs={"variables": PLASTIC}),
                        outdir=tmp_path / "a")["base"]["contact"]
    over = res["p"] >= 2e9
    assert np.all(res["plastic_contact_area_ratio"].where(over).fillna(1.0) == 1.0)


def test_the_joint_kernel_gives_the_same_areas():
    """elastoplastic_areas (what the stage calls) is elastic_area_ratio and plastic_area_ratio at once."""
    p = np.linspace(0.0, 1.2, 49)[:, None] * Y
    G = np.geomspace(1e-12, 1e4, 61)[None, :] * Y**2
    a_el, a_pl = pl.elastoplastic_areas(p, G, Y)
    np.testing.assert_allclose(a_el, pl.elastic_area_ratio(p, G, Y), rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(a_pl, pl.plastic_area_ratio(p, G, Y), rtol=1e-14, atol=1e-300)


@pytest.mark.parametrize("tau", [1e-6, 1e-3, 0.01, 0.0199])
def test_closed_image_form_is_the_full_image_sum(tau, monkeypatch):
    """The kernels' closed form of the images (three pairs, seven error functions shared by both
    areas, A_el taken at min(p, sigma_Y - p)) against the generic image sums with m = -4 .. 4:
    the pairs left out weigh below exp(-1/tau), and nothing else differs beyond rounding."""
    monkeypatch.setattr(pl, "_M", np.arange(-4, 5.0))
    p = np.array([1e-9, 1e-3, 0.2, 0.5, 0.8, 0.999, 1 - 1e-9]) * Y
    G, Yv = np.full_like(p, tau * Y**2), np.full_like(p, Y)
    a_el, a_pl = pl._areas_images(p, G, Yv)
    np.testing.assert_allclose(a_el, pl._elastic_area_images(p, G, Yv), rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(a_pl, pl._plastic_area_images(p, G, Yv), rtol=1e-13, atol=1e-16)
    if tau <= 1e-3:  # the other wall out of reach (exp(-1/4 tau) < 1e-108): A_el(sigma_Y - d) = erf(d / 2 sqrt G)
        d = Y - p[p >= Y / 2]  # exact (Sterbenz)
        np.testing.assert_allclose(a_el[p >= Y / 2], erf(d / (2 * np.sqrt(tau) * Y)), rtol=1e-14)
