"""Stage ``psd``: the two surfaces' spectra C1(q), C2(q) on one logarithmic q grid and their
combination C(q, eta) (seed eq 52).

Kernels: :mod:`roughcontact.physics.spectra`. The surface sections are declared in
:mod:`roughcontact.stages.shared.surfaces`.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from roughcontact.physics.quadrature import log_grid, log_grid_size
from roughcontact.physics.spectra import (
    CONVENTIONS,
    extend_psd,
    hrms_from_psd,
    psd_combined,
    psd_to_persson,
    rms_slope_from_psd,
    self_affine_hrms_factor,
    self_affine_psd,
)
from roughcontact.physics.uncertainty import combined_psd_error
from roughcontact.stage import SceneWarning, Shape, Stage, StageInput, Upstream, UserError, Var, register

from .shared.grid import scope_attrs
from .shared.maps import measured_coherence_on_grid, measured_psd_on_grid
from .shared.measured import coherence_error_grid, drawn_coherence, drawn_psd, psd_error_grid
from .shared.surfaces import (
    FITTED_SURFACES,
    MEASURED_SURFACES,
    SPECTRUM_KEYS,
    SURFACES,
    is_fitted,
    is_measured,
    is_rough,
    spectrum_file,
    surface_bands,
    surface_reads,
)


def _check_extent(name: str, spec: dict, spectrum, lo: float, hi: float) -> None:
    """With extend = 'none' the q grid [lo, hi] must lie inside the file's range."""
    q_si = spectrum.q
    if spec["extend"] == "none" and (lo < q_si[0] * (1 - 1e-9) or hi > q_si[-1] * (1 + 1e-9)):
        raise UserError(
            f"the q grid [{lo:.4g}, {hi:.4g}] 1/m reaches outside the file's range "
            f"[{q_si[0]:.4g}, {q_si[-1]:.4g}] 1/m; "
            f"set grid.q_min/q_max inside it or {name}.extend = 'power_law' or 'zero'",
            file=str(spectrum.path), key=f"{name}.extend")


def _measured(name: str, spec: dict, spectrum, q_grid: np.ndarray) -> tuple[np.ndarray, dict]:
    """A psd_file surface (read by the engine's spectrum reader, in SI) on the q grid, plus
    attributes saying how it was converted and extended."""
    q_si, convention = spectrum.q, spectrum.convention
    C = psd_to_persson(q_si, spectrum.values, convention, spec.get("hurst", 0.5))
    how = spec["extend"]
    _check_extent(name, spec, spectrum, q_grid[0], q_grid[-1])
    attrs = dict(
        spectrum.attrs,
        source_file=str(spectrum.path),
        psd_convention=convention,
        conversion=CONVENTIONS[convention][1],
        interpolation="log-log linear between file points",
        extension=how,
        file_q_range=f"{q_si[0]:.6g} {q_si[-1]:.6g} 1/m",
    )
    return extend_psd(q_grid, q_si, C, how if how != "none" else "zero"), attrs


def _measured_knots(inp: StageInput, topography: Shape | None) -> list[float]:
    """The wavenumbers between which a measured PSD is interpolated (the rows of a PSD file, the
    mean wavenumbers of measured bins), where the interpolated PSD has kinks. As nodes of the q
    grid no interval straddles a kink: a file's log-log interpolation is then integrated exactly
    by the power-law quadrature, and a measured map's (made unbiased between bins) converges
    three to four times faster (docs/accuracy.md). A table denser than the grid is left out:
    the grid would grow to its size."""
    knots = []
    for name in SURFACES:
        spec = inp[name]
        if not is_rough(spec) or spec["kind"] in ("self_affine", "fit"):
            continue
        if spec["kind"] == "psd_file":
            q = inp.files[f"{name}.path"].q
        else:
            q = topography.values.get(f"q_{name}_measured", np.array([])) if topography is not None else np.array([])
        if q.size >= 2 and q.size <= inp["numerics.points_per_decade"] * np.log10(q.max() / q.min()) + 1:
            knots += [float(k) for k in q]
    return knots


def _q_range(inp: StageInput, topography: Shape | None) -> tuple[float, float, list[float]]:
    """The q grid's ends and knots, from the surfaces' bands (``topography``: the preview of the
    topography stage's result, for measured maps)."""
    bands = surface_bands(inp, topography)
    for name in SURFACES:
        spec = inp[name]
        if is_fitted(spec) and name not in bands:
            raise UserError("the fitted data give no wavenumber bins", key=f"{name}.of")
        if is_rough(spec) and is_measured(spec) and name not in bands:
            raise UserError("the measured maps give no wavenumber bins",
                            key=f"{name}.{'container' if spec['kind'] == 'container' else 'files'}")
    knots = [inp[name][k] for name in SURFACES if is_rough(inp[name]) and inp[name]["kind"] == "self_affine"
             for k in ("qL", "q0", "q1")] + _measured_knots(inp, topography)
    knots += [k for name in SURFACES if is_fitted(inp[name]) and name in bands
              for k in (bands[name].lo, _fitted(inp, name)["q0"], bands[name].hi)]
    lo = inp["grid.q_min"] or (min(b.lo for b in bands.values()) if bands else None)
    hi = inp["grid.q_max"] or (max(b.hi for b in bands.values()) if bands else None)
    if lo is None or hi is None:
        raise UserError("both surfaces are smooth: give grid.q_min and grid.q_max, or a rough surface", key="grid")
    if not lo < hi:
        raise UserError(f"needs q_min < q_max, got {lo:g} and {hi:g} 1/m", key="grid")
    return lo, hi, knots


def check_psd(inp: StageInput) -> None:
    """Spectrum draws need a measured surface to draw from."""
    if np.ndim(inp["bands.draws"]) and not any(is_measured(inp[name]) for name in SURFACES):
        raise UserError("no surface is measured (kind 'topography' or 'container'): its spectra carry no statistical "
                        "band to draw from; set bands.draws = 0", key="bands.draws")


def _check_coverage(inp: StageInput, topography: Shape | None, lo: float, hi: float) -> None:
    """The files (or measured maps) cover the q grid; the coherence asked for can be had."""
    for name in SURFACES:
        spec = inp[name]
        if is_rough(spec) and spec["kind"] == "psd_file":
            _check_extent(name, spec, inp.files[f"{name}.path"], lo, hi)
        elif is_rough(spec) and is_measured(spec) and spec["extend"] == "none" and topography is not None:
            found = topography.ranges[f"q_{name}_measured"]
            if lo < found[0] * (1 - 1e-9) or hi > found[1] * (1 + 1e-9):
                raise UserError(f"the q grid [{lo:.4g}, {hi:.4g}] 1/m reaches outside the measured range "
                                f"[{found[0]:.4g}, {found[1]:.4g}] 1/m; set grid.q_min/q_max inside it or "
                                f"{name}.extend = 'power_law' or 'zero'", key=f"{name}.extend")
    if isinstance(inp["interface.eta"], str) and (topography is None or "coherence" not in topography.variables):
        why = topography.attrs.get("pairing", "") if topography is not None else ""
        raise UserError("eta = 'measured' needs both surfaces of kind 'topography' (or 'container'), paired on the "
                        "same grid" + (f" ({why})" if why else ""), key="interface.eta")


def _fitted(inp: StageInput, name: str) -> dict:
    """The fitted self-affine model of surface ``name`` (kind fit): H, C0 (m^4, NaN before the fit
    stage has computed), q0 (1/m; the fitted band's lower end before) and the fitted band (1/m)."""
    fit = inp.upstream["fit"]
    lo, hi = fit.ranges[f"q_fit_{name}"] if isinstance(fit, Shape) else (
        float(fit[f"q_fit_{name}"].min()), float(fit[f"q_fit_{name}"].max()))
    if isinstance(fit, Shape):
        return {"H": np.nan, "C0": np.nan, "q0": lo, "band": (lo, hi)}
    return {"H": float(fit[f"hurst_fit_{name}"]), "C0": float(fit[f"C0_fit_{name}"]),
            "q0": float(fit[f"q0_fit_{name}"]), "band": (lo, hi)}


def _warn_extrapolation(inp: StageInput, lo: float, hi: float) -> None:
    """A fitted surface used beyond the band it was fitted on is extrapolated: say so."""
    for name in SURFACES:
        if not is_fitted(inp[name]) or "fit" not in inp.upstream:
            continue
        flo, fhi = _fitted(inp, name)["band"]
        beyond = _beyond(inp[name], (flo, fhi), lo, hi)
        if beyond:
            warnings.warn(SceneWarning(
                f"{name}: the fitted self-affine spectrum is extrapolated {beyond} 1/m, beyond the band it was "
                f"fitted on [{flo:.4g}, {fhi:.4g}] 1/m (the q grid [{lo:.4g}, {hi:.4g}] 1/m, {name}.qL/q1); "
                "results there rest on the model, not on the measurement"), stacklevel=2)


def _beyond(spec: dict, band: tuple[float, float], lo: float, hi: float) -> str:
    """Where a fitted surface's spectrum on the grid [lo, hi] (nonzero on [qL, q1]) leaves the
    fitted band: e.g. 'above 4e7' ('' where it does not)."""
    qL, q1 = spec.get("qL") or band[0], spec.get("q1") or band[1]
    a, b = max(lo, qL), min(hi, q1)
    parts = [f"below {band[0]:.6g}" if a < band[0] * (1 - 1e-6) else "",
             f"above {band[1]:.6g}" if b > band[1] * (1 + 1e-6) else ""]
    return " and ".join(p for p in parts if p)


def describe_psd(inp: StageInput) -> Shape:
    """The q grid (its size and range, which the files or measured maps must cover; its nodes up
    to a million, approximate where they include
    measured bins not yet computed) and what the stages over zeta need to know of it (the
    reference wavenumber qL, the surfaces' bands); working memory: a few temporaries over the
    grid per sweep point."""
    topography = inp.upstream.get("topography")
    lo, hi, knots = _q_range(inp, topography)
    _check_coverage(inp, topography, lo, hi)
    _warn_extrapolation(inp, lo, hi)
    size = log_grid_size(lo, hi, inp["numerics.points_per_decade"], knots)
    grid = {"q": log_grid(lo, hi, inp["numerics.points_per_decade"], knots)} if size <= 10**6 else {}
    # measured bins' mean wavenumbers are nodes of the grid; before the topography stage computes they are approximate
    fit = inp.upstream.get("fit")
    # a fitted surface's roll-off q0 is a node of the grid, known once the fit stage has computed
    approximate = ("q",) if (topography is not None and topography.approximate) or fit is not None else ()
    return Shape(sizes={"q": size}, ranges={"q": (lo, hi)}, keys={"q": "numerics.points_per_decade"}, coords=grid,
                 attrs=scope_attrs(inp, topography, lo), work={"temporaries": 8, "q": size}, approximate=approximate)


def _surface(inp: StageInput, name: str, q: xr.DataArray, draw):
    """One surface's PSD on the grid (with dimension draw when measured and drawn), its attributes
    and its standard error on the grid (0: analytic, smooth or a file without errors)."""
    spec, q_values = inp[name], q.values
    err = np.zeros(q_values.size)
    if not is_rough(spec):
        return xr.zeros_like(q), {"surface": "smooth"}, err
    if spec["kind"] == "self_affine":
        attrs = {"surface": "self-affine", "H": spec["H"], "qL": spec["qL"], "q0": spec["q0"], "q1": spec["q1"]}
        factor = float(self_affine_hrms_factor(spec["H"], spec["qL"], spec["q0"], spec["q1"]))
        if spec.get("hrms") is not None:
            C0 = inp.sweep(f"hrms_{name}", spec["hrms"]) ** 2 / factor
        else:
            C0 = xr.DataArray(spec["C0"])
        shape = xr.DataArray(self_affine_psd(q_values, spec["H"], spec["qL"], spec["q0"], spec["q1"], 1.0), dims=("q",))
        return C0 * shape, attrs, err
    if is_fitted(spec):
        model = _fitted(inp, name)
        qL, q1 = spec.get("qL") or model["band"][0], spec.get("q1") or model["band"][1]
        values = self_affine_psd(q_values, model["H"], qL, max(model["q0"], qL), q1, model["C0"])
        lo, hi = model["band"]
        beyond = _beyond(spec, model["band"], q_values[0], q_values[-1])
        attrs = {"surface": "self-affine fit of measured data", "H": model["H"], "C0": model["C0"],
                 "q0": model["q0"], "qL": qL, "q1": q1, "fitted_q_range": f"{lo:.6g} {hi:.6g} 1/m",
                 "extrapolation": (f"the fitted model, extrapolated {beyond} 1/m (beyond the measured band: the "
                                   "model, not the data)") if beyond else "none: the grid lies within the fitted band"}
        return xr.DataArray(values, dims=("q",)), attrs, err
    if is_measured(spec):
        ds = inp.upstream["topography"]
        values, attrs = measured_psd_on_grid(ds, name, q_values, spec["extend"])
        err = psd_error_grid(ds, name, q_values, spec["extend"])
        if draw is None:
            return xr.DataArray(values, dims=("q",)), attrs, err
        attrs["draws"] = "draw 0: the measured PSD; draws 1..N: C* = C n / Gamma(n + 1, 1) per bin (n = (C / error)^2)"
        return drawn_psd(draw, ds, name, q_values, spec["extend"], inp["bands.seed"]), attrs, err
    values, attrs = _measured(name, spec, inp.files[f"{name}.path"], q_values)
    return xr.DataArray(values, dims=("q",)), dict(attrs, error="none known (a PSD file carries no errors)"), err


def _combined(inp: StageInput, surfaces, q: xr.DataArray, draw):
    """C(q, eta) of the pair (eq 52), how it was formed, and eta with its standard error on the grid."""
    both = is_rough(inp["substrate"]) and is_rough(inp["solid"])
    if isinstance(inp["interface.eta"], str):  # "measured": eta(q) from paired topographies (validate_psd checked them)
        ds = inp.upstream["topography"]
        eta0 = xr.DataArray(measured_coherence_on_grid(ds, q.values), dims=("q",)).assign_coords(q=q)
        eta = eta0 if draw is None else drawn_coherence(draw, ds, q.values, inp["bands.seed"]).assign_coords(q=q)
        combined = xr.apply_ufunc(psd_combined, surfaces["substrate"], surfaces["solid"], eta,
                                  dask="parallelized", output_dtypes=[float])
        how = ("C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2 (eq 52) with the measured eta(q) of the topography "
               "stage (interpolated in log q, held constant beyond the measured range)")
        return combined, how, eta0, xr.DataArray(coherence_error_grid(ds, q.values), dims=("q",))
    if both:
        eta = inp.sweep("eta", inp["interface.eta"])
        combined = xr.apply_ufunc(psd_combined, surfaces["substrate"], surfaces["solid"], eta, dask="parallelized",
                                  output_dtypes=[float])
        return combined, "C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2 (eq 52, non-negative form)", eta, 0.0
    combined = surfaces["substrate"] + surfaces["solid"]
    return combined, "only one surface is rough: C = C1 + C2 (eta has no effect)", xr.DataArray(0.0), 0.0


def compute_psd(inp: StageInput) -> xr.Dataset:
    topography = Shape.of(inp.upstream["topography"]) if "topography" in inp.upstream else None
    lo, hi, knots = _q_range(inp, topography)
    q_values = log_grid(lo, hi, inp["numerics.points_per_decade"], knots)
    q = xr.DataArray(q_values, dims=("q",))
    draws = inp["bands.draws"]
    draw = inp.sweep("draw", draws) if np.ndim(draws) else None
    surfaces, errors = {}, {}
    for name in SURFACES:
        da, attrs, err = _surface(inp, name, q, draw)
        da = da.assign_coords(q=q).transpose(..., "q")
        da.attrs = attrs
        surfaces[name], errors[name] = da, xr.DataArray(err, dims=("q",), coords={"q": q})
    combined, how, eta, eta_err = _combined(inp, surfaces, q, draw)
    combined = combined.transpose(..., "q")
    scope = scope_attrs(inp, topography, float(q_values[0]))
    combined.attrs = {"formula": how, "coherence": scope["coherence"]}
    if scope["coherence"] == "constant":  # the one eta, for labels (it is no coordinate)
        combined.attrs["eta"] = float(np.ravel(inp["interface.eta"])[0])
    nominal = {k: v.isel(draw=0, drop=True) if "draw" in v.dims else v for k, v in surfaces.items()}
    combined_err = xr.apply_ufunc(combined_psd_error, nominal["substrate"], nominal["solid"], eta, errors["substrate"],
                                  errors["solid"], eta_err, dask="parallelized", output_dtypes=[float])
    hrms = xr.apply_ufunc(hrms_from_psd, q, combined, input_core_dims=[["q"], ["q"]], dask="parallelized",
                          output_dtypes=[float])
    slope = xr.apply_ufunc(rms_slope_from_psd, q, combined, input_core_dims=[["q"], ["q"]], dask="parallelized",
                           output_dtypes=[float])
    ds = xr.Dataset(
        {"psd_substrate": surfaces["substrate"], "psd_solid": surfaces["solid"], "psd_combined": combined,
         "hrms_combined": hrms, "rms_slope_combined": slope, "psd_substrate_error": errors["substrate"],
         "psd_solid_error": errors["solid"], "psd_combined_error": combined_err.transpose(..., "q")},
    )
    ds.attrs["q_lower_cutoff"] = float(q_values[0])
    ds.attrs.update(scope)  # the reference of zeta and the surfaces' bands, for the checks of later runs
    return ds


STAGE = register(
    Stage(
        name="psd",
        version="3",
        compute=compute_psd,
        # a measured surface's spectrum comes from the topography stage: of it, only how to extend it
        # of a fitted surface its band (the fit stage fits it), and what reading its PSD file (if any) takes
        reads=(*surface_reads({"topography": ("extend",), "container": ("extend",),
                               "fit": ("qL", "q1", *SPECTRUM_KEYS)}),
               "interface.eta", "grid.q_min", "grid.q_max", "numerics.points_per_decade", "bands.draws", "bands.seed"),
        files=(spectrum_file("substrate"), spectrum_file("solid")),
        needs=(Upstream("topography", when=MEASURED_SURFACES), Upstream("fit", when=FITTED_SURFACES)),
        check=check_psd,
        describe=describe_psd,
        outputs={
            "psd_substrate": Var("m^4", "power spectral density C1 of the substrate",
                                 comment="Persson convention"),
            "psd_solid": Var("m^4", "power spectral density C2 of the solid", comment="Persson convention"),
            "psd_combined": Var("m^4", "combined power spectral density C(q) of the pair"),
            "hrms_combined": Var("m", "rms roughness of the combined surface",
                                 comment="from the combined PSD"),
            "rms_slope_combined": Var("1", "rms slope of the combined surface",
                                      comment="from the combined PSD"),
            "psd_substrate_error": Var("m^4", "standard error of C1",
                                       comment="statistical standard error of C1 on the grid; 0 where C1 is "
                                               "analytic or no errors are known"),
            "psd_solid_error": Var("m^4", "standard error of C2",
                                   comment="statistical standard error of C2 on the grid; 0 where C2 is "
                                           "analytic or no errors are known"),
            "psd_combined_error": Var("m^4", "standard error of the combined PSD C(q)",
                                      comment="linear propagation of the errors of C1, C2 and eta "
                                              "(measured spectra)"),
        },
        doc="C1(q), C2(q) on a log-spaced q grid and the combined C(q, eta) (eq 52).",
    )
)
