"""The keyed paths, for inspection: where the camera's eye, each keyed object and each keyed
light go over the animation, drawn as polylines over a frame (seen from a still view, they
show the in-betweening: Catmull–Rom against linear, the arc-length option, overshoot).

``paths_of(animation)`` samples every position channel; ``draw_paths(frame, paths, view,
settings)`` draws them with the wireframe stages (N_per/N_par, Cohen–Sutherland, M_vv3dv, the
midpoint line) as an overlay: not depth-tested, so a path behind a wall still shows.
"""

from __future__ import annotations

import numpy as np

from core.camera.view import normalizing_transform, vrc_basis
from core.pipeline import clip, project, raster_lines
from core.transforms import apply

SAMPLES_PER_SECOND = 60


def eye_of(view) -> np.ndarray:
    """The centre of projection in world coordinates: the PRP, given in the VRC, from the VRP."""
    u, v, n = vrc_basis(view)
    prp = np.asarray(view.prp, dtype=np.float64)
    return np.asarray(view.vrp, dtype=np.float64) + prp[0] * u + prp[1] * v + prp[2] * n


def paths_of(animation, samples_per_second: float = SAMPLES_PER_SECOND) -> dict[str, np.ndarray]:
    """channel → (S, 3) world points from time 0 to the end: ``view.eye``,
    ``object.NAME.translate`` (the object's keyed offset), ``light.N.position``."""
    count = max(2, int(np.ceil(animation.duration * samples_per_second)) + 1)
    times = np.linspace(0.0, animation.duration, count)
    out = {}
    if animation.view is not None:
        out["view.eye"] = np.array([eye_of(animation.view.at(t, "path")) for t in times])
    names = [m.name for m in animation.scene.meshes]
    for index, tracks in animation.objects.items():
        if tracks.translate is not None:
            out[f"object.{names[index]}.translate"] = np.array([tracks.translate(t) for t in times])
    for index, track in animation.lights.items():
        out[f"light.{index + 1}.position"] = np.array([track(t) for t in times])
    return out


def draw_paths(frame, paths: dict[str, np.ndarray], view, settings, color=(1.0, 0.85, 0.2)) -> int:
    """Draw every path as a polyline over ``frame.color``; returns the segments drawn."""
    projection = settings.projection
    height, width = frame.color.shape[:2]
    n, z_min = normalizing_transform(view, projection)
    vp = project.viewport(view.window, width, height, settings.keep_aspect)
    rgb = np.floor(np.clip(np.asarray(color, dtype=np.float64), 0, 1) * 255 + 0.5).astype(np.uint8)
    drawn = 0
    for points in paths.values():
        canonical = apply(n, points)
        canonical = canonical[:, :3] / canonical[:, 3:4]
        q0, q1 = clip.clip_lines(canonical[:-1], canonical[1:], projection, z_min)
        if len(q0):
            raster_lines.draw_lines(frame.color, project.project_lines(q0, projection, vp),
                                    project.project_lines(q1, projection, vp), rgb)
        drawn += len(q0)
    return drawn
