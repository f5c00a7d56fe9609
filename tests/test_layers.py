"""The import graph: no cycles between modules, and the layers import only downwards.

Layers, from the bottom: ``core`` (numbers, scene, camera, pipeline, shading, renderers, the
front door) → ``core.analysis`` (accuracy, stability, exact arithmetic) → ``app`` (viewer,
tools, command line). A module may import only from its own layer or below; imports inside
functions count too (they are still dependencies).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _modules() -> dict[str, Path]:
    found = {}
    for package in ("core", "app"):
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def import_graph() -> dict[str, set[str]]:
    modules = _modules()
    graph = {}
    for name, path in modules.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            else:
                continue
            targets |= {n for n in names if n in modules}
        graph[name] = targets - {name}
    return graph


def layer(module: str) -> int:
    if module.startswith("app"):
        return 2
    return 1 if module.startswith("core.analysis") else 0


def _is_package_of(a: str, b: str) -> bool:
    return b.startswith(a + ".")


def test_layers_import_only_downwards():
    wrong = [(a, b) for a, targets in import_graph().items() for b in targets
             if layer(b) > layer(a)]
    assert wrong == []


def test_no_import_cycles_between_modules():
    """Packages that re-export their modules (``core.scene`` → ``core.scene.model``) are not
    cycles; any other loop is."""
    graph = {a: {b for b in t if not _is_package_of(a, b)} for a, t in import_graph().items()}
    state, stack, cycles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert cycles == []
