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
a missing, unreadable, corrupt or too large file (not a regular file, over ``MAX_TEXTURE_SIDE``
on a side, or past the scene's :class:`TexelBudget`) gives a :class:`TextureError` whose
message names the file and the scene key that asked for it. The levels of a texture are views
of one float32 buffer, built a band of rows at a time (a 4096² image peaks near 0.6 GB).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.colour.srgb import decode, encode

from core.scene.formats.errors import MAX_TEXTURE_SIDE  # the readers' limit, used here too
from core.texture.modes import WRAPS


class TextureError(ValueError):
    """A texture that cannot be used; the message names the file and the scene key."""


# The sRGB curve (IEC 61966-2-1), one definition for the whole program (core.colour.srgb).
srgb_to_linear = decode
linear_to_srgb = encode


def _box_weights(n_fine: int, n_coarse: int) -> np.ndarray:
    """``(n_coarse, n_fine)``: the share of each fine texel in each coarse one (rows sum to 1)."""
    scale = n_fine / n_coarse
    weights = np.zeros((n_coarse, n_fine))
    for i in range(n_coarse):
        lo, hi = i * scale, (i + 1) * scale
        for k in range(int(np.floor(lo)), min(int(np.ceil(hi)), n_fine)):
            weights[i, k] = min(hi, k + 1) - max(lo, k)
    return weights / scale


def mip_chain(image: np.ndarray, convert=None) -> list[np.ndarray]:
    """Levels 0 … down to 1 x 1 of ``image (h, w, C)`` by box filtering (glGenerateMipmap).

    The levels are views of one float32 buffer, in order (what :meth:`Texture.packed` hands to
    the samplers, so the texels are held once), each computed from the one before a band of
    rows at a time in float64: the transient memory is a band's, not a whole level's.
    ``convert`` (optional) turns a band of ``image``'s rows into level 0's texels.
    """
    image = np.asarray(image)
    convert = convert or (lambda band: band)
    sizes = [image.shape[:2]]
    while sizes[-1] != (1, 1):
        h, w = sizes[-1]
        sizes.append((max(1, h // 2), max(1, w // 2)))
    channels = convert(image[:1]).shape[2]
    buffer = np.empty((sum(h * w for h, w in sizes), channels), dtype=np.float32)
    levels, offset = [], 0
    for h, w in sizes:
        levels.append(buffer[offset:offset + h * w].reshape(h, w, channels))
        offset += h * w
    for r0 in range(0, sizes[0][0], _BAND):
        levels[0][r0:r0 + _BAND] = convert(image[r0:r0 + _BAND])
    for fine, coarse in zip(levels, levels[1:]):
        _downsample(fine, coarse)
    return levels


_BAND = 256                       # rows converted or filtered at a time
_SMALL = 1 << 22                  # texels: an odd-sized level this small is filtered whole


def _downsample(fine: np.ndarray, coarse: np.ndarray) -> None:
    """``coarse`` = the box-filtered ``fine`` (the 2 x 2 box, or by area for odd sizes)."""
    h, w = fine.shape[:2]
    h2, w2 = coarse.shape[:2]
    if h == 2 * h2 and w == 2 * w2:                       # even sizes: the 2 x 2 box
        for r0 in range(0, h2, _BAND):
            band = fine[2 * r0:2 * (r0 + _BAND)].astype(np.float64)
            coarse[r0:r0 + _BAND] = band.reshape(-1, 2, w2, 2, fine.shape[2]).mean(axis=(1, 3))
        return
    weights_h, weights_w = _box_weights(h, h2), _box_weights(w, w2)
    bands = [(0, h2)] if h * w <= _SMALL else [(r, min(r + _BAND, h2)) for r in range(0, h2, _BAND)]
    for r0, r1 in bands:                                  # one axis at a time, by area
        rows = np.flatnonzero(weights_h[r0:r1].any(axis=0))
        lo, hi = (rows[0], rows[-1] + 1) if h * w > _SMALL else (0, h)
        part = np.tensordot(weights_h[r0:r1, lo:hi], fine[lo:hi].astype(np.float64), axes=(1, 0))
        coarse[r0:r1] = np.tensordot(weights_w, part, axes=(1, 1)).transpose(1, 0, 2)


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
                   source: str = "", mipmaps: bool = True, divisor: float = 1.0,
                   decoded: bool = False) -> "Texture":
        """A texture from ``image (h, w)`` or ``(h, w, 1 … 4)`` in [0, 1], row 0 at v = 0.

        Grey is spread to RGB, missing alpha is 1. With ``srgb`` the colour channels are
        decoded to linear (alpha never is), unless ``decoded`` says they are already (a
        procedural's palette, decoded colour by colour). ``image / divisor`` is used
        (integer pixels of a file are divided a band of rows at a time, never copied whole to
        float64); values outside [0, 1] are clamped to it (a signed 32-bit TIFF holds
        negative ones).
        """
        if wrap not in WRAPS:
            raise ValueError(f"wrap must be one of {', '.join(WRAPS)}, not {wrap!r}")
        image = np.asarray(image)
        if image.ndim == 2:
            image = image[:, :, None]
        if image.ndim != 3 or image.shape[2] not in (1, 2, 3, 4) or 0 in image.shape[:2]:
            raise ValueError(f"a texture image must be (h, w) or (h, w, 1..4), not {image.shape}")

        def convert(band):
            rgba = _to_rgba(np.clip(np.asarray(band, dtype=np.float64) / divisor, 0.0, 1.0))
            if srgb and not decoded:
                rgba[..., :3] = srgb_to_linear(rgba[..., :3])
            return rgba
        if mipmaps:
            levels = mip_chain(image, convert)
        else:
            levels = [np.concatenate([convert(image[r:r + _BAND]).astype(np.float32)
                                      for r in range(0, image.shape[0], _BAND)])]
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
            texels = self._shared_buffer()
            if texels is None:            # levels made elsewhere: one copy, once
                texels = np.concatenate([lv.reshape(-1, 4) for lv in self.levels]).astype(np.float32)
            self._packed = (np.ascontiguousarray(texels), table)
        return self._packed

    def _shared_buffer(self) -> np.ndarray | None:
        """The one buffer :func:`mip_chain` made the levels in, when they are its views."""
        base = self.levels[0].base
        total = sum(lv.shape[0] * lv.shape[1] for lv in self.levels)
        if (base is None or base.dtype != np.float32 or base.ndim != 2 or base.shape != (total, 4)
                or not all(lv.base is base for lv in self.levels)):
            return None
        return base

    @property
    def wrap_code(self) -> int:
        return WRAPS[self.wrap]


def _to_rgba(image: np.ndarray) -> np.ndarray:
    h, w, c = image.shape
    rgba = np.ones((h, w, 4))
    if c in (1, 2):                           # grey (and grey + alpha)
        rgba[..., :3] = image[..., :1]
        if c == 2:
            rgba[..., 3] = image[..., 1]
    else:
        rgba[..., :c] = image
    return rgba


# Texels (level 0) all the textures of one scene may hold together: two 4096 x 4096 images.
# Each costs 16 bytes and a third more for its MIP levels while the scene lives, and about
# 50 bytes while it is decoded; the budget is checked before any pixel is decoded.
MAX_SCENE_TEXELS = 2 * 4096 * 4096


class TexelBudget:
    """What is left of a scene's :data:`MAX_SCENE_TEXELS` as its textures are made."""

    def __init__(self, texels: int | None = None) -> None:
        self.total = MAX_SCENE_TEXELS if texels is None else texels
        self.left = self.total

    def take(self, count: int, what: str) -> str | None:
        """Take ``count`` texels for ``what``; the reason it cannot (nothing taken), or None."""
        if count > self.left:
            used = self.total - self.left
            return (f"{what} needs {count:,} texels and the scene's textures may hold "
                    f"{self.total:,} together ({used:,} already used)")
        self.left -= count
        return None


def load_image(path: str | Path, key: str, wrap: str = "repeat", srgb: bool = True,
               shown: str | None = None, budget: TexelBudget | None = None) -> Texture:
    """The texture in the image file ``path``; ``key`` is the scene key that named it.

    Raises :class:`TextureError` (a ValueError) naming ``shown`` (default: the path) and
    ``key`` for a missing or unreadable file, one that is not a regular file (a FIFO, a
    device, a folder) or is over ``MAX_INPUT_BYTES["texture"]`` (read whole before it is
    decoded; core.scene.formats.errors), a file that is not an image, a corrupt
    image, an image over ``MAX_TEXTURE_SIDE`` texels on a side, and one over what is left of
    ``budget`` (both checked from the header, before any pixel is decoded). The name is
    printed escaped and cut short, like every name from the input.
    """
    import io

    from PIL import Image, UnidentifiedImageError

    from core.scene.formats.errors import ReaderError, printable, read_file

    name, key = printable(shown or str(path), 200), printable(key, 100)

    def fail(reason: str) -> TextureError:
        return TextureError(f"{name}: {reason} (the texture of {key}); drawn untextured")

    try:
        data = read_file(Path(path), name, "texture")
    except ReaderError as error:
        raise fail(error.reason) from None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(io.BytesIO(data)) as img:
                w, h = img.size
                if w > MAX_TEXTURE_SIDE or h > MAX_TEXTURE_SIDE:
                    raise fail(f"the image is {w} x {h}; textures may be at most "
                               f"{MAX_TEXTURE_SIDE} x {MAX_TEXTURE_SIDE}")
                if w < 1 or h < 1:
                    raise fail(f"the image is {w} x {h}")
                over = budget.take(w * h, f"the image ({w} x {h})") if budget else None
                if over:
                    raise fail(over)
                img.load()
                pixels, divisor = _pixels(img)
    except TextureError:
        raise
    except UnidentifiedImageError:
        raise fail("not an image Pillow can read (PNG, JPEG, …)") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as error:
        raise fail(f"too large: {error}") from None
    except (OSError, ValueError, SyntaxError, EOFError) as error:
        raise fail(f"corrupt image ({printable(error, 120)})") from None
    except MemoryError:
        raise fail("not enough memory to decode it") from None
    return Texture.from_array(pixels[::-1], wrap=wrap, srgb=srgb, source=name, divisor=divisor)


def _pixels(img) -> tuple[np.ndarray, float]:
    """Pillow image → ``(pixels (h, w, C), divisor)``: ``pixels / divisor`` in [0, 1], row 0
    the top of the picture (the integers as stored: 1 byte a channel for 8-bit images)."""
    if img.mode in ("I;16", "I;16B", "I;16L", "I"):
        return np.asarray(img), (65535.0 if "16" in img.mode else 2**31 - 1)
    if img.mode not in ("L", "LA", "RGB", "RGBA"):
        img = img.convert("RGBA" if "A" in img.getbands() or img.mode == "P" else "RGB")
    return np.asarray(img), 255.0
