"""The theory read at the BEM's magnification, for the ``bem`` stage's comparison: the contact and
separation stages' results at zeta_bem = q_cut / qL (which the scene must list in ``contact.zeta``),
as (p, eta) arrays, and every theory variant (:mod:`roughcontact.stages.shared.variants`) with its
ratio to the BEM.

Not a stage (it registers nothing). See docs/bem.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.stage import UserError

from .material import coating_layer
from .variants import VARIANTS, theory_variants, variant_attrs


def zeta_index(values, zeta: float, stage: str, set_by: str) -> int:
    """Where the theory stage's magnifications hold the BEM's zeta; a UserError if they do not."""
    hit = np.flatnonzero(np.isclose(np.atleast_1d(values), zeta, rtol=1e-9, atol=0.0))
    if hit.size == 0:
        raise UserError(
            f"the {stage} stage has no magnification zeta = {zeta:.10g}, the band the BEM map resolves "
            f"(q_cut / qL, set by {set_by}); add {zeta:.10g} to contact.zeta", key="contact.zeta")
    return int(hit[0])


def at_zeta(ds: xr.Dataset, var: str, zeta: float, stage: str, set_by: str) -> xr.DataArray:
    """A theory variable at the BEM's magnification, which the stage must have computed."""
    da = ds[var]
    if "zeta" not in da.dims and "zeta" not in da.coords:
        return da
    index = zeta_index(da["zeta"].values, zeta, stage, set_by)
    return da.isel(zeta=index) if "zeta" in da.dims else da



def on_p_eta(da: xr.DataArray, p_values, eta_values, has_eta) -> np.ndarray:
    """A theory variable as a (p, eta) array."""
    if "p" not in da.dims:
        da = da.expand_dims(p=p_values)
    if has_eta:
        return da.transpose("p", "eta").values
    return np.asarray(da.transpose("p").values)[:, None] * np.ones(np.size(eta_values))



def with_variants(inp, ds, psd, q, zeta_bem, p_values, has_eta, E_star) -> xr.Dataset:
    """Every theory variant (eq 19 / eq 57 and each correction) at the BEM's magnification, and
    its ratio to the BEM, over (p, eta, theory)."""
    C = psd["psd_combined"]
    rows = C.transpose("eta", "q").values if has_eta else np.atleast_2d(C.values)
    area, gap = theory_variants(inp, q, rows, zeta_bem * q[0], p_values, E_star, layer=coating_layer(inp))
    dims = ("p", "eta", "theory")
    ds = ds.assign_coords(theory=list(VARIANTS))
    ds["theory_variant_contact_area_ratio"] = (dims, area)
    ds["theory_variant_mean_separation"] = (dims, gap)
    with np.errstate(divide="ignore", invalid="ignore"):
        ds["area_ratio_variant_to_bem"] = (dims, area / ds["bem_contact_area_ratio_mean"].values[..., None])
        ds["separation_ratio_variant_to_bem"] = (dims, gap / ds["bem_mean_gap_mean"].values[..., None])
    ds.attrs.update(variant_attrs(inp))
    return ds
