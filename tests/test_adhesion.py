"""Tests of the adhesion stage (docs/theory.md, section "Adhesion"; seed eqs 5-14, 42, 50; Figs 1-2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from scipy.integrate import quad
from scipy.special import erf

from roughcontact import engine, scene as scenes
from roughcontact.errors import ComputationError, UserError
from roughcontact.physics.adhesion import (
    AdhesionProblem,
    adhesion_length,
    gamma_eff_full_contact,
    layer_resolving_offset,
    surface_area_factor,
    zeta_grid,
)
from roughcontact.physics.contact import effective_modulus
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.spectra import psd_combined, self_affine_hrms_factor, self_affine_psd
from roughcontact.physics.volterra import detachment_volterra, solve_partial_contact, vanishing_scale

E_STAR = effective_modulus(77.2e9, 0.42)
DG = 1.602176634  # 100 meV/angstrom^2 in J/m^2
Q0, Q1, H = 7e6, 1.4e9, 0.8
Q = log_grid(Q0, Q1, 20)
SHAPE = self_affine_psd(Q, H, Q0, Q0, Q1, 1.0) / self_affine_hrms_factor(H, Q0, Q0, Q1)  # C per unit hrms^2
ANG = 1e-10


def _solve(hs, ppd=6, sigma0=0.0, c0=1.0, c1=0.0):
    hs = np.atleast_1d(hs)
    prob = AdhesionProblem(Q, hs[:, None] ** 2 * SHAPE, E_STAR, DG, zeta_grid(Q1 / Q0, ppd, 1e-10))
    n = hs.size
    return prob, solve_partial_contact(prob, sigma0, np.full(n, c0), np.full(n, c1))


def _h_star(ppd=6, C2=None, eta=0.0, lo=5 * ANG, hi=40 * ANG):
    C2 = np.zeros_like(SHAPE) if C2 is None else C2
    return vanishing_scale(lambda h: psd_combined(h[:, None] ** 2 * SHAPE, C2, eta), Q, E_STAR, DG,
                           zeta_grid(Q1 / Q0, ppd, 1e-10), np.array([lo]), np.array([hi]), np.ones(1), np.zeros(1))[0]


# --- the Volterra solver alone ------------------------------------------------------------

@pytest.mark.parametrize("sigma_a, sigma0", [(0.3, 0.0), (3.0, 0.0), (0.01, 0.0), (0.5, 0.7), (0.0, 0.4)])
def test_volterra_constant_sigma_a_gives_erf(sigma_a, sigma0):
    """Eq 9 with constant sigma_a has the exact solution P = erf((sigma_a + sigma0)/(2 sqrt a))."""
    zeta = zeta_grid(200.0, 10, 1e-8)
    a = (2.5 * (zeta - 1.0))[None, :]  # any increasing a(zeta) with a(1) = 0
    P = detachment_volterra(a, np.full_like(a, sigma_a), sigma0)
    exact = erf((sigma_a + sigma0) / (2.0 * np.sqrt(np.maximum(a, 1e-300))))
    assert np.max(np.abs(P - exact)) < 1e-3


def test_volterra_with_a_plateau_in_a():
    """No roughness over a band of zeta (a constant there): nothing detaches on it and the exact
    solution is still erf(sigma_a / (2 sqrt a)), a function of a alone."""
    zeta = zeta_grid(200.0, 10, 1e-8)
    a = np.where(zeta < 3, zeta - 1, np.where(zeta < 10, 2.0, 0.2 * zeta))[None, :]
    P = detachment_volterra(a, np.full_like(a, 1.5))
    exact = erf(1.5 / (2.0 * np.sqrt(a[:, 1:])))
    assert np.max(np.abs(P[:, 1:] - exact)) < 1e-3


def test_volterra_converges_at_second_order():
    errs = []
    for ppd in (5, 10, 20):
        zeta = zeta_grid(200.0, ppd, 1e-8)
        a = (zeta - 1.0)[None, :]
        P = detachment_volterra(a, np.full_like(a, 0.3))
        errs.append(np.max(np.abs(P - erf(0.3 / (2 * np.sqrt(np.maximum(a, 1e-300)))))))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 1.8), orders


def test_layer_resolving_offset():
    """The grid offset is kept when it resolves the layer and reduced (proportionally) when not."""
    assert layer_resolving_offset(Q, (5 * ANG) ** 2 * SHAPE[None, :], E_STAR, DG, 1e-10, 1e-8) == 1e-10
    C = (18 * ANG) ** 2 * SHAPE[None, :]
    small = layer_resolving_offset(Q, C, E_STAR, DG, 1e-10, 1e-14)
    assert small < 1e-10
    prob = AdhesionProblem(Q, C, E_STAR, DG, zeta_grid(Q1 / Q0, 6, small))
    assert prob.a[0, 1] <= 1.0001e-3 * 1e-14 * prob.F[0]


# --- full contact -------------------------------------------------------------------------

def test_surface_area_factor_closed_form_equals_integral():
    for xi in (1e-3, 0.3, 1.0, 4.0, 50.0):
        direct = quad(lambda x, xi=xi: np.sqrt(1 + xi * xi * x) * np.exp(-x), 0, np.inf)[0]
        assert surface_area_factor(xi) == pytest.approx(direct, rel=1e-10)
    assert surface_area_factor(0.0) == 1.0


@pytest.mark.parametrize("Hx", [0.3, 0.8, 1.0])
def test_full_contact_gamma_eff_power_law_closed_form(Hx):
    q0, q1, C0 = 1e7, 1e10, 1e-40
    q = log_grid(q0, q1, 10)
    C = C0 * (q / q0) ** (-2 * (1 + Hx))
    delta = adhesion_length(DG, E_STAR)
    m2 = C0 * q0 ** (2 + 2 * Hx) * (q1 ** (1 - 2 * Hx) - q0 ** (1 - 2 * Hx)) / (1 - 2 * Hx)  # int q^2 C dq
    xi = np.sqrt(2 * np.pi * C0 * q0 ** (2 + 2 * Hx) * (q1 ** (2 - 2 * Hx) - q0 ** (2 - 2 * Hx)) / (2 - 2 * Hx)) \
        if Hx != 1 else np.sqrt(2 * np.pi * C0 * q0**4 * np.log(q1 / q0))
    erfcx = __import__("scipy.special").special.erfcx
    expected = 1 + 0.5 * np.sqrt(np.pi) * xi * erfcx(1 / xi) - 2 * np.pi / delta * m2
    assert gamma_eff_full_contact(q, C, delta) == pytest.approx(expected, rel=1e-9)


def test_adhesion_length_seed_value():
    """Seed eq 64: Delta_gamma = 100 meV/A^2, E = 77.2 GPa, nu = 0.42 give delta = 0.68 A."""
    assert adhesion_length(DG, E_STAR) == pytest.approx(0.6837e-10, rel=1e-3)


# --- partial contact ----------------------------------------------------------------------

def test_partial_contact_P_bounded_and_non_increasing():
    _, sol = _solve(np.array([2, 8, 12, 15, 17, 18, 25]) * ANG)
    P = sol["P"]
    assert np.all((P >= 0) & (P <= 1))
    assert np.all(np.diff(P, axis=1) <= 1e-12)


def test_gamma_eff_decreases_with_hrms_one_surface():
    hs = np.linspace(1, 22, 12) * ANG
    prob, sol = _solve(hs)
    att = sol["attached"]
    assert att[0] and not att[-1]
    assert np.all(np.diff(sol["K"][att]) < 0)
    assert np.all(np.diff(sol["K"]) <= 0)
    assert np.all(np.diff(prob.full) < 0)
    assert np.all(np.diff(sol["P"][:, -1]) <= 0)


def test_self_consistency_of_the_solution():
    """The returned solution satisfies eq 13 at the top: numerator(zeta1) = P(zeta1) F, and
    gamma_eff(zeta1) = F Delta_gamma (only the adhesion term is left at the highest magnification)."""
    prob, sol = _solve(np.array([5, 12, 16]) * ANG)
    assert np.allclose(sol["gamma_ratio"][:, -1], prob.F, rtol=1e-6)


def test_flat_surfaces_give_full_adhesion():
    """No roughness (identical surfaces, eta = 1: combined PSD exactly 0): gamma_eff = Delta_gamma, P = 1."""
    C = psd_combined(SHAPE * (5 * ANG) ** 2, SHAPE * (5 * ANG) ** 2, 1.0)[None, :]
    prob = AdhesionProblem(Q, C, E_STAR, DG, zeta_grid(Q1 / Q0, 6, 1e-10))
    sol = solve_partial_contact(prob, 0.0, np.ones(1), np.zeros(1))
    assert sol["K"][0] == pytest.approx(1.0, abs=1e-9)
    assert np.all(sol["P"] == 1.0)


def test_load_increases_area():
    _, free = _solve(np.array([16.0]) * ANG)
    _, pressed = _solve(np.array([16.0]) * ANG, sigma0=1e7)
    assert pressed["P"][0, -1] > free["P"][0, -1]


def test_yang_persson_model_runs_and_differs():
    _, a = _solve(np.array([14.0]) * ANG)
    _, b = _solve(np.array([14.0]) * ANG, c0=0.45, c1=0.55)
    assert b["K"][0] != a["K"][0] and 0 < b["K"][0] <= 1.0 + 1e-12


def test_non_convergence_raises_computation_error_with_residual():
    hs = np.array([14.0]) * ANG
    prob = AdhesionProblem(Q, hs[:, None] ** 2 * SHAPE, E_STAR, DG, zeta_grid(Q1 / Q0, 6, 1e-10))
    with pytest.raises(ComputationError, match="residual"):
        solve_partial_contact(prob, 0.0, np.ones(1), np.zeros(1), maxiter=1)


# --- where adhesion vanishes --------------------------------------------------------------

def test_vanishing_hrms_two_surfaces_effective_hrms_rule():
    """Same H and q band: the pair is one surface of hrms_eff^2 = h1^2 + h2^2 - 2 eta h1 h2, so
    the vanishing substrate hrms h1 obeys h1^2 + h2^2 - 2 eta h1 h2 = h*^2 (h*: one surface)."""
    h_star = _h_star()
    h2 = 6 * ANG
    C2 = SHAPE * h2**2
    for eta, lo, hi in ((0.0, 5, 30), (-1.0, 5, 30), (1.0, 10, 40)):
        h1 = _h_star(C2=C2, eta=eta, lo=lo * ANG, hi=hi * ANG)
        assert np.sqrt(h1**2 + h2**2 - 2 * eta * h1 * h2) == pytest.approx(h_star, rel=1e-3)
    assert _h_star(C2=C2, eta=-1.0, lo=5 * ANG) == pytest.approx(h_star - h2, rel=1e-3)
    assert _h_star(C2=C2, eta=1.0, lo=10 * ANG) == pytest.approx(h_star + h2, rel=1e-3)


def test_vanishing_is_where_branch_ends():
    """Just below h*: attached with small gamma_eff and area; just above: detached."""
    h_star = _h_star()
    _, sol = _solve(np.array([0.995, 1.005]) * h_star)
    assert sol["attached"][0] and not sol["attached"][1]
    assert 0 < sol["K"][0] < 0.05 and 0 < sol["P"][0, -1] < 0.5


def test_vanishing_hrms_grid_convergence():
    """The vanishing hrms converges as the Volterra grid is refined (order > 1)."""
    h = np.array([_h_star(ppd) for ppd in (4, 8, 16)])
    d1, d2 = abs(h[1] - h[0]), abs(h[2] - h[1])
    assert d2 < d1 / 2.0
    assert d2 / h[2] < 2e-3


# --- extremes (hypothesis) ----------------------------------------------------------------

@settings(max_examples=15, deadline=None)
@given(Hx=st.floats(0.05, 1.0), log_h=st.floats(-13.0, -7.0), log_dg=st.floats(-3.0, 1.0),
       eta=st.sampled_from([-1.0, 0.0, 1.0, 0.37]), ratio=st.sampled_from([0.0, 0.5, 1.0, 3.0]))
def test_extremes_are_finite_and_bounded(Hx, log_h, log_dg, eta, ratio):
    """Tiny to huge roughness and binding energy, H -> 0 and 1, eta = -1..1, identical surfaces
    (eta = 1, ratio 1: combined PSD exactly 0): finite, 0 <= P <= 1, 0 <= gamma_eff(1) <= F Delta_gamma."""
    q0, q1 = 1e6, 1e9
    q = log_grid(q0, q1, 8)
    unit = self_affine_psd(q, Hx, q0, q0, q1, 1.0) / self_affine_hrms_factor(Hx, q0, q0, q1)
    C = psd_combined((10**log_h) ** 2 * unit, (ratio * 10**log_h) ** 2 * unit, eta)
    prob = AdhesionProblem(q, C[None, :], E_STAR, 10**log_dg, zeta_grid(q1 / q0, 4, 1e-10))
    sol = solve_partial_contact(prob, 0.0, np.ones(1), np.zeros(1))
    assert np.all(np.isfinite(sol["P"])) and np.all((sol["P"] >= 0) & (sol["P"] <= 1))
    assert 0.0 <= sol["K"][0] <= prob.F[0] + 1e-12
    assert np.isfinite(prob.full[0]) and prob.full[0] <= prob.F[0]


@settings(max_examples=10, deadline=None)
@given(sigma_a=st.floats(0.0, 50.0), sigma0=st.floats(0.0, 50.0))
def test_volterra_extremes(sigma_a, sigma0):
    """Any stresses, as long as the first cell resolves the detachment layer, a_1 << (sigma_a + sigma0)^2
    (the stage makes sure of that, see layer_resolving_offset), or sigma_a + sigma0 = 0 (P = 0 at once)."""
    zeta = zeta_grid(1e4, 5, 1e-10)
    a = (zeta - 1.0)[None, :]
    assume(sigma_a + sigma0 == 0 or (sigma_a + sigma0) ** 2 > 1e3 * a[0, 1])
    P = detachment_volterra(a, np.full_like(a, sigma_a), sigma0)
    assert np.all((P >= 0) & (P <= 1)) and np.all(np.diff(P) <= 1e-12)
    exact = erf((sigma_a + sigma0) / (2.0 * np.sqrt(a[:, 1:])))
    assert np.max(np.abs(P[:, 1:] - exact)) < 5e-3


# --- the stage through the engine ---------------------------------------------------------

def _raw(hrms, adhesion=None, solid=None, eta=0.0):
    raw = {
        "substrate": {"kind": "self_affine", "H": 0.8, "qL": "7e6 1/m", "q1": "1.4e9 1/m", "hrms": hrms},
        "material": {"E": "77.2 GPa", "nu": 0.42},
        "load": {"p": "1 MPa"},
        "interface": {"eta": eta},
        "adhesion": {"delta_gamma": "100 meV/angstrom^2", "vanishing_hrms": True, **(adhesion or {})},
        "outputs": {"variables": ["adhesion"]},
        "numerics": {"points_per_decade": 20, "adhesion_points_per_decade": 5},
    }
    if solid is not None:
        raw["solid"] = solid
    return raw


def _run(raw, tmp_path):
    sc = scenes.from_dict(raw)
    return engine.run(sc, tmp_path, report=engine.Reporter(None))["base"]["adhesion"]


def test_stage_end_to_end(tmp_path):
    ds = _run(_raw(["10 angstrom", "17 angstrom", "20 angstrom"]), tmp_path)
    for name in ds.variables:
        assert "units" in ds[name].attrs and "long_name" in ds[name].attrs
    assert float(ds["adhesion_length"]) == pytest.approx(0.6837e-10, rel=1e-3)
    hv = float(ds["hrms_substrate_vanishing"])
    assert 17e-10 < hv < 20e-10
    assert float(ds["gamma_eff_macroscopic"].sel(hrms_substrate=20e-10)) == 0.0


def test_stage_delta_directly_equals_delta_gamma(tmp_path):
    a = _run(_raw(["10 angstrom", "15 angstrom"], {"vanishing_hrms": False}), tmp_path / "a")
    raw = _raw(["10 angstrom", "15 angstrom"], {"vanishing_hrms": False})
    del raw["adhesion"]["delta_gamma"]
    raw["adhesion"]["delta"] = f"{float(a['adhesion_length']) * 1e10!r} angstrom"
    b = _run(raw, tmp_path / "b")
    assert np.allclose(a["gamma_eff_macroscopic"], b["gamma_eff_macroscopic"], rtol=1e-9)


@pytest.mark.parametrize("bad, match", [
    ({"delta_gamma": "-1 J/m^2"}, "must be >"),
    ({"delta_gamma": "0 J/m^2"}, "must be >"),
    ({"delta": "1 angstrom"}, "not both"),
    ({"model": ["alpa"]}, "not one of"),
])
def test_bad_input(bad, match, tmp_path):
    with pytest.raises(UserError, match=match):
        _run(_raw(["10 angstrom", "20 angstrom"], bad), tmp_path)


def test_sweep_never_detaching_is_a_user_error(tmp_path):
    with pytest.raises(UserError, match="still attached"):
        _run(_raw(["5 angstrom", "10 angstrom"]), tmp_path)
    assert not (tmp_path / "adhesion.nc").exists()


def test_vanishing_needs_a_sweep(tmp_path):
    with pytest.raises(UserError, match="sweep"):
        _run(_raw("10 angstrom"), tmp_path)


def test_stage_models_and_pairs(tmp_path):
    """Per model and per eta: S_el(yang_persson) = 0.45 + 0.55 P^2 <= 1 = S_el(alpha = 1) stores less
    elastic energy, so adhesion survives to a larger roughness; the pair rule holds per model."""
    raw = _raw(["5 angstrom", "12 angstrom", "17 angstrom", "20 angstrom", "30 angstrom"],
               {"model": ["alpha", "yang_persson"]},
               solid={"kind": "self_affine", "H": 0.8, "qL": "7e6 1/m", "q1": "1.4e9 1/m", "hrms": "3 angstrom"},
               eta=[0.0, -1.0])
    ds = _run(raw, tmp_path)
    hv = ds["hrms_substrate_vanishing"]
    assert set(hv.dims) == {"eta", "model"}
    assert np.all(hv.sel(model="yang_persson") > hv.sel(model="alpha"))
    h2 = 3e-10
    one_from_eta0 = np.sqrt(hv.sel(eta=0.0) ** 2 + h2**2)
    one_from_anti = hv.sel(eta=-1.0) + h2
    assert np.allclose(one_from_eta0, one_from_anti, rtol=1e-3)
    assert "model" not in ds["gamma_eff_full_contact"].dims


def test_non_convergence_in_the_stage_names_the_sweep_point(tmp_path, monkeypatch):
    import roughcontact.stages.adhesion as mod

    def failing(prob, sigma0, c0, c1, **kw):
        err = ComputationError("self-consistent gamma_eff: no convergence in 80 iterations; largest residual 0.25")
        err.failed = np.arange(prob.a.shape[0]) == 1
        raise err

    monkeypatch.setattr(mod, "solve_partial_contact", failing)
    with pytest.raises(ComputationError, match=r"hrms_substrate=1\.5e-09.*residual 0\.25"):
        _run(_raw(["10 angstrom", "15 angstrom"], {"vanishing_hrms": False}), tmp_path)
    assert not (tmp_path / "adhesion.nc").exists()


def test_figures_draw(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from roughcontact.stages.figures.adhesion import figure_one_surface, figure_two_surfaces

    raw = _raw(["5 angstrom", "12 angstrom", "20 angstrom"],
               solid={"kind": "self_affine", "H": 0.8, "qL": "7e6 1/m", "q1": "1.4e9 1/m", "hrms": "6 angstrom"},
               eta=[0.0])
    raw["variants"] = {"substrate_only": {"solid": {"kind": "smooth"}}}
    results = engine.run(scenes.from_dict(raw), tmp_path, report=engine.Reporter(None))
    for make in (figure_one_surface, figure_two_surfaces):
        fig = make(results)
        assert len(fig.axes) == 2 and all(ax.lines for ax in fig.axes)
