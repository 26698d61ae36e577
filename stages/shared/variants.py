"""Every theory variant at one magnification, for the stages that set the theory against exact
numerics (``bem``, ``validation``): eq 19 / eq 57 (``persson``) next to each contact-area
correction with its separation refinement (:data:`roughcontact.physics.corrections.VARIANTS`).

Not a stage: helpers of the stage layer. The gamma of a variant is the scene's
``contact.gamma`` when ``contact.correction`` names that variant, else the published one; the
``persson`` variant's separation uses the scene's ``separation.alpha``.
"""

from __future__ import annotations

import numpy as np

from roughcontact.physics.corrections import DEFAULT_GAMMA, VARIANTS, variant_theory
from roughcontact.stage import Var

from .magnification import CORRECTION_KEYS, area_correction

#: the scene keys the variants read (a stage that calls :func:`theory_variants` lists them)
VARIANT_KEYS = (*CORRECTION_KEYS, "separation.alpha", "numerics.separation_panels_per_decade",
                "numerics.separation_gauss_points", "numerics.separation_depth")

#: the coordinate ``theory`` of the stages that set the variants side by side
THEORY = Var("1", "theory variant", comment="persson (eq 19, eq 57), yang_persson, wang_mueser; each "
                                            "described in the attribute theory_variants")

#: a short description per variant (the ``theory`` coordinate's values)
DESCRIPTIONS = {
    "persson": "eq 19 and eq 57 with constant alpha (separation.alpha)",
    "yang_persson": "Yang-Persson 2008: area and energy factor S = gamma + (1 - gamma) P^2",
    "wang_mueser": "Wang-Mueser 2017: area factor S = gamma - (2/9) P^2 + (11/9 - gamma) P^4, same S in the energy",
}


def variant_gammas(inp) -> dict[str, float | None]:
    """gamma of each variant: the scene's for the variant it chooses, else the published one."""
    chosen, gamma = area_correction(inp)
    return {name: (gamma if name == chosen else DEFAULT_GAMMA[name]) for name in VARIANTS}


def theory_variants(inp, q, C_rows, q_upper, p_values, E_star, layer=None) -> tuple[np.ndarray, np.ndarray]:
    """A/A0 and u of every variant at zeta = q_upper / qL.

    Parameters
    ----------
    inp : StageInput
        With :data:`VARIANT_KEYS` among its parameters.
    q : array (n,)
        The psd stage's wavenumbers (1/m).
    C_rows : array (m, n)
        Combined PSDs, one row per case (e.g. per eta).
    q_upper : float
        zeta qL (1/m).
    p_values : array (k,)
        Nominal pressures (Pa).
    E_star : float
        Effective modulus (Pa); with ``layer``, the substrate's.
    layer : tuple, optional
        A coated solid (:func:`roughcontact.stages.shared.material.coating_layer`); None: a half-space.

    Returns
    -------
    (area, u) : arrays (k, m, len(VARIANTS))
    """
    numerics = {"panels_per_decade": inp["numerics.separation_panels_per_decade"],
                "order": inp["numerics.separation_gauss_points"], "depth": float(inp["numerics.separation_depth"])}
    gammas = variant_gammas(inp)
    alpha = float(inp["separation.alpha"])
    shape = (np.size(p_values), len(C_rows), len(VARIANTS))
    area, u = np.empty(shape), np.empty(shape)
    for j, C in enumerate(C_rows):
        for k, name in enumerate(VARIANTS):
            area[:, j, k], u[:, j, k] = variant_theory(q, C, q_upper, p_values, E_star, name, gammas[name],
                                                       alpha, numerics, layer=layer)
    return area, u


def variant_attrs(inp) -> dict:
    """Text attributes naming each variant and its gamma."""
    gammas = variant_gammas(inp)
    return {"theory_variants": "; ".join(
        f"{name}: {DESCRIPTIONS[name]}" + (f", gamma = {gammas[name]:.6g}" if gammas[name] is not None else
                                           f", alpha = {float(inp['separation.alpha']):g}")
        for name in VARIANTS)}
