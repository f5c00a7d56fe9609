"""Reading a scene for a command: the scene, or None after one ``error:`` line; the invalid
views and the files it drew without (a texture) are printed as warnings. ``render``,
``animate`` and the other commands read scenes through here, so they say the same things."""

from __future__ import annotations

import sys


def load_or_say(source: str, size=None, crease_angle=None):
    from core.scene.formats import ReaderError, load_scene
    try:
        scene = load_scene(source, size=size, crease_angle=crease_angle)
    except ReaderError as error:
        print(f"error: {error}", file=sys.stderr)
        return None
    for message in scene.view_messages:
        print(f"invalid view: {message}", file=sys.stderr)
    for message in scene.messages:
        print(f"warning: {message}", file=sys.stderr)
    return scene


def shipped_scenes() -> list:
    """The scene files in ``scenes/`` that the window opens (not the ``.views`` lists)."""
    from core.paths import ROOT
    from core.scene.formats import MESH_EXTENSIONS
    kinds = {".toml", ".tri", *MESH_EXTENSIONS}
    return sorted(p for p in (ROOT / "scenes").iterdir() if p.suffix.lower() in kinds)
