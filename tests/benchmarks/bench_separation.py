"""Benchmark of the separation stage: cost of u(p) and its error against a converged run.

Run: ``python tests/benchmarks/bench_separation.py [--smoke]`` from the repository root (not collected
by pytest). ``--smoke``: 20 pressures, coarse "converged" runs, two settings per table (seconds).

1. Time of u(p) for 200 pressures x 3 eta (seed section 4.2 surfaces, zeta = 4 and 200) at the
   default resolution, through the stage (psd grid given).
2. Error table against a converged run, for the default scene (piecewise power-law PSD: the
   q grid is exact there, only the s quadrature matters) and for a smooth PSD that is not a
   power law (self-affine with a Gaussian cut-off: the q grid matters, second order).
3. For comparison, a naive trapezoid over the q grid with w(qL) = inf dropped.
"""

from __future__ import annotations

import time

import numpy as np
from _bench import SMOKE, stage_result  # noqa: E402
from scipy.special import exp1

from roughcontact.physics.quadrature import cumulative_integral, log_grid  # noqa: E402
from roughcontact.physics.separation import mean_separation, separation_nodes  # noqa: E402
from roughcontact.physics.spectra import self_affine_hrms_factor, self_affine_psd  # noqa: E402
from roughcontact.scene import from_dict  # noqa: E402

H, QL, Q1 = 0.8, 2e8, 4e10
E_STAR = 77.2e9 / (1 - 0.42**2)
ALPHA = 0.45
P = np.geomspace(1e-10, 1e-1, 200 if not SMOKE else 20) * E_STAR
ZETA = np.array([4.0, 200.0])


def scene(**numerics):
    surface = {"kind": "self_affine", "H": H, "qL": "2e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}
    return from_dict({
        "substrate": surface, "solid": surface, "interface": {"eta": [0.0, 1.0, -1.0]},
        "material": {"E": "77.2 GPa", "nu": 0.42},
        "load": {"p": {"from": f"{P[0]} Pa", "to": f"{P[-1]} Pa", "num": P.size}},
        "contact": {"zeta": list(ZETA)}, "outputs": {"variables": ["mean_separation"]},
        "numerics": numerics,
    })


def separation_of(sc, psd=None):
    psd = psd if psd is not None else stage_result("psd", sc)
    return stage_result("separation", sc, {"psd": psd})["mean_separation"]


def rel_error(u, ref, mask):
    return float(np.max(np.abs(u - ref)[..., mask] / np.abs(ref)[..., mask]))


def _preset_settings():
    """(q points/decade, panels/decade, Gauss points) of each preset, read from the declarations."""
    from roughcontact.stage import sections

    params = {p.name: p for p in sections()["numerics"].params}
    names = ("points_per_decade", "separation_panels_per_decade", "separation_gauss_points")
    return {preset: tuple(params[n].value_in(preset) for n in names) for preset in ("fast", "default", "accurate")}


PRESET_SETTINGS = _preset_settings()


def timing():
    sc = scene()
    psd = stage_result("psd", sc)
    separation_of(sc, psd)  # warm up (Yang-Persson table, imports)
    times = []
    for _ in range(5 if not SMOKE else 1):
        t0 = time.perf_counter()
        separation_of(sc, psd)
        times.append(time.perf_counter() - t0)
    print(f"## time of u(p): {P.size} pressures x 3 eta x 2 zeta, default resolution (q: 50/decade)")
    print(f"best of 5: {min(times) * 1e3:.1f} ms   median: {np.median(times) * 1e3:.1f} ms")


def table_scene():
    conv = separation_of(scene(points_per_decade=400, separation_panels_per_decade=16,
                               separation_gauss_points=10, separation_depth=14.0) if not SMOKE else
                         scene(points_per_decade=100, separation_panels_per_decade=8, separation_gauss_points=6))
    # eta = +1: u = 0 exactly. The stage stores eta increasing (-1, 0, 1), not in the scene's order
    mask_eta = conv["eta"].values != 1.0
    conv = conv.values
    pmask = P / E_STAR <= 1e-2
    print("\n## error against a converged run (q 400/decade, 16 panels/decade, 10 Gauss points, depth 14)")
    print("seed section 4.2 PSD (piecewise power law), eta = 0 and -1, zeta = 4 and 200, p/E* in [1e-10, 1e-2]")
    print("| q points/decade | panels/decade | Gauss points | max rel. error | time (ms) |")
    print("|---|---|---|---|---|")
    settings = [(10, 4, 4), (20, 1, 2), (25, 4, 4), (50, 1, 2), (50, 2, 2), (50, 2, 3), (50, 4, 3),
                (50, 4, 4), (50, 8, 6), (100, 4, 4), (200, 4, 4)]
    for ppd, pan, gp in settings if not SMOKE else settings[:2]:
        sc = scene(points_per_decade=ppd, separation_panels_per_decade=pan, separation_gauss_points=gp)
        psd = stage_result("psd", sc)
        t0 = time.perf_counter()
        u = separation_of(sc, psd).values
        dt = time.perf_counter() - t0
        err = rel_error(u[mask_eta], conv[mask_eta], pmask)
        tag = "".join(f" ({name})" for name, setting in PRESET_SETTINGS.items() if setting == (ppd, pan, gp))
        print(f"| {ppd}{tag} | {pan} | {gp} | {err:.2e} | {dt * 1e3:.0f} |")


def smooth_psd(q):
    """Self-affine PSD with a Gaussian cut-off at q = 20 qL: not a power law anywhere."""
    C0 = 1e-18 / self_affine_hrms_factor(H, QL, QL, Q1)
    return self_affine_psd(q, H, QL, QL, Q1, C0) * np.exp(-((q / (20 * QL)) ** 2))


def kernel_u(ppd, panels=4, order=4, depth=10.0):
    q = log_grid(QL, 100 * QL, ppd)
    nodes = separation_nodes(q, smooth_psd(q), ZETA * QL / 2, panels, order, depth)
    s, w, count, _, s_tail, q_tail = nodes
    return mean_separation(P, s, w, count, s_tail, q_tail, E_star=E_STAR, alpha=ALPHA)


def naive_u(ppd):
    """Trapezoid in q of q^2 C w E1((w p/E*)^2), w from the running integral, first node dropped."""
    q = log_grid(QL, 100 * QL, ppd)
    C = smooth_psd(q)
    m3 = cumulative_integral(q, q**3 * C)  # running int q^3 C dq
    with np.errstate(divide="ignore"):
        w = np.where(m3 > 0, (np.pi * m3) ** -0.5, 0.0)
    out = []
    for z in ZETA / 2:
        k = q <= z * QL * (1 + 1e-12)
        with np.errstate(invalid="ignore"):
            f = np.where(w[k] > 0, q[k] ** 2 * C[k] * w[k] * exp1((w[k] * P[:, None] / E_STAR) ** 2), 0.0)
        out.append(np.sqrt(np.pi) * ALPHA / 2 * np.trapezoid(f, q[k], axis=-1))
    return np.stack(out, axis=-1)


def table_smooth():
    conv = kernel_u(3200, 16, 10, 14.0) if not SMOKE else kernel_u(100, 8, 6)
    pmask = P / E_STAR <= 1e-2
    print("\n## smooth PSD (self-affine x exp(-(q/20qL)^2), qL..100 qL), zeta = 2 and 100: the q grid matters")
    print("converged: q 3200/decade, 16 panels/decade, 10 Gauss points; p/E* in [1e-10, 1e-2]")
    print("| q points/decade | max rel. error (this stage) | observed order | naive, zeta = 2 | naive, zeta = 100 |")
    print("|---|---|---|---|---|")
    prev = None
    for ppd in (12, 25, 50, 100, 200, 400) if not SMOKE else (12, 25):
        err = rel_error(kernel_u(ppd).T, conv.T, pmask)
        naive = naive_u(ppd).T
        n2, n100 = (rel_error(naive[i], conv.T[i], pmask) for i in (0, 1))
        order = f"{np.log(prev / err) / np.log(2):.2f}" if prev else ""
        print(f"| {ppd} | {err:.2e} | {order} | {n2:.2e} | {n100:.2e} |")
        prev = err


if __name__ == "__main__":
    timing()
    table_scene()
    table_smooth()
