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
