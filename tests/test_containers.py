"""contact.engineering containers (kind = "container"): the reader hands the stages SI heights
and each measurement's metadata; the merged PSD of a container built from a known PSD agrees
with it within the stated standard errors (z-scores with unit variance over repeated seeds);
bad containers are one-line errors naming the container and the measurement; the built-in
scene merges two scales, pairs the two containers and records what it did."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from roughcontact import engine, scene  # noqa: E402
from roughcontact.errors import UserError  # noqa: E402
from roughcontact.physics.estimators import log_bin_edges  # noqa: E402
from roughcontact.readers import READERS  # noqa: E402
from roughcontact.scenes.data.make_container import write_container
from roughcontact.scenes.data.synthetic import self_affine, synthesize, wavevectors

pytest.importorskip("SurfaceTopography")

L, N = 20e-6, 96  # the coarse scan; the fine one is L / 8


def _psd(q):
    return self_affine(q, 0.8, 2 * np.pi / 5e-6, 1e-32)


def _two_scales(rng, periodic=True, **extra):
    """Two x3p measurements of one random surface (known PSD) at two scales, heights in nm."""
    out = []
    for name, side in (("coarse", L), ("fine", L / 8)):
        h = synthesize(_psd, N, N, side, side, rng)
        out.append(dict({"name": name, "heights": h / 1e-9, "size": [side / 1e-9] * 2, "unit": "nm",
                         "is_periodic": periodic, "detrend_mode": "center", "format": "x3p"}, **extra))
    return out


def _run(tmp_path, raw, targets):
    sc = scene.from_dict(dict({"name": "t", "material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "1 kPa"}}, **raw),
                         tmp_path / "scene.toml")
    return engine.run(sc, tmp_path / "out", targets=targets, report=engine.Reporter(None))


def _expected_binned(side, edges, q_max):
    """Mean of the true PSD over the Fourier modes of each bin (the estimator's expectation) and the modes."""
    q = wavevectors(N, N, side, side).ravel()
    b = np.searchsorted(edges, q) - 1
    b[(q > q_max) | (q == 0) | (b < 0) | (b >= edges.size - 1)] = edges.size - 1
    count = np.bincount(b, minlength=edges.size)[:-1]
    total = np.bincount(b, weights=_psd(q), minlength=edges.size)[:-1]
    with np.errstate(invalid="ignore"):
        return np.nan_to_num(total / count), count / 2.0


# -- the reader ------------------------------------------------------------------------------


def test_reader_hands_si_heights_sizes_units_and_reliability_cutoffs(tmp_path):
    """An x3p file in um and a bare .npy array of counts (unit nm and height scale from the
    metadata only): heights and sizes in metres, the resolution cutoff in metres, metadata kept."""
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((32, 32)), rng.standard_normal((16, 24))
    write_container(tmp_path / "c.zip", "steel", [
        {"name": "optical", "heights": a, "size": [40.0, 40.0], "unit": "um", "format": "x3p",
         "instrument": {"name": "profilometer", "parameters": {"resolution": {"value": 2.0, "unit": "um"}}}},
        {"name": "afm", "heights": b, "size": [1.0, 1.5], "unit": "nm", "height_scale": 0.05}])
    c = READERS["container"](tmp_path / "c.zip", key="substrate")
    assert c.surface == "steel" and [m.metadata["measurement"] for m in c.measurements] == ["optical", "afm"]
    optical, afm = c.measurements
    assert np.allclose(optical.heights, (a - a.mean()) * 1e-6, rtol=1e-6, atol=1e-12)  # x3p: float32; 'center' detrend
    assert optical.physical_sizes == pytest.approx((40e-6, 40e-6))
    assert optical.metadata["reliability_cutoff_m"] == pytest.approx(2e-6)
    assert np.allclose(afm.heights, b * 0.05e-9, rtol=1e-6)
    assert afm.physical_sizes == pytest.approx((1e-9, 1.5e-9))
    assert afm.metadata["reliability_cutoff_m"] is None and afm.metadata["height_scale"] == 0.05
    assert optical.metadata["notes"] == []  # the metadata agree with the x3p file's own unit and size


def _bad(tmp_path, case):
    rng = np.random.default_rng(1)
    good = {"name": "scan A", "heights": rng.standard_normal((16, 16)), "size": [1.0, 1.0], "unit": "um"}
    other = dict(good, name="scan B")
    if case == "missing unit":
        other = {k: v for k, v in other.items() if k != "unit"}
    elif case == "unknown format":
        other = dict(other, datafile="scan_B.xyz", raw=b"\x00\x01 this is not a topography \x02" * 3)
    elif case == "missing data file":
        other = dict(other, datafile="scan_B.npy")
    measurements = [good] if case == "one measurement" else [good, other]
    write_container(tmp_path / "bad.zip", "s", measurements)
    if case == "missing data file":  # rewrite the archive without the file
        import zipfile

        with zipfile.ZipFile(tmp_path / "bad.zip") as z:
            keep = {n: z.read(n) for n in z.namelist() if n != "scan_B.npy"}
        with zipfile.ZipFile(tmp_path / "bad.zip", "w") as z:
            for n, data in keep.items():
                z.writestr(n, data)
    return tmp_path / "bad.zip"


@pytest.mark.parametrize("case, message", [
    ("missing unit", r"measurement 'scan B' \(data file 'scan_B.npy'\): no height unit"),
    ("unknown format", r"measurement 'scan B' \(data file 'scan_B.xyz'\): unknown or unsupported file format"),
    ("one measurement", r"surface 's' has 1 measurement\(s\) \(measurement 'scan A', data file 'scan_A.npy'\)"),
    ("missing data file", r"measurement 'scan B' \(data file 'scan_B.npy'\): the data file is not in the archive"),
])
def test_bad_container_is_a_one_line_error_naming_container_and_measurement(tmp_path, case, message):
    path = _bad(tmp_path, case)
    raw = {"substrate": {"kind": "container", "container": str(path)}}
    with pytest.raises(UserError, match=message) as info:
        _run(tmp_path, raw, ("psd_substrate_measured",))
    text = str(info.value)
    assert "\n" not in text and str(path) in text and text.count("substrate.container") == 1
    assert not (tmp_path / "out" / "topography.nc").exists()  # nothing written


def test_not_a_container_and_several_surfaces(tmp_path):
    (tmp_path / "x.zip").write_bytes(b"PK not really")
    with pytest.raises(UserError, match="not a contact.engineering container"):
        READERS["container"](tmp_path / "x.zip", key="solid")
    import zipfile

    import yaml

    rng = np.random.default_rng(2)
    write_container(tmp_path / "two.zip", "a", [{"name": n, "heights": rng.standard_normal((8, 8)), "size": [1, 1],
                                                  "unit": "um"} for n in ("m1", "m2")], index_json=False)
    with zipfile.ZipFile(tmp_path / "two.zip") as z:
        files = {n: z.read(n) for n in z.namelist()}
    meta = yaml.safe_load(files["meta.yml"])
    meta["surfaces"].append(dict(meta["surfaces"][0], name="b"))
    files["meta.yml"] = yaml.safe_dump(meta).encode()
    with zipfile.ZipFile(tmp_path / "two.zip", "w") as z:
        for n, data in files.items():
            z.writestr(n, data)
    with pytest.raises(UserError, match=r"holds 2 surfaces \('a', 'b'\); choose one with solid.surface"):
        READERS["container"](tmp_path / "two.zip", key="solid")
    assert READERS["container"](tmp_path / "two.zip", key="solid", surface="b").surface == "b"


# -- errors of windowed scans ------------------------------------------------------------------


@pytest.mark.parametrize("profiles", [False, True])
def test_window_mode_factor_matches_the_variance_of_windowed_crops(profiles):
    """Crops of larger random surfaces, Hann-windowed (radial for maps, along x for profiles):
    the variance of each bin's PSD over 150 crops is C^2 / n times the predicted factor (about 4
    for wide bins of a radial window, 35/18 for profiles) within the Monte-Carlo error."""
    from roughcontact.physics.estimators import binned_spectra_area, binned_spectra_profiles
    from roughcontact.physics.modes import window_mode_factor_area, window_mode_factor_profiles
    from roughcontact.physics.preprocessing import hann_window_1d, hann_window_radial

    rng = np.random.default_rng(5)
    n, side = (1024 if profiles else 96), 1.0
    edges = log_bin_edges(2 * np.pi / side, np.pi * n / side, 10)
    q_max = np.pi * n / side

    def psd(q):
        return self_affine(q, 0.8, 2 * np.pi * 4 / side, 1.0)

    if profiles:
        w = hann_window_1d(n)
        factor = window_mode_factor_profiles(n, side, edges, q_max, w)
    else:
        w = hann_window_radial(n, n, side, side)
        factor = window_mode_factor_area(n, n, side, side, edges, q_max, w)
    values = []
    for _ in range(150):
        big = synthesize(psd, 4 * n, 4 * n if not profiles else 8, 4 * side, 4 * side if not profiles else side, rng)
        h = big[:n, :n] if not profiles else big[:n, :1]
        h = h - h.mean()
        r = (binned_spectra_profiles(h * w[:, None], side, edges, q_max, 0.5) if profiles else
             binned_spectra_area(h * w, side, side, edges, q_max))
        values.append(r["C11"])
    values = np.array(values)
    measured = values.var(axis=0) / values.mean(axis=0) ** 2 * r["n"]
    ok = r["n"] >= 8
    assert ok.sum() >= 5 and factor[ok].max() > (3.0 if not profiles else 1.7)
    ratio = measured[ok] / factor[ok]
    assert np.all(np.abs(ratio - 1) < 4 * np.sqrt(2 / 149)), ratio  # sampling error of a variance
    assert abs(np.mean(ratio) - 1) < 0.12


# -- the merged PSD against the known one ------------------------------------------------------


def test_merged_psd_agrees_with_the_known_psd_within_its_stated_errors(tmp_path):
    """Containers of two periodic scans (L and L/8) of surfaces with a known PSD, through the
    pipeline: per bin, z = (C - E[C]) / (E[C] r) has unit variance and zero mean over repeated
    seeds, r = error / C the stated relative error (E[C]: the n-weighted mean of each scan's
    expected bin average; dividing by the error stated at C itself would bias z by -1/sqrt(n));
    where the scans overlap, the Birge ratio of their spread is chi-square distributed (mean
    square about 1)."""
    z, birge = [], []
    for seed in range(5):
        path = tmp_path / f"c{seed}.zip"
        write_container(path, "s", _two_scales(np.random.default_rng(100 + seed)))
        res = _run(tmp_path / f"r{seed}", {"substrate": {"kind": "container", "container": str(path)}},
                   ("psd_substrate_measured",))["base"]["topography"]
        bpd = int(res.attrs["bins_per_decade"])
        edges = log_bin_edges(res["q_bin"].values[0] / 1.2, res["q_bin"].values[-1] * 1.2, bpd)
        centre = np.sqrt(edges[1:] * edges[:-1])
        pick = np.searchsorted(centre, res["q_bin"].values * (1 - 1e-9))  # this lattice's bins of the result
        expected, modes = np.zeros(edges.size - 1), np.zeros(edges.size - 1)
        for side in (L, L / 8):
            e, n = _expected_binned(side, edges, np.pi * N / side)
            expected, modes = expected + n * e, modes + n
        expected = (expected / np.where(modes > 0, modes, 1))[pick]
        C, err = res["psd_substrate_measured"].values, res["psd_substrate_measured_error"].values
        ok = res["modes_substrate"].values >= 10
        assert np.allclose(res["modes_substrate"].values, modes[pick])  # periodic scans: no window, every mode counts
        z.append(((C - expected) / (expected * err / C))[ok])  # the stated relative error, at the expectation
        ratio = res["psd_substrate_measured_spread"].values
        birge.append(ratio[np.isfinite(ratio) & ok])
    z, birge = np.concatenate(z), np.concatenate(birge)
    print(f"{z.size} bins: mean z^2 = {np.mean(z * z):.3f}, mean z = {np.mean(z):+.3f} +- {1 / np.sqrt(z.size):.3f}, "
          f"max |z| = {np.abs(z).max():.2f}; Birge ratio^2 over {birge.size} overlap bins: {np.mean(birge**2):.2f}")
    assert z.size > 150 and birge.size > 30
    assert 0.75 < np.mean(z * z) < 1.3, np.mean(z * z)
    assert abs(np.mean(z)) < 3.0 / np.sqrt(z.size)
    assert np.all(np.abs(z) < 5.0)
    assert 0.55 < np.mean(birge**2) < 1.6


# -- the built-in scene ------------------------------------------------------------------------


def test_builtin_container_scene_merges_pairs_and_records_provenance(tmp_path):
    """The example containers: two scales per surface merged on one bin lattice, each
    measurement's units, detrending and reliability cutoff from the metadata (recorded), the two
    containers paired (eta measured, about 0.6 by construction)."""
    sc = scene.load("container")
    raw = dict(sc.raw, bands={"draws": 0}, outputs={"variables": ["coherence", "psd_combined"]})
    raw.pop("variants")
    res = engine.run(scene.from_dict(raw, sc.path), tmp_path, report=engine.Reporter(None))["base"]
    topo = res["topography"]
    assert topo.attrs["pairing"].startswith("paired")
    files = json.loads(topo["psd_substrate_measured"].attrs["files"])
    assert [f["container_measurement"]["measurement"] for f in files] == ["profilometer 80 um", "AFM 10 um"]
    optical, afm = files
    assert optical["sizes_m"] == pytest.approx([80e-6, 80e-6]) and afm["sizes_m"] == pytest.approx([10e-6, 10e-6])
    assert optical["q_range_per_m"][1] == pytest.approx(2 * np.pi / 1.5e-6)  # the profilometer's resolution
    assert "tip radius" in afm["cutoff"] and afm["q_range_per_m"][1] < np.pi * 128 / 10e-6  # below Nyquist
    assert optical["detrend"] == afm["detrend"] == "plane" and optical["window"] == "hann"
    q = topo["q_substrate_measured"].values
    assert q[np.isfinite(q)].max() / q[np.isfinite(q)].min() > 300  # the union of both scales
    eta, err = topo["coherence"].values, topo["coherence_error"].values
    ok = np.isfinite(eta) & (err < 0.08)
    assert ok.sum() > 15 and abs(np.average(eta[ok], weights=1 / err[ok] ** 2) - 0.6) < 0.05
    psd = res["psd"]
    assert np.all(psd["psd_substrate_error"].values > 0) and np.all(psd["psd_combined_error"].values > 0)


# -- measurements as instruments deliver them ----------------------------------------------------


def _profile_text(rng, n=200, length_um=50.0) -> bytes:
    """A stylus-like line scan sampled at uneven x (um) with heights (um), as text columns."""
    x = np.sort(rng.uniform(0.0, length_um, n))
    x[0], x[-1] = 0.0, length_um
    h = 0.1 * np.cumsum(rng.standard_normal(n))
    return "".join(f"{a:.6f} {b:.6f}\n" for a, b in zip(x, h, strict=True)).encode()


def test_non_uniform_line_scan_left_out_with_a_warning_naming_it(tmp_path):
    """A container with two maps and one non-uniformly sampled line scan: the line scan is left
    out with a warning naming it, the PSD is merged from the two maps, and the result says
    which measurements entered and which were left out (and why)."""
    from roughcontact.errors import SceneWarning

    rng = np.random.default_rng(30)
    write_container(tmp_path / "c.zip", "s", [
        {"name": "wide", "heights": rng.standard_normal((64, 64)), "size": [40.0, 40.0], "unit": "um"},
        {"name": "stylus", "datafile": "stylus.txt", "raw": _profile_text(rng), "unit": "um", "size": [50.0]},
        {"name": "narrow", "heights": rng.standard_normal((64, 64)), "size": [5.0, 5.0], "unit": "um"}])
    with pytest.warns(SceneWarning, match=r"left out measurement 'stylus' \(data file 'stylus.txt'\): a non-uniformly "
                                          r"sampled line scan \(200 points"):
        res = _run(tmp_path, {"substrate": {"kind": "container", "container": str(tmp_path / "c.zip")}},
                   ("topography",))
    attrs = res["base"]["topography"]["psd_substrate_measured"].attrs
    assert json.loads(attrs["measurements_entered"]) == ["wide", "narrow"]
    (left,) = json.loads(attrs["measurements_left_out"])
    assert left["measurement"] == "stylus" and left["datafile"] == "stylus.txt" and "non-uniformly" in left["reason"]
    assert [d["container_measurement"]["measurement"] for d in json.loads(attrs["files"])] == ["wide", "narrow"]


def test_container_of_non_uniform_line_scans_only_is_refused(tmp_path):
    rng = np.random.default_rng(31)
    write_container(tmp_path / "c.zip", "s", [{"name": n, "datafile": f"{n}.txt", "raw": _profile_text(rng),
                                               "size": [50.0], "unit": "um"} for n in ("p1", "p2")])
    with pytest.raises(UserError, match=r"no measurement can be used: measurement 'p1' .*measurement 'p2'"):
        READERS["container"](tmp_path / "c.zip", key="substrate")


def test_container_undefined_heights_refused_or_filled(tmp_path):
    """A measurement with undefined heights (NaN in the data file): refused naming
    fill_undefined; with fill_undefined = 'harmonic' filled and recorded."""
    rng = np.random.default_rng(32)
    holed = rng.standard_normal((32, 32))
    holed[5, 6] = holed[20, 21] = np.nan
    write_container(tmp_path / "c.zip", "s", [
        {"name": "optical", "heights": holed, "size": [40.0, 40.0], "unit": "um"},
        {"name": "afm", "heights": rng.standard_normal((32, 32)), "size": [5.0, 5.0], "unit": "um"}])
    raw = {"substrate": {"kind": "container", "container": str(tmp_path / "c.zip")}}
    with pytest.raises(UserError, match=r"2 of 1024 heights are missing .*substrate.fill_undefined") as info:
        _run(tmp_path, raw, ("topography",))
    assert info.value.key == "substrate.fill_undefined"
    raw["substrate"]["fill_undefined"] = "harmonic"
    res = _run(tmp_path, raw, ("topography",))
    described = json.loads(res["base"]["topography"]["psd_substrate_measured"].attrs["files"])
    note = described[0]["undefined_filled"]
    assert note["points"] == 2 and note["first_indices"] == [[5, 6], [20, 21]] and note["regions"] == 2
    assert "undefined_filled" not in described[1]
