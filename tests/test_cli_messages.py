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
    other = write_scene(make_scene(material={"E": "20 MPa"}), name="b.toml")
    assert main(["plan", str(other), "--outdir", str(out)]) == 1
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


def test_ctrl_c_exits_130_as_shells_expect(tmp_path, capsys, monkeypatch, write_scene):
    from roughcontact import engine

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(engine, "run", interrupted)
    code = main(["run", str(write_scene(make_scene())), "--outdir", str(tmp_path / "out"), "--quiet"])
    assert code == 130 and "interrupted" in _err(capsys)


@pytest.mark.parametrize("name", ["topography", "container", "dma_flash", "bem_topography", "default"])
def test_scenes_copy_copies_the_scene_and_its_data_files(tmp_path, capsys, name):
    """`roughcontact scenes --copy NAME DIR`: the copy reads its own data files, not the package's."""
    from roughcontact import engine

    assert main(["scenes", "--copy", name, str(tmp_path / "mine")]) == 0
    copied = scenes.load(tmp_path / "mine" / f"{name}.toml")
    plans = engine.plan(copied, tmp_path / "out")
    read = [f for p in plans for v in p.file_paths.values() for f in (v if isinstance(v, tuple) else (v,))]
    assert all(str(tmp_path / "mine") in str(path) for path in read), read
    assert bool(read) == (name != "default")
    before = sorted(p.stat().st_mtime_ns for p in (tmp_path / "mine").rglob("*") if p.is_file())
    assert main(["scenes", "--copy", name, str(tmp_path / "mine")]) == 2  # never overwrites
    assert "exists already" in _err(capsys)
    assert sorted(p.stat().st_mtime_ns for p in (tmp_path / "mine").rglob("*") if p.is_file()) == before


def test_readme_agrees_with_the_scenes_and_the_accuracy_page():
    """README repeats the default scene's description (as `roughcontact scenes` prints it) and the
    measured-spectrum errors at the default resolution as docs/accuracy.md measures them."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    readme = " ".join((root / "README.md").read_text().split())
    assert f"`default` ({scenes.builtin_descriptions()['default']};" in readme
    row = re.search(r"^\| 50 \(default\) \| (.*) \|$", (root / "docs" / "accuracy.md").read_text(), flags=re.M)
    area_low, area_high, gap_low, gap_high = row.group(1).split(" | ")
    assert (f"the error is {area_low} in A/A0 and {gap_low} in the mean separation u where zeta < 8, {area_high} "
            f"and {gap_high} from zeta = 16 up") in readme


def test_every_option_of_every_command_has_help_text():
    """`roughcontact plot --help` listed --quiet without a word on it (issue 26)."""
    import argparse

    from roughcontact.cli import _parser

    commands = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in commands.choices.items():
        for action in sub._actions:
            if action.option_strings and not isinstance(action, argparse._HelpAction):
                assert action.help, f"{name} {action.option_strings[0]} has no help text"
