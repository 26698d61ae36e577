"""Non-adhesive contact: G(zeta), relative contact area A/A0(p, zeta) and the stress
distribution P(sigma; p, zeta).

Physics: ``equations.md`` section 2 (seed eqs 1-2, 16-20, 53); Persson, J. Chem. Phys. 115,
3840 (2001). For two rough surfaces the combined PSD of eq 52 replaces C(q) (eq 53).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import erf

from pipeline.errors import UserError
from pipeline.schema import Param, Section
from pipeline.stage import Figure, Stage, StageInput, Var, register, register_params, register_section

from ._plotting import curve_cases
from .quadrature import integral_to

# ----------------------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------------------


def effective_modulus(E, nu):
    """E* = E / (1 - nu^2) (Pa), seed eq 3."""
    return E / (1.0 - nu * nu)


def persson_G(q, C, q_upper, E_star):
    """G(zeta) = (pi/4) E*^2 \\int_{qL}^{zeta qL} q^3 C(q) dq  (Pa^2), seed eq 17 / eq 2.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q[0] = qL.
    C : array (..., n)
        PSD on the grid (m^4).
    q_upper : array (m,)
        Upper limits zeta qL (1/m), within the grid.
    E_star : float
        Effective modulus (Pa).

    Returns
    -------
    array (..., m)
        G in Pa^2.

    References
    ----------
    equations.md section 2; Persson, J. Chem. Phys. 115, 3840 (2001).
    """
    return (np.pi / 4.0) * E_star**2 * integral_to(q, np.asarray(q) ** 3 * C, q_upper)


def contact_area_ratio(p, G):
    """Relative contact area A/A0 = erf(p / (2 sqrt G)), seed eq 19 (dimensionless).

    G = 0 (no roughness at these scales) gives full contact, A/A0 = 1 for p > 0.
    Small p: A/A0 ~ p / sqrt(pi G) (eq 20).

    Parameters
    ----------
    p : array
        Nominal pressure (Pa), > 0.
    G : array
        Persson's G (Pa^2), >= 0.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        arg = np.where(G > 0, p / (2.0 * np.sqrt(np.where(G > 0, G, 1.0))), np.inf)
    return erf(arg)


def stress_distribution(sigma, p, G):
    """Stress distribution P(sigma) at nominal pressure p (1/Pa), seed eq 16 in its sinh form.

    P = (pi G)^-1/2 exp(-(sigma^2 + p^2)/(4G)) sinh(sigma p / (2G)), evaluated as
    (4 pi G)^-1/2 exp(-(sigma - p)^2/(4G)) (-expm1(-sigma p / G)), the same function without
    overflow of sinh or cancellation of the two Gaussians. Zero for sigma < 0. It integrates
    to A/A0 and its first moment is p.

    With G = 0 the distribution is a delta at sigma = p; on a grid it is returned as a
    spike of unit mass on the node nearest p (the grid spacing must be uniform there).

    Parameters
    ----------
    sigma : array (k,) or (..., k)
        Stress grid (Pa), uniform along the last axis; leading axes broadcast with p and G.
    p, G : arrays
        Nominal pressure (Pa) and Persson's G (Pa^2).

    Returns
    -------
    array (..., k)
    """
    sigma = np.asarray(sigma, dtype=float)
    p = np.asarray(p, dtype=float)[..., None]
    G = np.asarray(G, dtype=float)[..., None]
    Gs = np.where(G > 0, G, 1.0)
    with np.errstate(over="ignore", under="ignore"):
        smooth = np.exp(-((sigma - p) ** 2) / (4.0 * Gs)) * -np.expm1(-np.maximum(sigma, 0.0) * p / Gs)
        smooth = np.where(sigma >= 0, smooth / np.sqrt(4.0 * np.pi * Gs), 0.0)
    if np.all(G > 0):
        return smooth
    step = sigma[..., 1:2] - sigma[..., 0:1] if sigma.shape[-1] > 1 else np.ones_like(sigma[..., :1])
    distance = np.abs(sigma - p)
    nearest = distance == np.min(distance, axis=-1, keepdims=True)
    first = np.cumsum(nearest, axis=-1) == 1  # one node only, if two are equally near
    with np.errstate(divide="ignore"):
        spike = np.where(nearest & first, 1.0 / step, 0.0)
    return np.where(G > 0, smooth, spike)


def stress_distribution_adaptive(level, p, G, width):
    """P(sigma) on a grid adapted to each (p, G): sigma = level * (p + width sqrt(G)).

    Parameters
    ----------
    level : array (k,)
        Uniform nodes in [0, 1].
    p, G : arrays (broadcast together)
        Nominal pressure (Pa) and Persson's G (Pa^2).
    width : float
        How many sqrt(G) beyond p the grid reaches (the tail beyond has mass below
        erfc(width / 2)). With G = 0 the grid reaches 2 p.

    Returns
    -------
    (P, sigma) : arrays (..., k)
        The distribution (1/Pa, eq 16) and the stress at each node (Pa).
    """
    p, G = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(G, dtype=float))
    top = np.where(G > 0, p + width * np.sqrt(np.maximum(G, 0.0)), 2.0 * p)
    sigma = np.asarray(level, dtype=float) * top[..., None]
    return stress_distribution(sigma, p, G), sigma


# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------

register_section(
    Section(
        "material",
        (
            Param("E", "quantity", "Pa", lo=0.0, lo_open=True, doc="Young's modulus of the elastic solid"),
            Param("nu", "quantity", "", lo=-1.0, hi=0.5, lo_open=True, doc="Poisson ratio, -1 < nu <= 0.5"),
        ),
        doc="the elastic solid (the substrate is rigid)",
    )
)
register_section(
    Section(
        "load",
        (Param("p", "sweep", "Pa", lo=0.0, lo_open=True, doc="nominal pressure; a list or {from, to, num} is a sweep"),),
        doc="the nominal squeezing pressure",
    )
)
register_section(
    Section(
        "contact",
        (
            Param("zeta", "sweep", "", default="all", lo=1.0, choices=("all",),
                  doc="magnification(s) zeta = q/qL; 'all': every node of the q grid"),
        ),
        doc="the contact stage",
    )
)
register_params(
    "numerics",
    Param("sigma_points", "int", default=401, lo=3, doc="nodes of the stress grid of P(sigma)"),
    Param("sigma_width", "quantity", "", default=8.0, lo=1.0,
          doc="the stress grid of each (p, zeta, eta) reaches p + sigma_width sqrt(G)"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------


def _zeta_values(inp: StageInput, q: np.ndarray) -> np.ndarray:
    zeta = inp["contact.zeta"]
    if isinstance(zeta, str):
        return q / q[0]
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    top = q[-1] / q[0]
    if np.any(zeta > top * (1 + 1e-12)):
        raise UserError(f"magnification {zeta.max():g} beyond the q grid (zeta <= q_max/qL = {top:.6g})", key="contact.zeta")
    return zeta


def compute_contact(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = float(effective_modulus(inp["material.E"], inp["material.nu"]))
    zeta_values = _zeta_values(inp, q)
    zeta = xr.DataArray(zeta_values, dims=("zeta",), attrs={"units": "1", "long_name": "magnification zeta = q/qL"})
    G = xr.apply_ufunc(
        persson_G, psd["q"], psd["psd_combined"], zeta * q[0], E_star,
        input_core_dims=[["q"], ["q"], ["zeta"], []], output_core_dims=[["zeta"]],
        dask="parallelized", output_dtypes=[float],
    ).assign_coords(zeta=zeta)
    G.attrs = {"units": "Pa^2", "long_name": "Persson's G(zeta) = (pi/4) E*^2 int_qL^(zeta qL) q^3 C dq (eq 17)"}
    p = inp.sweep("p", inp["load.p"], "Pa", "nominal pressure")
    area = xr.apply_ufunc(contact_area_ratio, p, G, dask="parallelized", output_dtypes=[float])
    area.attrs = {"units": "1", "long_name": "relative contact area A/A0 = erf(p / 2 sqrt G) (eq 19)"}
    ds = xr.Dataset({"G": G, "contact_area_ratio": area})
    ds["E_star"] = xr.DataArray(E_star, attrs={"units": "Pa", "long_name": "effective modulus E* = E/(1 - nu^2)"})
    if "stress_distribution" in inp.wanted:
        level = xr.DataArray(np.linspace(0.0, 1.0, inp["numerics.sigma_points"]), dims=("stress_level",),
                             attrs={"units": "1", "long_name": "node of the stress grid, sigma / (p + sigma_width sqrt(G))"})
        dist, sigma = xr.apply_ufunc(
            stress_distribution_adaptive, level, p, G, inp["numerics.sigma_width"],
            input_core_dims=[["stress_level"], [], [], []], output_core_dims=[["stress_level"], ["stress_level"]],
            dask="parallelized", output_dtypes=[float, float],
        )
        sigma.attrs = {"units": "Pa", "long_name": "local normal stress sigma at each node of the stress grid"}
        dist.attrs = {"units": "1/Pa", "long_name": "stress distribution P(sigma; p, zeta) (eq 16)"}
        ds["stress_distribution"] = dist
        ds = ds.assign_coords(stress_level=level, sigma=sigma)
    return ds


# ----------------------------------------------------------------------------------------
# Figures (seed Figs 3 and 4)
# ----------------------------------------------------------------------------------------


def _cases(results):
    return curve_cases(results, "contact")


def _at_zeta(ds, zeta):
    return ds.sel(zeta=zeta, method="nearest") if "zeta" in ds.dims else ds


def figure_contact_area(results, zeta=4.0):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for (label, ds), marker in zip(_cases(results), "osx^dv"):
        ds = _at_zeta(ds, zeta)
        p = ds["p"].values / float(ds["E_star"])
        ax.semilogx(p, ds["contact_area_ratio"].values, marker=marker, markersize=3, label=label)
    ax.set_xlabel("p / E*")
    ax.set_ylabel("A / A0")
    ax.set_title(f"Relative contact area, zeta = {zeta:g} (seed Fig. 3)")
    ax.set_ylim(0, 1.02)
    ax.legend()
    fig.tight_layout()
    return fig


def figure_stress_distribution(results, zeta=4.0):
    """Seed Fig. 4: P(sigma) at three pressures (where the reference curve's A/A0 is about
    0.1, 0.3 and 0.6), one curve per case; a delta (no roughness) is drawn as a vertical line."""
    import matplotlib.pyplot as plt

    cases = _cases(results)
    base = _at_zeta(results["base"]["contact"], zeta)
    if "stress_distribution" not in base:
        raise UserError("the scene does not ask for 'stress_distribution' (add it to outputs.variables)",
                        key="outputs.variables")
    E_star = float(base["E_star"])
    ref = _at_zeta(cases[0][1], zeta)["contact_area_ratio"]
    ref = ref.isel({d: 0 for d in ref.dims if d != "p"})
    picks = sorted({float(ref["p"][int(np.argmin(np.abs(ref.values - a)))]) for a in (0.1, 0.3, 0.6)})
    fig, axes = plt.subplots(1, len(picks), figsize=(4.2 * len(picks), 3.8), squeeze=False)
    for ax, p in zip(axes[0], picks):
        right = 0.0
        for (label, ds), style in zip(cases, ("-", "--", ":", "-.", "-", "--")):
            ds = _at_zeta(ds, zeta)
            d = ds["stress_distribution"].sel(p=p, method="nearest")
            G = float(ds["G"])
            if "p" in d["sigma"].dims:
                d = d.assign_coords(sigma=d["sigma"])
            if G > 0:
                line, = ax.plot(d["sigma"].values / E_star, d.values * E_star, style, label=label)
                right = max(right, (p + 5.0 * np.sqrt(G)) / E_star)
            else:
                ax.axvline(p / E_star, linestyle=style, color="0.3", label=f"{label} (full contact: delta)")
        ax.set_xlim(0, right or 2 * p / E_star)
        ax.set_xlabel("sigma / E*")
        ax.set_title(f"p / E* = {p / E_star:.3g}")
    axes[0][0].set_ylabel("P(sigma) E*")
    axes[0][-1].legend(fontsize=8)
    fig.suptitle(f"Stress distribution, zeta = {zeta:g} (seed Fig. 4)")
    fig.tight_layout()
    return fig


def _point_bytes(params, wanted, upstream) -> int:
    """Working memory per sweep point: a few float64 temporaries, times the stress grid when
    P(sigma) is asked for, times the q grid when zeta = "all" adds a dimension of that size."""
    per = 8 * 4 * (params["numerics.sigma_points"] if "stress_distribution" in wanted else 2)
    if isinstance(params["contact.zeta"], str) and "psd" in upstream:
        per *= upstream["psd"].sizes["q"]
    return per


register(
    Stage(
        name="contact",
        version="1",
        compute=compute_contact,
        requires=("psd",),
        params=("material.E", "material.nu", "load.p", "contact.zeta", "numerics.sigma_points", "numerics.sigma_width"),
        outputs={
            "G": Var("Pa^2", "Persson's G(zeta) (eq 17)"),
            "contact_area_ratio": Var("1", "relative contact area A/A0 (eq 19)"),
            "E_star": Var("Pa", "effective modulus E*"),
            "stress_distribution": Var("1/Pa", "stress distribution P(sigma; p, zeta) (eq 16)", optional=True),
        },
        coords={
            "zeta": Var("1", "magnification"),
            "p": Var("Pa", "nominal pressure"),
            "sigma": Var("Pa", "local normal stress at each node of the stress grid"),
            "stress_level": Var("1", "node of the stress grid, sigma / (p + sigma_width sqrt(G))"),
        },
        figures=(
            Figure("fig3_contact_area", "A/A0 against p/E* (seed Fig. 3)", ("contact",), figure_contact_area),
            Figure("fig4_stress_distribution", "P(sigma) (seed Fig. 4)", ("contact",), figure_stress_distribution,
                   outputs=("stress_distribution",)),
        ),
        doc="G(zeta), A/A0(p, zeta, eta) and optionally P(sigma; p, zeta, eta).",
        point_bytes=_point_bytes,
        main_outputs=("contact_area_ratio",),
        tolerance=1e-4,
    )
)
