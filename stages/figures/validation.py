"""Figures of the validation stage: kappa = (A/A0) E* g / p against p / (E* g) (the form the
field uses: Hyun et al., Phys. Rev. E 70, 026117 (2004); Prodanov, Dapp & Müser, Tribol. Lett.
53, 433 (2014)) and the mean separation's theory / BEM ratios."""

from __future__ import annotations

import numpy as np

_COLORS = {"persson": "C3", "yang_persson": "C0", "wang_mueser": "C2"}
_MARKERS = ("o", "s", "^", "D")
_LABELS = {"persson": "eq 19 / eq 57 (Persson)", "yang_persson": "Yang-Persson", "wang_mueser": "Wang-Mueser"}


def _cases(ds):
    """(bandwidth index, eta index, label, marker, face) of each case of one H."""
    out = []
    for b, zeta in enumerate(ds["bandwidth"].values):
        for e, eta in enumerate(ds["eta"].values):
            out.append((b, e, f"zeta = {zeta:g}, eta = {eta:+g}".replace("+0 ", "0 "), _MARKERS[b % len(_MARKERS)],
                        f"C{4 + e}"))
    return out


def figure_kappa(results):
    """kappa against p/(E* g), one column per H: theory variants as lines, the BEM (extrapolated
    to zero pixel size) with its error bar; below, each variant's A/A0 theory / BEM."""
    import matplotlib.pyplot as plt

    ds = results["base"]["validation"]
    H = ds["hurst"].values
    fig, axes = plt.subplots(2, H.size, figsize=(4.6 * H.size, 8.0), squeeze=False, sharex=True)
    x = ds["reduced_pressure"].values
    for c, h in enumerate(H):
        d = ds.isel(hurst=c)
        top, bottom = axes[0, c], axes[1, c]
        for name in d["theory"].values:
            t = d["validation_kappa_theory"].sel(theory=name).isel(bandwidth=0, eta=0)
            top.semilogx(x, t, "-", color=_COLORS.get(str(name), "k"), linewidth=1.6, label=_LABELS.get(str(name), name))
        for b, e, label, marker, face in _cases(d):
            dd = d.isel(bandwidth=b, eta=e)
            k, err = dd["validation_kappa_bem"].values, (dd["validation_bem_area_error"] / dd["reduced_pressure"]).values
            top.errorbar(x, k, yerr=err, fmt=marker, color=face, markersize=4, capsize=2, linestyle="none",
                         label=f"BEM, {label}")
            for name in d["theory"].values:
                r = dd["validation_area_ratio"].sel(theory=name)
                bottom.semilogx(x, r, marker=marker, color=_COLORS.get(str(name), "k"), markersize=3, linewidth=0.7,
                                alpha=0.8, label=_LABELS.get(str(name), name) if (b, e) == (0, 0) else None)
        bottom.axhspan(0.93, 1.07, color="0.85", zorder=0, label="+-7 %")
        bottom.axhline(1.0, color="0.4", linewidth=0.8)
        top.set_title(f"H = {h:g}", fontsize=10)
        top.set_ylabel("kappa = (A/A0) E* g / p")
        top.set_ylim(0.0, 3.0)
        bottom.set_ylabel("A/A0: theory / BEM")
        bottom.set_ylim(0.5, 1.3)
        bottom.set_xlabel("p / (E* g)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=6.5, loc="lower left", ncol=1)
    axes[1, 0].legend(fontsize=7, loc="lower right")
    fig.suptitle("Contact area: theory variants (lines) against the BEM (points: extrapolated to zero pixel size;\n"
                 "error bars: realizations and extrapolation)", fontsize=10)
    fig.tight_layout()
    return fig


def figure_separation_ratio(results):
    """The mean separation: theory / BEM per variant against p/(E* g), one panel per H; filled
    markers where the BEM's A/A0 > 0.01 (the range of the table)."""
    import matplotlib.pyplot as plt

    ds = results["base"]["validation"]
    H = ds["hurst"].values
    fig, axes = plt.subplots(1, H.size, figsize=(4.6 * H.size, 4.2), squeeze=False, sharey=True)
    x = ds["reduced_pressure"].values
    for c, h in enumerate(H):
        d, ax = ds.isel(hurst=c), axes[0, c]
        for b, e, label, marker, _ in _cases(d):
            dd = d.isel(bandwidth=b, eta=e)
            inside = (dd["validation_bem_area"] > 0.01).values
            for name in d["theory"].values:
                r = dd["validation_gap_ratio"].sel(theory=name).values
                color = _COLORS.get(str(name), "k")
                ax.semilogx(x, r, "-", color=color, linewidth=0.7, alpha=0.7,
                            label=_LABELS.get(str(name), name) if (b, e) == (0, 0) else None)
                ax.semilogx(x[inside], r[inside], marker, color=color, markersize=3.5, linestyle="none")
        ax.axhspan(0.85, 1.15, color="0.85", zorder=0, label="+-15 %")
        ax.axhline(1.0, color="0.4", linewidth=0.8)
        ax.set_title(f"H = {h:g} (markers: bandwidth; filled where BEM A/A0 > 0.01)", fontsize=9)
        ax.set_xlabel("p / (E* g)")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("mean separation: theory / BEM")
    axes[0, 0].set_ylim(0.0, 2.0)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    fig.suptitle("Mean separation: theory variants against the BEM (finest rung, mean over realizations)", fontsize=10)
    fig.tight_layout()
    return fig
