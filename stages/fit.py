"""Stage ``fit``: self-affine fits of measured spectra (a PSD file, measured maps, a
contact.engineering container): H, C0 and the roll-off q0 with confidence intervals, and the rms
height, slope and curvature of the fit and of the measured bins.

Kernels: :mod:`roughcontact.physics.selfaffine_fit`. A surface of kind ``fit`` is the fitted
model, which the psd stage puts on its grid. Figure: :mod:`roughcontact.stages.figures.fit`. See
docs/measured-data.md, section "Self-affine fits".
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from roughcontact.physics.selfaffine_fit import fit_self_affine, fitted_rms, interval, psd_moments, rms_from_moments
from roughcontact.physics.spectra import psd_to_persson
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Shape,
    Stage,
    StageInput,
    Upstream,
    UserError,
    Var,
    register,
    register_section,
)

from .figures.fit import figure_fit
from .shared.maps import measured_bins
from .shared.surfaces import (
    FIT_DATA_KEYS,
    MAPPED_SURFACES,
    SPECTRUM_KEYS,
    SURFACES,
    is_fittable,
    is_fitted,
    measured_spec,
    spectrum_file,
    surface_reads,
)

register_section(Section(
    "fit",
    (
        Param("surfaces", "list", default=(),
              doc="the measured surfaces to fit ('substrate', 'solid'; default: every measured one)"),
        Param("level", "quantity", "", default=0.95, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
              doc="probability content of the confidence intervals"),
        Param("rolloff", "bool", default=True,
              doc="fit the roll-off q0 (false: a power law over the whole band, q0 = its lower end)"),
    ),
    doc="self-affine fits of measured spectra (H, C0, roll-off q0) with confidence intervals",
))

#: the fitted quantities: (name, units, long name, short name)
QUANTITIES = (
    ("hurst_fit", "1", "Hurst exponent H of the fit", "H"),
    ("C0_fit", "m^4", "plateau C0 of the fitted PSD", "C0"),
    ("q0_fit", "1/m", "roll-off wavenumber q0 of the fit", "q0"),
    ("hrms_fit", "m", "rms height of the fit", "hrms"),
    ("rms_slope_fit", "1", "rms slope of the fit", "rms slope"),
    ("rms_curvature_fit", "1/m", "rms curvature of the fit", "curvature"),
)
MEASURED = (
    ("hrms_measured", "m", "rms height of the measured bins", "hrms"),
    ("rms_slope_measured", "1", "rms slope of the measured bins", "rms slope"),
    ("rms_curvature_measured", "1/m", "rms curvature of the measured bins", "rms curvature"),
)


def fitted_surfaces(inp: StageInput) -> tuple[str, ...]:
    """The surfaces to fit: ``fit.surfaces`` (default: every measured one) and every surface of kind fit."""
    asked = tuple(inp["fit.surfaces"]) or tuple(n for n in SURFACES if is_fittable(inp[n]))
    return tuple(n for n in SURFACES if n in asked or is_fitted(inp[n]))


def check_fit(inp: StageInput) -> None:
    """A fit asked of a surface that is not measured (or of no surface) is refused."""
    for name in inp["fit.surfaces"]:
        if name not in SURFACES:
            raise UserError(f"{name!r} is not a surface (substrate, solid)", key="fit.surfaces")
        if not is_fittable(inp[name]):
            kind = (inp[name] or {}).get("kind", "smooth")
            raise UserError(f"a fit asked of the {name}, which is not measured (kind {kind!r}): give it measured data "
                            "(kind 'psd_file', 'topography' or 'container')", key="fit.surfaces")
    if not fitted_surfaces(inp):
        raise UserError("no surface is measured: a self-affine fit needs a PSD file, measured maps or a container "
                        "(kind 'psd_file', 'topography' or 'container')", key="fit.surfaces")


def _bins(inp: StageInput, name: str):
    """The measured bins of surface ``name``: q (1/m), C (m^4), standard errors (m^4, or None: a
    PSD file carries none), whether they come from line scans, and where they come from."""
    spec = inp[name]
    if measured_spec(spec) is None:  # a PSD file
        spectrum = inp.files[f"{name}.path"]
        hurst = spec.get("hurst") if spec.get("hurst") is not None else 0.5
        C = psd_to_persson(spectrum.q, spectrum.values, spectrum.convention, hurst)
        ok = np.isfinite(C) & (C > 0)
        return spectrum.q[ok], C[ok], None, spectrum.convention.startswith("1d"), str(spectrum.path)
    ds = inp.upstream["topography"]
    q, C, err = measured_bins(ds, name)
    files = json.loads(ds[f"psd_{name}_measured"].attrs.get("files", "[]"))
    profiles = bool(files) and all(f.get("analysis") == "profiles" for f in files)
    return q, C, err, profiles, "topography stage: measured bins (PSD and standard error)"


def _band_shape(inp: StageInput, name: str):
    """The wavenumbers of the bins that will be fitted (approximate for maps before they are analysed)."""
    if measured_spec(inp[name]) is None:  # a PSD file: its rows with a positive PSD
        spectrum = inp.files[f"{name}.path"]
        return np.asarray(spectrum.q, dtype=float)[np.isfinite(spectrum.values) & (spectrum.values > 0)]
    return np.asarray(inp.upstream["topography"].values.get(f"q_{name}_measured", []), dtype=float)


def describe_fit(inp: StageInput) -> Shape:
    """One dimension per fitted surface (its bins, approximate for measured maps), and the band."""
    sizes, ranges, coords, variables = {}, {}, {}, set()
    for name in fitted_surfaces(inp):
        q = _band_shape(inp, name)
        if q.size < 4:
            raise UserError(f"the measured spectrum of the {name} has {q.size} bin(s): a self-affine fit needs at "
                            "least 4", key="fit.surfaces")
        sizes[f"q_fit_{name}"] = int(q.size)
        ranges[f"q_fit_{name}"] = (float(q.min()), float(q.max()))
        coords[f"q_fit_{name}"] = np.sort(q)
        variables |= {f"{v}_{name}" for v, *_ in (*QUANTITIES, *MEASURED)}
        variables |= {f"{v}_{end}_{name}" for v, *_ in QUANTITIES for end in ("low", "high")}
        variables |= {f"{v}_{name}" for v in ("psd_fit_data", "psd_fit_data_error", "psd_fit", "fit_residual")}
    topo = inp.upstream.get("topography")
    approximate = tuple(d for d in sizes if topo is not None and measured_spec(inp[d[6:]]) is not None)
    return Shape(sizes=sizes, ranges=ranges, coords={k: v for k, v in coords.items() if k not in approximate},
                 variables=frozenset(variables), approximate=approximate)


def _estimates(fit, level: float, profile: bool) -> dict:
    """The fitted quantities with their standard errors and intervals, as (value, attrs)."""
    z_std = np.sqrt(np.diag(fit.cov))
    rms, rms_std = fitted_rms(fit, profile=profile)
    values = {"hurst_fit": (fit.H, z_std[0], False), "C0_fit": (fit.C0, z_std[1], True),
              "q0_fit": (fit.q0, z_std[2], True), "hrms_fit": (rms[0], rms_std[0], True),
              "rms_slope_fit": (rms[1], rms_std[1], True), "rms_curvature_fit": (rms[2], rms_std[2], True)}
    out = {}
    for name, (value, std, log) in values.items():
        attrs = {"ci_level": level}
        if name == "q0_fit" and fit.rolloff != "resolved":
            attrs["ci"] = (f"none: no roll-off {'resolved' if fit.rolloff == 'not resolved' else 'fitted'} in the "
                           "band; q0 is the band's lower end, held fixed")
        else:
            lo, hi = interval(float(value), float(std), level, log)
            attrs.update(ci_low=lo, ci_high=hi,
                         **({"standard_error_of_log": float(std)} if log else {"standard_error": float(std)}))
        out[name] = (float(value), attrs)
    return out


def _surface(inp: StageInput, name: str) -> tuple[dict, dict]:
    level = float(inp["fit.level"])
    q, C, err, profile, source = _bins(inp, name)
    try:
        fit = fit_self_affine(q, C, err, rolloff=bool(inp["fit.rolloff"]))
    except ValueError as exc:
        raise UserError(f"the {name}'s spectrum cannot be fitted: {exc}", key="fit.surfaces") from None
    dim = f"q_fit_{name}"
    out = {}
    for k, (v, a) in _estimates(fit, level, profile).items():
        out[f"{k}_{name}"] = ((), v, a)
        out[f"{k}_low_{name}"] = ((), a.get("ci_low", np.nan), {"ci_level": level})
        out[f"{k}_high_{name}"] = ((), a.get("ci_high", np.nan), {"ci_level": level})
    m = rms_from_moments(*psd_moments(q, C), profile=profile)
    out.update({f"{k}_{name}": ((), float(v), {}) for (k, *_), v in zip(MEASURED, m, strict=True)})
    out[f"psd_fit_data_{name}"] = ((dim,), C, {"source": source})
    out[f"psd_fit_data_error_{name}"] = ((dim,), err if err is not None else np.full(q.size, np.nan),
                                         {} if err is not None else {"comment": "none known (a PSD file)"})
    out[f"psd_fit_{name}"] = ((dim,), fit.psd(q), {})
    out[f"fit_residual_{name}"] = ((dim,), fit.residuals, {})
    if not 0.0 < fit.H <= 1.0:
        out[f"hurst_fit_{name}"][2]["warning"] = "H outside (0, 1]: the spectrum is not that of a self-affine surface"
    summary = {"band_per_m": list(fit.band), "rolloff": fit.rolloff, "chi2": fit.chi2, "dof": fit.dof,
               "covariance_scale": fit.scale, "errors": "the bins' standard errors" if fit.errors_known else
               "none known: equal weights in log C, the scatter about the fit sets them",
               "rms": "of a line scan (1D: slope dh/dx, curvature d2h/dx2)" if profile else
                      "of a map (2D: gradient, mean curvature = half the Laplacian)"}
    return out, {f"fit_{name}": json.dumps(summary), f"fit_{name}_coords": q}


def compute_fit(inp: StageInput) -> xr.Dataset:
    data_vars, coords, attrs = {}, {}, {}
    for name in fitted_surfaces(inp):
        out, info = _surface(inp, name)
        data_vars.update({k: xr.Variable(d, v, a) for k, (d, v, a) in out.items()})
        coords[f"q_fit_{name}"] = info.pop(f"fit_{name}_coords")
        attrs.update(info)
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(attrs, model="C = C0 (qL <= q < q0), C0 (q/q0)^(-2(1+H)) (q0 <= q <= q1), Persson convention",
                    method="weighted least squares in log C (bias of few-mode bins removed), linearised covariance "
                           "scaled by max(1, chi2/dof); intervals normal in H, log-normal in the positive quantities",
                    rms="from the PSD moments m_a = 2 pi int q^(a+1) C dq over the band: hrms = sqrt m0; maps: "
                        "slope = sqrt m2, curvature = sqrt(m4)/2; line scans: slope = sqrt(m2/2), "
                        "curvature = sqrt(3 m4/8)")
    return ds


def _vars(table, surface):
    return {f"{v}_{surface}": Var(u, f"{ln} ({surface})", comment="over the fitted band")
            for v, u, ln, _ in table}


def _bounds(surface):
    """The lower and upper ends of the fitted quantities' confidence intervals, as variables (for tables)."""
    out = {}
    for v, u, _, short in QUANTITIES:
        for end, word in (("low", "lower"), ("high", "upper")):
            out[f"{v}_{end}_{surface}"] = Var(u, f"{word} CI bound of the fit's {short} ({surface})",
                                              comment="probability content: attribute ci_level; NaN where "
                                                      "the quantity has no interval (q0 not resolved)")
    return out


STAGE = register(
    Stage(
        name="fit",
        version="1",
        compute=compute_fit,
        # a measured map's bins come from the topography stage (its key covers their keys)
        reads=(*surface_reads({"psd_file": SPECTRUM_KEYS, "topography": (), "container": (), "fit": FIT_DATA_KEYS,
                               "*": ()}),
               "fit.surfaces", "fit.level", "fit.rolloff"),
        files=tuple(spectrum_file(name) for name in SURFACES),
        needs=(Upstream("topography", when=MAPPED_SURFACES),),
        check=check_fit,
        describe=describe_fit,
        outputs={
            **{k: v for s in SURFACES for k, v in _vars(QUANTITIES, s).items()},
            **{k: v for s in SURFACES for k, v in _vars(MEASURED, s).items()},
            **{k: v for s in SURFACES for k, v in _bounds(s).items()},
            **{f"psd_fit_data_{s}": Var("m^4", f"PSD bins fitted ({s})") for s in SURFACES},
            **{f"psd_fit_data_error_{s}": Var("m^4", f"standard error of the fitted bins ({s})") for s in SURFACES},
            **{f"psd_fit_{s}": Var("m^4", f"fitted self-affine PSD at the bins ({s})") for s in SURFACES},
            **{f"fit_residual_{s}": Var("1", f"weighted residual in log C ({s})",
                                        comment="(y - model) / sigma per bin") for s in SURFACES},
        },
        coords={f"q_fit_{s}": Var("1/m", f"wavenumber of the fitted bins ({s})") for s in SURFACES},
        figures=(Figure("selfaffine_fit", "Self-affine fits of the measured spectra", ("fit",), figure_fit),),
        doc="Self-affine fits (H, C0, q0 with intervals) and rms height, slope, curvature of measured spectra.",
    )
)

