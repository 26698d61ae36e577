"""Benchmark: do the 90 % uncertainty bands cover 90 %?

Run: ``python tests/benchmarks/bench_coverage.py [--smoke] [--containers N]`` from the repository root
(not collected by pytest). Full mode: 200 containers per layout; ``--smoke``: 3 (seconds; its
numbers mean nothing).

Each container is one surface measured at two scales, as the example maker
(``pipeline/scenes/data/make_container.py``) builds them: crops (not periodic) of larger
random self-affine surfaces (H = 0.8, roll-off at 2 pi / 20 um, rms 0.4 um), detrended (plane)
and Hann-windowed, the coarse map cut at its optical resolution, the fine one at the tip-radius
cutoff of a 40 nm tip. Two layouts:

* ``A``: 100 um and 10 um maps, 256 x 256 points each (the layout of issue 24);
* ``B``: 40 um and 5 um maps, 64 x 64 points, H = 0.5: its coarsest map has fewer than 5
  independent modes in each of its two lowest bins (printed), and those bins weigh more.

The chain is the stages' own code without the engine's files: ``process_map`` (detrend,
window, reliability cutoff), the topography stage's binned spectra (the detrending's and the
window's bias removed, the window's mode factor within bins and its correlation between bins),
``merged_psd`` / ``merged_correlation``, ``measured_psd_on_grid`` / ``drawn_psd`` (the bins'
correlation drawn by a Gaussian copula; ``--independent``: bins independent) on the psd stage's grid (the
bins' mean wavenumbers as knots), then A/A0 = erf(p / 2 sqrt(G)) at the top magnification at two
pressures (p/E* = 1e-3 and 1e-2) and the mean separation u (eq 57, alpha 0.45) at p/E* = 1e-3.
The truth is the same prediction from the true PSD on the same q grid. A band covers when its
5 % and 95 % quantiles over 200 draws bracket the truth; the coverage's binomial standard error
is sqrt(0.09 / N) (0.021 for N = 200).

``--periodic``: the same surfaces measured as periodic maps without a window (the measured
spectrum then carries only its statistical error): separates the draws' statistics from the
window's and the detrending's bias in the lowest bins of each scan (docs/measured-data.md).
The output gives, per prediction, how often the truth fell below and above the band.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import xarray as xr
from _bench import SMOKE

from roughcontact.physics.contact import contact_area_ratio, persson_G
from roughcontact.physics.estimators import log_bin_edges
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.separation import mean_separation, separation_nodes
from roughcontact.scenes.data.synthetic import self_affine, synthesize, wavevectors
from roughcontact.stages.shared.maps import measured_psd_on_grid, process_map
from roughcontact.stages.shared.measured import drawn_psd, merged_correlation, merged_psd
from roughcontact.stages.topography import _spectra

Q0, HRMS, E_STAR, ALPHA, BPD, PPD = 2 * np.pi / 20e-6, 0.4e-6, 1.0, 0.45, 20, 50
LAYOUTS = {  # name: (H, points, ((side, crop factor, instrument spec), ...))
    "A": (0.8, 256, ((100e-6, 4, {"resolution": 1.5e-6}), (10e-6, 4, {"tip_radius": 40e-9}))),
    "B": (0.5, 64, ((40e-6, 4, {"resolution": 1.5e-6}), (5e-6, 4, {"tip_radius": 40e-9}))),
}
P_AREA, P_SEP = np.array([1e-3, 1e-2]), 1e-3  # p / E*
INDEPENDENT = False  # --independent: the bins drawn independently (the window's correlation between bins left out)


def _maps(layout, rng, periodic=False):
    """The two measurements of one surface, processed as the topography stage processes them."""
    H, n, scales = LAYOUTS[layout]
    big = scales[0][1] * scales[0][0]  # one spectrum for both scales: its expected rms over the largest crop is HRMS
    norm = HRMS**2 / np.sum(self_affine(wavevectors(4 * n, 4 * n, big, big), H, Q0, 1.0) * (2 * np.pi / big) ** 2)
    prepared = []
    for side, crop, instrument in scales:
        big, nb = crop * side, crop * n
        if periodic:
            h = synthesize(lambda q: self_affine(q, H, Q0, norm), n, n, side, side, rng)
        else:
            h = synthesize(lambda q: self_affine(q, H, Q0, norm), nb, nb, big, big, rng)[:n, :n]
        p = dict(h=h, sizes=(side, side), periodic=periodic, detrend="mean" if periodic else "plane",
                 window="none" if periodic else "hann", analysis="area",
                 path=f"{layout}-{side:g}", name="substrate")
        prepared.append(process_map(p, instrument))
    return prepared, lambda q: self_affine(q, H, Q0, norm)


def _topography(prepared):
    """The topography stage's dataset of the merged spectrum of one surface."""
    lo = min(p["q_min"] for p in prepared)
    hi = max(p["q_max"] for p in prepared)
    edges = log_bin_edges(lo, hi, BPD)
    spectra = [_spectra(p, edges, {"hurst": 0.5}) for p in prepared]
    q, C, n, err, _ = merged_psd(spectra)
    keep = n > 0
    ds = xr.Dataset({"psd_substrate_measured": ("q_bin", C[keep]), "psd_substrate_measured_error": ("q_bin", err[keep]),
                     "q_substrate_measured": ("q_bin", q[keep]), "modes_substrate": ("q_bin", n[keep])})
    if not INDEPENDENT:
        ds["psd_substrate_measured_correlation"] = (("q_bin", "q_bin_pair"), merged_correlation(spectra)[keep][:, keep])
    ds.attrs["bins_per_decade"] = BPD
    return ds, [s["n"] for s in spectra]


def _predictions(q, C, p_area, p_sep):
    """A/A0 at p_area (..., 2) and u at p_sep (...,) at the top magnification."""
    G = persson_G(q, C, q[-1:], E_STAR)[..., -1]
    area = contact_area_ratio(p_area, G[..., None])
    s, w, count, _, s_tail, q_tail = separation_nodes(q, C, q[-1:])
    u = mean_separation(np.full(C.shape[:-1], p_sep), s, w, count, s_tail, q_tail, E_star=E_STAR,
                        alpha=ALPHA)[..., -1]
    return np.concatenate([area, u[..., None]], axis=-1)


def one_container(layout, seed, draws, periodic=False):
    """Per prediction (A/A0 at two pressures, u at one): whether the band covers the truth, and
    the band's relative width; and the modes of the coarsest map's two lowest bins."""
    rng = np.random.default_rng([24, ord(layout), seed])
    prepared, true_psd = _maps(layout, rng, periodic)
    ds, modes = _topography(prepared)
    q_bins = ds["q_substrate_measured"].values
    grid = log_grid(q_bins[0], q_bins[-1], PPD, list(q_bins))
    nominal, _ = measured_psd_on_grid(ds, "substrate", grid, "none")
    drawn = drawn_psd(xr.DataArray(np.arange(draws + 1), dims="draw"), ds, "substrate", grid, "none", seed).values
    truth = _predictions(grid, true_psd(grid), P_AREA * E_STAR, P_SEP * E_STAR)
    values = _predictions(grid, drawn[1:], P_AREA * E_STAR, P_SEP * E_STAR)
    lo, hi = np.quantile(values, [0.05, 0.95], axis=0)
    centre = _predictions(grid, nominal[None], P_AREA * E_STAR, P_SEP * E_STAR)[0]
    coarse = modes[0][modes[0] > 0][:2]
    return np.stack([truth < lo, truth > hi]), (hi - lo) / centre, coarse


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true")
    parser.add_argument("--containers", type=int, default=3 if SMOKE else 200)
    parser.add_argument("--draws", type=int, default=20 if SMOKE else 200)
    parser.add_argument("--layouts", default="AB")
    parser.add_argument("--periodic", action="store_true",
                        help="periodic maps of the surface, no window (only the statistical error; no window bias)")
    parser.add_argument("--independent", action="store_true",
                        help="draw the bins independently (without the correlation between bins the window gives)")
    args = parser.parse_args()
    global INDEPENDENT
    INDEPENDENT = args.independent
    names = ["A/A0 at p/E* = 1e-3", "A/A0 at p/E* = 1e-2", "u at p/E* = 1e-3"]
    for layout in args.layouts:
        t0 = time.perf_counter()
        hits, widths, coarse = [], [], []
        for seed in range(args.containers):
            hit, width, low = one_container(layout, seed, args.draws, args.periodic)
            hits.append(hit)
            widths.append(width)
            coarse.append(low)
        misses, widths = np.array(hits), np.array(widths)
        hits = ~misses.any(axis=1)
        error = np.sqrt(0.09 / len(hits))
        H, n, scales = LAYOUTS[layout]
        sides = ", ".join(f"{s * 1e6:g} um" for s, _, _ in scales)
        print(f"layout {layout}{' (periodic, no window)' if args.periodic else ''}: maps {sides}, {n} x {n} points, "
              f"H = {H}; "
              f"{len(hits)} containers, {args.draws} draws; modes of the coarsest map's two lowest bins (mean): "
              f"{np.mean(coarse, axis=0).round(2)}  ({time.perf_counter() - t0:.0f} s)")
        for k, name in enumerate(names):
            print(f"  {name:22s} coverage {hits[:, k].mean():.3f} +- {error:.3f} (truth below the band "
                  f"{misses[:, 0, k].mean():.3f}, above {misses[:, 1, k].mean():.3f})   median band width "
                  f"{np.median(widths[:, k]) * 100:.1f} % of the value")


if __name__ == "__main__":
    main()
