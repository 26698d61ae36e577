"""What the interface transmits: normal contact stiffness and thermal / electrical contact
conductance per unit nominal area, from the separation law u(p) of the two rough surfaces.

Stiffness (Persson, Phys. Rev. Lett. 99, 125502 (2007)): K = -dp/du, with du/dp taken
analytically from eq 57 on the separation's own quadrature nodes (:func:`separation_log_slope`),
so K = p / D with D = -du/d(ln p); K -> p/u0 at small load (seed eq 59).

Conductance (Barber, Proc. R. Soc. A 459, 53 (2003); Persson, Lorenz & Volokitin, Eur. Phys.
J. E 31, 3 (2010)): for two elastic half-spaces touching in any set of spots, the electrical
conductance and the incremental normal stiffness solve the same mixed boundary-value problem,
so per unit nominal area

    G_el = 2 K / (E* (rho1 + rho2)),    h = 2 K / (E* (1/kappa1 + 1/kappa2)).

Assumptions: heat and current pass only through the real contact (no gas, no radiation, no
film or constriction resistance inside a spot), conductivities constant, small slopes (the
half-space approximation of the elastic and the transport problems alike). See docs/theory.md,
section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .separation import energy_factor_terms, node_sum, separation_nodes
from .special import erf, erfcx


def gaussian_integral(s, a):
    """F1(s) = \\int_0^s exp(-a^2 / s'^2) ds' in closed form (units of ``s``), 0 where a/s > 6.

    .. math:: F_1(s) = s\\, e^{-z^2} \\big(1 - \\sqrt{\\pi}\\, z\\, \\mathrm{erfcx}(z)\\big), \\qquad z = a/s

    (= s exp(-z^2) - sqrt(pi) a erfc(z)): the tail of :func:`separation_log_slope`, where q(s) is
    constant. ``s`` >= 0 (dimensionless, like 1/w), ``a`` = p/E* >= 0, broadcast. See docs/theory.md,
    section "Interface: stiffness, conductance, leakage".
    """
    s, a = np.broadcast_arrays(np.asarray(s, dtype=float), np.asarray(a, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        z = a / s
        value = s * np.exp(-z * z) * (1.0 - np.sqrt(np.pi) * z * erfcx(z))
    return np.where((s > 0) & (z <= 6.0), value, 0.0)


def separation_log_slope(p, s, weight, count, s_tail, q_tail, *, E_star, alpha, refinement="none"):
    """D(p) = -du/d(ln p) (m), eq 57 differentiated analytically: the contact stiffness is K = p / D.

    With d E1(x^2)/dp = -2 exp(-x^2)/p (x = w p/E*), on the nodes of
    :func:`roughcontact.physics.separation.mean_separation`:

    .. math:: D = \\sqrt{\\pi}\\, \\alpha \\int_{q_L}^{\\zeta q_L} q^2 C w\\, e^{-(w p/E^*)^2} dq
              = \\frac{2 \\alpha}{\\sqrt{\\pi}} \\int_0^{1/w(\\zeta q_L)} e^{-(p/(E^* s))^2} \\frac{ds}{q(s)}

    tail [0, s_tail] in closed form (:func:`gaussian_integral`). A refinement whose energy factor
    gives d(P S)/dP = sum_k c_k P^k (:func:`roughcontact.physics.separation.energy_factor_terms`;
    c_0 = alpha) puts sum_k c_k erf(x)^k in place of alpha under the integral (d/dp of the
    refinement's J_k(x) is -erf(x)^k exp(-x^2)/p); on the tail, the midpoint of erf^k's bounds
    erf(a/s_tail)^k and 1 (error below s_tail / S). D -> u0 as p -> 0 (seed eq 59).

    Parameters
    ----------
    p : array (...)
        Nominal pressure (Pa), > 0, broadcast against the nodes' leading dims.
    s, weight, count, s_tail, q_tail
        From :func:`roughcontact.physics.separation.separation_nodes`.
    E_star : float
        Effective modulus (Pa).
    alpha : float
        Persson's gamma, 0 < alpha <= 1.
    refinement : str
        A key of :data:`roughcontact.physics.separation.REFINEMENTS`.

    Returns
    -------
    array (..., m)
        D (m) at each upper limit zeta qL; 0 where the combined PSD vanishes.

    References
    ----------
    docs/theory.md, section "Interface: stiffness, conductance, leakage"; Persson, Phys. Rev. Lett.
    99, 125502 (2007); Yang & Persson, J. Phys.: Condens. Matter 20, 215214 (2008).
    """
    a = np.asarray(p, dtype=float)[..., None] / E_star
    with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
        z = np.where(s > 0, a / np.where(s > 0, s, 1.0), np.inf)
        zt = np.where(s_tail > 0, a / np.where(s_tail > 0, s_tail, 1.0), np.inf)
    gauss = np.exp(-np.minimum(z * z, 800.0))
    body, tail = 0.0, 0.0
    for k, c in energy_factor_terms(refinement, alpha).items():
        body = body + c * (erf(z) ** k if k else 1.0)
        tail = tail + c * (0.5 * (1.0 + erf(zt) ** k) if k else 1.0)
    tail = tail * gaussian_integral(s_tail, a) / q_tail[..., None]
    return 2.0 / np.sqrt(np.pi) * (node_sum(weight * gauss * body, count) + tail)


def contact_stiffness(p, D):
    """Normal contact stiffness per unit nominal area K = -dp/du = p / D (Pa/m).

    Parameters
    ----------
    p : array
        Nominal pressure (Pa), > 0.
    D : array
        -du/d(ln p) (m), >= 0, from :func:`roughcontact.physics.separation.separation_log_slope`
        (broadcast against ``p``).

    Returns
    -------
    array
        K (Pa/m); +inf where D = 0: no roughness left to compress (identical surfaces with
        eta = 1, or full contact where exp(-(w p/E*)^2) underflows), the interface adds no
        compliance.

    References
    ----------
    Persson, Phys. Rev. Lett. 99, 125502 (2007); docs/theory.md, section "Interface: stiffness,
    conductance, leakage".
    """
    p, D = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(D, dtype=float))
    with np.errstate(divide="ignore", over="ignore"):  # D below ~1e-300 p: K = inf, as for D = 0
        return np.where(D > 0, p / np.where(D > 0, D, 1.0), np.inf)


def stiffness_from_psd(q, C, q_upper, p, *, E_star, alpha, refinement="none", panels_per_decade=2, order=3,
                       depth=10.0, layer=None):
    """-du/d(ln p) (m) and K = -dp/du (Pa/m) at every upper limit zeta qL, from the combined PSD.

    The nodes of eq 57 (:func:`roughcontact.physics.separation.separation_nodes`) are built for
    each spectrum and the analytic derivative is summed on them: no finite differences, every
    pressure independent of the others (so ``p`` may be chunked).

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        Combined PSD (m^4), seed eq 52.
    q_upper : array (m,)
        Upper limits zeta qL (1/m).
    p : array (...)
        Nominal pressure (Pa), > 0, broadcast against the leading dims of ``C``.
    E_star, alpha, refinement
        As in :func:`roughcontact.physics.separation.mean_separation`.
    panels_per_decade, order, depth, layer
        As in :func:`roughcontact.physics.separation.separation_nodes` (with a layer, E_star is
        the substrate's E*).

    Returns
    -------
    D : array (..., m)
        -du/d(ln p) (m).
    K : array (..., m)
        Contact stiffness (Pa/m), +inf where D = 0.

    References
    ----------
    docs/theory.md, section "Interface: stiffness, conductance, leakage" (seed eqs 57, 59).
    """
    s, weight, count, _, s_tail, q_tail = separation_nodes(q, C, q_upper, panels_per_decade, order, depth, layer)
    D = separation_log_slope(p, s, weight, count, s_tail, q_tail, E_star=E_star, alpha=alpha, refinement=refinement)
    return D, contact_stiffness(np.asarray(p, dtype=float)[..., None], D)


def barber_conductance(K, E_star, resistance_sum):
    """Contact conductance per unit nominal area by Barber's analogy, 2 K / (E* R).

    .. math:: G = \\frac{2 K}{E^* R}, \\qquad R = \\rho_1 + \\rho_2 \\ \\text{(electrical, Ohm m)}
              \\quad\\text{or}\\quad R = 1/\\kappa_1 + 1/\\kappa_2 \\ \\text{(thermal, m K/W)}

    Exact for two half-spaces in contact (linear transport, perfect contact inside the spots,
    nothing across the gaps): the constriction problem of each body is the elastic contact
    problem with potential in place of displacement. A single circular spot of radius a checks
    the prefactor: stiffness 2 a E*, conductance 4 a / (rho1 + rho2) (Holm).

    Parameters
    ----------
    K : array
        Normal contact stiffness per unit area (Pa/m), may be +inf.
    E_star : float
        Effective modulus (Pa) of the pair, 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (rigid
        substrate: E/(1 - nu^2)).
    resistance_sum : float
        rho1 + rho2 (Ohm m) or 1/kappa1 + 1/kappa2 (m K/W), > 0.

    Returns
    -------
    array
        Conductance per unit area: S/m^2 (electrical) or W/(m^2 K) (thermal); +inf where K is.

    References
    ----------
    Barber, Proc. R. Soc. A 459, 53 (2003); Persson, Lorenz & Volokitin, Eur. Phys. J. E 31, 3
    (2010); Holm, Electric Contacts (Springer, 1967); docs/theory.md, section "Interface:
    stiffness, conductance, leakage".
    """
    return 2.0 * np.asarray(K, dtype=float) / (E_star * resistance_sum)


def barber_resistance(p, D, E_star, resistance_sum):
    """The reciprocal of :func:`barber_conductance`, E* R D / (2 p): contact resistance times area
    (Ohm m^2 or m^2 K/W); finite everywhere, exactly 0 where the surfaces fit (D = 0).

    Parameters
    ----------
    p : array
        Nominal pressure (Pa), > 0.
    D : array
        -du/d(ln p) (m), >= 0.
    E_star : float
        Effective modulus (Pa).
    resistance_sum : float
        rho1 + rho2 (Ohm m) or 1/kappa1 + 1/kappa2 (m K/W).
    """
    return E_star * resistance_sum * np.asarray(D, dtype=float) / (2.0 * np.asarray(p, dtype=float))
