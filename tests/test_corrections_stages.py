"""The contact-area correction where other stages use a contact fraction: the separation
stage's refinement "contact" (the correction's elastic-energy factor with its gamma) and the
friction stage's P(q) (the same universal map of eq 31's argument)."""

import numpy as np
import pytest
from conftest import make_scene
from scipy.special import erf
from test_friction import _run, _scene

from roughcontact.physics.contact import persson_G
from roughcontact.physics.corrections import DEFAULT_GAMMA, corrected_area


@pytest.mark.parametrize("correction, refinement", [("persson", "none"), ("yang_persson", "yang_persson"),
                                                    ("wang_mueser", "wang_mueser")])
def test_separation_follows_the_contact_correction(run_scene, tmp_path, correction, refinement):
    """refinement = "contact" is the same as naming the refinement with alpha = the correction's
    gamma (persson: "none" with separation.alpha)."""
    common = dict(outputs={"variables": ["mean_separation"]}, load={"p": ["10 MPa", "1 GPa", "10 GPa"]},
                  interface={"eta": [0.0, -1.0]})
    follow = make_scene(**common, contact={"zeta": [4.0, 200.0], "correction": correction},
                        separation={"refinement": "contact", "alpha": 0.4})
    alpha = 0.4 if correction == "persson" else DEFAULT_GAMMA[correction]
    named = make_scene(**common, contact={"zeta": [4.0, 200.0]}, separation={"refinement": refinement, "alpha": alpha})
    a = run_scene(follow, outdir=tmp_path / "a")["base"]["separation"]
    b = run_scene(named, outdir=tmp_path / "b")["base"]["separation"]
    np.testing.assert_allclose(a["mean_separation"], b["mean_separation"], rtol=1e-14)
    assert a.attrs["separation_refinement"] == refinement and a.attrs["separation_alpha"] == pytest.approx(alpha)


def test_refinements_order_the_separation(run_scene):
    """With their published gammas both refinements raise u over eq 57 at alpha = 0.45 at small
    load (S(0) >= 0.45 and the extra terms are positive there) and all meet at high load."""
    p = ["1 MPa", "100 MPa", "10 GPa", "200 GPa"]
    out = {}
    for refinement, alpha in (("none", 0.45), ("yang_persson", 0.45), ("wang_mueser", 5 / 9)):
        sc = make_scene(outputs={"variables": ["mean_separation"]}, load={"p": p}, interface={"eta": [0.0]},
                        contact={"zeta": [200.0]}, separation={"refinement": refinement, "alpha": alpha})
        out[refinement] = run_scene(sc)["base"]["separation"]["mean_separation"].values.ravel()
    assert np.all(out["yang_persson"][:2] > out["none"][:2]) and np.all(out["wang_mueser"][:2] > out["none"][:2])
    assert np.all(np.diff(out["wang_mueser"]) < 0) and np.all(out["wang_mueser"] > 0)


def test_friction_area_uses_the_contact_correction_in_the_elastic_limit(tmp_path):
    """A real constant modulus: the sliding contact fraction is the corrected A/A0 of the
    contact theory, corrected_area(1/(2 sqrt(G / sigma0^2))), at every velocity; mu stays 0."""
    for correction in ("yang_persson", "wang_mueser"):
        raw = _scene(**{"modulus": {"kind": "elastic", "E": "7 MPa"}, "contact.correction": correction,
                        "outputs.variables": ["friction_coefficient"]})
        res = _run(raw, tmp_path / correction)
        fric, psd = res["friction"], res["psd"]
        assert np.all(fric["friction_coefficient"].values == 0.0)
        q = psd["q"].values
        G = persson_G(q, psd["psd_combined"].values, q[-1:], 7e6 / (1 - 0.25))[-1] / 0.4e6**2
        expected = corrected_area(0.5 / np.sqrt(G), correction, DEFAULT_GAMMA[correction])
        area = fric["sliding_contact_area_ratio"].values
        np.testing.assert_allclose(area, expected, rtol=1e-12)
        assert np.all(area > erf(0.5 / np.sqrt(G)))
        assert fric["sliding_contact_area_ratio"].attrs["area_correction"] == correction


def test_friction_with_a_corrected_area_has_more_contact_and_more_friction(tmp_path):
    """A larger contact fraction at every scale puts more of the spectrum in contact: mu and
    A/A0 rise over the plain theory at every velocity."""
    plain = _run(_scene(**{"outputs.variables": ["friction_coefficient"]}), tmp_path / "plain")["friction"]
    corr = _run(_scene(**{"contact.correction": "yang_persson", "outputs.variables": ["friction_coefficient"]}),
                tmp_path / "yp")["friction"]
    assert np.all(corr["sliding_contact_area_ratio"].values > plain["sliding_contact_area_ratio"].values)
    assert np.all(corr["friction_coefficient"].values > plain["friction_coefficient"].values)


def test_bem_shows_every_variant_and_reads_the_scene_choice(run_scene, tmp_path):
    """The bem stage puts every variant next to eq 19 at the BEM's magnification: persson is the
    contact/separation stages' default result, each correction raises A/A0 over it at small
    load, and with contact.correction the stage's own theory is that variant."""
    pytest.importorskip("tamaas")
    from test_bem import bem_scene

    plain = run_scene(bem_scene(), outdir=tmp_path / "plain")["base"]["bem"]
    assert list(plain["theory"].values) == ["persson", "yang_persson", "wang_mueser"]
    area = plain["theory_variant_contact_area_ratio"]
    np.testing.assert_allclose(area.sel(theory="persson"), plain["theory_contact_area_ratio"], rtol=1e-12)
    np.testing.assert_allclose(plain["theory_variant_mean_separation"].sel(theory="persson"),
                               plain["theory_mean_separation"], rtol=1e-10)
    rough = area.sel(eta=[0.0, -1.0]).isel(p=0)
    assert np.all(rough.sel(theory="yang_persson") > 1.3 * rough.sel(theory="persson"))
    assert np.all(rough.sel(theory="wang_mueser") > 1.25 * rough.sel(theory="persson"))
    np.testing.assert_allclose(plain["area_ratio_variant_to_bem"],
                               area / plain["bem_contact_area_ratio_mean"], rtol=1e-12)
    assert "gamma = 0.45" in plain.attrs["theory_variants"]
    chosen = run_scene(bem_scene(contact={"zeta": [16.0], "correction": "yang_persson"},
                                 separation={"refinement": "contact"}), outdir=tmp_path / "yp")["base"]["bem"]
    np.testing.assert_allclose(chosen["theory_contact_area_ratio"],
                               chosen["theory_variant_contact_area_ratio"].sel(theory="yang_persson"), rtol=1e-12)
    np.testing.assert_allclose(chosen["theory_mean_separation"],
                               chosen["theory_variant_mean_separation"].sel(theory="yang_persson"), rtol=1e-10)


def test_flash_temperature_uses_the_corrected_contact_fraction():
    """With infinite conductivity the flash march is the isothermal theory, also with a
    contact-area correction: the same mu and A/A0 as the isothermal kernel with that correction,
    and more contact than without it."""
    from test_flash import BOX_TREAD, NU, SIGMA0, _material, _psd

    from roughcontact.physics import flash, friction as fr

    q, C = _psd()
    v = np.geomspace(1e-6, 1e2, 5)
    grid, Ep, Epp, shift = _material(BOX_TREAD, 298.15, 230.25)
    A, B = fr.angular_integrals(q, v, grid, Ep, Epp, 16)
    area = ("yang_persson", 0.45)
    mu0, a0 = fr.friction_kernel(q, C, A, B, np.asarray(SIGMA0), NU, "none", 0.5, False, 12, *area)
    mu, a, _ = flash.flash_friction_kernel(q, C, v, 298.15, grid, Ep, Epp, 16, SIGMA0, NU, np.inf, np.inf, shift,
                                           area=area)
    np.testing.assert_allclose(mu, mu0, rtol=1e-6)
    np.testing.assert_allclose(a, a0, rtol=1e-6)
    _, plain = fr.friction_kernel(q, C, A, B, np.asarray(SIGMA0), NU)
    assert np.all(a > plain)
