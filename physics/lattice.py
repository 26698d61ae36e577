"""The Fourier lattice of a measured map or of line scans, binned in log |q|: which bin each
mode falls in, and each bin's modes and mean wavenumber. Used by the spectral estimators
(:mod:`roughcontact.physics.estimators`) and, without any heights, to know a measurement's
wavenumber range before its spectrum is computed. See docs/topography.md.
"""

from __future__ import annotations

import numpy as np

from .synthesis import half_plane_weights


def bincount(idx, weights, nbins):
    """Sums of ``weights`` (counts if None) per bin index 0 .. nbins of ``idx`` (any shape)."""
    counts = np.bincount(idx.ravel(), weights=None if weights is None else weights.ravel(), minlength=nbins + 1)
    return counts[: nbins + 1]


def area_lattice(nx, ny, sx, sy, edges, q_max):
    """The real-to-complex Fourier lattice of an nx x ny map of sx x sy (m), binned.

    Parameters
    ----------
    nx, ny : int
        Points along x and y.
    sx, sy : float
        Physical sizes (m).
    edges : array (nb + 1,)
        Bin edges (1/m); bin i+1 holds edges[i] < |q| <= edges[i+1].
    q_max : float
        Modes with |q| > q_max (1/m) are dropped (index nb + 1), as is q = 0.

    Returns
    -------
    idx : int array (nx, ny // 2 + 1)
        Bin of each mode (0 and nb + 1: outside).
    w : array (ny // 2 + 1,)
        Half-plane weights (interior columns stand for themselves and their conjugates).
    count, qsum : arrays (nb + 2,)
        Weighted modes and weighted sum of |q| (1/m) per bin index.
    """
    qx = 2.0 * np.pi * np.fft.fftfreq(nx, d=sx / nx)
    qy = 2.0 * np.pi * np.fft.rfftfreq(ny, d=sy / ny)
    w = half_plane_weights(ny)
    q = np.sqrt(qx[:, None] ** 2 + qy[None, :] ** 2)
    nb = edges.size - 1
    idx = np.searchsorted(edges, q)  # bin i+1 <-> edges[i] < q <= edges[i+1]; 0 and nb+1: outside
    idx[(q > q_max) | (q == 0.0)] = nb + 1  # dropped
    idx[idx > nb + 1] = nb + 1
    wfull = np.broadcast_to(w, q.shape)
    return idx, w, bincount(idx, wfull, nb + 1), bincount(idx, q * wfull, nb + 1)


def profile_lattice(nx, nprof, sx, edges, q_max):
    """The Fourier lattice of ``nprof`` line scans of ``nx`` points over ``sx`` (m), binned.

    Returns
    -------
    qx : array (nx // 2 + 1,)
        Wavenumbers (1/m).
    idx : int array
        Bin of each wavenumber (0 and nb + 1: outside; q = 0 and q > q_max dropped).
    count, qsum : arrays (nb + 2,)
        Modes (one per wavenumber per profile) and summed q (1/m) per bin index.
    """
    qx = 2.0 * np.pi * np.fft.rfftfreq(nx, d=sx / nx)
    nb = edges.size - 1
    idx = np.searchsorted(edges, qx)
    idx[(qx > q_max) | (qx == 0.0)] = nb + 1
    idx[idx > nb + 1] = nb + 1
    count = np.bincount(idx, minlength=nb + 2)[: nb + 2] * float(nprof)
    return qx, idx, count, np.bincount(idx, weights=qx * nprof, minlength=nb + 2)[: nb + 2]


def binned_wavenumbers(shape, sizes, edges, q_max, profiles=False):
    """The bins' independent modes and mean wavenumber of a map or of line scans, without heights.

    Exactly the ``n`` and ``q`` that :func:`roughcontact.physics.estimators.binned_spectra_area`
    (or ``binned_spectra_profiles`` when ``profiles``) give for data of this ``shape`` and
    physical ``sizes`` (m), with no FFT: the measured wavenumber range is known before the
    spectrum is computed.

    Returns
    -------
    n, q : arrays (nb,)
        Independent modes per bin, and their mean |q| (1/m; NaN where a bin is empty).
    """
    nb = edges.size - 1
    if profiles:
        _, _, count, qsum = profile_lattice(shape[0], int(np.prod(shape[1:])), sizes[0], edges, q_max)
        n = count[1:nb + 1]
    else:
        _, _, count, qsum = area_lattice(shape[0], shape[1], sizes[0], sizes[1], edges, q_max)
        n = count[1:nb + 1] / 2.0
    with np.errstate(invalid="ignore", divide="ignore"):
        return n, np.where(count[1:nb + 1] > 0, qsum[1:nb + 1] / count[1:nb + 1], np.nan)
