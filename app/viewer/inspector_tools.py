"""The window's inspector tools: inspect mode, buffer views, the OpenGL comparison
and the plots. Nothing here runs while it is off: a frame costs what it cost before, and start-up
imports nothing more (the inspector's modules load on first use).

- ``i`` (View menu): inspect mode; a left click on the picture then shows that pixel's record
  in the panel (:func:`core.inspect.inspect_pixel`, the same record ``python -m app inspect``
  prints) instead of advancing the view; the record is logged as one JSON line.
- ``v`` (View > Buffer view): the picture, then each buffer view the frame has (depth,
  normal, triangle id, barycentrics, (u, v), MIP level, overdraw, ray-tree depth), then in a
  scene with volumes its axial, coronal and sagittal slices
  (:mod:`app.session.volume_controls`), in place of the picture; the panel says which.
- View > Compare with OpenGL: the same view drawn by real OpenGL (the GLSL oracle), held
  against the frame; the heat map takes the picture's place and ``h`` flips between the two.
- Plots: the last frames' times, and a progressive frame's progress, in the panel.

Nothing long runs on the UI thread: a pixel's record, a buffer view, the aliasing view (16
samples a pixel) and the OpenGL comparison are drawn on a thread of their own, one at a time
(:meth:`InspectorTools.off_thread`); the status line says what is being drawn
(:attr:`InspectorTools.busy`) and the window applies the result when it is done
(:meth:`InspectorTools.poll`, on the UI thread), so every key is answered at once.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
from collections import deque

import numpy as np

log = logging.getLogger("fvd")

PICTURE = "picture"
# The status line names the triangle under the cursor for scenes up to this size: its buffer
# is one more z-buffer pass a frame, in a fresh context (116 ms at 500 x 500 for the
# 74k-triangle bunny, median of 7, beside its 16 ms frame), on the picker's thread.
MAX_PICKED = 100_000
# The aliasing buffer view: the same frame aliased (left) and antialiased (right): 16
# samples a pixel through the Mitchell-Netravali filter, or Wu's lines for a wireframe.
ALIASING = "aliasing"
ALIASED = {"samples": 1, "pixel_filter": "box", "filter_radius": None, "antialias_lines": False}
ANTIALIASED = {"samples": 16, "pixel_filter": "mitchell", "filter_radius": None,
               "antialias_lines": True}
# A wireframe's lines are antialiased by Wu's coverage at one sample a pixel: supersampled,
# the renderer draws them one sample wide, a quarter of their ink at 16 samples.
ANTIALIASED_LINES = {**ALIASED, "antialias_lines": True}


class InspectorTools:
    def __init__(self, state):
        self.state = state
        self.inspecting = False
        self.record: dict | None = None
        self.lines: list[str] = []
        self.buffer = PICTURE
        self.overlay: np.ndarray | None = None     # (H, W, 4) shown instead of the frame
        self.heat: np.ndarray | None = None        # the comparison's heat map, (H, W, 4)
        self.verdict = ""
        self.showing_heat = False
        self.frame_ms: deque = deque(maxlen=120)
        self.progress: deque = deque(maxlen=240)
        self.convergence: deque = deque(maxlen=240)
        self._context = None
        self._edits = state.scene_edits            # the scene's in-place edits seen so far
        self.changed = False                       # the picture to show changed: upload it
        self.reference = None                      # app.viewer.reference.ReferenceView (--reference)
        self._picked = (None, (None, ()))          # (frame, its triangle ids) for the status line
        self._picking = None                       # the thread drawing them
        self.profile_row: int | None = None        # the row whose intensity is plotted
        self.wake = lambda: None                   # the window's: wakes its loop (any thread)
        self._job: dict | None = None              # the tool job running off the UI thread
        self._next_job: tuple | None = None        # the one asked for while it ran (newest)
        self._scene_serial = 0                     # scenes opened so far (a job's is kept)

    # -- work off the UI thread --------------------------------------------------------------
    def off_thread(self, what: str, work, done) -> None:
        """``work()`` on a thread of its own, then ``done(result)`` on the UI thread at the
        next :meth:`poll`. One job runs at a time; one asked for meanwhile waits, and a newer
        one replaces it. ``work`` must not touch the window's state (take what it needs
        first, on the UI thread)."""
        self._next_job = (what, work, done)
        self._start_next()

    def _start_next(self) -> None:
        if self._job is not None or self._next_job is None:
            return
        what, work, done = self._next_job
        self._next_job = None
        job = {"what": what, "done": done, "scene": self._scene_serial}

        def run():
            try:
                job["result"] = work()
            except Exception as error:            # said in the panel, never fatal
                job["error"] = error
            self.wake()                           # the window applies it at once

        job["thread"] = threading.Thread(target=run, name=f"tool: {what}", daemon=True)
        self._job = job
        job["thread"].start()

    def poll(self) -> bool:
        """Apply a tool job that finished (on the UI thread); whether one was applied."""
        job = self._job
        if job is None or job["thread"].is_alive():
            return False
        self._job = None
        if job["scene"] != self._scene_serial:
            log.info("%s: done for the scene before; dropped", job["what"])
        elif "error" in job:
            error = job["error"]
            self.verdict = f"{job['what']} failed: {type(error).__name__}: {error}"
            log.error("%s", self.verdict, exc_info=error)
        else:
            job["done"](job["result"])
        self._start_next()
        return True

    def settle(self, timeout: float = 300.0) -> None:
        """Wait for the tool jobs asked for so far and apply them (tests; the window's close)."""
        while self._job is not None:
            self._job["thread"].join(timeout)
            if not self.poll():
                break

    @property
    def busy(self) -> str:
        """What is being drawn off the UI thread ("" when nothing)."""
        return f"drawing {self._job['what']}" if self._job is not None else ""

    # -- what the picture area shows ---------------------------------------------------------
    def picture(self, frame) -> np.ndarray:
        if self.reference is not None and self.reference.shown is not None:
            return self.reference.shown
        if self.showing_heat and self.heat is not None:
            return self.heat
        if self.overlay is not None:
            return self.overlay
        return frame.rgbx

    def frame_changed(self, frame, seconds: float) -> None:
        """A new final frame: the plots take its time; a buffer view follows it; a
        comparison made for the old frame is dropped."""
        self.frame_ms.append(seconds * 1e3)
        if self._edits != self.state.scene_edits:        # a mesh replaced: stale caches
            self._edits = self.state.scene_edits
            if self._context is not None:
                self._context.forget(self.state.scene)
        self.note_convergence(getattr(frame, "stats", None))
        if self.reference is not None:
            self.reference.refresh(frame)
        if self.heat is not None:
            self.heat, self.showing_heat, self.verdict = None, False, ""
        if self.buffer != PICTURE:
            self._show_buffer(self.buffer, "the new frame", quiet_loss=False)
        self.changed = True

    def scene_changed(self) -> None:
        """Another scene: the last one's pixel record, comparison, plots and buffer view go."""
        self.record, self.lines, self.profile_row = None, [], None
        self.heat, self.showing_heat, self.verdict = None, False, ""
        self.buffer, self.overlay, self.changed = PICTURE, None, True
        self.frame_ms.clear()
        self.progress.clear()
        self.convergence.clear()
        self._next_job = None                      # a job asked for the old scene is not wanted
        self._scene_serial += 1                    # and one running for it is dropped when done
        if self.reference is not None:
            self.reference.refresh(None)

    # -- inspect mode ------------------------------------------------------------------------
    def toggle_inspect(self, how: str) -> None:
        self.inspecting = not self.inspecting
        log.info("action: %s -> inspect mode %s", how, "on" if self.inspecting else "off")

    def inspect(self, x: int, y: int, where: str) -> None:
        """The record of pixel (x, y), drawn off the UI thread and shown in the panel."""
        from core.inspect import NotInspectable, inspect_pixel
        try:
            drawn = self._drawn()
        except NotInspectable as error:
            self._inspected((None, error), x, y, where)
            return
        context = self.context()

        def work():
            try:
                return inspect_pixel(*drawn, x, y, context), None
            except NotInspectable as error:
                return None, error

        log.info("action: %s -> drawing the record of pixel (%d, %d)", where, x, y)
        self.off_thread(f"the record of pixel ({x}, {y})", work,
                        lambda found: self._inspected(found, x, y, where))

    def _inspected(self, found, x: int, y: int, where: str) -> None:
        import json
        from core.inspect.text import describe
        record, error = found
        if record is None:
            self.record, self.lines = None, [str(error)]
            log.info("action: %s -> inspect pixel (%d, %d): %s", where, x, y, error)
            return
        self.record, self.lines = record, describe(record)
        self.profile_row = y
        log.info("action: %s -> inspect pixel (%d, %d)", where, x, y)
        log.info("inspect record: %s", json.dumps(record, default=_jsonable))

    def _drawn(self):
        """``(scene, view, settings)`` as the frame was drawn (the course's .tri rules and
        the headlight applied); animated scenes are refused (the moment's objects are not
        kept)."""
        from core.inspect import NotInspectable
        s = self.state
        if s.playback is not None:
            raise NotInspectable("animated scenes are not inspected: the objects of the "
                                 "moment shown are not kept (use a still scene)")
        return s.lighting.drawn_scene(), s.views.current, s.choices.settings()

    def context(self):
        if self._context is None:
            from core.context import RenderContext
            self._context = RenderContext()
        return self._context

    # -- the triangle under the cursor -------------------------------------------------------
    def triangle_ids(self, frame):
        """``(ids, meshes)`` for the status line: the frame's visible-triangle ids in scene
        order and each mesh's (name, triangle count); ``(None, ())`` until they are drawn, and
        where the renderer keeps no triangle buffer. They are drawn once per frame on a thread
        of their own with a context of their own (the first pass loads the inspector's
        kernels: seconds for a large mesh; a fresh context, so that no cache is shared with
        the UI thread), for scenes up to ``MAX_PICKED`` triangles."""
        done_for, found = self._picked
        if done_for is frame:
            return found
        s = self.state
        if (self._picking is None and s.views.current is not None and s.scene is not None
                and s.playback is None and s.scene.triangle_count <= MAX_PICKED
                and s.choices.renderer_entry.triangle_ids):
            drawn = self._drawn()
            self._picking = threading.Thread(target=self._pick, args=(frame, drawn),
                                             name="triangle ids", daemon=True)
            self._picking.start()
        return None, ()

    def _pick(self, frame, drawn) -> None:
        from core.context import RenderContext
        from core.inspect import NotInspectable
        from core.inspect.buffers import buffer
        found = None, ()
        try:
            ids, _ = buffer(*drawn, "triangle", RenderContext())
            height, width = frame.color.shape[:2]
            side = max(1, ids.shape[0] // height)
            found = ids[::side, ::side][:height, :width], \
                [(m.name, len(m.triangles)) for m in drawn[0].meshes]
        except (NotInspectable, ValueError, MemoryError) as error:
            log.info("triangle ids: %s", error)
        self._picked, self._picking = (frame, found), None

    # -- buffer views ------------------------------------------------------------------------
    def buffer_names(self) -> tuple[str, ...]:
        """The buffer views to choose from: the renderer's, then a volume scene's slices."""
        from app.session.volume_controls import SLICES
        from core.inspect.buffers import BUFFERS
        return (*BUFFERS, ALIASING, *(SLICES if self.state.volumes.all else ()))

    def next_buffer(self, how: str) -> None:
        """``v``: the next buffer view this frame keeps (those it lacks are skipped), found
        and drawn off the UI thread; back to the picture after the last."""
        from app.session.volume_controls import SLICES
        from core.inspect import NotInspectable
        if self._job is not None and self._job["what"].startswith("the buffer view"):
            log.info("action: %s -> still %s", how, self.busy)
            return
        cycle = (PICTURE, *self.buffer_names())
        start = cycle.index(self.buffer) if self.buffer in cycle else 0
        names = [cycle[(start + step) % len(cycle)] for step in range(1, len(cycle))]
        try:
            drawn, shape = self._drawn(), self.state.frame.color.shape[:2]
        except (NotInspectable, AttributeError):
            drawn = shape = None
        context = self.context()

        def work():
            for name in names:
                if name == PICTURE:
                    return PICTURE, None
                if name in SLICES or drawn is None:
                    return name, None            # slices are cut on the UI thread (cheap)
                overlay, _ = buffer_overlay(drawn, name, shape, context)
                if overlay is not None:
                    return name, overlay
            return PICTURE, None

        def done(found):
            name, overlay = found
            if name == PICTURE or (name not in SLICES and overlay is None):
                self.choose_buffer(PICTURE, how)
            elif name in SLICES:
                self._show_slice(name, how)
            else:
                self._shown_buffer(name, overlay, how)
            self.changed = True

        self.off_thread(f"the buffer view after the {self.buffer}", work, done)

    def choose_buffer(self, name: str, how: str) -> None:
        if name == PICTURE:
            self.buffer, self.overlay = PICTURE, None
            log.info("action: %s -> buffer view: picture", how)
        else:
            self._show_buffer(name, how)
        self.changed = True

    def _show_buffer(self, name: str, how: str, quiet_loss: bool = True) -> None:
        """Show buffer ``name`` of the frame: a slice at once, any other drawn off the UI
        thread (the picture stays until it is there). A buffer the frame does not keep
        leaves the picture shown (said in the log)."""
        from app.session.volume_controls import SLICES
        from core.inspect import NotInspectable
        s = self.state
        if s.views.current is None or s.frame is None:
            return
        if name in SLICES:
            self._show_slice(name, how)
            return
        try:
            drawn = self._drawn()
        except NotInspectable as error:
            self._buffer_lost(name, how, str(error), quiet_loss)
            return
        shape, context = s.frame.color.shape[:2], self.context()

        def done(found):
            overlay, why = found
            if overlay is None:
                self._buffer_lost(name, how, why, quiet_loss)
            else:
                self._shown_buffer(name, overlay, how)

        self.off_thread(f"the {name} view", lambda: buffer_overlay(drawn, name, shape, context),
                        done)

    def _shown_buffer(self, name: str, overlay: np.ndarray, how: str) -> None:
        self.buffer, self.overlay, self.changed = name, overlay, True
        log.info("action: %s -> buffer view: %s", how, name)

    def _buffer_lost(self, name: str, how: str, why: str, quiet: bool) -> None:
        if quiet:
            log.info("action: %s -> buffer view %s: %s", how, name, why or "not kept by this "
                     "frame")
            return
        self.buffer, self.overlay, self.changed = PICTURE, None, True
        log.info("buffer view: the new frame keeps no %s buffer; showing the picture", name)

    def _show_slice(self, name: str, how: str) -> bool:
        """A slice through the volume the controls act on, in place of the picture."""
        from app.session.volume_controls import slice_picture
        s = self.state
        if s.volumes.current is None:
            return False
        if name != s.slice_name:
            s.volumes.set_slice(name)
        height, width = s.frame.color.shape[:2]
        volume, index = s.volumes.current, s.volumes.slice_shown()
        self.overlay = slice_picture(volume, name, index, (width, height))
        self.buffer = name
        log.info("action: %s -> buffer view: %s slice %d of %s", how, name, index, volume.name)
        return True

    def show_slice(self, name: str, index: int | None, how: str) -> None:
        """The slice slider or its axis: show that slice now."""
        self.state.volumes.set_slice(name, index)
        if self._show_slice(name, how):
            self.changed = True

    # -- the OpenGL comparison ---------------------------------------------------------------
    def compare_opengl(self, how: str) -> None:
        from app.oracles.reference_gl import opengl_reference
        from core.inspect import NotInspectable
        from core.inspect.compare import compare, heat_map
        s = self.state
        if s.frame is None or s.views.current is None:
            return
        ours = s.frame.color
        try:
            scene, view, settings = self._drawn()
        except NotInspectable as error:
            self.verdict = f"no comparison: {error}"
            log.info("action: %s -> %s", how, self.verdict)
            return
        settings = settings.replace(size=(ours.shape[1], ours.shape[0]))

        def work():
            reference, why = opengl_reference(scene, view, settings)
            if reference is None:
                return None, why
            result = compare(ours, reference)
            return (result, heat_map(result, reference)), ""

        def done(found):
            compared, why = found
            if compared is None:
                self.verdict = f"no comparison: {why}"
                log.info("action: %s -> %s", how, self.verdict)
                return
            result, heat = compared
            self.heat = np.zeros(ours.shape[:2] + (4,), np.uint8)
            self.heat[..., :3] = heat
            self.verdict = "against OpenGL: " + result.verdict()
            self.showing_heat = True
            self.changed = True
            log.info("action: %s -> compare with OpenGL: %s", how, result.verdict())

        log.info("action: %s -> drawing the OpenGL reference to compare with", how)
        self.off_thread("the OpenGL reference", work, done)

    def flip(self, how: str) -> None:
        if self.reference is not None:             # --reference: picture, reference, difference
            self.reference.cycle(self.state.frame, how)
            self.changed = True
            return
        if self.heat is None:
            self.compare_opengl(how)
            return
        self.showing_heat = not self.showing_heat
        self.changed = True
        log.info("action: %s -> showing %s", how,
                 "the heat map" if self.showing_heat else "the picture")

    # -- the panel ---------------------------------------------------------------------------
    def note_convergence(self, stats) -> None:
        """A picture on its way: a renderer that reports ``stats["convergence"]`` (a number:
        the path tracer's variance, radiosity's unshot energy) gets it plotted."""
        value = stats.get("convergence") if isinstance(stats, dict) else None
        if isinstance(value, (int, float)):
            self.convergence.append(float(value))

    def note_progress(self, fraction) -> None:
        if fraction is not None:
            if self.progress and fraction < self.progress[-1]:
                self.progress.clear()            # a new frame started: plot its progress
            self.progress.append(float(fraction))

    def panel(self, imgui, displayable) -> None:
        header = "Inspector" + (" (click a pixel)" if self.inspecting else "")
        expanded = imgui.collapsing_header(f"{header}###inspector",
                                           imgui.TreeNodeFlags_.default_open)
        if not expanded:
            return
        imgui.push_text_wrap_pos(0.0)
        if self.buffer != PICTURE:
            imgui.text_colored((0.55, 0.8, 1.0, 1.0),
                               f"showing the {self.buffer} buffer (v: next)")
        if self.reference is not None and self.reference.verdict:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.reference.verdict))
            imgui.text_disabled(f"h: showing the {self.reference.mode}; next "
                                "picture / reference / difference")
        if self.verdict:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.verdict))
            if self.heat is not None:
                imgui.text_disabled("h: " + ("picture" if self.showing_heat else "heat map"))
        if not self.lines and not self.inspecting:
            imgui.text_disabled("i: inspect mode, v: buffer views, h: compare with OpenGL")
        imgui.pop_text_wrap_pos()
        self._plots(imgui)
        imgui.push_text_wrap_pos(0.0)
        for line in self.lines:
            imgui.text(displayable(line))
        imgui.pop_text_wrap_pos()

    def _plots(self, imgui) -> None:
        """The last frames' times, the progress of a frame still refining, and the intensity
        along the row of the last pixel inspected (Mach bands: Gouraud's is continuous,
        its slope is not)."""
        frame = self.state.frame
        if self.profile_row is not None and frame is not None \
                and 0 <= self.profile_row < frame.color.shape[0]:
            values = row_profile(frame.color, self.profile_row)
            imgui.plot_lines("##profile", values, scale_min=0.0, scale_max=255.0,
                             overlay_text=f"intensity along row {self.profile_row}",
                             graph_size=(0, 60))
        if self.frame_ms:
            values = np.array(self.frame_ms, np.float32)
            imgui.plot_lines("##frame ms", values, overlay_text=f"frame {values[-1]:.1f} ms",
                             graph_size=(0, 40))
        if len(self.convergence) > 1:
            imgui.plot_lines("##convergence", np.array(self.convergence, np.float32),
                             overlay_text=f"convergence {self.convergence[-1]:.4g}",
                             graph_size=(0, 40))
        if len(self.progress) > 1:
            imgui.plot_lines("##progress", np.array(self.progress, np.float32), scale_min=0.0,
                             scale_max=1.0, overlay_text="progressive frame",
                             graph_size=(0, 40))


def buffer_overlay(drawn, name: str, shape: tuple[int, int], context):
    """``(overlay, why)``: buffer ``name`` of the frame drawn as ``drawn`` (scene, view,
    settings), an ``(H, W, 4)`` picture of the frame's ``shape``; ``(None, why)`` when the
    renderer keeps no such buffer. Runs off the UI thread."""
    from core.inspect import NotInspectable
    from core.inspect.buffers import buffer
    if name == ALIASING:
        return aliasing_overlay(drawn, context)
    try:
        _, picture = buffer(*drawn, name, context)
    except NotInspectable as error:
        return None, str(error)
    height, width = shape
    side = max(1, picture.shape[0] // height)
    picture = picture[::side, ::side][:height, :width]
    rgbx = np.zeros((height, width, 4), np.uint8)
    rgbx[:picture.shape[0], :picture.shape[1], :3] = picture
    return rgbx, ""


def aliasing_overlay(drawn, context):
    """The split view: the picture's left half drawn with one sample a pixel (midpoint lines),
    its right half antialiased (:data:`ANTIALIASED`), the same edges meeting at the middle
    column, for the loupe to show both. ``(overlay, why)``; runs off the UI thread."""
    from core.render import render
    from core.renderers import get_renderer, names_that
    scene, view, settings = drawn
    if not get_renderer(settings.renderer).rasterizes:  # 16 rays a pixel: seconds here
        return None, (f"drawn for the rasterizing renderers only "
                      f"({', '.join(names_that('rasterizes'))}), not {settings.renderer}")
    try:
        smooth = ANTIALIASED_LINES if settings.shading == "wireframe" else ANTIALIASED
        halves = [render(scene, view, dataclasses.replace(settings, **how_drawn),
                         context).rgbx for how_drawn in (ALIASED, smooth)]
    except ValueError as error:
        return None, str(error)
    return split_view(*halves), ""


def row_profile(color: np.ndarray, row: int) -> np.ndarray:
    """The intensity (Rec. 601 luma, 0-255) of each pixel of ``row`` of an RGB picture."""
    return (color[row, :, :3].astype(np.float32) @ np.float32([0.299, 0.587, 0.114]))


def split_view(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """``left``'s columns up to the middle, ``right``'s from it (both ``(H, W, 4)``)."""
    out = left.copy()
    middle = out.shape[1] // 2
    out[:, middle:] = right[:, middle:]
    return out


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(type(value).__name__)
