"""Bad input gives one clear line naming the file and the key or line, exit code 2, no traceback,
and nothing written."""

import pytest
from conftest import SURFACE, make_scene

from roughcontact.cli import main


def _run(tmp_path, capsys, path):
    out = tmp_path / "out"
    code = main(["run", str(path), "--outdir", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1, err
    assert not out.exists()  # nothing written: no result, no lock file, not even the folder
    return err


CASES = [
    ("unknown key", dict(material={"E": "77.2 GPa", "nu": 0.42, "Young": 1}), "material.Young"),
    ("unknown section", dict(materal={"E": "1 GPa"}), "did you mean 'material'"),
    ("no units", dict(substrate=dict(SURFACE, hrms=1.0)), "substrate.hrms: 1.0 has no units"),
    ("wrong units", dict(material={"E": "77.2 nm"}), "material.E"),
    ("hrms <= 0", dict(substrate=dict(SURFACE, hrms="0 nm")), "substrate.hrms: must be > 0"),
    ("C0 <= 0", dict(substrate={**{k: v for k, v in SURFACE.items() if k != "hrms"}, "C0": "-1e-36 m^4"}),
     "substrate.C0"),
    ("E <= 0", dict(material={"E": "-3 GPa"}), "material.E: must be > 0"),
    ("nu > 0.5", dict(material={"nu": 0.6}), "material.nu: must be <= 0.5"),
    ("nu <= -1", dict(material={"nu": -1.0}), "material.nu: must be > -1"),
    ("H > 1", dict(substrate=dict(SURFACE, H=1.2)), "substrate.H: must be <= 1"),
    ("H = 0", dict(solid=dict(SURFACE, H=0.0)), "solid.H: must be > 0"),
    ("q0 > q1", dict(substrate=dict(SURFACE, q0="5e10 1/m")), "substrate: needs qL <= q0 < q1"),
    ("q0 < qL", dict(substrate=dict(SURFACE, q0="1e8 1/m")), "substrate: needs qL <= q0 < q1"),
    ("eta > 1", dict(interface={"eta": [0.0, 1.5]}), "interface.eta: must be <= 1"),
    ("p <= 0", dict(load={"p": ["1 MPa", "0 MPa"]}), "load.p: must be > 0"),
    ("hrms and C0", dict(substrate=dict(SURFACE, C0="1e-36 m^4")), "exactly one of 'hrms' and 'C0'"),
    ("unknown kind", dict(substrate=dict(SURFACE, kind="selfaffine")), "did you mean 'self_affine'"),
    ("unknown output", dict(outputs={"variables": ["contact_area"]}), "did you mean 'contact_area_ratio'"),
    ("sub-normal viscosity", dict(leakage={"viscosity": "5e-324 Pa*s"},
                                  outputs={"variables": ["leak_rate_critical_junction"]}),
     "leakage.viscosity: 4.94066e-324 Pa*s is below the smallest normal double"),
    ("sub-normal modulus", dict(material={"E": "1e-320 GPa"}), "is below the smallest normal double"),
]


@pytest.mark.parametrize("label, overrides, expected", CASES, ids=[c[0] for c in CASES])
def test_scene_errors(tmp_path, capsys, write_scene, label, overrides, expected):
    path = write_scene(make_scene(**overrides))
    err = _run(tmp_path, capsys, path)
    assert str(path) in err and expected in err


def test_malformed_toml_names_the_line(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text('[material]\nE = "77 GPa\n')
    err = _run(tmp_path, capsys, path)
    assert str(path) in err and "malformed TOML" in err and "line 2" in err


def test_missing_scene_file(tmp_path, capsys):
    err = _run(tmp_path, capsys, tmp_path / "nope.toml")
    assert "nope.toml" in err


PSD_FILES = [
    ("non-increasing q", "# q [1/m] C [m^4]\n1e8 1e-30\n1e9 1e-33\n5e8 1e-32\n", "line 4", "strictly increasing"),
    ("negative C", "# q [1/m] C [m^4]\n1e8 1e-30\n1e9 -1e-33\n1e10 1e-36\n", "line 3", "negative"),
    ("NaN C", "# q [1/m] C [m^4]\n1e8 1e-30\n1e9 nan\n1e10 1e-36\n", "line 3", "NaN"),
    ("column count", "# q [1/m] C [m^4]\n1e8 1e-30\n1e9 1e-33 7\n", "line 3", "column"),
    ("no data", "# q [1/m] C [m^4]\n# nothing here\n", "", "no data"),
    ("text in data", "# q [1/m] C [m^4]\n1e8 1e-30\n1e9 abc\n", "line 3", "not a number"),
    ("no units", "1e8 1e-30\n1e9 1e-33\n1e10 1e-36\n", "", "units of the q column unknown"),
    ("header of 2 columns, rows of 3", "# q [1/m]  C [m^4]\n1e8 1e-30 1\n1e9 1e-33 1\n1e10 1e-36 1\n", "",
     "the header (line 1) names 2 column(s) but the rows hold 3"),
]


@pytest.mark.parametrize("label, text, where, expected", PSD_FILES, ids=[c[0] for c in PSD_FILES])
def test_psd_file_errors(tmp_path, capsys, write_scene, label, text, where, expected):
    data = tmp_path / "psd.txt"
    data.write_text(text)
    path = write_scene(make_scene(substrate={"kind": "psd_file", "path": str(data), "extend": "zero"}, solid=None,
                                  grid={"q_min": "1e8 1/m", "q_max": "1e10 1/m"}))
    err = _run(tmp_path, capsys, path)
    assert str(data) in err and where in err and expected in err


def test_required_key_is_needed_only_by_stages_that_read_it(tmp_path, capsys, write_scene):
    # no [material] E: fine for a scene that asks only for the PSD, an error naming the key otherwise
    raw = make_scene(material={"nu": 0.42}, outputs={"variables": ["psd_combined"]})
    raw["material"] = {"nu": 0.42}
    path = write_scene(raw)
    assert main(["run", str(path), "--outdir", str(tmp_path / "ok"), "--quiet"]) == 0
    capsys.readouterr()  # --quiet still says one line per stage
    raw["outputs"] = {"variables": ["contact_area_ratio"]}
    err = _run(tmp_path, capsys, write_scene(raw, "needs_e.toml"))
    assert "material.E: missing required key (stage contact needs it)" in err


def test_a_psd_path_that_is_a_folder_is_called_a_folder(tmp_path, capsys, write_scene):
    (tmp_path / "spectra").mkdir()
    path = write_scene(make_scene(substrate={"kind": "psd_file", "path": str(tmp_path / "spectra"), "extend": "zero"},
                                  solid=None, grid={"q_min": "1e8 1/m", "q_max": "1e10 1/m"}))
    err = _run(tmp_path, capsys, path)
    assert "substrate.path" in err and "is a folder, not a file" in err and "does not exist" not in err
