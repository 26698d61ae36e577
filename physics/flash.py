"""Flash temperature of rubber friction: the temperature T_q of the asperity contacts observed at
magnification q, raised by the heat that viscoelastic dissipation at longer wavelengths produces,
and the friction mu(v) with the modulus read at E(q v cos phi, T_q).

Picture (Persson, J. Phys.: Condens. Matter 18, 7789 (2006); general form with heat diffusion
in Fortunato et al., J. Phys.: Condens. Matter 27, 175008 (2015)): the roughness of wavenumber q
deforms the rubber in the contact spots seen at magnification q (diameter ~ pi/q, area fraction
P(q)); the power it dissipates per unit nominal area, sigma0 v dmu/dq dq, is released in those
spots, J(q) dq = sigma0 v (dmu/dq) dq / P(q) per unit contact area, and it is released in the
volume of the deformed layer (depth about 1/q: a source J q e^{-q z}), not on the surface. It
diffuses into the rubber in depth and laterally (conductivity lambda, diffusivity D = lambda/(rho c)).
The smaller spots of every higher q lie inside the larger ones and feel their temperature: T_q
depends only on the dissipation at q' < q. The temperature rise of one scale is the surface
temperature of that layer source, of lateral wavenumber q', switched on for the passage time
t0 = (pi/q')/v of a spot, averaged over the passage:

.. math::

    \\frac{dT}{dq} = \\frac{J(q)}{\\lambda q}\\,\\Theta\\Big(\\frac{\\pi D q}{v}\\Big)
                 = \\frac{2 v}{(1-\\nu^2)\\lambda}\\,q^2 C(q) S(q) B(q; T_q)\\,
                   \\Theta\\Big(\\frac{\\pi D q}{v}\\Big),

with B the angular integral of cos(phi) E''(q v cos phi, T_q) (:mod:`roughcontact.physics.friction`)
and Theta(x) the passage average of :func:`layer_surface_temperature` (:func:`passage_average`):
x/2 for x -> 0 (fast sliding, adiabatic heating of the layer: dT/dq = pi q^3 C S B / ((1 - nu^2) rho c),
bounded in v) and 1/2 for x -> inf (slow sliding, steady spreading). An earlier version put the heat
on the surface (Theta -> (4/(3 sqrt pi)) sqrt x), which overstated the rise by a factor growing like
sqrt(v) at speed.

This is an initial-value problem in q, T(q0) = T_start, solved by marching the q grid: each step
is the trapezoid rule of the project's power-law quadrature, implicit in T and solved by the one
root finder on a bracket that starts at the previous temperature. There is no fixed-point
iteration over the whole q range, hence no spurious solution; the solution is unique because the
right-hand side is Lipschitz in T. Background (cumulative) heating of the nominal contact over a sliding time is the
Duhamel integral of the mean flux mu sigma0 v into a semi-infinite rubber, marched in time
(:func:`background_march`). See docs/theory.md, section "Flash temperature".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from roughcontact.errors import ComputationError

from .friction import angular_integrals, area_factor, contact_fraction, friction_kernel
from .quadrature import loglog_interp, segment_integrals_pairs
from .roots import illinois
from .special import erf
from .volterra import abel_weights

#: series of E2(x) = int_0^x (x - s) erf(sqrt s) ds = (2/sqrt pi) sum_n c_n x^(n + 5/2) (small x)
_SERIES2 = np.array([(-1.0) ** n / (math.factorial(n) * (2 * n + 1) * (n + 1.5) * (n + 2.5)) for n in range(12)])
_SMALL = 0.2  # below: the series (14 digits with 12 terms); above: the closed form (no cancellation left)


def layer_surface_temperature(a):
    """theta(a): surface temperature of the rubber heated in a layer, in units of J / (lambda q).

    A heat source J q e^{-q z} cos(q x) (W/m^3; depth z, J the power per unit area of the contact,
    released in a layer of depth 1/q) switched on at t = 0 in a half-space with an insulated
    surface, observed at the surface under the hot spot:

    .. math:: T(0, t) = \\frac{J}{\\lambda q}\\,\\theta(a), \\qquad
              \\theta(a) = \\int_0^a \\mathrm{erfc}\\sqrt b\\,db
              = a - (a - \\tfrac12)\\,\\mathrm{erf}\\sqrt a - \\sqrt{a/\\pi}\\,e^{-a},
              \\qquad a = D q^2 t.

    theta = a for a -> 0 (adiabatic heating of the layer, rho c dT/dt = J q) and -> 1/2 for
    a -> inf (steady spreading, half the value J / (lambda q) of the same power put on the
    surface: the heat is released at the mean depth 1/q).

    Parameters
    ----------
    a : array
        D q^2 t, the diffusion time over the layer's depth (dimensionless, >= 0).

    Returns
    -------
    array
        theta (dimensionless, in [0, 1/2)).

    References
    ----------
    docs/theory.md, section "Flash temperature"; Persson, J. Phys.: Condens. Matter 18, 7789 (2006)
    (heat produced in the volume of the deformed layer).
    """
    a = np.asarray(a, dtype=float)
    small = a < 1e-4
    ab = np.clip(a, 1e-4, 1e12)
    with np.errstate(under="ignore"):
        closed = ab - (ab - 0.5) * erf(np.sqrt(ab)) - np.sqrt(ab / np.pi) * np.exp(-ab)
    s = np.where(small, a, 0.0)
    return np.where(small, s - 4.0 / (3.0 * np.sqrt(np.pi)) * s ** 1.5 * (1.0 - 0.2 * s), closed)


def passage_average(x):
    """Theta(x): the mean over a spot's passage (t from 0 to t0 = pi/(q v)) of the temperature factor
    theta(D q^2 t) of :func:`layer_surface_temperature`.

    .. math:: \\Theta(x) = \\frac1x\\int_0^x\\theta(a)\\,da
              = \\frac1x\\Big[\\frac{x^2}{2}\\,\\mathrm{erfc}\\sqrt x
                + \\Big(\\frac x2 - \\frac38\\Big)\\mathrm{erf}\\sqrt x
                - \\Big(\\frac{x^{3/2}}{2} - \\frac{3\\sqrt x}{4}\\Big)\\frac{e^{-x}}{\\sqrt\\pi}\\Big],
              \\qquad x = \\pi D q / v,

    (a series below x = 0.2, where the closed form cancels). Theta ~ x/2 - (8/(15 sqrt pi)) x^(3/2)
    for x -> 0 (fast sliding: the layer heats adiabatically, the mean rise over the passage being
    J q t0 / (2 rho c)) and 1/2 - 3/(8x) for x -> inf (slow sliding: steady spreading).

    Parameters
    ----------
    x : array
        Ratio pi D q / v = q^2 D t0 of the diffusion length to the spot size squared
        (dimensionless, >= 0).

    Returns
    -------
    array
        Theta (dimensionless, in [0, 1/2), increasing, below x/2).

    References
    ----------
    docs/theory.md, section "Flash temperature"; Persson, J. Phys.: Condens. Matter 18, 7789 (2006).
    """
    x = np.asarray(x, dtype=float)
    small = x < _SMALL
    xs = np.where(small, x, 0.0)
    series = 0.5 * xs - 2.0 / np.sqrt(np.pi) * xs * np.sqrt(xs) * np.polyval(_SERIES2[::-1], xs)
    xl = np.clip(np.where(small, 1.0, x), _SMALL, 1e12)  # Theta = 1/2 - 3/(8x) to rounding beyond 1e12
    r = np.sqrt(xl)
    with np.errstate(under="ignore"):
        e = erf(r)
        closed = (0.5 * xl * xl * (1.0 - e) + (0.5 * xl - 0.375) * e
                  - (0.5 * xl * r - 0.75 * r) * np.exp(-xl) / np.sqrt(np.pi)) / xl
    return np.where(small, series, closed)


def heating_rate(q, v, C, S, B, nu, conductivity, diffusivity):
    """dT/dq, the temperature rise of the contact spots per unit wavenumber (K m).

    .. math:: \\frac{dT}{dq} = \\frac{J}{\\lambda q}\\,\\Theta\\Big(\\frac{\\pi D q}{v}\\Big)
              = \\frac{2 v}{(1-\\nu^2)\\lambda}\\,q^2 C S B\\,\\Theta(\\pi D q / v)

    with J = 2 v q^3 C S B / (1 - nu^2) the power per unit contact area released in the layer of
    depth 1/q. Limits: (v / ((1 - nu^2) lambda)) q^2 C S B at low speed (steady spreading) and
    pi q^3 C S B / ((1 - nu^2) rho c) at high speed (adiabatic heating of the layer, independent
    of v). Independent of the nominal pressure: the heat per unit nominal area and the contact
    area both grow in proportion to sigma0.

    Parameters
    ----------
    q : array (n,)
        Wavenumbers (1/m).
    v : array (...)
        Sliding velocity (m/s), > 0.
    C : array (..., n)
        Combined PSD (m^4).
    S : array (..., n)
        Area factor S(q) of the friction (dimensionless).
    B : array (..., n)
        Angular integral of cos(phi) E'' at the local temperature (Pa).
    nu : float
        Poisson's ratio (dimensionless).
    conductivity, diffusivity : float
        Thermal conductivity lambda (W/(m K)) and diffusivity D = lambda/(rho c) (m^2/s) of the rubber.

    References
    ----------
    docs/theory.md, section "Flash temperature"; Persson, J. Phys.: Condens. Matter 18, 7789 (2006).
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)[..., None]
    return 2.0 * v / ((1.0 - nu * nu) * conductivity) * q * q * C * S * B * passage_average(np.pi * diffusivity * q / v)


class _State(NamedTuple):
    """The march at one q node: wavenumber (1/m), PSD (m^4), T (K), A (Pa^2), B (Pa), dG/dq (m),
    G and dT/dq (K m), each (...) but q."""

    q: float
    C: np.ndarray
    T: np.ndarray
    A: np.ndarray
    B: np.ndarray
    g: np.ndarray
    G: np.ndarray
    h: np.ndarray


class _March:
    """One node of the march for a trial temperature, and the implicit step between two nodes."""

    def __init__(self, v, grid, storage, loss, n_phi, k, nu, conductivity, diffusivity, shift, correction, gamma, tol,
                 area=("persson", None)):
        self.v, self.grid, self.storage, self.loss, self.n_phi = v, grid, storage, loss, n_phi
        self.k, self.nu, self.lam, self.D, self.shift = k, nu, conductivity, diffusivity, shift
        self.correction, self.gamma, self.tol, self.area = correction, gamma, tol, tuple(area)

    def evaluate(self, q, C, T, prev: _State | None) -> _State:
        """The node at wavenumber q for the temperature T: E(w, T) = beta E_stored(w rho)."""
        rho, beta = self.shift(T)
        qa = np.array([q])
        A, B = angular_integrals(qa, self.v * rho, self.grid, self.storage, self.loss, self.n_phi)
        A, B = beta * beta * A[..., 0], beta * B[..., 0]
        g = 0.5 * self.k ** 2 * q ** 3 * C * A
        G = np.zeros(np.shape(g)) if prev is None else prev.G + segment_integrals_pairs(prev.q, q, prev.g, g)
        S = area_factor(contact_fraction(G, *self.area), self.correction, self.gamma)
        h = heating_rate(qa, self.v, C[..., None], S[..., None], B[..., None], self.nu, self.lam, self.D)[..., 0]
        return _State(q, C, np.broadcast_to(T, np.shape(h)), A, B, g, G, h)

    def step(self, prev: _State, q, C) -> _State:
        """The next node: T solves the trapezoid (power-law) step T = T_prev + int_{q_prev}^{q} dT/dq,
        found by the project's root finder on [T_prev, T_hi] (the residual is <= 0 at T_prev since
        dT/dq >= 0); T_hi is the explicit step, raised while the residual is still negative
        (heating that grows with T)."""
        seg = lambda h: segment_integrals_pairs(prev.q, q, prev.h, h)  # noqa: E731
        residual = lambda T: T - prev.T - seg(self.evaluate(q, C, T, prev).h)  # noqa: E731
        lo, flo = prev.T, -seg(self.evaluate(q, C, prev.T, prev).h)
        hi = prev.T - flo
        fhi = residual(hi)
        for _ in range(60):
            if np.all(fhi >= -self.tol):
                break
            hi = np.where(fhi < -self.tol, hi - fhi, hi)
            fhi = residual(hi)
        else:
            raise ComputationError(f"no flash temperature at q = {q:.4g} 1/m: the heating grows faster than the "
                                   "temperature (thermal runaway); check the thermal properties")
        T = illinois(residual, lo, hi, flo, fhi, ftol=self.tol, xtol=self.tol, maxiter=60).x
        return self.evaluate(q, C, T, prev)

    def segment(self, prev: _State, q, C, q_all, C_all, max_shift) -> list[_State]:
        """The states from prev to the next grid node q: one step, or m geometric sub-steps when the
        step moves the modulus by more than ``max_shift`` decades of frequency (C between the
        nodes as the quadrature's power law)."""
        full = self.step(prev, q, C)
        jump = np.abs(np.log10(self.shift(full.T)[0]) - np.log10(self.shift(prev.T)[0]))
        m = int(np.ceil(np.max(jump, initial=0.0) / max_shift))
        if m <= 1:
            return [full]
        states = [prev]
        for j in range(1, m):
            qj = prev.q * (q / prev.q) ** (j / m)
            states.append(self.step(states[-1], qj, loglog_interp(qj, q_all, C_all)))
        states.append(self.step(states[-1], q, C))
        return states[1:]


def flash_march(q, C, v, T_start, omega_grid, storage, loss, n_phi, sigma0, nu, conductivity, diffusivity, shift,
                correction="none", gamma=0.5, tolerance=1e-6, max_shift=0.05, area=("persson", None)):
    """T_q, A, B and G along the q grid with the flash temperature, by marching in q.

    The initial-value problem dT/dq = F(q, T, G) (:func:`heating_rate`), dG/dq = (k^2/2) q^3 C A(q, T),
    T(q0) = T_start, G(q0) = 0, is advanced node by node with the trapezoid rule of the project's
    power-law quadrature, each implicit step solved for T_i by the project's root finder on a
    bracket that starts at T_{i-1} (see ``_March.step``). Each step uses only what was dissipated
    at q' <= q_i, so there is no global fixed point to converge to and no spurious branch; the
    rule is second order in the q spacing. Where a step would shift the modulus by more than
    ``max_shift`` decades of frequency (steep heating just above q0 at high speed), the segment
    is cut into geometric sub-steps, which join the returned grid.

    Parameters
    ----------
    q : array (n,)
        Wavenumber grid (1/m), q0 .. q1.
    C : array (..., n)
        Combined PSD (m^4).
    v : array (...)
        Sliding velocity (m/s), > 0.
    T_start : array (...)
        Temperature of the rubber at the largest scale (K): the given temperature plus any
        background heating.
    omega_grid, storage, loss
        The modulus stage's grid (rad/s) and E', E'' on it (Pa, (..., m)) at the temperature
        ``shift`` refers to.
    n_phi : int
        Gauss-Legendre nodes of the angular integrals.
    sigma0 : array (...)
        Nominal pressure (Pa).
    nu : float
        Poisson's ratio.
    conductivity, diffusivity : float
        lambda (W/(m K)) and D (m^2/s) of the rubber; ``conductivity = inf`` is the isothermal theory.
    shift : callable
        T (...) -> (rho, beta): E(omega, T) = beta E_stored(omega rho) (dimensionless ratios of the
        shift factors to those of the stored temperature; rho = beta = 1 there, exactly).
    correction, gamma
        The area factor S of :func:`roughcontact.physics.friction.area_factor`.
    tolerance : float
        Temperature tolerance of each implicit step (K).
    max_shift : float
        Largest change of log10 a_T within one step (decades).
    area : (str, float or None)
        The contact-area correction of P(q) and its gamma
        (:func:`roughcontact.physics.friction.contact_fraction`).

    Returns
    -------
    (q, C, T, A, B, G, index)
        The grid with its sub-steps (1/m, (N,)), C on it (m^4), temperature (K), angular
        integrals at that temperature (Pa^2, Pa) and G, each (..., N); ``index`` (n,) locates
        the input grid's nodes in it.

    References
    ----------
    docs/theory.md, section "Flash temperature"; Persson, J. Phys.: Condens. Matter 18, 7789 (2006);
    Fortunato et al., J. Phys.: Condens. Matter 27, 175008 (2015).
    """
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    k = 1.0 / ((1.0 - nu * nu) * np.asarray(sigma0, dtype=float))
    march = _March(np.asarray(v, dtype=float), omega_grid, storage, loss, n_phi, k, nu, conductivity, diffusivity,
                   shift, correction, gamma, tolerance, area)
    states = [march.evaluate(q[0], C[..., 0], np.asarray(T_start, dtype=float), None)]
    index = [0]
    for i in range(1, q.size):
        states += march.segment(states[-1], q[i], C[..., i], q[i - 1:i + 1], C[..., i - 1:i + 1], max_shift)
        index.append(len(states) - 1)
    lead = np.shape(states[-1].h)
    stack = lambda name: np.stack([np.broadcast_to(getattr(s, name), lead) for s in states], axis=-1)  # noqa: E731
    q_all = np.array([s.q for s in states])
    return q_all, stack("C"), stack("T"), stack("A"), stack("B"), stack("G"), np.array(index)


def flash_friction_kernel(q, C, v, T_start, omega_grid, storage, loss, n_phi, sigma0, nu, conductivity, diffusivity,
                          shift, correction="none", gamma=0.5, segment_nodes=12, tolerance=1e-6, max_shift=0.05,
                          profile=False, area=("persson", None)):
    """mu(v), A/A0(v) and the flash temperature with the modulus at E(q v cos phi, T_q).

    :func:`flash_march` gives T_q and the angular integrals at T_q on the q grid; mu and A/A0
    then follow from :func:`roughcontact.physics.friction.friction_kernel` exactly as in the
    isothermal theory (eqs 61-62 integrated in the variable G).

    Parameters
    ----------
    As :func:`flash_march`, plus ``segment_nodes`` (Gauss-Legendre nodes per q segment of the mu
    integral) and ``profile`` (also return T_q and the heat flux density over q).

    Returns
    -------
    (mu, area, T_contact) or (mu, area, T_contact, T_q, heat)
        mu and A/A0 (dimensionless), T_contact = T_q at q1 (K), shape (...); with ``profile``,
        T_q (K) and the heat released per unit nominal area and time per unit ln q,
        sigma0 v d mu / d ln q (W/m^2), over q.

    References
    ----------
    docs/theory.md, section "Flash temperature"; Persson, J. Phys.: Condens. Matter 18, 7789 (2006).
    """
    qs, Cs, T, A, B, _, index = flash_march(q, C, v, T_start, omega_grid, storage, loss, n_phi, sigma0, nu,
                                            conductivity, diffusivity, shift, correction, gamma, tolerance, max_shift,
                                            area)
    out = friction_kernel(qs, Cs, A, B, np.asarray(sigma0, dtype=float), nu, correction, gamma, profile, segment_nodes,
                          *area)
    mu, area = out[0], out[1]
    if profile:
        heat = np.asarray(sigma0, dtype=float)[..., None] * np.asarray(v, dtype=float)[..., None] * out[3]
        return mu, area, T[..., -1], T[..., index], heat[..., index]
    return mu, area, T[..., -1]


def background_march(times, sliding_time, flux, effusivity, T_given):
    """Background (cumulative) temperature rise of the nominal contact: the Duhamel integral of
    the frictional heat flux into a semi-infinite rubber, marched in time.

    .. math:: \\Delta T(t) = \\frac{1}{e\\sqrt\\pi}\\int_0^t \\frac{J(t')\\,dt'}{\\sqrt{t - t'}},
              \\qquad J(t) = \\mu\\big(T_\\mathrm{given} + \\Delta T(t)\\big)\\,\\sigma_0 v,
              \\qquad e = \\sqrt{\\lambda\\rho c},

    (a rubber block whose nominal contact is heated continuously, all the heat into the rubber:
    an upper bound; one-dimensional while sqrt(D t) is small against the contact size). J is
    piecewise linear in t between the nodes (product integration with the Abel weights of
    :func:`roughcontact.physics.volterra.abel_weights`); each node is one predictor (J held
    from the last node) and one corrector step: causal, so no fixed point is sought.

    Parameters
    ----------
    times : array (M,)
        Node times as fractions of the sliding time, times[0] = 0 < ... < times[-1] = 1.
    sliding_time : array (...)
        Sliding time t_s (s), e.g. distance / v.
    flux : callable
        Temperature (...) -> (J (...) in W/m^2, anything): the heat flux mu sigma0 v at that
        background temperature, and what the caller wants kept from the last evaluation.
    effusivity : float
        e = sqrt(lambda rho c) of the rubber (W s^0.5/(m^2 K)).
    T_given : array (...)
        Temperature before sliding (K).

    Returns
    -------
    (rise, kept) : (array (...), the last ``flux`` extra)
        Temperature rise at t_s (K) and the flux function's extra output at the final temperature.

    References
    ----------
    docs/theory.md, section "Flash temperature"; Carslaw & Jaeger (1959), section 2.9;
    Fortunato et al., J. Phys.: Condens. Matter 27, 175008 (2015).
    """
    tau = np.asarray(times, dtype=float)
    scale = np.sqrt(np.asarray(sliding_time, dtype=float)) / (effusivity * np.sqrt(np.pi))
    J0, kept = flux(np.asarray(T_given, dtype=float))
    fluxes = [J0]
    rise = np.zeros(np.shape(J0))
    for n in range(1, tau.size):
        W = abel_weights(tau[None, :], n)[0] / np.sqrt(tau[n])  # int_0^tau_n g / sqrt(tau_n - s) ds = sum W g
        past = sum(W[j] * fluxes[j] for j in range(n))
        guess = fluxes[-1]
        for _ in range(2):
            rise = scale * (past + W[n] * guess)
            guess, kept = flux(T_given + rise)
        fluxes.append(guess)
    return rise, kept
