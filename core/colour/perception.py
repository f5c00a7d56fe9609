"""Perception beside the numbers: a chart of what the eye makes of the values a frame holds.

Two demonstrations on one picture, both drawn with numpy in sRGB code values (what a PNG and
the window show):

- **Simultaneous contrast**: one grey square on a dark ground and the same grey on a light
  ground. The two squares are the same bytes; the eye judges the one on the dark ground
  lighter (the Mach bands' cause, lateral inhibition, at the scale of a patch).
- **Equal steps of code and equal steps of light**: two ramps of ``steps`` patches from
  black to white. The upper one steps the sRGB code evenly; the lower one steps the light
  (luminance) evenly and encodes it. CIE 1976 lightness L* (a closed form that models the
  eye's response, :func:`lightness`) rises by nearly equal amounts along the first and by
  very unequal ones along the second: evenly spaced light looks bunched in the lights, and
  the darks take one big jump. It is why frames store codes (about a 2.2 gamma) rather than
  light in 8 bits, and why the course's model, lit on codes, still looks even
  (``docs/colour.md``).
"""

from __future__ import annotations

import numpy as np

from core.colour import srgb

DARK_GROUND, LIGHT_GROUND, PATCH = 0.12, 0.88, 0.5      # sRGB code values
RAMP_STEPS = 11
GAP = 6                                                   # pixels between the chart's parts


def lightness(luminance) -> np.ndarray:
    """CIE 1976 L* of relative luminance Y (white = 1): ``116 f(Y) - 16``, with
    ``f(t) = t^(1/3)`` above (6/29)^3 and the straight line ``t / (3 (6/29)^2) + 4/29``
    below it (CIE 015:2004, 8.2.1)."""
    y = np.asarray(luminance, np.float64)
    delta = 6.0 / 29.0
    f = np.where(y > delta ** 3, np.cbrt(y), y / (3 * delta ** 2) + 4.0 / 29.0)
    return 116.0 * f - 16.0


def ramps(steps: int = RAMP_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """(codes stepped evenly, codes of light stepped evenly): two (steps,) rows in [0, 1]."""
    even = np.linspace(0.0, 1.0, steps)
    return even, srgb.encode(even)


def lightness_steps(codes) -> np.ndarray:
    """The rises of L* from each patch of a ramp of sRGB codes to the next."""
    return np.diff(lightness(srgb.decode(codes)))


def _bytes(code) -> np.ndarray:
    return np.full(3, int(np.floor(255.0 * float(code) + 0.5)), np.uint8)


def contrast_panel(width: int, height: int) -> np.ndarray:
    """(H, W, 3): the dark and the light ground side by side, the same grey square on each."""
    image = np.empty((height, width, 3), np.uint8)
    half = width // 2
    image[:, :half] = _bytes(DARK_GROUND)
    image[:, half:] = _bytes(LIGHT_GROUND)
    side = max(2, min(half, height) // 3)
    top = (height - side) // 2
    for left in (half // 2 - side // 2, half + (width - half) // 2 - side // 2):
        image[top:top + side, left:left + side] = _bytes(PATCH)
    return image


def ramp_panel(codes, width: int, height: int) -> np.ndarray:
    """(H, W, 3): one patch a code, left to right."""
    image = np.empty((height, width, 3), np.uint8)
    edges = np.linspace(0, width, len(codes) + 1).round().astype(int)
    for code, a, b in zip(codes, edges[:-1], edges[1:]):
        image[:, a:b] = _bytes(code)
    return image


def perception_chart(width: int, height: int, background=(36, 36, 40)) -> np.ndarray:
    """(H, W, 3) uint8: the contrast panel over the top half, the even-code ramp and the
    even-light ramp below it, ``GAP`` pixels apart (rows: :func:`layout`)."""
    image = np.empty((height, width, 3), np.uint8)
    image[:] = np.array(background, np.uint8)
    rows = layout(width, height)
    (_, top), codes, light = rows["contrast"], *ramps()
    image[:top] = contrast_panel(width, top)
    for name, ramp in (("even codes", codes), ("even light", light)):
        a, b = rows[name]
        image[a:b] = ramp_panel(ramp, width, b - a)
    return image


def layout(width: int, height: int) -> dict:
    """Where :func:`perception_chart` puts its parts: rows (start, stop) of each."""
    top = (height - 2 * GAP) // 2
    band = (height - top - 2 * GAP) // 2
    return {"contrast": (0, top), "even codes": (top + GAP, top + GAP + band),
            "even light": (top + 2 * GAP + band, top + 2 * GAP + 2 * band)}
