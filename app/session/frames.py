"""The frames the window asks for: the next frame's job (built on the UI thread, run on the
render worker's), rendered at once (:meth:`FrameRequests.update`, for the PNG path and the
tests) or on the worker (:meth:`FrameRequests.request`, then :meth:`FrameRequests.accept`), and
numba's compiles heard while they run (the slow first frame's notice, the window's progress).

:class:`FrameRequests` is the ``frames`` part of :class:`app.session.state.ViewerState`, which
holds the fields (``frame``, ``dirty``, ``render_error``, ...).
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time

from core.registry import get_renderer

log = logging.getLogger("fvd")


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


class FrameRequests:
    """The next frame: its job, asked for and taken; the last frame's summary
    (``state.frames``)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here
        self.generation = 0       # the worker's number for the last request made

    def summary(self) -> str:
        """One log line for the last frame: which view, settings, size and time."""
        s, views = self.state, self.state.views
        label = views.current.label if views.count else "-"
        message = getattr(s.frame, "message", None)
        stats = getattr(s.frame, "stats", None) or {}
        moment = f" t={stats['time']:.3f}" if "time" in stats else ""
        return (f"frame {s.frame_count}: {views.label} ({label}) "
                f"projection={s.projection} shading={s.shading} "
                f"renderer={s.renderer_name} filter={s.texture_filter}{moment} "
                f"rasterizer={s.rasterizer} aspect={'kept' if s.keep_aspect else 'stretched'} "
                f"size={s.size[0]}x{s.size[1]} render={s.frame_seconds * 1e3:.1f}ms"
                + (" camera=moved" if s.hand_view is not None else "")
                + (f" message={message!r}" if message else ""))

    def job(self):
        """What the next frame needs: ``run(control=None)`` that renders it (a
        :class:`app.viewer.worker.Control` lets it report progress, hand over pictures on the
        way and stop when superseded), and a short description.

        An animated scene draws the moment shown (particles and all); a ray-traced still is
        drawn progressively; everything else is one ``core.render``. The bump demo's map and
        mode are set on its material here, on the thread that renders.
        """
        s = self.state
        base, view, settings, renderer = s.scene, s.views.current, s.choices.settings(), s.renderer
        lights_for, course_tri = s.lighting.lights_for(view), s.course_tri and view is not None
        what = f"{s.views.label}, {s.projection}, {s.shading}"
        context = s.context
        demo = (s.bump_map, s.bump) if s.choices.is_bump_demo else None
        playback = s.playback
        isos = {v: iso for v, iso in s.iso_wanted.items() if v.iso != iso}
        extract = s.volumes.extract

        def prepare(control=None):
            """On the rendering thread: surfaces re-extracted, the demo's map set; returns
            the scene to draw (headlit, with the course's .tri rules)."""
            if isos:
                extract(base, isos, control)
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
            index = (s.hand_view if s.hand_view is not None     # the user's camera
                     else 0 if s.keyed_view else s.view_index + keyed)
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
        s = self.state
        if not s.dirty or not s.renderable:
            return False
        first_of_mode = s.shading not in s._modes_rendered
        watch = (announce_compiles(s.compile_notice_after) if first_of_mode
                 else contextlib.nullcontext())
        run, _ = self.job()
        s._clear_failed_open = bool(s.failed_open)
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
        was made (its generation in :attr:`generation`); the frame arrives through
        :meth:`accept`. Until it does, a picture the worker finishes for an older request of
        the same scene may still come (a camera that moves faster than frames are drawn);
        another scene's never does."""
        s = self.state
        if not s.dirty or not s.renderable:
            return False
        run, what = self.job()
        if s.gate is not None:
            run = s.gate(run)
        self.generation = worker.submit(run, what, control=True,
                                        keep_older=s.scene is s._requested_scene)
        s._clear_failed_open = bool(s.failed_open)    # its frame is the next success
        s._requested_scene = s.scene
        s.dirty = False
        return True

    def accept(self, result) -> bool:
        """Take a finished request (or a picture on its way: ``result.final`` False) from the
        worker; returns whether a new frame is shown."""
        s = self.state
        if result.error is not None:
            self._failed(result.error)
            return False
        if not getattr(result, "final", True):
            s.frame, s.frame_partial = result.frame, True
            s.frame_seconds = result.seconds
            return True
        self._shown(result.frame, result.seconds)
        return True

    def _failed(self, error: BaseException) -> None:
        from core.volume.data import VolumeError
        s = self.state
        if isinstance(error, VolumeError) and s.volumes.extracting:
            # the surface could not be re-extracted: the last good one stays, and is asked for
            s.volume_message = f"{error}; the surface stays at the last good iso"
            s.iso_wanted = {v: v.iso for v in s.iso_wanted}
            log.info("volume: %s", s.volume_message)
            s.dirty = False
            return
        s.render_error = (f"could not render {s.views.label} "
                          f"({s.projection}, {s.shading}): "
                          f"{type(error).__name__}: {error}")
        log.error("%s", s.render_error, exc_info=error)
        s.dirty = False

    def _shown(self, frame, seconds: float) -> None:
        s = self.state
        s.frame, s.render_error, s.frame_partial = frame, None, False
        if s._clear_failed_open:
            s.failed_open, s._clear_failed_open = "", False
        s.frame_seconds = seconds
        s._modes_rendered.add(s.shading)
        s.frame_count += 1
        s.dirty = False
