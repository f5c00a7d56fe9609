"""The front door: ``render(scene, view, settings) -> Frame``, whatever the renderer.

``view`` is any :class:`core.camera.view.View` — one of ``scene.views`` or not (an
interpolated one, an animated one); ``settings`` a :class:`core.settings.RenderSettings`
(default: the scene's own). The renderer named by ``settings.renderer`` (:mod:`core.renderers`)
draws; this module checks the view, owns the frame, the film and the per-stage clock, and
never raises for bad scene data: an invalid view or an empty framebuffer gives a frame of the
background colour whose ``message`` says why.

Supersampling is the film's (:mod:`core.camera.film`): a renderer that places samples itself
(a ray caster) gets ``settings.samples`` as it is; any other is run once per sample with the
sample's offset in ``settings.pixel_offset`` — or, for a regular grid that fits in memory, once
at ``s`` times the size and box-filtered, which puts the samples at exactly the same points.

What outlives a frame (the z-buffer's memory, per-mesh normals and edge lists) lives in a
:class:`RenderContext`: the viewer keeps one; calls without one share :data:`DEFAULT_CONTEXT`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from core.context import DEFAULT_CONTEXT, RenderContext
from core.camera.film import Film, box_filter, fill, grid_side
from core.camera.view import View, ViewError, problems
from core.plan import Stage, plan
from core.renderers import get_renderer
from core.scene.model import Scene
from core.settings import RenderSettings
from core.stages import TRANSPARENCY, ran

# Above this many samples in one pass (k·W x k·H), a regular grid is drawn sample by sample.
MAX_PASS_PIXELS = 16_000_000


@dataclass
class Frame:
    """One rendered picture: ``color`` is ``(H, W, 3)`` uint8, row 0 at the top.

    ``color`` is a view of ``rgbx``, ``(H, W, 4)``: the same pixels with one padding byte each
    (undefined, never read), so that showing the frame is one aligned copy into an RGBA
    texture (on llvmpipe 0.05 ms against 0.56 ms for packed RGB at 500 x 500).

    ``depth`` ``(H, W)``: the z-buffer's canonical depth at each pixel centre (larger is nearer,
    ``-inf`` where nothing was drawn), for stages drawn after the opaque pass; ``None`` when the
    renderer keeps none or the frame is supersampled. It is the context's buffer, valid until
    the next frame drawn with the same context. ``sample_color``: for a regular grid drawn in
    one pass, the ``(s·H, s·W, 3)`` samples before the box filter, and ``filtered`` their
    ``(H, W, 3)`` means on 0–255 before rounding.
    """

    rgbx: np.ndarray
    plan: list[Stage]
    message: str | None = None
    stats: dict = field(default_factory=dict)
    depth: np.ndarray | None = None
    sample_color: np.ndarray | None = None
    filtered: np.ndarray | None = None

    @property
    def color(self) -> np.ndarray:
        return self.rgbx[:, :, :3]

    def _repr_png_(self) -> bytes:
        """The picture as PNG bytes: Jupyter shows a frame inline as it shows an image."""
        import io

        from PIL import Image
        out = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(self.color)).save(out, format="PNG")
        return out.getvalue()




class Timer:
    """Collects per-stage wall times (ms) into a stats dict, and hands each stage's arrays to
    an ``inspect(stage, arrays)`` callback when one is given (the stability suite checks every
    intermediate array that way, on the real path)."""

    def __init__(self, stats: dict, inspect=None):
        self.times = stats.setdefault("ms", {})
        self.inspect = inspect
        self.t = time.perf_counter()

    @property
    def keeps_arrays(self) -> bool:
        """Does anyone look at the stages' arrays (then every one is computed, the
        barycentrics of a flat frame included)?"""
        return self.inspect is not None

    def lap(self, stage: str, **arrays) -> None:
        now = time.perf_counter()
        self.times[stage] = self.times.get(stage, 0.0) + (now - self.t) * 1e3
        if self.inspect is not None and arrays:
            self.inspect(stage, arrays)
        self.t = time.perf_counter()


def render(scene: Scene, view: View | None, settings: RenderSettings | None = None,
           context: RenderContext | None = None, inspect=None) -> Frame:
    """Draw ``scene`` seen through ``view`` with ``settings``.

    ``view`` ``None`` means the scene has none to show (the frame says so). ``inspect(stage,
    arrays)``, when given, is called after each stage of the triangle path with the arrays it
    produced (named as in :mod:`core.renderers.zbuffer.draw`).
    """
    settings = settings or RenderSettings.for_scene(scene)
    context = context or DEFAULT_CONTEXT
    scene = lit_as_asked(scene, settings, context)
    renderer = get_renderer(settings.renderer)
    width, height = settings.size
    frame = Frame(rgbx=np.empty((max(height, 0), max(width, 0), 4), dtype=np.uint8),
                  plan=plan(scene, settings.projection, settings.shading, settings.keep_aspect,
                            settings.rasterizer, settings.texture_filter, settings.renderer,
                            settings.transparency),
                  stats={"allocated": ["color"], "computed": [], "renderer": renderer.name,
                         "projection": settings.projection, "shading": settings.shading})
    message = _why_not(scene, view, settings, context)
    if message:
        frame.message = message
        frame.stats["refused"] = "view"       # nothing was drawn: the view (or size) says why
        fill(frame.color, scene.background)
        return frame
    draw = renderer.function()
    if (settings.transparency != "off" and renderer.transparency
            and any(m.material.kt > 0 for m in scene.meshes)):   # k_t > 0 laid over the picture
        from core.effects.transparency import with_transparency
        draw = with_transparency(draw)
    if settings.depth_cue:                    # any renderer's picture, cued by its depth
        from core.effects.depth_cue import depth_cued
        draw = depth_cued(draw)
    if settings.samples == 1 or renderer.samples_itself:
        draw(scene, view, settings, frame, context, Timer(frame.stats, inspect))
    else:
        _supersample(draw, scene, view, settings, frame, context, inspect)
    if "transparency" in frame.stats.get("ms", {}):    # the effect timed it: k_t > 0 laid over
        ran(frame.stats, TRANSPARENCY)
    _say_what_is_not_drawn(scene, renderer, frame.stats, settings.transparency,
                           settings.shading)
    return frame


def render_file(source, view: int = 1, size: tuple[int, int] | None = None,
                context: RenderContext | None = None, **settings) -> Frame:
    """A scene file's view ``view`` (counting from 1, as ``render --view``) drawn with the
    scene's own settings and ``settings`` over them: ``render_file("scenes/cube.toml",
    shading="phong")`` in a notebook shows the picture (:meth:`Frame._repr_png_`). Raises
    the reader's error for a file that cannot be read, ValueError for a view it lacks."""
    from core.scene.formats import load_scene
    scene = load_scene(source, size=size)
    if not 1 <= view <= len(scene.views):
        raise ValueError(f"{source}: view {view} of {len(scene.views)} valid views")
    chosen = RenderSettings.for_scene(scene, **settings)
    return render(scene, scene.views[view - 1], chosen, context)


def lit_as_asked(scene: Scene, settings: RenderSettings, context: RenderContext) -> Scene:
    """``scene``, or, when ``settings.lighting_model`` names a model, its copy with every
    material lit by that model (kept with the scene, so its caches live as long). The copy
    carries the scene's volumes as they are: the ray marcher applies the settings' model."""
    if settings.lighting_model is None:
        return scene
    from core.shading.models import scene_lit_by
    cache = context.cache(scene)
    key = f"lit by {settings.lighting_model}"
    if key not in cache:
        # the copy has the same volumes (Scene.systems; the window edits them in place): the
        # marcher takes the model from the settings
        cache[key] = scene_lit_by(scene, settings.lighting_model)
    return cache[key]


def _say_what_is_not_drawn(scene: Scene, renderer, stats: dict,
                           transparency: str = "off", shading: str = "") -> None:
    """Add to ``stats["not drawn"]`` what of the scene this renderer leaves out by design:
    the local renderers take no light from area emitters, and draw mirrors (k_r) without
    their reflection and glass (k_t) opaque unless asked for transparency; the
    global-illumination ones use each material's colour, not its texture maps, and the path
    tracer takes no point light's light through glass; only the z-buffer and the painters
    colour by depth (``shading = "depth"``)."""
    from core.texture.material import maps_of
    notes = stats.setdefault("not drawn", [])
    said = []                           # meshes of one name (a checker's two) say it once
    name_of = renderer.name
    if shading == "depth" and not renderer.shaders and scene.meshes:
        said.append(f"depth shading (the height colour map): {name_of} lights the surfaces "
                    f"with the illumination model instead; {_who('shaders')} draw it")
    for mesh in scene.meshes:
        name = getattr(mesh, "name", None) or "a mesh"
        if not renderer.emitters and any(c > 0 for c in mesh.material.emission):
            said.append(f"the light of the emitter ({name}): only {_who('emitters')} "
                        f"light a scene with it")
        elif not renderer.textures and maps_of(mesh.material):
            said.append(f"texture maps ({name}): {name_of} uses the material's own colour")
        if not renderer.recursive and mesh.material.kr > 0:
            said.append(f"the reflection in the mirror ({name}): only {_who('recursive')} "
                        f"follow reflected rays")
        if (renderer.emitters and renderer.recursive and not renderer.caustics
                and (mesh.material.kt > 0 or mesh.material.kr > 0)):
            # The two-pass method's first pass is radiosity: no light is carried from a
            # mirror or through glass onto the diffuse surfaces (no extended form factors).
            from core.registry import names_that
            said.append(f"the light that {name} passes on to the diffuse surfaces (k_r, "
                        f"k_t > 0: a mirror's light thrown on a wall, the light through glass, "
                        f"caustics): {name_of}'s first pass is radiosity, where {name} is an "
                        f"opaque diffuse surface of rho = k_d O_d (--renderer "
                        f"{' or '.join(names_that('caustics'))} draws it)")
        if (renderer.emitters and renderer.recursive and renderer.caustics
                and mesh.material.kt > 0 and scene.lights):
            # A path tracer reaches a point or directional light only by a shadow ray, which a
            # k_t > 0 surface stops: what lies behind glass or water gets none of their light
            # (caustics of a delta light: no sampled path can hit it).
            said.append(f"the scene's point and directional light through {name} "
                        f"(k_t > 0): {name_of} finds none through it (a caustic of a point "
                        f"light); an emitter's light is traced through")
        if not renderer.recursive and mesh.material.kt > 0 and not (
                renderer.transparency and transparency != "off"):
            said.append(f"the transparency of {name} (k_t > 0): drawn opaque"
                         + (" (transparency interpolated or screen-door shows it: "
                            "--transparency, or the Render menu)"
                            if renderer.transparency else ""))
    untessellated = getattr(scene, "untessellated", ())
    if untessellated and not renderer.analytic:
        said.append(f"{len(untessellated):,} spheres past the triangle budget, which were not "
                    f"tessellated: {_who('analytic')} draw them (Render > Ray traced, or "
                    f"--renderer raytrace)")
    from core.renderers import volumes_note
    volumes = volumes_note(scene)
    if volumes and not renderer.volumes:
        said.append(volumes)
    for note in said:
        if note not in notes:
            notes.append(note)


def _who(capability: str) -> str:
    """The renderers that can do ``capability``, as a phrase: "zbuffer, bsp and depth-sort"."""
    from core.registry import names_that
    names = names_that(capability)
    return " and ".join(n for n in (", ".join(names[:-1]), names[-1]) if n) if names else "none"


def _why_not(scene: Scene, view: View | None, settings: RenderSettings,
             context: RenderContext) -> str | None:
    """Why nothing can be drawn, or None."""
    if view is None:
        return f"{scene.name}: no valid view to show"
    try:
        context.normalizing_transform(view, settings.projection)
    except ViewError:
        return (f"{view.label}: invalid for {settings.projection} projection: "
                + "; ".join(problems(view, settings.projection)))
    width, height = settings.size
    if width <= 0 or height <= 0:
        return f"the framebuffer is {width} x {height}: nothing to draw"
    return None


def _supersample(draw, scene, view, settings, frame, context, inspect) -> None:
    """Run a one-sample renderer over the film's samples and box-filter them into ``frame``
    (or reconstruct them with ``settings.pixel_filter``)."""
    width, height = settings.size
    side = grid_side(settings.samples)
    frame.stats["samples per pixel"] = settings.samples
    if settings.pixel_filter != "box" or settings.filter_radius not in (None, 0.5):
        return _filtered(draw, scene, view, settings, frame, context, inspect)
    big = _one_pass(draw, scene, view, settings, frame, context, inspect)
    if big is not None:
        frame.filtered = box_filter(big.color, side)
        frame.color[:] = np.floor(frame.filtered + 0.5).astype(np.uint8)
        frame.sample_color = big.color
        return
    film = Film(width, height, settings.samples, settings.sample_pattern, settings.seed)
    one = Frame(rgbx=np.empty_like(frame.rgbx), plan=frame.plan, stats=frame.stats)
    for offset in film.offsets:
        draw(scene, view, settings.replace(samples=1, pixel_offset=tuple(offset)), one, context,
             Timer(frame.stats, inspect))
        _take_message(frame, one)
        film.add(one.color)
    frame.color[:] = film.resolve()


def _take_message(frame, sample) -> None:
    """A sample's frame said why it could not draw (a renderer's refusal): the frame the
    caller gets says it (the samples share the stats, not the message)."""
    if sample.message and not frame.message:
        frame.message = sample.message


def _one_pass(draw, scene, view, settings, frame, context, inspect):
    """A regular grid of samples drawn as one frame ``side`` times larger each way, where the
    pattern is a full grid and it fits the pass budget; else None (one frame per sample)."""
    width, height = settings.size
    side = grid_side(settings.samples)
    if not (settings.sample_pattern == "regular" and side * side == settings.samples
            and width * height * settings.samples <= MAX_PASS_PIXELS):
        return None
    big = Frame(rgbx=np.empty((height * side, width * side, 4), np.uint8), plan=frame.plan,
                stats=frame.stats)
    draw(scene, view, settings.replace(samples=1, size=(width * side, height * side)), big,
         context, Timer(frame.stats, inspect))
    _take_message(frame, big)
    return big


def _filtered(draw, scene, view, settings, frame, context, inspect) -> None:
    """The film's samples (a regular grid in one pass where it fits, else one frame per
    sample) reconstructed with the settings' filter (core.camera.filters)."""
    from core.camera.filters import check, reconstruct, regular_grid
    width, height = settings.size
    side = grid_side(settings.samples)
    radius = check(settings.pixel_filter, settings.filter_radius)
    frame.stats["pixel filter"] = f"{settings.pixel_filter}, radius {radius:g}"
    big = _one_pass(draw, scene, view, settings, frame, context, inspect)
    if big is not None:
        images, offsets = regular_grid(big.color, side)
        frame.sample_color = big.color
    else:
        film = Film(width, height, settings.samples, settings.sample_pattern, settings.seed)
        images, offsets = [], [tuple(o) for o in film.offsets]
        for offset in offsets:
            one = Frame(rgbx=np.empty_like(frame.rgbx), plan=frame.plan, stats=frame.stats)
            draw(scene, view, settings.replace(samples=1, pixel_offset=offset), one, context,
                 Timer(frame.stats, inspect))
            _take_message(frame, one)
            images.append(one.color.copy())
    frame.filtered = reconstruct(images, offsets, settings.pixel_filter, radius)
    frame.color[:] = np.floor(frame.filtered + 0.5).astype(np.uint8)

