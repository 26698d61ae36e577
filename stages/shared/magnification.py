"""The magnifications asked for (``[contact] zeta``), the contact-area theory
(``contact.correction``) and the penetration hardness (``contact.yield_stress``): the zeta
values on the q grid, their checks against the surfaces' bands, and the correction's gamma."""

from __future__ import annotations

import json
import warnings

import numpy as np

from roughcontact.physics.corrections import CORRECTIONS, DEFAULT_GAMMA, check_gamma
from roughcontact.stage import Param, SceneWarning, Section, Shape, UserError, register_params, register_section

from .grid import wavenumber_text
from .surfaces import Band

register_section(
    Section(
        "contact",
        (
            Param("zeta", "sweep", "", default="all", lo=1.0, choices=("all",),
                  doc="magnification(s) zeta = q/qL; 'all': every node of the q grid"),
        ),
        doc="the magnifications at which contact and separation are computed",
    )
)
#: the contact-area correction (docs/theory.md, "Contact-area corrections"); read by contact,
#: separation (refinement "contact"), friction and bem
register_params(
    "contact",
    Param("correction", "choice", default="persson", choices=tuple(CORRECTIONS),
          doc="contact-area theory: persson (eq 19, the seed), yang_persson (S = gamma + (1 - gamma) (A/A0)^2) "
              "or wang_mueser (S = gamma - (2/9) (A/A0)^2 + (11/9 - gamma) (A/A0)^4): dV = S dV_full along zeta"),
    Param("gamma", "quantity", "", default=None, lo=0.0, hi=1.0, lo_open=True,
          doc="gamma of the correction (default: the published value, 0.45 yang_persson, 5/9 wang_mueser)"),
)
CORRECTION_KEYS = ("contact.correction", "contact.gamma")
#: the penetration hardness of elastoplastic contact (docs/plasticity.md); read by contact
register_params(
    "contact",
    Param("yield_stress", "quantity", "Pa", default=None, lo=0.0, lo_open=True,
          doc="penetration hardness sigma_Y of the softer solid: contact spots whose stress reaches it yield "
              "(absorbing wall at sigma_Y); adds elastic_contact_area_ratio and plastic_contact_area_ratio. "
              "Default: none (elastic contact)"),
)


def area_correction(inp) -> tuple[str, float | None]:
    """The scene's contact-area correction and its gamma (the published one unless given),
    checked: S(A/A0) > 0 on [0, 1]."""
    name = inp["contact.correction"]
    gamma = inp["contact.gamma"]
    gamma = DEFAULT_GAMMA[name] if gamma is None else float(gamma)
    try:
        check_gamma(name, gamma)
    except ValueError as exc:
        raise UserError(str(exc), key="contact.gamma") from None
    return name, (None if name == "persson" else gamma)


def zeta_values(inp, q: np.ndarray) -> np.ndarray:
    """The magnifications ``[contact] zeta`` asks for on the wavenumber grid ``q`` (q[0] = qL):
    every node of the grid for ``"all"``, else the given values, which must lie on the grid."""
    zeta = inp["contact.zeta"]
    if isinstance(zeta, str):
        return q / q[0]
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    _check_zeta(zeta, q[-1] / q[0])
    return zeta


def _check_zeta(zeta: np.ndarray, top: float) -> None:
    if np.any(zeta > top * (1 + 1e-12)):
        raise UserError(f"magnification {zeta.max():g} beyond the q grid (zeta <= q_max/qL = {top:.6g})",
                        key="contact.zeta")


def zeta_shape(inp, psd) -> Shape:
    """Before anything computes: the magnifications ``[contact] zeta`` asks for (their number, and
    their values where known: approximate where the q grid is), checked against the q grid of the
    psd stage's shape ``psd``."""
    zeta = inp["contact.zeta"]
    if isinstance(zeta, str):
        q = psd.coords.get("q")
        return Shape(sizes={"zeta": int(psd.sizes["q"])}, coords={"zeta": q / q[0]} if q is not None else {},
                     keys={"zeta": "numerics.points_per_decade"},
                     approximate=("zeta",) if "q" in psd.approximate else ())
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    lo, hi = psd.ranges["q"]
    _check_zeta(zeta, hi / lo)
    check_magnifications(zeta, psd)
    return Shape(sizes={"zeta": int(zeta.size)}, coords={"zeta": zeta}, keys={"zeta": "contact.zeta"})


def check_magnifications(zeta: np.ndarray, psd) -> None:
    """A rough surface whose whole band lies outside the magnifications asked for (``psd``: the
    psd stage's Shape) is an error when nothing rough is left or when a coherence is swept or
    measured (it could change nothing), a SceneWarning otherwise; the message names the keys."""
    if "surface_bands" not in psd.attrs:
        return
    bands = {n: Band(*b) for n, b in json.loads(psd.attrs["surface_bands"]).items()}
    scope_check(bands, psd.ranges["q"][0], str(psd.attrs["q_reference_source"]), zeta,
                psd.attrs.get("coherence") in ("swept", "measured"), int(psd.attrs["rough_surfaces"]))


def scope_check(bands, qL: float, source: str, zeta, coupled: bool, n_rough: int) -> None:
    """Raise or warn when the magnifications ``zeta`` (a list, or "all") leave out the whole band
    of a rough surface (see :func:`check_magnifications`)."""
    if isinstance(zeta, str):
        return
    top = qL * float(np.max(zeta))
    lost = {n: b for n, b in bands.items() if not b.spans_grid and (b.lo > top * (1 + 1e-9) or b.hi < qL * (1 - 1e-9))}
    if not lost:
        return
    parts = [f"the {n}'s roughness ({b.key}: {wavenumber_text(b.lo)} to {wavenumber_text(b.hi)} 1/m) is outside "
             "that range" for n, b in lost.items()]
    need = max(b.lo for b in lost.values()) / qL
    fix = (f"Raise contact.zeta to at least {wavenumber_text(need)} (or \"all\") or set grid.q_min, the system's "
           f"lowest wavenumber 2 pi/L" if all(b.hi >= qL for b in lost.values()) else "Lower grid.q_min")
    where = (f"contact.zeta up to {np.max(zeta):g} sees q from qL = {wavenumber_text(qL)} to {wavenumber_text(top)} "
             f"1/m (qL: {source})")
    if len(lost) == n_rough:
        raise UserError(f"{where}; {'; '.join(parts)}: no roughness is left. {fix}", key="contact.zeta")
    if coupled:
        raise UserError(f"{where}; {'; '.join(parts)}, so interface.eta can change nothing: every result would be that "
                        f"of the other surface alone. {fix}", key="contact.zeta")
    warnings.warn(SceneWarning(f"{where}; {'; '.join(parts)}: the results are those of the other "
                               f"surface alone. {fix}"), stacklevel=2)
