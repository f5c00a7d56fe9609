"""Textures: texel arrays with their MIP chain, read from image files or made procedurally.

A :class:`Texture` holds linear RGBA float32 levels, level 0 the full image with its row 0 at
v = 0 (the bottom of the picture, as OpenGL and OBJ's ``vt`` have it), and how it wraps.
``srgb`` says the colours were sRGB-encoded in the file: they are decoded to linear here, so
that filtering and MIP averaging mix light rather than code values (averaging code values
darkens a fine black-and-white checker), and a shader encodes the filtered colour back before
it enters the lighting, which this project evaluates on display values like every material
colour. Height maps and normal maps are data, not colours: ``srgb = False``.

The MIP chain is the one ``glGenerateMipmap`` makes: each level half the size of the one
before (⌊w/2⌋, at least 1) down to 1 x 1, each texel the average of the texels of the finer
level it covers — a 2 x 2 box for even sizes; for an odd size the footprint of a coarse texel
covers fractions of the fine ones and each counts by the area it covers.

:func:`load_image` reads PNG or JPEG (anything Pillow reads) and never raises for bad input:
a missing, unreadable, corrupt or too large file (over ``MAX_TEXTURE_SIDE`` on a side) gives a
:class:`TextureError` whose message names the file and the scene key that asked for it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.texture.modes import WRAPS

MAX_TEXTURE_SIDE = 16384          # texels on a side; larger images are refused, not read


class TextureError(ValueError):
    """A texture that cannot be used; the message names the file and the scene key."""


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """The sRGB decoding (IEC 61966-2-1): code values in [0, 1] to linear light."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """The sRGB encoding, the inverse of :func:`srgb_to_linear` (clamped to [0, 1])."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def _box_weights(n_fine: int, n_coarse: int) -> np.ndarray:
    """``(n_coarse, n_fine)``: the share of each fine texel in each coarse one (rows sum to 1)."""
    scale = n_fine / n_coarse
    weights = np.zeros((n_coarse, n_fine))
    for i in range(n_coarse):
        lo, hi = i * scale, (i + 1) * scale
        for k in range(int(np.floor(lo)), min(int(np.ceil(hi)), n_fine)):
            weights[i, k] = min(hi, k + 1) - max(lo, k)
    return weights / scale


def mip_chain(image: np.ndarray) -> list[np.ndarray]:
    """Levels 0 … down to 1 x 1 of ``image (h, w, C)`` by box filtering (glGenerateMipmap)."""
    levels = [np.ascontiguousarray(image, dtype=np.float32)]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        fine = levels[-1].astype(np.float64)
        h, w = fine.shape[:2]
        h2, w2 = max(1, h // 2), max(1, w // 2)
        if h == 2 * h2 and w == 2 * w2:                   # even sizes: the 2 x 2 box
            coarse = fine.reshape(h2, 2, w2, 2, -1).mean(axis=(1, 3))
        else:                                             # one axis at a time, by area
            coarse = np.tensordot(_box_weights(h, h2), fine, axes=(1, 0))
            coarse = np.tensordot(_box_weights(w, w2), coarse, axes=(1, 1)).transpose(1, 0, 2)
        levels.append(np.ascontiguousarray(coarse, dtype=np.float32))
    return levels


@dataclass(eq=False)
class Texture:
    """RGBA float32 levels (row 0 at v = 0), a wrap mode and where the texture came from."""

    levels: list[np.ndarray] = field(repr=False)
    wrap: str = "repeat"
    srgb: bool = False
    source: str = ""
    _packed: tuple | None = field(default=None, repr=False)

    @classmethod
    def from_array(cls, image: np.ndarray, wrap: str = "repeat", srgb: bool = False,
                   source: str = "", mipmaps: bool = True) -> "Texture":
        """A texture from ``image (h, w)`` or ``(h, w, 1 … 4)`` in [0, 1], row 0 at v = 0.

        Grey is spread to RGB, missing alpha is 1. With ``srgb`` the colour channels are
        decoded to linear (alpha never is).
        """
        if wrap not in WRAPS:
            raise ValueError(f"wrap must be one of {', '.join(WRAPS)}, not {wrap!r}")
        rgba = _to_rgba(np.asarray(image, dtype=np.float64))
        if srgb:
            rgba[..., :3] = srgb_to_linear(rgba[..., :3])
        levels = mip_chain(rgba) if mipmaps else [rgba.astype(np.float32)]
        return cls(levels=levels, wrap=wrap, srgb=srgb, source=source)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of level 0."""
        return self.levels[0].shape[1], self.levels[0].shape[0]

    def packed(self) -> tuple[np.ndarray, np.ndarray]:
        """``(texels (N, 4) float32, levels (L, 3) int64)`` for the numba samplers."""
        if self._packed is None:
            table = np.zeros((len(self.levels), 3), dtype=np.int64)
            offset = 0
            for k, level in enumerate(self.levels):
                h, w = level.shape[:2]
                table[k] = offset, w, h
                offset += w * h
            texels = np.concatenate([lv.reshape(-1, 4) for lv in self.levels]).astype(np.float32)
            self._packed = (np.ascontiguousarray(texels), table)
        return self._packed

    @property
    def wrap_code(self) -> int:
        return WRAPS[self.wrap]


def _to_rgba(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        image = image[:, :, None]
    if image.ndim != 3 or image.shape[2] not in (1, 2, 3, 4) or 0 in image.shape[:2]:
        raise ValueError(f"a texture image must be (h, w) or (h, w, 1..4), not {image.shape}")
    h, w, c = image.shape
    rgba = np.ones((h, w, 4))
    if c in (1, 2):                           # grey (and grey + alpha)
        rgba[..., :3] = image[..., :1]
        if c == 2:
            rgba[..., 3] = image[..., 1]
    else:
        rgba[..., :c] = image
    return rgba


def load_image(path: str | Path, key: str, wrap: str = "repeat", srgb: bool = True,
               shown: str | None = None) -> Texture:
    """The texture in the image file ``path``; ``key`` is the scene key that named it.

    Raises :class:`TextureError` (a ValueError) naming ``shown`` (default: the path) and
    ``key`` for a missing or unreadable file, a file that is not an image, a corrupt image
    and an image over ``MAX_TEXTURE_SIDE`` texels on a side (checked from the header,
    before any pixel is decoded).
    """
    from PIL import Image, UnidentifiedImageError

    name = shown or str(path)

    def fail(reason: str) -> TextureError:
        return TextureError(f"{name}: {reason} (the texture of {key}); drawn untextured")

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                w, h = img.size
                if w > MAX_TEXTURE_SIDE or h > MAX_TEXTURE_SIDE:
                    raise fail(f"the image is {w} x {h}; textures may be at most "
                               f"{MAX_TEXTURE_SIDE} x {MAX_TEXTURE_SIDE}")
                if w < 1 or h < 1:
                    raise fail(f"the image is {w} x {h}")
                img.load()
                pixels = _pixels(img)
    except TextureError:
        raise
    except FileNotFoundError:
        raise fail("no such file") from None
    except IsADirectoryError:
        raise fail("is a folder, not an image") from None
    except PermissionError:
        raise fail("permission denied") from None
    except UnidentifiedImageError:
        raise fail("not an image Pillow can read (PNG, JPEG, …)") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as error:
        raise fail(f"too large: {error}") from None
    except (OSError, ValueError, SyntaxError, EOFError) as error:
        raise fail(f"corrupt image ({error})") from None
    except MemoryError:
        raise fail("not enough memory to decode it") from None
    return Texture.from_array(pixels[::-1], wrap=wrap, srgb=srgb, source=name)


def _pixels(img) -> np.ndarray:
    """Pillow image → float (h, w, C) in [0, 1], row 0 the top of the picture."""
    if img.mode in ("I;16", "I;16B", "I;16L", "I"):
        return np.asarray(img, dtype=np.float64) / (65535.0 if "16" in img.mode else 2**31 - 1)
    if img.mode not in ("L", "LA", "RGB", "RGBA"):
        img = img.convert("RGBA" if "A" in img.getbands() or img.mode == "P" else "RGB")
    return np.asarray(img, dtype=np.float64) / 255.0
