"""Measured surfaces: height maps and line scans -> isotropic PSD; paired surfaces -> coherence.

Physics: ``equations.md`` section 1 (seed eqs 4, 41, 52, 65).

* 2D maps: C(q) = (2 pi)^-2 \\int d^2x <h(x) h(0)> exp(-i q.x) (Persson, eq 4) estimated as the
  radial average of (dx dy)^2 |DFT h|^2 / ((2 pi)^2 Lx Ly) over the Fourier modes in log-spaced
  bins of |q|. Discretely, sum_q C(q) (2 pi)^2 / (Lx Ly) = <h^2> (Parseval).
* Line scans: C1D(q) = (dx^2 / L) |DFT h|^2 (hrms^2 = (1/pi) \\int_0^inf C1D dq), converted to the
  isotropic 2D PSD with C(q) = c(H) C1D(q) / q, c(H) = Gamma(1 + H) / (2 pi^(3/2) Gamma(H + 1/2)),
  exact for an isotropic self-affine surface with Hurst exponent H (c(1/2) = 1/(4 pi)).
* Pairs h1, h2 of the two surfaces on the same grid: the cross-spectrum C12 (radial average of
  Re h1(q) h2(q)*, same normalisation) and the coherence eta(q) = C12 / sqrt(C11 C22) (eq 41).

The stage reads nothing itself: the engine hands it the files read by
:func:`pipeline.readers.read_topography` (heights in metres, x first).
"""

from __future__ import annotations

import json
import math

import numpy as np
import scipy.fft
import scipy.special
import xarray as xr

from roughcontact.stage import UserError
from roughcontact.stage import Param
from roughcontact.stage import FileInput, Figure, Stage, StageInput, Var, register, register_params
from roughcontact.units import array_to_si

from roughcontact.physics.quadrature import loglog_interp
from roughcontact.physics.spectra import isotropic_factor

from .shared import DETREND_DEGREE, SURFACES, is_topography, needs_topography  # noqa: F401

# ----------------------------------------------------------------------------------------
# Kernels (pure numpy)
# ----------------------------------------------------------------------------------------



def _orthogonal_polynomials(n: int, degree: int) -> np.ndarray:
    """Discrete polynomials 1, t, t^2 - <t^2> (t centred), orthogonal on n uniform points; (n, degree+1)."""
    t = np.arange(n, dtype=float) - (n - 1) / 2.0
    cols = [np.ones(n), t, t * t - np.mean(t * t)][: degree + 1]
    return np.stack(cols, axis=1)


def detrend(h, degree, *, profiles=False):
    """Remove the least-squares polynomial of total degree ``degree`` (0 mean, 1 plane,
    2 curvature: 1, x, y, x^2, xy, y^2) from a line scan (n,) or a map (nx, ny).

    With ``profiles=True`` a map is treated as ny line scans along x, each detrended on its own.
    Uses polynomials orthogonal on the grid, so the fit is exact least squares and needs only
    one temporary map. Returns a new array.

    Parameters
    ----------
    h : array (n,) or (nx, ny)
        Heights (m), uniform grid.
    degree : int
        0, 1 or 2.
    """
    h = np.array(h, dtype=float)
    nx = h.shape[0]
    px = _orthogonal_polynomials(nx, degree)
    norm_x = np.sum(px * px, axis=0)
    if h.ndim == 1 or profiles:
        coef = (px.T @ h.reshape(nx, -1)) / norm_x[:, None]
        h -= (px @ coef).reshape(h.shape)
        return h
    ny = h.shape[1]
    py = _orthogonal_polynomials(ny, degree)
    norm_y = np.sum(py * py, axis=0)
    terms = [(a, b) for a in range(degree + 1) for b in range(degree + 1) if a + b <= degree]
    hy = h @ py  # (nx, degree+1)
    A = np.stack([px[:, a] * (px[:, a] @ hy[:, b]) / (norm_x[a] * norm_y[b]) for a, b in terms], axis=1)
    B = np.stack([py[:, b] for a, b in terms], axis=0)
    h -= A @ B
    return h


def hann_window_1d(n: int) -> np.ndarray:
    """Periodic Hann window along x, normalised so that its mean square is 1."""
    w = 0.5 * (1.0 - np.cos(2.0 * np.pi * np.arange(n) / n))
    return w / np.sqrt(np.mean(w * w))


def hann_window_radial(nx: int, ny: int, sx: float, sy: float) -> np.ndarray:
    """Rotationally symmetric Hann window w(r) = [1 + cos(pi r / r_max)] / 2 for r < r_max =
    min(Lx, Ly)/2 (r from grid point (nx//2, ny//2)), normalised to mean square 1 (as
    SurfaceTopography's ``get_window_2D``)."""
    x = (np.arange(nx) - nx // 2) * (sx / nx)
    y = (np.arange(ny) - ny // 2) * (sy / ny)
    w = np.hypot(x[:, None], y[None, :])  # r, turned into the window in place (one map of memory)
    rmax = min(sx, sy) / 2.0
    outside = w >= rmax
    w *= np.pi / rmax
    np.cos(w, out=w)
    w += 1.0
    w *= 0.5
    w[outside] = 0.0
    w /= np.sqrt(np.mean(w * w))
    return w


def log_bin_edges(q_lo: float, q_hi: float, bins_per_decade: int) -> np.ndarray:
    """Edges 10^(k / bins_per_decade) (1/m) of the fixed logarithmic bin lattice covering
    [q_lo, q_hi]; bin i holds edges[i-1] < |q| <= edges[i]. The lattice does not depend on the
    data, so spectra of several files share bins."""
    k0 = math.floor(bins_per_decade * math.log10(q_lo)) - 1
    k1 = math.ceil(bins_per_decade * math.log10(q_hi)) + 1
    return 10.0 ** (np.arange(k0, k1 + 1) / bins_per_decade)


def psd_map(h, sx, sy):
    """Full 2D PSD in Persson's convention (m^4), in the layout of ``numpy.fft.fft2``:
    C(q) = (dx dy)^2 |DFT h|^2 / ((2 pi)^2 Lx Ly), so that sum_q C (2 pi)^2 / (Lx Ly) = <h^2>."""
    nx, ny = h.shape
    area_per_pt = (sx / nx) * (sy / ny)
    return area_per_pt**2 * np.abs(np.fft.fft2(h)) ** 2 / ((2.0 * np.pi) ** 2 * sx * sy)


def _bincount(idx, weights, nbins):
    return np.bincount(idx.ravel(), weights=None if weights is None else weights.ravel(), minlength=nbins + 1)[: nbins + 1]


def binned_spectra_area(h1, sx, sy, edges, q_max, h2=None):
    """Radially binned 2D spectra of a map (and of a second map on the same grid).

    Parameters
    ----------
    h1, h2 : array (nx, ny)
        Prepared (detrended, windowed) heights (m); ``h2`` optional.
    sx, sy : float
        Physical sizes (m).
    edges : array
        Bin edges (1/m), see :func:`log_bin_edges`.
    q_max : float
        Modes with |q| > q_max (Nyquist or reliability cutoff) are left out.

    Returns
    -------
    dict of arrays over the bins (len(edges) - 1)
        ``n`` independent Fourier modes (a mode and its conjugate count once), ``q`` the mean
        |q| of the modes, ``C11`` (and ``C22``, ``C12`` = Re cross-spectrum) the mean PSD in
        Persson's convention (m^4); NaN where a bin holds no mode.

    Notes
    -----
    Real-to-complex FFT over y; interior columns stand for themselves and their conjugates
    (weight 2), so averages equal those over the full Fourier plane. Peak memory: the input
    plus about three map-sizes of temporaries.
    """
    nx, ny = h1.shape
    norm = ((sx / nx) * (sy / ny)) ** 2 / ((2.0 * np.pi) ** 2 * sx * sy)
    qx = 2.0 * np.pi * np.fft.fftfreq(nx, d=sx / nx)
    qy = 2.0 * np.pi * np.fft.rfftfreq(ny, d=sy / ny)
    w = np.full(qy.size, 2.0)
    w[0] = 1.0
    if ny % 2 == 0:
        w[-1] = 1.0
    q = np.sqrt(qx[:, None] ** 2 + qy[None, :] ** 2)
    nb = edges.size - 1
    idx = np.searchsorted(edges, q)  # bin i+1 <-> edges[i] < q <= edges[i+1]; 0 and nb+1: outside
    idx[(q > q_max) | (q == 0.0)] = nb + 1  # dropped
    idx[idx > nb + 1] = nb + 1
    wfull = np.broadcast_to(w, q.shape)
    count = _bincount(idx, wfull, nb + 1)
    qsum = _bincount(idx, q * wfull, nb + 1)
    del q
    out = {}
    H1 = scipy.fft.rfft2(h1)
    P = H1.real**2 + H1.imag**2
    P *= w
    out["C11"] = _bincount(idx, P, nb + 1)
    if h2 is not None:
        H2 = scipy.fft.rfft2(h2)
        np.multiply(H2.real, H2.real, out=P)
        P += H2.imag**2
        P *= w
        out["C22"] = _bincount(idx, P, nb + 1)
        np.multiply(H1.real, H2.real, out=P)
        P += H1.imag * H2.imag
        P *= w
        out["C12"] = _bincount(idx, P, nb + 1)
        del H2
    del H1, P, idx
    sl = slice(1, nb + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        res = {k: np.where(count[sl] > 0, v[sl] * norm / count[sl], np.nan) for k, v in out.items()}
        res["q"] = np.where(count[sl] > 0, qsum[sl] / count[sl], np.nan)
    res["n"] = count[sl] / 2.0
    return res


def binned_spectra_profiles(h1, sx, edges, q_max, hurst, h2=None):
    """Binned isotropic PSD from line scans along x: the 1D PSD C1D = (dx^2/L) |DFT h|^2 per
    mode and profile, converted by C = c(H) C1D / q (:func:`isotropic_factor`), averaged over
    profiles and bins.

    ``h1`` (and ``h2``) are (nx,) or (nx, n_profiles) arrays (m), prepared (detrended, windowed).
    Returns the same dict as :func:`binned_spectra_area`; ``n`` counts one independent mode
    per positive wavenumber per profile (profiles are taken as independent).
    """
    h1 = h1.reshape(h1.shape[0], -1)
    nx, nprof = h1.shape
    norm = (sx / nx) ** 2 / sx
    qx = 2.0 * np.pi * np.fft.rfftfreq(nx, d=sx / nx)
    nb = edges.size - 1
    idx = np.searchsorted(edges, qx)
    idx[(qx > q_max) | (qx == 0.0)] = nb + 1
    idx[idx > nb + 1] = nb + 1
    conv = np.zeros_like(qx)
    conv[qx > 0] = isotropic_factor(hurst) / qx[qx > 0]
    count = np.bincount(idx, minlength=nb + 2)[: nb + 2] * float(nprof)
    qsum = np.bincount(idx, weights=qx * nprof, minlength=nb + 2)[: nb + 2]
    H1 = scipy.fft.rfft(h1, axis=0)
    out = {"C11": (np.abs(H1) ** 2).sum(axis=1)}
    if h2 is not None:
        H2 = scipy.fft.rfft(h2.reshape(nx, -1), axis=0)
        out["C22"] = (np.abs(H2) ** 2).sum(axis=1)
        out["C12"] = (H1.real * H2.real + H1.imag * H2.imag).sum(axis=1)
    sl = slice(1, nb + 1)
    res = {}
    with np.errstate(invalid="ignore", divide="ignore"):
        for k, v in out.items():
            s = np.bincount(idx, weights=v * conv * norm, minlength=nb + 2)[: nb + 2]
            res[k] = np.where(count[sl] > 0, s[sl] / count[sl], np.nan)
        res["q"] = np.where(count[sl] > 0, qsum[sl] / count[sl], np.nan)
    res["n"] = count[sl]
    return res


def merge_spectra(spectra, key="C11"):
    """Merge binned spectra of several files of one surface (e.g. several magnifications).

    In each bin the files that have modes there are averaged with weights n (their numbers of
    independent modes: the inverse-variance weights for equal true PSDs). Returns q, C, n and
    the standard error C / sqrt(n) (Gaussian random-phase statistics: each mode's power is
    exponentially distributed, standard deviation = mean).
    """
    n = np.stack([s["n"] for s in spectra])
    has = n > 0
    C = np.where(has, np.stack([s[key] for s in spectra]), 0.0)
    q = np.where(has, np.stack([s["q"] for s in spectra]), 0.0)
    ntot = n.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        Cm = np.where(ntot > 0, (n * C).sum(axis=0) / ntot, np.nan)
        qm = np.where(ntot > 0, (n * q).sum(axis=0) / ntot, np.nan)
        err = Cm / np.sqrt(ntot)
    return qm, Cm, ntot, err


def coherence(C11, C22, C12, n):
    """Coherence eta(q) = Re C12 / sqrt(C11 C22) (eq 41) and its statistical standard error.

    For n independent complex Gaussian mode pairs with real coherency eta, each mode gives two
    real sample pairs with correlation eta, so the estimator's standard error is
    (1 - eta^2) / sqrt(2 n) (Fisher's large-sample variance of a correlation coefficient).
    eta is NaN where C11 or C22 is 0 (a flat surface has no coherence).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        eta = C12 / np.sqrt(C11 * C22)
        eta = np.clip(eta, -1.0, 1.0)
        err = (1.0 - eta * eta) / np.sqrt(2.0 * n)
    return eta, err


def tip_radius_cutoff(h, sx, tip_radius, safety_factor=0.5):
    """Shortest reliable wavelength (m) of a scanning-probe measurement with tip radius R.

    Sanner et al., Appl. Surf. Sci. Adv. 7, 100190 (2022): a tip of radius R cannot follow
    valleys with curvature below -1/R. The scale-dependent curvature at stencil length
    lambda = 2 s is the second difference (h(x+s) - 2 h(x) + h(x-s)) / s^2 along x; the cutoff
    is the smallest lambda at which its minimum over the data is >= -f/R (f = 1/2). Returns
    None when even the grid spacing satisfies the criterion.
    """
    h = h.reshape(h.shape[0], -1)
    nx = h.shape[0]
    dx = sx / nx
    target = -safety_factor / tip_radius
    steps = np.unique(np.round(np.geomspace(1, max(1, nx // 4), 60)).astype(int))
    for s in steps:
        curv = (h[2 * s:] - 2.0 * h[s:-s] + h[: -2 * s]) / (s * dx) ** 2
        if curv.size and curv.min() >= target:
            return None if s == 1 else 2.0 * s * dx
    return 2.0 * steps[-1] * dx


# ----------------------------------------------------------------------------------------
# Scene keys (the "topography" kind of the [substrate]/[solid] sections, in stages/psd.py)
# ----------------------------------------------------------------------------------------

register_params(
    "numerics",
    Param("topography_bins_per_decade", "int", default=20, lo=2, hi=200,
          doc="logarithmic wavenumber bins per decade for the radial average of measured PSDs"),
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------


def _prepare(name, spec, topo, index):
    """Heights in metres, sizes, and the processing settings for one file, checked."""
    key = f"{name}.files"
    path = str(topo.path)
    h = topo.heights
    sizes = topo.physical_sizes
    if topo.unit is None:
        unit = spec.get("height_unit")
        if unit is None:
            raise UserError(f"the file does not say the unit of its heights; set {name}.height_unit (e.g. \"nm\")",
                            file=path, key=f"{name}.height_unit")
        factor = float(array_to_si(np.array(1.0), unit, "m", key=f"{name}.height_unit"))
        h = h * factor
        sizes = tuple(s * factor for s in sizes) if sizes is not None else None
        unit_note = f"{unit} (scene)"
    else:
        unit_note = f"{topo.unit} (file)"
    if sizes is None:
        if spec.get("size_x") is None:
            raise UserError(f"the file does not say its physical size; set {name}.size_x (and size_y)",
                            file=path, key=f"{name}.size_x")
        sx = spec["size_x"]
        sizes = (sx,) if h.ndim == 1 else (sx, spec.get("size_y") or sx * h.shape[1] / h.shape[0])
        size_note = "scene"
    else:
        size_note = "file"
    bad = np.isnan(h)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise UserError(
            f"{int(bad.sum())} of {h.size} heights are missing (NaN or masked), first at index {first}; the FFT needs a "
            "complete grid: fill them (interpolate) or crop the map in the instrument software", file=path, key=key)
    if not np.all(np.isfinite(h)):
        raise UserError("infinite height values", file=path, key=key)
    if h.ndim not in (1, 2) or min(h.shape) < (8 if h.ndim == 1 else 4) or h.shape[0] < 8:
        raise UserError(f"too few points for a spectrum (shape {h.shape}; needs at least 8 along x)", file=path, key=key)
    periodic = spec.get("periodic") if spec.get("periodic") is not None else topo.periodic
    detrend_how = spec.get("detrend") or ("mean" if periodic else "plane")
    window = spec.get("window") or ("none" if periodic else "hann")
    analysis = "profiles" if h.ndim == 1 else spec["analysis"]
    return dict(h=h, sizes=tuple(float(s) for s in sizes), periodic=bool(periodic), detrend=detrend_how,
                window=window, analysis=analysis, unit=unit_note, size_source=size_note, path=path,
                format=topo.format, index=index)


def _process(p, spec):
    """Detrend and window the heights in place; the reliable q range."""
    h, sizes = p["h"], p["sizes"]
    profiles = p["analysis"] == "profiles"
    h = detrend(h, DETREND_DEGREE[p["detrend"]], profiles=profiles)
    rms = float(np.sqrt(np.mean(h * h)))
    if p["window"] == "hann":
        if profiles:
            h *= hann_window_1d(h.shape[0]).reshape((-1,) + (1,) * (h.ndim - 1))
        else:
            h *= hann_window_radial(*h.shape, *sizes)
    dx = [s / n for s, n in zip(sizes, h.shape)]
    q_max = np.pi / (dx[0] if profiles else min(dx))
    why = "Nyquist pi/dx"
    cut = []
    if spec.get("tip_radius") is not None:
        lam = tip_radius_cutoff(p["h"], sizes[0], spec["tip_radius"])  # 2nd differences ignore mean and plane
        if lam is not None:
            cut.append((2 * np.pi / lam, f"tip radius {spec['tip_radius']:.3g} m (cutoff wavelength {lam:.3g} m)"))
    if spec.get("resolution") is not None:
        cut.append((2 * np.pi / spec["resolution"], f"resolution {spec['resolution']:.3g} m"))
    if spec.get("q_reliable") is not None:
        cut.append((spec["q_reliable"], "given q_reliable"))
    for qc, text in cut:
        if qc < q_max:
            q_max, why = qc, text
    q_min = 2 * np.pi / max(sizes[:1] if profiles else sizes)
    if q_max <= q_min:
        raise UserError(f"no reliable data: the reliability cutoff {q_max:.4g} 1/m ({why}) is below the lowest "
                        f"wavenumber {q_min:.4g} 1/m of the scan", file=p["path"], key=None)
    p.update(h=h, q_max=q_max, q_min=q_min, cutoff=why, rms=rms)
    return p


def _spectra(p, edges, spec, other=None):
    h2 = other["h"] if other is not None else None
    if p["analysis"] == "profiles":
        return binned_spectra_profiles(p["h"], p["sizes"][0], edges, p["q_max"], spec["hurst"], h2)
    return binned_spectra_area(p["h"], p["sizes"][0], p["sizes"][1], edges, p["q_max"], h2)


def _describe(p, spec):
    d = {k: p[k] for k in ("path", "format", "unit", "size_source", "periodic", "detrend", "window", "analysis", "cutoff")}
    d.update(shape=list(p["h"].shape), sizes_m=list(p["sizes"]), q_range_per_m=[p["q_min"], p["q_max"]],
             rms_height_after_detrend_m=p["rms"])
    if p["analysis"] == "profiles":
        d["isotropic_conversion"] = (f"C(q) = c(H) C1D(q) / q with c(H) = Gamma(1+H)/(2 pi^1.5 Gamma(H+1/2)), "
                                     f"H = {spec['hurst']:g}; exact only for an isotropic self-affine surface with "
                                     "that H (roll-off and band edges bias it)")
    return d


def _pairing_problem(a, b) -> str | None:
    if len(a) != len(b):
        return f"the substrate has {len(a)} file(s) and the solid {len(b)}; pairs need one solid file per substrate file"
    for i, (p, r) in enumerate(zip(a, b)):
        if p["h"].shape != r["h"].shape:
            return f"file pair {i}: grids differ ({p['h'].shape} vs {r['h'].shape} points)"
        if not np.allclose(p["sizes"], r["sizes"], rtol=1e-6):
            return f"file pair {i}: physical sizes differ ({p['sizes']} vs {r['sizes']} m)"
        if p["analysis"] != r["analysis"] or p["window"] != r["window"]:
            return f"file pair {i}: analysis/window differ"
    return None


def compute_topography(inp: StageInput) -> xr.Dataset:
    bpd = inp["numerics.topography_bins_per_decade"]
    specs = {name: inp[name] for name in SURFACES if is_topography(inp[name])}
    if not specs:
        raise UserError("no surface has kind = 'topography'", key="substrate.kind")
    prepared = {}
    for name, spec in specs.items():
        prepared[name] = [_process(_prepare(name, spec, t, i), spec) for i, t in enumerate(inp.files[f"{name}.files"])]
    q_lo = min(p["q_min"] for ps in prepared.values() for p in ps)
    q_hi = max(p["q_max"] for ps in prepared.values() for p in ps)
    edges = log_bin_edges(q_lo, q_hi, bpd)
    centres = np.sqrt(edges[1:] * edges[:-1])
    data_vars = {}
    pair_note = _pairing_problem(prepared["substrate"], prepared["solid"]) if len(specs) == 2 else None
    paired = len(specs) == 2 and pair_note is None
    spectra = {}
    if paired:
        joint = []
        for p, r in zip(prepared["substrate"], prepared["solid"]):
            # a pair uses the modes reliable in both files; each surface keeps its own line-scan H
            both = dict(p, q_max=min(p["q_max"], r["q_max"]))
            s = _spectra(both, edges, specs["substrate"], r)
            if p["analysis"] == "profiles":
                ratio = float(isotropic_factor(specs["solid"]["hurst"]) / isotropic_factor(specs["substrate"]["hurst"]))
                s["C22"] = s["C22"] * ratio
                s["C12"] = s["C12"] * math.sqrt(ratio)  # keeps eta = C12 / sqrt(C11 C22) free of the conversion
            joint.append(s)
        spectra["substrate"] = joint
        spectra["solid"] = [{"n": s["n"], "q": s["q"], "C11": s["C22"]} for s in joint]
    else:
        for name in specs:
            spectra[name] = [_spectra(p, edges, specs[name]) for p in prepared[name]]
    keep = np.zeros(centres.size, bool)
    for name in specs:
        q, C, n, err = merge_spectra(spectra[name])
        keep |= n > 0
        described = [_describe(p, specs[name]) for p in prepared[name]]
        common = {"surface": name, "files": json.dumps(described), "convention": "Persson, C(q) = (2 pi)^-2 int d^2x <hh> e^-iqx",
                  "radial_average": f"mean over Fourier modes with |q| in log bins, {bpd} per decade"}
        data_vars[f"psd_{name}_measured"] = (("q_bin",), C, {"units": "m^4", "long_name": f"measured PSD of the {name} (Persson convention)", **common})
        data_vars[f"psd_{name}_measured_error"] = (("q_bin",), err, {
            "units": "m^4", "long_name": f"statistical standard error of the measured PSD of the {name}",
            "estimate": "C / sqrt(n): Gaussian random-phase modes; window-correlated and correlated profiles make it an underestimate"})
        data_vars[f"q_{name}_measured"] = (("q_bin",), q, {"units": "1/m", "long_name": f"mean wavenumber of the {name}'s Fourier modes in the bin"})
        data_vars[f"modes_{name}"] = (("q_bin",), n, {"units": "1", "long_name": f"independent Fourier modes of the {name} in the bin"})
    if paired:
        joint = spectra["substrate"]
        n = np.stack([s["n"] for s in joint])
        has = n > 0
        sums = {k: np.where(has, n * np.stack([np.nan_to_num(s[k]) for s in joint]), 0.0).sum(axis=0) for k in ("C11", "C22", "C12")}
        ntot = n.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            C12 = np.where(ntot > 0, sums["C12"] / ntot, np.nan)
        eta, eta_err = coherence(sums["C11"], sums["C22"], sums["C12"], ntot)
        data_vars["cross_psd_measured"] = (("q_bin",), C12, {"units": "m^4", "long_name": "measured cross-spectrum Re C12 of the pair (Persson convention)"})
        data_vars["coherence"] = (("q_bin",), np.where(ntot > 0, eta, np.nan), {
            "units": "1", "long_name": "measured coherence eta(q) = Re C12 / sqrt(C11 C22) (eq 41)"})
        data_vars["coherence_error"] = (("q_bin",), np.where(ntot > 0, eta_err, np.nan), {
            "units": "1", "long_name": "statistical standard error of the coherence, (1 - eta^2) / sqrt(2 n)"})
    sel = np.flatnonzero(keep)
    sl = slice(sel[0], sel[-1] + 1)
    ds = xr.Dataset({k: (d, v[sl], a) for k, (d, v, a) in data_vars.items()},
                    coords={"q_bin": ("q_bin", centres[sl], {"units": "1/m", "long_name": "wavenumber (geometric bin centre)"})})
    ds.attrs["bins_per_decade"] = bpd
    ds.attrs["pairing"] = ("paired: file i of the substrate with file i of the solid" if paired else
                           f"not paired: {pair_note}" if pair_note else "not paired: one surface only")
    return ds


def measured_psd_on_grid(ds: xr.Dataset, name: str, q_grid: np.ndarray, how: str, path_hint: str = ""):
    """The measured PSD of surface ``name`` interpolated (log-log) onto ``q_grid``; used by the
    psd stage. ``how`` extends beyond the measured range: 'none' (error), 'power_law', 'zero'."""
    q = ds[f"q_{name}_measured"].values
    C = ds[f"psd_{name}_measured"].values
    ok = np.isfinite(q) & np.isfinite(C) & (C > 0)
    q, C = q[ok], C[ok]
    order = np.argsort(q)
    q, C = q[order], C[order]
    if q.size < 2:
        raise UserError("the measured PSD has fewer than two valid bins", key=f"{name}.files")
    lo, hi = q_grid[0], q_grid[-1]
    if how == "none" and (lo < q[0] * (1 - 1e-9) or hi > q[-1] * (1 + 1e-9)):
        raise UserError(
            f"the q grid [{lo:.4g}, {hi:.4g}] 1/m reaches outside the measured range [{q[0]:.4g}, {q[-1]:.4g}] 1/m; "
            f"set grid.q_min/q_max inside it or {name}.extend = 'power_law' or 'zero'", key=f"{name}.extend")
    inside = (q_grid >= q[0]) & (q_grid <= q[-1])
    out = np.zeros_like(q_grid)
    out[inside] = loglog_interp(q_grid[inside], q, C)
    if how == "power_law":
        for sel, (i, j) in ((q_grid < q[0], (0, min(3, q.size - 1))), (q_grid > q[-1], (max(-4, -q.size), -1))):
            if np.any(sel):
                slope = np.log(C[j] / C[i]) / np.log(q[j] / q[i])
                out[sel] = C[i] * (q_grid[sel] / q[i]) ** slope
    attrs = {"surface": "measured topography", "source_files": ds[f"psd_{name}_measured"].attrs.get("files", ""),
             "interpolation": "log-log linear between bin averages", "extension": how,
             "measured_q_range": f"{q[0]:.6g} {q[-1]:.6g} 1/m"}
    return out, attrs


def measured_coherence_on_grid(ds: xr.Dataset, q_grid: np.ndarray) -> np.ndarray:
    """The measured coherence interpolated (linear in log q) onto ``q_grid``; held constant at
    its end values outside the measured range."""
    q = ds["q_substrate_measured"].values
    eta = ds["coherence"].values
    ok = np.isfinite(q) & np.isfinite(eta)
    q, eta = q[ok], eta[ok]
    order = np.argsort(q)
    return np.interp(np.log(q_grid), np.log(q[order]), eta[order])


# ----------------------------------------------------------------------------------------
# Figures
# ----------------------------------------------------------------------------------------


def _figure_psd(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["topography"]
    fig, ax = plt.subplots(figsize=(6.4, 4.6), constrained_layout=True)
    for name, colour in (("substrate", "C0"), ("solid", "C3")):
        var = f"psd_{name}_measured"
        if var not in ds:
            continue
        q, C, e = ds[f"q_{name}_measured"].values, ds[var].values, ds[f"{var}_error"].values
        ok = np.isfinite(C) & (C > 0)
        band = np.exp(2 * e[ok] / C[ok])  # +-2 s.e. in log space (the relative error is what matters on log axes)
        ax.fill_between(q[ok], C[ok] / band, C[ok] * band, color=colour, alpha=0.25, lw=0)
        ax.loglog(q[ok], C[ok], "o", color=colour, ms=2.5, label=f"{name}: measured bins (band: 2 s.e.)")
        if "psd" in results["base"]:
            p = results["base"]["psd"]
            ax.loglog(p["q"].values, p[f"psd_{name}"].values, "-", color=colour, lw=0.8, label=f"{name}: on the psd stage's q grid")
    ax.set_xlabel("wavenumber q (1/m)")
    ax.set_ylabel("C(q) (m$^4$, Persson convention)")
    ax.set_title("Measured power spectral densities")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def _figure_coherence(results):
    import matplotlib.pyplot as plt

    ds = results["base"]["topography"]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), constrained_layout=True)
    if "coherence" not in ds:
        ax.text(0.5, 0.5, "no paired topographies: coherence not measured", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    q, eta, e = ds["q_substrate_measured"].values, ds["coherence"].values, ds["coherence_error"].values
    ok = np.isfinite(eta)
    ax.fill_between(q[ok], eta[ok] - 2 * e[ok], eta[ok] + 2 * e[ok], color="C2", alpha=0.25, lw=0, label="2 s.e.")
    ax.semilogx(q[ok], eta[ok], "o-", color="C2", ms=2.5, lw=1, label="eta(q) = Re C12 / sqrt(C11 C22)")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylim(-1.05, 1.05)
    ax.set_xlabel("wavenumber q (1/m)")
    ax.set_ylabel("coherence eta")
    ax.set_title("Measured coherence of the two surfaces")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


register(
    Stage(
        name="topography",
        version="1",
        compute=compute_topography,
        params=("substrate", "solid", "numerics.topography_bins_per_decade"),
        files=(FileInput("substrate.files", reader="topography"), FileInput("solid.files", reader="topography")),
        outputs={
            **{f"psd_{s}_measured": Var("m^4", f"measured PSD of the {s} (Persson convention)") for s in SURFACES},
            **{f"psd_{s}_measured_error": Var("m^4", f"standard error of the measured PSD of the {s}") for s in SURFACES},
            **{f"q_{s}_measured": Var("1/m", f"mean wavenumber of the {s}'s modes in the bin") for s in SURFACES},
            **{f"modes_{s}": Var("1", f"independent Fourier modes of the {s} in the bin") for s in SURFACES},
            "cross_psd_measured": Var("m^4", "measured cross-spectrum Re C12 of the pair"),
            "coherence": Var("1", "measured coherence eta(q)"),
            "coherence_error": Var("1", "standard error of the measured coherence"),
        },
        coords={"q_bin": Var("1/m", "wavenumber (geometric bin centre)")},
        figures=(
            Figure("measured_psd", "Measured PSDs", ("topography",), _figure_psd),
            Figure("coherence", "Measured coherence eta(q)", ("topography",), _figure_coherence),
        ),
        doc="Isotropic PSDs from measured height maps / line scans; cross-spectrum and coherence of paired surfaces.",
    )
)
