"""Stages ``validation_bem`` and ``validation``: every theory variant against the project's own
exact solver over Hurst exponents, bandwidths, coherences and loads, with the BEM's error bar
measured (realizations, and the contact area's convergence in the pixel size).

``validation_bem`` is a set of independent BEM tasks, one dask block per (H, bandwidth, eta,
realization, pixels per wavelength): the engine computes them on the scene's scheduler (threads,
processes or a dask.distributed cluster, ``--scheduler tcp://...``) and writes each block as it
arrives. ``validation`` reduces them (Richardson extrapolation of the area, realization
spread), evaluates every theory variant on the same spectra and writes the deviation table.
Kernels: :mod:`roughcontact.physics.validation`, :mod:`roughcontact.physics.corrections`.
Figures: :mod:`roughcontact.stages.figures.validation`. See docs/validation.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.validation import FIELDS, bem_block
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Shape,
    Stage,
    StageInput,
    UserError,
    Var,
    register,
    register_section,
)

from .figures.validation import figure_kappa, figure_separation_ratio
from .shared.bem_solve import solver
from .shared.material import COATING_KEYS, MATERIAL_KEYS, refuse_coating
from .shared.validation_table import OUTPUTS as TABLE_OUTPUTS, TABLE_COORDS, case_kwargs, compute_table
from .shared.variants import VARIANT_KEYS

register_section(
    Section(
        "validation",
        (
            Param("hurst", "sweep", "", lo=0.0, hi=1.0, lo_open=True, dim="hurst",
                  doc="Hurst exponents H of both surfaces (a list is a sweep)"),
            Param("bandwidth", "sweep", "", lo=2.0, dim="bandwidth",
                  doc="bandwidths zeta = q_max / qL of the cases (whole numbers; the BEM grid has "
                      "pixels_per_wavelength x bandwidth pixels per side)"),
            Param("reduced_pressure", "sweep", "", lo=0.0, lo_open=True, dim="reduced_pressure",
                  doc="loads p / (E* g), g the rms slope of the case's combined spectrum"),
            Param("pixels_per_wavelength", "sweep", "", lo=2.0, dim="pixels_per_wavelength",
                  doc="the BEM's resolution ladder (pixels per shortest wavelength), coarse to fine, each twice the "
                      "last: the area is extrapolated to zero pixel size from the two finest solved"),
            Param("max_grid", "int", default=512, lo=8, hi=8192,
                  doc="largest BEM grid solved; rungs with pixels_per_wavelength x bandwidth above it are skipped"),
            Param("realizations", "int", default=2, lo=1, hi=1000, doc="random surface pairs per case"),
            Param("seed", "int", default=0, lo=0, doc="random seed (same seed, same surfaces)"),
            Param("qL", "quantity", "1/m", default=2e8, lo=0.0, lo_open=True, doc="lowest wavenumber 2 pi / L"),
            Param("rolloff_substrate", "quantity", "", default=4.0, lo=1.0, doc="substrate roll-off q0 / qL"),
            Param("rolloff_solid", "quantity", "", default=2.0, lo=1.0, doc="solid roll-off q0 / qL"),
            Param("hrms_substrate", "quantity", "m", default=1e-9, lo=0.0, lo_open=True,
                  doc="substrate rms height on the band"),
            Param("hrms_solid", "quantity", "m", default=0.5e-9, lo=0.0, lo_open=True,
                  doc="solid rms height on the band"),
            Param("lattice", "choice", default="cell", choices=("cell", "point"),
                  doc="PSD on the BEM lattice: averaged over each mode's cell (the band's variance exactly) or "
                      "sampled at |k| (a few per cent more long-wavelength roughness)"),
        ),
        doc="the validation of the theory variants against the BEM (needs the [bem] extra: tamaas)",
    )
)

BEM_KEYS = (*MATERIAL_KEYS, *COATING_KEYS, "interface.eta", "numerics.bem_tolerance", "numerics.points_per_decade",
            *(f"validation.{k}" for k in ("hurst", "bandwidth", "reduced_pressure", "pixels_per_wavelength", "max_grid",
                                          "realizations", "seed", "qL", "rolloff_substrate", "rolloff_solid",
                                          "hrms_substrate", "hrms_solid", "lattice")))


def check_validation_bem(inp: StageInput) -> None:
    """The optional dependency (tamaas), and a BEM grid for every bandwidth: a bandwidth whose
    coarsest rung exceeds max_grid would have no task solved (and the table nothing to compare); no coating."""
    refuse_coating(inp, "the validation stages (their BEM kernel is the homogeneous half-space's)")
    solver()
    coarsest = float(np.min(inp["validation.pixels_per_wavelength"]))
    for bandwidth in np.atleast_1d(inp["validation.bandwidth"]):
        if coarsest * bandwidth > inp["validation.max_grid"]:
            raise UserError(
                f"bandwidth {bandwidth:g} needs a BEM grid of at least {coarsest * bandwidth:.6g} pixels per side "
                f"(pixels_per_wavelength {coarsest:g} x bandwidth) but validation.max_grid is "
                f"{inp['validation.max_grid']}: no rung would be solved; use bandwidths up to "
                f"{inp['validation.max_grid'] / coarsest:g} (or a larger max_grid)", key="validation.bandwidth")


def compute_validation_bem(inp: StageInput) -> xr.Dataset:
    # one task per block, whatever the engine's memory-based chunks: every task is a whole BEM solve
    hurst, band, eta = (_one_per_block(inp.sweep(dim, inp[key])) for dim, key in
                        (("hurst", "validation.hurst"), ("bandwidth", "validation.bandwidth"),
                         ("eta", "interface.eta")))
    p_red = inp.sweep("reduced_pressure", np.sort(np.atleast_1d(inp["validation.reduced_pressure"])))
    R = int(inp["validation.realizations"])
    realization = xr.DataArray(np.arange(R), dims=("realization",), coords={"realization": np.arange(R)}).chunk(1)
    n_w = _rungs(inp)
    out = xr.apply_ufunc(
        bem_block, hurst, band, eta, realization, n_w, p_red,
        kwargs=dict(**case_kwargs(inp), seed=int(inp["validation.seed"]),
                    tolerance=float(inp["numerics.bem_tolerance"]), lattice=inp["validation.lattice"]),
        input_core_dims=[[], [], [], [], [], ["reduced_pressure"]], output_core_dims=[["reduced_pressure", "field"]],
        dask="parallelized", output_dtypes=[float], dask_gufunc_kwargs={"output_sizes": {"field": len(FIELDS)}},
    )
    names = {"area": "validation_bem_contact_area_ratio", "gap": "validation_bem_mean_gap",
             "seconds": "validation_bem_seconds_per_solve"}
    ds = xr.Dataset({names[f]: out.isel(field=k, drop=True) for k, f in enumerate(FIELDS)})
    grid = np.outer(np.atleast_1d(inp["validation.bandwidth"]), np.atleast_1d(inp["validation.pixels_per_wavelength"]))
    if "bandwidth" in ds.dims and "pixels_per_wavelength" in ds.dims:
        ds = ds.assign_coords(grid=(("bandwidth", "pixels_per_wavelength"), grid))
    ds.attrs.update({"validation_lattice": inp["validation.lattice"], "validation_seed": int(inp["validation.seed"]),
                     "validation_synthesis": "substrate and solid self-affine with H on qL..bandwidth qL, roll-offs "
                                             "and hrms as the attributes say; noise from (seed, realization, "
                                             "bandwidth): the same surfaces on every rung, for every H and eta"})
    return ds


def _rungs(inp: StageInput) -> xr.DataArray:
    """Pixels per wavelength per (bandwidth, rung), NaN where the grid would exceed max_grid
    (those tasks are not solved); built from the scene's values, one chunk per task."""
    arrays = {}
    for key, dim in (("pixels_per_wavelength", "pixels_per_wavelength"), ("bandwidth", "bandwidth")):
        v = np.asarray(inp[f"validation.{key}"], dtype=float)
        arrays[dim] = xr.DataArray(v, dims=(dim,), coords={dim: v}) if v.ndim else xr.DataArray(v)
    n_w = arrays["pixels_per_wavelength"].where(arrays["pixels_per_wavelength"] * arrays["bandwidth"]
                                                <= inp["validation.max_grid"])
    return n_w.chunk({d: 1 for d in n_w.dims}) if n_w.dims else n_w


def _one_per_block(da: xr.DataArray) -> xr.DataArray:
    return da.chunk({d: 1 for d in da.dims}) if da.dims else da


def describe_validation_bem(inp: StageInput) -> Shape:
    """Working memory per load of a task: the solver's fields, about 200 bytes (25 values) per
    pixel of the largest map solved (pixels_per_wavelength x bandwidth, at most max_grid; docs/bem.md:
    ~150 measured), shared by the task's loads, which one task solves together (never chunked).
    A map too large is blamed on validation.max_grid, which caps it (not on the loads). Each task
    (a block) is long work: the engine keeps it once finished, so that a killed run resumes
    (``keep_blocks``)."""
    loads = max(np.size(inp["validation.reduced_pressure"]), 1)
    grids = np.outer(np.atleast_1d(inp["validation.bandwidth"]), np.atleast_1d(inp["validation.pixels_per_wavelength"]))
    solved = grids[grids <= inp["validation.max_grid"]]
    largest = int(solved.max()) if solved.size else int(inp["validation.max_grid"])
    return Shape(work={"values_per_pixel": 25, "pixels": largest ** 2, "per_load": 1 / loads},
                 keys={"pixels": "validation.max_grid"}, coupled=("reduced_pressure",), keep_blocks=True,
                 # a task's map has bandwidth x pixels_per_wavelength pixels a side: the largest first
                 costlier_with=("bandwidth", "pixels_per_wavelength"))


TASK_COORDS = {
    "hurst": Var("1", "Hurst exponent H of both surfaces"),
    "bandwidth": Var("1", "bandwidth zeta = q_max / qL", comment="of the case's band qL..zeta qL"),
    "reduced_pressure": Var("1", "reduced pressure p / (E* g)",
                            comment="g is the rms slope of the case's combined spectrum on its band"),
    "pixels_per_wavelength": Var("1", "BEM pixels per shortest wavelength",
                                 comment="the resolution rung of the BEM task"),
    "realization": Var("1", "index of the random surface pair"),
    "grid": Var("1", "BEM pixels per side", comment="pixels_per_wavelength x bandwidth"),
}
_PER_TASK = {"comment": "one value per BEM task (hurst, bandwidth, eta, realization, pixels_per_wavelength) and "
                        "reduced pressure; NaN where the rung is beyond validation.max_grid or the contact is "
                        "below one pixel"}

register(
    Stage(
        name="validation_bem",
        version="1",
        compute=compute_validation_bem,
        check=check_validation_bem,
        describe=describe_validation_bem,
        reads=BEM_KEYS,
        outputs={
            "validation_bem_contact_area_ratio": Var("1", "BEM relative contact area", attrs=_PER_TASK),
            "validation_bem_mean_gap": Var("m", "BEM mean interfacial separation", attrs=_PER_TASK),
            "validation_bem_seconds_per_solve": Var("s", "BEM wall time per solve",
                                                    comment="wall time of the task divided by the pressures it solved"),
        },
        coords=TASK_COORDS,
        doc="The validation's BEM tasks: synthesized pairs solved at every reduced pressure, per (H, bandwidth, eta, "
            "realization, pixels per wavelength).",
    )
)

register(
    Stage(
        name="validation",
        version="1",
        compute=compute_table,
        needs=("validation_bem",),
        reads=BEM_KEYS + VARIANT_KEYS,
        outputs=TABLE_OUTPUTS,
        coords={**TASK_COORDS, **TABLE_COORDS},
        figures=(Figure("validation_kappa", "kappa = (A/A0) E* g / p against p/(E* g): theory variants and BEM",
                        ("validation",), figure_kappa),
                 Figure("validation_separation", "mean separation, theory / BEM per variant, against p/(E* g)",
                        ("validation",), figure_separation_ratio)),
        doc="Theory variants against the BEM: extrapolated BEM area and its error bar, the variants on the same "
            "spectra, and the deviation table.",
    )
)
