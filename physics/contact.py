"""Non-adhesive contact of rough surfaces (Persson's theory): G(zeta), the relative contact
area A/A0 and the stress distribution P(sigma).

For two rough surfaces the combined PSD (:func:`roughcontact.physics.spectra.psd_combined`,
seed eq 52) replaces C(q) (eq 53). See docs/theory.md, section "Contact"; Persson, J. Chem.
Phys. 115, 3840 (2001).
"""

from __future__ import annotations

import numpy as np

from .inputs import require_nonnegative, require_pressure
from .layered import layered_spectrum
from .quadrature import integral_to
from .special import erf


def effective_modulus(E, nu):
    """Effective (plane-strain) modulus of an elastic solid on a rigid substrate (Pa).

    .. math:: E^* = E / (1 - \\nu^2)

    Parameters
    ----------
    E : float or array
        Young's modulus (Pa), > 0.
    nu : float or array
        Poisson ratio (dimensionless), -1 < nu <= 0.5.

    Returns
    -------
    float or array
        E* in Pa.

    References
    ----------
    Seed eq 3; docs/theory.md, section "Elasticity".
    """
    return E / (1.0 - nu * nu)


def persson_G(q, C, q_upper, E_star, layer=None):
    """G(zeta) = (pi/4) E*^2 \\int_{qL}^{zeta qL} q^3 C(q) dq  (Pa^2), seed eq 17 / eq 2.

    A coated solid (``layer``) has E_eff(q) under the integral:
    G = (pi/4) \\int q^3 C(q) E_eff(q)^2 dq, with E_star the substrate's E*
    (:func:`roughcontact.physics.layered.layered_spectrum`).

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        PSD on the grid (m^4).
    q_upper : array (m,)
        Upper limits zeta qL (1/m), within the grid.
    E_star : float
        Effective modulus (Pa); with a layer, the substrate's E_sub / (1 - nu_sub^2).
    layer : tuple or None
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub) of a coating on the
        elastic solid (:data:`roughcontact.physics.layered.LAYER_FIELDS`); None: a homogeneous
        half-space.

    Returns
    -------
    array (..., m)
        G in Pa^2.

    References
    ----------
    docs/theory.md, sections "Contact" and "Coated (layered) solids"; Persson, J. Chem. Phys.
    115, 3840 (2001); Persson, J. Phys.: Condens. Matter 24, 095008 (2012).
    """
    if layer is not None:
        C = layered_spectrum(q, C, layer)
    return (np.pi / 4.0) * E_star**2 * integral_to(q, np.asarray(q) ** 3 * C, q_upper)


def contact_area_ratio(p, G):
    """Relative contact area A/A0 = erf(p / (2 sqrt G)), seed eq 19 (dimensionless).

    G = 0 (no roughness at these scales) gives full contact, A/A0 = 1 for p > 0.
    Small p: A/A0 ~ p / sqrt(pi G) (eq 20).

    Parameters
    ----------
    p : array
        Nominal pressure (Pa), > 0.
    G : array
        Persson's G (Pa^2), >= 0.

    Raises ValueError for a negative p or G.
    """
    p, G = require_pressure(p), require_nonnegative(G, "G")
    positive = G > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        # the denominator on G's own (smaller) shape, then one array of the broadcast shape, filled
        # in place: a sweep's block of p x G makes no further temporaries of its size
        arg = np.asarray(np.divide(p, 2.0 * np.sqrt(np.where(positive, G, 1.0))))
    np.copyto(arg, np.inf, where=~positive)
    return erf(arg, out=arg) if arg.ndim else erf(arg[()])


def stress_distribution(sigma, p, G):
    """Stress distribution P(sigma) at nominal pressure p (1/Pa), seed eq 16 in its sinh form.

    P = (pi G)^-1/2 exp(-(sigma^2 + p^2)/(4G)) sinh(sigma p / (2G)), evaluated as
    (4 pi G)^-1/2 exp(-(sigma - p)^2/(4G)) (-expm1(-sigma p / G)), the same function without
    overflow of sinh or cancellation of the two Gaussians. Zero for sigma < 0. It integrates
    to A/A0 and its first moment is p.

    With G = 0 the distribution is a delta at sigma = p; on a grid it is returned as a
    spike of unit mass on the node nearest p (the grid spacing must be uniform there).

    Parameters
    ----------
    sigma : array (k,) or (..., k)
        Stress grid (Pa), uniform along the last axis; leading axes broadcast with p and G.
    p, G : arrays
        Nominal pressure (Pa) and Persson's G (Pa^2).

    Returns
    -------
    array (..., k)
    """
    sigma = np.asarray(sigma, dtype=float)
    p = require_pressure(p)[..., None]
    G = require_nonnegative(G, "G")[..., None]
    Gs = np.where(G > 0, G, 1.0)
    with np.errstate(over="ignore", under="ignore"):
        smooth = np.exp(-((sigma - p) ** 2) / (4.0 * Gs)) * -np.expm1(-np.maximum(sigma, 0.0) * p / Gs)
        smooth = np.where(sigma >= 0, smooth / np.sqrt(4.0 * np.pi * Gs), 0.0)
    if np.all(G > 0):
        return smooth
    step = sigma[..., 1:2] - sigma[..., 0:1] if sigma.shape[-1] > 1 else np.ones_like(sigma[..., :1])
    distance = np.abs(sigma - p)
    nearest = distance == np.min(distance, axis=-1, keepdims=True)
    first = np.cumsum(nearest, axis=-1) == 1  # one node only, if two are equally near
    with np.errstate(divide="ignore"):
        spike = np.where(nearest & first, 1.0 / step, 0.0)
    return np.where(G > 0, smooth, spike)


#: below this relative width w sqrt(G) / p the distribution is a delta at p for a float64 grid
DELTA_WIDTH = 1e-9


def stress_grid(level, p, G, width):
    """The stress grid of P(sigma) for each (p, G): where the distribution lives.

    sigma = lo + level (hi - lo) with lo = max(0, p - width sqrt(G)) and hi = p + width sqrt(G):
    near full contact (p >> sqrt(G)) the distribution is a Gaussian of width sqrt(2 G) about p,
    and a grid reaching from 0 would not resolve it; in partial contact lo = 0. Where
    width sqrt(G) < :data:`DELTA_WIDTH` p (G = 0, or too narrow for float64 about p) the
    distribution is a delta at p, and the grid is [0, 2 p].

    Parameters
    ----------
    level : array (k,)
        Uniform nodes in [0, 1].
    p, G : arrays (broadcast together)
        Nominal pressure (Pa, >= 0) and Persson's G (Pa^2, >= 0).
    width : float
        Half-width of the grid in units of sqrt(G) (the tails beyond hold erfc(width / 2)).

    Returns
    -------
    (sigma, delta) : arrays (..., k) and (...)
        The stress at each node (Pa), and where the distribution is a delta.
    """
    p, G = np.broadcast_arrays(require_pressure(p), require_nonnegative(G, "G"))
    half = width * np.sqrt(G)
    delta = half <= DELTA_WIDTH * p
    lo = np.where(delta, 0.0, np.maximum(p - half, 0.0))
    hi = np.where(delta, 2.0 * p, p + half)
    sigma = lo[..., None] + np.asarray(level, dtype=float) * (hi - lo)[..., None]
    return sigma, delta


def stress_distribution_adaptive(level, p, G, width):
    """P(sigma) on the grid of :func:`stress_grid`, and its mass on that grid.

    Parameters
    ----------
    level : array (k,)
        Uniform nodes in [0, 1].
    p, G : arrays (broadcast together)
        Nominal pressure (Pa) and Persson's G (Pa^2).
    width : float
        How many sqrt(G) about p the grid reaches (the tails beyond have mass below
        erfc(width / 2)).

    Returns
    -------
    (P, sigma, mass) : arrays (..., k), (..., k), (...)
        The distribution (1/Pa, eq 16), the stress at each node (Pa), and the integral of P
        over the grid by the trapezoidal rule, which equals A/A0 = erf(p / 2 sqrt G) to 1e-3 or
        better with at least 401 nodes and width >= 8 (tests/test_reliability.py); a coarser
        grid shows here how much of the distribution it misses.
    """
    sigma, delta = stress_grid(level, p, G, width)
    P = stress_distribution(sigma, p, np.where(delta, 0.0, G))
    return P, sigma, np.trapezoid(P, sigma, axis=-1)
