"""The bem stage's surface hardness (contact.yield_stress): the saturated BEM on the same map
pairs as the elastic one, against the elastoplastic theory at the BEM's magnification.

Facts checked: the hardness out of reach gives the elastic BEM's contact area (two solvers,
Tamaas' and physics/bem_cg.py, through the stage); A_pl sigma_Y <= p (the capped spots carry
at most the load); A_pl/A0 = 1 at p >= sigma_Y on both sides; the theory columns are the
contact stage's elastic and plastic areas at the same zeta; the figure draws; asking for the
outputs without a hardness is refused before anything is written.
"""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact import scene as scenes
from roughcontact.stage import UserError
from roughcontact.stages.figures.bem import figure_bem_elastoplastic
from roughcontact.stages.shared.bem_hardness import PLASTIC, PLASTIC_REALIZATIONS

pytest.importorskip("tamaas")

WANTED = [n for n in PLASTIC if n not in PLASTIC_REALIZATIONS] + [
    "bem_contact_area_ratio", "elastic_contact_area_ratio", "plastic_contact_area_ratio"]


def small_scene(yield_stress="1.2 GPa", p=("12 MPa", "120 MPa", "600 MPa", "2.4 GPa")):
    raw = dict(scenes.load("elastoplastic_bem").raw)
    raw["bem"] = {"grid": 32, "realizations": 2, "seed": 3, "pixels_per_wavelength": 3.2}  # zeta = 10, as the scene
    raw["load"] = {"p": list(p)}
    raw["contact"] = {**raw["contact"], "yield_stress": yield_stress}
    raw["outputs"] = {"variables": WANTED}
    return raw


@pytest.mark.filterwarnings("ignore:load.p reaches")
def test_stage_elastoplastic_bem(run_scene, tmp_path):
    res = run_scene(small_scene(), outdir=tmp_path / "a")
    bem, contact = res["base"]["bem"].squeeze(drop=True), res["base"]["contact"].squeeze(drop=True)
    p, Y = bem["p"].values, 1.2e9
    pl = bem["bem_plastic_contact_area_ratio_mean"].values
    el = bem["bem_elastic_contact_area_ratio_mean"].values
    below = p < Y
    assert np.all(pl[below] * Y <= p[below] * (1 + 1e-9)) and np.all(pl[below] > 0) and np.all(el[below] > 0)
    assert np.all(pl[~below] == 1.0) and np.all(el[~below] == 0.0)
    assert np.all(bem["theory_plastic_contact_area_ratio"].values[~below] == 1.0)
    for kind in ("elastic", "plastic"):  # the theory is the contact stage's at the BEM's zeta
        np.testing.assert_allclose(bem[f"theory_{kind}_contact_area_ratio"].values,
                                   contact[f"{kind}_contact_area_ratio"].values,
                                   rtol=1e-12)
    assert np.all(np.diff(pl) > 0)  # more load, more yielded area
    fig = figure_bem_elastoplastic(res)
    assert len(fig.axes) == 2


def test_hardness_out_of_reach_is_the_elastic_bem(run_scene, tmp_path):
    """A hardness far above every local pressure: the saturated solver (numpy) finds the same
    contact area as Tamaas' elastic solver, pixel for pixel on average, and nothing yields."""
    bem = run_scene(small_scene(yield_stress="1e6 GPa", p=("12 MPa", "120 MPa")), outdir=tmp_path / "b")["base"]["bem"]
    bem = bem.squeeze(drop=True)
    assert np.all(bem["bem_plastic_contact_area_ratio_mean"].values == 0)
    np.testing.assert_allclose(bem["bem_elastic_contact_area_ratio_mean"].values,
                               bem["bem_contact_area_ratio_mean"].values, rtol=0, atol=1e-12)


def test_plastic_outputs_need_a_hardness(run_scene, tmp_path):
    raw = small_scene()
    raw["contact"] = {k: v for k, v in raw["contact"].items() if k != "yield_stress"}
    raw["outputs"] = {"variables": ["bem_plastic_contact_area_ratio_mean"]}
    with pytest.raises(UserError, match="contact.yield_stress"):
        run_scene(raw, outdir=tmp_path / "c")
    assert not any((tmp_path / "c").rglob("*.nc"))
