"""Scale-out: stages only build dask graphs; results are the same on threads, processes and a
dask.distributed cluster; a sweep larger than a worker's memory limit completes."""

import dask
import numpy as np
import pytest
import xarray as xr
from conftest import SURFACE, make_scene

from roughcontact import engine, scene as scenes
from roughcontact.scheduling import auto_chunks
from roughcontact.stage import StageInput, stages

PROVENANCE = ("history", "date_created", "git_commit", "scene", "data_checksum")


def _strip(ds):
    ds = ds.copy()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k not in PROVENANCE}
    return ds


def _sweep_scene(num_p=40, **kw):
    return make_scene(substrate=dict(SURFACE, hrms=["0.5 nm", "1 nm", "2 nm"]),
                      load={"p": {"from": "1 MPa", "to": "10 GPa", "num": num_p}},
                      outputs={"variables": ["stress_distribution"]},
                      numerics={"points_per_decade": 20, "chunks": {"p": 9, "eta": 2}}, **kw)


def test_stages_never_compute_while_building_the_graph(tmp_path):
    """Under a default scheduler that refuses to compute, every stage builds its graph; the one
    exception, a small intermediate every block needs (StageInput.shared), names its scheduler."""
    sc = scenes.from_dict(_sweep_scene())
    psd_result = engine.run(sc, tmp_path, targets=["psd_combined"], report=engine.Reporter(None))["base"]["psd"]
    contact = stages()["contact"]
    plan = [p for p in engine.plan(sc, tmp_path) if p.stage.name == "contact"][0]
    lazy_psd = psd_result.chunk({"eta": 1, "hrms_substrate": 2})

    def refuse(*args, **kwargs):
        raise AssertionError("dask computed while the stage built its graph")

    inp = StageInput(params=plan.params, upstream={"psd": lazy_psd}, wanted=plan.wanted,
                     chunks={"p": 9, "eta": 1, "hrms_substrate": 2})
    with dask.config.set(scheduler=refuse):
        ds = contact.compute(inp)
    assert ds["contact_area_ratio"].chunks is not None
    assert ds["stress_distribution"].chunks is not None


def test_processes_scheduler_gives_identical_results(tmp_path):
    raw = _sweep_scene()
    a = engine.run(scenes.from_dict(raw), tmp_path / "threads", report=engine.Reporter(None))
    b = engine.run(scenes.from_dict(raw), tmp_path / "procs", report=engine.Reporter(None), scheduler="processes")
    for stage in ("psd", "contact"):
        xr.testing.assert_identical(_strip(a["base"][stage]), _strip(b["base"][stage]))


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, memory_limit="400MB",
                                  dashboard_address=None) as c:
        yield c


def test_local_cluster_result_is_identical_to_threaded(tmp_path, cluster):
    raw = _sweep_scene()
    threaded = engine.run(scenes.from_dict(raw), tmp_path / "threads", report=engine.Reporter(None))
    on_cluster = engine.run(scenes.from_dict(raw), tmp_path / "cluster", report=engine.Reporter(None),
                            scheduler=cluster.scheduler_address)
    for stage in ("psd", "contact"):
        xr.testing.assert_identical(_strip(threaded["base"][stage]), _strip(on_cluster["base"][stage]))


def test_sweep_larger_than_worker_memory_completes(tmp_path, cluster):
    # 2e3 p x 3 eta x 40 hrms x 116 zeta = 2.8e7 points = 220 MB of output per variable: more than
    # half a worker's 400 MB limit unchunked (with its temporaries, several times the limit)
    raw = make_scene(substrate=dict(SURFACE, hrms={"from": "0.2 nm", "to": "5 nm", "num": 40}),
                     load={"p": {"from": "1 MPa", "to": "100 GPa", "num": 2000}},
                     contact={"zeta": "all"}, numerics={"points_per_decade": 50, "chunk_mb": 16})
    sc = scenes.from_dict(raw)
    res = engine.run(sc, tmp_path / "big", report=engine.Reporter(None), scheduler=cluster.scheduler_address)
    area = res["base"]["contact"]["contact_area_ratio"]
    assert area.size * 8 > 200e6
    assert float(area.min()) >= 0.0 and float(area.max()) <= 1.0
    # spot check against a small direct computation at one hrms
    picks = area["p"].values[[0, 1234]]
    small = make_scene(substrate=dict(SURFACE, hrms=f"{float(area['hrms_substrate'][7]) * 1e9!r} nm"),
                       load={"p": [f"{float(v)!r} Pa" for v in picks]}, contact={"zeta": "all"},
                       numerics={"points_per_decade": 50})
    ref = engine.run(scenes.from_dict(small), tmp_path / "small", report=engine.Reporter(None))["base"]["contact"]
    got = area.isel(hrms_substrate=7).sel(p=picks)
    np.testing.assert_allclose(got.transpose(*ref["contact_area_ratio"].dims).values,
                               ref["contact_area_ratio"].values, rtol=1e-12)


def test_auto_chunks_respect_the_budget_and_explicit_sizes():
    sizes = {"p": 1000, "eta": 21, "hrms_substrate": 41}
    chunks = auto_chunks(sizes, 50_000, {"eta": 3})
    full = {d: chunks.get(d, n) for d, n in sizes.items()}
    assert full["eta"] == 3
    assert np.prod(list(full.values())) <= 50_000
    assert auto_chunks(sizes, 1e12) == {}


def test_a_small_intermediate_every_block_needs_is_computed_once(tmp_path, monkeypatch):
    """G (per eta and hrms) is needed by every block of pressures: computed once per G block, not
    once per batch of blocks of the area (the large sweep computed it 512 times), same values."""
    import roughcontact.stages.contact as contact_stage

    raw = _sweep_scene(num_p=60)
    with monkeypatch.context() as m:  # G left lazy, as before: computed again for every batch of area blocks
        m.setattr(StageInput, "shared", lambda self, value: value)
        reference = engine.run(scenes.from_dict(raw), tmp_path / "reference", report=engine.Reporter(None))
    calls = []
    real = contact_stage.persson_G
    monkeypatch.setattr(contact_stage, "persson_G", lambda *a, **k: calls.append(1) or real(*a, **k))
    again = engine.run(scenes.from_dict(raw), tmp_path / "again", force=("contact",), report=engine.Reporter(None))
    assert len(calls) == 2  # G's blocks (eta in 2 chunks); lazy, a block per batch of 4 of the 14 area blocks
    xr.testing.assert_identical(_strip(reference["base"]["contact"]), _strip(again["base"]["contact"]))
