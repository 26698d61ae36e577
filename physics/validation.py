"""Validation of the theory variants on the project's own exact solver: one BEM task per
(Hurst exponent, bandwidth, coherence, realization, pixels per wavelength), the Richardson
extrapolation of the BEM's contact area in the pixel size, and the deviation summaries.

A case is a pair of self-affine surfaces on the band qL <= q <= zeta qL (zeta the bandwidth):
the substrate rolls off at q0 = r1 qL, the solid at r2 qL (different roll-offs, so that the
coherence eta changes the shape of the combined spectrum, not only its scale). Loads are given
as reduced pressures p / (E* g), g the rms slope of the combined spectrum on the band (the
unit in which the contact area barely depends on the spectrum: Prodanov, Dapp & Müser,
Tribol. Lett. 53, 433 (2014)); eq 19 is then A/A0 = erf(sqrt(2) p / (E* g)) for every case.
See docs/validation.md.
"""

from __future__ import annotations

import time

import numpy as np

from .bem import SubPixelContact, contact_pair
from .quadrature import log_grid
from .spectra import hrms_from_psd, psd_combined, rms_slope_from_psd, self_affine_hrms_factor, self_affine_psd
from .synthesis import (
    cell_psd_on_lattice,
    half_plane_weights,
    lattice_wavenumbers,
    psd_on_lattice,
    synthesize_pair,
    white_noise_pair,
)

#: fields of a BEM task's result, in order along its last axis
FIELDS = ("area", "gap", "seconds")


def case_spectra(hurst, zeta, qL, rolloffs, hrms, points_per_decade=50):
    """The two surfaces' PSDs of one case on a log grid from qL to zeta qL (m^4).

    Parameters
    ----------
    hurst : float
        H of both surfaces, 0 < H <= 1.
    zeta : float
        Bandwidth: the highest wavenumber is zeta qL.
    qL : float
        Lowest wavenumber 2 pi / L (1/m).
    rolloffs : (float, float)
        q0 / qL of the substrate and of the solid, >= 1 and < zeta.
    hrms : (float, float)
        rms heights of the substrate and the solid on the band (m).
    points_per_decade : int
        Density of the q grid (its knots qL, q0, zeta qL are nodes; the quadrature is exact).

    Returns
    -------
    q, C1, C2 : arrays (n,)
        1/m, m^4, m^4.
    """
    q1 = zeta * qL
    knots = [r * qL for r in rolloffs]
    q = log_grid(qL, q1, points_per_decade, knots=knots)
    out = [q]
    for r, h in zip(rolloffs, hrms, strict=True):
        q0 = r * qL
        C0 = h * h / self_affine_hrms_factor(hurst, qL, q0, q1)
        out.append(self_affine_psd(q, hurst, qL, q0, q1, C0))
    return tuple(out)


def case_pressures(p_reduced, hurst, zeta, eta, qL, rolloffs, hrms, E_star, points_per_decade=50):
    """Nominal pressures p = (p / (E* g)) E* g of one case (Pa), and g (dimensionless)."""
    q, C1, C2 = case_spectra(hurst, zeta, qL, rolloffs, hrms, points_per_decade)
    g = float(rms_slope_from_psd(q, psd_combined(C1, C2, eta)))
    return np.asarray(p_reduced, dtype=float) * E_star * g, g


def bem_task(hurst, zeta, eta, realization, n_w, p_reduced, *, qL, rolloffs, hrms, E_star, seed=0, tolerance=1e-10,
             points_per_decade=50, lattice="cell"):
    """One BEM task: synthesize the case's pair on an (n_w zeta)^2 grid and solve every pressure.

    The noise depends only on (seed, realization, zeta): every eta, H and n_w of a realization
    sees the same random numbers, and a finer grid the same surface. Pressures whose contact is
    below one pixel (the solver cannot resolve it) are NaN.

    Parameters
    ----------
    hurst, zeta, eta : float
        The case (see :func:`case_spectra`; eta the coherence).
    realization : int
        Index of the random pair.
    n_w : float
        Pixels per shortest wavelength; the grid has n_w zeta pixels per side.
    p_reduced : array (k,)
        Reduced pressures p / (E* g), increasing.
    qL, rolloffs, hrms, E_star, seed, tolerance, points_per_decade
        See :func:`case_spectra`; E* in Pa; the solver's relative tolerance.
    lattice : {"cell", "point"}
        How the PSD is put on the lattice (:func:`roughcontact.physics.synthesis.synthesize_pair`).

    Returns
    -------
    array (k, 3)
        A/A0, the mean gap (m) and the mean wall time per solve (s) (:data:`FIELDS`).
    """
    zeta, n = float(zeta), int(round(float(n_w) * float(zeta)))
    q, C1, C2 = case_spectra(hurst, zeta, qL, rolloffs, hrms, points_per_decade)
    p, g = case_pressures(p_reduced, hurst, zeta, eta, qL, rolloffs, hrms, E_star, points_per_decade)
    if g == 0.0:  # identical surfaces fully correlated: flat composite, full contact
        return np.column_stack([np.ones(p.size), np.zeros(p.size), np.zeros(p.size)])
    noise = white_noise_pair(n, seed, int(realization), band=zeta)
    h1, h2 = synthesize_pair(q, C1, C2, eta, n, zeta * qL, noise=noise, lattice=lattice)
    out = np.full((p.size, len(FIELDS)), np.nan)
    start, t0 = 0, time.perf_counter()
    while start < p.size:
        try:
            res = contact_pair(h1, h2, 2.0 * np.pi / qL / n, E_star, p[start:], tolerance=tolerance)
        except SubPixelContact as exc:
            start = int(np.searchsorted(p, exc.pressure, side="right"))
            continue
        out[start:, 0], out[start:, 1] = res["area"], res["mean_gap"]
        break
    solved = max(p.size - start, 1)
    out[:, 2] = (time.perf_counter() - t0) / solved
    return out


def bem_block(hurst, zeta, eta, realization, n_w, p_reduced, **kwargs):
    """:func:`bem_task` over broadcast leading axes (the form ``xarray.apply_ufunc`` calls on a
    dask block): arrays (...) of the case parameters and (..., k) of the pressures; returns
    (..., k, 3), NaN where n_w is NaN (a rung that is not solved)."""
    lead = np.broadcast_shapes(*(np.shape(v) for v in (hurst, zeta, eta, realization, n_w)),
                               np.shape(p_reduced)[:-1])
    args = [np.broadcast_to(v, lead) for v in (hurst, zeta, eta, realization, n_w)]
    p = np.broadcast_to(p_reduced, lead + np.shape(p_reduced)[-1:])
    out = np.full(lead + (p.shape[-1], len(FIELDS)), np.nan)
    for idx in np.ndindex(*lead):
        if np.isfinite(args[4][idx]):  # n_w = NaN: a rung not solved (beyond the largest grid)
            out[idx] = bem_task(*(float(a[idx]) for a in args), p[idx], **kwargs)
    return out


def extrapolated_area(area, n_w):
    """The BEM's contact area extrapolated to zero pixel size, per realization.

    Parameters
    ----------
    area : array (..., m)
        A/A0 on m resolution rungs (NaN where not solved), coarse to fine along the last axis.
    n_w : array (m,)
        Pixels per wavelength of the rungs, increasing.

    Returns
    -------
    (extrapolated, finest, coarse) : arrays (...)
        First-order Richardson value from the two finest solved rungs, and those two values
        (docs/bem.md: the area converges to first order in the pixel size; the measured order is
        reported by :func:`observed_order`).
    """
    area = np.asarray(area, dtype=float)
    solved = np.isfinite(area)
    last = area.shape[-1] - 1 - np.argmax(solved[..., ::-1], axis=-1)
    prev = np.clip(last - 1, 0, None)
    fine = np.take_along_axis(area, last[..., None], -1)[..., 0]
    coarse = np.take_along_axis(area, prev[..., None], -1)[..., 0]
    ratio = np.asarray(n_w, dtype=float)[last] / np.asarray(n_w, dtype=float)[prev]
    ok = (last >= 1) & np.all(solved.sum(-1, keepdims=True) >= 2, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ext = np.where(ok, richardson(coarse, fine, ratio), np.nan)
    return ext, fine, np.where(ok, coarse, np.nan)


def richardson(coarse, fine, ratio=2.0, order=1.0):
    """Extrapolation to zero pixel size from two resolutions (pixel sizes in ``ratio``):
    fine + (fine - coarse) / (ratio^order - 1)."""
    return fine + (fine - coarse) / (ratio**order - 1.0)


def observed_order(a, b, c, ratio=2.0):
    """Convergence order from three resolutions refined by ``ratio`` each: log((a - b)/(b - c)) /
    log(ratio); NaN where the differences do not shrink monotonically."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (a - b) / (b - c)
        return np.where(r > 1.0, np.log(r) / np.log(ratio), np.nan)


def lattice_moments(q, C, zeta, lattice="point"):
    """What the BEM's periodic lattice holds against the continuum integrals of the theory,
    on the band qL <= |q| <= zeta qL: (lattice / continuum) of hrms^2 and of the mean-square
    slope g^2 (dimensionless).

    The lattice sum is sum_k (2 pi / L)^2 C_k (times |k|^2 for the slope), C_k sampled at |k|
    (``point``) or averaged over the mode's cell (``cell``; see
    :func:`roughcontact.physics.synthesis.cell_psd_on_lattice`); the continuum integral is
    2 pi \\int_qL^(zeta qL) q C dq (q^3 C). With point sampling the four modes at |k| = qL
    stand for a cell that reaches below qL, so the lattice holds more long-wavelength roughness.
    """
    q = np.asarray(q, dtype=float)
    qL = q[0]
    n = 2 * int(np.ceil(zeta)) + 4
    ql = lattice_wavenumbers(n, 2.0 * np.pi / qL / n)
    Ck = cell_psd_on_lattice(n, q, C, zeta * qL) if lattice == "cell" else psd_on_lattice(ql, q, C, zeta * qL)
    Cl = Ck * half_plane_weights(n) * qL * qL
    h2 = float(np.sum(Cl)) / float(hrms_from_psd(q, C) ** 2)
    g2 = float(np.sum(Cl * ql * ql)) / float(rms_slope_from_psd(q, C) ** 2)
    return h2, g2


def deviation(theory, reference, mask):
    """(largest |theory / reference - 1|, mean theory / reference - 1) over ``mask`` (NaN-safe);
    NaN where the mask is empty."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(mask, theory / reference - 1.0, np.nan)
    if not np.any(np.isfinite(r)):
        return np.nan, np.nan
    return float(np.nanmax(np.abs(r))), float(np.nanmean(r))
