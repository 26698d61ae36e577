"""A text line scan whose header says its units (``# x [um]  h [um]``) is read in those units, no
``height_unit`` needed (issue 14); the scene's height_unit still serves files that say nothing."""

import numpy as np
import pytest

from roughcontact import engine, scene
from roughcontact.errors import UserError
from roughcontact.readers import read_topography

pytest.importorskip("SurfaceTopography")


def _scan(path, header, x_factor, h_factor, sep=" "):
    """A Brownian line scan of 10 um with heights of a few nm, written in the given units."""
    rng = np.random.default_rng(3)
    x = np.arange(512) * (10e-6 / 512)
    h = np.cumsum(rng.standard_normal(512)) * 1e-9
    lines = [header] if header else []
    lines += [f"{a * x_factor:.12g}{sep}{b * h_factor:.12g}" for a, b in zip(x, h, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return h


def test_header_units_are_the_units_read(tmp_path):
    h = _scan(tmp_path / "um.txt", "# x [um] h [um]", 1e6, 1e6)
    _scan(tmp_path / "mixed.txt", "x (mm)\th (nm)", 1e3, 1e9, sep="\t")
    a = read_topography(tmp_path / "um.txt", key="substrate")
    b = read_topography(tmp_path / "mixed.txt", key="substrate")
    assert a.unit_source == b.unit_source == "header" and (a.unit, b.unit) == ("um", "nm")
    assert np.allclose(a.heights, h, rtol=1e-9, atol=0) and np.allclose(b.heights, h, rtol=1e-9, atol=0)
    # the lateral size in metres from the x column's own unit (n dx = 10 um), whatever the height unit
    assert a.physical_sizes == pytest.approx((10e-6,), rel=1e-9)
    assert b.physical_sizes == pytest.approx((10e-6,), rel=1e-9)


def test_a_file_that_says_nothing_still_needs_height_unit(tmp_path):
    _scan(tmp_path / "bare.txt", None, 1e6, 1e6)
    with pytest.raises(UserError, match=r"height_unit") as err:
        read_topography(tmp_path / "bare.txt", key="solid")
    assert err.value.key == "solid.height_unit"
    assert read_topography(tmp_path / "bare.txt", key="solid", height_unit="um").unit_source == "scene"


def test_a_line_scan_with_a_header_gives_the_psd_of_the_same_scan_in_si(tmp_path):
    _scan(tmp_path / "scan.txt", "# x [um]  h [um]", 1e6, 1e6)
    _scan(tmp_path / "si.txt", None, 1.0, 1.0)
    out = {}
    for name, extra in (("scan.txt", {}), ("si.txt", {"height_unit": "m"})):
        raw = {"material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "0.1 MPa"},
               "substrate": {"kind": "topography", "files": [str(tmp_path / name)], **extra}}
        out[name] = engine.run(scene.from_dict(raw, tmp_path / "scene.toml"), tmp_path / name.replace(".", "_"),
                               targets=("topography",), report=engine.Reporter(None))["base"]["topography"]
    assert "um (header)" in out["scan.txt"]["psd_substrate_measured"].attrs["files"]
    a, b = (out[n]["psd_substrate_measured"].values for n in ("scan.txt", "si.txt"))
    assert np.isfinite(a).sum() > 5 and np.allclose(a, b, rtol=1e-8, equal_nan=True)
