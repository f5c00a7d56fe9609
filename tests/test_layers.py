"""The import graph: no cycles between modules, and the layers import only downwards.

Layers, from the bottom: ``core`` (numbers, scene, camera, pipeline, shading, renderers, the
front door) → ``core.analysis`` (accuracy, stability, exact arithmetic) → ``app`` (viewer,
commands, benches, oracles, reports, distribution, command line). A module may import only from its own layer or below; imports inside
functions count too (they are still dependencies), and so do modules named in strings (the
registries' lazy "package.module:function" entries, ``importlib.import_module("…")``).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.conftest import ROOT


def _modules() -> dict[str, Path]:
    found = {}
    for package in ("core", "app"):
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


# A module named in a string, as the registries name what they import lazily
# ("core.renderers.painters.plan:bsp_stages") or importlib is handed one: a dependency too.
STRING_IMPORT = re.compile(r"^((?:core|app)(?:\.\w+)+)(?::\w+)?$")


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
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                named = STRING_IMPORT.match(node.value)
                names = [named.group(1)] if named else []
            else:
                continue
            targets |= {n for n in names if n in modules}
        graph[name] = targets - {name}
    return graph


def test_a_module_named_in_a_string_is_an_import():
    registered = import_graph()["core.renderers"]
    assert "core.renderers.painters.plan" in registered     # plan_stages="…plan:bsp_stages"


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


# -- the order inside core ---------------------------------------------------------------
# Each package of core, lowest first, as docs/architecture.md lists them; a module may import
# from its own package, from a package of its own rank, or from one of a lower rank. Packages
# of one rank may use each other's public parts (the renderers: the z-buffer draws radiosity's
# elements, the path tracer reads radiosity's patches).
CORE_RANKS = {
    "core.jit": 0, "core.vectors": 0, "core.transforms": 0, "core.settings": 0, "core.paths": 0,
    "core.registry": 0, "core.registries": 0, "core.arrays": 0, "core.progressive": 0,
    "core.work": 0, "core.prefetch": 0, "core.colour": 0,
    "core.camera": 1,
    "core.scene": 2,
    "core.context": 3,
    "core.pipeline": 4,
    "core.shading": 5,
    "core.texture": 6,
    "core.raytrace": 7, "core.visibility": 7,
    "core.plan": 8, "core.stages": 8,
    "core.renderers": 9, "core.radiosity": 9, "core.pathtrace": 9, "core.volume": 9,
    "core.twopass": 9,
    "core.effects": 10,
    "core.render": 11,
    "core.inspect": 12, "core.animation": 12, "core.systems": 12, "core": 12,
    "core.analysis": 13,
}


def core_package(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 else parts[0]


def upward_imports() -> list[tuple[str, str]]:
    """(module, imported module) where core's order is broken (imports in functions too)."""
    wrong = []
    for a, targets in import_graph().items():
        if not a.startswith("core"):
            continue
        pa = core_package(a)
        for b in targets:
            pb = core_package(b)
            if b.startswith("core") and pa != pb and CORE_RANKS[pb] > CORE_RANKS[pa]:
                wrong.append((a, b))
    return sorted(wrong)


def test_every_core_package_has_a_rank():
    packages = {core_package(m) for m in import_graph() if m.startswith("core")}
    assert packages <= set(CORE_RANKS), sorted(packages - set(CORE_RANKS))
    assert set(CORE_RANKS) <= packages, sorted(set(CORE_RANKS) - packages)


def test_core_packages_import_only_their_own_rank_or_below():
    assert upward_imports() == []


def private_imports() -> list[tuple[str, str, str]]:
    """(module, from module, name): a name with a leading underscore imported from another
    package (a helper two packages share is public in the one that owns it)."""
    found = []
    for name, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                if core_package(node.module) == core_package(name):
                    continue
                found += [(name, node.module, a.name) for a in node.names
                          if a.name.startswith("_") and node.module.split(".")[0] in ("core", "app")]
    return sorted(found)


def test_no_private_name_is_imported_across_packages():
    assert private_imports() == []


def _module_names(tree, modules) -> dict[str, str]:
    """The names a module binds to other modules of ours (``from core.texture import sample
    as sampling``, ``import app.commands.animate as animate``): name -> module."""
    bound = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            bound.update({a.asname or a.name: f"{node.module}.{a.name}" for a in node.names
                          if f"{node.module}.{a.name}" in modules})
        elif isinstance(node, ast.Import):
            bound.update({a.asname: a.name for a in node.names
                          if a.asname and a.name in modules})
    return bound


def private_attributes() -> list[tuple[str, str, str]]:
    """(module, other module, name): ``other._name`` read from another package's module."""
    modules, found = _modules(), set()
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        bound = _module_names(tree, modules)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in bound and node.attr.startswith("_")
                    and not node.attr.startswith("__")
                    and core_package(bound[node.value.id]) != core_package(name)):
                found.add((name, bound[node.value.id], node.attr))
    return sorted(found)


def test_no_private_module_attribute_is_read_across_packages():
    assert private_attributes() == []


# -- the packages of app -------------------------------------------------------------------
# Which package of app may import which (imports in functions too). The oracles are outside
# references and import nothing of app; the rest is the graph as it stands, so a new edge
# between them is a decision made here. Modules never import each other in a loop (above).
# ``app`` is app's own modules (cli, loading, naming, output_files, startup_gc, versions).
APP_PACKAGES = ("commands", "bench", "oracles", "reports", "distribution", "session", "viewer")
APP_IMPORTS = {                    # lowest first; no package imports one above it
    "app.oracles": set(),
    "app.session": set(),          # what the window holds and the frames it asks for: no window
    "app.distribution": {"app", "app.session"},     # the warm-up makes the window's frames
    "app.commands": {"app", "app.oracles", "app.distribution", "app.session"},
    "app.viewer": {"app", "app.distribution", "app.oracles", "app.session"},   # warm-up; OpenGL compare
    "app.bench": {"app", "app.oracles", "app.commands", "app.session", "app.viewer",
                  "app.distribution"},   # the blit's cost; --window: a warm cache first
    "app.reports": {"app.bench", "app.oracles"},
}


def app_package(module: str) -> str:
    parts = module.split(".")
    return f"app.{parts[1]}" if len(parts) > 1 and parts[1] in APP_PACKAGES else "app"


def app_imports_out_of_order(allowed: dict[str, set[str]]) -> list[tuple[str, str]]:
    wrong = []
    for a, targets in import_graph().items():
        pa = app_package(a) if a.startswith("app") else None
        if pa not in allowed:
            continue
        wrong += [(a, b) for b in targets if b.startswith("app")
                  and app_package(b) != pa and app_package(b) not in allowed[pa]]
    return sorted(wrong)


def test_app_packages_import_only_what_they_may():
    assert app_imports_out_of_order(APP_IMPORTS) == []


def test_the_order_of_app_packages_is_checked():
    """An import the table does not allow is found (the check can fail)."""
    found = app_imports_out_of_order({**APP_IMPORTS, "app.viewer": set()})
    assert ("app.viewer.launch", "app.distribution.warm_stamp") in found


def package_cycles(allowed: dict[str, set[str]]) -> list[tuple[str, ...]]:
    """Each pair of app packages that the table lets import each other, directly or round a
    longer loop (a depth-first search from every package)."""
    cycles = set()

    def walk(start, at, path):
        for nxt in allowed.get(at, ()):
            if nxt == start:
                cycles.add(tuple(sorted(path)))
            elif nxt not in path and nxt in allowed:
                walk(start, nxt, path + [nxt])
    for package in allowed:
        walk(package, package, [package])
    return sorted(cycles)


def test_no_two_app_packages_import_each_other():
    """The table is a partial order: the window imports the warm-up and the session, the
    warm-up the session, never back."""
    assert package_cycles(APP_IMPORTS) == []
    assert ("app.session", "app.viewer") in package_cycles(
        {**APP_IMPORTS, "app.session": {"app.viewer"}})
