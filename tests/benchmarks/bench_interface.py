"""The exact check of the stiffness and leakage theories at a useful size: the interface_bem stage
on synthesized pairs (default 256^2, 4 realizations) and on the two example height maps, with
a table of theory/exact ratios over p and the comparison figure.

    python tests/benchmarks/bench_interface.py [--grid 256] [--realizations 4] [--outdir DIR] [--figure PNG] [--smoke]

Prints, per case, a Markdown table: p/E*, the BEM's contact area, the exact leak rate, the
critical-junction and effective-medium ratios to it, and the stiffness ratio; then the sealing
loads (theory and BEM) and the contact area at the BEM's sealing load. Wall time per case.
--smoke: one 32^2 pair, the measured maps left out (seconds, for CI).
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from roughcontact import engine, scene as scenes
from roughcontact.stage import stages

E_STAR = 77.2e9 / (1 - 0.42**2)
SURFACE = {"kind": "self_affine", "H": 0.8, "qL": "2e8 1/m", "q0": "8e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}
LEAKAGE = {"viscosity": "1 mPa*s", "pressure_drop": "1 kPa", "seal_width": "1 mm", "seal_length": "1 mm"}


def synthesized(grid, realizations):
    return {
        "name": "bench-interface", "substrate": dict(SURFACE), "solid": dict(SURFACE), "interface": {"eta": [0.0]},
        "material": {"E": "77.2 GPa", "nu": 0.42},
        "load": {"p": [f"{E_STAR * float(x)!r} Pa" for x in np.geomspace(0.003, 0.3, 7)]},
        "leakage": dict(LEAKAGE),
        "bem": {"grid": grid, "realizations": realizations, "seed": 1, "pixels_per_wavelength": 4},
        "outputs": {"variables": ["exact_leak_rate"]}, "numerics": {"points_per_decade": 20},
    }


def measured():
    """The built-in bem_topography scene (two example maps, measured coherence) plus a seal."""
    path = Path(scenes.builtin_scenes()["bem_topography"])
    raw = tomllib.loads(path.read_text())
    raw["leakage"] = dict(LEAKAGE)
    raw["load"] = {"p": {"from": "10 kPa", "to": "2 MPa", "num": 6, "spacing": "log"}}
    raw["outputs"] = {"variables": ["exact_leak_rate"]}
    return raw, path


def table(ds) -> str:
    ds = ds.isel(eta=0) if "eta" in ds.dims else ds
    E = float(ds["E_star"])
    rows = ["| p/E* | A/A0 (BEM) | Q exact (m^3/s) | Q_CJ / Q_exact | Q_EMT / Q_exact | K theory / K BEM |",
            "|---|---|---|---|---|---|"]
    area = ds["exact_contact_area_ratio"].mean("realization")
    for i, p in enumerate(ds["p"].values):
        rows.append(f"| {p / E:.3g} | {float(area[i]):.3f} | {float(ds['exact_leak_rate'][i]):.3g} | "
                    f"{float(ds['leak_ratio_critical_junction_to_exact'][i]):.3g} | "
                    f"{float(ds['leak_ratio_effective_medium_to_exact'][i]):.3g} | "
                    f"{float(ds['stiffness_ratio_theory_to_exact'][i]):.3g} |")
    seal = ds["exact_sealing_pressure"].values / E
    rows.append("")
    rows.append(f"sealing load p/E*: BEM {np.nanmean(seal):.3g} (+- {np.nanstd(seal):.2g} over {seal.size} pair(s)), "
                f"A/A0 there {np.nanmean(ds['exact_percolation_area'].values):.3f}; critical junction "
                f"{float(ds['theory_sealing_pressure_critical_junction']) / E:.3g}, effective medium "
                f"{float(ds['theory_sealing_pressure_effective_medium']) / E:.3g}")
    return "\n".join(rows)


def run(raw, outdir, path=None):
    sc = scenes.from_dict(raw, path)
    t0 = time.perf_counter()
    res = engine.run(sc, outdir, report=engine.Reporter(None))["base"]
    return res["interface_bem"], time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=256)
    parser.add_argument("--realizations", type=int, default=4)
    parser.add_argument("--outdir", type=Path, default=None)
    parser.add_argument("--figure", type=Path, default=None, help="write the synthesized case's figure here")
    parser.add_argument("--skip-measured", action="store_true")
    parser.add_argument("--smoke", action="store_true", help="one 32^2 pair, no measured maps (seconds)")
    args = parser.parse_args()
    if args.smoke:
        args.grid, args.realizations, args.skip_measured = 32, 1, True
    outdir = args.outdir or Path(tempfile.mkdtemp(prefix="bench-interface-"))
    ds, seconds = run(synthesized(args.grid, args.realizations), outdir / "synthesized")
    print(f"## synthesized pairs, {args.grid}^2, {args.realizations} realizations, zeta = {ds.attrs['bem_zeta']:.4g} "
          f"({seconds:.0f} s)\n")
    print(table(ds))
    if args.figure:
        figure = next(f for f in stages()["interface_bem"].figures)
        figure.make({"base": {"interface_bem": ds}}).savefig(args.figure, dpi=110)
        print(f"\nfigure: {args.figure}")
    if not args.skip_measured:
        raw, path = measured()
        ds, seconds = run(raw, outdir / "measured", path)
        print(f"\n## the two example maps (bem_topography), zeta = {ds.attrs['bem_zeta']:.4g} ({seconds:.0f} s)\n")
        print(table(ds))


if __name__ == "__main__":
    main()
