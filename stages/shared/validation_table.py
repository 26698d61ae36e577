"""The reductions of the ``validation`` stage (declared in :mod:`roughcontact.stages.validation`):
the BEM reference with its measured error bar, every theory variant on the same spectra, their
ratios and the deviation table. Not a stage module of its own: helpers of the stage layer.

BEM reference: the area extrapolated to zero pixel size (first-order Richardson from the two
finest solved rungs, per realization; mean over realizations); its error bar combines the
realization standard error with half the extrapolation step (the measured convergence order,
attribute ``validation_area_order``, lies near 1 but varies by about +-0.5, which moves the
extrapolated value by about half the step). The mean gap converges fast: the finest rung,
with the realization standard error and the change over the last refinement.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.corrections import VARIANTS
from roughcontact.physics.spectra import psd_combined
from roughcontact.physics.validation import (
    case_pressures,
    case_spectra,
    deviation,
    extrapolated_area,
    lattice_moments,
    observed_order,
)
from roughcontact.stage import StageInput, Var

from .material import e_star
from .variants import THEORY, theory_variants, variant_attrs

#: the ranges of the deviation table: (name, what, lower and upper BEM A/A0)
RANGES = (("area_0.005_0.3", "area", 0.005, 0.3), ("area_0.3_0.9", "area", 0.3, 0.9),
          ("area_0.005_0.9", "area", 0.005, 0.9), ("separation_area_above_0.01", "gap", 0.01, 1.0),
          ("separation_area_0.01_0.9", "gap", 0.01, 0.9))
CASE = ("hurst", "bandwidth", "eta")

TABLE_COORDS = {
    "theory": THEORY,
    "range": Var("1", "range of the deviation table",
                 comment="the quantity and the BEM A/A0 interval it covers"),
    "lattice_kind": Var("1", "PSD sampling on the BEM lattice",
                        comment="point (sampled at |k|) or cell (averaged over the mode's cell)"),
}
_MEAN = "mean over realizations"
_IN_RANGE = "over every case and load in the range"
OUTPUTS = {
    "validation_bem_area": Var("1", "BEM reference A/A0",
                               comment=f"BEM reference, extrapolated to zero pixel size; {_MEAN}"),
    "validation_bem_area_error": Var("1", "error bar of the BEM A/A0",
                                     comment="realization standard error and half the extrapolation step, "
                                             "in quadrature"),
    "validation_bem_area_finest": Var("1", "BEM A/A0 on the finest rung",
                                      comment=f"on the finest solved rung; {_MEAN}"),
    "validation_bem_gap": Var("m", "BEM mean separation on the finest rung",
                              comment=f"on the finest solved rung; {_MEAN}"),
    "validation_bem_gap_error": Var("m", "error bar of the BEM mean separation",
                                    comment="realization standard error and the change over the last "
                                            "refinement, in quadrature"),
    "validation_theory_area": Var("1", "A/A0 of each theory variant", comment="on the case's spectrum"),
    "validation_theory_gap": Var("m", "mean separation of each theory variant",
                                 comment="on the case's spectrum"),
    "validation_area_ratio": Var("1", "theory / BEM ratio of A/A0 per variant"),
    "validation_gap_ratio": Var("1", "theory / BEM ratio of the separation",
                                comment="of the mean separation, per variant"),
    "validation_kappa_bem": Var("1", "kappa = (A/A0) E* g / p of the BEM"),
    "validation_kappa_theory": Var("1", "kappa = (A/A0) E* g / p of each theory variant"),
    "validation_rms_slope": Var("1", "rms slope g of the case's spectrum",
                                comment="of the case's combined spectrum on its band"),
    "validation_deviation_max": Var("1", "largest |theory / BEM - 1| in the range", comment=_IN_RANGE),
    "validation_deviation_mean": Var("1", "mean of theory / BEM - 1 in the range", comment=_IN_RANGE),
    "validation_deviation_case_max": Var("1", "largest |theory / BEM - 1| per case",
                                         comment="over the loads in the range"),
    "validation_bem_error_max": Var("1", "largest relative BEM error bar in the range",
                                    comment="relative error bar of the BEM reference"),
    "validation_lattice_variance_ratio": Var("1", "lattice / continuum hrms^2 of the band",
                                             comment="hrms^2 the BEM lattice holds / the continuum "
                                                     "integral of the band"),
    "validation_lattice_slope_ratio": Var("1", "lattice / continuum g^2 of the band",
                                          comment="g^2 the BEM lattice holds / the continuum integral of "
                                                  "the band"),
}


def _reference(bem: xr.Dataset) -> dict:
    """Extrapolated BEM area and finest gap, each with its error bar, over (case..., p)."""
    area = bem["validation_bem_contact_area_ratio"]
    n_w = bem["pixels_per_wavelength"].values
    R = bem.sizes["realization"]
    ext, fine, coarse = xr.apply_ufunc(extrapolated_area, area, n_w, input_core_dims=[["pixels_per_wavelength"], []],
                                       output_core_dims=[[], [], []])
    gap_ext, gap_fine, gap_coarse = xr.apply_ufunc(
        extrapolated_area, bem["validation_bem_mean_gap"], n_w, input_core_dims=[["pixels_per_wavelength"], []],
        output_core_dims=[[], [], []])
    se = (ext.std("realization", ddof=1) / np.sqrt(R)) if R > 1 else xr.zeros_like(ext.mean("realization"))
    gap_se = (gap_fine.std("realization", ddof=1) / np.sqrt(R)) if R > 1 else xr.zeros_like(se)
    step = np.abs((ext - fine).mean("realization"))
    out = {"validation_bem_area": ext.mean("realization"), "validation_bem_area_finest": fine.mean("realization"),
           "validation_bem_area_error": np.sqrt(se**2 + (0.5 * step) ** 2),
           "validation_bem_gap": gap_fine.mean("realization"),
           "validation_bem_gap_error": np.sqrt(gap_se**2 + (gap_fine - gap_coarse).mean("realization") ** 2)}
    means = area.mean("realization")
    if means.sizes["pixels_per_wavelength"] >= 3:
        k = xr.apply_ufunc(observed_order, *(means.isel(pixels_per_wavelength=i) for i in (-3, -2, -1)))
        k = k.where((means.isel(pixels_per_wavelength=-1) > 0.005) & (means.isel(pixels_per_wavelength=-1) < 0.9))
        out["order"] = k.values[np.isfinite(k.values)]
    return out


def _theory(inp: StageInput, bem: xr.Dataset, kwargs: dict) -> dict:
    """Every variant on each case's spectrum at the case's pressures, and the lattice moments."""
    p_red = bem["reduced_pressure"].values
    sizes = [bem.sizes.get(d, 1) for d in CASE]
    coord = {d: np.atleast_1d(bem[d].values) if d in bem.coords else np.array([0.0]) for d in CASE}
    area = np.empty(sizes + [len(VARIANTS), p_red.size])
    gap, slope = np.empty_like(area), np.empty(sizes)
    lattice = np.empty(sizes + [2, 2])
    for idx in np.ndindex(*sizes):
        H, zeta, eta = (float(coord[d][i]) for d, i in zip(CASE, idx, strict=True))
        q, C1, C2 = case_spectra(H, zeta, kwargs["qL"], kwargs["rolloffs"], kwargs["hrms"], kwargs["points_per_decade"])
        C = psd_combined(C1, C2, eta)
        p, slope[idx] = case_pressures(p_red, H, zeta, eta, **kwargs)
        a, u = theory_variants(inp, q, C[None, :], zeta * q[0], p, kwargs["E_star"])
        area[idx], gap[idx] = a[:, 0, :].T, u[:, 0, :].T
        lattice[idx] = [lattice_moments(q, C, zeta, kind) for kind in ("point", "cell")]
    dims = CASE + ("theory", "reduced_pressure")
    return {"validation_theory_area": (dims, area), "validation_theory_gap": (dims, gap),
            "validation_rms_slope": (CASE, slope),
            "validation_lattice_variance_ratio": (CASE + ("lattice_kind",), lattice[..., 0]),
            "validation_lattice_slope_ratio": (CASE + ("lattice_kind",), lattice[..., 1])}


def _table(ds: xr.Dataset) -> xr.Dataset:
    """The deviation table: per range and variant, over every case and load, and per case."""
    ref = ds["validation_bem_area"]
    nv, nr = ds.sizes["theory"], len(RANGES)
    dmax, dmean, berr = np.full((nv, nr), np.nan), np.full((nv, nr), np.nan), np.full(nr, np.nan)
    case_shape = [ds.sizes[d] for d in CASE]
    dcase = np.full(case_shape + [nv, nr], np.nan)
    for j, (_, what, lo, hi) in enumerate(RANGES):
        mask = ((ref >= lo) & (ref <= hi)).values
        theory = ds["validation_theory_area" if what == "area" else "validation_theory_gap"]
        bem = ds["validation_bem_area" if what == "area" else "validation_bem_gap"]
        err = ds["validation_bem_area_error" if what == "area" else "validation_bem_gap_error"]
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(mask, (err / bem).values, np.nan)
        berr[j] = np.nanmax(rel) if np.any(np.isfinite(rel)) else np.nan
        for k in range(nv):
            t = theory.isel(theory=k).transpose(*CASE, "reduced_pressure").values
            b = bem.transpose(*CASE, "reduced_pressure").values
            m = np.broadcast_to(mask, b.shape)
            dmax[k, j], dmean[k, j] = deviation(t, b, m)
            for idx in np.ndindex(*case_shape):
                dcase[idx + (k, j)] = deviation(t[idx], b[idx], m[idx])[0]
    names = [r[0] for r in RANGES]
    return ds.assign(validation_deviation_max=(("theory", "range"), dmax),
                     validation_deviation_mean=(("theory", "range"), dmean),
                     validation_bem_error_max=(("range",), berr),
                     validation_deviation_case_max=(CASE + ("theory", "range"), dcase)).assign_coords(range=names)


def case_kwargs(inp: StageInput) -> dict:
    """The fixed parameters of every validation case (SI)."""
    return dict(qL=float(inp["validation.qL"]),
                rolloffs=(float(inp["validation.rolloff_substrate"]), float(inp["validation.rolloff_solid"])),
                hrms=(float(inp["validation.hrms_substrate"]), float(inp["validation.hrms_solid"])),
                E_star=e_star(inp), points_per_decade=int(inp["numerics.points_per_decade"]))


def compute_table(inp: StageInput) -> xr.Dataset:
    bem = inp.upstream["validation_bem"]
    for d in CASE:
        if d not in bem.dims:
            bem = bem.expand_dims({d: np.atleast_1d(bem[d].values) if d in bem.coords else [0.0]})
    kwargs = case_kwargs(inp)
    ref = _reference(bem)
    order = ref.pop("order", np.array([]))
    ds = xr.Dataset({k: v.transpose(*CASE, "reduced_pressure") for k, v in ref.items()})
    ds = ds.assign_coords(theory=list(VARIANTS), lattice_kind=["point", "cell"])
    ds = ds.assign(**_theory(inp, bem, kwargs))
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["validation_area_ratio"] = ds["validation_theory_area"] / ds["validation_bem_area"]
        ds["validation_gap_ratio"] = ds["validation_theory_gap"] / ds["validation_bem_gap"]
        ds["validation_kappa_bem"] = ds["validation_bem_area"] / ds["reduced_pressure"]
        ds["validation_kappa_theory"] = ds["validation_theory_area"] / ds["reduced_pressure"]
    ds = _table(ds)
    ds.attrs.update(variant_attrs(inp))
    ds.attrs["validation_area_order"] = (
        f"convergence order of the BEM area in the pixel size from the three finest rungs (0.005 < A/A0 < 0.9): "
        f"median {np.median(order):.3g}, quartiles {np.percentile(order, 25):.3g}-{np.percentile(order, 75):.3g} "
        f"over {order.size} points" if order.size else "fewer than three rungs: not measured")
    ds.attrs["validation_lattice"] = bem.attrs.get("validation_lattice", "?")
    return ds
