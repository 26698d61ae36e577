"""A coating on the elastic solid ([material] coating_thickness, coating_E, coating_nu) in the
contact, separation and stiffness stages: off by default (results bit for bit those of the
homogeneous solid), its limits, its G and stiffness against independent quadratures, what a
soft coating does, and the refusals (bad keys, stages that take a homogeneous solid only)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import cli_error_line, make_scene

from roughcontact.cli import main
from roughcontact.physics.layered import effective_modulus
from roughcontact.physics.special import erf

STEEL = {"E": "210 GPa", "nu": 0.3}
POLYMER = {"coating_E": "3 GPa", "coating_nu": 0.35}
GROUND = {"kind": "self_affine", "H": 0.8, "qL": "1e4 1/m", "q0": "1e5 1/m", "q1": "1e7 1/m", "hrms": "0.5 um"}
OUTPUTS = ["contact_area_ratio", "stress_distribution", "mean_separation", "contact_stiffness"]


def coated_scene(material=None, **over):
    """A rough ground-steel counterface (the rigid substrate) on a smooth coated steel part."""
    tables = dict(substrate=dict(GROUND), solid={"kind": "smooth"}, interface={"eta": 0.0},
                  material={**STEEL, **(material or {})},
                  load={"p": {"from": "1 MPa", "to": "1 GPa", "num": 7, "spacing": "log"}},
                  contact={"zeta": [10.0, 1000.0]}, outputs={"variables": OUTPUTS},
                  numerics={"points_per_decade": 20, "sigma_points": 51})
    return make_scene(**{**tables, **over})


def results(run_scene, tmp_path, name, material=None, **over):
    res = run_scene(coated_scene(material, **over), outdir=tmp_path / name)["base"]
    return {st: res[st] for st in ("contact", "separation", "stiffness")}


VARIABLES = {"contact": ("G", "contact_area_ratio", "stress_distribution"), "separation": ("mean_separation",
             "separation_u0", "separation_beta"), "stiffness": ("contact_stiffness", "stiffness_length")}


def test_no_coating_and_none_give_the_homogeneous_results_bit_for_bit(run_scene, tmp_path):
    plain = results(run_scene, tmp_path, "plain")
    off = results(run_scene, tmp_path, "off", {"coating_thickness": "none", **POLYMER})
    for st, names in VARIABLES.items():
        assert "coating" not in plain[st].attrs and "coating" not in off[st].attrs
        for name in names:
            np.testing.assert_array_equal(off[st][name].values, plain[st][name].values)


def test_a_coating_of_the_substrate_material_is_the_homogeneous_solid(run_scene, tmp_path):
    plain = results(run_scene, tmp_path, "plain")
    same = results(run_scene, tmp_path, "same", {"coating_thickness": "10 um", "coating_E": "210 GPa",
                                                 "coating_nu": 0.3})
    assert same["contact"].attrs["coating_thickness_m"] == pytest.approx(1e-5, rel=1e-15)
    for st, names in VARIABLES.items():
        for name in names:
            np.testing.assert_allclose(same[st][name].values, plain[st][name].values, rtol=1e-12, atol=0)


@pytest.mark.parametrize("thickness, limit", [("1e-18 m", "substrate"), ("1 m", "layer")])
def test_thin_coating_is_the_substrate_and_thick_coating_the_layer(run_scene, tmp_path, thickness, limit):
    """q d <= 1e-11 over the band: the bare steel (k1 q d ~ 3e-10); q d >= 1e4: the polymer alone. The
    small-load law p = beta E* exp(-u/u0) of a coated solid is written with the substrate's E*."""
    coated = results(run_scene, tmp_path, "coated", {"coating_thickness": thickness, **POLYMER})
    bulk = {"E": "3 GPa", "nu": 0.35} if limit == "layer" else {}
    ref = results(run_scene, tmp_path, "ref", bulk)
    for st, names in VARIABLES.items():
        for name in names:
            a, b = coated[st][name], ref[st][name]
            if name == "separation_beta":
                a, b = a * coated[st]["E_star"], b * ref[st]["E_star"]
            np.testing.assert_allclose(a.values, b.values, rtol=1e-9, atol=0)


def test_a_soft_coating_raises_the_area_and_closes_the_gap_the_more_the_thicker(run_scene, tmp_path):
    """At the same pressure a softer surface conforms more: more contact, a smaller mean gap."""
    runs = [results(run_scene, tmp_path, "steel")] + [
        results(run_scene, tmp_path, d, {"coating_thickness": d, **POLYMER}) for d in ("1 um", "10 um", "100 um")]
    area = np.array([r["contact"]["contact_area_ratio"].sel(zeta=1000.0).values for r in runs])
    gap = np.array([r["separation"]["mean_separation"].sel(zeta=1000.0).values for r in runs])
    assert np.all(np.diff(area, axis=0) > 0) and np.all(np.diff(gap, axis=0) < 0)
    # at low load A/A0 ~ p / sqrt(pi G): the 100 um coating (the polymer at most scales) is ~E*_steel / E*_polymer
    # = 68 times the bare steel's, less the long wavelengths where the steel still carries it
    assert 30 < area[-1, 0] / area[0, 0] < 68.5


def test_G_and_stiffness_length_are_the_layered_integrals(run_scene, tmp_path):
    """G = (pi/4) int q^3 C E_eff^2 dq and -du/dln p = (sqrt(pi) alpha / 2) int q^2 C E_eff G^-1/2 e^(-p^2/4G) dq
    (the elastic energy with E_eff differentiated in p), by the trapezoidal rule in ln q on a fine grid."""
    scene = coated_scene({"coating_thickness": "10 um", **POLYMER}, contact={"zeta": "all"},
                         numerics={"points_per_decade": 100, "sigma_points": 51})
    res = run_scene(scene, outdir=tmp_path / "o")["base"]
    psd = res["psd"]
    q, C = psd["q"].values, psd["psd_combined"].values.reshape(-1)
    sub = 400  # points per interval of the psd grid, so that every grid node is a node of the fine grid
    fine = np.exp(np.interp(np.arange((q.size - 1) * sub + 1) / sub, np.arange(q.size), np.log(q)))
    Cf = np.exp(np.interp(np.log(fine), np.log(q), np.log(C)))  # the psd is a power law between nodes
    E = effective_modulus(fine, 10e-6, 3e9, 0.35, 210e9, 0.3)
    f = fine**4 * Cf * E**2
    G = np.pi / 4 * np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(np.log(fine)))])
    # the stage integrates q^3 C E_eff^2 as a power law between the 100-per-decade nodes: 2.5e-5 here
    np.testing.assert_allclose(res["contact"]["G"].values.reshape(-1), G[::sub], rtol=1e-4)
    alpha = float(res["separation"].attrs["separation_alpha"])
    D = res["stiffness"]["stiffness_length"].isel(zeta=-1)
    for p in D["p"].values[2:]:
        with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
            g = np.where(G > 0, fine**3 * Cf * E * np.exp(-p * p / (4 * G)) / np.sqrt(G), 0.0)
        expected = np.sqrt(np.pi) * alpha / 2 * np.sum(0.5 * (g[1:] + g[:-1]) * np.diff(np.log(fine)))
        assert float(D.sel(p=p)) == pytest.approx(expected, rel=2e-3)
    # and A/A0 is eq 19 on that G
    A = res["contact"]["contact_area_ratio"].isel(zeta=-1).values
    np.testing.assert_allclose(A, erf(D["p"].values / (2 * np.sqrt(G[-1]))), rtol=1e-4)


def _edited(tmp_path: Path, name: str, lines: str) -> Path:
    """The built-in scene ``name`` copied to tmp_path with ``lines`` added to its [material] table."""
    assert main(["scenes", "--copy", name, str(tmp_path / name)]) == 0
    path = next((tmp_path / name).glob("*.toml"))
    text = path.read_text()
    edited = re.sub(r"^\[material\][^\n]*\n", lambda m: m.group(0) + lines, text, count=1, flags=re.M)
    assert edited != text
    path.write_text(edited)
    return path


COATING = 'coating_thickness = "10 um"\ncoating_E = "3 GPa"\ncoating_nu = 0.35\n'


@pytest.mark.parametrize("scene, what", [("friction", "friction stage"), ("adhesion", "adhesion stage"),
                                         ("seal", "leakage stage"), ("interface_bem", "interface_bem stage")])
def test_stages_that_take_a_homogeneous_solid_refuse_a_coating_in_one_line(tmp_path, capsys, scene, what):
    path = _edited(tmp_path, scene, COATING)
    out = tmp_path / "out"
    code, err = cli_error_line(capsys, "run", path, "--outdir", out, "--quiet")
    assert code == 2 and "material.coating_thickness" in err and what in err and "not supported" in err, err
    assert not out.exists() or not any(out.rglob("*.nc"))
    shutil.rmtree(tmp_path / scene)


@pytest.mark.parametrize("lines, key, message", [
    ('coating_thickness = "0 um"\ncoating_E = "3 GPa"\ncoating_nu = 0.35\n', "material.coating_thickness", "> 0"),
    ('coating_thickness = "-1 um"\ncoating_E = "3 GPa"\ncoating_nu = 0.35\n', "material.coating_thickness", "> 0"),
    ('coating_thickness = "1 um"\ncoating_E = "3 GPa"\ncoating_nu = 0.6\n', "material.coating_nu", "<= 0.5"),
    ('coating_thickness = "1 um"\ncoating_E = "3 GPa"\ncoating_nu = -1.0\n', "material.coating_nu", "> -1"),
    ('coating_thickness = "1 um"\ncoating_E = "0 GPa"\ncoating_nu = 0.3\n', "material.coating_E", "> 0"),
    ('coating_thickness = "1 um"\ncoating_nu = 0.3\n', "material.coating_E", "Young modulus"),
    ('coating_E = "3 GPa"\ncoating_nu = 0.3\n', "material.coating_thickness", "thickness"),
    ('coating_thickness = ["1 um", "2 um"]\ncoating_E = "3 GPa"\ncoating_nu = 0.3\n', "material.coating_thickness",
     "variants"),
])
def test_bad_coating_is_a_one_line_error_naming_the_key_before_anything_is_written(tmp_path, capsys, lines, key,
                                                                                   message):
    path = _edited(tmp_path, "default", lines)
    out = tmp_path / "out"
    code, err = cli_error_line(capsys, "run", path, "--outdir", out, "--quiet")
    assert code == 2 and key in err and message in err, err
    assert not out.exists() or not any(out.rglob("*.nc"))


def test_coating_figures_draw_each_thickness_and_nothing_for_a_homogeneous_solid(run_scene, tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roughcontact.stages.figures.coating import figure_coating_area, figure_coating_modulus

    plain = run_scene(coated_scene(), outdir=tmp_path / "plain")
    assert figure_coating_area(plain) is None and figure_coating_modulus(plain) is None
    scene = coated_scene({"coating_thickness": "10 um", **POLYMER},
                         variants={"thin": {"material": {"coating_thickness": "1 um"}},
                                   "bare": {"material": {"coating_thickness": "none"}}})
    res = run_scene(scene, outdir=tmp_path / "coated")
    for make in (figure_coating_area, figure_coating_modulus):
        fig = make(res)
        labels = {line.get_label() for ax in fig.axes for line in ax.get_lines()}
        assert {"coating d = 1 um", "coating d = 10 um"} <= labels
        assert any(label.startswith("bare: no coating, E* = 230.8 GPa") for label in labels), labels
        plt.close(fig)
