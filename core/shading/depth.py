"""Depth shading (the notes' light-source-independent model: "colour or intensity of the image
determined solely by depth", "darker colours at lower elevations", "effective in modelling
terrain data"). Varyings: ``position`` (3), the world point, interpolated perspective-correct.

The pixel step turns the point into one number and that number into a colour through a
colour map, no light involved:

- ``height`` (``RenderSettings.depth_shading``, the default): the world y, from the lowest to
  the highest vertex of the scene, through the ``terrain`` map (dark water low, green, brown,
  snow high);
- ``view``: the distance from the eye (for a parallel view, along the direction of
  projection), nearest vertex bright to farthest dark, through a grey ramp.
"""

from __future__ import annotations

import numpy as np

from core.arrays import read_only
from core.jit import njit, prange
from core.shading.illumination import EYE_POINT, quantize
from core.shading.registry import Shader, register_shader
from core.shading.shade import ShadeInput, covered_spans

MODES = ("height", "view")
# (t, r, g, b) stops of the colour maps, t from low (0) to high (1)
TERRAIN = ((0.00, 0.05, 0.10, 0.30), (0.30, 0.15, 0.35, 0.60), (0.34, 0.20, 0.40, 0.15),
           (0.60, 0.45, 0.60, 0.25), (0.80, 0.55, 0.42, 0.30), (1.00, 0.95, 0.95, 0.95))
GREY = ((0.00, 0.08, 0.08, 0.08), (1.00, 0.95, 0.95, 0.95))
LUT_SIZE = 256


def colour_map(stops) -> np.ndarray:
    """``(LUT_SIZE, 3)``: the stops linearly interpolated."""
    stops = np.asarray(stops, dtype=np.float64)
    t = np.linspace(0.0, 1.0, LUT_SIZE)
    return np.stack([np.interp(t, stops[:, 0], stops[:, c]) for c in (1, 2, 3)], axis=1)


def _vertex(s: ShadeInput, scene, meshes, weighting) -> None:
    s.vertex_attrs = s.positions                  # read-only, kept with the scene: no copy
    s.computed.append("depth shading")


def _scalar_setup(s: ShadeInput):
    """``(axis (4,), low, high, lut)``: the scalar is ``axis[3] + axis[:3]·P`` (height: y;
    view: the distance from the eye point, flagged by axis[3] = nan; parallel: along the
    direction away from the viewer)."""
    mode = getattr(s.settings, "depth_shading", "height") if s.settings is not None else "height"
    p = s.positions
    if mode == "height":
        axis = np.array([0.0, 1.0, 0.0, 0.0])
        values = p[:, 1]
        lut = colour_map(TERRAIN)
    else:
        if s.eye[0] == EYE_POINT:
            axis = np.array([s.eye[1], s.eye[2], s.eye[3], np.nan])
            values = np.sqrt(((p - s.eye[1:4]) ** 2).sum(axis=1))
        else:
            axis = np.array([-s.eye[1], -s.eye[2], -s.eye[3], 0.0])
            values = p @ axis[:3]
        lut = colour_map(GREY)[::-1].copy()        # far (high distance) dark
    low, high = (float(values.min()), float(values.max())) if len(values) else (0.0, 1.0)
    return axis, low, high, lut


@njit(cache=True, parallel=True, nogil=True)
def _resolve_depth(tri, b1, b2, span, triangles, positions, axis, low, high, lut, out):
    scale = (lut.shape[0] - 1) / (high - low) if high > low else 0.0
    for row in prange(tri.shape[0]):
        for col in range(span[row, 0], span[row, 1] + 1):
            t = tri[row, col]
            if t < 0:
                continue
            i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            w1, w2 = b1[row, col], b2[row, col]
            w0 = 1.0 - w1 - w2
            x = w0 * positions[i0, 0] + w1 * positions[i1, 0] + w2 * positions[i2, 0]
            y = w0 * positions[i0, 1] + w1 * positions[i1, 1] + w2 * positions[i2, 1]
            z = w0 * positions[i0, 2] + w1 * positions[i1, 2] + w2 * positions[i2, 2]
            if np.isnan(axis[3]):                  # distance from the eye point
                dx, dy, dz = x - axis[0], y - axis[1], z - axis[2]
                value = np.sqrt(dx * dx + dy * dy + dz * dz)
            else:
                value = axis[3] + axis[0] * x + axis[1] * y + axis[2] * z
            k = int((value - low) * scale + 0.5)
            k = min(max(k, 0), lut.shape[0] - 1)
            for c in range(3):
                out[row, col, c] = quantize(lut[k, c])


def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    axis, low, high, lut = _scalar_setup(s)
    _resolve_depth(np.ascontiguousarray(vis.tri, dtype=np.int32),
                   np.ascontiguousarray(vis.b1, dtype=np.float64),
                   np.ascontiguousarray(vis.b2, dtype=np.float64), covered_spans(vis),
                   triangles, read_only(np.ascontiguousarray(attrs, dtype=np.float64)), axis,
                   low, high,
                   lut, out)


register_shader(Shader("depth", _vertex, _pixel, varyings=("position",), width=3,
                       description="colour from height or view depth alone, through a colour map"))
