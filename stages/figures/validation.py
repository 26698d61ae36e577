"""Figures of the validation stage: kappa = (A/A0) E* g / p against p / (E* g) (the form the
field uses: Hyun et al., Phys. Rev. E 70, 026117 (2004); Prodanov, Dapp & Müser, Tribol. Lett.
53, 433 (2014)) and the mean separation's theory / BEM ratios."""

from __future__ import annotations

from .common import eta_label, style

#: line style of each theory variant (colour and marker are the eta case's, as in every figure)
_LINES = {"persson": "-", "yang_persson": "--", "wang_mueser": ":"}
_LABELS = {"persson": "eq 19 / eq 57 (Persson)", "yang_persson": "Yang-Persson", "wang_mueser": "Wang-Mueser"}


def _cases(ds):
    """(bandwidth index, eta index, label, case style, marker face) of each case of one H: the
    colour and marker of the eta case, filled for the first bandwidth and open for the others."""
    out = []
    for b, zeta in enumerate(ds["bandwidth"].values):
        for e, eta in enumerate(ds["eta"].values):
            case = style(eta_label(eta))
            out.append((b, e, f"zeta = {zeta:g}, {eta_label(eta)}", case, case["color"] if b == 0 else "white"))
    return out


def _legend(fig, ds, band_label):
    """One legend below the panels: the eta cases (colour, marker), the bandwidths (filled, open),
    the theory variants (line styles) and the agreement band."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Line2D([], [], linestyle="none", label=eta_label(e), **{k: v for k, v in style(eta_label(e)).items()
                                                                        if k != "linestyle"}) for e in ds["eta"].values]
    handles += [Line2D([], [], color="0.3", marker="o", linestyle="none", markerfacecolor="0.3" if b == 0 else "white",
                       label=f"bandwidth zeta = {z:g}") for b, z in enumerate(ds["bandwidth"].values)]
    handles += [Line2D([], [], color="0.2", linestyle=_LINES.get(str(n), "-."), label=_LABELS.get(str(n), str(n)))
                for n in ds["theory"].values]
    handles.append(Patch(color="0.85", label=band_label))
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=min(len(handles), 5))


def figure_kappa(results):
    """kappa against p/(E* g), one column per H: theory variants as lines, the BEM (extrapolated
    to zero pixel size) with its error bar; below, each variant's A/A0 theory / BEM."""
    import matplotlib.pyplot as plt

    ds = results["base"]["validation"]
    H = ds["hurst"].values
    fig, axes = plt.subplots(2, H.size, figsize=(4.6 * H.size, 8.8), squeeze=False, sharex=True, layout="constrained")
    x = ds["reduced_pressure"].values
    for c, h in enumerate(H):
        d = ds.isel(hurst=c)
        top, bottom = axes[0, c], axes[1, c]
        for name in d["theory"].values:
            t = d["validation_kappa_theory"].sel(theory=name).isel(bandwidth=0, eta=0)
            top.semilogx(x, t, _LINES.get(str(name), "-."), color="0.2", linewidth=1.6)
        for b, e, _label, case, face in _cases(d):
            dd = d.isel(bandwidth=b, eta=e)
            k = dd["validation_kappa_bem"].values
            err = (dd["validation_bem_area_error"] / dd["reduced_pressure"]).values
            top.errorbar(x, k, yerr=err, fmt=case["marker"], color=case["color"], markerfacecolor=face, markersize=4,
                         capsize=2, linestyle="none")
            for name in d["theory"].values:
                r = dd["validation_area_ratio"].sel(theory=name)
                bottom.semilogx(x, r, _LINES.get(str(name), "-."), marker=case["marker"], color=case["color"],
                                markerfacecolor=face, markersize=3, linewidth=0.7, alpha=0.8)
        bottom.axhspan(0.93, 1.07, color="0.85", zorder=0)
        bottom.axhline(1.0, color="0.4", linewidth=0.8)
        top.set_title(f"H = {h:g}", fontsize=10)
        top.set_ylabel("kappa = (A/A0) E* g / p")
        top.set_ylim(0.0, 3.0)
        bottom.set_ylabel("A/A0: theory / BEM")
        bottom.set_ylim(0.5, 1.3)
        bottom.set_xlabel("p / (E* g)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    fig.suptitle("Contact area: theory variants (lines; black above: the first case) against the BEM (points: "
                 "extrapolated to zero pixel size;\nerror bars: realizations and extrapolation)", fontsize=10)
    _legend(fig, ds, "+-7 %")
    return fig


def figure_separation_ratio(results):
    """The mean separation: theory / BEM per variant against p/(E* g), one panel per H; filled
    markers where the BEM's A/A0 > 0.01 (the range of the table)."""
    import matplotlib.pyplot as plt

    ds = results["base"]["validation"]
    H = ds["hurst"].values
    fig, axes = plt.subplots(1, H.size, figsize=(4.6 * H.size, 5.0), squeeze=False, sharey=True, layout="constrained")
    x = ds["reduced_pressure"].values
    for c, h in enumerate(H):
        d, ax = ds.isel(hurst=c), axes[0, c]
        for b, e, _label, case, face in _cases(d):
            dd = d.isel(bandwidth=b, eta=e)
            inside = (dd["validation_bem_area"] > 0.01).values
            for name in d["theory"].values:
                r = dd["validation_gap_ratio"].sel(theory=name).values
                ax.semilogx(x, r, _LINES.get(str(name), "-."), color=case["color"], linewidth=0.7, alpha=0.7)
                ax.semilogx(x[inside], r[inside], case["marker"], color=case["color"], markerfacecolor=face,
                            markersize=3.5, linestyle="none")
        ax.axhspan(0.85, 1.15, color="0.85", zorder=0)
        ax.axhline(1.0, color="0.4", linewidth=0.8)
        ax.set_title(f"H = {h:g} (markers where BEM A/A0 > 0.01)", fontsize=9)
        ax.set_xlabel("p / (E* g)")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("mean separation: theory / BEM")
    axes[0, 0].set_ylim(0.0, 2.0)
    fig.suptitle("Mean separation: theory variants against the BEM (finest rung, mean over realizations)", fontsize=10)
    _legend(fig, ds, "+-15 %")
    return fig
