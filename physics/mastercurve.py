"""Master curves from multi-temperature DMA frequency sweeps: horizontal (and optional vertical)
time-temperature shifts, the WLF fit, a relaxation spectrum and the Kramers-Kronig check.

Time-temperature superposition: the sweep at temperature T_j, shifted to reduced frequency
omega a_j and divided by b_j, lies on one curve E(omega, T_ref):

.. math:: E(\\omega, T_j) = b_j\\,E(\\omega a_j, T_\\mathrm{ref}), \\qquad
          \\log_{10}a_T = -\\frac{C_1 (T - T_\\mathrm{ref})}{C_2 + T - T_\\mathrm{ref}}.

The shifts are found by least squares on the log moduli: every sweep's log10 E' and log10 E''
against the one smooth curve (a cubic B-spline in log10 of the reduced frequency, refitted for
every trial shift) through all shifted data. ``free`` shifts fit log10 a_j per sweep (started
from pairwise overlaps of neighbouring sweeps) and then C1, C2 to them; ``wlf`` fits C1, C2 to
the data directly. The master curve at T_ref is then a generalized Maxwell (Prony) spectrum fitted
with non-negative moduli (causal by construction), and causality of the data is checked by
Kramers-Kronig: E' rebuilt from a spectrum fitted to E'' alone (plus the one constant E'' does
not fix, the relaxed modulus) must match the measured E'. See docs/theory.md, section "Master
curves from DMA data"; Ferry, Viscoelastic Properties of Polymers, 3rd ed. (1980), ch. 11;
Tschoegl (1989), ch. 3-4.

scipy.optimize and scipy.interpolate are imported inside the functions that fit (loading the stage
declarations, as a rerun with nothing to compute does, does not import them).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .viscoelastic import prony_modulus, wlf_log10_shift


class Shifts(NamedTuple):
    """Outcome of :func:`build_master_curve`.

    Attributes
    ----------
    log10_aT, log10_bT : arrays (n_T,)
        Horizontal and vertical shifts of the sweeps to T_ref (dimensionless, log10).
    C1, C2 : float
        WLF constants about T_ref (dimensionless; K).
    T_ref : float
        Reference temperature (K).
    residual : array (n_T,)
        rms of log10 E' and log10 E'' of each sweep about the shifted master curve (decades).
    wlf_residual : array (n_T,)
        log10 a_j minus the fitted WLF law (decades; 0 for ``wlf`` shifts).
    """

    log10_aT: np.ndarray
    log10_bT: np.ndarray
    C1: float
    C2: float
    T_ref: float
    residual: np.ndarray
    wlf_residual: np.ndarray


def _spline_residuals(x, ys, knots_per_decade):
    """Residuals of ys (each (m,)) about a least-squares cubic B-spline in x, uniform knots over x's span."""
    from scipy.interpolate import BSpline

    lo, hi = float(np.min(x)), float(np.max(x))
    n = max(2, int(np.ceil((hi - lo) * knots_per_decade)))
    inner = np.linspace(lo, hi, n + 1)
    t = np.concatenate([[lo] * 3, inner, [hi] * 3])
    M = BSpline.design_matrix(np.clip(x, lo, hi), t, 3).toarray()
    D = np.diff(np.eye(M.shape[1]), 2, axis=0) * 1e-3  # a whisper of smoothing where data are sparse
    A = np.vstack([M, D])
    out = []
    for y in ys:
        coef = np.linalg.lstsq(A, np.concatenate([y, np.zeros(D.shape[0])]), rcond=None)[0]
        out.append(y - M @ coef)
    return np.concatenate(out)


def pairwise_shifts(logw, logE1, logE2, sweep, n_T, vertical=False, step=0.01):
    """log10 a_j of each sweep relative to the first (coldest) one, from overlaps of neighbours.

    For each pair (j, j + 1) the shift d of sweep j + 1 along log10 omega that minimises the
    mean squared difference of log10 E' and log10 E'' to sweep j (linear interpolation in
    log-log) where the two overlap (at least two points), scanned in steps of ``step`` decades;
    with ``vertical``, the best log10 b offset is removed for each trial d.

    Parameters
    ----------
    logw, logE1, logE2 : arrays (m,)
        log10 omega (rad/s), log10 E', log10 E'' (Pa) of every point, sorted by sweep then frequency.
    sweep : int array (m,)
        Sweep index of each point (0 = coldest).
    n_T : int
        Number of sweeps.

    Returns
    -------
    (log10_a, log10_b) : arrays (n_T,)
        Cumulative shifts relative to sweep 0 (dimensionless, log10).

    References
    ----------
    docs/theory.md, section "Master curves from DMA data".
    """
    log_a, log_b = np.zeros(n_T), np.zeros(n_T)
    for j in range(n_T - 1):
        a, b = sweep == j, sweep == j + 1
        xa, xb = logw[a], logw[b]
        span = (xa.max() - xa.min()) + (xb.max() - xb.min())
        best = (np.inf, 0.0, 0.0)
        for d in np.arange(-span, span + step, step):
            inside = (xb + d >= xa.min()) & (xb + d <= xa.max())
            if inside.sum() < 2:
                continue
            r1 = logE1[b][inside] - np.interp(xb[inside] + d, xa, logE1[a])
            r2 = logE2[b][inside] - np.interp(xb[inside] + d, xa, logE2[a])
            off = 0.5 * (r1.mean() + r2.mean()) if vertical else 0.0
            cost = np.mean((r1 - off) ** 2) + np.mean((r2 - off) ** 2)
            if cost < best[0]:
                best = (cost, d, off)
        log_a[j + 1] = log_a[j] + best[1]
        log_b[j + 1] = log_b[j] + best[2]
    return log_a, log_b


def fit_wlf(T, log10_aT, T_ref, anchor=None, sigma=None):
    """C1, C2 of the WLF law about T_ref fitted to measured shifts (least squares in log10 a_T).

    The shifts may be relative to the sweep ``anchor`` (then the model is W(T_j) - W(T_anchor));
    the start is the classical linearisation -(T - T_0)/log10 a = C2/C1 + (T - T_0)/C1. C2 is kept
    above T_ref - min(T) so that the law is finite at every measured temperature.

    Parameters
    ----------
    T : array (n,)
        Temperatures (K).
    log10_aT : array (n,)
        Shifts (log10).
    T_ref : float
        Reference temperature of the law (K).
    anchor : int or None
        Index whose shift is the zero of ``log10_aT`` (None: the shifts are absolute, about T_ref).
    sigma : array (n,) or None
        Standard errors of the shifts (decades): weights 1/sigma (the anchor's 0 is exact).

    Returns
    -------
    (C1, C2, residual) : (float, float (K), array (n,))
        WLF constants and log10 a_j minus the law (decades).

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Williams, Landel & Ferry, J. Am. Chem.
    Soc. 77, 3701 (1955).
    """
    from scipy.optimize import least_squares

    T = np.asarray(T, dtype=float)
    L = np.asarray(log10_aT, dtype=float)
    T0 = T[anchor] if anchor is not None else T_ref
    L0 = L - (L[anchor] if anchor is not None else 0.0)
    use = np.abs(T - T0) > 1e-9
    slope, intercept = np.polyfit(T[use] - T0, -(T[use] - T0) / np.where(L0[use] != 0, L0[use], 1e-30), 1)
    C1s, C2s = (1.0 / slope, intercept / slope) if slope > 0 and intercept > 0 else (10.0, 100.0)
    C2_start = C2s + (T_ref - T0)
    floor = T_ref - T.min()
    C2_start = max(C2_start, floor + 1.0)
    C1_start = C1s * C2s / C2_start if C2s > 0 else 10.0

    def model(p):
        C1, C2 = p[0], floor + np.exp(p[1])
        W = wlf_log10_shift(T, T_ref, C1, C2)
        return W - (wlf_log10_shift(T0, T_ref, C1, C2) if anchor is not None else 0.0)

    weight = 1.0 / np.maximum(sigma, 1e-6 * np.max(sigma)) if sigma is not None else np.ones_like(T)
    fit = least_squares(lambda p: (model(p) - L0) * weight, [C1_start, np.log(C2_start - floor)], x_scale="jac",
                        xtol=1e-14, ftol=1e-14, gtol=1e-14)
    C1, C2 = float(fit.x[0]), float(floor + np.exp(fit.x[1]))
    return C1, C2, L0 - model(fit.x)


def _per_sweep_rms(r, sweep, n_T):
    """rms of the residual pairs (E', E'') of each sweep."""
    r = r.reshape(2, -1)
    return np.array([np.sqrt(np.mean(r[:, sweep == j] ** 2)) for j in range(n_T)])


def build_master_curve(T, sweep, omega, storage, loss, T_ref, method="free", vertical=False, knots_per_decade=2.0):
    """Shift multi-temperature sweeps onto one master curve at T_ref and fit the WLF law.

    Least squares on log10 E' and log10 E'' of every point against one cubic B-spline in the
    reduced frequency (``knots_per_decade`` uniform knots, refitted for each trial shift):
    ``method = "free"``: one log10 a_j per sweep (the sweep nearest T_ref held at the WLF value),
    started from :func:`pairwise_shifts`, then C1, C2 fitted to them (:func:`fit_wlf`);
    ``"wlf"``: C1, C2 fitted to the data directly, started from the free fit. ``vertical`` adds
    one log10 b_j per sweep (b = 1 at the sweep nearest T_ref).

    Parameters
    ----------
    T : array (n_T,)
        Sweep temperatures (K), increasing.
    sweep : int array (m,)
        Sweep of each point.
    omega, storage, loss : arrays (m,)
        Angular frequency (rad/s), E' (Pa, > 0) and E'' (Pa, >= 0; zeros are raised to 1e-12 E').
    T_ref : float
        Reference temperature (K).

    Returns
    -------
    Shifts

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Ferry (1980), ch. 11.
    """
    from scipy.optimize import least_squares

    T = np.asarray(T, dtype=float)
    n_T = T.size
    logw, l1 = np.log10(omega), np.log10(storage)
    l2 = np.log10(np.maximum(loss, 1e-12 * storage))
    j0 = int(np.argmin(np.abs(T - T_ref)))
    others = np.arange(n_T) != j0
    la, lb = pairwise_shifts(logw, l1, l2, sweep, n_T, vertical)
    la, lb = la - la[j0], lb - lb[j0]

    def unpack(theta, horizontal):
        a = np.zeros(n_T)
        a[others] = horizontal
        b = np.zeros(n_T)
        if vertical:
            b[others] = theta[-(n_T - 1):]
        return a, b

    def residual(a, b):
        return _spline_residuals(logw + a[sweep], (l1 - b[sweep], l2 - b[sweep]), knots_per_decade)

    free = least_squares(lambda th: residual(*unpack(th, th[:n_T - 1])),
                         np.concatenate([la[others]] + ([lb[others]] if vertical else [])), x_scale=1.0)
    la, lb = unpack(free.x, free.x[:n_T - 1])
    J = free.jac[:, :n_T - 1]
    cov = np.linalg.pinv(J.T @ J) * 2.0 * free.cost / max(J.shape[0] - free.x.size, 1)
    sigma = np.zeros(n_T)
    sigma[others] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    sigma[j0] = np.min(sigma[others])
    C1, C2, wres = fit_wlf(T, la, T_ref, anchor=j0, sigma=sigma)
    log_a = la + wlf_log10_shift(T[j0], T_ref, C1, C2)
    r = residual(log_a, lb)
    if method == "wlf":
        floor = T_ref - T.min()

        def law(th):
            return wlf_log10_shift(T, T_ref, th[0], floor + np.exp(th[1]))

        start = np.concatenate([[C1, np.log(C2 - floor)], lb[others] if vertical else []])
        fit = least_squares(lambda th: residual(law(th), unpack(th, law(th)[others])[1]), start, x_scale="jac")
        C1, C2 = float(fit.x[0]), float(floor + np.exp(fit.x[1]))
        log_a = law(fit.x)
        lb = unpack(fit.x, log_a[others])[1]
        wres = np.zeros(n_T)
        r = residual(log_a, lb)
    return Shifts(log_a, lb, C1, C2, float(T_ref), _per_sweep_rms(r, sweep, n_T), wres)


def relaxation_times(omega, per_decade=3, pad=1.0):
    """Geometric grid of relaxation times (s) covering 1/omega of the data with ``pad`` decades
    to spare at both ends, ``per_decade`` times per decade.

    Parameters
    ----------
    omega : array
        (Reduced) angular frequencies of the data (rad/s).
    """
    lo = -np.log10(np.max(omega)) - pad
    hi = -np.log10(np.min(omega)) + pad
    return np.logspace(lo, hi, int(np.ceil((hi - lo) * per_decade)) + 1)


def _basis(omega, times):
    """E', E'' of unit Prony terms (m, K) (through :func:`roughcontact.physics.viscoelastic.prony_modulus`)."""
    return prony_modulus(np.asarray(omega, dtype=float)[:, None], 0.0, np.eye(times.size), times)


def fit_prony(omega, storage, loss, times):
    """Generalized Maxwell fit E = E0 + sum_k E_k i w tau_k / (1 + i w tau_k) with E0, E_k >= 0 to
    E' and E'' (relative residuals, non-negative least squares): a causal master curve.

    Parameters
    ----------
    omega, storage, loss : arrays (m,)
        Reduced angular frequency (rad/s), E' and E'' (Pa, > 0) at T_ref.
    times : array (K,)
        Relaxation times (s).

    Returns
    -------
    (E0, moduli, residual) : (float (Pa), array (K,) (Pa), float)
        The spectrum and the rms relative residual of E' and E''.

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Tschoegl (1989), ch. 4.
    """
    from scipy.optimize import nnls

    S, L = _basis(omega, times)
    M = np.vstack([np.column_stack([np.ones_like(omega), S]) / storage[:, None],
                   np.column_stack([np.zeros_like(omega), L]) / loss[:, None]])
    scale = np.linalg.norm(M, axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    coef, rnorm = nnls(M / scale, np.ones(M.shape[0]), maxiter=50 * M.shape[1])
    coef = coef / scale
    return float(coef[0]), coef[1:], float(rnorm / np.sqrt(M.shape[0]))


def kramers_kronig_deviation(omega, storage, loss, times, sweep):
    r"""E' rebuilt from E'' alone, and its relative deviation from the measured E'.

    A spectrum E_k >= 0 is fitted to E'' (relative residuals, non-negative least squares). By
    Kramers-Kronig the loss modulus fixes E' up to a constant; within one sweep's window the
    relaxations the data cannot see (far beyond the data, or in a gap between sweeps) add a
    constant too (omega tau >> 1 there: E_k; omega tau << 1: nothing), so one constant c_j per
    sweep is fitted to E' last:

    .. math:: E'_{KK}(\omega) = c_j + \sum_k E_k \frac{\omega^2\tau_k^2}{1 + \omega^2\tau_k^2}

    Causal data (that also superpose) give deviations at the noise level; an E' whose variation
    across a sweep does not follow from its E'' does not.

    Parameters
    ----------
    omega, storage, loss : arrays (m,)
        Reduced angular frequency (rad/s), E' and E'' (Pa, > 0).
    times : array (K,)
        Relaxation times (s).
    sweep : int array (m,)
        Sweep of each point.

    Returns
    -------
    (rebuilt, deviation) : arrays (m,)
        E'_KK (Pa) and E'_KK / E' - 1 (dimensionless).

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Tschoegl (1989), ch. 4; Booij & Thoone,
    Rheol. Acta 21, 15 (1982).
    """
    from scipy.optimize import nnls

    S, L = _basis(omega, times)
    M = L / loss[:, None]
    scale = np.linalg.norm(M, axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    coef = nnls(M / scale, np.ones(omega.size), maxiter=50 * M.shape[1])[0] / scale
    rebuilt = S @ coef
    w = 1.0 / storage ** 2
    for j in np.unique(sweep):
        mine = sweep == j
        rebuilt[mine] += np.sum((storage[mine] - rebuilt[mine]) * w[mine]) / np.sum(w[mine])
    return rebuilt, rebuilt / storage - 1.0
