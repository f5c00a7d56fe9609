"""The film: where in a pixel the samples lie, and how they become the pixel (pbrt's Film + Filter).

Every renderer asks the film for its sample offsets and hands it back one image per sample;
supersampling is therefore a setting of any renderer (``RenderSettings.samples``), not a trick
of one of them.

- Offsets are in pixel units inside ``[0, 1)²``, measured from the pixel's top-left corner,
  x to the right and y **down** (image order). One sample is the pixel centre (0.5, 0.5), the
  course's sample point.
- ``regular``: the centres of an ``s x s`` grid of strata (``samples`` must be a square);
  ``jittered``: one uniformly random point in each stratum, from ``seed`` (reproducible).
  A non-square count with ``jittered`` takes the first ``samples`` strata of the smallest
  ``s x s`` grid with at least that many.
- Reconstruction is the box filter: the mean of the samples, rounded half up to 8 bits.
"""

from __future__ import annotations

import functools
import math

import numpy as np


def grid_side(samples: int) -> int:
    """The side of the smallest square grid with at least ``samples`` strata."""
    return int(math.ceil(math.sqrt(samples) - 1e-9))


def progressive_order(samples: int) -> np.ndarray:
    """An order of a full grid's ``samples`` strata (row by row, as :func:`sample_offsets`
    makes them) whose every prefix covers the pixel evenly: the strata of the points of the
    (0, 2)-sequence in base 2 (van der Corput's radical inverse beside Sobol's second
    dimension; Kollig and Keller 2002). Its first 4, 16, 64, … points lie one in each cell of
    a 2 x 2, 4 x 4, 8 x 8, … grid, so a picture accumulated pass by pass samples the whole
    pixel at every count. Row by row when the grid's side is not a power of two."""
    return np.array(_progressive_order(samples), np.int64)


@functools.lru_cache(maxsize=8)
def _progressive_order(samples: int) -> tuple[int, ...]:
    """:func:`progressive_order` as a tuple, made once per count (the window asks at every
    pass)."""
    side = grid_side(samples)
    if side * side != samples or side & (side - 1):
        return tuple(range(samples))
    return tuple(int(_sobol_second(i) * side) * side + int(_radical_inverse(i) * side)
                 for i in range(samples))


def _radical_inverse(i: int) -> float:
    """Van der Corput: the bits of ``i`` mirrored about the binary point."""
    return int(f"{i:032b}"[::-1], 2) / 2.0 ** 32


def _sobol_second(i: int) -> float:
    """Sobol's second dimension (generator matrix: Pascal's triangle mod 2)."""
    v, r = 1 << 31, 0
    while i:
        if i & 1:
            r ^= v
        i >>= 1
        v ^= v >> 1
    return r / 2.0 ** 32


def sample_offsets(samples: int, pattern: str = "regular", seed: int = 0) -> np.ndarray:
    """``(samples, 2)`` offsets (x right, y down) in ``[0, 1)²``, row by row over the strata."""
    if samples < 1:
        raise ValueError(f"samples per pixel must be at least 1, not {samples}")
    if samples == 1:
        return np.array([[0.5, 0.5]])        # one sample is the centre, whatever the pattern
    if pattern == "adaptive":
        # Adaptive supersampling is the ray tracer's (core.raytrace.adaptive); a renderer
        # that cannot adapt takes every sample of the finest grid.
        pattern = "regular"
    side = grid_side(samples)
    if pattern == "regular" and side * side != samples:
        raise ValueError(f"a regular grid needs a square number of samples (1, 4, 9, 16, …), "
                         f"not {samples}; use the jittered pattern")
    row, col = np.divmod(np.arange(side * side)[:samples], side)
    if pattern == "regular":
        jitter = np.full((samples, 2), 0.5)
    elif pattern == "jittered":
        jitter = np.random.default_rng(seed).random((samples, 2))
    else:
        raise ValueError(f"sample pattern must be 'regular' or 'jittered', not {pattern!r}")
    return np.stack([(col + jitter[:, 0]) / side, (row + jitter[:, 1]) / side], axis=1)


class Film:
    """Accumulates one float image per sample and reconstructs the pixels (box filter)."""

    def __init__(self, width: int, height: int, samples: int = 1, pattern: str = "regular",
                 seed: int = 0):
        self.width, self.height = int(width), int(height)
        self.offsets = sample_offsets(samples, pattern, seed)
        self._sum = np.zeros((self.height, self.width, 3))
        self._count = 0

    @property
    def samples(self) -> int:
        return len(self.offsets)

    def add(self, rgb) -> None:
        """One sample's image: ``(H, W, 3)`` floats in [0, 1] or uint8 in [0, 255]."""
        rgb = np.asarray(rgb)
        self._sum += rgb / 255.0 if rgb.dtype == np.uint8 else rgb
        self._count += 1

    def resolve(self) -> np.ndarray:
        """The box-filtered image, ``(H, W, 3)`` uint8, rounded half up."""
        if self._count == 0:
            raise ValueError("the film has no samples yet")
        mean = self._sum / self._count
        return np.floor(np.clip(mean, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def box_filter(image: np.ndarray, k: int) -> np.ndarray:
    """``(kH, kW, 3)`` uint8 samples on a regular grid → ``(H, W, 3)`` float64: the mean of each
    k x k block, on 0–255. A compiled loop: numpy's ``reshape(...).mean(axis=(1, 3))`` takes
    longer than the 4 x 4 render it filters."""
    if k == 1:
        return image.astype(np.float64)
    from core.camera._box import _box_filter
    out = np.empty((image.shape[0] // k, image.shape[1] // k, 3))
    _box_filter(np.ascontiguousarray(image), int(k), out)
    return out


def to_rgb8(color) -> np.ndarray:
    """A colour in [0, 1] → uint8, rounded half up."""
    return np.floor(np.clip(np.asarray(color, dtype=np.float64), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def fill(color: np.ndarray, rgb) -> None:
    """Fill an (H, W, 3) image with one colour in [0, 1]."""
    fill_bytes(color, to_rgb8(rgb))


def fill_bytes(color: np.ndarray, rgb8) -> None:
    """Fill an (H, W, 3) uint8 image with one colour given as 3 bytes.

    A frame's colour is the first three bytes of each 4-byte pixel of ``Frame.rgbx``: then
    the fill is one 32-bit memset over the whole frame (0.03 ms at 500 x 500, where copying
    3 bytes in every 4 took 1–2 ms). Any other image is filled one row, then whole rows.
    """
    if not color.size:
        return
    rgb8 = np.asarray(rgb8, dtype=np.uint8).reshape(3)
    base = color.base
    if (isinstance(base, np.ndarray) and base.dtype == np.uint8 and base.ndim == 3
            and base.shape == color.shape[:2] + (4,) and base.flags.c_contiguous
            and color.strides == base.strides
            and color.__array_interface__["data"][0] == base.__array_interface__["data"][0]):
        word = np.array([rgb8[0], rgb8[1], rgb8[2], 255], np.uint8).view(np.uint32)[0]
        base.view(np.uint32).fill(word)
        return
    color[0] = rgb8
    color[1:] = color[0]


def viewport(window: tuple[float, float, float, float], width: int, height: int,
             keep_aspect: bool = False):
    """The device rectangle the view window maps onto: ``(x_min, x_max, y_min, y_max)`` pixels.

    The course's mapping (the notes: "if Window + viewport have different dimensions, a
    scaling is done"; M_vv3dv) is the default: the window fills the whole framebuffer, each
    axis scaled on its own, so a window whose aspect differs from the framebuffer's is
    stretched. ``keep_aspect`` instead gives the largest whole-pixel rectangle of the window's
    aspect, centred (letterboxed), so that a circle stays round.
    """
    if not keep_aspect:
        return 0.0, float(width), 0.0, float(height)
    u_min, u_max, v_min, v_max = window
    aspect = (u_max - u_min) / (v_max - v_min)
    if width >= height * aspect:
        w, h = max(1, min(width, round(height * aspect))), height
    else:
        w, h = width, max(1, min(height, round(width / aspect)))
    x0, y0 = (width - w) // 2, (height - h) // 2
    return float(x0), float(x0 + w), float(y0), float(y0 + h)


def sample_viewport(vp, pixel_offset):
    """The viewport moved so that the sample at ``pixel_offset`` (x right, y down, in its
    pixel) lands where the scan conversion samples, the pixel centre."""
    dx, dy = 0.5 - pixel_offset[0], pixel_offset[1] - 0.5       # device y runs up
    if dx == 0.0 and dy == 0.0:
        return vp
    x0, x1, y0, y1 = vp
    return x0 + dx, x1 + dx, y0 + dy, y1 + dy
