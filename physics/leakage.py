"""Leak rate of a static seal from the contact of two rough surfaces: the critical-junction
theory and the effective-medium (Bruggeman) theory, both on Persson's u(p, zeta) and A(p, zeta).

A liquid of viscosity mu flows through the gaps of a seal of width W (across the flow) and
length L (along the flow) under a pressure drop dp; in the thin-film (Reynolds) limit a gap g
conducts the flow u = -(g^3 / 12 mu) grad P per unit width. Both theories give an effective
flow factor sigma (m^3) of the interface, and the leak rate

    Q = (W / L) sigma dp / (12 mu)   (m^3/s).

* Critical junction (Persson & Yang, J. Phys.: Condens. Matter 20, 315011 (2008); Lorenz &
  Persson, Eur. Phys. Lett. 86, 44006 (2009)): increase the magnification until the contact
  area A(zeta)/A0 falls to the percolation value a_c; the flow is limited by the last open
  constriction, of separation u1(zeta_c); sigma = u1^3.
* Effective medium (Lorenz & Persson, Eur. Phys. J. E 31, 159 (2010)): Bruggeman's 2D
  self-consistent conductivity of the field of local gaps, with the gap distribution P(u)
  of Persson's theory (Almqvist et al., J. Mech. Phys. Solids 59, 2355 (2011)).

See docs/theory.md, section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .contact import persson_G
from .corrections import corrected_G, variance_factor, variance_function
from .quadrature import cumulative_integral, integral_to, inverse_cumulative_integral, loglog_interp
from .roots import illinois
from .separation import mean_separation, separation_nodes
from .special import erf, erfcx, erfinv, ndtr

#: relative contact area at which the non-contact area stops percolating: 0.42 for randomly
#: rough, isotropic surfaces (Dapp, Luecke, Persson & Mueser, Phys. Rev. Lett. 108, 244301 (2012);
#: "of order 0.4" in Persson & Yang 2008's molecular dynamics)
PERCOLATION_AREA = 0.42
#: the effective-medium (2D Bruggeman) theory percolates at A/A0 = 1/2 by construction
BRUGGEMAN_AREA = 0.5


def leak_rate(flow_factor, pressure_drop, viscosity, width, length):
    """Q = (W / L) sigma dp / (12 mu) (m^3/s): the volume flow through a seal.

    Parameters
    ----------
    flow_factor : array
        sigma (m^3): the interface's effective g^3 (u1^3, Bruggeman's sigma, or the exact one).
    pressure_drop : float
        dp across the seal (Pa), > 0.
    viscosity : float
        mu (Pa s), > 0.
    width, length : float
        W across the flow, L along it (m), > 0; W/L is the seal's aspect ratio.

    References
    ----------
    Persson & Yang, J. Phys.: Condens. Matter 20, 315011 (2008).
    """
    return (width / length) * np.asarray(flow_factor, dtype=float) * pressure_drop / (12.0 * viscosity)


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


def area_slope(q, C, zeta, p, E_star, correction="persson", gamma=None):
    """A(zeta)/A0 and its slope dA/d(ln zeta) (dimensionless) at nominal pressure p (Pa).

    A = erf(x), x = 1/sqrt(2 v), v the reduced variance, which grows as dv = S(A) dv_full with
    dv_full/d ln zeta = 2 (dG/d ln zeta) / p^2 (S = 1 for Persson; :mod:`roughcontact.physics.corrections`), so

    .. math:: \\frac{dA}{d\\ln\\zeta} = -\\frac{2}{\\sqrt\\pi}\\, x^3 e^{-x^2}\\, S(A)\\, \\frac{2}{p^2}
              \\frac{dG}{d\\ln\\zeta}, \\qquad
              \\frac{dG}{d\\ln\\zeta} = \\frac{\\pi}{4} E^{*2} (\\zeta q_L)^4 C(\\zeta q_L)

    (seed eqs 17, 19; for Persson it is -(x/sqrt(pi)) exp(-x^2) (dG/d ln zeta)/G); 0 where G = 0.
    """
    q_z = zeta * q[0]
    p = np.asarray(p, dtype=float)
    G = persson_G(q, C, np.array([q_z]), E_star)[..., 0]
    dG = 0.25 * np.pi * E_star**2 * q_z**4 * loglog_interp(np.array([q_z]), q, C)[0]
    x = contact_argument(p, G, correction, gamma)
    area = erf(x)
    S = variance_factor(area, correction, gamma) if correction != "persson" else 1.0
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        slope = np.where(np.isfinite(x), -(2.0 / np.sqrt(np.pi)) * x**3 * np.exp(-x * x) * S * 2.0 * dG / p**2, 0.0)
    return area, slope


def critical_gap(q, C, zeta, p, *, E_star, alpha, refinement="none", numerics=None, step=1e-3,
                 correction="persson", gamma=None):
    """Separation u1(zeta) (m) of the constrictions that open as the magnification passes zeta.

    .. math:: u_1(\\zeta) = \\bar u(\\zeta) + \\bar u'(\\zeta)\\,\\frac{A(\\zeta)}{A'(\\zeta)}

    (Lorenz & Persson 2009): the volume between the surfaces in the apparent contact, A u_bar,
    loses dA' u1 when the area dA' opens, d(A u_bar) = A' u1 dzeta. A' is analytic
    (:func:`area_slope`); u_bar' is a central difference of :func:`gap_above` over
    ln zeta +- ``step`` (one-sided at the band's ends; error ~ step^2). u1 = u_bar where A' = 0.

    Parameters
    ----------
    q, C, zeta, p, E_star, alpha, refinement, numerics, correction, gamma
        As in :func:`gap_above` (``p`` an array (P,)).
    step : float
        Step in ln zeta of the difference (dimensionless).

    Returns
    -------
    array (P,)
        u1 (m), >= u_bar(zeta).
    """
    kw = dict(E_star=E_star, alpha=alpha, refinement=refinement, numerics=numerics, correction=correction,
              gamma=gamma)
    top = q[-1] / q[0]
    lo, hi = max(zeta * np.exp(-step), 1.0), min(zeta * np.exp(step), top)
    u_mid = gap_above(q, C, zeta, p, **kw)
    slope = (gap_above(q, C, hi, p, **kw) - gap_above(q, C, lo, p, **kw)) / np.log(hi / lo)
    area, dA = area_slope(q, C, zeta, p, E_star, correction, gamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        extra = np.where(dA < 0, slope * area / np.where(dA < 0, dA, -1.0), 0.0)
    return u_mid + np.maximum(extra, 0.0)


def percolation_G(p, area, correction="persson", gamma=None):
    """The G of eq 17 (Pa^2) at which A/A0 = ``area`` under nominal pressure p (Pa):
    p^2 Phi(v_c) / 2 with v_c = 1 / (2 erfinv(area)^2) (Phi(v) = v for Persson:
    (p / (2 erfinv(area)))^2; :func:`roughcontact.physics.corrections.variance_function`)."""
    v_c = 0.5 / erfinv(area) ** 2
    phi = v_c if correction == "persson" else float(variance_function(np.array(v_c), correction, gamma))
    return 0.5 * np.asarray(p, dtype=float) ** 2 * phi


def sealing_pressure(q, C, E_star, area, q_top=None, correction="persson", gamma=None):
    """The nominal pressure (Pa) at which A/A0 over the band [qL, q_top] (default: the whole grid)
    reaches ``area``, so that the non-contact area stops percolating: sqrt(2 G / Phi(v_c))
    (:func:`percolation_G`; 2 sqrt(G) erfinv(area) for Persson, seed eq 19); C (..., n)."""
    q_top = q[-1] if q_top is None else q_top
    G = persson_G(q, C, np.array([q_top], dtype=float), E_star)[..., 0]
    return np.sqrt(G / percolation_G(1.0, area, correction, gamma))


def critical_junction(q, C, p, *, E_star, alpha, refinement="none", numerics=None, area=PERCOLATION_AREA,
                      correction="persson", gamma=None):
    """The critical junction of one spectrum: zeta_c (dimensionless) and u1(zeta_c) (m) per pressure.

    zeta_c solves A(zeta_c)/A0 = a_c: G(zeta_c) = :func:`percolation_G` (Persson: (p / (2 erfinv(a_c)))^2),
    inverted in closed form on the power-law model of q^3 C. Where even the whole band leaves
    A/A0 >= a_c the non-contact area does not percolate: zeta_c = NaN and u1 = 0 (no leak).

    Parameters
    ----------
    q, C : arrays (n,)
        Grid (1/m) and combined PSD (m^4) of one case.
    p : array (P,)
        Nominal pressures (Pa).
    E_star, alpha, refinement, numerics, correction, gamma
        As in :func:`gap_above`.
    area : float
        a_c, 0 < a_c < 1.

    Returns
    -------
    zeta_c, u1 : arrays (P,)
    """
    p = np.atleast_1d(np.asarray(p, dtype=float))
    G1 = persson_G(q, C, q[-1:], E_star)[0]
    G_c = percolation_G(p, area, correction, gamma)
    open_ = G_c < G1
    level = G_c / (0.25 * np.pi * E_star**2)
    zeta_c = np.where(open_, inverse_cumulative_integral(q, q**3 * C, level) / q[0], np.nan)
    u1 = np.zeros_like(p)
    for i in np.flatnonzero(open_):
        u1[i] = critical_gap(q, C, zeta_c[i], p[i:i + 1], E_star=E_star, alpha=alpha, refinement=refinement,
                             numerics=numerics, correction=correction, gamma=gamma)[0]
    return zeta_c, u1


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
        As in :func:`gap_above` (``p`` an array (P,)).
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


def leakage_kernel(q, C, p, *, E_star, alpha, refinement="none", numerics=None, area=PERCOLATION_AREA,
                   bins_per_decade=20, points_per_decade=20, q_top=None,
                   methods=("critical_junction", "effective_medium"), correction="persson", gamma=None):
    """Both theories for every (spectrum, pressure): zeta_c, u1 (m), sigma_cj = u1^3 and sigma_emt (m^3).

    ``C`` (..., n) and ``p`` (...) broadcast against each other (as xarray hands them over);
    the spectra are handled one at a time and all of a spectrum's pressures at once, on the band
    [qL, q_top] (default: the whole grid; :func:`band_grid`). A method left out of ``methods``
    is NaN; ``bins_per_decade`` and ``points_per_decade`` are those of :func:`gap_distribution`;
    ``correction`` and ``gamma`` the contact-area theory of A(zeta)/A0 (:func:`contact_argument`).

    Returns
    -------
    zeta_c, u1, sigma_cj, sigma_emt : arrays, the broadcast shape of C[..., 0] and p
    """
    C = np.asarray(C, dtype=float)
    p = np.asarray(p, dtype=float)
    shape = np.broadcast_shapes(C.shape[:-1], p.shape)
    C = C.reshape((1,) * (len(shape) - C.ndim + 1) + C.shape)
    p = np.broadcast_to(p, shape)
    out = [np.full(shape, np.nan) for _ in range(4)]
    kw = dict(E_star=E_star, alpha=alpha, refinement=refinement, numerics=numerics, correction=correction,
              gamma=gamma)
    for idx in np.ndindex(C.shape[:-1]):
        sel = tuple(i if n > 1 else slice(None) for i, n in zip(idx, C.shape[:-1], strict=True))
        ps = p[sel]
        flat = ps.ravel()
        qs, Cs = (q, C[idx]) if q_top is None or q_top >= q[-1] else band_grid(q, C[idx], q[0], q_top)
        if "critical_junction" in methods:
            zeta_c, u1 = critical_junction(qs, Cs, flat, area=area, **kw)
            out[0][sel], out[1][sel], out[2][sel] = (v.reshape(ps.shape) for v in (zeta_c, u1, u1**3))
        if "effective_medium" in methods:
            u, weight, top = gap_distribution(qs, Cs, flat, bins_per_decade=bins_per_decade,
                                              points_per_decade=points_per_decade, **kw)
            out[3][sel] = bruggeman_flow_factor(u, weight, top).reshape(ps.shape)
    return tuple(out)
