"""Mean interfacial separation u(p, zeta, eta) between the elastic solid and the substrate,
and its small-pressure law p = beta E* exp(-u/u0).

Physics: ``equations.md`` section 3 (seed eqs 21-28 and 54-60); Persson, J. Chem. Phys. 115,
3840 (2001); Yang & Persson, J. Phys.: Condens. Matter 20, 215214 (2008). For two rough
surfaces the combined PSD of eq 52 replaces C(q) (eqs 54-60).

Numerics in one paragraph: eq 57 is written with the exponential integral,
u = (sqrt(pi) alpha / 2) \\int_{qL}^{zeta qL} q^2 C w E1((w p/E*)^2) dq, and the q integral is
done in the variable s = 1/w = (pi \\int_{qL}^q q'^3 C dq')^(1/2), for which
q^2 C w dq = (2/pi) ds / q(s): the 1/sqrt singularity of w at qL disappears and
u = (alpha / sqrt(pi)) \\int_0^{s(zeta qL)} E1((p / (E* s))^2) ds / q(s). The s axis is cut into
panels at the images of the q nodes, at s(zeta qL) and on a geometric grid (so the E1 factor,
which varies on the scale of ln s, is resolved at every pressure); each panel gets
Gauss-Legendre nodes, and q(s) there is the exact inverse of the piecewise power-law running
integral (:func:`stages.quadrature.inverse_cumulative_integral`). Below the geometric grid
(s < s_b = s_total 10^-depth) q(s) = q(0) and the E1 integral is done in closed form.
"""

from __future__ import annotations

import functools

import numpy as np
import xarray as xr
from scipy.special import erf, erfcx, exp1

from roughcontact.stage import UserError
from roughcontact.stage import Param, Section
from roughcontact.stage import Figure, Stage, StageInput, Var, register, register_params, register_section

from roughcontact.physics.contact import effective_modulus

from .shared import zeta_values as _zeta_values
from .figures.common import curve_cases
from roughcontact.physics.quadrature import (
    cumulative_integral,
    gauss_legendre_panels,
    integral_to,
    inverse_cumulative_integral,
)

#: eps = exp(\\int_0^inf 2x ln x exp(-x^2) dx) = exp(-gamma_Euler / 2), seed eq 28.
EPSILON = float(np.exp(-0.5 * np.euler_gamma))

REFINEMENTS = {
    "none": "Persson: alpha constant (eq 57)",
    "yang_persson": "Yang & Persson 2008: alpha -> alpha + 3 (1 - alpha) P(q, p')^2 inside the p' integral, "
                    "P = erf(w p'/E*)",
}

# ----------------------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------------------


def inverse_w(q, C):
    """s(q) = 1/w(q) = (pi \\int_{qL}^{q} q'^3 C(q') dq')^(1/2) at the grid nodes (dimensionless),
    seed eq 24 / 54. s(qL) = 0 (w is infinite there).

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        Combined PSD (m^4).
    """
    q = np.asarray(q, dtype=float)
    return np.sqrt(np.pi * cumulative_integral(q, q**3 * np.asarray(C, dtype=float)))


def e1_integral(s, a):
    """F0(s) = \\int_0^s E1(a^2 / s'^2) ds' in closed form (same units as s).

    F0 = s E1(a^2/s^2) - 2 s exp(-a^2/s^2) + 2 sqrt(pi) a erfc(a/s), written with the scaled
    functions exp(x) E1(x) and erfcx so that nothing overflows; for a/s > 6 (where the
    result is below 1e-15 s and suffers cancellation) it is set to 0.

    Parameters
    ----------
    s : array
        Upper limit (>= 0).
    a : array
        p / E* (> 0), broadcast against ``s``.
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


@functools.lru_cache(maxsize=1)
def _yang_persson_table():
    """Nodes x_k and J(x_k) of J(x0) = \\int_{x0}^inf erf(x)^2 exp(-x^2) dx / x (tabulated once)."""
    x = np.concatenate([[0.0], np.geomspace(1e-3, 7.0, 400)])
    nodes, weights = gauss_legendre_panels(x, 10)
    f = _yp_integrand(nodes) * weights
    pieces = f.reshape(x.size - 1, 10).sum(-1)
    # J(7) = \int_7^inf ... < exp(-49)/98 ~ 5e-24: taken as 0
    J = np.concatenate([np.cumsum(pieces[::-1])[::-1], [0.0]])
    return x, J


def _yp_integrand(x):
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
        return np.where(x > 0, erf(x) ** 2 * np.exp(-x * x) / np.where(x > 0, x, 1.0), 0.0)


def yang_persson_J(x0):
    """J(x0) = \\int_{x0}^inf erf(x)^2 exp(-x^2) dx / x (dimensionless), x0 >= 0.

    The extra term of the Yang-Persson refinement: with x = w p'/E*, the p' integral of eq 57
    with alpha -> alpha + 3 (1 - alpha) erf(x)^2 becomes (alpha/2) E1(x0^2) + 3 (1 - alpha) J(x0).
    J(0) = 0.40712493... Evaluated as a tabulated value at the next table node plus a
    10-point Gauss-Legendre integral from ``x0`` to that node (accurate to ~1e-15).
    """
    x0 = np.asarray(x0, dtype=float)
    xt, Jt = _yang_persson_table()
    k = np.clip(np.searchsorted(xt, x0, side="right"), 1, xt.size - 1)
    top = xt[k]
    nodes, weights = gauss_legendre_panels(np.stack([np.minimum(x0, top), top], axis=-1), 10)
    local = (_yp_integrand(nodes) * weights).sum(-1)
    return np.where(x0 >= xt[-1], 0.0, Jt[k] + local)


def separation_nodes(q, C, q_upper, panels_per_decade=4, order=4, depth=10.0):
    """Quadrature nodes in s = 1/w for eq 57 and its small-pressure moments.

    Panels on the s axis end at the images s(q_i) of the grid nodes, at s(q_upper) and on a
    geometric grid of ``panels_per_decade`` per decade from s_b = s_total 10^-depth to s_total;
    each panel carries ``order`` Gauss-Legendre nodes. The integrand's factor q^2 C w dq becomes
    (2/pi) ds / q(s), q(s) the exact inverse of the power-law running integral of q^3 C.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        Combined PSD (m^4), >= 0.
    q_upper : array (m,)
        Upper limits zeta qL (1/m), within the grid.

    Returns
    -------
    s : array (..., K)
        Nodes in s (ascending).
    weight : array (..., K)
        Gauss-Legendre weight / q(s) (m): \\int_0^S f(s) ds / q(s) ~ sum(weight f(s)) + tail.
    count : array (..., m) of int
        Number of nodes below s(q_upper_j): the integral up to zeta_j sums the first count_j.
    s_upper : array (..., m)
        s(q_upper) = 1/w(zeta qL).
    s_tail : array (..., m)
        min(s_b, s_upper): the tail [0, s_tail] is integrated with q = q_tail.
    q_tail : array (...)
        q(s = 0): the lowest wavenumber with roughness (qL).
    """
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    q_upper = np.atleast_1d(np.asarray(q_upper, dtype=float))
    y = q**3 * C
    s_nodes = inverse_w(q, C)
    s_upper = np.sqrt(np.pi * integral_to(q, y, q_upper))
    s_total = s_nodes[..., -1:]
    s_b = s_total * 10.0**-depth
    # zeta values on a grid node reuse that node's break; the others add one (same for every row)
    on_node = np.isclose(q_upper[:, None], q[None, :], rtol=1e-12, atol=0.0)
    node_of = np.where(on_node.any(axis=1), on_node.argmax(axis=1), -1)
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
    s_tail = np.minimum(s_b, s_upper)
    return nodes, weight, count, s_upper, s_tail, q_tail


def _cumulative_at(values, count):
    """sum(values[..., :count_j]) for each j: values (..., K), count (..., m)."""
    cum = np.concatenate([np.zeros(values.shape[:-1] + (1,)), np.cumsum(values, axis=-1)], axis=-1)
    count = np.broadcast_to(count, values.shape[:-1] + count.shape[-1:])
    return np.take_along_axis(cum, count, -1)


def separation_moments(s, weight, count, s_tail, q_tail):
    """M0 = \\int_0^S ds/q(s) and M1 = \\int_0^S ln(s) ds/q(s) (m) up to each S = 1/w(zeta qL).

    In q: M0 = (pi/2) \\int q^2 C w dq and M1 = -(pi/2) \\int q^2 C w ln w dq (eqs 59-60).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.where(s > 0, np.log(np.where(s > 0, s, 1.0)), 0.0)
        tail_log = np.where(s_tail > 0, s_tail * (np.log(np.where(s_tail > 0, s_tail, 1.0)) - 1.0), 0.0)
    qt = q_tail[..., None]
    M0 = _cumulative_at(weight, count) + s_tail / qt
    M1 = _cumulative_at(weight * logs, count) + tail_log / qt
    return M0, M1


def small_pressure_law(M0, M1, alpha, refinement="none"):
    """u0 (m) and beta (1) of p ~ beta E* exp(-u/u0), seed eqs 59-60 (sign of eq 60 restored).

    u0 = sqrt(pi) alpha \\int q^2 C w dq = (2 alpha / sqrt(pi)) M0;
    beta = eps exp(-\\int q^2 C w ln w dq / \\int q^2 C w dq) = eps exp(M1 / M0), eps = exp(-gamma/2).
    With the Yang-Persson refinement the constant 3 (1 - alpha) J(0) of the extra term adds
    3 (1 - alpha) J(0) / alpha to the exponent (u0 is unchanged).
    beta is NaN where M0 = 0 (combined PSD identically zero: no roughness, u = 0).
    """
    u0 = 2.0 * alpha / np.sqrt(np.pi) * M0
    shift = 3.0 * (1.0 - alpha) * float(yang_persson_J(0.0)) / alpha if refinement == "yang_persson" else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = np.where(M0 > 0, EPSILON * np.exp(M1 / np.where(M0 > 0, M0, 1.0) + shift), np.nan)
    return u0, beta


def mean_separation(p, s, weight, count, s_tail, q_tail, *, E_star, alpha, refinement="none"):
    """Mean interfacial separation u(p) (m), seed eq 57 with the p' integral done in closed form.

    u = (sqrt(pi) alpha / 2) \\int_{qL}^{zeta qL} q^2 C w E1((w p / E*)^2) dq
      = (alpha / sqrt(pi)) \\int_0^{1/w(zeta qL)} E1((p / (E* s))^2) ds / q(s).
    Yang-Persson: (alpha/2) E1(x0^2) -> (alpha/2) E1(x0^2) + 3 (1 - alpha) J(x0), x0 = w p / E*.

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
    refinement : {"none", "yang_persson"}

    Returns
    -------
    array (..., m)
        u at each upper limit zeta qL.

    References
    ----------
    equations.md section 3; Persson J. Chem. Phys. 115, 3840 (2001); Yang & Persson,
    J. Phys.: Condens. Matter 20, 215214 (2008).
    """
    a = np.asarray(p, dtype=float)[..., None] / E_star
    with np.errstate(divide="ignore", over="ignore", under="ignore"):
        z = np.where(s > 0, a / np.where(s > 0, s, 1.0), np.inf)
        x = z * z
        kernel = np.where(x < 750.0, exp1(np.minimum(x, 750.0)), 0.0)
    body = _cumulative_at(weight * kernel, count)
    tail = e1_integral(s_tail, a)
    u = alpha / np.sqrt(np.pi) * (body + tail / q_tail[..., None])
    if refinement == "yang_persson":
        with np.errstate(divide="ignore", invalid="ignore"):
            zt = np.where(s_tail > 0, a / np.where(s_tail > 0, s_tail, 1.0), np.inf)
        # on [0, s_tail] J(a/s) rises from 0 to J(a/s_tail): midpoint of the bounds, error
        # <= s_tail J(0) / 2 (s_tail <= 10^-depth of the s range)
        extra = _cumulative_at(weight * yang_persson_J(z), count) + 0.5 * s_tail * yang_persson_J(zt) / q_tail[..., None]
        u = u + 6.0 * (1.0 - alpha) / np.sqrt(np.pi) * extra
    return u


# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------

register_section(
    Section(
        "separation",
        (
            Param("alpha", "quantity", "", default=0.45, lo=0.0, hi=1.0, lo_open=True,
                  doc="Persson's gamma in eq 57 (0 < alpha <= 1; ~0.4-0.5)"),
            Param("refinement", "choice", default="none", choices=tuple(REFINEMENTS),
                  doc="'none' (eq 57) or 'yang_persson' (alpha -> alpha + 3(1 - alpha) P^2)"),
        ),
        doc="the mean interfacial separation stage",
    )
)
register_params(
    "numerics",
    Param("separation_panels_per_decade", "int", default=2, lo=1,
          presets={"fast": 1, "accurate": 4}, ladder=(1, 2, 2, 3, 4, 6, 8, 16),
          doc="geometric panels per decade of s = 1/w in the separation integral"),
    Param("separation_gauss_points", "int", default=3, lo=1, hi=64,
          presets={"fast": 2, "accurate": 4}, ladder=(2, 2, 3, 3, 4, 4, 6, 10),
          doc="Gauss-Legendre nodes per panel in the separation integral"),
    Param("separation_depth", "quantity", "", default=10.0, lo=1.0, hi=100.0,
          doc="decades of s below 1/w(q_max) resolved by panels (closed form below)"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------

_NUMERICS = ("numerics.separation_panels_per_decade", "numerics.separation_gauss_points", "numerics.separation_depth")


def compute_separation(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = float(effective_modulus(inp["material.E"], inp["material.nu"]))
    alpha = float(inp["separation.alpha"])
    refinement = inp["separation.refinement"]
    if not 0.0 < alpha <= 1.0:  # the schema checks this; kernels called directly rely on it too
        raise UserError(f"must be in (0, 1], got {alpha:g}", key="separation.alpha")
    p_values = np.atleast_1d(np.asarray(inp["load.p"], dtype=float))
    if np.any(~(p_values > 0)):
        raise UserError("pressures must be > 0", key="load.p")
    zeta_values = _zeta_values(inp, q)
    zeta = xr.DataArray(zeta_values, dims=("zeta",), attrs={"units": "1", "long_name": "magnification zeta = q/qL"})
    q_upper = zeta_values * q[0]
    ppd = inp["numerics.separation_panels_per_decade"]
    order = inp["numerics.separation_gauss_points"]
    depth = float(inp["numerics.separation_depth"])
    nodes_dim = "separation_node"
    n_nodes = _node_count(q, q_upper, ppd, order, depth)
    s, weight, count, s_upper, s_tail, q_tail = xr.apply_ufunc(
        separation_nodes, psd["q"], psd["psd_combined"], q_upper,
        kwargs={"panels_per_decade": ppd, "order": order, "depth": depth},
        input_core_dims=[["q"], ["q"], ["zeta"]],
        output_core_dims=[[nodes_dim], [nodes_dim], ["zeta"], ["zeta"], ["zeta"], []],
        dask="parallelized", output_dtypes=[float, float, int, float, float, float],
        dask_gufunc_kwargs={"output_sizes": {nodes_dim: n_nodes, "zeta": zeta_values.size}},
    )
    M0, M1 = xr.apply_ufunc(
        separation_moments, s, weight, count, s_tail, q_tail,
        input_core_dims=[[nodes_dim], [nodes_dim], ["zeta"], ["zeta"], []],
        output_core_dims=[["zeta"], ["zeta"]], dask="parallelized", output_dtypes=[float, float],
    )
    u0, beta = xr.apply_ufunc(
        small_pressure_law, M0, M1, kwargs={"alpha": alpha, "refinement": refinement},
        output_core_dims=[["zeta"], ["zeta"]], input_core_dims=[["zeta"], ["zeta"]],
        dask="parallelized", output_dtypes=[float, float],
    )
    p = inp.sweep("p", inp["load.p"], "Pa", "nominal pressure")
    u = xr.apply_ufunc(
        mean_separation, p, s, weight, count, s_tail, q_tail,
        kwargs={"E_star": E_star, "alpha": alpha, "refinement": refinement},
        input_core_dims=[[], [nodes_dim], [nodes_dim], ["zeta"], ["zeta"], []],
        output_core_dims=[["zeta"]], dask="parallelized", output_dtypes=[float],
    )
    numerics = {"separation_panels_per_decade": ppd, "separation_gauss_points": order, "separation_depth": depth}
    u = u.assign_coords(zeta=zeta).transpose(..., "zeta", *(("p",) if "p" in u.dims else ()))
    u.attrs = {
        "units": "m",
        "long_name": "mean interfacial separation u(p) (eq 57)",
        "formula": "u = (sqrt(pi) alpha / 2) int_qL^(zeta qL) q^2 C w E1((w p / E*)^2) dq",
        "alpha": alpha,
        "refinement": refinement,
        "refinement_description": REFINEMENTS[refinement],
        "method": "s = 1/w substitution (q^2 C w dq = (2/pi) ds / q(s)), Gauss-Legendre panels; closed-form tail",
        **numerics,
    }
    u0 = u0.assign_coords(zeta=zeta)
    u0.attrs = {"units": "m", "long_name": "decay length u0 of the small-pressure law p = beta E* exp(-u/u0) (eq 59)",
                "formula": "u0 = sqrt(pi) alpha int q^2 C w dq", "alpha": alpha}
    beta = beta.assign_coords(zeta=zeta)
    beta.attrs = {
        "units": "1",
        "long_name": "prefactor beta of the small-pressure law p = beta E* exp(-u/u0) (eq 60)",
        "formula": "beta = eps exp(-int q^2 C w ln w dq / int q^2 C w dq), eps = exp(-gamma_Euler/2)"
                   + (" times exp(3 (1 - alpha) J(0) / alpha), J(0) = %.10f (Yang-Persson)" % float(yang_persson_J(0.0))
                      if refinement == "yang_persson" else ""),
        "epsilon": EPSILON,
        "sign_note": "eq 60 of the seed lost the minus sign in the exponent; restored here (equations.md section 3)",
        "nan_reason": "beta is NaN where the combined PSD is identically zero up to zeta qL (e.g. eta = 1 with "
                      "identical surfaces): then u = 0 and u0 = 0 at every pressure and p = beta E* exp(-u/u0) "
                      "has no meaning",
    }
    ds = xr.Dataset({"mean_separation": u, "separation_u0": u0, "separation_beta": beta})
    ds["E_star"] = xr.DataArray(E_star, attrs={"units": "Pa", "long_name": "effective modulus E* = E/(1 - nu^2)"})
    ds.attrs.update({"separation_alpha": alpha, "separation_refinement": refinement, "separation_epsilon": EPSILON})
    return ds


def _node_count(q, q_upper, ppd, order, depth):
    on_node = np.isclose(q_upper[:, None], q[None, :], rtol=1e-12, atol=0.0).any(axis=1)
    n_breaks = q.size + int(np.sum(~on_node)) + int(np.ceil(depth * ppd)) + 1
    return (n_breaks - 1) * int(order)


# ----------------------------------------------------------------------------------------
# Figure (seed Fig. 5)
# ----------------------------------------------------------------------------------------


def _cases(results):
    return curve_cases(results, "separation")


def figure_separation(results, zeta=4.0):
    """log10(p/E*) against u (seed Fig. 5) at zeta = 4 (nearest available magnification), with
    the small-pressure law u = u0 ln(beta E*/p) (eqs 58-60) as thin dashed lines."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    styles = [dict(marker="o", markersize=3, linestyle="-", linewidth=0.8), dict(marker="*", markersize=5),
              dict(linestyle="-", linewidth=2), dict(linestyle=":", linewidth=2), dict(linestyle="--"),
              dict(linestyle="-.")]
    zeta_used = None
    for i, ((label, ds), style) in enumerate(zip(_cases(results), styles)):
        if "zeta" in ds.dims:
            ds = ds.sel(zeta=zeta, method="nearest")
        zeta_used = float(ds["zeta"])
        u = np.atleast_1d(ds["mean_separation"].values)
        p = np.atleast_1d(ds["p"].values) / float(ds["E_star"])
        label = label.replace("+0", "0")
        if np.all(u == 0):
            label += " (u = 0: no combined roughness)"
        if "marker" in style:
            style = dict(style, markevery=max(1, u.size // 25))
        line, = ax.plot(u * 1e9, np.log10(p), label=label, **style)
        u0, beta = float(ds["separation_u0"]), float(ds["separation_beta"])
        if u0 > 0 and np.isfinite(beta):
            law = u0 * np.log(beta / p)
            keep = law > 0
            ax.plot(law[keep] * 1e9, np.log10(p[keep]), "--", color=line.get_color(), linewidth=0.7, alpha=0.7,
                    label="u0 ln(beta E*/p) (eqs 58-60)" if i == 0 else None)
    ax.set_xlabel("mean separation u (nm)")
    ax.set_ylabel("log10(p / E*)")
    ax.set_xlim(left=-0.03 * ax.get_xlim()[1])
    ax.set_title(f"Interfacial separation, zeta = {zeta_used:g} (seed Fig. 5)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


register(
    Stage(
        name="separation",
        version="1",
        compute=compute_separation,
        requires=("psd",),
        params=("material.E", "material.nu", "load.p", "contact.zeta", "separation.alpha", "separation.refinement",
                *_NUMERICS),
        outputs={
            "mean_separation": Var("m", "mean interfacial separation u(p) (eq 57)"),
            "separation_u0": Var("m", "decay length u0 of p = beta E* exp(-u/u0) (eq 59)"),
            "separation_beta": Var("1", "prefactor beta of p = beta E* exp(-u/u0) (eq 60)"),
            "E_star": Var("Pa", "effective modulus E*"),
        },
        coords={},
        figures=(Figure("fig5_separation", "log10(p/E*) against u (seed Fig. 5)", ("separation",), figure_separation),),
        doc="Mean interfacial separation u(p, zeta, eta) (eq 57) and its small-pressure law u0, beta (eqs 59-60).",
        main_outputs=("mean_separation",),
        tolerance=1e-4,
    )
)
