"""Every reader path on real instrument files.

One real file ships with the repository (tests/data/instrument/, see the README there): an
Asylum Research AFM height map (Igor binary wave, .ibw) from the source distribution of the PyPI
package afm-tools 2.1.4 (MIT licence); its tests always run.

The others are the files SurfaceTopography's own tests read (its repository's
test/file_format_examples, MIT licence, copyright Lars Pastewka and the SurfaceTopography authors;
the contact.engineering container container-2.zip holds its own CC BY 4.0 licence). Neither the
PyPI sdist nor the wheel of SurfaceTopography ships them (its MANIFEST.in prunes test/), and files
fetched from a repository are not committed here: point ROUGHCONTACT_INSTRUMENT_FILES at a folder
holding them (a checkout's test/file_format_examples), or put them in the project's shared folder
beside the checkout (shared/data/instrument_files, which CI receives), and those tests run; without
them they are skipped.

The expected shapes, sizes, units and numbers of undefined points are those the files
declare (and SurfaceTopography's tests assert)."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from roughcontact import engine, scene  # noqa: E402
from roughcontact.errors import SceneWarning, UserError  # noqa: E402
from roughcontact.readers import READERS  # noqa: E402

pytest.importorskip("SurfaceTopography")
#: where CI finds the files when the project's shared folder (beside the checkout) holds them
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "instrument_files"
FOLDER = Path(os.environ.get("ROUGHCONTACT_INSTRUMENT_FILES", SHARED))
#: the tests on the files that are not in the repository
external = pytest.mark.skipif(not FOLDER.is_dir(), reason="set ROUGHCONTACT_INSTRUMENT_FILES to SurfaceTopography's "
                                                        "test/file_format_examples to run the real-file tests")
#: the real AFM map shipped with the repository (tests/data/instrument/README.md)
SHIPPED_AFM = Path(__file__).parent / "data" / "instrument" / "asylum-vero-pfm.ibw"


def _file(name: str) -> Path:
    path = FOLDER / name
    if not path.is_file():
        pytest.skip(f"{name} is not in {FOLDER}")
    return path


def _run(tmp_path, raw, targets=("topography",)):
    raw = {"material": {"E": "10 MPa", "nu": 0.5}, "load": {"p": "0.1 MPa"}, **raw}
    sc = scene.from_dict(raw, tmp_path / "scene.toml")
    return engine.run(sc, tmp_path / "out", targets=targets, report=engine.Reporter(None))["base"]["topography"]


# name, reader format, shape, physical sizes (m), unit, undefined points
FILES = [
    ("opd-1.opd", "OPD", (640, 480), (1.2591e-4, 9.4432e-5), "mm", 116),  # Wyko white-light interferometer
    ("sur-2.sur", "SUR", (563, 484), (1.9615e-3, 1.6863e-3), "mm", 117),  # Digital Surf
    ("plu-1.plu", "PLU", (768, 576), (1.2749e-3, 9.5616e-4), "µm", 0),  # Sensofar confocal
    ("x3p-2.x3p", "X3P", (650, 650), (8.2977e-5, 2.0448e-4), "m", 0),  # ISO 25178-72
    ("metropro-1.dat", "MetroPro", (640, 480), (7.0288e-4, 5.2716e-4), "m", 0),  # Zygo
    ("di-1.di", "DI", (512, 512), (5.0e-7, 5.0e-7), "nm", 0),  # Bruker/Digital Instruments AFM
    ("matrix-3.txt", "Asc", (256, 256), (1.0e-5, 1.0e-5), "m", 0),  # text matrix with a header
    ("sdf-1.sdf", "SDF", (7, 4), (7.0e-6, 4.0e-6), "µm", 0),  # ISO 25178-71 text
    ("nc-1.nc", "NC", (5, 10), (5.0e-9, 1.0e-8), "nm", 0),  # SurfaceTopography's NetCDF
]


@external
@pytest.mark.parametrize("name, fmt, shape, sizes, unit, undefined", FILES, ids=[f[0] for f in FILES])
def test_reader_on_real_files(name, fmt, shape, sizes, unit, undefined):
    """Each format read in SI with the file's own shape, sizes, unit and undefined points (NaN)."""
    topo = READERS["topography"](_file(name), key="substrate")
    assert topo.format == fmt and topo.heights.shape == shape and topo.unit == unit
    assert topo.physical_sizes == pytest.approx(sizes, rel=1e-4)
    assert int(np.isnan(topo.heights).sum()) == undefined
    finite = topo.heights[np.isfinite(topo.heights)]
    assert 0 < np.ptp(finite) < 1e-3  # metres: a surface's height range, not the file's units


@external
@pytest.mark.parametrize("name, points", [("opd-1.opd", 116), ("sur-2.sur", 117)])
def test_optical_maps_with_undefined_points_refused_then_filled(tmp_path, name, points):
    """The optical maps with undefined points: refused by default naming fill_undefined; with
    fill_undefined = 'harmonic' the PSD is computed and the result records the points filled."""
    path = _file(name)
    (tmp_path / "a").mkdir()
    refusal = rf"{points} of \d+ heights are missing .*substrate.fill_undefined = 'harmonic'"
    with pytest.raises(UserError, match=refusal):
        _run(tmp_path / "a", {"substrate": {"kind": "topography", "files": str(path)}})
    ds = _run(tmp_path, {"substrate": {"kind": "topography", "files": str(path), "fill_undefined": "harmonic"}})
    psd = ds["psd_substrate_measured"]
    assert np.isfinite(psd.values).sum() > 20 and np.nanmin(psd.values) > 0
    (described,) = json.loads(psd.attrs["files"])
    assert described["undefined_filled"]["points"] == points
    assert described["undefined_filled"]["method"].startswith("harmonic")


@external
def test_real_container_with_a_non_uniform_line_scan(tmp_path):
    """contact.engineering's demo container (UNCD: a TEM line scan sampled non-uniformly, a
    Bruker AFM map, a stylus line scan): the TEM scan is left out with a warning naming it, the
    PSD merges the other two, the result lists them."""
    path = _file("container-2.zip")
    with pytest.warns(SceneWarning, match=r"left out measurement '80_Scale10.472_FIXEDv2p1.asc' .*non-uniformly"):
        container = READERS["container"](path, key="substrate")
    assert [m.metadata["measurement"] for m in container.measurements] == ["gain_control_uncd_35.001",
                                                                          "uncd_stylus_300um_5mar_3.txt"]
    afm, stylus = container.measurements
    assert afm.heights.shape == (512, 512) and afm.physical_sizes == pytest.approx((1e-7, 1e-7))
    assert stylus.heights.ndim == 1 and stylus.physical_sizes == pytest.approx((2.9878e-4,), rel=1e-4)
    with pytest.warns(SceneWarning):
        ds = _run(tmp_path, {"substrate": {"kind": "container", "container": str(path), "analysis": "profiles"}})
    attrs = ds["psd_substrate_measured"].attrs
    assert json.loads(attrs["measurements_entered"]) == ["gain_control_uncd_35.001", "uncd_stylus_300um_5mar_3.txt"]
    assert json.loads(attrs["measurements_left_out"])[0]["datafile"] == "80_Scale10.472_FIXEDv2p1_D7eHXiT.asc"


@external
@pytest.mark.parametrize("name", ["dektak-1.csv", "nonuniform.asc"])
def test_a_non_uniform_line_scan_file_is_a_clear_error(tmp_path, name):
    """A single non-uniformly sampled line scan (a Bruker Dektak stylus export) is refused in one
    line naming the file and why."""
    path = _file(name)
    with pytest.raises(UserError, match="non-uniformly sampled line scan") as info:
        READERS["topography"](path, key="substrate")
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_shipped_afm_map_reads_with_the_files_own_facts():
    """The Asylum Research map (a Vero AFM in PFM mode, 256 x 256 points over a 10 µm scan): read as
    its height channel in metres, with the pixel the Igor wave declares (the 10 µm scan size spans the
    255 intervals between its 256 points), no undefined point, and the heights of a surface (nm)."""
    topo = READERS["topography"](SHIPPED_AFM, key="substrate")
    assert topo.format == "IBW" and topo.channel.startswith("Height")
    assert topo.heights.shape == (256, 256) and topo.unit == "m" and topo.unit_source == "file"
    pixel = 10e-6 / 255
    assert topo.physical_sizes == pytest.approx((256 * pixel, 256 * pixel), rel=1e-9)
    assert not np.isnan(topo.heights).any()
    assert 1e-9 < np.ptp(topo.heights) < 1e-6
    assert topo.metadata["instrument"]["vendor"] == "Asylum Research"


def test_shipped_afm_map_gives_a_finite_psd_between_its_size_and_its_pixel(tmp_path):
    """Through the topography stage the map gives a PSD that is finite and positive from 2 pi / L to
    pi / dx (the range recorded for the file), NaN outside it, and falling with q over that range, as a
    rough surface's does."""
    ds = _run(tmp_path, {"substrate": {"kind": "topography", "files": str(SHIPPED_AFM)}})
    psd, q = ds["psd_substrate_measured"], ds["q_substrate_measured"].values
    (described,) = json.loads(psd.attrs["files"])
    length, pixel = 256 * 10e-6 / 255, 10e-6 / 255
    assert described["q_range_per_m"] == pytest.approx([2 * np.pi / length, np.pi / pixel], rel=1e-6)
    finite = np.isfinite(psd.values)
    assert finite.sum() > 20 and np.all(psd.values[finite] > 0)
    lo, hi = described["q_range_per_m"]
    assert np.all((q[finite] >= lo * 0.9) & (q[finite] <= hi * 1.1))
    assert psd.values[finite][0] > 1e3 * psd.values[finite][-1]
