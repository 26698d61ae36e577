"""The layout rules of docs/architecture.md hold: one package, layers that import only
downwards, no private imports, a small stage declaration, folders that hold what they say,
metadata and scene keys declared once and checked, one description of a result's shape that the
engine holds the computation to, checks before any write, dimensions a stage couples never
chunked, and the page's worked example runs."""

from __future__ import annotations

import ast
import dataclasses
import importlib.metadata
import math
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import make_scene

import roughcontact
from roughcontact import engine, scene as scenes, sizing, stage as stage_api
from roughcontact.stage import Shape, Stage, StageInput, UserError, Var

ROOT = Path(__file__).resolve().parent.parent
LAYERS = {"pipeline": ROOT / "pipeline", "stages": ROOT / "stages", "physics": ROOT / "physics"}


#: the example-data makers shipped beside the built-in scenes' data: tools, not the engine (they may
#: use the kernels that model the data they make)
DATA_MAKERS = LAYERS["pipeline"] / "scenes" / "data"


def _sources(layer: str):
    return sorted(p for p in LAYERS[layer].rglob("*.py") if DATA_MAKERS not in p.parents)


def _imports(path: Path):
    """(module, names, level) of every import statement of a file."""
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, (), 0
        elif isinstance(node, ast.ImportFrom):
            yield node.module or "", tuple(a.name for a in node.names), node.level


def test_one_package_and_no_generic_top_level_module():
    assert roughcontact.__version__
    installed = [d for d in importlib.metadata.distributions(name="roughcontact")
                 if str(getattr(d, "_path", "")).endswith(".dist-info")]  # not a build's egg-info in the checkout
    assert installed, "roughcontact is not installed (pip install .)"
    for dist in installed:
        tops = {f.parts[0] for f in dist.files or [] if f.suffix == ".py" and len(f.parts) > 1}
        assert tops <= {"roughcontact"}, f"the distribution installs other top-level packages: {tops}"
        top_level = (dist.read_text("top_level.txt") or "roughcontact").split()
        assert top_level == ["roughcontact"]
    for name in ("roughcontact.engine", "roughcontact.stages.contact", "roughcontact.physics.contact"):
        __import__(name)


@pytest.mark.parametrize("layer", ["pipeline", "stages", "physics"])
def test_layers_import_only_downwards(layer):
    # roughcontact.errors is a leaf module of exception types: a kernel may raise ComputationError
    allowed_rc = {"pipeline": ("roughcontact",), "stages": ("roughcontact.stage", "roughcontact.physics"),
                  "physics": ("roughcontact.physics", "roughcontact.errors")}[layer]
    forbidden_third_party = {"physics": ("xarray", "matplotlib", "dask", "netCDF4", "pint")}.get(layer, ())
    bad = []
    for path in _sources(layer):
        for module, names, level in _imports(path):
            where = f"{path.relative_to(ROOT)}: {'.' * level}{module} {names}"
            if level == 0 and module.split(".")[0] in ("pipeline", "stages", "physics"):
                bad.append(f"{where} (generic top-level name)")
            if level == 0 and module.startswith("roughcontact") and not module.startswith(allowed_rc):
                bad.append(where)
            if level == 0 and module.split(".")[0] in forbidden_third_party:
                bad.append(f"{where} (physics is pure numpy)")
            if layer == "pipeline" and (module.split(".")[0] in ("physics", "stages") and level >= 1
                                        or module.startswith(("roughcontact.physics", "roughcontact.stages"))):
                bad.append(f"{where} (the engine reaches stages only through the registry)")
            if level >= 2 and layer != "stages":
                bad.append(f"{where} (leaves its layer)")
            if layer == "stages" and level >= 2:
                bad.append(f"{where} (use roughcontact.stage / roughcontact.physics)")
    assert not bad, "\n".join(bad)


def test_no_module_imports_a_private_name_of_another():
    bad = []
    for layer in LAYERS:
        for path in _sources(layer):
            for module, names, level in _imports(path):
                private = [n for n in names if n.startswith("_") and not n.startswith("__")]
                if private:
                    bad.append(f"{path.relative_to(ROOT)}: from {'.' * level}{module} import {private}")
    assert not bad, "\n".join(bad)


def test_a_stage_declaration_stays_small():
    """One description per stage: at most 12 fields, at most 3 of them functions (compute,
    describe, check)."""
    fields = dataclasses.fields(Stage)
    callables = [f.name for f in fields if "Callable" in str(f.type)]
    assert len(fields) <= 12, [f.name for f in fields]
    assert sorted(callables) == ["check", "compute", "describe"]


def test_the_stages_folder_holds_stages():
    """Every module directly in stages/ registers a stage; what stages share lives in
    stages/shared/, figures in stages/figures/."""
    registry = stage_api.stages()
    modules = {st.compute.__module__ for st in registry.values()}
    for path in sorted((ROOT / "stages").glob("*.py")):
        if path.name != "__init__.py":
            assert f"roughcontact.stages.{path.stem}" in modules, f"{path.relative_to(ROOT)} registers no stage"


def test_E_star_is_derived_in_one_place():
    callers = [p.relative_to(ROOT) for p in _sources("stages") if "effective_modulus(" in p.read_text()]
    assert callers == [Path("stages/shared/material.py")]


def test_every_declared_scene_key_exists_and_a_misspelt_one_is_caught():
    registry, schema, shared = stage_api.stages(), stage_api.sections(), stage_api.coords()
    stage_api.check_declarations(registry, schema, shared)
    contact = registry["contact"]
    misspelt = dataclasses.replace(contact, reads=contact.reads + ("material.poisson",))
    with pytest.raises(ValueError, match=r"material\.poisson"):
        stage_api.check_declarations({**registry, "contact": misspelt}, schema, shared)
    no_section = dataclasses.replace(contact, reads=("materials.E",))
    with pytest.raises(ValueError, match=r"no scene section \[materials\]"):
        stage_api.check_declarations({**registry, "contact": no_section}, schema, shared)
    redeclared = dataclasses.replace(contact, coords={"p": Var("Pa", "pressure")})
    with pytest.raises(ValueError, match="redeclares the shared coordinate"):
        stage_api.check_declarations({**registry, "contact": redeclared}, schema, shared)
    with pytest.raises(KeyError, match="does not declare"):
        StageInput(params={"material.E": 1.0}, stage="contact")["material.nu"]


def _toy(name, compute, **kwargs):
    return Stage(name=name, version="1", compute=compute, needs=("psd",), **kwargs)


@pytest.fixture
def toy_registry(monkeypatch):
    """Register toy stages for one test only."""
    stage_api.stages()

    def add(st):
        monkeypatch.setitem(stage_api._STAGES, st.name, st)
        return st

    return add


def _run(tmp_path, target):
    sc = scenes.from_dict(make_scene(outputs={"variables": [target]}))
    return engine.run(sc, tmp_path / "out", report=engine.Reporter(None))


def test_engine_stamps_declared_metadata_and_refuses_what_a_stage_labels_itself(tmp_path, toy_registry):
    declared = Var("m", "toy length", standard_name="toy_length_for_the_test")

    def good(inp):
        return xr.Dataset({"toy_length": xr.DataArray(np.arange(3.0), dims=("p",), coords={"p": [1.0, 2.0, 3.0]})})

    toy_registry(_toy("toy_good", good, outputs={"toy_length": declared}))
    ds = _run(tmp_path, "toy_length")["base"]["toy_good"]
    assert {k: ds["toy_length"].attrs[k] for k in ("units", "long_name", "standard_name")} == declared.stamp()
    assert ds["p"].attrs["units"] == "Pa" and ds["p"].attrs["long_name"] == "nominal pressure"

    def labelled(inp):
        return xr.Dataset({"toy_speed": xr.DataArray(1.0, attrs={"units": "km/h", "long_name": "speed"})})

    toy_registry(_toy("toy_labelled", labelled, outputs={"toy_speed": Var("m/s", "toy speed")}))
    with pytest.raises(RuntimeError, match="labels 'toy_speed' itself"):
        _run(tmp_path, "toy_speed")

    def stray(inp):
        return xr.Dataset({"toy_mass": xr.DataArray([1.0], dims=("stray",), coords={"stray": [0.0]})})

    toy_registry(_toy("toy_stray", stray, outputs={"toy_mass": Var("kg", "toy mass")}))
    with pytest.raises(RuntimeError, match="coordinate 'stray' that nothing declares"):
        _run(tmp_path, "toy_mass")


def test_a_dimension_the_stage_couples_is_never_chunked(toy_registry):
    raw = make_scene()
    raw["numerics"]["chunks"] = {"p": 2, "eta": 1}
    sc = scenes.from_dict(raw)
    free = toy_registry(_toy("toy_free", lambda inp: None, outputs={"toy_a": Var("1", "a")}))
    coupled = toy_registry(_toy("toy_coupled", lambda inp: None, outputs={"toy_b": Var("1", "b")},
                                describe=lambda inp: Shape(coupled=("p",))))
    sweeps = sc.sweep_sizes()
    assert sizing.stage_chunks(sc, free, frozenset(), Shape(), sweeps) == {"p": 2, "eta": 1}
    chunks = sizing.stage_chunks(sc, coupled, frozenset(), coupled.describe(None), sweeps)
    assert chunks == {"eta": 1}
    inp = StageInput(params={}, chunks=chunks)
    assert inp.sweep("p", np.arange(9.0)).chunks is None


def test_a_sweep_the_result_does_not_span_takes_no_share_of_the_chunk_budget(toy_registry):
    """A stage whose result spans the draws but not the pressures (the psd stage with bands) gets
    draw blocks as large as the memory budget allows: the pressures do not shrink them."""
    raw = make_scene(load={"p": {"from": "1 kPa", "to": "1 MPa", "num": 100}}, bands={"draws": 200})
    raw["interface"]["eta"] = [0.0, 0.5, -0.5]
    sc = scenes.from_dict(raw)
    st = toy_registry(_toy("toy_spectra", lambda inp: None, outputs={"toy_c": Var("m^4", "c")}))
    work = Shape(work={"values": 2**20 / 8 / 201})  # about 201 sweep points per block of chunk_mb = 1 MiB
    sc.chunk_mb = 1
    everything = sizing.stage_chunks(sc, st, frozenset(), work, sc.sweep_sizes())
    spanned = {d: n for d, n in sc.sweep_sizes().items() if d != "p"}
    without_p = sizing.stage_chunks(sc, st, frozenset(), work, spanned)
    assert "p" not in without_p and everything.get("draw", 201) < without_p.get("draw", 201)
    block = math.prod(without_p.get(d, n) for d, n in spanned.items())
    assert block <= 201 < 2 * block  # as large as halving the largest dimension allows


def test_a_result_unlike_its_description_is_refused(tmp_path, toy_registry):
    """describe and compute cannot drift: the engine compares the computed result with the shape
    the preflight relied on."""
    def compute(inp):
        return xr.Dataset({"toy_level": xr.DataArray(np.zeros(4), dims=("toy_node",))})

    toy_registry(_toy("toy_drift", compute, outputs={"toy_level": Var("1", "level")},
                      coords={"toy_node": Var("1", "node")}, describe=lambda inp: Shape(sizes={"toy_node": 5})))
    with pytest.raises(RuntimeError, match="toy_node of size 4, but its describe said 5"):
        _run(tmp_path, "toy_level")


def test_a_check_refuses_before_anything_is_written(tmp_path, toy_registry):
    def check(inp):
        raise UserError("toy rule between keys", key="load.p")

    toy_registry(_toy("toy_checked", lambda inp: pytest.fail("computed"), outputs={"toy_c": Var("1", "c")},
                      check=check))
    with pytest.raises(UserError, match="toy rule"):
        _run(tmp_path, "toy_c")
    assert not list((tmp_path / "out").glob("*.nc"))  # not even the upstream psd result


def test_an_upstream_stage_needed_only_by_some_scenes_is_data():
    psd = stage_api.stages()["psd"]
    assert psd.upstream_for({"substrate": {"kind": "self_affine"}, "solid": {"kind": "smooth"}}) == ()
    assert psd.upstream_for({"substrate": {"kind": "self_affine"}, "solid": {"kind": "container"}}) == ("topography",)
    bands = stage_api.stages()["bands"]
    assert bands.upstream_for({"outputs": {"variables": ["psd_combined_band"]}}) == ("psd",)
    assert set(bands.upstream_for({"outputs": {"variables": ["mean_separation_band"]}})) == {"psd", "separation"}


def test_the_architecture_page_example_runs_as_written(tmp_path):
    text = (ROOT / "docs" / "architecture.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 1 and len(blocks[0].strip().splitlines()) <= 30
    script = blocks[0] + textwrap.dedent(f"""
        from roughcontact import engine, scene
        sys_scene = scene.from_dict({make_scene(outputs={"variables": ["mean_contact_pressure"]})!r})
        results = engine.run(sys_scene, __import__("pathlib").Path({str(tmp_path)!r}), report=engine.Reporter(None))
        ds, contact = results["base"]["mean_pressure"], results["base"]["contact"]
        assert ds["mean_contact_pressure"].attrs["units"] == "Pa"
        expected = contact["p"] / contact["contact_area_ratio"]
        mean = ds["mean_contact_pressure"]
        np.testing.assert_allclose(mean.values, expected.transpose(*mean.dims).values, rtol=1e-15)
        print("dims", ds["mean_contact_pressure"].dims)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert (tmp_path / "mean_pressure.nc").is_file()
    assert "dims" in out.stdout
