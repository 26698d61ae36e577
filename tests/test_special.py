"""The numpy exponential integral of the separation kernel (physics/special.py: exp1_fast) against
scipy's exp1 over its whole range, and against bounds that hold for E1 itself."""

from __future__ import annotations

import numpy as np
import scipy.special as sp

from roughcontact.physics.special import exp1_fast


def test_e1_matches_scipy_over_the_whole_range():
    """Relative error below 1e-13 under x = 1 (economised series) and below 2e-8 from 1 to 700
    (Abramowitz & Stegun 5.1.56), from 1e-300 to where E1 underflows."""
    x = np.geomspace(1e-300, 700.0, 400_001)
    rel = np.abs(exp1_fast(x) / sp.exp1(x) - 1.0)
    assert rel[x < 1].max() < 1e-13
    assert rel[x >= 1].max() < 2e-8


def test_e1_limits_and_shapes():
    """E1(0) = inf, E1 = 0 from 750 on (below the smallest double), NaN stays NaN; any shape and
    memory layout in, the same shape out."""
    special = exp1_fast(np.array([0.0, 750.0, 1e4, np.inf, np.nan]))
    assert special[0] == np.inf and np.all(special[1:4] == 0.0) and np.isnan(special[4])
    grid = np.geomspace(1e-6, 20.0, 600).reshape(20, 30)
    assert np.array_equal(exp1_fast(grid.T), exp1_fast(grid).T)  # a transposed (non-contiguous) input
    assert exp1_fast(0.5).shape == () and exp1_fast([]).shape == (0,)
    assert float(exp1_fast(1.0)) == float(exp1_fast(np.nextafter(1.0, 0.0))) or abs(
        float(exp1_fast(1.0)) / float(exp1_fast(np.nextafter(1.0, 0.0))) - 1) < 2e-8  # continuous at the switch


def test_e1_within_its_classical_bounds():
    """Abramowitz & Stegun 5.1.20: e^-x ln(1 + 2/x) / 2 < E1(x) < e^-x ln(1 + 1/x) for x > 0, and
    5.1.11: E1(x) + gamma + ln x = x - x^2/4 + x^3/18 + O(x^4) as x -> 0 (to the rounding of ln x)."""
    x = np.geomspace(1e-8, 600.0, 20_001)
    e1 = exp1_fast(x)
    assert np.all(0.5 * np.exp(-x) * np.log1p(2.0 / x) < e1) and np.all(e1 < np.exp(-x) * np.log1p(1.0 / x))
    small = np.geomspace(1e-6, 1e-3, 7)
    ein = exp1_fast(small) + np.euler_gamma + np.log(small)
    np.testing.assert_allclose(ein, small - small**2 / 4 + small**3 / 18, rtol=1e-10, atol=1e-14)
