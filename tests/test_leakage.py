"""Tests of the leakage stage, the Reynolds thin-film solver and the exact check on the BEM's gap
(issue 17).

Facts asserted: the leak rate is exactly proportional to dp, 1/mu and W/L; it falls
monotonically with load and is exactly 0 past each theory's sealing pressure, which is
2 sqrt(G) erfinv(a_c); A(zeta_c) = a_c; the volume identity -A' u1 = -(A u_bar)' that defines
u1 holds for the critical gap; u_bar(1) is eq 57's separation; Bruggeman's 2D medium gives
2f - 1 for a two-phase mixture and percolates at 1/2; the Reynolds solver reproduces the closed
forms for a uniform gap and a 1D sinusoidal gap to 1e-6, lies within Wiener's bounds, is
symmetric and cubic in the gap, and finds no flow without a wrapping channel; on the BEM's gap
the exact leak rate falls with load, is 0 for identical surfaces and stops at the sealing load.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make_scene
from reference_solutions import reynolds_sinusoidal_gap
from scipy.special import erf, erfinv

from roughcontact import cli
from roughcontact.physics.apparent_contact import gap_above
from roughcontact.physics.contact import persson_G
from roughcontact.physics.critical_junction import critical_gap, critical_junction
from roughcontact.physics.effective_medium import (
    bruggeman_flow_factor,
    folded_parameters,
    gap_distribution,
    interval_volumes,
)
from roughcontact.physics.leakage import sealing_pressure
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.reynolds import flow_factors, percolates
from roughcontact.physics.separation import mean_separation, separation_nodes
from roughcontact.physics.spectra import self_affine_psd

E_STAR = 77.2e9 / (1 - 0.42**2)
NUMERICS = dict(panels_per_decade=2, order=3, depth=10.0)
SEAL = {"viscosity": "1 mPa*s", "pressure_drop": "0.1 MPa", "seal_width": "10 mm", "seal_length": "1 mm"}


def spectrum(points_per_decade=20):
    q = log_grid(2e8, 4e10, points_per_decade, knots=(8e8,))
    return q, self_affine_psd(q, 0.8, 2e8, 8e8, 4e10, 1e-38)


def leak_scene(**over):
    raw = make_scene(outputs={"variables": ["leak_rate_critical_junction"]}, interface={"eta": [0.0, -1.0]},
                     load={"p": {"from": "100 MPa", "to": "200 GPa", "num": 12}}, leakage=dict(SEAL))
    for k, v in over.items():
        raw[k] = {**raw.get(k, {}), **v}
    return raw


# ----------------------------------------------------------------------------------------
# leakage theories
# ----------------------------------------------------------------------------------------


def test_leak_rate_scales_exactly_with_pressure_drop_viscosity_and_aspect_ratio(run_scene, tmp_path):
    base = run_scene(leak_scene(), tmp_path / "a")["base"]["leakage"]
    other = run_scene(leak_scene(leakage={"pressure_drop": "0.35 MPa", "viscosity": "2.5 mPa*s",
                                          "seal_width": "3 mm", "seal_length": "4 mm"}),
                      tmp_path / "b")["base"]["leakage"]
    factor = 3.5 / 2.5 * (3.0 / 4.0) / (10.0 / 1.0)
    for method in ("critical_junction", "effective_medium"):
        a, b = base[f"leak_rate_{method}"].values, other[f"leak_rate_{method}"].values
        assert np.any(a > 0)
        np.testing.assert_allclose(b, factor * a, rtol=1e-13, atol=0)
        np.testing.assert_array_equal(base[f"flow_factor_{method}"], other[f"flow_factor_{method}"])


def test_leak_rate_falls_with_load_and_vanishes_past_the_sealing_pressure(run_scene):
    res = run_scene(leak_scene())["base"]["leakage"]
    for eta in res["eta"].values:
        d = res.sel(eta=eta)
        p = d["p"].values
        for method in ("critical_junction", "effective_medium"):
            Q = d[f"leak_rate_{method}"].values
            seal = float(d[f"sealing_pressure_{method}"])
            assert np.all(Q[p >= seal] == 0) and np.all(Q[p < seal] > 0)
            assert np.any(p >= seal) and np.any(p < seal)
            assert np.all(np.diff(Q[p < seal]) < 0)
        assert np.all(np.isnan(d["critical_magnification"].values[p >= float(d["sealing_pressure_critical_junction"])]))
        ratio = float(d["sealing_pressure_effective_medium"] / d["sealing_pressure_critical_junction"])
        assert ratio == pytest.approx(erfinv(0.5) / erfinv(0.42), rel=1e-12)
    assert "nan_reason" in res["critical_magnification"].attrs


def test_sealing_pressure_and_critical_magnification_are_the_closed_forms():
    q, C = spectrum()
    p = E_STAR * np.array([1e-3, 1e-2, 0.1])
    zeta_c, u1 = critical_junction(q, C, p, E_star=E_STAR, alpha=0.45, numerics=NUMERICS, area=0.42)
    G = persson_G(q, C, zeta_c * q[0], E_STAR)
    np.testing.assert_allclose(erf(p / (2 * np.sqrt(G))), 0.42, rtol=1e-10)
    G1 = persson_G(q, C, q[-1:], E_STAR)[0]
    assert sealing_pressure(q, C, E_STAR, 0.42) == pytest.approx(2 * np.sqrt(G1) * erfinv(0.42), rel=1e-14)
    assert np.all(u1 > 0)


def test_gap_above_one_is_eq57_and_vanishes_at_the_top():
    q, C = spectrum()
    p = E_STAR * np.logspace(-6, -1, 6)
    nodes = separation_nodes(q, C, q[-1:], **NUMERICS)
    u = mean_separation(p, *(nodes[i] for i in (0, 1, 2, 4, 5)), E_star=E_STAR, alpha=0.45)[:, 0]
    np.testing.assert_allclose(gap_above(q, C, 1.0, p, E_star=E_STAR, alpha=0.45, numerics=NUMERICS), u, rtol=1e-13)
    assert np.all(gap_above(q, C, q[-1] / q[0], p, E_star=E_STAR, alpha=0.45, numerics=NUMERICS) == 0)


def test_critical_gap_obeys_the_volume_identity():
    """-A'(zeta) u1(zeta) = -(A u_bar)'(zeta): integrated over all magnifications, u1 weighted by
    the area that opens returns the mean separation u_bar(1) (to the quadrature's accuracy)."""
    q, C = spectrum(40)
    p = np.array([0.02 * E_STAR])
    zeta = 1.0 + np.geomspace(1e-4, q[-1] / q[0] * 0.999 - 1.0, 160)
    kw = dict(E_star=E_STAR, alpha=0.45, numerics=NUMERICS)
    u1 = np.array([critical_gap(q, C, z, p, **kw)[0] for z in zeta])
    area = erf(p[0] / (2 * np.sqrt(persson_G(q, C, zeta * q[0], E_STAR))))
    lhs = np.sum(-np.diff(area) * 0.5 * (u1[1:] + u1[:-1]))
    u_bar = gap_above(q, C, zeta[0], p, **kw)[0] * area[0] - gap_above(q, C, zeta[-1], p, **kw)[0] * area[-1]
    assert lhs == pytest.approx(u_bar, rel=2e-3)
    u_mid = np.array([gap_above(q, C, z, p, **kw)[0] for z in zeta[::20]])
    assert np.all(u1[::20] >= u_mid)  # u_bar falls and A falls with zeta: the constriction is wider than the mean


def test_gap_distribution_is_normalised_and_its_mean_is_the_mean_separation():
    """The mean of P(u) (contact at u = 0 included) is eq 57's u_bar(1) to 1e-3 (issue 24: the
    reflected Gaussians centred on u1 had 1.3-6 times u_bar), for Persson's A(zeta) and a corrected one,
    from small load to near the effective medium's threshold."""
    q, C = spectrum()
    p = E_STAR * np.array([1e-4, 1e-2, 0.1, 0.16])
    u_bar = gap_above(q, C, 1.0, p, E_star=E_STAR, alpha=0.45, numerics=NUMERICS)
    for correction, gamma in (("persson", None), ("wang_mueser", 5 / 9)):
        u, weight, top = gap_distribution(q, C, p, E_star=E_STAR, alpha=0.45, numerics=NUMERICS, correction=correction,
                                          gamma=gamma)
        np.testing.assert_allclose(weight.sum(0) + top, 1.0, rtol=1e-12)
        np.testing.assert_allclose((u * weight).sum(0), u_bar, rtol=1e-3)
        assert np.all(u >= 0)


def test_interval_volumes_keep_the_volume_where_no_area_opens():
    """Where A/A0 = 1 to double precision the volume A u_bar still falls; it is carried to the next
    interval that opens area, so the centres average to u_bar(1) exactly (they did to 0.94-0.997)."""
    areas = np.array([[1.0], [1.0], [1.0], [0.9], [0.5], [0.5], [0.2]])
    opened = 1.0 - areas
    ubar = np.array([[5.0], [4.0], [3.5], [3.0], [1.0], [0.9], [0.0]])
    drop, volume = interval_volumes(areas, ubar, opened)
    assert np.all(volume[drop == 0] == 0)
    assert volume.sum() == pytest.approx(5.0, rel=1e-15)
    assert volume[2, 0] == pytest.approx(5.0 - 0.9 * 3.0, rel=1e-15)  # the first interval that opens area


@pytest.mark.parametrize("mean, width", [(1.0, 0.1), (1.0, 1.0), (1.0, 1.25), (0.3, 1.0), (1e3, 1e-3), (0.0, 1.0)])
def test_folded_normal_has_the_asked_mean_and_the_published_width_where_it_fits(mean, width):
    mu, s = folded_parameters(np.array([mean]), np.array([width]))
    x = np.linspace(max(0.0, mu[0] - 12 * s[0]), mu[0] + 12 * s[0], 200001)
    density = (np.exp(-0.5 * ((x - mu) / s) ** 2) + np.exp(-0.5 * ((x + mu) / s) ** 2)) / (s * np.sqrt(2 * np.pi)) \
        if s[0] > 0 else None
    if density is None:
        assert mean == 0 and mu[0] == 0
        return
    assert np.trapezoid(x * density, x) == pytest.approx(mean, rel=1e-6)
    assert s[0] == (width if mean >= width * np.sqrt(2 / np.pi) else pytest.approx(mean * np.sqrt(np.pi / 2)))


@pytest.mark.parametrize("f", [0.3, 0.5, 0.6, 0.75, 0.9, 1.0])
def test_bruggeman_two_phase_mixture_is_2f_minus_1(f):
    """A fraction f of gap 1 (conductivity 1) in contact (conductivity 0): sigma = 2f - 1 above
    the 2D Bruggeman threshold f = 1/2, 0 below (Kirkpatrick 1973)."""
    u = np.array([[1.0]])
    weight = np.array([[f]])
    sigma = bruggeman_flow_factor(u, weight, np.array([1.0 - f]))[0]
    assert sigma == pytest.approx(max(2 * f - 1, 0.0), abs=1e-10)


# ----------------------------------------------------------------------------------------
# the Reynolds solver
# ----------------------------------------------------------------------------------------


def test_reynolds_uniform_gap_is_g_cubed():
    np.testing.assert_allclose(flow_factors(np.full((24, 40), 3e-9)), 27e-27, rtol=1e-13)


@pytest.mark.parametrize("n", [32, 64])
def test_reynolds_sinusoidal_gap_matches_the_closed_forms(n):
    """g = g0 + g1 cos(2 pi x / L): along the flow sigma = 1/<g^-3> = 2 (g0^2 - g1^2)^(5/2) /
    (2 g0^2 + g1^2), across it <g^3> = g0^3 + 3 g0 g1^2 / 2."""
    g0, g1 = 2e-9, 1.3e-9
    x = np.arange(n) / n
    g = np.repeat((g0 + g1 * np.cos(2 * np.pi * x))[:, None], 12, axis=1)
    along, across = flow_factors(g)
    exact_along, exact_across = reynolds_sinusoidal_gap(g0, g1)
    assert along == pytest.approx(exact_along, rel=1e-6)
    assert across == pytest.approx(exact_across, rel=1e-6)
    np.testing.assert_allclose(flow_factors(g.T)[::-1], (along, across), rtol=1e-12)


def random_gap(n=48, level=-0.5, seed=3):
    rng = np.random.default_rng(seed)
    k = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n), indexing="ij"))
    k[0, 0] = 1.0
    h = np.real(np.fft.ifft2(np.fft.fft2(rng.normal(size=(n, n))) * k**-1.6))
    return np.maximum(h / h.std() - level, 0.0) * 1e-9


def test_reynolds_lies_within_wiener_bounds_and_is_cubic_and_symmetric():
    g = random_gap(level=-6.0)  # all open: the harmonic and arithmetic means of g^3 bound sigma
    assert np.all(g > 0)
    sigma = flow_factors(g)
    assert np.all(sigma > 1 / np.mean(g**-3.0)) and np.all(sigma < np.mean(g**3))
    np.testing.assert_allclose(flow_factors(2.5 * g), 2.5**3 * sigma, rtol=1e-10)
    np.testing.assert_allclose(flow_factors(g.T)[::-1], sigma, rtol=1e-10)


def test_reynolds_no_flow_without_a_wrapping_channel():
    g = np.zeros((10, 12))
    g[2, 2:7] = g[6, 2:7] = g[2:7, 2] = g[2:7, 6] = 1e-9  # a ring: flow can circle, not cross
    assert not percolates(g > 0, 0) and not percolates(g > 0, 1)
    np.testing.assert_array_equal(flow_factors(g), 0.0)
    g[:, 4] = 1e-9  # a channel along axis 0 only
    assert percolates(g > 0, 0) and not percolates(g > 0, 1)
    along, across = flow_factors(g)
    assert along > 0 and across == 0


# ----------------------------------------------------------------------------------------
# bad input
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("key, value, message", [
    ("viscosity", "0 Pa*s", "must be > 0"),
    ("viscosity", "-1 mPa*s", "must be > 0"),
    ("seal_width", "0 mm", "must be > 0"),
    ("seal_length", "-2 mm", "must be > 0"),
    ("pressure_drop", "0.1", "has no units"),
    ("pressure_drop", 1000, "has no units"),
    ("percolation_area", 1.2, "must be < 1"),
])
def test_bad_leakage_input_is_a_one_line_error_naming_the_key(write_scene, capsys, tmp_path, key, value, message):
    raw = leak_scene(leakage={key: value})
    code = cli.main(["run", str(write_scene(raw)), "--outdir", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and f"leakage.{key}" in err and message in err and len(err.splitlines()) == 1, err


def test_effective_medium_converges_with_the_gap_bins_and_magnifications():
    """Away from its threshold (up to 0.6 of its sealing pressure), Bruggeman's sigma at the default
    resolution (20 magnifications and 20 gap bins per decade) is within 1 % of a four times finer one."""
    q, C = spectrum()
    p = E_STAR * np.array([1e-3, 1e-2, 0.1])
    kw = dict(E_star=E_STAR, alpha=0.45, numerics=NUMERICS)
    coarse = bruggeman_flow_factor(*gap_distribution(q, C, p, **kw))
    fine = bruggeman_flow_factor(*gap_distribution(q, C, p, bins_per_decade=80, points_per_decade=80, **kw))
    assert np.all(coarse > 0)
    np.testing.assert_allclose(coarse, fine, rtol=1e-2)
