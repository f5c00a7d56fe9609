"""The loupe: the finished picture magnified by whole numbers, nearest neighbour, round the
cursor, and the value under the cursor.

Takes Alt+wheel notches at a picture pixel and keeps the magnification ``m`` (1, 2, 4 … 32)
and an anchor: the framebuffer pixel ``texel`` that the screen pixel ``screen`` shows. Screen
pixel ``q`` then shows framebuffer pixel ``texel + floor((q - screen) / m)``, so each pixel of
the frame is an m x m block of one colour and the pixel under the cursor stays under it while
the magnification changes. The blit samples the finished framebuffer with the same formula
(``shaders/blit.frag``); nothing is re-rendered. :meth:`Loupe.texel_at` is that mapping for the
window (the value under the cursor, the inspector's click on a magnified picture).

No GL here.
"""

from __future__ import annotations

import math

import numpy as np

MAX_MAGNIFICATION = 32


class Loupe:
    """Magnification and anchor; ``m == 1`` is the picture as it is (identity mapping)."""

    def __init__(self):
        self.magnification = 1
        self.screen = (0, 0)
        self.texel = (0, 0)

    def texel_at(self, x: float, y: float) -> tuple[int, int]:
        """The framebuffer pixel (column, row from the top) shown at picture pixel (x, y)."""
        m = self.magnification
        qx, qy = int(math.floor(x)), int(math.floor(y))
        return (self.texel[0] + (qx - self.screen[0]) // m,
                self.texel[1] + (qy - self.screen[1]) // m)

    def wheel(self, notches: float, x: float, y: float) -> int:
        """Alt+wheel at picture pixel (x, y): up doubles, down halves (1 to 32); returns m."""
        steps = int(round(notches)) or (1 if notches > 0 else -1)
        m = int(min(max(self.magnification * 2.0 ** steps, 1), MAX_MAGNIFICATION))
        texel = self.texel_at(x, y)
        if m == 1:
            self.screen = self.texel = (0, 0)          # 1:1 is the picture, untouched
        else:
            self.screen, self.texel = (int(math.floor(x)), int(math.floor(y))), texel
        self.magnification = m
        return m

    def set(self, m: int, x: float, y: float) -> int:
        """Magnification ``m`` (1 to 32, a power of two) round picture pixel (x, y)."""
        steps = round(math.log2(min(max(int(m), 1), MAX_MAGNIFICATION) / self.magnification))
        return self.wheel(steps, x, y) if steps else self.magnification

    def pan_from(self, start: tuple[int, int], dx: float, dy: float) -> None:
        """A drag of (dx, dy) picture pixels moves the magnified picture with the pointer
        (``start``: the screen anchor when the drag began)."""
        self.screen = (start[0] + int(round(dx)), start[1] + int(round(dy)))

    def reset(self) -> None:
        self.magnification, self.screen, self.texel = 1, (0, 0), (0, 0)

    def uniforms(self) -> dict:
        return {"magnify": self.magnification, "screen_anchor": self.screen,
                "texel_anchor": self.texel}


def stretched(texel: tuple[int, int], shown: tuple[int, int],
              size: tuple[int, int]) -> tuple[int, int]:
    """The pixel of a ``size`` (W, H) frame that picture texel ``texel`` shows when the frame
    is stretched over a picture of ``shown`` pixels (the blit's mapping, nearest neighbour:
    ``floor(t * size / shown)``); the texel itself when the sizes agree or it lies outside."""
    if tuple(shown) == tuple(size) or texel[0] < 0 or texel[1] < 0:
        return texel
    return (texel[0] * size[0] // max(shown[0], 1), texel[1] * size[1] // max(shown[1], 1))


def value_at(frame, column: int, row: int, triangles=None, meshes=()) -> str:
    """The status line's words for frame pixel (column, row): its RGB and depth, and, where
    ``triangles`` (the frame's ``(H, W)`` visible-triangle ids in scene order, -1 empty) is
    given, the triangle there and the mesh it belongs to (``meshes``: each mesh's name and
    triangle count, in scene order)."""
    if frame is None:
        return ""
    height, width = frame.color.shape[:2]
    if not (0 <= column < width and 0 <= row < height):
        return f"pixel ({column}, {row}): outside the frame"
    r, g, b = (int(c) for c in frame.color[row, column])
    text = f"pixel ({column}, {row}): RGB ({r}, {g}, {b})"
    depth = getattr(frame, "depth", None)
    if isinstance(depth, np.ndarray) and depth.shape[:2] == (height, width):
        z = float(depth[row, column])
        text += f", depth {z:.6g}" if math.isfinite(z) else ", depth empty"
    if isinstance(triangles, np.ndarray) and triangles.shape[:2] == (height, width):
        text += ", " + triangle_words(int(triangles[row, column]), meshes)
    return text


def triangle_words(face: int, meshes) -> str:
    """``"triangle 5 of 'roof' (scene triangle 17)"`` for scene triangle ``face``."""
    if face < 0:
        return "background"
    first = 0
    for name, count in meshes:
        if face < first + count:
            return f"triangle {face - first} of {name or 'a mesh'!r} (scene triangle {face})"
        first += count
    return f"scene triangle {face}"
