"""The course tutorial's texture-coordinate path: screen (x, y) → polygon (s, t) → texture (u, v).

The tutorial ("A Texture Mapping Algorithm", CS4451 group 4, after Sean Barrett) gives a
polygon's texture by an origin ``P`` and the vectors ``M`` and ``N`` of its u and v axes, and
computes nine numbers that stay constant over the polygon::

    O_a = N_x P_z − N_z P_x    H_a = N_z P_y − N_y P_z    V_a = N_y P_x − N_x P_y
    O_b = M_x P_z − M_z P_x    H_b = M_z P_y − M_y P_z    V_b = M_y P_x − M_x P_y
    O_c = M_z N_x − M_x N_z    H_c = M_y N_z − M_z N_y    V_c = M_x N_y − M_y N_x

then for pixel i of row j: ``a = O_a + H_a i + V_a j`` (likewise b, c), ``u = 256 a / c``,
``v = 256 b / c`` and ``screen[i] = texture_map[v][u]``. Read as vectors these are
``a = (P × N)·r``, ``b = (P × M)·r``, ``c = (M × N)·r`` for the ray ``r = (i, 1, j)``: the
tutorial's camera space has x across the screen, **y the depth** and z down the screen, and
the screen is the plane y = 1, so pixel (i, j) sees the points k (i, 1, j). Where that ray
meets the plane ``P + s M + t N``, Cramer's rule gives ``s = −a / c`` and ``t = b / c``: with
the constants as printed, u runs along −M. We keep the nine formulas as printed and hand them
``M = −∂X/∂u`` (the u axis pointing back), so that ``u = 256 a / c`` is the texture's u.

Our pipeline's device coordinates are projective images of eye space, so the tutorial's
camera space is a linear map of the canonical perspective volume: depth ``y_t = W = −z``
(canonical), ``x_t = (x_dev − ½) W`` and ``z_t = (row) W`` where ``x_dev`` is the device x
before the divide by W and row counts pixel rows from the top (so integer (i, j) are pixel
centres). A linear map keeps planes, so P, M, N of a triangle (from its vertices and their
(u, v)) map to the tutorial's space and the nine constants follow. Along a scan line a, b and
c are stepped incrementally (``a += H_a``), the tutorial's "for i = each x value in the row".

It is the same mapping as perspective-correct barycentric interpolation of (u, v) (the
tests show the two agree to 1e-9 on random triangles under perspective); the tutorial samples
the nearest texel, one texel per pixel, with no filtering.
"""

from __future__ import annotations

import numpy as np
from core.jit import njit, prange


def nine_constants(P: np.ndarray, M: np.ndarray, N: np.ndarray) -> np.ndarray:
    """``(3, 3)``: rows O, H, V; columns a, b, c — the tutorial's formulas, as printed."""
    Px, Py, Pz = P
    Mx, My, Mz = M
    Nx, Ny, Nz = N
    return np.array([
        [Nx * Pz - Nz * Px, Mx * Pz - Mz * Px, Mz * Nx - Mx * Nz],     # O_a, O_b, O_c
        [Nz * Py - Ny * Pz, Mz * Py - My * Pz, My * Nz - Mz * Ny],     # H_a, H_b, H_c
        [Ny * Px - Nx * Py, My * Px - Mx * Py, Mx * Ny - My * Nx],     # V_a, V_b, V_c
    ])


def triangle_constants(device_h: np.ndarray, triangles: np.ndarray, uv: np.ndarray,
                       height: int) -> np.ndarray:
    """``(T, 3, 3)``: each triangle's nine constants (u, v in texture units, not texels).

    A triangle whose (u, v) are collinear has no texture frame: its constants are 0 (c = 0,
    so u = v = nan there). Compiled, one triangle per iteration (100k in a few ms).
    """
    out = np.zeros((len(triangles), 3, 3))
    _constants(np.ascontiguousarray(device_h, dtype=np.float64),
               np.ascontiguousarray(triangles, dtype=np.int64),
               np.ascontiguousarray(uv, dtype=np.float64), float(height), out)
    return out


@njit(cache=True)
def _tutorial_point(device_h, k, height):
    """Vertex k of the device (x W, y W, z W, W) in the tutorial's camera space."""
    w = device_h[k, 3]
    return device_h[k, 0] - 0.5 * w, w, (height - 0.5) * w - device_h[k, 1]


@njit(cache=True, parallel=True, nogil=True)
def _constants(device_h, triangles, uv, height, out):
    for t in prange(triangles.shape[0]):
        plane_constants(device_h, triangles[t, 0], triangles[t, 1], triangles[t, 2],
                        uv[triangles[t, 0], 0], uv[triangles[t, 0], 1],
                        uv[triangles[t, 1], 0], uv[triangles[t, 1], 1],
                        uv[triangles[t, 2], 0], uv[triangles[t, 2], 1], height, out, t)


@njit(cache=True)
def plane_constants(device_h, i0, i1, i2, u0, v0, u1, v1, u2, v2, height, out, slot):
    """The nine constants of the triangle (i0, i1, i2) with (u, v) at its corners, into
    ``out[slot]`` (left as they are when the (u, v) are collinear: no texture frame)."""
    x0, y0, z0 = _tutorial_point(device_h, i0, height)
    x1, y1, z1 = _tutorial_point(device_h, i1, height)
    x2, y2, z2 = _tutorial_point(device_h, i2, height)
    du1, dv1 = u1 - u0, v1 - v0
    du2, dv2 = u2 - u0, v2 - v0
    det = du1 * dv2 - dv1 * du2
    if not abs(det) > 1e-300:
        return
    # [dX/du; dX/dv] = [[du1, dv1], [du2, dv2]]^-1 [E1; E2]
    e1x, e1y, e1z = x1 - x0, y1 - y0, z1 - z0
    e2x, e2y, e2z = x2 - x0, y2 - y0, z2 - z0
    ux, uy, uz = (dv2 * e1x - dv1 * e2x) / det, (dv2 * e1y - dv1 * e2y) / det, \
        (dv2 * e1z - dv1 * e2z) / det
    vx, vy, vz = (du1 * e2x - du2 * e1x) / det, (du1 * e2y - du2 * e1y) / det, \
        (du1 * e2z - du2 * e1z) / det
    Px, Py, Pz = x0 - u0 * ux - v0 * vx, y0 - u0 * uy - v0 * vy, z0 - u0 * uz - v0 * vz
    Mx, My, Mz = -ux, -uy, -uz                         # M = −∂X/∂u (see the docstring)
    Nx, Ny, Nz = vx, vy, vz
    out[slot, 0, 0] = Nx * Pz - Nz * Px                # O_a, O_b, O_c
    out[slot, 0, 1] = Mx * Pz - Mz * Px
    out[slot, 0, 2] = Mz * Nx - Mx * Nz
    out[slot, 1, 0] = Nz * Py - Ny * Pz                # H_a, H_b, H_c
    out[slot, 1, 1] = Mz * Py - My * Pz
    out[slot, 1, 2] = My * Nz - Mz * Ny
    out[slot, 2, 0] = Ny * Px - Nx * Py                # V_a, V_b, V_c
    out[slot, 2, 1] = My * Px - Mx * Py
    out[slot, 2, 2] = Mx * Ny - My * Nx


# numpy's error model: a triangle without (u, v) has zero constants, and its callers take the
# inf or nan that gives as "no (u, v) here" (textured_pixel) wherever they run
@njit(cache=True, error_model="numpy")
def uv_at(constants, t, i, j):
    """(u, v) of triangle ``t`` at pixel (column i, row j from the top), and the exact
    screen-space derivatives ``du/dx, dv/dx, du/dy, dv/dy`` (x right, y up).

    u = a / c with a and c linear in (i, j), so du/di = (H_a c − a H_c) / c² (and so on);
    the row index runs down the screen, so d/dy = −d/dj.
    """
    a = constants[t, 0, 0] + constants[t, 1, 0] * i + constants[t, 2, 0] * j
    b = constants[t, 0, 1] + constants[t, 1, 1] * i + constants[t, 2, 1] * j
    c = constants[t, 0, 2] + constants[t, 1, 2] * i + constants[t, 2, 2] * j
    u, v = a / c, b / c
    dudi = (constants[t, 1, 0] - u * constants[t, 1, 2]) / c
    dvdi = (constants[t, 1, 1] - v * constants[t, 1, 2]) / c
    dudj = (constants[t, 2, 0] - u * constants[t, 2, 2]) / c
    dvdj = (constants[t, 2, 1] - v * constants[t, 2, 2]) / c
    return u, v, dudi, dvdi, -dudj, -dvdj


@njit(cache=True, parallel=True, nogil=True)
def scan_uv(tri, constants, size, uv_out):
    """(u, v) at every covered pixel, stepped along each scan line as the tutorial does.

    ``tri (H, W)``: the visible triangle per pixel (−1 empty), ``constants (T, 3, 3)``,
    ``size``: the texture's side (256 in the tutorial). Writes ``size · a / c`` and
    ``size · b / c`` into ``uv_out (H, W, 2)`` (nan where empty).
    """
    height, width = tri.shape
    for j in prange(height):
        current = -1
        a = b = c = 0.0
        for i in range(width):
            t = tri[j, i]
            if t < 0:
                uv_out[j, i, 0] = uv_out[j, i, 1] = np.nan
                current = -1
                continue
            if t != current:                    # a new span: a, b, c from O + H i + V j
                current = t
                a = constants[t, 0, 0] + constants[t, 1, 0] * i + constants[t, 2, 0] * j
                b = constants[t, 0, 1] + constants[t, 1, 1] * i + constants[t, 2, 1] * j
                c = constants[t, 0, 2] + constants[t, 1, 2] * i + constants[t, 2, 2] * j
            uv_out[j, i, 0] = size * a / c
            uv_out[j, i, 1] = size * b / c
            a += constants[t, 1, 0]             # one pixel to the right: + H
            b += constants[t, 1, 1]
            c += constants[t, 1, 2]


@njit(cache=True, parallel=True, nogil=True)
def tutorial_map(tri, constants, texels, levels, background, out):
    """``screen[i] = texture_map[v][u]``: the nearest texel of level 0 (repeat) per pixel.

    ``out (H, W, 3)`` float. The texture is ``levels[0]``'s ``w x h``; u and v are in texels.
    """
    height, width = tri.shape
    w, h = levels[0, 1], levels[0, 2]
    uv = np.empty((height, width, 2))
    scan_uv(tri, constants, 1.0, uv)
    for j in prange(height):
        for i in range(width):
            if tri[j, i] < 0:
                for k in range(3):
                    out[j, i, k] = background[k]
                continue
            tu = int(np.floor(uv[j, i, 0] * w)) % w
            tv = int(np.floor(uv[j, i, 1] * h)) % h
            row = levels[0, 0] + tv * w + tu
            for k in range(3):
                out[j, i, k] = texels[row, k]
