"""Power spectral densities: self-affine spectra, the combined PSD of two surfaces, and the
conversion of measured spectra to Persson's convention.

Convention (Persson, seed eq 4): C(q) = (2 pi)^-2 \\int d^2x <h(x) h(0)> exp(-i q.x), in m^4,
with hrms^2 = 2 pi \\int q C(q) dq. See docs/theory.md, section "Spectra".
"""

from __future__ import annotations

import numpy as np

from . import special
from .inputs import require_coherence
from .quadrature import integral, loglog_interp


def self_affine_hrms_factor(H, qL, q0, q1):
    """hrms^2 / C0 for the self-affine PSD with roll-off (docs/theory.md, section "Spectra").

    hrms^2 = pi C0 [ q0^2 - qL^2 + (q0^2 / H) (1 - (q0/q1)^(2H)) ]

    The last term is written as -expm1(2 H ln(q0/q1)) / H so that it stays accurate for
    H -> 0 and for q1 close to q0.

    Parameters
    ----------
    H : float or array
        Hurst exponent, 0 < H <= 1.
    qL, q0, q1 : float
        Lowest wavenumber, roll-off and upper cut-off (1/m), qL <= q0 < q1.

    Returns
    -------
    float or array
        hrms^2 / C0 in 1/m^2.

    References
    ----------
    Persson, J. Chem. Phys. 115, 3840 (2001); seed eq 63 (case qL = q0).
    """
    H = np.asarray(H, dtype=float)
    return np.pi * (q0**2 - qL**2 - q0**2 * np.expm1(2.0 * H * np.log(q0 / q1)) / H)


def self_affine_psd(q, H, qL, q0, q1, C0):
    """Self-affine isotropic PSD with roll-off, Persson's convention (m^4).

    C(q) = C0 for qL <= q < q0; C0 (q/q0)^(-2(1+H)) for q0 <= q <= q1; 0 outside [qL, q1].

    Parameters
    ----------
    q : array
        Wavenumbers (1/m).
    H : float
        Hurst exponent.
    qL, q0, q1 : float
        Band edges and roll-off (1/m).
    C0 : float or array
        Plateau value (m^4); must broadcast against ``q``.

    References
    ----------
    docs/theory.md, section "Spectra"; seed eq 63.
    """
    q = np.asarray(q, dtype=float)
    shape = np.where(q < q0, 1.0, (np.maximum(q, q0) / q0) ** (-2.0 * (1.0 + H)))
    inside = (q >= qL * (1 - 1e-12)) & (q <= q1 * (1 + 1e-12))
    return C0 * np.where(inside, shape, 0.0)


def psd_combined(C1, C2, eta):
    """Combined PSD of two rough surfaces with coherence eta (m^4), seed eqs 52/65.

    C = C1 + C2 - 2 eta sqrt(C1 C2), computed in the non-negative form
    C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2, which is exactly 0 when eta = 1 and C1 = C2.

    Parameters
    ----------
    C1, C2 : array
        PSDs of the substrate and the elastic solid (m^4), Persson's convention.
    eta : float or array
        Coherence, -1 <= eta <= 1 (may depend on q).

    References
    ----------
    docs/theory.md, section "Spectra" (eqs 52, 65).
    """
    C1 = np.asarray(C1, dtype=float)
    C2 = np.asarray(C2, dtype=float)
    eta = require_coherence(eta)
    return (np.sqrt(C1) - eta * np.sqrt(C2)) ** 2 + (1.0 - eta * eta) * C2


def hrms_from_psd(q, C):
    """Root-mean-square roughness (m) from a PSD: hrms^2 = 2 pi \\int q C(q) dq (eq 4).

    Piecewise power-law quadrature over the grid ``q`` (last axis of ``C``).
    """
    return np.sqrt(2.0 * np.pi * integral(q, np.asarray(q) * C))


def rms_slope_from_psd(q, C):
    """Root-mean-square slope xi (dimensionless): xi^2 = 2 pi \\int q^3 C dq (eq 12)."""
    return np.sqrt(2.0 * np.pi * integral(q, np.asarray(q) ** 3 * C))


#: Conventions of measured PSDs and their conversion to Persson's C(q) (docs/theory.md, section "Spectra").
CONVENTIONS = {
    "persson": ("m^4", "C(q) as given (Persson's convention)"),
    "contact.engineering": ("m^4", "C(q) = C_ST(q) / (2 pi)^2 (contact.engineering / SurfaceTopography convention)"),
    "1d": (
        "m^3",
        "C(q) = c(H) C1D(q) / q, c(H) = Gamma(1+H) / (2 pi^1.5 Gamma(H+1/2)) (= 1/(4 pi) at H = 1/2), from a "
        "1D profile PSD with hrms^2 = (1/pi) int_0^inf C1D dq; exact only for an isotropic self-affine "
        "surface with that Hurst exponent (the earlier statement C1D/(pi q) is 4x too large)",
    ),
    "1d_persson": (
        "m^3",
        "C(q) = 2 pi c(H) C1D_P(q) / q from a 1D profile PSD in Persson's 1D convention, C1D_P = C1D / (2 pi) with "
        "hrms^2 = 2 int_0^inf C1D_P dq (Persson et al. 2005); c(H) as for '1d'; exact only for an isotropic "
        "self-affine surface with that Hurst exponent",
    ),
}


def psd_to_persson(q, values, convention, hurst=0.5):
    """Convert a measured PSD in ``convention`` to Persson's C(q) in m^4 (see CONVENTIONS).

    For a 1D profile PSD, C1D(q) = 2 pi \\int dq_y C(sqrt(q^2 + q_y^2)) (hrms^2 = (1/pi)
    \\int_0^inf C1D dq), which for C ~ q^(-2(1+H)) inverts to C = c(H) C1D / q
    (:func:`isotropic_factor`). Persson's 1D convention, C1D_P(q) = (1/2 pi) \\int dx <h(x) h(0)>
    exp(-i q x) with hrms^2 = 2 \\int_0^inf C1D_P dq, is C1D / (2 pi): C = 2 pi c(H) C1D_P / q.

    References
    ----------
    Persson, Albohr, Tartaglino, Volokitin & Tosatti, J. Phys.: Condens. Matter 17, R1 (2005);
    docs/theory.md, section "Spectra".
    """
    if convention == "persson":
        return values
    if convention == "contact.engineering":
        return values / (2.0 * np.pi) ** 2
    if convention == "1d":
        return isotropic_factor(hurst) * values / q
    if convention == "1d_persson":
        return 2.0 * np.pi * isotropic_factor(hurst) * values / q
    raise ValueError(convention)


def extend_psd(q_grid, q_data, C_data, how):
    """Interpolate a tabulated PSD onto ``q_grid`` in log-log; outside the data, ``how`` is
    ``"power_law"`` (continue the end slopes), ``"zero"`` (no roughness there) or ``"none"``
    (the caller has checked the grid lies within the data)."""
    inside = (q_grid >= q_data[0]) & (q_grid <= q_data[-1])
    out = np.zeros_like(q_grid)
    out[inside] = loglog_interp(q_grid[inside], q_data, C_data)
    if how == "power_law":
        for sel, (i, j) in ((q_grid < q_data[0], (0, 1)), (q_grid > q_data[-1], (-2, -1))):
            if np.any(sel):
                slope = np.log(C_data[j] / C_data[i]) / np.log(q_data[j] / q_data[i])
                out[sel] = C_data[i] * (q_grid[sel] / q_data[i]) ** slope
    return out


def isotropic_factor(H):
    """c(H) in C(q) = c(H) C1D(q) / q, the 2D isotropic PSD (Persson) from a profile PSD C1D.

    c(H) = Gamma(1 + H) / (2 pi^(3/2) Gamma(H + 1/2)); c(1/2) = 1/(4 pi). Exact for an
    isotropic surface whose PSD is a power law C ~ q^(-2(1+H)) (from C1D(q) = 2 pi
    \\int dq_y C(sqrt(q^2 + q_y^2))); an approximation otherwise (roll-off, cut-offs).
    """
    H = np.asarray(H, dtype=float)
    return np.exp(special.gammaln(1.0 + H) - special.gammaln(H + 0.5)) / (2.0 * np.pi**1.5)
