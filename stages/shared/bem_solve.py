"""Solving the BEM's surface pairs, shared by the ``bem`` and ``interface_bem`` stages: the solver
(Tamaas on the homogeneous half-space, :func:`roughcontact.physics.bem.contact_pair`; with a
coating the layered kernel, :func:`roughcontact.physics.bem_coated.coated_contact_pair`) and its
failures as the user's errors, the map and its band (synthesized or measured), the coherences
solved for, the map pairs (realizations), every pair solved at every pressure, and the text
attributes that say how.

Not a stage (it registers nothing); :data:`REALIZATION` is the metadata of both stages' coordinate
``realization``. The scene section ``[bem]`` is declared by :mod:`roughcontact.stages.bem`. See docs/bem.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.bem import SolverMissing, SubPixelContact, contact_pair, tamaas_module
from roughcontact.physics.bem_cg import NoConvergence
from roughcontact.physics.bem_coated import coated_contact_pair
from roughcontact.physics.estimators import rms_slope_of_map
from roughcontact.physics.synthesis import band_limit, grid_band, synthesize_pair, white_noise_pair
from roughcontact.stage import StageInput, UserError, Var

from .maps import map_band, measured_maps
from .material import coating_attrs, coating_layer

#: the optional dependency and how to install it (named in the error without it)
EXTRA = 'pip install "roughcontact[bem]"'


def _missing(exc: SolverMissing) -> UserError:
    return UserError(f"the bem stage needs the optional dependency tamaas, which is not installed ({exc.reason}); "
                     f"install it with: {EXTRA}", key="outputs.variables")


def solver():
    """The tamaas module, or a UserError naming the extra to install."""
    try:
        return tamaas_module()
    except SolverMissing as exc:
        raise _missing(exc) from None


def solve_pair(h1, h2, pixel_size, E_star, pressures, layer=None, **kwargs):
    """:func:`roughcontact.physics.bem.contact_pair` (Tamaas, the half-space), or with a coating
    ``layer`` :func:`roughcontact.physics.bem_coated.coated_contact_pair` (the layered kernel; E_star
    unused), their failures as the user's errors."""
    try:
        if layer is not None:
            return coated_contact_pair(h1, h2, pixel_size, layer, pressures, **kwargs)
        return contact_pair(h1, h2, pixel_size, E_star, pressures, **kwargs)
    except NoConvergence as exc:
        raise UserError(f"the BEM of the coated solid did not converge ({exc}); use a larger "
                        "numerics.bem_tolerance", key="numerics.bem_tolerance") from None
    except SolverMissing as exc:
        raise _missing(exc) from None
    except SubPixelContact as exc:
        nx, ny = exc.shape
        raise UserError(
            f"the BEM cannot solve p = {exc.pressure:.6g} Pa on this {nx} x {ny} map: the contact area is a single "
            f"pixel or less (tamaas: {exc.detail}); use larger pressures or a finer bem.grid", key="load.p") from None


def single_surfaces(sizes) -> None:
    """The BEM solves one pair of surfaces: no hrms sweep, no spectrum draws."""
    for name in ("substrate", "solid"):
        if sizes.get(f"hrms_{name}", 1) > 1:
            raise UserError(f"the bem stage does not sweep hrms_{name}: give a single value", key=f"{name}.hrms")
    if sizes.get("draw", 1) > 1:
        raise UserError("the bem stage does not take spectrum draws: set bands.draws = 0", key="bands.draws")


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


def solve_all(inp, band, q, C1, C2, E_star, p_values, eta_values, edges, fields=None) -> dict:
    """Every map pair solved at every pressure: area, gap, histogram and overflow over
    (p, eta, realization), and the composite's rms height and slope over (eta, realization);
    ``fields`` (:class:`.bem_fields.Fields`) keeps the maps of the realization it wants."""
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
        keep = fields is not None and fields.wants(r)
        res = solve_pair(h1, h2, dx, E_star, p_values[order], layer=coating_layer(inp),
                         tolerance=inp["numerics.bem_tolerance"], stress_edges=edges[order, j], progress=tick,
                         fields=keep)
        for k in ("area", "mean_gap", "histogram", "overflow"):
            out[k][order, j, r] = res[k]
        if keep:
            fields.keep_solved(j, res, order)
    return out


def add_solve_attrs(inp: StageInput, ds: xr.Dataset, band: dict) -> None:
    """The text attributes: solver, surfaces, grid mapping, and how the maps were made."""
    measured = band["maps"] is not None
    tolerance = inp["numerics.bem_tolerance"]
    if coating_layer(inp) is None:
        method = f"tamaas {solver().__version__} PolonskyKeerRey, tolerance {tolerance:g}"
    else:
        method = (f"roughcontact.physics.bem_coated: Polonsky-Keer constrained conjugate gradients (physics/bem_cg.py) "
                  f"with the coated solid's surface compliance 2 / (q E_eff(q)) (physics/layered.py), tolerance "
                  f"{tolerance:g}")
    ds.attrs.update(coating_attrs(inp))
    ds.attrs.update({
        "bem_solver": method,
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



#: the coordinate realization of the stages that solve BEM maps
REALIZATION = Var("1", "realization (surface pair)", comment="index of the surface pair: random pairs; a "
                                                            "single 0 for the measured maps")
