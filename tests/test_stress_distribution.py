"""P(sigma) is resolved where it lives: every stored distribution integrates to A/A0 (seed eq 16
integrates to erf(p / 2 sqrt G), eq 19) within 1e-3, from deep partial contact to p/sqrt(G) of
1e20 (near full contact the distribution is a Gaussian of width sqrt(2G) about p) and G = 0
(a delta at p), at the defaults sigma_points = 401, sigma_width = 8 (issue 15)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import SURFACE, make_scene
from hypothesis import HealthCheck, given, settings, strategies as st
from reference_solutions import contact_area_ratio

from roughcontact import engine, scene as scenes
from roughcontact.physics.contact import stress_distribution_adaptive

settings.register_profile("ci", max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("exhaustive", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "ci")

LEVEL = np.linspace(0.0, 1.0, 401)
E_STAR = 77.2e9 / (1 - 0.42**2)


def _relative_error(mass, area):
    return np.abs(mass - area) / area


@settings(max_examples=200, deadline=None)
@given(log_ratio=st.floats(-12.0, 20.0), log_g=st.floats(-40.0, 40.0))
def test_the_kernel_integrates_to_the_contact_area_at_any_ratio(log_ratio, log_g):
    G = 10.0**log_g
    p = 10.0**log_ratio * np.sqrt(G)
    P, sigma, mass = stress_distribution_adaptive(LEVEL, p, G, 8.0)
    area = contact_area_ratio(p, G)
    assert np.all(np.isfinite(P)) and np.all(P >= 0) and np.all(np.diff(sigma) >= 0)
    assert _relative_error(np.trapezoid(P, sigma), area) < 1e-3
    assert mass == pytest.approx(np.trapezoid(P, sigma), rel=1e-12)
    assert np.trapezoid(P * sigma, sigma) == pytest.approx(p, rel=1e-3)  # first moment: the load (eq 16)


def test_no_roughness_is_a_delta_of_unit_mass_at_p():
    P, sigma, mass = stress_distribution_adaptive(LEVEL, np.array([1e3, 1e9]), 0.0, 8.0)
    assert np.all(mass == pytest.approx(1.0, rel=1e-12))
    assert np.all(sigma[np.arange(2), P.argmax(axis=-1)] == [1e3, 1e9])


hurst = st.one_of(st.sampled_from([0.05, 1.0]), st.floats(0.05, 1.0))


@settings.get_profile(PROFILE)
@given(H=hurst, decades=st.floats(0.3, 8.0), logp=st.floats(-12.0, 3.0), eta=st.sampled_from([-1.0, 0.0, 0.5, 1.0]),
       identical=st.booleans(), zeta=st.floats(1.0, 1e4))
def test_every_stored_distribution_integrates_to_the_contact_area(H, decades, logp, eta, identical, zeta):
    """End to end over the extremes: identical surfaces at huge p/E*, H = 1, q1/qL up to 1e8, zeta up to 1e4."""
    q1 = 2e8 * 10**decades
    solid = dict(SURFACE, H=H, q1=f"{q1!r} 1/m") if identical else dict(SURFACE, H=0.8, hrms="0.7 nm")
    raw = make_scene(substrate=dict(SURFACE, H=H, q1=f"{q1!r} 1/m"), solid=solid, interface={"eta": eta},
                     load={"p": [f"{v!r} Pa" for v in sorted({10**logp * E_STAR, 10**min(logp + 2, 3.0) * E_STAR})]},
                     contact={"zeta": sorted({1.0, min(zeta, q1 / 2e8)})},
                     outputs={"variables": ["stress_distribution"]}, numerics={"points_per_decade": 10})
    with tempfile.TemporaryDirectory() as tmp:
        contact = engine.run(scenes.from_dict(raw), Path(tmp), report=engine.Reporter(None))["base"]["contact"]
    area = contact["contact_area_ratio"].values
    P, sigma = contact["stress_distribution"], contact["sigma"].broadcast_like(contact["stress_distribution"])
    mass = np.trapezoid(P.values, sigma.values, axis=P.dims.index("stress_level"))
    assert np.all(_relative_error(mass, area) < 1e-3)
    np.testing.assert_allclose(contact["stress_distribution_mass"].values, mass, rtol=1e-12)
