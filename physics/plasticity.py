"""Elastoplastic contact of rough surfaces in Persson's theory: the stress distribution with a
penetration hardness sigma_Y, the elastic and the plastic contact areas, and their load.

Persson's P(sigma, zeta) obeys the diffusion equation dP/dG = d^2P/dsigma^2 (seed eq 1 with G
of eq 17 as "time"), starting from P(sigma, 0) = delta(sigma - p). Elastic contact alone puts
one absorbing wall at sigma = 0 (separation), whose image solution is eq 16. A solid that
yields where the local pressure reaches its penetration hardness sigma_Y adds a second
absorbing wall at sigma = sigma_Y: the probability flowing out there is contact area that has
deformed plastically and carries exactly sigma_Y (Persson, Phys. Rev. Lett. 87, 116101 (2001);
J. Chem. Phys. 115, 3840 (2001)).

With tau = G / sigma_Y^2 (dimensionless) every quantity has two exact forms:

- the Fourier sine series on [0, sigma_Y], whose n-th term carries exp(-(n pi)^2 tau): fast
  where tau is large;
- the method of images (image charges at 2 m sigma_Y +- p), whose m-th pair carries about
  exp(-(2|m| - 1)^2 / (4 tau)): fast where tau is small.

The kernels use the images for tau < :data:`TAU_SWITCH` = 0.02 and the series at and above it,
with N = 1, 2, 3, 4, 8 or 16 terms for tau >= 1.5, 0.65, 0.37, 0.3, 0.08 or 0.02 (:data:`SERIES_BINS`):
the first term left out is below exp(-(N + 1)^2 pi^2 tau) <= exp(-57) ~ 1e-25 of the first. Below the switch
the image pairs m = -1, 0, 1 (:data:`IMAGE_PAIRS`) suffice: the next pairs lie at least
2 sigma_Y outside [0, sigma_Y] and weigh exp(-1/tau) < exp(-50) ~ 1e-22. Where the wall at
sigma_Y lies beyond :data:`FAR` = 27 diffusion lengths 2 sqrt(G) of p (every image term below
1e-300), the one-wall solution (eqs 16, 19) is returned, as exact. So a fixed, small number of
terms converges for every G from 0 to infinity (tests/test_plasticity.py checks G / sigma_Y^2
from 1e-30 to 1e30, and that doubling the terms changes nothing). Each image sum is written as
differences of erfc of same-signed arguments, so that small areas keep their relative precision
(sigma_Y -> infinity gives eq 19 to rounding).

See docs/theory.md, section "Elastoplastic contact", and docs/plasticity.md.
"""

from __future__ import annotations

import numpy as np

from .contact import contact_area_ratio
from .inputs import require_nonnegative, require_pressure
from .special import erf, ndtr

#: below this tau = G / sigma_Y^2 the method of images, at and above it the sine series
TAU_SWITCH = 0.02
#: the sine series' terms n = 1 .. N for tau at or above each bound: exp(-(N + 1)^2 pi^2 tau) < exp(-57)
#: ~ 2e-25 at the bound (the next term's size relative to the first); most of a sweep over zeta has
#: tau >= 1.5, where one term is exact
SERIES_BINS = ((1.5, 1), (0.65, 2), (0.37, 3), (0.3, 4), (0.08, 8), (TAU_SWITCH, 16))
#: the bounds of SERIES_BINS, increasing (for searchsorted)
_BOUNDS = np.array([bound for bound, _ in SERIES_BINS[::-1]])
#: the largest number of series terms
SERIES_TERMS = 16
#: image pairs m = -IMAGE_PAIRS .. IMAGE_PAIRS (the next pairs weigh exp(-1 / tau) < 1e-21 below TAU_SWITCH)
IMAGE_PAIRS = 1
#: where (sigma_Y - p) / (2 sqrt G) exceeds this, erfc of it underflows (< 1e-300): the wall at sigma_Y
#: is out of reach and the one-wall solution (eqs 16, 19) is exact in float64
FAR = 27.0

_N = np.arange(1, SERIES_TERMS + 1, dtype=float)
_M = np.arange(-IMAGE_PAIRS, IMAGE_PAIRS + 1, dtype=float)


def _erfc(x):
    """erfc(x) for any real x, precise in relative terms for x >= 0 (from the normal tail, ndtr)."""
    return 2.0 * ndtr(-np.sqrt(2.0) * np.asarray(x, dtype=float))


def _erf_difference(u, v):
    """erf(u) - erf(v) without cancellation: from the tails (erfc) where u and v share a sign,
    from erf where they do not (then no cancellation: the two have opposite signs)."""
    u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    flip = (u < 0) & (v < 0)  # erf(u) - erf(v) = erf(-v) - erf(-u)
    u, v = np.where(flip, -v, u), np.where(flip, -u, v)
    out = _erfc(v) - _erfc(u)
    mixed = (u < 0) | (v < 0)
    if np.any(mixed):
        out[mixed] = erf(u[mixed]) - erf(v[mixed])
    return out


def _inputs(p, G, sigma_Y):
    p = require_pressure(p)
    G = require_nonnegative(G, "G")
    sigma_Y = require_pressure(sigma_Y, "sigma_Y", positive=True)
    return np.broadcast_arrays(p, G, sigma_Y)


def _dispatch(p, G, sigma_Y, series, images, one_wall, saturated):
    """Evaluate each point in its regime, on its points only (no point pays for two forms):
    ``saturated`` (constants) where p >= sigma_Y; ``one_wall(p, G)`` (the elastic solution, G = 0
    included) where the wall at sigma_Y is out of float64 reach; ``images`` where tau < TAU_SWITCH;
    ``series(p, G, sigma_Y, N)`` with the N terms of :data:`SERIES_BINS` above. Each function
    returns an array (k, points): k results at once (k = len(saturated))."""
    p, G, sigma_Y = _inputs(p, G, sigma_Y)
    shape = p.shape
    p, G, sigma_Y = p.ravel(), G.ravel(), sigma_Y.ravel()
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        tau = G / sigma_Y**2
        far = (sigma_Y - p) > FAR * 2.0 * np.sqrt(G)
    # regime of each point: 0 saturated, 1 one wall, 2 images, 3 + i the series of SERIES_BINS[i];
    # the points are sorted by regime once, so that each form runs on one contiguous slice
    code = (3 + len(_BOUNDS) - np.searchsorted(_BOUNDS, tau, side="right")).astype(np.int8)
    code[tau < TAU_SWITCH] = 2
    code[far] = 1
    code[p >= sigma_Y] = 0
    order = np.argsort(code, kind="stable")
    ends = np.cumsum(np.bincount(code, minlength=3 + len(SERIES_BINS)))
    p, G, sigma_Y = p[order], G[order], sigma_Y[order]
    sorted_out = np.empty((len(saturated), p.size))
    forms = [lambda a, b, c: np.asarray(saturated, dtype=float)[:, None], lambda a, b, c: one_wall(a, b), images]
    forms += [lambda a, b, c, n=terms: series(a, b, c, n) for _, terms in SERIES_BINS]
    for form, lo, hi in zip(forms, np.concatenate([[0], ends[:-1]]), ends, strict=True):
        if hi > lo:
            sorted_out[:, lo:hi] = form(p[lo:hi], G[lo:hi], sigma_Y[lo:hi])
    out = np.empty_like(sorted_out)
    out[:, order] = sorted_out
    return out.reshape((len(saturated), *shape))


def _areas_series(p, G, sigma_Y, terms):
    """A_el/A0 and A_pl/A0 from one set of modes (one term: the same arithmetic on 1-d arrays)."""
    if terms == 1:
        k = np.pi / sigma_Y
        with np.errstate(under="ignore"):
            weighted = np.sin(k * p) * np.exp(-(k * k) * G)
        return np.stack([(4.0 / np.pi) * weighted, (p - 2.0 * (weighted / k)) / sigma_Y])
    n, k, s, decay = _modes(p, G, sigma_Y, terms)
    weighted = s * decay
    a_el = np.sum(((n % 2 == 1) * 4.0 / (n * np.pi)) * weighted, axis=-1)
    load = 2.0 * np.sum(np.where(n % 2 == 1, 1.0, -1.0) * weighted / k, axis=-1)
    return np.stack([a_el, (p - load) / sigma_Y])


def _areas_images(p, G, sigma_Y):
    """A_el/A0 and A_pl/A0 of the image pairs m = -1, 0, 1 (:data:`IMAGE_PAIRS`) in closed form.

    With 0 < p < sigma_Y the sign of every charge's distance to each wall is known, and the sums of
    :func:`_elastic_area_images` and :func:`_plastic_area_images` collapse to error functions of
    u, w, v = (k sigma_Y -+ p) / 2 sqrt G, k = 1, 2, 3:

        A_el(p) = erf(p / 2 sqrt G) + [erfc w- - erfc w+] - [erfc u- - erfc u+] - [erfc v- - erfc v+] / 2,
        A_pl(p) = [erfc u- - erfc u+] + [erfc v- - erfc v+] / 2.

    A_el is evaluated at min(p, sigma_Y - p) (the two walls are alike: A_el(p) = A_el(sigma_Y - p)),
    so that near p = sigma_Y it keeps its relative precision (no cancellation of erf ~ 1 against
    erfc ~ 1); A_pl has none to fear (erfc u- ~ 1 there, erfc u+ tiny)."""
    s = 2.0 * np.sqrt(G)
    k = np.array([1.0, 2.0, 3.0])[:, None] * sigma_Y
    x = np.minimum(p, sigma_Y - p)
    # erfc of u-, w-, v-, u+, w+, v+ at x, then of u-, v-, u+, v+ at p
    t = _erfc(np.concatenate([k - x, k + x, k[::2] - p, k[::2] + p]) / s)
    a_el = erf(x / s) + (t[1] - t[4]) - (t[0] - t[3]) - 0.5 * (t[2] - t[5])
    return np.stack([a_el, (t[6] - t[8]) + 0.5 * (t[7] - t[9])])


def _elastic_area_images_closed(p, G, sigma_Y):
    return _areas_images(p, G, sigma_Y)[0]


def _plastic_area_images_closed(p, G, sigma_Y):
    return _areas_images(p, G, sigma_Y)[1]


# --- sine series (tau >= TAU_SWITCH) -------------------------------------------------------------

def _modes(p, G, sigma_Y, terms):
    """k_n = n pi / sigma_Y (1/Pa), sin(k_n p) and exp(-k_n^2 G) for n = 1 .. terms."""
    n = _N[:terms]
    k = n * np.pi / sigma_Y[:, None]
    with np.errstate(under="ignore"):
        decay = np.exp(-(k * k) * G[:, None])
    return n, k, np.sin(k * p[:, None]), decay


def _elastic_area_series(p, G, sigma_Y, terms=SERIES_TERMS):
    n, _, s, decay = _modes(p, G, sigma_Y, terms)
    odd = (n % 2 == 1) * 4.0 / (n * np.pi)
    return np.sum(odd * s * decay, axis=-1)


def _elastic_load_series(p, G, sigma_Y, terms=SERIES_TERMS):
    n, k, s, decay = _modes(p, G, sigma_Y, terms)
    sign = np.where(n % 2 == 1, 1.0, -1.0)
    return 2.0 * np.sum(sign * s * decay / k, axis=-1)


def _plastic_area_series(p, G, sigma_Y, terms=SERIES_TERMS):
    return (p - _elastic_load_series(p, G, sigma_Y, terms)) / sigma_Y


# --- method of images (0 < tau < TAU_SWITCH) ------------------------------------------------------

def _charges(p, G, sigma_Y):
    """Positive charges a_m = p + 2 m sigma_Y, negative b_m = -p + 2 m sigma_Y (Pa), and s = 2 sqrt G."""
    shift = 2.0 * _M * sigma_Y[:, None]
    return p[:, None] + shift, -p[:, None] + shift, 2.0 * np.sqrt(G)[:, None]


def _elastic_area_images(p, G, sigma_Y):
    a, b, s = _charges(p, G, sigma_Y)
    Y = sigma_Y[:, None]
    # int_0^Y g(sigma - c) dsigma = (erf((Y - c)/s) + erf(c/s)) / 2, summed as a_m minus b_m
    return 0.5 * np.sum(_erf_difference(a / s, b / s) + _erf_difference((Y - a) / s, (Y - b) / s), axis=-1)


def _in_window(c, s, Y):
    """int_0^Y g(sigma - c) dsigma for the Gaussian g of variance s^2 / 2 centred at c."""
    return 0.5 * _erf_difference((Y - c) / s, -c / s)


def _elastic_load_images(p, G, sigma_Y):
    a, b, s = _charges(p, G, sigma_Y)
    Y = sigma_Y[:, None]
    # int_0^Y sigma g(sigma - c) dsigma = c W(c) + sqrt(G/pi) (exp(-c^2/4G) - exp(-(Y - c)^2/4G));
    # a W(a) - b W(b) = (a - b) W(a) + b (W(a) - W(b)) keeps the small pairs' cancellation exact
    window_diff = 0.5 * (_erf_difference(a / s, b / s) + _erf_difference((Y - a) / s, (Y - b) / s))
    first = (a - b) * _in_window(a, s, Y) + b * window_diff
    with np.errstate(under="ignore"):
        gauss = (np.exp(-(a / s) ** 2) - np.exp(-((Y - a) / s) ** 2)
                 - np.exp(-(b / s) ** 2) + np.exp(-((Y - b) / s) ** 2))
    return np.sum(first + 0.5 * s / np.sqrt(np.pi) * gauss, axis=-1)


def _plastic_area_images(p, G, sigma_Y):
    a, b, s = _charges(p, G, sigma_Y)
    Y = sigma_Y[:, None]

    def passed(x):  # int_0^G of the flux x/(2G') g(x, G') dG' through a wall at distance x
        return 0.5 * np.sign(x) * _erfc(np.abs(x) / s)

    return np.sum(passed(Y - a) - passed(Y - b), axis=-1)


# --- public kernels -------------------------------------------------------------------------------

def _one(series, images, one_wall, saturated):
    """A kernel of one result from the per-regime functions (see :func:`_dispatch`)."""
    def kernel(p, G, sigma_Y):
        return _dispatch(p, G, sigma_Y, lambda *a: series(*a)[None], lambda *a: images(*a)[None],
                         lambda *a: one_wall(*a)[None], (saturated,))[0]
    return kernel


def elastoplastic_areas(p, G, sigma_Y):
    """A_el/A0 and A_pl/A0 together (both dimensionless), sharing the series' modes: the same
    numbers as :func:`elastic_area_ratio` and :func:`plastic_area_ratio`, at about half their
    joint cost.

    Parameters
    ----------
    p, G, sigma_Y : float or array
        Nominal pressure (Pa), Persson's G (Pa^2, eq 17), penetration hardness (Pa); broadcast.

    Returns
    -------
    (A_el/A0, A_pl/A0) : arrays

    References
    ----------
    Persson, Phys. Rev. Lett. 87, 116101 (2001); docs/theory.md, section "Elastoplastic contact".
    """
    a_el, a_pl = _dispatch(p, G, sigma_Y, _areas_series, _areas_images,
                           lambda p, G: np.stack([contact_area_ratio(p, G), np.zeros_like(p)]), (0.0, 1.0))
    return a_el, a_pl


def elastic_area_ratio(p, G, sigma_Y):
    """Relative area of elastic contact A_el/A0 (dimensionless) with penetration hardness sigma_Y.

    .. math::
        A_{el}/A_0 = \\int_0^{\\sigma_Y} P(\\sigma, G)\\,d\\sigma
                   = \\sum_{n\\,\\mathrm{odd}} \\frac{4}{n\\pi} \\sin(k_n p)\\, e^{-k_n^2 G},
        \\qquad k_n = n\\pi/\\sigma_Y,

    or its image form (sums of erf differences, module docstring) for G < 0.02 sigma_Y^2.
    sigma_Y -> infinity gives eq 19, erf(p / 2 sqrt G); G = 0 gives 1 (full contact);
    p >= sigma_Y gives 0 (the nominal pressure already exceeds the hardness: every contact
    spot is plastic).

    Parameters
    ----------
    p : float or array
        Nominal pressure (Pa), >= 0.
    G : float or array
        Persson's G (Pa^2, eq 17) at the magnification of interest, >= 0; for two rough surfaces
        the G of their combined spectrum (eq 52-53).
    sigma_Y : float or array
        Penetration hardness (Pa), > 0. All three broadcast together.

    Returns
    -------
    array
        A_el/A0 in [0, 1].

    References
    ----------
    Persson, Phys. Rev. Lett. 87, 116101 (2001); Persson, J. Chem. Phys. 115, 3840 (2001);
    docs/theory.md, section "Elastoplastic contact".
    """
    return _one(_elastic_area_series, _elastic_area_images_closed, contact_area_ratio, 0.0)(p, G, sigma_Y)


def plastic_area_ratio(p, G, sigma_Y):
    """Relative area of plastically deformed contact A_pl/A0 (dimensionless).

    The probability absorbed at sigma = sigma_Y between G = 0 and G (the flux -dP/dsigma at
    sigma_Y accumulated over the magnifications). Series form (from the load it leaves the
    elastic spots):

    .. math::
        A_{pl}/A_0 = \\frac{1}{\\sigma_Y}\\Big[p - 2\\sum_{n\\ge1} (-1)^{n+1}
                     \\frac{\\sin(k_n p)}{k_n} e^{-k_n^2 G}\\Big];

    image form (first passage, computed from the flux itself, not from the load):
    A_pl/A0 = sum_m [h(sigma_Y - a_m) - h(sigma_Y - b_m)], h(x) = sign(x) erfc(|x| / 2 sqrt G) / 2,
    a_m = p + 2 m sigma_Y, b_m = -p + 2 m sigma_Y. Limits: G -> infinity gives p / sigma_Y
    (all load carried plastically); G = 0 gives 0; p >= sigma_Y gives 1.

    Parameters
    ----------
    p : float or array
        Nominal pressure (Pa), >= 0.
    G : float or array
        Persson's G (Pa^2, eq 17), >= 0.
    sigma_Y : float or array
        Penetration hardness (Pa), > 0.

    Returns
    -------
    array
        A_pl/A0 in [0, min(1, p / sigma_Y)].

    References
    ----------
    Persson, Phys. Rev. Lett. 87, 116101 (2001); docs/theory.md, section "Elastoplastic contact".
    """
    return _one(_plastic_area_series, _plastic_area_images_closed, lambda p, G: np.zeros_like(p), 1.0)(p, G, sigma_Y)


def elastic_load(p, G, sigma_Y):
    """Load per nominal area carried by the elastic contact spots (Pa): the first moment
    int_0^sigma_Y sigma P(sigma, G) dsigma = (mean stress in the elastic area) x A_el/A0.

    .. math::
        \\int_0^{\\sigma_Y}\\sigma P\\,d\\sigma = 2\\sum_{n\\ge1}(-1)^{n+1}\\frac{\\sin(k_n p)}{k_n}e^{-k_n^2 G}

    (image form for G < 0.02 sigma_Y^2). Load balance: elastic_load + sigma_Y A_pl/A0 = p for
    p < sigma_Y (:func:`load_residual`).

    Parameters
    ----------
    p, G, sigma_Y : float or array
        Nominal pressure (Pa), Persson's G (Pa^2), penetration hardness (Pa).

    Returns
    -------
    array
        Pa.

    References
    ----------
    Persson, Phys. Rev. Lett. 87, 116101 (2001); docs/theory.md, section "Elastoplastic contact".
    """
    return _one(_elastic_load_series, _elastic_load_images, lambda p, G: p, 0.0)(p, G, sigma_Y)


def load_residual(p, G, sigma_Y):
    """The load check (dimensionless): [elastic_load + sigma_Y A_pl/A0] / p - 1, zero for p < sigma_Y.

    In the image regime (G < 0.02 sigma_Y^2) the elastic load and A_pl are computed
    independently (first moment of P; flux through sigma_Y), so the residual measures their
    consistency; in the series regime A_pl follows from the load and the residual is zero by
    construction. For p >= sigma_Y the interface cannot carry p (sigma_Y A0 < p A0): the
    residual is sigma_Y / p - 1 < 0. NaN at p = 0.

    Parameters
    ----------
    p, G, sigma_Y : float or array
        Nominal pressure (Pa), Persson's G (Pa^2), penetration hardness (Pa).
    """
    p, G, sigma_Y = _inputs(p, G, sigma_Y)
    total = elastic_load(p, G, sigma_Y) + sigma_Y * plastic_area_ratio(p, G, sigma_Y)
    with np.errstate(divide="ignore", invalid="ignore"):
        return total / p - 1.0


def elastoplastic_stress_distribution(sigma, p, G, sigma_Y):
    """Stress distribution P(sigma, G) (1/Pa) between the absorbing walls sigma = 0 and sigma_Y.

    .. math::
        P = \\frac{2}{\\sigma_Y}\\sum_{n\\ge1}\\sin(k_n p)\\sin(k_n\\sigma)e^{-k_n^2 G}
          = \\sum_m [g(\\sigma - p - 2m\\sigma_Y) - g(\\sigma + p - 2m\\sigma_Y)],
        \\quad g(x) = \\frac{e^{-x^2/4G}}{\\sqrt{4\\pi G}},

    the series (16 terms) for G >= 0.02 sigma_Y^2, the images (m = -1, 0, 1) below (module docstring). Zero outside
    (0, sigma_Y) and for p >= sigma_Y; it integrates to A_el/A0. The plastic spots, at exactly
    sigma_Y, are a delta of weight A_pl/A0 not included here. sigma_Y -> infinity gives eq 16.

    Parameters
    ----------
    sigma : array (k,) or (..., k)
        Local normal stress (Pa); leading axes broadcast with p, G and sigma_Y.
    p : float or array
        Nominal pressure (Pa), >= 0.
    G : float or array
        Persson's G (Pa^2), > 0.
    sigma_Y : float or array
        Penetration hardness (Pa), > 0.

    Returns
    -------
    array (..., k)
        1/Pa.

    References
    ----------
    Persson, Phys. Rev. Lett. 87, 116101 (2001); docs/theory.md, section "Elastoplastic contact".
    """
    sigma = np.asarray(sigma, dtype=float)
    p, G, sigma_Y = (x[..., None] for x in _inputs(p, G, sigma_Y))
    if np.any(G <= 0):
        raise ValueError("G must be > 0 for P(sigma) (G = 0 is a delta at sigma = p)")
    tau = G / sigma_Y**2
    with np.errstate(under="ignore"):
        k = np.pi * _N / sigma_Y[..., None]
        series = (2.0 / sigma_Y) * np.sum(np.sin(k * p[..., None]) * np.sin(k * sigma[..., None])
                                          * np.exp(-(k * k) * G[..., None]), axis=-1)
        # pair m: g(x - p) - g(x + p), x = sigma - 2 m sigma_Y, as g(x -+ p) (-expm1(-+x p / G)): no cancellation
        x = sigma[..., None] - 2.0 * _M * sigma_Y[..., None]
        pp, GG = p[..., None], G[..., None]
        near = np.where(x >= 0, x - pp, x + pp)
        pairs = np.sign(x) * np.exp(-near**2 / (4.0 * GG)) * -np.expm1(-np.abs(x) * pp / GG)
        images = np.sum(pairs, axis=-1) / np.sqrt(np.pi * 4.0 * G)
    inside = (sigma > 0) & (sigma < sigma_Y) & (p < sigma_Y)
    return np.where(inside, np.where(tau >= TAU_SWITCH, series, images), 0.0)
