"""The status lines at the top of the panel: the last problem, the scene and view, the
settings and the renderer's words, the frame's size and time, what the worker is doing (and
whether kernels compile), the last notice, and the value under the cursor.
"""

from __future__ import annotations

import logging
import time

from imgui_bundle import imgui

from app.session.state import compile_count
from app.viewer.gui_text import displayable
from app.viewer.loupe import value_at

log = logging.getLogger("fvd")
PROBLEM_COLOUR = (1.0, 0.45, 0.4, 1.0)     # the last error or refusal, top of the status
PROGRESS_LINES = 3                         # the progress line's space, whatever it says


class StatusLine:
    """The status lines, drawn from the state and the worker's progress."""

    def __init__(self, win):
        self.win, self.state = win, win.state


    def _cursor_line(self) -> None:
        """The status line's value under the cursor (through the loupe), and the loupe's m."""
        x, y = self.win.sizes.cursor
        if self.state.frame is None or not self.win.on_picture(x, y) or self.win.menus.popup_open \
                or self.win.files.dialog.open:
            return                        # a menu or a dialog over the picture: not a pixel
        column, row = self.win.pointer.frame_pixel(x, y)
        m = self.win.loupe.magnification
        zoom = f"loupe {m}x, " if m > 1 else ""
        if self.win.pointer.resizing():
            zoom = "resizing (the last frame, stretched): " + zoom
        ids, meshes = (None, ()) if imgui.is_any_mouse_down() else \
            self.win.tools.triangle_ids(self.state.frame)        # not while a drag moves the view
        imgui.text_disabled(zoom + value_at(self.state.frame, column, row, ids, meshes))

    def draw(self) -> None:
        s = self.state
        imgui.push_text_wrap_pos(0.0)
        problem = s.messages.problem or self.win.hands.message
        if problem:                       # where the eye is, until the next success clears it
            imgui.text_colored(PROBLEM_COLOUR, displayable(problem))
        imgui.text(displayable(f"{s.scene.name}: {s.views.label}"))
        if s.views.count:
            imgui.text_disabled(displayable(s.views.current.label))
        rasterizer = (f", {s.rasterizer} rasterizer"                 # the tracers have none
                      if s.choices.has_triangles and s.choices.renderer_entry.rasterizes else "")
        imgui.text(f"{s.projection}, {s.shading}{rasterizer}")
        imgui.text("aspect kept (letterbox)" if s.keep_aspect
                   else "window stretched over the viewport")
        if s.course_tri:
            imgui.text_disabled("course .tri rules: left Phong, middle Gouraud, right flat")
        words = s.choices.renderer_entry.status           # the registry entry's status words
        extras = [words + (" (refining)" if s.frame_partial else "")] if words else []
        if s.choices.has_textures:
            extras.append(f"{s.texture_filter} textures" + ("" if s.bump else ", no bump maps"))
        if s.shading == "depth":
            extras.append("depth: " + ("height, terrain map" if s.depth_shading == "height"
                                       else "distance from the eye, near bright"))
        if s.lighting.note:
            extras.append(s.lighting.note)
        if extras:
            imgui.text(", ".join(extras))
        for note in (s.frame.stats.get("not drawn", []) if s.frame is not None else []):
            imgui.text_colored((1.0, 0.7, 0.3, 1.0), displayable(f"not drawn: {note}"))
        if s.choices.bump_label:
            imgui.text_colored((0.6, 0.7, 1.0, 1.0), displayable(s.choices.bump_label))
            imgui.text_disabled("left click: bump / Phong; other buttons: next map")
        if not s.renderable:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0),
                               "the panel takes the whole window: widen it to see the picture")
        elif s.frame is None:
            imgui.text("")
        else:
            imgui.text(f"{s.size[0]} x {s.size[1]}, frame {s.frame_seconds * 1e3:.1f} ms")
        self._progress_line(displayable(self._progress_text()))
        if self.win.notice:
            imgui.text_disabled(displayable(self.win.notice))
        self._cursor_line()
        imgui.pop_text_wrap_pos()
        imgui.separator()

    def _progress_line(self, text: str) -> None:
        """What runs, in a space of :data:`PROGRESS_LINES` lines whatever it says, so that the
        timeline and the controls under it do not jump as a render starts and ends (a click
        aimed at the slider used to land on the speed combo)."""
        width = imgui.get_content_region_avail().x
        line = imgui.get_text_line_height_with_spacing()
        top = imgui.get_cursor_pos_y()
        imgui.text_colored((0.55, 0.8, 1.0, 1.0), text)
        used = imgui.get_cursor_pos_y() - top
        if used < PROGRESS_LINES * line and width > 0:
            imgui.dummy((1.0, PROGRESS_LINES * line - used))

    def _progress_text(self) -> str:
        """What the worker is doing, how long it has taken, and whether it compiles."""
        from app.viewer.kernels import status
        p = self.win.worker.progress()
        compiling = status(self.win.loop.warmup) if self.win.loop.warmup is not None else ""
        if compiling and not self.win.loop.warmup.finished and not (p.what and p.frame):
            return compiling
        compiled = compile_count() - self.win.loop.compiles_at_request
        extra = f", compiling kernels ({compiled} so far)" if compiled else ""
        if p.what and p.frame:
            how_far = (f", {p.detail}" if p.detail else "") + (
                f" ({p.fraction * 100:.0f}%)" if p.fraction is not None else "")
            return f"rendering {p.what}: {time.perf_counter() - p.since:.1f} s{how_far}{extra}"
        if p.what and self.win.worker.waiting:
            return (f"your frame is next; loading kernels ({p.done + 1} of {p.total}: "
                    f"{p.what}) {time.perf_counter() - p.since:.1f} s{extra}")
        if self.win.tools.busy:
            return f"{self.win.tools.busy} (the picture stays until it is there)"
        if p.done < p.total:
            return f"loading kernels in the background: {p.done} of {p.total}"
        return compiling or "ready"
