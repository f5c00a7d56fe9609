"""The textured pixel step: colour textures, Blinn's bump mapping, normal maps, environment maps.

One numba kernel shades every visible pixel of a visibility buffer. Per pixel it interpolates
the varyings (normal, world position, (u, v), ∂P/∂u, ∂P/∂v) with the perspective-correct
barycentrics, finds the screen-space derivatives of (u, v) from the triangle's plane
constants (:func:`core.texture.tutorial.uv_at`), and then, for the pixel's material:

1. **normal** — Blinn (1978): the surface raised by F = ``bump_scale`` · h(u, v) has the normal
   ``N' = N + (F_u (N × P_v) − F_v (N × P_u)) / |P_u × P_v|`` (N unit; P_u = ∂P/∂u, P_v = ∂P/∂v
   from :func:`core.texture.material.tangent_frames`); F_u, F_v are central differences of the
   height map one texel of the pixel's MIP level apart, so the bumps are filtered like the
   colour. A **normal map** instead gives n = 2 rgb − 1 in the tangent frame (T, B, N): T = P_u
   made orthogonal to N, B = ± N × T (the sign of P_v's side), as tinyrenderer and glTF do;
2. **colour** — the texture's (filtered in linear light, encoded back to display values when the
   texture is sRGB) replaces the material's O_d in the Phong model
   (:func:`core.shading.illumination.phong_point`, the one model every renderer uses);
3. **environment** (Blinn & Newell 1976) — the view direction reflected about the normal,
   ``R = 2 (N·V) N − V``, looked up in an equirectangular image (u = ½ + atan2(R_x, −R_z)/2π,
   v = ½ + asin(R_y)/π: v up, the −z direction in the middle) and mixed in by ``reflectivity``.

Textures of all materials are packed together (:func:`pack_maps`): one texel array, one level
table, and per texture its first level, level count and wrap; per material the texture of each
role (−1: none) and its numbers.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit

# The kernels here that are not inlined declare _nrt=False (no reference counts): they make
# no array, and numba compiles a callee with the flags of the first caller that needs it,
# so without the declaration a counted copy, linked into the ray tracer's or the pixel
# step's uncounted code, would take and give back a count for every view it makes.
from core.shading.illumination import OD, TWO_SIDED, unit3
from core.shading.models.dispatch import light_point
from core.texture.sample import BILINEAR, sample
from core.texture.tutorial import uv_at

# Columns of the varyings the textured shaders carry through clipping.
NORMAL, POSITION, UV, DPDU, DPDV = 0, 3, 6, 8, 11
VARYING_COLUMNS = 14
# Columns of a packed material row (pack_maps).
COLOR, HEIGHT, NORMAL_MAP, ENVIRONMENT, BUMP_SCALE, REFLECTIVITY, COLOR_SRGB = range(7)
MAP_COLUMNS = 7
NO_TEXTURE = -1.0


def pack_maps(maps_per_surface: list) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(texels (N, 4) float32, levels (L, 3) int64, textures (K, 3) int64, rows (M, 7))``.

    ``textures[k]`` = first level row in ``levels``, level count, wrap code; ``rows[s]`` the
    texture index of each role of surface s (−1 none), bump scale, reflectivity, sRGB flag.
    """
    texel_parts, level_parts, textures = [], [], []
    rows = np.full((len(maps_per_surface), MAP_COLUMNS), NO_TEXTURE)
    rows[:, BUMP_SCALE] = 0.0
    rows[:, REFLECTIVITY] = 0.0
    rows[:, COLOR_SRGB] = 0.0
    index: dict[int, int] = {}
    offset = level_count = 0

    def add(texture) -> int:
        nonlocal offset, level_count
        if id(texture) not in index:
            texels, levels = texture.packed()
            shifted = levels.copy()
            shifted[:, 0] += offset
            texel_parts.append(texels)
            level_parts.append(shifted)
            textures.append((level_count, len(levels), texture.wrap_code))
            offset += len(texels)
            level_count += len(levels)
            index[id(texture)] = len(textures) - 1
        return index[id(texture)]

    for s, maps in enumerate(maps_per_surface):
        if maps is None:
            continue
        for column, texture in ((COLOR, maps.color), (HEIGHT, maps.height),
                                (NORMAL_MAP, maps.normal_map), (ENVIRONMENT, maps.environment)):
            if texture is not None:
                rows[s, column] = add(texture)
        rows[s, BUMP_SCALE] = maps.bump_scale
        rows[s, REFLECTIVITY] = maps.reflectivity
        rows[s, COLOR_SRGB] = 1.0 if maps.color is not None and maps.color.srgb else 0.0
    texels = (np.concatenate(texel_parts) if texel_parts else np.zeros((1, 4), np.float32))
    levels = (np.concatenate(level_parts) if level_parts else np.array([[0, 1, 1]], np.int64))
    table = np.array(textures, dtype=np.int64).reshape(-1, 3)
    return np.ascontiguousarray(texels), np.ascontiguousarray(levels), table, rows


@njit(cache=True, _nrt=False)
def lookup(texels, levels, textures, k, filter_, u, v, dudx, dvdx, dudy, dvdy):
    first, count, wrap = textures[k, 0], textures[k, 1], textures[k, 2]
    return sample(texels, levels, wrap, filter_, u, v, dudx, dvdx, dudy, dvdy, first, count)


@njit(cache=True, _nrt=False)
def encode_srgb(c):
    """Linear light → sRGB display value (IEC 61966-2-1), c clamped to [0, 1]."""
    c = min(max(c, 0.0), 1.0)
    return c * 12.92 if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


@njit(cache=True, _nrt=False)
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, _nrt=False)
def bumped_normal(nx, ny, nz, pux, puy, puz, pvx, pvy, pvz, texels, levels, textures, k,
                  scale, filter_, u, v, dudx, dvdx, dudy, dvdy):
    """Blinn's perturbed normal from height map ``k``; P_u, P_v: ∂P/∂u, ∂P/∂v.

    Turning N over (two-sided lighting) turns the cross products over too, so the result is
    the same surface's normal, turned over: no special case.
    """
    first = textures[k, 0]
    w, h = levels[first, 1], levels[first, 2]
    # one texel of the level the pixel reads (level 0 when magnified)
    rho = max(math.sqrt((dudx * w) ** 2 + (dvdx * h) ** 2),
              math.sqrt((dudy * w) ** 2 + (dvdy * h) ** 2))
    step = max(rho, 1.0) if math.isfinite(rho) else 1.0
    du, dv = step / w, step / h
    hu1 = lookup(texels, levels, textures, k, filter_, u + du, v, dudx, dvdx, dudy, dvdy)[0]
    hu0 = lookup(texels, levels, textures, k, filter_, u - du, v, dudx, dvdx, dudy, dvdy)[0]
    hv1 = lookup(texels, levels, textures, k, filter_, u, v + dv, dudx, dvdx, dudy, dvdy)[0]
    hv0 = lookup(texels, levels, textures, k, filter_, u, v - dv, dudx, dvdx, dudy, dvdy)[0]
    fu = scale * (hu1 - hu0) / (2 * du)
    fv = scale * (hv1 - hv0) / (2 * dv)
    cx, cy, cz = _cross(pux, puy, puz, pvx, pvy, pvz)
    area = math.sqrt(cx * cx + cy * cy + cz * cz)
    if not area > 0.0:
        return nx, ny, nz
    ax, ay, az = _cross(nx, ny, nz, pvx, pvy, pvz)              # N × P_v
    bx, by, bz = _cross(nx, ny, nz, pux, puy, puz)              # N × P_u
    mx, my, mz, _ = unit3(nx + (fu * ax - fv * bx) / area, ny + (fu * ay - fv * by) / area,
                          nz + (fu * az - fv * bz) / area)
    return mx, my, mz


@njit(cache=True, _nrt=False)
def mapped_normal(nx, ny, nz, pux, puy, puz, pvx, pvy, pvz, texels, levels, textures, k,
                  filter_, u, v, dudx, dvdx, dudy, dvdy):
    """The tangent-space normal map ``k``: n = 2 rgb − 1 in the frame (T, B, N)."""
    r, g, b, _ = lookup(texels, levels, textures, k, filter_, u, v, dudx, dvdx, dudy, dvdy)
    d = pux * nx + puy * ny + puz * nz
    tx, ty, tz, length = unit3(pux - d * nx, puy - d * ny, puz - d * nz)
    if not length > 0.0:
        return nx, ny, nz
    bx, by, bz = _cross(nx, ny, nz, tx, ty, tz)
    if bx * pvx + by * pvy + bz * pvz < 0.0:                   # a mirrored (u, v) layout
        bx, by, bz = -bx, -by, -bz
    sx, sy, sz = 2 * r - 1, 2 * g - 1, 2 * b - 1
    mx, my, mz, _ = unit3(sx * tx + sy * bx + sz * nx, sx * ty + sy * by + sz * ny,
                          sx * tz + sy * bz + sz * nz)
    return mx, my, mz


@njit(cache=True, _nrt=False)
def environment(texels, levels, textures, k, rx, ry, rz):
    """The equirectangular environment in direction R (unit): ``(r, g, b)``, linear."""
    u = 0.5 + math.atan2(rx, -rz) / (2 * math.pi)
    v = 0.5 + math.asin(min(max(ry, -1.0), 1.0)) / math.pi
    r, g, b, _ = lookup(texels, levels, textures, k, BILINEAR, u, v, 0.0, 0.0, 0.0, 0.0)
    return r, g, b


@njit(cache=True, _nrt=False)
def view_direction(eye, px, py, pz):
    if eye[0] == 1.0:                                   # a point: perspective
        vx, vy, vz, _ = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
        return vx, vy, vz
    return eye[1], eye[2], eye[3]


@njit(cache=True, _nrt=False)
def _lerp(attrs, c, i0, i1, i2, w0, w1, w2):
    return w0 * attrs[i0, c] + w1 * attrs[i1, c] + w2 * attrs[i2, c]


# numpy's error model, as in the parallel loops that call it with their index: one
# compiled form for both (core.jit.reuse_plain_overloads)
@njit(cache=True, error_model="numpy", _nrt=False)
def textured_pixel(attrs, i0, i1, i2, w0, w1, w2, t, col, row, constants, s, maps,
                   texels, levels, textures, filter_, bump, surf, lights, ambient, eye,
                   halfway):
    """The colour ``(r, g, b)`` of one pixel; ``surf`` is a scratch copy of the surfaces."""
    u, v, dudx, dvdx, dudy, dvdy = uv_at(constants, t, col, row)
    if not (math.isfinite(u) and math.isfinite(v)):      # (u, v) degenerate on this triangle
        u = _lerp(attrs, UV, i0, i1, i2, w0, w1, w2)
        v = _lerp(attrs, UV + 1, i0, i1, i2, w0, w1, w2)
        dudx = dvdx = dudy = dvdy = 0.0
    return textured_at(attrs, i0, i1, i2, w0, w1, w2, u, v, dudx, dvdx, dudy, dvdy, s, maps,
                       texels, levels, textures, filter_, bump, surf, lights, ambient, eye,
                       halfway)


@njit(cache=True, _nrt=False)
def textured_at(attrs, i0, i1, i2, w0, w1, w2, u, v, dudx, dvdx, dudy, dvdy, s, maps,
                texels, levels, textures, filter_, bump, surf, lights, ambient, eye, halfway):
    """The textured colour at barycentrics ``(w0, w1, w2)`` of corners ``i0, i1, i2`` with
    texture coordinates ``(u, v)`` and their derivatives per pixel — from the z-buffer's
    plane constants or from a ray's differentials (:mod:`core.raytrace.whitted`)."""
    nx, ny, nz, _ = unit3(_lerp(attrs, NORMAL, i0, i1, i2, w0, w1, w2),
                          _lerp(attrs, NORMAL + 1, i0, i1, i2, w0, w1, w2),
                          _lerp(attrs, NORMAL + 2, i0, i1, i2, w0, w1, w2))
    px = _lerp(attrs, POSITION, i0, i1, i2, w0, w1, w2)
    py = _lerp(attrs, POSITION + 1, i0, i1, i2, w0, w1, w2)
    pz = _lerp(attrs, POSITION + 2, i0, i1, i2, w0, w1, w2)
    if bump and (maps[s, HEIGHT] >= 0 or maps[s, NORMAL_MAP] >= 0):
        pux = _lerp(attrs, DPDU, i0, i1, i2, w0, w1, w2)
        puy = _lerp(attrs, DPDU + 1, i0, i1, i2, w0, w1, w2)
        puz = _lerp(attrs, DPDU + 2, i0, i1, i2, w0, w1, w2)
        pvx = _lerp(attrs, DPDV, i0, i1, i2, w0, w1, w2)
        pvy = _lerp(attrs, DPDV + 1, i0, i1, i2, w0, w1, w2)
        pvz = _lerp(attrs, DPDV + 2, i0, i1, i2, w0, w1, w2)
        if maps[s, HEIGHT] >= 0:
            nx, ny, nz = bumped_normal(nx, ny, nz, pux, puy, puz, pvx, pvy, pvz, texels,
                                       levels, textures, int(maps[s, HEIGHT]),
                                       maps[s, BUMP_SCALE], filter_, u, v, dudx, dvdx, dudy,
                                       dvdy)
        else:
            nx, ny, nz = mapped_normal(nx, ny, nz, pux, puy, puz, pvx, pvy, pvz, texels,
                                       levels, textures, int(maps[s, NORMAL_MAP]), filter_,
                                       u, v, dudx, dvdx, dudy, dvdy)
    if maps[s, COLOR] >= 0:
        r, g, b, _ = lookup(texels, levels, textures, int(maps[s, COLOR]), filter_, u, v,
                             dudx, dvdx, dudy, dvdy)
        if maps[s, COLOR_SRGB] > 0.5:
            r, g, b = encode_srgb(r), encode_srgb(g), encode_srgb(b)
        surf[s, OD], surf[s, OD + 1], surf[s, OD + 2] = r, g, b
    r, g, b = light_point(px, py, pz, nx, ny, nz, s, surf, lights, ambient, eye, halfway)
    if maps[s, ENVIRONMENT] >= 0 and maps[s, REFLECTIVITY] > 0.0:
        vx, vy, vz = view_direction(eye, px, py, pz)
        d = nx * vx + ny * vy + nz * vz
        if d < 0.0 and surf[s, TWO_SIDED] != 0.0:      # the side the viewer sees
            nx, ny, nz, d = -nx, -ny, -nz, -d
        er, eg, eb = environment(texels, levels, textures, int(maps[s, ENVIRONMENT]),
                                 2 * d * nx - vx, 2 * d * ny - vy, 2 * d * nz - vz)
        k = maps[s, REFLECTIVITY]
        r = (1 - k) * r + k * encode_srgb(er)
        g = (1 - k) * g + k * encode_srgb(eg)
        b = (1 - k) * b + k * encode_srgb(eb)
    return r, g, b
