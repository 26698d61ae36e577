"""Random periodic surface pairs with given spectra and coherence (the BEM's input maps).

A pair h1 (substrate), h2 (elastic solid) on an n x n periodic cell of side L = 2 pi / qL is
synthesized in Fourier space so that each surface has its tabulated PSD (Persson's
convention, seed eq 4) and the pair has the coherence eta at every wavenumber (seed eq 41);
the composite h1 - h2 then has the combined PSD C1 + C2 - 2 eta sqrt(C1 C2) (seed eq 52).
A measured periodic map is put in the same band by :func:`band_limit`; :func:`fourier_refine`
samples a band-limited map on a finer grid. See docs/theory.md, section "Spectra", and docs/bem.md (grid <-> q band).
"""

from __future__ import annotations

import numpy as np

from .quadrature import loglog_interp


def lattice_wavenumbers(n: int, pixel_size: float) -> np.ndarray:
    """|q| (1/m) of the periodic lattice of an n x n map, in ``numpy.fft.rfft2`` layout.

    .. math:: \\mathbf{q} = (2 \\pi / L) (i, j), \\quad L = n \\, dx

    Parameters
    ----------
    n : int
        Pixels per side.
    pixel_size : float
        dx (m).

    Returns
    -------
    array (n, n // 2 + 1)
        |q| in 1/m.
    """
    kx = 2.0 * np.pi * np.fft.fftfreq(n, d=pixel_size)
    ky = 2.0 * np.pi * np.fft.rfftfreq(n, d=pixel_size)
    return np.hypot(kx[:, None], ky[None, :])


def half_plane_weights(n: int) -> np.ndarray:
    """Weights of the columns of an ``rfft2`` array with n points along its last axis.

    The interior columns 1 .. n/2 - 1 stand for a mode and its conjugate (weight 2); column 0
    and, for even n, the Nyquist column stand for themselves (weight 1). With them, sums over
    the half plane equal sums over the full Fourier plane.

    Returns
    -------
    array (n // 2 + 1,)
        Dimensionless weights, 1 or 2.
    """
    w = np.full(n // 2 + 1, 2.0)
    w[0] = 1.0
    if n % 2 == 0:
        w[-1] = 1.0
    return w


def grid_band(q_lowest, q_highest, n, pixels_per_wavelength):
    """Map size, pixel size, roughness cut-off and magnification of a synthesized BEM map.

    .. math:: L = 2 \\pi / q_L, \\quad dx = L / n, \\quad
              q_{cut} = \\min(q_{max}, n q_L / n_w), \\quad \\zeta_{bem} = q_{cut} / q_L

    The shortest wavelength 2 pi / q_cut spans at least n_w pixels (n_w = 2 is the Nyquist
    limit).

    Parameters
    ----------
    q_lowest, q_highest : float
        Lowest (qL) and highest wavenumber of the PSD grid (1/m).
    n : int
        Pixels per side.
    pixels_per_wavelength : float
        n_w, >= 2.

    Returns
    -------
    L, dx, q_cut, zeta_bem : float
        Map side (m), pixel size (m), cut-off (1/m), magnification (dimensionless).

    References
    ----------
    docs/bem.md, "Grid <-> q band".
    """
    L = 2.0 * np.pi / q_lowest
    q_cut = min(float(q_highest), n * q_lowest / float(pixels_per_wavelength))
    return L, L / n, q_cut, q_cut / q_lowest


def psd_on_lattice(q_lattice, q, C, q_cut):
    """A tabulated PSD at the lattice wavenumbers, zero outside [q[0], q_cut] (m^4).

    Log-log interpolation between the table's nodes: exact for the self-affine PSD, whose
    knots qL, q0, q1 are nodes of the psd stage's grid. The k = 0 mode (the mean height)
    gets zero.

    Parameters
    ----------
    q_lattice : array
        Lattice wavenumbers |q| (1/m), e.g. :func:`lattice_wavenumbers`.
    q : array (m,)
        Wavenumber grid of the table (1/m), increasing.
    C : array (m,)
        PSD on ``q`` (m^4, Persson's convention, seed eq 4).
    q_cut : float
        Highest wavenumber kept (1/m).

    Returns
    -------
    array like ``q_lattice``
        C(|q|) in m^4, >= 0.
    """
    q_lattice = np.asarray(q_lattice, dtype=float)
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    top = min(float(q_cut), float(q[-1]))
    inside = (q_lattice >= q[0] * (1 - 1e-12)) & (q_lattice <= top * (1 + 1e-12))
    out = np.zeros_like(q_lattice)
    out[inside] = loglog_interp(np.clip(q_lattice[inside], q[0], q[-1]), q, C)
    return np.maximum(out, 0.0)


def cell_psd_on_lattice(n: int, q, C, q_cut, subsamples: int = 12, near: float = 16.0) -> np.ndarray:
    """The PSD averaged over each lattice mode's cell of the Fourier plane (m^4), the band's
    continuum roughness shared out exactly among the modes.

    Mode k = qL (i, j) stands for the square cell qL [i - 1/2, i + 1/2] x [j - 1/2, j + 1/2];
    its value is the mean of C_band(|q|) over that cell, C_band = C on qL <= |q| <= q_cut and 0
    outside. The cells tile the plane, so sum_k (2 pi / L)^2 C_k = \\int_band d^2q C = hrms^2
    of the band exactly (point sampling, :func:`psd_on_lattice`, gives the four modes at
    |k| = qL the weight of the whole cell around them, part of which lies below qL: several per
    cent more variance for a roll-off spectrum, tens of per cent without roll-off; see
    docs/validation.md). Cells cut by a band edge or within ``near`` qL of the origin (where C
    curves on the cell's scale) are averaged over subsamples^2 points; the others take the
    point value (relative error below ~(1 + H)(3 + 2 H) / (12 near^2)). Modes just beyond
    q_cut whose cell reaches into the band get that part.

    Parameters
    ----------
    n : int
        Pixels per side (the map side is L = 2 pi / q[0]).
    q, C : arrays (m,)
        The tabulated PSD (1/m, m^4), q[0] = qL.
    q_cut : float
        Top of the band (1/m).
    subsamples : int
        Midpoint-rule points per cell side.
    near : float
        |k| / qL below which every cell is averaged.

    Returns
    -------
    array (n, n // 2 + 1)
        C per mode (m^4), rfft2 layout, 0 for the mean.
    """
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    qL = q[0]
    top = min(float(q_cut), float(q[-1])) / qL
    i = np.fft.fftfreq(n, d=1.0 / n)
    j = np.fft.rfftfreq(n, d=1.0 / n)
    r = np.hypot(i[:, None], j[None, :])
    reach = np.sqrt(0.5)

    def c_band(x):  # C at |q| = x qL, zero outside the band
        inside = (x >= 1.0 - 1e-12) & (x <= top * (1 + 1e-12))
        out = np.zeros_like(x)
        out[inside] = loglog_interp(np.clip(x[inside] * qL, q[0], q[-1]), q, C)
        return out

    out = np.zeros(r.shape)
    point = (r - reach >= 1.0) & (r + reach <= top) & (r >= near)
    out[point] = c_band(r[point])
    cells = np.argwhere((r + reach >= 1.0) & (r - reach <= top) & ~point)
    offsets = (np.arange(subsamples) + 0.5) / subsamples - 0.5
    dx, dy = np.meshgrid(offsets, offsets, indexing="ij")
    x = np.hypot(i[cells[:, 0], None] + dx.ravel(), j[cells[:, 1], None] + dy.ravel())
    out[cells[:, 0], cells[:, 1]] = c_band(x).mean(axis=-1)
    return out


def white_noise_pair(n: int, seed: int, realization: int, band: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two independent unit complex Gaussian white noises xi1, xi2 on the rfft2 lattice.

    xi = rfft2(w) / m with w an m x m field of independent standard normals, so
    <|xi_k|^2> = 1 and xi is Hermitian (its inverse transform is real). With ``band`` = K
    (the highest |q| / qL that will be used), w is drawn on the smallest even grid
    m = 2 floor(K) + 2 holding every mode |i|, |j| <= K, and those modes are placed on the
    n x n lattice: the noise in the band then does not depend on n, so the same seed gives
    the *same surface* on a finer grid (only the discretization changes). Without ``band``
    (or when m > n), m = n.

    Parameters
    ----------
    n : int
        Pixels per side.
    seed, realization : int
        Drawn from ``numpy.random.default_rng([seed, realization])``: realization r is the
        same whatever the number of realizations asked for.
    band : float, optional
        K = q_cut / qL (dimensionless).

    Returns
    -------
    xi1, xi2 : complex arrays (n, n // 2 + 1)
        Dimensionless noises.
    """
    rng = np.random.default_rng([int(seed), int(realization)])
    m = n if band is None else 2 * int(np.floor(band + 1e-9)) + 2
    if m >= n:
        w = rng.standard_normal((2, n, n))
        xi = np.fft.rfft2(w, axes=(-2, -1)) / n
        return xi[0], xi[1]
    w = rng.standard_normal((2, m, m))
    small = np.fft.rfft2(w, axes=(-2, -1)) / m
    k = m // 2  # rows 0 .. k-1 and -(k-1) .. -1, columns 0 .. k-1: every |i|, |j| <= K (m's Nyquist dropped)
    xi = np.zeros((2, n, n // 2 + 1), dtype=complex)
    xi[:, :k, :k] = small[:, :k, :k]
    xi[:, n - (k - 1):, :k] = small[:, m - (k - 1):, :k]
    return xi[0], xi[1]


def synthesize_pair(q, C1, C2, eta, n, q_cut, seed=0, realization=0, noise=None, lattice="point"):
    """Periodic height maps h1, h2 (m) with tabulated PSDs C1, C2 and coherence eta.

    On the periodic cell of side L = 2 pi / q[0] with n x n pixels (dx = L/n):

    .. math::

        h(\\mathbf{x}) = \\sum_k H_k e^{i \\mathbf{k} \\cdot \\mathbf{x}}, \\quad
        H^1_k = \\frac{2 \\pi}{L} \\sqrt{C_1(|k|)} \\, \\xi^1_k, \\quad
        H^2_k = \\frac{2 \\pi}{L} \\sqrt{C_2(|k|)} \\left(\\eta \\xi^1_k + \\sqrt{1 - \\eta^2} \\, \\xi^2_k\\right)

    with xi1, xi2 independent unit white noises (:func:`white_noise_pair`). Then
    <|H_k|^2> = C(|k|) (2 pi / L)^2, i.e. <h^2> = sum_k (2 pi/L)^2 C -> \\int d^2q C = hrms^2
    (seed eq 4), and Re<H1_k H2_k*> / sqrt(<|H1_k|^2><|H2_k|^2>) = eta (seed eq 41): the
    pair's coherence is eta at every wavenumber. The composite h1 - h2 has the combined PSD
    C1 + C2 - 2 eta sqrt(C1 C2) (seed eq 52).

    Parameters
    ----------
    q : array (m,)
        Wavenumber grid of the PSDs (1/m); q[0] = qL sets the map size L = 2 pi / qL.
    C1, C2 : array (m,)
        PSDs of the substrate and of the solid on ``q`` (m^4, Persson's convention).
    eta : float
        Coherence (dimensionless), -1 <= eta <= 1.
    n : int
        Pixels per side.
    q_cut : float
        Highest wavenumber kept (1/m); modes above it are zero.
    seed, realization : int
        Random stream (see :func:`white_noise_pair`).
    noise : (xi1, xi2), optional
        Noise to use instead of drawing it (e.g. shared between several eta).
    lattice : {"point", "cell"}
        C at each mode's |k| (:func:`psd_on_lattice`) or averaged over its cell of the Fourier
        plane (:func:`cell_psd_on_lattice`: the band's continuum variance exactly).

    Returns
    -------
    h1, h2 : arrays (n, n)
        Heights (m), zero mean.

    References
    ----------
    docs/theory.md, section "Spectra"; docs/bem.md.
    """
    eta = float(eta)
    if not -1.0 <= eta <= 1.0:
        raise ValueError(f"eta must be in [-1, 1], got {eta}")
    q = np.asarray(q, dtype=float)
    L = 2.0 * np.pi / q[0]
    ql = lattice_wavenumbers(n, L / n)
    xi1, xi2 = noise if noise is not None else white_noise_pair(n, seed, realization, band=q_cut / q[0])
    if lattice == "cell":
        a1 = (2.0 * np.pi / L) * np.sqrt(cell_psd_on_lattice(n, q, C1, q_cut))
        a2 = (2.0 * np.pi / L) * np.sqrt(cell_psd_on_lattice(n, q, C2, q_cut))
    else:
        a1 = (2.0 * np.pi / L) * np.sqrt(psd_on_lattice(ql, q, C1, q_cut))
        a2 = (2.0 * np.pi / L) * np.sqrt(psd_on_lattice(ql, q, C2, q_cut))
    H1 = a1 * xi1
    H2 = a2 * (eta * xi1 + np.sqrt(max(0.0, 1.0 - eta * eta)) * xi2)
    h1 = np.fft.irfft2(H1, s=(n, n)) * n * n
    h2 = np.fft.irfft2(H2, s=(n, n)) * n * n
    return h1, h2


def band_limit(h, pixel_size, q_cut):
    """A periodic square map (m) with its mean and every Fourier mode |q| > q_cut removed.

    The measured-map counterpart of the synthesis band qL <= |q| <= q_cut: the lattice of an
    n x n map of side L = n dx has no mode between 0 and qL = 2 pi / L, so keeping
    0 < |q| <= q_cut leaves exactly the band the theory integrates over. Modes on the edge
    (|q| = q_cut to 1e-12) are kept.

    Parameters
    ----------
    h : array (n, n)
        Heights (m).
    pixel_size : float
        dx (m).
    q_cut : float
        Highest wavenumber kept (1/m).
    """
    h = np.asarray(h, dtype=float)
    n = h.shape[0]
    if h.shape != (n, n):
        raise ValueError(f"band_limit needs a square map, got shape {h.shape}")
    H = np.fft.rfft2(h)
    q = lattice_wavenumbers(n, pixel_size)
    H[(q == 0.0) | (q > q_cut * (1 + 1e-12))] = 0.0
    return np.fft.irfft2(H, s=(n, n))


def fourier_refine(h, n):
    """The same band-limited periodic map sampled on a finer n x n grid (m).

    Zero-pads the map's Fourier transform: the surface is unchanged, only the discretization
    is refined (the grid-convergence check of docs/bem.md). The map's Nyquist row and column
    are dropped; they are zero for maps synthesized with ``pixels_per_wavelength`` > 2.

    Parameters
    ----------
    h : array (m, m)
        Heights (m).
    n : int
        New pixels per side, >= m.
    """
    h = np.asarray(h, dtype=float)
    m = h.shape[0]
    if h.shape != (m, m) or n < m:
        raise ValueError("fourier_refine needs a square map and n >= its size")
    H = np.fft.rfft2(h)
    k = (m + 1) // 2  # modes 0 .. k-1 and -(k-1) .. -1 along the first axis; 0 .. k-1 along the second
    out = np.zeros((n, n // 2 + 1), dtype=complex)
    out[:k, :k] = H[:k, :k]
    out[n - (k - 1):, :k] = H[m - (k - 1):, :k]
    return np.fft.irfft2(out, s=(n, n)) * (n * n) / (m * m)
