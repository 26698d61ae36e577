"""Independent Fourier modes of windowed scans.

A window (against edge leakage of non-periodic scans) correlates neighbouring Fourier modes,
so the C / sqrt(n) error of a bin of n independent modes is too small. These kernels give, per
logarithmic bin, the factor by which a window divides n: exactly (pairs of modes in a bin and
their squared correlation) where bins are thin, the wide-bin limit N sum(w^4) / (sum w^2)^2
(4 for a radial Hann window, 35/18 for a 1D Hann) where they are wide. See
docs/measured-data.md and :mod:`roughcontact.physics.uncertainty`.
"""

from __future__ import annotations

import numpy as np


def window_lags(w, threshold=1e-4, max_lag=6):
    """Squared correlations between the periodogram values of modes ``delta`` apart.

    For a window w, the Fourier coefficients of w h are correlated with
    rho(delta) = DFT(w^2)(delta) / sum(w^2); the powers of two modes of a Gaussian surface are
    correlated with |rho|^2 (Isserlis). Their sum over all lags is
    F = N sum(w^4) / (sum w^2)^2 (Parseval), the variance factor of a wide bin.

    Parameters
    ----------
    w : array (nx,) or (nx, ny)
        The window (dimensionless).
    threshold : float
        Lags with |rho|^2 below this are left out.
    max_lag : int
        Largest lag (lattice steps per axis) considered; a smooth window's correlations
        decay within a few steps (Hann: |rho(1)|^2 = 4/9, |rho(2)|^2 = 1/36, then 0 in 1D).

    Returns
    -------
    lags : int array (m, w.ndim)
        Index offsets, zero lag excluded.
    rho2 : array (m,)
        |rho(delta)|^2.
    F : float
        N sum(w^4) / (sum w^2)^2 (1 for no window; 35/18 for a 1D Hann, about 4 for a radial Hann).
    """
    w2 = np.asarray(w, dtype=float) ** 2
    d = np.arange(-max_lag, max_lag + 1)
    rho = w2
    for axis, n in enumerate(w2.shape):  # DFT at the small lags only, one axis at a time
        k = min(max_lag, n // 2)
        phase = 2.0 * np.pi * np.outer(np.arange(n), d[max_lag - k:max_lag + k + 1]) / n
        rho = np.moveaxis(np.tensordot(np.moveaxis(rho, axis, -1), np.cos(phase) - 1j * np.sin(phase), axes=1),
                          -1, axis)
    rho2 = np.abs(rho) ** 2 / np.sum(w2) ** 2
    index = np.argwhere(rho2 > threshold)
    lags = index - np.array([min(max_lag, n // 2) for n in w2.shape])
    keep = np.any(lags != 0, axis=1)
    F = float(w2.size * np.sum(w2 * w2) / np.sum(w2) ** 2)
    return lags[keep], rho2[tuple(index[keep].T)], F


def _bin_index(q, edges, q_max):
    """Bin of each wavenumber (0-based), -1 where dropped (outside the edges, q = 0, q > q_max)."""
    nb = edges.size - 1
    b = np.searchsorted(edges, q) - 1
    b[(q > q_max) | (q == 0.0) | (b < 0) | (b >= nb)] = -1
    return b


def window_pair_sums_area(nx, ny, sx, sy, edges, q_max, w, box=192):
    """Per pair of bins (b, b'), the sum over their modes of the squared correlations the window gives.

    S_bb' = sum over modes i of bin b and j of bin b' (full Fourier plane) of |rho(q_i - q_j)|^2
    (:func:`window_lags`; |rho(0)|^2 = 1). For a Gaussian surface whose spectrum is smooth on the
    scale of the window's kernel, the binned means of the periodogram C_b (m_b modes) have
    relative covariance cov(C_b, C_b') / (C_b C_b') = 2 S_bb' / (m_b m_b'). S is summed exactly over
    the whole Fourier plane (lags wrapping around) for maps of up to 2 ``box`` points a side; for
    larger maps over the modes within ``box`` lattice steps of the origin (the thin low-q bins, where
    it matters), and a bin reaching beyond is flagged not ``exact``.

    Parameters
    ----------
    nx, ny, sx, sy, edges, q_max, w, box
        As :func:`window_mode_factor_area`.

    Returns
    -------
    S : array (nb, nb)
        The pair sums (dimensionless, symmetric).
    m : array (nb,)
        Modes of each bin in the full Fourier plane (within the box for large maps).
    exact : bool array (nb,)
        Whether bin b lies within the exactly summed region.
    F : float
        The wide-bin factor of :func:`window_lags`.
    """
    lags, rho2, F = window_lags(w)
    reach = int(np.abs(lags).max()) if lags.size else 0
    whole = nx <= 2 * box and ny <= 2 * box  # the whole Fourier plane, lags wrapping around
    if whole:
        ix, iy = np.fft.fftfreq(nx, 1.0 / nx), np.fft.fftfreq(ny, 1.0 / ny)
    else:
        bx, by = min(box, nx // 2 - 1), min(box, ny // 2 - 1)
        ix, iy = np.arange(-bx, bx + 1), np.arange(-by, by + 1)
    b = _bin_index(2.0 * np.pi * np.hypot(ix[:, None] / sx, iy[None, :] / sy), edges, q_max)
    nb = edges.size - 1
    m = np.bincount(b[b >= 0], minlength=nb).astype(float)
    S = np.diag(m)
    for (dx, dy), r2 in zip(lags, rho2, strict=True):
        if whole:
            a, c = b, np.roll(b, (-dx, -dy), axis=(0, 1))
        else:
            a = b[max(0, -dx):b.shape[0] - max(0, dx), max(0, -dy):b.shape[1] - max(0, dy)]
            c = b[max(0, dx):b.shape[0] - max(0, -dx), max(0, dy):b.shape[1] - max(0, -dy)]
        both = (a >= 0) & (c >= 0)
        S += r2 * np.bincount(a[both] * nb + c[both], minlength=nb * nb).reshape(nb, nb)
    inner = np.inf if whole else 2.0 * np.pi * min((bx - reach) / sx, (by - reach) / sy)
    exact = (np.minimum(edges[1:], q_max) <= inner) | (edges[:-1] >= q_max)
    return S, m, exact, F


def window_mode_factor_area(nx, ny, sx, sy, edges, q_max, w, box=192, neighbours=False):
    """Per bin, the factor by which a window divides the independent modes of a map.

    Var(bin mean) = 2 S C^2 / m^2 with m the bin's modes in the full Fourier plane and
    S = sum over pairs (i, j) of the bin of |rho(q_i - q_j)|^2 (:func:`window_pair_sums_area`,
    S_bb), so n_eff = m^2 / (2 S) and the factor n / n_eff = 2 n S / m^2 with n = m / 2. A bin
    beyond the exactly summed region gets the wide-bin factor F of :func:`window_lags`.

    Parameters
    ----------
    nx, ny : int
        Grid points.
    sx, sy : float
        Physical sizes (m).
    edges : array
        Bin edges (1/m).
    q_max : float
        Highest wavenumber used (1/m).
    w : array (nx, ny)
        The window applied to the heights.
    box : int
        Half-width (lattice steps) of the exactly summed region.
    neighbours : bool
        Count each mode's correlations with the modes of every bin, not only its own (the row
        sum of S): an upper bound of the variance a bin contributes to a sum over bins, exact
        only where that sum weighs correlated modes alike.

    Returns
    -------
    array (len(edges) - 1,)
        Factor >= 1 (1 where a bin has no modes).
    """
    S, m, exact, F = window_pair_sums_area(nx, ny, sx, sy, edges, q_max, w, box)
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(m > 0, (S.sum(axis=1) if neighbours else np.diag(S)) / m, 1.0)
    return np.maximum(np.where(exact, factor, F), 1.0)


def window_mode_factor_profiles(nx, sx, edges, q_max, w):
    """Per bin, the factor by which a window along x divides the independent modes of each
    line scan: n_eff = n^2 / S, S = sum over mode pairs (i, j > 0) of the bin of
    |rho(i - j)|^2 + |rho(i + j)|^2 (see :func:`window_mode_factor_area`).

    Parameters
    ----------
    nx : int
        Points per profile.
    sx : float
        Scan length (m).
    edges : array
        Bin edges (1/m).
    q_max : float
        Highest wavenumber used (1/m).
    w : array (nx,)
        The window.

    Returns
    -------
    array (len(edges) - 1,)
        Factor >= 1 (1 where a bin has no modes).
    """
    w2 = np.asarray(w, dtype=float) ** 2
    rho2 = np.abs(np.fft.fft(w2)) ** 2
    rho2 /= rho2[0]
    top = nx // 2
    index = np.arange(1, top + 1)
    b = _bin_index(2.0 * np.pi * index / sx, edges, q_max)
    nb = edges.size - 1
    n = np.bincount(b[b >= 0], minlength=nb).astype(float)
    S = np.zeros(nb)
    signed = np.flatnonzero(rho2 > 1e-6)
    signed = np.where(signed > top, signed - nx, signed)
    for lag in signed:
        for j in (index + lag, lag - index, lag + nx - index):  # rho(i - j) and rho(i + j), j in 1..nx/2
            ok = (j >= 1) & (j <= top)
            same = np.zeros_like(ok)
            same[ok] = (b[ok] == b[j[ok] - 1]) & (b[ok] >= 0)
            S += rho2[lag % nx] * np.bincount(b[same], minlength=nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.maximum(np.where(n > 0, S / n, 1.0), 1.0)
