"""The docs that are generated from code stay in step with it, and the README's quick start is
what CI runs."""

from pathlib import Path

from roughcontact import scene

ROOT = Path(__file__).resolve().parent.parent


def test_scene_reference_is_up_to_date():
    committed = (ROOT / "docs" / "scene-reference.md").read_text()
    assert committed == scene.reference() + "\n", "run: roughcontact reference > docs/scene-reference.md"


def test_readme_quick_start_test_command_is_what_ci_runs():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    assert "python -m pytest -q" in readme and ci.rstrip().endswith("python -m pytest -q")
    assert "roughcontact run" in readme


def test_every_builtin_scene_loads():
    for name, path in scene.builtin_scenes().items():
        assert scene.load(path).name == name
