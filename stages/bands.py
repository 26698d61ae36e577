"""Stage ``bands``: uncertainty bands of the predictions, from spectra drawn within the
statistical band of the measured spectra.

With ``[bands] draws = N``, the psd stage draws N spectra of each measured surface (and of a
measured coherence) within their statistical band (:mod:`roughcontact.physics.uncertainty`);
``draw`` is then a sweep dimension like eta, which every downstream stage carries (draw 0 is
the measured spectrum) and which chunks and distributes like any sweep. This stage reduces the
draws 1..N of the variables asked for (``<variable>_band`` in ``[outputs] variables``) to the
quantiles (1 - level)/2, 1/2 and (1 + level)/2 over the dimension ``quantile``. The figures of
the other stages shade the same band. See docs/measured-data.md.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from roughcontact.physics.uncertainty import quantiles
from roughcontact.stage import Figure, Stage, StageInput, Upstream, UserError, Var, register

from .adhesion import STAGE as ADHESION
from .contact import STAGE as CONTACT
from .figures.bands import (
    figure_band_contact_area,
    figure_band_friction,
    figure_band_psd,
    figure_band_separation,
    figure_band_stress,
)
from .friction import STAGE as FRICTION
from .psd import STAGE as PSD
from .separation import STAGE as SEPARATION

#: the variables that get a band, by the stage that computes them
BANDED = (
    (PSD, ("psd_combined", "hrms_combined", "rms_slope_combined")),
    (CONTACT, ("contact_area_ratio", "G", "stress_distribution")),
    (SEPARATION, ("mean_separation",)),
    (ADHESION, ("gamma_eff_macroscopic", "gamma_eff_full_contact", "adhesive_contact_area_ratio",
                "adhesive_area_ratio_zeta", "hrms_substrate_vanishing")),
    (FRICTION, ("friction_coefficient", "sliding_contact_area_ratio")),
)
SOURCE = {f"{var}_band": (st, var) for st, names in BANDED for var in names}
ALWAYS = ("psd_combined_band",)
#: the band's own label where "<the source's label> (band)" would be too long for a label
_LABELS = {"psd_combined": "combined PSD C(q) (band)", "contact_area_ratio": "relative contact area A/A0 (band)",
           "G": "G(zeta) (band)", "stress_distribution": "stress distribution P(sigma) (band)",
           "hrms_substrate_vanishing": "substrate hrms for vanishing adhesion (band)"}
_COMMENT = "the coordinate quantile gives the probability levels (CF 1.11 has no cell method for quantiles)"


def _band_var(st: Stage, var: str) -> Var:
    """The band of ``var`` of stage ``st``: a short label, and in the comment what it is a band of (the
    source's label and comment)."""
    source = st.outputs[var]
    about = "; ".join(filter(None, (source.long_name, source.stamp().get("comment"))))
    comment = (f"quantiles over the dimension draw (standard_name realization) of the draws 1..N of {st.name}.{var} "
               f"({about}); {_COMMENT}")
    return Var(source.units, _LABELS.get(var, f"{source.long_name} (band)"),
               optional=f"{var}_band" not in ALWAYS, comment=comment)


def _needs() -> tuple:
    """The psd stage always; each other stage when a band of one of its variables is asked for."""
    return ("psd", *(Upstream(st.name, when={"outputs.variables": tuple(f"{v}_band" for v in names)})
                     for st, names in BANDED if st is not PSD))


def check_bands(inp: StageInput) -> None:
    """Bands need spectrum draws (``[bands] draws`` > 0)."""
    if np.ndim(inp["bands.draws"]) == 0:
        raise UserError("bands need spectrum draws: set [bands] draws (e.g. 200)", key="bands.draws")


def _on_nominal_stress_grid(da: xr.DataArray) -> xr.DataArray:
    """P(sigma) of every draw interpolated onto the stress grid of draw 0 (each draw has its own
    adaptive grid), so that quantiles are taken at fixed sigma."""
    sigma = da["sigma"]
    nominal = sigma.isel(draw=0, drop=True)
    values = xr.apply_ufunc(lambda x, xp, fp: np.interp(x, xp, fp, left=0.0, right=0.0),
                            nominal, sigma.variable, da.variable,
                            input_core_dims=[["stress_level"]] * 3, output_core_dims=[["stress_level"]],
                            vectorize=True, dask="parallelized", output_dtypes=[float])
    coords = {k: v for k, v in da.coords.items() if k != "sigma"}
    return xr.DataArray(values.transpose(*da.dims).data, dims=da.dims, coords=coords).assign_coords(sigma=nominal)


def band(da: xr.DataArray, probabilities) -> xr.DataArray:
    """Quantiles over the draws 1..N of ``da`` (dimension quantile first; draw 0, the measured
    spectrum, is the nominal prediction and is left out)."""
    draws = da.isel(draw=slice(1, None))
    if draws.chunks is not None:
        draws = draws.chunk({"draw": -1})
    out = xr.apply_ufunc(quantiles, draws, kwargs={"probabilities": np.asarray(probabilities)},
                         input_core_dims=[["draw"]], output_core_dims=[["quantile"]], dask="parallelized",
                         output_dtypes=[float], dask_gufunc_kwargs={"output_sizes": {"quantile": len(probabilities)}})
    out = xr.DataArray(np.moveaxis(out.data, -1, 0), dims=("quantile",) + out.dims[:-1],
                       coords={k: v for k, v in out.coords.items() if "draw" not in v.dims})
    return out.assign_coords(quantile=np.asarray(probabilities, dtype=float))


def compute_bands(inp: StageInput) -> xr.Dataset:
    if "draw" not in inp.upstream["psd"]["psd_combined"].dims:
        raise UserError("no surface is measured (kind 'topography' or 'container'): its spectra carry no statistical "
                        "band to draw from", key="bands.draws")
    level = float(inp["bands.level"])
    probabilities = [(1.0 - level) / 2.0, 0.5, (1.0 + level) / 2.0]
    out = {}
    for name in sorted(set(inp.wanted) | set(ALWAYS)):
        st, var = SOURCE[name]
        if var not in inp.upstream[st.name]:  # an optional output the scene did not ask for
            raise UserError(f"{name} needs {var}: add it to outputs.variables", key="outputs.variables")
        da = inp.upstream[st.name][var]
        if "draw" not in da.dims:  # does not depend on the measured spectra
            da = da.expand_dims(draw=inp.upstream["psd"]["draw"].size)
        if var == "stress_distribution":
            da = _on_nominal_stress_grid(da)
        out[name] = band(da, probabilities)
    ds = xr.Dataset(out)
    ds.attrs.update(level=level, draws=int(np.size(inp["bands.draws"]) - 1),
                    method="quantiles (linear between order statistics) over draws 1..N of spectra drawn within the "
                           "measured spectra's statistical band; draw 0 (the measured spectrum) is the nominal "
                           "prediction")
    return ds


register(
    Stage(
        name="bands",
        version="1",
        compute=compute_bands,
        needs=_needs(),
        check=check_bands,
        reads=("bands.draws", "bands.level"),
        outputs={name: _band_var(st, var) for name, (st, var) in SOURCE.items()},
        coords={"quantile": Var("1", "probability level of the quantile",
                                comment="quantile over the spectrum draws"),
                **CONTACT.coords, **ADHESION.coords},
        figures=(
            Figure("bands_psd", "Combined PSD with its uncertainty band", ("bands",), figure_band_psd),
            Figure("bands_contact_area", "A/A0(p) over the measured band, with its uncertainty band", ("bands",),
                   figure_band_contact_area, outputs=("contact_area_ratio_band",)),
            Figure("bands_separation", "u(p) over the measured band, with its uncertainty band", ("bands",),
                   figure_band_separation, outputs=("mean_separation_band",)),
            Figure("bands_stress_distribution", "P(sigma) over the measured band, with its uncertainty band",
                   ("bands",), figure_band_stress, outputs=("stress_distribution_band",)),
            Figure("bands_friction", "mu(v) with its uncertainty band", ("bands",), figure_band_friction,
                   outputs=("friction_coefficient_band",)),
        ),
        doc="Uncertainty bands: quantiles over spectra drawn within the measured spectra's statistical band.",
    )
)
