"""Self-affine fits of measured spectra, and the rms height, slope and curvature of a spectrum.

The model is the project's analytic self-affine PSD with roll-off
(:func:`roughcontact.physics.spectra.self_affine_psd`), in Persson's convention:

    C(q) = C0                          qL <= q < q0
    C(q) = C0 (q / q0)^(-2 (1 + H))    q0 <= q <= q1

It is fitted to binned PSD estimates by weighted least squares in log C (the fit of
:func:`fit_self_affine`); its parameters get confidence intervals from the linearised
covariance, and so do the rms height, slope and curvature of the fitted model
(:func:`fitted_rms`). :func:`psd_moments` and :func:`rms_from_moments` give those from any
spectrum, the way contact.engineering (SurfaceTopography) reports them. See docs/measured-data.md,
section "Self-affine fits".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from . import special
from .estimators import hurst_from_spectrum
from .quadrature import integral, log_grid
from .spectra import self_affine_hrms_factor, self_affine_psd

#: names of the fitted parameters, in the order of :attr:`SelfAffineFit.cov`
PARAMETERS = ("H", "ln_C0", "ln_q0")
#: nodes per decade of the grids the fitted model's moments are integrated on (exact: the kink q0 is a node)
_MOMENT_POINTS = 20


class SelfAffineFit(NamedTuple):
    """The result of :func:`fit_self_affine`.

    ``cov`` is the covariance of (H, ln C0, ln q0) (rows and columns of ln q0 are 0 when the
    roll-off was not fitted or not resolved: q0 is then the band's lower end, held fixed)."""

    H: float
    C0: float  #: m^4
    q0: float  #: 1/m
    band: tuple[float, float]  #: the fitted bins' lowest and highest wavenumber (1/m)
    cov: np.ndarray  #: 3 x 3
    chi2: float  #: sum of the squared weighted residuals
    dof: int  #: bins minus fitted parameters
    scale: float  #: the factor the covariance was multiplied by (chi2 / dof, at least 1 with known errors)
    errors_known: bool  #: whether the bins' standard errors weighted the fit
    rolloff: str  #: "resolved", "not resolved" (at the band's lower end) or "not fitted"
    residuals: np.ndarray  #: weighted residuals per bin, (data - model) / sigma, in log C

    def theta(self) -> np.ndarray:
        return np.array([self.H, math.log(self.C0), math.log(self.q0)])

    def psd(self, q, qL=None, q1=None):
        """The fitted model at ``q`` (m^4), between ``qL`` and ``q1`` (default: the fitted band)."""
        lo, hi = self.band
        return self_affine_psd(q, self.H, lo if qL is None else qL, self.q0, hi if q1 is None else q1, self.C0)


def log_mean_bias(n):
    """E[ln X] - ln E[X] for X the mean of n independent exponentially distributed mode powers:
    psi(n) - ln n (about -1/(2n)); and the variance of ln X, psi'(n) (about 1/n).

    X / E[X] is Gamma(n, 1/n) distributed (Gaussian random-phase modes: each mode's power is
    exponential, standard deviation = mean). Used to fit ln C without the bias of few-mode bins.

    Parameters
    ----------
    n : array
        Effective independent modes (> 0, need not be whole).

    Returns
    -------
    bias, variance : arrays
        Dimensionless.
    """
    import scipy.special  # imported when a fit runs, not with the stage declarations

    n = np.asarray(n, dtype=float)
    return scipy.special.digamma(n) - np.log(n), scipy.special.polygamma(1, n)


def _log_model(theta, q, lo, hi):
    H, ln_c0, ln_q0 = theta
    return np.log(self_affine_psd(q, H, lo, math.exp(ln_q0), hi, math.exp(ln_c0)))


def _starts(q, C, lo, hi, rolloff: bool):
    """Starting points (H, ln C0, ln q0): H from the slope over the upper half of the band, the
    roll-off at a few places across it (the misfit has a kink at each bin)."""
    upper = q >= math.sqrt(lo * hi)
    H, _, _ = hurst_from_spectrum(q[upper], C[upper], np.ones(int(upper.sum())), min_modes=0.0)
    H = float(np.clip(H if np.isfinite(H) else 0.5, 0.05, 1.0))
    places = np.geomspace(lo, hi, 6)[:-1] if rolloff else np.array([lo])
    for q0 in places:
        below = q <= q0 * (1 + 1e-12)
        ln_c0 = float(np.mean(np.log(C[below]))) if below.any() else float(np.log(C[0]))
        yield np.array([H, ln_c0, math.log(q0)])


def fit_self_affine(q, C, err=None, rolloff=True) -> SelfAffineFit:
    """Weighted least-squares fit of the self-affine PSD with roll-off to binned PSD estimates.

    The residuals are taken in log C. With standard errors ``err`` (a bin mean of n effective
    independent modes, n = (C / err)^2) the data are y = ln C - (psi(n) - ln n) (the expected
    log of a mean of n exponential mode powers is below the log of the mean by psi(n) - ln n,
    :func:`log_mean_bias`) and sigma_y^2 = psi'(n); without errors, sigma_y = 1 and the scatter
    about the fit sets it (the covariance is multiplied by chi^2 / dof). The fit minimises

        chi^2 = sum_i [(y_i - ln C_model(q_i; H, ln C0, ln q0)) / sigma_i]^2

    over H, ln C0 and ln q0 (scipy.optimize.least_squares, trust-region reflective, from
    several roll-off starts; q0 bounded to the band). The covariance is
    s (J^T J)^-1, J the Jacobian of the weighted residuals at the optimum, s = max(1, chi^2/dof)
    with errors (the errors are a lower bound when the model misfits) and chi^2/dof without.
    When the fitted q0 sits at the band's lower end, no roll-off is resolved: the fit is redone
    with q0 held there (power law over the whole band).

    Parameters
    ----------
    q : array
        Wavenumbers of the bins (1/m, > 0); any order.
    C : array
        PSD estimates (m^4, Persson's convention, > 0).
    err : array or None
        Their standard errors (m^4, > 0); None: unknown (equal weights in log C).
    rolloff : bool
        Fit the roll-off q0 (else q0 is the band's lower end: a power law).

    Returns
    -------
    SelfAffineFit

    References
    ----------
    Persson, J. Chem. Phys. 115, 3840 (2001) (the model); Jacobs, Junge & Pastewka, Surf. Topogr.:
    Metrol. Prop. 5, 013001 (2017) (the statistics of PSD estimates); docs/measured-data.md.
    """
    from scipy.optimize import least_squares  # imported when a fit runs, not with the stage declarations

    q, C = np.asarray(q, dtype=float), np.asarray(C, dtype=float)
    order = np.argsort(q)
    q, C = q[order], C[order]
    errors_known = err is not None
    if errors_known:
        n = (C / np.asarray(err, dtype=float)[order]) ** 2
        bias, var = log_mean_bias(n)
        y, sigma = np.log(C) - bias, np.sqrt(var)
    else:
        y, sigma = np.log(C), np.ones_like(C)
    lo, hi = float(q[0]), float(q[-1])
    free = 3 if rolloff else 2
    if q.size <= free:
        raise ValueError(f"a self-affine fit of {free} parameters needs more than {free} bins, got {q.size}")

    def solve(start, fixed_q0):
        def residual(t):
            theta = t if fixed_q0 is None else np.array([t[0], t[1], fixed_q0])
            return (y - _log_model(theta, q, lo, hi)) / sigma

        if fixed_q0 is None:
            bounds = ([-1.0, -np.inf, math.log(lo)], [3.0, np.inf, math.log(hi)])
            x0 = np.clip(start, [-0.99, -np.inf, math.log(lo)], [2.99, np.inf, math.log(hi)])
        else:
            bounds, x0 = ([-1.0, -np.inf], [3.0, np.inf]), start[:2]
        return least_squares(residual, x0, bounds=bounds, x_scale=[0.1, 1.0, 0.3][: len(x0)], xtol=1e-14,
                             ftol=1e-14, gtol=1e-14, max_nfev=2000)

    state = "not fitted"
    if rolloff:
        best = min((solve(s, None) for s in _starts(q, C, lo, hi, True)), key=lambda r: r.cost)
        state = "resolved" if best.x[2] > math.log(lo) + 1e-6 else "not resolved"
    if state != "resolved":
        best = solve(next(_starts(q, C, lo, hi, False)), math.log(lo))
        best.x = np.array([best.x[0], best.x[1], math.log(lo)])
        best.jac = np.column_stack([best.jac, np.zeros(q.size)])
    chi2 = float(2.0 * best.cost)
    dof = q.size - (3 if state == "resolved" else 2)
    scale = chi2 / dof if not errors_known else max(1.0, chi2 / dof)
    J = best.jac[:, :3] if state == "resolved" else best.jac[:, :2]
    cov = np.zeros((3, 3))
    cov[: J.shape[1], : J.shape[1]] = scale * np.linalg.pinv(J.T @ J)
    H, ln_c0, ln_q0 = (float(v) for v in best.x)
    return SelfAffineFit(H, math.exp(ln_c0), math.exp(ln_q0), (lo, hi), cov, chi2, int(dof), float(scale),
                         errors_known, state, best.fun)


def z_value(level: float) -> float:
    """The two-sided standard normal quantile of probability content ``level`` (1.96 for 0.95)."""
    return float(math.sqrt(2.0) * special.erfinv(level))


def interval(value: float, std: float, level: float, log: bool = False) -> tuple[float, float]:
    """The confidence interval of probability content ``level`` about ``value`` with standard error
    ``std`` (of ``ln value`` when ``log``: a log-normal interval, for positive quantities)."""
    z = z_value(level)
    if log:
        return value * math.exp(-z * std), value * math.exp(z * std)
    return value - z * std, value + z * std


def psd_moments(q, C, orders=(0, 2, 4)):
    """Spectral moments of an isotropic 2D PSD (Persson's convention) over the grid ``q``:

        m_alpha = \\int d^2q |q|^alpha C(q) = 2 pi \\int q^(alpha + 1) C(q) dq

    (m_0 = <h^2>, m_2 = <|grad h|^2>, m_4 = <(laplacian h)^2>), by the project's piecewise
    power-law quadrature (:func:`roughcontact.physics.quadrature.integral`).

    Parameters
    ----------
    q : array
        Increasing wavenumbers (1/m).
    C : array
        PSD at ``q`` (m^4), last axis.
    orders : tuple of int
        The alphas.

    Returns
    -------
    tuple of arrays
        m_alpha in m^(2 - alpha).

    References
    ----------
    Nayak, J. Lubr. Technol. 93, 398 (1971) (moments of isotropic surfaces); seed eqs 4 and 12.
    """
    q = np.asarray(q, dtype=float)
    return tuple(2.0 * np.pi * integral(q, q ** (a + 1) * np.asarray(C, dtype=float)) for a in orders)


def rms_from_moments(m0, m2, m4, profile=False):
    """rms height, slope and curvature from the moments of :func:`psd_moments`, as
    contact.engineering (SurfaceTopography) reports them.

    Of an area map (2D, ``profile`` False):

        h_rms = sqrt(m0),  slope_rms = sqrt(m2) (the gradient),  curvature_rms = sqrt(m4) / 2

    (the mean curvature, half the Laplacian, in the small-slope limit). Of a line scan along x
    across the same isotropic surface (``profile`` True), whose 1D moments are
    m_alpha^1D = (1/pi) \\int_0^inf q^alpha C1D(q) dq:

        h_rms = sqrt(m0),  slope_rms = sqrt(m2 / 2) (dh/dx),  curvature_rms = sqrt(3 m4 / 8) (d2h/dx2)

    since averaging cos^2 and cos^4 of the mode's direction gives m2^1D = m2 / 2 and
    m4^1D = 3 m4 / 8.

    Parameters
    ----------
    m0, m2, m4 : float or array
        Moments of the isotropic 2D PSD (m^2, 1, 1/m^2).
    profile : bool
        Report what a line scan measures (True) or what a map does (False).

    Returns
    -------
    h_rms, slope_rms, curvature_rms : float or array
        m, dimensionless, 1/m.

    References
    ----------
    Nayak, J. Lubr. Technol. 93, 398 (1971); Jacobs, Junge & Pastewka, Surf. Topogr.: Metrol. Prop.
    5, 013001 (2017) (the 1D and 2D moments, the rms curvature as half the Laplacian).
    """
    if profile:
        return np.sqrt(m0), np.sqrt(m2 / 2.0), np.sqrt(3.0 * m4 / 8.0)
    return np.sqrt(m0), np.sqrt(m2), np.sqrt(m4) / 2.0


def model_rms(theta, qL, q1, profile=False):
    """rms height, slope and curvature of the self-affine model (H, ln C0, ln q0) over [qL, q1]
    (:func:`rms_from_moments` of its moments, integrated exactly: q0 is a node of the grid).
    The height is also exact in closed form, :func:`roughcontact.physics.spectra.self_affine_hrms_factor`."""
    H, ln_c0, ln_q0 = theta
    q0 = min(max(math.exp(ln_q0), qL), q1)
    q = log_grid(qL, q1, _MOMENT_POINTS, (q0,))
    m0, m2, m4 = psd_moments(q, self_affine_psd(q, H, qL, q0, q1, math.exp(ln_c0)))
    m0 = float(math.exp(ln_c0) * self_affine_hrms_factor(H, qL, q0, q1))
    return rms_from_moments(m0, m2, m4, profile)


def fitted_rms(fit: SelfAffineFit, qL=None, q1=None, profile=False):
    """rms height, slope and curvature of the fitted model over [qL, q1] (default: the fitted
    band) with the standard errors of their logs, by the delta method:
    var ln f = g^T cov g, g = d ln f / d theta (central differences).

    Returns
    -------
    values : array (3,)
        m, dimensionless, 1/m.
    log_std : array (3,)
        Standard errors of their natural logs.
    """
    lo, hi = fit.band
    qL, q1 = lo if qL is None else qL, hi if q1 is None else q1
    theta = fit.theta()
    values = np.array(model_rms(theta, qL, q1, profile))
    grad = np.zeros((3, 3))
    for k, step in enumerate((1e-5, 1e-5, 1e-5)):
        if fit.cov[k, k] == 0.0:
            continue
        up, down = theta.copy(), theta.copy()
        up[k] += step
        down[k] -= step
        grad[:, k] = (np.log(model_rms(up, qL, q1, profile)) - np.log(model_rms(down, qL, q1, profile))) / (2 * step)
    log_std = np.sqrt(np.maximum(np.einsum("ik,kl,il->i", grad, fit.cov, grad), 0.0))
    return values, log_std
