"""Stage ``bem``: exact FFT boundary-element contact on synthesized or measured surface pairs,
compared with the ``contact`` and ``separation`` stages at the same magnification.

Kernels: :mod:`roughcontact.physics.synthesis` (random pairs with the psd stage's spectra and
coherence, seed eqs 4, 41, 52; the band limit of a measured map), :mod:`roughcontact.physics.bem`
(the Tamaas solver, an optional dependency), :mod:`roughcontact.physics.bem_coated` (a coated
solid: the Polonsky-Keer solver with the layered surface compliance, material.coating_*) and
:mod:`roughcontact.physics.estimators` (rms slope of a map). The measured maps (``bem.surfaces``) are checked by
:mod:`roughcontact.stages.shared.maps`. Figure: :mod:`roughcontact.stages.figures.bem`.

This module declares the stage and orchestrates its compute; the work is in ``stages/shared/``:
:mod:`~roughcontact.stages.shared.bem_solve` (the solver, Tamaas or the layered kernel, the map,
its band and the realizations, every pair solved), :mod:`~roughcontact.stages.shared.bem_theory`
(the theory and its variants at the BEM's magnification), :mod:`~roughcontact.stages.shared.bem_hardness`
(the elastoplastic outputs with contact.yield_stress) and :mod:`~roughcontact.stages.shared.bem_fields`
(the pressure and gap maps).

The comparison uses one band on both sides: roughness on qL <= |q| <= q_cut on an N x N
periodic map of side L = 2 pi / qL, the theory read at zeta_bem = q_cut / qL, which the scene
must list in ``contact.zeta``. See docs/bem.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.synthesis import grid_band
from roughcontact.stage import (
    Figure,
    Param,
    Section,
    Shape,
    Stage,
    StageInput,
    Var,
    register,
    register_params,
    register_section,
)

from .figures.bem import figure_bem_comparison, figure_bem_elastoplastic, figure_bem_reduced_pressure
from .figures.bem_coating import figure_bem_coating
from .figures.bem_fields import field_figures
from .shared.bem_fields import FIELD_KEYS, MAPS as FIELD_MAPS, PARAMS as FIELD_PARAMS, Fields, with_fields
from .shared.bem_hardness import PLASTIC, PLASTIC_REALIZATIONS, PLASTIC_VARS, check_hardness, with_hardness
from .shared.bem_solve import (
    REALIZATION,
    add_solve_attrs,
    bem_band,
    bem_eta_values,
    single_surfaces,
    solve_all,
    solver,
)
from .shared.bem_theory import at_zeta, on_p_eta, with_variants, zeta_index
from .shared.maps import check_eta, map_band, map_surfaces, measured_maps, topography_files
from .shared.material import COATING_KEYS, E_STAR, MATERIAL_KEYS, e_star, refuse_coating
from .shared.surfaces import MAP_KEYS, surface_reads
from .shared.variants import THEORY, VARIANT_KEYS, VARIANTS

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
register_params("bem", *FIELD_PARAMS)  # the maps stored as optional outputs (stages/shared/bem_fields.py)


def check_bem(inp: StageInput) -> None:
    """The optional dependency, usable measured maps, a hardness for the elastoplastic outputs; a
    coating only for the bem stage itself (it solves the coated solid with the layered kernel; the
    stages that share this check take a homogeneous solid)."""
    if inp.stage != "bem":
        refuse_coating(inp, f"the {inp.stage} stage (its surface kernel is the homogeneous half-space's)")
    solver()
    check_hardness(inp)
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
    **dict.fromkeys(PLASTIC_REALIZATIONS, ("p", "eta", "realization")),
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
        values_per_pixel += 9 * np.size(inp["load.p"])  # gap and pressure maps at p, p exp(+-step); gaps sorted
        return Shape(sizes={"realization": realizations}, coupled=("p", "eta"), keys=keys,
                     work={"values_per_pixel": values_per_pixel, "pixels": n * n, "per_point": 1 / max(points, 1)})
    sizes = {"realization": realizations, "bem_stress_level": int(inp["numerics.bem_stress_bins"]),
             "theory": len(VARIANTS)}
    lacks = {name: tuple(d for d in _DIMS_ALL if d not in spans) for name, spans in _SPANS.items()}
    lacks.update({name: ("zeta", "realization", "bem_stress_level", "theory") for name in _SPAN_P_ETA})
    return with_fields(inp, Shape(sizes=sizes, lacks=lacks, coupled=("p", "eta", "zeta"),
                                  keys={**keys, "bem_stress_level": "numerics.bem_stress_bins"},
                                  work={"values_per_pixel": values_per_pixel, "pixels": n * n,
                                        "per_point": 1 / max(points, 1)}))


#: the outputs over (p, eta) alone
_SPAN_P_ETA = ("bem_contact_area_ratio_mean", "bem_contact_area_ratio_std", "bem_mean_gap_mean", "bem_mean_gap_std",
               "theory_contact_area_ratio", "theory_mean_separation", "area_ratio_theory_to_bem",
               "separation_ratio_theory_to_bem", *(n for n in PLASTIC if n not in PLASTIC_REALIZATIONS))


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
            zeta_index(values, zeta, stage, limit)
    swept = {"p": np.size(inp["load.p"])}  # the sweep points the engine counts: those its upstream results span
    for shape in inp.upstream.values():
        swept.update({d: n for d, n in shape.sizes.items() if d in ("p", "eta", "zeta")})
    return _bem_shape(inp, maps, int(np.prod(list(swept.values()))))


def compute_bem(inp: StageInput) -> xr.Dataset:
    """Solve every map pair at every load (:func:`solve_all`), set the theory beside it at the BEM's
    magnification (and every variant; with contact.yield_stress the elastoplastic areas), add the
    maps asked for, and say how (the text attributes)."""
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
    G = at_zeta(contact, "G", zeta_bem, "contact", limit)
    theory_area = at_zeta(contact, "contact_area_ratio", zeta_bem, "contact", limit)
    theory_gap = at_zeta(separation, "mean_separation", zeta_bem, "separation", limit)
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
    fields = Fields(inp, band, eta_values.size)
    res = solve_all(inp, band, q, C1, C2, E_star, p_values, eta_values, edges, fields)

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
    t_area = on_p_eta(theory_area, p_values, eta_values, has_eta)
    t_gap = on_p_eta(theory_gap, p_values, eta_values, has_eta)
    ds["theory_contact_area_ratio"] = (("p", "eta"), t_area)
    ds["theory_mean_separation"] = (("p", "eta"), t_gap)
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["area_ratio_theory_to_bem"] = (("p", "eta"), t_area / ds["bem_contact_area_ratio_mean"].values)
        ds["separation_ratio_theory_to_bem"] = (("p", "eta"), t_gap / ds["bem_mean_gap_mean"].values)
    ds = with_variants(inp, ds, psd, q, zeta_bem, p_values, has_eta, E_star)
    # the theory_* columns' theory, as the contact and separation stages that computed them say it
    ds.attrs["contact_correction"] = contact["contact_area_ratio"].attrs.get("correction", "persson")
    ds.attrs.update({k: v for k, v in separation.attrs.items() if k.startswith("separation_refinement")})
    if set(PLASTIC) & inp.wanted:
        ds = with_hardness(inp, ds, band, q, C1, C2, E_star, p_values, eta_values, G_pe)
    ds = fields.add_to(ds, p_values)
    for k, v in attrs.items():
        ds[k] = xr.DataArray(v)
    ds["E_star"] = xr.DataArray(E_star)
    add_solve_attrs(inp, ds, band)
    if not has_eta:
        ds = ds.isel(eta=0, drop=True)
    if np.ndim(inp["load.p"]) == 0:
        ds = ds.isel(p=0)
    return ds



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
        version="5",  # 4: contact.yield_stress (optional outputs only); 5: records the theory columns' theory
        compute=compute_bem,
        check=check_bem,
        describe=describe_bem,
        needs=("psd", "contact", "separation"),
        # measured maps (kind = "topography"): the engine reads them; used when bem.surfaces allows.
        # Synthesized surfaces come from the psd stage's spectra: of those sections, only the kind
        # (of a fitted surface's maps, which the engine reads too, what reading them takes)
        reads=(*MATERIAL_KEYS, "load.p", "interface.eta",
               *surface_reads({"topography": MAP_KEYS, "fit": ("height_unit", "fill_undefined"), "*": ()}),
               "bem.surfaces", "bem.grid", "bem.realizations", "bem.seed", "bem.pixels_per_wavelength",
               "numerics.bem_tolerance", "numerics.bem_stress_bins", "numerics.sigma_width", *VARIANT_KEYS,
               "contact.yield_stress", *FIELD_KEYS, *COATING_KEYS),
        files=(topography_files("substrate"), topography_files("solid")),
        outputs={
            "bem_contact_area_ratio": Var("1", "relative contact area A/A0, BEM",
                                          comment="fraction of pixels in contact, per realization"),
            "bem_mean_gap": Var("m", "mean interfacial separation u, BEM",
                                comment="map average of the gap, per realization"),
            "bem_stress_histogram": Var("1/Pa", "contact pressure density P(sigma), BEM",
                                        comment="BEM density of the local contact pressure (integrates to "
                                                "A/A0 within the bins)"),
            "bem_stress_overflow": Var("1", "contact area beyond the last bin, BEM",
                                       comment="fraction of the map in contact at pressures beyond the "
                                               "last histogram bin"),
            "bem_hrms_combined": Var("m", "rms height of h1 - h2 in the BEM band",
                                     comment="of the composite h1 - h2, synthesized or measured (attribute "
                                             "bem_surfaces)"),
            "bem_rms_slope_combined": Var("1", "rms slope of h1 - h2 in the BEM band",
                                          comment="of the composite h1 - h2, synthesized or measured "
                                                  "(attribute bem_surfaces)"),
            "bem_contact_area_ratio_mean": Var("1", "BEM relative contact area, mean over realizations"),
            "bem_contact_area_ratio_std": Var("1", "BEM relative contact area, std over realizations",
                                              comment="standard deviation over realizations; 0 for a single "
                                                      "realization"),
            "bem_mean_gap_mean": Var("m", "BEM mean separation, mean over realizations"),
            "bem_mean_gap_std": Var("m", "BEM mean separation, std over realizations",
                                    comment="standard deviation over realizations; 0 for a single "
                                            "realization"),
            "theory_contact_area_ratio": Var("1", "relative contact area A/A0, theory",
                                             comment="A/A0 of the contact stage (eq 19, or "
                                                     f"contact.correction) {_THEORY}"),
            "theory_mean_separation": Var("m", "mean interfacial separation u, theory",
                                          comment="mean separation of the separation stage (eq 57, with "
                                                  f"separation.refinement) {_THEORY}"),
            "theory_variant_contact_area_ratio": Var("1", "A/A0 of each theory variant",
                                                     comment=f"coordinate theory; {_THEORY}"),
            "theory_variant_mean_separation": Var("m", "mean separation of each theory variant",
                                                  comment=_THEORY),
            "area_ratio_variant_to_bem": Var("1", "A/A0 ratio theory / BEM, per variant"),
            "separation_ratio_variant_to_bem": Var("1", "mean separation ratio theory / BEM, per variant"),
            "area_ratio_theory_to_bem": Var("1", "A/A0 ratio theory / BEM",
                                            comment="relative contact area, theory and BEM on the same "
                                                    "band"),
            "separation_ratio_theory_to_bem": Var("1", "mean separation ratio theory / BEM",
                                                  comment="theory and BEM on the same band; NaN where both "
                                                          "are 0"),
            **{k: Var(_BAND_UNITS[k], label, comment=comment)
               for k, (label, comment) in _BAND_NAMES.items()},
            "E_star": E_STAR,
            **PLASTIC_VARS,
            **FIELD_MAPS["bem"],
        },
        coords={
            "realization": REALIZATION,
            "theory": THEORY,
            "bem_stress_level": Var("1", "histogram bin centre sigma/sigma_max",
                                    comment="sigma / sigma_max, sigma_max = p + sigma_width sqrt(G)"),
            "bem_sigma": Var("Pa", "contact pressure at the bin centre",
                             comment="local contact pressure at each histogram bin centre"),
        },
        figures=(Figure("bem_comparison", "theory vs BEM: A/A0, mean separation and their ratios",
                        ("bem",), figure_bem_comparison),
                 Figure("bem_reduced_pressure", "theory / BEM ratios of every variant against p/(E* g)",
                        ("bem",), figure_bem_reduced_pressure),
                 Figure("bem_elastoplastic", "A_el/A0 and A_pl/A0, theory vs saturated BEM, against p/sigma_Y",
                        ("bem",), figure_bem_elastoplastic,
                        outputs=tuple(n for n in PLASTIC if n not in PLASTIC_REALIZATIONS)),
                 Figure("bem_coating", "coated solids: A/A0 and theory / BEM against the coating thickness d qL",
                        ("bem",), figure_bem_coating),
                 *field_figures("bem")),
        doc="Exact FFT-BEM contact (tamaas; a coated solid: Polonsky-Keer with the layered kernel) on synthesized or "
            "measured surface pairs, compared with the theory at the same band.",
    )
)
