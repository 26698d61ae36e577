"""Exact contact of an elastic half-space with a rigid periodic rough surface: the FFT
boundary-element (BEM) solve that checks Persson's theory.

Frictionless, non-adhesive contact, exact up to discretization on periodic height maps. The
solver is Tamaas' Polonsky-Keer-Rey conjugate-gradient method (Frérot, Anciaux & Molinari,
Tamaas, J. Open Source Softw. 5, 2121 (2020); Polonsky & Keer, Wear 231, 206 (1999));
this module sets the solver up and reduces its fields. Tamaas is an optional dependency,
imported only when a solve needs it (:class:`SolverMissing` without it).

Two rough surfaces (seed eqs 52, 65): the substrate height h1 and the elastic solid's height
h2 are measured upwards in the same frame; the local gap is (d + h2) - h1, so contact depends
on the composite h = h1 - h2 only. See docs/theory.md, section "Contact", and docs/bem.md.
"""

from __future__ import annotations

import numpy as np


class SolverMissing(ImportError):
    """The optional BEM solver (the tamaas package) is not installed; ``reason`` is why the
    import failed."""

    def __init__(self, reason: str):
        super().__init__(f"the BEM needs the optional dependency tamaas, which is not installed ({reason})")
        self.reason = reason


class SubPixelContact(ArithmeticError):
    """The solver failed at a pressure whose contact area is one pixel or less.

    Attributes ``pressure`` (Pa), ``shape`` (the map's grid) and ``detail`` (the solver's message).
    """

    def __init__(self, pressure: float, shape: tuple[int, int], detail: str):
        super().__init__(f"contact area of a single pixel or less at p = {pressure:.6g} Pa ({detail})")
        self.pressure, self.shape, self.detail = pressure, shape, detail


def tamaas_module():
    """The tamaas module, quiet (errors only); :class:`SolverMissing` when not installed."""
    try:
        import tamaas
    except ImportError as exc:
        raise SolverMissing(str(exc)) from None
    tamaas.set_log_level(tamaas.LogLevel.error)
    return tamaas


def new_results(n, nb, shape=None):
    """Zeroed result arrays for ``n`` pressures, ``nb`` histogram bins and gap maps of ``shape``."""
    out = {"area": np.zeros(n), "mean_gap": np.zeros(n), "histogram": np.zeros((n, nb)), "overflow": np.zeros(n)}
    if shape is not None:
        out["gap"] = np.zeros((n,) + tuple(shape))
        out["pressure"] = np.zeros((n,) + tuple(shape))
    return out


def flat_contact(pressures, stress_edges, nb, shape=None):
    """A flat composite (e.g. identical surfaces with eta = 1): full contact at any pressure,
    the local pressure everywhere equal to p (a delta in the histogram); zero gap maps and
    pressure maps equal to p of ``shape`` when asked for."""
    out = new_results(pressures.size, nb, shape)
    out["area"][:] = 1.0
    for i, p in enumerate(pressures):
        if shape is not None:
            out["pressure"][i] = p
        if nb:
            edges = np.asarray(stress_edges[i])
            k = np.searchsorted(edges, p, side="right") - 1
            if 0 <= k < nb:
                out["histogram"][i, k] = 1.0 / (edges[k + 1] - edges[k])
            else:
                out["overflow"][i] = 1.0
    return out


def solve_contact(heights, pixel_size, E_star, pressures, *, tolerance=1e-10, stress_edges=None, progress=None,
                  fields=False):
    """Frictionless non-adhesive contact of an elastic half-space with a rigid periodic surface.

    Tamaas' Polonsky-Keer-Rey solver at each mean pressure, on the map's periodic cell,
    increasing pressures warm-started from the previous solution, in reduced units (lengths in
    pixels, stresses in E*: exact for linear elasticity, the tolerance meaningful at any scale).

    Parameters
    ----------
    heights : array (nx, ny)
        Composite surface (m): the rigid rough surface seen by a flat elastic solid
        (for a pair, h1 - h2; see :func:`contact_pair`).
    pixel_size : float
        dx (m); the cell is nx dx by ny dx.
    E_star : float
        Effective modulus (Pa), E* = E / (1 - nu^2) (seed eq 3).
    pressures : array (np,)
        Mean (nominal) pressures (Pa), > 0.
    tolerance : float
        Relative tolerance of the solver (dimensionless).
    stress_edges : array (np, nb + 1), optional
        Per pressure, edges of the histogram of the local contact pressure (Pa).
    progress : callable, optional
        Called as ``progress(1)`` after each pressure is solved (for a progress bar).
    fields : bool
        Also return the gap and pressure maps ``gap`` and ``pressure``, below.

    Returns
    -------
    dict with
        ``area`` (np,): relative contact area A/A0 (fraction of pixels with pressure > 0);
        ``mean_gap`` (np,): mean interfacial separation, the map average of the gap (m);
        ``histogram`` (np, nb): density of the local pressure (1/Pa) over the whole map (sum of
        histogram * width = the map's fraction in contact inside the edges; no delta at 0, eq 16);
        ``overflow`` (np,): fraction of the map in contact above the last edge;
        ``gap`` (np, nx, ny), with ``fields``: local gap (m), 0 where the pressure is > 0;
        ``pressure`` (np, nx, ny), with ``fields``: local contact pressure (Pa), >= 0, its map
        average the mean pressure p (force balance, to the solver's tolerance).

    Raises
    ------
    SolverMissing
        Without tamaas (only a flat surface is solved without it).
    SubPixelContact
        The solver failed on a contact of one pixel or less, even from a cold start.

    References
    ----------
    Polonsky & Keer, Wear 231, 206 (1999); Frérot et al., JOSS 5, 2121 (2020); docs/bem.md.
    """
    heights = np.asarray(heights, dtype=float)
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    if np.any(~(pressures > 0)):
        raise ValueError("pressures must be > 0")
    nx, ny = heights.shape
    nb = 0 if stress_edges is None else np.shape(stress_edges)[-1] - 1
    surface = (heights - heights.mean()) / pixel_size
    if np.ptp(surface) == 0.0:
        return flat_contact(pressures, stress_edges, nb, (nx, ny) if fields else None)
    out = new_results(pressures.size, nb, (nx, ny) if fields else None)
    tm = tamaas_module()
    model, solver = _pkr(tm, surface, tolerance)
    for i, p in enumerate(pressures):
        for attempt in (0, 1):
            try:
                solver.solve(float(p / E_star))
                break
            except tm.FloatingPointError as exc:
                # PKR's error measure is 0/0 when the contact is one node; a warm start from a
                # one-node solution can hit it where a cold start does not: retry cold once
                if attempt:
                    raise SubPixelContact(float(p), (nx, ny), str(exc).strip().splitlines()[-1]) from None
                model, solver = _pkr(tm, surface, tolerance)
        traction = np.array(model.traction, copy=True).reshape(nx, ny) * E_star
        gap = (np.array(model.displacement, copy=True).reshape(nx, ny) - surface) * pixel_size
        reduce_solution(out, i, traction, gap, None if stress_edges is None else stress_edges[i])
        if progress is not None:
            progress(1)
    return out


def _pkr(tm, surface, tolerance):
    """A fresh tamaas model (E* = 1 in reduced units) and its Polonsky-Keer-Rey solver on the
    periodic ``surface`` (heights in pixels)."""
    nx, ny = surface.shape
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(nx), float(ny)], [nx, ny])
    model.E = 1.0
    model.nu = 0.0  # E* = E / (1 - nu^2) = 1 in reduced units
    return model, tm.PolonskyKeerRey(model, np.ascontiguousarray(surface), float(tolerance))


def reduce_solution(out, i, traction, gap, edges):
    """Store the solution at pressure index ``i``: contact fraction, mean gap (m), the
    histogram of the local pressure (Pa) on ``edges`` and, if ``out`` has them, the gap and
    pressure maps."""
    npix = traction.size
    contact = traction > 0
    if "gap" in out:
        out["gap"][i] = np.where(contact, 0.0, np.maximum(gap, 0.0))
        out["pressure"][i] = np.maximum(traction, 0.0)
    out["area"][i] = np.count_nonzero(contact) / npix
    out["mean_gap"][i] = max(float(gap.mean()), 0.0)
    if edges is not None and np.size(edges) > 1:
        edges = np.asarray(edges, dtype=float)
        counts, _ = np.histogram(traction[contact], bins=edges)
        out["histogram"][i] = counts / (npix * np.diff(edges))
        out["overflow"][i] = np.count_nonzero(traction > edges[-1]) / npix


def contact_pair(h1, h2, pixel_size, E_star, pressures, **kwargs):
    """Contact of two rough surfaces on one grid: :func:`solve_contact` of the composite h1 - h2.

    Parameters
    ----------
    h1, h2 : arrays (nx, ny)
        The substrate's and the elastic solid's heights, both measured upwards in the same
        frame (m), same shape. Synthesized maps
        (:func:`roughcontact.physics.synthesis.synthesize_pair`) and measured topographies alike.
    pixel_size : float
        dx (m).
    E_star : float
        Effective modulus (Pa).
    pressures : array
        Mean pressures (Pa), > 0.
    **kwargs
        ``tolerance``, ``stress_edges``, ``progress`` of :func:`solve_contact`.
    """
    h1, h2 = np.asarray(h1, dtype=float), np.asarray(h2, dtype=float)
    if h1.shape != h2.shape:
        raise ValueError(f"the two maps must be on one grid, got shapes {h1.shape} and {h2.shape}")
    return solve_contact(h1 - h2, pixel_size, E_star, pressures, **kwargs)
