"""Closed-form form factors (Howell's catalogue, C-11, C-14, C-41) and the test shapes that
go with them, for checking the hemicube and the ray-cast factors.

Each ``*_pair`` function returns ``(source corners (T, 3, 3), target corners (T, 3, 3),
exact F(source → target))``; :func:`measured` computes the same factor with either method by
area-averaging point-to-target factors over the source cut into ``n`` pieces.
"""

from __future__ import annotations

import math

import numpy as np


def parallel_rectangles(a: float, b: float, c: float) -> float:
    """Two directly opposed a x b rectangles a distance c apart (C-11)."""
    x, y = a / c, b / c
    return 2.0 / (math.pi * x * y) * (
        0.5 * math.log((1 + x * x) * (1 + y * y) / (1 + x * x + y * y))
        + x * math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))
        + y * math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
        - x * math.atan(x) - y * math.atan(y))


def perpendicular_rectangles(l: float, w: float, h: float) -> float:
    """From a rectangle l x w to a perpendicular one l x h sharing the edge l (C-14)."""
    W, H = w / l, h / l
    s = H * H + W * W
    log_term = (math.log((1 + W * W) * (1 + H * H) / (1 + s))
                + W * W * math.log(W * W * (1 + s) / ((1 + W * W) * s))
                + H * H * math.log(H * H * (1 + s) / ((1 + H * H) * s)))
    return (W * math.atan(1 / W) + H * math.atan(1 / H) - math.sqrt(s) * math.atan(1 / math.sqrt(s))
            + 0.25 * log_term) / (math.pi * W)


def coaxial_discs(r1: float, r2: float, h: float) -> float:
    """From a disc of radius r1 to a coaxial parallel disc of radius r2 at distance h (C-41)."""
    R1, R2 = r1 / h, r2 / h
    x = 1 + (1 + R2 * R2) / (R1 * R1)
    return 0.5 * (x - math.sqrt(x * x - 4 * (R2 / R1) ** 2))


def _quad(p0, p1, p2, p3) -> np.ndarray:
    """Two triangles, counter-clockwise p0 p1 p2 p3."""
    return np.array([[p0, p1, p2], [p0, p2, p3]], dtype=np.float64)


def _disc(radius: float, z: float, up: bool, segments: int = 96) -> np.ndarray:
    """A fan of ``segments`` triangles of the same area as the disc, facing ±z."""
    r = radius * math.sqrt(2 * math.pi / (segments * math.sin(2 * math.pi / segments)))
    a = np.linspace(0, 2 * math.pi, segments + 1)
    rim = np.stack([r * np.cos(a), r * np.sin(a), np.full_like(a, z)], axis=1)
    centre = np.array([0.0, 0.0, z])
    tris = np.array([[centre, rim[i], rim[i + 1]] for i in range(segments)])
    return tris if up else tris[:, ::-1]


def parallel_pair(a=1.0, b=1.0, c=1.0):
    low = _quad((0, 0, 0), (a, 0, 0), (a, b, 0), (0, b, 0))               # faces +z
    high = _quad((0, 0, c), (0, b, c), (a, b, c), (a, 0, c))              # faces -z
    return low, high, parallel_rectangles(a, b, c)


def perpendicular_pair(l=1.0, w=1.0, h=1.0):
    floor = _quad((0, 0, 0), (l, 0, 0), (l, w, 0), (0, w, 0))             # z = 0, faces +z
    wall = _quad((0, 0, 0), (0, 0, h), (l, 0, h), (l, 0, 0))              # y = 0, faces +y
    return floor, wall, perpendicular_rectangles(l, w, h)


def disc_pair(r1=1.0, r2=1.0, h=1.0, segments=96):
    return (_disc(r1, 0.0, True, segments), _disc(r2, h, False, segments),
            coaxial_discs(r1, r2, h))


def measured(source: np.ndarray, target: np.ndarray, method: str, resolution: int = 256,
             pieces: int = 8) -> float:
    """F(source → target) by ``method`` ("hemicube" or "raycast"): the point-to-target factor
    at the centres of the source cut into ``pieces²`` per triangle, area-averaged."""
    from core.radiosity.mesh import _frames, subdivide
    parts, _ = subdivide(source, np.full(len(source), pieces))
    area, normal, centre = _frames(parts)
    everything = np.concatenate([source, target])
    lo, hi = everything.reshape(-1, 3).min(axis=0), everything.reshape(-1, 3).max(axis=0)
    scale = float(np.linalg.norm(hi - lo))
    if method == "hemicube":
        from core.radiosity.hemicube import form_factors
        positions = target.reshape(-1, 3)
        triangles = np.arange(len(positions), dtype=np.int64).reshape(-1, 3)
        f = np.array([form_factors(positions, triangles, c, n, resolution, scale).sum()
                      for c, n in zip(centre, normal)])
    elif method == "raycast":
        from core.radiosity.raycast import factors_to_patch
        from core.raytrace.bvh import build
        bvh, _ = build(everything.reshape(-1, 3),
                       np.arange(3 * len(everything), dtype=np.int64).reshape(-1, 3))
        _, target_normal, _ = _frames(target)
        f = sum(factors_to_patch(bvh, centre, normal, tri, tn, scale)
                for tri, tn in zip(target, target_normal))
    else:
        raise ValueError(f"method must be hemicube or raycast, not {method!r}")
    return float((f * area).sum() / area.sum())
