"""The effective-medium theory of a seal's leak rate (Lorenz & Persson, Eur. Phys. J. E 31, 159
(2010)): Bruggeman's 2D self-consistent conductivity of the field of local gaps, with the gap
distribution P(u) of Persson's theory (Almqvist et al., J. Mech. Phys. Solids 59, 2355 (2011)) in
the volume-conserving form of :func:`gap_distribution`; the flow factor sigma
(:func:`roughcontact.physics.leakage.leak_rate`).

See docs/theory.md, section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .apparent_contact import contact_argument, gap_above, open_area
from .contact import persson_G
from .quadrature import cumulative_integral, integral_to
from .roots import illinois
from .special import erf, ndtr

#: the effective-medium (2D Bruggeman) theory percolates at A/A0 = 1/2 by construction
BRUGGEMAN_AREA = 0.5


def magnification_nodes(q, C, p_min, E_star, points_per_decade=10):
    """Magnifications at which P(u) is resolved: 1 and 1 + delta, delta geometric
    (``points_per_decade``) up to q[-1]/qL - 1, from where the contact area of the smallest
    pressure ``p_min`` (Pa) starts to fall. Near zeta = 1, G ~ (pi/4) E*^2 qL^4 C(qL) delta, so
    A(1 + delta) drops where delta ~ p_min^2 / (pi E*^2 qL^4 C(qL)); the grid starts 1e3 below
    (and at most 1e-14 of the band below its top). Independent of the q grid, so the cost of P(u)
    grows with the q grid only through u_bar."""
    top = q[-1] / q[0] - 1.0
    rate = np.pi * E_star**2 * q[0] ** 4 * float(np.asarray(C)[0])
    lo = 1e-3 * p_min**2 / rate if rate > 0 else 1e-6 * top
    lo = min(max(lo, 1e-14 * top), 1e-2 * top)
    n = max(2, int(np.ceil(np.log10(top / lo) * points_per_decade)))
    return np.concatenate([[1.0], 1.0 + np.geomspace(lo, top, n)])


def interval_volumes(areas, ubar, opened):
    """The area that opens on each interval [zeta_k, zeta_k+1] and the volume it carries (per pressure).

    The volume between the surfaces is A u_bar (m, per unit nominal area); an interval carries
    V_k - V_k+1 over the area opened[k+1] - opened[k] (opened = 1 - A/A0, from erfc so that it is
    exact where A/A0 rounds to 1). Where no area opens to double precision (less than 1e-280 of A0, at
    the smallest magnifications) the volume is carried on to the next interval that opens area, and a
    remainder after the last one goes back to it: sum(volume) = V_0 - V_K = u_bar(1) exactly
    (A(1) = 1, u_bar(q1/qL) = 0), the theory's mean separation.

    Parameters
    ----------
    areas, ubar, opened : arrays (K + 1, P)
        A/A0, u_bar (m) and 1 - A/A0 at the magnification nodes.

    Returns
    -------
    drop, volume : arrays (K, P)
        Opened area (dimensionless, >= 0) and its volume (m, >= 0; 0 where drop = 0).
    """
    V = areas * ubar
    drop = opened[1:] - opened[:-1]
    drop = np.where(drop > 1e-280, drop, 0.0)  # below: the gap volume / area would overflow
    raw = V[:-1] - V[1:]
    volume = np.zeros_like(raw)
    carry = np.zeros(raw.shape[1:])
    last = np.full(raw.shape[1:], -1)
    for k in range(raw.shape[0]):
        total = carry + raw[k]
        takes = (drop[k] > 0) & (total >= 0)
        volume[k] = np.where(takes, total, 0.0)
        carry = np.where(takes, 0.0, total)
        last = np.where(takes, k, last)
    cols = np.flatnonzero((last >= 0) & (carry != 0))
    volume[last[cols], cols] += carry[cols]
    return drop, np.maximum(volume, 0.0)


def folded_mean(t):
    """E|X| / s of X ~ N(t s, s^2) (dimensionless): t erf(t / sqrt 2) + sqrt(2/pi) exp(-t^2/2), t >= 0."""
    t = np.asarray(t, dtype=float)
    with np.errstate(over="ignore", under="ignore"):
        return t * erf(t / np.sqrt(2.0)) + np.sqrt(2.0 / np.pi) * np.exp(-0.5 * t * t)


def folded_parameters(mean, width):
    """Location mu and scale s (m) of the reflected normal |X|, X ~ N(mu, s^2), with E|X| = ``mean``.

    The scale is the finer roughness ``width`` h where that is possible (mean >= h sqrt(2/pi), the
    mean of the half-normal of scale h); mu then solves s folded_mean(mu/s) = mean (increasing in mu,
    bracket [0, mean]; :func:`roughcontact.physics.roots.illinois`). Where the mean is smaller, the
    half-normal of that mean: mu = 0, s = mean sqrt(pi/2) (the gap cannot fluctuate by more than it
    is wide without touching, and the touching is the contact area counted at larger zeta).
    ``mean`` >= 0 and ``width`` >= 0 broadcast.
    """
    mean, width = np.broadcast_arrays(np.asarray(mean, dtype=float), np.asarray(width, dtype=float))
    wide = (width > 0) & (mean >= width * np.sqrt(2.0 / np.pi))
    s = np.where(wide, width, mean * np.sqrt(0.5 * np.pi)).ravel()
    with np.errstate(over="ignore"):
        target = np.where(wide, mean / np.where(wide, width, 1.0), np.sqrt(2.0 / np.pi)).ravel()
    far = target > 40.0  # folded_mean(t) = t to double precision: no reflection
    solve = wide.ravel() & ~far
    target = np.where(solve, target, np.sqrt(2.0 / np.pi))

    def residual(t):
        return folded_mean(t) - target

    root = illinois(residual, np.zeros_like(target), target, residual(np.zeros_like(target)), residual(target),
                    ftol=1e-14 * target, xtol=1e-15, rtol=1e-14, maxiter=200, skip=~solve)
    t = np.where(solve, root.x, 0.0)
    mu = np.where(far & wide.ravel(), mean.ravel(), t * s)
    return mu.reshape(mean.shape), s.reshape(mean.shape)


def _folded_cdf_moment(e, mu, s):
    """P(|X| <= e) and E[|X|; |X| <= e] (m) of X ~ N(mu, s^2) (s = 0: the atom at mu); e may be inf."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ss = np.where(s > 0, s, 1.0)
        a, b, c = (e - mu) / ss, (-e - mu) / ss, -mu / ss
        pdf = [np.exp(-0.5 * np.where(np.isfinite(z), z, 0.0) ** 2) * np.isfinite(z) / np.sqrt(2 * np.pi)
               for z in (a, b, c)]
        cdf = ndtr(a) - ndtr(b)
        # int_0^e y f dy - int_-e^0 y f dy, f the normal density of X
        moment = mu * (ndtr(a) - 2.0 * ndtr(c) + ndtr(b)) + s * (2.0 * pdf[2] - pdf[0] - pdf[1])
    atom = e >= mu
    return np.where(s > 0, cdf, atom.astype(float)), np.where(s > 0, moment, np.where(atom, mu, 0.0))


def gap_distribution(q, C, p, *, E_star, alpha, refinement="none", numerics=None, bins_per_decade=20,
                     points_per_decade=20, span=(1e-8, 1e2), correction="persson", gamma=None):
    """P(u) of Persson's theory as the mass in logarithmic bins of u, per pressure, plus A(q1)/A0;
    its mean is the theory's mean separation u_bar(1) (eq 57) to rounding.

    .. math:: P(u) = \\frac{A(\\zeta_1)}{A_0}\\delta(u) + \\int_1^{\\zeta_1} d\\zeta\\,
              \\frac{-A'(\\zeta)}{A_0}\\,\\big[g(u - \\mu(\\zeta)) + g(u + \\mu(\\zeta))\\big]

    the form of Almqvist et al. (J. Mech. Phys. Solids 59, 2355 (2011)) used by Lorenz & Persson
    (Eur. Phys. J. E 31, 159 (2010)): the area that opens between two magnifications has the gap of
    its constriction, spread by the finer roughness (g a normal density of width
    h(zeta)^2 = 2 pi \\int_{zeta qL}^{q1} q C dq, the roughness not yet resolved at zeta), reflected at
    u = 0. Centred on u1(zeta) with width h, the reflection adds volume (h is 2.5-8 times u1 on a
    seal): the mean gap was 1.3-6 times u_bar(1). Here each reflected normal has the mean that
    conserves the volume, d(A u_bar) = A' u1 dzeta, exactly:

    .. math:: E|X_k| = c_k = \\frac{A_k \\bar u_k - A_{k+1}\\bar u_{k+1}}{A_k - A_{k+1}}, \\qquad
              \\sum_k (A_k - A_{k+1})\\, c_k = \\bar u(1)

    (:func:`interval_volumes`; the published width h where it fits, a half-normal of mean c_k where
    c_k < h sqrt(2/pi): :func:`folded_parameters`), so that the mean of P(u) is u_bar(1). Discretized
    on :func:`magnification_nodes` (h at each interval's geometric midpoint); each reflected normal
    is put into bins of u exactly, mass and first moment (:func:`_folded_cdf_moment`):
    ``bins_per_decade`` geometric bins from span[0] to span[1] times u_bar(1), one bin below and one
    above; a bin's gap is the mean gap of its mass (its geometric centre where it is empty), so the
    bins keep the mean. Bins, unlike Gauss-Hermite nodes, resolve the step of Bruggeman's integrand
    at u^3 = sigma whatever sigma is.

    Parameters
    ----------
    q, C, p, E_star, alpha, refinement, numerics, correction, gamma
        As in :func:`~roughcontact.physics.apparent_contact.gap_above` (``p`` an array (P,)).
    bins_per_decade, points_per_decade, span
        The gap bins and the magnification nodes (:func:`magnification_nodes`).

    Returns
    -------
    u : array (B, P)
        Bin gaps (m), >= 0.
    weight : array (B, P)
        Mass in each bin (dimensionless); with ``area_top`` the masses sum to 1.
    area_top : array (P,)
        A(q1)/A0, the weight of u = 0 (contact).
    """
    p = np.atleast_1d(np.asarray(p, dtype=float))
    zeta = magnification_nodes(q, C, float(p.min()), E_star, points_per_decade)
    x = contact_argument(p[None, :], persson_G(q, C, zeta * q[0], E_star)[:, None], correction, gamma)  # (K + 1, P)
    areas, opened = erf(x), open_area(x)
    ubar = np.zeros_like(areas)
    for k, z in enumerate(zeta[:-1]):
        ubar[k] = gap_above(q, C, z, p, E_star=E_star, alpha=alpha, refinement=refinement, numerics=numerics,
                            correction=correction, gamma=gamma)
    drop, volume = interval_volumes(areas, ubar, opened)
    with np.errstate(divide="ignore", invalid="ignore"):
        centre = np.where(drop > 0, volume / np.where(drop > 0, drop, 1.0), 0.0)
    qC = q * C
    h = np.sqrt(np.maximum(2.0 * np.pi * (cumulative_integral(q, qC)[-1]
                                          - integral_to(q, qC, np.sqrt(zeta[:-1] * zeta[1:]) * q[0])), 0.0))
    mu, s = folded_parameters(centre, h[:, None])
    decades = np.log10(span[1] / span[0])
    scale = np.where(ubar[0] > 0, ubar[0], 1.0)
    edges = scale[None, :] * np.geomspace(*span, int(np.ceil(decades * bins_per_decade)) + 1)[:, None]  # (E, P)
    bounds = np.concatenate([np.zeros((1,) + edges.shape[1:]), edges, np.full((1,) + edges.shape[1:], np.inf)])
    cdf, moment = _folded_cdf_moment(bounds[None], mu[:, None, :], s[:, None, :])  # (K, E + 2, P)
    mass = np.clip(np.diff(cdf, axis=1), 0.0, 1.0)
    weight = np.einsum("kp,kbp->bp", drop, mass)
    first = np.einsum("kp,kbp->bp", drop, np.diff(moment, axis=1))
    centres = np.concatenate([0.5 * edges[:1], np.sqrt(edges[:-1] * edges[1:]), edges[-1:]], axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(weight > 0, first / np.where(weight > 0, weight, 1.0), centres)
    u = np.clip(u, bounds[:-1], bounds[1:])
    return u, weight, areas[-1]


def bruggeman_flow_factor(u, weight, area_top):
    """Bruggeman's 2D effective flow factor sigma (m^3) of a field of gaps (one per pressure).

    .. math:: \\frac{A(\\zeta_1)}{A_0}\\,(-1) + \\sum_j W_j\\,\\frac{u_j^3 - \\sigma}{u_j^3 + \\sigma} = 0

    (each patch a disc of conductivity u^3 in the effective medium; contact: conductivity 0).
    The left side falls monotonically in sigma from 1 - 2 A(zeta1)/A0 to -1, so a root exists
    exactly when A(zeta1)/A0 < 1/2 (the medium percolates); it is found by
    :func:`roughcontact.physics.roots.illinois` in ln sigma. sigma = 0 otherwise.

    Parameters
    ----------
    u, weight, area_top
        As returned by :func:`gap_distribution` (atoms along the leading axes, pressures last).

    Returns
    -------
    array (P,)
        sigma (m^3).

    References
    ----------
    Bruggeman, Ann. Phys. 416, 636 (1935); Kirkpatrick, Rev. Mod. Phys. 45, 574 (1973); Lorenz &
    Persson, Eur. Phys. J. E 31, 159 (2010).
    """
    P = area_top.shape[-1]
    u = u.reshape(-1, P)
    weight = weight.reshape(-1, P)
    scale = np.where(np.sum(weight * u, 0) > 0, np.sum(weight * u, 0) / np.maximum(np.sum(weight, 0), 1e-300), 1.0)
    with np.errstate(divide="ignore"):
        logv = 3.0 * np.log(u / scale)  # ln(u^3 / scale^3); -inf at u = 0 (conducts nothing)
    open_ = area_top < BRUGGEMAN_AREA

    def residual(x):  # increasing in x = ln(sigma / scale^3)
        return area_top + np.sum(weight * np.tanh(0.5 * (x - logv)), 0)

    finite = np.isfinite(logv)
    lo = np.min(np.where(finite, logv, np.inf), 0) - 40.0
    hi = np.max(np.where(finite, logv, -np.inf), 0) + 40.0
    open_ = open_ & np.isfinite(lo) & np.isfinite(hi)
    lo, hi = np.where(open_, lo, 0.0), np.where(open_, hi, 1.0)
    root = illinois(residual, lo, hi, residual(lo), residual(hi), xtol=1e-12, maxiter=200, skip=~open_)
    return np.where(open_, np.exp(root.x) * scale**3, 0.0)
