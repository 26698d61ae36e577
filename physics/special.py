"""The special functions the kernels use, from :mod:`scipy.special`, imported on first call.

Importing scipy.special costs a few tenths of a second; a run with nothing to compute (every
result fresh) loads the stage declarations, and with them these kernels, but never calls them.
"""

from __future__ import annotations


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
