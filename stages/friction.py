"""Hysteretic rubber friction mu(v) and the relative contact area A/A0(v) while sliding, for an
elastic (viscoelastic) solid and a hard substrate that may both be rough.

Physics: ``equations.md`` section 6 (seed eqs 29-32 for one rough surface, 61-62 for two,
with the combined PSD C(q, eta) of eq 52); Persson, J. Chem. Phys. 115, 3840 (2001).
With omega = q v cos(phi) (the seed's eq 30 is misprinted) and k = 1 / ((1 - nu^2) sigma0):

    mu(v)   = 2 k \\int_{q0}^{q1} dq q^3 C(q) P(q) S(q) \\int_0^{pi/2} dphi cos(phi) E''(q v cos phi)
    G(q; v) = (k^2 / 2) \\int_{q0}^{q} dq' q'^3 C(q') \\int_0^{pi/2} dphi |E(q' v cos phi)|^2
    P(q)    = erf(1 / (2 sqrt G(q))),      A/A0 = P(q1),

which are eqs 61-62 with the angular integrals over [0, 2 pi] folded onto [0, pi/2] (E(-omega)
= conj E(omega)), |E|^2 instead of the seed's "Im|E|^2" and the upper limit q instead of q_a
in G (seed misprints in eqs 32/62). S = 1 is the 2001 theory (the seed); S = gamma +
(1 - gamma) P^2 is the later correction (Persson's papers from 2004 on, gamma ~ 1/2).

The nominal pressure sigma0 is the scene's ``load.p`` (a list is a sweep); Poisson's ratio is
``material.nu``; the temperature(s) are the modulus stage's ``modulus.T``.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr
from scipy.special import erf

from roughcontact.stage import UserError
from roughcontact.stage import Param, Section
from roughcontact.stage import Figure, Stage, StageInput, Var, register, register_params, register_section

from .modulus import modulus_at
from roughcontact.physics.quadrature import cumulative_integral, gauss_legendre, running_weighted_integral

# ----------------------------------------------------------------------------------------
# Kernels (pure numpy)
# ----------------------------------------------------------------------------------------


def angular_integrals(q, v, omega_grid, storage, loss, n_phi):
    """The two angular integrals of eqs 61-62, by Gauss-Legendre on [0, pi/2].

    A(q; v) = \\int_0^{pi/2} |E(q v cos phi)|^2 dphi   (Pa^2)
    B(q; v) = \\int_0^{pi/2} cos(phi) E''(q v cos phi) dphi   (Pa)

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m).
    v : array (...)
        Sliding velocities (m/s), > 0.
    omega_grid : array (m,)
        Geometric angular-frequency grid of the modulus (rad/s).
    storage, loss : arrays (..., m)
        E' and E'' on that grid (Pa); leading axes broadcast against ``v``.
    n_phi : int
        Gauss-Legendre nodes in phi.

    Returns
    -------
    (A, B) : arrays (..., n)

    References
    ----------
    equations.md section 6; seed eqs 29, 32, 61, 62.
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    storage = np.asarray(storage, dtype=float)
    loss = np.asarray(loss, dtype=float)
    phi, weight = gauss_legendre(0.0, 0.5 * np.pi, n_phi)
    cos = np.cos(phi)
    lead = np.broadcast_shapes(v.shape, storage.shape[:-1])
    omega = v[..., None, None] * q[:, None] * cos  # (..., n, n_phi)
    omega = np.broadcast_to(omega, lead + (q.size, cos.size)).reshape(lead + (q.size * cos.size,))
    Ep, Epp = modulus_at(omega, omega_grid, storage, loss)
    Ep = Ep.reshape(lead + (q.size, cos.size))
    Epp = Epp.reshape(lead + (q.size, cos.size))
    A = (Ep * Ep + Epp * Epp) @ weight
    B = (Epp * cos) @ weight
    return A, B


def sliding_G(q, C, A, sigma0, nu):
    """G(q; v) of the corrected eq 62 (dimensionless): (k^2/2) \\int_{q0}^{q} q'^3 C A dq'.

    k = 1/((1 - nu^2) sigma0); A(q) = \\int_0^{pi/2} |E|^2 dphi from :func:`angular_integrals`.
    For a real constant modulus E it equals Persson's elastic G (eq 17) divided by sigma0^2.

    Parameters
    ----------
    q : array (n,)
    C : array (..., n)
        Combined PSD (m^4).
    A : array (..., n)
        Angular integral of |E|^2 (Pa^2).
    sigma0 : array (...)
        Nominal pressure (Pa).
    nu : float
        Poisson's ratio.

    Returns
    -------
    array (..., n), G(q0) = 0.
    """
    k = 1.0 / ((1.0 - nu * nu) * np.asarray(sigma0, dtype=float))
    return 0.5 * k[..., None] ** 2 * cumulative_integral(q, np.asarray(q) ** 3 * C * A)


def contact_fraction(G):
    """P(q) = erf(1/(2 sqrt G)) (eq 31); 1 where G = 0 (full contact at the largest scale)."""
    G = np.asarray(G, dtype=float)
    with np.errstate(divide="ignore"):
        return erf(np.where(G > 0, 0.5 / np.sqrt(np.where(G > 0, G, 1.0)), np.inf))


def area_factor(P, correction: str, gamma: float):
    """S(q) in mu: 1 (seed, 2001 theory) or gamma + (1 - gamma) P^2 ('yang_persson')."""
    if correction == "none":
        return np.ones_like(P)
    return gamma + (1.0 - gamma) * P * P


def friction_integrand(q, C, P, S, B, sigma0, nu):
    """d mu / d q of eq 61 (1/m): 2 k q^3 C P S B, k = 1/((1 - nu^2) sigma0)."""
    k = 1.0 / ((1.0 - nu * nu) * np.asarray(sigma0, dtype=float))
    return 2.0 * k[..., None] * np.asarray(q) ** 3 * C * P * S * B


def friction_kernel(q, C, A, B, sigma0, nu, correction="none", gamma=0.5, extras=False, segment_nodes=12):
    """mu(v) and A/A0(v) from the PSD and the angular integrals (eqs 61-62, 31).

    mu is integrated in the variable G: with dG/dq = (k^2/2) q^3 C A,
    mu = 2 k \\int q^3 C P S B dq = (4/k) \\int P(G) S(G) (B/A) dG, segment by segment by
    :func:`stages.quadrature.running_weighted_integral` (``segment_nodes`` Gauss-Legendre nodes
    per q segment). This keeps second-order accuracy where P(q) falls like 1/sqrt(q - q0) just
    above q0 (high velocities: G grows by orders of magnitude in the first q segment), where
    power-law quadrature of the integrand in q is only first order.

    Returns ``(mu, area)`` and, with ``extras``, also ``(G, dmu/dln q)`` over q.
    """
    k = 1.0 / ((1.0 - nu * nu) * np.asarray(sigma0, dtype=float))
    g = 0.5 * k[..., None] ** 2 * np.asarray(q) ** 3 * C * A
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(A > 0, B / np.where(A > 0, A, 1.0), 0.0)

    def weight(G):
        P = contact_fraction(G)
        return P * area_factor(P, correction, gamma)

    I, G = running_weighted_integral(q, g, r, weight, nodes=segment_nodes)
    mu = 4.0 / k * I
    P = contact_fraction(G)
    area = P[..., -1]
    if extras:
        S = area_factor(P, correction, gamma)
        return mu, area, G, friction_integrand(q, C, P, S, B, sigma0, nu) * np.asarray(q)
    return mu, area


# ----------------------------------------------------------------------------------------
# Scene section and numerics
# ----------------------------------------------------------------------------------------

#: velocities when the scene gives none: 1e-9 .. 1e3 m/s, 6 points per decade
DEFAULT_VELOCITIES = np.geomspace(1e-9, 1e3, 73)

register_section(
    Section(
        "friction",
        (
            Param("v", "sweep", "m/s", default=None, lo=0.0, lo_open=True, hi=1e6,
                  doc="sliding velocity; a list or {from, to, num} is a sweep (default 1e-9..1e3 m/s, 73 points)"),
            Param("correction", "choice", default="none", choices=("none", "yang_persson"),
                  doc="S(q) in mu: none (S = 1, the seed) or yang_persson (S = gamma + (1 - gamma) P^2)"),
            Param("gamma", "quantity", "", default=0.5, lo=0.0, hi=1.0, doc="gamma of the yang_persson correction"),
        ),
        doc="hysteretic friction of the elastic solid sliding on the substrate (nominal pressure: load.p)",
    )
)
register_params(
    "numerics",
    Param("friction_phi_nodes", "int", default=16, lo=2, presets={"fast": 8, "accurate": 24},
          ladder=(6, 8, 10, 12, 16, 20, 24, 32, 64), doc="Gauss-Legendre nodes of the friction angular integrals"),
    Param("friction_segment_nodes", "int", default=12, lo=2, presets={"fast": 6, "accurate": 16},
          ladder=(4, 4, 6, 8, 12, 12, 16, 16, 24),
          doc="Gauss-Legendre nodes per q segment of the friction integral (integrated in the variable G)"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------


def compute_friction(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    mod = inp.upstream["modulus"]
    q = psd["q"]
    grid = mod["omega"].values
    ratios = np.diff(np.log(grid))
    if grid.size < 4 or np.ptp(ratios) > 1e-6 * np.abs(ratios).max():
        raise UserError("the modulus stage's omega grid must be geometric with at least 4 points", key="modulus")
    nu = float(inp["material.nu"])
    n_phi = int(inp["numerics.friction_phi_nodes"])
    n_seg = int(inp["numerics.friction_segment_nodes"])
    correction, gamma = inp["friction.correction"], float(inp["friction.gamma"])
    v_values = inp["friction.v"] if inp["friction.v"] is not None else DEFAULT_VELOCITIES
    v = inp.sweep("v", v_values, "m/s", "sliding velocity")
    p = inp.sweep("p", inp["load.p"], "Pa", "nominal pressure sigma0")
    omega = mod["omega"]

    A, B = xr.apply_ufunc(
        angular_integrals, q, v, omega, mod["storage_modulus"], mod["loss_modulus"], n_phi,
        input_core_dims=[["q"], [], ["omega"], ["omega"], ["omega"], []],
        output_core_dims=[["q"], ["q"]], dask="parallelized", output_dtypes=[float, float],
    )
    extras = bool({"sliding_G", "friction_density"} & inp.wanted)
    outputs = xr.apply_ufunc(
        friction_kernel, q, psd["psd_combined"], A, B, p, nu, correction, gamma, extras, n_seg,
        input_core_dims=[["q"], ["q"], ["q"], ["q"], [], [], [], [], [], []],
        output_core_dims=[[], []] + ([["q"], ["q"]] if extras else []),
        dask="parallelized", output_dtypes=[float] * (4 if extras else 2),
    )
    mu, area = outputs[0], outputs[1]
    S_text = "S = 1" if correction == "none" else f"S = {gamma:g} + {1 - gamma:g} P^2"
    mu.attrs = {"units": "1", "long_name": "hysteretic friction coefficient mu (eq 61)",
                "formula": f"mu = 2/((1-nu^2) sigma0) int dq q^3 C P S int_0^(pi/2) cos(phi) E''(q v cos phi) dphi, {S_text}"}
    area.attrs = {"units": "1", "long_name": "relative contact area while sliding A/A0 = P(q1) (eqs 31, 62)"}
    last = ("v",) if v.ndim else ()
    ds = xr.Dataset({"friction_coefficient": mu.transpose(..., *last),
                     "sliding_contact_area_ratio": area.transpose(..., *last)})
    if "sliding_G" in inp.wanted:
        G = outputs[2].transpose(..., *last, "q")
        G.attrs = {"units": "1", "long_name": "G(q; v) of eq 62 (corrected: |E|^2, upper limit q), sigma0^2 absorbed"}
        ds["sliding_G"] = G
    if "friction_density" in inp.wanted:
        d = outputs[3].transpose(..., *last, "q")
        d.attrs = {"units": "1", "long_name": "contribution to mu per unit ln q, d mu / d ln q"}
        ds["friction_density"] = d
    if "q" in ds.coords:
        ds["q"].attrs = {"units": "1/m", "long_name": "wavenumber"}
    for sweep in (v, p):
        if sweep.ndim == 0:
            ds = ds.assign_coords({sweep.name: sweep})
    needed_hi = float(q.values[-1] * np.max(v_values))
    if needed_hi > grid[-1]:
        warnings.warn(f"friction needs the modulus up to omega = q1 v_max = {needed_hi:.3g} rad/s, beyond the modulus "
                      f"grid ({grid[-1]:.3g} rad/s): extrapolated with E' constant, E'' ~ 1/omega; "
                      "raise modulus.omega_max if that is not the glassy plateau", UserWarning, stacklevel=2)
    ds.attrs = {
        "angular_quadrature": f"Gauss-Legendre, {n_phi} nodes on [0, pi/2]",
        "q_quadrature": ("G: piecewise power law on the psd stage's q grid; mu: in the variable G, "
                         f"{n_seg} Gauss-Legendre nodes per q segment (stages.quadrature.running_weighted_integral)"),
        "area_factor": S_text,
        "poisson_ratio": nu,
        "omega_needed_max": needed_hi,
        "modulus_omega_range": f"{grid[0]:.6g} {grid[-1]:.6g} rad/s",
        "modulus_extrapolated": ("yes: frequencies above the modulus grid use E' constant, E'' ~ 1/omega"
                                 if needed_hi > grid[-1] else "no (above); below the grid E'' ~ omega"),
        "equations": "equations.md section 6 (seed eqs 29-32, 61-62 with the eq 30 and eq 32/62 misprints corrected)",
    }
    return ds


# ----------------------------------------------------------------------------------------
# Figures (seed Figs 6, 8-11)
# ----------------------------------------------------------------------------------------


def _first(da: xr.DataArray, keep: tuple[str, ...]) -> tuple[xr.DataArray, str]:
    """Reduce every dimension but ``keep`` to its first value; say which in a note."""
    notes = []
    for dim in list(da.dims):
        if dim not in keep:
            value = da[dim].values[0]
            notes.append(f"{dim} = {value:.4g}" if dim != "T" else f"T = {value - 273.15:.4g} °C")
            da = da.isel({dim: 0})
    return da, ", ".join(notes)


def _curves(results, which: str, etas: tuple[float, ...] | None):
    """(label, DataArray over v, note) for substrate-only (if etas is None) and the pair's eta values."""
    out = []
    base = results["base"]["friction"]
    if etas is None:
        if "substrate_only" in results:
            da, note = _first(results["substrate_only"]["friction"][which], ("v",))
            out.append(("substrate only", da, note))
        etas = (0.0,)
    for eta in etas:
        da = base[which]
        if "eta" in da.dims:
            hits = np.flatnonzero(np.isclose(da["eta"].values, eta))
            if not hits.size:
                continue
            da = da.isel(eta=int(hits[0]))
            label = "both rough, uncorrelated (eta = 0)" if eta == 0 else f"both rough, eta = {eta:+g}"
        else:
            label = "as in the scene"
        da, note = _first(da, ("v",))
        out.append((label, da, note))
    return out


def _friction_figure(results, which, etas, title, ylabel, logy=False):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.8, 4.3))
    notes = set()
    for (label, da, note), marker in zip(_curves(results, which, etas), "o*+xsd"):
        ax.semilogx(da["v"].values, da.values, marker=marker, markersize=4, label=label)
        if note:
            notes.add(note)
    ax.set_xlabel("sliding velocity v (m/s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title + (f"\n({'; '.join(sorted(notes))})" if notes else ""), fontsize=10)
    if logy:
        ax.set_yscale("log")
    else:
        ax.set_ylim(bottom=0)
    ax.grid(True, which="both" if logy else "major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def figure_mu_substrate(results):
    return _friction_figure(results, "friction_coefficient", None,
                            "Friction: substrate only vs both rough (seed Fig. 8)", "friction coefficient mu")


def figure_area_substrate(results):
    return _friction_figure(results, "sliding_contact_area_ratio", None,
                            "Contact area while sliding (seed Fig. 9)", "A / A0", logy=True)


def figure_mu_eta(results):
    return _friction_figure(results, "friction_coefficient", (0.0, 1.0, -1.0),
                            "Friction for correlated roughness (seed Fig. 10)", "friction coefficient mu")


def figure_area_eta(results):
    return _friction_figure(results, "sliding_contact_area_ratio", (0.0, 1.0, -1.0),
                            "Contact area for correlated roughness (seed Fig. 11)", "A / A0", logy=True)


def figure_psds(results):
    import matplotlib.pyplot as plt

    psd = results["base"]["psd"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for ax, name, title in ((axes[0], "solid", "(a) elastic solid (rubber)"), (axes[1], "substrate", "(b) substrate")):
        da, note = _first(psd[f"psd_{name}"], ("q",))
        q = da["q"].values
        C = da.values
        mask = C > 0
        if not np.any(mask):
            ax.text(0.5, 0.5, "smooth", transform=ax.transAxes, ha="center")
        else:
            ax.loglog(q[mask], C[mask], "-", label="C(q)")
            H = da.attrs.get("H")
            if H is not None:
                q0 = float(da.attrs.get("q0", q[mask][0]))
                ref = C[mask][np.searchsorted(q[mask], q0)] if q0 >= q[mask][0] else C[mask][0]
                qq = q[mask][q[mask] >= q0]
                ax.loglog(qq, 3.0 * ref * (qq / q0) ** (-2.0 * (1.0 + H)), "--",
                          label=f"slope -2(1+H) = {-2 * (1 + H):.2f}")
            hrms = float(np.sqrt(2 * np.pi * np.trapezoid(q * np.where(mask, C, 0.0), q)))
            ax.set_title(f"{title}: hrms = {hrms * 1e6:.3g} um" + (f" ({note})" if note else ""), fontsize=10)
            ax.legend(fontsize=8)
        ax.set_xlabel("wavenumber q (1/m)")
        ax.set_ylabel("C(q) (m^4)")
        ax.grid(True, alpha=0.3)
    fig.suptitle("Power spectral densities (seed Fig. 6)")
    fig.tight_layout()
    return fig


STAGE = register(
    Stage(
        name="friction",
        version="1",
        compute=compute_friction,
        requires=("modulus", "psd"),
        main_outputs=("friction_coefficient", "sliding_contact_area_ratio"),
        tolerance=1e-4,
        params=("load.p", "material.nu", "friction.v", "friction.correction", "friction.gamma",
                "numerics.friction_phi_nodes", "numerics.friction_segment_nodes"),
        outputs={
            "friction_coefficient": Var("1", "hysteretic friction coefficient mu (eq 61)"),
            "sliding_contact_area_ratio": Var("1", "relative contact area while sliding A/A0 (eqs 31, 62)"),
            "sliding_G": Var("1", "G(q; v) of eq 62 (corrected)", optional=True),
            "friction_density": Var("1", "d mu / d ln q", optional=True),
        },
        coords={},
        figures=(
            Figure("fig6_psds", "C(q) of the two surfaces (seed Fig. 6)", ("psd", "friction"), figure_psds),
            Figure("fig8_friction_substrate_only", "mu(v): substrate only vs both rough (seed Fig. 8)",
                   ("friction",), figure_mu_substrate),
            Figure("fig9_area_substrate_only", "A/A0(v): substrate only vs both rough (seed Fig. 9)",
                   ("friction",), figure_area_substrate),
            Figure("fig10_friction_eta", "mu(v) for eta = 0, +1, -1 (seed Fig. 10)", ("friction",), figure_mu_eta),
            Figure("fig11_area_eta", "A/A0(v) for eta = 0, +1, -1 (seed Fig. 11)", ("friction",), figure_area_eta),
        ),
        doc="mu(v, eta, T, p) and A/A0(v, ...) of hysteretic rubber friction (eqs 61-62, corrected).",
    )
)
