"""Uncertainty bands (``[bands] draws``): spectra drawn within the measured spectra's statistical
band, carried through every prediction as the sweep dimension ``draw`` and reduced to quantiles.

Asserted: the draws are centred on the measured spectrum with the right spread and are
reproducible whatever else is drawn (chunks); the log-log interpolation of noisy bins is made
unbiased; the 90 % band of A/A0 at a fixed pressure contains the value of the true PSD 90 % of
the time over repeated synthetic surfaces (kernels: 200 surfaces in CI; the whole pipeline from
containers: slow); the bands stage stores the quantiles of the stored draws with CF attributes
and chunking the draws changes nothing; adhesion and friction carry bands too; clear errors.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.stats

sys.path.insert(0, str(Path(__file__).parent))
from roughcontact import engine, scene  # noqa: E402
from roughcontact.errors import UserError  # noqa: E402
from roughcontact.physics.contact import contact_area_ratio, persson_G  # noqa: E402
from roughcontact.physics.estimators import binned_psd_on_grid, binned_spectra_area, log_bin_edges, merge_spectra  # noqa: E402
from roughcontact.physics.quadrature import log_grid  # noqa: E402
from roughcontact.physics.uncertainty import (  # noqa: E402
    bin_curvature_factor,
    interpolation_unbiasing,
    psd_draws,
    psd_draws_on_grid,
    quantiles,
)
from roughcontact.scenes.data.make_container import write_container
from roughcontact.scenes.data.synthetic import self_affine, synthesize

DATA = Path(__file__).resolve().parent.parent / "pipeline" / "scenes" / "data"
L, H, Q0 = 20e-6, 0.8, 2 * np.pi / 5e-6


def _psd(q):
    return self_affine(q, H, Q0, 1e-32)


# -- the draws -------------------------------------------------------------------------------


def test_draws_are_centred_on_the_measurement_with_the_inverse_gamma_spread():
    """C* = C n / Gamma(n + 1): mean C, quantiles those of the inverse gamma; draw 0 is C; a
    draw is the same whatever other draws are computed with it."""
    C, n = np.array([2.0, 5.0, 1e-30]), np.array([3.0, 40.0, 500.0])
    draws = psd_draws(C, n, np.arange(8001), seed=7, stream=1)
    assert np.array_equal(draws[0], C)
    d = draws[1:]
    sd = C / np.sqrt(n - 1) / np.sqrt(d.shape[0])  # standard error of the sample mean
    assert np.all(np.abs(d.mean(axis=0) - C) < 4 * sd)
    for k in range(3):
        expected = scipy.stats.invgamma(n[k] + 1, scale=C[k] * n[k]).ppf([0.05, 0.5, 0.95])
        assert np.allclose(np.quantile(d[:, k], [0.05, 0.5, 0.95]), expected, rtol=0.03)
    assert np.array_equal(psd_draws(C, n, np.array([6543]), 7, 1)[0], draws[6543])
    assert not np.array_equal(psd_draws(C, n, np.array([5]), 7, 2)[0], draws[5])  # another surface, another stream


def test_correlated_draws_keep_each_bins_law_and_carry_the_correlation():
    """With a correlation between bins (a window's), each bin's draws keep their inverse-gamma law
    (mean C, same quantiles) and the bins' normal scores have the given correlation; draw 0 is C."""
    C, n = np.array([2.0, 5.0, 1.0]), np.array([3.0, 40.0, 1.5])
    R = np.array([[1.0, 0.6, 0.3], [0.6, 1.0, 0.0], [0.3, 0.0, 1.0]])
    draws = psd_draws(C, n, np.arange(8001), seed=7, stream=1, correlation=R)
    assert np.array_equal(draws[0], C)
    d = draws[1:]
    for k in range(3):
        law = scipy.stats.invgamma(n[k] + 1, scale=C[k] * n[k])
        assert np.allclose(np.quantile(d[:, k], [0.05, 0.5, 0.95]), law.ppf([0.05, 0.5, 0.95]), rtol=0.04)
    assert abs(d[:, 1].mean() - C[1]) < 4 * C[1] / np.sqrt(n[1] - 1) / np.sqrt(d.shape[0])
    scores = scipy.stats.norm.ppf(scipy.stats.invgamma(n + 1, scale=C * n).sf(d))
    assert np.allclose(np.corrcoef(scores.T), R, atol=0.03)


def test_window_correlates_neighbouring_bins_as_predicted():
    """Hann-windowed crops of a larger random surface: the correlation between the binned PSDs of
    neighbouring low-q bins over 300 crops is the predicted 2 S_bb' / (m_b m_b') over the relative
    variances (bin_covariance), within the Monte-Carlo error, where it is large (0.3-0.8)."""
    from roughcontact.physics.preprocessing import hann_window_radial
    from roughcontact.stages.shared.measured import bin_covariance, mode_factor

    rng = np.random.default_rng(11)
    n, side = 48, 1.0
    edges = log_bin_edges(2 * np.pi / side, np.pi * n / side, 20)
    q_max = np.pi * n / side
    w = hann_window_radial(n, n, side, side)

    def psd(q):  # flat over the lowest bins (roll-off at 8 lattice steps)
        return self_affine(q, 0.8, 2 * np.pi * 8 / side, 1.0)

    values = []
    for _ in range(300):
        h = synthesize(psd, 4 * n, 4 * n, 4 * side, 4 * side, rng)[:n, :n]
        r = binned_spectra_area((h - h.mean()) * w, side, side, edges, q_max)
        values.append(r["C11"])
    values = np.array(values)
    p = {"window": "hann", "analysis": "area", "h": np.zeros((n, n)), "sizes": (side, side), "q_max": q_max}
    K = bin_covariance(p, edges, r["n"] / mode_factor(p, edges))  # the effective modes, as the topography stage
    with np.errstate(invalid="ignore", divide="ignore"):
        predicted = K / np.sqrt(np.outer(np.diag(K), np.diag(K)))
    ok = np.flatnonzero(r["n"] > 0)[:8]  # the lowest bins: lattice steps 1 to about 3
    measured = np.corrcoef(values[:, ok].T)
    pairs = [(i, j) for i in range(ok.size) for j in range(i + 1, ok.size) if predicted[ok[i], ok[j]] > 0.3]
    assert len(pairs) >= 3
    for i, j in pairs:
        assert abs(measured[i, j] - predicted[ok[i], ok[j]]) < 0.12, (i, j, measured[i, j], predicted[ok[i], ok[j]])


def test_lowest_bins_covariance_of_detrended_windowed_crops_is_exact():
    """Plane-detrended, Hann-windowed crops of a surface that rolls off 2 lattice steps above q = 0
    (the spectrum changes by 2-3 over the window's kernel): the correlation and variance of the
    lowest bins over 400 crops are those of processed_bin_covariance_area, within the Monte-Carlo
    error, where the flat-spectrum correlation is off by up to 0.2."""
    from roughcontact.physics.estimators import processed_bin_covariance_area
    from roughcontact.physics.preprocessing import detrend, detrend_basis, hann_window_radial

    rng = np.random.default_rng(12)
    n, side = 32, 1.0
    edges = log_bin_edges(2 * np.pi / side, np.pi * n / side, 20)
    q_max = np.pi * n / side
    w = hann_window_radial(n, n, side, side)

    def psd(q):
        return self_affine(q, 0.5, 2 * np.pi * 2 / side, 1.0)

    values = []
    for _ in range(400):
        h = synthesize(psd, 4 * n, 4 * n, 4 * side, 4 * side, rng)[:n, :n]
        values.append(binned_spectra_area(detrend(h, 1) * w, side, side, edges, q_max)["C11"])
    values = np.array(values)
    K, inside = processed_bin_covariance_area(psd, n, n, side, side, edges, q_max, window=w,
                                              basis=detrend_basis((n, n), 1))
    ok = np.flatnonzero(inside)
    assert ok.size >= 5
    rel = values[:, ok] / values[:, ok].mean(axis=0)
    assert np.allclose(rel.var(axis=0) / np.diag(K)[ok], 1.0, atol=0.3)  # heavy-tailed: few modes per bin
    predicted = K[np.ix_(ok, ok)] / np.sqrt(np.outer(np.diag(K)[ok], np.diag(K)[ok]))
    assert np.abs(np.corrcoef(values[:, ok].T) - predicted).max() < 0.12


def test_few_mode_bins_follow_the_chi_square_law_and_their_draws_cover_one_bin():
    """A periodic map's bin of n modes: C_hat / C is chi-square with 2n degrees of freedom over
    2n (mean 1, variance 1/n; 4000 maps, n = 2 and 4); the 90 % interval of the draws
    C n / Gamma(n + 1) of one such bin contains C with the probability F_2n(q95) - F_2n(q05)
    of that law (0.79 at n = 2: the truth is above a single few-mode bin's band 20 % of the time;
    sums of many bins are not, see docs/measured-data.md)."""
    rng = np.random.default_rng(11)
    side, npts = 1e-6, 16
    edges = log_bin_edges(2 * np.pi / side * 0.99, 2 * np.pi / side * 2.01, 20)
    ratios = []
    for _ in range(4000):
        s = binned_spectra_area(synthesize(_psd, npts, npts, side, side, rng), side, side, edges, np.pi * npts / side)
        ok = s["n"] > 0
        ratios.append(s["C11"][ok] / _psd(s["q"][ok]))
    ratios, n = np.array(ratios), s["n"][s["n"] > 0]
    assert set(n) == {2.0, 4.0}
    for k, nk in enumerate(n):
        assert abs(ratios[:, k].mean() - 1) < 4 / np.sqrt(nk * ratios.shape[0])
        assert ratios[:, k].var() == pytest.approx(1 / nk, rel=0.1)
        assert scipy.stats.kstest(2 * nk * ratios[:, k], scipy.stats.chi2(2 * nk).cdf).pvalue > 1e-3
    n2 = 2.0
    draws = psd_draws(np.ones(4000), np.full(4000, n2), np.arange(1, 201), seed=3, stream=1) * ratios[:, 0]
    lo, hi = np.quantile(draws, [0.05, 0.95], axis=0)
    law = scipy.stats.chi2(2 * n2)
    q05, q95 = scipy.stats.gamma(n2 + 1).ppf([0.05, 0.95])
    expected = law.cdf(2 * q95) - law.cdf(2 * q05)
    assert np.mean((lo <= 1) & (1 <= hi)) == pytest.approx(expected, abs=0.03)


def test_interpolation_of_noisy_bins_is_made_unbiased():
    """Bins of a power law with Gamma(n)/n noise, interpolated log-log: their mean on the grid
    is biased low by about t(1 - t)/n between bins; with interpolation_unbiasing it equals the
    power law (Monte Carlo, 8000 samples), for the measurement and for its draws alike."""
    rng = np.random.default_rng(3)
    q = np.geomspace(1.0, 10.0, 5)
    n = np.array([2.0, 4.0, 3.0, 8.0, 2.5])
    C = q**-3.0
    grid = np.geomspace(1.0, 10.0, 41)
    noisy = C * rng.gamma(n, size=(8000, q.size)) / n
    plain = np.mean([binned_psd_on_grid(grid, q, c, "none") for c in noisy], axis=0) / grid**-3.0
    fixed = plain * interpolation_unbiasing(grid, q, n, "none")
    se = 4 * np.std(plain) / np.sqrt(noisy.shape[0]) + 4 / np.sqrt(noisy.shape[0] * n.min())
    assert plain.min() < 1 - 0.05 and np.all(np.abs(fixed - 1) < se)
    drawn = psd_draws_on_grid(np.arange(1, 8001), grid, q, C, n, "none", seed=1, stream=1)
    nominal = binned_psd_on_grid(grid, q, C, "none") * interpolation_unbiasing(grid, q, n, "none")
    assert np.all(np.abs(drawn.mean(axis=0) / nominal - 1) < 0.03)


# -- coverage --------------------------------------------------------------------------------


def _band_and_truth(seed, n_points=96, draws=200, bpd=20):
    """Kernels as the pipeline chains them: two periodic scans (L, L/8) of a surface with a known
    PSD -> merged bins -> curvature-corrected bins on the grid -> draws -> A/A0 at the top
    magnification at three pressures; returns (band lower, band upper, true A/A0)."""
    rng = np.random.default_rng(seed)
    edges = log_bin_edges(2 * np.pi / L, np.pi * n_points / (L / 8), bpd)
    spectra = [binned_spectra_area(synthesize(_psd, n_points, n_points, s, s, rng), s, s, edges, np.pi * n_points / s)
               for s in (L, L / 8)]
    q, C, n, _ = merge_spectra(spectra)
    ok = np.isfinite(C) & (C > 0)
    q, C, n = q[ok], C[ok], n[ok]
    C = C * bin_curvature_factor(q, C, bpd)
    grid = log_grid(q[0], q[-1], 50)
    drawn = psd_draws_on_grid(np.arange(draws + 1), grid, q, C, n, "none", seed, 1)
    G = persson_G(grid, drawn, grid[-1:], 1.0)[..., -1]
    G_true = persson_G(grid, _psd(grid), grid[-1:], 1.0)[-1]
    p = 2 * np.sqrt(G_true) * np.array([0.02, 0.07, 0.2])  # A/A0 about 0.02, 0.08, 0.22
    band = quantiles(contact_area_ratio(p[None, :], G[1:, None]).T, [0.05, 0.95])
    return band[:, 0], band[:, 1], contact_area_ratio(p, G_true)


def test_band_of_the_contact_area_covers_the_true_value_90_percent_of_the_time():
    """200 synthetic surfaces: the 90 % band of A/A0 at fixed p contains the true-PSD value
    with frequency 0.9 within 3 binomial standard errors (0.021)."""
    hits = []
    for seed in range(200):
        lo, hi, true = _band_and_truth(seed)
        hits.append((lo <= true) & (true <= hi))
    coverage = np.mean(hits, axis=0)
    error = np.sqrt(0.9 * 0.1 / len(hits))
    print(f"coverage of the 90 % band of A/A0 at A/A0 = 0.02, 0.08, 0.22: {coverage} +- {error:.3f} "
          "(binomial, n = 200)")
    assert np.all(np.abs(coverage - 0.9) < 3 * error), f"coverage {coverage} +- {error:.3f}"


def _container_run(tmp_path, seed, draws, p):
    rng = np.random.default_rng(seed)
    measurements = []
    for name, side in (("coarse", L), ("fine", L / 8)):
        h = synthesize(_psd, 128, 128, side, side, rng)
        measurements.append({"name": name, "heights": h / 1e-9, "size": [side / 1e-9] * 2, "unit": "nm",
                             "is_periodic": True, "detrend_mode": "center", "format": "x3p"})
    write_container(tmp_path / f"c{seed}.zip", "s", measurements)
    raw = {"name": "cov", "substrate": {"kind": "container", "container": str(tmp_path / f"c{seed}.zip")},
           "material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": [f"{x} Pa" for x in p]}, "contact": {"zeta": "all"},
           "bands": {"draws": draws}, "outputs": {"variables": ["contact_area_ratio_band"]}}
    return engine.run(scene.from_dict(raw), tmp_path / f"out{seed}", report=engine.Reporter(None))["base"]


@pytest.mark.slow
def test_band_coverage_through_the_pipeline(tmp_path):
    """The same through containers, the topography, psd, contact and bands stages (200
    surfaces, about 2 s each): coverage 0.9 within 3 binomial standard errors."""
    from scipy.special import erf

    p, hits = np.array([300.0, 1000.0, 3000.0]), []
    for seed in range(200):
        res = _container_run(tmp_path, seed, 200, p)
        q = res["psd"]["q"].values
        true = erf(p / (2 * np.sqrt(persson_G(q, _psd(q), q[-1:], 10e6 / 0.75)[-1])))
        band = res["bands"]["contact_area_ratio_band"].isel(zeta=-1)
        hits.append((band.isel(quantile=0).values <= true) & (true <= band.isel(quantile=-1).values))
    coverage, error = np.mean(hits, axis=0), np.sqrt(0.09 / len(hits))
    print(f"pipeline coverage of the 90 % band of A/A0 at p = {p} Pa: {coverage} +- {error:.3f} "
          f"(binomial, n = {len(hits)})")
    assert np.all(np.abs(coverage - 0.9) < 3 * error), coverage


# -- the stage -------------------------------------------------------------------------------


def _scene(draws=30, chunks=None, outputs=("contact_area_ratio_band", "mean_separation_band", "stress_distribution",
                                            "stress_distribution_band", "hrms_combined_band")):
    raw = scene.load("container").raw
    raw = dict(raw, bands={"draws": draws}, load={"p": ["10 kPa", "100 kPa", "1 MPa"]}, contact={"zeta": [1.0, 100.0]},
               outputs={"variables": list(outputs)})
    raw.pop("variants")
    if chunks:
        raw["numerics"] = {"chunks": chunks}
    return scene.from_dict(raw, scene.resolve("container"))


def test_bands_are_quantiles_of_the_stored_draws_with_cf_attributes(tmp_path):
    res = engine.run(_scene(), tmp_path, report=engine.Reporter(None))["base"]
    bands, contact = res["bands"], res["contact"]
    area = contact["contact_area_ratio"]
    assert area.sizes["draw"] == 31 and contact["draw"].attrs["standard_name"] == "realization"
    expected = np.quantile(area.isel(draw=slice(1, None)).values, [0.05, 0.5, 0.95], axis=area.dims.index("draw"))
    band = bands["contact_area_ratio_band"].transpose("quantile", *[d for d in area.dims if d != "draw"])
    assert np.allclose(band.values, expected, rtol=1e-12)
    assert list(bands["quantile"].values) == pytest.approx([0.05, 0.5, 0.95])
    assert bands["quantile"].attrs["units"] == "1" and "probability" in bands["quantile"].attrs["long_name"]
    for name in ("contact_area_ratio_band", "mean_separation_band", "hrms_combined_band", "stress_distribution_band"):
        source = name.removesuffix("_band")
        upstream = next(ds for ds in res.values() if source in ds)
        assert bands[name].attrs["units"] == upstream[source].attrs["units"]
        assert "quantile" in bands[name].attrs["comment"] and bands[name].dims[0] == "quantile"
    assert np.all(np.diff(bands["mean_separation_band"].values, axis=0) >= 0)  # quantiles ordered
    stress = bands["stress_distribution_band"]
    assert np.allclose(stress["sigma"].values, contact["sigma"].isel(draw=0).values)  # on draw 0's stress grid
    assert bands.attrs["draws"] == 30 and bands.attrs["level"] == 0.9


def test_chunking_the_draws_changes_nothing(tmp_path):
    """draw is a sweep dimension: chunked (7 draws a chunk) or not, the same draws and bands."""
    outputs = ("contact_area_ratio_band", "mean_separation_band")
    whole = engine.run(_scene(outputs=outputs), tmp_path / "a", report=engine.Reporter(None))["base"]
    chunked = engine.run(_scene(outputs=outputs, chunks={"draw": 7}), tmp_path / "b",
                         report=engine.Reporter(None))["base"]
    for stage, var in (("psd", "psd_combined"), ("bands", "contact_area_ratio_band"),
                       ("bands", "mean_separation_band")):
        assert np.array_equal(whole[stage][var].values, chunked[stage][var].values)


def test_friction_and_adhesion_carry_bands(tmp_path):
    raw = {"name": "af",
           "substrate": {"kind": "container", "container": str(DATA / "substrate.zip"), "extend": "power_law"},
           "material": {"nu": 0.5, "E": "10 MPa"}, "load": {"p": "0.4 MPa"},
           "modulus": {"kind": "box", "E0": "5 MPa", "E_inf": "3 GPa", "tau1": "1e-6 s", "tau2": "1e4 s",
                       "T_ref": "-42.9 degC", "T": "25 degC", "shift": "wlf", "C1": 17.44, "C2": "51.6 K"},
           "friction": {"v": {"from": "1e-4 m/s", "to": "1 m/s", "num": 5}}, "adhesion": {"delta_gamma": "0.05 J/m^2"},
           "bands": {"draws": 12},
           "outputs": {"variables": ["friction_coefficient_band", "sliding_contact_area_ratio_band",
                                     "gamma_eff_full_contact_band"]}}
    res = engine.run(scene.from_dict(raw, tmp_path / "s.toml"), tmp_path / "out", report=engine.Reporter(None))["base"]
    mu = res["bands"]["friction_coefficient_band"]
    assert mu.dims == ("quantile", "v") and np.all(mu.values > 0) and np.all(np.diff(mu.values, axis=0) >= 0)
    assert np.any(np.diff(mu.values, axis=0) > 0)  # a band, not a line
    nominal = res["friction"]["friction_coefficient"].isel(draw=0).values
    assert np.all(np.abs(nominal / mu.isel(quantile=1).values - 1) < 0.2)
    full = res["bands"]["gamma_eff_full_contact_band"].values
    assert np.all(np.diff(full) >= 0) and full[0] < full[-1]


@pytest.mark.parametrize("draws, substrate, message", [
    (0, "container", "bands need spectrum draws"),
    (10, "self_affine", "no surface is measured"),
])
def test_bands_without_draws_or_without_a_measured_surface_is_a_clear_error(tmp_path, draws, substrate, message):
    surface = ({"kind": "container", "container": str(DATA / "substrate.zip")} if substrate == "container" else
               {"kind": "self_affine", "H": 0.8, "qL": "1e5 1/m", "q1": "1e8 1/m", "hrms": "1 um"})
    raw = {"name": "e", "substrate": surface, "material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "1 MPa"},
           "bands": {"draws": draws}, "outputs": {"variables": ["contact_area_ratio_band"]}}
    with pytest.raises(UserError, match=message) as info:
        engine.run(scene.from_dict(raw, tmp_path / "s.toml"), tmp_path / "out", report=engine.Reporter(None))
    assert info.value.key == "bands.draws"


def test_draws_must_be_a_whole_number():
    raw = {"name": "e", "bands": {"draws": 2.5}}
    with pytest.raises(UserError, match="whole number of draws"):
        scene.from_dict(raw)
    assert scene.from_dict({"name": "e", "bands": {"draws": 4}}).sweep_sizes()["draw"] == 5
    assert "draw" not in scene.from_dict({"name": "e"}).sweep_sizes()


# -- line scans: the Hurst exponent of the conversion -----------------------------------------


def _line_scans(tmp_path, H, seed=0, n=512, profiles=32):
    """Profiles (along x, 10 um) of an isotropic self-affine surface of Hurst exponent H, saved as
    a map with one profile per column. The map is synthesized with a finer y lattice than x, so
    that each profile's 1D spectrum holds every q_y up to well beyond its own Nyquist."""
    side = 10e-6
    psd = lambda q: self_affine(q, H, np.pi / side, 1e-33)  # noqa: E731
    h = synthesize(psd, n, 4 * n, side, side, np.random.default_rng(seed))[:, :: 4 * n // profiles]
    np.save(tmp_path / f"scan{H}.npy", h)
    return str(tmp_path / f"scan{H}.npy"), psd


@pytest.mark.parametrize("H", [0.8, 0.3])
def test_line_scans_are_converted_with_the_hurst_exponent_of_their_spectrum(tmp_path, H):
    """Without a given hurst, H is fitted to the scans' spectrum (within 0.05 of the surface's)
    and the converted PSD is the surface's within 5 % over the self-affine band; the default
    H = 0.5 of before made an H = 0.8 surface 15 % low (c(0.5) / c(0.8) = 0.854). The result
    says which H was used and that its uncertainty is not in the bands."""
    pytest.importorskip("SurfaceTopography")
    path, psd = _line_scans(tmp_path, H)
    surface = {"kind": "topography", "files": path, "height_unit": "m", "size_x": "10 um", "analysis": "profiles",
               "periodic": True}
    raw = {"name": "h", "substrate": surface, "material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "1 MPa"}}
    res = engine.run(scene.from_dict(raw, tmp_path / "s.toml"), tmp_path / "out", targets=("topography",),
                     report=engine.Reporter(None))["base"]["topography"]
    note = res["psd_substrate_measured"].attrs["line_scan_hurst"]
    fitted = float(note.split("=")[1].split("+-")[0])
    assert abs(fitted - H) < 0.05 and "NOT in the errors or the bands" in note
    q, C = res["q_substrate_measured"].values, res["psd_substrate_measured"].values
    band = (q > 10 * 2 * np.pi / 10e-6) & (q < 0.5 * np.pi * 512 / 10e-6)
    assert abs(np.mean(C[band] / psd(q[band])) - 1) < 0.05
    from roughcontact.physics.spectra import isotropic_factor

    assert isotropic_factor(0.5) / isotropic_factor(0.8) == pytest.approx(0.854, abs=1e-3)


def test_line_scans_whose_spectrum_gives_no_slope_need_a_given_hurst(tmp_path):
    pytest.importorskip("SurfaceTopography")
    np.save(tmp_path / "short.npy", np.random.default_rng(1).standard_normal(16) * 1e-9)
    surface = {"kind": "topography", "files": str(tmp_path / "short.npy"), "height_unit": "m", "size_x": "1 um"}
    raw = {"name": "h", "substrate": surface, "material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "1 MPa"}}
    with pytest.raises(UserError, match="give substrate.hurst") as info:
        engine.run(scene.from_dict(raw, tmp_path / "s.toml"), tmp_path / "out", targets=("topography",),
                   report=engine.Reporter(None))
    assert info.value.key == "substrate.hurst"
