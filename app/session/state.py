"""The viewer's state: the one place it lives, and the only thing that asks the core for frames.

:class:`ViewerState` holds the scene and where it came from, the view index, the render
settings the user chose (projection, shading, rasterizer, kept aspect, the ``.tri`` startup
code's rules), the picture's size, the messages to show (invalid views from the reader, in
their own collapsed strip; scenes that could not be opened; the current frame's own message),
the last :class:`core.render.Frame` and a ``dirty`` flag. The window changes it through its
methods and reads it to draw; a frame is rendered only when something that changes the
picture changed, and never for a zero-sized (minimised) framebuffer: at once
(:meth:`ViewerState.update`, for the PNG path and the tests) or on the render worker's thread
(:meth:`ViewerState.request`, then :meth:`ViewerState.accept`, for the window).

Views are numbered by their position in the file (``core.scene.view_numbers``): the window
steps over invalid ones and says "view 7 of 20 (6 invalid)".

Beyond the course's settings it holds the renderer (``"zbuffer"`` or ``"raytrace"``: a
ray-traced still is drawn progressively, :mod:`core.progressive`), the texture filter and
whether bump maps are used (in the bump demo's scene also the demo's map, which its clicks
change), and for an animated scene its :class:`app.session.playback.Playback` (the moment shown,
playing or paused, the speed) and whether the keyed camera is the view.

For a scene with volumes it holds the volume controls' state (:mod:`app.session.volume_controls`):
which volume, the iso values asked for (re-extracted by the next frame's job, on the worker's
thread), the transfer edits (checked; a bad one keeps the last good function with a message)
and the slice shown among the buffer views.

No GL and no window library here, so everything about it is testable without a display.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from core.registry import get_renderer
from core.scene.model import Scene
from core.scene import view_numbers
from core.registry import shading_names
from core.settings import PROJECTIONS, RASTERIZERS

log = logging.getLogger("fvd")
CAMERA_HISTORY = 100          # camera changes Ctrl+Z can go back through


def load_scene(source: str | Path, size: tuple[int, int] | None = None,
               crease_angle: float | None = None) -> Scene:
    """``core.scene.formats.load_scene``, imported when first needed (it pulls in the readers)."""
    from core.scene.formats import load_scene as load
    return load(source, size=size, crease_angle=crease_angle)


def render(scene, view, settings, context=None):
    """``core.render.render``, imported when first needed.

    A wireframe needs no compiled kernel, so numba is imported (to listen for compiles) only
    when a frame will draw triangles; the default scene's first frame then skips it entirely.
    """
    from core.render import render as render_frame
    if settings.shading != "wireframe" and scene.triangle_count:
        _listen_for_compiles()
    return render_frame(scene, view, settings, context)


# Set when numba starts compiling a kernel (a cache miss), so that the slow-frame notice
# speaks of compiling only when it is true: loading cached kernels takes ~0.5 s too.
_compiling = threading.Event()
_listening: list[bool] = []
_compiles = [0]                 # kernels compiled so far in this process (the window's progress)


def compile_count() -> int:
    """How many numba compilations have started in this process (once listening)."""
    return _compiles[0]


def _listen_for_compiles() -> None:
    if _listening:
        return
    _listening.append(True)
    try:
        from numba.core import event
    except ImportError:
        return

    class CompileListener(event.Listener):
        def on_start(self, ev):
            _compiles[0] += 1
            _compiling.set()

        def on_end(self, ev):
            pass

    event.register("numba:compile", CompileListener())


@contextlib.contextmanager
def announce_compiles(after: float = 0.5):
    """Print the compile notice once if numba compiles while the block runs, but not before
    ``after`` seconds (loading cached kernels is quick and stays silent)."""
    _compiling.clear()
    done = threading.Event()

    def watch():
        if done.wait(after):
            return
        while not done.is_set():
            if _compiling.is_set():
                compile_notice()
                return
            done.wait(0.1)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    try:
        yield
    finally:
        done.set()


def compile_notice() -> None:
    """Printed while a first frame is slow because numba is compiling kernels."""
    if _compiling.is_set():
        print("compiling the kernels (once; `python -m app warmup` does it ahead)…",
              file=sys.stderr, flush=True)


def compiling() -> bool:
    """Has numba started compiling a kernel since the flag was last cleared?"""
    return _compiling.is_set()


def bump_demos(scene) -> list:
    """The bump demo's materials on ``scene`` (empty elsewhere)."""
    from core.texture.demo_scene import demo_materials
    return demo_materials(scene)


def reader_errors() -> tuple[type[BaseException], ...]:
    """What a failed open raises: the readers' own error, and the OS's for unreadable paths."""
    from core.scene.formats import ReaderError
    return (ReaderError, OSError)


@dataclass
class ViewerState:
    """Scene, settings, messages and the last frame. Change it only through its methods."""

    scene: Scene
    scene_source: str
    size: tuple[int, int]
    projection: str = ""
    shading: str = ""
    rasterizer: str = ""
    keep_aspect: bool | None = None
    course_tri: bool = False          # the .tri startup code's back-face rule and mouse buttons
    texture_filter: str = "trilinear"   # nearest | bilinear | trilinear | anisotropic
    view_index: int = 0                                      # into scene.views (valid views)
    open_messages: list[str] = field(default_factory=list)   # scenes that failed to open
    frame: object | None = None                              # the last core.render.Frame
    frame_seconds: float = 0.0                               # how long that frame took
    frame_count: int = 0
    render_error: str | None = None                          # the last render that raised
    # The last scene that failed to open, said at the top of the status until a frame asked
    # for after it is shown (the next successful action).
    failed_open: str = ""
    _clear_failed_open: bool = field(default=False, repr=False)
    dirty: bool = True
    renderer: Callable = render
    loader: Callable = load_scene
    # The first frame of each shading mode may compile numba kernels (seconds, once: numba
    # caches them on disk). Say so when it takes longer than this.
    compile_notice_after: float = 0.5
    _modes_rendered: set = field(default_factory=set, repr=False)
    context: object = None          # the core.context.RenderContext of this window's frames
    renderer_name: str = ""         # RenderSettings.renderer: "zbuffer" | "raytrace" (the menu's)
    bump: bool = True               # bump and normal maps perturb the normal (the demo: Phong)
    bump_map: int = 0               # the bump demo's height map B(x, y), 0..3
    playback: object = None         # app.session.playback.Playback of an animated scene, or None
    keyed_view: bool = False        # an animated scene: show the keyed camera (not a file view)
    frame_partial: bool = False     # the frame shown is a ray-traced one still being refined
    # Depth cueing (None: the scene's), transparency ("": the scene's), and the
    # draw-order slider of the painter's renderers (None: paint everything)
    depth_cue: bool | None = None
    transparency: str = ""
    paint_first: int | None = None
    # A lighting model for every material (core.shading.models; "": each material's own).
    lighting_model: str = ""
    # The headlight (app.session.headlight): one light at the eye in place of the scene's,
    # off by default (the course's lights are fixed in the world).
    headlight: bool = False
    # Depth shading's scalar (core.shading.depth.MODES): "view", the distance from the eye, or
    # "height", the world y through the terrain map.
    depth_shading: str = "view"
    # The renderers' own options set in the panel (field name -> value; app.session.options),
    # kept across renderers and scenes like the renderer itself; the last refused value's
    # message, shown under the controls.
    option_values: dict = field(default_factory=dict)
    # Samples per pixel the user chose (the panel, ``view --samples``); None: the renderer's
    # ``samples_at_rest`` where it has one (the path tracer accumulates 256), else the scene's.
    samples: int | None = None
    option_message: str = ""
    # The window's kernel gate while the warm-up compiles in worker processes (a frame waits
    # for its kernels rather than compiling them a second time; app.viewer.kernels.gated):
    # wraps each frame's job; None renders it as it is.
    gate: Callable | None = None
    # A camera the user made with the mouse (app.viewer.hands): shown in place of the file's
    # view until the view is stepped, reset or the scene changes; None shows the file's.
    hand_view: object = None
    # The volume controls (app.session.volume_controls): the volume they act on, the last
    # refused edit's message, the iso values asked for (each re-extracted by the next frame's
    # job, on the worker's thread), and the slice shown among the buffer views.
    volume_index: int = 0
    volume_message: str = ""
    iso_wanted: dict = field(default_factory=dict, repr=False)
    slice_name: str = "axial"
    slice_index: int | None = None            # None: the middle slice
    scene_edits: int = 0                      # isosurfaces replaced in place so far
    _requested_scene: object = field(default=None, repr=False)   # the last request's scene
    # The camera history (Ctrl+Z / Ctrl+Shift+Z): (view index, moved camera, keyed view) before
    # each change, and the ones undone. The hands set ``camera_gesture`` to the gesture that
    # moves the camera (a drag, a spin of the wheel): its changes are one step.
    camera_gesture: object = field(default=None, repr=False)
    _camera_undo: list = field(default_factory=list, repr=False)
    _camera_redo: list = field(default_factory=list, repr=False)
    _remembered_gesture: object = field(default=None, repr=False)
    _headlights: object = field(default=None, repr=False)   # app.session.headlight.Headlights

    def __post_init__(self) -> None:
        self._scene_defaults(keep_settings=True)
        self.size = (int(self.size[0]), int(self.size[1]))
        if self.context is None:
            from core.context import RenderContext
            self.context = RenderContext()

    def current_view(self):
        """The view shown now (None when the scene has no valid view)."""
        return self.view

    def _scene_defaults(self, keep_settings: bool = False) -> None:
        s = self.scene
        if not keep_settings or not self.projection:
            self.projection = s.projection
        if not keep_settings or not self.shading:
            self.shading = s.shading
        if not keep_settings or not self.rasterizer:
            self.rasterizer = getattr(s, "rasterizer", "edge")
        if not keep_settings or self.keep_aspect is None:
            self.keep_aspect = bool(getattr(s, "keep_aspect", False))
        if not keep_settings or not self.renderer_name:
            self.renderer_name = getattr(s, "renderer", None) or "zbuffer"
        self.volume_index, self.volume_message, self.slice_index = 0, "", None
        self.iso_wanted = {}
        demo = bump_demos(s)
        if demo:
            self.bump_map, self.bump = int(demo[0].bump_map), bool(demo[0].bump)
        elif not keep_settings:
            self.bump = True
        from core.animation.keys import animation_of
        animation = animation_of(s)
        if animation is None:
            self.playback, self.keyed_view = None, False
        else:
            from app.session.playback import Playback
            self.playback = Playback(animation)
            self.keyed_view = animation.view is not None

    @classmethod
    def open(cls, source: str | Path, size: tuple[int, int] | None = None,
             **kwargs) -> ViewerState:
        """Load ``source`` (raises the reader's error: there is no earlier scene to keep)."""
        loader = kwargs.get("loader", load_scene)
        scene = loader(source, size=size)
        return cls(scene=scene, scene_source=str(source), size=size or scene.size, **kwargs)

    # -- what the window shows ---------------------------------------------------------------
    @property
    def view_count(self) -> int:
        """How many views can be shown (the valid ones)."""
        return len(self.scene.views)

    @property
    def view_number(self) -> int:
        """The current view's position in its file (from 1), 0 when there is none (or when
        the animation's keyed camera is shown)."""
        if self.keyed_view:
            return 0
        return view_numbers.file_number(self.scene, self.view_index) if self.view_count else 0

    @property
    def view_label(self) -> str:
        """``"view 7 of 20 (6 invalid)"``: positions in the file, or why there is nothing;
        ``"the keyed view"`` for an animation's moving camera."""
        if self.hand_view is not None and self.playback is not None:
            return "your camera (Enter: the scene's)"
        if self.keyed_view:
            return f"the keyed view (then the file's {self.view_count})"
        return view_numbers.label(self.scene, self.view_index)

    @property
    def view(self):
        if self.hand_view is not None:          # the user's camera, over a keyed one too
            return self.hand_view
        if self.keyed_view:
            return self.playback.animation.view_at(self.playback.time)
        return self.scene.views[self.view_index] if self.view_count else None

    @property
    def file_view(self):
        """The file's view at the current index (what Reset returns to), or None."""
        return self.scene.views[self.view_index] if self.view_count else None

    def set_hand_view(self, view) -> None:
        """Show ``view`` (a moved camera, already checked) in place of the file's."""
        if view != self.hand_view:
            self._remember_camera()
            self.hand_view, self.dirty = view, True

    def reset_view(self) -> bool:
        """Back to the file's view, bit for bit; returns whether the camera had moved."""
        if self.hand_view is None:
            return False
        self.camera_gesture = None
        self._remember_camera()
        self.hand_view, self.dirty = None, True
        return True

    # -- the camera's history ------------------------------------------------------------------
    def _camera(self) -> tuple:
        return self.view_index, self.hand_view, self.keyed_view

    def _remember_camera(self) -> None:
        """Before the camera changes: keep it to go back to (one step per gesture)."""
        gesture = self.camera_gesture
        if gesture is not None and gesture is self._remembered_gesture:
            return
        self._remembered_gesture = gesture
        self._camera_undo.append(self._camera())
        del self._camera_undo[:-CAMERA_HISTORY]
        self._camera_redo.clear()

    def undo_camera(self) -> bool:
        """The camera before the last change (a drag, a wheel spin, a fit, another view);
        whether there was one."""
        return self._swap_camera(self._camera_undo, self._camera_redo)

    def redo_camera(self) -> bool:
        """The camera change undone last, again; whether there was one."""
        return self._swap_camera(self._camera_redo, self._camera_undo)

    def _swap_camera(self, source: list, other: list) -> bool:
        if not source:
            return False
        other.append(self._camera())
        self.view_index, self.hand_view, self.keyed_view = source.pop()
        self.camera_gesture = self._remembered_gesture = None
        self.dirty = True
        return True

    @property
    def camera_history(self) -> tuple[int, int]:
        """(steps that can be undone, steps that can be redone)."""
        return len(self._camera_undo), len(self._camera_redo)

    @property
    def animated(self) -> bool:
        return self.playback is not None

    @property
    def playing(self) -> bool:
        return self.playback is not None and self.playback.playing

    @property
    def has_textures(self) -> bool:
        """Has a mesh of the scene a texture, bump, normal or environment map?"""
        from core.texture.material import maps_of
        return any(maps_of(m.material) is not None for m in self.scene.meshes)

    @property
    def is_bump_demo(self) -> bool:
        """Is this the bump demo's scene (J3DPanel's clicks apply)?"""
        return bool(bump_demos(self.scene))

    @property
    def bump_label(self) -> str | None:
        """The demo's text: ``"Bump: B(x,y) = …"`` or ``"Phong"`` (None elsewhere)."""
        if not self.is_bump_demo:
            return None
        from core.texture.demo_scene import label
        return f"Bump: {label(self.bump_map)}" if self.bump else "Phong"

    def settings(self):
        """The :class:`core.settings.RenderSettings` of the next frame."""
        from core.settings import RenderSettings
        return RenderSettings.for_scene(self.scene, projection=self.projection,
                                        shading=self.shading, size=self.size,
                                        rasterizer=self.rasterizer,
                                        keep_aspect=bool(self.keep_aspect),
                                        renderer=self.renderer_name,
                                        samples=self.samples_wanted,
                                        texture_filter=self.texture_filter, bump=self.bump,
                                        depth_cue=self.depth_cue,
                                        transparency=self.transparency or None,
                                        lighting_model=self.lighting_model or None,
                                        depth_shading=self.depth_shading,
                                        paint_first=(self.paint_first if self.renderer_entry
                                                     .has_option("paint_first") else None),
                                        **self.option_values)

    @property
    def samples_wanted(self) -> int | None:
        """The next frame's samples per pixel: the user's, or the renderer's at rest."""
        return self.samples if self.samples is not None else self.renderer_entry.samples_at_rest

    def set_samples(self, samples: int | None) -> bool:
        """Samples per pixel for the next frames (None: the default); a number the settings
        refuse keeps the last good one, with its message in :attr:`option_message`."""
        if samples is not None:
            try:
                self.settings().replace(samples=samples)
            except (ValueError, TypeError) as error:
                self.option_message = f"{error}; samples per pixel stay {self.samples_wanted}"
                return False
        self.option_message = ""
        if samples != self.samples:
            self.samples, self.dirty = samples, True
        return True

    @property
    def invalid_messages(self) -> list[str]:
        """The reader's message for each invalid view (the window's collapsed strip)."""
        return [f"invalid view: {m}" for m in self.scene.view_messages]

    @property
    def notices(self) -> list[str]:
        """Everything else to read: failed opens, this frame's message, a failed render."""
        found = list(self.open_messages) + [f"warning: {m}" for m in self.scene.messages]
        message = getattr(self.frame, "message", None)
        if message:
            found.append(message)
        if self.render_error:
            found.append(self.render_error)
        return found

    @property
    def messages(self) -> list[str]:
        """Every message: the invalid views first, then :attr:`notices`."""
        return self.invalid_messages + self.notices

    @property
    def has_triangles(self) -> bool:
        return self.scene.triangle_count > 0

    def frame_summary(self) -> str:
        """One log line for the last frame: which view, settings, size and time."""
        label = self.view.label if self.view_count else "-"
        message = getattr(self.frame, "message", None)
        stats = getattr(self.frame, "stats", None) or {}
        moment = f" t={stats['time']:.3f}" if "time" in stats else ""
        return (f"frame {self.frame_count}: {self.view_label} ({label}) "
                f"projection={self.projection} shading={self.shading} "
                f"renderer={self.renderer_name} filter={self.texture_filter}{moment} "
                f"rasterizer={self.rasterizer} aspect={'kept' if self.keep_aspect else 'stretched'} "
                f"size={self.size[0]}x{self.size[1]} render={self.frame_seconds * 1e3:.1f}ms"
                + (" camera=moved" if self.hand_view is not None else "")
                + (f" message={message!r}" if message else ""))

    @property
    def renderable(self) -> bool:
        """A zero-sized framebuffer (a minimised window) is never rendered."""
        return self.size[0] > 0 and self.size[1] > 0

    # -- changes -----------------------------------------------------------------------------
    def next_view(self) -> None:
        self._step_view(+1)

    def prev_view(self) -> None:
        self._step_view(-1)

    def _step_view(self, step: int) -> None:
        """Next / previous view; an animation with a keyed camera has it before the file's
        views (keyed, 1, 2, …, keyed)."""
        keyed = self.playback is not None and self.playback.animation.view is not None
        positions = ([-1] if keyed else []) + list(range(self.view_count))
        if not positions:
            return
        here = positions.index(-1 if self.keyed_view else self.view_index)
        there = positions[(here + step) % len(positions)]
        self.camera_gesture = None
        self._remember_camera()
        self.keyed_view = there < 0
        if there >= 0:
            self.view_index = there
        self.hand_view = None
        self.dirty = True

    def set_view(self, index: int) -> None:
        if not 0 <= index < max(self.view_count, 1):
            raise ValueError(f"view index must be in 0..{self.view_count - 1}, not {index}")
        if index != self.view_index or self.keyed_view or self.hand_view is not None:
            self.camera_gesture = None
            self._remember_camera()
            self.view_index, self.keyed_view, self.hand_view = index, False, None
            self.dirty = True

    # -- the renderer, the texture filter and the bump demo ------------------------------------
    @property
    def renderer_entry(self):
        """The renderer's registry entry (:class:`core.registry.Renderer`: what it can do)."""
        return get_renderer(self.renderer_name or "zbuffer")

    def set_renderer(self, name: str) -> None:
        """``"zbuffer"`` or ``"raytrace"`` (any registered renderer)."""
        from core.renderers import renderer_names
        self._set("renderer_name", name, renderer_names())

    def next_texture_filter(self) -> str:
        """The texture filter after this one (nearest, bilinear, trilinear, anisotropic)."""
        from core.texture.modes import FILTERS
        names = tuple(FILTERS)
        self.set_texture_filter(names[(names.index(self.texture_filter) + 1) % len(names)])
        return self.texture_filter

    def set_bump(self, on: bool) -> None:
        if bool(on) != self.bump:
            self.bump, self.dirty = bool(on), True

    def next_bump_map(self) -> int:
        """The demo's next height map (0 → 1 → 2 → 3 → 0), as its other mouse buttons do."""
        from core.texture.demo_scene import MAPS
        self.bump_map, self.dirty = (self.bump_map + 1) % MAPS, True
        return self.bump_map

    # -- depth cueing, transparency, the painter's draw order ---------------------------------
    def set_depth_cue(self, on: bool) -> None:
        if bool(on) != bool(self.settings().depth_cue):
            self.depth_cue, self.dirty = bool(on), True

    def set_transparency(self, mode: str) -> None:
        from core.settings import TRANSPARENCIES
        self._set("transparency", mode, TRANSPARENCIES)

    def renderer_options(self):
        """The current renderer's options object as the next frame uses it (None: it has
        none)."""
        return self.settings().options_of(self.renderer_name or "zbuffer")

    def set_option(self, name: str, value) -> bool:
        """Set the renderer's option ``name`` (a field of its options class). A value its class
        refuses keeps the last good one, with the class's message (:attr:`option_message`)."""
        try:
            self.settings().replace(**{name: value})      # the options class checks it
        except (ValueError, TypeError) as error:
            kept = getattr(self.renderer_options(), name, None)
            self.option_message = f"{error}; {name.replace('_', ' ')} stays {kept!r}"
            return False
        self.option_message = ""
        if self.option_values.get(name, object()) != value:
            self.option_values = {**self.option_values, name: value}
            self.dirty = True
        return True

    def set_paint_first(self, count: int | None) -> None:
        """Paint only the first ``count`` triangles of the order (None: all of them)."""
        count = None if count is None else max(int(count), 0)
        if count != self.paint_first:
            self.paint_first, self.dirty = count, True

    @property
    def painted_total(self) -> int | None:
        """How many triangles the last painter's frame painted in all (the slider's end)."""
        stats = getattr(self.frame, "stats", None) or {}
        return stats.get("painted total", stats.get("painted"))

    # -- playing an animated scene ---------------------------------------------------------
    def toggle_play(self, now: float) -> None:
        if self.playback is not None:
            self.playback.toggle(now)
            self.dirty = True

    def step_frame(self, frames: int) -> None:
        if self.playback is not None:
            self.playback.step(frames)
            self.dirty = True

    def seek(self, t: float, now: float | None = None) -> None:
        if self.playback is not None and float(t) != self.playback.time:
            self.playback.seek(t, now)
            self.dirty = True

    def set_speed(self, speed: float) -> None:
        if self.playback is not None:
            self.playback.set_speed(speed)

    def tick(self, now: float, busy: bool) -> bool:
        """While playing: move time on (the wall clock times the speed) unless the last frame
        asked for is still being drawn (``busy``: the picture then skips ahead)."""
        if self.playback is None or busy or not self.renderable:
            return False
        if self.playback.tick(now):
            self.dirty = True
            return True
        return False

    def set_projection(self, projection: str) -> None:
        self._set("projection", projection, PROJECTIONS)

    def set_shading(self, shading: str) -> None:
        self._set("shading", shading, shading_names())

    def set_rasterizer(self, rasterizer: str) -> None:
        self._set("rasterizer", rasterizer, RASTERIZERS)

    def _set(self, name: str, value: str, allowed) -> None:
        if value not in allowed:
            raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {value!r}")
        if value != getattr(self, name):
            setattr(self, name, value)
            self.dirty = True

    def set_headlight(self, on: bool) -> None:
        if bool(on) != self.headlight:
            self.headlight, self.dirty = bool(on), True

    def set_depth_shading(self, mode: str) -> None:
        """Depth shading by the distance from the eye ("view") or by height ("height")."""
        from core.shading.depth import MODES
        self._set("depth_shading", mode, MODES)

    @property
    def headlight_note(self) -> str:
        """The status line's words for the headlight: "" when it is off."""
        if not self.headlight:
            return ""
        from app.session.headlight import headlight_refused
        if self.playback is not None:
            return "headlight off on animated scenes: the scene's keyed lights are used"
        return headlight_refused(self.renderer_entry) or "headlight on: a light at the eye"

    def _lights_for(self, view):
        """None when the scene's own lights draw the next frame; else ``lit(scene)`` giving
        the scene lit by the headlight at ``view``'s eye (called on the rendering thread)."""
        from app.session.headlight import Headlights, headlight_refused
        if (not self.headlight or view is None or self.playback is not None
                or headlight_refused(self.renderer_entry)):
            return None
        if self._headlights is None:
            self._headlights = Headlights()
        headlights, projection = self._headlights, self.projection
        return lambda scene: headlights.lit(scene, self.scene_edits, view, projection)

    def drawn_scene(self):
        """The scene as the frame shown was drawn, for work beside the renderer (the
        inspector's records and buffer views): the course's .tri rules applied, and under the
        headlight a copy of its own lit at the eye (not the renderer's twin, which the
        worker's next frame relights)."""
        scene, view = self.scene, self.view
        if self._lights_for(view) is not None:
            import dataclasses
            from app.session.headlight import headlight
            from core.volume.data import attach_volumes, volumes_of
            lit = dataclasses.replace(scene, lights=[headlight(view, self.projection)])
            attach_volumes(lit, volumes_of(scene))
            scene = lit
        if self.course_tri and view is not None:
            from core.scene.course_tri import course_tri_scene
            scene = course_tri_scene(scene, view)
        return scene

    def set_lighting_model(self, name: str) -> None:
        """A registered lighting model for every material, or "" for each material's own."""
        from core.shading.models import lighting_model_names
        self._set("lighting_model", name, ("",) + lighting_model_names())

    def set_texture_filter(self, name: str) -> None:
        from core.texture.modes import FILTERS
        self._set("texture_filter", name, tuple(FILTERS))

    # -- the bump demo's mouse (J3DPanel): left click toggles bump/Phong, any other
    # button cycles the height maps. Only in a scene with the demo's material.
    def demo_click(self, left: bool) -> str | None:
        """The demo's click; returns its label, or None (the click keeps its usual meaning).
        The demo's material is set now and again by the next frame's job (on the worker's
        thread, so that a frame never sees it change half-way)."""
        if not self.is_bump_demo:
            return None
        if left:
            self.set_bump(not self.bump)
        else:
            self.next_bump_map()
        from core.texture.demo_scene import apply_demo_options
        return apply_demo_options(self.scene, self.bump_map, self.bump)
    # --

    def set_keep_aspect(self, keep: bool) -> None:
        if bool(keep) != self.keep_aspect:
            self.keep_aspect = bool(keep)
            self.dirty = True

    def set_course_tri(self, on: bool) -> None:
        if bool(on) != self.course_tri:
            self.course_tri = bool(on)
            self.dirty = True

    def resize(self, width: int, height: int) -> None:
        """The picture's new size in pixels; 0 x 0 (minimised) is kept but never rendered."""
        size = (max(int(width), 0), max(int(height), 0))
        if size != self.size:
            self.size = size
            # Restoring a minimised window to the size of the frame it shows needs no render.
            shown = None if self.frame is None else self.frame.color.shape[1::-1]
            if self.renderable and shown != size:
                self.dirty = True

    def open_scene(self, source: str | Path) -> bool:
        """Replace the scene by ``source``; on a reader error keep the current one.

        Returns whether it opened. A failure's message goes into :attr:`messages` — the user's
        scene, view and settings stay as they were; so does a file whose views are all
        invalid (its messages are shown, there is nothing of it to draw). A new scene starts
        at its first valid view with its own default settings.
        """
        if str(source).strip() == "-":            # the viewer's stdin is the terminal: refuse
            return self._open_failed("could not open -: a view file on standard input can only "
                                     "be given at start-up (python -m app view - < views)")
        try:
            scene = self.loader(source, size=self.size if self.renderable else None)
        except reader_errors() as error:
            reason = str(error)        # the readers' messages start with the file's name
            return self._open_failed(f"could not open {reason}" if reason.startswith(str(source))
                                     else f"could not open {source}: {reason}")
        if not scene.views:
            return self._open_failed(f"did not open {source}: none of its "
                                     f"{view_numbers.total(scene)} views is valid; "
                                     f"{self.scene.name} stays",
                                     [f"invalid view: {m}" for m in scene.view_messages])
        self.scene = scene
        self.scene_source = str(source)
        self.view_index, self.hand_view = 0, None
        self._scene_defaults()
        self.open_messages.clear()
        self.failed_open = ""
        self._camera_undo.clear()               # another scene's cameras mean nothing here
        self._camera_redo.clear()
        self.frame = None
        self.dirty = True
        return True

    def _open_failed(self, message: str, details: list[str] = ()) -> bool:
        self.open_messages.append(message)
        self.open_messages.extend(details)
        self.failed_open, self._clear_failed_open = message, False
        return False

    @property
    def problem(self) -> str:
        """The last error or refusal, for the top of the status line: a render that failed,
        the frame's own message (a renderer's refusal, an invalid view), a scene that did not
        open, a refused setting or volume edit; "" when all is well."""
        for text in (self.render_error, getattr(self.frame, "message", None), self.failed_open,
                     self.option_message, self.volume_message):
            if text:
                return text
        return ""

    def clear_messages(self) -> None:
        self.open_messages.clear()
        self.failed_open = ""

    # -- frames ------------------------------------------------------------------------------
    def _job(self):
        """What the next frame needs: ``run(control=None)`` that renders it (a
        :class:`app.viewer.worker.Control` lets it report progress, hand over pictures on the
        way and stop when superseded), and a short description.

        An animated scene draws the moment shown (particles and all); a ray-traced still is
        drawn progressively; everything else is one ``core.render``. The bump demo's map and
        mode are set on its material here, on the thread that renders.
        """
        base, view, settings, renderer = self.scene, self.view, self.settings(), self.renderer
        lights_for, course_tri = self._lights_for(view), self.course_tri and view is not None
        what = f"{self.view_label}, {self.projection}, {self.shading}"
        context = self.context
        demo = (self.bump_map, self.bump) if self.is_bump_demo else None
        playback = self.playback
        isos = {v: iso for v, iso in self.iso_wanted.items() if v.iso != iso}

        def prepare(control=None):
            """On the rendering thread: surfaces re-extracted, the demo's map set; returns
            the scene to draw (headlit, with the course's .tri rules)."""
            if isos:
                self._extract(base, isos, control)
            if demo is not None:
                from core.texture.demo_scene import apply_demo_options
                apply_demo_options(base, *demo)
            scene = base if lights_for is None else lights_for(base)
            if course_tri:
                from core.scene.course_tri import course_tri_scene
                scene = course_tri_scene(scene, view)
            return scene

        def picked(frame):
            """The frame with its depth kept for the pivot under the cursor (app.session.pick)
            and the readout: a copy of its own, since the context's buffer it points at is
            overwritten by the next frame while this one is still shown."""
            from app.session.pick import PICK_KEY, depth_pick
            pick = frame.stats[PICK_KEY] = depth_pick(frame, view, settings)
            if pick is not None:
                frame.depth = pick.depth
            return frame

        if playback is not None:
            from app.session.playback import render_animated
            t = playback.time
            # render_at numbers the keyed camera (when there is one) before the file's views
            keyed = 1 if playback.animation.view is not None else 0
            index = (self.hand_view if self.hand_view is not None     # the user's camera
                     else 0 if self.keyed_view else self.view_index + keyed)
            what = f"t = {t:.2f} s, {what}"

            def run(control=None):
                prepare(control)
                frame = render_animated(playback.animation, t, settings, context, index, control)
                frame.stats["time"] = t           # the moment drawn (the clock moves on)
                return picked(frame)
        elif view is not None and get_renderer(settings.renderer).progressive:
            progressively = get_renderer(settings.renderer).drawer()
            what = f"{what}, {get_renderer(settings.renderer).label.lower()}"

            def run(control=None):
                return picked(progressively(prepare(control), view, settings, context,
                                            renderer, control))
        else:
            def run(control=None):
                return picked(renderer(prepare(control), view, settings, context))
        return run, what

    def update(self) -> bool:
        """Render a new frame now if the picture changed; returns whether one was rendered.

        A stage that raises does not end the session: the error becomes a message (and its
        traceback goes to the log), the last good frame stays, and another mode or view can
        still be chosen.
        """
        if not self.dirty or not self.renderable:
            return False
        first_of_mode = self.shading not in self._modes_rendered
        watch = (announce_compiles(self.compile_notice_after) if first_of_mode
                 else contextlib.nullcontext())
        run, _ = self._job()
        self._clear_failed_open = bool(self.failed_open)
        start = time.perf_counter()
        try:
            with watch:
                frame = run()
        except Exception as error:
            self._failed(error)
            return False
        self._shown(frame, time.perf_counter() - start)
        return True

    def request(self, worker) -> bool:
        """Hand the next frame to ``worker`` (an :class:`app.viewer.worker.RenderWorker`) if
        the picture changed; a request still waiting there is replaced. Returns whether one
        was made; the frame arrives through :meth:`accept`. Until it does, a picture the
        worker finishes for an older request of the same scene may still come (a camera that
        moves faster than frames are drawn); another scene's never does."""
        if not self.dirty or not self.renderable:
            return False
        run, what = self._job()
        if self.gate is not None:
            run = self.gate(run)
        worker.submit(run, what, control=True, keep_older=self.scene is self._requested_scene)
        self._clear_failed_open = bool(self.failed_open)    # its frame is the next success
        self._requested_scene = self.scene
        self.dirty = False
        return True

    def accept(self, result) -> bool:
        """Take a finished request (or a picture on its way: ``result.final`` False) from the
        worker; returns whether a new frame is shown."""
        if result.error is not None:
            self._failed(result.error)
            return False
        if not getattr(result, "final", True):
            self.frame, self.frame_partial = result.frame, True
            self.frame_seconds = result.seconds
            return True
        self._shown(result.frame, result.seconds)
        return True

    def _failed(self, error: BaseException) -> None:
        from core.volume.data import VolumeError
        if isinstance(error, VolumeError) and self.extracting:
            # the surface could not be re-extracted: the last good one stays, and is asked for
            self.volume_message = f"{error}; the surface stays at the last good iso"
            self.iso_wanted = {v: v.iso for v in self.iso_wanted}
            log.info("volume: %s", self.volume_message)
            self.dirty = False
            return
        self.render_error = (f"could not render {self.view_label} "
                             f"({self.projection}, {self.shading}): "
                             f"{type(error).__name__}: {error}")
        log.error("%s", self.render_error, exc_info=error)
        self.dirty = False

    def _shown(self, frame, seconds: float) -> None:
        self.frame, self.render_error, self.frame_partial = frame, None, False
        if self._clear_failed_open:
            self.failed_open, self._clear_failed_open = "", False
        self.frame_seconds = seconds
        self._modes_rendered.add(self.shading)
        self.frame_count += 1
        self.dirty = False

    # -- the volume controls ---------------------------------------------------------------
    @property
    def volumes(self) -> list:
        """The scene's volumes (``[[volume]]`` tables), in file order."""
        from app.session.volume_controls import scene_volumes
        return scene_volumes(self.scene)

    @property
    def volume(self):
        """The volume the controls act on, or None."""
        found = self.volumes
        return found[min(self.volume_index, len(found) - 1)] if found else None

    def select_volume(self, index: int) -> None:
        if not 0 <= index < max(len(self.volumes), 1):
            raise ValueError(f"volume index must be in 0..{len(self.volumes) - 1}, not {index}")
        self.volume_index, self.slice_index = int(index), None

    @property
    def extracting(self) -> bool:
        """Is an isosurface asked for that the worker has not extracted yet?"""
        return any(v.iso != iso for v, iso in self.iso_wanted.items())

    def iso_shown(self, volume) -> float | None:
        """The iso value the slider shows: the one asked for, else the volume's."""
        return self.iso_wanted.get(volume, volume.iso)

    def set_iso(self, iso: float) -> bool:
        """Ask for the current volume's isosurface at ``iso`` (marching cubes runs in the next
        frame's job). Outside the data's range: a message, and the last good surface stays."""
        from app.session.volume_controls import checked_iso
        from core.volume.data import VolumeError
        volume = self.volume
        if volume is None or volume.mode != "isosurface":
            self.volume_message = "iso: this volume is not drawn as an isosurface"
            return False
        try:
            iso = checked_iso(volume, iso)
        except VolumeError as error:
            self.volume_message = f"{error}; the surface stays at iso {self.iso_shown(volume):g}"
            return False
        self.volume_message = ""
        if iso != self.iso_shown(volume):
            self.iso_wanted[volume] = iso
            self.dirty = True
        return True

    def _extract(self, scene, isos: dict, control=None) -> None:
        """On the worker's thread: marching cubes for each iso asked for, then the scene's
        caches are dropped (its meshes changed in place)."""
        from app.session.volume_controls import reextract
        for volume, iso in isos.items():
            if control is not None:
                control.check()
                control.report(0.0, f"extracting {volume.name} at iso {iso:g}…")
            count = reextract(scene, volume, iso)
            log.info("volume: %s re-extracted at iso %r: %d triangles", volume.name, iso, count)
        self.context.forget(scene)
        self.scene_edits += 1              # other contexts (the inspector's) drop theirs too

    def move_transfer_point(self, index: int, value: float, alpha: float) -> bool:
        """Move the current volume's transfer point ``index`` to ``value`` with extinction
        ``alpha``; a bad point (alpha < 0, values out of order) gets a message and the last
        good transfer function stays."""
        import numpy as np
        from app.session.volume_controls import moved_transfer
        from core.volume.data import VolumeError
        volume = self.volume
        if volume is None or volume.transfer is None:
            self.volume_message = "transfer: this volume has no transfer function"
            return False
        try:
            transfer = moved_transfer(volume.transfer, index, value, alpha)
        except VolumeError as error:
            self.volume_message = f"{error}; the last good transfer function stays"
            return False
        self.volume_message = ""
        if not np.array_equal(transfer, volume.transfer):
            volume.transfer = transfer       # a new array: a frame being drawn keeps the old
            self.dirty = True
        return True

    def set_slice(self, name: str, index: int | None = None) -> None:
        """The slice the buffer view shows: ``name`` (axial, coronal, sagittal) and its index
        (None: the middle); an index past the end is refused."""
        from app.session.volume_controls import SLICE_AXIS, SLICES
        if name not in SLICE_AXIS:
            raise ValueError(f"slice must be one of {', '.join(SLICES)}, not {name!r}")
        if index is not None and self.volume is not None:
            n = self.volume.values.shape[SLICE_AXIS[name]]
            if not 0 <= index < n:
                raise ValueError(f"{name} slice index must be in 0..{n - 1}, not {index}")
        self.slice_name, self.slice_index = name, index

    def slice_shown(self) -> int:
        """The index of the slice shown (the middle one when none was chosen)."""
        from app.session.volume_controls import SLICE_AXIS
        n = self.volume.values.shape[SLICE_AXIS[self.slice_name]]
        return n // 2 if self.slice_index is None else min(self.slice_index, n - 1)
