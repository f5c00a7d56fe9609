"""The course's Java bump-mapping demo (``J3DPanel``), as a material and a view like any other.

What the demo does, per pixel (x, y) of a w x h panel (the course packet, ``J3DPanel.java``):

- the point ``P = (x/w · 100, y/h · (−100), 0)`` on the plane z = 0 (the view window runs from
  the origin to ``botRight = (100, −100, 0)``), normal ``N = (0, 0, 1)``;
- bump mode: ``P' = P + N B(P.x, P.y)``, ``P1 = P + (ε, ε, 0) + N B(P.x + ε, P.y + ε)``,
  ``P2 = P + (ε, −ε, 0) + N B(P.x + ε, P.y − ε)`` with ε = 1e-4, ``N' = (v2 × v1)/|…|`` for
  ``v1 = P1 − P'``, ``v2 = P2 − P'``, and the model at ``(P', N')``; Phong mode: the model at
  ``(P, N)``;
- the model (``phongIntensity``): ``L = (light − P)/|…|``, ``d = max(N·L, 0)``,
  ``V = (viewPoint − P)/|…|``, ``R = 2 d N − L``, ``s = max(R·V, 0)``, ``I = d + (1 − d) s``
  (no exponent), returned as a Java ``float``; light and viewpoint both at (50, −50, 50);
- the colour ``Color(0, 0, (float)(0.3 + 0.7 I))``, i.e. blue = (int)(b · 255 + 0.5).

The four height maps B are ``bump(x, y)``'s cases (:data:`LABELS` is the text the demo shows);
map numbers past 3 fall to the ``default`` case, map 0. The panel's ``fillRect(x, y, x+1,
y+1)`` passes a corner where Java wants a size, so each pixel paints a (x+1) x (y+1) block; but
pixels are painted column by column, top to bottom, and the last block to cover (X, Y) is the
one of pixel (X, Y) itself, so the picture is the per-pixel one above.

Here the demo is not a special renderer: ``scenes/bump_demo.toml`` is a quad on z = 0 with a
material of kind ``"bump_demo"`` (:func:`demo_pixel` is its pixel step: it takes the
interpolated position and normal like any Phong pixel step) and one point light; the view is
a parallel view down −z whose window is shifted by half a pixel, so that the renderer's pixel
centres fall on the demo's pixel corners (:func:`demo_view`). Java's ``float`` roundings are
kept (``np.float32``), so the bytes are the demo's.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit
from core.texture.demo_scene import (DEMO_LIGHT, DEMO_VIEWPOINT, LABELS, MAPS,  # noqa: F401
                                     WINDOW_SIZE, apply_demo_options, demo_bump_numpy,
                                     demo_view, label, panel_views)

EPSILON = 1e-4



@njit(cache=True)
def demo_bump(bump_map, x, y):
    """``J3DPanel.bump``: the height B(x, y) of map ``bump_map``."""
    if bump_map == 1:
        return math.sin(x) + math.cos(y)
    if bump_map == 2:
        return math.sin(x) + math.sin(y)
    if bump_map == 3:
        return math.sin(math.pow((x - 50) * (x - 50) + (y + 50) * (y + 50), 0.5))
    return math.sin(math.pow(x * x + y * y, 0.5))       # case 0 and the default case


@njit(cache=True)
def _normalize(x, y, z):
    mag = math.pow(x * x + y * y + z * z, 0.5)
    return x / mag, y / mag, z / mag


@njit(cache=True)
def demo_phong(px, py, pz, nx, ny, nz, light, viewpoint):
    """``phongIntensity``: I = d + (1 − d) max(R·V, 0), as a Java float."""
    nx, ny, nz = _normalize(nx, ny, nz)
    lx, ly, lz = _normalize(light[0] - px, light[1] - py, light[2] - pz)
    diffuse = max(nx * lx + ny * ly + nz * lz, 0.0)
    vx, vy, vz = _normalize(viewpoint[0] - px, viewpoint[1] - py, viewpoint[2] - pz)
    rx, ry, rz = nx * (2 * diffuse) - lx, ny * (2 * diffuse) - ly, nz * (2 * diffuse) - lz
    specular = max(rx * vx + ry * vy + rz * vz, 0.0)
    return np.float32(diffuse + (1 - diffuse) * specular)


@njit(cache=True)
def demo_bumped(px, py, pz, nx, ny, nz, bump_map):
    """``bumpIntensity``'s point and normal: ``(P', N')`` from two nearby points at ±ε."""
    b0 = demo_bump(bump_map, px, py)
    b1 = demo_bump(bump_map, px + EPSILON, py + EPSILON)
    b2 = demo_bump(bump_map, px + EPSILON, py - EPSILON)
    ppx, ppy, ppz = px + nx * b0, py + ny * b0, pz + nz * b0
    v1x = (px + EPSILON + nx * b1) - ppx
    v1y = (py + EPSILON + ny * b1) - ppy
    v1z = (pz + nz * b1) - ppz
    v2x = (px + EPSILON + nx * b2) - ppx
    v2y = (py - EPSILON + ny * b2) - ppy
    v2z = (pz + nz * b2) - ppz
    cx, cy, cz = v2y * v1z - v2z * v1y, v2z * v1x - v2x * v1z, v2x * v1y - v2y * v1x  # v2 × v1
    cx, cy, cz = _normalize(cx, cy, cz)
    return ppx, ppy, ppz, cx, cy, cz


@njit(cache=True)
def demo_pixel(px, py, pz, nx, ny, nz, light, viewpoint, bump_map, bump):
    """The demo's colour at a point with normal N: ``(0, 0, blue)`` in [0, 1], where blue is
    the Java float ``0.3 + 0.7 I`` (with ``bump`` the bumped point and normal's I)."""
    if bump:
        px, py, pz, nx, ny, nz = demo_bumped(px, py, pz, nx, ny, nz, bump_map)
    intensity = demo_phong(px, py, pz, nx, ny, nz, light, viewpoint)
    return np.float32(0.3 + 0.7 * np.float64(intensity))


@njit(cache=True)
def java_color_byte(c):
    """``new Color(float …)``: ``(int)(c * 255 + 0.5)``, the product in float."""
    return int(np.float64(np.float32(c) * np.float32(255.0)) + 0.5)


