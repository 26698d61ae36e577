"""Every benchmark and report script of tests/benchmarks/ runs, in its --smoke mode (the same code
path at tiny sizes), so that none can rot unnoticed (issue 23: three crashed on main because
nothing ran them). A smoke run checks that the script finishes; its numbers are not checked, and
no benchmark asserts a wall-clock time."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parent / "benchmarks"
SCRIPTS = sorted(p.name for p in BENCHMARKS.glob("*.py") if not p.name.startswith("_"))


def test_the_folder_holds_the_benchmarks():
    assert "bench_friction.py" in SCRIPTS and not list(BENCHMARKS.parent.glob("bench_*.py"))


@pytest.mark.parametrize("script", SCRIPTS)
def test_benchmark_smoke_run_succeeds(script, tmp_path):
    done = subprocess.run([sys.executable, str(BENCHMARKS / script), "--smoke"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, f"{script} --smoke failed:\n{done.stdout[-2000:]}\n{done.stderr[-4000:]}"
    assert done.stdout.strip(), f"{script} --smoke printed nothing"
