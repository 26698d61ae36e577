"""Helpers shared by the stages' figures (not a stage: the name starts with an underscore)."""

from __future__ import annotations


def curve_cases(results, stage: str):
    """(label, Dataset) per curve of a seed-style comparison figure: the ``substrate_only``
    variant first if the scene has it, then one curve per eta of the base scene (or one curve
    when eta is not a dimension)."""
    out = []
    if "substrate_only" in results and stage in results["substrate_only"]:
        out.append(("substrate only", results["substrate_only"][stage]))
    base = results["base"][stage]
    if "eta" in base.dims:
        out += [(f"eta = {e:+g}", base.sel(eta=e)) for e in base["eta"].values]
    else:
        out.append(("pair", base))
    return out
