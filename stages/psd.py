"""Power spectral densities: the two surfaces' C1(q), C2(q) and their combination C(q, eta).

Physics: ``equations.md`` section 1 (seed eqs 4, 52, 63, 65).

Convention (Persson, eq 4): C(q) = (2 pi)^-2 \\int d^2x <h(x) h(0)> exp(-i q.x), in m^4,
with hrms^2 = 2 pi \\int q C(q) dq.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from pipeline.errors import UserError
from pipeline.schema import Param, Section
from pipeline.stage import FileInput, Stage, StageInput, Var, register, register_params, register_section
from pipeline.units import array_to_si

from .quadrature import integral, log_grid, loglog_interp
from .topography import (
    TOPOGRAPHY_PARAMS,
    isotropic_factor,
    measured_coherence_on_grid,
    measured_psd_on_grid,
    needs_topography,
)

# ----------------------------------------------------------------------------------------
# Kernels (pure numpy)
# ----------------------------------------------------------------------------------------


def self_affine_hrms_factor(H, qL, q0, q1):
    """hrms^2 / C0 for the self-affine PSD with roll-off (equations.md section 1).

    hrms^2 = pi C0 [ q0^2 - qL^2 + (q0^2 / H) (1 - (q0/q1)^(2H)) ]

    The last term is written as -expm1(2 H ln(q0/q1)) / H so that it stays accurate for
    H -> 0 and for q1 close to q0.

    Parameters
    ----------
    H : float or array
        Hurst exponent, 0 < H <= 1.
    qL, q0, q1 : float
        Lowest wavenumber, roll-off and upper cut-off (1/m), qL <= q0 < q1.

    Returns
    -------
    float or array
        hrms^2 / C0 in 1/m^2.

    References
    ----------
    Persson, J. Chem. Phys. 115, 3840 (2001); seed eq 63 (case qL = q0).
    """
    H = np.asarray(H, dtype=float)
    return np.pi * (q0**2 - qL**2 - q0**2 * np.expm1(2.0 * H * np.log(q0 / q1)) / H)


def self_affine_psd(q, H, qL, q0, q1, C0):
    """Self-affine isotropic PSD with roll-off, Persson's convention (m^4).

    C(q) = C0 for qL <= q < q0; C0 (q/q0)^(-2(1+H)) for q0 <= q <= q1; 0 outside [qL, q1].

    Parameters
    ----------
    q : array
        Wavenumbers (1/m).
    H : float
        Hurst exponent.
    qL, q0, q1 : float
        Band edges and roll-off (1/m).
    C0 : float or array
        Plateau value (m^4); must broadcast against ``q``.

    References
    ----------
    equations.md section 1; seed eq 63.
    """
    q = np.asarray(q, dtype=float)
    shape = np.where(q < q0, 1.0, (np.maximum(q, q0) / q0) ** (-2.0 * (1.0 + H)))
    inside = (q >= qL * (1 - 1e-12)) & (q <= q1 * (1 + 1e-12))
    return C0 * np.where(inside, shape, 0.0)


def psd_combined(C1, C2, eta):
    """Combined PSD of two rough surfaces with coherence eta (m^4), seed eqs 52/65.

    C = C1 + C2 - 2 eta sqrt(C1 C2), computed in the non-negative form
    C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2, which is exactly 0 when eta = 1 and C1 = C2.

    Parameters
    ----------
    C1, C2 : array
        PSDs of the substrate and the elastic solid (m^4), Persson's convention.
    eta : float or array
        Coherence, -1 <= eta <= 1 (may depend on q).

    References
    ----------
    equations.md section 1 (eqs 52, 65).
    """
    C1 = np.asarray(C1, dtype=float)
    C2 = np.asarray(C2, dtype=float)
    eta = np.asarray(eta, dtype=float)
    return (np.sqrt(C1) - eta * np.sqrt(C2)) ** 2 + (1.0 - eta * eta) * C2


def hrms_from_psd(q, C):
    """Root-mean-square roughness (m) from a PSD: hrms^2 = 2 pi \\int q C(q) dq (eq 4).

    Piecewise power-law quadrature over the grid ``q`` (last axis of ``C``).
    """
    return np.sqrt(2.0 * np.pi * integral(q, np.asarray(q) * C))


def rms_slope_from_psd(q, C):
    """Root-mean-square slope xi (dimensionless): xi^2 = 2 pi \\int q^3 C dq (eq 12)."""
    return np.sqrt(2.0 * np.pi * integral(q, np.asarray(q) ** 3 * C))


#: Conventions of measured PSDs and their conversion to Persson's C(q) (equations.md section 1).
CONVENTIONS = {
    "persson": ("m^4", "C(q) as given (Persson's convention)"),
    "contact.engineering": ("m^4", "C(q) = C_ST(q) / (2 pi)^2 (contact.engineering / SurfaceTopography convention)"),
    "1d": (
        "m^3",
        "C(q) = c(H) C1D(q) / q, c(H) = Gamma(1+H) / (2 pi^1.5 Gamma(H+1/2)) (= 1/(4 pi) at H = 1/2), from a "
        "1D profile PSD with hrms^2 = (1/pi) int_0^inf C1D dq; exact only for an isotropic self-affine "
        "surface with that Hurst exponent (equations.md's C1D/(pi q) is 4x too large)",
    ),
}


def psd_to_persson(q, values, convention, hurst=0.5):
    """Convert a measured PSD in ``convention`` to Persson's C(q) in m^4 (see CONVENTIONS).

    For a 1D profile PSD, C1D(q) = 2 pi \\int dq_y C(sqrt(q^2 + q_y^2)), which for
    C ~ q^(-2(1+H)) inverts to C = c(H) C1D / q (:func:`stages.topography.isotropic_factor`).
    """
    if convention == "persson":
        return values
    if convention == "contact.engineering":
        return values / (2.0 * np.pi) ** 2
    if convention == "1d":
        return isotropic_factor(hurst) * values / q
    raise ValueError(convention)


def extend_psd(q_grid, q_data, C_data, how):
    """Interpolate a tabulated PSD onto ``q_grid`` in log-log; outside the data, ``how`` is
    ``"power_law"`` (continue the end slopes), ``"zero"`` (no roughness there) or ``"none"``
    (the caller has checked the grid lies within the data)."""
    inside = (q_grid >= q_data[0]) & (q_grid <= q_data[-1])
    out = np.zeros_like(q_grid)
    out[inside] = loglog_interp(q_grid[inside], q_data, C_data)
    if how == "power_law":
        for sel, (i, j) in ((q_grid < q_data[0], (0, 1)), (q_grid > q_data[-1], (-2, -1))):
            if np.any(sel):
                slope = np.log(C_data[j] / C_data[i]) / np.log(q_data[j] / q_data[i])
                out[sel] = C_data[i] * (q_grid[sel] / q_data[i]) ** slope
    return out


# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------


def _check_surface(values: dict, key: str) -> None:
    if values.get("kind") == "self_affine":
        qL, q1 = values["qL"], values["q1"]
        q0 = values.get("q0") if values.get("q0") is not None else qL
        values["q0"] = q0
        if not (qL <= q0 < q1):
            raise UserError(f"needs qL <= q0 < q1, got qL={qL:g}, q0={q0:g}, q1={q1:g} 1/m", key=key)
        has_h, has_c = values.get("hrms") is not None, values.get("C0") is not None
        if has_h == has_c:
            raise UserError("give exactly one of 'hrms' and 'C0'", key=key)


_SELF_AFFINE = (
    Param("H", "quantity", "", lo=0.0, hi=1.0, lo_open=True, doc="Hurst exponent, 0 < H <= 1"),
    Param("qL", "quantity", "1/m", lo=0.0, lo_open=True, doc="lowest wavenumber 2 pi / L"),
    Param("q0", "quantity", "1/m", default=None, lo=0.0, lo_open=True, doc="roll-off wavenumber (default qL: no roll-off)"),
    Param("q1", "quantity", "1/m", lo=0.0, lo_open=True, doc="upper cut-off wavenumber"),
    Param("hrms", "sweep", "m", default=None, lo=0.0, lo_open=True, dim="hrms_{section}",
          doc="rms roughness; a list is a sweep (dimension hrms_substrate / hrms_solid)"),
    Param("C0", "quantity", "m^4", default=None, lo=0.0, lo_open=True, doc="PSD plateau C(q0) (instead of hrms)"),
)
_PSD_FILE = (
    Param("path", "path", doc="text/CSV file with q and C columns, or a NetCDF file with a q coordinate"),
    Param("columns", "intlist", default=(0, 1), lo=0, doc="0-based column indices of q and C"),
    Param("q_unit", "str", default=None, doc="unit of the q column (else from the header)"),
    Param("C_unit", "str", default=None, doc="unit of the C column (else from the header)"),
    Param("convention", "choice", default="persson", choices=tuple(CONVENTIONS), doc="PSD convention of the file"),
    Param("hurst", "quantity", "", default=0.5, lo=0.0, hi=1.0, lo_open=True,
          doc="Hurst exponent assumed by the '1d' (profile) conversion"),
    Param("variable", "str", default=None, doc="NetCDF: name of the PSD variable (default: the only one over q)"),
    Param("extend", "choice", default="none", choices=("none", "power_law", "zero"),
          doc="how to extend beyond the file's q range (none: error)"),
)


def _surface_section(name: str, doc: str) -> Section:
    return Section(
        name,
        doc=doc,
        optional=True,
        discriminator="kind",
        variants={"self_affine": _SELF_AFFINE, "psd_file": _PSD_FILE, "topography": TOPOGRAPHY_PARAMS, "smooth": ()},
        check=_check_surface,
    )


register_section(_surface_section("substrate", "the hard, rough surface (absent or kind = 'smooth': flat)"))
register_section(_surface_section("solid", "the elastic solid's surface (absent or kind = 'smooth': flat)"))
register_section(
    Section(
        "interface",
        (Param("eta", "sweep", "", default=0.0, lo=-1.0, hi=1.0, choices=("measured",),
               doc="coherence of the two surfaces; a list is a sweep; 'measured': eta(q) from paired topographies"),),
        doc="how the two surfaces' roughness is correlated",
    )
)
register_section(
    Section(
        "grid",
        (
            Param("q_min", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="lowest wavenumber of the q grid (qL of the system; default: lowest of the surfaces)"),
            Param("q_max", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="highest wavenumber (default: highest of the surfaces)"),
        ),
        doc="the wavenumber grid shared by all stages",
    )
)
register_params(
    "numerics",
    Param("points_per_decade", "int", default=50, lo=2, presets={"fast": 20, "accurate": 100},
          ladder=(10, 14, 20, 35, 50, 70, 100, 200, 400), doc="q grid points per decade"),
    doc="resolution of the numerical methods",
)

# ----------------------------------------------------------------------------------------
# Stage wrapper
# ----------------------------------------------------------------------------------------

_SURFACES = {"substrate": "1", "solid": "2"}


def _rough(spec) -> bool:
    return spec is not None and spec.get("kind") != "smooth"


def _measured(name: str, spec: dict, loaded, q_grid: np.ndarray) -> tuple[np.ndarray, dict]:
    """A psd_file surface interpolated onto the q grid, plus attributes saying how."""
    path = str(spec["path"])
    attrs: dict = {}
    convention = spec["convention"]
    if isinstance(loaded, xr.Dataset):
        q_name = "q" if "q" in loaded.coords or "q" in loaded.variables else None
        if q_name is None:
            raise UserError("NetCDF file has no 'q' coordinate", file=path)
        var = spec.get("variable")
        if var is None:
            candidates = [v for v in loaded.data_vars if loaded[v].dims == ("q",)]
            if len(candidates) != 1:
                raise UserError(
                    f"cannot tell which variable is the PSD ({', '.join(candidates) or 'none over q'}); "
                    f"set {name}.variable", file=path)
            var = candidates[0]
        if var not in loaded:
            raise UserError(f"no variable {var!r} in the file", file=path, key=f"{name}.variable")
        q_unit = spec.get("q_unit") or loaded[q_name].attrs.get("units")
        c_unit = spec.get("C_unit") or loaded[var].attrs.get("units")
        convention = loaded[var].attrs.get("psd_convention", convention)
        q_raw, c_raw = loaded[q_name].values, loaded[var].values
        rows = np.arange(q_raw.size)
        where = lambda i: f"index {i}"  # noqa: E731
        attrs["source_provenance"] = json.dumps({k: str(v) for k, v in loaded.attrs.items()})
    else:
        iq, ic = (spec["columns"] + (None, None))[:2]
        if iq is None or ic is None:
            raise UserError("needs two column indices [q, C]", key=f"{name}.columns")
        q_raw, c_raw = loaded.column(iq), loaded.column(ic)
        q_unit = spec.get("q_unit") or (loaded.units[iq] if loaded.units else None)
        c_unit = spec.get("C_unit") or (loaded.units[ic] if loaded.units else None)
        rows = loaded.lines
        where = lambda i: f"line {rows[i]}"  # noqa: E731
    if not q_unit or not c_unit:
        raise UserError(
            f"units of the {'q' if not q_unit else 'C'} column unknown: put them in the file's header "
            f"('# q [1/m]  C [m^4]') or set {name}.{'q_unit' if not q_unit else 'C_unit'}", file=path)
    si_unit = CONVENTIONS[convention][0]
    q_si = array_to_si(q_raw, q_unit, "1/m", key=f"{name}.q_unit")
    c_si = array_to_si(c_raw, c_unit, si_unit, key=f"{name}.C_unit")
    bad = np.flatnonzero(~np.isfinite(q_si) | ~np.isfinite(c_si))
    if bad.size:
        raise UserError("NaN or infinite value", file=path, key=where(bad[0]))
    bad = np.flatnonzero(c_si < 0)
    if bad.size:
        raise UserError(f"negative PSD value {c_raw[bad[0]]:g}", file=path, key=where(bad[0]))
    bad = np.flatnonzero(q_si <= 0)
    if bad.size:
        raise UserError(f"wavenumber must be positive, got {q_raw[bad[0]]:g}", file=path, key=where(bad[0]))
    bad = np.flatnonzero(np.diff(q_si) <= 0)
    if bad.size:
        raise UserError("q is not strictly increasing", file=path, key=where(bad[0] + 1))
    if q_si.size < 2:
        raise UserError("needs at least two data rows", file=path)
    C = psd_to_persson(q_si, c_si, convention, spec.get("hurst", 0.5))
    how = spec["extend"]
    lo, hi = q_grid[0], q_grid[-1]
    if how == "none" and (lo < q_si[0] * (1 - 1e-9) or hi > q_si[-1] * (1 + 1e-9)):
        raise UserError(
            f"the q grid [{lo:.4g}, {hi:.4g}] 1/m reaches outside the file's range [{q_si[0]:.4g}, {q_si[-1]:.4g}] 1/m; "
            f"set grid.q_min/q_max inside it or {name}.extend = 'power_law' or 'zero'", file=path, key=f"{name}.extend")
    attrs.update(
        source_file=path,
        psd_convention=convention,
        conversion=CONVENTIONS[convention][1],
        interpolation="log-log linear between file points",
        extension=how,
        file_q_range=f"{q_si[0]:.6g} {q_si[-1]:.6g} 1/m",
    )
    return extend_psd(q_grid, q_si, C, how if how != "none" else "zero"), attrs


def _q_range(inp: StageInput) -> tuple[float, float, list[float]]:
    lows, highs, knots = [], [], []
    for name in _SURFACES:
        spec = inp[name]
        if not _rough(spec):
            continue
        if spec["kind"] == "self_affine":
            lows.append(spec["qL"])
            highs.append(spec["q1"])
            knots += [spec["qL"], spec["q0"], spec["q1"]]
        elif spec["kind"] == "topography":  # measured range, from the topography stage
            ds = inp.upstream["topography"]
            q = ds[f"q_{name}_measured"].values[np.isfinite(ds[f"psd_{name}_measured"].values)]
            lows.append(float(np.nanmin(q)))
            highs.append(float(np.nanmax(q)))
        else:
            loaded = inp.files[f"{name}.path"]
            if isinstance(loaded, xr.Dataset):
                q = np.asarray(loaded["q"].values, dtype=float)
                unit = spec.get("q_unit") or loaded["q"].attrs.get("units", "1/m")
            else:
                q = loaded.column(spec["columns"][0])
                unit = spec.get("q_unit") or (loaded.units[spec["columns"][0]] if loaded.units else None) or "1/m"
            q = array_to_si(q, unit, "1/m", key=f"{name}.q_unit")
            lows.append(float(np.nanmin(q)))
            highs.append(float(np.nanmax(q)))
    lo = inp["grid.q_min"] or (min(lows) if lows else None)
    hi = inp["grid.q_max"] or (max(highs) if highs else None)
    if lo is None or hi is None:
        raise UserError("both surfaces are smooth: give grid.q_min and grid.q_max, or a rough surface", key="grid")
    if not lo < hi:
        raise UserError(f"needs q_min < q_max, got {lo:g} and {hi:g} 1/m", key="grid")
    return lo, hi, knots


def compute_psd(inp: StageInput) -> xr.Dataset:
    lo, hi, knots = _q_range(inp)
    q_values = log_grid(lo, hi, inp["numerics.points_per_decade"], knots)
    q = xr.DataArray(q_values, dims=("q",), attrs={"units": "1/m", "long_name": "wavenumber"})
    surfaces: dict[str, xr.DataArray] = {}
    for name, index in _SURFACES.items():
        spec = inp[name]
        if not _rough(spec):
            da = xr.zeros_like(q)
            attrs = {"surface": "smooth"}
        elif spec["kind"] == "self_affine":
            attrs = {"surface": "self-affine", "H": spec["H"], "qL": spec["qL"], "q0": spec["q0"], "q1": spec["q1"]}
            factor = float(self_affine_hrms_factor(spec["H"], spec["qL"], spec["q0"], spec["q1"]))
            if spec.get("hrms") is not None:
                hrms = inp.sweep(f"hrms_{name}", spec["hrms"], "m", f"rms roughness of the {name}")
                C0 = hrms**2 / factor
            else:
                C0 = xr.DataArray(spec["C0"])
            shape = xr.DataArray(self_affine_psd(q_values, spec["H"], spec["qL"], spec["q0"], spec["q1"], 1.0), dims=("q",))
            da = C0 * shape
        elif spec["kind"] == "topography":
            values, attrs = measured_psd_on_grid(inp.upstream["topography"], name, q_values, spec["extend"])
            da = xr.DataArray(values, dims=("q",))
        else:
            values, attrs = _measured(name, spec, inp.files[f"{name}.path"], q_values)
            da = xr.DataArray(values, dims=("q",))
        da = da.assign_coords(q=q).transpose(..., "q")
        da.attrs = {"units": "m^4", "long_name": f"power spectral density of the {name} (C{index}, Persson convention)", **attrs}
        surfaces[name] = da
    both = _rough(inp["substrate"]) and _rough(inp["solid"])
    if isinstance(inp["interface.eta"], str):  # "measured": eta(q) from paired topographies
        if "topography" not in inp.upstream or "coherence" not in inp.upstream["topography"]:
            why = inp.upstream["topography"].attrs.get("pairing", "") if "topography" in inp.upstream else ""
            raise UserError("eta = 'measured' needs both surfaces of kind 'topography', paired on the same grid"
                            + (f" ({why})" if why else ""), key="interface.eta")
        eta_q = xr.DataArray(measured_coherence_on_grid(inp.upstream["topography"], q_values), dims=("q",))
        combined = xr.apply_ufunc(psd_combined, surfaces["substrate"], surfaces["solid"], eta_q.assign_coords(q=q),
                                  dask="parallelized", output_dtypes=[float])
        how = ("C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2 (eq 52) with the measured eta(q) of the topography "
               "stage (interpolated in log q, held constant beyond the measured range)")
    elif both:
        eta = inp.sweep("eta", inp["interface.eta"], "1", "coherence of the two surfaces' roughness")
        combined = xr.apply_ufunc(
            psd_combined, surfaces["substrate"], surfaces["solid"], eta, dask="parallelized", output_dtypes=[float]
        )
        how = "C = (sqrt C1 - eta sqrt C2)^2 + (1 - eta^2) C2 (eq 52, non-negative form)"
    else:
        combined = surfaces["substrate"] + surfaces["solid"]
        how = "only one surface is rough: C = C1 + C2 (eta has no effect)"
    combined = combined.transpose(..., "q")
    combined.attrs = {"units": "m^4", "long_name": "combined power spectral density C(q) of the pair", "formula": how}
    hrms = xr.apply_ufunc(hrms_from_psd, q, combined, input_core_dims=[["q"], ["q"]], dask="parallelized", output_dtypes=[float])
    hrms.attrs = {"units": "m", "long_name": "rms roughness of the combined surface (from the PSD)"}
    slope = xr.apply_ufunc(rms_slope_from_psd, q, combined, input_core_dims=[["q"], ["q"]], dask="parallelized", output_dtypes=[float])
    slope.attrs = {"units": "1", "long_name": "rms slope of the combined surface (from the PSD)"}
    ds = xr.Dataset(
        {"psd_substrate": surfaces["substrate"], "psd_solid": surfaces["solid"], "psd_combined": combined,
         "hrms_combined": hrms, "rms_slope_combined": slope},
    )
    ds["q"].attrs = {"units": "1/m", "long_name": "wavenumber"}
    ds.attrs["q_lower_cutoff"] = float(q_values[0])
    return ds


def _files(spec_name: str) -> FileInput:
    return FileInput(f"{spec_name}.path", reader="auto")


register(
    Stage(
        name="psd",
        version="1",
        compute=compute_psd,
        params=("substrate", "solid", "interface.eta", "grid.q_min", "grid.q_max", "numerics.points_per_decade"),
        files=(_files("substrate"), _files("solid")),
        requires=("topography",),
        needed=lambda values: ("topography",) if needs_topography(values) else (),
        outputs={
            "psd_substrate": Var("m^4", "power spectral density of the substrate (C1)"),
            "psd_solid": Var("m^4", "power spectral density of the elastic solid (C2)"),
            "psd_combined": Var("m^4", "combined power spectral density C(q) of the pair"),
            "hrms_combined": Var("m", "rms roughness of the combined surface"),
            "rms_slope_combined": Var("1", "rms slope of the combined surface"),
        },
        coords={
            "q": Var("1/m", "wavenumber"),
            "eta": Var("1", "coherence of the two surfaces' roughness"),
            "hrms_substrate": Var("m", "rms roughness of the substrate"),
            "hrms_solid": Var("m", "rms roughness of the solid"),
        },
        doc="C1(q), C2(q) on a log-spaced q grid and the combined C(q, eta) (eq 52).",
    )
)
