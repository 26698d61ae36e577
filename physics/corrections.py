"""Contact-area corrections of Persson's theory: the pressure variance grown with a factor
S(A/A0) along the magnification.

Persson's eq 19 is A/A0 = erf(p / sqrt(2 V)) with V = 2 G the variance of the full-contact
stress distribution, dV_full = (pi/2) E*^2 q^3 C dq. The corrected theories grow the variance
with the contact fraction reached so far:

.. math:: \\frac{dV}{d\\zeta} = S\\big(A(\\zeta)/A_0\\big)\\,\\frac{dV_\\mathrm{full}}{d\\zeta},
          \\qquad A(\\zeta)/A_0 = \\mathrm{erf}\\big(p / \\sqrt{2 V(\\zeta)}\\big), \\qquad V(1) = 0,

* ``persson``: S = 1 (eq 19 exactly; Persson, J. Chem. Phys. 115, 3840 (2001));
* ``yang_persson``: S = gamma + (1 - gamma) a^2, gamma ~ 0.45 (Yang & Persson, J. Phys.:
  Condens. Matter 20, 215214 (2008));
* ``wang_mueser``: S = gamma - (2/9) a^2 + (11/9 - gamma) a^4, gamma = 5/9 (Wang & Müser,
  Tribol. Lett. 65, 103 (2017)).

**Exact solution.** In the reduced variance v = V / p^2 the ODE is separable and independent of
the spectrum: dv / S(erf(1/sqrt(2 v))) = dv_full, so

.. math:: \\Phi(v) \\equiv \\int_0^{v} \\frac{dv'}{S\\big(\\mathrm{erf}(1/\\sqrt{2 v'})\\big)} = v_\\mathrm{full}
          = \\frac{2 G}{p^2}.

Every correction is one universal, increasing function Phi: given eq 17's G, the corrected
variance is v = Phi^-1(2 G / p^2) and the stress distribution is eq 16 with G replaced by
G_eff = v p^2 / 2 (it integrates to the corrected A/A0 and its first moment is still p). Phi is
tabulated once per (correction, gamma) on panels geometric in v (Gauss-Legendre in ln v, the
project's :func:`~roughcontact.physics.quadrature.gauss_legendre_panels`) and inverted with the
project's root finder (:func:`~roughcontact.physics.roots.illinois`) inside one panel; S = 1
exactly below v = 1e-3 (erf(22) = 1 in double precision) and S = S(0) above v = 1e16
(A/A0 < 1e-8), where Phi is linear in closed form. See docs/theory.md, section
"Contact-area corrections".
"""

from __future__ import annotations

import functools

import numpy as np

from .contact import contact_area_ratio, persson_G
from .quadrature import gauss_legendre_panels
from .roots import illinois
from .separation import mean_separation, separation_nodes
from .special import erf

#: the corrections by name, with what each one means
CORRECTIONS = {
    "persson": "Persson 2001: S = 1 (seed eq 19)",
    "yang_persson": "Yang & Persson 2008: S = gamma + (1 - gamma) (A/A0)^2",
    "wang_mueser": "Wang & Mueser 2017: S = gamma - (2/9) (A/A0)^2 + (11/9 - gamma) (A/A0)^4",
}
#: published gamma of each correction (persson has none)
DEFAULT_GAMMA = {"persson": None, "yang_persson": 0.45, "wang_mueser": 5.0 / 9.0}

_V_LO, _V_HI, _PANELS_PER_DECADE, _ORDER = 1e-3, 1e16, 8, 12


def variance_factor(a, correction: str, gamma):
    """S(A/A0): the factor of the variance increment (dimensionless).

    Parameters
    ----------
    a : array
        Relative contact area A/A0 reached so far, in [0, 1].
    correction : {"persson", "yang_persson", "wang_mueser"}
        See :data:`CORRECTIONS`.
    gamma : float
        The correction's gamma (ignored for ``persson``).

    References
    ----------
    docs/theory.md, section "Contact-area corrections"; Yang & Persson, J. Phys.: Condens.
    Matter 20, 215214 (2008); Wang & Müser, Tribol. Lett. 65, 103 (2017).
    """
    a2 = np.asarray(a, dtype=float) ** 2
    if correction == "persson":
        return np.ones_like(a2)
    if correction == "yang_persson":
        return gamma + (1.0 - gamma) * a2
    if correction == "wang_mueser":
        return gamma - (2.0 / 9.0) * a2 + (11.0 / 9.0 - gamma) * a2 * a2
    raise ValueError(f"unknown correction {correction!r}; use one of {', '.join(CORRECTIONS)}")


def smallest_factor(correction: str, gamma) -> float:
    """min of S over 0 <= A/A0 <= 1 (S is a polynomial of degree <= 2 in b = (A/A0)^2)."""
    b = np.concatenate([np.linspace(0.0, 1.0, 2001), [1.0 / (11.0 - 9.0 * gamma)] if gamma is not None
                        and 11.0 - 9.0 * gamma > 1.0 else []])
    return float(np.min(variance_factor(np.sqrt(b), correction, gamma)))


def check_gamma(correction: str, gamma) -> None:
    """ValueError unless S > 0 on [0, 1] and S(1) = 1 (the correction must vanish in full contact)."""
    if correction not in CORRECTIONS:
        raise ValueError(f"unknown correction {correction!r}; use one of {', '.join(CORRECTIONS)}")
    if correction == "persson":
        return
    if not (gamma is not None and 0.0 < gamma <= 1.0):
        raise ValueError(f"gamma of {correction} must be in (0, 1], got {gamma}")
    if smallest_factor(correction, gamma) <= 0.0:
        raise ValueError(f"gamma = {gamma:g} makes the {correction} factor S(A/A0) <= 0 somewhere in [0, 1]")


def _integrand(v, correction, gamma):
    """1 / S(erf(1/sqrt(2 v))) times v (the integrand of Phi in ln v)."""
    with np.errstate(divide="ignore"):
        a = erf(1.0 / np.sqrt(2.0 * v))
    return v / variance_factor(a, correction, gamma)


@functools.lru_cache(maxsize=16)
def _table(correction: str, gamma):
    """Panel edges e_k (geometric in v from 1e-3 to 1e16) and Phi(e_k)."""
    decades = np.log10(_V_HI / _V_LO)
    edges = np.geomspace(_V_LO, _V_HI, int(round(decades * _PANELS_PER_DECADE)) + 1)
    t, w = gauss_legendre_panels(np.log(edges), _ORDER)
    pieces = (_integrand(np.exp(t), correction, gamma) * w).reshape(edges.size - 1, _ORDER).sum(-1)
    return edges, np.concatenate([[_V_LO], _V_LO + np.cumsum(pieces)])


def variance_function(v, correction: str, gamma):
    """Phi(v) = \\int_0^v dv' / S(erf(1/sqrt(2 v'))) (dimensionless), the reduced full-contact
    variance v_full = 2 G / p^2 at which the corrected reduced variance is v.

    Parameters
    ----------
    v : array
        Reduced variance V / p^2 >= 0.
    correction, gamma
        See :func:`variance_factor`.

    Returns
    -------
    array
        Phi(v), increasing, Phi(v) = v for v <= 1e-3.
    """
    v = np.asarray(v, dtype=float)
    edges, T = _table(correction, gamma)
    k = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, edges.size - 2)
    inside = (v > edges[0]) & (v < edges[-1])
    lo = np.log(edges[k])
    hi = np.log(np.where(inside, v, edges[k]))
    t, w = gauss_legendre_panels(np.stack([lo, hi], axis=-1), _ORDER)
    local = (_integrand(np.exp(t), correction, gamma) * w).sum(-1)
    s0 = float(variance_factor(0.0, correction, gamma))
    return np.where(v <= edges[0], v, np.where(inside, T[k] + local, T[-1] + (v - edges[-1]) / s0))


def reduced_variance(v_full, correction: str, gamma):
    """The corrected reduced variance v = Phi^-1(v_full) (dimensionless).

    Parameters
    ----------
    v_full : array
        2 G / p^2 >= 0 (inf allowed: returns inf).
    correction, gamma
        See :func:`variance_factor`.

    Returns
    -------
    array
        v with Phi(v) = v_full, to ~1e-14 relative; v = v_full for ``persson``.
    """
    y = np.asarray(v_full, dtype=float)
    if correction == "persson":
        return y.copy()
    check_gamma(correction, gamma)
    edges, T = _table(correction, gamma)
    s0 = float(variance_factor(0.0, correction, gamma))
    flat = y.ravel()
    inside = (flat > T[0]) & (flat < T[-1])
    out = np.where(flat <= T[0], flat, edges[-1] + (flat - T[-1]) * s0)
    if np.any(inside):
        target = flat[inside]
        k = np.clip(np.searchsorted(T, target, side="right") - 1, 0, edges.size - 2)
        lo, hi = edges[k], edges[k + 1]
        root = illinois(lambda v: variance_function(v, correction, gamma) - target, lo, hi,
                        T[k] - target, T[k + 1] - target, rtol=1e-15, maxiter=200)
        out[inside] = root.x
    return out.reshape(y.shape)


def corrected_G(p, G, correction: str, gamma):
    """G_eff = V / 2 of the corrected theory (Pa^2): eq 16 and eq 19 with G -> G_eff.

    .. math:: G_\\mathrm{eff} = \\frac{p^2}{2}\\,\\Phi^{-1}\\Big(\\frac{2G}{p^2}\\Big)

    Parameters
    ----------
    p : array
        Nominal pressure (Pa), > 0.
    G : array
        Persson's G of eq 17 (Pa^2), >= 0, broadcast against ``p``.
    correction, gamma
        See :func:`variance_factor`.

    Returns
    -------
    array
        G_eff (Pa^2), G_eff = G for ``persson``; 0 where G = 0; S_min G <= G_eff <= G.

    References
    ----------
    docs/theory.md, section "Contact-area corrections".
    """
    p, G = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(G, dtype=float))
    if correction == "persson":
        return G.copy()
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v_full = np.where(G > 0, 2.0 * G / (p * p), 0.0)
        v = reduced_variance(v_full, correction, gamma)
        out = np.where(np.isfinite(v), 0.5 * v * p * p, G * float(variance_factor(0.0, correction, gamma)))
    return np.where(G > 0, np.minimum(out, G), 0.0)


def corrected_area(x0, correction: str, gamma):
    """The corrected contact fraction as a function of eq 19's argument (dimensionless):
    A/A0 = erf(x) with Phi(1/(2 x^2)) = 1/(2 x0^2), x0 = p / (2 sqrt G).

    Used where a contact fraction of the form erf(x0) appears (the friction stage's
    P(q) = erf(1/(2 sqrt G(q)))).

    Parameters
    ----------
    x0 : array
        Argument of eq 19, >= 0 (inf: full contact).
    correction, gamma
        See :func:`variance_factor`.
    """
    x0 = np.asarray(x0, dtype=float)
    if correction == "persson":
        return erf(x0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = reduced_variance(np.where(x0 > 0, 0.5 / (x0 * x0), np.inf), correction, gamma)
        return np.where(x0 > 0, erf(1.0 / np.sqrt(2.0 * v)), 0.0)


#: the theory variants set against exact numerics: the contact correction and, for the mean
#: separation, the elastic-energy refinement of eq 57 that goes with it (persson: eq 57 with a
#: constant alpha; the others: their S(P) in the energy, alpha = the correction's gamma)
VARIANTS = {"persson": "none", "yang_persson": "yang_persson", "wang_mueser": "wang_mueser"}


def variant_theory(q, C, q_upper, p, E_star, variant: str, gamma=None, alpha=0.45, numerics=None, layer=None):
    """A/A0 and the mean separation u of one theory variant at one magnification.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (n,)
        Combined PSD (m^4).
    q_upper : float
        zeta qL (1/m), within the grid.
    p : array (k,)
        Nominal pressures (Pa), > 0.
    E_star : float
        Effective modulus (Pa).
    variant : {"persson", "yang_persson", "wang_mueser"}
        See :data:`VARIANTS`.
    gamma : float, optional
        The correction's gamma (default :data:`DEFAULT_GAMMA`); also alpha of its energy factor.
    alpha : float
        Persson's alpha of eq 57 for the ``persson`` variant.
    numerics : dict, optional
        ``panels_per_decade``, ``order``, ``depth`` of
        :func:`roughcontact.physics.separation.separation_nodes`.
    layer : tuple, optional
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub) of a coated solid (E_eff(q)
        in G and in the elastic energy; E_star is then the substrate's); None: a half-space.

    Returns
    -------
    (area, u) : arrays (k,)
        Dimensionless and m.

    References
    ----------
    docs/theory.md, sections "Contact-area corrections" and "Separation".
    """
    gamma = DEFAULT_GAMMA[variant] if gamma is None else gamma
    p = np.atleast_1d(np.asarray(p, dtype=float))
    upper = np.atleast_1d(float(q_upper))
    G = float(persson_G(q, C, upper, E_star, layer=layer)[0])
    area = contact_area_ratio(p, corrected_G(p, G, variant, gamma))
    s, weight, count, _, s_tail, q_tail = separation_nodes(q, C, upper, **(numerics or {}), layer=layer)
    u = mean_separation(p, s, weight, count, s_tail, q_tail, E_star=E_star,
                        alpha=alpha if variant == "persson" else gamma, refinement=VARIANTS[variant])
    return area, u[:, 0]
