"""The one quadrature helper of roughcontact: integrals over log-spaced grids.

Roughness spectra are power laws over many decades, so every integral over q is done by
*piecewise power-law* quadrature: between two grid nodes the integrand is interpolated
linearly in log-log space and that piece is integrated exactly. This is exact for the
self-affine PSD (with the knots qL, q0, q1 on the grid) and second-order accurate in the
log-spacing otherwise. Segments where the integrand is zero or negative at an end are
integrated by the trapezoidal rule (power-law interpolation is undefined there).

All functions work along the last axis and broadcast over leading axes (numpy kernels,
wrapped with ``xarray.apply_ufunc`` by the stages).
"""

from __future__ import annotations

import functools

import numpy as np


def _exprel(z):
    """(exp(z) - 1) / z, accurate near 0 and finite for large |z| (overflow clipped)."""
    z = np.asarray(z, dtype=float)
    small = np.abs(z) < 1e-8
    safe = np.where(small, 1.0, z)
    out = np.expm1(np.clip(safe, -700.0, 700.0)) / safe
    return np.where(small, 1.0 + 0.5 * z, out)


def segment_integrals(x, y):
    """Integrals of ``y`` over each segment [x_i, x_{i+1}], piecewise power law.

    Parameters
    ----------
    x : array (n,)
        Strictly increasing positive abscissae.
    y : array (..., n)
        Integrand values at ``x``.

    Returns
    -------
    array (..., n - 1)
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return segment_integrals_pairs(x[:-1], x[1:], y[..., :-1], y[..., 1:])


def cumulative_integral(x, y):
    """Running integral from ``x[0]`` to each node, shape of ``y`` (first value 0)."""
    seg = segment_integrals(x, y)
    out = np.zeros(np.shape(y), dtype=float)
    np.cumsum(seg, axis=-1, out=out[..., 1:])
    return out


def integral(x, y):
    """Integral of ``y`` over the whole grid ``x`` (last axis)."""
    return segment_integrals(x, y).sum(axis=-1)


def integral_to(x, y, upper):
    """Integral of ``y`` from ``x[0]`` to each value of ``upper`` (within [x[0], x[-1]]).

    The partial last segment is integrated with the same power-law interpolation.

    Parameters
    ----------
    x : array (n,)
    y : array (..., n)
    upper : array (m,)

    Returns
    -------
    array (..., m)
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    upper = np.asarray(upper, dtype=float)
    if np.any(upper < x[0] * (1 - 1e-12)) or np.any(upper > x[-1] * (1 + 1e-12)):
        raise ValueError("upper limits must lie within the grid")
    upper = np.clip(upper, x[0], x[-1])
    cum = cumulative_integral(x, y)
    i = np.clip(np.searchsorted(x, upper, side="right") - 1, 0, x.size - 2)
    xa, xb = x[i], x[i + 1]
    ya, yb = y[..., i], y[..., i + 1]
    yu = _loglog_between(xa, xb, ya, yb, upper)
    partial = segment_integrals_pairs(xa, upper, ya, yu)
    return cum[..., i] + partial


def segment_integrals_pairs(xa, xb, ya, yb):
    """Power-law integral over [xa, xb] for arrays of segment ends (elementwise)."""
    xa, xb, ya, yb = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (xa, xb, ya, yb)))
    L = np.log(xb / xa)
    positive = (ya > 0) & (yb > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(positive & (L > 0),
                     np.log(np.where(positive, yb, 1.0) / np.where(positive, ya, 1.0)) / np.where(L > 0, L, 1.0), 0.0)
        power = ya * xa * L * _exprel((s + 1.0) * L)
    trapezoid = 0.5 * (ya + yb) * (xb - xa)
    return np.where(positive, power, trapezoid)


def _loglog_between(xa, xb, ya, yb, xq):
    positive = (ya > 0) & (yb > 0)
    t = np.log(xq / xa) / np.log(xb / xa)
    with np.errstate(divide="ignore", invalid="ignore"):
        loglog = np.exp(np.log(np.where(positive, ya, 1.0)) * (1 - t) + np.log(np.where(positive, yb, 1.0)) * t)
    linear = ya + (yb - ya) * (xq - xa) / (xb - xa)
    return np.where(positive, loglog, linear)


def loglog_interp(xq, x, y):
    """Interpolate ``y(x)`` at ``xq`` linearly in log-log space (linear where y <= 0).

    ``xq`` must lie within [x[0], x[-1]]; extrapolation is the caller's decision.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    xq = np.asarray(xq, dtype=float)
    i = np.clip(np.searchsorted(x, xq, side="right") - 1, 0, x.size - 2)
    return _loglog_between(x[i], x[i + 1], y[..., i], y[..., i + 1], xq)


def _log_pieces(lo: float, hi: float, points_per_decade: int, knots=()):
    """The knots of :func:`log_grid` (lo, hi and the knots between) and the nodes per piece."""
    if not (0 < lo < hi):
        raise ValueError("log_grid needs 0 < lo < hi")
    if points_per_decade < 1:
        raise ValueError("points_per_decade must be >= 1")
    edges = np.unique(np.concatenate([[lo, hi], [k for k in knots if lo < k < hi]]))
    counts = [max(1, int(np.ceil(np.log10(b / a) * points_per_decade - 1e-9)))
              for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return edges, counts


def log_grid_size(lo: float, hi: float, points_per_decade: int, knots=()) -> int:
    """The number of nodes :func:`log_grid` gives for these arguments, without building it."""
    return int(sum(_log_pieces(lo, hi, points_per_decade, knots)[1])) + 1


def log_grid(lo: float, hi: float, points_per_decade: int, knots=()) -> np.ndarray:
    """Geometric grid from ``lo`` to ``hi`` with about ``points_per_decade`` nodes per decade.

    Every knot inside [lo, hi] (band edges, roll-off) is a node: the grid is built piece by
    piece between consecutive knots, each piece geometric with the spacing closest to the
    requested one. Exact power-law quadrature then needs no node to straddle a kink.
    """
    edges, counts = _log_pieces(lo, hi, points_per_decade, knots)
    pieces = [np.geomspace(a, b, n + 1)[:-1] for a, b, n in zip(edges[:-1], edges[1:], counts, strict=True)]
    pieces.append([hi])
    return np.concatenate(pieces)


def gauss_legendre_panels(edges, order: int):
    """Gauss-Legendre nodes and weights on consecutive panels [edges_k, edges_{k+1}].

    Parameters
    ----------
    edges : array (..., n + 1)
        Panel ends, non-decreasing along the last axis (zero-width panels get zero weights).
    order : int
        Nodes per panel; exact for polynomials of degree ``2 order - 1`` on each panel.

    Returns
    -------
    nodes, weights : arrays (..., n * order)
        Panel by panel, in increasing order; ``(weights * f(nodes)).sum(-1)`` is the integral
        of ``f`` from ``edges[..., 0]`` to ``edges[..., -1]``.
    """
    edges = np.asarray(edges, dtype=float)
    t, w = _leggauss(int(order))
    a, b = edges[..., :-1, None], edges[..., 1:, None]
    half = 0.5 * (b - a)
    nodes = 0.5 * (a + b) + half * t
    weights = half * w
    shape = edges.shape[:-1] + (-1,)
    return nodes.reshape(shape), np.broadcast_to(weights, nodes.shape).reshape(shape)


@functools.lru_cache(maxsize=64)
def _leggauss(order: int):
    """Gauss-Legendre nodes and weights on [-1, 1] (cached: the kernels ask for the same few
    orders thousands of times; the arrays are read-only)."""
    t, w = np.polynomial.legendre.leggauss(order)
    t.flags.writeable = w.flags.writeable = False
    return t, w


def inverse_cumulative_integral(x, y, level):
    """The abscissa at which the running integral of ``y`` from ``x[0]`` reaches ``level``.

    The inverse of :func:`cumulative_integral` / :func:`integral_to` under the same model: on
    each segment the integrand is the power law through its end values (or the straight line
    where an end is zero), and that model's running integral is inverted in closed form
    (``x_i (1 + (k + 1) dI / (y_i x_i))^(1/(k + 1))`` for a power law of exponent k, the root
    of a quadratic for a straight line). Where ``y`` vanishes on a stretch the running
    integral is flat and the *end* of the stretch is returned.

    Parameters
    ----------
    x : array (n,)
        Strictly increasing positive abscissae.
    y : array (..., n)
        Integrand values, ``y >= 0`` (the running integral must be non-decreasing).
    level : array (..., m)
        Target values of the running integral, within [0, total] (clipped to it).

    Returns
    -------
    array (..., m)
        Abscissae in [x[0], x[-1]].
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    cum = cumulative_integral(x, y)
    lead = np.broadcast_shapes(cum.shape[:-1], np.shape(level)[:-1])
    cum = np.broadcast_to(cum, lead + cum.shape[-1:])
    y = np.broadcast_to(y, cum.shape)
    level = np.broadcast_to(np.asarray(level, dtype=float), lead + np.shape(level)[-1:])
    level = np.clip(level, 0.0, cum[..., -1:])
    found = _searchsorted_rows(cum, level)
    i = np.clip(found, 0, x.size - 2)
    xa, xb = x[i], x[i + 1]
    ya, yb = np.take_along_axis(y, i, -1), np.take_along_axis(y, i + 1, -1)
    dI = np.maximum(level - np.take_along_axis(cum, i, -1), 0.0)
    positive = (ya > 0) & (yb > 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # power law y = ya (x/xa)^k: dI = ya xa ((x/xa)^(k+1) - 1)/(k+1)
        k1 = np.log(np.where(positive, yb, 1.0) / np.where(positive, ya, 1.0)) / np.log(xb / xa) + 1.0
        r = dI / np.where(positive, ya * xa, 1.0)
        t = k1 * r
        logratio = np.where(np.abs(t) < 1e-8, r * (1.0 - 0.5 * t),
                            np.log1p(np.maximum(t, -1.0 + 1e-300)) / np.where(k1 == 0, 1.0, k1))
        x_power = xa * np.exp(logratio)
        # straight line y = ya + m (x - xa): dI = ya d + m d^2 / 2
        m = (yb - ya) / (xb - xa)
        den = ya + np.sqrt(np.maximum(ya * ya + 2.0 * m * dI, 0.0))
        x_line = xa + np.where(den > 0, 2.0 * dI / np.where(den > 0, den, 1.0), 0.0)
    out = np.clip(np.where(positive, x_power, x_line), xa, xb)
    return np.where(found >= x.size - 1, x[-1], out)


def _searchsorted_rows(a, v):
    """Row-wise ``searchsorted(a_row, v_row, side='right') - 1`` for non-decreasing rows.

    ``a`` (..., n) and ``v`` (..., m) with the same leading shape. Each row is mapped to its
    own interval of the real line so that one flat ``searchsorted`` serves every row.
    """
    lead = a.shape[:-1]
    n, m = a.shape[-1], v.shape[-1]
    a2 = a.reshape(-1, n)
    v2 = v.reshape(-1, m)
    lo = a2[:, :1]
    span = a2[:, -1:] - lo
    span = np.where(span > 0, span, 1.0)
    offset = 4.0 * np.arange(a2.shape[0])[:, None]
    keys = (a2 - lo) / span + offset
    targets = np.clip((v2 - lo) / span, -0.5, 1.5) + offset
    idx = np.searchsorted(keys.ravel(), targets.ravel(), side="right").reshape(v2.shape) - 1
    idx -= n * np.arange(a2.shape[0])[:, None]
    return idx.reshape(lead + (m,))


def gauss_legendre(a: float, b: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the ``n``-point Gauss-Legendre rule on [a, b].

    ``(f(nodes) * weights).sum(-1)`` integrates polynomials of degree <= 2n - 1 exactly;
    for smooth integrands the error falls exponentially with ``n``. Used for the angular
    integrals of the friction stage (phi on [0, pi/2]).
    """
    if n < 1:
        raise ValueError("gauss_legendre needs n >= 1")
    return gauss_legendre_panels(np.array([a, b], dtype=float), n)


def running_weighted_integral(x, g, r, F, nodes: int = 12, scale: float = 0.01):
    """\\int r(x) F(Y(x)) g(x) dx = \\int r F(Y) dY over the grid, where Y(x) = \\int_{x[0]}^x g.

    For integrands whose fast variation comes through a known function F of the running
    integral Y (e.g. the contact fraction P(G) = erf(1/(2 sqrt G)) of the friction stage,
    which falls like 1/sqrt(x - x[0]) just above x[0] when G grows steeply there): plain
    power-law quadrature of r F g converges only to first order in the grid spacing then.
    Here each segment is integrated in the variable Y by Gauss-Legendre in
    t = ln(sqrt(Y) + scale), with g and r interpolated as power laws in x between the nodes
    (exactly as :func:`segment_integrals` does, so Y at the nodes is that of
    :func:`cumulative_integral`); x(Y) inside a segment is the inverse of that power-law
    model. Second order in the spacing for smooth r, g, whatever the growth of Y.

    Parameters
    ----------
    x : array (n,)
        Grid, strictly increasing, positive.
    g : array (..., n)
        dY/dx >= 0 at the nodes.
    r : array (..., n)
        Smooth weight >= 0 at the nodes.
    F : callable
        F(Y) (vectorised), smooth in sqrt(Y) on scales >= ``scale``.
    nodes : int
        Gauss-Legendre nodes per segment.
    scale : float
        sqrt(Y) below which F is taken as slowly varying (the node mapping's offset).

    Returns
    -------
    (integral (...,), Y (..., n))
    """
    x = np.asarray(x, dtype=float)
    g = np.asarray(g, dtype=float)
    r = np.asarray(r, dtype=float)
    Y = cumulative_integral(x, g)
    xa, xb = x[:-1], x[1:]
    h = np.log(xb / xa)
    ga, gb, Ya, Yb = g[..., :-1], g[..., 1:], Y[..., :-1], Y[..., 1:]
    ra, rb = r[..., :-1], r[..., 1:]
    ta, tb = np.log(np.sqrt(Ya) + scale), np.log(np.sqrt(Yb) + scale)
    u, w = gauss_legendre(0.0, 1.0, nodes)
    t = ta[..., None] + (tb - ta)[..., None] * u
    s = np.exp(t) - scale
    s = np.maximum(s, 0.0)
    Yn = s * s
    dY_dt = 2.0 * s * (s + scale)
    dY = Yn - Ya[..., None]
    # x(Y) in the segment from the power-law model of g (trapezoid where g <= 0 at an end)
    power = (ga > 0) & (gb > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha1 = np.where(power, np.log(np.where(power, gb / np.where(power, ga, 1.0), 1.0)) / h, 0.0) + 1.0
        c = np.where(power, ga * xa, 1.0)[..., None]
        z = np.maximum(alpha1[..., None] * dY / c, -1.0 + 1e-15)
        a1 = alpha1[..., None]
        L = np.where(np.abs(a1) > 1e-12, np.log1p(z) / np.where(np.abs(a1) > 1e-12, a1, 1.0), dY / c)
        span = np.where(Yb > Ya, Yb - Ya, 1.0)[..., None]
        frac_lin = np.clip(dY / span, 0.0, 1.0)
        L = np.where(power[..., None], np.clip(L, 0.0, h[:, None]), np.log1p(frac_lin * (xb / xa - 1.0)[:, None]))
        # r at x(Y): power law in x, or linear in x where r <= 0 at an end
        rpos = (ra > 0) & (rb > 0)
        rho = np.where(rpos, np.log(np.where(rpos, rb, 1.0) / np.where(rpos, ra, 1.0)) / h, 0.0)
        frac_x = np.expm1(L) / (xb / xa - 1.0)[:, None]
        rn = np.where(rpos[..., None], ra[..., None] * np.exp(rho[..., None] * L),
                      ra[..., None] + (rb - ra)[..., None] * frac_x)
    seg = (F(Yn) * rn * dY_dt * w).sum(-1) * (tb - ta)
    seg = np.where(Yb > Ya, seg, 0.0)
    return seg.sum(-1), Y
