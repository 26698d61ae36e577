"""Exact contact of a coated (layered) elastic solid with a rigid periodic rough surface: the
Polonsky-Keer solver of :mod:`roughcontact.physics.bem_cg` with the layered solid's surface
compliance, reduced as the half-space BEM of :mod:`roughcontact.physics.bem` reduces Tamaas'
fields (contact area, mean gap, pressure histogram, optional maps).

The coated solid (a layer of thickness d, E_l, nu_l bonded to a half-space E_s, nu_s) displaces
its surface under one Fourier component of the pressure by

    u(q) = 2 p(q) / (q E_eff(q))

(:func:`roughcontact.physics.layered.surface_compliance`): the kernel the solver takes. With
equal layer and substrate it is the half-space's 2 / (q E*) exactly. See docs/bem.md, section
"Coated solids", and docs/coating.md.

Units: SI (heights and pixel size in m, pressures in Pa). Solved in reduced units (lengths in
pixels, stresses in the substrate's E*), as the half-space BEM, so that the tolerance means the
same at any scale.
"""

from __future__ import annotations

import numpy as np

from .bem import flat_contact, new_results, reduce_solution
from .bem_cg import solve
from .layered import surface_compliance


def layered_kernel(layer, pixel_size: float, E_unit: float):
    """The layered solid's surface compliance in reduced units: a function of |q| in 1/pixel
    returning pixel / E_unit, i.e. compliance(q / dx) E_unit / dx.

    Parameters
    ----------
    layer : tuple
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub)
        (:data:`roughcontact.physics.layered.LAYER_FIELDS`).
    pixel_size : float
        dx (m).
    E_unit : float
        The stress unit (Pa), e.g. the substrate's E*.

    Returns
    -------
    callable
        q (1/pixel, > 0) -> reduced compliance (dimensionless: pixel per E_unit).

    References
    ----------
    docs/coating.md; Persson, J. Phys.: Condens. Matter 24, 095008 (2012).
    """
    d, E_l, nu_l, E_s, nu_s = (float(v) for v in layer)
    dx, E_unit = float(pixel_size), float(E_unit)
    return lambda q: surface_compliance(q / dx, d, E_l, nu_l, E_s, nu_s) * (E_unit / dx)


def coated_contact_pair(h1, h2, pixel_size, layer, pressures, *, tolerance=1e-10, stress_edges=None, progress=None,
                        fields=False):
    """Frictionless non-adhesive contact of a coated elastic solid with a rigid periodic surface,
    at several nominal pressures: :func:`roughcontact.physics.bem_cg.solve` with the layered
    compliance 2 / (q E_eff(q)), increasing pressures warm-started from the previous solution.

    Parameters
    ----------
    h1, h2 : arrays (nx, ny)
        The substrate's and the elastic (coated) solid's heights, upwards in one frame (m); the
        contact depends on the composite h1 - h2 only (as :func:`roughcontact.physics.bem.contact_pair`).
    pixel_size : float
        dx (m).
    layer : tuple
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub) of the coated solid.
    pressures : array (np,)
        Nominal pressures (Pa), > 0.
    tolerance : float
        Relative complementarity error of the solver (dimensionless).
    stress_edges : array (np, nb + 1), optional
        Per pressure, edges of the histogram of the local contact pressure (Pa).
    progress : callable, optional
        ``progress(1)`` after each pressure.
    fields : bool
        Also return the gap and pressure maps.

    Returns
    -------
    dict
        As :func:`roughcontact.physics.bem.solve_contact`: ``area``, ``mean_gap`` (m),
        ``histogram`` (1/Pa), ``overflow`` and, with ``fields``, ``gap`` (m) and ``pressure`` (Pa).

    Raises
    ------
    roughcontact.physics.bem_cg.NoConvergence
        When a solve does not reach the tolerance.

    References
    ----------
    Polonsky & Keer, Wear 231, 206 (1999); Persson, J. Phys.: Condens. Matter 24, 095008 (2012);
    docs/bem.md.
    """
    h1, h2 = np.asarray(h1, dtype=float), np.asarray(h2, dtype=float)
    if h1.shape != h2.shape:
        raise ValueError(f"the two maps must be on one grid, got shapes {h1.shape} and {h2.shape}")
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    if np.any(~(pressures > 0)):
        raise ValueError("pressures must be > 0")
    heights = h1 - h2
    shape = heights.shape
    nb = 0 if stress_edges is None else np.shape(stress_edges)[-1] - 1
    surface = (heights - heights.mean()) / pixel_size
    if np.ptp(surface) == 0.0:
        return flat_contact(pressures, stress_edges, nb, shape if fields else None)
    E_unit = float(layer[3]) / (1.0 - float(layer[4]) ** 2)  # the substrate's E*
    kernel = layered_kernel(layer, pixel_size, E_unit)
    out = new_results(pressures.size, nb, shape if fields else None)
    previous = None
    for i, p in enumerate(pressures):
        res = solve(surface, 1.0, kernel, p / E_unit, tolerance=tolerance, initial=previous)
        previous = res["pressure"]
        traction = res["pressure"] * E_unit
        gap = (res["displacement"] - surface) * pixel_size
        reduce_solution(out, i, traction, gap, None if stress_edges is None else stress_edges[i])
        if progress is not None:
            progress(1)
    return out
