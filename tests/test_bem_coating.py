"""The bem stage on a coated solid (material.coating_*): the Polonsky-Keer solver with the layered
surface compliance 2 / (q E_eff(q)) (physics/bem_coated.py) on the same synthesized pairs,
compared with the theory that uses the same E_eff(q).

Facts checked: a layer of the substrate's own material is the half-space, and Tamaas' half-space
solution is reproduced to 1e-8; a vanishing layer is the bare substrate and a thick one (d qL >> 1)
the layer's half-space; a thin soft layer gives an area between the two half-spaces; through the
stage, the theory columns are the contact and separation stages' (which take E_eff), the solver
is recorded, a coating of the substrate's material gives the homogeneous scene's results, the
homogeneous path is Tamaas' solve bit for bit, and the stages that share the BEM's
check without a layered kernel still refuse a coating before anything is written.
"""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact.physics.bem_coated import coated_contact_pair
from roughcontact.physics.synthesis import grid_band, synthesize_pair, white_noise_pair
from roughcontact.stage import UserError

tamaas = pytest.importorskip("tamaas")

from roughcontact.physics.bem import contact_pair  # noqa: E402

E, NU = 100e9, 0.3
E_STAR = E / (1 - NU**2)
QL = 1e5


def _pair(n=64, seed=1):
    """A synthesized self-affine pair (the substrate rough, the solid flat) on an n x n map of side 2 pi / qL."""
    q = np.geomspace(QL, 1e8, 300)
    C = np.where(q < 4 * QL, 1.0, (q / (4 * QL)) ** -2.6) * 1e-28
    _, dx, q_cut, zeta = grid_band(q[0], q[-1], n, 4)
    h1, h2 = synthesize_pair(q, C, 0 * C, 0.0, n, q_cut, noise=white_noise_pair(n, seed, 0, band=zeta))
    return h1, h2, dx


P = np.array([3e6, 1e7, 3e7])  # A/A0 from ~1 % to ~15 % on the 100 GPa solid


def test_layer_of_the_substrate_material_is_tamaas_half_space():
    h1, h2, dx = _pair()
    edges = np.linspace(0, 1, 21)[None, :] * (3 * P[:, None])
    ref = contact_pair(h1, h2, dx, E_STAR, P, tolerance=1e-12, stress_edges=edges)
    for d in (1e-7, 1e-5, 1e-3):  # d qL = 0.01, 1, 100: any thickness
        got = coated_contact_pair(h1, h2, dx, (d, E, NU, E, NU), P, tolerance=1e-12, stress_edges=edges)
        np.testing.assert_array_equal(got["area"], ref["area"])
        np.testing.assert_allclose(got["mean_gap"], ref["mean_gap"], rtol=1e-8)
        np.testing.assert_allclose(got["histogram"], ref["histogram"], rtol=0, atol=1e-8 * ref["histogram"].max())
    assert 0.005 < ref["area"][0] < ref["area"][-1] < 0.5  # partial contact: the check means something


@pytest.mark.parametrize("limit", ["thin", "thick"])
def test_thickness_limits_are_the_half_spaces(limit):
    """d -> 0: the substrate's half-space; d qL = 50 (exp(-2 q d) < 1e-43 at every q of the map): the
    layer's. A soft (10 GPa) layer on the 100 GPa substrate, both solved by Tamaas for reference."""
    h1, h2, dx = _pair()
    E_layer = 10e9
    d, E_ref = (1e-15, E_STAR) if limit == "thin" else (50 / QL, E_layer / (1 - NU**2))
    ref = contact_pair(h1, h2, dx, E_ref, P, tolerance=1e-12)
    got = coated_contact_pair(h1, h2, dx, (d, E_layer, NU, E, NU), P, tolerance=1e-12)
    np.testing.assert_array_equal(got["area"], ref["area"])
    np.testing.assert_allclose(got["mean_gap"], ref["mean_gap"], rtol=1e-7)


def test_a_thin_soft_layer_lies_between_the_two_half_spaces():
    """A soft layer thinner than the map's wavelengths (d q_cut <= 5): more contact than the bare
    substrate, less than the layer's half-space, more the thicker it is. (Not a theorem for any
    thickness: at d qL = 1 the BEM finds 1 % more area than the layer's half-space at A/A0 = 0.26.)"""
    h1, h2, dx = _pair()
    E_layer = 10e9
    stiff = contact_pair(h1, h2, dx, E_STAR, P, tolerance=1e-10)["area"]
    soft = contact_pair(h1, h2, dx, E_layer / (1 - NU**2), P, tolerance=1e-10)["area"]
    areas = np.array([coated_contact_pair(h1, h2, dx, (x / QL, E_layer, NU, E, NU), P, tolerance=1e-10)["area"]
                      for x in (0.03, 0.1, 0.3)])
    assert np.all(areas > stiff) and np.all(areas < soft)
    assert np.all(np.diff(areas, axis=0) > 0)


# --- through the stage ------------------------------------------------------------------------


def small_scene(coating=None, outputs=("bem_contact_area_ratio", "contact_area_ratio", "mean_separation")):
    """The coating_bem scene's surfaces and pressures on a 32 x 32 map (zeta = 8), one coherence."""
    from roughcontact import scene as scenes

    raw = dict(scenes.load("coating_bem").raw)
    raw.pop("variants", None)
    raw["bem"] = {"grid": 32, "realizations": 2, "seed": 3, "pixels_per_wavelength": 4}
    raw["contact"] = {"zeta": [8.0]}
    raw["outputs"] = {"variables": list(outputs)}
    material = {"E": "100 GPa", "nu": 0.3}
    if coating is not None:
        material.update(coating)
    raw["material"] = material
    return raw


SOFT = {"coating_thickness": "10 um", "coating_E": "10 GPa", "coating_nu": 0.3}


def test_stage_solves_the_coated_solid_against_the_layered_theory(run_scene, tmp_path):
    res = run_scene(small_scene(SOFT), outdir=tmp_path / "a")["base"]
    bem, contact, sep = res["bem"], res["contact"], res["separation"]
    assert "bem_coated" in bem.attrs["bem_solver"] and "E_eff" in bem.attrs["bem_solver"]
    assert bem.attrs["coating_thickness_m"] == pytest.approx(1e-5)
    np.testing.assert_allclose(bem["theory_contact_area_ratio"].values,
                               contact["contact_area_ratio"].squeeze(drop=True).values, rtol=1e-12)
    np.testing.assert_allclose(bem["theory_mean_separation"].values,
                               sep["mean_separation"].squeeze(drop=True).values, rtol=1e-12)
    persson = bem["theory_variant_contact_area_ratio"].sel(theory="persson").values
    np.testing.assert_allclose(persson, bem["theory_contact_area_ratio"].values, rtol=1e-9)  # variants take E_eff
    # the coated solid is softer than its substrate: more contact than the bare 100 GPa solid
    bare = run_scene(small_scene(), outdir=tmp_path / "b")["base"]["bem"]
    assert "tamaas" in bare.attrs["bem_solver"] and "coating_thickness_m" not in bare.attrs
    assert np.all(bem["bem_contact_area_ratio_mean"].values > bare["bem_contact_area_ratio_mean"].values)
    assert np.all(bem["theory_contact_area_ratio"].values > bare["theory_contact_area_ratio"].values)


def test_a_coating_of_the_substrate_material_is_the_homogeneous_result(run_scene, tmp_path):
    same = {"coating_thickness": "10 um", "coating_E": "100 GPa", "coating_nu": 0.3}
    coated = run_scene(small_scene(same), outdir=tmp_path / "a")["base"]["bem"]
    bare = run_scene(small_scene(), outdir=tmp_path / "b")["base"]["bem"]
    np.testing.assert_array_equal(coated["bem_contact_area_ratio"].values, bare["bem_contact_area_ratio"].values)
    for name in ("bem_mean_gap", "theory_contact_area_ratio", "theory_mean_separation"):
        np.testing.assert_allclose(coated[name].values, bare[name].values, rtol=1e-8, err_msg=name)


def test_the_homogeneous_path_is_tamaas_bit_for_bit(run_scene, tmp_path):
    """No coating: the stage's areas and gaps are Tamaas' solve of the same synthesized maps, exactly."""
    from roughcontact.stages.shared.bem_solve import map_pairs

    bem = run_scene(small_scene(), outdir=tmp_path / "a")["base"]
    psd, out = bem["psd"], bem["bem"]
    q = psd["q"].values
    C1, C2 = psd["psd_substrate"].values.squeeze(), psd["psd_solid"].values.squeeze()
    n, L = int(out["bem_grid"]), float(out["bem_system_size"])
    band = {"n": n, "R": 2, "seed": 3, "zeta": float(out["bem_zeta"]), "q_cut": float(out["bem_q_cut"]), "maps": None}
    p = out["p"].values
    for _, r, h1, h2 in map_pairs(band, q, C1, C2, np.array([0.0])):
        ref = contact_pair(h1, h2, L / n, float(out["E_star"]), p, tolerance=1e-10)
        np.testing.assert_array_equal(out["bem_contact_area_ratio"].isel(realization=r).values, ref["area"])
        np.testing.assert_array_equal(out["bem_mean_gap"].isel(realization=r).values, ref["mean_gap"])


def test_interface_bem_still_refuses_a_coating(run_scene, tmp_path):
    from roughcontact import scene as scenes

    raw = dict(scenes.load("interface_bem").raw)
    raw["material"] = {**raw["material"], **SOFT}
    with pytest.raises(UserError, match="coating"):
        run_scene(raw, outdir=tmp_path / "c")
    assert not any((tmp_path / "c").rglob("*.nc"))



def test_the_saturated_solve_takes_the_layered_kernel_too(run_scene, tmp_path):
    """A hardness far above every local pressure: the saturated BEM of the coated solid finds the
    elastic coated BEM's contact area (both with the layered kernel; with the half-space's it would
    find the bare substrate's, less)."""
    raw = small_scene(SOFT, outputs=("bem_contact_area_ratio", "bem_elastic_contact_area_ratio_mean",
                                     "bem_plastic_contact_area_ratio_mean"))
    raw["contact"] = {**raw["contact"], "yield_stress": "1e6 GPa"}
    bem = run_scene(raw, outdir=tmp_path / "a")["base"]["bem"]
    assert np.all(bem["bem_plastic_contact_area_ratio_mean"].values == 0)
    np.testing.assert_allclose(bem["bem_elastic_contact_area_ratio_mean"].values,
                               bem["bem_contact_area_ratio_mean"].values, rtol=0, atol=1e-12)
    assert "E_eff" in bem["bem_elastic_contact_area_ratio_mean"].attrs["bem_solver"]
