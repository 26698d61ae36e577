"""A requested magnification range never silently leaves out a rough surface, and every result
over zeta says which wavenumber zeta is measured against (issue 14)."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import SURFACE, make_scene

from roughcontact import engine, scene as scenes
from roughcontact.cli import main
from roughcontact.errors import SceneWarning, UserError
from roughcontact.physics.contact import persson_G

ROOT = Path(__file__).resolve().parent.parent


def _solid_psd(folder: Path) -> Path:
    """A measured PSD file spanning 1e4-1e9 1/m in the contact.engineering convention (as README's example says)."""
    q = np.logspace(4, 9, 51)
    C = 1e-20 * (q / 1e4) ** -3.6 * (2 * np.pi) ** 2
    path = folder / "solid_psd.txt"
    path.write_text("# q [1/m]  C [m^4]\n" + "\n".join(f"{a:.8g} {b:.8g}" for a, b in zip(q, C, strict=True)) + "\n")
    return path


def _readme_scene() -> str:
    readme = (ROOT / "README.md").read_text()
    return readme.split("## Scenes", 1)[1].split("```toml", 1)[1].split("```", 1)[0]


def _without_grid(text: str) -> str:
    """README's example as the issue copied it: no [grid] table (qL defaults to the file's 1e4 1/m)."""
    return re.sub(r"\[grid\][^\[]*", "", text)


def _run_file(path: Path, outdir: Path):
    return engine.run(scenes.load(path), outdir, report=engine.Reporter(None))


def test_readme_example_without_a_system_size_is_refused_naming_the_keys(tmp_path):
    _solid_psd(tmp_path)
    path = tmp_path / "scene.toml"
    path.write_text(_without_grid(_readme_scene()))
    with pytest.raises(UserError) as err:
        _run_file(path, tmp_path / "out")
    text = str(err.value)
    # eta = 0, +1, -1 cannot differ when the substrate is not seen: an error naming the keys to change
    for key in ("contact.zeta", "substrate.qL", "solid.path", "grid.q_min", "interface.eta"):
        assert key in text
    assert not (tmp_path / "out" / "psd.nc").exists()  # refused before anything was computed


def test_readme_example_with_one_eta_warns_and_the_substrate_is_absent(tmp_path):
    _solid_psd(tmp_path)
    path = tmp_path / "scene.toml"
    path.write_text(_without_grid(_readme_scene()).replace("eta = [0.0, 1.0, -1.0]", "eta = 0.0"))
    with pytest.warns(SceneWarning, match=r"substrate\.qL.*grid\.q_min"):
        res = _run_file(path, tmp_path / "out")
    contact, psd = res["base"]["contact"], res["base"]["psd"]
    assert float(contact["qL"]) == pytest.approx(1e4)
    # what the warning says: G at zeta = 4 is the solid's alone
    q = psd["q"].values
    solid_alone = persson_G(q, psd["psd_solid"].values, np.array([4.0 * q[0]]), float(contact["E_star"]))
    assert float(contact["G"].sel(zeta=4.0)) == pytest.approx(float(solid_alone[0]), rel=1e-12)


def test_readme_example_as_printed_sees_both_surfaces(tmp_path):
    _solid_psd(tmp_path)
    path = tmp_path / "scene.toml"
    path.write_text(_readme_scene())
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        res = _run_file(path, tmp_path / "out")
    contact = res["base"]["contact"]
    assert float(contact["qL"]) == pytest.approx(2e8)
    G = {e: float(contact["G"].sel(zeta=4.0, eta=e)) for e in (0.0, 1.0, -1.0)}
    assert G[-1.0] > G[0.0] > G[1.0] >= 0  # anti-correlated roughness is worst, correlated cancels (eq 52)


def test_nothing_rough_left_is_an_error_and_all_magnifications_are_fine(run_scene):
    grid = {"q_min": "1e6 1/m"}  # far below the only rough surface's band (2e8 to 4e10 1/m)
    with pytest.raises(UserError, match="no roughness is left") as err:
        run_scene(make_scene(solid=None, grid=grid, contact={"zeta": [4.0, 100.0]}))
    assert err.value.key == "contact.zeta"
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        res = run_scene(make_scene(solid=None, grid=grid, contact={"zeta": "all"}))
    assert float(res["base"]["contact"]["qL"]) == pytest.approx(1e6)


def test_a_band_below_the_system_size_is_named(run_scene):
    low = dict(SURFACE, qL="1e6 1/m", q1="1e7 1/m")  # ends below grid.q_min
    with pytest.raises(UserError, match=r"solid\.qL.*Lower grid\.q_min"):
        run_scene(make_scene(solid=low, grid={"q_min": "2e8 1/m"}))


def test_plan_prints_the_reference_wavenumber_and_the_warning(tmp_path, capsys, write_scene):
    path = write_scene(make_scene(solid=dict(SURFACE, qL="2e6 1/m"), interface={"eta": 0.0},
                                 contact={"zeta": [4.0]}))
    assert main(["plan", str(path), "--outdir", str(tmp_path / "o")]) == 1
    out, err = capsys.readouterr()
    assert "qL = 2e6 1/m (the lowest wavenumber of the solid, solid.qL" in out
    assert "roughcontact: warning:" in err and "substrate.qL" in err


def test_the_check_also_runs_when_only_the_magnifications_changed(tmp_path):
    """psd is then fresh and not recomputed: its stored result carries the surfaces' bands."""
    _solid_psd(tmp_path)
    text = _without_grid(_readme_scene()).replace("eta = [0.0, 1.0, -1.0]", "eta = 0.0")
    path = tmp_path / "scene.toml"
    path.write_text(text.replace("zeta = [4.0]", 'zeta = "all"'))
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        _run_file(path, tmp_path / "out")
    path.write_text(text)
    assert {p.label: p.status for p in engine.plan(scenes.load(path), tmp_path / "out")}["psd"] == "fresh"
    with pytest.warns(SceneWarning, match=r"substrate\.qL"):
        _run_file(path, tmp_path / "out")
