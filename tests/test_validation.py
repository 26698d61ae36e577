"""The validation stages on a small case (one H, one bandwidth, two coherences, two rungs):
the BEM reference, the theory variants in reduced units, the lattice moments, the deviation
table and the dask.distributed path."""

import numpy as np
import pytest
import xarray as xr
from scipy.special import erf

from roughcontact import engine, scene as scenes
from roughcontact.physics.corrections import corrected_area
from roughcontact.physics.spectra import psd_combined
from roughcontact.physics.validation import case_spectra, extrapolated_area, lattice_moments, observed_order

pytest.importorskip("tamaas")

SMALL = {
    "name": "validation_test",
    "interface": {"eta": [0.0, -1.0]},
    "material": {"E": "77.2 GPa", "nu": 0.42},
    "validation": {"hurst": [0.8], "bandwidth": [8], "reduced_pressure": [0.01, 0.1, 0.5],
                   "pixels_per_wavelength": [4, 8], "realizations": 2, "max_grid": 64},
    "outputs": {"variables": ["validation_deviation_max"]},
    "numerics": {"points_per_decade": 20},
}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    out = tmp_path_factory.mktemp("validation")
    return engine.run(scenes.from_dict(SMALL), out, report=engine.Reporter(None))["base"], out


def test_bem_reference_and_theory_in_reduced_units(small):
    res, _ = small
    ds = res["validation"]
    x = ds["reduced_pressure"]
    # eq 19 in reduced units is erf(sqrt(2) p / (E* g)) on every spectrum; each correction maps it
    np.testing.assert_allclose(ds["validation_theory_area"].sel(theory="persson"), erf(np.sqrt(2) * x)
                               .broadcast_like(ds["validation_theory_area"].sel(theory="persson")), rtol=1e-10)
    yp = ds["validation_theory_area"].sel(theory="yang_persson").isel(hurst=0, bandwidth=0, eta=0)
    np.testing.assert_allclose(yp, corrected_area(np.sqrt(2) * x.values, "yang_persson", 0.45), rtol=1e-10)
    bem = ds["validation_bem_area"]
    assert np.all(bem.diff("reduced_pressure") > 0) and np.all((bem > 0) & (bem <= 1))
    # coarse pixels overestimate the area: the extrapolation lies below the finest rung
    assert np.all(bem <= ds["validation_bem_area_finest"] + 1e-12)
    assert np.all(ds["validation_bem_area_error"] > 0)
    # the known bias: eq 19 gives less area than the BEM at small load, each correction more than eq 19
    ratio = ds["validation_area_ratio"].isel(reduced_pressure=0)
    assert np.all(ratio.sel(theory="persson") < 0.9)
    assert np.all(ratio.sel(theory="yang_persson") > ratio.sel(theory="persson"))
    np.testing.assert_allclose(ds["validation_kappa_bem"], bem / x)


def test_deviation_table_is_what_the_ratios_say(small):
    ds = small[0]["validation"]
    ref = ds["validation_bem_area"]
    mask = (ref >= 0.005) & (ref <= 0.3)
    for name in ds["theory"].values:
        r = ds["validation_area_ratio"].sel(theory=name).where(mask)
        expected = float(np.abs(r - 1).max())
        assert float(ds["validation_deviation_max"].sel(theory=name, range="area_0.005_0.3")) == pytest.approx(expected)
    assert set(ds["range"].values) >= {"area_0.005_0.3", "area_0.3_0.9", "separation_area_above_0.01"}


def test_tasks_are_independent_and_reproducible(small, tmp_path):
    """Realization 0 of a one-realization run is the same surface and result as in the two-realization run."""
    res, _ = small
    raw = {**SMALL, "validation": {**SMALL["validation"], "realizations": 1}, "interface": {"eta": [0.0]}}
    one = engine.run(scenes.from_dict(raw), tmp_path, report=engine.Reporter(None))["base"]["validation_bem"]
    a = res["validation_bem"]["validation_bem_contact_area_ratio"].sel(eta=0.0).isel(realization=0).squeeze(drop=True)
    b = one["validation_bem_contact_area_ratio"].isel(realization=0).squeeze(drop=True)
    np.testing.assert_array_equal(a.transpose(*b.dims).values, b.values)


@pytest.mark.parametrize("H", [0.3, 0.8])
def test_cell_lattice_holds_the_band_variance(H):
    """Point sampling puts more long-wavelength roughness on the lattice than the continuum band
    has (the cell of the modes at qL reaches below qL); cell averaging shares out the band's
    variance exactly (to the subsampling) and its slope to a few 1e-3."""
    q, C1, C2 = case_spectra(H, 16, 2e8, (4.0, 2.0), (1e-9, 0.5e-9), 20)
    C = psd_combined(C1, C2, 0.0)
    h_point, _ = lattice_moments(q, C, 16, "point")
    h_cell, g_cell = lattice_moments(q, C, 16, "cell")
    assert h_point > 1.015
    assert h_cell == pytest.approx(1.0, abs=1e-3) and g_cell == pytest.approx(1.0, abs=1e-2)


def test_richardson_and_order():
    """A(n) = A0 + c / n (first order) is extrapolated exactly and its order measured as 1."""
    n_w = np.array([4.0, 8.0, 16.0])
    a = 0.2 + 0.3 / n_w
    ext, fine, coarse = extrapolated_area(a, n_w)
    assert float(ext) == pytest.approx(0.2) and float(fine) == pytest.approx(a[-1]) and float(coarse) == a[1]
    assert float(observed_order(*a)) == pytest.approx(1.0)
    ext, _, _ = extrapolated_area(np.array([a[0], a[1], np.nan]), n_w)  # the finest rung not solved
    assert float(ext) == pytest.approx(0.2)


def test_on_a_local_cluster(tmp_path, small):
    distributed = pytest.importorskip("distributed")
    raw = {**SMALL, "interface": {"eta": [0.0]}, "validation": {**SMALL["validation"], "realizations": 1}}
    threaded = engine.run(scenes.from_dict(raw), tmp_path / "t", report=engine.Reporter(None))["base"]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        on = engine.run(scenes.from_dict(raw), tmp_path / "c", report=engine.Reporter(None),
                        scheduler=c.scheduler_address)["base"]
    for var in ("validation_bem_contact_area_ratio", "validation_bem_mean_gap"):
        xr.testing.assert_equal(threaded["validation_bem"][var], on["validation_bem"][var])


# --- a long run resumes: each finished BEM task is kept (by the result's content key) until the result is written

LADDER = {**SMALL, "interface": {"eta": [0.0]}, "outputs": {"variables": ["validation_bem_contact_area_ratio"]},
          "validation": {**SMALL["validation"], "reduced_pressure": [0.1, 0.5]}}  # 2 realizations x 2 rungs: 4 tasks


def _count_solves(monkeypatch):
    """The BEM tasks solved in this process (every scheduler but processes and clusters)."""
    import roughcontact.physics.validation as pv

    calls, real = [], pv.bem_task

    def counted(*args, **kwargs):
        calls.append(args[:5])
        return real(*args, **kwargs)

    monkeypatch.setattr(pv, "bem_task", counted)
    return calls


def _leftovers(out):
    return sorted(p.relative_to(out).as_posix() for p in out.rglob(".tmp-*"))


def test_on_a_cluster_each_task_is_solved_once(tmp_path, monkeypatch):
    """A task's three outputs (area, gap, time per solve) come from one BEM solve on the cluster,
    as on threads: 4 tasks, 4 solves (each solve ran once per output before, three times the work)."""
    distributed = pytest.importorskip("distributed")
    calls = _count_solves(monkeypatch)  # workers in this process (processes=False) see the counter
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as c:
        res = engine.run(scenes.from_dict(LADDER), tmp_path, report=engine.Reporter(None),
                         scheduler=c.scheduler_address)["base"]["validation_bem"]
    assert res["validation_bem_contact_area_ratio"].notnull().all()
    assert sorted(calls) == sorted(set(calls)) and len(calls) == 4


def test_a_run_interrupted_after_its_first_task_resumes_with_the_others(tmp_path, monkeypatch):
    """Ctrl-C (a KeyboardInterrupt, here raised by the progress tick of the first finished task)
    keeps that task; the rerun solves only the three others and gives what an uninterrupted run
    gives; nothing temporary remains, and the kept tasks go once the result is written."""
    import io

    from roughcontact.progress import Reporter, Tick

    out, sc = tmp_path / "out", scenes.from_dict(LADDER)
    solves = _count_solves(monkeypatch)

    def interrupt(self, n=1):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(Tick, "__call__", interrupt)
        with pytest.raises(KeyboardInterrupt):
            engine.run(sc, out, report=Reporter(None), scheduler="synchronous")
    assert len(solves) == 1 and not (out / "validation_bem.nc").exists()
    assert len(list((out / ".blocks").rglob("*.npz"))) == 1 and _leftovers(out) == []
    solves.clear()
    log = io.StringIO()
    res = engine.run(sc, out, report=Reporter(log, interval=0.0))["base"]["validation_bem"]
    assert len(solves) == 3 and len(set(solves)) == 3
    assert "1 of 4 blocks kept from an interrupted run" in log.getvalue()
    assert "writing: 4/4 blocks (100%)" in log.getvalue()  # off a terminal: one line per task (interval 0 here)
    assert _leftovers(out) == [] and not (out / ".blocks").exists()
    solves.clear()
    whole = engine.run(sc, tmp_path / "whole", report=Reporter(None))["base"]["validation_bem"]
    assert len(solves) == 4
    for var in ("validation_bem_contact_area_ratio", "validation_bem_mean_gap"):
        xr.testing.assert_equal(res[var], whole[var])


def test_a_killed_run_resumes_and_leaves_no_temporary(tmp_path, monkeypatch):
    """A run killed (SIGKILL) after its first kept task: the rerun solves only what was not kept,
    removes the killed run's temporaries, and ends with none."""
    import json
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "out"
    script = ("import json, sys, time\n"
              "import roughcontact.physics.validation as pv\n"
              "real = pv.bem_task\n"
              "def slow(*a, **k):\n"
              "    time.sleep(1.0)\n"
              "    return real(*a, **k)\n"
              "pv.bem_task = slow\n"
              "from roughcontact import engine, scene\n"
              "engine.run(scene.from_dict(json.loads(sys.argv[1])), sys.argv[2], report=engine.Reporter(None),\n"
              "           scheduler='synchronous')\n")
    proc = subprocess.Popen([sys.executable, "-c", script, json.dumps(LADDER), str(out)])
    try:
        deadline = time.monotonic() + 300
        while not list((out / ".blocks").rglob("*.npz")) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    kept = len(list((out / ".blocks").rglob("*.npz")))
    assert 1 <= kept < 4 and not (out / "validation_bem.nc").exists()
    assert _leftovers(out)  # the killed run's result being written
    solves = _count_solves(monkeypatch)
    engine.run(scenes.from_dict(LADDER), out, report=engine.Reporter(None))
    assert len(solves) == 4 - kept
    assert _leftovers(out) == [] and not (out / ".blocks").exists()


def test_no_dask_warning_reaches_the_user(tmp_path, monkeypatch):
    """Many one-task blocks make dask warn ("Increasing number of chunks by factor of 12"): the
    engine's choice of chunks, not the user's, so it is not shown."""
    import warnings

    import roughcontact.physics.validation as pv

    monkeypatch.setattr(pv, "bem_task", lambda *a, **k: np.full((np.size(a[5]), 3), 0.5))
    raw = {**LADDER, "interface": {"eta": [0.0, 0.5, -1.0]},
           "validation": {**LADDER["validation"], "hurst": [0.5, 0.8], "bandwidth": [4, 8]}}
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        engine.run(scenes.from_dict(raw), tmp_path, report=engine.Reporter(None))
    assert [str(w.message) for w in seen if "dask" in w.filename or "chunks" in str(w.message)] == []
