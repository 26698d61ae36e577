"""Stability across the extremes, end to end through the pipeline: every output finite and
bounded (0 <= A/A0 <= 1, u >= 0, mu >= 0, P(sigma) >= 0) or a clear UserError; never a silent
NaN or inf.

CI draws a few examples per property (profile "ci"); run the exhaustive search with
``HYPOTHESIS_PROFILE=exhaustive python -m pytest -m slow tests/test_stability.py``.
"""

from __future__ import annotations

import copy
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import SURFACE, make_scene
from hypothesis import HealthCheck, given, settings, strategies as st

from roughcontact import engine, scene as scenes
from roughcontact.errors import UserError

settings.register_profile("ci", max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("exhaustive", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "ci")

E_STAR = 77.2e9 / (1 - 0.42**2)

hurst = st.one_of(st.sampled_from([0.05, 0.5, 0.99, 1.0]), st.floats(0.05, 1.0))
coherence = st.one_of(st.sampled_from([-1.0, 0.0, 1.0]), st.floats(-1.0, 1.0))
bandwidth = st.floats(0.3, 8.0)  # decades of q1/qL: up to 1e8
pressure = st.floats(-12.0, 3.0)  # log10(p/E*)


def _run(raw):
    with tempfile.TemporaryDirectory() as tmp:
        return engine.run(scenes.from_dict(raw), Path(tmp), report=engine.Reporter(None))


def _check_contact_and_separation(res):
    c = res["base"]["contact"]
    area = c["contact_area_ratio"].values
    assert np.all(np.isfinite(area)) and np.all((area >= 0) & (area <= 1))
    d = c["stress_distribution"].values
    assert np.all(np.isfinite(d)) and np.all(d >= 0)
    u = res["base"]["separation"]["mean_separation"].values
    assert np.all(np.isfinite(u)) and np.all(u >= 0)


@settings.get_profile(PROFILE)
@given(H1=hurst, H2=hurst, eta=coherence, decades=bandwidth,
       logp=st.lists(pressure, min_size=1, max_size=4, unique_by=lambda x: round(x, 6)),
       ratio=st.floats(0.0, 3.0), identical=st.booleans(), zeta_one=st.booleans())
def test_contact_and_separation_are_finite_and_bounded(H1, H2, eta, decades, logp, ratio, identical, zeta_one):
    q1 = f"{2e8 * 10**decades!r} 1/m"
    solid = dict(SURFACE, H=H1 if identical else H2, q1=q1, hrms="1 nm" if identical else f"{max(ratio, 1e-3)!r} nm")
    raw = make_scene(
        substrate=dict(SURFACE, H=H1, q1=q1), solid=solid, interface={"eta": eta},
        load={"p": [f"{10**lp * E_STAR!r} Pa" for lp in sorted(logp)]},
        contact={"zeta": [1.0] if zeta_one else "all"},
        outputs={"variables": ["stress_distribution", "mean_separation"]},
        numerics={"points_per_decade": 10, "sigma_points": 33},
    )
    res = _run(raw)
    _check_contact_and_separation(res)
    if identical and eta == 1.0:
        assert np.all(res["base"]["contact"]["contact_area_ratio"].values == 1.0)
        assert np.all(res["base"]["separation"]["mean_separation"].values == 0.0)


FRICTION = scenes.load("friction").raw
_WLF = scenes.load("friction").values["modulus"]
#: below this temperature the scene's WLF shift exceeds 10^100 (MAX_LOG10_SHIFT) and must be refused
WLF_LIMIT_DEGC = _WLF["T_ref"] - 100.0 * _WLF["C2"] / (100.0 + _WLF["C1"]) - 273.15 + 1e-9


@settings.get_profile(PROFILE)
@given(logv=st.lists(st.floats(-9.0, 3.0), min_size=1, max_size=5, unique_by=lambda x: round(x, 6)),
       T=st.floats(-100.0, 150.0), eta=coherence, logp=st.floats(3.0, 8.0))
def test_friction_is_finite_and_bounded_across_velocity_and_glass_transition(logv, T, eta, logp):
    # T from 57 K below to 193 K above Tg = -42.9 C: below T_ref - C2 (-94.5 C) WLF is singular and
    # near it a_T leaves any physical range (|log10 a_T| > 100 below T_ref - 100 C2/(100 + C1) =
    # -86.84 C): there, and only there, the user must get a clear error naming modulus.T
    raw = copy.deepcopy(FRICTION)
    raw.pop("variants", None)
    raw["friction"]["v"] = [f"{10**x!r} m/s" for x in sorted(logv)]
    raw["modulus"]["T"] = f"{T!r} degC"
    raw["interface"]["eta"] = eta
    raw["load"]["p"] = f"{10**logp!r} Pa"
    raw.setdefault("numerics", {})["preset"] = "fast"
    try:
        res = _run(raw)["base"]["friction"]
    except UserError as exc:
        assert exc.key == "modulus.T" and T < WLF_LIMIT_DEGC, exc
        return
    mu = res["friction_coefficient"].values
    area = res["sliding_contact_area_ratio"].values
    assert np.all(np.isfinite(mu)) and np.all(mu >= 0)
    assert np.all(np.isfinite(area)) and np.all((area >= 0) & (area <= 1))


@pytest.mark.parametrize("overrides, key", [
    (dict(load={"p": ["0 Pa"]}), "load.p"),
    (dict(interface={"eta": 1.0000001}), "interface.eta"),
    (dict(substrate=dict(SURFACE, H=0.0)), "substrate.H"),
    (dict(contact={"zeta": [0.5]}), "contact.zeta"),
    (dict(contact={"zeta": [1e9]}), "contact.zeta"),
])
def test_out_of_range_input_is_a_clear_error_not_a_nan(overrides, key):
    with pytest.raises(UserError) as err:
        _run(make_scene(**overrides))
    assert err.value.key == key or err.value.key.startswith(key)


_COUNT_EXAMPLES = """
import sys
import numpy as np
import xarray as xr
sys.path.insert(0, sys.argv[1])
import test_stability as t
ones, zeros = xr.DataArray(np.ones(1)), xr.DataArray(np.zeros(1))
result = {"base": {"contact": {"contact_area_ratio": ones, "stress_distribution": zeros},
                   "separation": {"mean_separation": zeros},
                   "friction": {"friction_coefficient": zeros, "sliding_contact_area_ratio": ones}}}
calls = []
t._run = lambda raw: calls.append(raw) or result
for test in (t.test_contact_and_separation_are_finite_and_bounded,
             t.test_friction_is_finite_and_bounded_across_velocity_and_glass_transition):
    calls.clear()
    test()
    print(len(calls))
"""


def test_exhaustive_profile_is_available(tmp_path):
    # the slow run: HYPOTHESIS_PROFILE=exhaustive python -m pytest -m slow tests/test_stability.py
    # must draw >= 300 examples in each property test above: import this module afresh with that
    # environment, replace the pipeline run by a stub that counts the scenes it is handed, and
    # run the two property tests
    env = dict(os.environ, HYPOTHESIS_PROFILE="exhaustive")
    done = subprocess.run([sys.executable, "-c", _COUNT_EXAMPLES, str(Path(__file__).resolve().parent)], env=env,
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    counts = [int(n) for n in done.stdout.split()]
    assert len(counts) == 2 and min(counts) >= settings.get_profile("exhaustive").max_examples >= 300, counts
