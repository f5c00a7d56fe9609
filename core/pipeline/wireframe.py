"""Wireframe edges, compiled: Cohen–Sutherland, M_per · M_vv3dv, divide by W, midpoint line.

The same three stages as ``clip.clip_lines`` → ``project.project_lines`` →
``raster_lines.draw_lines`` (those stay as the readable, vectorised reference and the tests
hold the two to the same pixels), fused into one numba loop over the edges: a big mesh's
wireframe (scenes/big.toml: 196 000 edges) then costs about what its shaded frame does, where
the numpy stages allocated a dozen arrays per stage and spent most of the frame in them.

Takes canonical points (after N_per / N_par), the mesh's edges (each once: ``Mesh.all_edges``),
the projection's clip planes (``clip.planes``), the 4 x 4 matrix to the device (``M_vv3dv``,
times ``M_per`` for perspective) and draws into a ``(H, W, 3)`` uint8 image, top row first.
Returns the number of segments drawn.
"""

from __future__ import annotations

import numpy as np
from core.jit import njit


@njit(cache=True)
def _outcode(x, y, z, pl):
    """The 6-bit outcode: bit k set when plane k's ``a x + b y + c z + d`` is > 0."""
    code = 0
    for k in range(6):
        if pl[k, 0] * x + pl[k, 1] * y + pl[k, 2] * z + pl[k, 3] > 0.0:
            code |= 1 << k
    return code


@njit(cache=True)
def _clip(a, b, pl):
    """FvDFH's Cohen–Sutherland on the segment a–b (3-vectors, moved in place); True if a
    part is visible. An outside endpoint is moved to the first plane it violates."""
    code_a = _outcode(a[0], a[1], a[2], pl)
    code_b = _outcode(b[0], b[1], b[2], pl)
    for _ in range(12):              # each pass clears one bit; 12 bounds round-off cycling
        if (code_a | code_b) == 0:
            return True
        if (code_a & code_b) != 0:
            return False
        a_out = code_a != 0
        code = code_a if a_out else code_b
        bit = 0
        while not (code >> bit) & 1:
            bit += 1
        out = a if a_out else b
        other = b if a_out else a
        f_out = pl[bit, 0] * out[0] + pl[bit, 1] * out[1] + pl[bit, 2] * out[2] + pl[bit, 3]
        f_in = pl[bit, 0] * other[0] + pl[bit, 1] * other[1] + pl[bit, 2] * other[2] + pl[bit, 3]
        denominator = f_out - f_in
        t = f_out / denominator if denominator != 0.0 else 0.0
        t = min(max(t, 0.0), 1.0)
        for c in range(3):
            out[c] = out[c] + t * (other[c] - out[c])
        new_code = _outcode(out[0], out[1], out[2], pl) & ~(1 << bit)
        if a_out:
            code_a = new_code
        else:
            code_b = new_code
    return (code_a | code_b) == 0


@njit(cache=True)
def _to_pixel(p, m, width, height):
    """Device pixel (column, device row) of canonical point p: m · (x, y, z, 1), / W, floor,
    clamped to the image (a point on the far edge belongs to the last pixel)."""
    x = m[0, 0] * p[0] + m[0, 1] * p[1] + m[0, 2] * p[2] + m[0, 3]
    y = m[1, 0] * p[0] + m[1, 1] * p[1] + m[1, 2] * p[2] + m[1, 3]
    w = m[3, 0] * p[0] + m[3, 1] * p[1] + m[3, 2] * p[2] + m[3, 3]
    col = min(max(np.floor(x / w), 0.0), width - 1.0)
    row = min(max(np.floor(y / w), 0.0), height - 1.0)
    return np.int64(col), np.int64(row)


@njit(cache=True)
def _midpoint_line(image, x0, y0, x1, y1, rgb):
    """FvDFH's MidpointLine, all eight octants; device rows run up, image rows down."""
    height = image.shape[0]
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    sx = 1 if x1 >= x0 else -1
    sy = 1 if y1 >= y0 else -1
    x, y = x0, y0
    if dx >= dy:
        d = 2 * dy - dx
        for _ in range(dx + 1):
            for c in range(3):
                image[height - 1 - y, x, c] = rgb[c]
            if d > 0:
                y += sy
                d -= 2 * dx
            d += 2 * dy
            x += sx
    else:
        d = 2 * dx - dy
        for _ in range(dy + 1):
            for c in range(3):
                image[height - 1 - y, x, c] = rgb[c]
            if d > 0:
                x += sx
                d -= 2 * dy
            d += 2 * dx
            y += sy


@njit(cache=True)
def draw_edges(points, edges, pl, m, image, rgb):
    """Clip, project and draw every edge ``points[e0]–points[e1]``; returns how many drew."""
    height, width = image.shape[0], image.shape[1]
    a = np.empty(3)
    b = np.empty(3)
    drawn = 0
    for e in range(edges.shape[0]):
        for c in range(3):
            a[c] = points[edges[e, 0], c]
            b[c] = points[edges[e, 1], c]
        if not _clip(a, b, pl):
            continue
        x0, y0 = _to_pixel(a, m, width, height)
        x1, y1 = _to_pixel(b, m, width, height)
        _midpoint_line(image, x0, y0, x1, y1, rgb)
        drawn += 1
    return drawn
