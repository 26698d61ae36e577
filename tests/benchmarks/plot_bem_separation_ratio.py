"""The mean-separation ratio theory / BEM of the two built-in bem scenes against p / (E* g):
docs/bem.md, "The separation ratio". Runs (or reuses) `bem` and `bem_topography` into
OUTDIR and writes docs/img/bem-separation-ratio.png.

    python tests/benchmarks/plot_bem_separation_ratio.py [OUTDIR] [--smoke]

--smoke: zeta = 8 (bem: a 32^2 grid, one realization; bem_topography: 32 pixels per wavelength),
into a temporary folder, the figure written there too (not into docs/; seconds, for CI).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from _bench import ROOT, SMOKE, positional  # noqa: E402

from roughcontact import engine, scene  # noqa: E402
from roughcontact.accuracy import with_settings  # noqa: E402
from roughcontact.stages.figures.bem import reduced_pressure  # noqa: E402

STYLES = {"persson": "-", "yang_persson": "--", "wang_mueser": ":"}


def _scene(name):
    sc = scene.load(name)
    if not SMOKE:
        return sc
    # zeta = 8: grid 32 / 4 pixels per wavelength (bem), 256 / 32 (bem_topography, whose maps are 256^2)
    small = {"bem.grid": 32, "bem.realizations": 1} if name == "bem" else {"bem.pixels_per_wavelength": 32,
                                                                            "numerics.points_per_decade": 20}
    return with_settings(sc, {**small, "contact.zeta": [8.0]})


def main(outdir: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.3))
    for name, marker in (("bem", "o"), ("bem_topography", "s")):
        ds = engine.run(_scene(name), outdir / name)["base"]["bem"]
        if "eta" in ds.dims:
            ds = ds.sel(eta=0.0)
        x = reduced_pressure(ds).values
        xs = ds["p"].values / float(ds["E_star"])
        label = "synthesized (bem, eta = 0)" if name == "bem" else "measured maps (bem_topography)"
        for k, theory in enumerate(ds["theory"].values):
            r = ds["separation_ratio_variant_to_bem"].sel(theory=theory).values
            axes[0].semilogx(xs, r, STYLES[str(theory)], marker=marker, color=f"C{k}", markersize=4,
                             label=f"{theory}, {label}")
            axes[1].semilogx(x, r, STYLES[str(theory)], marker=marker, color=f"C{k}", markersize=4)
    for ax, xlabel in ((axes[0], "p / E*"), (axes[1], "p / (E* g), g = rms slope of the BEM composite")):
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("mean separation: theory / BEM")
        ax.set_ylim(0, 1.5)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[0].set_title("against p/E*: the two scenes differ", fontsize=9)
    axes[1].set_title("against p/(E* g): one curve per theory", fontsize=9)
    fig.suptitle("Mean separation, theory / BEM: eq 57 with alpha = 0.45 (persson), Yang-Persson, Wang-Mueser")
    fig.tight_layout()
    target = (ROOT / "docs" / "img" if not SMOKE else outdir) / "bem-separation-ratio.png"
    fig.savefig(target, dpi=110)
    print(target)


if __name__ == "__main__":
    args = positional(sys.argv[1:])
    main(Path(args[0]) if args else Path("outputs/bem-separation-ratio") if not SMOKE else Path(tempfile.mkdtemp()))
