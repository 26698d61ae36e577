"""Benchmark of the adhesion stage (not collected by pytest). Run from the worktree root:

    python tests/benchmarks/bench_adhesion.py [--smoke]

Prints: the time of seed Fig 1's partial-contact curve (41 substrate hrms values) and of each
vanishing-hrms root at the default resolution; the convergence of the vanishing hrms with the
Volterra grid (observed order), with the refinement towards zeta = 1, with the continuation
point K_min and with the q grid; and the default's error against a converged run.
Case: the built-in scene ``adhesion`` (H = 0.8, qL = q0 = 7e6 1/m, q1 = 1.4e9 1/m,
Delta_gamma = 100 meV/A^2, E = 77.2 GPa, nu = 0.42).
--smoke: 5 hrms values, the "converged" run at the default resolution, one setting per table.
"""

from __future__ import annotations

import time

import numpy as np
from _bench import SMOKE

from roughcontact.physics.adhesion import AdhesionProblem, layer_resolving_offset, zeta_grid  # noqa: E402
from roughcontact.physics.contact import effective_modulus  # noqa: E402
from roughcontact.physics.quadrature import log_grid  # noqa: E402
from roughcontact.physics.spectra import psd_combined, self_affine_hrms_factor, self_affine_psd  # noqa: E402
from roughcontact.physics.volterra import solve_partial_contact, vanishing_scale  # noqa: E402

E_STAR = effective_modulus(77.2e9, 0.42)
DG = 1.602176634
Q0, Q1, H = 7e6, 1.4e9, 0.8
ANG = 1e-10
DEFAULT = dict(ppd=10, offset=1e-10, K_min=1e-8, q_ppd=50)
CONVERGED = dict(ppd=80, offset=1e-13, K_min=1e-11, q_ppd=200) if not SMOKE else DEFAULT


def settings(*values):
    """The values a table runs through (only the first with --smoke)."""
    return values if not SMOKE else values[:1]


def setup(q_ppd):
    q = log_grid(Q0, Q1, q_ppd)
    return q, self_affine_psd(q, H, Q0, Q0, Q1, 1.0) / self_affine_hrms_factor(H, Q0, Q0, Q1)


def curve(hs, ppd, offset, K_min, q_ppd):
    q, shape = setup(q_ppd)
    C = hs[:, None] ** 2 * shape
    offset = layer_resolving_offset(q, C, E_STAR, DG, offset, K_min)  # as the stage does
    prob = AdhesionProblem(q, C, E_STAR, DG, zeta_grid(Q1 / Q0, ppd, offset))
    t0 = time.perf_counter()
    sol = solve_partial_contact(prob, 0.0, np.ones(hs.size), np.zeros(hs.size), K_min=K_min)
    return time.perf_counter() - t0, sol["K"], sol["P"][:, -1]


def h_star(ppd, offset, K_min, q_ppd, h2=0.0, eta=0.0, lo=5 * ANG, hi=40 * ANG):
    q, shape = setup(q_ppd)
    C2 = shape * h2**2
    offset = layer_resolving_offset(q, psd_combined(hi**2 * shape, C2, eta)[None, :], E_STAR, DG, offset, K_min)
    t0 = time.perf_counter()
    h = vanishing_scale(lambda h: psd_combined(h[:, None] ** 2 * shape, C2, eta), q, E_STAR, DG,
                        zeta_grid(Q1 / Q0, ppd, offset), np.array([lo]), np.array([hi]), np.ones(1), np.zeros(1),
                        K_min=K_min)[0]
    return time.perf_counter() - t0, h


def main():
    hs = np.linspace(1, 30, 41 if not SMOKE else 5) * ANG
    print(f"== Fig 1 partial-contact curve, {hs.size} hrms values (1-30 A), default resolution")
    t, K, A = curve(hs, **DEFAULT)
    print(f"time {t:.2f} s ({t / hs.size * 1e3:.0f} ms per hrms value)")
    tc, Kc, Ac = curve(hs, **CONVERGED)
    print(f"converged run (ppd {CONVERGED['ppd']}): {tc:.1f} s")
    print(f"default error: max |gamma_eff(1)/Delta_gamma| {np.max(np.abs(K - Kc)):.2e}, "
          f"max |A/A0| {np.max(np.abs(A - Ac)):.2e}")

    print("\n== vanishing-hrms roots, default resolution (solid hrms 6 A for the pairs)")
    print(f"{'case':22s} {'h (A)':>10s} {'time (s)':>9s}")
    cases = [("one surface", 0.0, 0.0, 5, 40), ("pair eta = 0", 6 * ANG, 0.0, 5, 40),
             ("pair eta = +1", 6 * ANG, 1.0, 10, 40), ("pair eta = -1", 6 * ANG, -1.0, 5, 40)]
    for name, h2, eta, lo, hi in settings(*cases):
        t, h = h_star(**DEFAULT, h2=h2, eta=eta, lo=lo * ANG, hi=hi * ANG)
        print(f"{name:22s} {h / ANG:10.5f} {t:9.2f}")

    ref_t, ref = h_star(**CONVERGED)
    print(f"\nconverged one-surface vanishing hrms: {ref / ANG:.6f} A ({ref_t:.1f} s)")
    print("\n== Volterra grid (points per decade of zeta - 1); others converged")
    print(f"{'ppd':>5s} {'nodes':>6s} {'h* (A)':>12s} {'rel. error':>11s} {'order':>6s} {'time (s)':>9s}")
    prev = None
    for ppd in settings(5, 10, 20, 40):
        t, h = h_star(ppd, CONVERGED["offset"], CONVERGED["K_min"], CONVERGED["q_ppd"])
        err = abs(h - ref) / ref
        order = f"{np.log2(prev / err):6.2f}" if prev else "      "
        n = zeta_grid(Q1 / Q0, ppd, CONVERGED["offset"]).size
        print(f"{ppd:5d} {n:6d} {h / ANG:12.6f} {err:11.2e} {order} {t:9.2f}")
        prev = err
    print("\n== requested smallest zeta - 1 of the grid (ppd 10; reduced further when the layer needs it)")
    for off in settings(1e-6, 1e-8, 1e-10, 1e-12):
        t, h = h_star(10, off, CONVERGED["K_min"], CONVERGED["q_ppd"])
        print(f"offset {off:8.0e}: h* = {h / ANG:.6f} A")
    print("\n== continuation point K_min (ppd 10)")
    for K_min in settings(1e-4, 1e-6, 1e-8, 1e-10):
        t, h = h_star(10, CONVERGED["offset"], K_min, CONVERGED["q_ppd"])
        print(f"K_min {K_min:8.0e}: h* = {h / ANG:.6f} A")
    print("\n== q grid points per decade (ppd 10)")
    for q_ppd in settings(20, 50, 200):
        t, h = h_star(10, CONVERGED["offset"], CONVERGED["K_min"], q_ppd)
        print(f"q ppd {q_ppd:4d}: h* = {h / ANG:.6f} A")
    t, h = h_star(**DEFAULT)
    print(f"\ndefault resolution: h* = {h / ANG:.6f} A, error against converged {abs(h - ref) / ref:.2e} (relative)")


if __name__ == "__main__":
    main()
