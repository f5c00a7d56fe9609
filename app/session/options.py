"""The current renderer's own options as the window's panel shows them.

A renderer that registers an options class (``core.registry``: the ray tracer's depth limit
and shadows, radiosity's solver, the painters' BSP root) gets one control per field, read from
the class itself: its type gives the kind of control, its metadata the choices of a named
option and a line of help, and ``"panel": False`` leaves a field out (the painters'
``paint_first`` has the draw-order slider). A new renderer's options appear in the panel
with no change here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

# A field's annotation (a string: the options modules use postponed annotations) -> control.
KINDS = {"bool": "bool", "int": "int", "float": "float", "str": "choice",
         "tuple[float, float]": "pair"}


@dataclass(frozen=True)
class Control:
    name: str                  # the field's name: settings.replace(name=value) sets it
    kind: str                  # "bool" | "int" | "float" | "choice" | "pair"
    value: object
    choices: tuple = ()
    help: str = ""

    @property
    def label(self) -> str:
        return self.name.replace("_", " ")


def controls(options) -> list[Control]:
    """One control per field of the options object ``options`` that the panel shows (none
    for None: a renderer without options). A field of a type with no control is left out."""
    if options is None:
        return []
    found = []
    for f in dataclasses.fields(options):
        kind = KINDS.get(str(f.type))
        if kind is None or not f.metadata.get("panel", True):
            continue
        if kind == "choice" and "choices" not in f.metadata:
            continue                              # a free string: nothing to choose from
        found.append(Control(f.name, kind, getattr(options, f.name),
                             tuple(f.metadata.get("choices", ())), f.metadata.get("help", "")))
    return found
