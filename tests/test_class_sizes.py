"""No class in ``app`` or ``core`` has more than 40 methods, counting what it inherits, and no
module in ``app`` is longer than 800 lines.

A class that grows past that does several jobs; it is split into parts that it holds (the
viewer's state and its views, choices, messages, ... in ``app.session``), not into mixins it
inherits from, since a mixin's methods still land on the one class.

The source is read, not imported (importing every module would pull in numba, GL and the
readers): a ``class`` statement's methods are its ``def`` statements, properties included,
dunders not; a base defined in the project (in the same module, or imported from another with
``from ... import``, followed through re-exports) adds its own, and so on up.
"""

from __future__ import annotations

import ast

from tests.test_layers import _modules

MOST_METHODS = 40
MOST_APP_LINES = 800     # a window, a command or a bench that grows past it does several jobs


def _own_methods(node: ast.ClassDef) -> set[str]:
    return {s.name for s in node.body
            if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef))
            and not (s.name.startswith("__") and s.name.endswith("__"))}


def method_counts(sources: dict[str, str]) -> dict[str, int]:
    """``"module.Class"`` -> how many methods it has, its project bases' included, for the
    modules' source texts ``sources`` (module name -> text)."""
    classes, imported = {}, {}
    for module, text in sources.items():
        tree = ast.parse(text)
        imported[module] = {a.asname or a.name: (node.module, a.name)
                            for node in ast.walk(tree)
                            if isinstance(node, ast.ImportFrom) and node.module
                            for a in node.names}
        for node in ast.walk(tree):            # classes inside functions too
            if isinstance(node, ast.ClassDef):
                classes.setdefault((module, node.name), node)

    def resolve(module: str, name: str, hops: int = 0):
        if (module, name) in classes:
            return module, name
        if name in imported.get(module, {}) and hops < 10:     # a re-export is followed
            return resolve(*imported[module][name], hops + 1)
        return None

    def methods(key) -> set[str]:
        node = classes[key]
        found = _own_methods(node)
        for base in node.bases:
            if isinstance(base, ast.Name) and (project_base := resolve(key[0], base.id)):
                found |= methods(project_base)
        return found

    return {f"{module}.{name}": len(methods((module, name))) for module, name in classes}


def project_method_counts() -> dict[str, int]:
    return method_counts({module: path.read_text() for module, path in _modules().items()})


def test_inherited_methods_are_counted_through_imports_and_re_exports():
    sources = {
        "p.mixins": "class Mixin:\n    def a(self): ...\n    @property\n    def b(self): ...\n",
        "p.reexport": "from p.mixins import Mixin as Renamed\n",
        "p.user": ("from p.reexport import Renamed\nimport threading\n"
                   "class Base:\n    def __init__(self): ...\n    def a(self): ...\n"
                   "class User(Base, Renamed, threading.Thread):\n    def c(self): ...\n"),
    }
    counts = method_counts(sources)
    assert counts == {"p.mixins.Mixin": 2, "p.user.Base": 1, "p.user.User": 3}


def test_no_class_has_more_than_40_methods():
    big = {name: n for name, n in project_method_counts().items() if n > MOST_METHODS}
    assert not big, "; ".join(f"{name} has {n} methods (its bases' included), more than "
                              f"{MOST_METHODS}" for name, n in sorted(big.items()))


def test_no_module_of_the_app_is_longer_than_800_lines():
    long = {name: len(path.read_text().splitlines()) for name, path in _modules().items()
            if name.startswith("app")}
    long = {name: n for name, n in long.items() if n > MOST_APP_LINES}
    assert not long, "; ".join(f"{name} has {n} lines, more than {MOST_APP_LINES}"
                               for name, n in sorted(long.items()))
