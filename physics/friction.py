"""Hysteretic rubber friction mu(v) and the relative contact area A/A0(v) while sliding, for an
elastic (viscoelastic) solid and a hard substrate that may both be rough.

With omega = q v cos(phi) (the seed's eq 30 is misprinted) and k = 1 / ((1 - nu^2) sigma0):

.. math::

    \\mu(v) = 2k \\int_{q_0}^{q_1} dq\\, q^3 C(q) P(q) S(q) \\int_0^{\\pi/2} d\\phi \\cos\\phi\\,
              E''(q v \\cos\\phi)

    G(q; v) = \\frac{k^2}{2} \\int_{q_0}^{q} dq'\\, q'^3 C(q') \\int_0^{\\pi/2} d\\phi\\,
              |E(q' v \\cos\\phi)|^2

    P(q) = \\mathrm{erf}(1 / (2\\sqrt{G(q)})), \\qquad A/A_0 = P(q_1),

which are the seed's eqs 61-62 (eqs 29-32 for one rough surface; C is the combined PSD of
eq 52) with the angular integrals over [0, 2 pi] folded onto [0, pi/2] (E(-omega) =
conj E(omega)), |E|^2 instead of the seed's "Im|E|^2" and the upper limit q instead of q_a in G
(seed misprints in eqs 32/62). S = 1 is the 2001 theory (the seed); S = gamma + (1 - gamma) P^2
is the later correction (Persson's papers from 2004 on, gamma ~ 1/2).

See docs/theory.md, section "Friction"; Persson, J. Chem. Phys. 115, 3840 (2001).
"""

from __future__ import annotations

import numpy as np

from .corrections import corrected_area
from .inputs import require_pressure
from .quadrature import cumulative_integral, gauss_legendre, running_weighted_integral
from .rows import row_chunks
from .special import erf
from .viscoelastic import modulus_at

#: Elements of one temporary array of the kernels below (125 KiB of float64): they work through
#: their leading axes (velocities, cases) a few rows at a time (:mod:`roughcontact.physics.rows`).
#: Whole-array temporaries (2.5-7.7 MB each for 100 velocities x 4 cases) were mapped fresh from
#: the OS and returned to it on every call: about 20 000 page faults and as much system time as
#: computing. Chunking changes no value (docs/scale-out.md).
CHUNK_ELEMENTS = 16_000


def _row_chunks(lead: tuple, per_row: int):
    """:func:`roughcontact.physics.rows.row_chunks` with this module's :data:`CHUNK_ELEMENTS`."""
    return row_chunks(lead, per_row, CHUNK_ELEMENTS)


def _k(sigma0, nu):
    """k = 1 / ((1 - nu^2) sigma0) (1/Pa)."""
    return 1.0 / ((1.0 - nu * nu) * require_pressure(sigma0, "sigma0", positive=True))


def angular_integrals(q, v, omega_grid, storage, loss, n_phi):
    """The two angular integrals of eqs 61-62, by Gauss-Legendre on [0, pi/2].

    .. math::

        A(q; v) = \\int_0^{\\pi/2} |E(q v \\cos\\phi)|^2 d\\phi, \\qquad
        B(q; v) = \\int_0^{\\pi/2} \\cos\\phi\\, E''(q v \\cos\\phi)\\, d\\phi

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m).
    v : array (...)
        Sliding velocities (m/s), > 0.
    omega_grid : array (m,)
        Geometric angular-frequency grid of the modulus (rad/s).
    storage, loss : arrays (..., m)
        E' and E'' on that grid (Pa); leading axes broadcast against ``v``.
    n_phi : int
        Gauss-Legendre nodes in phi.

    Returns
    -------
    (A, B) : arrays (..., n)
        A in Pa^2, B in Pa.

    References
    ----------
    docs/theory.md, section "Friction"; seed eqs 29, 32, 61, 62.
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    storage = np.asarray(storage, dtype=float)
    loss = np.asarray(loss, dtype=float)
    phi, weight = gauss_legendre(0.0, 0.5 * np.pi, n_phi)
    cos = np.cos(phi)
    lead = np.broadcast_shapes(v.shape, storage.shape[:-1], loss.shape[:-1])
    qcos = q[:, None] * cos  # (n, n_phi)
    A, B = np.empty(lead + q.shape), np.empty(lead + q.shape)
    v_rows = np.broadcast_to(v, lead)
    shared = storage.ndim == 1 and loss.ndim == 1  # one modulus for every row: not gathered per chunk
    if not shared:
        storage = np.broadcast_to(storage, lead + storage.shape[-1:])
        loss = np.broadcast_to(loss, lead + loss.shape[-1:])
    for rows in _row_chunks(lead, qcos.size):  # a few rows at a time (CHUNK_ELEMENTS)
        vr = v_rows[rows]
        omega = (vr[..., None, None] * qcos).reshape(vr.shape + (qcos.size,))
        Ep, Epp = modulus_at(omega, omega_grid, storage if shared else storage[rows], loss if shared else loss[rows])
        Ep, Epp = Ep.reshape(vr.shape + qcos.shape), Epp.reshape(vr.shape + qcos.shape)
        A[rows] = (Ep * Ep + Epp * Epp) @ weight
        B[rows] = (Epp * cos) @ weight
    return A, B


def sliding_G(q, C, A, sigma0, nu):
    """G(q; v) of the corrected eq 62 (dimensionless).

    .. math:: G(q; v) = \\frac{k^2}{2} \\int_{q_0}^{q} q'^3 C(q') A(q'; v)\\, dq', \\qquad
              k = \\frac{1}{(1 - \\nu^2)\\sigma_0}

    For a real constant modulus E it equals Persson's elastic G (eq 17) divided by sigma0^2.

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m).
    C : array (..., n)
        Combined PSD (m^4).
    A : array (..., n)
        Angular integral of |E|^2 from :func:`angular_integrals` (Pa^2).
    sigma0 : array (...)
        Nominal pressure (Pa).
    nu : float
        Poisson's ratio (dimensionless).

    Returns
    -------
    array (..., n)
        G (dimensionless), G(q0) = 0.

    References
    ----------
    docs/theory.md, section "Friction"; seed eqs 32, 62 (corrected).
    """
    k = _k(sigma0, nu)
    return 0.5 * k[..., None] ** 2 * cumulative_integral(q, np.asarray(q) ** 3 * C * A)


def contact_fraction(G, area_correction="persson", area_gamma=None):
    """Relative contact area at magnification q, P(q) = erf(1/(2 sqrt G)) (dimensionless).

    Parameters
    ----------
    G : array
        G(q; v) of :func:`sliding_G` (dimensionless), >= 0; G = 0 gives 1 (full contact at the
        largest scale).
    area_correction, area_gamma
        A contact-area correction (:func:`roughcontact.physics.corrections.corrected_area`):
        G is the variance of eq 31 in units of sigma0^2, so the same universal map of the
        argument 1/(2 sqrt G) applies. Default: eq 31 as printed (Persson 2001).

    References
    ----------
    docs/theory.md, sections "Friction" and "Contact-area corrections"; seed eq 31.
    """
    G = np.asarray(G, dtype=float)
    with np.errstate(divide="ignore"):
        x0 = np.where(G > 0, 0.5 / np.sqrt(np.where(G > 0, G, 1.0)), np.inf)
    if area_correction == "persson":
        return erf(x0)
    return corrected_area(x0, area_correction, area_gamma)


def area_factor(P, correction: str, gamma: float):
    """The factor S(q) in mu (dimensionless).

    .. math:: S = 1 \\ (\\text{none}), \\qquad S = \\gamma + (1 - \\gamma) P^2 \\ (\\text{yang\\_persson})

    Parameters
    ----------
    P : array
        P(q) of :func:`contact_fraction` (dimensionless).
    correction : {"none", "yang_persson"}
        The seed's 2001 theory (S = 1) or the later correction.
    gamma : float
        gamma of the correction (dimensionless, ~ 1/2).

    References
    ----------
    docs/theory.md, section "Friction"; seed eq 29 (S = 1, Persson 2001); the correction S is Persson's
    from 2004 on.
    """
    if correction == "none":
        return np.ones_like(P)
    return gamma + (1.0 - gamma) * P * P


def friction_integrand(q, C, P, S, B, sigma0, nu):
    """d mu / d q of eq 61 (1/m): 2 k q^3 C P S B, k = 1/((1 - nu^2) sigma0).

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m).
    C : array (..., n)
        Combined PSD of the pair (m^4).
    P, S : arrays (..., n)
        :func:`contact_fraction` and :func:`area_factor` (dimensionless).
    B : array (..., n)
        Angular integral of cos(phi) E'' from :func:`angular_integrals` (Pa).
    sigma0 : array (...)
        Nominal pressure (Pa).
    nu : float
        Poisson's ratio (dimensionless).

    References
    ----------
    docs/theory.md, section "Friction"; seed eqs 29, 61.
    """
    k = _k(sigma0, nu)
    return 2.0 * k[..., None] * np.asarray(q) ** 3 * C * P * S * B


def friction_kernel(q, C, A, B, sigma0, nu, correction="none", gamma=0.5, extras=False, segment_nodes=12,
                    area_correction="persson", area_gamma=None):
    """mu(v) and A/A0(v) from the PSD and the angular integrals (eqs 61-62, 31).

    mu is integrated in the variable G: with dG/dq = (k^2/2) q^3 C A,

    .. math:: \\mu = 2k \\int q^3 C P S B\\, dq = \\frac{4}{k} \\int P(G) S(G) \\frac{B}{A}\\, dG,

    segment by segment by :func:`roughcontact.physics.quadrature.running_weighted_integral`
    (``segment_nodes`` Gauss-Legendre nodes per q segment). This keeps second-order accuracy
    where P(q) falls like 1/sqrt(q - q0) just above q0 (high velocities: G grows by orders of
    magnitude in the first q segment), where power-law quadrature of the integrand in q is only
    first order.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid of the PSD (1/m), from q0 to q1.
    C : array (..., n)
        Combined PSD of the two surfaces (m^4, seed eq 52).
    A, B : arrays (..., n)
        The angular integrals of :func:`angular_integrals` (Pa^2, Pa).
    sigma0 : array (...)
        Nominal pressure (Pa), the load of the sliding contact.
    nu : float
        Poisson's ratio (dimensionless).
    correction, gamma
        The factor S of :func:`area_factor`.
    extras : bool
        Also return G(q; v) and d mu / d ln q.
    segment_nodes : int
        Gauss-Legendre nodes per q segment.
    area_correction, area_gamma
        The contact-area correction of P(q) (:func:`contact_fraction`).

    Returns
    -------
    (mu, area) or (mu, area, G, dmu_dlnq)
        Friction coefficient and A/A0 (dimensionless, shape (...)) and, with ``extras``,
        G and d mu / d ln q over q (dimensionless, (..., n)).

    References
    ----------
    docs/theory.md, section "Friction"; seed eqs 29-32, 61-62 (corrected); Persson, J. Chem. Phys. 115,
    3840 (2001).
    """
    k = _k(sigma0, nu)
    q = np.asarray(q, dtype=float)
    C, A, B = (np.asarray(x, dtype=float) for x in (C, A, B))
    lead = np.broadcast_shapes(C.shape[:-1], A.shape[:-1], B.shape[:-1], k.shape)
    C, A, B = (np.broadcast_to(x, lead + q.shape) for x in (C, A, B))
    sigma0, k = np.broadcast_to(sigma0, lead), np.broadcast_to(k, lead)
    mu, area = np.empty(lead), np.empty(lead)
    if extras:
        G_out, density = np.empty(lead + q.shape), np.empty(lead + q.shape)

    def weight(G):
        P = contact_fraction(G, area_correction, area_gamma)
        return P * area_factor(P, correction, gamma)

    # a few (case, v) rows at a time (CHUNK_ELEMENTS): the q integral's temporaries are
    # (rows, q segments, segment_nodes)
    for rows in _row_chunks(lead, max(q.size - 1, 1) * segment_nodes):
        kr, Ar, Br, Cr = k[rows], A[rows], B[rows], C[rows]
        g = 0.5 * kr[..., None] ** 2 * q ** 3 * Cr * Ar
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(Ar > 0, Br / np.where(Ar > 0, Ar, 1.0), 0.0)
        integral, G = running_weighted_integral(q, g, r, weight, nodes=segment_nodes)
        mu[rows] = 4.0 / kr * integral
        P = contact_fraction(G, area_correction, area_gamma)
        area[rows] = P[..., -1]
        if extras:
            S = area_factor(P, correction, gamma)
            G_out[rows] = G
            density[rows] = friction_integrand(q, Cr, P, S, Br, sigma0[rows], nu) * q
    if extras:
        return mu, area, G_out, density
    return mu, area


def contact_shear_gaussian(v_reduced, tau0, v0, c):
    """Frictional shear stress of the real contact area, the Gaussian-in-log-velocity law (Pa).

    .. math:: \\tau_f(v, T) = \\tau_{f0}\\,\\exp\\Big[-c\\,\\Big(\\log_{10}\\frac{v\\,a_T}{v_0}\\Big)^2\\Big]

    Parameters
    ----------
    v_reduced : array
        Sliding velocity reduced to the reference temperature, v a_T(T) (m/s), > 0 (a_T of the
        modulus' temperature law, read at the contacts' temperature).
    tau0 : float
        Peak shear stress tau_f0 (Pa), >= 0.
    v0 : float
        Reduced velocity of the peak (m/s), > 0.
    c : float
        Width parameter (dimensionless, > 0): the stress falls to tau0/e at 1/sqrt(c) decades
        from v0.

    References
    ----------
    docs/theory.md, section "Contact shear term"; Lorenz et al., J. Chem. Phys. 142, 194701 (2015);
    Fortunato et al., J. Phys.: Condens. Matter 27, 175008 (2015).
    """
    x = np.log10(np.asarray(v_reduced, dtype=float) / v0)
    return tau0 * np.exp(-c * x * x)


def contact_shear_table(v_reduced, v_table, tau_table):
    """Frictional shear stress of the real contact area from a table (Pa): linear in log10 of the
    reduced velocity between the table's points, held at the end values outside.

    Parameters
    ----------
    v_reduced : array
        v a_T(T) (m/s), > 0.
    v_table : array (m,)
        Increasing reduced velocities of the table (m/s), > 0.
    tau_table : array (m,)
        tau_f at those velocities (Pa), >= 0.

    References
    ----------
    docs/theory.md, section "Contact shear term".
    """
    return np.interp(np.log10(np.asarray(v_reduced, dtype=float)), np.log10(np.asarray(v_table, dtype=float)),
                     np.asarray(tau_table, dtype=float))


def contact_friction(tau, area, sigma0):
    """mu_cont = tau_f (A/A0) / sigma0, the friction of shearing the real contact area (dimensionless).

    .. math:: \\mu_\\mathrm{cont} = \\frac{\\tau_f(v, T_c)\\,A(v)/A_0}{\\sigma_0}

    Parameters
    ----------
    tau : array
        Frictional shear stress of the contacts (Pa).
    area : array
        Relative contact area while sliding A/A0 (dimensionless), at the magnification q1.
    sigma0 : array
        Nominal pressure (Pa), > 0.

    References
    ----------
    docs/theory.md, section "Contact shear term"; Persson & Volokitin, Eur. Phys. J. E 21, 69 (2006);
    Lorenz et al., J. Chem. Phys. 142, 194701 (2015).
    """
    return np.asarray(tau, dtype=float) * np.asarray(area, dtype=float) / np.asarray(sigma0, dtype=float)
