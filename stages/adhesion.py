"""Stage ``adhesion``: effective interfacial energy, contact area at zero load, and the
roughness at which adhesion vanishes (Persson & Tosatti 2001, extended to two rough surfaces;
seed eqs 5-14, 42, 50).

Kernels: :mod:`roughcontact.physics.adhesion` (full contact, eqs 11-14) and
:mod:`roughcontact.physics.volterra` (partial contact: eq 9 with eq 13, solved by a forward
march). Figures: :mod:`roughcontact.stages.figures.adhesion` (seed Figs 1 and 2).
See docs/adhesion.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.adhesion import (
    MODELS,
    AdhesionProblem,
    adhesion_length,
    elastic_energy_coefficients,
    layer_resolving_offset,
    zeta_grid,
)
from roughcontact.physics.volterra import solve_partial_contact, vanishing_hrms_from_sweep
from roughcontact.stage import (
    ComputationError,
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

from .figures.adhesion import figure_one_surface, figure_two_surfaces
from .shared.material import COATING_KEYS, MATERIAL_KEYS, e_star, refuse_coating

# ----------------------------------------------------------------------------------------
# Scene sections
# ----------------------------------------------------------------------------------------


def _check_adhesion(values: dict, key: str) -> None:
    if values.get("delta_gamma") is not None and values.get("delta") is not None:
        raise UserError("give one of 'delta_gamma' and 'delta', not both (delta = 4 Delta_gamma / E*)", key=key)
    models = values.get("model", ())
    if not models:
        raise UserError("needs at least one model", key=f"{key}.model")
    for m in models:
        if m not in MODELS:
            raise UserError(f"{m!r} is not one of {', '.join(map(repr, MODELS))}", key=f"{key}.model")
    if len(set(models)) != len(models):
        raise UserError("a model is listed twice", key=f"{key}.model")


register_section(
    Section(
        "adhesion",
        (
            Param("delta_gamma", "quantity", "J/m^2", default=None, lo=0.0, lo_open=True,
                  doc="interfacial binding energy of flat surfaces, e.g. \"100 meV/angstrom^2\""),
            Param("delta", "quantity", "m", default=None, lo=0.0, lo_open=True,
                  doc="adhesion length 4 Delta_gamma / E* (instead of delta_gamma)"),
            Param("sigma0", "quantity", "Pa", default=0.0, lo=0.0,
                  doc="nominal compressive stress (0: zero external load, seed Figs 1b, 2b)"),
            Param("model", "list", default=("alpha",),
                  doc="elastic-energy factor S_el in eq 10: 'alpha' (constant, the seed) and/or 'yang_persson'"),
            Param("alpha", "quantity", "", default=1.0, lo=0.0, hi=1.0, lo_open=True,
                  doc="S_el of the 'alpha' model (seed: of order 1; 1 = full-contact elastic energy)"),
            Param("gamma", "quantity", "", default=0.45, lo=0.0, hi=1.0,
                  doc="gamma of the 'yang_persson' model S_el = gamma + (1 - gamma) P^2"),
            Param("vanishing_hrms", "bool", default=False,
                  doc="find the substrate hrms at which adhesion vanishes (needs a substrate.hrms sweep reaching it)"),
        ),
        doc="the adhesion stage (docs/theory.md, section 'Adhesion')",
        check=_check_adhesion,
    )
)
register_params(
    "numerics",
    Param("adhesion_points_per_decade", "int", default=10, lo=2, presets={"fast": 5, "accurate": 20},
          ladder=(3, 4, 5, 7, 10, 14, 20, 28),  # the presets at rungs 2, 4, 6; 40 (minutes) is not needed
          doc="adhesion: Volterra nodes per decade of (zeta - 1)"),
    Param("adhesion_zeta_offset", "quantity", "", default=1e-10, lo=0.0, lo_open=True, hi=1e-2,
          doc="adhesion: smallest zeta - 1 of the Volterra grid (geometric refinement towards zeta = 1)"),
    Param("adhesion_K_min", "quantity", "", default=1e-8, lo=0.0, lo_open=True, hi=1e-3,
          doc="adhesion: smallest gamma_eff(1)/(F Delta_gamma) taken as attached (the vanishing-hrms continuation "
              "point)"),
    Param("adhesion_tolerance", "quantity", "", default=1e-10, lo=0.0, lo_open=True, hi=1e-3,
          doc="adhesion: tolerance of the root-finding (residual of eq 13 at zeta1; relative in hrms)"),
)


# ----------------------------------------------------------------------------------------
# Partial contact over the sweep
# ----------------------------------------------------------------------------------------


def _where(labels, names, bad) -> str:
    """Coordinates of the first failing case, for error messages."""
    i = int(np.flatnonzero(bad)[0])
    parts = [f"{n}={np.ravel(v)[i] if np.ndim(v) else v}" for n, v in zip(names, labels, strict=True)]
    return ", ".join(parts) or "the only case"


def _partial_kernel(C, c0, c1, *labels, q, E_star, delta_gamma, sigma0, zeta, K_min, tol, names, progress=None):
    """apply_ufunc kernel: the partial-contact solution for every case of the sweep, in SI
    (gamma_eff(1), P(zeta), gamma_eff(zeta), sigma_a(zeta), full-contact gamma_eff, F)."""
    shape = np.broadcast_shapes(C.shape[:-1], np.shape(c0), np.shape(c1), *(np.shape(v) for v in labels))
    Cf = np.broadcast_to(C, shape + C.shape[-1:]).reshape(-1, C.shape[-1])
    c0f = np.broadcast_to(c0, shape).reshape(-1)
    c1f = np.broadcast_to(c1, shape).reshape(-1)
    prob = AdhesionProblem(q, Cf, E_star, delta_gamma, zeta)
    try:
        sol = solve_partial_contact(prob, sigma0, c0f, c1f, K_min=K_min, tol=tol, progress=progress)
    except ComputationError as exc:
        lab = [np.broadcast_to(v, shape).reshape(-1) for v in labels]
        where = _where(lab, names, exc.failed) if hasattr(exc, "failed") else "?"
        raise ComputationError(f"adhesion stage at {where}: {exc}") from None
    if np.any(sol["node_residual"] > 1e-8):
        lab = [np.broadcast_to(v, shape).reshape(-1) for v in labels]
        bad = sol["node_residual"] > 1e-8
        raise ComputationError(f"adhesion stage at {_where(lab, names, bad)}: the node equation of eq 9 did not "
                               f"converge (residual {sol['node_residual'].max():.3g})")
    M = zeta.size
    sigma_u = np.sqrt(prob.sigma_u2)
    return (
        sol["K"].reshape(shape) * delta_gamma,
        sol["P"].reshape(shape + (M,)),
        (sol["gamma_ratio"] * delta_gamma).reshape(shape + (M,)),
        (sol["sigma"] * sigma_u).reshape(shape + (M,)),
        (prob.full * delta_gamma).reshape(shape),
        prob.F.reshape(shape),
    )


def _partial(C, c0, c1, nodes, **kwargs):
    """The partial-contact results over the sweep dims of C (and model), with the zeta coordinate."""
    multi = "model" in c0.dims
    labels = [C[d] if d in C.coords else xr.DataArray(np.arange(C.sizes[d]), dims=(d,)) for d in C.dims if d != "q"]
    if multi:
        labels.append(c0["model"])
    names = [str(d) for d in C.dims if d != "q"] + (["model"] if multi else [])
    results = xr.apply_ufunc(
        _partial_kernel, C, c0, c1, *labels,
        input_core_dims=[["q"], [], []] + [[] for _ in labels],
        output_core_dims=[[], ["zeta"], ["zeta"], ["zeta"], [], []],
        dask="parallelized", output_dtypes=[float] * 6,
        dask_gufunc_kwargs={"output_sizes": {"zeta": nodes.size}},
        kwargs=dict(zeta=nodes, names=names, **kwargs),
    )
    zeta = xr.DataArray(nodes, dims=("zeta",), attrs={"comment": "nodes of the Volterra grid of eq 9"})
    return [r.assign_coords(zeta=zeta) if "zeta" in r.dims else r for r in results]


def _binding_energy(spec, E_star):
    """Delta_gamma (J/m^2) and delta (m) from whichever of the two the scene gives (eq 14)."""
    dg, delta = spec["delta_gamma"], spec["delta"]
    if dg is None and delta is None:
        raise UserError("give delta_gamma (e.g. \"100 meV/angstrom^2\") or delta (the adhesion length)", key="adhesion")
    if dg is None:
        dg = delta * E_star / 4.0
    return dg, adhesion_length(dg, E_star)


def _models(spec):
    """The model coordinate and the S_el coefficients c0, c1 (over dimension model if several)."""
    models = tuple(spec["model"])
    coefs = [elastic_energy_coefficients(m, spec["alpha"], spec["gamma"]) for m in models]
    attrs = {"description": "; ".join(f"{m}: {MODELS[m]}" for m in models)}
    if len(models) == 1:
        return xr.DataArray(models[0], attrs=attrs), xr.DataArray(coefs[0][0]), xr.DataArray(coefs[0][1])
    model = xr.DataArray(list(models), dims=("model",), attrs=attrs)
    c0 = xr.DataArray([c[0] for c in coefs], dims=("model",), coords={"model": model})
    c1 = xr.DataArray([c[1] for c in coefs], dims=("model",), coords={"model": model})
    return model, c0, c1


def check_adhesion(inp: StageInput) -> None:
    """The binding energy is given, and the vanishing hrms is sought at zero load; no coating."""
    refuse_coating(inp, "the adhesion stage")
    spec = inp["adhesion"]
    _binding_energy(spec, e_star(inp))
    if spec["vanishing_hrms"] and spec["sigma0"] != 0:
        raise UserError("the hrms at which adhesion vanishes is defined at zero load: set adhesion.sigma0 = 0 "
                        "or adhesion.vanishing_hrms = false", key="adhesion.vanishing_hrms")


def describe_adhesion(inp: StageInput) -> Shape:
    """The size of the Volterra grid of magnifications (approximate: its offset is adapted to the
    spectrum when it computes), and the models compared; the vanishing hrms needs the spectra
    over a substrate hrms sweep."""
    spec, psd = inp["adhesion"], inp.upstream["psd"]
    if spec["vanishing_hrms"] and psd.sizes.get("hrms_substrate", 0) < 2:
        raise UserError("needs substrate.hrms as a sweep (a list or {from, to, num}) that reaches detachment",
                        key="adhesion.vanishing_hrms")
    lo, hi = psd.ranges["q"]
    nodes = zeta_grid(hi / lo, inp["numerics.adhesion_points_per_decade"], inp["numerics.adhesion_zeta_offset"])
    return Shape(sizes={"zeta": int(nodes.size), **({"model": len(spec["model"])} if len(spec["model"]) > 1 else {})},
                 keys={"zeta": "numerics.adhesion_points_per_decade", "model": "adhesion.model"}, approximate=("zeta",))


def compute_adhesion(inp: StageInput) -> xr.Dataset:
    psd = inp.upstream["psd"]
    q = psd["q"].values
    E_star = e_star(inp)
    spec = inp["adhesion"]
    dg, delta = _binding_energy(spec, E_star)
    sigma0 = spec["sigma0"]
    K_min, tol = inp["numerics.adhesion_K_min"], inp["numerics.adhesion_tolerance"]
    C_all = psd["psd_combined"].values.reshape(-1, q.size)
    offset = layer_resolving_offset(q, C_all, E_star, dg, inp["numerics.adhesion_zeta_offset"], K_min, sigma0)
    nodes = zeta_grid(q[-1] / q[0], inp["numerics.adhesion_points_per_decade"], offset)
    model, c0, c1 = _models(spec)
    g1, P, g, sa, full, F = _partial(psd["psd_combined"], c0, c1, nodes, q=q, E_star=E_star, delta_gamma=dg,
                                     sigma0=sigma0, K_min=K_min, tol=tol,
                                     progress=inp.progress("partial-contact marches", unit="march"))
    if "model" in full.dims:  # the full-contact theory and F do not depend on the S_el model
        full, F = full.isel(model=0, drop=True), F.isel(model=0, drop=True)
    ds = xr.Dataset({
        "gamma_eff_macroscopic": g1, "gamma_eff_full_contact": full,
        "adhesive_contact_area_ratio": P.isel(zeta=-1, drop=True),
        "adhesive_area_ratio_zeta": P, "gamma_eff": g, "detachment_stress": sa, "surface_area_factor": F,
    }).assign_coords(model=model)
    ds["delta_gamma"] = xr.DataArray(dg)
    ds["adhesion_length"] = xr.DataArray(delta)
    ds.attrs["elastic_energy_model"] = model.attrs["description"]
    ds.attrs["load"] = "zero load" if sigma0 == 0 else f"nominal stress sigma0 = {sigma0:g} Pa"
    if spec["vanishing_hrms"]:
        ds = ds.compute()
        ds["hrms_substrate_vanishing"] = _vanishing(ds, psd, c0, c1, q, E_star, dg, nodes, K_min, tol, sigma0,
                                                    inp.progress("vanishing-hrms marches", unit="march"))
    return ds


# ----------------------------------------------------------------------------------------
# Where adhesion vanishes
# ----------------------------------------------------------------------------------------


def _vanishing_kernel(K, C1, C2, eta, c0, c1, *, hs, **kwargs):
    """apply_ufunc kernel: broadcast the cases (leading dims) and find each one's vanishing hrms."""
    shape = np.broadcast_shapes(K.shape[:-1], C1.shape[:-2], C2.shape[:-1], np.shape(eta), np.shape(c0), np.shape(c1))
    n = hs.size
    Kf = np.broadcast_to(K, shape + K.shape[-1:]).reshape(-1, n)
    B = Kf.shape[0]
    h, status = vanishing_hrms_from_sweep(
        Kf, np.broadcast_to(C1, shape + C1.shape[-2:]).reshape(B, n, -1),
        np.broadcast_to(C2, shape + C2.shape[-1:]).reshape(B, -1),
        *(np.broadcast_to(v, shape).reshape(-1) for v in (eta, c0, c1)), hs, **kwargs)
    return h.reshape(shape), status.reshape(shape)


def _vanishing(ds, psd, c0, c1, q, E_star, dg, nodes, K_min, tol, sigma0, progress=None):
    """The substrate hrms at which adhesion vanishes, per case (zero load and an hrms sweep: checked by
    validate_adhesion); a UserError when the sweep does not bracket it."""
    hs = psd["hrms_substrate"].values
    order = np.argsort(hs)
    K = ds["gamma_eff_macroscopic"].isel(hrms_substrate=order)
    C1 = psd["psd_substrate"].isel(hrms_substrate=order)
    C2 = psd["psd_solid"]
    eta = psd["eta"] if "eta" in psd.coords else xr.DataArray(0.0)
    try:
        h, status = xr.apply_ufunc(
            _vanishing_kernel, K, C1, C2, eta, c0, c1,
            input_core_dims=[["hrms_substrate"], ["hrms_substrate", "q"], ["q"], [], [], []],
            output_core_dims=[[], []], output_dtypes=[float, int],
            kwargs=dict(hs=hs[order], q=q, E_star=E_star, delta_gamma=dg, zeta=nodes, K_min=K_min, tol=tol,
                        progress=progress),
        )
    except ComputationError as exc:
        cases = ", ".join(f"{d} = {list(np.atleast_1d(K[d].values))}"
                          for d in K.dims if d != "hrms_substrate" and d in K.coords)
        raise ComputationError(f"adhesion stage, hrms at which adhesion vanishes ({cases or 'one case'}): "
                               f"{exc}") from None
    flat = np.ravel(status.values)
    if np.any(flat != 0):
        first = int(np.flatnonzero(flat)[0])
        index = np.unravel_index(first, status.shape) if status.ndim else ()
        where = ", ".join(f"{d} = {status[d].values[i]:g}" if status[d].dtype.kind == "f"
                          else f"{d} = {status[d].values[i]}"
                          for d, i in zip(status.dims, index, strict=True) if d in status.coords)
        more = int(np.count_nonzero(flat)) - 1
        why = (f"still attached at the largest swept substrate hrms {hs.max() * 1e10:.4g} angstrom: extend the sweep"
               if flat[first] == 1 else
               f"already detached at the smallest swept substrate hrms {hs.min() * 1e10:.4g} angstrom: start the "
               "sweep lower")
        at = f" at {where}" if where else ""
        also = f" (and {more} more case(s))" if more else ""
        raise UserError(f"cannot find the hrms at which adhesion vanishes{at}{also}: the partial-contact solution "
                        f"is {why}",
                        key="adhesion.vanishing_hrms")
    return h


# ----------------------------------------------------------------------------------------
# The stage
# ----------------------------------------------------------------------------------------

STAGE = register(
    Stage(
        name="adhesion",
        version="1",
        compute=compute_adhesion,
        check=check_adhesion,
        describe=describe_adhesion,
        needs=("psd",),
        reads=(*MATERIAL_KEYS, *COATING_KEYS, "adhesion", "numerics.adhesion_points_per_decade",
                "numerics.adhesion_zeta_offset", "numerics.adhesion_K_min", "numerics.adhesion_tolerance"),
        outputs={
            "gamma_eff_macroscopic": Var("J/m^2", "effective interfacial energy gamma_eff(1)",
                                         comment="at the lowest magnification, partial-contact theory, at "
                                                 "the nominal stress sigma0; eqs 9, 13"),
            "gamma_eff_full_contact": Var("J/m^2", "effective interfacial energy, full contact",
                                          comment="full-contact theory: Delta_gamma [F - (2 pi/delta) int "
                                                  "q^2 C dq]; eq 13 with P = S = 1"),
            "adhesive_contact_area_ratio": Var("1", "relative contact area A/A0 with adhesion",
                                               comment="P(zeta1), at the highest magnification, at the "
                                                       "nominal stress sigma0 (zero load by default)"),
            "adhesive_area_ratio_zeta": Var("1", "contact area P(zeta) with adhesion",
                                            comment="relative apparent contact area P(zeta) = A(zeta)/A0 "
                                                    "at the nominal stress sigma0; eqs 8-9"),
            "gamma_eff": Var("J/m^2", "effective interfacial energy gamma_eff(zeta)",
                             comment="partial contact; eq 13 corrected; NaN where P = 0"),
            "detachment_stress": Var("Pa", "detachment stress sigma_a(zeta)",
                                     comment="sigma_a = (gamma_eff E* zeta qL)^(1/2), eq 6; 0 where "
                                             "gamma_eff <= 0"),
            "surface_area_factor": Var("1", "surface-area factor F",
                                       comment="F = 1 + (sqrt(pi) xi/2) erfcx(1/xi), eq 11"),
            "delta_gamma": Var("J/m^2", "interfacial binding energy Delta_gamma",
                               comment="of flat surfaces"),
            "adhesion_length": Var("m", "adhesion length delta",
                                   comment="delta = 4 Delta_gamma / E*, eq 14"),
            "hrms_substrate_vanishing": Var("m", "substrate rms roughness for vanishing adhesion",
                                            comment="the substrate rms roughness at which adhesion "
                                                    "vanishes: gamma_eff(1) and A/A0 reach 0 together; root "
                                                    "along the attached branch, zero load",
                                            tolerance=1e-3),
        },
        coords={"model": Var("1", "elastic-energy factor model S_el", comment="eq 10")},
        figures=(
            Figure("fig1_adhesion_one_surface", "gamma_eff and A/A0 at zero load, one rough surface (seed Fig. 1)",
                   ("adhesion",), figure_one_surface),
            Figure("fig2_adhesion_two_surfaces", "gamma_eff and A/A0 at zero load, two rough surfaces (seed Fig. 2)",
                   ("adhesion",), figure_two_surfaces),
        ),
        doc="gamma_eff (full and partial contact), P(zeta), sigma_a(zeta), A/A0 at zero load, and the hrms at which "
            "adhesion vanishes.",
    )
)
