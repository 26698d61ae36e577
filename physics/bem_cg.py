"""Exact contact of a flat elastic body with a rigid periodic rough surface, for any surface
kernel: the constrained conjugate-gradient method of Polonsky and Keer, in pure numpy.

The elastic body enters only through its surface compliance in Fourier space: a pressure
p(x) on the periodic cell displaces the surface by u(x) with

    u(q) = compliance(q) p(q),   q != 0,

(the q = 0 mode is the rigid approach, fixed by the contact itself). For a homogeneous
half-space compliance(q) = 2 / (q E*) (:func:`half_space_compliance`); for a coated solid
compliance(q) = 2 / (q E_eff(q)) with the layered solid's wavenumber-dependent effective
modulus; any callable of |q| (1/m) returning m/Pa, or an array on the ``rfft2`` grid, works.

The problem (frictionless, non-adhesive, load controlled): find p >= 0 with mean p = p0 and a
rigid approach d such that the gap g = u - h + d is >= 0 everywhere and zero where p > 0
(h: the rigid surface's heights, upwards towards the elastic body). It minimises the convex
energy (1/2) <p, K p> - <p, h> over {p >= 0, mean p = p0}, so the solution is unique.

Algorithm (Polonsky & Keer, Wear 231, 206 (1999), load-controlled form):

1. start from the uniform pressure p = p0 (or a given one);
2. u = K p by FFT; the gap g = u - h, shifted so that its mean over the contact set
   I_c = {p > 0} is zero (the shift is the rigid approach);
3. conjugate direction on I_c: t = g + delta (G / G_old) t, G = sum_{I_c} g^2, t = 0 off I_c;
4. r = K t, shifted to zero mean on I_c; step tau = sum_{I_c} g t / sum_{I_c} r t;
5. p <- p - tau t; negative pressures set to 0; points out of contact that overlap
   (p = 0, g < 0) enter the contact with p = -tau g, and the conjugacy restarts (delta = 0);
6. p scaled to the mean p0; repeat from 2 until the error
   sum |p g| / (sum p rms(h)) (complementarity, relative; overlaps outside the contact count
   too) and the load error |mean p / p0 - 1| are below the tolerance.

Saturated (Kato) variant, ``pressure_cap`` = sigma_Y: the pressure is also bounded above,
0 <= p <= sigma_Y; where p = sigma_Y the surfaces may interpenetrate (g <= 0: the solid has
flowed plastically). The free set is then {0 < p < sigma_Y}; step 5 also clips p at sigma_Y
and releases capped points whose gap opens (g > 0) to p = sigma_Y - tau g; step 6 finds the
scale of the points below the cap that restores p0 (those it lifts above the cap are clipped).
If every loaded point is capped and they cannot carry p0, the approach grows until the next
point touches, which enters the contact. The error also counts sigma_Y max(g, 0) over the
capped points (capped points whose gap would open). This is the same quadratic programme on
{0 <= p <= sigma_Y, mean p = p0} (as solved by Tamaas' ``KatoSaturated``; Almqvist et al.,
Tribol. Int. 40, 574 (2007)).

Units: SI (heights and pixel size in m, pressures in Pa, compliance in m/Pa). See
docs/bem.md, section "The kernel-agnostic solver".
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


class NoConvergence(ArithmeticError):
    """The solver did not reach its tolerance within ``max_iterations``; ``error`` is the last."""

    def __init__(self, error: float, iterations: int):
        super().__init__(f"no convergence after {iterations} iterations (error {error:.3g})")
        self.error, self.iterations = error, iterations


def half_space_compliance(E_star: float) -> Callable[[np.ndarray], np.ndarray]:
    """The compliance 2 / (q E*) (m/Pa) of an elastic half-space of effective modulus E* (Pa),
    E* = E / (1 - nu^2) (Johnson, Contact Mechanics, sec. 13.2; seed eq 3), as a function of
    |q| (1/m, q > 0)."""
    E_star = float(E_star)
    if not E_star > 0:
        raise ValueError(f"E_star must be > 0, got {E_star!r}")
    return lambda q: 2.0 / (q * E_star)


def wavenumbers(shape: tuple[int, int], pixel_size: float) -> np.ndarray:
    """|q| (1/m) on the ``rfft2`` grid of a periodic map of ``shape`` pixels of side ``pixel_size`` (m)."""
    nx, ny = shape
    qx = 2.0 * np.pi * np.fft.fftfreq(nx, d=pixel_size)
    qy = 2.0 * np.pi * np.fft.rfftfreq(ny, d=pixel_size)
    return np.hypot(qx[:, None], qy[None, :])


def compliance_grid(compliance, shape: tuple[int, int], pixel_size: float) -> np.ndarray:
    """The compliance (m/Pa) on the ``rfft2`` grid, 0 at q = 0: ``compliance`` evaluated at
    :func:`wavenumbers`, or the array itself (checked: shape, finite, >= 0)."""
    nx, ny = shape
    q = wavenumbers(shape, pixel_size)
    if callable(compliance):
        k = np.zeros_like(q)
        nz = q > 0
        k[nz] = np.asarray(compliance(q[nz]), dtype=float)
    else:
        k = np.array(compliance, dtype=float, copy=True)
        if k.shape != q.shape:
            raise ValueError(f"a compliance array must have the rfft2 shape {q.shape} of the map, got {k.shape}")
        k[0, 0] = 0.0
    if not np.all(np.isfinite(k)) or np.any(k < 0):
        raise ValueError("the compliance must be finite and >= 0 at every q != 0")
    return k


def _error(p, g, p0, cap, free, capped, scale):
    """Relative complementarity error: sum |p g| on the free contact, p0 |g| where points out of
    contact overlap (p = 0, g < 0), cap g where capped points open (g > 0), over sum p rms(h)."""
    res = np.abs(p[free] * g[free]).sum()
    res += p0 * np.maximum(-g[p == 0], 0.0).sum()
    if cap is not None:
        res += cap * np.maximum(g[capped], 0.0).sum()
    return res / (p.sum() * scale)


def _rescale(p, p0, cap):
    """The pressure scaled to mean p0: c p elastic; with a cap, the points below it scaled (c p),
    those the scaling lifts above it clipped to the cap (and the rest rescaled), the capped kept."""
    n = p.size
    if cap is None:
        return p * (p0 * n / p.sum())
    p = np.minimum(p, cap)
    for _ in range(n):
        below = (p > 0) & (p < cap)
        rest = p0 * n - cap * np.count_nonzero(p >= cap)
        total = p[below].sum()
        if rest <= 0 or total == 0:  # the capped points alone carry more than the load: scale them all
            return _rescale_all(p, p0, cap)
        p = np.where(below, p * (rest / total), p)
        if not np.any(p[below] > cap):
            return p
        p = np.minimum(p, cap)
    return p


def _rescale_all(p, p0, cap):
    """min(c p, cap) with c such that its mean is p0 (piecewise linear in c, solved exactly)."""
    n = p.size
    loaded = np.sort(p[p > 0])[::-1]
    tail = np.concatenate([np.cumsum(loaded[::-1])[::-1], [0.0]])  # tail[k] = sum of loaded[k:]
    for k in range(loaded.size):  # c in [cap / loaded[k-1], cap / loaded[k]]: the first k capped
        c = (p0 * n - k * cap) / tail[k]
        if (cap / loaded[k - 1] if k else 0.0) <= c <= cap / loaded[k]:
            return np.minimum(c * p, cap)
    return np.where(p > 0, cap, 0.0)


def solve(heights, pixel_size, compliance, mean_pressure, *, pressure_cap=None, tolerance=1e-12,
          max_iterations=10000, initial=None):
    """Contact pressure, gap and displacement of a flat elastic body on a rigid periodic surface.

    Polonsky-Keer constrained conjugate gradients with the compliance as a parameter (module
    docstring for the algorithm).

    Parameters
    ----------
    heights : array (nx, ny)
        Heights of the rigid surface (m), upwards towards the elastic body; for two rough
        surfaces the composite h1 - h2. Its mean is irrelevant.
    pixel_size : float
        dx (m); the periodic cell is nx dx by ny dx.
    compliance : callable or array
        Surface compliance in Fourier space (m/Pa), u(q) = compliance(q) p(q): a function of
        |q| (1/m, called with the q > 0 of the grid), e.g. :func:`half_space_compliance` or
        ``lambda q: 2 / (q * effective_modulus(q, ...))``; or an array on the ``rfft2`` grid
        (its q = 0 entry ignored).
    mean_pressure : float
        Nominal pressure p0 (Pa), > 0 (and < pressure_cap).
    pressure_cap : float, optional
        Saturation pressure sigma_Y (Pa): 0 <= p <= sigma_Y (Kato's saturated contact, a
        perfectly plastic surface layer of penetration hardness sigma_Y). None: elastic.
    tolerance : float
        Relative complementarity error at which to stop (dimensionless).
    max_iterations : int
        Iterations before :class:`NoConvergence`.
    initial : array (nx, ny), optional
        Starting pressure (Pa), e.g. the solution at a nearby load (rescaled to p0).

    Returns
    -------
    dict with ``pressure`` (Pa), ``gap`` (m; 0 on the free contact, <= 0 where capped),
    ``displacement`` (m; u with the rigid approach, so that gap = displacement - heights),
    ``area`` (fraction of pixels with p > 0), ``plastic_area`` (fraction at the cap),
    ``iterations``, ``error``.

    References
    ----------
    I. A. Polonsky, L. M. Keer, Wear 231, 206 (1999); Tamaas (Frérot, Anciaux & Molinari,
    J. Open Source Softw. 5, 2121 (2020)) for the same method in C++; docs/bem.md.
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim != 2:
        raise ValueError(f"heights must be a 2-d map, got shape {h.shape}")
    p0 = float(mean_pressure)
    if not p0 > 0:
        raise ValueError(f"mean_pressure must be > 0, got {mean_pressure!r}")
    cap = None if pressure_cap is None else float(pressure_cap)
    if cap is not None and not cap > p0:
        raise ValueError(f"pressure_cap ({cap!r}) must exceed the mean pressure ({p0!r})")
    K = compliance_grid(compliance, h.shape, pixel_size)
    h = h - h.mean()
    scale = float(h.std()) or 1.0
    shape = h.shape

    def apply(x):
        return np.fft.irfft2(K * np.fft.rfft2(x), s=shape)

    p = np.full(shape, p0) if initial is None else _rescale(np.maximum(np.asarray(initial, float), 0.0), p0, cap)
    t = np.zeros(shape)
    G_old, delta = 1.0, 0.0
    error, iterations = np.inf, 0
    while iterations < max_iterations:
        iterations += 1
        g = apply(p) - h
        free = (p > 0) if cap is None else (p > 0) & (p < cap)
        capped = np.zeros(shape, bool) if cap is None else p >= cap
        touch = np.zeros(shape, bool)
        if not free.any():  # every loaded point capped: the gap on the loaded set fixes the approach
            g -= g[p > 0].max()
            if p.mean() < p0 and (p == 0).any():  # the capped points cannot carry p0: approach until
                g -= max(float(g[p == 0].min()), 0.0)  # the next point touches, and let it in
                touch = (p == 0) & (g <= 0)
        else:
            g -= g[free].mean()
        error = max(_error(p, g, p0, cap, free, capped, scale), abs(p.mean() / p0 - 1.0))
        if error < tolerance:
            break
        G = float(np.sum(g[free] ** 2))
        t = np.where(free, g + delta * (G / G_old) * t, 0.0)
        G_old = G if G > 0 else 1.0
        r = apply(t)
        if free.any():
            r -= r[free].mean()
        denom = float(np.sum(r[free] * t[free]))
        tau = float(np.sum(g[free] * t[free])) / denom if denom > 0 else 0.0
        p = np.where(free, p - tau * t, p)
        p = np.maximum(p, 0.0)
        enter = ((p == 0) & (g < 0)) | touch  # overlapping points out of contact
        leave = capped & (g > 0) if cap is not None else np.zeros(shape, bool)  # capped points opening
        p[enter] = -tau * g[enter] if tau > 0 else p0
        if cap is not None:
            p[leave] = cap - (tau * g[leave] if tau > 0 else 0.5 * cap)
            p = np.minimum(p, cap)
        delta = 0.0 if (enter.any() or leave.any()) else 1.0
        p = _rescale(np.maximum(p, 0.0), p0, cap)
    if not error < tolerance:
        raise NoConvergence(error, max_iterations)
    u = g + h  # displacement including the rigid approach
    return {"pressure": p, "gap": np.where(free, 0.0, g), "displacement": u,
            "area": np.count_nonzero(p > 0) / p.size,
            "plastic_area": 0.0 if cap is None else np.count_nonzero(p >= cap) / p.size,
            "iterations": iterations, "error": float(error)}


def saturated_areas(heights, pixel_size, E_star, pressures, sigma_Y, *, compliance=None, tolerance=1e-10,
                    progress=None):
    """Elastic and plastic contact area of a rough surface on an elastic-perfectly-plastic
    surface layer (Kato's saturated contact: local pressure bounded by the penetration hardness
    sigma_Y), at several nominal pressures: :func:`solve` with ``pressure_cap = sigma_Y``.

    Solved in reduced units (lengths in pixels, stresses in E*: exact for linear elasticity),
    increasing pressures warm-started from the previous solution. A pressure p >= sigma_Y cannot
    be carried (sigma_Y A0 < p A0): the whole map is at the cap there, A_pl/A0 = 1, A_el/A0 = 0
    (the convention of :func:`roughcontact.physics.plasticity.plastic_area_ratio`).

    Parameters
    ----------
    heights : array (nx, ny)
        Composite heights of the rigid surface (m), e.g. h1 - h2 of a pair.
    pixel_size : float
        dx (m).
    E_star : float
        Effective modulus (Pa) of the half-space; with ``compliance`` only the stress unit.
    pressures : array (np,)
        Nominal pressures (Pa), > 0.
    sigma_Y : float
        Penetration hardness (Pa), > 0.
    compliance : callable, optional
        Compliance of |q| (m/Pa) instead of the half-space's 2 / (q E*).
    tolerance : float
        Relative error of :func:`solve`.
    progress : callable, optional
        ``progress(1)`` after each pressure.

    Returns
    -------
    dict of arrays (np,): ``elastic_area`` (fraction of pixels with 0 < p < sigma_Y),
    ``plastic_area`` (fraction at sigma_Y), ``area`` (their sum).

    References
    ----------
    Polonsky & Keer, Wear 231, 206 (1999); Almqvist et al., Tribol. Int. 40, 574 (2007);
    docs/bem.md, section "Elastoplastic contact".
    """
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    sigma_Y, E_star = float(sigma_Y), float(E_star)
    if not sigma_Y > 0 or np.any(~(pressures > 0)):
        raise ValueError("sigma_Y and the pressures must be > 0")
    h = np.asarray(heights, dtype=float)
    surface = (h - h.mean()) / pixel_size
    kernel = half_space_compliance(1.0) if compliance is None else (lambda q: compliance(q / pixel_size)
                                                                     * E_star / pixel_size)
    out = {k: np.zeros(pressures.size) for k in ("elastic_area", "plastic_area", "area")}
    order = np.argsort(pressures)
    previous = None
    for i in order:
        p = pressures[i]
        if p >= sigma_Y:
            out["plastic_area"][i] = out["area"][i] = 1.0
        elif np.ptp(surface) == 0.0:  # flat: uniform pressure p < sigma_Y, all elastic
            out["elastic_area"][i] = out["area"][i] = 1.0
        else:
            res = solve(surface, 1.0, kernel, p / E_star, pressure_cap=sigma_Y / E_star, tolerance=tolerance,
                        initial=previous)
            previous = res["pressure"]
            out["plastic_area"][i] = res["plastic_area"]
            out["area"][i] = res["area"]
            out["elastic_area"][i] = res["area"] - res["plastic_area"]
        if progress is not None:
            progress(1)
    return out
