"""Benchmark of elastoplastic contact: the contact stage with ``contact.yield_stress`` (A/A0, A_el/A0,
A_pl/A0) against the plain elastic stage (A/A0), and the kernels alone.

Run: ``python tests/benchmarks/bench_plasticity.py [--smoke]`` from the repository root (not collected by
pytest). ``--smoke``: 10 pressures, one run each (seconds).

Surfaces: the built-in ``elastoplastic`` scene (a ground mild-steel pair, sigma_Y = 1.2 GPa), 100
pressures from 1 MPa to 1 GPa x 3 coherences (eta = 0, +-0.5), at the scene's three magnifications and
at every node of the q grid (``contact.zeta = "all"``). The psd stage is computed once beforehand (both
runs read it); the contact stage's compute runs 7 times each, best time reported. Times are CPU times of
this process (time.process_time: numpy here is single-threaded), which a machine shared with other jobs
disturbs far less than wall-clock times. The target (issue 28): the elastoplastic stage costs at most 3x
the elastic one. The ratio is the number to read; no time is asserted.
"""

from __future__ import annotations

import time

import numpy as np
from _bench import SMOKE, stage_result

from roughcontact import scene
from roughcontact.physics.contact import contact_area_ratio
from roughcontact.physics.plasticity import elastic_area_ratio, elastoplastic_areas, plastic_area_ratio
from roughcontact.stage import StageInput, stages

PRESSURES, RUNS = (100, 7) if not SMOKE else (10, 1)
PLASTIC = frozenset({"elastic_contact_area_ratio", "plastic_contact_area_ratio"})


def _scene(zeta):
    raw = dict(scene.load("elastoplastic").raw)
    raw["load"] = {"p": {"from": "1 MPa", "to": "1 GPa", "num": PRESSURES, "spacing": "log"}}
    raw["contact"] = {**raw["contact"], "zeta": zeta}
    return scene.from_dict(raw, scene.resolve("elastoplastic"))


def _contact(sc, psd, wanted, yield_stress):
    st = stages()["contact"]
    values = {k: st.section_view(k, sc.get(k)) for k in st.keys}
    values["contact.yield_stress"] = yield_stress
    return st.compute(StageInput(params=values, upstream={"psd": psd}, wanted=wanted, stage="contact"))


def _best(fn):
    times = []
    for _ in range(RUNS):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def stage_table():
    print(f"## contact stage: {PRESSURES} pressures x 3 eta, best of {RUNS}")
    print("| magnifications | elastic (ms) | elastoplastic (ms) | ratio |")
    print("|---|---|---|---|")
    for zeta in ([3.0, 10.0, 1000.0], "all"):
        sc = _scene(zeta)
        psd = stage_result("psd", sc)
        Y = float(sc.get("contact")["yield_stress"])
        ds = _contact(sc, psd, PLASTIC, Y)  # once, to check what it computes
        assert {"elastic_contact_area_ratio", "plastic_contact_area_ratio"} <= set(ds)
        t_el = _best(lambda sc=sc, psd=psd: _contact(sc, psd, frozenset(), None))
        t_pl = _best(lambda sc=sc, psd=psd, Y=Y: _contact(sc, psd, PLASTIC, Y))
        label = f"{ds.sizes['zeta']} ({'all q nodes' if zeta == 'all' else 'the scene'})"
        print(f"| {label} | {t_el * 1e3:.1f} | {t_pl * 1e3:.1f} | {t_pl / t_el:.2f} |")


def kernel_table():
    rng = np.random.default_rng(0)
    n = 300_000 if not SMOKE else 3000
    Y = 1.2e9
    p = rng.uniform(0.0, 0.999, n) * Y
    G = 10.0 ** rng.uniform(-4.0, 2.0, n) * Y**2
    t_erf = _best(lambda: contact_area_ratio(p, G))
    t_el = _best(lambda: elastic_area_ratio(p, G, Y))
    t_pl = _best(lambda: plastic_area_ratio(p, G, Y))
    t_both = _best(lambda: elastoplastic_areas(p, G, Y))
    print(f"\n## kernels alone: {n} points, G / sigma_Y^2 log-uniform in [1e-4, 1e2] (both forms), best of {RUNS}")
    print("| kernel | time (ms) | per point (ns) | / eq 19 |")
    print("|---|---|---|---|")
    rows = (("eq 19 erf (elastic)", t_erf), ("A_el/A0", t_el), ("A_pl/A0", t_pl), ("both at once (the stage)", t_both))
    for name, t in rows:
        print(f"| {name} | {t * 1e3:.1f} | {t / n * 1e9:.0f} | {t / t_erf:.1f} |")


if __name__ == "__main__":
    stage_table()
    kernel_table()
