"""Tests of the stiffness and conductance stages (issue 17).

Each test asserts a physical fact: K = -dp/du equals an independent central difference of eq 57
(adaptive quadrature of the printed integral, no code of the package) to 1e-4; K -> p/u0 at
small load; the exact scaling C -> lambda^2 C; K rises with load; identical surfaces with
eta = 1 fit (infinite stiffness and conductance, zero resistance, stored as +inf and 0); the
conductance of one rough surface is Barber's analogy applied to that surface's stiffness, and
kappa p / (E* u0) at small load; Holm's single spot fixes the prefactor; bad input is a one-line
error naming the key.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make_scene
from reference_solutions import self_affine_C0, self_affine_psd, self_affine_q3C_integral
from scipy import integrate, special

from roughcontact import cli
from roughcontact.physics.interface import barber_conductance, contact_stiffness, stiffness_from_psd
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.separation import mean_separation, separation_nodes

H, QL, Q0, Q1 = 0.8, 2e8, 8e8, 4e10
E_STAR = 77.2e9 / (1 - 0.42**2)
ALPHA = 0.45


def plateau(hrms):
    """C0 of the self-affine PSD with roll-off from its rms height (exact integral)."""
    return self_affine_C0(hrms, H, QL, Q0, Q1)


def psd(q, C0):
    return self_affine_psd(q, C0, H, Q0)


def running_q3C(dq, C0):
    """\\int_qL^(qL + dq) q'^3 C dq' in closed form (no cancellation as dq -> 0)."""
    return self_affine_q3C_integral(dq, C0, H, QL, Q0)


def separation_by_quad(p, zeta, C0):
    """Eq 57 by adaptive quadrature, u = (sqrt(pi) alpha/2) int q^2 C w E1((w p/E*)^2) dq, in
    t = sqrt(q - qL) (which removes the 1/sqrt end of w)."""
    def f(t):
        q = QL + t * t
        w = 1.0 / np.sqrt(np.pi * running_q3C(t * t, C0))
        return 2 * t * q * q * psd(q, C0) * w * special.exp1((w * p / E_STAR) ** 2)

    top = np.sqrt(zeta * QL - QL)
    cut = np.sqrt(Q0 - QL)
    parts = [(0.0, min(cut, top))] + ([(cut, top)] if top > cut else [])
    total = sum(integrate.quad(f, a, b, epsabs=0, epsrel=1e-13, limit=400)[0] for a, b in parts)
    return np.sqrt(np.pi) * ALPHA / 2 * total


def stiffness_by_difference(p, zeta, C0, h=1e-3):
    return -(2 * h * p) / (separation_by_quad(p * (1 + h), zeta, C0) - separation_by_quad(p * (1 - h), zeta, C0))


def stiffness_scene(**over):
    raw = make_scene(outputs={"variables": ["contact_stiffness"]},
                     load={"p": [E_STAR * x for x in (1e-7, 1e-4, 1e-2, 0.1)]},
                     contact={"zeta": [4.0, 200.0]}, interface={"eta": [0.0]},
                     numerics={"points_per_decade": 50}, substrate={"q0": f"{Q0!r} 1/m"},
                     solid={"q0": f"{Q0!r} 1/m"})
    for k, v in over.items():
        raw[k] = {**raw.get(k, {}), **v} if isinstance(v, dict) else v
    raw["load"]["p"] = [f"{float(x)!r} Pa" for x in raw["load"]["p"]]
    return raw


def test_stiffness_equals_an_independent_central_difference_of_eq57(run_scene):
    ds = run_scene(stiffness_scene())["base"]["stiffness"]
    C0 = 2 * plateau(1e-9)  # two uncorrelated surfaces of 1 nm: the combined PSD doubles
    for zeta in (4.0, 200.0):
        for p in ds["p"].values:
            K = float(ds["contact_stiffness"].sel(zeta=zeta, p=p).squeeze())
            expected = stiffness_by_difference(p, zeta, C0)
            assert K == pytest.approx(expected, rel=1e-4), (zeta, p / E_STAR)


def test_stiffness_tends_to_p_over_u0_at_small_load(run_scene):
    raw = stiffness_scene(load={"p": [E_STAR * x for x in (1e-11, 1e-9, 1e-7, 1e-5, 1e-3)]})
    raw["outputs"]["variables"].append("mean_separation")
    res = run_scene(raw)["base"]
    ds = res["stiffness"]
    ratio = (ds["contact_stiffness"] / ds["small_load_stiffness"]).sel(zeta=200.0).squeeze().values
    assert abs(ratio[0] - 1) < 1e-6
    assert np.all(np.diff(ratio) > 0)  # the law holds better the smaller the load
    u0 = res["separation"]["separation_u0"].sel(zeta=200.0).squeeze()
    np.testing.assert_allclose(ds["small_load_stiffness"].sel(zeta=200.0).squeeze(), ds["p"] / u0, rtol=1e-14)


@pytest.mark.parametrize("refinement", ["yang_persson", "wang_mueser"])
def test_refined_stiffness_is_the_derivative_of_its_separation(refinement):
    q = log_grid(QL, Q1, 50, knots=(Q0,))
    C = psd(q, plateau(1e-9))
    s, weight, count, _, s_tail, q_tail = separation_nodes(q, C, np.array([Q1]), 4, 6, 10.0)
    p = E_STAR * np.logspace(-8, -1, 8)
    kw = dict(E_star=E_STAR, alpha=ALPHA, refinement=refinement)
    D, K = stiffness_from_psd(q, C, np.array([Q1]), p, panels_per_decade=4, order=6, **kw)
    h = 1e-4
    du = mean_separation(p * (1 + h), s, weight, count, s_tail, q_tail, **kw) - \
        mean_separation(p * (1 - h), s, weight, count, s_tail, q_tail, **kw)
    np.testing.assert_allclose(K, -(2 * h * p[:, None]) / du, rtol=1e-6)


def test_exact_scaling_of_the_stiffness():
    """C -> lambda^2 C maps u(p) to lambda u(p/lambda), hence K(p) to K(p/lambda)."""
    q = log_grid(QL, Q1, 30, knots=(Q0,))
    C = psd(q, plateau(1e-9))
    p = E_STAR * np.logspace(-6, -1, 6)
    lam = 7.3
    kw = dict(E_star=E_STAR, alpha=ALPHA)
    _, K = stiffness_from_psd(q, lam**2 * C, np.array([Q1]), p, **kw)
    _, K_ref = stiffness_from_psd(q, C, np.array([Q1]), p / lam, **kw)
    np.testing.assert_allclose(K, K_ref, rtol=1e-10)


def test_stiffness_rises_with_load_and_is_finite_from_tiny_to_huge_loads(run_scene):
    raw = stiffness_scene(load={"p": list(E_STAR * np.logspace(-12, 0.5, 27))}, interface={"eta": [0.0, -1.0]})
    K = run_scene(raw)["base"]["stiffness"]["contact_stiffness"].sel(zeta=200.0).transpose("eta", "p").values
    finite = np.isfinite(K)
    assert finite[:, :-2].all() and np.all(K > 0)
    assert np.all(np.diff(K, axis=-1) > 0)


def conductance_scene(**over):
    raw = stiffness_scene(**over)
    raw["outputs"]["variables"] = ["thermal_contact_conductance", "electrical_contact_conductance"]
    raw["conductance"] = {"thermal_conductivity_substrate": "60 W/(m*K)", "thermal_conductivity_solid": "0.25 W/(m*K)",
                          "resistivity_substrate": "1.4e-7 ohm*m", "resistivity_solid": "2 ohm*m"}
    return raw


def test_identical_surfaces_fit_infinite_stiffness_and_conductance_zero_resistance(run_scene):
    res = run_scene(conductance_scene(interface={"eta": [0.0, 1.0]}))["base"]
    K = res["stiffness"]["contact_stiffness"].sel(eta=1.0)
    assert np.all(np.isposinf(K)) and np.all(res["stiffness"]["stiffness_length"].sel(eta=1.0) == 0)
    assert "+inf" in K.attrs["comment"]
    c = res["conductance"]
    for kind in ("thermal", "electrical"):
        assert np.all(np.isposinf(c[f"{kind}_contact_conductance"].sel(eta=1.0)))
        assert np.all(c[f"{kind}_contact_resistance"].sel(eta=1.0) == 0)
        finite = c[f"{kind}_contact_conductance"].sel(eta=0.0)
        assert np.all(np.isfinite(finite) & (finite > 0))


def test_one_rough_surface_gives_barbers_single_surface_conductance(run_scene):
    """Solid flat: h = 2 K / (E* (1/k1 + 1/k2)) with K of the substrate alone (independent
    quadrature); at small load, for equal conductivities k, h = k p / (E* u0)."""
    raw = conductance_scene(solid=None)
    raw["conductance"].update(thermal_conductivity_substrate="40 W/(m*K)", thermal_conductivity_solid="40 W/(m*K)")
    raw["load"]["p"] = [f"{E_STAR * x!r} Pa" for x in (1e-10, 1e-3)]
    raw["outputs"]["variables"].append("mean_separation")
    res = run_scene(raw)["base"]
    h = res["conductance"]["thermal_contact_conductance"].sel(zeta=200.0).squeeze()
    C0 = plateau(1e-9)
    for p in h["p"].values:
        expected = 2 * stiffness_by_difference(p, 200.0, C0) / (E_STAR * (2 / 40.0))
        assert float(h.sel(p=p)) == pytest.approx(expected, rel=1e-4)
    u0 = float(res["separation"]["separation_u0"].sel(zeta=200.0).squeeze())
    p = h["p"].values[0]
    assert float(h.sel(p=p)) == pytest.approx(40.0 * p / (E_STAR * u0), rel=1e-6)


def test_a_single_circular_spot_fixes_the_prefactor():
    """One spot of radius a between two half-spaces: stiffness 2 a E* (Sneddon's flat punch) and
    constriction resistance (rho1 + rho2) / (4 a) (Holm): the analogy must give 4 a / (rho1 + rho2)."""
    a, rho1, rho2 = 3e-6, 1.7e-8, 2.5e-7
    assert barber_conductance(2 * a * E_STAR, E_STAR, rho1 + rho2) == pytest.approx(4 * a / (rho1 + rho2), rel=1e-14)
    assert contact_stiffness(1e6, 0.0) == np.inf and contact_stiffness(1e6, 2e-9) == pytest.approx(5e14)


@pytest.mark.parametrize("over, key, message", [
    ({"thermal_conductivity_substrate": "-5 W/(m*K)"}, "conductance.thermal_conductivity_substrate", "must be > 0"),
    ({"resistivity_solid": "0 ohm*m"}, "conductance.resistivity_solid", "must be > 0"),
    ({"thermal_conductivity_solid": None}, "conductance.thermal_conductivity_solid", "give it for the solid too"),
    ({"thermal_conductivity_substrate": "5 W/m"}, "conductance.thermal_conductivity_substrate", "not convertible"),
    ("none", "conductance", "needs the thermal conductivities or the electrical resistivities"),
])
def test_bad_conductance_input_is_a_one_line_error_naming_the_key(write_scene, capsys, over, key, message):
    raw = conductance_scene()
    if over == "none":
        raw.pop("conductance")
    else:
        for k, v in over.items():
            if v is None:
                raw["conductance"].pop(k)
            else:
                raw["conductance"][k] = v
    code = cli.main(["run", str(write_scene(raw)), "--outdir", str(write_scene(raw).parent / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert key in err and message in err and len(err.splitlines()) == 1, err
