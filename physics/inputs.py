"""Checks of the physical inputs the kernels take: a kernel handed an impossible value (a
negative pressure, a coherence outside [-1, 1]) raises ValueError instead of returning a
negative area or spectrum. The stages validate the scene before any kernel runs, so these
checks guard direct (Python) use of the kernels.
"""

from __future__ import annotations

import numpy as np


def require_pressure(p, name: str = "p", positive: bool = False) -> np.ndarray:
    """``p`` as a float array; ValueError if any value is negative (or zero when ``positive``).

    Parameters
    ----------
    p : float or array
        A pressure or stress (Pa). NaN passes (it marks a missing case, not a wrong one).
    name : str
        The argument's name, for the message.
    positive : bool
        Refuse zero as well (a kernel that divides by the pressure).
    """
    p = np.asarray(p, dtype=float)
    bad = p <= 0 if positive else p < 0
    if np.any(bad):
        raise ValueError(f"{name} must be {'> 0' if positive else '>= 0'} (Pa), got {p[bad].flat[0]:g}")
    return p


def require_coherence(eta, name: str = "eta") -> np.ndarray:
    """``eta`` as a float array; ValueError if any value lies outside [-1, 1] (by more than rounding).

    Parameters
    ----------
    eta : float or array
        Coherence of two surfaces' roughness (dimensionless), seed eq 41.
    """
    eta = np.asarray(eta, dtype=float)
    bad = np.abs(eta) > 1.0 + 1e-12
    if np.any(bad):
        raise ValueError(f"{name} must lie in [-1, 1], got {eta[bad].flat[0]:g}")
    return np.clip(eta, -1.0, 1.0)


def require_nonnegative(x, name: str) -> np.ndarray:
    """``x`` as a float array; ValueError if any value is negative (e.g. Persson's G, a PSD)."""
    x = np.asarray(x, dtype=float)
    if np.any(x < 0):
        raise ValueError(f"{name} must be >= 0, got {x[x < 0].flat[0]:g}")
    return x
