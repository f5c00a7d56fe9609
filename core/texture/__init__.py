"""Texture mapping and bump mapping: textures, samplers, the course's two systems.

- :mod:`core.texture.sample`: numba samplers (nearest, bilinear, trilinear, anisotropic) and
  GL's wrap modes, callable from any compiled kernel;
- :mod:`core.texture.image`: :class:`Texture` (linear RGBA levels, the MIP chain), image files
  through Pillow (sRGB decoded), :class:`TextureError` for bad files;
- :mod:`core.texture.procedural`: checker, bricks, the demo's height maps, value/Perlin noise;
- :mod:`core.texture.tutorial`: the tutorial's nine-constant (u, v) path;
- :mod:`core.texture.bump_demo`: the Java bump demo's material and view.
"""

from core.texture.image import MAX_TEXTURE_SIDE, Texture, TextureError, load_image
from core.texture.modes import FILTERS, WRAPS

__all__ = ["FILTERS", "MAX_TEXTURE_SIDE", "Texture", "TextureError", "WRAPS", "load_image"]
