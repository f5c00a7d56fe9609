"""The warm-up's steps: each ``(label, run)`` draws one small frame down a path the window can
take (every shading mode and rasterizer, each renderer's own frames from its registry entry,
the systems' kernels), or opens a shipped scene as the window opens it, so that its kernels
compile before the window needs them (:mod:`app.distribution.warmup` runs them).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from app.loading import shipped_scenes


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

    from core.pipeline.layers import depth_layers
    from core.pipeline import clip_polygon, raster
    xy_z, inv_w, triangles = depth_layers(21, 10_000, *SIZE)   # (either order: same code)
    assert len(triangles) >= raster.BATCH_FROM
    raster.rasterize(xy_z, inv_w, triangles, *SIZE)
    inside = np.full((clip_polygon.PARALLEL_POINTS, 3), -0.5)
    clip_polygon.clip_triangles(inside, np.zeros((1, 3), np.int64), None, "parallel")


_MOVERS = """
name = "warm-up movers"
[[geometry]]
primitive = "sphere"
name = "ball"
center = [0, 1, 0]
radius = 0.2
[[geometry]]
generator = "cube"
name = "box"
transform = { scale = [0.2, 0.2, 0.2], translate = [1, 1, 0] }
[[geometry]]
generator = "cube"
name = "arm"
transform = { scale = [0.5, 0.05, 0.05], translate = [0.5, 3, 0] }
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 6]
front = 3
back = -3
[animation]
duration = 1
[dynamics]
planes = [{ point = [0, 0, 0] }]
spheres = [{ center = [3, 0, 0], radius = 0.5 }]
[[body]]
mesh = "ball"
[[body]]
mesh = "box"
[[linkage]]
base = [0, 3, 0]
[[linkage.joint]]
bone = [1, 0, 0]
meshes = ["arm"]
[[linkage.joint]]
bone = [0.5, 0, 0]
[[linkage.key]]
time = 0
target = [0.8, 3.5, 0]
"""


def _movers():
    """The warm-up scene's rigid bodies and linkage (a first picture takes no step at t = 0)."""
    from core.animation.keys import animation_of
    from core.scene.formats import read_scene_file
    return animation_of(read_scene_file(_MOVERS, "warm-up movers.toml")).movers


def _rigid_bodies():
    """The rigid bodies' step: collisions with the plane, the sphere and each other."""
    world, _ = _movers()
    world.state_at(0.1)


def _linkages():
    """The linkages' kinematics with both inverse-kinematics solvers."""
    import numpy as np

    from core.animation import linkage
    _, arm = _movers()
    for solver in (linkage.DLS, linkage.CCD):
        arm.solver = solver
        arm.angles_at(0.0)
        linkage.solve_many(arm.base, arm.axes, arm.bones, np.zeros(2), arm.lo, arm.hi,
                           np.array([[0.5, 3.5, 0.0]]), solver, 0.5, 10)


def _marching_cubes():
    """An isosurface by marching cubes, drawn by the volume renderer's z-buffer pass."""
    from core.render import render
    from core.scene.model import Scene
    from core.settings import RenderSettings
    from core.volume import generators
    from core.volume.data import Volume
    from core.volume.marching import isosurface

    closed, _, _ = _scenes()
    values, spacing = generators.sphere(12)
    surface = isosurface(Volume(values=values, spacing=spacing, mode="isosurface", iso=0.5))
    scene = Scene(name="warm-up isosurface", views=closed.views, meshes=[surface])
    render(scene, scene.views[0], RenderSettings.for_scene(scene, size=SIZE, renderer="volume"))


def _ray_marcher():
    """The ray marcher's emission-absorption (lit and unlit) and MIP over an opaque mesh (the
    z-buffer's depth cuts the rays)."""
    import numpy as np

    from core.render import render
    from core.scene.generators import uv_sphere
    from core.scene.model import Scene
    from core.settings import RenderSettings
    from core.volume import generators
    from core.volume.data import Volume, attach_volumes

    closed, _, _ = _scenes()
    values, spacing = generators.sphere(12)
    transfer = np.array([[0.0, 1, 1, 1, 0.0], [1.0, 1, 0.5, 0.2, 2.0]])
    scene = Scene(name="warm-up volume", views=closed.views,
                  meshes=[uv_sphere(0.3, segments=12, rings=6)])
    attach_volumes(scene, [Volume(values=values, spacing=spacing, transfer=transfer),
                           Volume(values=values, spacing=spacing, transfer=transfer,
                                  lighting="none"),
                           Volume(values=values, spacing=spacing, mode="mip")])
    render(scene, scene.views[0], RenderSettings.for_scene(scene, size=SIZE, renderer="volume"))


def steps() -> list[tuple[str, Callable[[], object]]]:
    """(label, run) for every path the window can take; each ``run`` renders one small frame."""
    from core.registry import shading_modes
    from core.render import render
    from core.renderers import renderers
    from core.settings import RASTERIZERS, RenderSettings

    closed, opened, large = _scenes()
    out = []

    def add(label, scene, **settings):
        s = RenderSettings.for_scene(scene, size=SIZE, **settings)
        out.append((label, lambda: render(scene, scene.views[0], s)))

    for projection in ("perspective", "parallel"):
        add(f"wireframe, {projection}", opened, shading="wireframe", projection=projection)
        for shading in (m.name for m in shading_modes() if m.module):   # those with a shader
            for rasterizer in RASTERIZERS:
                add(f"{shading}, {projection}, {rasterizer} rasterizer", closed,
                    shading=shading, projection=projection, rasterizer=rasterizer)
            add(f"{shading}, {projection}, open mesh and lines", opened, shading=shading,
                projection=projection)
    for shading in (m.name for m in shading_modes() if m.module and m.lights):
        # the textbook float64 kernels, which a material float32 cannot light exactly takes
        # (Cook–Torrance, an exponent that is not a whole number): compiled here, not by the
        # first shipped scene that has one (cook_torrance.toml, 8 s of its step)
        add(f"{shading}, the float64 kernels", opened, shading=shading,
            shading_precision="float64")
    add("flat, 4 samples a pixel", closed, shading="flat", samples=4)
    add("flat, 50k faces culled on all cores", large, shading="flat")
    out.append(("a large frame in two batches (early z)", _batched_frame))
    scenes = {"closed": closed, **_renderer_scenes(closed)}
    for entry in renderers():                   # each renderer's own frames (its entry's)
        for label, scene, settings in entry.warm_up:
            add(label, scenes[scene], renderer=entry.name, **settings)
    out.append(("the Liang-Barsky and homogeneous clippers", _other_clippers))
    out.append(("rigid bodies", _rigid_bodies))              # two steps: 20 s as one
    out.append(("linkages (both IK solvers)", _linkages))
    out.append(("volume: marching cubes", _marching_cubes))   # two steps: 32 s as one
    out.append(("volume: emission-absorption and MIP", _ray_marcher))
    return out


def foundation_label() -> str:
    """The step that compiles the z-buffer's own kernels (the first flat frame), which most
    other steps draw through too (the volume renderer's opaque pass, the painters' rasterizer,
    the inspectors): it runs first, so that no other step compiles them beside it (run beside
    the ray marcher's step, that step took 18 s, 11 of them the z-buffer's)."""
    from core.settings import RASTERIZERS
    return f"flat, perspective, {RASTERIZERS[0]} rasterizer"


def _renderer_scenes(closed) -> dict:
    """The small scenes a renderer's warm-up frames name: ``small``, a closed sphere (the
    painters' kernels, and the window's background warm-up never holds a frame for a tree of
    12k triangles, 1.8 s), and ``box``, a cube (radiosity's form factors, solver and display;
    the path tracer)."""
    import dataclasses

    from core.scene.generators import cube, uv_sphere
    from core.scene.model import Scene
    small = Scene(name="warm-up small sphere", views=closed.views, meshes=[
        dataclasses.replace(uv_sphere(1.0, segments=24, rings=12), closed=True)])
    box = Scene(name="warm-up box", meshes=[cube(1.0)], views=closed.views)
    return {"small": small, "box": box}


def _other_clippers() -> None:
    """Lines and triangles cut by the two clippers beside the default (``--clipper``): a
    scene whose front plane crosses it, so that the clipping kernels really run."""
    from core.paths import SCENES_DIR
    from core.render import render
    from core.scene.formats import load_scene
    from core.settings import CLIPPERS, RenderSettings
    scene = load_scene(SCENES_DIR / "crossing_front_plane.tri")
    for clipper in CLIPPERS[1:]:                # those beside the default
        for shading in ("wireframe", "flat"):
            settings = RenderSettings.for_scene(scene, size=SIZE, shading=shading,
                                                clipper=clipper)
            render(scene, scene.views[0], settings)


def scene_jobs(path, size=SIZE, every=False):
    """(label, run) for the first picture of scene file ``path`` in every renderer, shading
    and (when it has textures) texture filter, each made as the window makes it. A renderer
    that shades through no shading mode, or draws no texture, is drawn in the scene's own
    only, unless ``every`` (the test that holds the warm-up complete opens all of them)."""
    from app.session.state import ViewerState
    from core.registry import shading_names
    from core.renderers import get_renderer, renderer_names
    from core.texture.modes import FILTERS

    state = ViewerState.open(path, size=size)
    choices = state.choices
    window_settings = choices.settings
    # Fewer elements, a coarser hemicube, an early stop and one sample a pixel change no
    # kernel's argument types, only how long each solve runs: the same kernels compile. The
    # stop is early indeed (1 % of the light shot): a solve of the bezier patches to half of
    # it took 2,013 shots and 15 s, a third of all the rendering the warm-up did.
    choices.settings = lambda: quick(window_settings())
    filters = tuple(FILTERS) if choices.has_textures else (state.texture_filter,)
    own_shading, own_filter = state.shading, state.texture_filter
    jobs = []
    for renderer in renderer_names():
        # A renderer that does not shade through the shading modes, or draw texture maps,
        # draws the same picture with the same kernels in each: once is enough (the ray
        # tracer five times over a textured scene's four filters was 20 frames for one).
        entry = get_renderer(renderer)
        for shading in shading_names() if entry.shaders or every else (own_shading,):
            for filter_ in filters if entry.textures or every else (own_filter,):
                choices.set_renderer(renderer)
                choices.set_shading(shading)
                choices.set_texture_filter(filter_)
                run, _ = state.frames.job()
                jobs.append((f"{path.name}: {renderer}, {shading}, {filter_}", run))
    return jobs


def quick(settings):
    """``settings`` with its renderer's work cut to a token amount (its entry's ``quick``)."""
    from core.renderers import get_renderer
    return settings.replace(**(get_renderer(settings.renderer).quick or {}))


def scene_label(path) -> str:
    """The label of the step that opens scene file ``path``."""
    return f"{Path(path).name}, every renderer, shading and filter"


def scene_steps() -> list[tuple[str, Callable[[], object]]]:
    """One step per shipped scene: its first pictures in every renderer, shading, filter."""
    def opener(path):
        def run():                   # every shipped scene's files are in the repository
            for _, job in scene_jobs(path):
                job()
        return run
    return [(scene_label(path), opener(path)) for path in shipped_scenes()]


def opening_label(path) -> str:
    """The label of the step that draws file ``path``'s first picture as the window opens it."""
    return f"{Path(path).name} as it opens"


def opening_steps(path) -> list[tuple[str, Callable[[], object]]]:
    """One step: ``path``'s first picture with its own settings (the window's first frame).
    Far fewer kernels than the scene's every-renderer step, so the window that asked for it
    (``--first``) draws after this one step, not after the whole warm-up."""
    def run():
        from app.session.state import ViewerState
        state = ViewerState.open(path, size=SIZE)
        state.frames.job()[0]()
    return [(opening_label(path), run)]


def all_steps() -> list[tuple[str, Callable[[], object]]]:
    """Every step of ``python -m app warmup``: the paths, then the shipped scenes."""
    return steps() + scene_steps()


def step_scenes() -> dict[str, list[str]]:
    """label → the shipped scene files (names) that the step opens (none for the paths)."""
    return {scene_label(path): [path.name] for path in shipped_scenes()}


def run(progress: Callable[[int, int, str, float], None] | None = None) -> float:
    """Run every step in this process, one after another; ``progress(k, n, label, seconds)``
    after each. Returns the total."""
    todo = all_steps()
    start = time.perf_counter()
    for k, (label, job) in enumerate(todo, start=1):
        t = time.perf_counter()
        job()
        if progress is not None:
            progress(k, len(todo), label, time.perf_counter() - t)
    return time.perf_counter() - start
