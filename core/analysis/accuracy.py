"""Error against run time: how wrong each image is, and what accuracy time buys.

Takes a :class:`SweepConfig` (image size, tessellation levels, shading modes, samples per pixel,
repeats) and returns one :class:`Point` per setting of the sweep

    scene (sphere, torus) x shading (flat, Gouraud, Phong) x tessellation level x samples (1, 4, 16)

measured as follows.

- The image: :func:`core.render.render` at ``k`` times the size (``k² `` = samples per pixel,
  k = 1, 2, 4), box-filtered: every k x k block of 8-bit pixels averaged into one pixel. That
  is our pipeline run at the higher resolution, nothing else; its samples sit at the centres of
  a regular k x k grid in each pixel.
- Run time: the median over ``repeats`` frames of render + box filter, in the steady state a
  viewer is in (one untimed frame first: it compiles, fills the per-mesh caches and
  allocates the z-buffer). The timed frames go round-robin over the settings of one size, so
  that load from other programs spreads evenly. Fewer repeats at the bigger sizes keep the
  sweep short.
- The reference: :func:`core.renderers.raycast.draw.render_reference` on the true sphere or
  torus, the same view, lights and materials, float64, 16 samples a pixel (4 x 4), computed
  once and cached on disk (:func:`cached_reference`).
- Errors on the 0–255 scale: RMSE and the maximum absolute difference over every pixel and
  channel of the image; the RMSE over the pixels that both cover fully (``rmse_inside``, the
  shading error without the silhouette); and the fraction of pixels whose coverage differs —
  the number of the pixel's k x k samples that see the surface, ours against the exact
  surface's at the same sample points (the reference at k x k samples). The background is
  black and every surface colour has an ambient term of at least one level, so a sample sees
  the surface exactly when its colour is not black.

:func:`pareto_front` marks the settings no other setting beats in both time and RMSE, and
:func:`reading` turns the points into a few sentences: which setting to choose for a budget.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import statistics
import tempfile
import time
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Callable

import numpy as np

from core.settings import RenderSettings
from core.renderers.raycast import draw as reference_module
from core.camera import film
from core.settings import SOLID_SHADINGS
from core.scene.generators import torus, uv_sphere
from core.renderers.raycast.draw import Reference, Sphere, Torus, render_reference
from core.scene.model import Light, Material, Mesh, Scene
from core.camera.view import View

# A series is a shading mode, drawn by the default edge rasterizer (perspective-correct), or
# "MODE scanline": the course's scan-line rasterizer, whose interpolation is screen-linear, or
# "MODE bsp" / "MODE depth-sort": the painter's renderers, same shading.
SCANLINE = " scanline"
PAINTERS = (" bsp", " depth-sort")
SHADINGS = SOLID_SHADINGS + ("gouraud" + SCANLINE,) + tuple("gouraud" + p for p in PAINTERS)
SCENES = ("sphere", "torus")
CACHE = Path(tempfile.gettempdir()) / "fvdfh-reference-cache"
REFERENCE_SAMPLES = 4                  # per axis: 16 samples a pixel

SPHERE_MATERIAL = Material(ka=0.3, kd=0.6, ks=0.5, n=30.0, od=(0.85, 0.3, 0.25))
TORUS_MATERIAL = Material(ka=0.3, kd=0.6, ks=0.5, n=30.0, od=(0.2, 0.45, 0.85))
LIGHTS = [Light(intensity=(0.9, 0.9, 0.9), position=(3.0, 4.0, 5.0)),
          Light(intensity=(0.3, 0.3, 0.3), direction=(-1.0, 0.3, 0.5))]
AMBIENT = (0.15, 0.15, 0.15)
VIEWS = {
    # slightly from above: the pole, where a UV sphere's triangles are worst, is in sight
    "sphere": View(vrp=(0, 0, 0), vpn=(0.2, 0.5, 1.0), vup=(0, 1, 0),
                   window=(-1.25, 1.25, -1.25, 1.25), prp=(0, 0, 5), front=1.2, back=-1.2,
                   label="sphere"),
    # the ring from 40 degrees above its plane: inner and outer silhouettes, the hole
    "torus": View(vrp=(0, 0, 0), vpn=(0.0, -0.85, 1.0), vup=(0, 1, 0),
                  window=(-1.5, 1.5, -1.5, 1.5), prp=(0, 0, 6), front=1.5, back=-1.5,
                  label="torus"),
}


@dataclass(frozen=True)
class SweepConfig:
    """What to sweep. ``repeats`` maps samples per pixel to the number of timed frames."""

    size: int = 500
    levels: tuple[int, ...] = (8, 16, 32, 64, 128)
    samples: tuple[int, ...] = (1, 4, 16)
    shadings: tuple[str, ...] = SHADINGS
    scenes: tuple[str, ...] = SCENES
    repeats: dict = field(default_factory=lambda: {1: 15, 4: 9, 16: 5})
    cache: Path | None = CACHE


DEFAULT = SweepConfig()
QUICK = SweepConfig(size=128, levels=(8, 16, 32), samples=(1, 4), repeats={1: 3, 4: 3})


@dataclass
class Point:
    """One setting of the sweep and what it measured."""

    scene: str
    shading: str
    level: int
    samples: int             # per pixel
    triangles: int
    ms: float                # median frame time, render + box filter
    frames: int              # timed frames behind the median
    ms_min: float            # the fastest of them: the cost with the machine to itself
    rmse: float              # 0-255 scale, whole image
    max_error: float         # 0-255 scale, whole image
    rmse_inside: float       # 0-255 scale, pixels fully covered in both
    coverage_differs: float  # fraction of pixels
    pareto: bool = False

    def label(self) -> str:
        return f"{self.shading} L{self.level} {self.samples}spp"


# --------------------------------------------------------------------------------------------
# The analytic scenes


def analytic_scene(name: str, level: int) -> tuple[Scene, object]:
    """``(scene with the tessellated mesh, the exact shape)`` for ``name`` at ``level``.

    Sphere: a UV sphere of radius 1 with ``level`` rings and ``2 level`` segments
    (4 level (level - 1) triangles); torus: R = 1, r = 0.35, ``level`` sides around the tube
    and ``2 level`` segments around the ring (4 level² triangles). Both carry their exact
    vertex normals.
    """
    if name == "sphere":
        mesh: Mesh = uv_sphere(radius=1.0, segments=2 * level, rings=level)
        mesh.material = SPHERE_MATERIAL
        shape = Sphere((0.0, 0.0, 0.0), 1.0, SPHERE_MATERIAL)
    elif name == "torus":
        mesh = torus(R=1.0, r=0.35, segments=2 * level, sides=level)
        mesh.material = TORUS_MATERIAL
        shape = Torus((0.0, 0.0, 0.0), 1.0, 0.35, material=TORUS_MATERIAL)
    else:
        raise ValueError(f"scene must be one of {SCENES}, not {name!r}")
    scene = Scene(name=f"{name}-L{level}", meshes=[mesh], views=[VIEWS[name]], lights=LIGHTS,
                  ambient=AMBIENT, background=(0.0, 0.0, 0.0), shading="phong")
    return scene, shape


def _check_never_black(material: Material) -> None:
    """Coverage is read as "not black": the ambient term must reach at least one level."""
    if max(a * material.ka * o for a, o in zip(AMBIENT, material.od)) * 255 < 0.5:
        raise ValueError("the ambient term rounds to black: coverage could not be read")


# --------------------------------------------------------------------------------------------
# References, computed once


def _source_hash() -> str:
    """The code an exact image depends on: the reference itself, the model it evaluates, and
    the viewing it shares with the pipeline. A change to any of them recomputes the cache."""
    from core.shading import illumination
    from core.pipeline import project
    from core.camera import view
    text = "".join(inspect.getsource(m) for m in (reference_module, illumination, project, view))
    return hashlib.sha256(text.encode()).hexdigest()


def _reference_key(name: str, size: int, samples: int) -> str:
    scene, shape = analytic_scene(name, 3)
    text = json.dumps({
        "code": _source_hash(),
        "shape": repr(shape), "lights": repr(scene.lights), "ambient": scene.ambient,
        "background": scene.background, "specular": scene.specular, "view": repr(VIEWS[name]),
        "size": size, "samples": samples}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_reference(name: str, size: int, samples: int, cache: Path | None = CACHE) -> Reference:
    """The exact image of scene ``name`` at ``samples`` x ``samples`` samples a pixel.

    Kept in ``cache`` (a temp folder) under a key made of everything it depends on, the source
    of :mod:`core.renderers.raycast.draw` included, so a change anywhere recomputes it.
    """
    path = None
    if cache is not None:
        path = Path(cache) / f"{name}-{size}-{samples}-{_reference_key(name, size, samples)}.npz"
        if path.exists():
            try:
                with np.load(path) as data:
                    arrays = {f.name: data[f.name] for f in fields(Reference) if f.name != "samples"}
                return Reference(**arrays, samples=samples)
            except (OSError, ValueError, KeyError, TypeError):
                pass                                    # damaged or outdated: compute it again
    scene, shape = analytic_scene(name, 3)
    ref = render_reference([shape], scene, VIEWS[name], "perspective", size=(size, size),
                           samples=samples)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_suffix(".tmp.npz")
        np.savez_compressed(partial, **{f.name: getattr(ref, f.name) for f in fields(Reference)
                                        if f.name != "samples"})
        partial.replace(path)
    return ref


# --------------------------------------------------------------------------------------------
# The pipeline at k x k samples a pixel


box_filter = film.box_filter            # the film's compiled box filter


def sample_coverage(image: np.ndarray, k: int) -> np.ndarray:
    """``(H, W)`` count of the k x k samples of each pixel that see the surface (not black)."""
    seen = np.any(image != 0, axis=2)
    height, width = seen.shape[0] // k, seen.shape[1] // k
    return seen.reshape(height, k, width, k).sum(axis=(1, 3))


def render_supersampled(scene: Scene, shading: str, size: int, k: int):
    """``(samples (kH, kW, 3) uint8, their box-filtered mean (H, W, 3) float64 on 0–255)``:
    the renderer's own supersampling (``RenderSettings.samples`` = k², a regular grid).
    ``shading`` is a series name (``"gouraud scanline"``: Gouraud, scan-line rasterizer)."""
    from core.render import render
    mode, renderer = shading.removesuffix(SCANLINE), "zbuffer"
    for painter in PAINTERS:
        if shading.endswith(painter):
            mode, renderer = shading.removesuffix(painter), painter.strip()
    rasterizer = "scanline" if shading.endswith(SCANLINE) else "edge"
    frame = render(scene, scene.views[0],
                   RenderSettings(shading=mode, size=(size, size), samples=k * k,
                                  rasterizer=rasterizer, renderer=renderer))
    if frame.message:
        raise ValueError(frame.message)
    if k == 1:
        return frame.color, frame.color.astype(np.float64)
    return frame.sample_color, frame.filtered


def errors(name: str, scene: Scene, shading: str, level: int, samples: int, size: int,
           reference: Reference, coverage_reference: Reference) -> Point:
    """One frame of a setting and its errors against the references (time still unmeasured).

    The pipeline is deterministic, so one frame gives the errors of every frame; this one is
    also the untimed frame that compiles and fills the caches.
    """
    k = int(round(samples ** 0.5))
    big, image = render_supersampled(scene, shading, size, k)
    error = image - 255.0 * reference.rgb
    ours = sample_coverage(big, k)
    exact_count = np.rint(coverage_reference.coverage * k * k).astype(np.int64)
    inside = (ours == k * k) & (reference.coverage == 1.0)
    return Point(scene=name, shading=shading, level=level, samples=samples,
                 triangles=int(scene.triangle_count), ms=float("nan"), frames=0,
                 ms_min=float("nan"),
                 rmse=float(np.sqrt(np.mean(error ** 2))),
                 max_error=float(np.max(np.abs(error))),
                 rmse_inside=float(np.sqrt(np.mean(error[inside] ** 2))) if inside.any() else 0.0,
                 coverage_differs=float(np.mean(ours != exact_count)))


def frame_time(scene: Scene, shading: str, size: int, samples: int) -> float:
    """Seconds for one frame at ``samples`` per pixel (box filter included)."""
    k = int(round(samples ** 0.5))
    start = time.perf_counter()
    render_supersampled(scene, shading, size, k)
    return time.perf_counter() - start


def settings(config: SweepConfig) -> list[tuple[int, str, int, str]]:
    """``(samples, scene, level, shading)`` in sweep order: by size first, so the z-buffer is
    reallocated only when the size changes."""
    return [(s, name, level, shading) for s in config.samples for name in config.scenes
            for level in config.levels for shading in config.shadings]


def sweep(config: SweepConfig = DEFAULT, progress: Callable[[str], None] | None = None
          ) -> list[Point]:
    """Every setting of ``config``, measured; ``progress`` gets a line per step.

    For each number of samples a pixel (one framebuffer size): first one frame of every
    setting (its errors; compiles and fills the caches), then the timed frames round-robin
    over those settings, so that a burst of load from other programs spreads over all of them
    instead of skewing the few that happened to run then.
    """
    say = progress or (lambda line: None)
    references: dict[tuple[str, int], Reference] = {}

    def ref(name: str, samples_per_axis: int) -> Reference:
        if (name, samples_per_axis) not in references:
            start = time.perf_counter()
            references[(name, samples_per_axis)] = cached_reference(
                name, config.size, samples_per_axis, config.cache)
            say(f"reference {name} {config.size}x{config.size} at {samples_per_axis ** 2} "
                f"samples a pixel: {time.perf_counter() - start:.1f} s")
        return references[(name, samples_per_axis)]

    scenes: dict[tuple[str, int], Scene] = {}
    for name in config.scenes:
        for level in config.levels:
            scene, shape = analytic_scene(name, level)
            _check_never_black(shape.material)
            scenes[(name, level)] = scene
    points: list[Point] = []
    todo = settings(config)
    step = 0
    for samples in config.samples:
        k = int(round(samples ** 0.5))
        if k * k != samples:
            raise ValueError(f"samples a pixel must be a square (1, 4, 16), not {samples}")
        group = []
        for _, name, level, shading in (t for t in todo if t[0] == samples):
            step += 1
            point = errors(name, scenes[(name, level)], shading, level, samples, config.size,
                           ref(name, REFERENCE_SAMPLES), ref(name, k))
            group.append(point)
            say(f"[{step}/{len(todo)}] {name} {point.label()} ({point.triangles} triangles): "
                f"RMSE {point.rmse:.2f}, max {point.max_error:.0f}, RMSE inside "
                f"{point.rmse_inside:.2f}, coverage differs {100 * point.coverage_differs:.2f}%")
        repeats = config.repeats.get(samples, 3)
        times: dict[int, list[float]] = {i: [] for i in range(len(group))}
        start = time.perf_counter()
        for _ in range(repeats):
            for i, p in enumerate(group):
                times[i].append(frame_time(scenes[(p.scene, p.level)], p.shading, config.size,
                                           samples))
        for i, p in enumerate(group):
            p.ms, p.frames = 1e3 * statistics.median(times[i]), len(times[i])
            p.ms_min = 1e3 * min(times[i])
        say(f"timed {samples} sample{'s' if samples > 1 else ''} a pixel: {repeats} rounds of "
            f"{len(group)} frames in {time.perf_counter() - start:.1f} s; median "
            + ", ".join(f"{p.scene[0]}{p.shading[0]}{p.level} {p.ms:.0f}" for p in group) + " ms")
        points += group
    for name in config.scenes:
        pareto_front([p for p in points if p.scene == name])
    return points


# --------------------------------------------------------------------------------------------
# Reading the result


def pareto_front(points: list[Point]) -> list[Point]:
    """Mark and return the points no other point beats in both time and RMSE (fastest first)."""
    front = []
    best = float("inf")
    for p in sorted(points, key=lambda p: (p.ms, p.rmse)):
        p.pareto = p.rmse < best
        if p.pareto:
            front.append(p)
            best = p.rmse
    return front


def best_within(points: list[Point], budget_ms: float) -> Point | None:
    """The lowest-RMSE setting whose frame time is within ``budget_ms``."""
    fitting = [p for p in points if p.ms <= budget_ms]
    return min(fitting, key=lambda p: p.rmse) if fitting else None


def _budgets(points: list[Point]) -> list[float]:
    """Round budgets (1, 2, 5 x 10^k ms) spanning the measured times."""
    low, high = min(p.ms for p in points), max(p.ms for p in points)
    budgets = []
    for exponent in range(-1, 6):
        for m in (1, 2, 5):
            b = m * 10.0 ** exponent
            if low <= b <= high * 1.0001:
                budgets.append(b)
    return budgets


def _ms(x: float) -> str:
    return f"{x / 1000:.1f} s" if x >= 1000 else f"{x:.0f} ms"


def reading(points: list[Point]) -> list[str]:
    """A few sentences on what the sweep shows, computed from the points (Markdown bullets)."""
    lines = []
    for name in sorted({p.scene for p in points}, key=SCENES.index):
        mine = [p for p in points if p.scene == name]
        front = sorted([p for p in mine if p.pareto], key=lambda p: p.ms)
        choices = []
        last = None
        for budget in _budgets(mine):
            best = best_within(mine, budget)
            if best is not None and best is not last:
                choices.append(f"≤ {_ms(budget)}: **{best.label()}** (RMSE {best.rmse:.2f}, "
                               f"{_ms(best.ms)})")
                last = best
        top = min(mine, key=lambda p: p.rmse)
        if top is not last:
            choices.append(f"no limit: **{top.label()}** (RMSE {top.rmse:.2f}, {_ms(top.ms)})")
        lines.append(f"**{name.capitalize()}, which setting for a frame-time budget:** "
                     + "; ".join(choices) + ".")
        modes = {s: sum(p.shading == s for p in front) for s in SHADINGS}
        lines.append(f"{name.capitalize()}: the Pareto front has {len(front)} settings: "
                     + ", ".join(f"{n} {s}" for s, n in modes.items() if n) + ".")
    by = {(p.scene, p.shading, p.level, p.samples): p for p in points}
    levels = sorted({p.level for p in points})
    samples = sorted({p.samples for p in points})
    # Shading order at equal tessellation and samples.
    ordered = sum(1 for (sc, sh, lv, sp), p in by.items() if sh == "flat"
                  and by.get((sc, "gouraud", lv, sp)) and by.get((sc, "phong", lv, sp))
                  and p.rmse > by[(sc, "gouraud", lv, sp)].rmse > by[(sc, "phong", lv, sp)].rmse)
    total = sum(1 for k in by if k[1] == "flat")
    lines.append(f"At equal tessellation and samples, RMSE falls flat > Gouraud > Phong in "
                 f"{ordered} of {total} cases.")
    # What a finer mesh and what more samples buy, taking Phong as the example.
    for name in sorted({p.scene for p in points}, key=SCENES.index):
        first, last = (by.get((name, "phong", lv, samples[0])) for lv in (levels[0], levels[-1]))
        if first and last:
            lines.append(f"{name.capitalize()}, Phong at 1 sample a pixel: level {levels[0]} → "
                         f"{levels[-1]} takes RMSE from {first.rmse:.2f} to {last.rmse:.2f} "
                         f"(inside the silhouette {first.rmse_inside:.2f} → {last.rmse_inside:.2f}) "
                         f"for {_ms(first.ms)} → {_ms(last.ms)}; what is left at 1 sample is "
                         f"mostly the jagged silhouette.")
        hi = by.get((name, "phong", levels[-1], samples[-1]))
        if last and hi and samples[-1] > samples[0]:
            lines.append(f"{name.capitalize()}, Phong level {levels[-1]}: {samples[-1]} samples a "
                         f"pixel take RMSE from {last.rmse:.2f} to {hi.rmse:.2f} at "
                         f"{hi.ms / last.ms:.0f}x the time.")
    return lines


COLUMNS = ("scene", "shading", "level", "triangles", "samples", "ms", "frames", "ms_min", "rmse",
           "max_error", "rmse_inside", "coverage_differs", "pareto")


def as_rows(points: list[Point]) -> list[dict]:
    return [{k: asdict(p)[k] for k in COLUMNS} for p in points]
