"""One rule for the name of every file the viewer writes.

The PNGs of ``make run`` without a display, the window's screenshots, ``render`` without
``--out`` and ``animate``'s frames are all named here, so that they read alike and are safe on
every file system: lowercase ASCII letters, digits, hyphens and underscores only (no spaces,
colons, slashes or accents), the parts joined by hyphens, the scene's name shortened at a word
boundary, never in the middle of a word::

    whitted-glass-and-mirror-spheres-view01-perspective-phong-raytrace.png
    fvdfh-house-view05-perspective-wireframe-zbuffer.png
    frame_00042.png
"""

from __future__ import annotations

import re
import unicodedata
from pathlib import Path

SCENE_PART = 32          # the most characters of the scene's name a file name keeps
SAFE_NAME = re.compile(r"^[a-z0-9]+([-_][a-z0-9]+)*\.[a-z0-9]+$")   # every name matches


def slug(text: str, limit: int = SCENE_PART, empty: str = "scene") -> str:
    """``text`` as lowercase ASCII words joined by hyphens, at most ``limit`` characters, cut
    at the last whole word ("Whitted: glass…" → "whitted-glass…")."""
    ascii_text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    words = re.findall(r"[a-z0-9]+", ascii_text.lower())
    kept = ""
    for word in words:
        joined = f"{kept}-{word}" if kept else word
        if len(joined) > limit:
            if not kept:                     # one word longer than the limit: cut it
                kept = word[:limit]
            break
        kept = joined
    return kept or empty


def picture_name(scene_name: str, view_number: int, projection: str, shading: str,
                 renderer: str) -> str:
    """The file name of one picture: scene, view (its place in the file), projection,
    shading and renderer, e.g. ``torus-view01-perspective-phong-zbuffer.png``."""
    parts = [slug(scene_name), f"view{view_number:02d}", slug(projection), slug(shading),
             slug(renderer)]
    return "-".join(parts) + ".png"


def frame_name(k: int) -> str:
    """The file name of an animation's frame ``k`` (from 0) in its frames folder."""
    return f"frame_{k:05d}.png"


def unused(path: Path) -> Path:
    """``path``, or the first of ``name-2.png``, ``name-3.png``… that does not exist yet."""
    n = 1
    candidate = path
    while candidate.exists():
        n += 1
        candidate = path.with_name(f"{path.stem}-{n}{path.suffix}")
    return candidate
