"""The quadrature helper integrates power laws exactly and converges at second order otherwise."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from roughcontact.physics.quadrature import cumulative_integral, integral, integral_to, log_grid, loglog_interp


@given(s=st.floats(-6, 6), decades=st.floats(0.1, 8), ppd=st.integers(2, 60))
@settings(max_examples=60, deadline=None)
def test_power_law_is_integrated_exactly(s, decades, ppd):
    x = log_grid(1.0, 10**decades, ppd)
    exact = np.log(x[-1]) if abs(s + 1) < 1e-12 else np.expm1((s + 1) * np.log(x[-1])) / (s + 1)
    assert integral(x, x**s) == pytest.approx(exact, rel=1e-10)


def test_integral_to_partial_segments_are_exact_for_power_laws():
    x = log_grid(2e8, 4e10, 7)
    upper = np.array([2e8, 3.3e8, 1e9, 4e10])
    y = x**-2.6
    exact = (upper**-1.6 - x[0] ** -1.6) / -1.6
    assert np.allclose(integral_to(x, y, upper), exact, rtol=1e-12)


def test_knots_are_nodes_and_kinked_integrand_is_exact():
    x = log_grid(1.0, 1e3, 5, knots=[7.3])
    assert 7.3 in x
    y = np.where(x < 7.3, 1.0, (x / 7.3) ** -3.0)
    exact = (7.3 - 1.0) + 7.3 * (1 - (1e3 / 7.3) ** -2.0) / 2.0
    assert integral(x, y) == pytest.approx(exact, rel=1e-12)


def test_smooth_non_power_law_converges_at_second_order():
    f = lambda x: np.exp(-x) * x  # noqa: E731
    exact = np.exp(-0.01) * (1 + 0.01) - np.exp(-10.0) * 11.0  # int_0.01^10 x e^-x dx
    errors = [abs(integral(x, f(x)) - exact) for x in (log_grid(0.01, 10, n) for n in (10, 20, 40))]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8)


def test_zero_integrand_and_cumulative():
    x = log_grid(1, 100, 10)
    assert integral(x, np.zeros_like(x)) == 0.0
    c = cumulative_integral(x, np.ones_like(x))
    assert c[0] == 0.0 and np.allclose(c, x - 1.0)


def test_loglog_interp_reproduces_power_law():
    x = log_grid(1, 1e4, 3)
    xq = np.geomspace(1, 1e4, 37)
    assert np.allclose(loglog_interp(xq, x, 5 * x**-3.2), 5 * xq**-3.2, rtol=1e-12)
