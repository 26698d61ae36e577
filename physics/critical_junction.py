"""The critical-junction theory of a seal's leak rate (Persson & Yang, J. Phys.: Condens. Matter 20,
315011 (2008); Lorenz & Persson, Eur. Phys. Lett. 86, 44006 (2009)): increase the magnification
until the contact area A(zeta)/A0 falls to the percolation value a_c; the flow is limited by the
last open constriction, of separation u1(zeta_c); the flow factor is sigma = u1^3
(:func:`roughcontact.physics.leakage.leak_rate`).

See docs/theory.md, section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .apparent_contact import contact_argument, gap_above
from .contact import persson_G
from .corrections import variance_factor, variance_function
from .quadrature import inverse_cumulative_integral, loglog_interp
from .special import erf, erfinv

#: relative contact area at which the non-contact area stops percolating: 0.42 for randomly
#: rough, isotropic surfaces (Dapp, Luecke, Persson & Mueser, Phys. Rev. Lett. 108, 244301 (2012);
#: "of order 0.4" in Persson & Yang 2008's molecular dynamics)
PERCOLATION_AREA = 0.42


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
    (:func:`area_slope`); u_bar' is a central difference of
    :func:`~roughcontact.physics.apparent_contact.gap_above` over ln zeta +- ``step`` (one-sided at
    the band's ends; error ~ step^2). u1 = u_bar where A' = 0.

    Parameters
    ----------
    q, C, zeta, p, E_star, alpha, refinement, numerics, correction, gamma
        As in :func:`~roughcontact.physics.apparent_contact.gap_above` (``p`` an array (P,)).
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
        As in :func:`~roughcontact.physics.apparent_contact.gap_above`.
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
