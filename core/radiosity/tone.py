"""Radiosity (or radiance) to display values: ``scene.tone`` "linear" keeps them (the pixel
clamps to [0, 1], as Phong intensities do), "srgb" applies the sRGB transfer curve (IEC
61966-2-1), for scenes in physical units."""

from __future__ import annotations

import numpy as np


def tone_map(values: np.ndarray, tone: str = "linear") -> np.ndarray:
    if tone == "linear":
        return values
    v = np.clip(values, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)
