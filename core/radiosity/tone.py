"""Radiosity (or radiance) to display values: ``scene.tone`` "linear" keeps them (the pixel
clamps to [0, 1], as Phong intensities do), "srgb" applies the sRGB transfer curve (IEC
61966-2-1), for scenes in physical units."""

from __future__ import annotations

import numpy as np

from core.colour.srgb import encode


def tone_map(values: np.ndarray, tone: str = "linear") -> np.ndarray:
    if tone == "linear":
        return values
    return encode(values)                 # the sRGB curve (core.colour.srgb), clamped
