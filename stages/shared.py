"""What several stages share: the scene sections they all read, the coordinates they all
write, and the values derived from scene keys (E*, the magnifications).

Declared once here so that a key, a coordinate's units or E* cannot drift between stages.
The sections: ``[substrate]`` and ``[solid]`` (the two surfaces), ``[interface]`` (their
coherence eta), ``[material]`` (the elastic solid), ``[load]`` (the nominal pressure),
``[contact]`` (the magnifications asked for), ``[grid]`` (the wavenumber grid) and the
``points_per_decade`` setting of ``[numerics]``.
"""

from __future__ import annotations

import json
import warnings
from typing import NamedTuple

import numpy as np

from roughcontact.physics.contact import effective_modulus
from roughcontact.physics.corrections import CORRECTIONS, DEFAULT_GAMMA, check_gamma
from roughcontact.physics.spectra import CONVENTIONS
from roughcontact.stage import (Param, Preview, SceneWarning, Section, UserError, Var, readable, register_coords,
                                register_params, register_section)

# ----------------------------------------------------------------------------------------
# Coordinates written by several stages
# ----------------------------------------------------------------------------------------

register_coords(
    q=Var("1/m", "wavenumber"),
    p=Var("Pa", "nominal pressure"),
    eta=Var("1", "coherence of the two surfaces' roughness"),
    zeta=Var("1", "magnification zeta = q/qL"),
    hrms_substrate=Var("m", "rms roughness of the substrate"),
    hrms_solid=Var("m", "rms roughness of the solid"),
    v=Var("m/s", "sliding velocity"),
    # CF has no standard name for the temperature of a solid (its temperature names are of the air, sea,
    # soil, ...); CF-1.11's units_metadata says it is a temperature on its scale, not a difference
    T=Var("K", "temperature", attrs={"units_metadata": "temperature: on_scale"}),
    omega=Var("rad/s", "angular frequency"),
    draw=Var("1", "spectrum draw: 0 = the measured spectrum, 1..N = spectra drawn within its statistical band",
             standard_name="realization"),
)

#: E*, stored by the stages whose results are read against it (p/E*)
E_STAR = Var("Pa", "effective modulus E* = E/(1 - nu^2)")

#: the scene keys E* is derived from
MATERIAL_KEYS = ("material.E", "material.nu")

#: qL, stored by the stages whose results are over zeta, so that every zeta has its reference
Q_REFERENCE = Var("1/m", "reference wavenumber qL of the magnification zeta = q/qL: the lowest wavenumber of the "
                  "q grid (grid.q_min, else the lowest of the surfaces), the system size L = 2 pi/qL")


def e_star(inp) -> float:
    """E* of the scene's solid on a rigid substrate (Pa), from ``[material]`` (seed eq 3)."""
    return float(effective_modulus(inp["material.E"], inp["material.nu"]))


def zeta_values(inp, q: np.ndarray) -> np.ndarray:
    """The magnifications ``[contact] zeta`` asks for on the wavenumber grid ``q`` (q[0] = qL):
    every node of the grid for ``"all"``, else the given values, which must lie on the grid."""
    zeta = inp["contact.zeta"]
    if isinstance(zeta, str):
        return q / q[0]
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    _check_zeta(zeta, q[-1] / q[0])
    return zeta


def _check_zeta(zeta: np.ndarray, top: float) -> None:
    if np.any(zeta > top * (1 + 1e-12)):
        raise UserError(f"magnification {zeta.max():g} beyond the q grid (zeta <= q_max/qL = {top:.6g})", key="contact.zeta")


def zeta_preview(inp, psd) -> Preview:
    """Before anything computes: the magnifications ``[contact] zeta`` asks for (their number, and
    their values where known), checked against the q grid of the psd stage's ``psd`` preview."""
    zeta = inp["contact.zeta"]
    if isinstance(zeta, str):
        q = psd.coords.get("q")
        return Preview(sizes={"zeta": int(psd.sizes["q"])}, coords={"zeta": q / q[0]} if q is not None else {},
                       keys={"zeta": "numerics.points_per_decade"})
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    lo, hi = psd.ranges["q"]
    _check_zeta(zeta, hi / lo)
    check_magnifications(zeta, psd)
    return Preview(sizes={"zeta": int(zeta.size)}, coords={"zeta": zeta}, keys={"zeta": "contact.zeta"})


# ----------------------------------------------------------------------------------------
# The two surfaces
# ----------------------------------------------------------------------------------------

SURFACES = ("substrate", "solid")


class Band(NamedTuple):
    """The wavenumbers (1/m) a rough surface has roughness at, and the scene key that sets them."""

    lo: float
    hi: float
    key: str
    #: a measured PSD extended as a power law: rough at every wavenumber of the grid
    spans_grid: bool = False


def surface_bands(psd, topography=None) -> dict[str, Band]:
    """The :class:`Band` of each rough surface (the measured range for a measured PSD).

    ``psd`` is the psd stage's StageInput (its surface sections and files, SI); ``topography``
    the Preview of the topography stage's result, for measured maps (left out without it)."""
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
        elif topography is not None and f"q_{name}_measured" in topography.ranges:  # topography, container
            lo, hi = topography.ranges[f"q_{name}_measured"]
            key = f"{name}.{'container' if spec['kind'] == 'container' else 'files'}"
            bands[name] = Band(float(lo), float(hi), key, spec["extend"] == "power_law")
    return bands


def reference_wavenumber(psd, bands) -> tuple[float | None, str]:
    """qL, the reference of zeta = q/qL and lowest wavenumber of the q grid, and where it comes
    from: ``grid.q_min``, else the lowest band edge of the rough surfaces (None if unknown yet)."""
    if psd["grid.q_min"]:
        return float(psd["grid.q_min"]), "grid.q_min"
    if not bands or len(bands) < sum(is_rough(psd[n]) for n in SURFACES):
        return None, "the lowest wavenumber of the surfaces"
    name = min(bands, key=lambda n: bands[n].lo)
    return bands[name].lo, f"the lowest wavenumber of the {name}, {bands[name].key}"


def _wavenumber(q: float) -> str:
    """A wavenumber for a message, e.g. 2e8 1/m as '2e8'."""
    return readable(q, "1/m").removesuffix(" 1/m")


def scope_attrs(psd, topography, lo: float) -> dict:
    """What the psd stage tells the stages over zeta before they compute (its Preview's and its
    result's attributes): the reference of zeta as a note for the user, each rough surface's band
    (JSON), how the coherence enters and how many surfaces are rough. ``lo``: the grid's qL."""
    bands = surface_bands(psd, topography)
    source = reference_wavenumber(psd, bands)[1]
    eta, n_rough = psd["interface.eta"], sum(is_rough(psd[n]) for n in SURFACES)
    coherence = "measured" if isinstance(eta, str) else "swept" if np.size(eta) > 1 else "constant"
    return {"note": f"zeta = q/qL with qL = {_wavenumber(lo)} 1/m ({source}; grid.q_min sets another system size)",
            "surface_bands": json.dumps({n: list(b) for n, b in bands.items()}), "q_reference_source": source,
            "coherence": coherence if n_rough == 2 else "none", "rough_surfaces": n_rough}


def check_magnifications(zeta: np.ndarray, psd) -> None:
    """A rough surface whose whole band lies outside the magnifications asked for (``psd``: the
    psd stage's Preview) is an error when nothing rough is left or when a coherence is swept or
    measured (it could change nothing), a SceneWarning otherwise; the message names the keys."""
    if "surface_bands" not in psd.attrs:
        return
    bands = {n: Band(*b) for n, b in json.loads(psd.attrs["surface_bands"]).items()}
    scope_check(bands, psd.ranges["q"][0], str(psd.attrs["q_reference_source"]), zeta,
                psd.attrs.get("coherence") in ("swept", "measured"), int(psd.attrs["rough_surfaces"]))


def scope_check(bands, qL: float, source: str, zeta, coupled: bool, n_rough: int) -> None:
    """Raise or warn when the magnifications ``zeta`` (a list, or "all") leave out the whole band
    of a rough surface (see :func:`check_magnifications`)."""
    if isinstance(zeta, str):
        return
    top = qL * float(np.max(zeta))
    lost = {n: b for n, b in bands.items() if not b.spans_grid and (b.lo > top * (1 + 1e-9) or b.hi < qL * (1 - 1e-9))}
    if not lost:
        return
    parts = [f"the {n}'s roughness ({b.key}: {_wavenumber(b.lo)} to {_wavenumber(b.hi)} 1/m) is outside that range"
             for n, b in lost.items()]
    need = max(b.lo for b in lost.values()) / qL
    fix = (f"Raise contact.zeta to at least {_wavenumber(need)} (or \"all\") or set grid.q_min, the system's lowest wavenumber "
           f"2 pi/L" if all(b.hi >= qL for b in lost.values()) else "Lower grid.q_min")
    where = f"contact.zeta up to {np.max(zeta):g} sees q from qL = {_wavenumber(qL)} to {_wavenumber(top)} 1/m (qL: {source})"
    if len(lost) == n_rough:
        raise UserError(f"{where}; {'; '.join(parts)}: no roughness is left. {fix}", key="contact.zeta")
    if coupled:
        raise UserError(f"{where}; {'; '.join(parts)}, so interface.eta can change nothing: every result would be that "
                        f"of the other surface alone. {fix}", key="contact.zeta")
    warnings.warn(SceneWarning(f"{where}; {'; '.join(parts)}: the results are those of the other "
                               f"surface alone. {fix}"), stacklevel=2)


def is_rough(spec) -> bool:
    """Whether a surface section describes a rough surface (absent or ``smooth``: flat)."""
    return spec is not None and spec.get("kind") != "smooth"


def is_topography(spec) -> bool:
    """Whether a surface section is a measured topography."""
    return spec is not None and spec.get("kind") == "topography"


def is_measured(spec) -> bool:
    """Whether a surface section is measured height data the topography stage analyses: kind
    'topography' (files) or 'container' (a contact.engineering container)."""
    return spec is not None and spec.get("kind") in ("topography", "container")


def needs_topography(values) -> bool:
    """Whether a scene (its section values) has a surface of kind 'topography' or 'container'."""
    return any(is_measured(values.get(name)) for name in SURFACES)


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


SELF_AFFINE_PARAMS = (
    Param("H", "quantity", "", lo=0.0, hi=1.0, lo_open=True, doc="Hurst exponent, 0 < H <= 1"),
    Param("qL", "quantity", "1/m", lo=0.0, lo_open=True, doc="lowest wavenumber 2 pi / L"),
    Param("q0", "quantity", "1/m", default=None, lo=0.0, lo_open=True, doc="roll-off wavenumber (default qL: no roll-off)"),
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
    Param("height_unit", "str", default=None, doc="unit of heights (and sizes) for files that do not say (npy; text without a header "
          "like '# x [um]  h [nm]', whose units are used)"),
    Param("size_x", "quantity", "m", default=None, lo=0.0, lo_open=True, doc="scan length along x, for files that do not say"),
    Param("size_y", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="scan length along y, for files that do not say (default: square pixels)"),
    Param("periodic", "bool", default=None, doc="treat the data as periodic (default: as the file says; measurements are not)"),
    Param("analysis", "choice", default="area", choices=("area", "profiles"),
          doc="maps: 2D radial PSD ('area') or average of the line scans along x ('profiles'); line scans: always profiles"),
    Param("detrend", "choice", default=None, choices=tuple(DETREND_DEGREE),
          doc="polynomial removed before the FFT (default: mean if periodic, else plane)"),
    Param("window", "choice", default=None, choices=("hann", "none"),
          doc="window against edge leakage (default: hann if not periodic, else none)"),
    Param("hurst", "quantity", "", default=0.5, lo=0.0, hi=1.0, lo_open=True,
          doc="Hurst exponent assumed in the line-scan -> isotropic PSD conversion (exact for a self-affine surface)"),
    Param("tip_radius", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="probe tip radius: drop wavelengths shorter than the tip-artefact cutoff (Sanner 2022)"),
    Param("resolution", "quantity", "m", default=None, lo=0.0, lo_open=True,
          doc="lateral resolution of the instrument: drop wavelengths shorter than it"),
    Param("q_reliable", "quantity", "1/m", default=None, lo=0.0, lo_open=True, doc="drop wavenumbers above this"),
    Param("extend", "choice", default="none", choices=("none", "power_law", "zero"),
          doc="how the psd stage extends the measured PSD beyond its q range (none: error)"),
)

CONTAINER_PARAMS = (
    Param("container", "path", doc="contact.engineering container (ZIP with the measurements and index.json / meta.yml); "
          "units, sizes, height scale, detrending and reliability cutoffs come from its metadata"),
    Param("surface", "str", default=None, doc="which surface of the container (by name) when it holds several"),
    Param("detrend", "choice", default=None, choices=tuple(DETREND_DEGREE),
          doc="polynomial removed before the FFT (default: the measurement's detrend_mode, else mean if periodic, else plane)"),
    *(p for p in TOPOGRAPHY_PARAMS if p.name in ("analysis", "window", "hurst", "extend")),
)

#: the keys of a measured surface (kind "topography") that reading and preparing its maps takes
#: (units, sizes, detrending, window, analysis, reliability cutoffs); ``extend`` and ``hurst`` are not among them
MAP_KEYS = ("files", "height_unit", "size_x", "size_y", "periodic", "analysis", "detrend", "window", "tip_radius",
            "resolution", "q_reliable")
#: the same for a contact.engineering container (kind "container"), whose metadata gives the rest
CONTAINER_KEYS = ("container", "surface", "detrend", "analysis", "window")


def surface_reads(by_kind: dict) -> dict:
    """A stage's ``reads`` for both surface sections: the same keys of each per kind."""
    return {name: dict(by_kind) for name in SURFACES}


def _surface_section(name: str, doc: str) -> Section:
    return Section(
        name,
        doc=doc,
        optional=True,
        discriminator="kind",
        variants={"self_affine": SELF_AFFINE_PARAMS, "psd_file": PSD_FILE_PARAMS, "topography": TOPOGRAPHY_PARAMS,
                  "container": CONTAINER_PARAMS, "smooth": ()},
        check=_check_surface,
    )


register_section(_surface_section("substrate", "the hard, rough surface (absent or kind = 'smooth': flat)"))
register_section(_surface_section("solid", "the elastic solid's surface (absent or kind = 'smooth': flat)"))

# ----------------------------------------------------------------------------------------
# Interface, solid, load, magnifications, grid
# ----------------------------------------------------------------------------------------

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
        "material",
        (
            Param("E", "quantity", "Pa", lo=0.0, lo_open=True, doc="Young's modulus of the elastic solid"),
            Param("nu", "quantity", "", lo=-1.0, hi=0.5, lo_open=True, doc="Poisson ratio, -1 < nu <= 0.5"),
        ),
        doc="the elastic solid (the substrate is rigid)",
    )
)
register_section(
    Section(
        "load",
        (Param("p", "sweep", "Pa", lo=0.0, lo_open=True, doc="nominal pressure; a list or {from, to, num} is a sweep"),),
        doc="the nominal squeezing pressure",
    )
)
register_section(
    Section(
        "contact",
        (
            Param("zeta", "sweep", "", default="all", lo=1.0, choices=("all",),
                  doc="magnification(s) zeta = q/qL; 'all': every node of the q grid"),
        ),
        doc="the magnifications at which contact and separation are computed",
    )
)
#: the contact-area correction (docs/theory.md, "Contact-area corrections"); read by contact,
#: separation (refinement "contact"), friction and bem
register_params(
    "contact",
    Param("correction", "choice", default="persson", choices=tuple(CORRECTIONS),
          doc="contact-area theory: persson (eq 19, the seed), yang_persson (S = gamma + (1 - gamma) (A/A0)^2) "
              "or wang_mueser (S = gamma - (2/9) (A/A0)^2 + (11/9 - gamma) (A/A0)^4): dV = S dV_full along zeta"),
    Param("gamma", "quantity", "", default=None, lo=0.0, hi=1.0, lo_open=True,
          doc="gamma of the correction (default: the published value, 0.45 yang_persson, 5/9 wang_mueser)"),
)
CORRECTION_KEYS = ("contact.correction", "contact.gamma")


def area_correction(inp) -> tuple[str, float | None]:
    """The scene's contact-area correction and its gamma (the published one unless given),
    checked: S(A/A0) > 0 on [0, 1]."""
    name = inp["contact.correction"]
    gamma = inp["contact.gamma"]
    gamma = DEFAULT_GAMMA[name] if gamma is None else float(gamma)
    try:
        check_gamma(name, gamma)
    except ValueError as exc:
        raise UserError(str(exc), key="contact.gamma") from None
    return name, (None if name == "persson" else gamma)


register_section(
    Section(
        "grid",
        (
            Param("q_min", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="lowest wavenumber of the q grid: qL = 2 pi/L, the system size and the reference of zeta = q/qL "
                      "(default: lowest of the surfaces; `plan` prints it)"),
            Param("q_max", "quantity", "1/m", default=None, lo=0.0, lo_open=True,
                  doc="highest wavenumber (default: highest of the surfaces)"),
        ),
        doc="the wavenumber grid shared by all stages",
    )
)


def _check_bands(values: dict, key: str) -> None:
    """``draws = N`` becomes the sweep dimension draw = 0..N (0: the measured spectrum)."""
    n = values.get("draws")
    if isinstance(n, np.ndarray) or float(n) != int(n):
        raise UserError(f"expected a whole number of draws, got {n!r}", key=f"{key}.draws")
    values["draws"] = np.arange(int(n) + 1, dtype=float) if int(n) > 0 else 0.0


register_section(
    Section(
        "bands",
        (
            Param("draws", "sweep", "", default=0, lo=0, hi=100000, dim="draw",
                  doc="spectra drawn within the measured PSDs' statistical band (0: none); a sweep dimension "
                      "'draw' = 0..N that every downstream stage carries (0 = the measured spectrum)"),
            Param("level", "quantity", "", default=0.9, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
                  doc="probability content of the bands (quantiles (1 - level)/2, 0.5, (1 + level)/2 of the draws)"),
            Param("seed", "int", default=0, lo=0, doc="random seed of the draws (draw d uses the stream (seed, surface, d))"),
        ),
        doc="uncertainty bands: predictions from spectra drawn within the measured spectra's statistical band",
        check=_check_bands,
    )
)
register_params(
    "numerics",
    Param("points_per_decade", "int", default=50, lo=2, presets={"fast": 20, "accurate": 100},
          ladder=(10, 14, 20, 35, 50, 70, 100, 200, 400), doc="q grid points per decade"),
    doc="resolution of the numerical methods",
)
