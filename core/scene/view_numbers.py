"""Views numbered by their position in the file, as the course numbers them.

A view file may hold invalid views between valid ones; the reader's messages already number
views by position ("view 3 (line 13): VUP is parallel to VPN"), and so does everything else:
``--view K`` is the K-th view of the file, the window says "view 7 of 20 (6 invalid)".
``Scene.views`` keeps only the valid ones (what a renderer can draw); this module maps
between the two numberings using ``Scene.view_order`` (every view in file order).
"""

from __future__ import annotations

from core.camera.view import View


class ViewNumberError(ValueError):
    """``--view K`` names no view, or an invalid one; the message says which and why."""


def entries(scene) -> list:
    """Every view in file order: the View when valid, the reader's message when not."""
    order = scene.view_order
    return list(order) if order else [*scene.views, *scene.view_messages]


def file_number(scene, index: int) -> int:
    """The file position (from 1) of ``scene.views[index]``."""
    target = scene.views[index]
    for number, entry in enumerate(entries(scene), start=1):
        if entry is target:
            return number
    return index + 1                   # a scene built by hand: its views are its file


def total(scene) -> int:
    """How many views the file holds, valid or not."""
    return len(entries(scene))


def invalid_count(scene) -> int:
    return total(scene) - len(scene.views)


def index_of(scene, number: int) -> int:
    """``scene.views`` index of file view ``number``; ViewNumberError when it is invalid or
    there is no such view (the message is the reader's own for an invalid one)."""
    order = entries(scene)
    if not order:
        raise ViewNumberError(f"{scene.name}: the scene has no views")
    if not 1 <= number <= len(order):
        raise ViewNumberError(f"--view {number}: the file has {len(order)} views (1 to "
                              f"{len(order)})")
    entry = order[number - 1]
    if not isinstance(entry, View):
        raise ViewNumberError(f"--view {number} is invalid: {entry}")
    for index, view in enumerate(scene.views):
        if view is entry:
            return index
    raise ViewNumberError(f"--view {number}: not among the scene's views")


def label(scene, index: int) -> str:
    """``"view 7 of 20 (6 invalid)"`` for ``scene.views[index]``, or why there is none."""
    if not scene.views:
        n = total(scene)
        return f"no valid view ({n} invalid)" if n else "no view"
    bad = invalid_count(scene)
    return (f"view {file_number(scene, index)} of {total(scene)}"
            + (f" ({bad} invalid)" if bad else ""))
