"""Measured height maps in the stage layer: how they are read, checked and prepared, shared by
the ``topography`` stage (spectra, coherence) and the ``bem`` stage (contact on the maps: the
checks a map must pass and its band), and how the ``psd`` stage puts the measured spectra on
its q grid.

Not a stage (it registers nothing). Kernels: :mod:`roughcontact.physics.preprocessing` and
:mod:`roughcontact.physics.estimators`. The
``[substrate]`` / ``[solid]`` keys of ``kind = "topography"`` are declared in
:mod:`roughcontact.stages.shared.surfaces`; docs/topography.md describes them.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.estimators import binned_psd_on_grid, coherence_on_grid, valid_bins
from roughcontact.physics.preprocessing import detrend, hann_window_1d, hann_window_radial, tip_radius_cutoff
from roughcontact.physics.uncertainty import bin_curvature_factor, interpolation_unbiasing
from roughcontact.stage import FileInput, UserError

from .surfaces import DETREND_DEGREE, SURFACES, is_rough, is_topography


def topography_files(name: str) -> FileInput:
    """The height maps of surface ``name``, read in metres by the engine's topography reader
    (the scene's ``height_unit`` for files that do not say their unit)."""

    def options(params):
        return dict(key=name, height_unit=params[name].get("height_unit"), fill=params[name].get("fill_undefined"))

    return FileInput(f"{name}.files", reader="topography", options=options)


def filled_note(topo) -> dict | None:
    """What the result records about the undefined heights the reader filled (None if none
    was): how, how many, and where (connected regions, the largest, their bounding box, the
    first indices)."""
    mask = getattr(topo, "filled", None)
    if mask is None:
        return None
    from scipy import ndimage

    labels, regions = ndimage.label(mask)
    sizes = np.bincount(labels.ravel())[1:]
    where = np.argwhere(mask)
    return {"method": topo.fill_method,
            "points": int(mask.sum()), "of_points": int(mask.size), "fraction": float(mask.mean()),
            "regions": int(regions), "largest_region_points": int(sizes.max()),
            "bounding_box_index": [[int(a), int(b)] for a, b in zip(where.min(axis=0), where.max(axis=0), strict=True)],
            "first_indices": [[int(i) for i in idx] for idx in where[:10]]}


def _sizes(name, spec, topo, path):
    """The scan's physical sizes (m) and where they come from (the file or the scene)."""
    h, sizes = topo.heights, topo.physical_sizes
    if sizes is not None:
        return sizes, "file"
    if spec.get("size_x") is None:
        raise UserError(f"the file does not say its physical size; set {name}.size_x (and size_y)",
                        file=path, key=f"{name}.size_x")
    sx = spec["size_x"]
    return ((sx,) if h.ndim == 1 else (sx, spec.get("size_y") or sx * h.shape[1] / h.shape[0])), "scene"


def prepare_map(name: str, spec: dict, topo, index: int) -> dict:
    """One file of surface ``name`` checked, with its sizes and processing settings.

    ``topo`` is what the topography reader returned (heights in metres). Missing points (not
    filled by the reader: ``name.fill_undefined``), infinite values and too small grids are a
    :class:`UserError` naming the file. Returns a dict with ``h`` (heights, m), ``sizes`` (m),
    ``periodic``, ``detrend``, ``window``, ``analysis`` and what to record about the file
    (``unit``, ``size_source``, ``path``, ``format``, ``index``, ``filled``: :func:`filled_note`).
    """
    key = f"{name}.files"
    path = str(topo.path)
    h = topo.heights
    sizes, size_note = _sizes(name, spec, topo, path)
    bad = np.isnan(h)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        option = f"{name}.fill_undefined" if topo.unit_source != "container" else f"{name}.fill_undefined (or the " \
                 "container's fill_undefined_data_mode)"
        raise UserError(
            f"{int(bad.sum())} of {h.size} heights are missing (NaN or masked), first at index {first}; the FFT needs "
            f"a complete grid: set {option} = 'harmonic' to interpolate them (SurfaceTopography's harmonic fill; where "
            "and how many are recorded in the result), or crop the map in the instrument software", file=path,
            key=f"{name}.fill_undefined")
    if not np.all(np.isfinite(h)):
        raise UserError("infinite height values", file=path, key=key)
    if h.ndim not in (1, 2) or min(h.shape) < (8 if h.ndim == 1 else 4) or h.shape[0] < 8:
        raise UserError(f"too few points for a spectrum (shape {h.shape}; needs at least 8 along x)", file=path,
                        key=key)
    periodic = spec.get("periodic") if spec.get("periodic") is not None else topo.periodic
    detrend_how = spec.get("detrend") or ("mean" if periodic else "plane")
    window = spec.get("window") or ("none" if periodic else "hann")
    analysis = "profiles" if h.ndim == 1 else spec["analysis"]
    return dict(h=h, sizes=tuple(float(s) for s in sizes), periodic=bool(periodic), detrend=detrend_how,
                window=window, analysis=analysis, unit=f"{topo.unit} ({topo.unit_source})", size_source=size_note,
                path=path, format=topo.format, index=index, name=name, filled=filled_note(topo))


def _cutoffs(p, spec):
    """The instrument's reliability cutoffs (1/m) with what sets each."""
    cut = []
    if spec.get("tip_radius") is not None:
        lam = tip_radius_cutoff(p["h"], p["sizes"][0], spec["tip_radius"])  # 2nd differences ignore mean and plane
        if lam is not None:
            cut.append((2 * np.pi / lam, f"tip radius {spec['tip_radius']:.3g} m (cutoff wavelength {lam:.3g} m)"))
    if spec.get("resolution") is not None:
        cut.append((2 * np.pi / spec["resolution"], f"resolution {spec['resolution']:.3g} m"))
    if spec.get("q_reliable") is not None:
        cut.append((spec["q_reliable"], "given q_reliable"))
    return cut


def process_map(p: dict, spec: dict) -> dict:
    """Detrend and window the heights of :func:`prepare_map`'s ``p``; add the reliable q range.

    Adds ``h`` (processed heights, m), ``rms`` (after detrending, m), ``q_min`` = 2 pi / L and
    ``q_max`` (1/m, the Nyquist wavenumber or a lower instrument cutoff) and ``cutoff`` (what
    set q_max). No reliable band is a :class:`UserError`.
    """
    h, sizes = p["h"], p["sizes"]
    profiles = p["analysis"] == "profiles"
    h = detrend(h, DETREND_DEGREE[p["detrend"]], profiles=profiles)
    rms = float(np.sqrt(np.mean(h * h)))
    if not rms > 1e-12 * float(np.max(np.abs(p["h"]))):  # nothing left but rounding (or all equal)
        raise UserError(f"a flat {'profile' if profiles else 'map'}: no roughness is left after removing the "
                        f"{p['detrend']} (rms {rms:.3g} m), so there is no spectrum to measure",
                        file=p["path"], key=f"{p['name']}.files")
    if p["window"] == "hann":
        if profiles:
            h *= hann_window_1d(h.shape[0]).reshape((-1,) + (1,) * (h.ndim - 1))
        else:
            h *= hann_window_radial(*h.shape, *sizes)
    dx = [s / n for s, n in zip(sizes, h.shape, strict=False)]
    q_max = np.pi / (dx[0] if profiles else min(dx))
    why = "Nyquist pi/dx"
    for qc, text in _cutoffs(p, spec):
        if qc < q_max:
            q_max, why = qc, text
    q_min = 2 * np.pi / max(sizes[:1] if profiles else sizes)
    if q_max <= q_min:
        raise UserError(f"no reliable data: the reliability cutoff {q_max:.4g} 1/m ({why}) is below the lowest "
                        f"wavenumber {q_min:.4g} 1/m of the scan", file=p["path"], key=None)
    p.update(h=h, q_max=q_max, q_min=q_min, cutoff=why, rms=rms)
    return p


def measured_bin_index(ds: xr.Dataset, name: str) -> np.ndarray:
    """Indices (along q_bin) of the valid bins of surface ``name`` (finite q, PSD > 0), by increasing q."""
    psd, q = ds[f"psd_{name}_measured"].values, ds[f"q_{name}_measured"].values
    ok = np.flatnonzero(np.isfinite(psd) & (psd > 0) & np.isfinite(q))
    return ok[np.argsort(q[ok])]


def measured_bins(ds: xr.Dataset, name: str):
    """The topography stage's valid bins of surface ``name``: mean wavenumbers q (1/m,
    increasing), the PSD at q (m^4: the bin mean corrected for the curvature of the spectrum
    across the bin, :func:`roughcontact.physics.uncertainty.bin_curvature_factor`) and its
    standard error (m^4, same correction)."""
    index = measured_bin_index(ds, name)
    psd, q = ds[f"psd_{name}_measured"].values[index], ds[f"q_{name}_measured"].values[index]
    err = ds[f"psd_{name}_measured_error"].values[index] if f"psd_{name}_measured_error" in ds else np.zeros(q.size)
    factor = bin_curvature_factor(q, psd, int(ds.attrs.get("bins_per_decade", 20))) if q.size >= 2 else np.ones_like(q)
    return q, psd * factor, err * factor


def measured_psd_on_grid(ds: xr.Dataset, name: str, q_grid: np.ndarray, how: str):
    """The topography stage's measured PSD of surface ``name`` on the psd stage's ``q_grid``
    (m^4; :func:`measured_bins` put on the grid by
    :func:`roughcontact.physics.estimators.binned_psd_on_grid`) and the attributes saying how.
    ``how`` = ``name.extend``: beyond the measured range 'none' is an error."""
    q, C, err = measured_bins(ds, name)
    if q.size < 2:
        raise UserError("the measured PSD has fewer than two valid bins", key=f"{name}.files")
    lo, hi = q_grid[0], q_grid[-1]
    if how == "none" and (lo < q[0] * (1 - 1e-9) or hi > q[-1] * (1 + 1e-9)):
        raise UserError(
            f"the q grid [{lo:.4g}, {hi:.4g}] 1/m reaches outside the measured range [{q[0]:.4g}, {q[-1]:.4g}] 1/m; "
            f"set grid.q_min/q_max inside it or {name}.extend = 'power_law' or 'zero'", key=f"{name}.extend")
    attrs = {"surface": "measured topography", "source_files": ds[f"psd_{name}_measured"].attrs.get("files", ""),
             "interpolation": "log-log linear between the bins' PSD at their mean |q| (bin averages corrected for the "
                              "spectrum's curvature across a bin; the interpolation's bias between bins of few modes "
                              "removed)", "extension": how,
             "measured_q_range": f"{q[0]:.6g} {q[-1]:.6g} 1/m"}
    with np.errstate(divide="ignore"):
        modes = np.where(err > 0, (C / np.where(err > 0, err, 1.0)) ** 2, 1e12)
    return binned_psd_on_grid(q_grid, q, C, how) * interpolation_unbiasing(q_grid, q, modes, how), attrs


def measured_coherence_on_grid(ds: xr.Dataset, q_grid: np.ndarray) -> np.ndarray:
    """The topography stage's measured coherence on ``q_grid`` (linear in log q, held constant
    at its end values beyond the measured range)."""
    q, eta = valid_bins(ds["q_substrate_measured"].values, ds["coherence"].values)
    return coherence_on_grid(q_grid, q, eta)


# ----------------------------------------------------------------------------------------
# Measured maps as the BEM's surfaces (stage bem)
# ----------------------------------------------------------------------------------------

_SYNTHESIZE_INSTEAD = ("; or set bem.surfaces = 'synthesized' to compare on random periodic surfaces with the "
                       "measured spectra")


def map_surfaces(inp) -> tuple[str, ...]:
    """The rough surfaces whose measured maps the BEM solves on; () means synthesize.

    ``bem.surfaces``: "synthesized" always synthesizes; "auto" (default) uses the maps when
    every rough surface is of kind "topography"; "measured" requires that.
    """
    how = inp["bem.surfaces"]
    rough = tuple(name for name in SURFACES if is_rough(inp[name]))
    if how == "synthesized":
        return ()
    if rough and all(is_topography(inp[name]) for name in rough):
        return rough
    if how == "measured":
        raise UserError("bem.surfaces = 'measured' needs every rough surface to be of kind 'topography' (an area "
                        "map); use 'auto' or 'synthesized' for self_affine or psd_file surfaces", key="bem.surfaces")
    return ()


def check_eta(inp, names: tuple[str, ...]) -> None:
    """Two measured maps carry their own coherence: eta must be 'measured'; synthesized pairs
    need numeric eta values."""
    measured = isinstance(inp["interface.eta"], str)
    if len(names) == 2 and not measured:
        raise UserError("the BEM solves on the two measured maps, which have their own coherence: set "
                        "interface.eta = 'measured' so that the theory uses it too" + _SYNTHESIZE_INSTEAD
                        + " and the given eta", key="interface.eta")
    if not names and measured and is_rough(inp["substrate"]) and is_rough(inp["solid"]):
        raise UserError("synthesized BEM surfaces are mixed with one coherence: give numeric interface.eta values, "
                        "or solve on the measured maps (bem.surfaces = 'auto')", key="interface.eta")


def _bem_map(name: str, spec: dict, files) -> dict:
    """One surface's single map, prepared (:func:`prepare_map`, :func:`process_map` without a
    window) and checked: an area map, periodic, unwindowed, square."""
    key = f"{name}.files"
    files = [] if files is None else list(files) if isinstance(files, (list, tuple)) else [files]
    if len(files) != 1:
        raise UserError(f"the BEM solves on one map per surface; the {name} has {len(files)} files"
                        + _SYNTHESIZE_INSTEAD, key=key)
    p = prepare_map(name, spec, files[0], 0)
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
    return process_map(dict(p, window="none"), spec)


def measured_maps(inp, names: tuple[str, ...]) -> dict:
    """The measured maps the BEM solves on, prepared as the topography stage prepares them.

    Per surface: exactly one file, an area map (``analysis = "area"``), periodic
    (``periodic = true`` or the file says so), no window, square; both surfaces on the same
    grid. Units, sizes, missing points and detrending are the topography stage's (with the
    window off: a window would change the heights the solver sees). Bad input is a
    :class:`UserError` naming the key.

    Returns
    -------
    dict with ``h`` (name -> detrended heights, m), ``n`` (pixels per side), ``side`` (m),
    ``pixel_size`` (m), ``q_reliable`` (1/m, the lowest of the maps' cutoffs), ``cutoff``
    (what set it), ``files`` (name -> path) and ``detrend`` (name -> polynomial removed).
    """
    prepared = {name: _bem_map(name, inp[name], inp.files.get(f"{name}.files")) for name in names}
    if len(prepared) == 2:
        a, b = prepared["substrate"], prepared["solid"]
        if a["h"].shape != b["h"].shape:
            raise UserError(f"the two maps are not on one grid: the substrate has {a['h'].shape[0]} x "
                            f"{a['h'].shape[1]} points, the solid {b['h'].shape[0]} x {b['h'].shape[1]}"
                            + _SYNTHESIZE_INSTEAD, key="solid.files")
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


def map_band(q_grid_lo, q_grid_hi, n, side, q_reliable, pixels_per_wavelength):
    """The band of a measured n x n periodic map of side ``side`` (m), matched to the psd grid.

    The map's lattice starts at qL = 2 pi / side, which must be the psd grid's lowest
    wavenumber ``q_grid_lo`` (1/m; the topography stage's lowest bin holds only the modes
    |q| = qL, so it is, unless ``grid.q_min`` moves it); the theory integrates from there.
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
