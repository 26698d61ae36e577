"""Preparing measured scans for spectral estimation: polynomial detrending, windows against
edge leakage, and the tip-radius reliability cutoff of scanning-probe data.

See docs/theory.md, section "Spectra", and docs/topography.md (preprocessing keys).
"""

from __future__ import annotations

import numpy as np


def _orthogonal_polynomials(n: int, degree: int) -> np.ndarray:
    """Discrete polynomials 1, t, t^2 - <t^2> (t centred), orthogonal on n uniform points; (n, degree+1)."""
    t = np.arange(n, dtype=float) - (n - 1) / 2.0
    cols = [np.ones(n), t, t * t - np.mean(t * t)][: degree + 1]
    return np.stack(cols, axis=1)


def detrend(h, degree, *, profiles=False):
    """Remove the least-squares polynomial of total degree ``degree`` from a scan.

    Degree 0 removes the mean, 1 a plane (1, x, y), 2 a curvature (1, x, y, x^2, xy, y^2).
    Uses polynomials orthogonal on the grid, so the fit is exact least squares and needs only
    one temporary map.

    Parameters
    ----------
    h : array (n,) or (nx, ny)
        Heights (m) on a uniform grid, x first.
    degree : int
        0, 1 or 2.
    profiles : bool
        Treat a map as ny line scans along x, each detrended on its own.

    Returns
    -------
    array like ``h``
        New array of heights (m).
    """
    h = np.array(h, dtype=float)
    nx = h.shape[0]
    px = _orthogonal_polynomials(nx, degree)
    norm_x = np.sum(px * px, axis=0)
    if h.ndim == 1 or profiles:
        coef = (px.T @ h.reshape(nx, -1)) / norm_x[:, None]
        h -= (px @ coef).reshape(h.shape)
        return h
    ny = h.shape[1]
    py = _orthogonal_polynomials(ny, degree)
    norm_y = np.sum(py * py, axis=0)
    terms = [(a, b) for a in range(degree + 1) for b in range(degree + 1) if a + b <= degree]
    hy = h @ py  # (nx, degree+1)
    A = np.stack([px[:, a] * (px[:, a] @ hy[:, b]) / (norm_x[a] * norm_y[b]) for a, b in terms], axis=1)
    B = np.stack([py[:, b] for a, b in terms], axis=0)
    h -= A @ B
    return h


def detrend_basis(shape, degree) -> np.ndarray:
    """Orthonormal basis of the polynomials :func:`detrend` removes from a map (total degree).

    Parameters
    ----------
    shape : (int, int)
        Grid points (nx, ny).
    degree : int
        0, 1 or 2.

    Returns
    -------
    array (p, nx, ny)
        The p = 1, 3 or 6 polynomials, orthonormal over the grid (sum of squares 1); removing
        the projection on them is :func:`detrend` with that degree.
    """
    nx, ny = shape
    px, py = _orthogonal_polynomials(nx, degree), _orthogonal_polynomials(ny, degree)
    px = px / np.sqrt(np.sum(px * px, axis=0))
    py = py / np.sqrt(np.sum(py * py, axis=0))
    return np.stack([np.outer(px[:, a], py[:, b]) for a in range(degree + 1) for b in range(degree + 1)
                     if a + b <= degree])


def hann_window_1d(n: int) -> np.ndarray:
    """Periodic Hann window along x, w_i = [1 - cos(2 pi i / n)] / 2, scaled to mean square 1.

    Returns
    -------
    array (n,)
        Dimensionless window.
    """
    w = 0.5 * (1.0 - np.cos(2.0 * np.pi * np.arange(n) / n))
    return w / np.sqrt(np.mean(w * w))


def hann_window_radial(nx: int, ny: int, sx: float, sy: float) -> np.ndarray:
    """Rotationally symmetric Hann window, scaled to mean square 1.

    .. math:: w(r) = [1 + \\cos(\\pi r / r_{max})] / 2 \\text{ for } r < r_{max} = \\min(L_x, L_y)/2

    with r measured from grid point (nx//2, ny//2); as SurfaceTopography's ``get_window_2D``.

    Parameters
    ----------
    nx, ny : int
        Grid points.
    sx, sy : float
        Physical sizes Lx, Ly (m).

    Returns
    -------
    array (nx, ny)
        Dimensionless window.
    """
    x = (np.arange(nx) - nx // 2) * (sx / nx)
    y = (np.arange(ny) - ny // 2) * (sy / ny)
    w = np.hypot(x[:, None], y[None, :])  # r, turned into the window in place (one map of memory)
    rmax = min(sx, sy) / 2.0
    outside = w >= rmax
    w *= np.pi / rmax
    np.cos(w, out=w)
    w += 1.0
    w *= 0.5
    w[outside] = 0.0
    w /= np.sqrt(np.mean(w * w))
    return w


def tip_radius_cutoff(h, sx, tip_radius, safety_factor=0.5):
    """Shortest reliable wavelength (m) of a scanning-probe measurement with tip radius R.

    A tip of radius R cannot follow valleys with curvature below -1/R. The scale-dependent
    curvature at stencil length lambda = 2 s is the second difference
    (h(x+s) - 2 h(x) + h(x-s)) / s^2 along x; the cutoff is the smallest lambda at which its
    minimum over the data is >= -f/R (f = ``safety_factor``).

    Parameters
    ----------
    h : array (nx,) or (nx, ny)
        Heights (m); mean and plane do not matter (second differences).
    sx : float
        Scan length along x (m).
    tip_radius : float
        R (m).
    safety_factor : float
        f (dimensionless), 1/2 as in Sanner et al.

    Returns
    -------
    float or None
        Cutoff wavelength (m); None when even the grid spacing satisfies the criterion.

    References
    ----------
    Sanner et al., Appl. Surf. Sci. Adv. 7, 100190 (2022).
    """
    h = h.reshape(h.shape[0], -1)
    nx = h.shape[0]
    dx = sx / nx
    target = -safety_factor / tip_radius
    steps = np.unique(np.round(np.geomspace(1, max(1, nx // 4), 60)).astype(int))
    for s in steps:
        curv = (h[2 * s:] - 2.0 * h[s:-s] + h[: -2 * s]) / (s * dx) ** 2
        if curv.size and curv.min() >= target:
            return None if s == 1 else 2.0 * s * dx
    return 2.0 * steps[-1] * dx
