"""Mean interfacial separation u(p) between an elastic solid and a rough substrate, and its
small-pressure law p = beta E* exp(-u/u0).

For two rough surfaces the combined PSD (:func:`roughcontact.physics.spectra.psd_combined`,
seed eq 52) replaces C(q) (seed eqs 54-60). See docs/theory.md, section "Separation";
Persson, J. Chem. Phys. 115, 3840 (2001); Yang & Persson, J. Phys.: Condens. Matter 20,
215214 (2008).

Numerics in one paragraph: eq 57 is written with the exponential integral,
u = (sqrt(pi) alpha / 2) \\int_{qL}^{zeta qL} q^2 C w E1((w p/E*)^2) dq, and the q integral is
done in the variable s = 1/w = (pi \\int_{qL}^q q'^3 C dq')^(1/2), for which
q^2 C w dq = (2/pi) ds / q(s): the 1/sqrt singularity of w at qL disappears and
u = (alpha / sqrt(pi)) \\int_0^{s(zeta qL)} E1((p / (E* s))^2) ds / q(s). The s axis is cut into
panels at the images of the q nodes, at s(zeta qL) and on a geometric grid (so the E1 factor,
which varies on the scale of ln s, is resolved at every pressure); each panel gets
Gauss-Legendre nodes, and q(s) there is the exact inverse of the piecewise power-law running
integral (:func:`roughcontact.physics.quadrature.inverse_cumulative_integral`). Below the
geometric grid (s < s_b = s_total 10^-depth) q(s) = q(0) and the E1 integral is done in
closed form.

Pipeline: :func:`separation_nodes` (once per PSD), then :func:`separation_moments` and
:func:`small_pressure_law` (u0, beta) and :func:`mean_separation` (u at every pressure).
"""

from __future__ import annotations

import functools

import numpy as np

from .inputs import require_pressure
from .layered import layered_spectrum, modulus_weight
from .quadrature import cumulative_integral, gauss_legendre_panels, integral_to, inverse_cumulative_integral
from .rows import row_chunks
from .special import erf, erfcx, exp1, exp1_fast

#: elements of one temporary of :func:`mean_separation` per chunk of rows (512 KiB: in L2 cache; the
#: fastest of 16 000-262 144 on the bands' 32 million nodes, docs/scale-out.md)
CHUNK = 65_536

#: eps = exp(\\int_0^inf 2x ln x exp(-x^2) dx) = exp(-gamma_Euler / 2) = 0.749306..., seed eq 28.
EPSILON = float(np.exp(-0.5 * np.euler_gamma))

#: The variants of eq 57 the kernels implement, by name, with what each one means.
REFINEMENTS = {
    "none": "Persson: alpha constant (eq 57)",
    "yang_persson": "Yang & Persson 2008: alpha -> alpha + 3 (1 - alpha) P(q, p')^2 inside the p' integral, "
                    "P = erf(w p'/E*)",
    "wang_mueser": "elastic-energy factor S = alpha - (2/9) P^2 + (11/9 - alpha) P^4 of Wang & Mueser 2017 (their "
                   "contact-area correction used in the energy, as Yang-Persson's is): alpha -> alpha - (2/3) P^2 "
                   "+ 5 (11/9 - alpha) P^4 inside the p' integral",
}


def energy_factor_terms(refinement: str, alpha: float) -> dict[int, float]:
    """d(P S)/dP = sum_k c_k P^k of the elastic-energy factor S(P) of each refinement:
    the coefficients {k: c_k} (dimensionless; c_0 = alpha). See :data:`REFINEMENTS`."""
    if refinement == "none":
        return {0: alpha}
    if refinement == "yang_persson":
        return {0: alpha, 2: 3.0 * (1.0 - alpha)}
    if refinement == "wang_mueser":
        return {0: alpha, 2: -2.0 / 3.0, 4: 5.0 * (11.0 / 9.0 - alpha)}
    raise ValueError(f"unknown refinement {refinement!r}; use one of {', '.join(REFINEMENTS)}")


def inverse_w(q, C):
    """s(q) = 1/w(q) at the grid nodes (dimensionless), seed eq 24 / 54.

    .. math:: s(q) = 1 / w(q) = \\Big(\\pi \\int_{q_L}^{q} q'^3 C(q')\\, dq'\\Big)^{1/2}

    s(qL) = 0 (w is infinite there).

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        Combined PSD (m^4).

    Returns
    -------
    array (..., n)
        s at each node (dimensionless).

    References
    ----------
    docs/theory.md, section "Separation"; Persson, J. Chem. Phys. 115, 3840 (2001).
    """
    q = np.asarray(q, dtype=float)
    return np.sqrt(np.pi * cumulative_integral(q, q**3 * np.asarray(C, dtype=float)))


def e1_integral(s, a):
    """F0(s) = \\int_0^s E1(a^2 / s'^2) ds' in closed form (same units as ``s``).

    .. math:: F_0(s) = s\\, E_1(a^2/s^2) - 2 s\\, e^{-a^2/s^2} + 2 \\sqrt{\\pi}\\, a\\,
              \\mathrm{erfc}(a/s)

    Written with the scaled functions exp(x) E1(x) and erfcx so that nothing overflows; for
    a/s > 6 (where the result is below 1e-15 s and suffers cancellation) it is set to 0.
    This is the tail [0, s_b] of eq 57 in the variable s, where q(s) is constant.

    Parameters
    ----------
    s : array
        Upper limit (dimensionless, like s = 1/w), >= 0.
    a : array
        p / E* (dimensionless), > 0, broadcast against ``s``.

    Returns
    -------
    array
        F0 (units of ``s``); inf where a = 0 and s > 0.

    References
    ----------
    docs/theory.md, section "Separation" (seed eq 57).
    """
    s, a = np.broadcast_arrays(np.asarray(s, dtype=float), np.asarray(a, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        z = a / s
        x = z * z
        # exp(x) E1(x) is finite for every x > 0; exp1 * exp overflows only where z > 6 (masked)
        scaled = np.exp(np.minimum(x, 700.0)) * exp1(x)
        value = s * np.exp(-x) * (scaled - 2.0 + 2.0 * np.sqrt(np.pi) * z * erfcx(z))
    small = (a == 0) & (s > 0)
    return np.where(small, np.inf, np.where((s > 0) & (z <= 6.0), value, 0.0))


@functools.lru_cache(maxsize=4)
def _power_table(k: int):
    """Nodes x_i and J_k(x_i) of J_k(x0) = \\int_{x0}^inf erf(x)^k exp(-x^2) dx / x (tabulated once)."""
    x = np.concatenate([[0.0], np.geomspace(1e-3, 7.0, 400)])
    nodes, weights = gauss_legendre_panels(x, 10)
    f = _power_integrand(nodes, k) * weights
    pieces = f.reshape(x.size - 1, 10).sum(-1)
    # J_k(7) <= \int_7^inf ... < exp(-49)/98 ~ 5e-24: taken as 0
    J = np.concatenate([np.cumsum(pieces[::-1])[::-1], [0.0]])
    return x, J


def _power_integrand(x, k):
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
        return np.where(x > 0, erf(x) ** k * np.exp(-x * x) / np.where(x > 0, x, 1.0), 0.0)


def power_J(x0, k: int = 2):
    """The terms P^k of a refinement of eq 57 (dimensionless), k >= 1.

    .. math:: J_k(x_0) = \\int_{x_0}^{\\infty} \\mathrm{erf}(x)^k\\, e^{-x^2}\\, \\frac{dx}{x}

    With x = w p'/E*, the p' integral of eq 57 with alpha -> sum_k c_k erf(x)^k
    (:func:`energy_factor_terms`) becomes (c_0/2) E1(x0^2) + sum_{k>0} c_k J_k(x0).
    J_2(0) = 0.40712493... Evaluated as a tabulated value at the next table node plus a
    10-point Gauss-Legendre integral from ``x0`` to that node (accurate to ~1e-15).

    Parameters
    ----------
    x0 : array
        Lower limit w p / E* (dimensionless), >= 0.
    k : int
        Power of erf.

    Returns
    -------
    array
        J_k(x0), shape of ``x0``.

    References
    ----------
    docs/theory.md, section "Separation"; Yang & Persson, J. Phys.: Condens. Matter 20, 215214 (2008).
    """
    x0 = np.asarray(x0, dtype=float)
    xt, Jt = _power_table(int(k))
    i = np.clip(np.searchsorted(xt, x0, side="right"), 1, xt.size - 1)
    top = xt[i]
    nodes, weights = gauss_legendre_panels(np.stack([np.minimum(x0, top), top], axis=-1), 10)
    local = (_power_integrand(nodes, int(k)) * weights).sum(-1)
    return np.where(x0 >= xt[-1], 0.0, Jt[i] + local)


def yang_persson_J(x0):
    """J(x0) = J_2(x0) of the Yang-Persson refinement (:func:`power_J` with k = 2)."""
    return power_J(x0, 2)


def _limits_on_grid(q, q_upper):
    """Index of the grid node each upper limit lies on (-1: between nodes)."""
    on_node = np.isclose(q_upper[:, None], q[None, :], rtol=1e-12, atol=0.0)
    return np.where(on_node.any(axis=1), on_node.argmax(axis=1), -1)


def separation_node_count(q, q_upper, panels_per_decade=4, order=4, depth=10.0):
    """Number of nodes :func:`separation_nodes` returns along its last axis (for dask).

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m).
    q_upper : array (m,)
        Upper limits zeta qL (1/m).
    panels_per_decade, order, depth
        As in :func:`separation_nodes`.
    """
    q = np.asarray(q, dtype=float)
    q_upper = np.atleast_1d(np.asarray(q_upper, dtype=float))
    n_breaks = q.size + int(np.sum(_limits_on_grid(q, q_upper) < 0)) + int(np.ceil(depth * panels_per_decade)) + 1
    return (n_breaks - 1) * int(order)


def separation_nodes(q, C, q_upper, panels_per_decade=4, order=4, depth=10.0, layer=None):
    """Quadrature nodes in s = 1/w for eq 57 and its small-pressure moments (eqs 59-60).

    Panels on the s axis end at the images s(q_i) of the grid nodes, at s(q_upper) and on a
    geometric grid of ``panels_per_decade`` per decade from s_b = s_total 10^-depth to s_total;
    each panel carries ``order`` Gauss-Legendre nodes. The integrand's factor q^2 C w dq becomes

    .. math:: q^2 C(q)\\, w(q)\\, dq = \\frac{2}{\\pi} \\frac{ds}{q(s)},

    q(s) the exact inverse of the power-law running integral of q^3 C.

    A coated solid (``layer``) has E_eff(q) in the elastic energy: eq 57 becomes
    u = (sqrt(pi) alpha / 2) \\int q^2 C E_eff w_l E1((w_l p)^2) dq with
    w_l = (pi \\int q^3 C E_eff^2 dq)^(-1/2). With C -> C (E_eff/E*)^2 (E* the substrate's,
    :func:`roughcontact.physics.layered.layered_spectrum`) s and the E1 argument are those above,
    and each node's weight carries the factor E*/E_eff(q(s)); the tail's 1/q_tail does too
    (``q_tail`` is returned times E_eff(q_tail)/E*). Every kernel that sums on these nodes
    (u, u0, beta, the stiffness) then holds for the coated solid, with E* the substrate's.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        Combined PSD (m^4), >= 0.
    q_upper : array (m,)
        Upper limits zeta qL (1/m), within the grid.
    panels_per_decade : int
        Geometric panels per decade of s.
    order : int
        Gauss-Legendre nodes per panel.
    depth : float
        Decades of s resolved by panels below s_total (closed form below).
    layer : tuple or None
        (thickness in m, E_layer in Pa, nu_layer, E_sub in Pa, nu_sub) of a coating
        (:data:`roughcontact.physics.layered.LAYER_FIELDS`); None: a homogeneous half-space.

    Returns
    -------
    s : array (..., K)
        Nodes in s (dimensionless, ascending).
    weight : array (..., K)
        Gauss-Legendre weight / q(s) (m): \\int_0^S f(s) ds / q(s) ~ sum(weight f(s)) + tail.
    count : array (..., m) of int
        Number of nodes below s(q_upper_j): the integral up to zeta_j sums the first count_j.
    s_upper : array (..., m)
        s(q_upper) = 1/w(zeta qL) (dimensionless).
    s_tail : array (..., m)
        min(s_b, s_upper): the tail [0, s_tail] is integrated with q = q_tail.
    q_tail : array (...)
        q(s = 0) (1/m): the lowest wavenumber with roughness (qL); with a layer, times
        E_eff/E* there.

    References
    ----------
    docs/theory.md, sections "Separation" (seed eqs 24, 54, 57) and "Coated (layered) solids".
    """
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    if layer is not None:
        C = layered_spectrum(q, C, layer)
    q_upper = np.atleast_1d(np.asarray(q_upper, dtype=float))
    y = q**3 * C
    s_nodes = inverse_w(q, C)
    s_upper = np.sqrt(np.pi * integral_to(q, y, q_upper))
    s_total = s_nodes[..., -1:]
    s_b = s_total * 10.0**-depth
    # zeta values on a grid node reuse that node's break; the others add one (same for every row)
    node_of = _limits_on_grid(q, q_upper)
    extra = np.flatnonzero(node_of < 0)
    n_geo = int(np.ceil(depth * panels_per_decade))
    geo = s_total * 10.0 ** (-depth * np.arange(n_geo, -1, -1) / n_geo)
    breaks = np.concatenate([np.broadcast_to(s_nodes, C.shape[:-1] + (q.size,)), s_upper[..., extra],
                             np.broadcast_to(geo, C.shape[:-1] + (n_geo + 1,))], axis=-1)
    breaks = np.maximum(breaks, s_b)
    order_idx = np.argsort(breaks, axis=-1, kind="stable")
    breaks = np.take_along_axis(breaks, order_idx, -1)
    rank = np.argsort(order_idx, axis=-1, kind="stable")  # where each original break went
    source = np.where(node_of >= 0, node_of, q.size + np.cumsum(node_of < 0) - 1)
    count = rank[..., source] * int(order)
    nodes, gl = gauss_legendre_panels(breaks, order)
    q_of_s = inverse_cumulative_integral(q, y, nodes * nodes / np.pi)
    weight = gl / q_of_s
    q_tail = inverse_cumulative_integral(q, y, np.zeros(C.shape[:-1] + (1,)))[..., 0]
    if layer is not None:
        weight = weight / modulus_weight(q_of_s, layer)
        q_tail = q_tail * modulus_weight(q_tail, layer)
    s_tail = np.minimum(s_b, s_upper)
    return nodes, weight, count, s_upper, s_tail, q_tail


def _cumulative_at(values, count):
    """sum(values[..., :count_j]) for each j: values (..., K), count (..., m)."""
    cum = np.cumsum(values, axis=-1)
    count = np.broadcast_to(count, values.shape[:-1] + count.shape[-1:])
    return np.where(count > 0, np.take_along_axis(cum, np.maximum(count - 1, 0), -1), 0.0)


def node_sum(values, count):
    """sum(values[..., :count_j]) for each upper limit j: a quantity on the nodes of
    :func:`separation_nodes` (..., K) summed up to each magnification (count (..., m))."""
    return _cumulative_at(values, count)


def separation_moments(s, weight, count, s_tail, q_tail):
    """The two moments of the small-pressure law up to each S = 1/w(zeta qL) (m), eqs 59-60.

    .. math:: M_0 = \\int_0^S \\frac{ds}{q(s)} = \\frac{\\pi}{2} \\int q^2 C w\\, dq, \\qquad
              M_1 = \\int_0^S \\ln s\\, \\frac{ds}{q(s)} = -\\frac{\\pi}{2} \\int q^2 C w \\ln w\\, dq

    Parameters
    ----------
    s, weight, count, s_tail, q_tail
        From :func:`separation_nodes`.

    Returns
    -------
    M0, M1 : arrays (..., m)
        In m.

    References
    ----------
    docs/theory.md, section "Separation" (seed eqs 59-60).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.where(s > 0, np.log(np.where(s > 0, s, 1.0)), 0.0)
        tail_log = np.where(s_tail > 0, s_tail * (np.log(np.where(s_tail > 0, s_tail, 1.0)) - 1.0), 0.0)
    qt = q_tail[..., None]
    M0 = _cumulative_at(weight, count) + s_tail / qt
    M1 = _cumulative_at(weight * logs, count) + tail_log / qt
    return M0, M1


def small_pressure_law(M0, M1, alpha, refinement="none"):
    """u0 (m) and beta (dimensionless) of p ~ beta E* exp(-u/u0), seed eqs 59-60.

    .. math:: u_0 = \\sqrt{\\pi}\\, \\alpha \\int q^2 C w\\, dq = \\frac{2 \\alpha}{\\sqrt{\\pi}} M_0,
              \\qquad \\beta = \\epsilon \\exp\\Big(-\\frac{\\int q^2 C w \\ln w\\, dq}
              {\\int q^2 C w\\, dq}\\Big) = \\epsilon\\, e^{M_1 / M_0}

    with eps = exp(-gamma_Euler/2) (eq 28). The seed prints eq 60 without the minus sign in
    the exponent; it is restored here. With a refinement the constants sum_k c_k J_k(0) of
    the extra terms add sum_k c_k J_k(0) / alpha to the exponent (Yang-Persson:
    3 (1 - alpha) J_2(0) / alpha; u0 is unchanged). beta is NaN where M0 = 0 (combined PSD identically zero: no
    roughness, u = 0).

    Parameters
    ----------
    M0, M1 : arrays
        From :func:`separation_moments` (m).
    alpha : float
        Persson's gamma in eq 57, 0 < alpha <= 1.
    refinement : {"none", "yang_persson", "wang_mueser"}
        See :data:`REFINEMENTS` and :func:`energy_factor_terms`.

    Returns
    -------
    u0 : array
        Decay length (m).
    beta : array
        Prefactor (dimensionless).

    References
    ----------
    docs/theory.md, section "Separation"; Persson, J. Chem. Phys. 115, 3840 (2001).
    """
    u0 = 2.0 * alpha / np.sqrt(np.pi) * M0
    terms = energy_factor_terms(refinement, alpha)
    shift = sum(c * float(power_J(0.0, k)) for k, c in terms.items() if k) / alpha
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = np.where(M0 > 0, EPSILON * np.exp(M1 / np.where(M0 > 0, M0, 1.0) + shift), np.nan)
    return u0, beta


def mean_separation(p, s, weight, count, s_tail, q_tail, *, E_star, alpha, refinement="none"):
    """Mean interfacial separation u(p) (m), seed eq 57 with the p' integral done in closed form.

    .. math:: u = \\frac{\\sqrt{\\pi}\\, \\alpha}{2} \\int_{q_L}^{\\zeta q_L} q^2 C w\\,
              E_1\\big((w p / E^*)^2\\big)\\, dq
              = \\frac{\\alpha}{\\sqrt{\\pi}} \\int_0^{1/w(\\zeta q_L)} E_1\\big((p / (E^* s))^2\\big)
              \\frac{ds}{q(s)}

    Refinements: (alpha/2) E1(x0^2) -> (alpha/2) E1(x0^2) + sum_k c_k J_k(x0), x0 = w p / E*
    (:func:`energy_factor_terms`, :func:`power_J`; Yang-Persson: c_2 = 3 (1 - alpha)).

    Parameters
    ----------
    p : array (...)
        Nominal pressure (Pa), > 0; broadcast against the leading dims of the nodes.
    s, weight, count, s_tail, q_tail
        From :func:`separation_nodes`.
    E_star : float
        Effective modulus (Pa).
    alpha : float
        Persson's gamma, 0 < alpha <= 1.
    refinement : {"none", "yang_persson", "wang_mueser"}
        See :data:`REFINEMENTS` and :func:`energy_factor_terms`.

    Returns
    -------
    array (..., m)
        u (m) at each upper limit zeta qL.

    References
    ----------
    docs/theory.md, section "Separation"; Persson, J. Chem. Phys. 115, 3840 (2001); Yang & Persson,
    J. Phys.: Condens. Matter 20, 215214 (2008).
    """
    a = require_pressure(p, positive=True)[..., None] / E_star
    s, weight, count, s_tail, q_tail = (np.asarray(x) for x in (s, weight, count, s_tail, q_tail))
    lead = np.broadcast_shapes(a.shape[:-1], s.shape[:-1], weight.shape[:-1], count.shape[:-1], s_tail.shape[:-1],
                               q_tail.shape)
    rows = [np.broadcast_to(x, lead + x.shape[-1:]) for x in (a, s, weight, count, s_tail)]
    rows.append(np.broadcast_to(q_tail, lead))
    terms = {k: c for k, c in energy_factor_terms(refinement, alpha).items() if k != 0}
    u = np.empty(lead + count.shape[-1:])
    for chunk in row_chunks(lead, s.shape[-1], CHUNK):  # a few rows at a time: every temporary stays in cache
        u[chunk] = _mean_separation_rows(*(x[chunk] for x in rows), alpha, terms)
    return u


def _mean_separation_rows(a, s, weight, count, s_tail, q_tail, alpha, terms):
    """:func:`mean_separation` on rows (rows, 1), (rows, K), (rows, K), (rows, m), (rows, m), (rows,)."""
    with np.errstate(divide="ignore", over="ignore", under="ignore"):
        z = a * np.where(s > 0, 1.0 / np.where(s > 0, s, 1.0), np.inf)
        kernel = exp1_fast(z * z)  # numpy E1: 3-4x scipy's exp1 here (the bands' draws multiply its calls)
    kernel *= weight
    body = _cumulative_at(kernel, count)
    tail = e1_integral(s_tail, a)
    u = alpha / np.sqrt(np.pi) * (body + tail / q_tail[..., None])
    for k, c in terms.items():
        with np.errstate(divide="ignore", invalid="ignore"):
            zt = np.where(s_tail > 0, a / np.where(s_tail > 0, s_tail, 1.0), np.inf)
        # on [0, s_tail] J_k(a/s) rises from 0 to J_k(a/s_tail): midpoint of the bounds, error
        # <= s_tail J_k(0) / 2 (s_tail <= 10^-depth of the s range)
        extra = _cumulative_at(weight * power_J(z, k), count) + 0.5 * s_tail * power_J(zt, k) / q_tail[..., None]
        u = u + 2.0 * c / np.sqrt(np.pi) * extra
    return u

