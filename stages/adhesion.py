"""Adhesion: effective interfacial energy, contact area at zero load, and the roughness at
which adhesion vanishes (Persson & Tosatti 2001, extended to two rough surfaces).

Physics: ``equations.md`` section 4 (seed eqs 5-14, 42, 50; Figs 1-2).

Full-contact theory (eq 13 with P = S = 1)::

    gamma_eff / Delta_gamma = F - (2 pi / delta) int_{qL}^{q1} q^2 C(q) dq,
    F = 1 + (sqrt(pi) xi / 2) erfcx(1 / xi)      (eq 11; xi^2 = 2 pi int q^3 C dq, eq 12)
    delta = 4 Delta_gamma / E*                   (eq 14)

Partial-contact theory: P(zeta) = A(zeta)/A0 from the Volterra equation (eq 9, primes
restored) with the detachment stress sigma_a(zeta) = [gamma_eff(zeta) E* zeta qL]^(1/2)
(eq 6) and gamma_eff(zeta) from P (eq 13 corrected, eq 50)::

    gamma_eff(zeta) / Delta_gamma = [P(zeta1) F - (2 pi/delta) int_{zeta qL}^{q1} q^2 C P S_el dq] / P(zeta)

solved self-consistently. How (see ``docs/adhesion.md``): the numerator equals
``K + (2 pi/delta) int_{qL}^{zeta qL} q^2 C P S_el dq`` with ``K = gamma_eff(1)/Delta_gamma``
(P(1) = 1), which depends only on P below zeta. So for a trial K the whole solution is one
forward march in zeta (eq 9 by product integration, node by node, with the node's own
self-consistency solved by a bracketed scalar root), and K is fixed by the single condition
at the top, ``numerator(zeta1) = P(zeta1) F``. K = 0 (detached, P = 0) is always a solution;
the attached branch is the root with K > 0. The hrms at which adhesion vanishes is where that
root reaches K = 0+: it is found by root-finding in the substrate's hrms at a tiny fixed K
(continuation in K along the attached branch), bracketed by the sweep.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import erfcx

from roughcontact.stage import ComputationError, UserError
from roughcontact.stage import Param, Section
from roughcontact.stage import Figure, Stage, StageInput, Var, register, register_params, register_section

from roughcontact.physics.spectra import hrms_from_psd, psd_combined, rms_slope_from_psd
from roughcontact.physics.quadrature import integral, integral_to

#: Elastic-energy factor models S_el(P) in U_el (eq 10): name -> description.
MODELS = {
    "alpha": "S_el = alpha (constant; the seed, eq 10/13)",
    "yang_persson": "S_el = gamma + (1 - gamma) P^2 (Yang & Persson 2008; equals 1 at full contact)",
}

# ----------------------------------------------------------------------------------------
# Kernels (pure numpy)
# ----------------------------------------------------------------------------------------


def effective_modulus(E, nu):
    """E* = E / (1 - nu^2) (Pa)."""
    return E / (1.0 - nu * nu)


def adhesion_length(delta_gamma, E_star):
    """Adhesion length delta = 4 Delta_gamma / E* (m), seed eq 14.

    Parameters
    ----------
    delta_gamma : float
        Interfacial binding energy per unit area of flat surfaces (J/m^2).
    E_star : float
        Effective modulus E/(1 - nu^2) (Pa).
    """
    return 4.0 * delta_gamma / E_star


def surface_area_factor(xi):
    """Surface-area enhancement F = int_0^inf (1 + xi^2 x)^(1/2) e^-x dx, seed eq 11.

    Closed form F = 1 + (sqrt(pi) xi / 2) erfcx(1 / xi); F(0) = 1, F ~ (sqrt(pi)/2) xi for
    large xi.

    Parameters
    ----------
    xi : array
        Root-mean-square slope (dimensionless), xi^2 = 2 pi int q^3 C dq (eq 12).
    """
    xi = np.asarray(xi, dtype=float)
    with np.errstate(divide="ignore"):
        inv = np.where(xi > 0, 1.0 / np.where(xi > 0, xi, 1.0), np.inf)
    return 1.0 + 0.5 * np.sqrt(np.pi) * xi * erfcx(inv)


def gamma_eff_full_contact(q, C, delta):
    """Full-contact effective interfacial energy gamma_eff / Delta_gamma (eq 13, P = S = 1).

    gamma_eff/Delta_gamma = F - (2 pi / delta) int_{qL}^{q1} q^2 C dq.

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m), log grid.
    C : array (..., n)
        Combined PSD (m^4).
    delta : float
        Adhesion length (m), eq 14.

    Returns
    -------
    array (...)
        Dimensionless; negative means the full-contact theory predicts no adhesion.
    """
    F = surface_area_factor(rms_slope_from_psd(q, C))
    return F - 2.0 * np.pi / delta * integral(q, np.asarray(q) ** 2 * C)


def zeta_grid(zeta1, points_per_decade, zeta_offset):
    """Nodes of the Volterra grid: zeta = 1 and 1 + (zeta1 - 1) geometric in (zeta - 1) from
    ``zeta_offset`` up, ``points_per_decade`` per decade of (zeta - 1).

    Near zeta = 1, a(zeta) ~ f(1)(zeta - 1): the grid is geometric in a there (where the
    detachment layer sits when sigma_a(1) is small) and geometric in zeta far from 1.
    """
    if zeta1 <= 1.0:
        raise ValueError("zeta1 must exceed 1")
    top = zeta1 - 1.0
    lo = min(zeta_offset, 0.1 * top)
    decades = np.log10(top / lo)
    n = max(2, int(np.ceil(decades * points_per_decade)))
    return np.concatenate([[1.0], 1.0 + top * np.logspace(-decades, 0.0, n + 1)])


def layer_resolving_offset(q, C, E_star, delta_gamma, offset, K_min, sigma0=0.0, margin=1e-3):
    """Smallest zeta - 1 of the Volterra grid that resolves the detachment layer at zeta -> 1.

    Detachment starts where a(zeta) ~ (sigma_a(1) + sigma0)^2; on the attached branch
    sigma_a(1)^2 >= K_min F Delta_gamma E* qL. The first grid cell must be much thinner:
    a(1 + offset) <= margin (sigma_a,min + sigma0)^2 for every PSD of the batch. Returns
    ``offset`` if it already does, else the (smaller) offset that does (a ~ zeta - 1 there).

    Parameters
    ----------
    q : array (n,)
    C : array (B, n)
        Combined PSDs (m^4).
    E_star, delta_gamma, sigma0 : float
        Pa, J/m^2, Pa.
    offset, K_min : float
        The requested smallest zeta - 1, and the smallest gamma_eff(1)/(F Delta_gamma) solved for.
    """
    C = np.atleast_2d(np.asarray(C, dtype=float))
    qL = float(q[0])
    F = surface_area_factor(rms_slope_from_psd(q, C))
    sigma_min = np.sqrt(K_min * float(np.min(F)) * delta_gamma * E_star * qL) + sigma0
    target = margin * sigma_min**2
    G1 = 0.25 * np.pi * E_star**2 * integral_to(q, q**3 * C, np.array([qL * (1.0 + offset)]))[:, 0]
    worst = float(np.max(G1))
    if worst <= target:
        return offset
    return offset * target / worst


def abel_weights(a, i):
    """Product-trapezoid weights of the Abel kernel at node i.

    int_0^{a_i} sqrt(a_i / (a_i - a')) g(a') da' = sum_{j<=i} W_ij g(a_j) for g piecewise
    linear in a' between the nodes a_0 = 0 < a_1 < ... (exact for such g). Written without
    cancellation: with u = a_i - a', segment integrals of u^-1/2 and u^-1/2 (a' - a_{j-1}) are
    2 d and (2/3) d (2 sqrt(u_lo) + sqrt(u_hi)) d / (sqrt(u_lo) + sqrt(u_hi)) with
    d = (u_lo - u_hi) / (sqrt(u_lo) + sqrt(u_hi)).

    Parameters
    ----------
    a : array (B, M)
        Non-decreasing nodes (any units), a[:, 0] = 0.
    i : int
        Collocation node, 1 <= i < M.

    Returns
    -------
    array (B, i + 1)
    """
    ai = a[:, i:i + 1]
    ulo = np.maximum(ai - a[:, :i], 0.0)
    uhi = np.maximum(ai - a[:, 1:i + 1], 0.0)
    rl, rh = np.sqrt(ulo), np.sqrt(uhi)
    den = rl + rh
    ok = den > 0
    safe = np.where(ok, den, 1.0)
    d = np.where(ok, (ulo - uhi) / safe, 0.0)
    i1 = np.where(ok, (2.0 / 3.0) * d * (2.0 * rl + rh) / safe, 0.0)
    W = np.zeros((a.shape[0], i + 1))
    W[:, 1:] += i1
    W[:, :-1] += 2.0 * d - i1
    return np.sqrt(ai) * W


def march(zeta, a, wel, F, K, sigma0=0.0, c0=1.0, c1=0.0, sigma_fixed=None, node_iterations=60, node_tol=1e-13):
    """One forward march of the partial-contact adhesion problem for trial K = gamma_eff(1)/Delta_gamma.

    Everything is dimensionless: stresses in units of sigma_u = (Delta_gamma E* qL)^(1/2),
    a in sigma_u^2. Eq 9 (primes restored) at node i::

        exp(-(sigma_a,i + sigma0)^2 / (4 a_i)) = sum_j W_ij exp(-(sigma_a,i - sigma_a,j)^2 / (4 (a_i - a_j))) s_j

    with s = -dP/da piecewise linear (product trapezoid, :func:`abel_weights`), s >= 0,
    P_i = P_{i-1} - (s_{i-1} + s_i)(a_i - a_{i-1})/2 >= 0. The detachment stress
    sigma_a,i = (zeta_i N_i / P_i)^(1/2) (eq 6) with N_i = K + sum of w_el,j (S_el P)_mid
    (numerator of eq 13); it depends on P_i, so each node solves the scalar equation
    P_i = T(P_i) (T decreasing) by bracketed Illinois iteration on [0, P_{i-1}].

    Parameters
    ----------
    zeta : array (M,)
        Volterra nodes, zeta[0] = 1.
    a : array (B, M)
        Persson's a(zeta) = G(zeta) / sigma_u^2, a[:, 0] = 0, non-decreasing.
    wel : array (B, M - 1)
        (2 pi / delta) int q^2 C dq over each segment.
    F : array (B,)
        Surface-area factor (eq 11).
    K : array (B,)
        Trial gamma_eff(1) / Delta_gamma.
    sigma0 : float or array (B,)
        Nominal stress / sigma_u (>= 0, compressive).
    c0, c1 : float or array (B,)
        S_el = c0 + c1 P^2 (alpha model: c0 = alpha, c1 = 0).
    sigma_fixed : array (B, M), optional
        Prescribed sigma_a (then gamma_eff is not used): the Volterra solver alone.

    Returns
    -------
    dict with P, N, sigma (B, M), residual R = N(zeta1) - P(zeta1) F (B,), node_residual (max
    over nodes of |P_i - T(P_i)|).
    """
    a = np.asarray(a, dtype=float)
    B, M = a.shape
    K = np.broadcast_to(np.asarray(K, dtype=float), (B,))
    sigma0 = np.broadcast_to(np.asarray(sigma0, dtype=float), (B,))
    c0 = np.broadcast_to(np.asarray(c0, dtype=float), (B,))
    c1 = np.broadcast_to(np.asarray(c1, dtype=float), (B,))
    P = np.ones((B, M))
    N = np.zeros((B, M))
    sig = np.zeros((B, M))
    s = np.zeros((B, M))
    N[:, 0] = K
    sig[:, 0] = np.sqrt(np.maximum(K, 0.0) * zeta[0]) if sigma_fixed is None else sigma_fixed[:, 0]
    worst = np.zeros(B)
    # sigma_a(1) + sigma0 = 0: nothing holds the surfaces together at the largest scale, eq 9
    # gives P = erf(0) = 0 at once (left to the march, the jump would be smeared over a segment)
    instant = sig[:, 0] + sigma0 <= 0

    def el(p):
        return p * (c0 + c1 * p * p)

    for i in range(1, M):
        ai = a[:, i]
        da = np.maximum(ai - a[:, i - 1], 0.0)
        W = abel_weights(a, i)
        dj = ai[:, None] - a[:, :i]
        okj = dj > 0
        dj4 = 4.0 * np.where(okj, dj, 1.0)
        Pprev = P[:, i - 1]
        live = (Pprev > 0) & ~instant
        sprev = s[:, i - 1]
        Ws = W[:, :i] * s[:, :i]
        Wii = W[:, i]
        grows = (da > 0) & (Wii > 0)
        ai4 = 4.0 * np.where(ai > 0, ai, 1.0)
        Wsafe = np.where(Wii > 0, Wii, 1.0)

        def node(Pi):
            Ni = N[:, i - 1] + wel[:, i - 1] * 0.5 * (el(Pprev) + el(Pi))
            if sigma_fixed is None:
                pos = Pi > 0
                g = np.where(pos, Ni / np.where(pos, Pi, 1.0), np.where(Ni > 0, np.inf, 0.0))
                sg = np.sqrt(np.maximum(g, 0.0) * zeta[i])
            else:
                sg = sigma_fixed[:, i]
            fin = np.isfinite(sg)
            sgf = np.where(fin, sg, 0.0)
            with np.errstate(under="ignore"):
                E = np.where(okj, np.exp(-((sgf[:, None] - sig[:, :i]) ** 2) / dj4), 0.0)
                lhs = np.where((ai > 0) & fin, np.exp(-((sgf + sigma0) ** 2) / ai4), 0.0)
            known = np.sum(Ws * E, axis=1)
            # where a does not grow (no roughness on this segment) nothing detaches; s keeps its
            # value so that its piecewise-linear interpolant is not broken at the repeated node
            si = np.where(grows, np.maximum(lhs - known, 0.0) / Wsafe, np.where(da > 0, 0.0, sprev))
            Pn = np.maximum(Pprev - 0.5 * (sprev + si) * da, 0.0)
            return Pn, si, Ni, sgf

        # g(x) = T(x) - x is decreasing on [0, Pprev]; g(0) >= 0, g(Pprev) <= 0.
        lo = np.zeros(B)
        hi = Pprev.copy()
        flo = node(lo)[0] - lo
        fhi = node(hi)[0] - hi
        done = (fhi >= -node_tol) | ~live
        x = np.where(fhi >= -node_tol, hi, lo)
        side = np.zeros(B)
        for _ in range(node_iterations):
            if np.all(done):
                break
            den = fhi - flo
            xn = np.where(den != 0, hi - fhi * (hi - lo) / np.where(den != 0, den, 1.0), 0.5 * (lo + hi))
            xn = np.clip(xn, lo, hi)
            gx = node(xn)[0] - xn
            x = np.where(done, x, xn)
            up = gx > 0
            lo = np.where(done | ~up, lo, xn)
            hi = np.where(done | up, hi, xn)
            flo = np.where(done, flo, np.where(up, gx, np.where(side == 1, 0.5 * flo, flo)))
            fhi = np.where(done, fhi, np.where(up, np.where(side == -1, 0.5 * fhi, fhi), gx))
            side = np.where(up, -1.0, 1.0)
            done = done | (np.abs(gx) <= node_tol) | (hi - lo <= node_tol)
        Pn, si, Ni, sg = node(x)
        worst = np.maximum(worst, np.where(live, np.abs(Pn - x) * (hi - lo > node_tol), 0.0))
        P[:, i] = np.where(live, Pn, 0.0)
        s[:, i] = np.where(live, si, 0.0)
        N[:, i] = np.where(live, Ni, N[:, i - 1])
        sig[:, i] = np.where(live, sg, 0.0)
    return {"P": P, "N": N, "sigma": sig, "R": N[:, -1] - P[:, -1] * F, "node_residual": worst}


def detachment_volterra(a, sigma_a, sigma0=0.0, zeta=None):
    """The Volterra solver alone: P(zeta) for a prescribed detachment stress sigma_a(zeta) (eq 9).

    Parameters
    ----------
    a : array (B, M)
        Persson's a(zeta) (Pa^2), a[:, 0] = 0, non-decreasing.
    sigma_a : array (B, M)
        Detachment stress (Pa) at the nodes.
    sigma0 : float
        Nominal stress (Pa).

    Returns
    -------
    array (B, M): P(zeta) = A(zeta)/A0. For constant sigma_a it approximates
    erf((sigma_a + sigma0) / (2 a^(1/2))) (product trapezoid: error ~ h^2.4).
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    sigma_a = np.broadcast_to(np.asarray(sigma_a, dtype=float), a.shape)
    scale = np.sqrt(np.maximum(a[:, -1], np.finfo(float).tiny))[:, None]
    zeta = np.ones(a.shape[1]) if zeta is None else zeta
    out = march(zeta, a / scale**2, np.zeros((a.shape[0], a.shape[1] - 1)), np.ones(a.shape[0]), np.zeros(a.shape[0]),
                sigma0=sigma0 / scale[:, 0], sigma_fixed=sigma_a / scale)
    return out["P"]


def _illinois(fun, lo, hi, flo, fhi, tol, maxiter, what):
    """Vectorised Illinois (regula falsi) on brackets [lo, hi] with flo < 0 <= fhi.

    Returns (x, f(x)); raises ComputationError naming ``what`` if a bracket does not close.
    """
    x = hi.copy()
    fx = fhi.copy()
    side = np.zeros_like(lo)
    done = np.abs(fhi) <= tol
    for _ in range(maxiter):
        if np.all(done):
            return x, fx
        den = fhi - flo
        xn = np.where(den != 0, hi - fhi * (hi - lo) / np.where(den != 0, den, 1.0), 0.5 * (lo + hi))
        xn = np.clip(xn, lo, hi)
        fn = fun(xn)
        x = np.where(done, x, xn)
        fx = np.where(done, fx, fn)
        up = fn < 0
        lo = np.where(done | ~up, lo, xn)
        hi = np.where(done | up, hi, xn)
        flo = np.where(done, flo, np.where(up, fn, np.where(side == 1, 0.5 * flo, flo)))
        fhi = np.where(done, fhi, np.where(up, np.where(side == -1, 0.5 * fhi, fhi), fn))
        side = np.where(up, -1.0, 1.0)
        done = done | (np.abs(fn) <= tol) | (hi - lo <= tol * np.maximum(np.abs(hi), 1e-300))
    bad = ~done
    err = ComputationError(f"{what}: no convergence in {maxiter} iterations for {int(bad.sum())} case(s); "
                           f"largest residual {np.max(np.abs(fx[bad])):.3g}")
    err.failed = bad
    raise err


class _Problem:
    """Dimensionless arrays of the adhesion problem on the Volterra grid, for a batch of PSDs."""

    def __init__(self, q, C, E_star, delta_gamma, zeta):
        C = np.atleast_2d(np.asarray(C, dtype=float))
        self.qL = float(q[0])
        self.sigma_u2 = delta_gamma * E_star * self.qL
        delta = adhesion_length(delta_gamma, E_star)
        upper = np.clip(zeta * self.qL, q[0], q[-1])
        G = 0.25 * np.pi * E_star**2 * integral_to(q, q**3 * C, upper)
        G = np.maximum.accumulate(np.maximum(G - G[:, :1], 0.0), axis=1)
        self.a = G / self.sigma_u2
        self.G = G
        I2 = 2.0 * np.pi / delta * integral_to(q, q**2 * C, upper)
        self.wel = np.maximum(np.diff(I2, axis=1), 0.0)
        self.F = surface_area_factor(rms_slope_from_psd(q, C))
        self.full = self.F - I2[:, -1]
        self.zeta = zeta


def solve_partial_contact(prob, sigma0, c0, c1, K_min=1e-8, tol=1e-10, maxiter=80):
    """Self-consistent partial-contact solution (attached branch) for every PSD of ``prob``.

    Root of R(K) = N(zeta1) - P(zeta1) F in K = gamma_eff(1)/Delta_gamma. R(F) >= 0 always.
    At zero load (sigma0 = 0) the root is sought on [K_min F, F] by Illinois in t = K^(1/6)
    (near K = 0 the detachment layer at zeta -> 1 makes R ~ K^(1/6), nearly linear in t);
    R(K_min F) >= 0 means there is no attached branch: the solids separate (K = 0, P = 0
    beyond zeta = 1). Under a compressive sigma0 > 0 the contact holds even with K <= 0, and
    the root is sought on [-I, F], I = (2 pi/delta) int q^2 C S_el(1) dq (R(-I) <= 0).

    Returns
    -------
    dict: K (B,), P, gamma_ratio (= N/P, NaN where P = 0), sigma (dimensionless), attached (B,)
    """
    B = prob.a.shape[0]
    c0 = np.broadcast_to(np.asarray(c0, dtype=float), (B,))
    c1 = np.broadcast_to(np.asarray(c1, dtype=float), (B,))
    sig0 = np.broadcast_to(np.asarray(sigma0, dtype=float) / np.sqrt(prob.sigma_u2), (B,))

    def run(K, idx):
        return march(prob.zeta, prob.a[idx], prob.wel[idx], prob.F[idx], K, sig0[idx], c0[idx], c1[idx])["R"]

    K = np.zeros(B)
    every = np.arange(B)
    what = "self-consistent gamma_eff at the lowest magnification (root in K of eq 13 at zeta1)"
    if np.all(sig0 == 0):
        t_lo = np.full(B, K_min ** (1.0 / 6.0))
        f_lo = run(t_lo**6 * prob.F, every)
        attached = f_lo < 0
        idx = np.flatnonzero(attached)
        if idx.size:
            f_hi = run(prob.F[idx], idx)
            t, _ = _illinois(lambda t: run(t**6 * prob.F[idx], idx), t_lo[idx], np.ones(idx.size), f_lo[idx], f_hi,
                             tol, maxiter, what)
            K[idx] = t**6 * prob.F[idx]
    else:
        attached = np.ones(B, dtype=bool)
        I_max = prob.wel.sum(axis=1) * (c0 + c1)
        lo, hi = -I_max, prob.F.copy()
        f_lo, f_hi = run(lo, every), run(hi, every)
        K, _ = _illinois(lambda k: run(k, every), lo, hi, np.minimum(f_lo, -0.0), f_hi, tol, maxiter, what)
    out = march(prob.zeta, prob.a, prob.wel, prob.F, K, sig0, c0, c1)
    first = np.arange(prob.a.shape[1]) == 0
    P = np.where(attached[:, None], out["P"], np.where(first, 1.0, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(P > 0, out["N"] / np.where(P > 0, P, 1.0), np.nan)
    g[:, 0] = K
    return {"K": K, "P": P, "gamma_ratio": g, "sigma": np.where(attached[:, None], out["sigma"], 0.0),
            "attached": attached, "node_residual": out["node_residual"]}


def vanishing_scale(make_C, q, E_star, delta_gamma, zeta, h_lo, h_hi, c0, c1, K_min=1e-8, tol=1e-10, maxiter=100):
    """Substrate hrms at which adhesion vanishes (sigma0 = 0), by root-finding between an
    attached ``h_lo`` and a detached ``h_hi``.

    The attached branch ends where its root K = gamma_eff(1)/Delta_gamma reaches 0+; at the
    fixed tiny K = K_min F (continuation in K along the branch) the residual
    R(K_min F; h) of :func:`solve_partial_contact` changes sign there, and Illinois on h finds
    it (the error of a finite K_min is ~ K_min^(2/3) relative: 1e-8 -> ~1e-6).

    Parameters
    ----------
    make_C : callable h (B,) -> C (B, n)
        Combined PSD for substrate hrms h.
    h_lo, h_hi : array (B,)
        Bracket (m).
    """
    def R(h):
        prob = _Problem(q, make_C(h), E_star, delta_gamma, zeta)
        return march(zeta, prob.a, prob.wel, prob.F, K_min * prob.F, 0.0, c0, c1)["R"]

    f_lo, f_hi = R(h_lo), R(h_hi)
    if np.any(f_lo >= 0) or np.any(f_hi < 0):
        raise ComputationError("vanishing hrms: the sweep's attached/detached bracket is not confirmed at "
                               f"K = {K_min:g} F (residuals {f_lo}, {f_hi})")
    return _illinois_x(R, h_lo, h_hi, f_lo, f_hi, tol, maxiter)


def _illinois_x(fun, lo, hi, flo, fhi, xtol, maxiter):
    """Illinois root in x to relative tolerance ``xtol`` on the bracket (flo < 0 <= fhi)."""
    side = np.zeros_like(lo)
    x = 0.5 * (lo + hi)
    for _ in range(maxiter):
        if np.all(hi - lo <= xtol * hi):
            break
        den = fhi - flo
        xn = np.where(den != 0, hi - fhi * (hi - lo) / np.where(den != 0, den, 1.0), 0.5 * (lo + hi))
        xn = np.clip(xn, lo, hi)
        # keep at least a bisection's progress on lopsided brackets
        done = hi - lo <= xtol * hi
        fn = fun(xn)
        up = fn < 0
        x = np.where(done, x, xn)
        lo = np.where(done | ~up, lo, xn)
        hi = np.where(done | up, hi, xn)
        flo = np.where(done, flo, np.where(up, fn, np.where(side == 1, 0.5 * flo, flo)))
        fhi = np.where(done, fhi, np.where(up, np.where(side == -1, 0.5 * fhi, fhi), fn))
        side = np.where(up, -1.0, 1.0)
        if np.all(done | (fn == 0)):
            break
    else:
        bad = hi - lo > xtol * hi
        if np.any(bad):
            raise ComputationError(f"hrms at which adhesion vanishes: bracket not closed in {maxiter} iterations "
                                   f"(width {np.max((hi - lo)[bad]):.3g} m)")
    return 0.5 * (lo + hi)


# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------


def _check_adhesion(values: dict, key: str) -> None:
    if values.get("delta_gamma") is not None and values.get("delta") is not None:
        raise UserError("give one of 'delta_gamma' and 'delta', not both (delta = 4 Delta_gamma / E*)", key=key)
    models = values.get("model", ())
    if not models:
        raise UserError("needs at least one model", key=f"{key}.model")
    for m in models:
        if m not in MODELS:
            raise UserError(f"{m!r} is not one of {', '.join(map(repr, MODELS))}", key=f"{key}.model")
    if len(set(models)) != len(models):
        raise UserError("a model is listed twice", key=f"{key}.model")


register_section(
    Section(
        "adhesion",
        (
            Param("delta_gamma", "quantity", "J/m^2", default=None, lo=0.0, lo_open=True,
                  doc="interfacial binding energy of flat surfaces, e.g. \"100 meV/angstrom^2\""),
            Param("delta", "quantity", "m", default=None, lo=0.0, lo_open=True,
                  doc="adhesion length 4 Delta_gamma / E* (instead of delta_gamma)"),
            Param("sigma0", "quantity", "Pa", default=0.0, lo=0.0,
                  doc="nominal compressive stress (0: zero external load, seed Figs 1b, 2b)"),
            Param("model", "list", default=("alpha",),
                  doc="elastic-energy factor S_el in eq 10: 'alpha' (constant, the seed) and/or 'yang_persson'"),
            Param("alpha", "quantity", "", default=1.0, lo=0.0, hi=1.0, lo_open=True,
                  doc="S_el of the 'alpha' model (seed: of order 1; 1 = full-contact elastic energy)"),
            Param("gamma", "quantity", "", default=0.45, lo=0.0, hi=1.0,
                  doc="gamma of the 'yang_persson' model S_el = gamma + (1 - gamma) P^2"),
            Param("vanishing_hrms", "bool", default=False,
                  doc="find the substrate hrms at which adhesion vanishes (needs a substrate.hrms sweep reaching it)"),
        ),
        doc="the adhesion stage (equations.md section 4)",
        check=_check_adhesion,
    )
)
register_params(
    "numerics",
    Param("adhesion_points_per_decade", "int", default=10, lo=2, presets={"fast": 5, "accurate": 20},
          ladder=(3, 4, 5, 7, 10, 14, 20, 28, 40),
          doc="adhesion: Volterra nodes per decade of (zeta - 1)"),
    Param("adhesion_zeta_offset", "quantity", "", default=1e-10, lo=0.0, lo_open=True, hi=1e-2,
          doc="adhesion: smallest zeta - 1 of the Volterra grid (geometric refinement towards zeta = 1)"),
    Param("adhesion_K_min", "quantity", "", default=1e-8, lo=0.0, lo_open=True, hi=1e-3,
          doc="adhesion: smallest gamma_eff(1)/(F Delta_gamma) taken as attached (the vanishing-hrms continuation point)"),
    Param("adhesion_tolerance", "quantity", "", default=1e-10, lo=0.0, lo_open=True, hi=1e-3,
          doc="adhesion: tolerance of the root-finding (residual of eq 13 at zeta1; relative in hrms)"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------

_COEFS = {"alpha": lambda alpha, gamma: (alpha, 0.0), "yang_persson": lambda alpha, gamma: (gamma, 1.0 - gamma)}


def _where(labels, names, bad) -> str:
    """Coordinates of the first failing case, for error messages."""
    i = int(np.flatnonzero(bad)[0])
    parts = [f"{n}={np.ravel(v)[i] if np.ndim(v) else v}" for n, v in zip(names, labels)]
    return ", ".join(parts) or "the only case"


def _partial_kernel(C, c0, c1, *labels, q, E_star, delta_gamma, sigma0, zeta, K_min, tol, names):
    shape = np.broadcast_shapes(C.shape[:-1], np.shape(c0), np.shape(c1), *(np.shape(v) for v in labels))
    Cf = np.broadcast_to(C, shape + C.shape[-1:]).reshape(-1, C.shape[-1])
    c0f = np.broadcast_to(c0, shape).reshape(-1)
    c1f = np.broadcast_to(c1, shape).reshape(-1)
    prob = _Problem(q, Cf, E_star, delta_gamma, zeta)
    try:
        sol = solve_partial_contact(prob, sigma0, c0f, c1f, K_min=K_min, tol=tol)
    except ComputationError as exc:
        lab = [np.broadcast_to(v, shape).reshape(-1) for v in labels]
        where = _where(lab, names, exc.failed) if hasattr(exc, "failed") else "?"
        raise ComputationError(f"adhesion stage at {where}: {exc}") from None
    if np.any(sol["node_residual"] > 1e-8):
        lab = [np.broadcast_to(v, shape).reshape(-1) for v in labels]
        bad = sol["node_residual"] > 1e-8
        raise ComputationError(f"adhesion stage at {_where(lab, names, bad)}: the node equation of eq 9 did not "
                               f"converge (residual {sol['node_residual'].max():.3g})")
    M = zeta.size
    sigma_u = np.sqrt(prob.sigma_u2)
    out = (
        sol["K"].reshape(shape) * delta_gamma,
        sol["P"].reshape(shape + (M,)),
        (sol["gamma_ratio"] * delta_gamma).reshape(shape + (M,)),
        (sol["sigma"] * sigma_u).reshape(shape + (M,)),
        (prob.full * delta_gamma).reshape(shape),
        prob.F.reshape(shape),
    )
    return out


def _vanishing_kernel(K, C1, C2, eta, c0, c1, *, hs, q, E_star, delta_gamma, zeta, K_min, tol):
    """Per case (leading dims), the substrate hrms where the attached branch ends."""
    shape = np.broadcast_shapes(K.shape[:-1], C1.shape[:-2], C2.shape[:-1], np.shape(eta), np.shape(c0), np.shape(c1))
    K = np.broadcast_to(K, shape + K.shape[-1:])
    n = hs.size
    Kf = K.reshape(-1, n)
    B = Kf.shape[0]
    C1f = np.broadcast_to(C1, shape + C1.shape[-2:]).reshape(B, n, -1)
    C2f = np.broadcast_to(C2, shape + C2.shape[-1:]).reshape(B, -1)
    etaf = np.broadcast_to(eta, shape).reshape(-1)
    c0f = np.broadcast_to(c0, shape).reshape(-1)
    c1f = np.broadcast_to(c1, shape).reshape(-1)
    attached = Kf > 0
    ends = attached[:, :-1] & ~attached[:, 1:]
    has = ends.any(axis=1)
    out = np.full(B, np.nan)
    status = np.where(attached[:, -1], 1, np.where(~attached.any(axis=1), 2, 0))
    if np.any(has):
        idx = np.flatnonzero(has)
        j = np.argmax(ends[idx], axis=1)  # first attached -> detached step with growing hrms
        # substrate PSD per unit hrms^2, from the sweep point at the bracket's lower end
        ref_C1 = C1f[idx, j]
        ref_h = hrms_from_psd(q, ref_C1)
        unit = ref_C1 / ref_h[:, None] ** 2

        def make_C(h):
            return psd_combined(h[:, None] ** 2 * unit, C2f[idx], etaf[idx, None])

        out[idx] = vanishing_scale(make_C, q, E_star, delta_gamma, zeta, hs[j], hs[j + 1], c0f[idx], c1f[idx],
                                   K_min=K_min, tol=tol)
    return out.reshape(shape), status.reshape(shape)


def compute_adhesion(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = float(effective_modulus(inp["material.E"], inp["material.nu"]))
    spec = inp["adhesion"]
    dg, delta = spec["delta_gamma"], spec["delta"]
    if dg is None and delta is None:
        raise UserError("give delta_gamma (e.g. \"100 meV/angstrom^2\") or delta (the adhesion length)", key="adhesion")
    if dg is None:
        dg = delta * E_star / 4.0
    delta = adhesion_length(dg, E_star)
    sigma0 = spec["sigma0"]
    ppd, offset = inp["numerics.adhesion_points_per_decade"], inp["numerics.adhesion_zeta_offset"]
    K_min, tol = inp["numerics.adhesion_K_min"], inp["numerics.adhesion_tolerance"]
    C_all = psd["psd_combined"].values.reshape(-1, q.size)
    offset = layer_resolving_offset(q, C_all, E_star, dg, offset, K_min, sigma0)
    zeta_values = zeta_grid(q[-1] / q[0], ppd, offset)
    models = tuple(spec["model"])
    coefs = [_COEFS[m](spec["alpha"], spec["gamma"]) for m in models]
    model_attrs = {"units": "1", "long_name": "elastic-energy factor model S_el (eq 10)",
                   "description": "; ".join(f"{m}: {MODELS[m]}" for m in models)}
    if len(models) > 1:
        model = xr.DataArray(list(models), dims=("model",), attrs=model_attrs)
        c0 = xr.DataArray([c[0] for c in coefs], dims=("model",), coords={"model": model})
        c1 = xr.DataArray([c[1] for c in coefs], dims=("model",), coords={"model": model})
    else:
        c0, c1 = xr.DataArray(coefs[0][0]), xr.DataArray(coefs[0][1])
    C = psd["psd_combined"]
    sweep_dims = [d for d in C.dims if d != "q"] + (["model"] if len(models) > 1 else [])
    labels = [C[d] if d in C.coords else xr.DataArray(np.arange(C.sizes[d]), dims=(d,)) for d in C.dims if d != "q"]
    if len(models) > 1:
        labels.append(c0["model"])
    names = [str(d) for d in sweep_dims]
    results = xr.apply_ufunc(
        _partial_kernel, C, c0, c1, *labels,
        input_core_dims=[["q"], [], []] + [[] for _ in labels],
        output_core_dims=[[], ["zeta"], ["zeta"], ["zeta"], [], []],
        dask="parallelized", output_dtypes=[float] * 6,
        dask_gufunc_kwargs={"output_sizes": {"zeta": zeta_values.size}},
        kwargs=dict(q=q, E_star=E_star, delta_gamma=dg, sigma0=sigma0, zeta=zeta_values, K_min=K_min, tol=tol,
                    names=names),
    )
    zeta = xr.DataArray(zeta_values, dims=("zeta",),
                        attrs={"units": "1", "long_name": "magnification zeta = q/qL (Volterra grid of eq 9)"})
    g1, P, g, sa, full, F = (r.assign_coords(zeta=zeta) if "zeta" in r.dims else r for r in results)
    if "model" in full.dims:  # the full-contact theory and F do not depend on the S_el model
        full, F = full.isel(model=0, drop=True), F.isel(model=0, drop=True)
    load = "zero load" if sigma0 == 0 else f"nominal stress sigma0 = {sigma0:g} Pa"
    g1.attrs = {"units": "J/m^2", "long_name": f"effective interfacial energy gamma_eff at the lowest magnification, "
                f"partial-contact theory, {load} (eqs 9, 13)"}
    P.attrs = {"units": "1", "long_name": f"relative apparent contact area P(zeta) = A(zeta)/A0 with adhesion, {load} (eqs 8-9)"}
    g.attrs = {"units": "J/m^2", "long_name": "effective interfacial energy gamma_eff(zeta), partial contact (eq 13 corrected; NaN where P = 0)"}
    sa.attrs = {"units": "Pa", "long_name": "detachment stress sigma_a(zeta) = (gamma_eff E* zeta qL)^(1/2) (eq 6; 0 where gamma_eff <= 0)"}
    full.attrs = {"units": "J/m^2", "long_name": "effective interfacial energy, full-contact theory: Delta_gamma [F - (2 pi/delta) int q^2 C dq] (eq 13, P = S = 1)"}
    F.attrs = {"units": "1", "long_name": "surface-area factor F = 1 + (sqrt(pi) xi/2) erfcx(1/xi) (eq 11)"}
    area = P.isel(zeta=-1, drop=True)
    area.attrs = {"units": "1", "long_name": f"relative contact area A/A0 at the highest magnification, {load} (P(zeta1))"}
    ds = xr.Dataset({
        "gamma_eff_macroscopic": g1, "gamma_eff_full_contact": full, "adhesive_contact_area_ratio": area,
        "adhesive_area_ratio_zeta": P, "gamma_eff": g, "detachment_stress": sa, "surface_area_factor": F,
    })
    if len(models) > 1:
        ds = ds.assign_coords(model=model)
    else:
        ds = ds.assign_coords(model=xr.DataArray(models[0], attrs=model_attrs))
    ds["delta_gamma"] = xr.DataArray(dg, attrs={"units": "J/m^2", "long_name": "interfacial binding energy Delta_gamma of flat surfaces"})
    ds["adhesion_length"] = xr.DataArray(delta, attrs={"units": "m", "long_name": "adhesion length delta = 4 Delta_gamma / E* (eq 14)"})
    ds.attrs["elastic_energy_model"] = "; ".join(f"{m}: {MODELS[m]}" for m in models)
    if spec["vanishing_hrms"]:
        ds = ds.compute()
        ds["hrms_substrate_vanishing"] = _vanishing(ds, psd, c0, c1, q, E_star, dg, zeta_values, K_min, tol, sigma0)
    return ds


def _vanishing(ds, psd, c0, c1, q, E_star, dg, zeta_values, K_min, tol, sigma0):
    if sigma0 != 0:
        raise UserError("the hrms at which adhesion vanishes is defined at zero load: set adhesion.sigma0 = 0 "
                        "or adhesion.vanishing_hrms = false", key="adhesion.vanishing_hrms")
    if "hrms_substrate" not in psd["psd_combined"].dims or psd.sizes["hrms_substrate"] < 2:
        raise UserError("needs substrate.hrms as a sweep (a list or {from, to, num}) that reaches detachment",
                        key="adhesion.vanishing_hrms")
    hs = psd["hrms_substrate"].values
    order = np.argsort(hs)
    K = ds["gamma_eff_macroscopic"].isel(hrms_substrate=order)
    C1 = psd["psd_substrate"].isel(hrms_substrate=order)
    C2 = psd["psd_solid"]
    eta = psd["eta"] if "eta" in psd.coords else xr.DataArray(0.0)
    try:
        h, status = xr.apply_ufunc(
            _vanishing_kernel, K, C1, C2, eta, c0, c1,
            input_core_dims=[["hrms_substrate"], ["hrms_substrate", "q"], ["q"], [], [], []],
            output_core_dims=[[], []], output_dtypes=[float, int],
            kwargs=dict(hs=hs[order], q=q, E_star=E_star, delta_gamma=dg, zeta=zeta_values, K_min=K_min, tol=tol),
        )
    except ComputationError as exc:
        cases = ", ".join(f"{d} = {list(np.atleast_1d(K[d].values))}" for d in K.dims if d != "hrms_substrate" and d in K.coords)
        raise ComputationError(f"adhesion stage, hrms at which adhesion vanishes ({cases or 'one case'}): {exc}") from None
    flat = np.ravel(status.values)
    if np.any(flat != 0):
        first = int(np.flatnonzero(flat)[0])
        index = np.unravel_index(first, status.shape) if status.ndim else ()
        where = ", ".join(f"{d} = {status[d].values[i]:g}" if status[d].dtype.kind == "f" else f"{d} = {status[d].values[i]}"
                          for d, i in zip(status.dims, index) if d in status.coords)
        more = int(np.count_nonzero(flat)) - 1
        why = (f"still attached at the largest swept substrate hrms {hs.max() * 1e10:.4g} angstrom: extend the sweep"
               if flat[first] == 1 else
               f"already detached at the smallest swept substrate hrms {hs.min() * 1e10:.4g} angstrom: start the sweep lower")
        at = f" at {where}" if where else ""
        also = f" (and {more} more case(s))" if more else ""
        raise UserError(f"cannot find the hrms at which adhesion vanishes{at}{also}: the partial-contact solution is {why}",
                        key="adhesion.vanishing_hrms")
    h.attrs = {"units": "m", "long_name": "substrate rms roughness at which adhesion vanishes (gamma_eff(1) and A/A0 "
               "reach 0 together; root along the attached branch, zero load)"}
    return h


# ----------------------------------------------------------------------------------------
# Figures (seed Figs 1 and 2)
# ----------------------------------------------------------------------------------------

_ANGSTROM = 1e-10


def _per_model(ds):
    if "model" in ds.dims:
        return [(str(m), ds.sel(model=m)) for m in ds["model"].values]
    return [(str(ds["model"].values) if "model" in ds.coords else "", ds)]


def _curve(ax_a, ax_b, ds, label, style, full=False, color=None):
    if "hrms_substrate" not in ds.dims:
        raise UserError("the adhesion figures need substrate.hrms as a sweep", key="substrate.hrms")
    h = ds["hrms_substrate"].values / _ANGSTROM
    dg = float(ds["delta_gamma"])
    g = ds["gamma_eff_macroscopic"].values / dg
    A = ds["adhesive_contact_area_ratio"].values
    hp, gp, Ap = h, g, A
    if "hrms_substrate_vanishing" in ds:  # the end of the attached branch, where both reach 0
        hv = float(ds["hrms_substrate_vanishing"]) / _ANGSTROM
        order = np.argsort(np.append(h, hv), kind="stable")
        hp, gp, Ap = np.append(h, hv)[order], np.append(g, 0.0)[order], np.append(A, 0.0)[order]
    (line,) = ax_a.plot(hp, gp, style, color=color, label=label, markersize=4, markevery=list(np.flatnonzero(np.isin(hp, h))))
    ax_b.plot(hp, Ap, style, color=line.get_color(), label=label, markersize=4, markevery=list(np.flatnonzero(np.isin(hp, h))))
    if full:
        ax_a.plot(h, ds["gamma_eff_full_contact"].values / dg, "-.", color=line.get_color(), label="full contact")
    if "hrms_substrate_vanishing" in ds:
        hv = float(ds["hrms_substrate_vanishing"]) / _ANGSTROM
        for ax in (ax_a, ax_b):
            ax.axvline(hv, color=line.get_color(), lw=0.8, ls=":")
        ax_b.annotate(f"{hv:.3f} Å", (hv, 0.02), rotation=90, va="bottom", ha="right", fontsize=8, color=line.get_color())


def _axes(title):
    import matplotlib.pyplot as plt

    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(10, 4.2))
    ax_a.set_ylabel("gamma_eff / Delta_gamma")
    ax_b.set_ylabel("A / A0 at zero load")
    for ax, tag in ((ax_a, "(a)"), (ax_b, "(b)")):
        ax.set_xlabel("rms roughness of the substrate (Å)")
        ax.set_title(tag, loc="left")
        ax.grid(alpha=0.3)
    ax_b.set_ylim(0, 1.02)
    fig.suptitle(title)
    return fig, ax_a, ax_b


def figure_one_surface(results):
    """Seed Fig 1: one rough surface, partial (solid) and full (dash-dot) contact theory."""
    variant = "substrate_only" if "substrate_only" in results else "base"
    ds = results[variant]["adhesion"]
    if "eta" in ds.dims:
        ds = ds.isel(eta=0)
    fig, ax_a, ax_b = _axes("One rough surface (seed Fig. 1)")
    for k, (label, d) in enumerate(_per_model(ds)):
        _curve(ax_a, ax_b, d, f"partial contact ({label})" if label else "partial contact", "-", full=(k == 0))
    top = float(ds["gamma_eff_full_contact"].max() / ds["delta_gamma"])
    ax_a.set_ylim(0, max(1.02, 1.05 * top))
    ax_a.legend(fontsize=8)
    fig.tight_layout()
    return fig


def figure_two_surfaces(results):
    """Seed Fig 2: two rough surfaces (eta = 0 solid, +1 dotted, -1 asterisks), substrate-only for reference."""
    ds = results["base"]["adhesion"]
    fig, ax_a, ax_b = _axes("Two rough surfaces (seed Fig. 2)")
    styles = {0.0: "-", 1.0: ":", -1.0: "*-"}
    for label, d in _per_model(ds):
        suffix = f" ({label})" if "model" in ds.dims else ""
        if "eta" in d.dims:
            for e in d["eta"].values:
                _curve(ax_a, ax_b, d.sel(eta=e), f"eta = {e:+g}{suffix}", styles.get(float(e), "--"))
        else:
            _curve(ax_a, ax_b, d, f"pair{suffix}", "-")
    if "substrate_only" in results:
        for label, d in _per_model(results["substrate_only"]["adhesion"]):
            _curve(ax_a, ax_b, d, "substrate only" + (f" ({label})" if "model" in ds.dims else ""), "--", color="0.6")
    ax_a.set_ylim(0, 1.02 * max(1.0, float(ds["gamma_eff_macroscopic"].max() / ds["delta_gamma"])))
    ax_a.legend(fontsize=8)
    fig.tight_layout()
    return fig


register(
    Stage(
        name="adhesion",
        version="1",
        compute=compute_adhesion,
        requires=("psd",),
        main_outputs=("hrms_substrate_vanishing",),
        tolerance=1e-3,
        params=("material.E", "material.nu", "adhesion", "numerics.adhesion_points_per_decade",
                "numerics.adhesion_zeta_offset", "numerics.adhesion_K_min", "numerics.adhesion_tolerance"),
        outputs={
            "gamma_eff_macroscopic": Var("J/m^2", "effective interfacial energy at the lowest magnification, partial contact"),
            "gamma_eff_full_contact": Var("J/m^2", "effective interfacial energy, full-contact theory"),
            "adhesive_contact_area_ratio": Var("1", "relative contact area A/A0 at the nominal stress sigma0 (zero load)"),
            "adhesive_area_ratio_zeta": Var("1", "P(zeta) = A(zeta)/A0 with adhesion"),
            "gamma_eff": Var("J/m^2", "effective interfacial energy gamma_eff(zeta), partial contact"),
            "detachment_stress": Var("Pa", "detachment stress sigma_a(zeta)"),
            "surface_area_factor": Var("1", "surface-area factor F (eq 11)"),
            "delta_gamma": Var("J/m^2", "interfacial binding energy of flat surfaces"),
            "adhesion_length": Var("m", "adhesion length delta (eq 14)"),
            "hrms_substrate_vanishing": Var("m", "substrate hrms at which adhesion vanishes"),
        },
        coords={"model": Var("1", "elastic-energy factor model")},
        figures=(
            Figure("fig1_adhesion_one_surface", "gamma_eff and A/A0 at zero load, one rough surface (seed Fig. 1)",
                   ("adhesion",), figure_one_surface),
            Figure("fig2_adhesion_two_surfaces", "gamma_eff and A/A0 at zero load, two rough surfaces (seed Fig. 2)",
                   ("adhesion",), figure_two_surfaces),
        ),
        doc="gamma_eff (full and partial contact), P(zeta), sigma_a(zeta), A/A0 at zero load, and the hrms at which "
            "adhesion vanishes.",
    )
)
