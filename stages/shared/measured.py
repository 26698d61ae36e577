"""Measured surfaces in the stage layer beyond single files, and their statistical errors.

* ``kind = "container"``: the measurements of a contact.engineering container (read by the
  engine's ``container`` reader) prepared like the files of ``kind = "topography"``, each with
  its own units, detrending and reliability cutoff from the container's metadata.
* The errors of the topography stage's binned PSDs: independent modes of windowed scans
  (:func:`mode_factor`) and the spread between several measurements (:func:`merged_psd`).
* For the psd stage: the errors on its q grid and the spectra (and coherences) drawn within
  them, the sweep dimension ``draw`` of the uncertainty bands.

Not a stage (it registers nothing). Kernels: :mod:`roughcontact.physics.uncertainty`. See
docs/measured-data.md.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from roughcontact.physics.estimators import merge_spectra, processed_bin_covariance_area, processing_bias_area
from roughcontact.physics.modes import window_mode_factor_area, window_mode_factor_profiles, window_pair_sums_area
from roughcontact.physics.preprocessing import detrend_basis, hann_window_1d, hann_window_radial
from roughcontact.physics.uncertainty import (
    coherence_draws_on_grid,
    coherence_error_on_grid,
    correlation_root,
    psd_draws_on_grid,
    psd_error_on_grid,
    spread_inflation,
)
from roughcontact.stage import FileInput, UserError

from .maps import measured_bin_index, measured_bins, prepare_map, process_map
from .surfaces import DETREND_DEGREE

#: contact.engineering's detrend modes (SurfaceTopography) and the polynomial each removes
DETREND_FROM_MODE = {"center": "mean", "height": "plane", "slope": "plane", "curvature": "curvature"}
#: random streams of the draws, one per measured quantity
STREAMS = {"substrate": 1, "solid": 2, "coherence": 3}


def container_files(name: str) -> FileInput:
    """The container of surface ``name`` (kind container), read by the engine's container reader."""

    def options(params):
        return dict(key=name, surface=params[name].get("surface"), fill=params[name].get("fill_undefined"))

    return FileInput(f"{name}.container", reader="container", options=options)


def _member(name: str, spec: dict, topo, index: int, container) -> dict:
    """One measurement of a container, prepared and processed with the settings its metadata gives."""
    meta = topo.metadata
    cut = meta.get("reliability_cutoff_m")
    own = dict(spec, detrend=spec.get("detrend") or DETREND_FROM_MODE.get(meta.get("detrend_mode")),
               q_reliable=2.0 * np.pi / cut if cut else None, tip_radius=None, resolution=None,
               size_x=None, size_y=None, periodic=None)
    try:
        p = process_map(prepare_map(name, own, topo, index), own)
    except UserError as exc:
        own_key = exc.key if exc.key == f"{name}.fill_undefined" else f"{name}.container"
        raise UserError(exc.message, file=exc.file, key=own_key) from None
    if p["cutoff"] == "given q_reliable":
        p["cutoff"] = f"container metadata: {meta['reliability_cutoff_source']}"
    p["member"] = {"container": str(container.path), "surface": container.surface, **meta}
    p["left_out"] = list(getattr(container, "left_out", []))  # the container's measurements not read
    return p


def measurements_entered(prepared: list[dict]) -> dict:
    """Which measurements (or files) of one surface entered its PSD and which were left out
    (a container's non-uniformly sampled line scans), as result attributes."""
    entered = [p["member"]["measurement"] if "member" in p else p["path"] for p in prepared]
    left = prepared[0].get("left_out", []) if prepared else []
    attrs = {"measurements_entered": json.dumps(entered)}
    if left:
        attrs["measurements_left_out"] = json.dumps(left)
    return attrs


def prepared_files(name: str, spec: dict, files) -> list[dict]:
    """The prepared, processed scans of measured surface ``name`` (:func:`roughcontact.stages.maps.process_map`):
    its files (kind topography) or the measurements of its container (kind container; those the
    reader left out, non-uniformly sampled line scans, are listed in each one's ``left_out``)."""
    if spec["kind"] == "container":
        container = files[f"{name}.container"]
        return [_member(name, spec, t, i, container) for i, t in enumerate(container.measurements)]
    return [process_map(prepare_map(name, spec, t, i), spec) for i, t in enumerate(files[f"{name}.files"])]


def mode_factor(p: dict, edges: np.ndarray):
    """Per bin, by how much the window of scan ``p`` divides its independent modes (1: no window):
    the correlations of a bin's modes among themselves. Those with the modes of other bins are
    carried by :func:`bin_covariance` (issue 24)."""
    if p["window"] != "hann":
        return 1.0
    h, sizes = p["h"], p["sizes"]
    if p["analysis"] == "profiles":
        return window_mode_factor_profiles(h.shape[0], sizes[0], edges, p["q_max"], hann_window_1d(h.shape[0]))
    return window_mode_factor_area(*h.shape, *sizes, edges, p["q_max"], hann_window_radial(*h.shape, *sizes))


def bin_covariance(p: dict, edges: np.ndarray, n: np.ndarray, model=None) -> np.ndarray:
    """Relative covariance cov(C_b, C_b') / (C_b C_b') of the binned PSD of scan ``p`` (``n``: its
    effective modes per bin, :func:`mode_factor` counted): 1/n on the diagonal; between the bins
    of a Hann-windowed map, 2 S_bb' / (m_b m_b') from the window's correlation of their modes
    (:func:`roughcontact.physics.modes.window_pair_sums_area`; 0 for bins beyond its exactly
    summed region, and for line scans and unwindowed maps, whose bins are independent)."""
    with np.errstate(divide="ignore"):
        K = np.diag(np.where(n > 0, 1.0 / np.where(n > 0, n, 1.0), 0.0))
    if p["window"] != "hann" or p["analysis"] != "area":
        return K
    h, sizes = p["h"], p["sizes"]
    S, m, exact, _ = window_pair_sums_area(*h.shape, *sizes, edges, p["q_max"], hann_window_radial(*h.shape, *sizes))
    ok = exact & (m > 0) & (n > 0)
    pair = ok[:, None] & ok[None, :] & ~np.eye(ok.size, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        K[pair] = (2.0 * S / np.outer(m, m))[pair]
    if model is not None and model[0] is not None:  # the lowest bins exactly, for the model spectrum
        args = {k: v for k, v in model[1].items() if k not in ("edges", "q_max")}
        exact, inside = processed_bin_covariance_area(model[0], edges=edges, q_max=p["q_max"], **args)
        K[np.ix_(inside, inside)] = exact[np.ix_(inside, inside)]
    return K


def merged_correlation(spectra: list[dict]) -> np.ndarray:
    """Correlation matrix of the merged PSD's bins (:func:`merged_psd`; each scan's ``K`` from
    :func:`bin_covariance`): the merge averages the scans with weights w = n / sum n, so the merged
    relative covariance is sum over scans of w_b w_b' K_bb'. Scans are independent; NaN where a
    bin has no modes."""
    n = np.stack([s["n"] for s in spectra])
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(n > 0, n / n.sum(axis=0), 0.0)
        K = sum(np.outer(wf, wf) * s["K"] for wf, s in zip(w, spectra, strict=True))
        d = np.sqrt(np.diag(K))
        return K / np.outer(d, d)


def unbias_processing(p: dict, edges: np.ndarray, s: dict) -> dict:
    """The binned spectra ``s`` of area map ``p`` with the bias of its detrending and window
    removed (:func:`roughcontact.physics.estimators.processing_bias_area`, each spectrum
    modelled by itself; the cross-spectrum divided by the geometric mean of both factors);
    unchanged for periodic maps without a window and for line scans. Adds ``processing_bias``
    (the factor of C11, 1 where unchanged)."""
    nb = edges.size - 1
    if p["analysis"] != "area" or (p["periodic"] and p["window"] == "none"):
        return dict(s, processing_bias=np.ones(nb))
    h, (sx, sy) = p["h"], p["sizes"]
    args = dict(nx=h.shape[0], ny=h.shape[1], sx=sx, sy=sy, edges=edges, q_max=p["q_max"],
                window=hann_window_radial(*h.shape, sx, sy) if p["window"] == "hann" else None,
                basis=detrend_basis(h.shape, DETREND_DEGREE[p["detrend"]]), periodic=p["periodic"])
    out = dict(s)
    r1, model = processing_bias_area(s["q"], s["C11"], s["n"], **args, model=True)
    out["C11"] = s["C11"] / r1
    out["model"] = (model, args)  # for bin_covariance: the spectrum's model and the map's processing
    if "C22" in s:
        r2 = processing_bias_area(s["q"], s["C22"], s["n"], **args)
        out["C22"], out["C12"] = s["C22"] / r2, s["C12"] / np.sqrt(r1 * r2)
    out["processing_bias"] = r1
    return out


def merged_psd(spectra: list[dict], key: str = "C11"):
    """The merged PSD of several scans of one surface with its standard error: C / sqrt(n)
    (n: effective independent modes), inflated where the scans disagree beyond it.

    Returns
    -------
    q, C, n, err, ratio : arrays over the bins
        As :func:`roughcontact.physics.estimators.merge_spectra`, and the Birge ratio of the
        spread between the scans (NaN where fewer than two have modes).
    """
    q, C, n, err = merge_spectra(spectra, key)
    values = np.stack([s[key] for s in spectra])
    ratio, inflation = spread_inflation(values, np.stack([s["n"] for s in spectra]), C)
    return q, C, n, err * inflation, ratio


def _modes(C, err):
    """Effective independent modes behind a PSD estimate with standard error ``err``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(err > 0, (C / np.where(err > 0, err, 1.0)) ** 2, 1e12)


def psd_error_grid(ds: xr.Dataset, name: str, q_grid: np.ndarray, how: str) -> np.ndarray:
    """Standard error (m^4) of the measured PSD of ``name`` on the psd stage's grid."""
    q, C, err = measured_bins(ds, name)
    return psd_error_on_grid(q_grid, q, C, err, "zero" if how == "none" else how)


def drawn_psd(draw: xr.DataArray, ds: xr.Dataset, name: str, q_grid: np.ndarray, how: str, seed: int) -> xr.DataArray:
    """The measured PSD of ``name`` drawn within its band, on the grid: dims (draw, q)."""
    q, C, err = measured_bins(ds, name)
    corr = ds.get(f"psd_{name}_measured_correlation")
    root = None
    if corr is not None:  # the window's correlation between the bins (bin_covariance), on the same bins
        index = measured_bin_index(ds, name)
        root = correlation_root(np.nan_to_num(corr.values[np.ix_(index, index)]))  # once, not per block of draws
    kwargs = dict(q_grid=q_grid, q=q, C=C, modes=_modes(C, err), how="zero" if how == "none" else how,
                  seed=seed, stream=STREAMS[name], root=root)
    return xr.apply_ufunc(psd_draws_on_grid, draw, kwargs=kwargs, output_core_dims=[["q"]], dask="parallelized",
                          output_dtypes=[float], dask_gufunc_kwargs={"output_sizes": {"q": q_grid.size}})


def _coherence_bins(ds: xr.Dataset):
    q, eta, err = (ds[k].values for k in ("q_substrate_measured", "coherence", "coherence_error"))
    ok = np.isfinite(q) & np.isfinite(eta) & np.isfinite(err)
    order = np.argsort(q[ok])
    return q[ok][order], eta[ok][order], err[ok][order]


def coherence_error_grid(ds: xr.Dataset, q_grid: np.ndarray) -> np.ndarray:
    """Standard error of the measured coherence on the psd stage's grid (dimensionless)."""
    q, _, err = _coherence_bins(ds)
    return coherence_error_on_grid(q_grid, q, err)


def drawn_coherence(draw: xr.DataArray, ds: xr.Dataset, q_grid: np.ndarray, seed: int) -> xr.DataArray:
    """The measured coherence drawn within its band, on the grid: dims (draw, q)."""
    q, eta, err = _coherence_bins(ds)
    kwargs = dict(q_grid=q_grid, q=q, eta=eta, err=err, seed=seed, stream=STREAMS["coherence"])
    return xr.apply_ufunc(coherence_draws_on_grid, draw, kwargs=kwargs, output_core_dims=[["q"]], dask="parallelized",
                          output_dtypes=[float], dask_gufunc_kwargs={"output_sizes": {"q": q_grid.size}})
