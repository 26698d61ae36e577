"""What the command line tells a user (issue 14): options blamed as options, hints that are
right, quantities printed with units at readable precision, scenes described."""

import pytest
from conftest import make_scene

from roughcontact import scene as scenes
from roughcontact.cli import main
from roughcontact.errors import UserError
from roughcontact.units import readable, to_si


def _err(capsys):
    return capsys.readouterr().err.strip().splitlines()[-1]


def test_force_of_an_unknown_or_unused_stage_names_the_option(tmp_path, capsys, write_scene):
    path = write_scene(make_scene())
    assert main(["run", str(path), "--outdir", str(tmp_path / "o"), "--force", "frition"]) == 2
    assert _err(capsys) == "roughcontact: error: --force: no stage 'frition' (did you mean 'friction'?)"
    assert main(["run", str(path), "--outdir", str(tmp_path / "o"), "--force", "friction"]) == 2
    assert _err(capsys) == ("roughcontact: error: --force: the scene does not use stage 'friction' "
                            "(it runs psd, contact)")
    assert not list((tmp_path / "o").rglob("*.nc"))  # refused before anything was computed


def test_a_bad_scheduler_is_blamed_on_the_option(tmp_path, capsys, write_scene):
    path = write_scene(make_scene())
    assert main(["run", str(path), "--outdir", str(tmp_path / "o"), "--scheduler", "bogus"]) == 2
    message = _err(capsys)
    assert message.startswith("roughcontact: error: --scheduler: scheduler 'bogus'") and str(path) not in message


@pytest.mark.parametrize("value, hint", [(77.2e9, "77.2 GPa"), (1e6, "1 MPa"), ("2e8", "200 MPa")])
def test_the_hint_for_a_bare_number_is_the_number_in_a_readable_unit(value, hint):
    with pytest.raises(UserError) as err:
        to_si(value, "Pa", key="material.E")
    assert f'e.g. "{hint}" if it is in Pa' in err.value.message
    assert to_si(hint, "Pa") == pytest.approx(float(value))  # the hint means the same number


def test_readable_quantities():
    assert [readable(7.72e10, "Pa"), readable(1e-9, "m"), readable(2e8, "1/m"), readable(0.42, "")] == \
        ["77.2 GPa", "1 nm", "2e8 1/m", "0.42"]


def test_plan_prints_changed_quantities_with_units(tmp_path, capsys, write_scene):
    out = tmp_path / "o"
    assert main(["run", str(write_scene(make_scene(material={"E": "10 MPa"}))), "--outdir", str(out), "--quiet"]) == 0
    capsys.readouterr()
    changed = write_scene(make_scene(material={"E": "20 MPa"}), name="b.toml")
    assert main(["plan", str(changed), "--outdir", str(out)]) == 1
    assert "material.E: 10 MPa -> 20 MPa" in capsys.readouterr().out


def test_show_prints_parameters_with_units_and_scalars(tmp_path, capsys, write_scene):
    out = tmp_path / "o"
    assert main(["run", str(write_scene(make_scene())), "--outdir", str(out), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["show", str(out / "contact.nc")]) == 0
    text = capsys.readouterr().out
    assert "material.E = 77.2 GPa" in text and "load.p = [1 MPa, 3.162 MPa, ..., 10 GPa] (9 values)" in text
    assert "= 2e8 1/m" in text  # qL, the reference of zeta


def test_scenes_lists_descriptions(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    for name, description in scenes.builtin_descriptions().items():
        assert f"{name:16s} {description}" in out
    assert "site-packages" not in out.split("(scene files in")[0]


def test_every_option_of_every_command_has_help_text():
    """`roughcontact plot --help` listed --quiet without a word on it (issue 26)."""
    import argparse

    from roughcontact.cli import _parser

    commands = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in commands.choices.items():
        for action in sub._actions:
            if action.option_strings and not isinstance(action, argparse._HelpAction):
                assert action.help, f"{name} {action.option_strings[0]} has no help text"
