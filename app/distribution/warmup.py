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
does (:class:`app.session.state.ViewerState`), in every renderer and shading, and in every
texture filter when it has textures, so that no first picture the user asks for compiles
(``tests/app/distribution/test_warmup_complete.py`` checks it from an empty kernel cache).

The steps run in worker processes, one a core (``--jobs``), each taking the next step from
one queue, the longest first by :data:`COSTS` (``app/distribution/warmup_pool.py``). When every step
has succeeded a stamp says the cache is warm (``app/distribution/warm_stamp.py``: :func:`is_warm`).
``--progress-json`` prints one JSON object a line instead of the table, and
:class:`BackgroundWarmup` runs the whole thing as a subprocess for the window, so that the
window opens at once and its kernels compile beside it.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Callable

from app.distribution.warm_stamp import is_warm  # noqa: F401  (the viewer's import)
from app.loading import shipped_scenes  # noqa: F401  (tests and the smoke set read it here)

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
    add("flat, 4 samples a pixel", closed, shading="flat", samples=4)
    add("phong, the float64 pixel kernel", opened, shading="phong", shading_precision="float64")
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
    window_settings = state.settings
    # Fewer elements, a coarser hemicube, an early stop and one sample a pixel change no
    # kernel's argument types, only how long each solve runs: the same kernels compile. The
    # stop is early indeed (1 % of the light shot): a solve of the bezier patches to half of
    # it took 2,013 shots and 15 s, a third of all the rendering the warm-up did.
    state.settings = lambda: quick(window_settings())
    filters = tuple(FILTERS) if state.has_textures else (state.texture_filter,)
    own_shading, own_filter = state.shading, state.texture_filter
    jobs = []
    for renderer in renderer_names():
        # A renderer that does not shade through the shading modes, or draw texture maps,
        # draws the same picture with the same kernels in each: once is enough (the ray
        # tracer five times over a textured scene's four filters was 20 frames for one).
        entry = get_renderer(renderer)
        for shading in shading_names() if entry.shaders or every else (own_shading,):
            for filter_ in filters if entry.textures or every else (own_filter,):
                state.set_renderer(renderer)
                state.set_shading(shading)
                state.set_texture_filter(filter_)
                run, _ = state._job()
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
        state._job()[0]()
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


def compile_bytecode() -> bool:
    """Write the ``.pyc`` of ``app`` and ``core`` now: a process started with
    PYTHONDONTWRITEBYTECODE (or from a read-only checkout) would otherwise compile every
    module from source at each start, about 0.1 s before the first picture."""
    import compileall
    from core.paths import ROOT
    return all(compileall.compile_dir(ROOT / package, quiet=2) for package in ("app", "core"))


# Seconds each step took from an empty kernel cache, all of them one after another in one
# process (`python -m app.distribution.compile_profile --json F`, its "steps"; a 2-core
# machine): the scheduler starts the longest first, so that no long step is left for the
# end while the other cores idle. A step's cost includes the kernels it was the first to
# need; a step not listed counts as DEFAULT_COST. Refresh it when the steps change.
COSTS: dict[str, float] = {
    "ray traced (Whitted)": 29.49,
    "volume: emission-absorption and MIP": 13.14,
    "flat, perspective, edge rasterizer": 11.59,
    "cook_torrance.toml, every renderer, shading and filter": 11.39,
    "BSP tree (painter's)": 9.69,
    "rigid bodies": 9.57,
    "volume: marching cubes": 8.61,
    "whitted.toml, every renderer, shading and filter": 7.37,
    "path traced": 6.35,
    "linkages (both IK solvers)": 6.35,
    "depth sort (painter's), depth-cued": 5.37,
    "terrain.toml, every renderer, shading and filter": 5.34,
    "big.toml, every renderer, shading and filter": 5.27,
    "barr_deformations.toml, every renderer, shading and filter": 4.86,
    "blocks_falling.toml, every renderer, shading and filter": 4.78,
    "phong, perspective, edge rasterizer": 4.15,
    "the Liang-Barsky and homogeneous clippers": 3.58,
    "phong, the float64 pixel kernel": 3.41,
    "bump_demo.toml, every renderer, shading and filter": 3.25,
    "scan-line visible surface (Watkins)": 2.67,
    "fast_wheel.toml, every renderer, shading and filter": 2.14,
    "radiosity (raycast)": 1.77,
    "flat, perspective, open mesh and lines": 1.71,
    "texture_bump_sphere.toml, every renderer, shading and filter": 1.65,
    "flat, perspective, scanline rasterizer": 1.55,
    "flat, 50k faces culled on all cores": 1.24,
    "radiosity (hemicube)": 1.21,
    "texture_env_normal.toml, every renderer, shading and filter": 1.16,
    "wireframe, perspective": 1.16,
    "depth, perspective, edge rasterizer": 0.81,
    "texture_sphere_torus.toml, every renderer, shading and filter": 0.72,
    "glass_bunny.toml, every renderer, shading and filter": 0.59,
    "flat, 4 samples a pixel": 0.55,
    "volume_mip.toml, every renderer, shading and filter": 0.55,
    "refraction.toml, every renderer, shading and filter": 0.50,
    "a large frame in two batches (early z)": 0.50,
    "gouraud, perspective, edge rasterizer": 0.49,
    "cornell_box.toml, every renderer, shading and filter": 0.46,
    "texture_floor.toml, every renderer, shading and filter": 0.33,
    "bezier.toml, every renderer, shading and filter": 0.30,
    "volume_isosurface.toml, every renderer, shading and filter": 0.29,
    "flock.toml, every renderer, shading and filter": 0.26,
    "fountain.toml, every renderer, shading and filter": 0.24,
    "gouraud, perspective, open mesh and lines": 0.24,
    "sphere.toml, every renderer, shading and filter": 0.17,
    "update_dynamics.toml, every renderer, shading and filter": 0.15,
    "volume_phantom.toml, every renderer, shading and filter": 0.14,
    "torus.toml, every renderer, shading and filter": 0.13,
    "crossing_front_plane.tri, every renderer, shading and filter": 0.10,
    "transparent_pane.toml, every renderer, shading and filter": 0.08,
    "robot_arm.toml, every renderer, shading and filter": 0.07,
    "house_flyaround.toml, every renderer, shading and filter": 0.07,
    "icosphere.toml, every renderer, shading and filter": 0.06,
    "volume_alone.toml, every renderer, shading and filter": 0.05,
    "snow_house.toml, every renderer, shading and filter": 0.05,
    "cube.toml, every renderer, shading and filter": 0.05,
    "house_mirror.toml, every renderer, shading and filter": 0.04,
    "radiosity_room.toml, every renderer, shading and filter": 0.04,
    "particle_constraints.toml, every renderer, shading and filter": 0.04,
    "three_bars.toml, every renderer, shading and filter": 0.03,
    "fireworks.toml, every renderer, shading and filter": 0.03,
    "mach_bands.toml, every renderer, shading and filter": 0.03,
    "smoke.toml, every renderer, shading and filter": 0.03,
    "few_triangles.tri, every renderer, shading and filter": 0.02,
    "house_solid.obj, every renderer, shading and filter": 0.02,
    "interpenetrating.tri, every renderer, shading and filter": 0.02,
    "pierced_triangles.tri, every renderer, shading and filter": 0.02,
    "house_depth_cue.toml, every renderer, shading and filter": 0.02,
    "house.toml, every renderer, shading and filter": 0.01,
    "house_projections.toml, every renderer, shading and filter": 0.01,
    "phong, perspective, scanline rasterizer": 0.00,
    "depth, perspective, scanline rasterizer": 0.00,
    "gouraud, perspective, scanline rasterizer": 0.00,
    "phong, perspective, open mesh and lines": 0.00,
    "depth, perspective, open mesh and lines": 0.00,
    "flat, parallel, scanline rasterizer": 0.00,
    "gouraud, parallel, scanline rasterizer": 0.00,
    "flat, parallel, open mesh and lines": 0.00,
    "depth, parallel, scanline rasterizer": 0.00,
    "phong, parallel, scanline rasterizer": 0.00,
    "gouraud, parallel, open mesh and lines": 0.00,
    "flat, parallel, edge rasterizer": 0.00,
    "phong, parallel, open mesh and lines": 0.00,
    "depth, parallel, open mesh and lines": 0.00,
    "wireframe, parallel": 0.00,
    "gouraud, parallel, edge rasterizer": 0.00,
    "phong, parallel, edge rasterizer": 0.00,
    "depth, parallel, edge rasterizer": 0.00,
}
DEFAULT_COST = 5.0


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of ``python -m app warmup``."""
    parser.add_argument("--jobs", type=int, default=None, metavar="N",
                        help="worker processes (default: one a core)")
    parser.add_argument("--progress-json", action="store_true",
                        help="one JSON object a line instead of the progress table")
    parser.add_argument("--first", default=None, metavar="PATH",
                        help="first, the picture this file opens on (the window's first "
                             "frame)")
    parser.add_argument("--only", action="append", default=None, metavar="TEXT",
                        help=argparse.SUPPRESS)     # steps whose label contains TEXT (tests)
    parser.add_argument("--extra-steps", default=None, metavar="MODULE:FUNCTION",
                        help=argparse.SUPPRESS)     # more (label, run) steps (tests)
    parser.add_argument("--stamp", default=None, metavar="PATH",
                        help=argparse.SUPPRESS)     # the stamp's path (tests)
    parser.add_argument("--until-stdin-closes", action="store_true",
                        help=argparse.SUPPRESS)     # the window's: end when the window has gone
    return parser


def _end_when_stdin_closes() -> None:
    """A daemon thread that interrupts the warm-up (as SIGTERM does) once standard input is
    closed: the window that started it holds the other end, so a window that is killed or
    crashes does not leave this process compiling on."""
    def watch():
        try:        # the raw descriptor: a daemon thread in a buffered read aborts at exit
            while os.read(0, 4096):
                pass
        except OSError:
            pass
        os.kill(os.getpid(), signal.SIGTERM)
    threading.Thread(target=watch, name="end with the window", daemon=True).start()


def _options(args) -> argparse.Namespace:
    """``args`` as parsed by app/cli.py (which may not know these options yet: their
    defaults), a list of strings, or None (``sys.argv``)."""
    parser = add_arguments(argparse.ArgumentParser(prog="python -m app warmup"))
    if args is None or isinstance(args, (list, tuple)):
        return parser.parse_args(args)
    defaults = parser.parse_args([])
    for name, value in vars(defaults).items():
        if not hasattr(args, name):
            setattr(args, name, value)
    return args


class _Interrupted(KeyboardInterrupt):
    """SIGTERM, handled as Ctrl-C is."""


def _on_sigterm(signum, frame):
    raise _Interrupted()


class _Report:
    """What a warm-up run says: JSON events (``--progress-json``, for the window) or lines."""

    def __init__(self, as_json: bool):
        self.as_json = as_json
        self.out = sys.stdout                   # where the lines go, as when the run began
        self.finished: list = []
        self.total, self.scenes, self.first = 0, {}, None

    def emit(self, event: dict) -> None:
        try:
            print(json.dumps(event), flush=True)
        except BrokenPipeError:               # the reader (a window) has gone: no one to tell
            sys.stdout = open(os.devnull, "w")

    def say(self, text: str) -> None:
        if not self.as_json:
            print(text, file=self.out, flush=True)

    def start(self, total: int, jobs: int, scenes: dict, first: str | None) -> None:
        self.total, self.scenes, self.first = total, scenes, first
        if self.as_json:
            self.emit({"event": "start", "total": total, "jobs": jobs})
        else:
            self.say(f"  {total} steps on {jobs} worker process{'es' if jobs > 1 else ''}")

    def on_begin(self, label) -> None:
        if self.as_json:
            self.emit({"event": "begin", "label": label, "scenes": self.scenes.get(label, [])})

    def on_outcome(self, outcome) -> None:
        self.finished.append(outcome)
        k, n = len(self.finished), self.total
        common = {"k": k, "total": n, "label": outcome.label,
                  "seconds": round(outcome.seconds, 3),
                  "scenes": self.scenes.get(outcome.label, [])}
        if self.first is not None and outcome.label == opening_label(self.first):
            common["opens"] = self.first        # the window's first picture will load now
        if outcome.error is None:
            if self.as_json:
                self.emit({"event": "done", **common})
            self.say(f"  [{k:2d}/{n}] {outcome.label}: {outcome.seconds:.2f} s")
        elif self.as_json:
            self.emit({"event": "failed", **common, "error": outcome.error})
        else:
            print(f"  [{k:2d}/{n}] FAILED {outcome.label}: {outcome.error}",
                  file=sys.stderr, flush=True)


def main(args=None) -> int:
    """``python -m app warmup``: every step on ``--jobs`` workers; the stamp when all succeed.
    Exit status 0 when every step succeeded, 1 when one failed, 130 when interrupted."""
    options = _options(args)
    report = _Report(options.progress_json)
    stamp = _stamp_to_write(options)
    report.say("warming up: compiling the kernels once (numba keeps them on disk)")
    if not compile_bytecode():
        report.say("  (some Python bytecode could not be written: starts will compile it)")
    todo, scenes, first = _steps_to_run(options)
    jobs = _job_count(options, todo)
    report.start(len(todo), jobs, scenes, first)
    ran = _run_steps(options, todo, jobs, first, report)
    if ran is None:
        return 130
    outcomes, seconds = ran
    return _finish(outcomes, seconds, stamp, jobs, report)


def _stamp_to_write(options) -> Path | None:
    """The stamp this run writes when all its steps succeed (another version's is removed)."""
    from app.distribution import warm_stamp
    # A run of some steps (--only) says nothing about the whole cache: it writes a stamp only
    # where it is told to (the tests), never the real one.
    partial = bool(options.only or options.extra_steps)
    stamp = Path(options.stamp) if options.stamp else None if partial else warm_stamp.stamp_path()
    if stamp is not None and not warm_stamp.is_warm(stamp):
        warm_stamp.remove(stamp)                # another version's stamp: not ours to keep
    return stamp


def _steps_to_run(options) -> tuple[list, dict, str | None]:
    """(the steps in the order they run, the scenes each warms, the file the window opens)."""
    from app.distribution import warmup_pool
    listed = [label for label, _ in warmup_pool.load_steps(options.extra_steps)]
    if options.only:
        listed = [label for label in listed if any(text in label for text in options.only)]
    scenes = step_scenes()
    first = str(Path(options.first).resolve()) if options.first else None
    if first is not None and not Path(first).is_file():
        first = None                            # nothing to open: no step of its own
    if first is not None:
        listed.append(opening_label(first))
    todo = warmup_pool.order(listed, COSTS, DEFAULT_COST,
                             first=lambda label: first is not None
                             and label == opening_label(first),
                             later=lambda label: label in scenes)
    return todo, scenes, first


def _job_count(options, todo) -> int:
    """--jobs (by default the pool's), never more than there are steps."""
    from app.distribution import warmup_pool
    jobs = options.jobs if options.jobs and options.jobs > 0 else warmup_pool.default_jobs()
    return max(1, min(jobs, len(todo) or 1))


def _run_steps(options, todo, jobs, first, report):
    """Run the steps on the workers: (outcomes, seconds), or None when interrupted (said)."""
    from app.distribution import warmup_pool
    start = time.perf_counter()
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    if options.until_stdin_closes:
        _end_when_stdin_closes()
    try:
        outcomes = warmup_pool.run_parallel(todo, jobs, extra=options.extra_steps, first=first,
                                            on_begin=report.on_begin,
                                            on_outcome=report.on_outcome)
    except KeyboardInterrupt:
        seconds = time.perf_counter() - start
        if report.as_json:
            report.emit({"event": "finished", "seconds": round(seconds, 3), "ok": False,
                         "interrupted": True, "failed": []})
        else:
            print(f"warm-up interrupted after {seconds:.1f} s ({len(report.finished)} of "
                  f"{len(todo)} steps done; run it again for the rest)", file=sys.stderr,
                  flush=True)
        return None
    finally:
        signal.signal(signal.SIGTERM, previous)
    return outcomes, time.perf_counter() - start


def _finish(outcomes, seconds: float, stamp, jobs: int, report) -> int:
    """Write or remove the stamp, and say how the run went: 0 when every step succeeded."""
    from app.distribution import warm_stamp
    n = report.total
    failed = [outcome for outcome in outcomes if outcome.error is not None]
    if stamp is not None:
        if failed:
            warm_stamp.remove(stamp)
        else:
            warm_stamp.write(seconds, n, stamp)
    if report.as_json:
        report.emit({"event": "finished", "seconds": round(seconds, 3), "ok": not failed,
                     "failed": [outcome.label for outcome in failed]})
    elif failed:
        print(f"warm-up: {len(failed)} of {n} steps failed ("
              + "; ".join(outcome.label for outcome in failed) + "); the cache is not marked "
              "warm", file=sys.stderr, flush=True)
    else:
        report.say(f"warm: {seconds:.1f} s in all on {jobs} worker process"
                   f"{'es' if jobs > 1 else ''}; later starts load the compiled kernels")
    return 1 if failed else 0


class BackgroundWarmup:
    """``python -m app warmup --progress-json`` in a subprocess, for the window.

    Its stdout is read on a daemon thread; its stderr goes to ``log_path`` (by default
    ``warmup.log`` beside the stamp). The properties are safe to read from any thread.
    ``on_event``, when given, is called with no arguments after each event has been taken in
    (the window passes ``glfw.post_empty_event`` to wake its loop); it runs on the reader
    thread and what it raises is ignored.
    """

    def __init__(self, first_scene=None, jobs: int | None = None,
                 on_event: Callable[[], object] | None = None, log_path=None,
                 extra_args=()):
        from app.distribution.warm_stamp import stamp_path
        from core.paths import ROOT
        self._lock = threading.Condition()
        self._total: int | None = None
        self._done: list[str] = []
        self._current: list[str] = []
        self._scenes_done: set[str] = set()
        self._opened: set[str] = set()          # files whose first picture is compiled
        self._failed: list[str] = []
        self._finished = False
        self._ok: bool | None = None
        self._on_event = on_event
        self._scenes_dir = (ROOT / "scenes").resolve()
        command = [sys.executable, "-m", "app.distribution.warmup", "--progress-json",
                   "--until-stdin-closes"]
        if first_scene is not None:
            command += ["--first", str(first_scene)]
        if jobs:
            command += ["--jobs", str(int(jobs))]
        command += [str(arg) for arg in extra_args]
        self.log_path = Path(log_path) if log_path else stamp_path().with_name("warmup.log")
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = open(self.log_path, "ab")
        # its stdin is ours: when this process ends, however it ends, the warm-up ends too
        self._process = subprocess.Popen(command, cwd=ROOT, stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=self._log,
                                         text=True, encoding="utf-8", errors="replace",
                                         bufsize=1)
        self._reader = threading.Thread(target=self._read, name="warm-up progress",
                                        daemon=True)
        self._reader.start()

    # what the subprocess says
    def _read(self) -> None:
        for line in self._process.stdout:
            try:
                event = json.loads(line)
            except ValueError:
                continue                        # not one of ours (a stray print)
            if isinstance(event, dict):
                self._take(event)
        code = self._process.wait()
        with self._lock:
            if not self._finished:              # it ended without saying so (killed, crashed)
                self._finished, self._ok = True, False
                self._failed.append(f"the warm-up exited with code {code} before it finished")
            self._lock.notify_all()
        self._wake()
        self._log.close()

    def _take(self, event: dict) -> None:
        kind = event.get("event")
        with self._lock:
            if kind == "start":
                self._total = int(event.get("total", 0))
            elif kind == "begin":
                self._current.append(str(event.get("label")))
            elif kind in ("done", "failed"):
                label = str(event.get("label"))
                if label in self._current:
                    self._current.remove(label)
                if kind == "done":
                    self._done.append(label)
                    self._scenes_done.update(event.get("scenes") or ())
                    if event.get("opens"):
                        self._opened.add(str(event["opens"]))
                else:
                    self._failed.append(f"{label}: {event.get('error')}")
            elif kind == "finished":
                self._finished = True
                self._ok = bool(event.get("ok"))
                self._current.clear()
            self._lock.notify_all()
        self._wake()

    def _wake(self) -> None:
        if self._on_event is not None:
            try:
                self._on_event()
            except Exception:                   # noqa: BLE001  (the window's; not ours)
                pass

    # what the window asks
    @property
    def total(self) -> int | None:
        """How many steps the warm-up runs (None until it has said)."""
        with self._lock:
            return self._total

    @property
    def done(self) -> int:
        """How many steps have succeeded."""
        with self._lock:
            return len(self._done)

    @property
    def current(self) -> tuple[str, ...]:
        """The labels of the steps the workers are on now."""
        with self._lock:
            return tuple(self._current)

    @property
    def finished(self) -> bool:
        """Whether the warm-up has ended (every step run, stopped, or the process gone)."""
        with self._lock:
            return self._finished

    @property
    def ok(self) -> bool | None:
        """True when every step succeeded (the stamp is written), False when not, None
        while it runs."""
        with self._lock:
            return self._ok

    @property
    def failed(self) -> list[str]:
        """One message a failed step (``label: error``), and one if the process died."""
        with self._lock:
            return list(self._failed)

    def ready_for(self, scene_path, every_setting: bool = False) -> bool:
        """Whether pictures of ``scene_path`` will load, not compile: its first picture (the
        ``--first`` step) or the step for that shipped scene in every renderer, shading and
        filter (only that one with ``every_setting``) has succeeded, or the whole warm-up
        has finished."""
        with self._lock:
            return self._finished or self._covers(scene_path, every_setting)

    def _covers(self, scene_path, every_setting: bool) -> bool:
        path = Path(scene_path).resolve()
        if not every_setting and str(path) in self._opened:
            return True
        return path.parent == self._scenes_dir and path.name in self._scenes_done

    def wait_for(self, scene_path, timeout: float | None = None,
                 every_setting: bool = False) -> bool:
        """Block until :meth:`ready_for` ``scene_path`` (or ``timeout`` seconds); its value."""
        with self._lock:
            return self._lock.wait_for(
                lambda: self._finished or self._covers(scene_path, every_setting), timeout)

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the warm-up has finished (or ``timeout`` seconds); :attr:`finished`."""
        with self._lock:
            return self._lock.wait_for(lambda: self._finished, timeout)

    @property
    def returncode(self) -> int | None:
        """The subprocess's exit status, None while it runs."""
        return self._process.poll()

    def stop(self, timeout: float = 10.0) -> None:
        """End the warm-up: SIGTERM (it terminates its workers and exits), SIGKILL after
        ``timeout`` seconds (the workers then exit on their own: they watch their parent)."""
        if self.finished and self._process.poll() is None:
            try:                                # it has said its last: let it exit itself
                self._process.wait(timeout)
            except subprocess.TimeoutExpired:
                pass
        if self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(timeout)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        self._reader.join(timeout)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


if __name__ == "__main__":
    sys.exit(main())
