"""The volume renderer's pixel record (the inspector's contract: ``renderer``, ``pixel`` and
``color`` as ``render`` writes it), built from the same pieces the renderer uses:

- ``opaque``: the z-buffer's own record of the pixel (the surface the ray stops at, or the
  background); when that surface is an isosurface, ``isosurface cell`` names the marching
  cube the point lies in and its eight corner values (corner c = x + 2y + 4z);
- ``ray``: its origin, direction, interval between the view's planes and where the opaque
  surface stops it;
- ``volumes``: for each marched volume, farthest first, where the ray enters and leaves its
  grid, the number of samples, the light it emits and lets through, and for MIP the largest
  sample with where it lies: its cell and that cell's corner values.

One sample a pixel only (the record of a supersampled pixel would be a list of these).
"""

from __future__ import annotations

import math

import numpy as np

from core.camera.rays import camera_rays
from core.camera.view import eye_from_view
from core.context import DEFAULT_CONTEXT
from core.shading.illumination import pack_ambient, pack_eye, pack_lights, to_uint8
from core.volume.data import volumes_of
from core.volume.raymarch import march_volume
from core.renderers.volume.draw import farthest_first, step_of


def cell_of(volume, world) -> dict:
    """The marching cube holding world point ``world``: its index and corner values."""
    m_inv = np.linalg.inv(volume.world_from_index())
    p = m_inv[:3, :3] @ np.asarray(world, dtype=np.float64) + m_inv[:3, 3]
    top = np.array(volume.dims) - 2
    i, j, k = (int(c) for c in np.clip(np.floor(p), 0, top))
    corners = [float(volume.values[i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)])
               for c in range(8)]
    return {"volume": volume.name, "cell": [i, j, k], "index point": [float(c) for c in p],
            "corner values": corners, "iso": volume.iso}


def ray_samples(volume, origin, direction, t_lo, t_hi, step) -> np.ndarray:
    """The t of each sample the marcher takes along one ray (segment midpoints; see
    :mod:`core.volume.raymarch`), empty where the ray misses the grid."""
    m_inv = np.linalg.inv(volume.world_from_index())
    o, d = m_inv[:3, :3] @ origin + m_inv[:3, 3], m_inv[:3, :3] @ direction
    t0, t1 = t_lo, t_hi
    for a in range(3):
        hi = volume.dims[a] - 1.0
        if d[a] == 0.0:
            if not 0.0 <= o[a] <= hi:
                return np.zeros(0)
            continue
        ta, tb = -o[a] / d[a], (hi - o[a]) / d[a]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    if not t0 < t1:
        return np.zeros(0)
    starts = t0 + step * np.arange(int((t1 - t0) // step) + 1)
    starts = starts[starts < t1]
    return starts + 0.5 * np.minimum(step, t1 - starts)


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The record of image pixel (x, y) (see the module): the opaque surface's z-buffer
    record, the ray, and what each volume did along it."""
    from core.renderers.zbuffer.inspect import inspect_pixel as zbuffer_inspect
    context = context or DEFAULT_CONTEXT
    if settings.samples > 1:
        raise ValueError("the volume renderer's inspector reads one sample a pixel; "
                         "inspect the frame drawn with 1 sample a pixel")
    width, height = settings.size
    opaque = (zbuffer_inspect(scene, view, settings, x, y, context) if scene.meshes
              else {"layer": "background", "color": to_uint8(scene.background).tolist()})
    o, d, t_lo, t_hi = camera_rays(view, settings.projection, width, height,
                                   (settings.pixel_offset,), settings.keep_aspect,
                                   rows=(y, y + 1), cols=(x, x + 1))
    world = opaque.get("depth", {}).get("world point")
    t_stop = (float(((np.asarray(world) - o[0]) * d[0]).sum()) if world is not None
              else math.inf)
    record = {"renderer": "volume", "pixel": [int(x), int(y)], "opaque": opaque,
              "ray": {"origin": o[0].tolist(), "direction": d[0].tolist(),
                      "between the planes": [float(t_lo[0]), float(t_hi[0])],
                      "stopped by the opaque surface at t": t_stop}}
    for volume in volumes_of(scene):
        if volume.mode == "isosurface" and opaque.get("mesh name") == volume.name:
            record["isosurface cell"] = cell_of(volume, world)
    hi = np.minimum(t_hi, t_stop)
    eye = eye_from_view(view, settings.projection)
    behind = np.asarray(opaque["color"], dtype=np.float64) / 255.0
    marched = []
    for volume in farthest_first([v for v in volumes_of(scene) if v.mode != "isosurface"], eye):
        step = step_of(volume)
        color, through, largest = march_volume(volume, o, d, t_lo, hi, step,
                                               pack_lights(scene.lights),
                                               pack_ambient(scene.ambient), pack_eye(eye),
                                               scene.specular == "halfway",
                                               settings.lighting_model)
        ts = ray_samples(volume, o[0], d[0], float(t_lo[0]), float(hi[0]), step)
        entry = {"volume": volume.name, "mode": volume.mode, "samples": int(len(ts)),
                 "enters at t": float(ts[0] - 0.5 * step) if len(ts) else None,
                 "leaves at t": float(min(ts[-1] + 0.5 * step, hi[0])) if len(ts) else None}
        if volume.mode == "mip":
            lo, top = volume.mip_window()
            grey = (float(np.clip((largest[0] - lo) / max(top - lo, 1e-30), 0, 1))
                    if np.isfinite(largest[0]) else 0.0)
            entry.update({"largest sample": float(largest[0]), "grey": grey})
            if len(ts):
                at = _largest_at(volume, o[0], d[0], ts)
                entry.update({"at t": float(at), "at": cell_of(volume, o[0] + at * d[0])})
            behind = grey + (1.0 - grey) * behind
        else:
            entry.update({"emitted": color[0].tolist(), "transmittance": float(through[0])})
            behind = color[0] + through[0] * behind
        marched.append(entry)
    record["volumes"] = marched
    record["color"] = to_uint8(behind).tolist()
    return record


def _largest_at(volume, origin, direction, ts) -> float:
    """The t of the largest trilinear sample among ``ts`` (the first of equals)."""
    m_inv = np.linalg.inv(volume.world_from_index())
    o, d = m_inv[:3, :3] @ origin + m_inv[:3, 3], m_inv[:3, :3] @ direction
    return float(ts[int(np.argmax(trilinear(volume.values, o + ts[:, None] * d)))])


def trilinear(v, points) -> np.ndarray:
    """The kernels' trilinear rule in numpy, at index points ``(N, 3)`` inside the grid."""
    top = np.array(v.shape) - 2
    base = np.minimum(np.floor(points).astype(np.int64), top)
    f = points - base
    out = np.zeros(len(points))
    for c in range(8):
        bits = np.array([c & 1, c >> 1 & 1, c >> 2 & 1])
        weight = np.prod(np.where(bits, f, 1.0 - f), axis=1)
        i, j, k = (base + bits).T
        out += weight * v[i, j, k]
    return out
