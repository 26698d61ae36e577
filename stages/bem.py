"""Stage ``bem``: exact FFT boundary-element contact on synthesized or measured surface pairs,
compared with the ``contact`` and ``separation`` stages at the same magnification.

Kernels: :mod:`roughcontact.physics.synthesis` (random pairs with the psd stage's spectra and
coherence, seed eqs 4, 41, 52; the band limit of a measured map), :mod:`roughcontact.physics.bem`
(the Tamaas solver, an optional dependency) and :mod:`roughcontact.physics.estimators` (rms
slope of a map). The measured maps (``bem.surfaces``) are checked by
:mod:`roughcontact.stages.shared.maps`. Figure: :mod:`roughcontact.stages.figures.bem`.

The comparison uses one band on both sides: roughness on qL <= |q| <= q_cut on an N x N
periodic map of side L = 2 pi / qL, the theory read at zeta_bem = q_cut / qL, which the scene
must list in ``contact.zeta``. See docs/bem.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.bem import SolverMissing, SubPixelContact, contact_pair, tamaas_module
from roughcontact.physics.estimators import rms_slope_of_map
from roughcontact.physics.synthesis import band_limit, grid_band, synthesize_pair, white_noise_pair
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
    register_params,
    register_section,
)

from .figures.bem import figure_bem_comparison, figure_bem_reduced_pressure
from .shared.maps import check_eta, map_band, map_surfaces, measured_maps, topography_files
from .shared.material import E_STAR, MATERIAL_KEYS, e_star
from .shared.surfaces import MAP_KEYS, surface_reads
from .shared.variants import THEORY, VARIANT_KEYS, VARIANTS, theory_variants, variant_attrs

#: the optional dependency and how to install it (named in the error without it)
EXTRA = 'pip install "roughcontact[bem]"'

register_section(
    Section(
        "bem",
        (
            Param("grid", "int", default=256, lo=8, hi=8192,
                  doc="pixels per side of the synthesized periodic map (side L = 2 pi / qL; measured maps keep "
                      "theirs)"),
            Param("realizations", "int", default=4, lo=1, hi=10000,
                  doc="number of random surface pairs (measured maps: one)"),
            Param("seed", "int", default=0, lo=0, doc="random seed (results are reproducible for a given seed)"),
            Param("pixels_per_wavelength", "quantity", "", default=4.0, lo=2.0,
                  doc="pixels per shortest wavelength kept: q_cut = min(q_max, grid qL / this); 2 = Nyquist"),
            Param("surfaces", "choice", default="auto", choices=("auto", "synthesized", "measured"),
                  doc="auto: solve on the measured maps when every rough surface is a topography (one periodic "
                      "square map each, one grid), else synthesize; synthesized: always random surfaces with the "
                      "psd stage's spectra; measured: the maps or an error"),
        ),
        doc="the boundary-element check (needs the [bem] extra: tamaas)",
    )
)
register_params(
    "numerics",
    Param("bem_tolerance", "quantity", "", default=1e-10, lo=0.0, hi=1e-2, lo_open=True,
          doc="relative tolerance of the BEM contact solver"),
    Param("bem_stress_bins", "int", default=50, lo=2, doc="bins of the BEM contact-pressure histogram"),
)


def _missing(exc: SolverMissing) -> UserError:
    return UserError(f"the bem stage needs the optional dependency tamaas, which is not installed ({exc.reason}); "
                     f"install it with: {EXTRA}", key="outputs.variables")


def solver():
    """The tamaas module, or a UserError naming the extra to install."""
    try:
        return tamaas_module()
    except SolverMissing as exc:
        raise _missing(exc) from None


def solve_pair(h1, h2, pixel_size, E_star, pressures, **kwargs):
    """:func:`roughcontact.physics.bem.contact_pair`, its failures as the user's errors."""
    try:
        return contact_pair(h1, h2, pixel_size, E_star, pressures, **kwargs)
    except SolverMissing as exc:
        raise _missing(exc) from None
    except SubPixelContact as exc:
        nx, ny = exc.shape
        raise UserError(
            f"the BEM cannot solve p = {exc.pressure:.6g} Pa on this {nx} x {ny} map: the contact area is a single "
            f"pixel or less (tamaas: {exc.detail}); use larger pressures or a finer bem.grid", key="load.p") from None


def _zeta_index(values, zeta: float, stage: str, set_by: str) -> int:
    """Where the theory stage's magnifications hold the BEM's zeta; a UserError if they do not."""
    hit = np.flatnonzero(np.isclose(np.atleast_1d(values), zeta, rtol=1e-9, atol=0.0))
    if hit.size == 0:
        raise UserError(
            f"the {stage} stage has no magnification zeta = {zeta:.10g}, the band the BEM map resolves "
            f"(q_cut / qL, set by {set_by}); add {zeta:.10g} to contact.zeta", key="contact.zeta")
    return int(hit[0])


def _at_zeta(ds: xr.Dataset, var: str, zeta: float, stage: str, set_by: str) -> xr.DataArray:
    """A theory variable at the BEM's magnification, which the stage must have computed."""
    da = ds[var]
    if "zeta" not in da.dims and "zeta" not in da.coords:
        return da
    index = _zeta_index(da["zeta"].values, zeta, stage, set_by)
    return da.isel(zeta=index) if "zeta" in da.dims else da


def single_surfaces(sizes) -> None:
    """The BEM solves one pair of surfaces: no hrms sweep, no spectrum draws."""
    for name in ("substrate", "solid"):
        if sizes.get(f"hrms_{name}", 1) > 1:
            raise UserError(f"the bem stage does not sweep hrms_{name}: give a single value", key=f"{name}.hrms")
    if sizes.get("draw", 1) > 1:
        raise UserError("the bem stage does not take spectrum draws: set bands.draws = 0", key="bands.draws")


def check_bem(inp: StageInput) -> None:
    """The optional dependency, and usable measured maps."""
    solver()
    names = map_surfaces(inp)
    check_eta(inp, names)
    if names:
        measured_maps(inp, names)


#: the dimensions each output spans (of the sweep's p and eta and the stage's own); the others it lacks
_SPANS = {
    **dict.fromkeys(("bem_contact_area_ratio", "bem_mean_gap", "bem_stress_overflow"), ("p", "eta", "realization")),
    "bem_stress_histogram": ("p", "eta", "realization", "bem_stress_level"),
    "bem_sigma": ("p", "eta", "bem_stress_level"),
    **dict.fromkeys(("bem_hrms_combined", "bem_rms_slope_combined"), ("eta", "realization")),
    **dict.fromkeys(("theory_variant_contact_area_ratio", "theory_variant_mean_separation",
                     "area_ratio_variant_to_bem", "separation_ratio_variant_to_bem"), ("p", "eta", "theory")),
    **dict.fromkeys(("bem_zeta", "bem_q_cut", "bem_system_size", "bem_pixel_size", "bem_grid", "E_star"), ()),
}
_DIMS_ALL = ("p", "eta", "zeta", "realization", "bem_stress_level", "theory")  # zeta: the contact stage's


def _bem_shape(inp: StageInput, maps, points: int) -> Shape:
    """The dimensions the stage adds (realizations; for ``bem`` also histogram bins and theory
    variants) and its working memory: the solver's fields for one map, about 200 bytes (25
    values) per pixel (docs/bem.md: ~150 measured), held once whatever the loads and coherences
    (solved one after the other); the ``interface_bem`` stage, which shares this describe, also
    keeps the gap maps of its 3 pressures per load (twice: as solved, and sorted)."""
    n = maps["n"] if maps is not None else int(inp["bem.grid"])
    realizations = 1 if maps is not None else int(inp["bem.realizations"])
    keys = {"realization": "bem.realizations", "pixels": "bem.grid" if maps is None else "bem.surfaces"}
    values_per_pixel = 25
    if inp.stage == "interface_bem":
        values_per_pixel += 6 * np.size(inp["load.p"])
        return Shape(sizes={"realization": realizations}, coupled=("p", "eta"), keys=keys,
                     work={"values_per_pixel": values_per_pixel, "pixels": n * n, "per_point": 1 / max(points, 1)})
    sizes = {"realization": realizations, "bem_stress_level": int(inp["numerics.bem_stress_bins"]),
             "theory": len(VARIANTS)}
    lacks = {name: tuple(d for d in _DIMS_ALL if d not in spans) for name, spans in _SPANS.items()}
    lacks.update({name: ("zeta", "realization", "bem_stress_level", "theory") for name in _SPAN_P_ETA})
    return Shape(sizes=sizes, lacks=lacks, coupled=("p", "eta", "zeta"),
                 keys={**keys, "bem_stress_level": "numerics.bem_stress_bins"},
                 work={"values_per_pixel": values_per_pixel, "pixels": n * n, "per_point": 1 / max(points, 1)})


#: the outputs over (p, eta) alone
_SPAN_P_ETA = ("bem_contact_area_ratio_mean", "bem_contact_area_ratio_std", "bem_mean_gap_mean", "bem_mean_gap_std",
               "theory_contact_area_ratio", "theory_mean_separation", "area_ratio_theory_to_bem",
               "separation_ratio_theory_to_bem")


def describe_bem(inp: StageInput) -> Shape:
    """The dimensions it adds and its working memory (:func:`_bem_shape`); the scene must give one
    pair of surfaces, and the BEM's magnification must be among those the contact and separation
    stages compute (where the stage reads them: the interface_bem stage does not)."""
    names = map_surfaces(inp)
    maps = measured_maps(inp, names) if names else None
    psd = inp.upstream["psd"]
    single_surfaces(psd.sizes)
    lo, hi = psd.ranges["q"]
    n_w = inp["bem.pixels_per_wavelength"]
    if maps is not None:
        _, zeta, limit = map_band(lo, hi, maps["n"], maps["side"], maps["q_reliable"], n_w)
    else:
        zeta, limit = grid_band(lo, hi, inp["bem.grid"], n_w)[3], "bem.grid and bem.pixels_per_wavelength"
    for stage in ("contact", "separation"):
        values = inp.upstream[stage].coords.get("zeta") if stage in inp.upstream else None
        if values is not None:
            _zeta_index(values, zeta, stage, limit)
    swept = {"p": np.size(inp["load.p"])}  # the sweep points the engine counts: those its upstream results span
    for shape in inp.upstream.values():
        swept.update({d: n for d, n in shape.sizes.items() if d in ("p", "eta", "zeta")})
    return _bem_shape(inp, maps, int(np.prod(list(swept.values()))))


def bem_band(inp: StageInput, q: np.ndarray, names: tuple[str, ...]) -> dict:
    """The map and its band: grid n, side L, pixel dx, q_cut, zeta_bem, what limits them, the
    realizations and seed, and (measured) the band-limited maps."""
    n_w = inp["bem.pixels_per_wavelength"]
    if not names:
        n = inp["bem.grid"]
        L, dx, q_cut, zeta_bem = grid_band(q[0], q[-1], n, n_w)
        return dict(n=n, R=inp["bem.realizations"], seed=inp["bem.seed"], L=L, dx=dx, q_cut=q_cut, zeta=zeta_bem,
                    limit="bem.grid and bem.pixels_per_wavelength", maps=None)
    maps = measured_maps(inp, names)  # the map sets the grid and the band; one "realization"
    n, dx, L = maps["n"], maps["pixel_size"], maps["side"]
    q_cut, zeta_bem, limit = map_band(q[0], q[-1], n, L, maps["q_reliable"], n_w)
    if limit == "the maps' reliability cutoff":
        limit += f" ({maps['cutoff']})"
    zero = np.zeros((n, n))
    h_maps = {name: band_limit(maps["h"].get(name, zero), dx, q_cut) for name in ("substrate", "solid")}
    return dict(n=n, R=1, seed=None, L=L, dx=dx, q_cut=q_cut, zeta=zeta_bem, limit=limit, maps=maps, h=h_maps)


def bem_eta_values(inp: StageInput, psd: xr.Dataset, names, C1, C2) -> np.ndarray:
    """The coherences solved for: NaN alone when eta(q) is measured (in the maps and in the
    theory's combined PSD), the psd stage's eta sweep, or the scene's single value."""
    if names or isinstance(inp["interface.eta"], str):
        return np.array([np.nan])
    if "eta" in psd["psd_combined"].dims:
        return np.atleast_1d(psd["eta"].values)
    if not (np.any(C1 > 0) and np.any(C2 > 0)):
        return np.array([0.0])  # one surface is smooth: eta has no effect
    return np.atleast_1d(float(np.atleast_1d(inp["interface.eta"])[0]))


def map_pairs(band: dict, q, C1, C2, eta_values):
    """(eta index, realization, h1, h2) of every map pair to solve on: the measured maps, or for
    each realization the synthesized pair at every eta (the same noise for every eta)."""
    if band["maps"] is not None:
        yield 0, 0, band["h"]["substrate"], band["h"]["solid"]
        return
    for r in range(band["R"]):
        noise = white_noise_pair(band["n"], band["seed"], r, band=band["zeta"])
        for j, eta in enumerate(eta_values):
            yield (j, r) + synthesize_pair(q, C1, C2, eta, band["n"], band["q_cut"], noise=noise)


def _solve_all(inp, band, q, C1, C2, E_star, p_values, eta_values, edges) -> dict:
    """Every map pair solved at every pressure: area, gap, histogram and overflow over
    (p, eta, realization), and the composite's rms height and slope over (eta, realization)."""
    R, dx = band["R"], band["dx"]
    shape = (p_values.size, eta_values.size, R)
    out = {k: np.empty(shape) for k in ("area", "mean_gap", "overflow")}
    out["histogram"] = np.empty(shape + (edges.shape[-1] - 1,))
    out["hrms"], out["slope"] = np.empty(shape[1:]), np.empty(shape[1:])
    order = np.argsort(p_values)  # increasing load: each solve starts from the previous one
    tick = inp.progress("BEM solves", total=p_values.size * (1 if band["maps"] is not None else R * eta_values.size),
                        unit="solve")
    for j, r, h1, h2 in map_pairs(band, q, C1, C2, eta_values):
        out["hrms"][j, r] = float(np.std(h1 - h2))
        out["slope"][j, r] = rms_slope_of_map(h1 - h2, dx)
        res = solve_pair(h1, h2, dx, E_star, p_values[order], tolerance=inp["numerics.bem_tolerance"],
                         stress_edges=edges[order, j], progress=tick)
        for k in ("area", "mean_gap", "histogram", "overflow"):
            out[k][order, j, r] = res[k]
    return out


def _on(da: xr.DataArray, p_values, eta_values, has_eta) -> np.ndarray:
    """A theory variable as a (p, eta) array."""
    if "p" not in da.dims:
        da = da.expand_dims(p=p_values)
    if has_eta:
        return da.transpose("p", "eta").values
    return np.asarray(da.transpose("p").values)[:, None] * np.ones(np.size(eta_values))


def _describe(inp: StageInput, ds: xr.Dataset, band: dict) -> None:
    """The text attributes: solver, surfaces, grid mapping, and how the maps were made."""
    measured = band["maps"] is not None
    ds.attrs.update({
        "bem_solver": f"tamaas {solver().__version__} PolonskyKeerRey, tolerance {inp['numerics.bem_tolerance']:g}",
        "bem_surfaces": "measured" if measured else "synthesized",
        "bem_grid_mapping": f"map side L = {'the measured maps side' if measured else '2 pi / qL'} = "
                            f"{band['L']:.6g} m, {band['n']} x {band['n']} pixels of dx = {band['dx']:.6g} m; "
                            f"roughness on 2 pi / L <= |q| <= q_cut = {band['q_cut']:.6g} 1/m (set by "
                            f"{band['limit']}; zeta_bem = {band['zeta']:.6g}); theory read at the same zeta",
    })
    if measured:
        maps = band["maps"]
        ds.attrs["bem_maps"] = (
            "; ".join(f"{name}: {maps['files'][name]} (detrend {maps['detrend'][name]})" for name in maps["files"])
            + "; composite h1 - h2 (substrate minus solid, both heights upwards in one frame, as for the measured "
              "coherence), modes above q_cut and the mean removed; one realization")
    else:
        ds.attrs.update({
            "bem_synthesis": "H1 = (2 pi/L) sqrt(C1) xi1, H2 = (2 pi/L) sqrt(C2) (eta xi1 + sqrt(1 - eta^2) xi2), "
                             "xi = rfft2(white noise)/m on the smallest grid m holding the band (so a finer grid gives "
                             "the same surface), from numpy.random.default_rng([seed, realization]); "
                             "the same noise for every eta of a realization",
            "bem_seed": int(band["seed"]),
        })


def compute_bem(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    single_surfaces(psd.sizes)
    C1, C2 = psd["psd_substrate"].values, psd["psd_solid"].values
    E_star = e_star(inp)
    names = map_surfaces(inp)
    check_eta(inp, names)
    band = bem_band(inp, q, names)
    zeta_bem, limit = band["zeta"], band["limit"]
    contact, separation = inp.upstream["contact"], inp.upstream["separation"]
    G = _at_zeta(contact, "G", zeta_bem, "contact", limit)
    theory_area = _at_zeta(contact, "contact_area_ratio", zeta_bem, "contact", limit)
    theory_gap = _at_zeta(separation, "mean_separation", zeta_bem, "separation", limit)
    p_values = np.atleast_1d(np.asarray(inp["load.p"], dtype=float))
    has_eta = "eta" in psd["psd_combined"].dims
    eta_values = bem_eta_values(inp, psd, names, C1, C2)
    nb = inp["numerics.bem_stress_bins"]
    level = (np.arange(nb) + 0.5) / nb
    # histogram edges per (p, eta): the contact stage's adaptive stress grid, top = p + width sqrt(G)
    G_pe = G.transpose("eta").values if has_eta else np.full(eta_values.size, float(G))
    top = p_values[:, None] + inp["numerics.sigma_width"] * np.sqrt(np.maximum(G_pe, 0.0))[None, :]
    top = np.where(top > p_values[:, None], top, 2.0 * p_values[:, None])
    edges = np.linspace(0.0, 1.0, nb + 1) * top[..., None]  # (p, eta, nb + 1)
    res = _solve_all(inp, band, q, C1, C2, E_star, p_values, eta_values, edges)

    R, dims = band["R"], ("p", "eta", "realization")
    ds = xr.Dataset(coords={"p": p_values, "eta": eta_values, "realization": np.arange(R), "bem_stress_level": level})
    ds = ds.assign_coords(bem_sigma=(("p", "eta", "bem_stress_level"), level * top[..., None]))
    attrs = {"bem_zeta": zeta_bem, "bem_q_cut": band["q_cut"], "bem_system_size": band["L"],
             "bem_pixel_size": band["dx"], "bem_grid": band["n"]}
    ds["bem_contact_area_ratio"] = (dims, res["area"], attrs)
    ds["bem_mean_gap"] = (dims, res["mean_gap"], attrs)
    ds["bem_stress_histogram"] = (dims + ("bem_stress_level",), res["histogram"])
    ds["bem_stress_overflow"] = (dims, res["overflow"])
    ds["bem_hrms_combined"] = (("eta", "realization"), res["hrms"])
    ds["bem_rms_slope_combined"] = (("eta", "realization"), res["slope"])
    for var in ("bem_contact_area_ratio", "bem_mean_gap"):
        ds[f"{var}_mean"] = ds[var].mean("realization")
        ds[f"{var}_std"] = ds[var].std("realization", ddof=1 if R > 1 else 0)
    t_area = _on(theory_area, p_values, eta_values, has_eta)
    t_gap = _on(theory_gap, p_values, eta_values, has_eta)
    ds["theory_contact_area_ratio"] = (("p", "eta"), t_area)
    ds["theory_mean_separation"] = (("p", "eta"), t_gap)
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["area_ratio_theory_to_bem"] = (("p", "eta"), t_area / ds["bem_contact_area_ratio_mean"].values)
        ds["separation_ratio_theory_to_bem"] = (("p", "eta"), t_gap / ds["bem_mean_gap_mean"].values)
    ds = _with_variants(inp, ds, psd, q, zeta_bem, p_values, has_eta, E_star)
    # the theory_* columns' theory, as the contact and separation stages that computed them say it
    ds.attrs["contact_correction"] = contact["contact_area_ratio"].attrs.get("correction", "persson")
    ds.attrs.update({k: v for k, v in separation.attrs.items() if k.startswith("separation_refinement")})
    for k, v in attrs.items():
        ds[k] = xr.DataArray(v)
    ds["E_star"] = xr.DataArray(E_star)
    _describe(inp, ds, band)
    if not has_eta:
        ds = ds.isel(eta=0, drop=True)
    if np.ndim(inp["load.p"]) == 0:
        ds = ds.isel(p=0)
    return ds


def _with_variants(inp, ds, psd, q, zeta_bem, p_values, has_eta, E_star) -> xr.Dataset:
    """Every theory variant (eq 19 / eq 57 and each correction) at the BEM's magnification, and
    its ratio to the BEM, over (p, eta, theory)."""
    C = psd["psd_combined"]
    rows = C.transpose("eta", "q").values if has_eta else np.atleast_2d(C.values)
    area, gap = theory_variants(inp, q, rows, zeta_bem * q[0], p_values, E_star)
    dims = ("p", "eta", "theory")
    ds = ds.assign_coords(theory=list(VARIANTS))
    ds["theory_variant_contact_area_ratio"] = (dims, area)
    ds["theory_variant_mean_separation"] = (dims, gap)
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["area_ratio_variant_to_bem"] = (dims, area / ds["bem_contact_area_ratio_mean"].values[..., None])
        ds["separation_ratio_variant_to_bem"] = (dims, gap / ds["bem_mean_gap_mean"].values[..., None])
    ds.attrs.update(variant_attrs(inp))
    return ds


#: the coordinate realization of the stages that solve BEM maps
REALIZATION = Var("1", "realization (surface pair)", attrs={"comment": "index of the surface pair: random pairs; a "
                                                                      "single 0 for the measured maps"})

_BAND_NAMES = {
    "bem_zeta": ("magnification zeta of the BEM map", "the magnification resolved by the BEM map, q_cut / qL (the "
                 "theory is read there)"),
    "bem_q_cut": ("cut-off wavenumber q_cut of the BEM map", "highest wavenumber of the roughness in the BEM map"),
    "bem_system_size": ("side of the periodic map, 2 pi / qL", None),
    "bem_pixel_size": ("pixel size of the map", None),
    "bem_grid": ("pixels per side of the map", None),
}
_BAND_UNITS = {"bem_zeta": "1", "bem_q_cut": "1/m", "bem_system_size": "m", "bem_pixel_size": "m", "bem_grid": "1"}
_THEORY = "at the BEM's magnification bem_zeta"

register(
    Stage(
        name="bem",
        version="4",
        compute=compute_bem,
        check=check_bem,
        describe=describe_bem,
        needs=("psd", "contact", "separation"),
        # measured maps (kind = "topography"): the engine reads them; used when bem.surfaces allows.
        # Synthesized surfaces come from the psd stage's spectra: of those sections, only the kind
        reads=(*MATERIAL_KEYS, "load.p", "interface.eta", *surface_reads({"topography": MAP_KEYS, "*": ()}),
               "bem.surfaces", "bem.grid", "bem.realizations", "bem.seed", "bem.pixels_per_wavelength",
               "numerics.bem_tolerance", "numerics.bem_stress_bins", "numerics.sigma_width", *VARIANT_KEYS),
        files=(topography_files("substrate"), topography_files("solid")),
        outputs={
            "bem_contact_area_ratio": Var("1", "relative contact area A/A0, BEM",
                                          attrs={"comment": "fraction of pixels in contact, per realization"}),
            "bem_mean_gap": Var("m", "mean interfacial separation u, BEM",
                                attrs={"comment": "map average of the gap, per realization"}),
            "bem_stress_histogram": Var("1/Pa", "contact pressure density P(sigma), BEM",
                                        attrs={"comment": "BEM density of the local contact pressure (integrates to "
                                                          "A/A0 within the bins)"}),
            "bem_stress_overflow": Var("1", "contact area beyond the last bin, BEM",
                                       attrs={"comment": "fraction of the map in contact at pressures beyond the "
                                                         "last histogram bin"}),
            "bem_hrms_combined": Var("m", "rms height of h1 - h2 in the BEM band",
                                     attrs={"comment": "of the composite h1 - h2, synthesized or measured (attribute "
                                                       "bem_surfaces)"}),
            "bem_rms_slope_combined": Var("1", "rms slope of h1 - h2 in the BEM band",
                                          attrs={"comment": "of the composite h1 - h2, synthesized or measured "
                                                            "(attribute bem_surfaces)"}),
            "bem_contact_area_ratio_mean": Var("1", "BEM relative contact area, mean over realizations"),
            "bem_contact_area_ratio_std": Var("1", "BEM relative contact area, std over realizations",
                                              attrs={"comment": "standard deviation over realizations; 0 for a single "
                                                                "realization"}),
            "bem_mean_gap_mean": Var("m", "BEM mean separation, mean over realizations"),
            "bem_mean_gap_std": Var("m", "BEM mean separation, std over realizations",
                                    attrs={"comment": "standard deviation over realizations; 0 for a single "
                                                      "realization"}),
            "theory_contact_area_ratio": Var("1", "relative contact area A/A0, theory",
                                             attrs={"comment": "A/A0 of the contact stage (eq 19, or "
                                                               f"contact.correction) {_THEORY}"}),
            "theory_mean_separation": Var("m", "mean interfacial separation u, theory",
                                          attrs={"comment": "mean separation of the separation stage (eq 57, with "
                                                            f"separation.refinement) {_THEORY}"}),
            "theory_variant_contact_area_ratio": Var("1", "A/A0 of each theory variant",
                                                     attrs={"comment": f"coordinate theory; {_THEORY}"}),
            "theory_variant_mean_separation": Var("m", "mean separation of each theory variant",
                                                  attrs={"comment": _THEORY}),
            "area_ratio_variant_to_bem": Var("1", "A/A0 ratio theory / BEM, per variant"),
            "separation_ratio_variant_to_bem": Var("1", "mean separation ratio theory / BEM, per variant"),
            "area_ratio_theory_to_bem": Var("1", "A/A0 ratio theory / BEM",
                                            attrs={"comment": "relative contact area, theory and BEM on the same "
                                                              "band"}),
            "separation_ratio_theory_to_bem": Var("1", "mean separation ratio theory / BEM",
                                                  attrs={"comment": "theory and BEM on the same band; NaN where both "
                                                                    "are 0"}),
            **{k: Var(_BAND_UNITS[k], label, attrs={"comment": comment} if comment else {})
               for k, (label, comment) in _BAND_NAMES.items()},
            "E_star": E_STAR,
        },
        coords={
            "realization": REALIZATION,
            "theory": THEORY,
            "bem_stress_level": Var("1", "histogram bin centre sigma/sigma_max",
                                    attrs={"comment": "sigma / sigma_max, sigma_max = p + sigma_width sqrt(G)"}),
            "bem_sigma": Var("Pa", "contact pressure at the bin centre",
                             attrs={"comment": "local contact pressure at each histogram bin centre"}),
        },
        figures=(Figure("bem_comparison", "theory vs BEM: A/A0, mean separation and their ratios",
                        ("bem",), figure_bem_comparison),
                 Figure("bem_reduced_pressure", "theory / BEM ratios of every variant against p/(E* g)",
                        ("bem",), figure_bem_reduced_pressure)),
        doc="Exact FFT-BEM contact (tamaas) on synthesized or measured surface pairs, compared with the theory at "
            "the same band.",
    )
)
