"""The window's loop and the frames coming in: sleep until an event (or a frame, or the
movie's clock), then input, clicks, ask the worker for the next frame and take the one it
finished, build the GUI, blit the picture and swap. Also the kernels: compiled in worker
processes while the cache is cold (:mod:`app.viewer.kernels`), loaded in the background after
the first frame otherwise.
"""

from __future__ import annotations

import logging
import os
import sys
import time

from imgui_bundle import imgui  # noqa: I001  (first: it names the library glfw loads)
import glfw

from app import startup_gc
from app.session.state import compile_count
from app.viewer.blit import clear_around
from app.viewer.latency import InputLatency

log = logging.getLogger("fvd")
# While a camera gesture waits for its frame, the window is drawn again at most this often.
GESTURE_REDRAW_S = 1 / 30
# After an event, draw a few frames so that ImGui's hover and menu states settle; then sleep
# until the next event (a busy loop would take the CPU the rasterizer needs).
FRAMES_AFTER_EVENT = 3
WINDOW_GREY = (0.11, 0.11, 0.13, 1.0)      # the window behind the picture and the panel


class FrameLoop:
    """The loop, the frames in, the picture drawn; the kernels' warm-up."""

    def __init__(self, win):
        self.win, self.state = win, win.state
        self.warmup = None                # the kernels' worker processes (a cold cache)
        self._kernels_logged = False
        self._first_frame_logged = False
        self._warming = False
        self._warm_up_due = False
        self.compiles_at_request = 0
        self._swapped_at, self._picture_new = 0.0, False    # the last redraw; a picture since
        self.latency = InputLatency()     # from an input to the picture that shows it
        self._on_screen: int | None = None    # the request of a picture due on screen
        self._input_waits = False         # an input's picture is on its way
        self._swap_s = self._swapped_cpu = 0.0    # the last swap's length; the thread's CPU then

    def run(self) -> int:
        try:
            # Show the window (panel, the scene's background) before the first CPU frame: that
            # frame may wait for numba to load or compile its kernels.
            self.draw_frame()
            self._log_since_start("window shown")
            shown = True
            while not glfw.window_should_close(self.win.window):
                self._wait(shown)
                shown = self.draw_frame()
        finally:
            self.win.close()
        return 0

    def _wait(self, shown: bool) -> None:
        """Sleep until an event unless a frame is due; while the worker renders, wake ten
        times a second to show how long it has taken (it wakes us when done)."""
        if shown and self._redraw_can_wait():
            # a drag waits for its frame: sleep until the next pointer move, the frame, or
            # the next redraw (polling here spun 600 times a second and took a third of a
            # core, and the GIL, from the renderer)
            glfw.wait_events_timeout(max(1e-3, GESTURE_REDRAW_S
                                         - (time.perf_counter() - self._swapped_at)))
        elif shown and (self.win.busy > 0 or self.state.dirty):
            glfw.poll_events()
        elif self.state.player.playing:
            glfw.wait_events_timeout(1 / 60)     # the movie's clock moves on
        elif self.win.worker.waiting or self.win.tools.busy:
            glfw.wait_events_timeout(0.1)
        else:
            glfw.wait_events_timeout(0.5)

    def draw_frame(self) -> bool:
        """Input, clicks, ask for / collect a frame, GUI, blit, swap; False when minimised."""
        started, cpu = time.perf_counter(), time.thread_time()
        drawn = self._draw_frame()
        self.latency.drawn(self.state.dirty)
        if self._on_screen is not None and self._swapped_at >= started:
            self._log_on_screen(self._on_screen, self._swapped_at - started,
                                self._swapped_cpu - cpu)
            self._on_screen = None
        return drawn

    def _log_on_screen(self, generation: int, own: float, cpu: float) -> None:
        """A new picture was swapped onto the screen: the window's own time to draw it (and
        of that, this thread's CPU and the swap), and how long after the input it answers
        (``python -m app bench --window`` reads them)."""
        waited = self.latency.shown(generation, self._swapped_at)
        log.info("on screen: request %d, the window's own %.1f ms (CPU %.1f ms, swap "
                 "%.1f ms)%s", generation, 1e3 * own, 1e3 * cpu, 1e3 * self._swap_s,
                 "" if waited is None else f", {1e3 * waited:.0f} ms after the input")

    def _draw_frame(self) -> bool:
        """:meth:`draw_frame`'s work, without the bookkeeping of the picture it showed."""
        fb_w, fb_h = self.win.sizes.framebuffer
        self.win.fit_picture()
        if fb_w <= 0 or fb_h <= 0 or self.win.sizes.iconified:
            self.win.pointer.clicks.clear()
            self.win.busy = 0
            return False                  # minimised: nothing to render or draw
        self.win.busy -= 1
        self.win.input.new_frame()
        self.win.gui.new_frame()
        imgui.new_frame()
        self.win.pointer.handle_clicks()

        self._frames_in()
        if self.win.worker.waiting:
            self.win.tools.note_progress(self.win.worker.progress().fraction)
        if self._redraw_can_wait():
            imgui.end_frame()             # nothing new to show: the renderer keeps the CPU
            return True
        self.win.panel.build()
        imgui.render()

        self._draw_picture(fb_w, fb_h)
        self.win.gui.render(imgui.get_draw_data())
        swap = time.perf_counter()
        glfw.swap_buffers(self.win.window)
        self._swapped_at, self._picture_new = time.perf_counter(), False
        self._swap_s, self._swapped_cpu = self._swapped_at - swap, time.thread_time()
        if not self._first_frame_logged and self.state.frame is not None:
            self._first_frame_logged = True
            self._log_since_start("first frame shown")
            startup_gc.resume()
        elif (self.win.started is not None
              and time.perf_counter() - self.win.started > startup_gc.LATEST_S):
            startup_gc.resume()
        if self._warm_up_due:
            self._warm_up_due = False
            self._start_warm_up()
        return True

    def _redraw_can_wait(self) -> bool:
        """While a camera gesture, or an input whose picture is on its way (a shading key, a
        wheel turn), waits for its frame and no new picture came, the window need not be
        drawn again at every event (each redraw of the panel and the picture costs the
        software GL a few ms of the CPU the renderer is using): at most every
        ``GESTURE_REDRAW_S``. No panel widget is active during a gesture on the picture, and
        the panel settles at that rate, so skipping frames loses nothing. (Eight shading keys
        a second on the bunny at 500 x 500, in turns: each key's frame drew in 29 and 24 ms
        beside the three redraws after each key, in 21 ms without them.)"""
        drag = self.win.hands.drag
        gesture = drag is not None and drag.start is not None
        return ((gesture or self._input_waits) and not self._picture_new
                and time.perf_counter() - self._swapped_at < GESTURE_REDRAW_S)

    def _frames_in(self) -> None:
        """Ask the worker for the next frame and take the one it finished, if any."""
        self._note_kernels()
        self.win.files.poll_dialog()
        self.state.player.tick(time.perf_counter(), busy=self.win.worker.waiting)
        if self.state.frames.request(self.win.worker):
            self.compiles_at_request = compile_count()
            self._input_waits = self.latency.requested(self.state.frames.generation)
        self.win.tools.poll()                 # a buffer view, a record, a comparison: done?
        result = self.win.worker.collect()
        if result is not None:
            self._input_waits = False     # answered (a picture, or a message of what failed)
        if result is not None and self.state.frames.accept(result):
            if getattr(result, "final", True):
                self._log_frame()
                self._warm_up_due = True  # once this frame is on screen (the thread takes the GIL)
                self.win.tools.frame_changed(self.state.frame, self.state.frame_seconds)
            else:
                log.info("partial frame: %s (%s)", result.what,
                         self.state.frame.stats.get("pass", "on its way"))
                self.win.tools.note_convergence(self.state.frame.stats)
            self.win.blit.upload(self.win.tools.picture(self.state.frame))
            self.win.tools.changed = False
            self._picture_new, self._on_screen = True, result.generation
            self.win.wake()                  # the GUI shows the new frame's plan and timing next
        if self.win.tools.changed and self.state.frame is not None:
            self.win.blit.upload(self.win.tools.picture(self.state.frame))
            self.win.tools.changed, self._picture_new = False, True

    def _draw_picture(self, fb_w: int, fb_h: int) -> None:
        """Clear, then blit the picture inside its own area."""
        self.win.ctx.viewport = (0, 0, fb_w, fb_h)
        if self.state.frame is None or not self.state.renderable:
            self.win.ctx.clear(*WINDOW_GREY)
        else:
            clear_around(self.win.ctx, (fb_w, fb_h), self.state.size, WINDOW_GREY)
        if self.state.frame is not None and self.state.renderable:
            # after a scene change, never the old scene's picture; and only inside the picture's
            # area, so a frame of the old, larger size never shows under the panel
            # a frame of another size (resized, the new one due) is stretched over the picture
            width, height = self.state.size
            origin = (0, fb_h - height)   # the picture's bottom-left, GL counts rows up
            self.win.ctx.viewport = (*origin, width, height)
            self.win.ctx.scissor = (0, fb_h - self.state.size[1], *self.state.size)
            self.win.blit.draw(origin, shown=(width, height))
            self.win.ctx.scissor = None
            self.win.ctx.viewport = (0, 0, fb_w, fb_h)

    def start_kernel_processes(self) -> None:
        """A cold kernel cache: compile it in worker processes, and gate the frames on it
        (app/viewer/kernels.py); a warm one needs nothing."""
        from app.distribution.background_warmup import BackgroundWarmup
        from app.distribution.warm_stamp import is_warm
        if is_warm():
            return
        from app.viewer.kernels import gated
        try:
            self.warmup = BackgroundWarmup(first_scene=self.state.scene_source,
                                           on_event=glfw.post_empty_event)
        except OSError as error:          # no process could be started: compile here instead
            log.warning("could not start the kernel warm-up processes: %s", error)
            return
        log.info("kernel cache cold: compiling the kernels in worker processes (log: %s)",
                 self.warmup.log_path)
        self._kernels_logged = False
        self.state.gate = lambda run: gated(run, self.warmup, self.state.scene_source)

    def _note_kernels(self) -> None:
        """Once the warm-up's processes are done: say so, and stop gating frames."""
        if self.warmup is None or not self.warmup.finished or self._kernels_logged:
            return
        self._kernels_logged = True
        self.state.gate = None
        if self.warmup.ok:
            self._log_since_start("all kernels ready")
        else:
            log.warning("kernel warm-up failed: %s", "; ".join(self.warmup.failed) or "see above")
        self.win.wake()

    def _start_warm_up(self) -> None:
        """After the first frame: load (or compile) every other kernel in the background."""
        if self._warming or self.warmup is not None:
            return                        # worker processes compile them, not this one
        self._warming = True
        from app.distribution.warmup_steps import steps
        self.win.worker.add_background(steps())

    def _log_since_start(self, what: str) -> None:
        if self.win.started is None:
            log.info("%s", what)
        else:
            # CPU seconds too: on a busy machine the wall time says more about the neighbours.
            user, system = os.times()[:2]
            log.info("%s %.3f s after process start (%.3f s CPU)", what,
                     time.perf_counter() - self.win.started, user + system)

    def _log_frame(self) -> None:
        log.info("%s", self.state.frames.summary())
        if self.state.frame.message:
            print(self.state.frame.message, file=sys.stderr)
        self.win.sizes.set_title(self.win.title())
