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

The theories are in :mod:`roughcontact.physics.critical_junction` and
:mod:`roughcontact.physics.effective_medium`, on Persson's contact seen at magnification zeta
(:mod:`roughcontact.physics.apparent_contact`); this module holds the leak rate, the sealing
pressure and the kernel that runs both.

See docs/theory.md, section "Interface: stiffness, conductance, leakage", and docs/interface.md.
"""

from __future__ import annotations

import numpy as np

from .apparent_contact import band_grid
from .contact import persson_G
from .critical_junction import PERCOLATION_AREA, critical_junction, percolation_G
from .effective_medium import bruggeman_flow_factor, gap_distribution


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


def sealing_pressure(q, C, E_star, area, q_top=None, correction="persson", gamma=None):
    """The nominal pressure (Pa) at which A/A0 over the band [qL, q_top] (default: the whole grid)
    reaches ``area``, so that the non-contact area stops percolating: sqrt(2 G / Phi(v_c))
    (:func:`~roughcontact.physics.critical_junction.percolation_G`; 2 sqrt(G) erfinv(area) for Persson,
    seed eq 19); C (..., n)."""
    q_top = q[-1] if q_top is None else q_top
    G = persson_G(q, C, np.array([q_top], dtype=float), E_star)[..., 0]
    return np.sqrt(G / percolation_G(1.0, area, correction, gamma))


def leakage_kernel(q, C, p, *, E_star, alpha, refinement="none", numerics=None, area=PERCOLATION_AREA,
                   bins_per_decade=20, points_per_decade=20, q_top=None,
                   methods=("critical_junction", "effective_medium"), correction="persson", gamma=None):
    """Both theories for every (spectrum, pressure): zeta_c, u1 (m), sigma_cj = u1^3 and sigma_emt (m^3).

    ``C`` (..., n) and ``p`` (...) broadcast against each other (as xarray hands them over);
    the spectra are handled one at a time and all of a spectrum's pressures at once, on the band
    [qL, q_top] (default: the whole grid; :func:`~roughcontact.physics.apparent_contact.band_grid`). A
    method left out of ``methods`` is NaN; ``bins_per_decade`` and ``points_per_decade`` are those of
    :func:`~roughcontact.physics.effective_medium.gap_distribution`; ``correction`` and ``gamma`` the
    contact-area theory of A(zeta)/A0 (:func:`~roughcontact.physics.apparent_contact.contact_argument`).

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
