"""The one bracketing root finder of the project: the Illinois variant of regula falsi,
vectorised over many independent brackets.

See docs/theory.md (numerical methods) and docs/adhesion.md, where it solves the node
equation of the Volterra march, the self-consistency of gamma_eff(1) and the hrms at which
adhesion vanishes.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np


class Root(NamedTuple):
    """Outcome of :func:`illinois`, one entry per bracket.

    Attributes
    ----------
    x : array
        Last iterate (the upper end ``hi`` where f(hi) met ``ftol`` at the start).
    f : array
        f(x).
    lo, hi : array
        Final bracket, with f(lo) <= 0 <= f(hi) (up to the Illinois weights).
    converged : bool array
        Where a stopping test was met (or the bracket was skipped).
    """

    x: np.ndarray
    f: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    converged: np.ndarray


def illinois(fun: Callable[[np.ndarray], np.ndarray], lo, hi, flo, fhi, *, ftol=0.0, xtol=0.0, rtol=0.0,
             maxiter=100, skip=None) -> Root:
    """Roots of f on many brackets at once by the Illinois method (modified regula falsi).

    Each step replaces one end of every open bracket [lo, hi] by the secant point

    .. math:: x = hi - f(hi) \\frac{hi - lo}{f(hi) - f(lo)}

    (clipped to the bracket; the midpoint where f(hi) = f(lo)), keeping the sign change.
    When the same end survives two steps in a row, its stored f is halved (the Illinois
    modification), which restores superlinear convergence (order ~1.44) where plain regula
    falsi would stall with one end fixed. Solved brackets are frozen while the others go on,
    so ``fun`` is always called on the whole batch.

    Parameters
    ----------
    fun : callable, array (B,) -> array (B,)
        f at one point per bracket, element-wise independent.
    lo, hi : array (B,)
        Bracket ends (any units), lo <= hi.
    flo, fhi : array (B,)
        f(lo) <= 0 <= f(hi): f changes sign upwards (pass -f for a decreasing function;
        the negation is exact, so the iterates do not change).
    ftol : float
        Stop where |f(x)| <= ftol (units of f); the default 0 stops only on an exact zero.
    xtol, rtol : float
        Stop where hi - lo <= xtol + rtol max(|hi|, 1e-300) (units of x; relative).
    maxiter : int
        Largest number of calls of ``fun``.
    skip : bool array (B,), optional
        Brackets not to iterate (already solved, or not wanted): returned as given.

    Returns
    -------
    Root
        x, f(x), the final bracket and a converged mask. Brackets with |f(hi)| <= ftol at the
        start are solved at x = hi without a call. The caller decides what non-convergence
        means (raise, or measure a residual).

    References
    ----------
    M. Dowell and P. Jarratt, "A modified regula falsi method for computing the root of an
    equation", BIT 11, 168-174 (1971).
    """
    x = hi.copy()
    fx = fhi.copy()
    side = np.zeros_like(lo)  # which end the last step replaced: -1 lo, +1 hi
    done = np.abs(fhi) <= ftol
    if skip is not None:
        done = done | skip
    for _ in range(maxiter):
        if np.all(done):
            break
        den = fhi - flo
        xn = np.where(den != 0, hi - fhi * (hi - lo) / np.where(den != 0, den, 1.0), 0.5 * (lo + hi))
        xn = np.clip(xn, lo, hi)
        fn = fun(xn)
        x = np.where(done, x, xn)
        fx = np.where(done, fx, fn)
        up = fn < 0  # the root lies above xn
        lo = np.where(done | ~up, lo, xn)
        hi = np.where(done | up, hi, xn)
        flo = np.where(done, flo, np.where(up, fn, np.where(side == 1, 0.5 * flo, flo)))
        fhi = np.where(done, fhi, np.where(up, np.where(side == -1, 0.5 * fhi, fhi), fn))
        side = np.where(up, -1.0, 1.0)
        done = done | (np.abs(fn) <= ftol) | (hi - lo <= xtol + rtol * np.maximum(np.abs(hi), 1e-300))
    return Root(x, fx, lo, hi, done)
