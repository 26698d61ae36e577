"""Statistical uncertainty of measured spectra, and spectra drawn within it.

* The spread between several measurements of one surface (:func:`spread_inflation`): where
  they disagree by more than their mode-counting errors allow, the error is inflated.
* The bias of a bin average of a curved (power-law) PSD read at the bins' mean wavenumber
  (:func:`bin_curvature_factor`).
* The bias of the log-log interpolation between bins of few modes
  (:func:`interpolation_unbiasing`).
* Standard errors carried onto a wavenumber grid (:func:`psd_error_on_grid`), the combined
  PSD's error (:func:`combined_psd_error`), and spectra / coherences drawn within their
  statistical band (:func:`psd_draws_on_grid`, :func:`coherence_draws_on_grid`), reduced to
  quantiles (:func:`quantiles`).

How many independent modes a windowed scan has per bin: :mod:`roughcontact.physics.modes`.

Statistics: for a Gaussian random-phase surface each mode's power is exponentially
distributed, so the mean of n independent modes is Gamma(n, C/n) distributed. See
docs/measured-data.md and docs/theory.md, section "Spectra".
"""

from __future__ import annotations

import math

import numpy as np

from . import special
from .estimators import binned_psd_on_grid, coherence_on_grid

# ----------------------------------------------------------------------------------------
# Several measurements of one surface
# ----------------------------------------------------------------------------------------


def spread_inflation(values, modes, merged, alpha=0.01):
    """Error inflation from the spread between several measurements of one surface.

    In each bin, chi^2 = sum_f n_f (C_f - C)^2 / C^2 over the measurements f with modes there
    (C: their n-weighted mean; each C_f has variance C^2 / n_f) is chi-square distributed
    with k - 1 degrees of freedom when they estimate one PSD. Where chi^2 exceeds its
    (1 - alpha) quantile, the measurements disagree beyond their statistics (instrument
    artefacts, anisotropy, a drifting calibration) and the error is multiplied by the Birge
    ratio sqrt(chi^2 / (k - 1)); elsewhere it is left as it is.

    Parameters
    ----------
    values : array (k, nbins)
        Each measurement's binned PSD (m^4; NaN or anything where it has no modes).
    modes : array (k, nbins)
        Each measurement's independent modes per bin (0 where none).
    merged : array (nbins,)
        The merged PSD (m^4).
    alpha : float
        Significance level of the test.

    Returns
    -------
    ratio : array (nbins,)
        Birge ratio sqrt(chi^2 / (k - 1)); NaN where fewer than two measurements have modes.
    inflation : array (nbins,)
        Factor >= 1 for the standard error.
    """
    has = modes > 0
    k = has.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        dev = np.where(has, modes * (np.nan_to_num(values) - merged) ** 2, 0.0).sum(axis=0) / merged**2
        ratio = np.where(k >= 2, np.sqrt(dev / np.maximum(k - 1, 1)), np.nan)
    limit = 2.0 * special.gammaincinv(np.maximum(k - 1, 1) / 2.0, 1.0 - alpha)  # chi-square quantile
    inflation = np.where((k >= 2) & (dev > limit), ratio, 1.0)
    return ratio, np.nan_to_num(inflation, nan=1.0)


# ----------------------------------------------------------------------------------------
# Bins onto the grid
# ----------------------------------------------------------------------------------------


def bin_curvature_factor(q, C, bins_per_decade, span=2):
    """Factor turning a bin's mean PSD into the PSD at the bin's mean wavenumber.

    A bin averages C over its modes; for a local power law C ~ q^(-a) that average exceeds
    C(<q>) by exp(a (1 + a) v / 2) to second order, with v = var(ln q) over the bin,
    (ln 10 / bins_per_decade)^2 / 12 for a filled bin (about +0.9 % for a = 3.6 at 20 bins per
    decade). The slope a is fitted in log-log over the ``span`` bins on either side.

    Parameters
    ----------
    q, C : arrays
        Valid bins (q increasing, 1/m; C > 0, m^4).
    bins_per_decade : int
        Bin width.

    Returns
    -------
    array
        exp(-a (1 + a) v / 2), dimensionless.
    """
    x, y = np.log(q), np.log(C)
    a = np.zeros_like(x)
    for i in range(x.size):
        lo, hi = max(0, i - span), min(x.size, i + span + 1)
        if hi - lo >= 2:
            xs = x[lo:hi] - x[lo:hi].mean()
            a[i] = -np.sum(xs * (y[lo:hi] - y[lo:hi].mean())) / np.sum(xs * xs)
    v = (math.log(10.0) / bins_per_decade) ** 2 / 12.0
    return np.exp(-a * (1.0 + a) * v / 2.0)


def grid_weights(q_grid, q, how):
    """For each grid node, the two bins it is read from and the weight t of the second:
    C_grid = C_a^(1-t) C_b^t (log-log interpolation, or the power-law tail of
    :func:`roughcontact.physics.estimators.binned_psd_on_grid`); ``inside`` is False where the
    grid node gets 0 (beyond the bins with ``how`` 'zero' or 'none')."""
    lx, x = np.log(q_grid), np.log(q)
    j = np.clip(np.searchsorted(x, lx) - 1, 0, x.size - 2)
    a, b = j, j + 1
    inside = (lx >= x[0] - 1e-12) & (lx <= x[-1] + 1e-12)
    if how == "power_law":
        k = min(3, x.size - 1)
        below, above = lx < x[0], lx > x[-1]
        a, b = (np.where(below, 0, np.where(above, x.size - 1 - k, a)),
                np.where(below, k, np.where(above, x.size - 1, b)))
        inside = np.ones_like(inside)
    t = (lx - x[a]) / (x[b] - x[a])
    return a, b, t, inside


def _power_factor(n, s):
    """E[(C_hat/C)^s] for a bin mean of n exponential modes: Gamma(n + s) / (Gamma(n) n^s)."""
    return np.exp(special.gammaln(n + s) - special.gammaln(n) - s * np.log(n))


def _drawn_power_factor(n, s):
    """E[(C*/C_hat)^s] for the draws of :func:`psd_draws`: n^s Gamma(n + 1 - s) / Gamma(n + 1)."""
    return np.exp(s * np.log(n) + special.gammaln(n + 1.0 - s) - special.gammaln(n + 1.0))


def interpolation_unbiasing(q_grid, q, modes, how, drawn=False):
    """Per grid node, the factor that makes the log-log interpolation of noisy bins unbiased.

    Between bins a and b a grid node gets C_a^(1-t) C_b^t; for bin means of n exponential
    modes its expectation is C_a^(1-t) C_b^t f(n_a, 1-t) f(n_b, t) with
    f(n, s) = Gamma(n + s) / (Gamma(n) n^s) <= 1 (about 1 - s(1-s)/(2n)): the interpolated PSD
    is biased low between bins with few modes. Dividing by f removes that. ``drawn``: the
    factor for spectra drawn by :func:`psd_draws`, whose interpolation is divided as well by
    the draws' own E[(C*/C)^s], so that the draws' mean on the grid is the unbiased PSD.
    Nodes beyond the bins (extension) get 1.

    Parameters
    ----------
    q_grid : array
        Grid (1/m).
    q, modes : arrays (m,)
        Valid bins (increasing q, 1/m) and their effective independent modes.
    how : str
        'none', 'zero' or 'power_law'.

    Returns
    -------
    array (len(q_grid),)
        Dimensionless factor >= 1.
    """
    a, b, t, _ = grid_weights(q_grid, q, how)
    interior = (t >= 0.0) & (t <= 1.0)
    t = np.clip(t, 0.0, 1.0)
    n = np.maximum(np.asarray(modes, dtype=float), 1e-6)
    factor = _power_factor(n[a], 1.0 - t) * _power_factor(n[b], t)
    if drawn:
        factor = factor * _drawn_power_factor(n[a], 1.0 - t) * _drawn_power_factor(n[b], t)
    return np.where(interior, 1.0 / factor, 1.0)


def psd_error_on_grid(q_grid, q, C, err, how):
    """Standard error (m^4) of a binned PSD put on ``q_grid`` by
    :func:`roughcontact.physics.estimators.binned_psd_on_grid`, bins independent:
    the relative error of C_a^(1-t) C_b^t is sqrt((1-t)^2 r_a^2 + t^2 r_b^2) with r = err / C;
    0 where the grid gets 0.

    Parameters
    ----------
    q_grid : array
        Grid (1/m).
    q, C, err : arrays (m,)
        Valid bins: wavenumbers (increasing), PSD and its standard error (m^4).
    how : str
        'none', 'zero' or 'power_law' (as the PSD was extended).
    """
    a, b, t, inside = grid_weights(q_grid, q, how)
    r = err / C
    rel = np.sqrt((1.0 - t) ** 2 * r[a] ** 2 + t**2 * r[b] ** 2)
    return np.where(inside, binned_psd_on_grid(q_grid, q, C, how) * rel, 0.0)


def coherence_error_on_grid(q_grid, q, err):
    """Standard error of a binned coherence put on ``q_grid`` by
    :func:`roughcontact.physics.estimators.coherence_on_grid` (linear in log q, constant beyond
    the bins), bins independent: sqrt((1-t)^2 e_a^2 + t^2 e_b^2). Dimensionless."""
    a, b, t, _ = grid_weights(q_grid, q, "none")
    t = np.clip(t, 0.0, 1.0)
    return np.sqrt((1.0 - t) ** 2 * err[a] ** 2 + t**2 * err[b] ** 2)


def combined_psd_error(C1, C2, eta, s1, s2, s_eta):
    """Linear (delta-method) standard error of the combined PSD C = C1 + C2 - 2 eta sqrt(C1 C2)
    (seed eq 52) from independent errors s1, s2 (m^4) of C1, C2 and s_eta of eta.

    dC/dC1 s1 = (C1 - eta sqrt(C1 C2)) s1 / C1, likewise for C2, and dC/deta = -2 sqrt(C1 C2).

    Returns
    -------
    array
        Standard error (m^4), broadcast over the inputs.
    """
    g = np.sqrt(C1 * C2)
    with np.errstate(invalid="ignore", divide="ignore"):
        t1 = np.where(C1 > 0, (C1 - eta * g) * s1 / np.where(C1 > 0, C1, 1.0), s1)
        t2 = np.where(C2 > 0, (C2 - eta * g) * s2 / np.where(C2 > 0, C2, 1.0), s2)
    return np.sqrt(t1**2 + t2**2 + (2.0 * g * s_eta) ** 2)


# ----------------------------------------------------------------------------------------
# Draws within the band
# ----------------------------------------------------------------------------------------


def correlation_root(correlation):
    """A matrix R with R R^T = ``correlation`` (its negative eigenvalues, from rounding or from a
    matrix assembled of pair sums, set to 0; rows rescaled to a unit diagonal): z = R xi, xi standard
    normal, has that correlation (dimensionless, (m, m)). An eigen-decomposition, O(m^3): computed
    once for all the draws of a spectrum (``psd_draws(root=...)``), not once per block of draws."""
    lam, V = np.linalg.eigh(correlation)
    root = V * np.sqrt(np.clip(lam, 0.0, None))
    return root / np.sqrt(np.maximum(np.sum(root * root, axis=1), 1e-300))[:, None]


def psd_draws(C, modes, draws, seed, stream, correlation=None, root=None):
    """Binned PSDs drawn within their statistical band.

    A bin's mean of n independent exponential mode powers is C_true Gamma(n, 1)/n. Given the
    measured value C, the drawn C* = C n / Gamma(n + 1, 1) is inverse-gamma distributed (the
    posterior of C_true under the prior 1/C^2): it has the skew of the measurement's
    uncertainty (C_true is more likely above a measured value from few modes than below it)
    and mean exactly C, so that every linear functional of the spectrum (G, hrms^2, the
    q-integrals behind every prediction), the sum of many bins' contributions, is centred on
    its unbiased estimate. (The Jeffreys-prior posterior, shape n, has mean C n / (n - 1): over
    many bins of 5-50 modes it shifts such sums by a percent or more, several times their
    standard error, and its bands under-cover.) Without ``correlation`` bins are independent.
    With it (a window correlates the modes of neighbouring bins), the bins' gamma variates are
    joined by a Gaussian copula: g_b = F_b^-1(Phi(z_b)), z normal with that correlation, F_b the
    Gamma(n_b + 1) distribution function; each bin keeps its marginal, and neighbouring bins
    move together as the measurement's do. Draw 0 is the measurement itself; draw d > 0 uses
    the random stream (seed, stream, d), so a draw does not depend on which other draws are
    computed with it (chunks).

    Parameters
    ----------
    C : array (m,)
        Measured bin PSD (m^4, > 0).
    modes : array (m,)
        Effective independent modes per bin, (C / standard error)^2.
    draws : int array (any shape)
        Draw indices.
    seed, stream : int
        Random seed of the scene and the quantity's stream (one per surface).
    correlation : array (m, m) or None
        Correlation matrix of the bins' errors (dimensionless).
    root : array (m, m) or None
        ``correlation_root(correlation)``, given instead of ``correlation`` where the same
        correlation serves many calls (the blocks of draws of one spectrum): the same draws.

    Returns
    -------
    array draws.shape + (m,)
        Drawn PSDs (m^4).

    References
    ----------
    Nelsen, An Introduction to Copulas (2006), section 2.3 (Gaussian copula); docs/measured-data.md.
    """
    flat = np.ravel(draws).astype(int)
    out = np.empty((flat.size, C.size))
    if root is None and correlation is not None:
        root = correlation_root(correlation)
    for i, d in enumerate(flat):
        if d == 0:
            out[i] = C
            continue
        rng = np.random.default_rng([int(seed), int(stream), int(d)])
        if root is None:
            g = rng.gamma(modes + 1.0)
        else:
            g = special.gammaincinv(modes + 1.0, special.ndtr(root @ rng.standard_normal(C.size)))
        out[i] = C * modes / g
    return out.reshape(np.shape(draws) + (C.size,))


def psd_draws_on_grid(draws, q_grid, q, C, modes, how, seed, stream, correlation=None, root=None):
    """:func:`psd_draws` (``correlation`` or its ``root``) put on ``q_grid`` with
    :func:`roughcontact.physics.estimators.binned_psd_on_grid` and made unbiased by
    :func:`interpolation_unbiasing` (m^4), shape draws.shape + (len(q_grid),); draw 0 is the
    measured PSD on the grid."""
    flat = np.ravel(draws).astype(int)
    binned = psd_draws(C, modes, flat, seed, stream, correlation, root)
    a, b, t, inside = grid_weights(q_grid, q, how)
    with np.errstate(divide="ignore"):
        logs = np.log(binned)
    out = np.where(inside, np.exp((1.0 - t) * logs[:, a] + t * logs[:, b]), 0.0)  # all draws at once
    out *= interpolation_unbiasing(q_grid, q, modes, how, drawn=True)
    first = np.flatnonzero(flat == 0)
    if first.size:  # the measurement itself, exactly as the nominal path puts it on the grid
        out[first] = binned_psd_on_grid(q_grid, q, C, how) * interpolation_unbiasing(q_grid, q, modes, how)
    return out.reshape(np.shape(draws) + (q_grid.size,))


def coherence_draws_on_grid(draws, q_grid, q, eta, err, seed, stream):
    """Coherences drawn within their band and put on ``q_grid``.

    Per bin, Fisher's z = artanh(eta) is normal with standard error err / (1 - eta^2)
    (= 1/sqrt(2 n)); draw 0 is the measurement. Interpolated as
    :func:`roughcontact.physics.estimators.coherence_on_grid`.

    Returns
    -------
    array draws.shape + (len(q_grid),)
        Dimensionless, in [-1, 1].
    """
    flat = np.ravel(draws).astype(int)
    eta = np.clip(eta, -1.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.arctanh(eta)
        sz = np.where(np.abs(eta) < 1.0, err / (1.0 - eta * eta), 0.0)
    out = np.empty((flat.size, q_grid.size))
    for i, d in enumerate(flat):
        e = eta if d == 0 else np.tanh(
            z + sz * np.random.default_rng([int(seed), int(stream), int(d)]).standard_normal(z.size))
        out[i] = coherence_on_grid(q_grid, q, np.where(np.isfinite(e), e, eta))
    return out.reshape(np.shape(draws) + (q_grid.size,))


def quantiles(values, probabilities, axis=-1):
    """Quantiles of ``values`` along ``axis`` (linear interpolation between order statistics,
    NaNs ignored); ``axis`` is replaced by the axis of the probabilities, moved to the end.
    Units of ``values``."""
    values = np.asarray(values, dtype=float)
    method = np.nanquantile if np.isnan(values).any() else np.quantile
    return np.moveaxis(method(values, probabilities, axis=axis), 0, -1)
