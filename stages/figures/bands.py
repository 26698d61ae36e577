"""Figures of the bands stage: predictions over the whole measured band (the largest
magnification) with their uncertainty bands, and the combined PSD with its band."""

from __future__ import annotations

import numpy as np

from .common import EDGES, case_of, eta_label, legend_outside, scope_text, shade, style


def _label(variant: str, eta, res) -> tuple[str, str]:
    """(legend label, case of :data:`~.common.CASE_STYLES`) of one curve."""
    case = eta_label(eta) if eta is not None else case_of(res)
    return (case if variant == "base" else f"{variant.replace('_', ' ')}: {case}"), case


def _where(results, zeta) -> str:
    """'the whole measured band' when zeta is the top of the q grid, else the magnification."""
    psd = results["base"].get("psd")
    if zeta is None:
        return ""
    top = float(psd["q"].values[-1] / psd["q"].values[0]) if psd is not None else None
    where = "the whole measured band, " if top and abs(zeta / top - 1) < 1e-6 else ""
    return f"{where}{scope_text(results, zeta)}"


def _reduce(da, keep):
    """Every dimension but ``keep`` at its first value (a note says which)."""
    notes = []
    for dim in list(da.dims):
        if dim not in keep:
            notes.append(f"{dim} = {da[dim].values[0]:.4g}" if dim in da.coords else f"{dim} #0")
            da = da.isel({dim: 0})
    return da, notes


def _series(results, stage: str, var: str, xdim: str):
    """(label, case, x, measured-spectrum curve, lower, upper, notes) per variant and eta, at the largest zeta."""
    out = []
    for variant, res in results.items():
        if "bands" not in res or f"{var}_band" not in res["bands"]:
            continue
        band, curve = res["bands"][f"{var}_band"], res[stage][var]
        curve = curve.isel(draw=0, drop=True) if "draw" in curve.dims else curve
        if "zeta" in band.dims:
            zeta = float(band["zeta"].max())
            band, curve = band.sel(zeta=zeta), curve.sel(zeta=zeta, method="nearest")
        for eta in (band["eta"].values if "eta" in band.dims else [None]):
            b = band.sel(eta=eta) if eta is not None else band
            c = curve.sel(eta=eta) if eta is not None else curve
            b, notes = _reduce(b, ("quantile", xdim))
            c, _ = _reduce(c, (xdim,))
            out.append((*_label(variant, eta, res), c[xdim].values, c.values, b.isel(quantile=0).values,
                        b.isel(quantile=-1).values, notes))
    return out


def _figure(results, stage, var, xdim, xlabel, ylabel, title, scale=1.0, logy=False):
    """The curves from the measured spectra with their bands (top) and the bands relative to
    the curves, in percent (bottom: the width is readable there whatever the axes)."""
    import matplotlib.pyplot as plt

    fig, (ax, rel) = plt.subplots(2, 1, figsize=(8.4, 5.8), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]},
                                  layout="constrained")
    notes, level, zeta, n = set(), None, None, None
    for label, case, x, y, lo, hi, extra in _series(results, stage, var, xdim):
        s = style(case)
        line, = ax.plot(x, y * scale, color=s["color"], linestyle=s["linestyle"], lw=1.5, marker=s["marker"],
                        markevery=max(1, x.size // 12), markersize=4, label=label)
        shade(ax, x, lo * scale, hi * scale, line.get_color())
        with np.errstate(divide="ignore", invalid="ignore"):
            ok = y > 0
            shade(rel, x[ok], 100 * (lo[ok] / y[ok] - 1), 100 * (hi[ok] / y[ok] - 1), line.get_color(), alpha=0.08,
                  edge=1.3)
        notes.update(extra)
    for res in results.values():
        if "bands" in res:
            level, n = res["bands"].attrs.get("level"), res["bands"].attrs.get("draws")
            band = res["bands"]
            zeta = float(band["zeta"].max()) if "zeta" in band.coords else None
            break
    ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    rel.axhline(0.0, color="k", lw=0.6)
    rel.set_xlabel(xlabel)
    rel.set_ylabel("band / curve - 1 (%)")
    ax.set_ylabel(ylabel)
    sub = f"shaded: {float(level):.0%} band over {n} spectrum draws, {EDGES}" if level else ""
    sub += f"\n{_where(results, zeta)}" if zeta is not None else ""
    sub += f"\n({', '.join(sorted(notes))})" if notes else ""
    ax.set_title(f"{title}\n{sub}", fontsize=9.5)
    for a in (ax, rel):
        a.grid(True, alpha=0.3)
    return legend_outside(fig, [ax])


def figure_band_contact_area(results):
    fig = _figure(results, "contact", "contact_area_ratio", "p", "nominal pressure p (Pa)", "A / A0",
                  "Relative contact area with its uncertainty band", logy=True)
    ax = fig.axes[0]
    ax.set_ylim(top=1.05)
    return fig


def figure_band_stress(results):
    """P(sigma) at three pressures (A/A0 about 0.05, 0.2, 0.5 for the first curve) at the top
    magnification, with its band: the draws' quantiles at fixed sigma."""
    import matplotlib.pyplot as plt

    bands, contact = results["base"]["bands"], results["base"]["contact"]
    band, nominal = bands["stress_distribution_band"], contact["stress_distribution"].isel(draw=0, drop=True)
    area = contact["contact_area_ratio"].isel(draw=0, drop=True)
    zeta = None
    if "zeta" in band.dims:
        zeta = float(band["zeta"].max())
        band, nominal, area = band.sel(zeta=zeta), nominal.sel(zeta=zeta), area.sel(zeta=zeta)
    band, notes = _reduce(band, ("quantile", "p", "stress_level"))
    nominal, _ = _reduce(nominal, ("p", "stress_level"))
    area, _ = _reduce(area, ("p",))
    picks = sorted({int(np.argmin(np.abs(area.values - a))) for a in (0.05, 0.2, 0.5)})
    fig, ax = plt.subplots(figsize=(8.4, 4.6), layout="constrained")
    for i in picks:
        d, b = nominal.isel(p=i), band.isel(p=i)
        sigma = d["sigma"].values / 1e6
        line, = ax.plot(sigma, d.values * 1e6, lw=1.4,
                        label=f"p = {float(d['p']) / 1e6:.3g} MPa (A/A0 = {float(area[i]):.2f})")
        shade(ax, sigma, b.isel(quantile=0).values * 1e6, b.isel(quantile=-1).values * 1e6, line.get_color())
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("local stress sigma (MPa)")
    ax.set_ylabel("P(sigma) (1/MPa)")
    level, n = bands.attrs.get("level", 0.9), bands.attrs.get("draws")
    ax.set_title(f"Stress distribution with its uncertainty band\nshaded: {float(level):.0%} band over {n} spectrum "
                 f"draws, {EDGES}\n{_where(results, zeta)}" + (f"\n({', '.join(notes)})" if notes else ""),
                 fontsize=9.5)
    ax.grid(alpha=0.3)
    return legend_outside(fig)


def figure_band_separation(results):
    return _figure(results, "separation", "mean_separation", "p", "nominal pressure p (Pa)",
                   "mean separation u (nm)", "Mean interfacial separation with its uncertainty band", scale=1e9)


def figure_band_friction(results):
    return _figure(results, "friction", "friction_coefficient", "v", "sliding velocity v (m/s)",
                   "friction coefficient mu", "Hysteretic friction with its uncertainty band", logy=True)


def figure_band_psd(results):
    """The combined PSD C(q) of the pair with its band, and the measured bins of each surface."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.4, 4.6), layout="constrained")
    for label, case, q, C, lo, hi, _notes in _series(results, "psd", "psd_combined", "q"):
        ok = C > 0
        s = style(case)
        line, = ax.loglog(q[ok], C[ok], color=s["color"], linestyle=s["linestyle"], lw=1.2,
                          label=f"combined C(q), {label}")
        shade(ax, q[ok], lo[ok], hi[ok], line.get_color())
    topo = results["base"].get("topography")
    for name, colour in (("substrate", "0.35"), ("solid", "0.65")):
        if topo is not None and f"psd_{name}_measured" in topo:
            ax.loglog(topo[f"q_{name}_measured"].values, topo[f"psd_{name}_measured"].values, "o", color=colour,
                      ms=2.5, label=f"{name}: merged measured bins")
    level = results["base"]["bands"].attrs.get("level", 0.9) if "bands" in results["base"] else 0.9
    ax.set_xlabel("wavenumber q (1/m)")
    ax.set_ylabel("C(q) (m$^4$, Persson convention)")
    ax.set_title(f"Combined PSD of the pair\nshaded: {float(level):.0%} band of the spectrum draws, {EDGES}",
                 fontsize=10)
    ax.grid(True, alpha=0.3)
    return legend_outside(fig)
