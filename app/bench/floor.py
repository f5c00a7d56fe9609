"""The bench's floor: the least a numba rasterizer can do for the same picture.

Same scene, same view, same 500 x 500, but nothing the course pipeline adds: no clipping (the
bench scene lies inside the view volume), no visibility buffer, no deferred shading, one light
(the scene's first), Gouraud only, colours interpolated linearly in screen space, float32
buffers. Per frame:

1. one compiled pass over every vertex (all cores): world → device with the single matrix
   ``L · M · N`` of the GL oracle (:func:`app.oracles.reference_gl.clip_from_world`), the divide
   by W, and the one-light model (diffuse + (R·V)^n by repeated squaring) → an RGB per vertex;
2. clear colour and depth;
3. the triangles in order on one core (a bare loop: no setup pass, no binning), back faces
   of closed meshes culled by their screen winding, scan-converted by edge functions
   stepped pixel by pixel over their bounding boxes (leaving a row once past the triangle)
   with a depth test, the colour written as one 32-bit word per pixel.

It is what "close to what the hardware allows" is measured against: our pipeline within 1.5x
of it at 100k and 1M triangles. Used only by ``python -m app bench``.
"""

from __future__ import annotations

import numpy as np
from core.jit import njit, prange


@njit(cache=True, parallel=True)
def _vertices(positions, normals, m, light, light_is_point, intensity, material, eye, out_xyz,
              out_rgb):
    """Device x, y, depth and the one-light colour of every vertex."""
    ka, kd, ks, n = material[0], material[1], material[2], material[3]
    for i in prange(positions.shape[0]):
        x, y, z = positions[i, 0], positions[i, 1], positions[i, 2]
        w = m[3, 0] * x + m[3, 1] * y + m[3, 2] * z + m[3, 3]
        iw = 1.0 / w if w > 0.0 else 0.0
        for r in range(3):
            out_xyz[i, r] = (m[r, 0] * x + m[r, 1] * y + m[r, 2] * z + m[r, 3]) * iw
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        if light_is_point:
            lx, ly, lz = light[0] - x, light[1] - y, light[2] - z
        else:
            lx, ly, lz = light[0], light[1], light[2]
        inv = 1.0 / np.sqrt(lx * lx + ly * ly + lz * lz)
        lx, ly, lz = lx * inv, ly * inv, lz * inv
        vx, vy, vz = eye[0] - x, eye[1] - y, eye[2] - z
        inv = 1.0 / np.sqrt(vx * vx + vy * vy + vz * vz)
        vx, vy, vz = vx * inv, vy * inv, vz * inv
        n_dot_l = nx * lx + ny * ly + nz * lz
        diffuse = max(n_dot_l, 0.0)
        spec = 0.0
        if n_dot_l > 0.0:
            base = (2.0 * n_dot_l * nx - lx) * vx + (2.0 * n_dot_l * ny - ly) * vy \
                + (2.0 * n_dot_l * nz - lz) * vz
            base = min(max(base, 0.0), 1.0)
            k = int(n)
            spec = 1.0
            while k > 0:
                if k & 1:
                    spec *= base
                base *= base
                k >>= 1
        for c in range(3):
            v = ka * material[4 + c] * 0.15 + intensity[c] * (kd * material[4 + c] * diffuse
                                                              + ks * material[7 + c] * spec)
            out_rgb[i, c] = min(max(v, 0.0), 1.0) * 255.0


@njit(cache=True)
def _triangle(xyz, rgb, v0, v1, v2, cull, row_first, row_last, depth, color):
    """One triangle into device rows row_first..row_last: edge functions stepped per pixel."""
    height, width = depth.shape
    x0, y0, x1, y1, x2, y2 = xyz[v0, 0], xyz[v0, 1], xyz[v1, 0], xyz[v1, 1], xyz[v2, 0], xyz[v2, 1]
    j_min = max(int(np.ceil(min(y0, y1, y2) - 0.5)), row_first)
    j_max = min(int(np.floor(max(y0, y1, y2) - 0.5)), row_last)
    if j_min > j_max:
        return
    i_min = max(int(np.ceil(min(x0, x1, x2) - 0.5)), 0)
    i_max = min(int(np.floor(max(x0, x1, x2) - 0.5)), width - 1)
    if i_min > i_max:
        return
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    if area == 0.0 or (cull and area < 0.0):
        return
    inv_area = 1.0 / area
    # l0, l1 are affine in the pixel centre: their steps one pixel right and one row up
    dl0_dx, dl0_dy = (y1 - y2) * inv_area, (x2 - x1) * inv_area
    dl1_dx, dl1_dy = (y2 - y0) * inv_area, (x0 - x2) * inv_area
    px, py = i_min + 0.5, j_min + 0.5
    l0_row = ((x1 - px) * (y2 - py) - (x2 - px) * (y1 - py)) * inv_area
    l1_row = ((x2 - px) * (y0 - py) - (x0 - px) * (y2 - py)) * inv_area
    z0, z1, z2 = xyz[v0, 2], xyz[v1, 2], xyz[v2, 2]
    for j in range(j_min, j_max + 1):
        row = height - 1 - j
        l0, l1 = l0_row, l1_row
        entered = False
        for i in range(i_min, i_max + 1):
            l2 = 1.0 - l0 - l1
            if l0 >= 0.0 and l1 >= 0.0 and l2 >= 0.0:
                entered = True
                z = l0 * z0 + l1 * z1 + l2 * z2
                if z > depth[row, i]:
                    depth[row, i] = z
                    r = l0 * rgb[v0, 0] + l1 * rgb[v1, 0] + l2 * rgb[v2, 0]
                    g = l0 * rgb[v0, 1] + l1 * rgb[v1, 1] + l2 * rgb[v2, 1]
                    b = l0 * rgb[v0, 2] + l1 * rgb[v1, 2] + l2 * rgb[v2, 2]
                    color[row, i] = (np.uint32(r + 0.5) | (np.uint32(g + 0.5) << 8)
                                     | (np.uint32(b + 0.5) << 16) | np.uint32(0xFF000000))
            elif entered:
                break                      # convex: the row has left the triangle
            l0 += dl0_dx
            l1 += dl1_dx
        l0_row += dl0_dy
        l1_row += dl1_dy


@njit(cache=True)
def _draw(xyz, rgb, triangles, closed, background, depth, color):
    """Clear, then every triangle in order on one core. (A band of rows per core made each
    core read and set up every triangle: slower at 100k triangles, where setup dominates.)"""
    height = depth.shape[0]
    for row in range(height):
        for i in range(depth.shape[1]):
            depth[row, i] = -np.float32(np.inf)
            color[row, i] = background
    for t in range(triangles.shape[0]):
        _triangle(xyz, rgb, triangles[t, 0], triangles[t, 1], triangles[t, 2], closed[t], 0,
                  height - 1, depth, color)


class Floor:
    """The bare rasterizer, set up once per scene; :meth:`frame` draws one frame."""

    def __init__(self, scene, size=(500, 500)):
        from core.scene.normals import vertex_normals
        meshes = [m for m in scene.meshes if len(m.triangles)]
        offsets = np.cumsum([0] + [len(m.positions) for m in meshes])
        self.positions = np.concatenate([m.positions for m in meshes]).astype(np.float64)
        self.normals = np.concatenate([vertex_normals(m) for m in meshes]).astype(np.float64)
        self.triangles = np.concatenate([m.triangles + o for m, o in zip(meshes, offsets)])
        self.closed = np.concatenate([np.full(len(m.triangles), m.closed) for m in meshes])
        light = scene.lights[0]
        self.light_is_point = light.position is not None
        where = light.position if self.light_is_point else light.direction
        self.light = np.asarray(where, np.float64)
        if not self.light_is_point:
            self.light = self.light / np.linalg.norm(self.light)
        self.intensity = np.asarray(light.intensity, np.float64)
        mat = meshes[0].material
        self.material = np.array([mat.ka, mat.kd, mat.ks, mat.n, *mat.od, *mat.os], np.float64)
        self.background = np.array([*(np.floor(np.clip(scene.background, 0, 1) * 255 + 0.5)),
                                    255], np.uint8).view(np.uint32)[0]
        self.size = size
        width, height = size
        self.depth = np.empty((height, width), np.float32)
        self.color = np.empty((height, width), np.uint32)
        self.xyz = np.empty((len(self.positions), 3), np.float64)
        self.rgb = np.empty((len(self.positions), 3), np.float32)

    def frame(self, view) -> np.ndarray:
        """One frame of ``view``: ``(H, W)`` uint32 RGBA words, row 0 at the top."""
        from app.oracles.reference_gl import clip_from_world
        from core.camera.view import eye_from_view
        width, height = self.size
        # GL clip space → device pixels with depth larger = nearer, as the z-buffer keeps it
        to_device = np.array([[width / 2, 0, 0, width / 2], [0, height / 2, 0, height / 2],
                              [0, 0, -0.5, -0.5], [0, 0, 0, 1.0]])
        m = to_device @ clip_from_world(view, "perspective", self.size)
        eye = np.asarray(eye_from_view(view, "perspective").point, np.float64)
        _vertices(self.positions, self.normals, m, self.light, self.light_is_point,
                  self.intensity, self.material, eye, self.xyz, self.rgb)
        _draw(self.xyz, self.rgb, self.triangles, self.closed, self.background, self.depth,
              self.color)
        return self.color
