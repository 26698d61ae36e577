"""Coated (layered) solids: the normal surface response of an elastic layer perfectly bonded to an
elastic half-space, and the wavenumber-dependent effective modulus E_eff(q) it gives.

A layer of thickness d (Young's modulus E_l, Poisson ratio nu_l) on a substrate (E_s, nu_s),
loaded by a normal pressure on a frictionless top surface. For one Fourier component of the
pressure the vertical surface displacement is

    u(q) = 2 p(q) / (q E_eff(q)),

the half-space law u = 2 p / (q E*) with E* = E/(1 - nu^2) replaced by E_eff(q): E_eff -> the
substrate's E* where the layer is thin compared with the wavelength (q d << 1) and the layer's
E* where it is thick (q d >> 1). In Persson's theory E_eff(q) enters under the q integrals
(G of eq 17, the elastic energy of eq 57): :func:`layered_spectrum` and :func:`modulus_weight`
put it there. Derivation (Papkovich-Neuber potentials in the layer and the substrate, six
boundary conditions) in docs/theory.md, section "Coated (layered) solids"; Persson, J. Phys.:
Condens. Matter 24, 095008 (2012).
"""

from __future__ import annotations

import numpy as np

#: a layered solid: (thickness d in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub)
LAYER_FIELDS = ("thickness", "E_layer", "nu_layer", "E_sub", "nu_sub")


def _require_elastic(E, nu, name: str) -> tuple[float, float]:
    E, nu = float(E), float(nu)
    if not E > 0:
        raise ValueError(f"{name} Young's modulus must be > 0 (Pa), got {E:g}")
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"{name} Poisson ratio must be in (-1, 0.5], got {nu:g}")
    return E, nu


def layer_constants(E_layer, nu_layer, E_sub, nu_sub):
    """The two bimaterial constants of the layered response and their complements (dimensionless).

    With g = mu_l / mu_s (shear moduli mu = E / 2(1 + nu)), a = 3 - 4 nu_s, b = 3 - 4 nu_l:

    .. math:: \\lambda = \\frac{g a - b}{1 + g a}, \\qquad m = \\frac{g - 1}{g + b},

    1 - lambda = 4 (1 - nu_l)/(1 + g a), 1 - m = 4 (1 - nu_l)/(g + b) and
    1 - lambda m = g (1 + a)(1 + b) / ((1 + g a)(g + b)), each formed without cancellation.
    Equal materials give lambda = m = 0.

    Parameters
    ----------
    E_layer, E_sub : float
        Young's moduli of the layer and the substrate (Pa), > 0.
    nu_layer, nu_sub : float
        Poisson ratios (dimensionless), -1 < nu <= 0.5.

    Returns
    -------
    (lam, m, one_minus_lam, one_minus_m, one_minus_lam_m) : floats

    References
    ----------
    docs/theory.md, section "Coated (layered) solids".
    """
    E_layer, nu_layer = _require_elastic(E_layer, nu_layer, "layer")
    E_sub, nu_sub = _require_elastic(E_sub, nu_sub, "substrate")
    g = (E_layer / (1.0 + nu_layer)) / (E_sub / (1.0 + nu_sub))
    a, b = 3.0 - 4.0 * nu_sub, 3.0 - 4.0 * nu_layer
    lam = (g * a - b) / (1.0 + g * a)
    m = (g - 1.0) / (g + b)
    one_minus_lam = 4.0 * (1.0 - nu_layer) / (1.0 + g * a)
    one_minus_m = 4.0 * (1.0 - nu_layer) / (g + b)
    one_minus_lam_m = g * (1.0 + a) * (1.0 + b) / ((1.0 + g * a) * (g + b))
    return lam, m, one_minus_lam, one_minus_m, one_minus_lam_m


def compliance_factor(qd, E_layer, nu_layer, E_sub, nu_sub):
    """S(qd) = E*_layer / E_eff(q): the surface compliance of the layered solid in units of the
    layer's half-space compliance (dimensionless).

    .. math:: S = \\frac{1 + 4 m\\, t X - \\lambda m X^2}
              {1 - (\\lambda + m + 4 m t^2) X + \\lambda m X^2}, \\qquad t = q d,\\ X = e^{-2t},

    with lambda, m of :func:`layer_constants`. Evaluated as
    N = (1 - lambda m) + lambda m (1 - X)(1 + X) + 4 m t X and
    D = ((1 - lambda) + lambda y)((1 - m) + m y) - 4 m t^2 X, y = 1 - X = -expm1(-2t), so that
    neither the thin-layer limit (X -> 1, where N and D become small for very different moduli)
    nor the thick-layer limit (X underflows to 0: S = 1) loses precision or overflows.
    S(0) = g (1 - nu_s)/(1 - nu_l) (the substrate), S(inf) = 1 (the layer).

    Parameters
    ----------
    qd : array
        Wavenumber times layer thickness (dimensionless), >= 0.
    E_layer, nu_layer, E_sub, nu_sub : float
        As in :func:`effective_modulus`.

    Returns
    -------
    array
        S, shape of ``qd``.

    References
    ----------
    docs/theory.md, section "Coated (layered) solids"; Persson, J. Phys.: Condens. Matter 24,
    095008 (2012).
    """
    t = np.asarray(qd, dtype=float)
    if np.any(t < 0):
        raise ValueError(f"q d must be >= 0, got {t[t < 0].flat[0]:g}")
    lam, m, oml, omm, omlm = layer_constants(E_layer, nu_layer, E_sub, nu_sub)
    with np.errstate(under="ignore", over="ignore", invalid="ignore"):
        X = np.exp(-2.0 * t)
        y = -np.expm1(-2.0 * t)
        tX = np.where(X > 0, t * X, 0.0)
        ttX = np.where(X > 0, t * tX, 0.0)
        N = omlm + lam * m * y * (1.0 + X) + 4.0 * m * tX
        D = (oml + lam * y) * (omm + m * y) - 4.0 * m * ttX
    return N / D


def effective_modulus(q, thickness, E_layer, nu_layer, E_sub, nu_sub):
    """Effective modulus E_eff(q) of an elastic layer bonded to an elastic half-space (Pa).

    Normal load on a frictionless surface, perfect bonding at the interface; the surface
    displacement of one Fourier component is u(q) = 2 p(q) / (q E_eff(q)) (the half-space
    convention, E* = E / (1 - nu^2)):

    .. math:: E_{\\rm eff}(q) = \\frac{E_l}{1 - \\nu_l^2}\\, \\frac{1}{S(q d)}, \\qquad
              S = \\frac{1 + 4 m\\, q d\\, e^{-2qd} - \\lambda m\\, e^{-4qd}}
              {1 - (\\lambda + m + 4 m (qd)^2)\\, e^{-2qd} + \\lambda m\\, e^{-4qd}}

    (:func:`compliance_factor`, :func:`layer_constants`). Limits: q d -> 0 gives the
    substrate's E_s/(1 - nu_s^2), q d -> inf the layer's E_l/(1 - nu_l^2); equal materials give
    the half-space exactly. Thin layer: E_eff = E*_s (1 - k1 q d + O((qd)^2)) with
    k1 = 4 m (1 + lambda)/(1 - lambda m) - (2 (lambda + m) - 4 lambda m)/((1 - lambda)(1 - m));
    thick layer: E_eff = E*_l (1 - (4 m (qd)^2 + 4 m qd + lambda + m) e^{-2qd} + ...).
    E_eff lies between the two E* at every q when the layer's shear and bulk moduli are both
    at most, or both at least, the substrate's (an energy argument; equal Poisson ratios are a
    case); otherwise it can leave that range (a nearly incompressible layer on a softer-in-bulk
    substrate is stiffer than either: docs/theory.md).

    Parameters
    ----------
    q : array
        Wavenumber (1/m), >= 0.
    thickness : float
        Layer thickness d (m), >= 0 (0: the bare substrate).
    E_layer : float
        Young's modulus of the layer (Pa), > 0.
    nu_layer : float
        Poisson ratio of the layer (dimensionless), -1 < nu <= 0.5.
    E_sub : float
        Young's modulus of the substrate (Pa), > 0.
    nu_sub : float
        Poisson ratio of the substrate (dimensionless), -1 < nu <= 0.5.

    Returns
    -------
    array
        E_eff(q) in Pa, shape of ``q``.

    Raises
    ------
    ValueError
        A Poisson ratio outside (-1, 0.5], a modulus <= 0, a negative thickness or q.

    References
    ----------
    docs/theory.md, section "Coated (layered) solids"; Persson, J. Phys.: Condens. Matter 24,
    095008 (2012).
    """
    d = float(thickness)
    if not d >= 0:
        raise ValueError(f"layer thickness must be >= 0 (m), got {d:g}")
    q = np.asarray(q, dtype=float)
    if np.any(q < 0):
        raise ValueError(f"q must be >= 0 (1/m), got {q[q < 0].flat[0]:g}")
    E_layer, nu_layer = _require_elastic(E_layer, nu_layer, "layer")
    return (E_layer / (1.0 - nu_layer * nu_layer)) / compliance_factor(q * d, E_layer, nu_layer, E_sub, nu_sub)


def surface_compliance(q, thickness, E_layer, nu_layer, E_sub, nu_sub):
    """Surface compliance of the layered solid, 2 / (q E_eff(q)) (m/Pa).

    .. math:: u_z(\\mathbf q) = \\frac{2}{q\\, E_{\\rm eff}(q)}\\, p(\\mathbf q)

    with u_z and p the Fourier transforms of the surface displacement (m, transformed: m^3) and
    the pressure (Pa, transformed: Pa m^2): the compliance is in m/Pa. It is |M_zz(q)| of
    Persson's notation (M_zz = -2/(q E_eff) with his sign for the displacement). Infinite at
    q = 0. This is the surface kernel of an FFT boundary-element contact solver for the coated
    solid.

    Parameters
    ----------
    q : array
        Wavenumber (1/m), >= 0.
    thickness, E_layer, nu_layer, E_sub, nu_sub
        As in :func:`effective_modulus`.

    Returns
    -------
    array
        In m/Pa, shape of ``q``.

    References
    ----------
    docs/theory.md, section "Coated (layered) solids"; Persson, J. Phys.: Condens. Matter 24,
    095008 (2012).
    """
    q = np.asarray(q, dtype=float)
    E = effective_modulus(q, thickness, E_layer, nu_layer, E_sub, nu_sub)
    with np.errstate(divide="ignore"):
        return 2.0 / (q * E)


def modulus_weight(q, layer):
    """E_eff(q) / E*_sub of a layered solid (dimensionless): how much stiffer (> 1) or softer
    (< 1) the coated surface is at wavenumber q than the bare substrate.

    Parameters
    ----------
    q : array
        Wavenumber (1/m), >= 0.
    layer : tuple
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub), see :data:`LAYER_FIELDS`.

    Returns
    -------
    array
        Shape of ``q``.

    References
    ----------
    docs/theory.md, section "Coated (layered) solids".
    """
    d, E_l, nu_l, E_s, nu_s = layer
    return effective_modulus(q, d, E_l, nu_l, E_s, nu_s) * (1.0 - nu_s * nu_s) / E_s


def layered_spectrum(q, C, layer):
    """The spectrum C(q) (E_eff(q)/E*_sub)^2 (m^4) that, with the substrate's E* in eq 17, gives
    G of the layered solid.

    .. math:: G(\\zeta) = \\frac{\\pi}{4} \\int_{q_L}^{\\zeta q_L} q^3 C(q) E_{\\rm eff}(q)^2 dq
              = \\frac{\\pi}{4} E_s^{*2} \\int_{q_L}^{\\zeta q_L} q^3 C(q)
              \\Big(\\frac{E_{\\rm eff}(q)}{E_s^*}\\Big)^2 dq

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m).
    C : array (..., n)
        PSD (m^4).
    layer : tuple
        See :func:`modulus_weight`.

    Returns
    -------
    array (..., n)
        In m^4.

    References
    ----------
    docs/theory.md, section "Coated (layered) solids"; Persson, J. Phys.: Condens. Matter 24,
    095008 (2012).
    """
    return np.asarray(C, dtype=float) * modulus_weight(q, layer) ** 2
