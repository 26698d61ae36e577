"""Self-affine fits of measured spectra (issue 29, item 3).

Each test asserts a fact: an exact analytic PSD gives its parameters back; synthetic maps of
known H and hrms give them back within their intervals at the stated coverage; the moments are
contact.engineering's (SurfaceTopography's spectral moments of the same map) and the 1D/2D
factors those of an isotropic surface; a scene uses the fitted surface and says where it is
extrapolated; a fit asked of a surface that is not measured is refused before anything is written.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import roughcontact as rc
from roughcontact.errors import SceneWarning, UserError
from roughcontact.physics.estimators import binned_spectra_area, log_bin_edges, merge_spectra, psd_map
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.selfaffine_fit import (
    fit_self_affine,
    fitted_rms,
    model_rms,
    psd_moments,
    rms_from_moments,
    z_value,
)
from roughcontact.physics.spectra import self_affine_hrms_factor, self_affine_psd
from roughcontact.physics.uncertainty import bin_curvature_factor
from roughcontact.scenes.data.synthetic import synthesize

L, N = 10e-6, 128  # 10 um periodic maps of 128 x 128 points
H_TRUE, Q0_TRUE, C0_TRUE = 0.8, 8 * np.pi / L, 1e-33
Q_MAX = np.pi * N / L


def _map(seed, n=N):
    psd = lambda q: self_affine_psd(q, H_TRUE, 1e-30, Q0_TRUE, Q_MAX, C0_TRUE)  # noqa: E731
    return synthesize(psd, n, n, L, L, np.random.default_rng(seed))


# -- the kernel -----------------------------------------------------------------------------


@pytest.mark.parametrize("q0", [1.7e6, 1e5])  # a roll-off inside the band; none (q0 = the band's lower end)
@pytest.mark.parametrize("errors", [True, False])
def test_exact_analytic_psd_gives_its_parameters(q0, errors):
    """The analytic self-affine PSD fed exactly (tiny errors, or none) gives H, C0, q0 to 1e-6."""
    q = np.geomspace(1e5, 1e8, 61)
    C = self_affine_psd(q, 0.73, q[0], q0, q[-1], 3e-30)
    fit = fit_self_affine(q, C, C * 1e-7 if errors else None)
    assert fit.H == pytest.approx(0.73, abs=1e-6)
    assert fit.C0 == pytest.approx(3e-30, rel=1e-6)
    assert fit.q0 == pytest.approx(q0, rel=1e-6)
    assert fit.rolloff == ("resolved" if q0 > q[0] else "not resolved")
    if fit.rolloff == "not resolved":
        assert fit.cov[2, 2] == 0.0  # q0 held at the band's end: no interval claimed for it


def test_a_power_law_fit_holds_q0_at_the_band_end():
    """rolloff = False: a power law over the band (q0 its lower end, no interval), exact for a
    power law and misfitting a rolled-off spectrum (chi^2 far above its dof)."""
    q = np.geomspace(1e5, 1e8, 61)
    for q0, exact in ((1e5, True), (1.7e6, False)):
        C = self_affine_psd(q, 0.73, q[0], q0, q[-1], 3e-30)
        fit = fit_self_affine(q, C, C * 1e-3, rolloff=False)
        assert fit.rolloff == "not fitted" and fit.q0 == pytest.approx(q[0], rel=1e-12) and fit.cov[2, 2] == 0.0
        assert (fit.chi2 < 1e-6 * fit.dof) if exact else (fit.chi2 > 100 * fit.dof)


def test_moments_of_the_power_law_are_exact():
    """m_a = 2 pi int q^(a+1) C dq of a pure power law on [qL, q1], in closed form, and
    hrms from the closed-form self-affine factor."""
    H, qL, q1, C0 = 0.6, 1e5, 1e8, 1e-30
    q = log_grid(qL, q1, 10)
    m0, m2, m4 = psd_moments(q, self_affine_psd(q, H, qL, qL, q1, C0))
    a = -2 * (1 + H)
    closed = [2 * np.pi * C0 * qL ** -a * (q1 ** (k + 2 + a) - qL ** (k + 2 + a)) / (k + 2 + a) for k in (0, 2, 4)]
    assert [m0, m2, m4] == pytest.approx(closed, rel=1e-10)
    assert model_rms(np.array([H, math.log(C0), math.log(qL)]), qL, q1)[0] == pytest.approx(
        math.sqrt(C0 * self_affine_hrms_factor(H, qL, qL, q1)), rel=1e-12)


def test_moments_are_contact_engineerings_and_the_profile_factors_hold():
    """On a synthetic periodic map: the moments of its 2D periodogram are SurfaceTopography's
    spectral moments (contact.engineering's), and the line-scan rms slope and curvature along x
    are sqrt(m2 / 2) and sqrt(3 m4 / 8) (isotropic surface; within 2 % for 256 rows)."""
    ST = pytest.importorskip("SurfaceTopography")
    n = 256
    h = _map(3, n)
    C = psd_map(h, L, L)
    qx = 2 * np.pi * np.fft.fftfreq(n, L / n)
    Q = np.hypot(qx[:, None], qx[None, :])
    m = [np.sum(Q**a * C) * (2 * np.pi) ** 2 / L**2 for a in (0, 2, 4)]
    topo = ST.Topography(h, (L, L), periodic=True)
    assert m == pytest.approx([topo.moment_power_spectrum(order=a) for a in (0, 2, 4)], rel=1e-9)
    rows = np.abs(np.fft.fft(h, axis=0) * (L / n)) ** 2 / L  # 1D periodogram of every line scan along x
    m1d = [np.mean(np.sum(np.abs(qx[:, None]) ** a * rows, axis=0)) / L for a in (0, 2, 4)]
    h1, s1, k1 = rms_from_moments(*m, profile=True)
    assert [h1, s1, k1] == pytest.approx(np.sqrt(m1d), rel=0.02)
    h2, s2, k2 = rms_from_moments(*m)
    assert (s2, k2) == pytest.approx((math.sqrt(m[1]), math.sqrt(m[2]) / 2))


def _binned(seed):
    """The binned PSD of a synthetic map as the topography stage gives it to the fit (mean over the
    modes of each bin, standard error C / sqrt(n), corrected for the curvature across a bin)."""
    edges = log_bin_edges(2 * np.pi / L, Q_MAX, 20)
    q, C, _, err = merge_spectra([binned_spectra_area(_map(seed), L, L, edges, Q_MAX)])
    ok = np.isfinite(C) & (C > 0)
    f = bin_curvature_factor(q[ok], C[ok], 20)
    return q[ok], C[ok] * f, err[ok] * f


def test_synthetic_maps_give_h_and_hrms_back_at_the_stated_coverage():
    """40 maps of known H and hrms: the 95 % intervals of H and of hrms (over the fitted band)
    hold the true values in at least 34 of 40 (expected 38; fewer than 34 has probability 0.5 %
    for honest intervals), and the standardised errors average to about 0 (no bias)."""
    z = []
    for seed in range(40):
        q, C, err = _binned(seed)
        fit = fit_self_affine(q, C, err)
        rms, log_std = fitted_rms(fit)
        true = model_rms(np.array([H_TRUE, math.log(C0_TRUE), math.log(Q0_TRUE)]), *fit.band)
        z.append(((fit.H - H_TRUE) / math.sqrt(fit.cov[0, 0]), math.log(rms[0] / true[0]) / log_std[0]))
    z = np.array(z)
    inside = np.sum(np.abs(z) <= z_value(0.95), axis=0)
    assert np.all(inside >= 34), inside
    assert np.all(np.abs(z.mean(axis=0)) < 3 / math.sqrt(40)), z.mean(axis=0)


# -- through the engine: the fit stage, kind = "fit", bad input ----------------------------------


def _scene(tmp_path, substrate, **extra):
    np.save(tmp_path / "map.npy", _map(1) * 1e9)
    data = {"files": [str(tmp_path / "map.npy")], "height_unit": "nm", "size_x": "10 um", "periodic": True}
    return {"material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "0.1 MPa"},
            "substrate": {**data, **substrate}, **extra}


def test_fit_stage_of_a_measured_map(tmp_path):
    """The fit stage on a measured map: H and hrms hold the true values within their intervals,
    every output has units and a long name, and the intervals are attributes."""
    raw = _scene(tmp_path, {"kind": "topography"}, outputs={"variables": ["hurst_fit_substrate"]})
    ds = rc.compute(raw, progress=False)["base"]["fit"]
    H = ds["hurst_fit_substrate"]
    assert H.attrs["ci_low"] <= H_TRUE <= H.attrs["ci_high"]
    band = tuple(float(v) for v in ds["q_fit_substrate"].values[[0, -1]])
    true = model_rms(np.array([H_TRUE, math.log(C0_TRUE), math.log(Q0_TRUE)]), *band)
    h = ds["hrms_fit_substrate"]
    assert h.attrs["ci_low"] <= true[0] <= h.attrs["ci_high"]
    assert h.attrs["ci_level"] == 0.95
    for name, var in ds.variables.items():
        assert var.attrs.get("units") and 0 < len(var.attrs.get("long_name", "")) < 50, name


def test_a_scene_uses_the_fitted_surface_and_warns_where_it_extrapolates(tmp_path):
    """kind = "fit": the psd stage's spectrum is the fitted model; within the fitted band no
    warning; with q1 beyond it a warning, and the attribute says where."""
    for q1, extrapolated in ((None, False), ("1e9 1/m", True)):
        sub = {"kind": "fit", "of": "topography", **({"q1": q1} if q1 else {})}
        raw = _scene(tmp_path, sub, outputs={"variables": ["contact_area_ratio"]})
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = rc.compute(raw, progress=False)["base"]
        said = [w for w in caught if issubclass(w.category, SceneWarning) and "extrapolated" in str(w.message)]
        assert bool(said) == extrapolated
        fit, psd = res["fit"], res["psd"]
        q = psd["q"].values
        lo = float(fit["q_fit_substrate"].min())
        hi = 1e9 if extrapolated else float(fit["q_fit_substrate"].max())
        model = self_affine_psd(q, float(fit["hurst_fit_substrate"]), lo, float(fit["q0_fit_substrate"]), hi,
                                float(fit["C0_fit_substrate"]))
        assert psd["psd_substrate"].values == pytest.approx(model, rel=1e-12)
        assert q[-1] == pytest.approx(hi)
        assert ("extrapolated above" in psd["psd_substrate"].attrs["extrapolation"]) == extrapolated


def test_builtin_fit_scene_runs():
    """The built-in scene 'fit' (a container fitted, extrapolated to q1 = 1e9 1/m): the fit gives
    the container's H = 0.8 and roll-off 2 pi / 20 um within their intervals, and the contact
    area grows with load."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneWarning)
        res = rc.compute("fit", ["contact_area_ratio", "hurst_fit_substrate"], progress=False)["base"]
    fit = res["fit"]
    for name, true in (("hurst_fit_substrate", 0.8), ("q0_fit_substrate", 2 * np.pi / 20e-6)):
        assert fit[name].attrs["ci_low"] <= true <= fit[name].attrs["ci_high"], name
    area = res["contact"]["contact_area_ratio"].isel(zeta=-1).values
    assert np.all(np.diff(area) > 0)


@pytest.mark.parametrize(("bad", "key"), [
    ({"fit": {"surfaces": ["solid"]}, "solid": {"kind": "self_affine", "H": 0.8, "qL": "1e5 1/m", "q1": "1e8 1/m",
                                                "hrms": "1 nm"}}, "fit.surfaces"),
    ({"substrate": {"kind": "smooth"}}, "fit.surfaces"),
    ({"substrate": {"kind": "fit", "of": "container"}}, "substrate.container"),  # a fit of no data
])
def test_a_fit_of_a_surface_that_is_not_measured_is_refused_before_anything_is_written(tmp_path, bad, key):
    raw = {**_scene(tmp_path, {"kind": "topography"}, outputs={"variables": ["hurst_fit_substrate"]}), **bad}
    with pytest.raises(UserError) as err:
        rc.run(raw, tmp_path / "out", progress=False)
    assert err.value.key == key and "\n" not in str(err.value)
    assert not list((tmp_path / "out").glob("**/*.nc"))


def test_a_psd_file_of_the_analytic_spectrum_is_fitted_exactly(tmp_path):
    """kind = "fit" of a PSD file holding the analytic spectrum (no errors: equal weights): the
    fit stage gives H, C0 and q0 to 1e-6, and the psd stage's spectrum is the file's within its band."""
    q = np.geomspace(1e5, 1e8, 40)
    np.savetxt(tmp_path / "psd.txt", np.column_stack([q, self_affine_psd(q, 0.7, q[0], 1e6, q[-1], 2e-30)]),
               header="q [1/m]  C [m^4]")
    raw = {"material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "0.1 MPa"},
           "substrate": {"kind": "fit", "of": "psd_file", "path": str(tmp_path / "psd.txt")},
           "outputs": {"variables": ["psd_combined", "hurst_fit_substrate"]}}
    res = rc.compute(raw, progress=False)["base"]
    fit = res["fit"]
    assert float(fit["hurst_fit_substrate"]) == pytest.approx(0.7, abs=1e-6)
    assert float(fit["C0_fit_substrate"]) == pytest.approx(2e-30, rel=1e-6)
    assert float(fit["q0_fit_substrate"]) == pytest.approx(1e6, rel=1e-6)
    grid = res["psd"]["q"].values
    assert res["psd"]["psd_substrate"].values == pytest.approx(self_affine_psd(grid, 0.7, q[0], 1e6, q[-1], 2e-30),
                                                               rel=1e-6)
    assert res["psd"]["psd_substrate"].attrs["extrapolation"].startswith("none")
