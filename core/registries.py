"""One shape for every registry of the core: entries by name, looked up with one error.

Every registry is a :class:`Registry`: the renderers and the shading modes
(:mod:`core.registry`), the shaders (:mod:`core.shading.registry`), the lighting models
(:mod:`core.shading.models.registry`), the systems' scene and material keys
(:mod:`core.scene.formats.keys`) and the mesh file types (:mod:`core.scene.formats.mesh.read`).
Each module keeps its own entry type and its public functions, thin wrappers over its
registry. Every entry is plain data with

- ``name``: what it is registered and chosen by (a scene file's key, a command-line value);
- ``label``: its words in menus and listings (the name unless given);
- ``description``: a line on what it is (may be empty);
- its capabilities as fields, and its functions as ``"package.module:function"`` strings
  imported when first used (:func:`load`), or as the functions themselves.

A registry may have a *loader*, which imports the modules that register the built-in entries:
it is called with the name sought when a lookup misses (then with None, for every built-in,
so that the error names them all) and with None before a listing. Python imports a module
once, so the calls after the first cost a dictionary lookup.

This module imports nothing from the core, so every layer may hold a registry.
"""

from __future__ import annotations

import importlib
from typing import Callable


def load(target: str | Callable) -> Callable:
    """The function ``"package.module:function"`` names, its module imported now (a function
    is its own target)."""
    if callable(target):
        return target
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


class Registry:
    """Entries by name, in the order they registered (registered again under a name, an entry
    replaces the old one in its place). ``kind`` is the error's words: "KIND must be one of
    A, B, not 'x'"."""

    def __init__(self, kind: str, loader: Callable[[str | None], None] | None = None):
        self.kind = kind
        self._entries: dict[str, object] = {}
        self._loader = loader

    def register(self, entry):
        self._entries[entry.name] = entry
        return entry

    def unregister(self, name: str) -> None:
        """Remove ``name`` if it is there (a test's or a plug-in's entry)."""
        self._entries.pop(name, None)

    def _find(self, name: str):
        """The entry, or None; a miss loads the name's module, then every built-in."""
        for wanted in (name, None):
            if name in self._entries or self._loader is None:
                break
            self._loader(wanted)
        return self._entries.get(name)

    def get(self, name: str):
        entry = self._find(name)
        if entry is None:
            raise ValueError(f"{self.kind} must be one of {', '.join(self._entries)}, "
                             f"not {name!r}")
        return entry

    def __contains__(self, name: str) -> bool:
        return self._find(name) is not None

    def entries(self) -> tuple:
        if self._loader is not None:
            self._loader(None)
        return tuple(self._entries.values())

    def names(self) -> tuple[str, ...]:
        return tuple(entry.name for entry in self.entries())

    def names_that(self, capability: str) -> tuple[str, ...]:
        """The entries whose field ``capability`` is set, in order."""
        return tuple(entry.name for entry in self.entries() if getattr(entry, capability))
