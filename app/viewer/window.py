"""The window: glfw, a moderngl context, the blit of the CPU frame, Dear ImGui menus and input.

Takes a :class:`app.viewer.state.ViewerState` and shows it: each time the state says the picture
changed, the core renders a frame on the CPU (``ViewerState.update``) and :class:`app.viewer.blit.Blit`
copies it to the screen texel for pixel; ImGui draws the menu bar, the right-click pop-up (the
course's GLUT pop-up menu), the status line, the plan of the current frame and the messages
on top. Nothing here computes geometry or colour.

Input (the course's Assignment #1 controls, plus shading from Assignment #3):

- left click on the picture: next view (wraps); a click ImGui takes (the menu bar, a panel)
  does not also advance the view — ImGui's own ``WantCaptureMouse`` decides, for that click;
- right click: pop-up menu with projection and shading;
- ``p`` / ``o``: perspective / parallel; ``w``, ``1``, ``2``, ``3``: wireframe, flat,
  Gouraud, Phong; arrows: previous / next view; ``s``: save the CPU frame as a PNG;
  ``q`` / Esc: quit.

Every user action and every new frame is logged (logger ``fvd``; ``app.viewer`` sends it to
stderr and to ``$FVD_LOG``). The window asks for a framebuffer of the requested size (on HiDPI
screens the window size in points is scaled to get it) and always renders at the real
framebuffer size; a minimised (0 x 0) window renders nothing.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path

import glfw
import imgui
import moderngl

from app.viewer.blit import Blit
from app.viewer.imgui_backend import GlfwInput, ImGuiRenderer
from app.viewer.state import ViewerState
from core.paths import SCENES_DIR

log = logging.getLogger("fvd")

PROJECTION_LABELS = (("perspective", "Perspective", "P"), ("parallel", "Parallel", "O"))
SHADING_LABELS = (("wireframe", "Wireframe", "W"), ("flat", "Flat", "1"),
                  ("gouraud", "Gouraud", "2"), ("phong", "Phong", "3"))
CHAR_SHORTCUTS = {"p": ("projection", "perspective"), "o": ("projection", "parallel"),
                  "w": ("shading", "wireframe"), "1": ("shading", "flat"),
                  "2": ("shading", "gouraud"), "3": ("shading", "phong")}
# Files in scenes/ that are not scenes.
NOT_SCENES = {".md", ".py", ".pyc", ".txt", ".png"}
# After an event, draw a few frames so that ImGui's hover and menu states settle; then sleep
# until the next event (a busy loop would take the CPU the rasterizer needs).
FRAMES_AFTER_EVENT = 3
PANEL_FLAGS = imgui.WINDOW_NO_SAVED_SETTINGS | imgui.WINDOW_NO_FOCUS_ON_APPEARING


# ImGui's built-in font covers Latin-1 only; the core's messages use a few typographic marks.
_TYPOGRAPHY = str.maketrans({"\u2013": "-", "\u2014": "-", "\u2212": "-", "\u2018": "'",
                             "\u2019": "'", "\u201c": '"', "\u201d": '"', "\u2026": "...",
                             "\u00b7": "."})


def displayable(text: str) -> str:
    """``text`` in the characters the GUI font has (others become '?')."""
    return text.translate(_TYPOGRAPHY).encode("latin-1", "replace").decode("latin-1")


class WindowError(RuntimeError):
    """No window could be made (no display, no OpenGL 3.3)."""


def shipped_scenes() -> list[Path]:
    """The scene files in ``scenes/``, for File > Open."""
    if not SCENES_DIR.is_dir():
        return []
    return sorted(p for p in SCENES_DIR.iterdir()
                  if p.is_file() and not p.name.startswith((".", "_"))
                  and p.suffix not in NOT_SCENES)


def create_window(size: tuple[int, int], title: str):
    """A glfw window with an OpenGL 3.3 core context whose framebuffer is ``size`` pixels.

    Raises :class:`WindowError` with glfw's reason when there is no display or no context.
    """
    width, height = size
    reporting, glfw.ERROR_REPORTING = glfw.ERROR_REPORTING, "exception"
    try:
        if not glfw.init():
            raise WindowError("glfw could not initialise")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        glfw.window_hint(glfw.VISIBLE, False)          # shown once its size is right
        window = glfw.create_window(width, height, title, None, None)
        if not window:
            raise WindowError("glfw could not create a window")
    except glfw.GLFWError as error:
        glfw.terminate()
        raise WindowError(str(error)) from None
    finally:
        glfw.ERROR_REPORTING = reporting
    # HiDPI: the window size is in screen points; scale it so the framebuffer gets the pixels.
    window_w, window_h = glfw.get_window_size(window)
    fb_w, fb_h = glfw.get_framebuffer_size(window)
    if (fb_w, fb_h) != (width, height) and fb_w > 0 and fb_h > 0:
        glfw.set_window_size(window, max(1, round(width * window_w / fb_w)),
                             max(1, round(height * window_h / fb_h)))
    glfw.make_context_current(window)
    glfw.swap_interval(1)
    glfw.show_window(window)
    return window


class ViewerWindow:
    """The window around one :class:`ViewerState`. ``run()`` returns when the user quits."""

    def __init__(self, state: ViewerState, out_dir: Path | None = None,
                 started: float | None = None):
        self.state = state
        self.out_dir = Path(out_dir) if out_dir is not None else Path.cwd()
        self.started = started            # process start, in time.perf_counter() seconds
        self.window = create_window(state.size, self._title())
        glfw.ERROR_REPORTING = "log"      # later glfw errors are not fatal
        try:
            self.ctx = moderngl.create_context(require=330)
        except Exception as error:        # e.g. a display whose OpenGL is older than 3.3
            glfw.destroy_window(self.window)
            glfw.terminate()
            raise WindowError(f"no OpenGL 3.3 context: {error}") from None
        self.gui_context = None
        try:
            self.blit = Blit(self.ctx)
            self.gui_context = imgui.create_context()
            io = imgui.get_io()
            io.ini_file_name = None       # keep no imgui.ini in the user's directory
            self.gui = ImGuiRenderer(self.ctx)
            self.input = GlfwInput(self.window)
        except Exception as error:        # e.g. a shader that does not compile: close it all
            if self.gui_context is not None:
                imgui.destroy_context(self.gui_context)
            self.ctx.release()
            glfw.destroy_window(self.window)
            glfw.terminate()
            raise WindowError(f"could not set up the window: {error}") from error
        self._busy = FRAMES_AFTER_EVENT
        self._clicks: list[tuple[int, float, float]] = []   # (button, x, y) since last frame
        self._path = ""                   # File > Open: the path being typed
        self._notice = ""                 # the last screenshot, for the status line
        self._scenes = shipped_scenes()
        self._first_frame_logged = False
        self._plan_open = False
        self._install_callbacks()

    # -- glfw callbacks: forward to ImGui, then act unless ImGui took the event ---------------
    def _install_callbacks(self) -> None:
        w = self.window
        glfw.set_mouse_button_callback(w, self._on_mouse_button)
        glfw.set_key_callback(w, self._on_key)
        glfw.set_char_callback(w, self._on_char)
        glfw.set_scroll_callback(w, self._on_scroll)
        glfw.set_cursor_pos_callback(w, lambda *_: self._wake())
        glfw.set_cursor_enter_callback(w, lambda *_: self._wake())
        glfw.set_framebuffer_size_callback(w, self._on_framebuffer_size)
        glfw.set_window_refresh_callback(w, lambda *_: self._wake())
        glfw.set_window_focus_callback(w, lambda *_: self._wake())

    def _wake(self) -> None:
        self._busy = FRAMES_AFTER_EVENT

    def _on_mouse_button(self, window, button, action, mods) -> None:
        self.input.on_mouse_button(button, action)
        if action == glfw.PRESS and button in (glfw.MOUSE_BUTTON_LEFT, glfw.MOUSE_BUTTON_RIGHT):
            # Decided in the next frame, once ImGui has seen this press at this position.
            self._clicks.append((button, *glfw.get_cursor_pos(window)))
        self._wake()

    def _on_key(self, window, key, scancode, action, mods) -> None:
        self.input.on_key(key, action, mods)
        self._wake()
        if action not in (glfw.PRESS, glfw.REPEAT) or imgui.get_io().want_capture_keyboard:
            return
        if key == glfw.KEY_ESCAPE:
            self.quit("key Esc")
        elif key in (glfw.KEY_RIGHT, glfw.KEY_DOWN):
            self.step_view(+1, "key Right" if key == glfw.KEY_RIGHT else "key Down")
        elif key in (glfw.KEY_LEFT, glfw.KEY_UP):
            self.step_view(-1, "key Left" if key == glfw.KEY_LEFT else "key Up")

    def _on_char(self, window, codepoint) -> None:
        # Letters come as characters, so that the shortcuts follow the keyboard layout.
        self.input.on_char(codepoint)
        self._wake()
        if imgui.get_io().want_capture_keyboard:
            return
        char = chr(codepoint).lower()
        if char in CHAR_SHORTCUTS:
            what, value = CHAR_SHORTCUTS[char]
            self.choose(what, value, f"key {char}")
        elif char == "s":
            self.save_screenshot("key s")
        elif char == "q":
            self.quit("key q")

    def _on_scroll(self, window, x_offset, y_offset) -> None:
        self.input.on_scroll(x_offset, y_offset)
        self._wake()

    def _on_framebuffer_size(self, window, width, height) -> None:
        self.state.resize(width, height)
        self._wake()

    # -- actions -----------------------------------------------------------------------------
    def step_view(self, step: int, how: str) -> None:
        before = self.state.view_index
        self.state.next_view() if step > 0 else self.state.prev_view()
        log.info("action: %s -> %s view %d -> %d of %d", how, "next" if step > 0 else "previous",
                 before + 1, self.state.view_index + 1, self.state.view_count)

    def go_to_view(self, index: int, how: str) -> None:
        self.state.set_view(index)
        log.info("action: %s -> view %d of %d", how, index + 1, self.state.view_count)

    def choose(self, what: str, value: str, how: str) -> None:
        """Set the projection or the shading; the frame is re-rendered at once."""
        if what == "projection":
            self.state.set_projection(value)
        else:
            self.state.set_shading(value)
        log.info("action: %s -> %s %s", how, what, value)
        self._wake()

    def open_scene(self, source: str, how: str) -> None:
        source = source.strip()
        if not source:
            return
        if self.state.open_scene(source):
            log.info("action: %s -> opened %s (%s)", how, source, self.state.view_label)
            for message in self.state.scene.view_messages:
                print(f"invalid view: {message}", file=sys.stderr)
            glfw.set_window_title(self.window, self._title())
        else:
            log.info("action: %s -> %s", how, self.state.open_messages[-1])
            print(self.state.open_messages[-1], file=sys.stderr)
        self._wake()

    def save_screenshot(self, how: str) -> Path | None:
        """The CPU frame (not the screen: no menus) as a PNG in the output directory."""
        frame = self.state.frame
        if frame is None:
            log.info("action: %s -> no frame to save yet", how)
            return None
        from PIL import Image

        s = self.state
        stem = (f"{Path(s.scene.name).stem or 'scene'}-view{s.view_index + 1}"
                f"-{s.projection}-{s.shading}")
        path = self.out_dir / f"{stem}.png"
        n = 1
        while path.exists():
            n += 1
            path = self.out_dir / f"{stem}-{n}.png"
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            Image.fromarray(frame.color).save(path)
        except OSError as error:
            self._notice = f"could not save {path}: {error}"
            log.info("action: %s -> %s", how, self._notice)
            print(self._notice, file=sys.stderr)
            return None
        self._notice = f"saved {path.name}"
        log.info("action: %s -> screenshot saved to %s", how, path)
        print(f"screenshot saved to {path}", flush=True)
        return path

    def quit(self, how: str) -> None:
        log.info("action: %s -> quit", how)
        glfw.set_window_should_close(self.window, True)

    # -- the loop ----------------------------------------------------------------------------
    def run(self) -> int:
        try:
            # Show the window (menus, status, the scene's background) before the first CPU
            # frame: that frame may wait for numba to load or compile its kernels.
            self.draw_frame(allow_render=False)
            self._log_since_start("window shown")
            shown = True
            while not glfw.window_should_close(self.window):
                # Sleep until an event unless a frame is due; a minimised window always sleeps
                # (it stays "dirty" until it has a size again).
                if shown and (self._busy > 0 or self.state.dirty):
                    glfw.poll_events()
                else:
                    glfw.wait_events_timeout(0.5)
                shown = self.draw_frame()
        finally:
            self.close()
        return 0

    def draw_frame(self, allow_render: bool = True) -> bool:
        """Input, clicks, re-render if needed, GUI, blit, swap; False when minimised."""
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        self.state.resize(fb_w, fb_h)
        if not self.state.renderable or glfw.get_window_attrib(self.window, glfw.ICONIFIED):
            self._clicks.clear()
            self._busy = 0
            return False                  # minimised: nothing to render or draw
        self._busy -= 1
        self.input.new_frame()
        imgui.new_frame()
        self._handle_clicks()

        if allow_render and self.state.update():
            self._log_frame()
            self.blit.upload(self.state.frame.rgbx)
            self._wake()                  # the GUI shows the new frame's plan and timing next
        self._build_gui()
        imgui.render()

        self.ctx.viewport = (0, 0, fb_w, fb_h)
        self.ctx.clear(*self.state.scene.background[:3], 1.0)
        if self.state.frame is not None:  # after a scene change, never the old scene's picture
            self.blit.draw()
        self.gui.render(imgui.get_draw_data())
        glfw.swap_buffers(self.window)
        if not self._first_frame_logged and self.state.frame is not None:
            self._first_frame_logged = True
            self._log_since_start("first frame shown")
        return True

    def _log_since_start(self, what: str) -> None:
        if self.started is None:
            log.info("%s", what)
        else:
            # CPU seconds too: on a busy machine the wall time says more about the neighbours.
            user, system = os.times()[:2]
            log.info("%s %.3f s after process start (%.3f s CPU)", what,
                     time.perf_counter() - self.started, user + system)

    def _handle_clicks(self) -> None:
        """Left click: next view; right click: the pop-up — unless ImGui wants this click."""
        clicks, self._clicks = self._clicks, []
        if not clicks:
            return
        captured = imgui.get_io().want_capture_mouse
        for button, x, y in clicks:
            name = "left click" if button == glfw.MOUSE_BUTTON_LEFT else "right click"
            where = f"{name} at ({x:.0f}, {y:.0f})"
            if captured:
                log.info("action: %s -> taken by the menu/GUI, view unchanged", where)
            elif button == glfw.MOUSE_BUTTON_LEFT:
                self.step_view(+1, where)
            else:
                log.info("action: %s -> pop-up menu", where)
                imgui.open_popup("popup")

    def _log_frame(self) -> None:
        log.info("%s", self.state.frame_summary())
        if self.state.frame.message:
            print(self.state.frame.message, file=sys.stderr)
        glfw.set_window_title(self.window, self._title())

    def _title(self) -> str:
        s = self.state
        return f"FvD viewer - {s.scene.name} - {s.view_label} - {s.projection} - {s.shading}"

    # -- the GUI -----------------------------------------------------------------------------
    def _build_gui(self) -> None:
        self._menu_bar()
        self._popup()
        self._status_panel()
        self._plan_panel()
        self._messages_panel()

    def _projection_items(self, how: str) -> None:
        for value, label, key in PROJECTION_LABELS:
            clicked, _ = imgui.menu_item(label, key, self.state.projection == value)
            if clicked:
                self.choose("projection", value, how)

    def _shading_items(self, how: str) -> None:
        for value, label, key in SHADING_LABELS:
            clicked, _ = imgui.menu_item(label, key, self.state.shading == value)
            if clicked:
                self.choose("shading", value, how)

    def _menu_bar(self) -> None:
        if not imgui.begin_main_menu_bar().opened:
            return
        if imgui.begin_menu("File").opened:
            if imgui.begin_menu("Open scene").opened:
                for path in self._scenes:
                    if imgui.menu_item(path.name, None, str(path) == self.state.scene_source)[0]:
                        self.open_scene(str(path), "menu File > Open")
                imgui.separator()
                imgui.text("Path:")
                entered, self._path = imgui.input_text(
                    "##path", self._path, flags=imgui.INPUT_TEXT_ENTER_RETURNS_TRUE)
                imgui.same_line()
                if (imgui.button("Open") or entered) and self._path.strip():
                    self.open_scene(self._path, "menu File > Open path")
                    imgui.close_current_popup()
                imgui.end_menu()
            if imgui.menu_item("Save screenshot", "S")[0]:
                self.save_screenshot("menu File > Save screenshot")
            imgui.separator()
            if imgui.menu_item("Quit", "Q")[0]:
                self.quit("menu File > Quit")
            imgui.end_menu()
        if imgui.begin_menu("Projection").opened:
            self._projection_items("menu Projection")
            imgui.end_menu()
        if imgui.begin_menu("Shading").opened:
            self._shading_items("menu Shading")
            imgui.end_menu()
        if imgui.begin_menu("View", self.state.view_count > 0).opened:
            if imgui.menu_item("Next view", "Right")[0]:
                self.step_view(+1, "menu View > Next")
            if imgui.menu_item("Previous view", "Left")[0]:
                self.step_view(-1, "menu View > Previous")
            imgui.separator()
            for i, view in enumerate(self.state.scene.views):
                label = displayable(f"{i + 1}: {view.label}###view{i}")
                if imgui.menu_item(label, None, i == self.state.view_index)[0]:
                    self.go_to_view(i, "menu View")
            imgui.end_menu()
        # Always visible on the bar: where we are and how it is drawn.
        status = f"{self.state.view_label}  {self.state.projection}  {self.state.shading}"
        width = imgui.calc_text_size(status).x
        x = imgui.get_window_width() - width - 8
        if x > imgui.get_cursor_pos_x():
            imgui.set_cursor_pos_x(x)
        imgui.text(status)
        imgui.end_main_menu_bar()

    def _popup(self) -> None:
        # The course's GLUT pop-up menu: projection and shading at the click.
        if imgui.begin_popup("popup").opened:
            imgui.text_disabled("Projection")
            self._projection_items("pop-up")
            imgui.separator()
            imgui.text_disabled("Shading")
            self._shading_items("pop-up")
            imgui.separator()
            if imgui.menu_item("Next view", "Right", False, self.state.view_count > 0)[0]:
                self.step_view(+1, "pop-up Next view")
            imgui.end_popup()

    def _status_panel(self) -> None:
        s = self.state
        top = imgui.get_frame_height()
        imgui.set_next_window_position(4, top + 4)
        imgui.set_next_window_bg_alpha(0.55)
        flags = (imgui.WINDOW_NO_TITLE_BAR | imgui.WINDOW_ALWAYS_AUTO_RESIZE | imgui.WINDOW_NO_MOVE
                 | imgui.WINDOW_NO_SAVED_SETTINGS | imgui.WINDOW_NO_FOCUS_ON_APPEARING
                 | imgui.WINDOW_NO_NAV)
        imgui.begin("status", False, flags)
        imgui.text(displayable(f"{s.scene.name}: {s.view_label}"))
        if s.view_count:
            imgui.text_disabled(displayable(s.scene.views[s.view_index].label))
        imgui.text(f"{s.projection}, {s.shading}")
        if s.frame is None:
            imgui.text("rendering the first frame..." if s.dirty else "no frame to show")
        else:
            imgui.text(f"{s.size[0]} x {s.size[1]}, frame {s.frame_seconds * 1e3:.1f} ms")
        if self._notice:
            imgui.text_disabled(displayable(self._notice))
        imgui.end()

    def _plan_panel(self) -> None:
        frame = self.state.frame
        if frame is None:
            return
        width, height = imgui.get_io().display_size
        title = f"Plan  {self.state.frame_seconds * 1e3:.1f} ms"
        # Pinned to the top-right corner; narrow while collapsed so it hides little of the
        # picture, wide enough for the reasons when open (height 0: fit the contents).
        imgui.set_next_window_position(width - 4, imgui.get_frame_height() + 4,
                                       imgui.ALWAYS, pivot_x=1.0, pivot_y=0.0)
        panel_width = (min(320, width - 8) if self._plan_open
                       else imgui.calc_text_size(title).x + 40)
        imgui.set_next_window_size(panel_width, 0, imgui.ALWAYS)
        imgui.set_next_window_collapsed(True, imgui.FIRST_USE_EVER)
        imgui.set_next_window_bg_alpha(0.85)
        expanded, _ = imgui.begin(f"{title}###plan", False, PANEL_FLAGS | imgui.WINDOW_NO_MOVE)
        # Not ``expanded``: a window that auto-fits its height still takes items when collapsed.
        self._plan_open = expanded and not imgui.is_window_collapsed()
        if self._plan_open:
            stage_ms = frame.stats.get("ms", {}) if isinstance(frame.stats, dict) else {}
            for stage in frame.plan:
                name = getattr(stage, "name", str(stage))
                runs = getattr(stage, "runs", True)
                ms = stage_ms.get(name)
                timing = f" ({ms:.1f} ms)" if ms is not None else ""
                if runs:
                    imgui.text_colored(displayable(f"run   {name}{timing}"), 0.55, 0.9, 0.55)
                else:
                    imgui.text_colored(displayable(f"skip  {name}"), 0.6, 0.6, 0.6)
                reason = getattr(stage, "reason", "")
                if reason:
                    imgui.indent(24)
                    imgui.push_text_wrap_pos(0.0)
                    imgui.text_disabled(displayable(reason))
                    imgui.pop_text_wrap_pos()
                    imgui.unindent(24)
        imgui.end()

    def _messages_panel(self) -> None:
        messages = self.state.messages
        if not messages:
            return
        width, height = imgui.get_io().display_size
        imgui.set_next_window_position(4, height - 4, imgui.FIRST_USE_EVER,
                                       pivot_x=0.0, pivot_y=1.0)
        imgui.set_next_window_size(max(width - 8, 100), min(120, height / 3), imgui.FIRST_USE_EVER)
        imgui.set_next_window_bg_alpha(0.8)
        expanded, _ = imgui.begin(f"Messages ({len(messages)})###messages", False, PANEL_FLAGS)
        if expanded:
            if self.state.open_messages and imgui.small_button("Clear"):
                self.state.clear_messages()
            imgui.push_text_wrap_pos(0.0)
            for message in messages:
                imgui.text_colored(displayable(message), 1.0, 0.75, 0.4)
            imgui.pop_text_wrap_pos()
        imgui.end()

    def close(self) -> None:
        self.gui.release()
        self.blit.release()
        imgui.destroy_context(self.gui_context)
        glfw.destroy_window(self.window)
        glfw.terminate()
