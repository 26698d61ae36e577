"""The docs that are generated from code stay in step with it, and the README's quick start is
what CI runs."""

import re
from pathlib import Path

from roughcontact import scene

ROOT = Path(__file__).resolve().parent.parent


def test_scene_reference_is_up_to_date():
    committed = (ROOT / "docs" / "scene-reference.md").read_text()
    assert committed == scene.reference() + "\n", "run: roughcontact reference > docs/scene-reference.md"


def _quick_start(readme: str) -> list[str]:
    """The commands of the README's quick start: its first indented block."""
    section = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"\n\n((?:    \S.*\n)+)", section)
    return [line.strip() for line in block.group(1).splitlines()]


def test_readme_quick_start_is_two_commands_and_exactly_what_ci_runs():
    commands = _quick_start((ROOT / "README.md").read_text())
    ci = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()
          if line.strip() and not line.lstrip().startswith("#")]
    assert len(commands) == 2
    first, second = commands
    # each sets itself up: an install of the package (then its test extra) before it runs
    assert first.startswith("python -m pip install . && ") and first.endswith("roughcontact run")
    assert second.startswith('python -m pip install ".[test]" && ') and second.endswith("python -m pytest -q")
    assert ci[-2:] == commands  # the last two lines CI runs, in a fresh virtual environment
    assert "python3 -m venv" in " ".join(ci) and ci[0] == "set -euo pipefail"


def test_every_builtin_scene_loads():
    for name, path in scene.builtin_scenes().items():
        assert scene.load(path).name == name
