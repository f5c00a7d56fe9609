"""The viewer's state: the one place it lives, and the only thing that asks the core for frames.

:class:`ViewerState` holds the scene and where it came from, the view index, projection and
shading, the framebuffer size, the messages to show (invalid views from the reader, scenes
that could not be opened, the current frame's own message), the last :class:`core.render.Frame`
and a ``dirty`` flag. The window changes it through its methods and reads it to draw; a frame
is rendered (``core.render.render``) only when something that changes the picture changed, and
never for a zero-sized (minimised) framebuffer.

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

from core.scene.model import Scene
from core.settings import PROJECTIONS, SHADINGS

log = logging.getLogger("fvd")


def load_scene(source: str | Path, size: tuple[int, int] | None = None) -> Scene:
    """``core.scene.formats.load_scene``, imported when first needed (it pulls in the readers)."""
    from core.scene.formats import load_scene as load
    return load(source, size=size)


def render(scene, view_index, projection, shading, size):
    """``core.render.render``, imported when first needed.

    A wireframe needs no compiled kernel, so numba is imported (to listen for compiles) only
    when a frame will draw triangles; the default scene's first frame then skips it entirely.
    """
    from core.render import render as render_frame
    if (shading or scene.shading) != "wireframe" and scene.triangle_count:
        _listen_for_compiles()
    return render_frame(scene, view_index, projection, shading, size)


# Set when numba starts compiling a kernel (a cache miss), so that the slow-frame notice
# speaks of compiling only when it is true: loading cached kernels takes ~0.5 s too.
_compiling = threading.Event()
_listening: list[bool] = []


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
        print("compiling the rasterizer (first start only)…", file=sys.stderr, flush=True)


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
    view_index: int = 0
    open_messages: list[str] = field(default_factory=list)   # scenes that failed to open
    frame: object | None = None                              # the last core.render.Frame
    frame_seconds: float = 0.0                               # how long that frame took
    frame_count: int = 0
    render_error: str | None = None                          # the last render that raised
    dirty: bool = True
    renderer: Callable = render
    loader: Callable = load_scene
    # The first frame of each shading mode may compile numba kernels (seconds, once: numba
    # caches them on disk). Say so when it takes longer than this.
    compile_notice_after: float = 0.5
    _modes_rendered: set = field(default_factory=set, repr=False)

    def __post_init__(self) -> None:
        self.projection = self.projection or self.scene.projection
        self.shading = self.shading or self.scene.shading
        self.size = (int(self.size[0]), int(self.size[1]))

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
        return len(self.scene.views)

    @property
    def view_label(self) -> str:
        """``"view k of N"`` (k counts from 1), or why there is nothing to show."""
        if not self.view_count:
            return "no valid view"
        return f"view {self.view_index + 1} of {self.view_count}"

    @property
    def messages(self) -> list[str]:
        """Everything the user should read: reader messages, failed opens, this frame's message."""
        found = [f"invalid view: {m}" for m in self.scene.view_messages] + list(self.open_messages)
        message = getattr(self.frame, "message", None)
        if message:
            found.append(message)
        if self.render_error:
            found.append(self.render_error)
        return found

    def frame_summary(self) -> str:
        """One log line for the last frame: which view, projection, shading, size and time."""
        label = self.scene.views[self.view_index].label if self.view_count else "-"
        message = getattr(self.frame, "message", None)
        return (f"frame {self.frame_count}: view {self.view_index + 1 if self.view_count else 0} "
                f"of {self.view_count} ({label}) projection={self.projection} "
                f"shading={self.shading} size={self.size[0]}x{self.size[1]} "
                f"render={self.frame_seconds * 1e3:.1f}ms"
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
        if self.view_count:
            self.view_index = (self.view_index + step) % self.view_count
            self.dirty = True

    def set_view(self, index: int) -> None:
        if not 0 <= index < max(self.view_count, 1):
            raise ValueError(f"view index must be in 0..{self.view_count - 1}, not {index}")
        if index != self.view_index:
            self.view_index = index
            self.dirty = True

    def set_projection(self, projection: str) -> None:
        if projection not in PROJECTIONS:
            raise ValueError(
                f"projection must be one of {', '.join(PROJECTIONS)}, not {projection!r}")
        if projection != self.projection:
            self.projection = projection
            self.dirty = True

    def set_shading(self, shading: str) -> None:
        if shading not in SHADINGS:
            raise ValueError(f"shading must be one of {', '.join(SHADINGS)}, not {shading!r}")
        if shading != self.shading:
            self.shading = shading
            self.dirty = True

    def resize(self, width: int, height: int) -> None:
        """The framebuffer's new size in pixels; 0 x 0 (minimised) is kept but never rendered."""
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
        scene, view and settings stay as they were. A new scene starts at its first view with
        its own default projection and shading.
        """
        if str(source).strip() == "-":            # the viewer's stdin is the terminal: refuse
            self.open_messages.append("could not open -: a view file on standard input can only "
                                      "be given at start-up (python -m app view - < views)")
            return False
        try:
            scene = self.loader(source, size=self.size if self.renderable else None)
        except reader_errors() as error:
            reason = str(error)        # the readers' messages start with the file's name
            self.open_messages.append(f"could not open {reason}" if reason.startswith(str(source))
                                      else f"could not open {source}: {reason}")
            return False
        self.scene = scene
        self.scene_source = str(source)
        self.view_index = 0
        self.projection = scene.projection
        self.shading = scene.shading
        self.open_messages.clear()
        self.frame = None
        self.dirty = True
        return True

    def clear_messages(self) -> None:
        self.open_messages.clear()

    # -- frames ------------------------------------------------------------------------------
    def update(self) -> bool:
        """Render a new frame if the picture changed; returns whether one was rendered.

        A stage that raises does not end the session: the error becomes a message (and its
        traceback goes to the log), the last good frame stays, and another mode or view can
        still be chosen.
        """
        if not self.dirty or not self.renderable:
            return False
        first_of_mode = self.shading not in self._modes_rendered
        watch = (announce_compiles(self.compile_notice_after) if first_of_mode
                 else contextlib.nullcontext())
        start = time.perf_counter()
        try:
            with watch:
                frame = self.renderer(self.scene, self.view_index, self.projection,
                                      self.shading, self.size)
        except Exception as error:
            self.render_error = (f"could not render view {self.view_index + 1} "
                                 f"({self.projection}, {self.shading}): "
                                 f"{type(error).__name__}: {error}")
            log.error("%s", self.render_error, exc_info=True)
            self.dirty = False
            return False
        self.frame, self.render_error = frame, None
        self.frame_seconds = time.perf_counter() - start
        self._modes_rendered.add(self.shading)
        self.frame_count += 1
        self.dirty = False
        return True
