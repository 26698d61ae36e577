"""Adhesion of rough surfaces in full contact (Persson & Tosatti 2001, extended to two rough
surfaces), and what the partial-contact solver (:mod:`.volterra`) builds on: the S_el models,
the Volterra grid and the dimensionless arrays of the problem (:class:`AdhesionProblem`).

Full-contact theory (seed eq 13 with P = S = 1):

.. math::

    \\gamma_{eff} / \\Delta\\gamma = F - \\frac{2\\pi}{\\delta} \\int_{q_L}^{q_1} q^2 C(q)\\, dq,
    \\quad F = 1 + \\frac{\\sqrt{\\pi}\\, \\xi}{2} \\mathrm{erfcx}(1/\\xi),
    \\quad \\delta = 4 \\Delta\\gamma / E^*

(eqs 11, 14; xi^2 = 2 pi int q^3 C dq, eq 12). For two rough surfaces the combined PSD
(:func:`roughcontact.physics.spectra.psd_combined`, seed eq 52) replaces C(q).

See docs/theory.md, section "Adhesion", and docs/adhesion.md; B. N. J. Persson and
E. Tosatti, J. Chem. Phys. 115, 5597 (2001).
"""

from __future__ import annotations

import numpy as np

from .contact import persson_G
from .quadrature import integral, integral_to
from .special import erfcx
from .spectra import rms_slope_from_psd

#: Elastic-energy factor models S_el(P) in U_el (seed eq 10): name -> description.
MODELS = {
    "alpha": "S_el = alpha (constant; the seed, eq 10/13)",
    "yang_persson": "S_el = gamma + (1 - gamma) P^2 (Yang & Persson 2008; equals 1 at full contact)",
}


def elastic_energy_coefficients(model, alpha, gamma):
    """Coefficients (c0, c1) of S_el = c0 + c1 P^2 for one of :data:`MODELS` (seed eq 10).

    Parameters
    ----------
    model : str
        ``"alpha"`` (S_el = alpha: c0 = alpha, c1 = 0) or ``"yang_persson"``
        (S_el = gamma + (1 - gamma) P^2: c0 = gamma, c1 = 1 - gamma).
    alpha, gamma : float
        Dimensionless parameters of the two models, in (0, 1] and [0, 1].

    Returns
    -------
    (float, float)

    References
    ----------
    C. Yang and B. N. J. Persson, J. Phys.: Condens. Matter 20, 215214 (2008).
    """
    if model == "alpha":
        return alpha, 0.0
    if model == "yang_persson":
        return gamma, 1.0 - gamma
    raise ValueError(f"unknown elastic-energy model {model!r}")


def adhesion_length(delta_gamma, E_star):
    """Adhesion length delta = 4 Delta_gamma / E* (m), seed eq 14.

    Parameters
    ----------
    delta_gamma : float
        Interfacial binding energy per unit area of flat surfaces (J/m^2).
    E_star : float
        Effective modulus E/(1 - nu^2) (Pa).

    Returns
    -------
    float
        delta in m.
    """
    return 4.0 * delta_gamma / E_star


def surface_area_factor(xi):
    """Surface-area enhancement F, seed eq 11 (dimensionless).

    .. math::

        F = \\int_0^\\infty (1 + \\xi^2 x)^{1/2} e^{-x} dx
          = 1 + \\frac{\\sqrt{\\pi}\\, \\xi}{2} \\mathrm{erfcx}(1/\\xi)

    F(0) = 1, F ~ (sqrt(pi)/2) xi for large xi.

    Parameters
    ----------
    xi : array
        Root-mean-square slope (dimensionless), xi^2 = 2 pi int q^3 C dq (eq 12).

    Returns
    -------
    array
        F, same shape as ``xi``.
    """
    xi = np.asarray(xi, dtype=float)
    with np.errstate(divide="ignore"):
        inv = np.where(xi > 0, 1.0 / np.where(xi > 0, xi, 1.0), np.inf)
    return 1.0 + 0.5 * np.sqrt(np.pi) * xi * erfcx(inv)


def gamma_eff_full_contact(q, C, delta):
    """Full-contact effective interfacial energy gamma_eff / Delta_gamma (seed eq 13, P = S = 1).

    .. math:: \\gamma_{eff}/\\Delta\\gamma = F - \\frac{2\\pi}{\\delta} \\int_{q_L}^{q_1} q^2 C\\, dq

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m), log grid.
    C : array (..., n)
        Combined PSD (m^4).
    delta : float
        Adhesion length (m), eq 14.

    Returns
    -------
    array (...)
        Dimensionless; negative means the full-contact theory predicts no adhesion.
    """
    F = surface_area_factor(rms_slope_from_psd(q, C))
    return F - 2.0 * np.pi / delta * integral(q, np.asarray(q) ** 2 * C)


def zeta_grid(zeta1, points_per_decade, zeta_offset):
    """Nodes of the Volterra grid of the partial-contact solver (dimensionless).

    zeta = 1, then 1 + (zeta1 - 1) geometric in (zeta - 1) from ``zeta_offset`` up,
    ``points_per_decade`` per decade of (zeta - 1). Near zeta = 1, a(zeta) ~ f(1)(zeta - 1):
    the grid is geometric in a there (where the detachment layer sits when sigma_a(1) is
    small) and geometric in zeta far from 1.

    Parameters
    ----------
    zeta1 : float
        Largest magnification q1/qL, > 1.
    points_per_decade : int
        Nodes per decade of zeta - 1.
    zeta_offset : float
        Smallest zeta - 1 (lowered to 0.1 (zeta1 - 1) if larger).

    Returns
    -------
    array (M,)
        Increasing nodes, zeta[0] = 1, zeta[-1] = zeta1.
    """
    if zeta1 <= 1.0:
        raise ValueError("zeta1 must exceed 1")
    top = zeta1 - 1.0
    lo = min(zeta_offset, 0.1 * top)
    decades = np.log10(top / lo)
    n = max(2, int(np.ceil(decades * points_per_decade)))
    return np.concatenate([[1.0], 1.0 + top * np.logspace(-decades, 0.0, n + 1)])


def layer_resolving_offset(q, C, E_star, delta_gamma, offset, K_min, sigma0=0.0, margin=1e-3):
    """Smallest zeta - 1 of the Volterra grid that resolves the detachment layer at zeta -> 1.

    Detachment starts where a(zeta) ~ (sigma_a(1) + sigma0)^2; on the attached branch
    sigma_a(1)^2 >= K_min F Delta_gamma E* qL (eq 6). The first grid cell must be much thinner:

    .. math:: G(1 + \\mathrm{offset}) \\le \\mathrm{margin}\\, (\\sigma_{a,min} + \\sigma_0)^2

    for every PSD of the batch (G of seed eq 17). Returns ``offset`` if it already does, else
    the (smaller) offset that does (a ~ zeta - 1 there).

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m), q[0] = qL.
    C : array (B, n)
        Combined PSDs (m^4).
    E_star : float
        Effective modulus (Pa).
    delta_gamma : float
        Interfacial binding energy (J/m^2).
    offset : float
        The requested smallest zeta - 1.
    K_min : float
        The smallest gamma_eff(1)/(F Delta_gamma) solved for.
    sigma0 : float
        Nominal compressive stress (Pa).
    margin : float
        Largest a(first node) relative to the layer's width in a.

    Returns
    -------
    float
        The smallest zeta - 1 to use (dimensionless).
    """
    C = np.atleast_2d(np.asarray(C, dtype=float))
    qL = float(q[0])
    F = surface_area_factor(rms_slope_from_psd(q, C))
    sigma_min = np.sqrt(K_min * float(np.min(F)) * delta_gamma * E_star * qL) + sigma0
    target = margin * sigma_min**2
    G1 = persson_G(q, C, np.array([qL * (1.0 + offset)]), E_star)[:, 0]
    worst = float(np.max(G1))
    if worst <= target:
        return offset
    return offset * target / worst


class AdhesionProblem:
    """Dimensionless arrays of the adhesion problem on the Volterra grid, for a batch of PSDs.

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m), q[0] = qL.
    C : array (B, n)
        Combined PSDs (m^4), one case per row.
    E_star, delta_gamma : float
        Effective modulus (Pa) and interfacial binding energy of flat surfaces (J/m^2).
    zeta : array (M,)
        Volterra nodes (:func:`roughcontact.physics.adhesion.zeta_grid`).

    Attributes
    ----------
    qL : float
        Lowest wavenumber (1/m).
    sigma_u2 : float
        Stress unit squared, Delta_gamma E* qL (Pa^2).
    G : array (B, M)
        Persson's G(zeta) (Pa^2, seed eq 17), made non-decreasing from G(1) = 0.
    a : array (B, M)
        G / sigma_u2.
    wel : array (B, M - 1)
        (2 pi / delta) int q^2 C dq over each segment of the grid (eq 13).
    F : array (B,)
        Surface-area factor (eq 11).
    full : array (B,)
        Full-contact gamma_eff / Delta_gamma (eq 13 with P = S = 1).
    """

    def __init__(self, q, C, E_star, delta_gamma, zeta):
        C = np.atleast_2d(np.asarray(C, dtype=float))
        self.qL = float(q[0])
        self.sigma_u2 = delta_gamma * E_star * self.qL
        delta = adhesion_length(delta_gamma, E_star)
        upper = np.clip(zeta * self.qL, q[0], q[-1])
        G = persson_G(q, C, upper, E_star)
        G = np.maximum.accumulate(np.maximum(G - G[:, :1], 0.0), axis=1)
        self.a = G / self.sigma_u2
        self.G = G
        I2 = 2.0 * np.pi / delta * integral_to(q, q**2 * C, upper)
        self.wel = np.maximum(np.diff(I2, axis=1), 0.0)
        self.F = surface_area_factor(rms_slope_from_psd(q, C))
        self.full = self.F - I2[:, -1]
        self.zeta = zeta
