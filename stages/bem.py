"""Exact numerical check of the theory: FFT boundary-element (BEM) contact on synthesized
surface pairs, compared with the contact and separation stages at the same magnification.

What is exact and what is not. Persson's theory (``contact``, ``separation``) is an
approximation; the BEM here solves frictionless, non-adhesive contact of an elastic half-space
(modulus E*) with a rigid rough surface exactly, up to discretization, on periodic height maps.
The solver is Tamaas' Polonsky-Keer-Rey conjugate-gradient method (Frérot, Anciaux & Molinari,
Tamaas, J. Open Source Softw. 5, 2121 (2020); Polonsky & Keer, Wear 231, 206 (1999)); this
module only synthesizes the surfaces, sets the solver up and reduces its fields.

Two rough surfaces (equations.md section 1, seed eqs 52, 65). The substrate height h1 and the
elastic solid's height h2 are measured upwards in the same frame; the local gap is
(d + h2) - h1, so contact depends on the composite h = h1 - h2 only, whose PSD is
C = C1 + C2 - 2 eta sqrt(C1 C2): eta = 1 with identical surfaces gives h = 0 (a perfect fit).

Grid <-> q band (the comparison uses the same band on both sides):

* the map is the periodic cell of side L = 2 pi / qL, qL = the lowest wavenumber of the psd
  stage's q grid; N x N pixels of size dx = L / N;
* the lattice wavenumbers are q = qL (i, j), |i|, |j| <= N/2; Nyquist q_N = pi / dx = N qL / 2;
* roughness is kept on qL <= |q| <= q_cut, q_cut = min(q_max of the psd grid,
  N qL / pixels_per_wavelength): the shortest wavelength in the map spans
  ``bem.pixels_per_wavelength`` pixels (2 is the Nyquist limit; 4, the default, resolves each
  asperity by a few nodes);
* the theory is read at magnification zeta_bem = q_cut / qL, which the scene must list in
  ``contact.zeta`` (the stage says which value when it is missing).

Measured topographies (``bem.surfaces``, default "auto"): when every rough surface is a
``kind = "topography"`` surface given as one periodic, square area map (both on the same grid
when both are rough), the stage solves on those maps instead of synthesizing: the topography
stage's preprocessing (units, sizes, detrending; never a window), the composite h1 - h2 as
above, one "realization". The band is the map's: qL = 2 pi / L (L the map's side, which must be
the psd grid's lowest wavenumber), q_cut = min(q_max of the psd grid, the maps' reliability
cutoff, N qL / pixels_per_wavelength); modes above q_cut are removed from the maps
(:func:`band_limit`), and the theory is read at zeta_bem = q_cut / qL (:func:`map_band`).
With two measured surfaces, eta must be "measured" (the maps have their own coherence); the
outputs then have no eta dimension. See docs/bem.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.stage import UserError
from roughcontact.stage import Param, Section
from roughcontact.stage import FileInput, Figure, Stage, StageInput, Var, register, register_params, register_section

from roughcontact.physics.contact import effective_modulus
from roughcontact.physics.quadrature import loglog_interp
from .topography import _prepare, _process, is_topography

#: the optional dependency and how to install it (named in the error without it)
EXTRA = 'pip install "roughcontact[bem]"'

# ----------------------------------------------------------------------------------------
# Kernels: synthesis (pure numpy)
# ----------------------------------------------------------------------------------------


def lattice_wavenumbers(n: int, pixel_size: float) -> np.ndarray:
    """|q| (1/m) of the periodic lattice of an n x n map, in ``numpy.fft.rfft2`` layout (n, n//2 + 1).

    q = (2 pi / L) (i, j) with L = n * pixel_size.
    """
    kx = 2.0 * np.pi * np.fft.fftfreq(n, d=pixel_size)
    ky = 2.0 * np.pi * np.fft.rfftfreq(n, d=pixel_size)
    return np.hypot(kx[:, None], ky[None, :])


def psd_on_lattice(q_lattice, q, C, q_cut):
    """A tabulated PSD C(q) (m^4, Persson's convention) at the lattice wavenumbers, zero
    outside [q[0], q_cut] (so the k = 0 mode, the mean height, is zero).

    Log-log interpolation between the table's nodes: exact for the self-affine PSD, whose
    knots qL, q0, q1 are nodes of the psd stage's grid.
    """
    q_lattice = np.asarray(q_lattice, dtype=float)
    q = np.asarray(q, dtype=float)
    C = np.asarray(C, dtype=float)
    top = min(float(q_cut), float(q[-1]))
    inside = (q_lattice >= q[0] * (1 - 1e-12)) & (q_lattice <= top * (1 + 1e-12))
    out = np.zeros_like(q_lattice)
    out[inside] = loglog_interp(np.clip(q_lattice[inside], q[0], q[-1]), q, C)
    return np.maximum(out, 0.0)


def white_noise_pair(n: int, seed: int, realization: int, band: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two independent unit complex Gaussian white noises xi1, xi2 on the rfft2 lattice (n, n//2 + 1).

    xi = rfft2(w) / m with w an m x m field of independent standard normals, so <|xi_k|^2> = 1
    and xi is Hermitian (its inverse transform is real). With ``band`` = K (the highest |q| / qL
    that will be used), w is drawn on the smallest even grid m = 2 floor(K) + 2 holding every
    mode |i|, |j| <= K, and those modes are placed on the n x n lattice: the noise in the band
    then does not depend on n, so the same seed gives the *same surface* on a finer grid (only
    the discretization changes). Without ``band`` (or when m > n), m = n.
    Drawn from ``numpy.random.default_rng([seed, realization])``: realization r is the same
    whatever the number of realizations asked for.
    """
    rng = np.random.default_rng([int(seed), int(realization)])
    m = n if band is None else 2 * int(np.floor(band + 1e-9)) + 2
    if m >= n:
        w = rng.standard_normal((2, n, n))
        xi = np.fft.rfft2(w, axes=(-2, -1)) / n
        return xi[0], xi[1]
    w = rng.standard_normal((2, m, m))
    small = np.fft.rfft2(w, axes=(-2, -1)) / m
    k = m // 2  # rows 0 .. k-1 and -(k-1) .. -1, columns 0 .. k-1: every |i|, |j| <= K (m's Nyquist dropped)
    xi = np.zeros((2, n, n // 2 + 1), dtype=complex)
    xi[:, :k, :k] = small[:, :k, :k]
    xi[:, n - (k - 1):, :k] = small[:, m - (k - 1):, :k]
    return xi[0], xi[1]


def synthesize_pair(q, C1, C2, eta, n, q_cut, seed=0, realization=0, noise=None):
    """Periodic self-affine (any tabulated PSD) height maps h1, h2 (m) with coherence eta.

    On the periodic cell of side L = 2 pi / q[0] with n x n pixels (dx = L/n)::

        h(x) = sum_k H_k exp(i k.x),  H1_k = (2 pi / L) sqrt(C1(|k|)) xi1_k,
        H2_k = (2 pi / L) sqrt(C2(|k|)) (eta xi1_k + sqrt(1 - eta^2) xi2_k),

    xi1, xi2 independent unit white noises (:func:`white_noise_pair`). Then
    <|H_k|^2> = C(|k|) (2 pi / L)^2, i.e. <h^2> = sum_k (2 pi/L)^2 C -> \\int d^2q C = hrms^2
    (eq 4), and Re<H1_k H2_k*> / sqrt(<|H1_k|^2><|H2_k|^2>) = eta (equations.md section 1,
    eq 41): the pair's coherence is eta at every wavenumber. The composite h1 - h2 has the
    combined PSD C1 + C2 - 2 eta sqrt(C1 C2) (eq 52).

    Parameters
    ----------
    q : array (m,)
        Wavenumber grid of the PSDs (1/m); q[0] = qL sets the map size L = 2 pi / qL.
    C1, C2 : array (m,)
        PSDs of the substrate and of the solid on ``q`` (m^4, Persson's convention).
    eta : float
        Coherence, -1 <= eta <= 1.
    n : int
        Pixels per side.
    q_cut : float
        Highest wavenumber kept (1/m); modes above it are zero.
    seed, realization : int
        Random stream (see :func:`white_noise_pair`).
    noise : (xi1, xi2), optional
        Noise to use instead of drawing it (e.g. shared between several eta).

    Returns
    -------
    h1, h2 : arrays (n, n)
        Heights (m), zero mean.
    """
    eta = float(eta)
    if not -1.0 <= eta <= 1.0:
        raise ValueError(f"eta must be in [-1, 1], got {eta}")
    q = np.asarray(q, dtype=float)
    L = 2.0 * np.pi / q[0]
    ql = lattice_wavenumbers(n, L / n)
    xi1, xi2 = noise if noise is not None else white_noise_pair(n, seed, realization, band=q_cut / q[0])
    a1 = (2.0 * np.pi / L) * np.sqrt(psd_on_lattice(ql, q, C1, q_cut))
    a2 = (2.0 * np.pi / L) * np.sqrt(psd_on_lattice(ql, q, C2, q_cut))
    H1 = a1 * xi1
    H2 = a2 * (eta * xi1 + np.sqrt(max(0.0, 1.0 - eta * eta)) * xi2)
    h1 = np.fft.irfft2(H1, s=(n, n)) * n * n
    h2 = np.fft.irfft2(H2, s=(n, n)) * n * n
    return h1, h2


def pair_coherence(h1, h2, pixel_size, q_edges):
    """Measured coherence eta(q) = Re C12 / sqrt(C11 C22) of two maps on one grid, averaged
    over annuli q_edges[i] <= |q| < q_edges[i+1] (equations.md section 1, eq 41).

    NaN in annuli without modes or where one map has no roughness.
    """
    n0, n1 = np.shape(h1)
    if n0 != n1 or np.shape(h2) != np.shape(h1):
        raise ValueError("pair_coherence needs two square maps of the same shape")
    H1, H2 = np.fft.rfft2(h1), np.fft.rfft2(h2)
    q = lattice_wavenumbers(n0, pixel_size)
    # rfft2 stores the columns 1 .. n/2-1 once for two modes (k and -k): weight them twice
    weight = np.full(q.shape, 2.0)
    weight[:, 0] = 1.0
    if n0 % 2 == 0:
        weight[:, -1] = 1.0
    which = np.digitize(q, q_edges) - 1
    nb = len(q_edges) - 1
    ok = (which >= 0) & (which < nb)

    def binned(v):
        return np.bincount(which[ok], weights=(weight * v)[ok], minlength=nb)[:nb]

    c12 = binned(np.real(H1 * np.conj(H2)))
    c11, c22 = binned(np.abs(H1) ** 2), binned(np.abs(H2) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return c12 / np.sqrt(c11 * c22)


def fourier_refine(h, n):
    """The same band-limited periodic map sampled on a finer n x n grid (m), by zero-padding
    its Fourier transform: the surface is unchanged, only the discretization is refined (the
    grid-convergence check of docs/bem.md).

    The map's Nyquist row and column are dropped; they are zero for maps synthesized with
    ``pixels_per_wavelength`` > 2.
    """
    h = np.asarray(h, dtype=float)
    m = h.shape[0]
    if h.shape != (m, m) or n < m:
        raise ValueError("fourier_refine needs a square map and n >= its size")
    H = np.fft.rfft2(h)
    k = (m + 1) // 2  # modes 0 .. k-1 and -(k-1) .. -1 along the first axis; 0 .. k-1 along the second
    out = np.zeros((n, n // 2 + 1), dtype=complex)
    out[:k, :k] = H[:k, :k]
    out[n - (k - 1):, :k] = H[m - (k - 1):, :k]
    return np.fft.irfft2(out, s=(n, n)) * (n * n) / (m * m)


def rms_slope_of_map(h, pixel_size):
    """Root-mean-square slope of a periodic map (dimensionless), spectrally:
    xi^2 = sum_k |k|^2 |H_k|^2 (the continuum's 2 pi \\int q^3 C dq, eq 12)."""
    n = np.shape(h)[0]
    H = np.fft.rfft2(h) / (n * n)
    q = lattice_wavenumbers(n, pixel_size)
    weight = np.full(q.shape, 2.0)
    weight[:, 0] = 1.0
    if n % 2 == 0:
        weight[:, -1] = 1.0
    return float(np.sqrt(np.sum(weight * q * q * np.abs(H) ** 2)))


def band_limit(h, pixel_size, q_cut):
    """A periodic square map (m) with its mean and every Fourier mode |q| > q_cut removed.

    The measured-map counterpart of the synthesis band qL <= |q| <= q_cut: the lattice of an
    n x n map of side L = n dx has no mode between 0 and qL = 2 pi / L, so keeping
    0 < |q| <= q_cut (1/m) leaves exactly the band the theory integrates over. Modes on the
    edge (|q| = q_cut to 1e-12) are kept.
    """
    h = np.asarray(h, dtype=float)
    n = h.shape[0]
    if h.shape != (n, n):
        raise ValueError(f"band_limit needs a square map, got shape {h.shape}")
    H = np.fft.rfft2(h)
    q = lattice_wavenumbers(n, pixel_size)
    H[(q == 0.0) | (q > q_cut * (1 + 1e-12))] = 0.0
    return np.fft.irfft2(H, s=(n, n))


def map_band(q_grid_lo, q_grid_hi, n, side, q_reliable, pixels_per_wavelength):
    """The band of a measured n x n periodic map of side ``side`` (m), matched to the psd grid.

    The map's lattice starts at qL = 2 pi / side, which must be the psd grid's lowest
    wavenumber ``q_grid_lo`` (the topography stage's lowest bin holds only the modes |q| = qL,
    so it is, unless ``grid.q_min`` moves it); the theory integrates from there.
    zeta_bem = min(q_grid_hi / qL, q_reliable / qL, n / pixels_per_wavelength) and
    q_cut = zeta_bem qL: the psd grid's top, the maps' reliability cutoff (Nyquist pi / dx or
    the instrument cutoffs) and the same pixels-per-wavelength rule as the synthesis path
    (n qL / 2 is the Nyquist wavenumber, so pixels_per_wavelength = 2 keeps up to it).

    Returns
    -------
    q_cut : float
        Highest wavenumber kept (1/m).
    zeta_bem : float
        q_cut / qL.
    limit : str
        What set q_cut.
    """
    qL = 2.0 * np.pi / side
    if not np.isclose(q_grid_lo, qL, rtol=1e-9, atol=0.0):
        raise UserError(
            f"the measured maps' lowest wavenumber is 2 pi / L = {qL:.10g} 1/m (L = {side:.6g} m) but the psd "
            f"grid starts at {q_grid_lo:.10g} 1/m; the BEM solves on the whole periodic map, so the theory must "
            f"start at 2 pi / L: remove grid.q_min (or set it to {qL:.10g} 1/m)", key="grid.q_min")
    options = ((q_grid_hi / q_grid_lo, "the top of the psd grid"),
               (q_reliable / qL, "the maps' reliability cutoff"),
               (n / float(pixels_per_wavelength), f"{n} pixels / bem.pixels_per_wavelength"))
    zeta, limit = min(options, key=lambda o: o[0])
    if zeta <= 1.0:
        raise UserError(f"the measured maps resolve no band above 2 pi / L (zeta_bem = {zeta:.4g}, set by {limit})",
                        key="bem.pixels_per_wavelength")
    return zeta * q_grid_lo, zeta, limit


# ----------------------------------------------------------------------------------------
# Kernels: the contact solve (Tamaas, imported lazily)
# ----------------------------------------------------------------------------------------


def _tamaas():
    """The tamaas module, or a UserError naming the extra to install."""
    try:
        import tamaas
    except ImportError as exc:
        raise UserError(
            f"the bem stage needs the optional dependency tamaas, which is not installed ({exc}); "
            f"install it with: {EXTRA}", key="outputs.variables") from None
    tamaas.set_log_level(tamaas.LogLevel.error)
    return tamaas


def solve_contact(heights, pixel_size, E_star, pressures, *, tolerance=1e-10, stress_edges=None):
    """Frictionless non-adhesive contact of an elastic half-space with a rigid periodic surface.

    Tamaas' Polonsky-Keer-Rey solver at each mean pressure, on the map's periodic cell. The
    problem is solved in reduced units (lengths in pixels, stresses in E*), which is exact
    for linear elasticity and keeps the solver's tolerance meaningful whatever the scales.

    Parameters
    ----------
    heights : array (nx, ny)
        Composite surface (m): the rigid rough surface seen by a flat elastic solid
        (for a pair, h1 - h2; see :func:`contact_pair`).
    pixel_size : float
        dx (m); the cell is nx dx by ny dx.
    E_star : float
        Effective modulus (Pa).
    pressures : array (np,)
        Mean (nominal) pressures (Pa), > 0.
    tolerance : float
        Relative tolerance of the solver.
    stress_edges : array (np, nb + 1), optional
        Per pressure, edges of the histogram of the local contact pressure (Pa).

    Returns
    -------
    dict with
        ``area`` (np,): relative contact area A/A0 (fraction of pixels with pressure > 0);
        ``mean_gap`` (np,): mean interfacial separation, the map average of the gap (m);
        ``histogram`` (np, nb): density of the local pressure (1/Pa) over the whole map, so
        that sum(histogram * width) = fraction of the map in contact inside the edges
        (the non-contact part, a delta at 0, is left out, as in eq 16);
        ``overflow`` (np,): fraction of the map in contact above the last edge.
    """
    heights = np.asarray(heights, dtype=float)
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    if np.any(~(pressures > 0)):
        raise ValueError("pressures must be > 0")
    nx, ny = heights.shape
    npix = heights.size
    nb = 0 if stress_edges is None else np.shape(stress_edges)[-1] - 1
    out = {"area": np.empty(pressures.size), "mean_gap": np.empty(pressures.size),
           "histogram": np.zeros((pressures.size, nb)), "overflow": np.zeros(pressures.size)}
    surface = (heights - heights.mean()) / pixel_size
    if np.ptp(surface) == 0.0:
        # a flat composite (e.g. identical surfaces with eta = 1): full contact at any pressure
        out["area"][:] = 1.0
        out["mean_gap"][:] = 0.0
        for i, p in enumerate(pressures):
            if nb:
                edges = np.asarray(stress_edges[i])
                k = np.searchsorted(edges, p, side="right") - 1
                if 0 <= k < nb:
                    out["histogram"][i, k] = 1.0 / (edges[k + 1] - edges[k])
                else:
                    out["overflow"][i] = 1.0
        return out
    tm = _tamaas()

    def fresh():
        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(nx), float(ny)], [nx, ny])
        model.E = 1.0
        model.nu = 0.0  # E* = E / (1 - nu^2) = 1 in reduced units
        return model, tm.PolonskyKeerRey(model, np.ascontiguousarray(surface), float(tolerance))

    model, solver = fresh()
    for i, p in enumerate(pressures):
        for attempt in (0, 1):
            try:
                solver.solve(float(p / E_star))
                break
            except tm.FloatingPointError as exc:
                # PKR's error measure is 0/0 when the contact is one node; a warm start from a
                # one-node solution can hit it where a cold start does not: retry cold once
                if attempt:
                    raise UserError(
                        f"the BEM cannot solve p = {p:.6g} Pa on this {nx} x {ny} map: the contact area is a "
                        f"single pixel or less (tamaas: {str(exc).strip().splitlines()[-1]}); use larger "
                        f"pressures or a finer bem.grid", key="load.p") from None
                model, solver = fresh()
        traction = np.array(model.traction, copy=True).reshape(nx, ny) * E_star
        gap = (np.array(model.displacement, copy=True).reshape(nx, ny) - surface) * pixel_size
        contact = traction > 0
        out["area"][i] = np.count_nonzero(contact) / npix
        out["mean_gap"][i] = max(float(gap.mean()), 0.0)
        if nb:
            edges = np.asarray(stress_edges[i], dtype=float)
            counts, _ = np.histogram(traction[contact], bins=edges)
            out["histogram"][i] = counts / (npix * np.diff(edges))
            out["overflow"][i] = np.count_nonzero(traction > edges[-1]) / npix
    return out


def contact_pair(h1, h2, pixel_size, E_star, pressures, **kwargs):
    """Contact of two rough surfaces on one grid: :func:`solve_contact` of the composite h1 - h2.

    h1 is the substrate's height and h2 the elastic solid's, both measured upwards in the same
    frame (m), same shape, pixel size ``pixel_size`` (m). Works for synthesized maps
    (:func:`synthesize_pair`) and for measured topographies alike.
    """
    h1, h2 = np.asarray(h1, dtype=float), np.asarray(h2, dtype=float)
    if h1.shape != h2.shape:
        raise ValueError(f"the two maps must be on one grid, got shapes {h1.shape} and {h2.shape}")
    return solve_contact(h1 - h2, pixel_size, E_star, pressures, **kwargs)


# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------

register_section(
    Section(
        "bem",
        (
            Param("grid", "int", default=256, lo=8, hi=8192,
                  doc="pixels per side of the synthesized periodic map (side L = 2 pi / qL; measured maps keep theirs)"),
            Param("realizations", "int", default=4, lo=1, hi=10000,
                  doc="number of random surface pairs (measured maps: one)"),
            Param("seed", "int", default=0, lo=0, doc="random seed (results are reproducible for a given seed)"),
            Param("pixels_per_wavelength", "quantity", "", default=4.0, lo=2.0,
                  doc="pixels per shortest wavelength kept: q_cut = min(q_max, grid qL / this); 2 = Nyquist"),
            Param("surfaces", "choice", default="auto", choices=("auto", "synthesized", "measured"),
                  doc="auto: solve on the measured maps when every rough surface is a topography (one periodic "
                      "square map each, one grid), else synthesize; synthesized: always random surfaces with the "
                      "psd stage's spectra; measured: the maps or an error"),
        ),
        doc="the boundary-element check (needs the [bem] extra: tamaas)",
    )
)
register_params(
    "numerics",
    Param("bem_tolerance", "quantity", "", default=1e-10, lo=0.0, hi=1e-2, lo_open=True,
          doc="relative tolerance of the BEM contact solver"),
    Param("bem_stress_bins", "int", default=50, lo=2, doc="bins of the BEM contact-pressure histogram"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------


def grid_band(q_lowest, q_highest, n, pixels_per_wavelength):
    """Map size L (m), pixel size dx (m), cut-off q_cut (1/m) and magnification zeta_bem.

    L = 2 pi / q_lowest, dx = L / n, q_cut = min(q_highest, n q_lowest / pixels_per_wavelength)
    (the wavelength 2 pi / q_cut spans at least ``pixels_per_wavelength`` pixels),
    zeta_bem = q_cut / q_lowest.
    """
    L = 2.0 * np.pi / q_lowest
    q_cut = min(float(q_highest), n * q_lowest / float(pixels_per_wavelength))
    return L, L / n, q_cut, q_cut / q_lowest


def _at_zeta(ds: xr.Dataset, var: str, zeta: float, stage: str, set_by: str) -> xr.DataArray:
    da = ds[var]
    if "zeta" not in da.dims and "zeta" not in da.coords:
        return da
    values = np.atleast_1d(da["zeta"].values)
    hit = np.flatnonzero(np.isclose(values, zeta, rtol=1e-9, atol=0.0))
    if hit.size == 0:
        raise UserError(
            f"the {stage} stage has no magnification zeta = {zeta:.10g}, the band the BEM map resolves "
            f"(q_cut / qL, set by {set_by}); add {zeta:.10g} to contact.zeta", key="contact.zeta")
    return da.isel(zeta=int(hit[0])) if "zeta" in da.dims else da


_SYNTHESIZE_INSTEAD = "; or set bem.surfaces = 'synthesized' to compare on random periodic surfaces with the measured spectra"


def _rough(spec) -> bool:
    return spec is not None and spec.get("kind") != "smooth"


def map_surfaces(inp: StageInput) -> tuple[str, ...]:
    """The rough surfaces whose measured maps the BEM solves on; () means synthesize.

    ``bem.surfaces``: "synthesized" always synthesizes; "auto" (default) uses the maps when
    every rough surface is of kind "topography"; "measured" requires that.
    """
    how = inp["bem.surfaces"]
    rough = tuple(name for name in ("substrate", "solid") if _rough(inp[name]))
    if how == "synthesized":
        return ()
    if rough and all(is_topography(inp[name]) for name in rough):
        return rough
    if how == "measured":
        raise UserError("bem.surfaces = 'measured' needs every rough surface to be of kind 'topography' (an area "
                        "map); use 'auto' or 'synthesized' for self_affine or psd_file surfaces", key="bem.surfaces")
    return ()


def measured_maps(inp: StageInput, names: tuple[str, ...]) -> dict:
    """The measured maps the BEM solves on, prepared as the topography stage prepares them.

    Per surface: exactly one file, an area map (not a line scan, ``analysis = "area"``),
    periodic (``periodic = true`` or the file says so), no window, square (same number of
    points and the same length along x and y); both surfaces on the same grid. Units, sizes,
    missing points and detrending are the topography stage's (:func:`stages.topography._prepare`
    and ``_process`` with the window switched off: a window would change the heights the
    solver sees). Bad input is a :class:`UserError` naming the key.

    Returns
    -------
    dict with ``h`` (name -> detrended heights, m), ``n`` (pixels per side), ``side`` (m),
    ``pixel_size`` (m), ``q_reliable`` (1/m, the lowest of the maps' cutoffs), ``cutoff``
    (what set it) and ``files`` (name -> path).
    """
    prepared = {}
    for name in names:
        spec, key = inp[name], f"{name}.files"
        files = inp.files.get(key)
        files = [] if files is None else list(files) if isinstance(files, (list, tuple)) else [files]
        if len(files) != 1:
            raise UserError(f"the BEM solves on one map per surface; the {name} has {len(files)} files"
                            + _SYNTHESIZE_INSTEAD, key=key)
        p = _prepare(name, spec, files[0], 0)
        path = p["path"]
        if p["h"].ndim != 2:
            raise UserError("a line scan; the BEM needs an area map (a 2D height map)" + _SYNTHESIZE_INSTEAD,
                            file=path, key=key)
        if p["analysis"] != "area":
            raise UserError("the BEM compares with the map's 2D spectrum: set analysis = 'area'" + _SYNTHESIZE_INSTEAD,
                            file=path, key=f"{name}.analysis")
        if not p["periodic"]:
            raise UserError(
                "the map is not periodic and the FFT-BEM solves on a periodic cell: set periodic = true to use it "
                "as periodic (the step between opposite edges then adds roughness at all wavenumbers, to the "
                "measured PSD as well, which is then computed without a window)" + _SYNTHESIZE_INSTEAD,
                file=path, key=f"{name}.periodic")
        if p["window"] != "none":
            raise UserError("the BEM solves on the heights as they are; a windowed PSD would not describe them: "
                            "remove window (or set it to 'none')", file=path, key=f"{name}.window")
        (nx, ny), (sx, sy) = p["h"].shape, p["sizes"]
        if nx != ny or not np.isclose(sx, sy, rtol=1e-6):
            raise UserError(f"the BEM needs a square map (same points and length along x and y); this one has "
                            f"{nx} x {ny} points over {sx:.6g} m x {sy:.6g} m: crop it to a square" + _SYNTHESIZE_INSTEAD,
                            file=path, key=key)
        prepared[name] = _process(dict(p, window="none"), spec)
    if len(prepared) == 2:
        a, b = prepared["substrate"], prepared["solid"]
        if a["h"].shape != b["h"].shape:
            raise UserError(f"the two maps are not on one grid: the substrate has {a['h'].shape[0]} x {a['h'].shape[1]} "
                            f"points, the solid {b['h'].shape[0]} x {b['h'].shape[1]}" + _SYNTHESIZE_INSTEAD,
                            key="solid.files")
        if not np.isclose(a["sizes"][0], b["sizes"][0], rtol=1e-6):
            raise UserError(f"the two maps are not on one grid: the substrate is {a['sizes'][0]:.6g} m wide, the solid "
                            f"{b['sizes'][0]:.6g} m" + _SYNTHESIZE_INSTEAD, key="solid.size_x")
    first = prepared[names[0]]
    low = min(prepared.values(), key=lambda p: p["q_max"])
    n, side = first["h"].shape[0], first["sizes"][0]
    return {"h": {name: p["h"] for name, p in prepared.items()}, "n": n, "side": side, "pixel_size": side / n,
            "q_reliable": low["q_max"], "cutoff": low["cutoff"],
            "files": {name: p["path"] for name, p in prepared.items()},
            "detrend": {name: p["detrend"] for name, p in prepared.items()}}


def _check_eta(inp: StageInput, names: tuple[str, ...]) -> None:
    measured = isinstance(inp["interface.eta"], str)
    if len(names) == 2 and not measured:
        raise UserError("the BEM solves on the two measured maps, which have their own coherence: set "
                        "interface.eta = 'measured' so that the theory uses it too" + _SYNTHESIZE_INSTEAD
                        + " and the given eta", key="interface.eta")
    if not names and measured and _rough(inp["substrate"]) and _rough(inp["solid"]):
        raise UserError("synthesized BEM surfaces are mixed with one coherence: give numeric interface.eta values, "
                        "or solve on the measured maps (bem.surfaces = 'auto')", key="interface.eta")


def validate_bem(inp: StageInput) -> None:
    """Before anything computes: the optional dependency must be there, and measured maps usable."""
    _tamaas()
    names = map_surfaces(inp)
    _check_eta(inp, names)
    if names:
        measured_maps(inp, names)


def compute_bem(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    for name in ("psd_substrate", "psd_solid"):
        extra = [d for d in psd[name].dims if d != "q"]
        if extra:
            section = "substrate" if name == "psd_substrate" else "solid"
            raise UserError(f"the bem stage does not sweep {', '.join(extra)}: give a single value",
                            key=f"{section}.hrms")
    C1, C2 = psd["psd_substrate"].values, psd["psd_solid"].values
    E_star = float(effective_modulus(inp["material.E"], inp["material.nu"]))
    names = map_surfaces(inp)
    _check_eta(inp, names)
    n_w = inp["bem.pixels_per_wavelength"]
    if names:  # measured maps: the map sets the grid and the band; one "realization"
        maps = measured_maps(inp, names)
        n, R, seed, dx = maps["n"], 1, None, maps["pixel_size"]
        L = maps["side"]
        q_cut, zeta_bem, limit = map_band(q[0], q[-1], n, L, maps["q_reliable"], n_w)
        if limit == "the maps' reliability cutoff":
            limit += f" ({maps['cutoff']})"
        zero = np.zeros((n, n))
        h_maps = {name: band_limit(maps["h"].get(name, zero), dx, q_cut) for name in ("substrate", "solid")}
    else:
        n, R, seed = inp["bem.grid"], inp["bem.realizations"], inp["bem.seed"]
        L, dx, q_cut, zeta_bem = grid_band(q[0], q[-1], n, n_w)
        limit = "bem.grid and bem.pixels_per_wavelength"
    contact, separation = inp.upstream["contact"], inp.upstream["separation"]
    G = _at_zeta(contact, "G", zeta_bem, "contact", limit)
    theory_area = _at_zeta(contact, "contact_area_ratio", zeta_bem, "contact", limit)
    theory_gap = _at_zeta(separation, "mean_separation", zeta_bem, "separation", limit)

    p_values = np.atleast_1d(np.asarray(inp["load.p"], dtype=float))
    has_eta = "eta" in psd["psd_combined"].dims
    if names or isinstance(inp["interface.eta"], str):
        eta_values = np.array([np.nan])  # measured: eta(q) is in the maps (and in the theory's combined PSD)
    elif has_eta:
        eta_values = psd["eta"].values
    else:
        eta_values = np.atleast_1d(float(np.atleast_1d(inp["interface.eta"])[0]))
        if not (np.any(C1 > 0) and np.any(C2 > 0)):
            eta_values = np.array([0.0])  # one surface is smooth: eta has no effect
    eta_values = np.atleast_1d(eta_values)
    nb = inp["numerics.bem_stress_bins"]
    level = (np.arange(nb) + 0.5) / nb
    # histogram edges per (p, eta): the contact stage's adaptive stress grid, top = p + width sqrt(G)
    G_pe = G.transpose("eta").values if has_eta else np.full(eta_values.size, float(G))
    top = p_values[:, None] + inp["numerics.sigma_width"] * np.sqrt(np.maximum(G_pe, 0.0))[None, :]
    top = np.where(top > p_values[:, None], top, 2.0 * p_values[:, None])
    edges = np.linspace(0.0, 1.0, nb + 1) * top[..., None]  # (p, eta, nb + 1)

    def pairs():
        """(eta index, realization, h1, h2) of every map pair to solve on."""
        if names:
            yield 0, 0, h_maps["substrate"], h_maps["solid"]
            return
        for r in range(R):
            noise = white_noise_pair(n, seed, r, band=zeta_bem)
            for j, eta in enumerate(eta_values):
                yield (j, r) + synthesize_pair(q, C1, C2, eta, n, q_cut, noise=noise)

    shape = (p_values.size, eta_values.size, R)
    area, gap, overflow = np.empty(shape), np.empty(shape), np.empty(shape)
    hist = np.empty(shape + (nb,))
    hrms, slope = np.empty(shape[1:]), np.empty(shape[1:])
    order = np.argsort(p_values)  # increasing load: each solve starts from the previous one
    for j, r, h1, h2 in pairs():
        hrms[j, r] = float(np.std(h1 - h2))
        slope[j, r] = rms_slope_of_map(h1 - h2, dx)
        res = contact_pair(h1, h2, dx, E_star, p_values[order], tolerance=inp["numerics.bem_tolerance"],
                           stress_edges=edges[order, j])
        area[order, j, r] = res["area"]
        gap[order, j, r] = res["mean_gap"]
        hist[order, j, r] = res["histogram"]
        overflow[order, j, r] = res["overflow"]

    dims = ("p", "eta", "realization")
    coords = {
        "p": ("p", p_values, {"units": "Pa", "long_name": "nominal pressure"}),
        "eta": ("eta", eta_values, {"units": "1", "long_name": "coherence of the two surfaces' roughness"}),
        "realization": ("realization", np.arange(R), {"units": "1", "long_name": (
            "index of the surface pair (0: the measured maps)" if names else "index of the random surface pair")}),
        "bem_stress_level": ("bem_stress_level", level,
                             {"units": "1", "long_name": "histogram bin centre, sigma / (p + sigma_width sqrt(G))"}),
    }
    what = "measured" if names else "synthesized"
    band = {"bem_zeta": zeta_bem, "bem_q_cut": q_cut, "bem_system_size": L, "bem_pixel_size": dx, "bem_grid": n}
    ds = xr.Dataset(coords=coords)
    ds = ds.assign_coords(bem_sigma=(("p", "eta", "bem_stress_level"), level * top[..., None],
                                     {"units": "Pa", "long_name": "local contact pressure at each histogram bin centre"}))
    ds["bem_contact_area_ratio"] = (dims, area, {
        "units": "1", "long_name": "relative contact area A/A0 from the BEM (fraction of pixels in contact)", **band})
    ds["bem_mean_gap"] = (dims, gap, {
        "units": "m", "long_name": "mean interfacial separation (map average of the gap) from the BEM", **band})
    ds["bem_stress_histogram"] = (dims + ("bem_stress_level",), hist, {
        "units": "1/Pa", "long_name": "BEM density of the local contact pressure (integrates to A/A0 within the bins)"})
    ds["bem_stress_overflow"] = (dims, overflow, {
        "units": "1", "long_name": "fraction of the map in contact at pressures beyond the last histogram bin"})
    ds["bem_hrms_combined"] = (("eta", "realization"), hrms, {
        "units": "m", "long_name": f"rms height of the {what} composite h1 - h2 in the BEM band"})
    ds["bem_rms_slope_combined"] = (("eta", "realization"), slope, {
        "units": "1", "long_name": f"rms slope of the {what} composite h1 - h2 in the BEM band"})
    ddof = 1 if R > 1 else 0
    for var, unit, text in (("bem_contact_area_ratio", "1", "relative contact area"),
                            ("bem_mean_gap", "m", "mean interfacial separation")):
        ds[f"{var}_mean"] = ds[var].mean("realization").assign_attrs(
            units=unit, long_name=f"BEM {text}, mean over realizations")
        ds[f"{var}_std"] = ds[var].std("realization", ddof=ddof).assign_attrs(
            units=unit, long_name=f"BEM {text}, standard deviation over realizations"
                                  + ("" if R > 1 else " (0: a single realization)"))
    t_area = _on(theory_area, p_values, eta_values, has_eta)
    t_gap = _on(theory_gap, p_values, eta_values, has_eta)
    ds["theory_contact_area_ratio"] = (("p", "eta"), t_area, {
        "units": "1", "long_name": f"A/A0 of the contact stage (eq 19) at zeta = {zeta_bem:.6g}"})
    ds["theory_mean_separation"] = (("p", "eta"), t_gap, {
        "units": "m", "long_name": f"mean separation of the separation stage (eq 57) at zeta = {zeta_bem:.6g}"})
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["area_ratio_theory_to_bem"] = (("p", "eta"), t_area / ds["bem_contact_area_ratio_mean"].values, {
            "units": "1", "long_name": "theory / BEM ratio of the relative contact area (same band)"})
        ds["separation_ratio_theory_to_bem"] = (("p", "eta"), t_gap / ds["bem_mean_gap_mean"].values, {
            "units": "1", "long_name": "theory / BEM ratio of the mean separation (same band; NaN where both are 0)"})
    for k, v in band.items():
        unit = {"bem_zeta": "1", "bem_q_cut": "1/m", "bem_system_size": "m", "bem_pixel_size": "m", "bem_grid": "1"}[k]
        ds[k] = xr.DataArray(v, attrs={"units": unit, "long_name": _BAND_NAMES[k]})
    ds["E_star"] = xr.DataArray(E_star, attrs={"units": "Pa", "long_name": "effective modulus E* = E/(1 - nu^2)"})
    ds.attrs.update({
        "bem_solver": f"tamaas {_tamaas().__version__} PolonskyKeerRey, tolerance {inp['numerics.bem_tolerance']:g}",
        "bem_surfaces": what,
        "bem_grid_mapping": f"map side L = {'the measured maps side' if names else '2 pi / qL'} = {L:.6g} m, "
                            f"{n} x {n} pixels of dx = {dx:.6g} m; roughness on 2 pi / L <= |q| <= q_cut = {q_cut:.6g} 1/m "
                            f"(set by {limit}; zeta_bem = {zeta_bem:.6g}); theory read at the same zeta",
    })
    if names:
        ds.attrs["bem_maps"] = (
            "; ".join(f"{name}: {maps['files'][name]} (detrend {maps['detrend'][name]})" for name in names)
            + "; composite h1 - h2 (substrate minus solid, both heights upwards in one frame, as for the measured "
              f"coherence), modes above q_cut and the mean removed; one realization")
    else:
        ds.attrs.update({
            "bem_synthesis": "H1 = (2 pi/L) sqrt(C1) xi1, H2 = (2 pi/L) sqrt(C2) (eta xi1 + sqrt(1 - eta^2) xi2), "
                             "xi = rfft2(white noise)/m on the smallest grid m holding the band (so a finer grid gives "
                             "the same surface), from numpy.random.default_rng([seed, realization]); "
                             "the same noise for every eta of a realization",
            "bem_seed": int(seed),
        })
    if not has_eta:
        ds = ds.isel(eta=0, drop=True)
    if np.ndim(inp["load.p"]) == 0:
        ds = ds.isel(p=0)
    return ds


_BAND_NAMES = {
    "bem_zeta": "magnification resolved by the BEM map, q_cut / qL (the theory is read there)",
    "bem_q_cut": "highest wavenumber of the roughness in the BEM map",
    "bem_system_size": "side of the periodic map, 2 pi / qL",
    "bem_pixel_size": "pixel size of the map",
    "bem_grid": "pixels per side of the map",
}


def _on(da: xr.DataArray, p_values, eta_values, has_eta) -> np.ndarray:
    """A theory variable as a (p, eta) array."""
    if "p" not in da.dims:
        da = da.expand_dims(p=p_values)
    if has_eta:
        return da.transpose("p", "eta").values
    return np.asarray(da.transpose("p").values)[:, None] * np.ones(np.size(eta_values))


# ----------------------------------------------------------------------------------------
# Figure
# ----------------------------------------------------------------------------------------


def figure_bem_comparison(results):
    """Theory (lines) against BEM (markers, +- one standard deviation over realizations) at the
    BEM's magnification: A/A0 and mean separation against p/E*, and their theory/BEM ratios."""
    import matplotlib.pyplot as plt

    ds = results["base"]["bem"]
    E_star = float(ds["E_star"])
    measured = ds.attrs.get("bem_surfaces") == "measured"
    zeta_bem, grid = float(ds["bem_zeta"]), int(ds["bem_grid"])  # scalars, before eta/p are expanded
    if "eta" not in ds.dims:
        ds = ds.expand_dims(eta=[np.nan])
    if "p" not in ds.dims:
        ds = ds.expand_dims("p")
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.3))
    x = ds["p"].values / E_star
    for k, eta in enumerate(ds["eta"].values):
        d = ds.isel(eta=k)
        label = (("measured maps" if measured else "pair") if np.isnan(eta)
                 else f"eta = {eta:+g}".replace("+0", "0"))
        if np.all(np.asarray(d["bem_hrms_combined"].values) == 0):
            label += " (h1 = h2: full contact)"
        color = f"C{k}"
        axes[0].loglog(x, d["theory_contact_area_ratio"], "-", color=color, label=f"theory, {label}")
        axes[0].errorbar(x, d["bem_contact_area_ratio_mean"], yerr=d["bem_contact_area_ratio_std"], fmt="o",
                         color=color, markersize=4, capsize=2, label=f"BEM, {label}")
        axes[1].semilogx(x, d["theory_mean_separation"] * 1e9, "-", color=color)
        axes[1].errorbar(x, d["bem_mean_gap_mean"] * 1e9, yerr=d["bem_mean_gap_std"] * 1e9, fmt="o",
                         color=color, markersize=4, capsize=2)
        for var, style, what in (("area_ratio_theory_to_bem", "o-", "A/A0"), ("separation_ratio_theory_to_bem", "s--", "u")):
            if np.any(np.isfinite(d[var].values)):
                axes[2].semilogx(x, d[var], style, color=color, markersize=4, label=f"{what}, {label}")
    axes[0].set_ylabel("A / A0")
    axes[0].set_ylim(top=1.3)
    axes[0].legend(fontsize=7)
    axes[0].set_title("contact area: theory (lines), BEM (points)", fontsize=9)
    axes[1].set_ylabel("mean separation u (nm)")
    axes[1].set_ylim(bottom=0)
    axes[1].set_title("mean separation" + (" (one measured pair)" if measured else
                                           " (error bars: spread over realizations)"), fontsize=9)
    axes[2].axhline(1.0, color="0.5", linewidth=0.8)
    axes[2].set_ylabel("theory / BEM")
    axes[2].set_title("ratios, same band on both sides", fontsize=9)
    axes[2].set_ylim(top=max(1.4, axes[2].get_ylim()[1] * 1.15))
    axes[2].legend(fontsize=7, ncol=2, loc="upper center")
    for ax in axes:
        ax.set_xlabel("p / E*")
        ax.grid(alpha=0.3)
    R = ds.sizes.get("realization", 1)
    source = ("the measured maps" if measured else
              f"{R} realization{'s' if R > 1 else ''}, seed {ds.attrs.get('bem_seed', '?')}")
    fig.suptitle(f"Theory vs BEM at zeta = {zeta_bem:.4g}: {grid}^2 map, {source}")
    fig.tight_layout()
    return fig


register(
    Stage(
        name="bem",
        version="2",
        compute=compute_bem,
        validate=validate_bem,
        requires=("psd", "contact", "separation"),
        params=("material.E", "material.nu", "load.p", "interface.eta", "substrate", "solid", "bem.surfaces",
                "bem.grid", "bem.realizations", "bem.seed", "bem.pixels_per_wavelength", "numerics.bem_tolerance",
                "numerics.bem_stress_bins", "numerics.sigma_width"),
        # measured maps (kind = "topography"): the engine reads them; used when bem.surfaces allows
        files=(FileInput("substrate.files", reader="topography"), FileInput("solid.files", reader="topography")),
        outputs={
            "bem_contact_area_ratio": Var("1", "relative contact area from the BEM, per realization"),
            "bem_mean_gap": Var("m", "mean interfacial separation from the BEM, per realization"),
            "bem_stress_histogram": Var("1/Pa", "BEM density of the local contact pressure"),
            "bem_stress_overflow": Var("1", "fraction of the map in contact beyond the histogram"),
            "bem_hrms_combined": Var("m", "rms height of the composite in the BEM band"),
            "bem_rms_slope_combined": Var("1", "rms slope of the composite in the BEM band"),
            "bem_contact_area_ratio_mean": Var("1", "BEM relative contact area, mean over realizations"),
            "bem_contact_area_ratio_std": Var("1", "BEM relative contact area, standard deviation"),
            "bem_mean_gap_mean": Var("m", "BEM mean separation, mean over realizations"),
            "bem_mean_gap_std": Var("m", "BEM mean separation, standard deviation"),
            "theory_contact_area_ratio": Var("1", "A/A0 of the contact stage at the BEM's magnification"),
            "theory_mean_separation": Var("m", "mean separation of the separation stage at the BEM's magnification"),
            "area_ratio_theory_to_bem": Var("1", "theory / BEM ratio of the relative contact area"),
            "separation_ratio_theory_to_bem": Var("1", "theory / BEM ratio of the mean separation"),
            "bem_zeta": Var("1", _BAND_NAMES["bem_zeta"]),
            "bem_q_cut": Var("1/m", _BAND_NAMES["bem_q_cut"]),
            "bem_system_size": Var("m", _BAND_NAMES["bem_system_size"]),
            "bem_pixel_size": Var("m", _BAND_NAMES["bem_pixel_size"]),
            "bem_grid": Var("1", _BAND_NAMES["bem_grid"]),
            "E_star": Var("Pa", "effective modulus E*"),
        },
        coords={
            "realization": Var("1", "index of the surface pair"),
            "bem_stress_level": Var("1", "histogram bin centre, sigma / (p + sigma_width sqrt(G))"),
            "bem_sigma": Var("Pa", "local contact pressure at each histogram bin centre"),
        },
        figures=(Figure("bem_comparison", "theory vs BEM: A/A0, mean separation and their ratios",
                        ("bem",), figure_bem_comparison),),
        doc="Exact FFT-BEM contact (tamaas) on synthesized or measured surface pairs, compared with the theory at the same band.",
    )
)
