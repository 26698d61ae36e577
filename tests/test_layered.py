"""The layered solid's surface response (physics/layered.py): the closed form against an
independent solution of the boundary-value problem, its limits and asymptotes, the bound
between the two moduli (where it holds, and a case where it does not), and bad input."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from roughcontact.physics.layered import (
    compliance_factor,
    effective_modulus,
    layer_constants,
    layered_spectrum,
    modulus_weight,
    surface_compliance,
)


def e_star(E, nu):
    return E / (1.0 - nu * nu)


def bvp_modulus(qd, E_l, nu_l, E_s, nu_s, digits=50):
    """E_eff from the layered boundary-value problem solved as a linear system in high precision
    (q = 1, d = qd, unit pressure): Papkovich-Neuber potentials phi = A exp(+-z), psi_z = C exp(+-z)
    in the layer (4 constants) and decaying ones in the substrate (2); sigma_zz = -1 and
    sigma_xz = 0 at the surface, u_x, u_z, sigma_zz, sigma_xz continuous at z = d. Independent of
    the closed form: nothing is simplified by hand."""
    with mp.workdps(digits):
        d = mp.mpf(qd)
        mu_l, mu_s = mp.mpf(E_l) / (2 * (1 + mp.mpf(nu_l))), mp.mpf(E_s) / (2 * (1 + mp.mpf(nu_s)))

        def rows(z, mu, nu, kinds):
            out = []
            for kind, s in kinds:
                ez = mp.e ** (s * z)
                if kind == "phi":  # 2 mu u = grad phi
                    out.append([ez / (2 * mu), s * ez / (2 * mu), ez, s * ez])
                else:  # 2 mu u = grad(z psi) - 4 (1 - nu) psi e_z
                    out.append([z * ez / (2 * mu), (z * s * ez - (3 - 4 * nu) * ez) / (2 * mu),
                                z * ez - 2 * (1 - nu) * s * ez, z * s * ez - (1 - 2 * nu) * ez])
            return out  # per constant: u_x / i, u_z, sigma_zz, sigma_xz / i

        layer = [("phi", 1), ("phi", -1), ("psi", 1), ("psi", -1)]
        sub = [("phi", -1), ("psi", -1)]
        M, rhs = mp.zeros(6, 6), mp.zeros(6, 1)
        top = rows(mp.mpf(0), mu_l, mp.mpf(nu_l), layer)
        for j in range(4):
            M[0, j], M[1, j] = top[j][2], top[j][3]
        rhs[0] = -1
        lo, so = rows(d, mu_l, mp.mpf(nu_l), layer), rows(d, mu_s, mp.mpf(nu_s), sub)
        for i in range(4):
            for j in range(4):
                M[2 + i, j] = lo[j][i]
            for j in range(2):
                M[2 + i, 4 + j] = -so[j][i]
        x = mp.lu_solve(M, rhs)
        uz = sum(x[j] * top[j][1] for j in range(4))
        return float(2 / uz)  # u = 2 p / (q E_eff) with q = p = 1


@pytest.mark.parametrize("qd, E_l, nu_l, E_s, nu_s", [
    (1.0, 1.0, 0.3, 10.0, 0.2), (0.1, 3e9, 0.35, 210e9, 0.3), (2.0, 200.0, 0.3, 3.0, 0.5),
    (0.01, 1.0, 0.5, 1e4, 0.3), (0.5, 1.0, -0.5, 2.0, 0.45), (5.0, 1e-4, 0.49, 1.0, 0.0),
])
def test_closed_form_solves_the_layered_boundary_value_problem(qd, E_l, nu_l, E_s, nu_s):
    got = float(effective_modulus(qd, 1.0, E_l, nu_l, E_s, nu_s))
    assert got == pytest.approx(bvp_modulus(qd, E_l, nu_l, E_s, nu_s), rel=1e-12)
    # the thickness enters only through q d
    assert float(effective_modulus(qd / 7e-6, 7e-6, E_l, nu_l, E_s, nu_s)) == pytest.approx(got, rel=1e-13)


MATERIALS = [(3e9, 0.35, 210e9, 0.3), (210e9, 0.3, 3e9, 0.35), (1.0, 0.5, 1e4, -0.9), (1e4, 0.0, 1.0, 0.5),
             (1.0, 0.2, 1.0, 0.45)]


@pytest.mark.parametrize("E_l, nu_l, E_s, nu_s", MATERIALS)
def test_thin_layer_is_the_substrate_and_thick_layer_the_layer(E_l, nu_l, E_s, nu_s):
    q = np.array([1e3, 1e6])
    assert np.allclose(effective_modulus(q, 0.0, E_l, nu_l, E_s, nu_s), e_star(E_s, nu_s), rtol=1e-14, atol=0)
    thin = effective_modulus(1e-14 / q, 1.0, E_l, nu_l, E_s, nu_s)  # q d = 1e-14 ... 1e-20
    assert np.allclose(thin, e_star(E_s, nu_s), rtol=1e-10, atol=0)
    for qd in (40.0, 1e3, 1e6):
        assert float(effective_modulus(qd, 1.0, E_l, nu_l, E_s, nu_s)) == pytest.approx(e_star(E_l, nu_l), rel=1e-10)


@pytest.mark.parametrize("E, nu", [(1.0, 0.5), (210e9, 0.3), (5.0, -0.9), (3e6, 0.0)])
def test_equal_layer_and_substrate_is_the_half_space(E, nu):
    qd = np.geomspace(1e-9, 1e6, 61)
    assert np.allclose(effective_modulus(qd, 1.0, E, nu, E, nu), e_star(E, nu), rtol=4e-16, atol=0)
    lam, m, *_ = layer_constants(E, nu, E, nu)
    assert lam == 0.0 and m == 0.0


def thin_slope(E_l, nu_l, E_s, nu_s):
    """k1 of E_eff = E*_s (1 - k1 qd + O(qd^2)): the first-order Taylor coefficient of 1/S."""
    lam, m, oml, omm, omlm = layer_constants(E_l, nu_l, E_s, nu_s)
    return 4 * m * (1 + lam) / omlm - (2 * (lam + m) - 4 * lam * m) / (oml * omm)


@pytest.mark.parametrize("E_l, nu_l, E_s, nu_s", MATERIALS[:4])
def test_thin_layer_asymptote_is_first_order_in_qd(E_l, nu_l, E_s, nu_s):
    """E_eff / E*_s = 1 - k1 qd + O(qd^2): the remainder is below 1e3 (qd)^2 down to qd = 1e-7 (a k1
    off by 1e-4 would leave 1e-11 there, 1e-10 at 1e-6)."""
    k1 = thin_slope(E_l, nu_l, E_s, nu_s)
    if ordered(E_l, nu_l, E_s, nu_s):  # the modulus leaves the substrate's towards the layer's
        assert (k1 > 0) == (e_star(E_l, nu_l) < e_star(E_s, nu_s))
    for t in (1e-5, 1e-6, 1e-7):
        rest = float(effective_modulus(t, 1.0, E_l, nu_l, E_s, nu_s)) / e_star(E_s, nu_s) - (1 - k1 * t)
        assert abs(rest) <= 1e3 * t * t + 1e-15


@pytest.mark.parametrize("E_l, nu_l, E_s, nu_s", MATERIALS[:4])
def test_thick_layer_asymptote(E_l, nu_l, E_s, nu_s):
    """E_eff / E*_l = 1 - (4 m t^2 + 4 m t + lambda + m) e^{-2t} + O(t^4 e^{-4t}), t = qd."""
    lam, m, *_ = layer_constants(E_l, nu_l, E_s, nu_s)
    for t in (8.0, 12.0, 20.0):
        first = (4 * m * t * t + 4 * m * t + lam + m) * np.exp(-2 * t)
        got = float(effective_modulus(t, 1.0, E_l, nu_l, E_s, nu_s)) / e_star(E_l, nu_l)
        assert abs(first) > 1e-16
        assert abs(got - (1 - first)) <= 4 * (t**4 + 1) * np.exp(-4 * t) + 1e-15


def ordered(E_l, nu_l, E_s, nu_s):
    """Whether the layer's shear and bulk moduli are both <= or both >= the substrate's."""
    mu = E_l / (1 + nu_l) - E_s / (1 + nu_s)
    K = E_l / (1 - 2 * nu_l) - E_s / (1 - 2 * nu_s) if max(nu_l, nu_s) < 0.5 else \
        (np.inf if nu_l == 0.5 else 0.0) - (np.inf if nu_s == 0.5 else 0.0)
    return mu * K >= 0 if np.isfinite(K) else mu * np.sign(np.nan_to_num(K)) >= 0


NU = st.floats(-0.999, 0.5)


@settings(max_examples=400, deadline=None)
@given(qd=st.floats(1e-9, 1e6), log_ratio=st.floats(-4, 4), nu_l=NU, nu_s=NU)
def test_modulus_is_finite_positive_and_between_the_two_when_the_solids_are_ordered(qd, log_ratio, nu_l, nu_s):
    """The energy bound: where the layer is softer (or stiffer) in both shear and bulk than the
    substrate, the coated surface is softer than the substrate and stiffer than the layer at every
    q (or the reverse). For any pair E_eff is finite and > 0."""
    E_l, E_s = 10.0**log_ratio, 1.0
    E = float(effective_modulus(qd, 1.0, E_l, nu_l, E_s, nu_s))
    assert np.isfinite(E) and E > 0
    if ordered(E_l, nu_l, E_s, nu_s):
        a, b = e_star(E_l, nu_l), e_star(E_s, nu_s)
        assert min(a, b) * (1 - 1e-12) <= E <= max(a, b) * (1 + 1e-12)


def test_the_bound_fails_for_a_layer_stiffer_in_bulk_but_softer_in_shear():
    """A nearly incompressible layer (nu 0.49) on an auxetic substrate (nu -0.8) of about the same
    E*: the confined layer makes the surface about twice as stiff as either solid near qd ~ 0.6
    (the boundary-value problem agrees)."""
    E_l, nu_l, E_s, nu_s = 1.9, 0.49, 1.0, -0.8
    assert not ordered(E_l, nu_l, E_s, nu_s)
    qd = np.geomspace(1e-3, 10, 400)
    E = effective_modulus(qd, 1.0, E_l, nu_l, E_s, nu_s)
    top = max(e_star(E_l, nu_l), e_star(E_s, nu_s))
    assert E.max() > 1.5 * top
    i = int(np.argmax(E))
    assert float(E[i]) == pytest.approx(bvp_modulus(qd[i], E_l, nu_l, E_s, nu_s), rel=1e-12)


def test_compliance_weight_and_spectrum_follow_the_modulus():
    q = np.geomspace(1e2, 1e9, 50)
    layer = (10e-6, 3e9, 0.35, 210e9, 0.3)
    E = effective_modulus(q, *layer)
    assert np.allclose(surface_compliance(q, *layer), 2.0 / (q * E), rtol=1e-15)
    # equal materials: the half-space compliance 2 (1 - nu^2) / (q E)
    assert np.allclose(surface_compliance(q, 1e-6, 5e9, 0.4, 5e9, 0.4), 2 * (1 - 0.16) / (q * 5e9), rtol=1e-15)
    w = modulus_weight(q, layer)
    assert np.allclose(w, E / e_star(210e9, 0.3), rtol=1e-15)
    assert np.all(np.diff(w) <= 0) and w[0] > 0.9 > 0.02 > w[-1]  # a soft coating: softer at short wavelengths
    C = np.full((2, q.size), 1e-30)
    assert np.allclose(layered_spectrum(q, C, layer), C * w**2, rtol=1e-15)
    assert np.allclose(compliance_factor(q * 10e-6, *layer[1:]), e_star(3e9, 0.35) / E, rtol=1e-15)


@pytest.mark.parametrize("args, match", [
    ((1e-6, 3e9, 0.51, 210e9, 0.3), "layer Poisson ratio"),
    ((1e-6, 3e9, -1.0, 210e9, 0.3), "layer Poisson ratio"),
    ((1e-6, 3e9, 0.3, 210e9, 0.6), "substrate Poisson ratio"),
    ((1e-6, 3e9, 0.3, 210e9, -1.2), "substrate Poisson ratio"),
    ((1e-6, 0.0, 0.3, 210e9, 0.3), "layer Young's modulus"),
    ((1e-6, 3e9, 0.3, -1.0, 0.3), "substrate Young's modulus"),
    ((-1e-6, 3e9, 0.3, 210e9, 0.3), "thickness"),
])
def test_bad_input_is_refused(args, match):
    with pytest.raises(ValueError, match=match):
        effective_modulus(1e5, *args)
