"""Reconstruction filters for supersampled frames (FvDFH 14.10, 17.4; Mitchell and Netravali
1988): each pixel is the weighted mean of the film's samples around its centre.

``reconstruct(images, offsets, name, radius)`` takes one ``(H, W, 3)`` image per sample (the
frame drawn with its sample at ``offset`` in every pixel, x right and y down, pixel units in
[0, 1)) and returns the filtered ``(H, W, 3)`` on 0–255. The filters are separable,
``w(dx) w(dy)`` with dx, dy the sample's distance from the pixel centre:

- ``box``: 1 inside ``radius`` (0.5: the pixel's own samples, the film's mean);
- ``tent``: ``1 − |d| / radius``;
- ``gaussian``: ``exp(−d² / 2σ²)`` with σ = radius / 3, cut at ``radius``;
- ``mitchell``: Mitchell–Netravali's cubic with B = C = 1/3, its support [−2, 2] stretched to
  [−radius, radius] (negative lobes: the result is clamped to 0–255).

A sample reaches every pixel whose centre is within ``radius``, so with a radius above 0.5 a
pixel also takes its neighbours' samples; weights are renormalised by what reaches each pixel
(at the frame's border fewer samples do).
"""

from __future__ import annotations

import math

import numpy as np

from core.settings import FILTER_RADIUS as DEFAULT_RADIUS  # noqa: F401  (the names, listed once)
from core.settings import PIXEL_FILTERS as FILTERS
from core.settings import check_filter as check  # noqa: F401

B = C = 1.0 / 3.0


def weight(name: str, d, radius: float) -> np.ndarray:
    """The 1D filter at distances ``d`` (pixels), zero outside ``radius``."""
    a = np.abs(np.asarray(d, dtype=np.float64))
    inside = a < radius
    if name == "box":
        w = np.ones_like(a)
    elif name == "tent":
        w = 1.0 - a / radius
    elif name == "gaussian":
        sigma = radius / 3.0
        w = np.exp(-0.5 * (a / sigma) ** 2)
    elif name == "mitchell":
        x = 2.0 * a / radius
        near = ((12 - 9 * B - 6 * C) * x ** 3 + (-18 + 12 * B + 6 * C) * x ** 2 + (6 - 2 * B))
        far = ((-B - 6 * C) * x ** 3 + (6 * B + 30 * C) * x ** 2 + (-12 * B - 48 * C) * x
               + (8 * B + 24 * C))
        w = np.where(x < 1.0, near, far) / 6.0
    else:
        raise ValueError(f"the pixel filter must be one of {', '.join(FILTERS)}, not {name!r}")
    return np.where(inside, w, 0.0)


def reconstruct(images, offsets, name: str, radius: float) -> np.ndarray:
    """``(H, W, 3)`` float on 0–255 from one image per sample offset (see the module)."""
    total = weights = None
    reach = int(math.ceil(radius)) + 1
    for image, (ox, oy) in zip(images, offsets):
        image = np.asarray(image, dtype=np.float64)
        if total is None:
            total = np.zeros_like(image)
            weights = np.zeros(image.shape[:2])
        height, width = image.shape[:2]
        for dy in range(-reach, reach + 1):       # the sample of pixel y feeds pixel y + dy
            wy = float(weight(name, oy - 0.5 - dy, radius))
            if wy == 0.0 or abs(dy) >= height:
                continue
            for dx in range(-reach, reach + 1):
                w = wy * float(weight(name, ox - 0.5 - dx, radius))
                if w == 0.0 or abs(dx) >= width:
                    continue
                src = image[max(0, -dy):height - max(0, dy), max(0, -dx):width - max(0, dx)]
                rows = slice(max(0, dy), height + min(0, dy))
                cols = slice(max(0, dx), width + min(0, dx))
                total[rows, cols] += w * src
                weights[rows, cols] += w
    if total is None:
        raise ValueError("no samples to reconstruct")
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / weights[:, :, None]
    return np.clip(np.nan_to_num(out, nan=0.0), 0.0, 255.0)


def regular_grid(big: np.ndarray, side: int):
    """The ``side²`` sample images of a regular grid drawn in one pass at ``side`` times the
    size, and their offsets: ``(images, offsets)``."""
    images, offsets = [], []
    for b in range(side):
        for a in range(side):
            images.append(big[b::side, a::side])
            offsets.append(((a + 0.5) / side, (b + 0.5) / side))
    return images, offsets
