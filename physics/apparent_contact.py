"""Persson's contact seen at magnification zeta, on which both leakage theories
(:mod:`roughcontact.physics.critical_junction`, :mod:`roughcontact.physics.effective_medium`) build:
the relative contact area A(zeta)/A0 = erf(x) and the open area 1 - A/A0, the mean separation
u_bar(zeta) of the apparent contact, and the wavenumber grid restricted to a band.

See docs/theory.md, section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .contact import persson_G
from .corrections import corrected_G
from .quadrature import loglog_interp
from .separation import mean_separation, separation_nodes
from .special import erf, erfcx


def band_grid(q, C, q_lo, q_hi):
    """The wavenumber grid restricted to [q_lo, q_hi], ends added with C interpolated log-log
    (the power-law model of :mod:`roughcontact.physics.quadrature`, so integrals on the sub-grid
    equal those of the full grid over the same band). Returns (q_sub, C_sub), 1-D."""
    q = np.asarray(q, dtype=float)
    inside = (q > q_lo * (1 + 1e-12)) & (q < q_hi * (1 - 1e-12))
    qs = np.concatenate([[q_lo], q[inside], [q_hi]])
    ends = loglog_interp(np.array([q_lo, q_hi]), q, C)
    return qs, np.concatenate([ends[:1], np.asarray(C, dtype=float)[inside], ends[1:]])


def contact_argument(p, G, correction="persson", gamma=None):
    """x = p / (2 sqrt(G_eff)) (dimensionless): A/A0 = erf(x), the open area 1 - A/A0 = erfc(x).

    G_eff = G for Persson's eq 19, the corrected theory's G_eff otherwise
    (:func:`roughcontact.physics.corrections.corrected_G`); x = inf where G = 0 (full contact).
    ``p`` (Pa) and ``G`` (Pa^2) broadcast. See docs/theory.md, section "Contact-area corrections".
    """
    p, G = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(G, dtype=float))
    G_eff = corrected_G(p, G, correction, gamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(G_eff > 0, p / (2.0 * np.sqrt(np.where(G_eff > 0, G_eff, 1.0))), np.inf)


def open_area(x):
    """1 - A/A0 = erfc(x) (dimensionless) for x >= 0, written erfcx(x) exp(-x^2) so that it keeps its
    relative accuracy where A/A0 rounds to 1 (down to 1e-308; 0 beyond x = 26.6 or x = inf)."""
    x = np.asarray(x, dtype=float)
    with np.errstate(under="ignore", invalid="ignore", over="ignore"):
        return np.where(np.isfinite(x), erfcx(np.where(np.isfinite(x), x, 0.0)) * np.exp(-np.minimum(x, 40.0) ** 2),
                        0.0)


def gap_above(q, C, zeta, p, *, E_star, alpha, refinement="none", numerics=None, correction="persson", gamma=None):
    """Mean separation u_bar(zeta) (m) of the apparent contact seen at magnification zeta.

    The roughness above zeta qL only, squeezed by the pressure in the apparent contact,
    p(zeta) = p / (A(zeta)/A0) (Yang & Persson, J. Phys.: Condens. Matter 20, 215214 (2008)):

    .. math:: \\bar u(\\zeta) = \\frac{\\sqrt\\pi\\,\\alpha}{2}\\int_{\\zeta q_L}^{q_1} q^2 C\\, w_\\zeta\\,
              E_1\\big((w_\\zeta\\, p(\\zeta)/E^*)^2\\big) dq, \\qquad
              w_\\zeta(q) = \\Big(\\pi\\int_{\\zeta q_L}^{q} q'^3 C\\, dq'\\Big)^{-1/2}

    u_bar(1) is the mean separation of eq 57 over the whole band; u_bar(q1/qL) = 0.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL; q[-1] is the top of the band.
    C : array (n,)
        Combined PSD (m^4).
    zeta : float
        Magnification, 1 <= zeta <= q[-1]/qL.
    p : array (P,)
        Nominal pressure (Pa), > 0.
    E_star, alpha, refinement
        As in :func:`roughcontact.physics.separation.mean_separation`.
    numerics : dict
        ``panels_per_decade``, ``order``, ``depth`` of :func:`roughcontact.physics.separation.separation_nodes`.
    correction, gamma
        The contact-area theory of A(zeta)/A0 (:func:`contact_argument`).

    Returns
    -------
    array (P,)
        u_bar(zeta) (m).
    """
    p = np.asarray(p, dtype=float)
    q_lo = zeta * q[0]
    if q_lo >= q[-1] * (1 - 1e-12):
        return np.zeros_like(p)
    area = erf(contact_argument(p, persson_G(q, C, np.array([q_lo]), E_star)[..., 0], correction, gamma))
    qs, Cs = band_grid(q, C, q_lo, q[-1])
    s, weight, count, _, s_tail, q_tail = separation_nodes(qs, Cs, qs[-1:], **(numerics or {}))
    return mean_separation(p / area, s, weight, count, s_tail, q_tail, E_star=E_star, alpha=alpha,
                           refinement=refinement)[..., 0]
