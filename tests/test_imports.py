"""No import cycles among roughcontact's own modules (issue 23).

The import graph is built from the source with ``ast`` over the three folders the package is
built from (pipeline/, stages/, physics/, mapped to module names through the package-dir table of
pyproject.toml). Every ``import`` statement counts, wherever it stands: an import deferred into a
function to dodge a cycle is still a cycle (deferring a heavy third-party library for start-up
time is fine: it is not one of our modules). Relative imports are resolved; ``from . import x``
counts as importing the submodule ``x`` when there is one, else the package itself, so
``from . import __version__`` imports pipeline/__init__.py. Importing ``roughcontact.a.b`` counts
as importing that module (not its parent packages). Importing by string (``importlib``, as the
stage registry loads the stages) is not an import edge.
"""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def modules() -> dict[str, Path]:
    """Module name -> source file, through pyproject.toml's package-dir mapping."""
    package_dir = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    found = {}
    for package, folder in package_dir.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if ".venv" in parts or "__pycache__" in parts:
                continue
            found[".".join((package, *parts))] = path
    return found


def _base(module: str, path: Path, node: ast.ImportFrom) -> str:
    """The absolute module a ``from ... import`` statement names."""
    if node.level == 0:
        return node.module or ""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for _ in range(node.level - 1):
        package = package.rpartition(".")[0]
    return f"{package}.{node.module}" if node.module else package


def _ours(name: str, known) -> str | None:
    """The deepest of our modules that ``name`` (a dotted module name) is or lies in."""
    while name and name not in known:
        name = name.rpartition(".")[0]
    return name or None


def import_graph() -> dict[str, set[str]]:
    """Module -> the modules of ours it imports, anywhere in its source."""
    known = modules()
    graph = {}
    for module, path in known.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets.update(_ours(alias.name, known) for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = _base(module, path, node)
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    targets.add(sub if sub in known else _ours(base, known))
        graph[module] = {t for t in targets if t and t != module}
    return graph


def _shortest_path(start: str, goal: str, members: set[str], graph) -> list[str]:
    """The shortest import path from ``start`` to ``goal`` inside ``members`` (breadth first)."""
    previous = {start: None}
    queue = [start]
    while queue:
        node = queue.pop(0)
        if node == goal:
            path = [node]
            while previous[path[-1]] is not None:
                path.append(previous[path[-1]])
            return path[::-1]
        for nxt in sorted(graph[node] & members):
            if nxt not in previous:
                previous[nxt] = node
                queue.append(nxt)
    raise AssertionError(f"{goal} not reachable from {start} inside its component")


def cycles(graph) -> list[str]:
    """The import cycles, as "a -> b -> a": for every import inside a strongly connected
    component, the shortest cycle through it (so every import that closes a cycle is shown)."""
    index, low, stack, on_stack, components = {}, {}, [], set(), []

    def visit(node):  # Tarjan's algorithm
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                components.append(component)

    for node in sorted(graph):
        if node not in index:
            visit(node)
    shown = set()
    for component in components:
        for a in component:
            for b in graph[a] & component:
                cycle = [a, *_shortest_path(b, a, component, graph)]
                first = cycle.index(min(cycle[:-1]))
                cycle = cycle[first:-1] + cycle[:first + 1]  # the same cycle always starts at its first module
                shown.add(" -> ".join(cycle))
    return sorted(shown)


def test_the_graph_sees_deferred_and_relative_imports():
    graph = import_graph()
    assert "roughcontact.api" in graph["roughcontact"]  # deferred into __getattr__
    assert "roughcontact.physics.contact" in graph["roughcontact.stages.contact"]
    assert "roughcontact.errors" in graph["roughcontact.readers"]  # from .errors import UserError
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == ["a -> b -> c -> a"]


def test_no_import_cycles_among_our_modules():
    found = cycles(import_graph())
    assert not found, "import cycles (a deferred import is still one):\n" + "\n".join(found)


def test_every_package_folder_is_listed_for_the_build():
    """A folder of modules missing from ``[tool.setuptools] packages`` still installs from a git
    clone (setuptools-scm's file finder carries it along as data) but not from a tarball, where the
    import then fails: every folder with an ``__init__.py`` must be listed."""
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setuptools["packages"])
    for package, folder in setuptools["package-dir"].items():
        for init in (ROOT / folder).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT / folder).parts
            if ".venv" in parts or "__pycache__" in parts:
                continue
            assert ".".join((package, *parts)) in listed, f"{init.parent} is not in pyproject's packages"
