"""Viscoelastic modulus: models of the complex Young's modulus E(omega) of a rubber, its
temperature shift and its evaluation between tabulated frequencies.

The modulus comes from a model (box relaxation spectrum, generalized Maxwell / Prony series,
or a real constant for the elastic limit) or from a measured master curve at a reference
temperature, and is shifted to other temperatures by the time-temperature superposition

.. math:: E(\\omega, T) = b_T \\, E(\\omega a_T, T_\\mathrm{ref}),

with the horizontal factor a_T from the WLF equation or a table and the vertical factor b_T.
Every function takes and returns SI values (rad/s, Pa, s, K). The seed uses E(omega) in its
Fig. 7 and eqs 29-32, 61-62. See docs/theory.md, section "Viscoelasticity"; Tschoegl, The Phenomenological
Theory of Linear Viscoelastic Behavior (1989); Williams, Landel & Ferry, J. Am. Chem. Soc. 77,
3701 (1955).
"""

from __future__ import annotations

import numpy as np

from .quadrature import loglog_interp

#: largest |log10 a_T| accepted: beyond it (relaxation times shifted by more than 100 decades)
#: no shift law is physical, and the frequency grid would leave floating-point range
MAX_LOG10_SHIFT = 100


def _half_log1p_sq(x):
    """0.5 ln(1 + x^2) without overflow for huge |x|."""
    x = np.abs(np.asarray(x, dtype=float))
    big = x > 1.0
    xs = np.where(big, x, 1.0)
    return np.where(big, np.log(xs) + 0.5 * np.log1p(1.0 / (xs * xs)), 0.5 * np.log1p(np.where(big, 0.0, x) ** 2))


def box_spectrum_modulus(omega, E0, E_inf, tau1, tau2):
    """Complex modulus of the box relaxation spectrum (Pa).

    .. math:: E(\\omega) = E_0 + \\frac{E_\\infty - E_0}{\\ln(\\tau_2/\\tau_1)}
              [\\ln(1 + i\\omega\\tau_2) - \\ln(1 + i\\omega\\tau_1)],

    a flat distribution of relaxation times in ln(tau) between tau1 and tau2. It goes from the
    rubbery modulus E0 (omega -> 0) to the glassy modulus E_inf (omega -> infinity); between
    1/tau2 and 1/tau1 the loss modulus is nearly flat, E'' ~ (pi/2) (E_inf - E0) / ln(tau2/tau1).

    Evaluated as E' = E0 + D [L(omega tau2) - L(omega tau1)], L(x) = 0.5 ln(1 + x^2), and
    E'' = D arctan(omega (tau2 - tau1) / (1 + omega^2 tau1 tau2)), D = (E_inf - E0)/ln(tau2/tau1):
    no overflow and no cancellation of the two arctangents at high frequency.

    Parameters
    ----------
    omega : array
        Angular frequency (rad/s); negative values give the complex conjugate.
    E0, E_inf : float
        Relaxed (rubbery) and unrelaxed (glassy) Young's moduli (Pa), E_inf > E0 > 0.
    tau1, tau2 : float
        Shortest and longest relaxation times (s), 0 < tau1 < tau2.

    Returns
    -------
    (E', E'') : arrays
        Storage and loss moduli (Pa); E'' has the sign of omega.

    References
    ----------
    docs/theory.md, section "Viscoelasticity" (the modulus of the seed's Fig. 7); Tschoegl, The Phenomenological
    Theory of Linear Viscoelastic Behavior (1989), ch. 3 (box distribution).
    """
    omega = np.asarray(omega, dtype=float)
    D = (E_inf - E0) / np.log(tau2 / tau1)
    storage = E0 + D * (_half_log1p_sq(omega * tau2) - _half_log1p_sq(omega * tau1))
    with np.errstate(over="ignore"):
        loss = D * np.arctan(omega * (tau2 - tau1) / (1.0 + (omega * omega) * (tau1 * tau2)))
    return storage, loss


def prony_modulus(omega, E0, moduli, times):
    """Complex modulus of a generalized Maxwell model / Prony series (Pa).

    .. math:: E(\\omega) = E_0 + \\sum_k E_k \\frac{i\\omega\\tau_k}{1 + i\\omega\\tau_k},

    i.e. E' = E0 + sum E_k x_k^2 / (1 + x_k^2), E'' = sum E_k x_k / (1 + x_k^2), x_k = omega tau_k
    (written in 1/x_k for |x_k| > 1: no overflow).

    Parameters
    ----------
    omega : array
        Angular frequency (rad/s); negative values give the complex conjugate.
    E0 : float
        Equilibrium (relaxed) modulus (Pa).
    moduli, times : arrays (K,)
        Prony moduli E_k (Pa, > 0) and relaxation times tau_k (s, > 0).

    Returns
    -------
    (E', E'') : arrays
        Storage and loss moduli (Pa), shape of ``omega``.

    References
    ----------
    docs/theory.md, section "Viscoelasticity"; Tschoegl (1989), ch. 3.
    """
    omega = np.asarray(omega, dtype=float)[..., None]
    moduli = np.asarray(moduli, dtype=float)
    x = omega * np.asarray(times, dtype=float)
    ax = np.abs(x)
    small = ax <= 1.0
    inv = np.where(small, 1.0, 1.0 / np.where(small, 1.0, x))
    xs = np.where(small, x, 0.0)
    sq = np.where(small, xs * xs / (1.0 + xs * xs), 1.0 / (1.0 + inv * inv))
    lin = np.where(small, xs / (1.0 + xs * xs), inv / (1.0 + inv * inv))
    return E0 + (moduli * sq).sum(-1), (moduli * lin).sum(-1)


def elastic_modulus(omega, E):
    """The elastic limit: a real, frequency-independent modulus, E' = E, E'' = 0 (Pa).

    Parameters
    ----------
    omega : array
        Angular frequency (rad/s).
    E : float
        Young's modulus (Pa).

    Returns
    -------
    (E', E'') : arrays (Pa), shape of ``omega``.

    References
    ----------
    docs/theory.md, section "Viscoelasticity" (with it the friction of eq 61 vanishes).
    """
    return np.full(np.shape(omega), E), np.zeros(np.shape(omega))


def loss_modulus_from_tan_delta(storage, tan_delta):
    """Loss modulus from the storage modulus and the loss tangent (Pa).

    .. math:: E'' = E' \\tan\\delta,

    the definition of the loss tangent, tan delta = E''/E' (the phase lag of strain behind
    stress in harmonic loading). Measured master curves and DMA sweeps often give tan delta
    instead of E''.

    Parameters
    ----------
    storage : array
        Storage modulus E' (Pa).
    tan_delta : array
        Loss tangent tan delta (dimensionless), shape of ``storage``.

    Returns
    -------
    E'' : array (Pa).

    References
    ----------
    docs/theory.md, section "Viscoelasticity"; Ferry, Viscoelastic Properties of Polymers, 3rd
    ed. (1980), ch. 1; Tschoegl (1989), ch. 4.
    """
    return np.asarray(storage, dtype=float) * np.asarray(tan_delta, dtype=float)


def wlf_log10_shift(T, T_ref, C1, C2):
    """WLF horizontal shift factor (dimensionless, log10).

    .. math:: \\log_{10} a_T = -\\frac{C_1 (T - T_\\mathrm{ref})}{C_2 + T - T_\\mathrm{ref}}

    E(omega, T) = E(omega a_T, T_ref): at higher temperature (a_T < 1) the same modulus is
    reached at higher frequency.

    Parameters
    ----------
    T, T_ref : float or array
        Temperature and reference temperature (K).
    C1 : float
        WLF constant (dimensionless; universal value 17.44 with T_ref = Tg).
    C2 : float
        WLF constant (K; universal value 51.6 K with T_ref = Tg). Needs C2 + T - T_ref > 0.

    Returns
    -------
    float or array
        log10 a_T.

    References
    ----------
    docs/theory.md, section "Viscoelasticity"; Williams, Landel & Ferry, J. Am. Chem. Soc. 77, 3701 (1955).
    """
    dT = np.asarray(T, dtype=float) - T_ref
    return -C1 * dT / (C2 + dT)


#: gas constant (J/(mol K))
GAS_CONSTANT = 8.314462618


def wlf_arrhenius_log10_shift(T, T_ref, C1, C2, T_g, E_a):
    """WLF above the glass transition T_g, Arrhenius below it, continuous in log10 a_T at T_g.

    .. math:: \\log_{10} a_T = \\begin{cases} W(T) & T \\ge T_g \\\\
              W(T_g) + \\dfrac{E_a}{R \\ln 10}\\left(\\dfrac{1}{T} - \\dfrac{1}{T_g}\\right) & T < T_g \\end{cases}

    with W the WLF law (:func:`wlf_log10_shift`) about T_ref.

    Parameters
    ----------
    T, T_ref : float or array
        Temperature and reference temperature (K); T_ref >= T_g, so that a_T(T_ref) = 1.
    C1, C2 : float
        WLF constants (dimensionless; K). Needs C2 + T_g - T_ref > 0.
    T_g : float
        Glass-transition temperature where the law changes branch (K).
    E_a : float
        Activation energy of the Arrhenius branch (J/mol).

    Returns
    -------
    float or array
        log10 a_T.

    References
    ----------
    docs/theory.md, section "Master curves from DMA data"; Ferry, Viscoelastic Properties of Polymers,
    3rd ed. (1980), ch. 11.
    """
    T = np.asarray(T, dtype=float)
    glassy = wlf_log10_shift(T_g, T_ref, C1, C2) + E_a / (GAS_CONSTANT * np.log(10.0)) * (1.0 / T - 1.0 / T_g)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(T >= T_g, wlf_log10_shift(T, T_ref, C1, C2), glassy)


def shift_factors(T, T_ref, horizontal="none", vertical="none", C1=17.44, C2=51.6,
                  table_T=None, table_log10_aT=None, table_log10_bT=None, T_g=None, E_a=None):
    """Horizontal and vertical shift factors of time-temperature superposition.

    .. math:: E(\\omega, T) = b_T \\, E(\\omega a_T, T_\\mathrm{ref})

    Parameters
    ----------
    T : array (n,)
        Temperatures (K).
    T_ref : float or None
        Reference temperature (K); needed unless both shifts are ``"none"``.
    horizontal : {"none", "wlf", "wlf_arrhenius", "table"}
        a_T = 1, the WLF law (:func:`wlf_log10_shift` with ``C1``, ``C2`` in K), WLF above ``T_g``
        (K) and Arrhenius with ``E_a`` (J/mol) below (:func:`wlf_arrhenius_log10_shift`), or log10 a_T
        interpolated linearly in T in the table (``table_T`` in K, ``table_log10_aT``).
    vertical : {"none", "entropic", "table"}
        b_T = 1, b_T = T / T_ref (entropic elasticity), or log10 b_T interpolated linearly in T
        in the table (``table_T``, ``table_log10_bT``).

    Returns
    -------
    (log10_aT, b_T) : arrays (n,)
        log10 of the horizontal factor and the vertical factor (dimensionless).

    References
    ----------
    docs/theory.md, section "Viscoelasticity"; Ferry, Viscoelastic Properties of Polymers, 3rd ed. (1980), ch. 11.
    """
    if horizontal == "wlf":
        log_aT = wlf_log10_shift(T, T_ref, C1, C2)
    elif horizontal == "wlf_arrhenius":
        log_aT = wlf_arrhenius_log10_shift(T, T_ref, C1, C2, T_g, E_a)
    elif horizontal == "table":
        log_aT = np.interp(T, np.atleast_1d(table_T), np.atleast_1d(table_log10_aT))
    else:
        log_aT = np.zeros_like(T)
    if vertical == "entropic":
        b_T = T / T_ref
    elif vertical == "table":
        b_T = 10.0 ** np.interp(T, np.atleast_1d(table_T), np.atleast_1d(table_log10_bT))
    else:
        b_T = np.ones_like(T)
    return np.asarray(log_aT, dtype=float), b_T


def worst_shift(log10_aT):
    """Index of the first shift beyond the physical range (|log10 a_T| > :data:`MAX_LOG10_SHIFT`
    or not finite), the largest one; None when every shift is within it.

    Parameters
    ----------
    log10_aT : array
        log10 of horizontal shift factors (dimensionless).
    """
    log10_aT = np.asarray(log10_aT, dtype=float)
    if np.any(~np.isfinite(log10_aT)) or np.any(np.abs(log10_aT) > MAX_LOG10_SHIFT):
        return int(np.argmax(np.where(np.isfinite(log10_aT), np.abs(log10_aT), np.inf)))
    return None


def frequency_grid(aT, points_per_decade, times=None, data_omega=None, omega_min=None, omega_max=None):
    """Geometric grid of angular frequencies (rad/s) on which a modulus is tabulated.

    By default it covers the relaxation spectrum (times ``times``) or the measured curve
    (``data_omega``) at every temperature, with 3 decades to spare, and at least
    [1e-6, 1e12] rad/s, its ends rounded out to powers of ten.

    Parameters
    ----------
    aT : array
        Horizontal shift factors of the temperatures (dimensionless).
    points_per_decade : int
        Grid points per decade of omega (at least 4 points in all).
    times : (float, float) or None
        Shortest and longest relaxation times (s) of a model.
    data_omega : array or None
        Reduced angular frequencies of a measured master curve (rad/s), increasing.
    omega_min, omega_max : float or None
        Ends of the grid (rad/s), overriding the default ones.

    Returns
    -------
    array
        The grid (rad/s), geometric.

    References
    ----------
    docs/theory.md, section "Viscoelasticity" (cubic log-log interpolation between the nodes: :func:`modulus_at`).
    """
    lo, hi = 1e-6, 1e12
    if times is not None:
        lo = min(lo, 1e-3 / (times[1] * aT.max()))
        hi = max(hi, 1e3 / (times[0] * aT.min()))
    if data_omega is not None:
        lo = min(lo, data_omega[0] / aT.max())
        hi = max(hi, data_omega[-1] / aT.min())
    lo = 10.0 ** np.floor(np.log10(lo))
    hi = 10.0 ** np.ceil(np.log10(hi))
    lo = omega_min or lo
    hi = omega_max or hi
    n = int(np.ceil(np.log10(hi / lo) * points_per_decade)) + 1
    return np.geomspace(lo, hi, max(n, 4))


def extrapolate_modulus(omega, omega_lo, omega_hi, storage_lo, loss_lo, storage_hi, loss_hi):
    """Physical asymptotes of a viscoelastic solid outside [omega_lo, omega_hi] (omega > 0).

    Below: rubbery plateau, E' = E'(omega_lo), E'' = E''(omega_lo) omega / omega_lo (E'' ~ omega);
    above: glassy plateau, E' = E'(omega_hi), E'' = E''(omega_hi) omega_hi / omega (E'' ~ 1/omega).
    These are the terminal behaviours of any solid with a bounded relaxation spectrum.

    Parameters
    ----------
    omega : array
        Angular frequencies (rad/s), > 0.
    omega_lo, omega_hi : float
        Ends of the known range (rad/s).
    storage_lo, loss_lo, storage_hi, loss_hi : float or array
        E', E'' at the two ends (Pa).

    Returns
    -------
    (E', E'', inside) : arrays
        The asymptotes (Pa) and a mask of the points not extrapolated (their values are left
        to the caller: NaN here).

    References
    ----------
    docs/theory.md, section "Viscoelasticity"; Tschoegl (1989), ch. 3 (terminal behaviour).
    """
    omega = np.asarray(omega, dtype=float)
    below = omega < omega_lo
    above = omega > omega_hi
    with np.errstate(divide="ignore", invalid="ignore"):
        storage = np.where(below, storage_lo, np.where(above, storage_hi, np.nan))
        loss_above = loss_hi * omega_hi / np.where(above, omega, 1.0)
        loss = np.where(below, loss_lo * omega / omega_lo, np.where(above, loss_above, np.nan))
    return storage, loss, ~(below | above)


def _gather(y, idx):
    nd = max(y.ndim, idx.ndim)
    y = y.reshape((1,) * (nd - y.ndim) + y.shape)
    idx = idx.reshape((1,) * (nd - idx.ndim) + idx.shape)
    return np.take_along_axis(y, idx, axis=-1)


def _uniform_cubic(y, s):
    """4-point Lagrange interpolation of ``y`` (..., n) on the uniform grid 0..n-1 at ``s`` (..., m).

    Fourth-order accurate (error ~ h^4 f''''/24); the stencil is shifted at the ends.
    """
    n = y.shape[-1]
    i = np.clip(np.floor(s).astype(np.intp), 1, n - 3)
    t = s - i
    w_m = -t * (t - 1.0) * (t - 2.0) / 6.0
    w_0 = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
    w_1 = -(t + 1.0) * t * (t - 2.0) / 2.0
    w_2 = (t + 1.0) * t * (t - 1.0) / 6.0
    return (w_m * _gather(y, i - 1) + w_0 * _gather(y, i) + w_1 * _gather(y, i + 1) + w_2 * _gather(y, i + 2))


def modulus_at(omega, omega_grid, storage, loss):
    """E'(omega), E''(omega) from values tabulated on a geometric frequency grid.

    Inside the grid: cubic (4-point Lagrange) interpolation of ln E' and ln E'' against
    ln omega (of E'' itself where it is not positive everywhere, e.g. 0 for an elastic solid);
    outside: the physical asymptotes of :func:`extrapolate_modulus`; negative frequencies:
    E(-omega) = conj E(omega).

    Parameters
    ----------
    omega : array (..., m)
        Angular frequencies (rad/s).
    omega_grid : array (n,)
        Geometric grid (rad/s), n >= 4, as stored by the modulus stage.
    storage, loss : arrays (..., n)
        E' > 0 and E'' >= 0 on the grid (Pa); leading axes broadcast against ``omega``'s.

    Returns
    -------
    (E', E'') : arrays
        Storage and loss moduli (Pa), the broadcast shape.

    References
    ----------
    docs/theory.md, section "Viscoelasticity".
    """
    grid = np.asarray(omega_grid, dtype=float)
    storage = np.asarray(storage, dtype=float)
    loss = np.asarray(loss, dtype=float)
    omega = np.asarray(omega, dtype=float)
    n = grid.size
    if n < 4:
        raise ValueError("modulus_at needs at least 4 grid frequencies")
    x0 = np.log(grid[0])
    h = np.log(grid[-1] / grid[0]) / (n - 1)
    a = np.abs(omega)
    with np.errstate(divide="ignore"):
        s = (np.log(a) - x0) / h
    sc = np.clip(s, 0.0, n - 1.0)
    positive = np.all(loss > 0, axis=-1, keepdims=True)
    log_loss = np.where(positive, np.log(np.where(loss > 0, loss, 1.0)), loss)
    Ep = np.exp(_uniform_cubic(np.log(storage), sc))
    raw = _uniform_cubic(log_loss, sc)
    Epp = np.where(positive, np.exp(np.where(positive, raw, 0.0)), np.maximum(raw, 0.0))
    eSp, eSpp, inside = extrapolate_modulus(a, grid[0], grid[-1], storage[..., :1], loss[..., :1],
                                            storage[..., -1:], loss[..., -1:])
    Ep = np.where(inside, Ep, eSp)
    Epp = np.where(inside, Epp, eSpp)
    return Ep, np.sign(omega) * Epp


def master_curve_at(omega, data_omega, data_storage, data_loss):
    """A measured master curve at reduced angular frequencies ``omega``.

    Log-log linear between the data points, the physical asymptotes
    (:func:`extrapolate_modulus`) outside them.

    Parameters
    ----------
    omega : array
        Reduced angular frequencies omega a_T (rad/s), > 0.
    data_omega : array (k,)
        Angular frequencies of the data (rad/s), increasing.
    data_storage, data_loss : arrays (k,)
        E' > 0 and E'' >= 0 of the data (Pa).

    Returns
    -------
    (E', E'') : arrays
        E' and E'' of the master curve at ``omega`` (Pa).

    References
    ----------
    docs/theory.md, section "Viscoelasticity".
    """
    omega = np.asarray(omega, dtype=float)
    Ep, Epp, inside = extrapolate_modulus(omega, data_omega[0], data_omega[-1], data_storage[0], data_loss[0],
                                          data_storage[-1], data_loss[-1])
    clipped = np.clip(omega, data_omega[0], data_omega[-1])
    Ep = np.where(inside, loglog_interp(clipped, data_omega, data_storage), Ep)
    Epp = np.where(inside, loglog_interp(clipped, data_omega, data_loss), Epp)
    return Ep, Epp
