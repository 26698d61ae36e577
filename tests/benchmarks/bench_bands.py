"""Benchmark of the uncertainty bands: their cost against the single prediction, and whether a
linearisation would do.

Run: ``python tests/benchmarks/bench_bands.py [--smoke]`` from the repository root (not collected by
pytest). ``--smoke``: 5 draws, 10 pressures, one run each, the linearisation over two bins (seconds).

Surfaces: the built-in example containers (pipeline/scenes/data/substrate.zip, solid.zip), at
three constant coherences eta = 0, +0.5, -0.5 (3 eta), 100 pressures from 1 kPa to 3 MPa, at
the top magnification (the whole measured band).

1. Cost. The single prediction (A/A0(p) and u(p): psd, contact and separation stages) against
   the same with ``[bands] draws = 200`` plus the bands stage (quantiles), both through the
   engine, the containers' topography stage computed beforehand (it does not depend on the
   draws and is reused by both), 5 runs each, interleaved; median wall and process (CPU, all
   threads) times. The draws are a sweep dimension: every kernel runs once over
   (draw, eta, p), vectorised, in dask blocks. The ratio is the number to read (target <= 10x,
   issue 27). A third case, interleaved with the two, runs the bands with the separation
   kernel's E1 from scipy (below 1; Abramowitz & Stegun above), as before issue 27: the
   before/after of the numpy E1 (physics/special.py) in one run.
2. Linearisation. The delta-method band f0 +- 1.645 sigma, sigma^2 = sum over bins k of
   (d f / d ln C_k)^2 (s_k / C_k)^2 (finite differences through the same stage functions, one
   bin at a time), against the quantiles of the 200 draws, for A/A0 and u at three pressures.
"""

from __future__ import annotations

import io
import tempfile
import time
from pathlib import Path

import numpy as np
from _bench import SMOKE, stage_result

import roughcontact.physics.separation as separation_kernels
from roughcontact import engine, scene
from roughcontact.physics.special import exp1_fast

OUT = Path("outputs/bench_bands") if not SMOKE else Path(tempfile.mkdtemp(prefix="bench-bands-"))
DRAWS, PRESSURES, RUNS, BINS = (200, 100, 5, None) if not SMOKE else (5, 10, 1, 2)


def _scene(draws: int, zeta):
    raw = dict(scene.load("container").raw)
    raw.pop("variants")
    outputs = ["contact_area_ratio", "mean_separation"]
    if draws:
        outputs += ["contact_area_ratio_band", "mean_separation_band"]
    raw.update(interface={"eta": [0.0, 0.5, -0.5]}, load={"p": {"from": "1 kPa", "to": "3 MPa", "num": PRESSURES}},
               contact={"zeta": zeta}, bands={"draws": draws}, outputs={"variables": outputs})
    return scene.from_dict(raw, scene.resolve("container"))


def _timed(sc, force):
    stream = io.StringIO()
    t0 = time.perf_counter()
    res = engine.run(sc, OUT, force=force, report=engine.Reporter(stream))
    return time.perf_counter() - t0, res["base"], stream.getvalue()


def _scipy_e1(x):
    """The separation kernel's E1 before issue 27: scipy's exp1 below 1, A&S 5.1.56 above."""
    import scipy.special

    x = np.asarray(x, dtype=float)
    out = exp1_fast(x)
    low = x < 1.0
    out[low] = scipy.special.exp1(x[low])
    return out


def _predict(sc, topo, picks):
    """A/A0 and u at the pressures ``picks`` (indices), eta = 0, through the psd, contact and
    separation stages' own functions."""
    psd = stage_result("psd", sc, {"topography": topo})
    area = stage_result("contact", sc, {"psd": psd})["contact_area_ratio"]
    gap = stage_result("separation", sc, {"psd": psd})["mean_separation"]
    sel = dict(eta=0.0, zeta=area["zeta"].values[-1])
    return (area.sel(sel).isel(p=picks).values, gap.sel(sel).isel(p=picks).values)


def linearised_band(sc, topo, picks, eps=1e-3):
    """f0 +- 1.645 sigma from one-bin-at-a-time finite differences in ln C."""
    f0 = np.array(_predict(sc, topo, picks))
    var = np.zeros_like(f0)
    for name in ("substrate", "solid"):
        C, err = topo[f"psd_{name}_measured"].values, topo[f"psd_{name}_measured_error"].values
        for k in np.flatnonzero(np.isfinite(C) & (C > 0))[:BINS]:
            bumped = topo.copy(deep=True)
            bumped[f"psd_{name}_measured"].values[k] *= np.exp(eps)
            df = (np.array(_predict(sc, bumped, picks)) - f0) / eps
            var += (df * err[k] / C[k]) ** 2
    return f0, f0 - 1.645 * np.sqrt(var), f0 + 1.645 * np.sqrt(var)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    first = engine.run(_scene(0, "all"), OUT, targets=("psd_combined",), report=engine.Reporter(None))["base"]
    q = first["psd"]["q"].values
    zeta = [float(q[-1] / q[0])]
    single, banded = _scene(0, zeta), _scene(DRAWS, zeta)
    for title, redo in (("the stages the draws change (psd, contact, separation [+ bands]; topography reused)",
                         ("psd", "contact", "separation", "bands")),
                        ("end to end (the containers read and merged: + topography)",
                         ("topography", "psd", "contact", "separation", "bands"))):
        cases = {"single": single, "bands": banded, "bands, scipy E1": banded}
        walls, cpus, runs = {name: [] for name in cases}, {name: [] for name in cases}, []
        for _ in range(RUNS):  # interleaved, so that the load of a shared machine hits every case alike
            for name, sc in cases.items():
                used = {st.name for st in engine.needed_stages(sc, sc.outputs)}  # the single one runs no bands
                separation_kernels.exp1_fast = _scipy_e1 if "scipy" in name else exp1_fast
                c0 = time.process_time()
                try:
                    wall, res_, log_ = _timed(sc, tuple(stage for stage in redo if stage in used))
                finally:
                    separation_kernels.exp1_fast = exp1_fast
                walls[name].append(wall)
                cpus[name].append(time.process_time() - c0)
                if name == "bands":
                    runs.append((wall, res_, log_))
        _, res, log = sorted(runs, key=lambda r: r[0])[len(runs) // 2]
        wall, cpu = ({k: float(np.median(v)) for k, v in d.items()} for d in (walls, cpus))
        print(f"-- {title}, 3 eta x {PRESSURES} p")
        for name, label in (("single", "single prediction"), ("bands", f"with bands ({DRAWS} draws + quantiles)"),
                            ("bands, scipy E1", "the same, the E1 of before (scipy's exp1)")):
            print(f"{label + ':':44s} wall {wall[name]:6.2f} s, cpu {cpu[name]:6.2f} s")
        for name in ("bands", "bands, scipy E1"):
            print(f"ratio {name:16s} / single (median of {RUNS} interleaved runs): wall "
                  f"{wall[name] / wall['single']:.1f}x, cpu {cpu[name] / cpu['single']:.1f}x; per round (wall): "
                  + ", ".join(f"{b / a:.1f}" for a, b in zip(walls["single"], walls[name], strict=True))
                  + (f"  (target <= 10x; {DRAWS} separate predictions: ~{DRAWS}x)" if name == "bands" else ""))
        # the engine's progress lines: "[2/5] psd: computed in 0.51 s (...) -> path"
        print("stage times with bands:", "; ".join(line.split(": computed in ")[0].split("] ")[1] + " "
                                                  + line.split("computed in ")[1].split(" s")[0] + " s"
                                                  for line in log.splitlines() if "computed in" in line))

    picks = [10, 50, 90] if not SMOKE else [1, 5, 9]
    p = res["contact"]["p"].values[picks]
    topo = res["topography"]
    t0 = time.perf_counter()
    f0, lo_lin, hi_lin = linearised_band(single, topo, picks)
    t_lin = time.perf_counter() - t0
    sel = dict(eta=0.0, zeta=zeta[0])
    print(f"\nlinearisation ({t_lin:.1f} s, one stage pass per bin and surface) against the {DRAWS} draws, eta = 0:")
    print(" quantity   p (Pa)     measured     draws 5%     draws 95%    linear 5%    linear 95%"
          "   edge error / band width")
    for j, (name, var, scale) in enumerate((("A/A0", "contact_area_ratio", 1.0), ("u (nm)", "mean_separation", 1e9))):
        band = res["bands"][f"{var}_band"].sel(sel).isel(p=picks).values * scale
        for i in range(len(picks)):
            lo, hi = band[0, i], band[-1, i]
            worst = max(abs(lo_lin[j, i] * scale - lo), abs(hi_lin[j, i] * scale - hi)) / (hi - lo)
            print(f" {name:8s} {p[i]:9.3g} {f0[j, i] * scale:12.5g} {lo:12.5g} {hi:12.5g} {lo_lin[j, i] * scale:12.5g} "
                  f"{hi_lin[j, i] * scale:12.5g}   {worst:6.2f}")


if __name__ == "__main__":
    main()
