"""The two surfaces (``[substrate]`` and ``[solid]``, each of a kind: self-affine, a PSD file, measured
maps, a contact.engineering container, or smooth), their coherence (``[interface]``), and what the
stages ask of them (is a surface rough, measured; the band of wavenumbers it is rough at)."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

from roughcontact.physics.spectra import CONVENTIONS
from roughcontact.stage import REQUIRED, ByKind, FileInput, Param, Section, Shape, UserError, register_section

SURFACES = ("substrate", "solid")


class Band(NamedTuple):
    """The wavenumbers (1/m) a rough surface has roughness at, and the scene key that sets them."""

    lo: float
    hi: float
    key: str
    #: a measured PSD extended as a power law: rough at every wavenumber of the grid
    spans_grid: bool = False


def surface_bands(psd, topography=None, fit=None) -> dict[str, Band]:
    """The :class:`Band` of each rough surface (the measured range for a measured PSD).

    ``psd`` is the psd stage's StageInput (its surface sections and files, SI); ``topography``
    the Shape of the topography stage's result, for measured maps (left out without it); ``fit``
    the Shape of the fit stage's result, for fitted surfaces (kind fit: its ``qL`` and ``q1``,
    default the fitted band; by default the psd stage's upstream fit, a Shape or a Dataset)."""
    if fit is None and "fit" in getattr(psd, "upstream", {}):
        fit = psd.upstream["fit"]
        fit = fit if isinstance(fit, Shape) else Shape.of(fit)
    bands = {}
    for name in SURFACES:
        spec = psd[name]
        if not is_rough(spec):
            continue
        if spec["kind"] == "self_affine":
            bands[name] = Band(spec["qL"], spec["q1"], f"{name}.qL")
        elif spec["kind"] == "psd_file":
            q = psd.files[f"{name}.path"].q
            bands[name] = Band(float(q[0]), float(q[-1]), f"{name}.path", spec["extend"] == "power_law")
        elif spec["kind"] == "fit":
            if fit is not None and f"q_fit_{name}" in fit.ranges:
                lo, hi = fit.ranges[f"q_fit_{name}"]
                bands[name] = Band(spec.get("qL") or lo, spec.get("q1") or hi, f"{name}.qL")
        elif topography is not None and f"q_{name}_measured" in topography.ranges:  # topography, container
            lo, hi = topography.ranges[f"q_{name}_measured"]
            key = f"{name}.{'container' if spec['kind'] == 'container' else 'files'}"
            bands[name] = Band(float(lo), float(hi), key, spec["extend"] == "power_law")
    return bands


def is_rough(spec) -> bool:
    """Whether a surface section describes a rough surface (absent or ``smooth``: flat)."""
    return spec is not None and spec.get("kind") != "smooth"


def is_topography(spec) -> bool:
    """Whether a surface section is a measured topography."""
    return spec is not None and spec.get("kind") == "topography"


def is_measured(spec) -> bool:
    """Whether a surface section is measured height data the topography stage analyses: kind
    'topography' (files) or 'container' (a contact.engineering container)."""
    return spec is not None and spec.get("kind") in MEASURED_KINDS


def is_fitted(spec) -> bool:
    """Whether a surface section is the self-affine fit of measured data (kind 'fit')."""
    return spec is not None and spec.get("kind") == "fit"


def is_fittable(spec) -> bool:
    """Whether a self-affine fit can be made of a surface: measured data (a PSD file, maps, a
    container) or a fitted surface."""
    return spec is not None and spec.get("kind") in (*MEASURED_KINDS, "psd_file", "fit")


def measured_spec(spec):
    """The section of a surface whose height data the topography stage analyses, as the measured
    kind it is: a measured surface as it stands, a fitted one ('fit') of maps or a container as a
    section of kind ``of``; None for any other surface."""
    if is_measured(spec):
        return spec
    if is_fitted(spec) and spec.get("of") in MEASURED_KINDS:
        return dict(spec, kind=spec["of"])
    return None


def spectrum_source(spec) -> bool:
    """Whether a surface's data is a PSD file (kind 'psd_file', or 'fit' of one)."""
    return spec is not None and (spec.get("kind") == "psd_file" or (is_fitted(spec) and spec.get("of") == "psd_file"))


#: the kinds of measured surface (height data the topography stage analyses)
MEASURED_KINDS = ("topography", "container")
#: the condition of :class:`~roughcontact.stage.Upstream` under which a stage needs the topography
#: stage: a surface of a measured kind
MEASURED_SURFACES = {f"{name}.kind": MEASURED_KINDS for name in SURFACES}
#: the condition under which the psd stage needs the fit stage: a fitted surface
FITTED_SURFACES = {f"{name}.kind": ("fit",) for name in SURFACES}
#: the same for the stages that also analyse the maps of a fitted surface (kind 'fit' of maps or a container)
MAPPED_SURFACES = {**MEASURED_SURFACES, **{f"{name}.of": MEASURED_KINDS for name in SURFACES}}


#: the key holding the data of a fitted surface, by what it is fitted to (``of``)
FIT_DATA = {"topography": "files", "container": "container", "psd_file": "path"}


def _check_surface(values: dict, key: str) -> None:
    if values.get("kind") == "fit":
        data = FIT_DATA[values["of"]]
        if values.get(data) is None:
            raise UserError(f"a fit of {values['of']!r} data needs '{data}'", key=f"{key}.{data}")
        others = [k for k in FIT_DATA.values() if k != data and values.get(k) is not None]
        if others:
            raise UserError(f"of = {values['of']!r} reads '{data}', not '{others[0]}'", key=f"{key}.{others[0]}")
        if values.get("qL") is not None and values.get("q1") is not None and not values["qL"] < values["q1"]:
            raise UserError(f"needs qL < q1, got qL={values['qL']:g}, q1={values['q1']:g} 1/m", key=key)
    if values.get("kind") == "self_affine":
        qL, q1 = values["qL"], values["q1"]
        q0 = values.get("q0") if values.get("q0") is not None else qL
        values["q0"] = q0
        if not (qL <= q0 < q1):
            raise UserError(f"needs qL <= q0 < q1, got qL={qL:g}, q0={q0:g}, q1={q1:g} 1/m", key=key)
        has_h, has_c = values.get("hrms") is not None, values.get("C0") is not None
        if has_h == has_c:
            raise UserError("give exactly one of 'hrms' and 'C0'", key=key)


SELF_AFFINE_PARAMS = (
    Param("H", "quantity", "", lo=0.0, hi=1.0, lo_open=True, doc="Hurst exponent, 0 < H <= 1"),
    Param("qL", "quantity", "1/m", lo=0.0, lo_open=True, doc="lowest wavenumber 2 pi / L"),
    Param("q0", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
          doc="roll-off wavenumber (default qL: no roll-off)"),
    Param("q1", "quantity", "1/m", lo=0.0, lo_open=True, doc="upper cut-off wavenumber"),
    Param("hrms", "sweep", "m", default=None, lo=0.0, lo_open=True, dim="hrms_{section}",
          doc="rms roughness; a list is a sweep (dimension hrms_substrate / hrms_solid)"),
    Param("C0", "quantity", "m^4", default=None, lo=0.0, lo_open=True, doc="PSD plateau C(q0) (instead of hrms)"),
)
PSD_FILE_PARAMS = (
    Param("path", "path", doc="text/CSV file with q and C columns, or a NetCDF file with a q coordinate"),
    Param("columns", "intlist", default=(0, 1), lo=0, doc="0-based column indices of q and C"),
    Param("q_unit", "str", default=None, doc="unit of the q column (else from the header)"),
    Param("C_unit", "str", default=None, doc="unit of the C column (else from the header)"),
    Param("convention", "choice", default="persson", choices=tuple(CONVENTIONS), doc="PSD convention of the file"),
    Param("hurst", "quantity", "", default=0.5, lo=0.0, hi=1.0, lo_open=True,
          doc="Hurst exponent assumed by the '1d' (profile) conversion"),
    Param("variable", "str", default=None, doc="NetCDF: name of the PSD variable (default: the only one over q)"),
    Param("select", "table", default=None,
          doc="NetCDF: the slice of a PSD variable with more dimensions than q, e.g. { eta = 0.0 } for psd_combined"),
    Param("extend", "choice", default="none", choices=("none", "power_law", "zero"),
          doc="how to extend beyond the file's q range (none: error)"),
)
#: polynomial detrending of measured maps, by name (degree of the polynomial removed)
DETREND_DEGREE = {"mean": 0, "plane": 1, "curvature": 2}

TOPOGRAPHY_PARAMS = (
    Param("files", "paths", doc="height map(s) or line scan(s) of this surface, any format SurfaceTopography reads; "
          "several files (e.g. several magnifications) are merged onto one q grid"),
    Param("height_unit", "str", default=None,
          doc="unit of heights (and sizes) for files that do not say (npy; text without a header "
              "like '# x [um]  h [nm]', whose units are used)"),
    Param("size_x", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="scan length along x, for files that do not say"),
    Param("size_y", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="scan length along y, for files that do not say (default: square pixels)"),
    Param("periodic", "bool", default=None,
          doc="treat the data as periodic (default: as the file says; measurements are not)"),
    Param("fill_undefined", "choice", default="none", choices=("none", "harmonic"),
          doc="undefined heights (optical profilometers' non-measured points): 'none' refuses the file, 'harmonic' "
              "fills them with SurfaceTopography's harmonic interpolation (how many and where: attribute 'files')"),
    Param("analysis", "choice", default="area", choices=("area", "profiles"),
          doc="maps: 2D radial PSD ('area') or average of the line scans along x ('profiles'); line scans: always "
              "profiles"),
    Param("detrend", "choice", default=None, choices=tuple(DETREND_DEGREE),
          doc="polynomial removed before the FFT (default: mean if periodic, else plane)"),
    Param("window", "choice", default=None, choices=("hann", "none"),
          doc="window against edge leakage (default: hann if not periodic, else none)"),
    Param("hurst", "quantity", "", default=None, lo=0.0, hi=1.0, lo_open=True,
          doc="Hurst exponent of the line-scan -> isotropic PSD conversion (default: fitted to the scans' spectrum)"),
    Param("tip_radius", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="probe tip radius: drop wavelengths shorter than the tip-artefact cutoff (Sanner 2022)"),
    Param("resolution", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="lateral resolution of the instrument: drop wavelengths shorter than it"),
    Param("q_reliable", "quantity", "1/m", default=None, lo=0.0, lo_open=True, doc="drop wavenumbers above this"),
    Param("extend", "choice", default="none", choices=("none", "power_law", "zero"),
          doc="how the psd stage extends the measured PSD beyond its q range (none: error)"),
)

CONTAINER_PARAMS = (
    Param("container", "path",
          doc="contact.engineering container (ZIP with the measurements and index.json / meta.yml); "
              "units, sizes, height scale, detrending and reliability cutoffs come from its metadata"),
    Param("surface", "str", default=None, doc="which surface of the container (by name) when it holds several"),
    Param("detrend", "choice", default=None, choices=tuple(DETREND_DEGREE),
          doc="polynomial removed before the FFT (default: the measurement's detrend_mode, else mean if periodic, "
              "else plane)"),
    *(p for p in TOPOGRAPHY_PARAMS if p.name in ("fill_undefined", "analysis", "window", "hurst", "extend")),
)

#: the keys of a measured surface (kind "topography") that reading and preparing its maps takes
#: (units, sizes, detrending, window, analysis, reliability cutoffs); ``extend`` and ``hurst`` are not among them
MAP_KEYS = ("files", "height_unit", "size_x", "size_y", "periodic", "fill_undefined", "analysis", "detrend", "window",
            "tip_radius", "resolution", "q_reliable")
#: the same for a contact.engineering container (kind "container"), whose metadata gives the rest
CONTAINER_KEYS = ("container", "surface", "fill_undefined", "detrend", "analysis", "window")


def _optional(params, exclude=()):
    """The parameters with no required one (a fitted surface gives the keys of one kind of data)."""
    return tuple(dataclasses.replace(p, default=None) if p.default is REQUIRED else p
                 for p in params if p.name not in exclude)


FIT_PARAMS = (
    Param("of", "choice", choices=("topography", "container", "psd_file"),
          doc="the measured data fitted: height maps ('files' and the keys of kind topography), a "
              "contact.engineering container ('container', ...) or a PSD file ('path', ...)"),
    Param("qL", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
          doc="lowest wavenumber of the fitted spectrum (default: the fitted band's; lower extrapolates)"),
    Param("q1", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
          doc="upper cut-off of the fitted spectrum (default: the fitted band's; higher extrapolates)"),
    *_optional(TOPOGRAPHY_PARAMS, exclude=("extend",)),
    *_optional([p for p in CONTAINER_PARAMS if p.name in ("container", "surface")]),
    *_optional([p for p in PSD_FILE_PARAMS if p.name not in ("extend", "hurst")]),
)
#: the keys of a fitted surface (kind "fit") of a PSD file that reading the file takes
SPECTRUM_KEYS = ("path", "columns", "q_unit", "C_unit", "convention", "hurst", "variable", "select")
#: the keys of a fitted surface (kind "fit") that its measured data's analysis takes
FIT_DATA_KEYS = ("of", *MAP_KEYS, "surface", *SPECTRUM_KEYS[1:])


def spectrum_file(name: str) -> FileInput:
    """The measured PSD of surface ``name`` (kind psd_file, or fit of one), read in SI by the
    engine's spectrum reader."""

    def options(params):
        spec = params[name]
        return dict(key=name, convention=spec["convention"], columns=spec["columns"], q_unit=spec["q_unit"],
                    value_unit=spec["C_unit"], variable=spec["variable"], select=spec["select"],
                    convention_units={k: unit for k, (unit, _) in CONVENTIONS.items()})

    return FileInput(f"{name}.path", reader="spectrum", options=options)


def surface_reads(by_kind: dict) -> tuple[ByKind, ...]:
    """A stage's ``reads`` of both surface sections: the same keys of each, per kind."""
    return tuple(ByKind(name, dict(by_kind)) for name in SURFACES)


def _surface_section(name: str, doc: str) -> Section:
    return Section(
        name,
        doc=doc,
        optional=True,
        discriminator="kind",
        variants={"self_affine": SELF_AFFINE_PARAMS, "psd_file": PSD_FILE_PARAMS, "topography": TOPOGRAPHY_PARAMS,
                  "container": CONTAINER_PARAMS, "fit": FIT_PARAMS, "smooth": ()},
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
