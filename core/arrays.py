"""Arrays as the kernels take them.

numba compiles a kernel once per argument type, and a read-only array is another type than
a writable one (``Array(int64, 2, 'C', readonly=True)``). The renderer hands its kernels both:
cached arrays are read-only (``core/shading/shade.py``, the clipper's ``0..T-1``), freshly
computed ones are not, and which a frame gets depends on the scene (whether anything was
clipped, whether normals were cached). Each such kernel compiled twice or four times
(``python -m app warmup`` once found 41 kernels with more than one signature). A kernel
that only reads an argument gets it through :func:`read_only`, so it compiles once; a
read-only view costs no copy (about 0.3 µs) and the compiled code is the same.
"""

from __future__ import annotations

import numpy as np


def read_only(a: np.ndarray) -> np.ndarray:
    """``a`` when it is already read-only, else a read-only view of it (no copy)."""
    if not a.flags.writeable:
        return a
    view = a.view()
    view.flags.writeable = False
    return view


def rgb_picture(height: int, width: int) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 picture laid out as a frame's colour is (the RGB view of an RGBA
    buffer, ``core.render.Frame``): the pixel kernels that write pictures then compile for
    one layout, not for this one and a contiguous one (about 2 s of compiling each)."""
    return np.empty((max(height, 0), max(width, 0), 4), np.uint8)[..., :3]
