"""The house rules of docs/contributing.md that the code itself can check: the packages import one way (dwr_gym ->
baselines -> train -> benchmarks), no module imports one that imports it back (an import inside a function counts),
and no module is over 450 lines."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LAYERS = ("dwr_gym", "baselines", "train", "benchmarks")
MAX_LINES = 450


def modules() -> dict[str, Path]:
    found = {}
    for package in LAYERS:
        for path in (ROOT / package).rglob("*.py"):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
            found[name] = path
    return found


def import_graph() -> dict[str, set[str]]:
    """Each module's imports of the project's modules (``from a import b`` is ``a.b`` where that is a module)."""
    known = modules()

    def project_module(name: str) -> str | None:
        while name and name not in known:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in known.items():
        imported = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {project_module(alias.name) for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                imported |= {f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in known
                             else project_module(node.module) for a in node.names}  # fmt: skip
        graph[name] = imported - {None, name}
    return graph


def test_the_packages_import_one_way() -> None:
    rank = {package: i for i, package in enumerate(LAYERS)}
    layer = lambda name: rank[name.split(".")[0]]  # noqa: E731
    upward = sorted((a, b) for a, deps in import_graph().items() for b in deps if layer(b) > layer(a))
    assert upward == []


def test_no_module_imports_one_that_imports_it_back() -> None:
    graph = import_graph()
    circles = []
    for start in graph:  # a depth-first search for a path back to the start
        stack, seen = [(start, (start,))], set()
        while stack:
            node, path = stack.pop()
            for nxt in graph[node]:
                if nxt == start:
                    circles.append(path)
                elif nxt not in seen:
                    seen.add(nxt)
                    stack.append((nxt, (*path, nxt)))
    assert circles == []


def test_no_module_is_over_450_lines() -> None:
    long = {name: n for name, path in modules().items() if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert long == {}
