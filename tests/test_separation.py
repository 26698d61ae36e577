"""Tests of the separation stage (mean interfacial separation, seed eqs 21-28 and 54-60).

Each test checks a physical or mathematical fact: the small-pressure law, monotonicity and
limits, the exact scaling C -> lambda^2 C, the ordering of the two-surface cases, agreement
with an independent brute-force double integral, and the convergence order of the numerics.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from reference_solutions import brute_force_u, self_affine_q3C_integral
from scipy.integrate import quad
from scipy.special import erf

import roughcontact as rc
from roughcontact import cli
from roughcontact.physics.quadrature import gauss_legendre_panels, integral_to, inverse_cumulative_integral, log_grid
from roughcontact.physics.separation import (
    EPSILON,
    mean_separation,
    separation_moments,
    separation_nodes,
    small_pressure_law,
    yang_persson_J,
)
from roughcontact.physics.spectra import psd_combined, self_affine_hrms_factor, self_affine_psd

H, QL, Q1 = 0.8, 2e8, 4e10
E_STAR = 77.2e9 / (1 - 0.42**2)
ALPHA = 0.45


# ----------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------


def seed_scene(p, zeta=(4.0, 200.0), ppd=20, separation=None, numerics=None, eta=(0.0, 1.0, -1.0)):
    """Seed section 4.2 surfaces (equal H and hrms), with a substrate-only variant."""
    surface = {"kind": "self_affine", "H": H, "qL": "2e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}
    p = [f"{float(v)!r} Pa" for v in np.atleast_1d(p)]
    return {
        "substrate": surface, "solid": surface, "interface": {"eta": list(eta)},
        "material": {"E": "77.2 GPa", "nu": 0.42}, "load": {"p": p if len(p) > 1 else p[0]},
        "contact": {"zeta": list(zeta)}, "separation": separation or {},
        "outputs": {"variables": ["mean_separation"]},
        "numerics": {"points_per_decade": ppd, **(numerics or {})},
        "variants": {"substrate_only": {"solid": {"kind": "smooth"}}},
    }


def run_in_memory(raw):
    """{variant: separation Dataset} computed without touching the disk."""
    return {variant: by_stage["separation"] for variant, by_stage in rc.compute(raw, progress=False).items()}


def kernel_u(q, C, q_upper, p, alpha=ALPHA, refinement="none", panels=4, order=4, depth=10.0):
    s, w, count, _, s_tail, q_tail = separation_nodes(q, C, q_upper, panels, order, depth)
    return mean_separation(p, s, w, count, s_tail, q_tail, E_star=E_STAR, alpha=alpha, refinement=refinement)


def kernel_law(q, C, q_upper, alpha=ALPHA, refinement="none"):
    s, w, count, _, s_tail, q_tail = separation_nodes(q, C, q_upper)
    return small_pressure_law(*separation_moments(s, w, count, s_tail, q_tail), alpha=alpha, refinement=refinement)


def seed_psd(ppd=20, hrms=1e-9):
    q = log_grid(QL, Q1, ppd)
    return q, self_affine_psd(q, H, QL, QL, Q1, hrms**2 / self_affine_hrms_factor(H, QL, QL, Q1))


def smooth_psd(ppd):
    """Self-affine with a Gaussian cut-off: not a power law, so the q grid matters."""
    q = log_grid(QL, 100 * QL, ppd)
    C0 = 1e-18 / self_affine_hrms_factor(H, QL, QL, Q1)
    return q, self_affine_psd(q, H, QL, QL, Q1, C0) * np.exp(-((q / (20 * QL)) ** 2))


# ----------------------------------------------------------------------------------------
# small-pressure law (eqs 58-60)
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("refinement", ["none", "yang_persson", "wang_mueser"])
def test_small_pressure_asymptote(refinement):
    """u(p) -> u0 ln(beta E*/p) as p -> 0: within 1e-4 relative at p/E* = 1e-7 (every case)."""
    p = 1e-7 * E_STAR
    res = run_in_memory(seed_scene(p, separation={"refinement": refinement}))
    for variant, eta in (("base", 0.0), ("base", -1.0), ("substrate_only", None)):
        ds = res[variant] if eta is None else res[variant].sel(eta=eta)
        u = ds["mean_separation"].values.ravel()
        law = (ds["separation_u0"] * np.log(ds["separation_beta"] * E_STAR / p)).values.ravel()
        np.testing.assert_allclose(u, law, rtol=1e-4)
        assert np.all(ds["separation_beta"].values < 1.0) and np.all(ds["separation_u0"].values > 0)


def test_asymptote_is_a_lower_bound_and_slope_is_bounded():
    """E1(x) >= -gamma - ln x gives u(p) >= u0 ln(beta E*/p) at every p; du/dln p =
    -sqrt(pi) alpha int q^2 C w exp(-(wp/E*)^2) dq lies in [-u0, 0] and -> -u0 as p -> 0."""
    q, C = seed_psd()
    p = np.geomspace(1e-12, 1e-1, 300) * E_STAR
    u = kernel_u(q, C, np.array([4 * QL, Q1]), p)  # (p, zeta)
    u0, beta = kernel_law(q, C, np.array([4 * QL, Q1]))
    assert np.all(u >= u0 * np.log(beta * E_STAR / p[:, None]) * (1 - 1e-10))
    slope = np.diff(u, axis=0) / np.diff(np.log(p))[:, None]
    assert np.all(slope < 0) and np.all(slope > -u0 * (1 + 1e-8))
    np.testing.assert_allclose(slope[0], -u0, rtol=1e-6)


def test_beta_sign_of_eq_60():
    """beta = eps exp(-<ln w>) (minus sign restored): check against an independent quad."""
    q, C = seed_psd()
    _, beta = kernel_law(q, C, np.array([4 * QL]))
    C0 = C[0]

    def w(t):  # w at q = qL + t^2 (analytic running integral of the power law)
        return (math.pi * self_affine_q3C_integral(t * t, C0, H, QL)) ** -0.5

    def weight(t):  # q = qL + t^2 removes the 1/sqrt singularity
        qq = QL + t * t
        return 2 * t * qq**2 * C0 * (qq / QL) ** (-2 - 2 * H) * w(t) if t > 0 else 0.0

    edges = [0.0, *math.sqrt(3 * QL) * np.geomspace(1e-12, 1.0, 25)]  # ln w is log-singular at t = 0
    spans = list(zip(edges, edges[1:], strict=False))
    num = sum(quad(lambda t: weight(t) * math.log(w(t)), a, b, epsabs=0, epsrel=1e-13)[0] for a, b in spans)
    den = sum(quad(weight, a, b, epsabs=0, epsrel=1e-13)[0] for a, b in spans)
    assert EPSILON == pytest.approx(0.749306, abs=1e-6)
    assert beta[0] == pytest.approx(EPSILON * math.exp(-num / den), rel=1e-7)


# ----------------------------------------------------------------------------------------
# monotonicity, limits, scaling, ordering
# ----------------------------------------------------------------------------------------


def test_positive_strictly_decreasing_and_vanishing():
    p = np.geomspace(1e-10, 3.0, 200) * E_STAR
    res = run_in_memory(seed_scene(p, eta=(0.0, -1.0)))
    for ds in (res["base"], res["substrate_only"]):
        u = ds["mean_separation"].transpose(..., "p").values.reshape(-1, p.size)
        assert np.all(u > 0)
        assert np.all(np.diff(u, axis=-1) < 0)
    # large p: u -> 0 (full contact) like exp(-(p/(E* s_max))^2); at p = 30 E* it underflows to 0
    big = run_in_memory(seed_scene([1.0 * E_STAR, 3.0 * E_STAR, 30.0 * E_STAR], eta=(0.0,)))["base"]
    u = big["mean_separation"].sel(zeta=4.0).values.ravel()
    small = res["base"]["mean_separation"].sel(zeta=4.0, eta=0.0).values[0]
    assert u[0] < 1e-4 * small and u[1] < 1e-30 * small and u[2] == 0.0


@pytest.mark.parametrize("lam", [0.1, 3.0])
def test_scaling_of_the_psd(lam):
    """C -> lambda^2 C gives u(p) -> lambda u(p / lambda) (w -> w/lambda)."""
    q, C = seed_psd()
    p = np.geomspace(1e-9, 1e-1, 40) * E_STAR
    zu = np.array([4 * QL, 20 * QL, Q1])
    scaled = kernel_u(q, lam**2 * C, zu, p)
    np.testing.assert_allclose(scaled, lam * kernel_u(q, C, zu, p / lam), rtol=1e-10)


def test_ordering_of_the_two_surface_cases():
    """Equal hrms and shapes: u(eta=-1) > u(eta=0) > u(substrate only) > u(eta=+1) = 0 at every p."""
    p = np.geomspace(1e-10, 0.5, 60) * E_STAR
    res = run_in_memory(seed_scene(p))
    base = res["base"]["mean_separation"]
    only = res["substrate_only"]["mean_separation"]
    anti, unc, same = (base.sel(eta=e).values for e in (-1.0, 0.0, 1.0))
    assert np.all(anti > unc) and np.all(unc > only.values) and np.all(only.values > 0)
    assert np.all(same == 0.0)


def test_identical_surfaces_give_zero_separation_and_nan_beta():
    res = run_in_memory(seed_scene([1e3, 1e6, 1e9], eta=(1.0,)))["base"]
    assert np.all(res["mean_separation"].values == 0.0)
    assert np.all(res["separation_u0"].values == 0.0)
    assert np.all(np.isnan(res["separation_beta"].values))
    assert "identically zero" in res["separation_beta"].attrs["nan_reason"]


# ----------------------------------------------------------------------------------------
# independent brute-force double integral of eq 57
# ----------------------------------------------------------------------------------------


# brute_force_u: tests/reference_solutions.py


@pytest.mark.parametrize("p_rel,zeta", [(1e-9, 4.0), (1e-6, 4.0), (1e-3, 4.0), (3e-2, 20.0)])
def test_agrees_with_brute_force_double_integral(p_rel, zeta):
    q, C = seed_psd()
    u = kernel_u(q, C, np.array([zeta * QL]), p_rel * E_STAR)
    assert u[0] == pytest.approx(brute_force_u(p_rel * E_STAR, zeta, C[0]), rel=1e-6, abs=0)


def test_yang_persson_agrees_with_brute_force():
    q, C = seed_psd()
    for p_rel in (1e-6, 1e-2):
        u = kernel_u(q, C, np.array([4 * QL]), p_rel * E_STAR, refinement="yang_persson")
        assert u[0] == pytest.approx(brute_force_u(p_rel * E_STAR, 4.0, C[0], yang_persson=True), rel=1e-6, abs=0)


def test_wang_mueser_energy_factor_agrees_with_brute_force():
    """S = a - (2/9) P^2 + (11/9 - a) P^4 in the energy: d(P S)/dP = a - (2/3) P^2 + 5 (11/9 - a) P^4
    inside the p' integral, done by quad."""
    q, C = seed_psd()
    a = 5 / 9
    for p_rel in (1e-6, 1e-2):
        u = kernel_u(q, C, np.array([4 * QL]), p_rel * E_STAR, alpha=a, refinement="wang_mueser")
        ref = brute_force_u(p_rel * E_STAR, 4.0, C[0], factor=lambda P: a - 2 / 3 * P**2 + 5 * (11 / 9 - a) * P**4)
        assert u[0] == pytest.approx(ref, rel=1e-6, abs=0)


def test_yang_persson_function_and_limits():
    """J(0) = int_0^inf erf^2 exp(-x^2)/x dx; alpha = 1 makes the refinement vanish; with
    alpha < 1 the refined u is larger (the extra weight 3(1-alpha)P^2 is positive)."""
    ref = quad(lambda x: erf(x) ** 2 * math.exp(-x * x) / x, 0, math.inf, epsabs=0, epsrel=1e-13, limit=200)[0]
    assert float(yang_persson_J(0.0)) == pytest.approx(ref, rel=1e-12)
    x0 = np.array([1e-4, 0.3, 1.0, 2.5, 5.0])
    ref = [quad(lambda x: erf(x) ** 2 * math.exp(-x * x) / x, v, math.inf, epsabs=0, epsrel=1e-13)[0] for v in x0]
    np.testing.assert_allclose(yang_persson_J(x0), ref, rtol=1e-10)
    q, C = seed_psd()
    p = np.geomspace(1e-9, 1e-1, 20) * E_STAR
    zu = np.array([4 * QL, Q1])
    np.testing.assert_allclose(kernel_u(q, C, zu, p, alpha=1.0, refinement="yang_persson"),
                               kernel_u(q, C, zu, p, alpha=1.0), rtol=1e-14)
    assert np.all(kernel_u(q, C, zu, p, refinement="yang_persson") > kernel_u(q, C, zu, p))


# ----------------------------------------------------------------------------------------
# numerics: convergence and the default resolution
# ----------------------------------------------------------------------------------------


def test_q_grid_convergence_is_second_order():
    """For a PSD that is not a power law the q grid's power-law interpolation of q^3 C is the
    error: it falls as (ln-spacing)^2 (observed order 2 +- 0.25)."""
    p = np.geomspace(1e-9, 1e-2, 15) * E_STAR
    zu = np.array([2 * QL, 100 * QL])
    ref = kernel_u(*smooth_psd(800), zu, p, panels=8, order=8)
    errors = [np.max(np.abs(kernel_u(*smooth_psd(n), zu, p) / ref - 1)) for n in (12, 25, 50, 100)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.25), (errors, orders)
    assert errors[2] < 1e-4  # the default 50 points per decade


def test_s_quadrature_converges_fast_and_default_within_1e_4():
    """On a power-law PSD the q grid is exact; the Gauss-Legendre panels in s converge
    geometrically with the number of nodes; the default is within 1e-4 of a converged run."""
    q, C = seed_psd(50)
    p = np.geomspace(1e-10, 1e-2, 25) * E_STAR
    zu = np.array([4 * QL, Q1])
    ref = kernel_u(q, C, zu, p, panels=12, order=10, depth=14.0)
    errors = [np.max(np.abs(kernel_u(q, C, zu, p, panels=2, order=n) / ref - 1)) for n in (1, 2, 3, 4)]
    assert all(b < a / 5 for a, b in zip(errors, errors[1:], strict=False)) and errors[-1] < 1e-6, errors
    assert np.max(np.abs(kernel_u(q, C, zu, p) / ref - 1)) < 1e-4
    coarse_q = kernel_u(*seed_psd(10), zu, p)  # piecewise power law: the q grid is exact
    np.testing.assert_allclose(coarse_q, ref, rtol=1e-7)


def test_zeta_all_matches_listed_magnifications():
    """zeta = 'all' (every q node) agrees with the same magnifications listed, and with
    magnifications between nodes the integral is cut inside a q segment consistently."""
    p = [1e4, 1e7]
    raw = seed_scene(p, eta=(0.0,))
    raw["contact"]["zeta"] = "all"
    every = run_in_memory(raw)["base"]["mean_separation"]
    nodes = log_grid(QL, Q1, 20) / QL
    assert every.sizes["zeta"] == nodes.size
    picks = [float(nodes[0]), float(nodes[10]), float(nodes[-1])]
    listed = run_in_memory(seed_scene(p, zeta=picks + [4.0], eta=(0.0,)))["base"]["mean_separation"]
    for z in picks:
        np.testing.assert_allclose(every.sel(zeta=z).values, listed.sel(zeta=z).values, rtol=1e-10)
    assert np.all(listed.sel(zeta=1.0).values == 0.0)  # no q range: no separation
    below, above = (every.sel(zeta=float(nodes[nodes < 4][-1])), every.sel(zeta=float(nodes[nodes > 4][0])))
    assert np.all(below.values < listed.sel(zeta=4.0).values) and np.all(listed.sel(zeta=4.0).values < above.values)


def test_dask_chunks_give_the_same_result_and_units(run_scene, tmp_path):
    # through the engine: it stamps the declared units and long names on what the stage returns
    p = list(np.geomspace(1e3, 1e9, 12))
    plain = {v: res["separation"] for v, res in run_scene(seed_scene(p), outdir=tmp_path / "plain").items()}
    raw = seed_scene(p)
    raw["numerics"]["chunks"] = {"p": 5, "eta": 1}
    chunked = {v: res["separation"] for v, res in run_scene(raw, outdir=tmp_path / "chunked").items()}
    for v in ("base", "substrate_only"):
        np.testing.assert_allclose(chunked[v]["mean_separation"].values, plain[v]["mean_separation"].values, rtol=1e-14)
        for name in plain[v].variables:
            assert {"units", "long_name"} <= set(plain[v][name].attrs), name
    assert plain["base"]["mean_separation"].attrs["alpha"] == ALPHA
    assert plain["base"]["separation_beta"].attrs["epsilon"] == pytest.approx(math.exp(-np.euler_gamma / 2))


# ----------------------------------------------------------------------------------------
# quadrature primitives added for this stage
# ----------------------------------------------------------------------------------------


def test_inverse_cumulative_integral_round_trip():
    x = log_grid(1.0, 1e3, 7)
    y = np.stack([x**-0.6, np.where(x < 10, 0.0, x**-2.0), x**-1.0, np.zeros_like(x)])
    total = integral_to(x, y, np.array([x[-1]]))
    levels = total * np.linspace(0, 1, 9)
    xs = inverse_cumulative_integral(x, y, levels)
    for row in range(3):
        np.testing.assert_allclose(integral_to(x, y[row], xs[row]), levels[row], rtol=1e-12, atol=1e-15 * total[row, 0])
    assert xs[1, 0] == x[x < 10][-1]  # a flat stretch maps to its end
    assert np.all(xs[3] == x[-1])


def test_gauss_legendre_panels_exact_for_polynomials():
    nodes, weights = gauss_legendre_panels(np.array([[0.0, 0.5, 0.5, 2.0]]), 3)
    assert (weights * nodes**5).sum() == pytest.approx(2.0**6 / 6, rel=1e-14)


# ----------------------------------------------------------------------------------------
# extremes (hypothesis) and bad input
# ----------------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    log_p=st.lists(st.floats(-16.0, 3.0), min_size=2, max_size=6, unique=True),
    eta=st.floats(-1.0, 1.0),
    hurst=st.floats(0.05, 1.0),
    ratio=st.floats(0.0, 4.0),
    zeta=st.floats(1.0, 200.0),
    refinement=st.sampled_from(["none", "yang_persson"]),
)
def test_extreme_pressures_are_finite_bounded_and_monotone(log_p, eta, hurst, ratio, zeta, refinement):
    q = log_grid(QL, Q1, 8)
    C1 = self_affine_psd(q, hurst, QL, QL, Q1, 1e-18 / self_affine_hrms_factor(hurst, QL, QL, Q1))
    C = psd_combined(C1, ratio**2 * C1, eta)
    p = np.sort(10.0 ** np.array(log_p)) * E_STAR
    zu = np.array([zeta * QL, Q1])
    u = kernel_u(q, C, zu, p, refinement=refinement)
    u0, beta = kernel_law(q, C, zu, refinement=refinement)
    assert np.all(np.isfinite(u)) and np.all(u >= 0)
    assert np.all(np.diff(u, axis=0) <= 0)  # non-increasing in p (strictly where representable)
    assert np.all(u[:, 0] <= u[:, 1] * (1 + 1e-12))  # more roughness up to a larger zeta: more separation
    rough = u0 > 0
    assert np.all(np.isnan(beta) == ~rough)
    if refinement == "none":
        law = u0 * np.log(np.where(rough, beta, 1.0) * E_STAR / p[:, None])
        assert np.all(u >= np.where(rough, law, 0.0) - 1e-9 * np.abs(law))  # exact lower bound (E1 >= -gamma - ln x)
        # E1(x) <= ln(1 + 1/x): u <= (alpha/sqrt(pi)) int ln(1 + (E* s/p)^2) ds/q <= u0 ln(1 + (E* s_max/p)^2)/2
        s_max = np.sqrt(np.pi * integral_to(q, q**3 * C, zu))
        assert np.all(u <= 0.5 * u0 * np.log1p((E_STAR * s_max / p[:, None]) ** 2) * (1 + 1e-9) + 1e-300)


def _write_scene(tmp_path, **overrides):
    raw = seed_scene([1e6, 1e7], eta=(0.0,), ppd=10)
    raw.pop("variants")
    for key, value in overrides.items():
        section, name = key.split(".")
        raw[section][name] = value

    def toml(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, list):
            return "[" + ", ".join(toml(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{k} = {toml(x)}" for k, x in v.items()) + "}"
        return repr(v)

    text = "\n".join(f"[{s}]\n" + "\n".join(f"{k} = {toml(v)}" for k, v in body.items()) for s, body in raw.items())
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("key,value", [
    ("separation.alpha", 0.0), ("separation.alpha", 1.5), ("separation.alpha", -0.2),
    ("separation.refinement", "yang-persson"), ("load.p", ["1 MPa", "-2 MPa"]), ("load.p", "0 Pa"),
])
def test_bad_input_names_the_key_and_exits_2(tmp_path, capsys, key, value):
    path = _write_scene(tmp_path, **{key: value})
    code = cli.main(["run", str(path), "--outdir", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert key in err and "error" in err
    assert not (tmp_path / "out").exists()


def test_good_scene_runs_through_the_cli(tmp_path):
    path = _write_scene(tmp_path)
    assert cli.main(["run", str(path), "--outdir", str(tmp_path / "out"), "--quiet"]) == 0
    assert (tmp_path / "out" / "separation.nc").is_file()


@pytest.mark.parametrize("chunk", [1, 700, 65_536])
def test_the_kernel_working_row_by_row_changes_no_value(monkeypatch, chunk):
    """mean_separation works through its leading axes (spectra, pressures) a few rows at a time
    (physics.separation.CHUNK, to keep its temporaries in cache): on leading shapes of every kind (a
    scalar pressure; pressures x spectra with their own nodes; pressures broadcast against shared
    nodes), with each refinement, every value is bit for bit what one pass of the formula over the
    whole arrays gives."""
    from roughcontact.physics import separation as physics_separation

    q = log_grid(QL, Q1, 20)
    C0 = 1e-18 / self_affine_hrms_factor(H, QL, QL, Q1)  # hrms 1 nm
    spectra = np.stack([self_affine_psd(q, H, QL, QL, Q1, C0) * f for f in (0.5, 1.0, 2.0)])  # 3 spectra
    upper = QL * np.array([4.0, 200.0])
    nodes = [separation_nodes(q, C, upper, 4, 4, 10.0) for C in spectra]
    s, w, count, _, s_tail, q_tail = (np.stack([n[i] for n in nodes]) for i in range(6))
    p = np.geomspace(1e3, 1e8, 7)

    cases = [(refinement, args) for refinement in ("none", "yang_persson", "wang_mueser")
             for args in ((np.float64(1e6), s[0], w[0], count[0], s_tail[0], q_tail[0]),
                          (p[:, None], s, w, count, s_tail, q_tail),
                          (p, s[1], w[1], count[1], s_tail[1], q_tail[1]))]
    monkeypatch.setattr(physics_separation, "CHUNK", chunk)
    for refinement, (pressure, *nodes) in cases:
        got = mean_separation(pressure, *nodes, E_star=E_STAR, alpha=ALPHA, refinement=refinement)
        terms = {k: c for k, c in physics_separation.energy_factor_terms(refinement, ALPHA).items() if k}
        whole = physics_separation._mean_separation_rows(np.asarray(pressure)[..., None] / E_STAR, *nodes, ALPHA, terms)
        assert got.shape == whole.shape
        np.testing.assert_array_equal(got, whole)
