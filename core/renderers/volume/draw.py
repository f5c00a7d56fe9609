"""``--renderer volume``: the scene's opaque geometry by the z-buffer, then its volumes by
ray marching, each ray stopped at the depth of the opaque surface in its pixel.

``draw(scene, view, settings, frame, context, timer)`` (registered in :mod:`core.renderers`):

1. the meshes — isosurfaces among them, which are ordinary meshes — go through
   :func:`core.renderers.zbuffer.draw.draw` with the settings' shading; its depth buffer is kept;
2. the primary rays come from :func:`core.camera.rays.camera_rays` through the same sample
   of each pixel (``settings.pixel_offset``), limited to the view's front and back planes;
3. each pixel's z-buffer depth is carried back to the world point it came from (the inverse of
   ``M_vv3dv · M · N`` at the pixel centre), and the ray's interval ends there;
4. every emission–absorption or MIP volume is marched (:mod:`core.volume.raymarch`) and laid
   over what is behind it: ``C + T · behind`` (MIP: its grey ``g`` as emission with opacity
   ``g``). Several volumes are laid farthest first (by their centres' distance from the eye),
   which is exact while no ray passes through two at once.

``settings.volume_step`` is not a setting yet: the step is :data:`STEP` of the smallest voxel
side (world units), the default the exact-integral tests hold to 1/255, but never so short
that a ray across the box's diagonal takes more than :data:`MAX_STEPS` (a very anisotropic
spacing).
"""

from __future__ import annotations

import time

import numpy as np

from core.camera.film import fill, sample_viewport
from core.camera.rays import camera_rays
from core.camera.view import eye_from_view
from core.pipeline import project
from core.shading.illumination import pack_ambient, pack_eye, pack_lights, to_uint8
from core.volume.data import volumes_of
from core.volume.raymarch import march_volume
from core.work import next_chunk, report

STEP = 0.5                      # samples per voxel side: two
MAX_STEPS = 8192                # steps a ray may take across a volume's whole diagonal
FIRST_CHUNK = 1 << 14           # rays marched in the first call (the next sized by its time)


def draw(scene, view, settings, frame, context, timer) -> None:
    height, width = frame.color.shape[:2]
    if scene.meshes:
        from core.renderers.zbuffer.draw import draw as zbuffer
        zbuffer(scene, view, settings, frame, context, timer)
    else:
        fill(frame.color, scene.background)
    marched = [v for v in volumes_of(scene) if v.mode != "isosurface"]
    frame.stats["volumes marched"] = len(marched)
    if not marched:
        return
    origins, directions, t_lo, t_hi = camera_rays(view, settings.projection, width, height,
                                                  (settings.pixel_offset,),
                                                  settings.keep_aspect)
    if frame.depth is not None:
        t_hi = np.minimum(t_hi, opaque_distance(frame.depth, view, settings, context,
                                                origins, directions))
    timer.lap("volume rays")
    eye = eye_from_view(view, settings.projection)
    behind = frame.color.reshape(-1, 3).astype(np.float64) / 255.0
    for volume in farthest_first(marched, eye):
        color, transmittance, largest = march_in_chunks(
            volume, origins, directions, t_lo, t_hi, step_of(volume),
            pack_lights(scene.lights), pack_ambient(scene.ambient), pack_eye(eye),
            scene.specular == "halfway", settings.lighting_model)
        if volume.mode == "mip":
            lo, hi = volume.mip_window()
            grey = np.where(np.isfinite(largest),
                            np.clip((largest - lo) / max(hi - lo, 1e-30), 0.0, 1.0), 0.0)
            behind = grey[:, None] + (1.0 - grey[:, None]) * behind
        else:
            behind = color + transmittance[:, None] * behind
    frame.color[:] = to_uint8(behind).reshape(height, width, 3)
    frame.stats["computed"].append("ray marching")
    timer.lap("ray march")


def march_in_chunks(volume, origins, directions, t_lo, t_hi, *marching):
    """:func:`march_volume` over the rays a chunk at a time, each chunk sized to take about
    ``core.work.CHUNK_SECONDS`` and reported: a large frame shows its progress and stops on
    Ctrl+C or the window's cancel within a chunk. Each ray is marched alone, so the numbers
    are those of one call over every ray."""
    n = len(origins)
    color, transmittance, largest = np.empty((n, 3)), np.empty(n), np.empty(n)
    done, size = 0, FIRST_CHUNK
    report("ray marching", 0, n, "ray")
    while done < n:
        end = min(n, done + size)
        began = time.perf_counter()
        color[done:end], transmittance[done:end], largest[done:end] = march_volume(
            volume, origins[done:end], directions[done:end], t_lo[done:end], t_hi[done:end],
            *marching)
        size = next_chunk(end - done, time.perf_counter() - began)
        done = end
        report("ray marching", done, n, "ray")
    return color, transmittance, largest


def step_of(volume) -> float:
    """:data:`STEP` times the smallest world length of one sample step along an axis, but no
    shorter than the box's diagonal over :data:`MAX_STEPS`: a volume whose spacing is 10^6
    times longer along one axis than another would take 10^7 steps a ray at the short one."""
    m = volume.world_from_index()
    step = STEP * float(np.linalg.norm(m[:3, :3], axis=0).min())
    diagonal = float(np.linalg.norm(m[:3, :3] @ (np.array(volume.dims, np.float64) - 1.0)))
    return max(step, diagonal / MAX_STEPS)


def farthest_first(volumes, eye) -> list:
    def distance(volume):
        centre = volume.world_from_index() @ np.array([*(np.array(volume.dims) - 1) / 2, 1.0])
        if eye.point is not None:
            return -float(np.linalg.norm(centre[:3] - np.asarray(eye.point)))
        return float(np.dot(centre[:3], np.asarray(eye.direction)))   # towards the viewer
    return sorted(volumes, key=distance)


def opaque_distance(depth, view, settings, context, origins, directions) -> np.ndarray:
    """``(H·W,)``: how far along each ray the z-buffer's surface lies (inf where none)."""
    height, width = depth.shape
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                         settings.pixel_offset)
    inverse = np.linalg.inv(project.triangle_matrix(settings.projection, z_min, vp) @ n)
    flat = depth.reshape(-1)
    covered = np.isfinite(flat)
    rows, cols = np.divmod(np.nonzero(covered)[0], width)
    device = np.stack([cols + 0.5, (height - 1 - rows) + 0.5, flat[covered],
                       np.ones(len(rows))], axis=1)
    world = device @ inverse.T
    world = world[:, :3] / world[:, 3:4]
    t = np.full(len(flat), np.inf)
    t[covered] = ((world - origins[covered]) * directions[covered]).sum(1)
    return t
