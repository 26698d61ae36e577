"""Adhesion of rough surfaces in partial contact: the Volterra equation of the contact area
with adhesion, solved self-consistently by a forward march in the magnification zeta.

P(zeta) = A(zeta)/A0 obeys the Volterra equation of seed eq 9 (primes restored) with the
detachment stress sigma_a(zeta) = [gamma_eff(zeta) E* zeta qL]^(1/2) (eq 6) and gamma_eff(zeta)
from P (eq 13 corrected, eq 50):

.. math::

    \\frac{\\gamma_{eff}(\\zeta)}{\\Delta\\gamma} = \\frac{P(\\zeta_1) F
    - \\frac{2\\pi}{\\delta} \\int_{\\zeta q_L}^{q_1} q^2 C P S_{el}\\, dq}{P(\\zeta)}

The numerator equals K + (2 pi/delta) int_{qL}^{zeta qL} q^2 C P S_el dq with
K = gamma_eff(1)/Delta_gamma (P(1) = 1), which depends only on P below zeta. So for a trial K
the whole solution is one forward march in zeta (eq 9 by product integration, node by node,
with the node's own self-consistency solved by a bracketed scalar root), and K is fixed by
the single condition at the top, numerator(zeta1) = P(zeta1) F. K = 0 (detached, P = 0) is
always a solution; the attached branch is the root with K > 0. The hrms at which adhesion
vanishes is where that root reaches K = 0+: it is found by root-finding in the substrate's
hrms at a tiny fixed K (continuation in K along the attached branch), bracketed by a sweep.

See docs/theory.md, section "Adhesion", and docs/adhesion.md (numerics and accuracy);
B. N. J. Persson and E. Tosatti, J. Chem. Phys. 115, 5597 (2001).
"""

from __future__ import annotations

import numpy as np

from roughcontact.errors import ComputationError

from .adhesion import AdhesionProblem
from .inputs import require_pressure
from .roots import illinois
from .spectra import hrms_from_psd, psd_combined


def abel_weights(a, i):
    """Product-trapezoid weights of the Abel kernel at node i.

    .. math:: \\int_0^{a_i} \\sqrt{a_i / (a_i - a')}\\, g(a')\\, da' = \\sum_{j \\le i} W_{ij} g(a_j)

    for g piecewise linear in a' between the nodes a_0 = 0 < a_1 < ... (exact for such g).
    Written without cancellation: with u = a_i - a', segment integrals of u^-1/2 and
    u^-1/2 (a' - a_{j-1}) are 2 d and (2/3) d (2 sqrt(u_lo) + sqrt(u_hi)) d / (sqrt(u_lo) + sqrt(u_hi))
    with d = (u_lo - u_hi) / (sqrt(u_lo) + sqrt(u_hi)).

    Parameters
    ----------
    a : array (B, M)
        Non-decreasing nodes (any units), a[:, 0] = 0.
    i : int
        Collocation node, 1 <= i < M.

    Returns
    -------
    array (B, i + 1)
        Weights, in the units of a.
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


class _NodeEquation:
    """Eq 9 at node i of the march as a function of the unknown P_i (see :func:`march`).

    Holds what does not depend on P_i; calling it with P_i (B,) returns the new P_i, s_i,
    N_i and sigma_a,i that P_i implies.
    """

    def __init__(self, st, i):
        a = st["a"]
        self.st, self.i = st, i
        ai = a[:, i]
        self.da = np.maximum(ai - a[:, i - 1], 0.0)
        W = abel_weights(a, i)
        dj = ai[:, None] - a[:, :i]
        self.okj = dj > 0
        self.dj4 = 4.0 * np.where(self.okj, dj, 1.0)
        self.Pprev = st["P"][:, i - 1]
        self.sprev = st["s"][:, i - 1]
        self.Ws = W[:, :i] * st["s"][:, :i]
        Wii = W[:, i]
        self.grows = (self.da > 0) & (Wii > 0)
        self.ai_pos = ai > 0
        self.ai4 = 4.0 * np.where(self.ai_pos, ai, 1.0)
        self.Wsafe = np.where(Wii > 0, Wii, 1.0)

    def _el(self, p):
        return p * (self.st["c0"] + self.st["c1"] * p * p)

    def __call__(self, Pi):
        st, i = self.st, self.i
        Ni = st["N"][:, i - 1] + st["wel"][:, i - 1] * 0.5 * (self._el(self.Pprev) + self._el(Pi))
        if st["sigma_fixed"] is None:
            pos = Pi > 0
            g = np.where(pos, Ni / np.where(pos, Pi, 1.0), np.where(Ni > 0, np.inf, 0.0))
            sg = np.sqrt(np.maximum(g, 0.0) * st["zeta"][i])
        else:
            sg = st["sigma_fixed"][:, i]
        fin = np.isfinite(sg)
        sgf = np.where(fin, sg, 0.0)
        with np.errstate(under="ignore"):
            E = np.where(self.okj, np.exp(-((sgf[:, None] - st["sig"][:, :i]) ** 2) / self.dj4), 0.0)
            lhs = np.where(self.ai_pos & fin, np.exp(-((sgf + st["sigma0"]) ** 2) / self.ai4), 0.0)
        known = np.sum(self.Ws * E, axis=1)
        # where a does not grow (no roughness on this segment) nothing detaches; s keeps its
        # value so that its piecewise-linear interpolant is not broken at the repeated node
        si = np.where(self.grows, np.maximum(lhs - known, 0.0) / self.Wsafe, np.where(self.da > 0, 0.0, self.sprev))
        Pn = np.maximum(self.Pprev - 0.5 * (self.sprev + si) * self.da, 0.0)
        return Pn, si, Ni, sgf


def _march_state(zeta, a, wel, K, sigma0, c0, c1, sigma_fixed):
    """Arrays of the march, node 0 filled in: P = 1, N = K, sigma_a(1) = (K zeta_0)^(1/2)."""
    a = np.asarray(a, dtype=float)
    B, M = a.shape
    st = {"zeta": zeta, "a": a, "wel": wel, "sigma_fixed": sigma_fixed,
          "sigma0": np.broadcast_to(np.asarray(sigma0, dtype=float), (B,)),
          "c0": np.broadcast_to(np.asarray(c0, dtype=float), (B,)),
          "c1": np.broadcast_to(np.asarray(c1, dtype=float), (B,)),
          "P": np.ones((B, M)), "N": np.zeros((B, M)), "sig": np.zeros((B, M)), "s": np.zeros((B, M))}
    K = np.broadcast_to(np.asarray(K, dtype=float), (B,))
    st["N"][:, 0] = K
    st["sig"][:, 0] = np.sqrt(np.maximum(K, 0.0) * zeta[0]) if sigma_fixed is None else sigma_fixed[:, 0]
    return st


def _solve_node(node, live, maxiter, tol):
    """P_i = T(P_i) on [0, P_{i-1}] by Illinois (T decreasing: x - T(x) rises through 0).

    Returns the node's (P_i, s_i, N_i, sigma_a,i) and |P_i - T(P_i)| where the bracket did
    not close (0 where it did)."""
    lo = np.zeros(live.shape)
    hi = node.Pprev.copy()

    def excess(x):
        return x - node(x)[0]

    root = illinois(excess, lo, hi, excess(lo), excess(hi), ftol=tol, xtol=tol, maxiter=maxiter, skip=~live)
    Pn, si, Ni, sg = node(root.x)
    return (Pn, si, Ni, sg), np.abs(Pn - root.x) * (root.hi - root.lo > tol)


def march(zeta, a, wel, F, K, sigma0=0.0, c0=1.0, c1=0.0, sigma_fixed=None, node_iterations=60, node_tol=1e-13):
    """One forward march of the partial-contact adhesion problem for trial K = gamma_eff(1)/Delta_gamma.

    Everything is dimensionless: stresses in units of sigma_u = (Delta_gamma E* qL)^(1/2),
    a in sigma_u^2. Seed eq 9 (primes restored) at node i:

    .. math::

        e^{-(\\sigma_{a,i} + \\sigma_0)^2 / 4 a_i}
        = \\sum_j W_{ij}\\, e^{-(\\sigma_{a,i} - \\sigma_{a,j})^2 / 4 (a_i - a_j)}\\, s_j

    with s = -dP/da piecewise linear (product trapezoid, :func:`abel_weights`), s >= 0,
    P_i = P_{i-1} - (s_{i-1} + s_i)(a_i - a_{i-1})/2 >= 0. The detachment stress
    sigma_a,i = (zeta_i N_i / P_i)^(1/2) (eq 6) with N_i = K + sum of w_el,j (S_el P)_mid
    (numerator of eq 13); it depends on P_i, so each node solves the scalar equation
    P_i = T(P_i) (T decreasing) by bracketed Illinois iteration on [0, P_{i-1}]
    (:func:`roughcontact.physics.roots.illinois`).

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
    node_iterations, node_tol : int, float
        Illinois iterations and tolerance (in P and in P - T(P)) of each node equation.

    Returns
    -------
    dict
        P, N, sigma (B, M), residual R = N(zeta1) - P(zeta1) F (B,), node_residual (max
        over nodes of |P_i - T(P_i)|).
    """
    st = _march_state(zeta, a, wel, K, sigma0, c0, c1, sigma_fixed)
    P, N, sig, s = st["P"], st["N"], st["sig"], st["s"]
    worst = np.zeros(P.shape[0])
    # sigma_a(1) + sigma0 = 0: nothing holds the surfaces together at the largest scale, eq 9
    # gives P = erf(0) = 0 at once (left to the march, the jump would be smeared over a segment)
    instant = sig[:, 0] + st["sigma0"] <= 0
    for i in range(1, P.shape[1]):
        node = _NodeEquation(st, i)
        live = (node.Pprev > 0) & ~instant
        (Pn, si, Ni, sg), residual = _solve_node(node, live, node_iterations, node_tol)
        worst = np.maximum(worst, np.where(live, residual, 0.0))
        P[:, i] = np.where(live, Pn, 0.0)
        s[:, i] = np.where(live, si, 0.0)
        N[:, i] = np.where(live, Ni, N[:, i - 1])
        sig[:, i] = np.where(live, sg, 0.0)
    return {"P": P, "N": N, "sigma": sig, "R": N[:, -1] - P[:, -1] * F, "node_residual": worst}


def detachment_volterra(a, sigma_a, sigma0=0.0, zeta=None):
    """The Volterra solver alone: P(zeta) for a prescribed detachment stress sigma_a(zeta) (seed eq 9).

    Parameters
    ----------
    a : array (B, M)
        Persson's a(zeta) = G(zeta) (Pa^2), a[:, 0] = 0, non-decreasing.
    sigma_a : array (B, M)
        Detachment stress (Pa) at the nodes.
    sigma0 : float
        Nominal compressive stress (Pa).
    zeta : array (M,), optional
        Magnifications of the nodes (only passed through; default 1).

    Returns
    -------
    array (B, M)
        P(zeta) = A(zeta)/A0. For constant sigma_a it approximates
        erf((sigma_a + sigma0) / (2 a^(1/2))) (product trapezoid: error ~ h^2.4).
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    sigma_a = np.broadcast_to(np.asarray(sigma_a, dtype=float), a.shape)
    scale = np.sqrt(np.maximum(a[:, -1], np.finfo(float).tiny))[:, None]
    zeta = np.ones(a.shape[1]) if zeta is None else zeta
    out = march(zeta, a / scale**2, np.zeros((a.shape[0], a.shape[1] - 1)), np.ones(a.shape[0]), np.zeros(a.shape[0]),
                sigma0=sigma0 / scale[:, 0], sigma_fixed=sigma_a / scale)
    return out["P"]


def _raise_unconverged(root, failed, what, maxiter):
    """ComputationError naming ``what``, with ``failed`` (B,) the cases that did not converge."""
    bad = ~root.converged
    err = ComputationError(f"{what}: no convergence in {maxiter} iterations for {int(bad.sum())} case(s); "
                           f"largest residual {np.max(np.abs(root.f[bad])):.3g}")
    err.failed = failed
    raise err


def solve_partial_contact(prob, sigma0, c0, c1, K_min=1e-8, tol=1e-10, maxiter=80, progress=None):
    """Self-consistent partial-contact solution (attached branch) for every PSD of ``prob``.

    Root of R(K) = N(zeta1) - P(zeta1) F in K = gamma_eff(1)/Delta_gamma (seed eqs 9, 13).
    R(F) >= 0 always. At zero load (sigma0 = 0) the root is sought on [K_min F, F] by Illinois
    in t = K^(1/6) (near K = 0 the detachment layer at zeta -> 1 makes R ~ K^(1/6), nearly
    linear in t); R(K_min F) >= 0 means there is no attached branch: the solids separate
    (K = 0, P = 0 beyond zeta = 1). Under a compressive sigma0 > 0 the contact holds even with
    K <= 0, and the root is sought on [-I, F], I = (2 pi/delta) int q^2 C S_el(1) dq (R(-I) <= 0).

    Parameters
    ----------
    prob : AdhesionProblem
        The batch of B PSDs on the Volterra grid.
    sigma0 : float or array (B,)
        Nominal compressive stress (Pa).
    c0, c1 : array (B,)
        S_el = c0 + c1 P^2 (:func:`roughcontact.physics.adhesion.elastic_energy_coefficients`).
    K_min : float
        Smallest K / F taken as attached.
    tol : float
        Tolerance of the root in R and, relatively, in t (or K).
    maxiter : int
        Illinois iterations.
    progress : callable, optional
        Called as ``progress(1)`` after each march over the batch (for a progress bar).

    Returns
    -------
    dict
        K (B,), P (B, M), gamma_ratio (= N/P, NaN where P = 0), sigma (dimensionless sigma_a),
        attached (B,), node_residual (B,). Raises ComputationError (with a ``failed`` mask
        over the batch) if the root does not converge.
    """
    require_pressure(sigma0, "sigma0")
    B = prob.a.shape[0]
    c0 = np.broadcast_to(np.asarray(c0, dtype=float), (B,))
    c1 = np.broadcast_to(np.asarray(c1, dtype=float), (B,))
    sig0 = np.broadcast_to(np.asarray(sigma0, dtype=float) / np.sqrt(prob.sigma_u2), (B,))

    def run(K, idx):
        R = march(prob.zeta, prob.a[idx], prob.wel[idx], prob.F[idx], K, sig0[idx], c0[idx], c1[idx])["R"]
        if progress is not None:
            progress(1)
        return R

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
            root = illinois(lambda t: run(t**6 * prob.F[idx], idx), t_lo[idx], np.ones(idx.size), f_lo[idx], f_hi,
                            ftol=tol, rtol=tol, maxiter=maxiter)
            if not np.all(root.converged):
                failed = np.zeros(B, dtype=bool)
                failed[idx] = ~root.converged
                _raise_unconverged(root, failed, what, maxiter)
            K[idx] = root.x**6 * prob.F[idx]
    else:
        attached = np.ones(B, dtype=bool)
        I_max = prob.wel.sum(axis=1) * (c0 + c1)
        lo, hi = -I_max, prob.F.copy()
        f_lo, f_hi = run(lo, every), run(hi, every)
        root = illinois(lambda k: run(k, every), lo, hi, np.minimum(f_lo, -0.0), f_hi, ftol=tol, rtol=tol,
                        maxiter=maxiter)
        if not np.all(root.converged):
            _raise_unconverged(root, ~root.converged, what, maxiter)
        K = root.x
    return _solution(prob, K, attached, sig0, c0, c1)


def _solution(prob, K, attached, sig0, c0, c1):
    """The march at the converged K, P = 0 beyond zeta = 1 where there is no attached branch."""
    out = march(prob.zeta, prob.a, prob.wel, prob.F, K, sig0, c0, c1)
    first = np.arange(prob.a.shape[1]) == 0
    P = np.where(attached[:, None], out["P"], np.where(first, 1.0, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(P > 0, out["N"] / np.where(P > 0, P, 1.0), np.nan)
    g[:, 0] = K
    return {"K": K, "P": P, "gamma_ratio": g, "sigma": np.where(attached[:, None], out["sigma"], 0.0),
            "attached": attached, "node_residual": out["node_residual"]}


def vanishing_scale(make_C, q, E_star, delta_gamma, zeta, h_lo, h_hi, c0, c1, K_min=1e-8, tol=1e-10, maxiter=100,
                    progress=None):
    """Substrate hrms at which adhesion vanishes (sigma0 = 0), by root-finding between an
    attached ``h_lo`` and a detached ``h_hi``.

    The attached branch ends where its root K = gamma_eff(1)/Delta_gamma reaches 0+; at the
    fixed tiny K = K_min F (continuation in K along the branch) the residual
    R(K_min F; h) of :func:`solve_partial_contact` changes sign there, and Illinois on h finds
    it (the error of a finite K_min is ~ K_min^(2/3) relative: 1e-8 -> ~1e-6).

    Parameters
    ----------
    make_C : callable h (B,) -> C (B, n)
        Combined PSD (m^4) for substrate hrms h (m).
    q : array (n,)
        Wavenumbers (1/m).
    E_star, delta_gamma : float
        Effective modulus (Pa) and binding energy (J/m^2).
    zeta : array (M,)
        Volterra nodes.
    h_lo, h_hi : array (B,)
        Bracket (m).
    c0, c1 : array (B,)
        S_el = c0 + c1 P^2.
    K_min : float
        Continuation point K / F.
    tol : float
        Relative tolerance in h.
    maxiter : int
        Illinois iterations.
    progress : callable, optional
        Called as ``progress(1)`` after each march (for a progress bar).

    Returns
    -------
    array (B,)
        The midpoint of the closed bracket (m).
    """
    def R(h):
        prob = AdhesionProblem(q, make_C(h), E_star, delta_gamma, zeta)
        residual = march(zeta, prob.a, prob.wel, prob.F, K_min * prob.F, 0.0, c0, c1)["R"]
        if progress is not None:
            progress(1)
        return residual

    f_lo, f_hi = R(h_lo), R(h_hi)
    if np.any(f_lo >= 0) or np.any(f_hi < 0):
        raise ComputationError("vanishing hrms: the sweep's attached/detached bracket is not confirmed at "
                               f"K = {K_min:g} F (residuals {f_lo}, {f_hi})")
    root = illinois(R, h_lo, h_hi, f_lo, f_hi, rtol=tol, maxiter=maxiter, skip=h_hi - h_lo <= tol * h_hi)
    bad = ~root.converged
    if np.any(bad):
        raise ComputationError(f"hrms at which adhesion vanishes: bracket not closed in {maxiter} iterations "
                               f"(width {np.max((root.hi - root.lo)[bad]):.3g} m)")
    return 0.5 * (root.lo + root.hi)


def vanishing_hrms_from_sweep(K, C1, C2, eta, c0, c1, hs, q, E_star, delta_gamma, zeta, K_min, tol, progress=None):
    """Per case, the substrate hrms where the attached branch ends, bracketed by a sweep.

    The bracket is the first step of the (increasing) substrate-hrms sweep from attached
    (K > 0) to detached; it is closed by :func:`vanishing_scale`, with the combined PSD
    rebuilt for each h from the substrate PSD per unit hrms^2 at the bracket's lower end and
    the solid's PSD (seed eq 52).

    Parameters
    ----------
    K : array (B, n)
        gamma_eff(1) along the sweep (any positive units; only its sign is used).
    C1 : array (B, n, nq)
        Substrate PSDs along the sweep (m^4).
    C2 : array (B, nq)
        Solid PSD (m^4).
    eta : array (B,)
        Coherence of the two surfaces.
    c0, c1 : array (B,)
        S_el = c0 + c1 P^2.
    hs : array (n,)
        Increasing substrate hrms of the sweep (m).
    q, E_star, delta_gamma, zeta, K_min, tol, progress
        As in :func:`vanishing_scale`.

    Returns
    -------
    (array (B,), int array (B,))
        The hrms (m; NaN where there is no bracket) and a status: 0 found, 1 still attached at
        the largest hrms, 2 detached at every hrms of the sweep.
    """
    B = K.shape[0]
    attached = K > 0
    ends = attached[:, :-1] & ~attached[:, 1:]
    has = ends.any(axis=1)
    out = np.full(B, np.nan)
    status = np.where(attached[:, -1], 1, np.where(~attached.any(axis=1), 2, 0))
    if np.any(has):
        idx = np.flatnonzero(has)
        j = np.argmax(ends[idx], axis=1)  # first attached -> detached step with growing hrms
        ref_C1 = C1[idx, j]
        unit = ref_C1 / hrms_from_psd(q, ref_C1)[:, None] ** 2

        def make_C(h):
            return psd_combined(h[:, None] ** 2 * unit, C2[idx], eta[idx, None])

        out[idx] = vanishing_scale(make_C, q, E_star, delta_gamma, zeta, hs[j], hs[j + 1], c0[idx], c1[idx],
                                   K_min=K_min, tol=tol, progress=progress)
    return out, status
