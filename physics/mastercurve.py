"""Master curves from multi-temperature DMA frequency sweeps: horizontal (and optional vertical)
time-temperature shifts and the law fitted to them (WLF, or WLF-Arrhenius).

Time-temperature superposition: the sweep at temperature T_j, shifted to reduced frequency
omega a_j and divided by b_j, lies on one curve E(omega, T_ref):

.. math:: E(\\omega, T_j) = b_j\\,E(\\omega a_j, T_\\mathrm{ref}), \\qquad
          \\log_{10}a_T = -\\frac{C_1 (T - T_\\mathrm{ref})}{C_2 + T - T_\\mathrm{ref}}.

``overlap`` shifts lay each sweep on its neighbour by the overlap of the two curves (Gergesova et
al., Rheol. Acta 50, 519 (2011)), chained from T_ref outwards, with the sign the temperature order
demands. ``free`` and ``wlf`` fit by least squares on the log moduli: every sweep's log10 E' and
log10 E'' against the one smooth curve (a cubic B-spline in log10 of the reduced frequency, refitted
for every trial shift) through all shifted data; ``free`` fits log10 a_j per sweep (started from the
overlap shifts) and then C1, C2 to them; ``wlf`` fits C1, C2 to the data directly. The relaxation
spectrum of the shifted master curve and the Kramers-Kronig check are in
:mod:`roughcontact.physics.relaxation_spectrum`. See docs/theory.md, section "Master curves from DMA
data"; Ferry, Viscoelastic Properties of Polymers, 3rd ed. (1980), ch. 11.

scipy.optimize and scipy.interpolate are imported inside the functions that fit (loading the stage
declarations, as a rerun with nothing to compute does, does not import them).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .viscoelastic import GAS_CONSTANT, wlf_arrhenius_log10_shift, wlf_log10_shift


class Shifts(NamedTuple):
    """Outcome of :func:`build_master_curve`.

    Attributes
    ----------
    log10_aT, log10_bT : arrays (n_T,)
        Horizontal and vertical shifts of the sweeps to T_ref (dimensionless, log10).
    C1, C2 : float
        WLF constants about T_ref (dimensionless; K).
    T_ref : float
        Reference temperature (K).
    residual : array (n_T,)
        rms of log10 E' and log10 E'' of each sweep about the shifted master curve (decades).
    wlf_residual : array (n_T,)
        log10 a_j minus the fitted WLF law (decades; 0 for ``wlf`` shifts).
    overlap, misfit : arrays (n_T,)
        Per sweep but the reference one (NaN there): overlap in log10 omega with the neighbour it
        was laid on (decades) and the rms distance of the two curves there (decades), at the overlap
        shifts.
    at_edge : bool array (n_T,)
        The overlap shift of the sweep wanted less overlap than allowed (not determined by overlap).
    law : str
        The law fitted to the shifts (:data:`SHIFT_LAWS`).
    T_g, E_a : float
        With ``law = "wlf_arrhenius"``: glass transition (K) and activation energy (J/mol) of the
        Arrhenius branch below it (NaN with ``wlf``).
    """

    log10_aT: np.ndarray
    log10_bT: np.ndarray
    C1: float
    C2: float
    T_ref: float
    residual: np.ndarray
    wlf_residual: np.ndarray
    overlap: np.ndarray
    misfit: np.ndarray
    at_edge: np.ndarray
    law: str = "wlf"
    T_g: float = float("nan")
    E_a: float = float("nan")


def _spline_residuals(x, ys, knots_per_decade):
    """Residuals of ys (each (m,)) about a least-squares cubic B-spline in x, uniform knots over x's span."""
    from scipy.interpolate import BSpline

    lo, hi = float(np.min(x)), float(np.max(x))
    n = max(2, int(np.ceil((hi - lo) * knots_per_decade)))
    inner = np.linspace(lo, hi, n + 1)
    t = np.concatenate([[lo] * 3, inner, [hi] * 3])
    M = BSpline.design_matrix(np.clip(x, lo, hi), t, 3).toarray()
    D = np.diff(np.eye(M.shape[1]), 2, axis=0) * 1e-3  # a whisper of smoothing where data are sparse
    A = np.vstack([M, D])
    out = []
    for y in ys:
        coef = np.linalg.lstsq(A, np.concatenate([y, np.zeros(D.shape[0])]), rcond=None)[0]
        out.append(y - M @ coef)
    return np.concatenate(out)


#: the quantities a sweep can be shifted on, as functions of (log10 E', log10 E'')
SHIFT_QUANTITIES = ("moduli", "storage", "loss", "tan_delta", "complex")


def shift_quantities(l1, l2, quantity):
    """The log10 curves (tuple of arrays) to superpose for ``quantity``: ``moduli`` (log10 E' and
    log10 E''), ``storage`` (E'), ``loss`` (E''), ``tan_delta`` (E''/E', which needs no vertical
    shift) or ``complex`` (|E*| = sqrt(E'^2 + E''^2)); l1, l2: log10 E', log10 E'' (Pa)."""
    if quantity == "moduli":
        return (l1, l2)
    if quantity == "storage":
        return (l1,)
    if quantity == "loss":
        return (l2,)
    if quantity == "tan_delta":
        return (l2 - l1,)
    if quantity == "complex":
        return (0.5 * np.log10(10.0 ** (2 * l1) + 10.0 ** (2 * l2)),)
    raise ValueError(f"unknown shift quantity {quantity!r}; one of {SHIFT_QUANTITIES}")


class PairShift(NamedTuple):
    """Shift of one sweep onto its neighbour (see :func:`pair_shift`)."""

    shift: float
    offset: float
    overlap: float
    misfit: float
    at_edge: bool


def _pair_cost(xa, ya, xb, yb, d, vertical, samples=40):
    """Mean squared vertical distance between the curves (xa, ya) and (xb + d, yb) over their overlap
    in x (the area between them divided by the overlap's length, sampled at ``samples`` points, linear
    interpolation in log-log), with the best common vertical offset removed if ``vertical``; and the
    offset and the overlap (decades)."""
    lo, hi = max(xa[0], xb[0] + d), min(xa[-1], xb[-1] + d)
    x = np.linspace(lo, hi, samples)
    diffs = [np.interp(x - d, xb, b) - np.interp(x, xa, a) for a, b in zip(ya, yb, strict=True)]
    off = float(np.mean(diffs)) if vertical else 0.0
    return float(np.mean([np.mean((r - off) ** 2) for r in diffs])), off, hi - lo


def pair_shift(xa, ya, xb, yb, vertical=False, min_overlap=0.5, step=0.02, flat_width=0.25, direction=0):
    """The horizontal shift d (decades) that lays sweep b, at x = log10 omega + d, on its neighbour a.

    d minimises the area between the two curves in log-log over their overlap divided by the
    overlap's length (the mean squared distance; Gergesova, Zupancic, Saprunov & Emri, Rheol. Acta
    50, 519 (2011), minimise the area between neighbouring curves), among the shifts that leave an
    overlap of at least ``min_overlap`` decades (or the whole narrower sweep, if shorter): a scan in
    steps of ``step`` decades, refined by a bounded scalar minimisation around the best step.
    Requiring an overlap keeps the shift from sliding to the edge of the data where two flat or
    noisy curves meet by chance. With ``direction`` the shift keeps the sign that the temperature
    order demands: every relaxation time shortens on heating (a_T decreases with T, as WLF and
    Arrhenius do; Ferry (1980), ch. 11), so a warmer sweep laid on a colder one has d <= 0
    (``direction = -1``) and a colder one d >= 0 (``+1``); where the overlap wants the other sign
    (a flat curve, or a vertical change the shift should not absorb) the shift stays at 0 and is
    flagged ``at_edge``.

    Parameters
    ----------
    xa, xb : arrays
        log10 omega of the two sweeps (rad/s), increasing.
    ya, yb : tuples of arrays
        The log10 quantities shifted on (:func:`shift_quantities`) at xa and xb.
    vertical : bool
        Remove the best common vertical offset (log10 b) for each trial shift.
    min_overlap, step : float
        Decades.
    flat_width : float
        Half-width (decades) of the range of shifts over which the cost may stay within four times its
        least value (plus 1e-6) before the shift counts as not determined (flat curves).
    direction : int
        Sign the shift must have: +1 (d >= 0, sweep b colder than a), -1 (d <= 0, b warmer) or 0 (any).

    Returns
    -------
    PairShift
        ``shift`` (decades), ``offset`` (log10 b of b relative to a; 0 without ``vertical``),
        ``overlap`` (decades), ``misfit`` (rms distance of the curves there, decades) and ``at_edge``
        (the shift is not determined by the overlap: the best shift is the smallest overlap allowed,
        i.e. the data want less overlap than that, or it is 0 because the data want the sign that
        ``direction`` excludes, or the cost is flat over more than 2 flat_width).

    References
    ----------
    docs/theory.md, section "Master curves from DMA data".
    """
    from scipy.optimize import minimize_scalar

    need = min(min_overlap, xa[-1] - xa[0], xb[-1] - xb[0])
    lo, hi = xa[0] - xb[-1] + need, xa[-1] - xb[0] - need
    if direction > 0:
        lo = min(max(lo, 0.0), hi)
    elif direction < 0:
        hi = max(min(hi, 0.0), lo)
    trials = np.arange(lo, hi + 0.5 * step, step) if hi > lo else np.array([0.5 * (lo + hi)])
    costs = np.array([_pair_cost(xa, ya, xb, yb, d, vertical)[0] for d in trials])
    k = int(np.argmin(costs))
    d = float(trials[k])
    if trials.size > 2:
        res = minimize_scalar(lambda t: _pair_cost(xa, ya, xb, yb, t, vertical)[0], method="bounded",
                              bounds=(max(lo, d - step), min(hi, d + step)), options={"xatol": 1e-4})
        if res.fun <= costs[k]:
            d = float(res.x)
    cost, off, overlap = _pair_cost(xa, ya, xb, yb, d, vertical)
    at_edge = trials.size > 2 and (k == 0 or k == trials.size - 1)
    # flat curves: the cost stays within a few times its least value (plus 0.001 decade squared) over a
    # wide range of shifts, so the overlap does not fix the shift
    level = 4.0 * costs[k] + 1e-6
    left = np.argmax(costs[k::-1] > level) if np.any(costs[k::-1] > level) else k + 1
    right = np.argmax(costs[k:] > level) if np.any(costs[k:] > level) else trials.size - k
    flat = (left + right) * step > 2 * flat_width
    return PairShift(d, off, overlap, float(np.sqrt(cost)), bool(at_edge or flat))


def overlap_shifts(logw, l1, l2, sweep, n_T, j0, quantity="moduli", vertical=False, min_overlap=0.5):
    """log10 a_j, log10 b_j of every sweep from the overlap of neighbours, chained from the sweep j0
    (the one at or nearest T_ref, a = b = 1) outwards: each warmer sweep is laid on its colder
    neighbour, each colder sweep on its warmer one (:func:`pair_shift`, with the sign the temperature
    order demands: log10 a_j does not increase with T), and the shifts add up.

    Parameters
    ----------
    logw, l1, l2 : arrays (m,)
        log10 omega (rad/s), log10 E', log10 E'' (Pa), sorted by sweep then frequency.
    sweep : int array (m,)
        Sweep index of each point (0 = coldest).
    n_T, j0 : int
        Number of sweeps; the reference sweep.
    quantity : str
        What is superposed (:data:`SHIFT_QUANTITIES`); with ``tan_delta`` the vertical shifts are
        still taken from E' and E'' at the chosen horizontal shift.
    vertical : bool
        Also fit log10 b per pair (relative to the neighbour).
    min_overlap : float
        Least overlap of neighbours allowed (decades).

    Returns
    -------
    (log10_a, log10_b, overlap, misfit, at_edge) : arrays (n_T,)
        Shifts (log10, about sweep j0) and, for each sweep but j0, the overlap with the neighbour it
        was laid on (decades), the rms distance there (decades) and whether the overlap is the least
        allowed; NaN / False for j0.

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Gergesova et al., Rheol. Acta 50, 519 (2011).
    """
    curves = shift_quantities(l1, l2, quantity)
    log_a, log_b = np.zeros(n_T), np.zeros(n_T)
    overlap, misfit, edge = np.full(n_T, np.nan), np.full(n_T, np.nan), np.zeros(n_T, dtype=bool)
    for j, ref in [(j, j - 1) for j in range(j0 + 1, n_T)] + [(j, j + 1) for j in range(j0 - 1, -1, -1)]:
        a, b = sweep == ref, sweep == j
        pair = pair_shift(logw[a], tuple(c[a] for c in curves), logw[b], tuple(c[b] for c in curves),
                          vertical and quantity != "tan_delta", min_overlap, direction=1 if j < ref else -1)
        off = pair.offset
        if vertical and quantity == "tan_delta":
            off = _pair_cost(logw[a], (l1[a], l2[a]), logw[b], (l1[b], l2[b]), pair.shift, True)[1]
        log_a[j] = log_a[ref] + pair.shift
        log_b[j] = log_b[ref] + off
        overlap[j], misfit[j], edge[j] = pair.overlap, pair.misfit, pair.at_edge
    return log_a, log_b, overlap, misfit, edge


def fit_wlf(T, log10_aT, T_ref, anchor=None, sigma=None, C2=None):
    """C1, C2 of the WLF law about T_ref fitted to measured shifts (least squares in log10 a_T).

    With ``C2`` given (K), only C1 is fitted (linear least squares): the way to a law from two
    temperatures, whose one relative shift cannot fix two constants.

    The shifts may be relative to the sweep ``anchor`` (then the model is W(T_j) - W(T_anchor));
    the start is the classical linearisation -(T - T_0)/log10 a = C2/C1 + (T - T_0)/C1. C2 is kept
    above T_ref - min(T) so that the law is finite at every measured temperature.

    Parameters
    ----------
    T : array (n,)
        Temperatures (K).
    log10_aT : array (n,)
        Shifts (log10).
    T_ref : float
        Reference temperature of the law (K).
    anchor : int or None
        Index whose shift is the zero of ``log10_aT`` (None: the shifts are absolute, about T_ref).
    sigma : array (n,) or None
        Standard errors of the shifts (decades): weights 1/sigma (the anchor's 0 is exact).
    C2 : float or None
        Fixed C2 (K), or None to fit it.

    Returns
    -------
    (C1, C2, residual) : (float, float (K), array (n,))
        WLF constants and log10 a_j minus the law (decades).

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Williams, Landel & Ferry, J. Am. Chem.
    Soc. 77, 3701 (1955).
    """
    from scipy.optimize import least_squares

    T = np.asarray(T, dtype=float)
    L = np.asarray(log10_aT, dtype=float)
    T0 = T[anchor] if anchor is not None else T_ref
    L0 = L - (L[anchor] if anchor is not None else 0.0)
    use = np.abs(T - T0) > 1e-9
    if C2 is not None:
        shape = wlf_log10_shift(T, T_ref, 1.0, C2)
        shape = shape - (wlf_log10_shift(T0, T_ref, 1.0, C2) if anchor is not None else 0.0)
        C1 = float(np.dot(shape, L0) / np.dot(shape, shape))
        return C1, float(C2), L0 - C1 * shape
    slope, intercept = np.polyfit(T[use] - T0, -(T[use] - T0) / np.where(L0[use] != 0, L0[use], 1e-30), 1)
    C1s, C2s = (1.0 / slope, intercept / slope) if slope > 0 and intercept > 0 else (10.0, 100.0)
    C2_start = C2s + (T_ref - T0)
    floor = T_ref - T.min()
    C2_start = max(C2_start, floor + 1.0)
    C1_start = C1s * C2s / C2_start if C2s > 0 else 10.0

    def model(p):
        C1, C2 = p[0], floor + np.exp(p[1])
        W = wlf_log10_shift(T, T_ref, C1, C2)
        return W - (wlf_log10_shift(T0, T_ref, C1, C2) if anchor is not None else 0.0)

    weight = 1.0 / np.maximum(sigma, 1e-6 * np.max(sigma)) if sigma is not None else np.ones_like(T)
    fit = least_squares(lambda p: (model(p) - L0) * weight, [C1_start, np.log(C2_start - floor)], x_scale="jac",
                        xtol=1e-14, ftol=1e-14, gtol=1e-14)
    C1, C2 = float(fit.x[0]), float(floor + np.exp(fit.x[1]))
    return C1, C2, L0 - model(fit.x)


#: shift laws fitted to the shifts: WLF, or WLF above T_g and Arrhenius below
SHIFT_LAWS = ("wlf", "wlf_arrhenius")


class ShiftLaw(NamedTuple):
    """A fitted WLF-Arrhenius law (see :func:`fit_wlf_arrhenius`): C1, C2 (K), T_g (K), E_a
    (J/mol) and log10 a_j minus the law (decades)."""

    C1: float
    C2: float
    T_g: float
    E_a: float
    residual: np.ndarray


def fit_wlf_arrhenius(T, log10_aT, T_ref, anchor=None, sigma=None, T_g=None):
    """WLF above T_g and Arrhenius below it (:func:`~roughcontact.physics.viscoelastic.wlf_arrhenius_log10_shift`),
    continuous in log10 a_T at T_g, fitted to measured shifts (least squares in log10 a_T).

    With ``T_g`` given, C1, C2 and E_a are fitted; else T_g too, as the breakpoint: every T_g on a
    grid of 1/4 of the smallest temperature step between the second-coldest and the third-warmest
    temperature (below T_ref) is tried, and the best is refined within one grid step. The start of
    each fit is WLF fitted to the shifts at and above T_g (:func:`fit_wlf`) and E_a by linear least
    squares on the shifts below. C2 is kept above T_ref - T_g, so that the WLF branch is finite.

    Parameters
    ----------
    T : array (n,)
        Temperatures (K), increasing.
    log10_aT : array (n,)
        Shifts (log10), relative to the sweep ``anchor`` (or absolute, about T_ref, if None).
    T_ref : float
        Reference temperature of the law (K), above T_g.
    anchor : int or None
        Index whose shift is the zero of ``log10_aT``.
    sigma : array (n,) or None
        Standard errors of the shifts (decades): weights 1/sigma.
    T_g : float or None
        Given glass-transition temperature (K), or None to fit it.

    Returns
    -------
    ShiftLaw

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Ferry (1980), ch. 11.
    """
    from scipy.optimize import least_squares

    T = np.asarray(T, dtype=float)
    L = np.asarray(log10_aT, dtype=float)
    T0 = T[anchor] if anchor is not None else T_ref
    L0 = L - (L[anchor] if anchor is not None else 0.0)
    weight = 1.0 / np.maximum(sigma, 1e-6 * np.max(sigma)) if sigma is not None else np.ones_like(T)
    k = GAS_CONSTANT * np.log(10.0)

    def law(C1, C2, Tg, Ea):
        W = wlf_arrhenius_log10_shift(T, T_ref, C1, C2, Tg, Ea)
        return W - (wlf_arrhenius_log10_shift(T0, T_ref, C1, C2, Tg, Ea) if anchor is not None else 0.0)

    def fit_at(Tg, free_Tg=False, span=0.0, start=None):
        floor = T_ref - Tg + (span if free_Tg else 0.0)
        if start is None:
            above = T >= Tg
            anchor_above = (anchor if anchor is not None and above[anchor] else None)
            idx = np.flatnonzero(above)
            a = int(np.flatnonzero(idx == anchor_above)[0]) if anchor_above is not None else None
            try:
                C1, C2, _ = fit_wlf(T[above], L0[above], T_ref, anchor=a)
            except (ValueError, np.linalg.LinAlgError):
                C1, C2 = 10.0, 100.0
            C2 = max(C2, floor + 1.0)
            W = wlf_log10_shift(Tg, T_ref, C1, C2) - (wlf_log10_shift(T0, T_ref, C1, C2) if anchor is not None else 0)
            x = 1.0 / T[~above] - 1.0 / Tg
            slope = float(np.dot(x, L0[~above] - W) / np.dot(x, x)) if x.size else 1e4
            start = [C1, C2, Tg, max(slope * k, 1.0)]
        C1, C2, _, Ea = start
        p0 = [C1, np.log(max(C2 - floor, 1e-6)), np.log(Ea)] + ([Tg] if free_Tg else [])

        def unpack(p):
            with np.errstate(over="ignore"):  # trial steps of the solver far out; the cost is then inf
                return p[0], floor + np.exp(p[1]), (p[3] if free_Tg else Tg), np.exp(p[2])

        lo = [-np.inf] * 3 + ([Tg - span] if free_Tg else [])
        hi = [np.inf] * 3 + ([Tg + span] if free_Tg else [])
        if free_Tg:
            p0[3] = float(np.clip(start[2], lo[3] + 1e-9, hi[3] - 1e-9))
        fit = least_squares(lambda p: (law(*unpack(p)) - L0) * weight, p0, bounds=(lo, hi), x_scale="jac",
                            xtol=1e-15, ftol=1e-15, gtol=1e-15)
        params = unpack(fit.x)
        return float(np.sum(((law(*params) - L0) * weight) ** 2)), params

    if T_g is not None:
        _, params = fit_at(float(T_g))
    else:
        step = np.min(np.diff(T)) / 4.0
        hi_Tg = min(T[-3], T_ref) if T.size >= 5 else T_ref
        grid = np.arange(T[1], hi_Tg + 0.5 * step, step)
        if grid.size == 0:
            raise ValueError("too few temperatures to fit the glass transition: at least 5 are needed")
        trials = [fit_at(Tg) for Tg in grid]
        best = int(np.argmin([c for c, _ in trials]))
        cost, params = trials[best]
        refined = fit_at(float(grid[best]), free_Tg=True, span=step, start=params)
        if refined[0] <= cost:
            params = refined[1]
    C1, C2, Tg, Ea = (float(v) for v in params)
    return ShiftLaw(C1, C2, Tg, Ea, L0 - law(C1, C2, Tg, Ea))


def _per_sweep_rms(r, sweep, n_T):
    """rms of the residual pairs (E', E'') of each sweep."""
    r = r.reshape(2, -1)
    return np.array([np.sqrt(np.mean(r[:, sweep == j] ** 2)) for j in range(n_T)])


def bin_sweeps(sweep, logw, values, per_decade=20.0):
    """Means of ``values`` (each (m,), e.g. log10 E') and of log10 omega in bins of 1/``per_decade``
    decade of each sweep: a sweep logged at many points costs the fit no more than its bins.

    Parameters
    ----------
    sweep : int array (m,)
        Sweep of each point (sorted by sweep, then frequency).
    logw : array (m,)
        log10 omega (rad/s).
    values : tuple of arrays (m,)
        What to average per bin (the log10 moduli).
    per_decade : float
        Bins per decade of frequency.

    Returns
    -------
    (sweep, logw, values, counts)
        The binned points (sweep, mean log10 omega, mean values) and the number of points in each bin.
    """
    key = np.floor(logw * per_decade).astype(np.int64)
    ids = sweep.astype(np.int64) * (key.max() - key.min() + 2) + (key - key.min())
    _, first, inverse, counts = np.unique(ids, return_index=True, return_inverse=True, return_counts=True)
    mean = lambda v: np.bincount(inverse, weights=v) / counts  # noqa: E731
    order = np.argsort(first, kind="stable")  # keep the file order: by sweep, then frequency
    return sweep[first][order], mean(logw)[order], tuple(mean(v)[order] for v in values), counts[order]


def build_master_curve(T, sweep, omega, storage, loss, T_ref, method="overlap", vertical=False, quantity="moduli",
                       min_overlap=0.5, knots_per_decade=2.0, C2=None, law="wlf", T_g=None):
    """Shift multi-temperature sweeps onto one master curve at T_ref and fit the WLF law.

    ``method = "overlap"``: each sweep laid on its neighbour by the overlap of the two curves of
    ``quantity``, chained from the sweep nearest T_ref outwards (:func:`overlap_shifts`), then C1,
    C2 fitted to the shifts (:func:`fit_wlf`). ``"free"``: one log10 a_j per sweep by least squares
    on log10 E' and log10 E'' of every point against one cubic B-spline in the reduced frequency
    (``knots_per_decade`` uniform knots, refitted for each trial shift), started from the overlap
    shifts, then C1, C2 fitted to them. ``"wlf"``: C1, C2 fitted to the data directly (the same
    spline residual), started from the overlap shifts' law. ``vertical`` adds one log10 b_j per
    sweep (b = 1 at the sweep nearest T_ref). ``C2`` (K) fixes C2 of the law fitted to the shifts
    (needed with two temperatures). ``law = "wlf_arrhenius"`` fits WLF above T_g and Arrhenius below
    to the shifts (:func:`fit_wlf_arrhenius`; T_g given or fitted as the breakpoint) instead of WLF
    (``overlap`` and ``free`` only).

    Parameters
    ----------
    T : array (n_T,)
        Sweep temperatures (K), increasing.
    sweep : int array (m,)
        Sweep of each point.
    omega, storage, loss : arrays (m,)
        Angular frequency (rad/s), E' (Pa, > 0) and E'' (Pa, >= 0; zeros are raised to 1e-12 E').
    T_ref : float
        Reference temperature (K).
    quantity : str
        What the overlap shifts superpose (:data:`SHIFT_QUANTITIES`).
    min_overlap : float
        Least overlap of neighbouring sweeps (decades) for the overlap shifts.

    Returns
    -------
    Shifts

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Ferry (1980), ch. 11.
    """
    from scipy.optimize import least_squares

    T = np.asarray(T, dtype=float)
    n_T = T.size
    logw, l1 = np.log10(omega), np.log10(storage)
    l2 = np.log10(np.maximum(loss, 1e-12 * storage))
    j0 = int(np.argmin(np.abs(T - T_ref)))
    others = np.arange(n_T) != j0
    la, lb, overlap, misfit, edge = overlap_shifts(logw, l1, l2, sweep, n_T, j0, quantity, vertical, min_overlap)

    def unpack(theta, horizontal):
        a = np.zeros(n_T)
        a[others] = horizontal
        b = np.zeros(n_T)
        if vertical:
            b[others] = theta[-(n_T - 1):]
        return a, b

    def residual(a, b):
        return _spline_residuals(logw + a[sweep], (l1 - b[sweep], l2 - b[sweep]), knots_per_decade)

    sigma = None
    if method == "free":
        free = least_squares(lambda th: residual(*unpack(th, th[:n_T - 1])),
                             np.concatenate([la[others]] + ([lb[others]] if vertical else [])), x_scale=1.0)
        la, lb = unpack(free.x, free.x[:n_T - 1])
        J = free.jac[:, :n_T - 1]
        cov = np.linalg.pinv(J.T @ J) * 2.0 * free.cost / max(J.shape[0] - free.x.size, 1)
        sigma = np.zeros(n_T)
        sigma[others] = np.sqrt(np.maximum(np.diag(cov), 0.0))
        sigma[j0] = np.min(sigma[others])
    if law == "wlf_arrhenius":
        if method == "wlf":
            raise ValueError("the WLF-Arrhenius law is fitted to overlap or free shifts, not to the data directly")
        fitted = fit_wlf_arrhenius(T, la, T_ref, anchor=j0, sigma=sigma, T_g=T_g)
        log_a = la + wlf_arrhenius_log10_shift(T[j0], T_ref, fitted.C1, fitted.C2, fitted.T_g, fitted.E_a)
        r = residual(log_a, lb)
        return Shifts(log_a, lb, fitted.C1, fitted.C2, float(T_ref), _per_sweep_rms(r, sweep, n_T), fitted.residual,
                      overlap, misfit, edge, law, fitted.T_g, fitted.E_a)
    C1, C2, wres = fit_wlf(T, la, T_ref, anchor=j0, sigma=sigma, C2=C2)
    log_a = la + wlf_log10_shift(T[j0], T_ref, C1, C2)
    if method == "wlf":
        floor = T_ref - T.min()

        def law(th):
            return wlf_log10_shift(T, T_ref, th[0], floor + np.exp(th[1]))

        start = np.concatenate([[C1, np.log(max(C2 - floor, 1e-3))], lb[others] if vertical else []])
        fit = least_squares(lambda th: residual(law(th), unpack(th, law(th)[others])[1]), start, x_scale="jac")
        C1, C2 = float(fit.x[0]), float(floor + np.exp(fit.x[1]))
        log_a = law(fit.x)
        lb = unpack(fit.x, log_a[others])[1]
        wres = np.zeros(n_T)
    r = residual(log_a, lb)
    return Shifts(log_a, lb, C1, C2, float(T_ref), _per_sweep_rms(r, sweep, n_T), wres, overlap, misfit, edge)
