"""Tests of the friction stage (stages/friction.py): hysteretic friction mu(v) and A/A0(v).

Every test asserts a physical or mathematical fact: the elastic limit, signs, the linear
regime, monotonicity, the seed's orderings, an exact scaling, and agreement with an
independent brute-force evaluation of eqs 61-62 by scipy.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from reference_solutions import brute_force_mu
from scipy.special import erf

from roughcontact import engine, scene as scenes
from roughcontact.errors import UserError
from roughcontact.physics import friction as physics_friction, viscoelastic as ve
from roughcontact.physics.contact import persson_G
from roughcontact.physics.quadrature import log_grid

QUIET = engine.Reporter(None)


def _scene(**overrides):
    """A small two-surface scene with a box-spectrum modulus (dict, TOML-like)."""
    raw = {
        "name": "t",
        "substrate": {"kind": "self_affine", "H": 0.9, "qL": "1e4 1/m", "q1": "1e7 1/m", "hrms": "3 um"},
        "solid": {"kind": "self_affine", "H": 0.8, "qL": "1e4 1/m", "q1": "1e7 1/m", "hrms": "4 um"},
        "interface": {"eta": 0.0},
        "material": {"E": "5 MPa", "nu": 0.5},
        "load": {"p": "0.4 MPa"},
        "modulus": {"kind": "box", "E0": "5 MPa", "E_inf": "3 GPa", "tau1": "1e-6 s", "tau2": "1e4 s",
                    "T_ref": "-40 degC", "T": "20 degC", "shift": "wlf", "C2": "51.6 K"},
        "friction": {"v": {"from": "1e-9 m/s", "to": "1e3 m/s", "num": 25}},
        "outputs": {"variables": ["friction_coefficient"]},
        "numerics": {"points_per_decade": 20, "friction_phi_nodes": 16},
    }
    for key, value in overrides.items():
        section, _, name = key.partition(".")
        if not name:
            raw[section] = value
        else:
            raw.setdefault(section, {})[name] = value
    return raw


def _run(raw, tmp_path, variant="base"):
    sc = scenes.from_dict(raw)
    return engine.run(sc, tmp_path, report=QUIET)[variant]


# ----------------------------------------------------------------------------------------
# Elastic limit
# ----------------------------------------------------------------------------------------


def test_elastic_limit_gives_zero_friction_and_the_contact_stage_G(tmp_path):
    """A real constant modulus: no hysteresis (mu = 0 exactly) and G(q; v) = G_contact(q)/sigma0^2
    at every q and every v (eq 62 reduces to eq 17)."""
    raw = _scene(**{"modulus": {"kind": "elastic", "E": "7 MPa"},
                    "outputs.variables": ["friction_coefficient", "sliding_G"]})
    res = _run(raw, tmp_path)
    fric, psd = res["friction"], res["psd"]
    assert np.all(fric["friction_coefficient"].values == 0.0)
    q = psd["q"].values
    E_star = 7e6 / (1 - 0.25)
    G_contact = persson_G(q, psd["psd_combined"].values, q, E_star) / 0.4e6**2
    G = fric["sliding_G"].transpose("v", "q").values
    np.testing.assert_allclose(G, np.broadcast_to(G_contact, G.shape), rtol=1e-12)
    area = fric["sliding_contact_area_ratio"].values
    np.testing.assert_allclose(area, erf(1 / (2 * np.sqrt(G_contact[-1]))), rtol=1e-12)


# ----------------------------------------------------------------------------------------
# The built-in scene (seed section 4.3): signs, linear regime, monotonicity, orderings
# ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def builtin(tmp_path_factory):
    sc = scenes.load("friction")
    results = engine.run(sc, tmp_path_factory.mktemp("friction"), report=QUIET)
    return results


def test_builtin_mu_nonnegative_finite_and_bounded(builtin):
    for variant in ("base", "substrate_only"):
        mu = builtin[variant]["friction"]["friction_coefficient"].values
        area = builtin[variant]["friction"]["sliding_contact_area_ratio"].values
        assert np.all(np.isfinite(mu)) and np.all(mu >= 0) and np.all(mu < 10)
        assert np.all(np.isfinite(area)) and np.all((area > 0) & (area <= 1))


def test_builtin_mu_proportional_to_v_at_low_v(builtin):
    """Linear viscoelastic regime: E'' ~ omega and E' = E0 at omega = q v -> 0, so mu ~ v."""
    fric = builtin["base"]["friction"]
    low = fric.sel(v=slice(None, 1e-7))
    ratio = (low["friction_coefficient"] / low["v"]).values
    assert low["v"].size >= 3
    np.testing.assert_allclose(ratio, np.broadcast_to(ratio[..., :1], ratio.shape), rtol=1e-6)


def test_builtin_area_non_increasing_in_v(builtin):
    for variant in ("base", "substrate_only"):
        area = builtin[variant]["friction"]["sliding_contact_area_ratio"].transpose(..., "v").values
        assert np.all(np.diff(area, axis=-1) <= 1e-12 * area[..., 1:])


def test_builtin_orderings_at_every_velocity(builtin):
    """Seed Figs 8 and 10: mu(eta=-1) > mu(eta=0) > mu(substrate only), mu(eta=0) > mu(eta=+1)."""
    base = builtin["base"]["friction"]["friction_coefficient"]
    only = builtin["substrate_only"]["friction"]["friction_coefficient"].values
    m0, mp, mm = (base.sel(eta=e).values for e in (0.0, 1.0, -1.0))
    assert np.all(mm > m0) and np.all(m0 > only) and np.all(m0 > mp)
    # and the areas the other way round (seed Figs 9 and 11)
    area = builtin["base"]["friction"]["sliding_contact_area_ratio"]
    a_only = builtin["substrate_only"]["friction"]["sliding_contact_area_ratio"].values
    a0, ap, am = (area.sel(eta=e).values for e in (0.0, 1.0, -1.0))
    assert np.all(am < a0) and np.all(a0 < a_only) and np.all(a0 < ap)


def test_builtin_has_one_broad_maximum(builtin):
    """docs/theory.md, section "Friction": mu rises ~ v, has one maximum, then decreases."""
    mu = builtin["base"]["friction"]["friction_coefficient"].sel(eta=0.0).values
    i = int(np.argmax(mu))
    assert 0 < i < mu.size - 1
    assert np.all(np.diff(mu[: i + 1]) > 0) and np.all(np.diff(mu[i:]) < 0)


# ----------------------------------------------------------------------------------------
# Brute force: scipy over q and phi, analytic PSD and modulus
# ----------------------------------------------------------------------------------------


# brute_force_mu: tests/reference_solutions.py


@pytest.mark.parametrize("v", [1e-6, 3e-2, 30.0, 1e3])
def test_agrees_with_brute_force_scipy(v):
    """At default resolution the stage agrees with the brute-force evaluation to 1e-4."""
    sc = scenes.load("friction")
    spec = sc.values["modulus"]
    surfaces = [sc.values["substrate"], sc.values["solid"]]
    mu_bf, area_bf = brute_force_mu(v, spec, surfaces, sc.values["load"]["p"], sc.values["material"]["nu"])
    fric = _stage_at(sc, v)
    assert fric[0] == pytest.approx(mu_bf, rel=1e-4)
    assert fric[1] == pytest.approx(area_bf, rel=1e-4)


def _stage_at(sc, v):
    """mu, A/A0 of the built-in scene (eta = 0) at one velocity, through the stage's compute."""
    import copy

    import roughcontact as rc

    raw = copy.deepcopy(sc.raw)
    raw.pop("variants", None)
    raw["friction"]["v"] = f"{v!r} m/s"
    out = rc.compute(scenes.from_dict(raw, sc.path), outputs="friction", progress=False)["base"]["friction"]
    sel = out.sel(eta=0.0)
    return float(sel["friction_coefficient"]), float(sel["sliding_contact_area_ratio"])


# ----------------------------------------------------------------------------------------
# Kernels: properties over random inputs (hypothesis), exact scaling, options
# ----------------------------------------------------------------------------------------


def _kernel_case(H, hrms, p, E0, ratio, tau2, v, n_phi=12, ppd=10, eta=0.0, correction="none", gamma=0.5,
                 decades=3.0, H2=None):
    q = log_grid(1e4, 1e4 * 10.0**decades, ppd)
    C1 = hrms**2 * H / (np.pi * 1e8) * (q / 1e4) ** (-2 * (1 + H))
    C2 = C1 if H2 is None else hrms**2 * H2 / (np.pi * 1e8) * (q / 1e4) ** (-2 * (1 + H2))
    C = (np.sqrt(C1) - eta * np.sqrt(C2)) ** 2 + (1 - eta * eta) * C2
    grid = np.geomspace(1e-8, 1e22, 30 * 8 + 1)
    Ep, Epp = ve.box_spectrum_modulus(grid, E0, E0 * ratio, tau2 * 1e-10, tau2)
    A, B = physics_friction.angular_integrals(q, np.asarray(v), grid, Ep, Epp, n_phi)
    return physics_friction.friction_kernel(q, C, A, B, np.asarray(p), 0.5, correction, gamma)


velocities = st.lists(st.floats(-9, 3), min_size=2, max_size=6, unique=True).map(lambda xs: 10.0 ** np.sort(xs))


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(H=st.floats(0.2, 1.0), H2=st.floats(0.2, 1.0), hrms=st.floats(1e-9, 1e-4), p=st.floats(1e-2, 1e10),
       E0=st.floats(1e5, 1e8), ratio=st.floats(1.5, 1e4), tau2=st.floats(1e-12, 1e6), v=velocities,
       eta=st.sampled_from([-1.0, -0.5, 0.0, 0.7, 1.0]), decades=st.floats(1.0, 7.0))
def test_mu_finite_nonnegative_and_area_non_increasing(H, H2, hrms, p, E0, ratio, tau2, v, eta, decades):
    """Extremes: pressures from 1e-2 Pa to 10 GPa, 1 to 7 decades of q, eta = +-1, different H,
    v from 1e-9 to 1e3 m/s: finite, mu >= 0, 0 <= A/A0 <= 1 and non-increasing in v."""
    mu, area = _kernel_case(H, hrms, p, E0, ratio, tau2, v, eta=eta, decades=decades, H2=H2)
    assert np.all(np.isfinite(mu)) and np.all(mu >= 0)
    assert np.all(np.isfinite(area)) and np.all((area >= 0) & (area <= 1))
    assert np.all(np.diff(area) <= 1e-12)


def test_identical_surfaces_fully_correlated_give_no_friction_and_full_contact():
    """eta = +1 with C1 = C2: the combined PSD is exactly 0, no roughness: mu = 0, A/A0 = 1."""
    mu, area = _kernel_case(0.8, 1e-6, 1e5, 1e6, 100.0, 1e-3, np.geomspace(1e-9, 1e3, 5), eta=1.0)
    assert np.all(mu == 0.0) and np.all(area == 1.0)


def test_scaling_modulus_and_pressure_together_leaves_mu_unchanged():
    """eqs 61-62 depend on E and sigma0 only through E/sigma0."""
    v = np.geomspace(1e-6, 1e2, 5)
    mu1, a1 = _kernel_case(0.8, 2e-6, 3e5, 4e6, 500.0, 1e-4, v)
    mu2, a2 = _kernel_case(0.8, 2e-6, 3e5 * 7.0, 4e6 * 7.0, 500.0, 1e-4, v)
    np.testing.assert_allclose(mu2, mu1, rtol=1e-10)
    np.testing.assert_allclose(a2, a1, rtol=1e-10)


def test_yang_persson_factor_lowers_mu_and_gamma_one_is_the_plain_theory():
    v = np.geomspace(1e-6, 1e2, 5)
    plain, _ = _kernel_case(0.8, 2e-6, 3e5, 4e6, 500.0, 1e-4, v)
    yp, _ = _kernel_case(0.8, 2e-6, 3e5, 4e6, 500.0, 1e-4, v, correction="yang_persson", gamma=0.5)
    one, _ = _kernel_case(0.8, 2e-6, 3e5, 4e6, 500.0, 1e-4, v, correction="yang_persson", gamma=1.0)
    assert np.all(yp < plain)
    np.testing.assert_allclose(one, plain, rtol=1e-13)


def test_angular_integrals_of_a_constant_modulus_are_exact():
    """A = (pi/2) E^2 and B = 0 for E = const, for any number of nodes."""
    q = np.geomspace(1e3, 1e6, 7)
    grid = np.geomspace(1e-3, 1e12, 61)
    E = np.full(grid.size, 3e6)
    A, B = physics_friction.angular_integrals(q, np.asarray([1e-3, 1.0]), grid, E, np.zeros(grid.size), 3)
    np.testing.assert_allclose(A, np.pi / 2 * 9e12, rtol=1e-14)
    assert np.all(B == 0)


@pytest.mark.parametrize("chunk", [1, 700, 16_000])
def test_kernels_working_row_by_row_change_no_value(monkeypatch, chunk):
    """The kernels work through their leading axes (velocities, cases, pressures) a few rows at a
    time (physics.friction.CHUNK_ELEMENTS, to keep temporaries small): every output, on leading
    shapes of every kind (a scalar v, v x cases, a modulus per row, pressures x cases x v), is
    what one pass over the whole arrays gives, to 1e-14."""
    q = log_grid(1e4, 1e7, 10)
    C1 = 1e-20 * (q / 1e4) ** -3.6
    C = np.stack([C1, 0.5 * C1, 2 * C1])  # 3 cases
    grid = np.geomspace(1e-8, 1e22, 121)
    Ep, Epp = ve.box_spectrum_modulus(grid, 5e6, 3e9, 1e-6, 1e4)
    v = np.geomspace(1e-9, 1e3, 9)

    def everything():
        out = [physics_friction.angular_integrals(q, v, grid, Ep, Epp, 8),
               physics_friction.angular_integrals(q, np.float64(1e-3), grid, Ep, Epp, 8),
               physics_friction.angular_integrals(q, v[:, None], grid, np.stack([Ep, 2 * Ep]),
                                                  np.stack([Epp, 3 * Epp]), 8)]
        A, B = out[0]
        p = np.array([1e5, 4e5])[:, None, None]
        out += [physics_friction.friction_kernel(q, C[:, None, :], A[None], B[None], p, 0.5, "yang_persson", 0.5,
                                                 True),
                physics_friction.friction_kernel(q, C[1], A[4], B[4], np.asarray(4e5), 0.5)]
        return [np.asarray(x) for pair in out for x in pair]

    monkeypatch.setattr(physics_friction, "CHUNK_ELEMENTS", 10**12)
    whole = everything()
    monkeypatch.setattr(physics_friction, "CHUNK_ELEMENTS", chunk)
    for got, want in zip(everything(), whole, strict=True):
        assert got.shape == want.shape
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)


def test_dask_chunked_sweep_equals_unchunked(tmp_path):
    raw = _scene(**{"interface.eta": [0.0, 1.0, -1.0]})
    plain = _run(raw, tmp_path / "a")["friction"]
    raw["numerics"]["chunks"] = {"v": 7, "eta": 1}
    chunked = _run(raw, tmp_path / "b")["friction"]
    np.testing.assert_allclose(chunked["friction_coefficient"].values, plain["friction_coefficient"].values, rtol=1e-14)


# ----------------------------------------------------------------------------------------
# Bad input
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("v", ["0 m/s", "-1 m/s", ["1 m/s", "0 m/s"]])
def test_nonpositive_velocity_is_a_user_error_naming_the_key(v):
    with pytest.raises(UserError) as err:
        scenes.from_dict(_scene(**{"friction.v": v}))
    assert err.value.key == "friction.v" or err.value.key.startswith("friction.v")


def test_missing_modulus_section_is_a_user_error(tmp_path):
    raw = _scene()
    del raw["modulus"]
    with pytest.raises(UserError) as err:
        _run(raw, tmp_path)
    assert err.value.key == "modulus"


def test_time_temperature_superposition(tmp_path):
    """With E(omega, T) = E(omega a_T, T_ref) (no vertical shift), eqs 61-62 give
    mu(v, T) = mu(v a_T, T_ref) and the same for A/A0: a T sweep is a shifted v sweep."""
    v = np.geomspace(1e-6, 1e-2, 5)
    raw = _scene(**{"modulus.T": ["-40 degC", "0 degC"], "friction.v": [f"{float(x)!r} m/s" for x in v],
                    "load.p": ["0.2 MPa", "0.4 MPa"]})
    res = _run(raw, tmp_path / "a")
    fric, mod = res["friction"], res["modulus"]
    assert set(fric["friction_coefficient"].dims) == {"T", "p", "v"}
    aT = float(mod["shift_factor"].isel(T=1))
    raw_ref = _scene(**{"modulus.T": "-40 degC", "friction.v": [f"{float(x)!r} m/s" for x in v * aT],
                        "load.p": ["0.2 MPa", "0.4 MPa"]})
    ref = _run(raw_ref, tmp_path / "b")["friction"]
    for name in ("friction_coefficient", "sliding_contact_area_ratio"):
        hot = fric[name].isel(T=1).transpose("p", "v").values
        np.testing.assert_allclose(hot, ref[name].transpose("p", "v").values, rtol=2e-5)


def test_friction_density_integrates_to_mu(tmp_path):
    """d mu / d ln q integrated over ln q gives mu (two second-order quadratures of the same integral,
    in q and in G, at 20 points per decade: agreement to 1e-5)."""
    from roughcontact.physics.quadrature import integral

    raw = _scene(**{"friction.v": {"from": "1e-9 m/s", "to": "1e-6 m/s", "num": 4},
                    "outputs.variables": ["friction_coefficient", "friction_density"]})
    fric = _run(raw, tmp_path)["friction"]
    q = fric["q"].values
    total = integral(q, fric["friction_density"].transpose("v", "q").values / q)
    np.testing.assert_allclose(total, fric["friction_coefficient"].values, rtol=1e-5)


def test_frequencies_beyond_the_modulus_grid_are_announced(tmp_path):
    raw = _scene(**{"modulus.omega_max": "1e8 rad/s", "modulus.omega_min": "1e-6 rad/s",
                    "friction.v": ["1e-3 m/s", "100 m/s"]})
    with pytest.warns(UserWarning, match="beyond the modulus grid"):
        fric = _run(raw, tmp_path)["friction"]
    assert fric.attrs["modulus_extrapolated"].startswith("yes")
    assert np.all(np.isfinite(fric["friction_coefficient"].values))


# ----------------------------------------------------------------------------------------
# Contact shear term (friction.shear)
# ----------------------------------------------------------------------------------------

SHEAR = {"friction.shear": "gaussian", "friction.shear_tau0": "3 MPa", "friction.shear_v0": "1e-6 m/s",
         "friction.shear_c": 0.1}
SHEAR_OUT = ["friction_coefficient", "friction_coefficient_viscoelastic", "friction_coefficient_contact",
             "contact_shear_stress", "sliding_contact_area_ratio"]
V3 = ["1e-6 m/s", "1e-3 m/s", "1 m/s"]


def _gaussian(v_reduced, tau0=3e6, v0=1e-6, c=0.1):
    return tau0 * np.exp(-c * np.log10(v_reduced / v0) ** 2)


def test_zero_shear_stress_gives_the_seed_friction_exactly(tmp_path):
    seed = _run(_scene(**{"friction.v": V3}), tmp_path / "seed")["friction"]
    zero = _run(_scene(**{**SHEAR, "friction.shear_tau0": "0 Pa", "friction.v": V3,
                          "outputs.variables": SHEAR_OUT}), tmp_path / "zero")["friction"]
    np.testing.assert_array_equal(zero["friction_coefficient"].values, seed["friction_coefficient"].values)
    np.testing.assert_array_equal(zero["friction_coefficient_contact"].values, 0.0)


def test_contact_term_is_tau_area_over_pressure_at_each_velocity(tmp_path):
    """mu_cont = tau_f(v a_T) A/A0 / sigma0 at every v (a_T of the modulus at modulus.T, WLF about
    T_ref), and mu is the sum of the two terms."""
    res = _run(_scene(**SHEAR, **{"friction.v": V3, "load.p": ["0.2 MPa", "0.4 MPa"],
                                  "outputs.variables": SHEAR_OUT}), tmp_path)
    fric, aT = res["friction"], float(res["modulus"]["shift_factor"])
    tau = _gaussian(fric["v"].values * aT)
    np.testing.assert_allclose(fric["contact_shear_stress"].values, tau, rtol=1e-12)  # independent of p
    expected = tau[:, None] * fric["sliding_contact_area_ratio"].transpose("v", "p") / fric["p"]
    np.testing.assert_allclose(fric["friction_coefficient_contact"].transpose("v", "p"), expected, rtol=1e-12)
    np.testing.assert_allclose(fric["friction_coefficient"],
                               fric["friction_coefficient_viscoelastic"] + fric["friction_coefficient_contact"],
                               rtol=1e-14)
    assert np.all(fric["friction_coefficient_contact"] > 0)


def test_shear_table_is_read_at_the_reduced_velocity(tmp_path):
    """A table of tau_f: linear in log10(v a_T) between its points (here through the Gaussian's
    values at three decades: exact at the nodes), the end values outside."""
    res = _run(_scene(**{"friction.shear": "table", "friction.shear_table_v": ["1e-12 m/s", "1e-9 m/s", "1e-6 m/s"],
                         "friction.shear_table_tau": ["1 MPa", "2 MPa", "4 MPa"], "friction.v": V3,
                         "outputs.variables": SHEAR_OUT}), tmp_path)
    fric, aT = res["friction"], float(res["modulus"]["shift_factor"])
    expected = np.interp(np.log10(fric["v"].values * aT), [-12, -9, -6], [1e6, 2e6, 4e6])
    np.testing.assert_allclose(fric["contact_shear_stress"].values, expected, rtol=1e-12)


def test_with_flash_temperature_tau_follows_the_contacts_temperature(tmp_path):
    """With friction.flash the shear stress is read at the flash temperature of the contacts (its
    WLF a_T), not at modulus.T: the contacts are hotter at speed, so v a_T is smaller there."""
    thermal = {"friction.flash": True, "friction.thermal_conductivity": "0.25 W/(m*K)",
               "friction.density": "1200 kg/m^3", "friction.heat_capacity": "1500 J/(kg*K)"}
    res = _run(_scene(**SHEAR, **thermal, **{"friction.v": ["1e-6 m/s", "10 m/s", "100 m/s"],
                                             "outputs.variables": SHEAR_OUT + ["flash_temperature"]}), tmp_path)
    fric = res["friction"]
    Tc = fric["flash_temperature"].values
    assert np.all(Tc[1:] > float(fric["T"]) + 1.0)  # the contacts are hotter: the test can tell
    aT = 10.0 ** ve.wlf_log10_shift(Tc, 233.15, 17.44, 51.6)
    np.testing.assert_allclose(fric["contact_shear_stress"].values, _gaussian(fric["v"].values * aT), rtol=1e-10)
    at_given = _gaussian(fric["v"].values * float(res["modulus"]["shift_factor"]))
    assert np.all(np.abs(fric["contact_shear_stress"].values[1:] / at_given[1:] - 1) > 1e-3)
    np.testing.assert_allclose(fric["friction_coefficient_contact"],
                               fric["contact_shear_stress"] * fric["sliding_contact_area_ratio"] / fric["p"],
                               rtol=1e-12)


@pytest.mark.parametrize("overrides, key", [
    ({"friction.shear": "gaussian", "friction.shear_v0": "1 m/s", "friction.shear_c": 0.1}, "friction.shear_tau0"),
    ({"friction.shear": "table", "friction.shear_table_v": ["1 m/s", "0.1 m/s"],
      "friction.shear_table_tau": ["1 MPa", "2 MPa"]}, "friction.shear_table_v"),
    ({"outputs.variables": ["friction_coefficient_contact"]}, "friction.shear"),
])
def test_bad_shear_input_names_the_key(tmp_path, overrides, key):
    with pytest.raises(UserError) as err:
        _run(_scene(**overrides), tmp_path)
    assert err.value.key == key
