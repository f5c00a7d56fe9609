"""The viewer's state: the one place it lives, and the only thing that asks the core for frames.

:class:`ViewerState` holds the scene and where it came from, the view index, the render
settings the user chose (projection, shading, rasterizer, kept aspect, the ``.tri`` startup
code's rules), the picture's size, the messages to show (invalid views from the reader, in
their own collapsed strip; scenes that could not be opened; the current frame's own message),
the last :class:`core.render.Frame` and a ``dirty`` flag. The window changes it through its
parts' methods and reads it to draw; a frame is rendered only when something that changes the
picture changed, and never for a zero-sized (minimised) framebuffer: at once
(``state.frames.update()``, for the PNG path and the tests) or on the render worker's thread
(``state.frames.request(worker)``, then ``state.frames.accept(result)``, for the window).

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

It is one dataclass that holds its parts, one job each, as attributes; each part reads and
changes the state's fields through its ``state``: ``views``, the view shown and the camera's
history (:mod:`app.session.views`); ``choices``, the render settings chosen and the
:class:`core.settings.RenderSettings` they make (:mod:`app.session.choices`); ``lighting``, the
headlight (:mod:`app.session.headlight`); ``player``, playing an animation
(:mod:`app.session.playback`); ``messages``, what there is to say
(:mod:`app.session.messages`); ``volumes``, the volume controls (:mod:`app.session.volumes`);
and ``frames``, the frames asked for and taken (:mod:`app.session.frames`). Held, not
inherited: a mixin's methods would all land on the one class. Opening a scene and the
picture's size are here.

No GL and no window library here, so everything about it is testable without a display.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from app.session.choices import RenderChoices, bump_demos
# render, announce_compiles and compile_count: the front door's callers import them from here
from app.session.frames import (FrameRequests, announce_compiles, compile_count,  # noqa: F401
                                render)
from app.session.headlight import Lighting
from app.session.messages import Messages
from app.session.playback import Player
from app.session.views import CameraViews
from app.session.volumes import VolumeChoices
from core.scene import view_numbers
from core.scene.model import Scene


def load_scene(source: str | Path, size: tuple[int, int] | None = None,
               crease_angle: float | None = None) -> Scene:
    """``core.scene.formats.load_scene``, imported when first needed (it pulls in the readers)."""
    from core.scene.formats import load_scene as load
    return load(source, size=size, crease_angle=crease_angle)


def reader_errors() -> tuple[type[BaseException], ...]:
    """What a failed open raises: the readers' own error, and the OS's for unreadable paths."""
    from core.scene.formats import ReaderError
    return (ReaderError, OSError)


def _part():
    """A field for one of the state's parts: made by ``__post_init__``, left out of the
    constructor, the repr and comparisons (each part points back at the state)."""
    return field(init=False, repr=False, compare=False)


@dataclass
class ViewerState:
    """Scene, settings, messages and the last frame. Change it only through its parts'
    methods (and the few here that concern it whole: opening a scene, the picture's size).

    Every field is declared here, the one place the viewer's state lives; what is done with
    them is in the parts it holds, one job each (the modules beside this one)."""

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
    # The parts, each with its own job over the fields above (made in __post_init__).
    views: CameraViews = _part()
    choices: RenderChoices = _part()
    lighting: Lighting = _part()
    player: Player = _part()
    messages: Messages = _part()
    volumes: VolumeChoices = _part()
    frames: FrameRequests = _part()

    def __post_init__(self) -> None:
        self.views, self.choices = CameraViews(self), RenderChoices(self)
        self.lighting, self.player = Lighting(self), Player(self)
        self.messages, self.volumes = Messages(self), VolumeChoices(self)
        self.frames = FrameRequests(self)
        self._scene_defaults(keep_settings=True)
        self.size = (int(self.size[0]), int(self.size[1]))
        if self.context is None:
            from core.context import RenderContext
            self.context = RenderContext()

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

    def resize(self, width: int, height: int) -> None:
        """The picture's new size in pixels; 0 x 0 (minimised) is kept but never rendered."""
        size = (max(int(width), 0), max(int(height), 0))
        if size != self.size:
            self.size = size
            # Restoring a minimised window to the size of the frame it shows needs no render.
            shown = None if self.frame is None else self.frame.color.shape[1::-1]
            if self.renderable and shown != size:
                self.dirty = True

    @property
    def renderable(self) -> bool:
        """A zero-sized framebuffer (a minimised window) is never rendered."""
        return self.size[0] > 0 and self.size[1] > 0

    def open_scene(self, source: str | Path) -> bool:
        """Replace the scene by ``source``; on a reader error keep the current one.

        Returns whether it opened. A failure's message goes into the messages — the user's
        scene, view and settings stay as they were; so does a file whose views are all
        invalid (its messages are shown, there is nothing of it to draw). A new scene starts
        at its first valid view with its own default settings.
        """
        failed = self.messages.open_failed
        if str(source).strip() == "-":            # the viewer's stdin is the terminal: refuse
            return failed("could not open -: a view file on standard input can only "
                          "be given at start-up (python -m app view - < views)")
        try:
            scene = self.loader(source, size=self.size if self.renderable else None)
        except reader_errors() as error:
            reason = str(error)        # the readers' messages start with the file's name
            return failed(f"could not open {reason}" if reason.startswith(str(source))
                          else f"could not open {source}: {reason}")
        if not scene.views:
            return failed(f"did not open {source}: none of its "
                          f"{view_numbers.total(scene)} views is valid; {self.scene.name} stays",
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
