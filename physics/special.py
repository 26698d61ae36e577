"""The special functions the kernels use, from :mod:`scipy.special`, imported on first call, and
a numpy-only exponential integral for the separation kernel (:func:`exp1_fast`).

Importing scipy.special costs a few tenths of a second; a run with nothing to compute (every
result fresh) loads the stage declarations, and with them these kernels, but never calls them.
"""

from __future__ import annotations

import functools
import math

import numpy as np


def _from_scipy(name: str):
    def call(*args, **kwargs):
        import scipy.special

        return getattr(scipy.special, name)(*args, **kwargs)

    call.__name__ = call.__qualname__ = name
    call.__doc__ = f"scipy.special.{name} (imported on first call)."
    return call


#: error function, scaled complementary error function exp(x^2) erfc(x), exponential integral E1,
#: log of the absolute value of the gamma function, inverse of the regularized lower incomplete gamma
erf, erfcx, exp1, gammaln, gammaincinv = (_from_scipy(n) for n in ("erf", "erfcx", "exp1", "gammaln", "gammaincinv"))
#: inverse error function, standard normal distribution function
erfinv, ndtr = (_from_scipy(n) for n in ("erfinv", "ndtr"))


@functools.cache
def _ein_coefficients(degree: int = 11) -> tuple[float, ...]:
    """Monomial coefficients c_k of Ein(x)/x = sum_k c_k x^k on [0, 1]: the Chebyshev interpolant
    of degree ``degree`` of the series Ein(x)/x = sum_{k>=1} (-1)^(k+1) x^(k-1) / (k k!) (30 terms,
    exact in double precision there), economised to ``degree`` + 1 terms (instead of 17)."""
    from numpy.polynomial import Chebyshev

    def series(x):
        total, term = np.zeros_like(x), np.ones_like(x)
        for k in range(1, 30):
            total += term / (k * math.factorial(k))
            term = -term * x
        return total

    fit = Chebyshev.interpolate(series, degree, domain=[0.0, 1.0])
    return tuple(float(c) for c in fit.convert(kind=np.polynomial.Polynomial).coef)


#: Abramowitz & Stegun 5.1.56: x e^x E1(x) = P(x)/Q(x) within 2e-8 for x >= 1 (P, Q monic quartics)
_E1_P = (8.5733287401, 18.0590169730, 8.6347608925, 0.2677737343)
_E1_Q = (9.5733223454, 25.6329561486, 21.0996530827, 3.9584969228)


def exp1_fast(x):
    """The exponential integral E1(x) = \\int_x^inf e^-t dt / t for x >= 0 (dimensionless), in
    numpy only, 3-4 times faster than ``scipy.special.exp1`` over the arguments of the separation
    stage (whose kernel evaluates E1 at every pressure, node and spectrum draw).

    .. math:: E_1(x) = -\\gamma - \\ln x + \\mathrm{Ein}(x), \\quad
              \\mathrm{Ein}(x) = \\sum_{k \\ge 1} \\frac{(-1)^{k+1} x^k}{k\\, k!} \\quad (x < 1);
              \\qquad x e^x E_1(x) = \\frac{P(x)}{Q(x)} \\quad (x \\ge 1)

    Below 1, Ein(x)/x is a polynomial of degree 11 (the series economised on [0, 1],
    :func:`_ein_coefficients`): relative error below 1e-14 (tests/test_special.py). From 1 on,
    the rational approximation of Abramowitz & Stegun 5.1.56 (two quartics): relative error
    below 2e-8. E1(0) = inf; E1(x) = 0 from x = 750 on (E1 < 1e-328 there). NaN stays NaN.

    Parameters
    ----------
    x : array
        Argument (dimensionless), >= 0.

    Returns
    -------
    array
        E1(x), same shape as ``x``.

    References
    ----------
    Abramowitz & Stegun, Handbook of Mathematical Functions (1964), eqs 5.1.11 and 5.1.56;
    docs/theory.md, section "Separation".
    """
    x = np.asarray(x, dtype=float)
    out = np.empty(x.shape)
    flat, into = np.ascontiguousarray(x).reshape(-1), out.reshape(-1)  # ``into`` a view of ``out``
    for i in range(0, flat.size, _BLOCK):  # blocks that stay in the CPU cache through the ~30 passes
        _ein_branch(flat[i:i + _BLOCK], into[i:i + _BLOCK])
    high = x >= 1.0  # replaced (NaN compares false: it stays NaN from the series branch)
    if high.any():
        z = x[high]
        p = (((z + _E1_P[0]) * z + _E1_P[1]) * z + _E1_P[2]) * z + _E1_P[3]
        q = (((z + _E1_Q[0]) * z + _E1_Q[1]) * z + _E1_Q[2]) * z + _E1_Q[3]
        with np.errstate(under="ignore", over="ignore", invalid="ignore"):
            out[high] = np.where(z < 750.0, np.exp(-np.minimum(z, 750.0)) / z * p / q, 0.0)
    return out


#: elements per block of :func:`exp1_fast` (128 KiB of doubles)
_BLOCK = 2**14


def _ein_branch(x, out) -> None:
    """out = -gamma - ln y + Ein(y), y = min(x, 1), in place (``out`` a view of the result)."""
    coef = _ein_coefficients()
    y = np.minimum(x, 1.0)
    out.fill(coef[-1])
    for c in coef[-2::-1]:  # Horner
        out *= y
        out += c
    out *= y
    with np.errstate(divide="ignore"):
        np.log(y, out=y)
    out -= y
    out -= np.euler_gamma
