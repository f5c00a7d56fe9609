"""Per-pixel texture lookups over a visibility buffer.

Every pixel step here finds (u, v) and its screen-space derivatives from per-triangle plane
constants (:func:`core.texture.tutorial.triangle_constants`: u·(1/W), v·(1/W) and 1/W are
affine in the pixel position, the tutorial's a, b and c; :func:`core.texture.tutorial.uv_at`
differentiates the quotients exactly), then samples with the chosen filter
(:func:`core.texture.sample.sample`). The derivatives are analytic at the pixel centre,
not the 2 x 2-quad differences a GPU takes.
"""

from __future__ import annotations


from core.jit import njit, prange
from core.texture.sample import sample
from core.texture.tutorial import uv_at


@njit(cache=True, parallel=True, nogil=True)
def unlit_texture(tri, constants, texels, levels, wrap, filter_, background, out):
    """``out (H, W, 4)`` float: the filtered texel at each covered pixel, ``background``
    elsewhere (the texture alone, no light: the oracle's picture)."""
    height, width = tri.shape
    for j in prange(height):
        for i in range(width):
            t = tri[j, i]
            if t < 0:
                for k in range(4):
                    out[j, i, k] = background[k]
                continue
            u, v, dudx, dvdx, dudy, dvdy = uv_at(constants, t, i, j)
            r, g, b, a = sample(texels, levels, wrap, filter_, u, v, dudx, dvdx, dudy, dvdy)
            out[j, i, 0], out[j, i, 1], out[j, i, 2], out[j, i, 3] = r, g, b, a
