"""The sRGB colour space (IEC 61966-2-1:1999): primaries, white point, the linear RGB → XYZ
matrix they make, and the transfer curve between linear light and code values.

The matrix is derived, not copied (the standard prints it to four decimals): its columns
are the primaries' XYZ scaled so that RGB = (1, 1, 1) is D65 with Y = 1.
"""

from __future__ import annotations

import numpy as np

PRIMARIES = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])   # red, green, blue xy
D65 = np.array([0.3127, 0.3290])                                  # the white point's xy


def xyz_of(xy, luminance: float = 1.0) -> np.ndarray:
    """XYZ of chromaticity ``xy`` at the luminance Y."""
    x, y = np.asarray(xy, np.float64)[..., 0], np.asarray(xy, np.float64)[..., 1]
    return np.stack([x / y, np.ones_like(x), (1 - x - y) / y], axis=-1) * luminance


def rgb_to_xyz_matrix(primaries=PRIMARIES, white=D65) -> np.ndarray:
    """The 3 x 3 M with XYZ = M · (linear R, G, B): each primary's XYZ at the strength that
    makes R = G = B = 1 the white point at Y = 1."""
    columns = xyz_of(primaries).T
    strengths = np.linalg.solve(columns, xyz_of(white))
    return columns * strengths


RGB_TO_XYZ = rgb_to_xyz_matrix()
XYZ_TO_RGB = np.linalg.inv(RGB_TO_XYZ)


def encode(linear) -> np.ndarray:
    """Linear light in [0, 1] → sRGB code values in [0, 1] (clamped first)."""
    c = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def decode(code) -> np.ndarray:
    """sRGB code values in [0, 1] → linear light."""
    c = np.asarray(code, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
