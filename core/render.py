"""The renderer: assembles the stages a scene needs, in pipeline order, and runs them.

``render(scene, view_index, projection, shading, size) -> Frame``. The stages are those of
:func:`core.plan.plan`; what actually ran, what was allocated and how long each stage took go
into ``Frame.stats``. Nothing here touches GL: the frame is a numpy image, top row first.

Per-scene work that does not depend on the view (edge lists, concatenated triangle arrays,
normals) is computed once and kept in a cache keyed by the mesh object.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass, field

import numpy as np

from core.pipeline import clip
from core.pipeline import project
from core.pipeline import raster_lines
from core.plan import Stage, plan
from core.scene.model import Scene
from core.transforms import apply
from core.camera.view import ViewError, normalizing_transform, problems


@dataclass
class Frame:
    """One rendered picture: ``color`` is ``(H, W, 3)`` uint8, row 0 at the top.

    ``color`` is a view of ``rgbx``, ``(H, W, 4)``: the same pixels with one padding byte each
    (undefined, never read), so that showing the frame is one aligned copy into an RGBA
    texture (on llvmpipe 0.05 ms against 0.56 ms for packed RGB at 500 x 500).
    """

    rgbx: np.ndarray
    plan: list[Stage]
    message: str | None = None
    stats: dict = field(default_factory=dict)

    @property
    def color(self) -> np.ndarray:
        return self.rgbx[:, :, :3]


def to_rgb8(color) -> np.ndarray:
    """A colour in [0, 1] → uint8, rounded half up."""
    return np.floor(np.clip(np.asarray(color, dtype=np.float64), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


_edges_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _edges(mesh) -> np.ndarray:
    if mesh not in _edges_cache:
        _edges_cache[mesh] = mesh.all_edges()
    return _edges_cache[mesh]


class _Timer:
    """Collects per-stage wall times (ms) into a stats dict, and hands each stage's arrays to
    an ``inspect(stage, arrays)`` callback when one is given (the stability suite checks every
    intermediate array that way, on the real path)."""

    def __init__(self, stats: dict, inspect=None):
        self.times = stats.setdefault("ms", {})
        self.inspect = inspect
        self.t = time.perf_counter()

    def lap(self, stage: str, **arrays) -> None:
        now = time.perf_counter()
        self.times[stage] = self.times.get(stage, 0.0) + (now - self.t) * 1e3
        if self.inspect is not None and arrays:
            self.inspect(stage, arrays)
        self.t = time.perf_counter()


def render(scene: Scene, view_index: int, projection: str | None = None,
           shading: str | None = None, size: tuple[int, int] | None = None,
           inspect=None) -> Frame:
    """Render view ``view_index`` (0-based) of ``scene``.

    ``inspect(stage, arrays)``, when given, is called after each stage of the triangle path
    with the arrays it produced (named as in ``core/renderers/zbuffer.py``).

    An invalid view, a scene without views, or a zero-sized framebuffer gives a frame of the
    background colour with ``message`` saying why; it never raises for bad scene data.
    """
    projection = projection or scene.projection
    shading = shading or scene.shading
    width, height = size or scene.size
    stages = plan(scene, projection, shading)
    frame = Frame(rgbx=np.empty((max(height, 0), max(width, 0), 4), dtype=np.uint8), plan=stages,
                  stats={"allocated": ["color"], "computed": [], "projection": projection,
                         "shading": shading})
    color, stats = frame.color, frame.stats
    solid = shading != "wireframe" and scene.triangle_count > 0
    if not solid:
        fill(color, scene.background)          # the solid path's resolve writes every pixel
    if not scene.views:
        frame.message = f"{scene.name}: no valid view to show"
        return _blank(frame, scene, filled=not solid)
    view = scene.views[view_index % len(scene.views)]
    try:
        n, z_min = normalizing_transform(view, projection)
    except ViewError:
        frame.message = (f"{view.label}: invalid for {projection} projection: "
                         + "; ".join(problems(view, projection)))
        return _blank(frame, scene, filled=not solid)
    if width <= 0 or height <= 0:
        frame.message = f"the framebuffer is {width} x {height}: nothing to draw"
        return frame

    timer = _Timer(stats, inspect)
    vp = project.viewport(view.window, width, height)
    timer.lap("normalize")
    if solid:
        from core.renderers.zbuffer import render_solid     # the triangle pipeline (numba kernels)
        render_solid(frame, scene, view, projection, shading, n, z_min, vp, timer)
    line_meshes = [m for m in scene.meshes if shading == "wireframe" or not len(m.triangles)]
    if line_meshes:
        _render_lines(color, line_meshes, projection, n, z_min, vp, scene.line_color, timer, stats)
    return frame


def fill(color: np.ndarray, rgb) -> None:
    """Fill an (H, W, 3) image with one colour: one row, then whole rows (a length-3 inner
    broadcast over every pixel costs ~100x more)."""
    if color.size:
        color[0] = to_rgb8(rgb)
        color[1:] = color[0]


def _blank(frame: Frame, scene: Scene, filled: bool) -> Frame:
    if not filled:
        fill(frame.color, scene.background)
    return frame


def _render_lines(color, meshes, projection, n, z_min, vp, line_color, timer, stats) -> None:
    """Wireframe: transform, Cohen–Sutherland clip, M_per · M_vv3dv, divide, scan-convert."""
    drawn = 0
    for mesh in meshes:
        edges = _edges(mesh)
        if len(edges) == 0:
            continue
        points = apply(n, mesh.positions)[:, :3]
        timer.lap("normalize")
        q0, q1 = clip.clip_lines(points[edges[:, 0]], points[edges[:, 1]], projection, z_min)
        timer.lap("clip lines")
        d0 = project.project_lines(q0, projection, vp)
        d1 = project.project_lines(q1, projection, vp)
        timer.lap("project")
        raster_lines.draw_lines(color, d0, d1, to_rgb8(line_color))
        timer.lap("scan-convert lines")
        drawn += len(q0)
    stats["segments drawn"] = drawn
    stats["computed"].append("line clipping")
