"""The CIE 1931 2° standard observer and chromaticity coordinates.

A colour's tristimulus values are the integrals of its spectrum against x̄, ȳ, z̄; its
chromaticity is ``(x, y) = (X, Y) / (X + Y + Z)``, which forgets the brightness. A single
wavelength λ has ``XYZ = (x̄(λ), ȳ(λ), z̄(λ))``: their chromaticities, 380 to 780 nm, are the
spectral locus, the horseshoe that bounds every colour a person sees.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

TABLE = Path(__file__).with_name("cie1931_2deg_5nm.csv")


@lru_cache(maxsize=1)
def matching_functions() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths (N,) nm, x̄ȳz̄ (N, 3)) from the shipped table (5 nm, 380–780 nm)."""
    data = np.loadtxt(TABLE, delimiter=",", comments="#", skiprows=6)
    data.setflags(write=False)
    return data[:, 0], data[:, 1:]


def chromaticity(xyz) -> np.ndarray:
    """(..., 3) XYZ → (..., 2) xy."""
    xyz = np.asarray(xyz, np.float64)
    return xyz[..., :2] / xyz.sum(axis=-1, keepdims=True)


def spectral_locus(low: float = 380.0, high: float = 700.0) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths, xy (N, 2)) of the monochromatic colours from ``low`` to ``high`` nm. Past
    about 700 nm the locus stands still (x̄ : ȳ fixed) and the table's last digits wander, so
    the diagram stops there, as the usual drawings do."""
    nm, cmf = matching_functions()
    keep = (nm >= low) & (nm <= high)
    return nm[keep], chromaticity(cmf[keep])
