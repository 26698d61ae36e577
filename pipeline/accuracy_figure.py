"""The figure of ``roughcontact accuracy``: each stage's error against its wall time.

Each rung of the resolution ladder is a point (median time of its runs: timings are noisy, so
points are not joined into a line that would zig-zag); each preset is a large open marker; the
dotted line of a stage's colour is the target of its default preset (stages with the same target
share one line of alternating dashes in their colours). The axes span whole
decades, so that only decade ticks are labelled and labels never overlap.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

#: errors below this are drawn at it (rounding: the method is exact there)
SMALLEST = 1e-16
PRESET_MARKERS = {"fast": "v", "default": "D", "accurate": "^"}


def _decades(values) -> tuple[float, float]:
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values) & (values > 0)]
    if not values.size:
        return 0.1, 10.0
    lo, hi = np.floor(np.log10(values.min())), np.ceil(np.log10(values.max()))
    return 10.0 ** lo, 10.0 ** max(hi, lo + 1)


def _target_dashes(tolerances, i: int, dash: float = 3.0):
    """The line style of stage ``i``'s target line: dotted-like short dashes; when several stages
    share the target, their lines coincide, so each draws every n-th dash (offset by its rank) and
    the shared line shows every stage's colour in turn instead of the last one's only."""
    same = [k for k, t in enumerate(tolerances) if np.isclose(t, tolerances[i], rtol=1e-9)]
    n, rank = len(same), same.index(i)
    return (rank * dash, (dash, dash * (n - 1))) if n > 1 else (0, (1.0, 2.0))


def figure(ds: xr.Dataset):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator, NullFormatter

    fig, ax = plt.subplots(figsize=(8.2, 4.8), layout="constrained")
    times, errors = [], []
    for i, name in enumerate(ds["stage"].values):
        colour = f"C{i}"
        e = ds["rung_error"].isel(stage=i).values[:-1]  # the last rung is the reference
        t = ds["rung_time"].isel(stage=i).values[:-1]
        ok = np.isfinite(e) & np.isfinite(t)
        ax.loglog(t[ok], np.maximum(e[ok], SMALLEST), "o", color=colour, markersize=5, label=f"{name}: ladder rungs")
        for j, preset in enumerate(ds["preset"].values):
            pt, pe = float(ds["preset_time"][i, j]), max(float(ds["preset_error"][i, j]), SMALLEST)
            ax.loglog(pt, pe, PRESET_MARKERS[str(preset)], color=colour, markersize=11, markerfacecolor="none",
                      markeredgewidth=1.5)
            times.append(pt)
            errors.append(pe)
        ax.axhline(float(ds["tolerance"][i]), color=colour, linestyle=_target_dashes(ds["tolerance"].values, i),
                   linewidth=1.2, label=f"{name}: target of the default")
        times += list(t[ok])
        errors += list(np.maximum(e[ok], SMALLEST))
        errors += [0.3 * float(ds["tolerance"][i]), 3.0 * float(ds["tolerance"][i])]  # the target inside, off the edges
    for preset, marker in PRESET_MARKERS.items():
        ax.plot([], [], marker, color="0.3", markersize=9, markerfacecolor="none", label=f"preset {preset}")
    ax.set_xlim(*_decades(times))
    ax.set_ylim(*_decades(errors))
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(base=10, numticks=12))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("wall time (s, median of runs)")
    ax.set_ylabel(f"error vs finest rung (floor {float(ds['rung_error'].attrs.get('error_floor', 0)):g} of max)")
    ax.set_title(f"Accuracy against cost ({'; '.join(str(s) for s in ds['stage'].values)})", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    fig.legend(loc="outside right upper", fontsize=8)
    return fig
