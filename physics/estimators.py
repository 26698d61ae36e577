"""Spectral estimators on measured (or synthesized) height maps and line scans.

* 2D maps: C(q) = (2 pi)^-2 \\int d^2x <h(x) h(0)> exp(-i q.x) (Persson, seed eq 4) is
  estimated as the radial average of (dx dy)^2 |DFT h|^2 / ((2 pi)^2 Lx Ly) over the Fourier
  modes in log-spaced bins of |q|. Discretely, sum_q C(q) (2 pi)^2 / (Lx Ly) = <h^2> (Parseval).
* Line scans: C1D(q) = (dx^2 / L) |DFT h|^2 (hrms^2 = (1/pi) \\int_0^inf C1D dq), converted to
  the isotropic 2D PSD with C(q) = c(H) C1D(q) / q
  (:func:`roughcontact.physics.spectra.isotropic_factor`).
* Pairs h1, h2 on the same grid: the cross-spectrum C12 (radial average of Re h1(q) h2(q)*,
  same normalisation) and the coherence eta(q) = C12 / sqrt(C11 C22) (seed eq 41).
* Periodic square maps: the binned coherence of a pair and the rms slope (the BEM check).

The scans are prepared (detrended, windowed) by :mod:`roughcontact.physics.preprocessing`.
See docs/theory.md, section "Spectra", and docs/topography.md (estimators, errors, tests).
"""

from __future__ import annotations

import math

import numpy as np

from .lattice import area_lattice, bincount, profile_lattice
from .spectra import extend_psd, isotropic_factor
from .synthesis import half_plane_weights, lattice_wavenumbers

# ----------------------------------------------------------------------------------------
# Spectra on log bins
# ----------------------------------------------------------------------------------------


def log_bin_edges(q_lo: float, q_hi: float, bins_per_decade: int) -> np.ndarray:
    """Edges 10^(k / bins_per_decade) (1/m) of the fixed logarithmic bins covering [q_lo, q_hi].

    Bin i holds edges[i-1] < |q| <= edges[i]. The lattice does not depend on the data, so
    spectra of several files share bins.

    Parameters
    ----------
    q_lo, q_hi : float
        Range to cover (1/m).
    bins_per_decade : int
        Bins per factor 10 in q.

    Returns
    -------
    array
        Edges (1/m), increasing.
    """
    k0 = math.floor(bins_per_decade * math.log10(q_lo)) - 1
    k1 = math.ceil(bins_per_decade * math.log10(q_hi)) + 1
    return 10.0 ** (np.arange(k0, k1 + 1) / bins_per_decade)


def psd_map(h, sx, sy):
    """Full 2D PSD of a map in Persson's convention (m^4), in ``numpy.fft.fft2`` layout.

    .. math:: C(\\mathbf{q}) = \\frac{(dx\\,dy)^2 |\\mathrm{DFT}\\,h|^2}{(2\\pi)^2 L_x L_y},
              \\quad \\sum_q C \\frac{(2\\pi)^2}{L_x L_y} = \\langle h^2 \\rangle

    Parameters
    ----------
    h : array (nx, ny)
        Heights (m).
    sx, sy : float
        Physical sizes Lx, Ly (m).

    References
    ----------
    Seed eq 4; docs/theory.md, section "Spectra".
    """
    nx, ny = h.shape
    area_per_pt = (sx / nx) * (sy / ny)
    return area_per_pt**2 * np.abs(np.fft.fft2(h)) ** 2 / ((2.0 * np.pi) ** 2 * sx * sy)


def binned_spectra_area(h1, sx, sy, edges, q_max, h2=None):
    """Radially binned 2D spectra of a map (and of a second map on the same grid).

    The mean over the Fourier modes in each bin of :func:`psd_map` (and of the
    cross-spectrum Re H1 H2*, same normalisation), seed eqs 4 and 41.

    Parameters
    ----------
    h1, h2 : array (nx, ny)
        Prepared (detrended, windowed) heights (m); ``h2`` optional.
    sx, sy : float
        Physical sizes (m).
    edges : array
        Bin edges (1/m), see :func:`log_bin_edges`.
    q_max : float
        Modes with |q| > q_max (1/m; Nyquist or reliability cutoff) are left out.

    Returns
    -------
    dict of arrays over the bins (len(edges) - 1)
        ``n`` independent Fourier modes (a mode and its conjugate count once), ``q`` the mean
        |q| of the modes (1/m), ``C11`` (and ``C22``, ``C12`` = Re cross-spectrum) the mean
        PSD in Persson's convention (m^4); NaN where a bin holds no mode.

    Notes
    -----
    Real-to-complex FFT over y; interior columns stand for themselves and their conjugates
    (weight 2), so averages equal those over the full Fourier plane. Peak memory: the input
    plus about three map-sizes of temporaries.
    """
    nx, ny = h1.shape
    norm = ((sx / nx) * (sy / ny)) ** 2 / ((2.0 * np.pi) ** 2 * sx * sy)
    nb = edges.size - 1
    idx, w, count, qsum = area_lattice(nx, ny, sx, sy, edges, q_max)
    import scipy.fft  # imported when a map is analysed, not with the stage declarations

    out = {}
    H1 = scipy.fft.rfft2(h1)
    P = H1.real**2 + H1.imag**2
    P *= w
    out["C11"] = bincount(idx, P, nb + 1)
    if h2 is not None:
        H2 = scipy.fft.rfft2(h2)
        np.multiply(H2.real, H2.real, out=P)
        P += H2.imag**2
        P *= w
        out["C22"] = bincount(idx, P, nb + 1)
        np.multiply(H1.real, H2.real, out=P)
        P += H1.imag * H2.imag
        P *= w
        out["C12"] = bincount(idx, P, nb + 1)
        del H2
    del H1, P, idx
    sl = slice(1, nb + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        res = {k: np.where(count[sl] > 0, v[sl] * norm / count[sl], np.nan) for k, v in out.items()}
        res["q"] = np.where(count[sl] > 0, qsum[sl] / count[sl], np.nan)
    res["n"] = count[sl] / 2.0
    return res


def binned_spectra_profiles(h1, sx, edges, q_max, hurst, h2=None):
    """Binned isotropic PSD from line scans along x.

    The 1D PSD C1D = (dx^2/L) |DFT h|^2 per mode and profile is converted by
    C = c(H) C1D / q (:func:`roughcontact.physics.spectra.isotropic_factor`) and averaged over
    profiles and bins.

    Parameters
    ----------
    h1, h2 : array (nx,) or (nx, n_profiles)
        Prepared (detrended, windowed) heights (m); ``h2`` optional.
    sx : float
        Scan length along x (m).
    edges : array
        Bin edges (1/m).
    q_max : float
        Highest wavenumber used (1/m).
    hurst : float
        H of the conversion (dimensionless), exact for an isotropic self-affine surface.

    Returns
    -------
    dict
        As :func:`binned_spectra_area`; ``n`` counts one independent mode per positive
        wavenumber per profile (profiles are taken as independent).
    """
    h1 = h1.reshape(h1.shape[0], -1)
    nx, nprof = h1.shape
    norm = (sx / nx) ** 2 / sx
    nb = edges.size - 1
    qx, idx, count, qsum = profile_lattice(nx, nprof, sx, edges, q_max)
    conv = np.zeros_like(qx)
    conv[qx > 0] = isotropic_factor(hurst) / qx[qx > 0]
    import scipy.fft  # imported when a profile is analysed, not with the stage declarations

    H1 = scipy.fft.rfft(h1, axis=0)
    out = {"C11": (np.abs(H1) ** 2).sum(axis=1)}
    if h2 is not None:
        H2 = scipy.fft.rfft(h2.reshape(nx, -1), axis=0)
        out["C22"] = (np.abs(H2) ** 2).sum(axis=1)
        out["C12"] = (H1.real * H2.real + H1.imag * H2.imag).sum(axis=1)
    sl = slice(1, nb + 1)
    res = {}
    with np.errstate(invalid="ignore", divide="ignore"):
        for k, v in out.items():
            s = np.bincount(idx, weights=v * conv * norm, minlength=nb + 2)[: nb + 2]
            res[k] = np.where(count[sl] > 0, s[sl] / count[sl], np.nan)
        res["q"] = np.where(count[sl] > 0, qsum[sl] / count[sl], np.nan)
    res["n"] = count[sl]
    return res


# ----------------------------------------------------------------------------------------
# The bias of detrended, windowed crops
# ----------------------------------------------------------------------------------------


def expected_processed_psd_area(psd, nx, ny, sx, sy, window=None, basis=None, periodic=False):
    """Expected periodogram of a detrended, windowed map of a Gaussian random surface with PSD ``psd``.

    The prepared map is g = w (h - P h) (P: least-squares projection on the detrended
    polynomials, w: the window); its expected :func:`psd_map` at the map's Fourier modes k is

    E|DFT g|_k^2 = F Sigma F^H - 2 Re sum_j a_j c_j^* + sum_ij a_i M_ij a_j^*,

    F = e^{-ikx} w(x), Sigma the covariance R(x - x') of the heights, a_j = DFT(w b_j),
    c_j = DFT(w Sigma b_j), M = b^T Sigma b over the orthonormal polynomials b_j. The first
    term is the PSD convolved with the window's |DFT|^2, sum over lags of R(tau) A_w(tau)
    e^{-ik tau} with A_w the window's autocorrelation. R is the inverse transform of the PSD
    on the lattice of a periodic cell twice the map's size (a crop of a larger surface), or of
    the map itself (``periodic``; then without a window and polynomial it is the PSD).

    Parameters
    ----------
    psd : callable
        C(q) (m^4) of |q| (1/m), finite at q = 0 (the model of the surface's spectrum).
    nx, ny : int
        Grid points.
    sx, sy : float
        Physical sizes (m).
    window : array (nx, ny) or None
        The window the map was multiplied with (dimensionless).
    basis : array (p, nx, ny) or None
        Orthonormal polynomials removed before the window
        (:func:`roughcontact.physics.preprocessing.detrend_basis`).
    periodic : bool
        The map is one period of a periodic surface.

    Returns
    -------
    array (nx, ny // 2 + 1)
        E[psd_map(g)] (m^4) on the real-to-complex lattice of :func:`binned_spectra_area`.

    References
    ----------
    Percival & Walden, Spectral Analysis for Physical Applications (1993), ch. 6 (expected
    periodogram of a tapered series); docs/theory.md, section "Spectra".
    """
    m = 1 if periodic else 2
    qx = 2.0 * np.pi * np.fft.fftfreq(m * nx, d=sx / nx)
    qy = 2.0 * np.pi * np.fft.fftfreq(m * ny, d=sy / ny)
    cell = np.fft.ifft2(psd(np.hypot(qx[:, None], qy[None, :]))).real
    cell *= (m * nx) * (m * ny) * (2.0 * np.pi) ** 2 / (m * sx * m * sy)  # R(x) = sum_q C dq^2 e^{iqx}
    lags = (np.r_[0:nx, -nx:0] % (m * nx), np.r_[0:ny, -ny:0] % (m * ny))
    R = cell[np.ix_(*lags)]  # covariance at lags -n .. n-1 (wrapped) on a 2nx x 2ny grid
    w = np.ones((nx, ny)) if window is None else np.asarray(window, dtype=float)
    A = np.fft.ifft2(np.abs(np.fft.fft2(w, s=(2 * nx, 2 * ny))) ** 2).real
    E = np.fft.fft2(R * A)[::2, ::2][:, : ny // 2 + 1].real
    if basis is not None:
        FR = np.fft.fft2(R)
        V = [np.fft.ifft2(FR * np.fft.fft2(b, s=(2 * nx, 2 * ny))).real[:nx, :ny] for b in basis]
        a = [np.fft.rfft2(w * b) for b in basis]
        c = [np.fft.rfft2(w * v) for v in V]
        for i in range(len(basis)):
            E -= 2.0 * (a[i] * c[i].conj()).real
            for j in range(len(basis)):
                E += np.sum(basis[i] * V[j]) * (a[i] * a[j].conj()).real
    return E * ((sx / nx) * (sy / ny)) ** 2 / ((2.0 * np.pi) ** 2 * sx * sy)


def _height_covariance_lags(psd, nx, ny, sx, sy, periodic):
    """Covariance R(x - x') (m^2) of the heights at lags -n .. n-1 (wrapped on a 2nx x 2ny grid), the
    inverse transform of the PSD on the lattice of a cell twice the map (once, ``periodic``)."""
    m = 1 if periodic else 2
    qx = 2.0 * np.pi * np.fft.fftfreq(m * nx, d=sx / nx)
    qy = 2.0 * np.pi * np.fft.fftfreq(m * ny, d=sy / ny)
    cell = np.fft.ifft2(psd(np.hypot(qx[:, None], qy[None, :]))).real
    cell *= (m * nx) * (m * ny) * (2.0 * np.pi) ** 2 / (m * sx * m * sy)  # R(x) = sum_q C dq^2 e^{iqx}
    lags = (np.r_[0:nx, -nx:0] % (m * nx), np.r_[0:ny, -ny:0] % (m * ny))
    return cell[np.ix_(*lags)]


def processed_bin_covariance_area(psd, nx, ny, sx, sy, edges, q_max, window=None, basis=None, periodic=False,
                                  steps=4.0):
    """Relative covariance of the binned periodogram of a detrended, windowed map, exactly, in its lowest bins.

    With g = w (h - P h) (:func:`expected_processed_psd_area`) and Z_k = DFT(g)_k, the powers of a
    Gaussian surface have cov(|Z_i|^2, |Z_j|^2) = |E Z_i Z_j*|^2 + |E Z_i Z_j|^2 (Isserlis), with

    E Z_i Z_j* = DFT(w (I - P) R (I - P) (w e^{+i q_j x}))_i,

    R the covariance of the heights (a convolution, by FFT). For bins b, b' symmetric under
    q -> -q, the relative covariance of the bin means C_b (the modes of the full Fourier plane) is

    cov(C_b, C_b') / (E C_b E C_b') = 2 sum_{i in b, j in b'} |E Z_i Z_j*|^2 / (P_b P_b'),
    P_b = sum_{i in b} E|Z_i|^2.

    Unlike the flat-spectrum correlation of :func:`roughcontact.physics.modes.window_pair_sums_area`,
    it holds where the spectrum changes over the window's kernel (a roll-off a few lattice steps
    from q = 0) and counts what the removed polynomial does to the lowest modes. Computed for the
    modes within ``steps`` lattice steps of q = 0 (one convolution per mode).

    Parameters
    ----------
    psd : callable
        Model C(q) (m^4) of |q| (1/m), finite at q = 0.
    nx, ny, sx, sy, window, basis, periodic
        As :func:`expected_processed_psd_area`.
    edges : array
        Bin edges (1/m).
    q_max : float
        Highest wavenumber binned (1/m).
    steps : float
        Radius of the exactly computed region in lattice steps 2 pi / max(sx, sy).

    Returns
    -------
    K : array (nb, nb)
        Relative covariance (dimensionless) between the bins that lie wholly within the region;
        NaN elsewhere.
    inside : bool array (nb,)
        The bins it covers (holding modes).
    """
    nb = edges.size - 1
    ix, iy = np.fft.fftfreq(nx, 1.0 / nx).astype(int), np.fft.fftfreq(ny, 1.0 / ny).astype(int)
    qq = 2.0 * np.pi * np.hypot(ix[:, None] / sx, iy[None, :] / sy)
    reach = min(steps * 2.0 * np.pi / max(sx, sy), q_max)
    b = np.searchsorted(edges, qq) - 1
    inside_bins = (edges[1:] <= reach) & (np.bincount(b[(qq > 0) & (qq <= reach) & (b >= 0) & (b < nb)],
                                                       minlength=nb)[:nb] > 0)
    sel = (qq > 0) & (b >= 0) & (b < nb)
    sel &= inside_bins[np.clip(b, 0, nb - 1)]
    modes = np.argwhere(sel)  # (k, 2) lattice indices (a, c) into the fft2 layout
    K = np.full((nb, nb), np.nan)
    if modes.size == 0:
        return K, inside_bins
    w = np.ones((nx, ny)) if window is None else np.asarray(window, dtype=float)
    FR = np.fft.fft2(_height_covariance_lags(psd, nx, ny, sx, sy, periodic))
    ax, ay = np.arange(nx)[:, None], np.arange(ny)[None, :]
    B = None if basis is None else np.asarray(basis, dtype=float).reshape(len(basis), -1)

    def project_out(f):
        if B is None:
            return f
        flat = f.reshape(-1)
        return (flat - B.T @ (B @ flat)).reshape(f.shape)

    Sigma = np.zeros((len(modes), len(modes)), dtype=complex)
    for k, (a, c) in enumerate(modes):
        u = project_out(w * np.exp(2j * np.pi * (ix[a] * ax / nx + iy[c] * ay / ny)))
        v = np.fft.ifft2(FR * np.fft.fft2(u, s=(2 * nx, 2 * ny)))[:nx, :ny]
        Sigma[:, k] = np.fft.fft2(w * project_out(v))[modes[:, 0], modes[:, 1]]
    mode_bin = b[modes[:, 0], modes[:, 1]]
    power = np.bincount(mode_bin, weights=Sigma.diagonal().real, minlength=nb)[:nb]
    pair = np.abs(Sigma) ** 2
    onehot = (mode_bin[:, None] == np.arange(nb)[None, :]).astype(float)
    S = onehot.T @ pair @ onehot
    ok = np.flatnonzero(inside_bins)
    K[np.ix_(ok, ok)] = 2.0 * S[np.ix_(ok, ok)] / np.outer(power[ok], power[ok])
    return K, inside_bins


def rolloff_fit(q, C, n):
    """Least-squares fit of C = C0 (1 + (q/q0)^2)^(-a/2) to binned PSDs, in log C with weights n.

    A smooth model of a measured spectrum (flat below q0, power law q^-a above; a = 2 + 2H
    for a self-affine surface) for corrections that need its shape but must not follow the
    noise of few-mode bins.

    Parameters
    ----------
    q, C, n : arrays over the bins
        Mean wavenumbers (1/m), PSD (m^4) and independent modes (weights) of valid bins.

    Returns
    -------
    callable
        C(q) (m^4) of |q| (1/m), finite at q = 0.
    """
    from scipy.optimize import least_squares  # imported when a map is corrected, not with the stage declarations

    x, y, sw = np.log(q / q[0]), np.log(C), np.sqrt(n)

    def residual(theta):
        return sw * (theta[0] - theta[2] * np.maximum(x - theta[1], 0.0) - y)

    a0 = -np.polyfit(x, y, 1, w=sw)[0]
    start = [float(np.average(y[: max(2, y.size // 8)])), float(np.clip(x[min(2, x.size - 1)], -2.0, x[-1])),
             float(np.clip(a0, 0.5, 7.5))]
    theta = least_squares(residual, start, bounds=([-np.inf, -3.0, 0.0], [np.inf, x[-1] + 1.0, 8.0])).x
    q0 = q[0] * np.exp(theta[1])

    def psd(k):
        return np.exp(theta[0]) * np.maximum(np.asarray(k) / q0, 1.0) ** (-theta[2])

    return psd


#: lattice steps 2 pi / L above which bins enter the model of the spectrum (below, their own noise would be corrected)
FIT_FROM = 2.0


def processing_bias_area(q, C, n, nx, ny, sx, sy, edges, q_max, window=None, basis=None, periodic=False,
                         iterations=2, model=False):
    """Per bin, the factor by which detrending and a window bias the binned PSD of a map.

    r_b = <E psd_map(g)>_b / <C>_b, the bin means over the modes of :func:`binned_spectra_area`
    of :func:`expected_processed_psd_area` and of the spectrum itself. The spectrum is not
    known; it is modelled by a smooth fit to the measured bins (:func:`rolloff_fit`; through
    the bins themselves the correction would follow their noise and over-correct few-mode
    bins) and iterated: the model of step i + 1 is fitted to C_meas / r_i.
    Below 1 where the removed polynomial takes the longest waves' power, above 1 where the
    window's kernel (about 2 pi / L wide) smooths a convex spectrum (at k lattice steps from
    q = 0, about 1 + a^2 / (6 k^2) for C ~ q^-a).

    Parameters
    ----------
    q, C, n : arrays over the bins
        Mean wavenumbers (1/m), binned PSD (m^4) of the prepared map (NaN: empty bin) and
        its modes (the fit's weights).
    nx, ny, sx, sy, window, basis, periodic
        As :func:`expected_processed_psd_area`.
    edges : array
        Bin edges (1/m).
    q_max : float
        Highest wavenumber binned (1/m).
    iterations : int
        Fixed-point iterations of the model.

    model : bool
        Return the model spectrum too.

    Returns
    -------
    array over the bins
        r (dimensionless; 1 in empty bins): divide the binned PSD by it; with ``model``, the pair
        (r, the last model C(q) of |q|, m^4; None with fewer than two valid bins).
    """
    nb = edges.size - 1
    idx, wcol, count, _ = area_lattice(nx, ny, sx, sy, edges, q_max)
    qk = np.hypot(2.0 * np.pi * np.fft.fftfreq(nx, d=sx / nx)[:, None],
                  2.0 * np.pi * np.fft.rfftfreq(ny, d=sy / ny)[None, :])
    ok = np.isfinite(C) & (C > 0) & np.isfinite(q)
    r, psd = np.ones(nb), None
    if np.count_nonzero(ok) < 2:
        return (r, psd) if model else r
    sl = slice(1, nb + 1)
    for _ in range(iterations):
        fit = ok & (q >= FIT_FROM * 2.0 * np.pi / max(sx, sy))
        fit = fit if np.count_nonzero(fit) >= 3 else ok
        psd = rolloff_fit(q[fit], C[fit] / r[fit], n[fit])
        E = expected_processed_psd_area(psd, nx, ny, sx, sy, window, basis, periodic)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.where(count[sl] > 0, bincount(idx, E * wcol, nb + 1)[sl] / bincount(idx, psd(qk) * wcol, nb + 1)[sl],
                         1.0)
    return (r, psd) if model else r


def second_surface_hurst(spectra, hurst1, hurst2):
    """Paired line-scan spectra converted with H1 (:func:`binned_spectra_profiles`), with the
    second surface's PSD C22 rescaled to its own H2: C22 c(H2)/c(H1), C12 sqrt(c(H2)/c(H1)).

    The coherence C12 / sqrt(C11 C22) (seed eq 41) is unchanged by the conversion.

    Returns
    -------
    dict
        A new dict of the bins' arrays (m^4 for the spectra).
    """
    ratio = float(isotropic_factor(hurst2) / isotropic_factor(hurst1))
    return dict(spectra, C22=spectra["C22"] * ratio, C12=spectra["C12"] * math.sqrt(ratio))


def merge_spectra(spectra, key="C11"):
    """Merge binned spectra of several files of one surface (e.g. several magnifications).

    In each bin the files that have modes there are averaged with weights n (their numbers of
    independent modes: the inverse-variance weights for equal true PSDs). The standard error
    is C / sqrt(n) (Gaussian random-phase statistics: each mode's power is exponentially
    distributed, standard deviation = mean).

    Parameters
    ----------
    spectra : list of dict
        Outputs of :func:`binned_spectra_area` / :func:`binned_spectra_profiles` on one bin lattice.
    key : str
        Which spectrum to merge.

    Returns
    -------
    q, C, n, err : arrays over the bins
        Mean |q| (1/m), PSD (m^4), independent modes, standard error (m^4); NaN where empty.
    """
    n = np.stack([s["n"] for s in spectra])
    has = n > 0
    C = np.where(has, np.stack([s[key] for s in spectra]), 0.0)
    q = np.where(has, np.stack([s["q"] for s in spectra]), 0.0)
    ntot = n.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        Cm = np.where(ntot > 0, (n * C).sum(axis=0) / ntot, np.nan)
        qm = np.where(ntot > 0, (n * q).sum(axis=0) / ntot, np.nan)
        err = Cm / np.sqrt(ntot)
    return qm, Cm, ntot, err


def coherence(C11, C22, C12, n):
    """Coherence eta(q) = Re C12 / sqrt(C11 C22) (seed eq 41) and its standard error.

    For n independent complex Gaussian mode pairs with real coherency eta, each mode gives
    two real sample pairs with correlation eta, so the estimator's standard error is
    (1 - eta^2) / sqrt(2 n) (Fisher's large-sample variance of a correlation coefficient).

    Parameters
    ----------
    C11, C22, C12 : arrays
        Spectra of the two surfaces and their cross-spectrum (m^4).
    n : array
        Independent modes.

    Returns
    -------
    eta, err : arrays
        Dimensionless, eta in [-1, 1]; NaN where C11 or C22 is 0 (a flat surface has no coherence).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        eta = C12 / np.sqrt(C11 * C22)
        eta = np.clip(eta, -1.0, 1.0)
        err = (1.0 - eta * eta) / np.sqrt(2.0 * n)
    return eta, err


def pooled_coherence(pairs):
    """Cross-spectrum and coherence pooled over several file pairs on one bin lattice.

    The spectra C11, C22, C12 of the pairs are averaged per bin with weights n (independent
    modes), then eta = C12 / sqrt(C11 C22) (seed eq 41, :func:`coherence`).

    Parameters
    ----------
    pairs : list of dict
        Outputs of :func:`binned_spectra_area` / :func:`binned_spectra_profiles` with ``h2``.

    Returns
    -------
    C12, eta, err : arrays over the bins
        Mean cross-spectrum (m^4), coherence and its standard error (dimensionless); NaN
        where no pair has modes.
    """
    n = np.stack([s["n"] for s in pairs])
    has = n > 0
    sums = {k: np.where(has, n * np.stack([np.nan_to_num(s[k]) for s in pairs]), 0.0).sum(axis=0)
            for k in ("C11", "C22", "C12")}
    ntot = n.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        C12 = np.where(ntot > 0, sums["C12"] / ntot, np.nan)
    eta, err = coherence(sums["C11"], sums["C22"], sums["C12"], ntot)
    return C12, np.where(ntot > 0, eta, np.nan), np.where(ntot > 0, err, np.nan)


# ----------------------------------------------------------------------------------------
# Binned spectra onto a wavenumber grid
# ----------------------------------------------------------------------------------------


def valid_bins(q, values, positive=False):
    """The bins with finite q and value (and value > 0 if ``positive``), sorted by q.

    Returns
    -------
    q, values : arrays
        Wavenumbers (1/m) increasing, and the values in their units.
    """
    ok = np.isfinite(q) & np.isfinite(values)
    if positive:
        ok &= values > 0
    q, values = q[ok], values[ok]
    order = np.argsort(q)
    return q[order], values[order]


def _power_law_tail(q_grid, q, C, base, other):
    """C continued beyond node ``base`` as the power law through nodes ``base`` and ``other``."""
    slope = np.log(C[other] / C[base]) / np.log(q[other] / q[base])
    return C[base] * (q_grid / q[base]) ** slope


def binned_psd_on_grid(q_grid, q, C, how):
    """A binned PSD (valid bins, q increasing) on the wavenumber grid ``q_grid`` (m^4).

    Log-log linear interpolation between the bins' (mean |q|, mean C); beyond them ``how``:
    ``"zero"`` (or ``"none"``, the caller having checked the range) gives 0, ``"power_law"``
    continues the power law through the first (last) bin and the fourth from that end (or
    the other end of a shorter table).

    Parameters
    ----------
    q_grid : array
        Target wavenumbers (1/m), increasing.
    q, C : arrays (m,), m >= 2
        Bin wavenumbers (1/m) and PSD (m^4, > 0), see :func:`valid_bins`.
    how : str
        ``"none"``, ``"zero"`` or ``"power_law"``.
    """
    out = extend_psd(q_grid, q, C, "zero")
    if how == "power_law":
        k = min(3, q.size - 1)
        for sel, base, other in ((q_grid < q[0], 0, k), (q_grid > q[-1], -1 - k, -1)):
            if np.any(sel):
                out[sel] = _power_law_tail(q_grid[sel], q, C, base, other)
    return out


def coherence_on_grid(q_grid, q, eta):
    """Binned coherence on the grid ``q_grid``: linear in log q, held constant at its end
    values beyond the bins (dimensionless).

    Parameters
    ----------
    q_grid : array
        Target wavenumbers (1/m).
    q, eta : arrays
        Bin wavenumbers (1/m) and coherence, see :func:`valid_bins`.
    """
    return np.interp(np.log(q_grid), np.log(q), eta)


# ----------------------------------------------------------------------------------------
# Periodic square maps
# ----------------------------------------------------------------------------------------


def pair_coherence(h1, h2, pixel_size, q_edges):
    """Coherence eta(q) = Re C12 / sqrt(C11 C22) of two square maps on one periodic grid,
    averaged over annuli q_edges[i] <= |q| < q_edges[i+1] (seed eq 41).

    Parameters
    ----------
    h1, h2 : arrays (n, n)
        Heights (m).
    pixel_size : float
        dx (m).
    q_edges : array
        Annulus edges (1/m).

    Returns
    -------
    array (len(q_edges) - 1,)
        Dimensionless; NaN in annuli without modes or where one map has no roughness.
    """
    n0, n1 = np.shape(h1)
    if n0 != n1 or np.shape(h2) != np.shape(h1):
        raise ValueError("pair_coherence needs two square maps of the same shape")
    H1, H2 = np.fft.rfft2(h1), np.fft.rfft2(h2)
    q = lattice_wavenumbers(n0, pixel_size)
    weight = half_plane_weights(n0)
    which = np.digitize(q, q_edges) - 1
    nb = len(q_edges) - 1
    ok = (which >= 0) & (which < nb)

    def binned(v):
        return np.bincount(which[ok], weights=(weight * v)[ok], minlength=nb)[:nb]

    c12 = binned(np.real(H1 * np.conj(H2)))
    c11, c22 = binned(np.abs(H1) ** 2), binned(np.abs(H2) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return c12 / np.sqrt(c11 * c22)


def rms_slope_of_map(h, pixel_size):
    """Root-mean-square slope of a periodic square map (dimensionless), spectrally.

    .. math:: \\xi^2 = \\sum_k |k|^2 |H_k|^2

    the lattice form of the continuum's 2 pi \\int q^3 C dq (seed eq 12).

    Parameters
    ----------
    h : array (n, n)
        Heights (m) of the periodic cell.
    pixel_size : float
        Grid spacing dx (m); the cell's side is n dx.
    """
    n = np.shape(h)[0]
    H = np.fft.rfft2(h) / (n * n)
    q = lattice_wavenumbers(n, pixel_size)
    return float(np.sqrt(np.sum(half_plane_weights(n) * q * q * np.abs(H) ** 2)))


def hurst_from_spectrum(q, C, n, min_modes=5.0):
    """Hurst exponent H of a self-affine band from the slope of a binned PSD, with its error.

    For C ~ q^(-2(1 + H)) (isotropic 2D PSD; a line scan's C1D ~ q^(-(1 + 2H)) converted by
    c(H') C1D / q has the same slope whatever H' it was converted with),
    ln C = b - 2 (1 + H) ln q. The slope is fitted by least squares with the bins' weights n
    (var ln C = 1/n for a bin mean of n exponential modes), over the bins with at least
    ``min_modes`` modes: H = -slope / 2 - 1, standard error s_slope / 2 with
    s_slope^2 = max(1, chi^2 / (k - 2)) / sum n (ln q - mean)^2 (inflated by the scatter about
    the line when it exceeds the mode statistics: correlated profiles, a roll-off, a kink).

    Parameters
    ----------
    q : array
        Bins' mean wavenumbers (1/m).
    C : array
        Binned PSD (m^4, any positive multiple of the isotropic PSD).
    n : array
        Independent modes per bin.
    min_modes : float
        Fewest modes of a bin used.

    Returns
    -------
    H : float
        Fitted Hurst exponent (dimensionless; NaN with fewer than three usable bins).
    error : float
        Its standard error (dimensionless).
    used : int
        Bins used.

    References
    ----------
    docs/theory.md, section "Spectra" (the line-scan conversion); docs/measured-data.md.
    """
    q, C, n = (np.asarray(a, dtype=float) for a in (q, C, n))
    ok = np.isfinite(q) & np.isfinite(C) & (C > 0) & np.isfinite(n) & (n >= min_modes)
    if np.count_nonzero(ok) < 3:
        return float("nan"), float("nan"), int(np.count_nonzero(ok))
    x, y, w = np.log(q[ok]), np.log(C[ok]), n[ok]
    xm, ym = np.sum(w * x) / np.sum(w), np.sum(w * y) / np.sum(w)
    sxx = np.sum(w * (x - xm) ** 2)
    slope = np.sum(w * (x - xm) * (y - ym)) / sxx
    chi2 = np.sum(w * (y - ym - slope * (x - xm)) ** 2)
    dof = max(x.size - 2, 1)
    s_slope = math.sqrt(max(1.0, chi2 / dof) / sxx)
    return float(-slope / 2.0 - 1.0), float(s_slope / 2.0), int(x.size)
