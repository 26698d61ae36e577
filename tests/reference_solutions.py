"""Analytic oracles the tests check the package against (in the spirit of ContactMechanics'
``ReferenceSolutions/``): closed forms, and brute-force quadratures of the seed's equations
with no grid, written independently of :mod:`roughcontact.physics` so that a test compares two
derivations, not one with itself. Import them; do not re-derive them in a test file.

Conventions: SI units; Persson's isotropic PSD C(q) (m^4), with hrms^2 = 2 pi int q C(q) dq;
"seed" equations are those of the seed paper the package implements (docs/theory.md).
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.special import erf

#: the seed section 4.2 surfaces: H = 0.8, qL = q0 = 2e8 1/m, q1 = 4e10 1/m; E = 77.2 GPa, nu = 0.42
SEED_H, SEED_QL, SEED_Q1 = 0.8, 2e8, 4e10
SEED_E_STAR = 77.2e9 / (1 - 0.42**2)


# ---- self-affine spectra ---------------------------------------------------------------------


def self_affine_C0(hrms, H, qL, q0, q1):
    """The plateau C0 (m^4) of the self-affine PSD C = C0 for qL <= q < q0, C0 (q/q0)^(-2(1+H))
    for q0 <= q <= q1, from its rms height hrms (m): hrms^2 = 2 pi int q C dq gives

        C0 = hrms^2 / (pi [q0^2 - qL^2 + (q0^2 / H) (1 - (q0/q1)^(2H))])

    (Persson, J. Phys.: Condens. Matter 17 (2005) R1, eq 63 with the roll-off; qL = q0: no roll-off)."""
    return hrms**2 / (np.pi * (q0**2 - qL**2 + q0**2 / H * (1 - (q0 / q1) ** (2 * H))))


def self_affine_psd(q, C0, H, q0):
    """C(q) (m^4) = C0 below the roll-off q0 (1/m), C0 (q/q0)^(-2(1+H)) above (the band's ends are
    the caller's: evaluate it only on qL <= q <= q1)."""
    q = np.asarray(q, dtype=float)
    return np.where(q < q0, C0, C0 * (q / q0) ** (-2 * (1 + H)))


def self_affine_q3C_integral(dq, C0, H, qL, q0=None):
    """int_qL^(qL + dq) q'^3 C(q') dq' (m^2) of :func:`self_affine_psd` in closed form, for a scalar
    dq >= 0 (1/m): the plateau part C0 [(qL + d)^4 - qL^4] / 4 expanded in d = min(dq, q0 - qL),
    the power-law part C0 q0^4 [(q/q0)^(2-2H) - 1] / (2 - 2H) through expm1/log1p, so that neither
    cancels as dq -> 0. ``q0`` None: no roll-off (q0 = qL)."""
    q0 = qL if q0 is None else q0
    d = min(dq, q0 - qL)
    low = C0 * d * (4 * qL**3 + 6 * qL**2 * d + 4 * qL * d * d + d**3) / 4
    high = C0 * q0**4 * math.expm1((2 - 2 * H) * math.log1p((dq - d) / q0)) / (2 - 2 * H)
    return low + high


def self_affine_G(zeta, C0, H, qL, E_star, q0=None):
    """Persson's G(zeta) (Pa^2), seed eq 17: (pi/4) E*^2 int_qL^(zeta qL) q^3 C(q) dq, for the
    self-affine PSD of :func:`self_affine_q3C_integral` (E* in Pa, zeta scalar)."""
    return np.pi / 4 * E_star**2 * self_affine_q3C_integral((zeta - 1) * qL, C0, H, qL, q0)


def contact_area_ratio(p, G):
    """A/A0 = erf(p / (2 sqrt G)), seed eq 19 (p in Pa, G in Pa^2; Persson, J. Chem. Phys. 115
    (2001) 3840)."""
    return erf(p / (2 * np.sqrt(G)))


# ---- sinusoidal contact and flow ---------------------------------------------------------------


def westergaard_full_contact_pressure(h0, wavelength, E_star):
    """p* = pi E* h0 / lambda (Pa): the mean pressure that flattens the sinusoid h0 cos(2 pi x /
    lambda) against a rigid flat (Westergaard 1939; Johnson, Contact Mechanics, sec. 13.2)."""
    return np.pi * E_star * h0 / wavelength


def westergaard_contact_fraction(p_over_p_star):
    """The contact fraction 2a/lambda of the sinusoid at p/p* (<= 1): p/p* = sin^2(pi a / lambda),
    so 2a/lambda = (2/pi) arcsin(sqrt(p/p*)) (Johnson, Contact Mechanics, eq 13.13)."""
    return 2 / np.pi * np.arcsin(np.sqrt(p_over_p_star))


def reynolds_sinusoidal_gap(g0, g1):
    """The Reynolds flow factors (m^3) of the gap g = g0 + g1 cos(2 pi x / L), |g1| < g0: along x
    (the flow crosses every crest, in series) sigma = 1/<g^-3> = 2 (g0^2 - g1^2)^(5/2) / (2 g0^2 +
    g1^2), across x (the strips in parallel) <g^3> = g0^3 + 3 g0 g1^2 / 2. Returns (along, across)."""
    return 2 * (g0**2 - g1**2) ** 2.5 / (2 * g0**2 + g1**2), g0**3 + 1.5 * g0 * g1**2


# ---- brute-force quadratures of the seed's equations (no grid) ----------------------------------


def brute_force_u(p, zeta, C0, alpha=0.45, yang_persson=False, epsrel=1e-11, factor=None, *, H=SEED_H, qL=SEED_QL,
                  E_star=SEED_E_STAR):
    """Mean separation u (m) of seed eq 57 as written: sqrt(pi) alpha int dq q^2 C w int_p^inf
    dp'/p' S exp(-(w p'/E*)^2), S = 1 (or alpha -> alpha + 3(1-alpha) erf^2 inside, Yang-Persson;
    or ``factor(erf)``), both integrals by quad; w = (pi int q^3 C)^(-1/2) analytic for the pure
    power law C0 (q/qL)^(-2-2H) (no roll-off); q = qL + t^2 so that quad sees no endpoint singularity."""

    def w_of(t):  # w at q = qL + t^2
        m3 = self_affine_q3C_integral(t * t, C0, H, qL)  # int q^3 C dq from qL
        return (math.pi * m3) ** -0.5 if m3 > 0 else math.inf

    def inner(w):
        if not math.isfinite(w):
            return 0.0
        def f(lp):
            x = w * math.exp(lp) / E_star
            if factor is not None:
                return factor(math.erf(x)) * math.exp(-x * x)
            weight = alpha + 3 * (1 - alpha) * math.erf(x) ** 2 if yang_persson else alpha
            return weight * math.exp(-x * x)
        lo, mid = math.log(p), max(math.log(p), math.log(E_star / w)) + 4
        return (quad(f, lo, mid, epsabs=0, epsrel=epsrel / 10, limit=200)[0]
                + quad(f, mid, math.inf, epsabs=0, epsrel=epsrel / 10)[0])

    def outer(t):
        q = qL + t * t
        w = w_of(t)
        return 2 * t * q * q * C0 * (q / qL) ** (-2 - 2 * H) * w * inner(w) if math.isfinite(w) else 0.0

    # the E1 switch (w p/E* ~ 1) can sit arbitrarily close to t = 0: split the range geometrically
    edges = [0.0, *math.sqrt((zeta - 1) * qL) * np.geomspace(1e-12, 1.0, 25)]
    return math.sqrt(math.pi) * sum(quad(outer, a, b, epsabs=0, epsrel=epsrel, limit=200)[0]
                                    for a, b in zip(edges, edges[1:], strict=False))


def brute_force_mu(v, spec, psd_specs, sigma0, nu, rtol=1e-10):
    """Friction coefficient mu and A/A0 of seed eqs 61-62 (v in m/s, sigma0 in Pa) with no grid at
    all: quad over phi (adaptive) for the angular integrals of the analytic box modulus ``spec``
    (E0, E_inf, tau1, tau2 shifted by WLF from T_ref to T), and an adaptive ODE solver (DOP853,
    rtol 1e-10) for the q integrals of G and mu together, in the variable x = sqrt(ln(q/q0))
    (dq = 2 x q dx removes the integrable 1/sqrt(q - q0) of P(q) at q0). ``psd_specs``: the
    surfaces (H, hrms, qL = q0, q1; no roll-off), their PSDs summed (eta = 0)."""
    T, T_ref, C1, C2 = spec["T"], spec["T_ref"], spec["C1"], spec["C2"]
    aT = 10.0 ** (-C1 * (T - T_ref) / (C2 + T - T_ref))
    E0, Ei, t1, t2 = spec["E0"], spec["E_inf"], spec["tau1"] * aT, spec["tau2"] * aT
    D = (Ei - E0) / math.log(t2 / t1)

    def E(w):
        return E0 + D * (cmath.log(1 + 1j * w * t2) - cmath.log(1 + 1j * w * t1))

    q0, q1 = psd_specs[0]["qL"], psd_specs[0]["q1"]
    plateaus = [(s["H"], float(self_affine_C0(s["hrms"], s["H"], q0, q0, q1))) for s in psd_specs]

    def C(q):
        return sum(C0 * (q / q0) ** (-2 * (1 + H)) for H, C0 in plateaus)

    k = 1.0 / ((1 - nu * nu) * sigma0)
    opts = dict(epsabs=0.0, epsrel=rtol / 10, limit=400)

    def rhs(x, y):
        q = q0 * math.exp(x * x)
        jac = 2 * x * q
        A = quad(lambda p: abs(E(q * v * math.cos(p))) ** 2, 0, math.pi / 2, **opts)[0]
        B = quad(lambda p: math.cos(p) * E(q * v * math.cos(p)).imag, 0, math.pi / 2, **opts)[0]
        G = y[0]
        P = math.erf(1 / (2 * math.sqrt(G))) if G > 0 else 1.0
        c = q**3 * C(q) * jac
        return [0.5 * k * k * c * A, 2 * k * c * P * B]

    sol = solve_ivp(rhs, (0.0, math.sqrt(math.log(q1 / q0))), [0.0, 0.0], method="DOP853", rtol=rtol, atol=1e-30)
    G, mu = sol.y[:, -1]
    return mu, math.erf(1 / (2 * math.sqrt(G)))
