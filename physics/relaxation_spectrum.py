"""The relaxation spectrum of a DMA master curve: a generalized Maxwell (Prony) series fitted with
non-negative moduli (causal by construction), and the Kramers-Kronig check of the data.

The master curve at T_ref (the sweeps shifted by :mod:`roughcontact.physics.mastercurve`) is
represented by

.. math:: E(\\omega) = E_0 + \\sum_k E_k \\frac{i\\omega\\tau_k}{1 + i\\omega\\tau_k}, \\qquad E_0, E_k \\ge 0,

on a fixed geometric grid of relaxation times, fitted by non-negative least squares to the relative
residuals of E' and E''. Causality of the data is checked by Kramers-Kronig: E' rebuilt from a
spectrum fitted to E'' alone (plus the one constant E'' does not fix, the relaxed modulus) must match
the measured E'. See docs/theory.md, section "Master curves from DMA data"; Tschoegl, The
Phenomenological Theory of Linear Viscoelastic Behavior (1989), ch. 3-4.

scipy.optimize is imported inside the functions that fit.
"""

from __future__ import annotations

import numpy as np

from .viscoelastic import prony_modulus


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
