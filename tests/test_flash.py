"""Flash temperature (friction.flash; physics/flash.py, stages/shared/flash.py).

Facts checked: the isothermal theory is recovered for vanishing speed and for infinite thermal
conductivity; the temperature rise is non-negative and grows with v where E'' does not fall with
frequency; a compound whose loss falls with temperature at the sliding frequencies loses friction
to the heating while a flat-loss (box) spectrum barely changes; the heat released over the scales
adds up to sigma_f v; the background march reproduces the closed form of a constant flux; bad
input names the key.
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, linalg

from roughcontact import engine, scene as scenes
from roughcontact.errors import SceneWarning, UserError
from roughcontact.physics import flash, friction as fr, viscoelastic as ve
from roughcontact.physics.quadrature import integral, log_grid

sys.path.insert(0, str(Path(__file__).resolve().parent))
from reference_solutions import self_affine_C0  # noqa: E402
from test_friction import _scene  # noqa: E402

QUIET = engine.Reporter(None)
RUBBER = dict(conductivity=0.25, diffusivity=0.25 / (1200.0 * 1500.0))  # W/(m K), m^2/s: typical filled rubber
SIGMA0, NU = 4e5, 0.5


def _psd(ppd=40, decades=4):
    q = log_grid(1e4, 1e4 * 10.0**decades, ppd)
    q1 = q[-1]

    def one(h, H):
        C0 = self_affine_C0(h, H, 1e4, 1e4, q1)
        return C0 * (q / 1e4) ** (-2 * (1 + H))

    return q, one(2.7e-6, 0.93) + one(6e-6, 0.87)


def _material(model, T, T_ref, C1=17.44, C2=51.6):
    """Modulus grid at temperature T and the shift callable of the kernels (WLF about T_ref)."""
    law = lambda t: ve.wlf_log10_shift(t, T_ref, C1, C2)  # noqa: E731
    aT = 10.0 ** law(T)
    grid = np.geomspace(1e-12, 1e24, 36 * 20 + 1)
    Ep, Epp = model(grid * aT)
    return grid, Ep, Epp, lambda t: (10.0 ** (law(t) - law(T)), np.ones_like(t))


BOX_TREAD = lambda w: ve.box_spectrum_modulus(w, 5e6, 3e9, 1e-6, 1e4)  # noqa: E731  (the built-in scene's box)
FLAT_BOX = lambda w: ve.box_spectrum_modulus(w, 5e6, 3e9, 1e-14, 1e6)  # noqa: E731  (flat E'' over 20 decades)
#: a compound with a loss peak: log-normal relaxation spectrum (as in the master-curve tests)
TAU = np.logspace(-12, 4, 49)
PEAKED = lambda w: ve.prony_modulus(w, 5e6, 3e9 / 49 * 2.5 * np.exp(-0.5 * ((np.log10(TAU) + 5) / 3.0) ** 2), TAU)  # noqa: E731


def _both(model, v, T=298.15, T_ref=230.25, **thermal):
    q, C = _psd()
    grid, Ep, Epp, shift = _material(model, T, T_ref)
    A, B = fr.angular_integrals(q, v, grid, Ep, Epp, 16)
    iso = fr.friction_kernel(q, C, A, B, np.asarray(SIGMA0), NU)
    props = {**RUBBER, **thermal}
    hot = flash.flash_friction_kernel(q, C, v, T, grid, Ep, Epp, 16, SIGMA0, NU, props["conductivity"],
                                      props["diffusivity"], shift)
    return iso, hot


# ----------------------------------------------------------------------------------------
# Limits
# ----------------------------------------------------------------------------------------


def test_infinite_conductivity_is_the_isothermal_theory():
    v = np.geomspace(1e-6, 1e3, 10)
    (mu0, a0), (mu, a, Tc) = _both(BOX_TREAD, v, conductivity=np.inf, diffusivity=np.inf)
    np.testing.assert_allclose(mu, mu0, rtol=1e-6)
    np.testing.assert_allclose(a, a0, rtol=1e-6)
    assert np.all(Tc == 298.15)


def test_vanishing_speed_is_the_isothermal_theory():
    v = np.geomspace(1e-9, 1e-6, 4)
    (mu0, a0), (mu, a, Tc) = _both(BOX_TREAD, v)
    np.testing.assert_allclose(mu, mu0, rtol=1e-6)
    np.testing.assert_allclose(a, a0, rtol=1e-6)
    assert np.all(Tc - 298.15 < 1e-6)


def test_passage_average_limits_in_closed_form_and_series_join():
    """Theta(x) of the heat released in the layer of depth 1/q: x/2 - (8/(15 sqrt pi)) x^(3/2) for
    x -> 0 (adiabatic heating, the mean of J q t / (rho c) over the passage) and 1/2 - 3/(8x) for
    x -> inf (steady spreading); the series and the closed form join at x = 0.2; it is the mean of
    theta over the passage; increasing and never above the adiabatic x/2."""
    x = np.array([1e-12, 1e-6, 1e-4, 0.2 - 1e-9, 0.2 + 1e-9, 1.0, 1e3, 1e6, 1e15])
    th = flash.passage_average(x)
    small = x[:3]
    np.testing.assert_allclose(th[:3], small / 2 - 8 / (15 * math.sqrt(math.pi)) * small ** 1.5, rtol=1e-6)
    assert th[3] == pytest.approx(th[4], rel=1e-8)
    np.testing.assert_allclose(th[-3:], 0.5 - 3 / (8 * x[-3:]), rtol=1e-12)
    assert np.all(np.diff(th) > 0) and np.all(th <= x / 2)
    for xi in (0.05, 0.7, 4.0):  # the mean over the passage of the instantaneous surface temperature
        a = np.linspace(0.0, xi, 4001)
        mean = integrate.simpson(flash.layer_surface_temperature(a), x=a) / xi
        assert flash.passage_average(xi) == pytest.approx(mean, rel=1e-9)


def test_heating_rate_limits_steady_spreading_and_adiabatic_layer():
    """dT/dq at low speed is the steady spreading of the heat J released at depth 1/q,
    J / (2 lambda q) = v q^2 C S B / ((1 - nu^2) lambda); at high speed the adiabatic heating of
    the layer, the mean of J q t / (rho c) over a passage t0 = pi / (q v), per unit q
    pi q^3 C S B / ((1 - nu^2) rho c),
    independent of v (the temperature no longer grows with speed)."""
    q = np.geomspace(1e4, 1e8, 9)
    C, S, B = 1e-30 * (q / 1e4) ** -3.8, np.full(9, 0.7), np.full(9, 3e8)
    lam, D = RUBBER["conductivity"], RUBBER["diffusivity"]
    slow = np.array([1e-14, 1e-12])  # pi D q / v >= 1e5
    rate = flash.heating_rate(q, slow, C, S, B, NU, lam, D)
    steady = slow[:, None] / ((1 - NU**2) * lam) * q**2 * C * S * B
    np.testing.assert_allclose(rate, steady, rtol=1e-5)
    fast = np.array([1e4, 1e8])  # pi D q / v <= 5e-3, <= 5e-7
    rate = flash.heating_rate(q, fast, C, S, B, NU, lam, D)
    adiabatic = math.pi * q**3 * C * S * B / ((1 - NU**2) * lam / D)
    np.testing.assert_allclose(rate, np.broadcast_to(adiabatic, rate.shape), rtol=0.04)
    np.testing.assert_allclose(rate[1], adiabatic, rtol=1e-3)
    assert np.all(rate <= adiabatic)


def test_layer_heating_solves_the_heat_equation_and_keeps_the_energy_balance():
    """The closed form theta(a) against a Crank-Nicolson solution of the heat equation of the mode
    cos(qx): dT/da = T'' - T + e^{-z} (z in units of 1/q, a = D q^2 t, T in units of J/(lambda q)),
    insulated surface. Energy balance: the heat in the layer H = int T dz obeys dH/da = 1 - H
    (power in minus lateral spreading), H = 1 - e^{-a}."""
    dz, L, da = 0.01, 30.0, 2e-3
    z = np.arange(0.0, L + dz / 2, dz)
    n = z.size
    lap = np.zeros((3, n))  # second difference with a mirror node at the surface, T = 0 far down
    lap[0, 1:], lap[1, :], lap[2, :-1] = 1 / dz**2, -2 / dz**2 - 1.0, 1 / dz**2
    lap[0, 1] = 2 / dz**2
    lhs = -0.5 * da * lap
    lhs[1] += 1.0

    def apply(T):
        out = lap[1] * T
        out[:-1] += lap[0, 1:] * T[1:]
        out[1:] += lap[2, :-1] * T[:-1]
        return out

    T, a, checks = np.zeros(n), 0.0, {}
    for target in (0.02, 0.2, 1.0, 4.0):
        while a < target - 1e-12:
            T = linalg.solve_banded((1, 1), lhs, T + 0.5 * da * apply(T) + da * np.exp(-z))
            a += da
        checks[target] = (T[0], integrate.simpson(T, x=z))
    for target, (surface, heat) in checks.items():
        assert surface == pytest.approx(flash.layer_surface_temperature(target), rel=2e-3, abs=1e-6), target
        assert heat == pytest.approx(1 - math.exp(-target), rel=1e-3), target
    assert flash.layer_surface_temperature(1e-6) == pytest.approx(1e-6, rel=1e-3)  # adiabatic: rho c dT/dt = J q
    assert flash.layer_surface_temperature(1e6) == pytest.approx(0.5, rel=1e-12)  # steady: J / (2 lambda q)


# ----------------------------------------------------------------------------------------
# Temperature rise
# ----------------------------------------------------------------------------------------


def test_temperature_rise_nonnegative_and_growing_with_v_where_loss_does_not_fall():
    """With E''(omega) non-decreasing at every frequency the contacts reach (the flat box spectrum
    and the low-frequency side of its plateau), the heating rate grows with v at any temperature
    (v Theta(pi D q / v) grows with v, Theta being the mean of a concave function), so by comparison
    of the two initial-value problems T_q(v2) >= T_q(v1) for v2 > v1; and it is never negative."""
    v = np.geomspace(1e-4, 30.0, 16)
    _, (_, _, Tc) = _both(FLAT_BOX, v, T=293.15, T_ref=293.15)
    rise = Tc - 293.15
    assert np.all(rise >= 0)
    assert np.all(np.diff(rise) > 0)
    assert rise[-1] > 5.0  # the effect is not negligible at tens of m/s


def test_temperature_rise_bounded_by_adiabatic_heating_of_the_layers():
    """Theta(x) <= x/2, so at every speed the rise stays below the adiabatic heating of the layers,
    pi / ((1 - nu^2) rho c) int q^3 C B dq (S = 1, B <= max E'' for the flat box), and approaches it
    at high speed: the rise is bounded in v (a surface source grows like sqrt v instead)."""
    v = np.array([1.0, 100.0, 1e4])
    _, (_, _, Tc) = _both(FLAT_BOX, v, T=293.15, T_ref=293.15)
    q, C = _psd()
    _, _, Epp, _ = _material(FLAT_BOX, 293.15, 293.15)
    rho_c = RUBBER["conductivity"] / RUBBER["diffusivity"]
    bound = math.pi / ((1 - NU**2) * rho_c) * integral(q, q**3 * C * Epp.max())
    rise = Tc - 293.15
    assert np.all(rise <= bound) and np.all(np.diff(rise) > 0)
    assert rise[-1] > 0.95 * bound


def test_flat_loss_stays_close_but_a_loss_peak_compound_loses_friction():
    """Box spectrum with E'' flat over the sliding frequencies: B is unchanged by the heating, which
    only softens E' (by ~150 MPa per decade of shift for this box), so the contact area grows and mu
    with it, never by more than the area (P(q) grows most at q1): close at low speed, up to ~3x at
    30 m/s where the contacts are ~125 K hotter. Compound with a loss peak above the sliding
    frequencies (E'' falls with temperature there): mu with flash temperature is below the
    isothermal mu at high speed (3 % lower at 30 m/s, 10 K hotter)."""
    v = np.geomspace(0.1, 30.0, 6)
    (mu0, a0), (mu, a, _) = _both(FLAT_BOX, v, T=293.15, T_ref=293.15)
    assert np.all(mu >= mu0 * (1 - 1e-9)) and np.all(a >= a0 * (1 - 1e-9))
    assert np.all(mu / mu0 <= a / a0 * (1 + 1e-6))
    assert mu[0] / mu0[0] - 1 < 0.15
    (mu0, _), (mu, _, Tc) = _both(PEAKED, v, T=298.15, T_ref=230.25)
    grid = np.geomspace(1e2, 3e7, 50)  # q v over the first 3 decades of q: E'' falls with T there
    aT = lambda t: 10.0 ** ve.wlf_log10_shift(t, 230.25, 17.44, 51.6)  # noqa: E731
    hot, cold = PEAKED(grid * aT(318.15)), PEAKED(grid * aT(298.15))
    assert np.all(hot[1] < cold[1])
    assert np.all(mu[v >= 1.0] < mu0[v >= 1.0])
    assert np.all(Tc > 298.15)


def test_energy_balance_heat_over_the_scales_adds_up_to_sigma_f_v():
    """The heat released at each scale, sigma0 v dmu/dln q (from the march's contact heat flux
    J P), integrated over ln q with the power-law quadrature equals the dissipated power
    mu sigma0 v of the G-variable integral: two quadratures of one integral, second order."""
    v = np.array([0.01, 0.1, 1.0])
    errors = []
    for ppd in (50, 100):
        q, C = _psd(ppd, decades=3)
        grid, Ep, Epp, shift = _material(BOX_TREAD, 298.15, 230.25)
        mu, _, _, T, heat = flash.flash_friction_kernel(q, C, v, 298.15, grid, Ep, Epp, 16, SIGMA0, NU,
                                                        RUBBER["conductivity"], RUBBER["diffusivity"], shift,
                                                        profile=True)
        assert np.all(heat >= 0) and np.all(np.diff(T, axis=-1) >= 0)
        errors.append(np.abs(integral(q, heat / q) / (mu * SIGMA0 * v) - 1))
    assert np.all(errors[1] < 2e-3)
    assert np.all(errors[1] < errors[0] / 2.5)  # about second order


def test_background_march_reproduces_the_constant_flux_closed_form():
    """A constant flux J into a semi-infinite solid: Delta T(t) = 2 J sqrt(t / pi) / e exactly
    (product integration is exact for a piecewise-linear flux)."""
    times = np.concatenate([[0.0], np.geomspace(1e-6, 1.0, 15)])
    J, e, t_s = 2.0e4, 600.0, np.array([1e-3, 1.0, 100.0])
    rise, kept = flash.background_march(times, t_s, lambda T: (np.full(np.shape(T), J), "ok"), e,
                                        np.full(3, 293.15))
    np.testing.assert_allclose(rise, 2 * J * np.sqrt(t_s / math.pi) / e, rtol=1e-12)
    assert kept == "ok"


# ----------------------------------------------------------------------------------------
# The friction stage with friction.flash = true
# ----------------------------------------------------------------------------------------

THERMAL = {"friction.flash": True, "friction.thermal_conductivity": "0.25 W/(m*K)",
           "friction.density": "1200 kg/m^3", "friction.heat_capacity": "1500 J/(kg*K)"}


def _run(raw, tmp_path):
    return engine.run(scenes.from_dict(raw), tmp_path, report=QUIET)["base"]["friction"]


def test_stage_outputs_with_and_without_flash(tmp_path):
    raw = _scene(**THERMAL, **{"friction.background": "semi_infinite", "friction.sliding_distance": "1 cm",
                               "numerics.flash_time_nodes": 6,
                               "interface.eta": [0.0, -1.0], "friction.v": ["1e-6 m/s", "0.1 m/s", "10 m/s"],
                               "outputs.variables": ["friction_coefficient", "friction_coefficient_isothermal",
                                                     "flash_temperature", "background_temperature_rise",
                                                     "flash_temperature_profile", "frictional_heating"]})
    fric = _run(raw, tmp_path)
    for name in ("friction_coefficient", "friction_coefficient_isothermal", "flash_temperature",
                 "background_temperature_rise", "flash_temperature_profile", "frictional_heating"):
        assert name in fric and np.all(np.isfinite(fric[name].values)), name
    assert fric["flash_temperature"].attrs["units"] == "K"
    rise = fric["background_temperature_rise"].values
    assert np.all(rise >= 0)
    flash_rise = (fric["flash_temperature"] - fric["T"]).values
    assert np.all(flash_rise >= rise - 1e-9)  # the contacts are at least as hot as the background
    iso = _run(_scene(**{"interface.eta": [0.0, -1.0], "friction.v": ["1e-6 m/s", "0.1 m/s", "10 m/s"]}),
               tmp_path / "iso")
    np.testing.assert_allclose(fric["friction_coefficient_isothermal"].values, iso["friction_coefficient"].values,
                               rtol=1e-12)
    np.testing.assert_allclose(fric["friction_coefficient"].sel(v=1e-6).values,
                               iso["friction_coefficient"].sel(v=1e-6).values, rtol=1e-6)


def test_background_rise_grows_with_sliding_distance(tmp_path):
    rises = []
    for d in ("1 mm", "10 cm"):
        raw = _scene(**THERMAL, **{"friction.background": "semi_infinite", "friction.sliding_distance": d,
                                   "numerics.flash_time_nodes": 6, "numerics.points_per_decade": 10,
                                   "friction.v": ["0.01 m/s", "1 m/s"],
                                   "outputs.variables": ["background_temperature_rise"]})
        rises.append(_run(raw, tmp_path / d.replace(" ", ""))["background_temperature_rise"].values)
    assert np.all(rises[1] > rises[0]) and np.all(rises[0] > 0)


@pytest.mark.parametrize("overrides, key", [
    ({"friction.flash": True}, "friction.thermal_conductivity"),
    ({**THERMAL, "friction.background": "semi_infinite"}, "friction.sliding_distance"),
    ({"outputs.variables": ["flash_temperature"]}, "friction.flash"),
    ({**THERMAL, "outputs.variables": ["background_temperature_rise"]}, "friction.background"),
    ({**THERMAL, "friction.density": "-1 kg/m^3"}, "friction.density"),
])
def test_bad_flash_input_names_the_key(tmp_path, overrides, key):
    with pytest.raises(UserError) as err:
        _run(_scene(**overrides), tmp_path)
    assert err.value.key == key


DMA_FILE = Path(__file__).resolve().parents[1] / "pipeline" / "scenes" / "data" / "dma_example.txt"


def _dma_scene(T, v):
    """The DMA example (sweeps from -35 to 60 degC, WLF fitted to them) with the flash temperature."""
    return _scene(**THERMAL, **{"modulus": {"kind": "dma", "sweeps": str(DMA_FILE), "T_ref": "-20 degC", "T": T,
                                            "fit": "wlf"},
                                "friction.v": v, "numerics.points_per_decade": 10,
                                "outputs.variables": ["friction_coefficient", "flash_temperature"]})


def test_contacts_beyond_the_dma_sweeps_warn_with_the_data_range(tmp_path):
    """A user relies on this: when the flash temperature takes the contacts beyond the temperatures
    the WLF law was fitted on, the run says so, naming the sweeps' range and how far outside it the
    contacts go; inside the range it stays silent."""
    with pytest.warns(SceneWarning) as caught:
        fric = _run(_dma_scene("55 degC", ["1e-6 m/s", "100 m/s"]), tmp_path / "hot")
    hot = float(fric["flash_temperature"].max()) - 273.15
    assert hot > 61.0
    message = str(caught[0].message)
    assert "-35 degC to 60 degC" in message and f"reach {hot:.0f} degC" in message
    assert f"{hot - 60.0:.0f} K above the warmest" in message and "from v = 100 m/s on" in message
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        _run(_dma_scene("25 degC", ["1e-6 m/s", "0.01 m/s"]), tmp_path / "cool")
