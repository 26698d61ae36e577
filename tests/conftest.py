"""Shared fixtures: small scenes built as dicts, run into a temporary folder."""

from __future__ import annotations

import copy
import re

import pytest

from roughcontact import engine, scene as scenes

SURFACE = {"kind": "self_affine", "H": 0.8, "qL": "2e8 1/m", "q1": "4e10 1/m", "hrms": "1 nm"}

BASE = {
    "name": "test",
    "substrate": dict(SURFACE),
    "solid": dict(SURFACE),
    "interface": {"eta": [0.0, 1.0, -1.0]},
    "material": {"E": "77.2 GPa", "nu": 0.42},
    "load": {"p": {"from": "1 MPa", "to": "10 GPa", "num": 9}},
    "contact": {"zeta": [4.0, 200.0]},
    "outputs": {"variables": ["contact_area_ratio"]},
    "numerics": {"points_per_decade": 20},
}


def make_scene(**overrides) -> dict:
    """A copy of BASE with top-level tables replaced or updated: ``make_scene(material={"E": ...})``
    updates keys in the table; pass ``None`` to drop a table."""
    raw = copy.deepcopy(BASE)
    for key, value in overrides.items():
        if value is None:
            raw.pop(key, None)
        elif isinstance(value, dict) and isinstance(raw.get(key), dict) and "kind" not in value:
            raw[key].update(value)
        else:
            raw[key] = value
    return raw


@pytest.fixture
def run_scene(tmp_path):
    """Run a scene dict; returns results[variant][stage]."""

    def _run(raw, outdir=None, **kw):
        sc = scenes.from_dict(raw)
        return engine.run(sc, outdir or tmp_path / "out", report=engine.Reporter(None), **kw)

    return _run


def toml_dumps(raw: dict) -> str:
    """A minimal TOML writer for test scenes (tables of scalars, lists and inline tables)."""

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in raw.items() if not isinstance(v, dict)]
    for k, v in raw.items():
        if isinstance(v, dict):
            if k == "variants":
                for name, over in v.items():
                    lines.append(f"\n[variants.{name}]")
                    lines += [f"{a} = {value(b)}" for a, b in over.items()]
                continue
            lines.append(f"\n[{k}]")
            lines += [f"{a} = {value(b)}" for a, b in v.items()]
    return "\n".join(lines) + "\n"


@pytest.fixture
def write_scene(tmp_path):
    def _write(raw, name="scene.toml"):
        path = tmp_path / name
        path.write_text(toml_dumps(raw))
        return path

    return _write


def cli_error_line(capsys, *args):
    """Run the command line; return (exit code, its error line). --quiet still prints one line per
    stage ("[1/2] psd: ..."); apart from those, a failure says one line and never a traceback."""
    from roughcontact.cli import main

    code = main(list(map(str, args)))
    err = capsys.readouterr().err.strip()
    err = "\n".join(line for line in err.splitlines() if not re.match(r"\[\d+/\d+\] ", line))
    assert "Traceback" not in err and len(err.splitlines()) <= 1, err
    return code, err
