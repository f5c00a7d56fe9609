"""``python -m app warmup``: compile every kernel once, saying how far along it is.

numba compiles a kernel the first time it runs with given argument types and keeps the machine
code on disk (``cache=True``); later processes load it in a fraction of a second. Without this
step the first frame of each shading mode would compile in front of the user (seconds each).
``make`` runs it when it creates ``.venv``; the window runs the same steps in the background
after its first frame, so that switching modes later loads cached kernels off the UI thread.

:func:`steps` lists one small render per path through the renderers: every shading mode, both
projections and both rasterizers, a closed mesh large enough for the parallel set-up (back-face
culling, ≥ 10 000 triangles), an open one (two-sided lighting), lines, and several samples a
pixel. :func:`scene_steps` then opens every shipped scene (``scenes/``) the way the window
does (:class:`app.viewer.state.ViewerState`), in every renderer and shading, and in every
texture filter when it has textures, so that no first picture the user asks for compiles
(issue 21; ``tests/test_warmup_complete.py`` checks it from an empty kernel cache).
"""

from __future__ import annotations

import sys
import time
from typing import Callable

SIZE = (64, 48)


def _scenes():
    """A closed sphere of 12 288 triangles, the same sphere open, and the house (lines); and
    a closed sphere of 50 688, culled on all cores."""
    import dataclasses

    from core.camera.view import View
    from core.scene.generators import house, uv_sphere
    from core.scene.model import Scene

    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1.5, 1.5, -1.5, 1.5),
                prp=(0, 0, 5), front=2, back=-2, label="warm-up view")
    sphere = uv_sphere(1.0, segments=128, rings=48)
    closed = Scene(name="warm-up sphere", meshes=[dataclasses.replace(sphere, closed=True)],
                   views=[view])
    opened = Scene(name="warm-up open sphere", meshes=[dataclasses.replace(sphere, closed=False),
                                                       house()], views=[view])
    large = Scene(name="warm-up large sphere", views=[view], meshes=[
        dataclasses.replace(uv_sphere(1.0, segments=256, rings=100), closed=True)])
    return closed, opened, large


def _batched_frame():
    """The paths of very large frames: the rasterizer's two batches, the second set up
    against the first's coarse z (21 stacked layers of 10k triangles), and the clipper's
    classification on all cores."""
    import numpy as np

    from app.tools.depth_bench import depth_layers
    from core.pipeline import clip_polygon, raster
    xy_z, inv_w, triangles = depth_layers(21, 10_000, *SIZE)   # (either order: same code)
    assert len(triangles) >= raster.BATCH_FROM
    raster.rasterize(xy_z, inv_w, triangles, *SIZE)
    inside = np.full((clip_polygon.PARALLEL_POINTS, 3), -0.5)
    clip_polygon.clip_triangles(inside, np.zeros((1, 3), np.int64), None, "parallel")


def steps() -> list[tuple[str, Callable[[], object]]]:
    """(label, run) for every path the window can take; each ``run`` renders one small frame."""
    from core.render import render
    from core.scene.model import Scene
    from core.settings import RASTERIZERS, SHADINGS, RenderSettings

    import dataclasses

    closed, opened, large = _scenes()
    out = []

    def add(label, scene, **settings):
        s = RenderSettings.for_scene(scene, size=SIZE, **settings)
        out.append((label, lambda: render(scene, scene.views[0], s)))

    for projection in ("perspective", "parallel"):
        add(f"wireframe, {projection}", opened, shading="wireframe", projection=projection)
        for shading in SHADINGS[1:]:
            for rasterizer in RASTERIZERS:
                add(f"{shading}, {projection}, {rasterizer} rasterizer", closed,
                    shading=shading, projection=projection, rasterizer=rasterizer)
            add(f"{shading}, {projection}, open mesh and lines", opened, shading=shading,
                projection=projection)
    add("flat, 4 samples a pixel", closed, shading="flat", samples=4)
    add("phong, the float64 pixel kernel", opened, shading="phong", shading_precision="float64")
    add("flat, 50k faces culled on all cores", large, shading="flat")
    out.append(("a large frame in two batches (early z)", _batched_frame))
    add("ray traced (Whitted)", closed, shading="phong", renderer="raytrace")
    # The painters on a small closed mesh: the same kernels, and the window's background
    # warm-up never holds a frame for a tree of 12k triangles (1.8 s).
    from core.scene.generators import uv_sphere
    small = Scene(name="warm-up small sphere", views=closed.views, meshes=[
        dataclasses.replace(uv_sphere(1.0, segments=24, rings=12), closed=True)])
    add("BSP tree (painter's)", small, shading="flat", renderer="bsp")
    add("depth sort (painter's), depth-cued", small, shading="gouraud", renderer="depth-sort",
        depth_cue=True)
    # hemicube and ray-cast form factors, the solver, the display; the path tracer
    from core.scene.generators import cube
    box = Scene(name="warm-up box", meshes=[cube(1.0)], views=closed.views)
    for method in ("hemicube", "raycast"):
        add(f"radiosity ({method})", box, renderer="radiosity", form_factors=method,
            max_elements=64, hemicube_resolution=16)
    add("path traced", box, renderer="pathtrace")
    return out


def shipped_scenes() -> list:
    """The scene files in ``scenes/`` that the window opens (not the ``.views`` lists)."""
    from core.paths import ROOT
    from core.scene.formats import MESH_EXTENSIONS
    kinds = {".toml", ".tri", *MESH_EXTENSIONS}
    return sorted(p for p in (ROOT / "scenes").iterdir() if p.suffix.lower() in kinds)


def scene_jobs(path, size=SIZE):
    """(label, run) for the first picture of scene file ``path`` in every renderer, shading
    and (when it has textures) texture filter, each made as the window makes it."""
    from app.viewer.state import ViewerState
    from core.renderers import renderer_names
    from core.settings import SHADINGS
    from core.texture.modes import FILTERS

    state = ViewerState.open(path, size=size)
    window_settings = state.settings
    # Fewer elements, a coarser hemicube, an early stop and one sample a pixel change no
    # kernel's argument types, only how long each solve runs: the same kernels compile.
    state.settings = lambda: quick(window_settings())
    filters = tuple(FILTERS) if state.has_textures else (state.texture_filter,)
    jobs = []
    for renderer in renderer_names():
        for shading in SHADINGS:
            for filter_ in filters:
                state.set_renderer(renderer)
                state.set_shading(shading)
                state.set_texture_filter(filter_)
                run, _ = state._job()
                jobs.append((f"{path.name}: {renderer}, {shading}, {filter_}", run))
    return jobs


QUICK = {"radiosity": {"hemicube_resolution": 16, "max_elements": 64, "converge": 0.5},
         "pathtrace": {"samples": 1}}


def quick(settings):
    """``settings`` with the global-illumination renderers' work cut to a token amount."""
    return settings.replace(**QUICK.get(settings.renderer, {}))


def scene_steps() -> list[tuple[str, Callable[[], object]]]:
    """One step per shipped scene: its first pictures in every renderer, shading, filter."""
    def opener(path):
        def run():
            for _, job in scene_jobs(path):
                job()
        return run
    return [(f"{path.name}, every renderer, shading and filter", opener(path))
            for path in shipped_scenes()]


def run(progress: Callable[[int, int, str, float], None] | None = None) -> float:
    """Run every step; ``progress(k, n, label, seconds)`` after each. Returns the total."""
    todo = steps() + scene_steps()
    start = time.perf_counter()
    for k, (label, job) in enumerate(todo, start=1):
        t = time.perf_counter()
        job()
        if progress is not None:
            progress(k, len(todo), label, time.perf_counter() - t)
    return time.perf_counter() - start


def compile_bytecode() -> bool:
    """Write the ``.pyc`` of ``app`` and ``core`` now: a process started with
    PYTHONDONTWRITEBYTECODE (or from a read-only checkout) would otherwise compile every
    module from source at each start, about 0.1 s before the first picture."""
    import compileall
    from core.paths import ROOT
    return all(compileall.compile_dir(ROOT / package, quiet=2) for package in ("app", "core"))


def main(args=None) -> int:
    print("warming up: compiling the kernels once (numba keeps them on disk)", flush=True)
    if not compile_bytecode():
        print("  (some Python bytecode could not be written: starts will compile it)",
              flush=True)

    def say(k, n, label, seconds):
        print(f"  [{k:2d}/{n}] {label}: {seconds:.2f} s", flush=True)

    total = run(say)
    print(f"warm: {total:.1f} s in all; later starts load the compiled kernels", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
