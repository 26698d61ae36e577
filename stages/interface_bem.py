"""Stage ``interface_bem``: the exact check of the stiffness and leakage theories on the BEM's
gap maps, side by side with the theory over (p, eta).

The same surface pairs as the ``bem`` stage (synthesized with the scene's spectra and coherence,
or the measured maps; :func:`roughcontact.stages.shared.bem_solve.map_pairs`) are solved again, at each
pressure p and at p exp(+-step): the exact stiffness is the central difference of the mean gap,
K = -(p+ - p-)/(u+ - u-); the gap map at p is handed to the thin-film (Reynolds) solver
(:mod:`roughcontact.physics.reynolds`) for the exact flow factor along both axes; and a
bisection in ln p finds the load at which the open area stops percolating. The theory is
evaluated on the BEM's band [qL, q_cut] (zeta_bem = q_cut/qL): K by
:func:`roughcontact.physics.interface.stiffness_from_psd`, the leak rates by
:func:`roughcontact.physics.leakage.leakage_kernel`. See docs/interface.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.effective_medium import BRUGGEMAN_AREA
from roughcontact.physics.interface import stiffness_from_psd
from roughcontact.physics.leakage import leak_rate, leakage_kernel, sealing_pressure
from roughcontact.physics.reynolds import flow_factors, percolates
from roughcontact.stage import Figure, Param, Stage, StageInput, Var, register, register_params

from .bem import check_bem, describe_bem
from .figures.bem_fields import field_figures
from .figures.interface_bem import figure_interface_bem
from .leakage import NUMERICS as LEAKAGE_NUMERICS, SEAL_KEYS, leakage_settings, leakage_theory_attrs, seal_parameters
from .separation import check_separation
from .shared.bem_fields import FIELD_KEYS, MAPS as FIELD_MAPS, Fields, with_fields
from .shared.bem_solve import REALIZATION, bem_band, bem_eta_values, map_pairs, single_surfaces, solve_pair
from .shared.maps import check_eta, map_surfaces, topography_files
from .shared.material import COATING_KEYS, E_STAR, MATERIAL_KEYS, e_star
from .stiffness import SEPARATION_KEYS, separation_settings

register_params(
    "numerics",
    Param("interface_bem_step", "quantity", "", default=0.05, lo=0.0, hi=0.5, lo_open=True,
          doc="the BEM stiffness is the central difference of the mean gap over p exp(+-step)"),
    Param("interface_bem_bisections", "int", default=8, lo=1, hi=60,
          doc="bisection steps in ln p for the BEM's sealing pressure (the bracket shrinks 2^steps times)"),
)

BEM_KEYS = ("interface.eta", "substrate", "solid", "bem.surfaces", "bem.grid", "bem.realizations", "bem.seed",
            "bem.pixels_per_wavelength", "numerics.bem_tolerance", *FIELD_KEYS)


def _solver(inp, E_star, dx, tick):
    """solve(h1, h2, pressures) -> the BEM's results with gap maps at the sorted pressures."""
    def solve(h1, h2, pressures):
        return solve_pair(h1, h2, dx, E_star, np.sort(pressures), tolerance=inp["numerics.bem_tolerance"], fields=True,
                          progress=tick)
    return solve


def _open(gap, axis) -> bool:
    return bool(percolates(gap > 0, axis))


def sealing_bisection(solve, h1, h2, known, axis, steps, p_max):
    """The load (Pa) at which the open area stops percolating along ``axis``, and the contact area
    there: a bracket from the ``known`` (pressure, gap map, area) triples (widened by factors of 2
    up to ``p_max`` if every one percolates), then ``steps`` bisections in ln p. (0, 1) for a
    composite that is flat (closed at any load); NaN where no bracket is found."""
    if np.ptp(h1 - h2) == 0.0:
        return 0.0, 1.0
    states = sorted((p, _open(g, axis), a) for p, g, a in known)
    open_p = [p for p, is_open, _ in states if is_open]
    if not open_p:
        return np.nan, np.nan  # closed at every load asked for: the threshold lies below them
    lo = max(open_p)
    closed_above = [(p, a) for p, is_open, a in states if not is_open and p > lo]
    hi, area = closed_above[0] if closed_above else (lo, np.nan)
    while not closed_above:  # open at every load asked for: double the load until it closes
        hi *= 2.0
        if hi > p_max:
            return np.nan, np.nan
        res = solve(h1, h2, [hi])
        if not _open(res["gap"][0], axis):
            closed_above, area = [hi], float(res["area"][0])
    for _ in range(steps):
        mid = np.sqrt(lo * hi)
        res = solve(h1, h2, [mid])
        if _open(res["gap"][0], axis):
            lo = mid
        else:
            hi, area = mid, float(res["area"][0])
    return float(np.sqrt(lo * hi)), area


def _solve_exact(inp, band, q, C1, C2, E_star, p_values, eta_values, fields=None) -> dict:
    """Per (p, eta, realization): area, mean gap, exact stiffness and flow factor; per (eta,
    realization): the sealing pressure (where neither axis percolates any more) and the area there;
    ``fields`` (:class:`Fields`) keeps the maps at p of the realization it wants."""
    step = float(inp["numerics.interface_bem_step"])
    shape = (p_values.size, eta_values.size, band["R"])
    out = {k: np.empty(shape) for k in ("area", "gap", "stiffness", "flow")}
    out["seal"], out["seal_area"] = np.empty(shape[1:]), np.empty(shape[1:])
    pairs = band["R"] * (1 if band["maps"] is not None else eta_values.size)
    steps = int(inp["numerics.interface_bem_bisections"])
    solve = _solver(inp, E_star, band["dx"], inp.progress("BEM solves", total=pairs * (3 * p_values.size + 2 * steps),
                                                          unit="solve"))
    pressures = np.concatenate([p_values * np.exp(-step), p_values, p_values * np.exp(step)])
    order = np.argsort(pressures)
    for j, r, h1, h2 in map_pairs(band, q, C1, C2, eta_values):
        res = solve(h1, h2, pressures)
        at = {k: np.empty((pressures.size,) + np.shape(v)[1:]) for k, v in res.items()}
        for k, v in res.items():
            at[k][order] = v
        n = p_values.size
        u_minus, u, u_plus = at["mean_gap"][:n], at["mean_gap"][n:2 * n], at["mean_gap"][2 * n:]
        with np.errstate(divide="ignore"):
            out["stiffness"][:, j, r] = np.where(u_minus > u_plus, (pressures[2 * n:] - pressures[:n])
                                                 / np.where(u_minus > u_plus, u_minus - u_plus, 1.0), np.inf)
        out["area"][:, j, r], out["gap"][:, j, r] = at["area"][n:2 * n], u
        out["flow"][:, j, r] = [float(np.mean(flow_factors(g))) for g in at["gap"][n:2 * n]]
        if fields is not None and fields.wants(r):
            fields.keep(j, at["pressure"][n:2 * n], at["gap"][n:2 * n])
        known = list(zip(pressures, at["gap"], at["area"], strict=True))
        seals = [sealing_bisection(solve, h1, h2, known, axis, inp["numerics.interface_bem_bisections"],
                                   10.0 * E_star) for axis in (0, 1)]
        # the flow stops when neither axis percolates: the larger of the two thresholds
        out["seal"][j, r], out["seal_area"][j, r] = max(seals) if not np.isnan(seals).any() else (np.nan, np.nan)
    return out


def _theory(inp, psd, band, p_values, eta_values, E_star) -> dict:
    """The theory on the BEM's band: K, both leak rates over (p, eta), both sealing pressures over eta."""
    q = psd["q"].values
    C = psd["psd_combined"]
    C = C.transpose("eta", "q").values if "eta" in C.dims else np.broadcast_to(C.values, (eta_values.size, q.size))
    q_cut = band["q_cut"]
    settings = separation_settings(inp)
    _, K = stiffness_from_psd(q, C[:, None, :], np.array([q_cut]), p_values[None, :], E_star=E_star, **settings)
    kw = leakage_settings(inp, q_cut)
    _, _, s_cj, s_emt = leakage_kernel(q, C[:, None, :], p_values[None, :], **kw)
    seal = seal_parameters(inp)
    return {"stiffness": K[..., 0].T, "leak_cj": leak_rate(s_cj, *seal).T, "leak_emt": leak_rate(s_emt, *seal).T,
            "seal_cj": sealing_pressure(q, C, E_star, kw["area"], q_cut, kw["correction"], kw["gamma"]),
            "seal_emt": sealing_pressure(q, C, E_star, BRUGGEMAN_AREA, q_cut, kw["correction"], kw["gamma"])}


def _spectra(psd: xr.Dataset):
    single_surfaces(psd.sizes)
    return psd["psd_substrate"].values, psd["psd_solid"].values


def check_interface_bem(inp: StageInput) -> None:
    """The BEM's checks and the separation law's (a usable contact-correction gamma)."""
    check_bem(inp)
    check_separation(inp)


def describe_interface_bem(inp: StageInput):
    """The BEM's shape (:func:`describe_bem`), with the maps' dimensions when a map is asked for."""
    return with_fields(inp, describe_bem(inp), others=STAGE.outputs)


def compute_interface_bem(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    C1, C2 = _spectra(psd)
    E_star = e_star(inp)
    names = map_surfaces(inp)
    check_eta(inp, names)
    band = bem_band(inp, q, names)
    p_values = np.atleast_1d(np.asarray(inp["load.p"], dtype=float))
    eta_values = bem_eta_values(inp, psd, names, C1, C2)
    fields = Fields(inp, band, eta_values.size)
    exact = _solve_exact(inp, band, q, C1, C2, E_star, p_values, eta_values, fields)
    theory = _theory(inp, psd, band, p_values, eta_values, E_star)
    pe, per, er = ("p", "eta"), ("p", "eta", "realization"), ("eta", "realization")
    ds = xr.Dataset(coords={"p": p_values, "eta": eta_values, "realization": np.arange(band["R"])})
    for name, key in (("exact_contact_area_ratio", "area"), ("exact_mean_gap", "gap"), ("exact_stiffness", "stiffness"),
                      ("exact_flow_factor", "flow")):
        ds[name] = (per, exact[key])
    ds["exact_sealing_pressure"], ds["exact_percolation_area"] = (er, exact["seal"]), (er, exact["seal_area"])
    for name in ("exact_stiffness", "exact_flow_factor"):
        ds[f"{name}_mean"] = ds[name].mean("realization")
        finite = ds[name].where(np.isfinite(ds[name]), 0.0)  # +inf (full contact) in every realization: spread 0
        ds[f"{name}_std"] = finite.std("realization", ddof=1 if band["R"] > 1 else 0)
    ds["exact_leak_rate"] = (pe, leak_rate(ds["exact_flow_factor_mean"].values, *seal_parameters(inp)))
    ds["theory_stiffness"] = (pe, theory["stiffness"])
    for method, key in (("critical_junction", "cj"), ("effective_medium", "emt")):
        ds[f"theory_leak_rate_{method}"] = (pe, theory[f"leak_{key}"])
        ds[f"theory_sealing_pressure_{method}"] = ("eta", theory[f"seal_{key}"])
        with np.errstate(divide="ignore", invalid="ignore"):
            ds[f"leak_ratio_{method}_to_exact"] = (pe, theory[f"leak_{key}"] / ds["exact_leak_rate"].values)
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["stiffness_ratio_theory_to_exact"] = (pe, theory["stiffness"] / ds["exact_stiffness_mean"].values)
    ds["E_star"] = xr.DataArray(E_star)
    ds = fields.add_to(ds, p_values)
    ds.attrs.update({"bem_zeta": band["zeta"], "bem_q_cut": band["q_cut"], "bem_grid": band["n"],
                     "bem_pixel_size": band["dx"], "bem_surfaces": "measured" if band["maps"] is not None else
                     "synthesized", "bem_band_limit": band["limit"], "leakage_aspect_ratio": seal_parameters(inp)[2]
                     / seal_parameters(inp)[3], **leakage_theory_attrs(inp, leakage_settings(inp, band["q_cut"]))})
    if "eta" not in psd["psd_combined"].dims:
        ds = ds.isel(eta=0, drop=True)
    return ds.isel(p=0) if np.ndim(inp["load.p"]) == 0 else ds


_ZERO = ("NaN where both leak rates are 0; +inf where only the exact one is (the theory still leaks, the BEM map "
         "is closed)")
_NAN = "NaN where the bracket is not found: closed at every load asked for, or open up to 10 E*"
STAGE = register(
    Stage(
        name="interface_bem",
        version="2",
        compute=compute_interface_bem,
        check=check_interface_bem,
        describe=describe_interface_bem,
        needs=("psd",),
        reads=(*MATERIAL_KEYS, "load.p", *BEM_KEYS, *SEPARATION_KEYS, *SEAL_KEYS, "leakage.percolation_area",
                *LEAKAGE_NUMERICS, "numerics.interface_bem_step", "numerics.interface_bem_bisections",
                *COATING_KEYS),
        files=(topography_files("substrate"), topography_files("solid")),
        outputs={
            "exact_contact_area_ratio": Var("1", "BEM relative contact area at p, per realization"),
            "exact_mean_gap": Var("m", "BEM mean gap at p, per realization"),
            "exact_stiffness": Var("Pa/m", "BEM contact stiffness -dp/du",
                                   comment="central difference over p exp(+-step)"),
            "exact_stiffness_mean": Var("Pa/m", "BEM contact stiffness, mean over realizations"),
            "exact_stiffness_std": Var("Pa/m", "BEM contact stiffness, std over realizations",
                                       comment="standard deviation over realizations"),
            "exact_flow_factor": Var("m^3", "effective flow factor of the BEM gap map",
                                     comment="Reynolds equation; mean of the flows along the two axes"),
            "exact_flow_factor_mean": Var("m^3", "exact flow factor, mean over realizations"),
            "exact_flow_factor_std": Var("m^3", "exact flow factor, std over realizations",
                                         comment="standard deviation over realizations"),
            "exact_leak_rate": Var("m^3/s", "leak rate of the seal, exact flow factor",
                                   comment="from the mean exact flow factor"),
            "exact_sealing_pressure": Var("Pa", "sealing pressure, BEM",
                                          attrs={"comment": "load at which the BEM's open area stops percolating "
                                                            "along both axes (flow stops)", "nan_reason": _NAN}),
            "exact_percolation_area": Var("1", "BEM contact area at the sealing pressure", attrs={"nan_reason": _NAN}),
            "theory_stiffness": Var("Pa/m", "contact stiffness of the theory on the BEM band"),
            "theory_leak_rate_critical_junction": Var("m^3/s", "critical-junction leak rate on the BEM band"),
            "theory_leak_rate_effective_medium": Var("m^3/s", "effective-medium leak rate on the BEM band"),
            "theory_sealing_pressure_critical_junction": Var("Pa", "critical-junction sealing pressure, BEM band"),
            "theory_sealing_pressure_effective_medium": Var("Pa", "effective-medium sealing pressure, BEM band"),
            "leak_ratio_critical_junction_to_exact": Var("1", "critical-junction / exact leak rate",
                                                         attrs={"nan_reason": _ZERO}),
            "leak_ratio_effective_medium_to_exact": Var("1", "effective-medium / exact leak rate",
                                                        attrs={"nan_reason": _ZERO}),
            "stiffness_ratio_theory_to_exact": Var("1", "theory / BEM contact stiffness",
                                                   attrs={"nan_reason": "NaN where both are +inf (full contact)"}),
            "E_star": E_STAR,
            **FIELD_MAPS["interface_bem"],
        },
        coords={"realization": REALIZATION},
        figures=(Figure("interface_bem", "theory vs exact: leak rate and contact stiffness on the BEM's gap",
                        ("interface_bem",), figure_interface_bem), *field_figures("interface_bem")),
        doc="Exact check on the BEM gap maps: Reynolds leak rate, sealing load and stiffness against the theory.",
    )
)
