"""Non-adhesive contact of rough surfaces (Persson's theory): G(zeta), the relative contact
area A/A0 and the stress distribution P(sigma).

For two rough surfaces the combined PSD (:func:`roughcontact.physics.spectra.psd_combined`,
seed eq 52) replaces C(q) (eq 53). See docs/theory.md, section "Contact"; Persson, J. Chem.
Phys. 115, 3840 (2001).
"""

from __future__ import annotations

import numpy as np

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


def persson_G(q, C, q_upper, E_star):
    """G(zeta) = (pi/4) E*^2 \\int_{qL}^{zeta qL} q^3 C(q) dq  (Pa^2), seed eq 17 / eq 2.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        PSD on the grid (m^4).
    q_upper : array (m,)
        Upper limits zeta qL (1/m), within the grid.
    E_star : float
        Effective modulus (Pa).

    Returns
    -------
    array (..., m)
        G in Pa^2.

    References
    ----------
    docs/theory.md, section "Contact"; Persson, J. Chem. Phys. 115, 3840 (2001).
    """
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
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        arg = np.where(G > 0, p / (2.0 * np.sqrt(np.where(G > 0, G, 1.0))), np.inf)
    return erf(arg)


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
    p = np.asarray(p, dtype=float)[..., None]
    G = np.asarray(G, dtype=float)[..., None]
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


def stress_distribution_adaptive(level, p, G, width):
    """P(sigma) on a grid adapted to each (p, G): sigma = level * (p + width sqrt(G)).

    Parameters
    ----------
    level : array (k,)
        Uniform nodes in [0, 1].
    p, G : arrays (broadcast together)
        Nominal pressure (Pa) and Persson's G (Pa^2).
    width : float
        How many sqrt(G) beyond p the grid reaches (the tail beyond has mass below
        erfc(width / 2)). With G = 0 the grid reaches 2 p.

    Returns
    -------
    (P, sigma) : arrays (..., k)
        The distribution (1/Pa, eq 16) and the stress at each node (Pa).
    """
    p, G = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(G, dtype=float))
    top = np.where(G > 0, p + width * np.sqrt(np.maximum(G, 0.0)), 2.0 * p)
    sigma = np.asarray(level, dtype=float) * top[..., None]
    return stress_distribution(sigma, p, G), sigma
