"""Nothing lost, nothing half-written, no traceback (issue 15), part 2: the files and the machine.
Unreadable inputs, unusable output folders and a full disk give one line naming the file (and
nothing of the failed result is kept); concurrent runs on one folder wait for each other, and
runs in threads of one process never crash; a temporary is removed only when provably stale; an
edited result is found by its checksum and recomputed."""

from __future__ import annotations

import builtins
import errno
import io
import json
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import cli_error_line, make_scene

from roughcontact import engine, integrity, sizing
from roughcontact.cli import main
from roughcontact.errors import UserError
from roughcontact.preflight import LOCK_NAME

SMALL = {"points_per_decade": 10}
TESTS = Path(__file__).resolve().parent


_cli = cli_error_line


def _quiet():
    return engine.Reporter(None)


# ----------------------------------------------------------------------------------------
# Unreadable inputs (hashing under run and plan, then reading)
# ----------------------------------------------------------------------------------------

@pytest.fixture
def unreadable(monkeypatch):
    """Make files unreadable: chmod 000, and (as root, whom permissions do not stop) an open() that
    raises PermissionError for them, as the file system would."""
    locked: set[str] = set()
    real_open = builtins.open

    def guarded(file, *args, **kwargs):
        if str(Path(file).resolve()) in locked if isinstance(file, (str, Path)) else False:
            raise PermissionError(errno.EACCES, "Permission denied", str(file))
        return real_open(file, *args, **kwargs)

    if os.geteuid() == 0:
        monkeypatch.setattr(builtins, "open", guarded)
        monkeypatch.setattr(io, "open", guarded)

    def lock(path: Path) -> Path:
        path.chmod(0)
        locked.add(str(path.resolve()))
        return path

    yield lock
    for p in locked:
        Path(p).chmod(0o644)


@pytest.mark.parametrize("kind", ["psd_file", "topography"])
@pytest.mark.parametrize("command", ["run", "plan"])
def test_an_unreadable_input_file_is_a_clear_error(tmp_path, capsys, write_scene, unreadable, kind, command):
    if kind == "psd_file":
        data = tmp_path / "psd.txt"
        data.write_text("# q [1/m] C [m^4]\n1e8 1e-30\n1e9 1e-33\n1e11 1e-36\n")
        surface = {"kind": "psd_file", "path": str(data), "extend": "zero"}
    else:
        data = tmp_path / "map.npy"
        np.save(data, np.random.default_rng(1).normal(size=(32, 32)))
        surface = {"kind": "topography", "files": str(data), "height_unit": "nm", "size_x": "10 um"}
    path = write_scene(make_scene(solid=surface, numerics=SMALL))
    unreadable(data)
    code, err = _cli(capsys, command, path, "--outdir", tmp_path / "out")
    assert code == 2 and str(data) in err and "solid." in err and "ermission" in err
    assert not list((tmp_path / "out").glob("*.nc")) if (tmp_path / "out").exists() else True


# ----------------------------------------------------------------------------------------
# Output folders and result paths that cannot be used
# ----------------------------------------------------------------------------------------

@pytest.fixture
def read_only_dir(tmp_path):
    """A folder that refuses writes: chmod 555, or (as root) a read-only tmpfs mount."""
    folder = tmp_path / "ro"
    folder.mkdir()
    if os.geteuid() != 0:
        folder.chmod(0o555)
        yield folder
        folder.chmod(0o755)
        return
    mount = ["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(folder)]
    if subprocess.run(mount, capture_output=True).returncode:
        pytest.skip("running as root and cannot mount a read-only file system here")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=False)


def test_a_read_only_output_folder_is_a_clear_error(tmp_path, capsys, write_scene, read_only_dir):
    path = write_scene(make_scene(numerics=SMALL))
    for outdir in (read_only_dir, read_only_dir / "sub"):
        code, err = _cli(capsys, "run", path, "--outdir", outdir, "--quiet")
        assert code == 2 and str(outdir) in err and ("not writable" in err or "cannot create" in err), err


def test_an_output_folder_that_is_a_file_and_a_result_path_that_is_a_folder(tmp_path, capsys, write_scene):
    path = write_scene(make_scene(numerics=SMALL))
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    code, err = _cli(capsys, "run", path, "--outdir", afile, "--quiet")
    assert code == 2 and str(afile) in err and "not a folder" in err and afile.read_text() == "not a folder"
    out = tmp_path / "out"
    (out / "contact.nc").mkdir(parents=True)
    for command in ("run", "plan"):
        code, err = _cli(capsys, command, path, "--outdir", out)
        assert code == 2 and str(out / "contact.nc") in err and "move it away" in err
    assert not (out / "psd.nc").exists()



def test_a_figure_that_cannot_be_written_is_named_and_nothing_of_it_is_kept(tmp_path, capsys, write_scene):
    path = write_scene(make_scene(numerics=SMALL))
    out = tmp_path / "out"
    assert main(["run", str(path), "--outdir", str(out), "--quiet"]) == 0
    assert main(["plot", str(path), "--outdir", str(out)]) == 0
    figure = sorted((out / "figures").glob("*.png"))[0]
    figure.unlink()
    figure.mkdir()  # the figure's path is now a folder: the rename onto it fails
    capsys.readouterr()
    code, err = _cli(capsys, "plot", path, "--outdir", out)
    assert code == 1 and "cannot write this figure" in err and str(figure) in err
    assert not list((out / "figures").glob(".tmp-*")) and figure.is_dir()

# ----------------------------------------------------------------------------------------
# A full disk: the file that could not be written is named, nothing of it is kept
# ----------------------------------------------------------------------------------------

def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def _hdf_error(self, path, *args, **kwargs):
    Path(path).write_bytes(b"\x89HDF partial")
    raise RuntimeError("NetCDF: HDF error")


@pytest.mark.parametrize("where, stage", [("block writes", "contact"), ("netCDF library", "psd")])
def test_a_full_disk_names_the_file_and_keeps_nothing_of_it(tmp_path, capsys, monkeypatch, write_scene, where, stage):
    path = write_scene(make_scene(numerics={**SMALL, "chunks": {"p": 3}}))
    out = tmp_path / "out"
    assert main(["run", str(path), "--outdir", str(out), "--quiet"]) == 0
    before = {f: (out / f).read_bytes() for f in ("psd.nc", "contact.nc")}
    import roughcontact.store
    import roughcontact.writing

    if where == "block writes":
        monkeypatch.setattr(roughcontact.writing, "write_blocks", _enospc)
    else:
        monkeypatch.setattr(roughcontact.store, "_write_in_memory", _hdf_error)  # the in-memory variables' write
    capsys.readouterr()
    code, err = _cli(capsys, "run", path, "--outdir", out, "--quiet", "--force", stage)
    assert code == 1 and "cannot write this result" in err and "nothing of it was kept" in err
    assert str(out / f"{stage}.nc") in err
    assert not list(out.glob(".tmp-*"))
    assert {f: (out / f).read_bytes() for f in before} == before  # the results that were there are untouched


def test_a_really_full_file_system(tmp_path, capsys, monkeypatch, write_scene):
    """A 300 kB tmpfs (needs root to mount): the sizes check lets the run start (told the disk is
    large), the netCDF library then fails on the full disk."""
    folder = tmp_path / "tiny"
    folder.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(folder)],
                                           capture_output=True).returncode:
        pytest.skip("needs root and mount to make a small file system")
    try:
        monkeypatch.setattr(sizing, "free_disk", lambda path: 10**12)
        path = write_scene(make_scene(outputs={"variables": ["stress_distribution"]}))
        code, err = _cli(capsys, "run", path, "--outdir", folder / "out", "--quiet")
        assert code == 1 and "contact.nc" in err and "nothing of it was kept" in err
        assert not list((folder / "out").glob(".tmp-*")) and not (folder / "out" / "contact.nc").exists()
    finally:
        subprocess.run(["umount", str(folder)], check=False)


# ----------------------------------------------------------------------------------------
# Concurrency
# ----------------------------------------------------------------------------------------

HOLD = """
import sys, time
from filelock import FileLock
lock = FileLock(sys.argv[1])
lock.acquire()
print("held", flush=True)
time.sleep(float(sys.argv[2]))
"""


def test_a_second_run_on_a_locked_folder_waits_then_runs_or_refuses(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out / LOCK_NAME), "3"],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    raw = make_scene(numerics=SMALL)
    with pytest.raises(UserError, match="another roughcontact run is writing"):
        engine.run(raw, out, report=_quiet(), lock_timeout=0.2)
    assert not list(out.glob("*.nc"))
    said = io.StringIO()
    res = engine.run(raw, out, report=engine.Reporter(said))  # waits until the other run ends
    holder.wait()
    assert "waiting: another roughcontact run is writing" in said.getvalue() and "contact" in res["base"]


def test_two_runs_on_one_folder_from_two_threads_both_end_well(tmp_path):
    raw = make_scene(numerics={**SMALL, "chunks": {"p": 2}}, outputs={"variables": ["stress_distribution"]})
    errors, results = [], []

    def work():
        try:
            results.append(engine.run(raw, tmp_path / "out", report=_quiet(), force="all"))
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work) for _ in range(2)]
    [t.start() for t in threads]
    [t.join() for t in threads]
    assert errors == [] and len(results) == 2
    assert {p.status for p in engine.plan(raw, tmp_path / "out", verify=True)} == {"fresh"}


THREADS = """
import sys, tempfile, threading
from pathlib import Path
sys.path.insert(0, {tests!r})
from conftest import make_scene
from roughcontact import engine
raw = make_scene(load={{"p": {{"from": "1 MPa", "to": "10 GPa", "num": 300}}}}, numerics={{"points_per_decade": 20,
                 "chunks": {{"p": 20}}}}, outputs={{"variables": ["contact_area_ratio", "mean_separation"]}})
failed = []
def work(i):
    try:
        out = Path(tempfile.mkdtemp())
        for _ in range(2):
            engine.run(raw, out, report=engine.Reporter(None), force="all")
    except Exception as exc:
        failed.append(repr(exc))
for _ in range({rounds}):
    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    [t.start() for t in threads]
    [t.join() for t in threads]
print("failed", failed)
sys.exit(1 if failed else 0)
"""


def test_runs_in_two_threads_of_one_process_never_crash():
    """netCDF/HDF5 is not thread-safe; unserialised, this crashed (segfault, bus error) in every try."""
    done = subprocess.run([sys.executable, "-X", "faulthandler", "-c", THREADS.format(tests=str(TESTS), rounds=3)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]


def test_a_temporary_is_removed_only_when_provably_stale(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    host = socket.gethostname().replace(".", "_")
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    try:
        mine = out / f".tmp-contact.nc.{host}-{live.pid}.abc"
        stale = out / f".tmp-psd.nc.{host}-{dead.pid}.abc"
        old_style = out / ".tmp-psd.nc.xyz"
        for f in (mine, stale, old_style):
            f.write_bytes(b"partial")
        engine.run(make_scene(numerics=SMALL), out, report=_quiet())
        assert mine.exists() and not stale.exists() and not old_style.exists()
    finally:
        live.kill()
        live.wait()


# ----------------------------------------------------------------------------------------
# Integrity: an edited result is not taken as fresh
# ----------------------------------------------------------------------------------------

def _edit_value(path: Path, name: str):
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        var = nc.variables[name]
        index = (0,) * var.ndim
        var[index] = var[index] * 1.0001 + 1e-300


def _edit_attr(path: Path, attr: str, change):
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        nc.setncattr(attr, change(nc.getncattr(attr)))


EDITS = [
    ("a value in contact.nc", "contact", lambda p: _edit_value(p, "contact_area_ratio")),
    ("a coordinate in contact.nc", "contact", lambda p: _edit_value(p, "p")),
    ("a value in psd.nc", "psd", lambda p: _edit_value(p, "psd_combined")),
    ("parameters, key kept", "contact",
     lambda p: _edit_attr(p, "parameters", lambda v: v.replace("77200000000", "70000000000"))),
    ("units of a variable", "psd", lambda p: _edit_value(p, "q") if False else _edit_units(p)),
]


def _edit_units(path: Path):
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        nc.variables["psd_combined"].setncattr("units", "m^2")


@pytest.mark.parametrize("label, stage, edit", EDITS, ids=[e[0] for e in EDITS])
def test_an_edited_result_is_found_by_its_checksum_and_recomputed(tmp_path, label, stage, edit):
    raw = make_scene(numerics=SMALL)
    out = tmp_path / "out"
    engine.run(raw, out, report=_quiet())
    key = xr.open_dataset(out / f"{stage}.nc").attrs["stage_key"]
    edit(out / f"{stage}.nc")
    plans = {p.stage.name: p for p in engine.plan(raw, out)}
    assert plans[stage].status == "stale" and "checksum" in plans[stage].reasons[0]
    res = engine.run(raw, out, report=_quiet())
    assert res["base"][stage].attrs["stage_key"] == key
    assert {p.status for p in engine.plan(raw, out)} == {"fresh"}


def test_big_files_are_verified_on_request(tmp_path, monkeypatch):
    raw = make_scene(numerics=SMALL)
    out = tmp_path / "out"
    engine.run(raw, out, report=_quiet())
    _edit_value(out / "contact.nc", "contact_area_ratio")
    monkeypatch.setattr(integrity, "VERIFY_LIMIT_BYTES", 0)  # every file counts as big
    assert {p.status for p in engine.plan(raw, out)} == {"fresh"}  # documented: big files by key only
    assert {p.stage.name: p.status for p in engine.plan(raw, out, verify=True)}["contact"] == "stale"


def test_the_checksum_covers_every_variable_and_attribute(tmp_path):
    engine.run(make_scene(numerics={**SMALL, "chunks": {"p": 4}}, outputs={"variables": ["stress_distribution"]}),
               tmp_path, report=_quiet())
    record = json.loads(xr.open_dataset(tmp_path / "contact.nc").attrs[integrity.ATTR])
    with xr.open_dataset(tmp_path / "contact.nc") as ds:
        assert set(record["blocks"]) == set(ds.variables)
    assert record["blocks"]["contact_area_ratio"][-1] == 4 or 4 in record["blocks"]["contact_area_ratio"]
    assert integrity.verify(tmp_path / "contact.nc") is True


def test_checksums_hashed_in_memory_are_those_of_the_file_read_back(tmp_path):
    """A result written in one piece is hashed from the values the store encoded, not read back
    (issue 27): the checksum must be the one reading the file back gives, for values that change on
    the way to the file (a variable packed into scaled integers with a fill value for NaN; booleans,
    written as bytes) or might (NaN with its sign bit set, -0.0; text; scalars; a compressed
    variable), and for real results."""
    from roughcontact import cf, store

    negative_nan = -np.full(3, np.nan)
    assert np.signbit(negative_nan).all()
    tricky = xr.Dataset(
        {"with_nan": ("x", np.array([1.0, -0.0, 2.0]) + np.where([False, True, False], negative_nan, 0.0)),
         "flag": ("x", np.array([True, False, True])), "count": ("x", np.arange(3, dtype=np.int32)),
         "label": ("x", np.array(["a", "bb", "ccc"])), "scalar": ((), 2.5),
         "large": (("x", "y"), np.linspace(0.0, 1.0, 3 * 4000).reshape(3, 4000))},
        coords={"x": [0.1, 0.2, 0.3], "y": np.arange(4000.0)}, attrs={"title": "tricky", "ok": "True"})
    tricky["packed"] = ("x", np.array([0.25, np.nan, 1.5]))
    tricky["packed"].encoding = {"dtype": "int16", "scale_factor": 0.01, "_FillValue": -1}  # stored as integers
    run = engine.run(make_scene(numerics=SMALL), tmp_path / "run", report=_quiet())
    cases = {"tricky": tricky, **{name: ds.drop_attrs(deep=False).drop_encoding() for name, ds in run["base"].items()}}
    for name, ds in cases.items():
        path = tmp_path / f"{name}.nc"
        store.write(ds, path)
        stored = json.loads(xr.open_dataset(path).attrs[integrity.ATTR])
        copy = tmp_path / f"{name}-read-back.nc"
        copy.write_bytes(path.read_bytes())
        integrity.stamp(copy)  # every variable read back from the file
        assert json.loads(xr.open_dataset(copy).attrs[integrity.ATTR]) == stored, name
        assert integrity.verify(path) is True, name
    with xr.open_dataset(tmp_path / "tricky.nc") as back:
        assert "zlib" in str(cf.encoding(tricky)["large"]) and back["large"].encoding.get("zlib")
