"""The Phong model (FvDFH 16.1–16.2) as a registered lighting model: model 0, the default.

The local model is :func:`core.shading.illumination.phong_point` and its inspector terms
:func:`core.shading.terms.phong_terms` (written there once; the exact analysis runs that
source in rational arithmetic). Here is the path tracer's Phong lobe: the normalised modified
Phong BRDF ``k_s O_s (n + 2)/(2π) cos^n α`` (α between the mirror direction of ``ω_o`` and
``ω_i``), sampled as ``cos^n α`` about the mirror direction (pdf ``(n + 1)/(2π) cos^n α``).
"""

from __future__ import annotations

import math

from core.jit import njit
from core.shading.illumination import EXPONENT, KS, OS, phong_point as point  # noqa: F401
from core.shading.terms import phong_terms as terms  # noqa: F401
from core.vectors import around, reflect


@njit(cache=True, inline="always")
def glossy(m, at, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, ps):
    """The Phong lobe's BRDF (RGB) at ``ω_i`` and ``ps`` x its pdf (ω's unit, n on ω_o's side)."""
    rx, ry, rz = reflect(-wox, -woy, -woz, nx, ny, nz)
    cos_a = rx * wix + ry * wiy + rz * wiz
    if not cos_a > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    n = m[at + EXPONENT]
    lobe = math.pow(cos_a, n)
    s = m[at + KS] * (n + 2.0) / (2.0 * math.pi) * lobe
    return s * m[at + OS], s * m[at + OS + 1], s * m[at + OS + 2], \
        ps * (n + 1.0) / (2.0 * math.pi) * lobe


@njit(cache=True, inline="always")
def sample_glossy(m, at, nx, ny, nz, wox, woy, woz, u1, u2):
    """A direction of the cos^n lobe about the mirror direction of ``ω_o``."""
    rx, ry, rz = reflect(-wox, -woy, -woz, nx, ny, nz)
    cos_a = math.pow(u1, 1.0 / (m[at + EXPONENT] + 1.0))
    sin_a = math.sqrt(max(0.0, 1.0 - cos_a * cos_a))
    phi = 2.0 * math.pi * u2
    return around(rx, ry, rz, sin_a * math.cos(phi), sin_a * math.sin(phi), cos_a)
