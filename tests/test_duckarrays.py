"""The command line's xarray without dask.array and pint for numpy results (pipeline/duckarrays.py,
issue 27): a small run imports neither, once they are imported xarray still sees their arrays, and
the Python API leaves xarray as it is.

Each check runs in a fresh interpreter: which modules a process has imported is the fact tested.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from roughcontact import duckarrays


def _python(code: str, env: dict | None = None) -> dict:
    """Run ``code`` in a fresh interpreter; it prints one JSON line, returned."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300,
                          env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


needs_layout = pytest.mark.skipif(not duckarrays.supported(), reason="an xarray laid out otherwise")


@needs_layout
def test_a_small_run_imports_neither_dask_nor_pint(tmp_path):
    """The default scene into a fresh folder, its parsed scene cached (a scene parsed for the first
    time reads its quantities with pint: roughcontact.units)."""
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "cache"))
    _python("import json; from roughcontact import scene; scene.load('default'); print('{}')", env)
    seen = _python(f"""
        import contextlib, io, json, sys
        from roughcontact.cli import main
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            assert main(["run", "default", "--outdir", {str(tmp_path / "out")!r}]) == 0
        print(json.dumps({{m: m in sys.modules for m in ("dask", "dask.array", "pint", "distributed")}}))
    """, env)
    assert seen == {"dask": False, "dask.array": False, "pint": False, "distributed": False}


@needs_layout
def test_dask_and_pint_arrays_are_still_seen_once_imported():
    seen = _python("""
        import json, sys
        import numpy as np
        import xarray as xr
        from roughcontact import duckarrays
        duckarrays.install()
        before = xr.DataArray(np.zeros(3), dims="x", coords={"x": [0.0, 1.0, 2.0]})
        out = {"installed": duckarrays.installed("dask") and duckarrays.installed("pint"),
               "dask imported by numpy data": "dask.array" in sys.modules or "dask" in sys.modules,
               "pint imported by numpy data": "pint" in sys.modules}
        import dask.array as da
        lazy = xr.DataArray(da.zeros(4, chunks=2), dims="x")
        out["dask array kept lazy"] = lazy.chunks == ((2, 2),)
        out["numpy chunked"] = before.chunk({"x": 1}).chunks == ((1, 1, 1),)
        out["dask sum"] = float(lazy.sum().compute()) == 0.0
        import pint
        ureg = pint.UnitRegistry()
        quantity = xr.DataArray(ureg.Quantity(np.arange(3.0), "m"), dims="x")
        out["pint kept"] = isinstance(quantity.data, ureg.Quantity)
        metres = ureg.Quantity(np.arange(3.0), "m")
        indexed = xr.DataArray(np.ones(3), dims="x", coords={"x": metres})
        out["pint index"] = indexed.x.values.tolist() == [0.0, 1.0, 2.0]
        out["handed over"] = not duckarrays.installed("dask") and not duckarrays.installed("pint")
        print(json.dumps(out))
    """)
    assert seen == {"installed": True, "dask imported by numpy data": False, "pint imported by numpy data": False,
                    "dask array kept lazy": True, "numpy chunked": True, "dask sum": True, "pint kept": True,
                    "pint index": True, "handed over": True}


@needs_layout
def test_libraries_imported_before_keep_xarrays_own_entries():
    seen = _python("""
        import json
        import dask.array, pint
        from roughcontact import duckarrays
        duckarrays.install()
        print(json.dumps([duckarrays.installed("dask"), duckarrays.installed("pint")]))
    """)
    assert seen == [False, False]


@needs_layout
def test_the_python_api_leaves_xarray_as_it_is():
    seen = _python("""
        import json, sys
        import roughcontact as rc
        from roughcontact import duckarrays
        rc.compute("default")
        print(json.dumps([duckarrays.installed("dask"), duckarrays.installed("pint"), "dask.array" in sys.modules]))
    """)
    assert seen == [False, False, True]  # xarray imported dask.array for the first DataArray, as it always does
