"""The window: the CPU frame beside a side panel of menus, status, plan and messages.

Takes a :class:`app.session.state.ViewerState` and shows it. The picture is exactly the frame
the core rendered, ``W x H`` pixels at the window's top-left corner, and nothing lies on it:
the side panel to its right holds the menu bar (File, Projection, Shading, Render, View), the
status lines, and collapsed strips for the plan of the frame, the invalid views of the file and
other messages; the window is created ``W + panel`` wide to hold it, and when the user resizes
the window the picture takes what the panel leaves. Frames are rendered off the window's thread
(:class:`app.viewer.worker.RenderWorker`): the window keeps drawing, says what is being
rendered and for how long (and whether kernels are being compiled), and a newer request
supersedes a stale one. After the first frame the worker loads every other kernel in the
background (``app/distribution/warmup.py``), so a later change of mode does not stall.

Input (the course's Assignment #1 controls, plus shading from Assignment #3):

- left click on the picture: next view (wraps, stepping over invalid views); a click ImGui
  takes (an open menu) does not also advance the view;
- right click: pop-up menu with projection and shading, at the click;
- with ``--course-tri``, the startup code's buttons instead: left Phong, middle Gouraud,
  right flat;
- ``p`` / ``o``: perspective / parallel; ``w``, ``1``, ``2``, ``3``: wireframe, flat,
  Gouraud, Phong; ``a``: keep the window's aspect (letterbox) or stretch it (the course);
  arrows: previous / next view; ``s``: save the CPU frame as a PNG in ``screenshots/``;
- Esc closes an open menu or pop-up, and quits only when none is open; ``q`` quits;
- ``r``: z-buffer / ray traced (Render menu; a ray-traced picture comes coarse first, then
  tile by tile, and the z-buffer picture stays until the coarse one is there); ``t``: the
  next texture filter (nearest, bilinear, trilinear, anisotropic); ``b``: bump maps on/off;
- an animated scene: space plays / pauses, ``,`` and ``.`` step a frame back / forward,
  ``[`` ``]`` halve / double the speed; the panel has the timeline slider; a left click
  advances the view when paused and pauses when playing;
- the bump demo's scene (J3DPanel): a left click toggles bump / Phong, any other button
  cycles the four height maps, as in the demo.
- the camera's hands (:mod:`app.viewer.hands`, docs/hands.md): a left drag past ImGui's drag
  threshold orbits about the point under the cursor (read from the shown frame's depth; the
  scene's centre when the press misses, or the VRP: View menu) by the arcball or, ``y``, the
  turntable; ``l`` the headlight (:mod:`app.session.headlight`); Shift or
  middle drag pans, the wheel dollies, Ctrl+wheel changes the window, Enter returns to the
  file's view, ``f`` fits the scene, Ctrl+Z / Ctrl+Shift+Z undo and redo a camera move, Ctrl+S
  appends the view to ``saved.views`` in the user's state folder; a click without a drag
  keeps its meaning above; after a resize the last frame is stretched over the picture
  until the new one arrives (the readout maps the cursor the same way);
  Alt+wheel is the loupe (:mod:`app.viewer.loupe`); F1 the keys' help in the panel; a file
  dropped on the window opens (:mod:`app.viewer.files`, with File > Recent and the native
  dialog, or the window's own where the desktop has none: :mod:`app.viewer.path_dialog`);
- the inspector (View menu too; :mod:`app.viewer.inspector_tools`): ``i`` inspect mode, where a
  left click shows the pixel's record in the panel; ``v`` the next buffer view (depth, normal,
  triangle id, ..., and a volume's axial, coronal and sagittal slices) in place of the
  picture; ``h`` compares with OpenGL and flips between the picture and the heat map;
- a scene with volumes: the panel's Volume section (:mod:`app.viewer.volume_panel`): the
  transfer function's plot over the histogram, the iso slider, the slice and its index;
- a renderer with options of its own (the ray tracer's depth limit and shadows, radiosity's
  solver, the BSP root): the panel's options section (:mod:`app.viewer.options_panel`), one
  control per field of its registered options class.

Every user action and every new frame is logged (logger ``fvd``; ``app.viewer`` sends it to
stderr and to ``$FVD_LOG``). On HiDPI screens sizes in points are scaled so that the picture
gets the requested pixels; a minimised (0 x 0) window renders nothing.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path


# imgui-bundle points pyGLFW at the libglfw in its own wheel (``PYGLFW_LIBRARY``) unless the user
# named one: one GLFW in the process, and pyGLFW does not load every libglfw it finds in a
# Python subprocess to compare their versions (~40 ms at every start).
from imgui_bundle import imgui  # noqa: E402,I001  (first: it names the library glfw loads)
import glfw  # noqa: E402
import numpy as np  # noqa: E402
import moderngl  # noqa: E402

from app import startup_gc
from app.naming import picture_name, unused
from app.viewer.blit import Blit, clear_around
from app.viewer.files import SAVED_VIEWS, FileDialog, RecentFiles, check_drop, saved_views_file
from app.viewer.hands import KEYS_HELP, PIVOTS, ROTATIONS, CameraHands, save_view, view_lines
from app.viewer.gui_backend import GlfwInput, GuiRenderer
from app.viewer.inspector_tools import InspectorTools
from app.viewer.loupe import Loupe, stretched, value_at
from app.session.state import ViewerState, compile_count
from app.viewer import options_panel
from app.viewer.volume_panel import VolumePanel
from app.viewer.worker import RenderWorker
from core.paths import SCENES_DIR

log = logging.getLogger("fvd")

PROJECTION_LABELS = (("perspective", "Perspective", "P"), ("parallel", "Parallel", "O"))
# The Render menu lists the registry's renderers by their labels (core/registry.py): a renderer
# registered there is in the menu with no line here. `r` flips between these two.
RENDERER_KEYS = {"zbuffer": "R", "raytrace": "R"}
FILTER_LABELS = (("nearest", "Nearest"), ("bilinear", "Bilinear"),
                 ("trilinear", "Trilinear (MIP map)"), ("anisotropic", "Anisotropic"))
RASTERIZER_LABELS = (("edge", "Edge functions (perspective-correct)"),
                     ("scanline", "Scan line, ET/AET (course, screen-linear)"))
CHAR_SHORTCUTS = {"p": ("projection", "perspective"), "o": ("projection", "parallel"),
                  "w": ("shading", "wireframe"), "1": ("shading", "flat"),
                  "2": ("shading", "gouraud"), "3": ("shading", "phong")}
# The startup code's mouse (Assignment 3): left Phong, middle Gouraud, right flat.
COURSE_BUTTONS = {glfw.MOUSE_BUTTON_LEFT: "phong", glfw.MOUSE_BUTTON_MIDDLE: "gouraud",
                  glfw.MOUSE_BUTTON_RIGHT: "flat"}
PANEL_WIDTH = 340            # the side panel, in screen points
NO_TRIANGLES = ("This scene has no triangles: it is drawn as lines whatever the shading, "
                "so the shading modes change nothing.")
SCREENSHOTS_DIR = "screenshots"
PROBLEM_COLOUR = (1.0, 0.45, 0.4, 1.0)     # the last error or refusal, top of the status
PROGRESS_LINES = 3                         # the progress line's space, whatever it says
# While a camera gesture waits for its frame, the window is drawn again at most this often.
GESTURE_REDRAW_S = 1 / 30
# Files in scenes/ that are not scenes.
NOT_SCENES = {".md", ".py", ".pyc", ".txt", ".png"}
# After an event, draw a few frames so that ImGui's hover and menu states settle; then sleep
# until the next event (a busy loop would take the CPU the rasterizer needs).
FRAMES_AFTER_EVENT = 3
WINDOW_GREY = (0.11, 0.11, 0.13, 1.0)      # the window behind the picture and the panel
_W = imgui.WindowFlags_
PANEL_FLAGS = (_W.no_title_bar | _W.no_resize | _W.no_move | _W.no_collapse | _W.menu_bar
               | _W.no_saved_settings | _W.no_bring_to_front_on_focus)
ANY_POPUP = imgui.PopupFlags_.any_popup_id | imgui.PopupFlags_.any_popup_level


# ImGui's built-in font covers Latin-1 only; the core's messages use a few typographic marks.
_TYPOGRAPHY = str.maketrans({"\u2013": "-", "\u2014": "-", "\u2212": "-", "\u2018": "'",
                             "\u2019": "'", "\u201c": '"', "\u201d": '"', "\u2026": "...",
                             "\u00b7": ".", "\u203a": ">"})


def displayable(text: str) -> str:
    """``text`` in the characters the GUI font has (others become '?')."""
    return text.translate(_TYPOGRAPHY).encode("latin-1", "replace").decode("latin-1")


def pivot_words(drag) -> str:
    """What a finished orbit turned about, for the log."""
    if drag.pivot is None:
        return "the VRP"
    where = "the point under the cursor" if drag.under is not None and np.array_equal(
        drag.pivot, drag.under) else "the scene's centre"
    return f"{where} ({', '.join(f'{c:.6g}' for c in drag.pivot)})"


class WindowError(RuntimeError):
    """No window could be made (no display, no OpenGL 3.3)."""


def shipped_scenes() -> list[Path]:
    """The scene files in ``scenes/``, for File > Open."""
    if not SCENES_DIR.is_dir():
        return []
    return sorted(p for p in SCENES_DIR.iterdir()
                  if p.is_file() and not p.name.startswith((".", "_"))
                  and p.suffix not in NOT_SCENES)


def _glfw_message(error) -> str:
    """glfw's own words for ``error``: pyGLFW's message is ``(code) b'words'``."""
    text = str(error)
    code, _, words = text.partition(" ")
    if code.startswith("(") and words.startswith(("b'", 'b"')) and len(words) > 3:
        return words[2:-1]
    return text


def create_window(size: tuple[int, int], title: str):
    """A glfw window with an OpenGL 3.3 core context whose framebuffer is ``size`` pixels
    (the picture and the panel beside it).

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
        raise WindowError(f"glfw: {_glfw_message(error)}") from None
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
        self.out_dir = Path(out_dir) if out_dir is not None else Path.cwd() / SCREENSHOTS_DIR
        self.started = started            # process start, in time.perf_counter() seconds
        width, height = state.size
        self.window = create_window((width + PANEL_WIDTH, height), self._title())
        glfw.ERROR_REPORTING = "log"      # later glfw errors are not fatal
        self._fit_window(width, height)
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
            imgui.get_io().set_ini_filename(None)     # keep no imgui.ini in the user's directory
            self.gui = GuiRenderer()
            self.input = GlfwInput(self.window)
        except Exception as error:        # e.g. a shader that does not compile: close it all
            if self.gui_context is not None:
                imgui.destroy_context(self.gui_context)
            self.ctx.release()
            glfw.destroy_window(self.window)
            glfw.terminate()
            raise WindowError(f"could not set up the window: {error}") from error
        self.worker = RenderWorker(wake=glfw.post_empty_event)
        self._busy = FRAMES_AFTER_EVENT
        # (button, action, x, y, mods) since the last frame: presses and releases
        self._clicks: list[tuple[int, int, float, float, int]] = []
        self._path = ""                   # File > Open: the path being typed
        self._notice = ""                 # the last screenshot, for the status line
        self._scenes = shipped_scenes()
        self._first_frame_logged = False
        self._warming = False
        self._warm_up_due = False
        self._popup_open = False          # a menu or the pop-up was open in the last frame
        self._close_popups = False        # Esc: close them in the next frame
        self._compiles_at_request = 0
        self.tools = InspectorTools(state)    # inspect mode, buffer views, compare
        self.tools.wake = glfw.post_empty_event
        self.volume_panel = VolumePanel(state, self.tools)   # transfer, iso, slices
        self._init_hands()
        self._init_files()
        self._install_callbacks()
        self.warmup = None
        self._start_kernel_processes()

    # -- geometry: the picture at the top-left, the panel to its right -----------------------
    def _scale(self) -> float:
        """Framebuffer pixels per screen point (1 except on HiDPI screens)."""
        window_w, _ = glfw.get_window_size(self.window)
        fb_w, _ = glfw.get_framebuffer_size(self.window)
        return fb_w / window_w if window_w > 0 and fb_w > 0 else 1.0

    def _panel_pixels(self) -> int:
        return round(PANEL_WIDTH * self._scale())

    def _fit_window(self, width: int, height: int) -> None:
        """Size the window so the picture gets ``width x height`` framebuffer pixels."""
        scale = self._scale()
        glfw.set_window_size(self.window, max(1, round(width / scale) + PANEL_WIDTH),
                             max(1, round(height / scale)))
        glfw.set_window_size_limits(self.window, PANEL_WIDTH + 16, 120, glfw.DONT_CARE,
                                    glfw.DONT_CARE)

    def picture_size(self) -> tuple[int, int]:
        """The picture's size in framebuffer pixels: the window less the panel."""
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        return max(fb_w - self._panel_pixels(), 0), max(fb_h, 0)

    def _on_picture(self, x: float, y: float) -> bool:
        """Is the screen point (x, y) (from the window's top-left) on the picture?"""
        scale = self._scale()
        width, height = self.state.size
        return 0 <= x * scale < width and 0 <= y * scale < height

    # -- glfw callbacks: forward to ImGui, then act unless ImGui took the event ---------------
    def _install_callbacks(self) -> None:
        w = self.window
        glfw.set_mouse_button_callback(w, self._on_mouse_button)
        glfw.set_key_callback(w, self._on_key)
        glfw.set_char_callback(w, self._on_char)
        glfw.set_scroll_callback(w, self._on_scroll)
        glfw.set_cursor_pos_callback(w, self._on_cursor)
        glfw.set_cursor_enter_callback(w, self._on_cursor_enter)
        glfw.set_framebuffer_size_callback(w, self._on_framebuffer_size)
        glfw.set_window_refresh_callback(w, lambda *_: self._wake())
        glfw.set_window_focus_callback(w, lambda *_: self._wake())
        self._install_drop()

    def _wake(self) -> None:
        self._busy = FRAMES_AFTER_EVENT

    def _on_mouse_button(self, window, button, action, mods) -> None:
        self.input.on_mouse_button(button, action)
        if action in (glfw.PRESS, glfw.RELEASE) and button in (
                glfw.MOUSE_BUTTON_LEFT, glfw.MOUSE_BUTTON_RIGHT, glfw.MOUSE_BUTTON_MIDDLE):
            # Decided in the next frame, once ImGui has seen this press at this position.
            self._clicks.append((button, action, *glfw.get_cursor_pos(window), mods))
        self._wake()

    def _on_key(self, window, key, scancode, action, mods) -> None:
        self.input.on_key(key, action, mods)
        self._wake()
        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        if key == glfw.KEY_ESCAPE and self._popup_open:
            self._close_popups = True     # Esc closes the open menu or pop-up, nothing more
            log.info("action: key Esc -> close the open menu")
            return
        if key == glfw.KEY_ESCAPE and self.state.open_messages:
            self.state.clear_messages()   # an error is a message to dismiss, not a reason to quit
            log.info("action: key Esc -> dismiss the message")
            return
        if imgui.get_io().want_capture_keyboard:
            return                        # typing in a text field
        if self._hand_key(key, mods):
            return
        if key == glfw.KEY_ESCAPE:
            self.quit("key Esc")
        elif key == glfw.KEY_SPACE and action == glfw.PRESS:
            self.toggle_play("key Space")
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
        elif char == "a":
            self.choose("keep_aspect", not self.state.keep_aspect, "key a")
        elif char == "t":                 # the next texture filter
            from core.texture.modes import FILTERS
            names = tuple(FILTERS)
            after = names[(names.index(self.state.texture_filter) + 1) % len(names)]
            self.choose("texture_filter", after, "key t")
        elif char == "s":
            self.save_screenshot("key s")
        elif char == "r":
            self.choose("renderer", "zbuffer" if self.state.renderer_name == "raytrace"
                        else "raytrace", "key r")
        elif char == "b":
            self.choose("bump", not self.state.bump, "key b")
        elif char in ",." and self.state.animated:
            self.step_frame(-1 if char == "," else +1, f"key {char}")
        elif char in "[]" and self.state.animated:
            self.change_speed(0.5 if char == "[" else 2.0, f"key {char}")
        elif char == "q":
            self.quit("key q")
        elif char == "i":                 # inspect mode, buffer views, compare
            self.tools.toggle_inspect("key i")
        elif char == "v":
            self.tools.next_buffer("key v")
        elif char == "h":
            self.tools.flip("key h")
        elif char == "f":
            self.fit_view("key f")
        elif char == "y":
            self.set_rotation("turntable" if self.hands.rotation == "arcball" else "arcball",
                              "key y")
        elif char == "l":
            self.choose("headlight", not self.state.headlight, "key l")

    def _on_cursor(self, window, x, y) -> None:
        self.input.on_cursor(x, y)
        self._wake()

    def _on_cursor_enter(self, window, entered) -> None:
        self.input.on_cursor_enter(bool(entered))
        self._wake()

    def _on_scroll(self, window, x_offset, y_offset) -> None:
        self.input.on_scroll(x_offset, y_offset)
        self._wake()
        self._hand_wheel(y_offset)

    def _on_framebuffer_size(self, window, width, height) -> None:
        self._fit_picture()
        self._wake()

    def _fit_picture(self) -> None:
        """Give the picture what the panel leaves; say when that is nothing."""
        shown = self.state.renderable
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        self.state.resize(*self.picture_size())
        if shown != self.state.renderable and fb_w > 0 and fb_h > 0:
            log.info("picture %s", "shown" if self.state.renderable
                     else "hidden: the panel takes the whole window")

    # -- actions -----------------------------------------------------------------------------
    def step_view(self, step: int, how: str) -> None:
        before = self.state.view_label
        self.state.next_view() if step > 0 else self.state.prev_view()
        log.info("action: %s -> %s %s -> %s", how, "next" if step > 0 else "previous",
                 before, self.state.view_label)

    def go_to_view(self, index: int, how: str) -> None:
        self.state.set_view(index)
        log.info("action: %s -> %s", how, self.state.view_label)

    def choose(self, what: str, value, how: str) -> None:
        """Set the projection, shading, rasterizer, kept aspect or course rules; the frame is
        re-rendered at once."""
        setter = {"projection": self.state.set_projection, "shading": self.state.set_shading,
                  "rasterizer": self.state.set_rasterizer,
                  "keep_aspect": self.state.set_keep_aspect,
                  "course_tri": self.state.set_course_tri,
                  "renderer": self.state.set_renderer,
                  "texture_filter": self.state.set_texture_filter,
                  "bump": self.state.set_bump,
                  "depth_cue": self.state.set_depth_cue,
                  "transparency": self.state.set_transparency,
                  "paint_first": self.state.set_paint_first,
                  "lighting_model": self.state.set_lighting_model,
                  "headlight": self.state.set_headlight,
                  "depth_shading": self.state.set_depth_shading}[what]
        setter(value)
        log.info("action: %s -> %s %s", how, what, value)
        if what == "projection":
            self.hands.projection_changed()     # a moved camera's F and B for the new one
        self._wake()

    # -- an animated scene's timeline ---------------------------------------------------------
    def toggle_play(self, how: str) -> None:
        if not self.state.animated:
            log.info("action: %s -> nothing to play (the scene is not animated)", how)
            return
        self.state.toggle_play(time.perf_counter())
        log.info("action: %s -> %s at t=%.3f", how, "play" if self.state.playing else "pause",
                 self.state.playback.time)
        self._wake()

    def step_frame(self, frames: int, how: str) -> None:
        self.state.step_frame(frames)
        log.info("action: %s -> %s frame: %s", how, "next" if frames > 0 else "previous",
                 self.state.playback.label())
        self._wake()

    def change_speed(self, factor: float, how: str) -> None:
        from app.session.playback import SPEEDS
        speed = min(max(self.state.playback.speed * factor, SPEEDS[0]), SPEEDS[-1])
        self.state.set_speed(speed)
        log.info("action: %s -> speed %gx", how, speed)
        self._wake()

    def open_scene(self, source: str, how: str) -> None:
        source = source.strip()
        if not source:
            return
        earlier = len(self.state.open_messages)
        if self.state.open_scene(source):
            log.info("action: %s -> opened %s (%s)", how, source, self.state.view_label)
            self.recent.add(source)
            self._notice = ""             # what the panel said of the last scene goes with it
            self.tools.scene_changed()
            self.hands.message = ""
            for message in self.state.scene.view_messages:
                print(f"invalid view: {message}", file=sys.stderr)
            glfw.set_window_title(self.window, self._title())
        else:                             # this failure's messages only, not the earlier ones
            new = self.state.open_messages[earlier:]
            log.info("action: %s -> %s", how, new[0] if new else "not opened")
            print("\n".join(new), file=sys.stderr)
        self._wake()

    def save_screenshot(self, how: str) -> Path | None:
        """The CPU frame (not the screen: no panel) as a PNG in ``screenshots/``."""
        frame = self.state.frame
        if frame is None:
            log.info("action: %s -> no frame to save yet", how)
            return None
        from PIL import Image

        s = self.state
        path = unused(self.out_dir / picture_name(s.scene.name, s.view_number, s.projection,
                                                  s.shading, s.renderer_name))
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
            # Show the window (panel, the scene's background) before the first CPU frame: that
            # frame may wait for numba to load or compile its kernels.
            self.draw_frame()
            self._log_since_start("window shown")
            shown = True
            while not glfw.window_should_close(self.window):
                # Sleep until an event unless a frame is due; while the worker renders, wake
                # ten times a second to show how long it has taken (it wakes us when done).
                if shown and self._redraw_can_wait():
                    # a drag waits for its frame: sleep until the next pointer move, the
                    # frame, or the next redraw (polling here spun 600 times a second and took
                    # a third of a core, and the GIL, from the renderer)
                    glfw.wait_events_timeout(max(1e-3, GESTURE_REDRAW_S
                                                 - (time.perf_counter() - self._swapped_at)))
                elif shown and (self._busy > 0 or self.state.dirty):
                    glfw.poll_events()
                elif self.state.playing:
                    glfw.wait_events_timeout(1 / 60)     # the movie's clock moves on
                elif self.worker.waiting or self.tools.busy:
                    glfw.wait_events_timeout(0.1)
                else:
                    glfw.wait_events_timeout(0.5)
                shown = self.draw_frame()
        finally:
            self.close()
        return 0

    def draw_frame(self) -> bool:
        """Input, clicks, ask for / collect a frame, GUI, blit, swap; False when minimised."""
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        self._fit_picture()
        if fb_w <= 0 or fb_h <= 0 or glfw.get_window_attrib(self.window, glfw.ICONIFIED):
            self._clicks.clear()
            self._busy = 0
            return False                  # minimised: nothing to render or draw
        self._busy -= 1
        self.input.new_frame()
        self.gui.new_frame()
        imgui.new_frame()
        self._handle_clicks()

        self._frames_in()
        if self.worker.waiting:
            self.tools.note_progress(self.worker.progress().fraction)
        if self._redraw_can_wait():
            imgui.end_frame()             # nothing new to show: the renderer keeps the CPU
            return True
        self._build_gui()
        imgui.render()

        self._draw_picture(fb_w, fb_h)
        self.gui.render(imgui.get_draw_data())
        glfw.swap_buffers(self.window)
        self._swapped_at, self._picture_new = time.perf_counter(), False
        if not self._first_frame_logged and self.state.frame is not None:
            self._first_frame_logged = True
            self._log_since_start("first frame shown")
            startup_gc.resume()
        elif self.started is not None and time.perf_counter() - self.started > startup_gc.LATEST_S:
            startup_gc.resume()
        if self._warm_up_due:
            self._warm_up_due = False
            self._start_warm_up()
        return True

    def _redraw_can_wait(self) -> bool:
        """While a camera gesture waits for its frame and no new picture came, the window
        need not be drawn again at every pointer move (each redraw of the panel and the
        picture costs the software GL a few ms of the CPU the renderer is using): at most
        every ``GESTURE_REDRAW_S``. No panel widget is active during a gesture on the picture,
        so skipping its frames loses nothing."""
        drag = self.hands.drag
        return (drag is not None and drag.start is not None and not self._picture_new
                and time.perf_counter() - self._swapped_at < GESTURE_REDRAW_S)

    def _frames_in(self) -> None:
        """Ask the worker for the next frame and take the one it finished, if any."""
        self._note_kernels()
        self._poll_dialog()
        self.state.tick(time.perf_counter(), busy=self.worker.waiting)
        if self.state.request(self.worker):
            self._compiles_at_request = compile_count()
        self.tools.poll()                 # a buffer view, a record, a comparison: done?
        result = self.worker.collect()
        if result is not None and self.state.accept(result):
            if getattr(result, "final", True):
                self._log_frame()
                self._warm_up_due = True  # once this frame is on screen (the thread takes the GIL)
                self.tools.frame_changed(self.state.frame, self.state.frame_seconds)
            else:
                log.info("partial frame: %s (%s)", result.what,
                         self.state.frame.stats.get("pass", "on its way"))
                self.tools.note_convergence(self.state.frame.stats)
            self.blit.upload(self.tools.picture(self.state.frame))
            self.tools.changed = False
            self._picture_new = True
            self._wake()                  # the GUI shows the new frame's plan and timing next
        if self.tools.changed and self.state.frame is not None:
            self.blit.upload(self.tools.picture(self.state.frame))
            self.tools.changed, self._picture_new = False, True

    def _draw_picture(self, fb_w: int, fb_h: int) -> None:
        """Clear, then blit the picture inside its own area."""
        self.ctx.viewport = (0, 0, fb_w, fb_h)
        if self.state.frame is None or not self.state.renderable:
            self.ctx.clear(*WINDOW_GREY)
        else:
            clear_around(self.ctx, (fb_w, fb_h), self.state.size, WINDOW_GREY)
        if self.state.frame is not None and self.state.renderable:
            # after a scene change, never the old scene's picture; and only inside the picture's
            # area, so a frame of the old, larger size never shows under the panel
            # a frame of another size (resized, the new one due) is stretched over the picture
            width, height = self.state.size
            origin = (0, fb_h - height)   # the picture's bottom-left, GL counts rows up
            self.ctx.viewport = (*origin, width, height)
            self.ctx.scissor = (0, fb_h - self.state.size[1], *self.state.size)
            self.blit.draw(origin, shown=(width, height))
            self.ctx.scissor = None
            self.ctx.viewport = (0, 0, fb_w, fb_h)

    def _start_kernel_processes(self) -> None:
        """A cold kernel cache: compile it in worker processes, and gate the frames on it
        (app/viewer/kernels.py); a warm one needs nothing."""
        from app.distribution.warmup import BackgroundWarmup, is_warm
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
        self._wake()

    def _start_warm_up(self) -> None:
        """After the first frame: load (or compile) every other kernel in the background."""
        if self._warming or self.warmup is not None:
            return                        # worker processes compile them, not this one
        self._warming = True
        from app.distribution.warmup import steps
        self.worker.add_background(steps())

    def _log_since_start(self, what: str) -> None:
        if self.started is None:
            log.info("%s", what)
        else:
            # CPU seconds too: on a busy machine the wall time says more about the neighbours.
            user, system = os.times()[:2]
            log.info("%s %.3f s after process start (%.3f s CPU)", what,
                     time.perf_counter() - self.started, user + system)

    def _handle_clicks(self) -> None:
        """Presses and releases since the last frame, in order. A left or middle press on the
        picture starts a gesture (app.viewer.hands): past ImGui's drag threshold it orbits or
        pans, released before it is a click. Right press: the pop-up (or, with the course's
        rules, the startup code's buttons) at once — only on the picture, and unless ImGui
        wants this click."""
        clicks, self._clicks = self._clicks, []
        captured = bool(clicks) and (imgui.get_io().want_capture_mouse or self._popup_open)
        for button, action, x, y, mods in clicks:
            if action == glfw.RELEASE:
                self._hand_release(button, x, y)
                continue
            name = {glfw.MOUSE_BUTTON_LEFT: "left", glfw.MOUSE_BUTTON_RIGHT: "right"}.get(
                button, "middle") + " click"
            where = f"{name} at ({x:.0f}, {y:.0f})"
            if captured or not self._on_picture(x, y):
                log.info("action: %s -> taken by the menu/panel, view unchanged", where)
            elif button == glfw.MOUSE_BUTTON_RIGHT:
                self._click(button, x, y, where)
            else:
                self._hand_press(button, x, y, mods, where)
        self._hand_follow()

    def _click(self, button: int, x: float, y: float, where: str) -> None:
        """A click on the picture (a press released without a drag, or a right press)."""
        if (demo := self.state.demo_click(button == glfw.MOUSE_BUTTON_LEFT)) is not None:
            log.info("action: %s -> the bump demo: %s", where, demo)
        elif self.state.playing and button == glfw.MOUSE_BUTTON_LEFT:
            self.toggle_play(where)
        elif self.tools.inspecting and button == glfw.MOUSE_BUTTON_LEFT:
            self.tools.inspect(*self._frame_pixel(x, y), where)
        elif self.state.course_tri:
            self.choose("shading", COURSE_BUTTONS[button], f"{where} (course buttons)")
        elif button == glfw.MOUSE_BUTTON_LEFT:
            self.step_view(+1, where)
        elif button == glfw.MOUSE_BUTTON_RIGHT:
            log.info("action: %s -> pop-up menu", where)
            imgui.open_popup("popup")

    # -- the camera's hands (app.viewer.hands): drags, the wheel, Enter and F ----------------
    def _init_hands(self) -> None:
        self.hands = CameraHands(self.state)
        self.loupe = Loupe()
        self._loupe_drag: tuple[int, int] | None = None     # a drag moving the loupe's picture
        self._pressed: tuple[int, float, float, str] | None = None   # button, x, y, where
        self._swapped_at, self._picture_new = 0.0, False    # the last redraw; a picture since

    def _drag_threshold(self) -> float:
        """ImGui's drag threshold, in framebuffer pixels."""
        return float(imgui.get_io().mouse_drag_threshold) * self._scale()

    def _hand_press(self, button: int, x: float, y: float, mods: int, where: str) -> None:
        pan = button == glfw.MOUSE_BUTTON_MIDDLE or bool(mods & glfw.MOD_SHIFT)
        scale = self._scale()
        self.hands.press(x * scale, y * scale, pan, None if pan else self._point_under(x, y))
        self._pressed = (button, x, y, where)
        # magnified, a drag moves the loupe's picture instead of the camera
        self._loupe_drag = self.loupe.screen if self.loupe.magnification > 1 else None

    def _hand_release(self, button: int, x: float, y: float) -> None:
        if self._pressed is None or self._pressed[0] != button:
            return
        _, x0, y0, where = self._pressed
        self._pressed = None
        scale = self._scale()
        drag = self.hands.drag
        pan = drag is not None and drag.pan
        if self._loupe_drag is not None:
            self.hands.drag, start, self._loupe_drag = None, self._loupe_drag, None
            if np.hypot(x - x0, y - y0) * scale <= self._drag_threshold():
                self._click(button, x0, y0, where)
            else:
                self._pan_loupe(start, x - x0, y - y0)
                log.info("action: drag the loupe by (%.0f, %.0f)", x - x0, y - y0)
            return
        if not self.hands.release(x * scale, y * scale, self._drag_threshold()):
            self._click(button, x0, y0, where)
            return
        what = "pan" if pan else f"{self.hands.rotation} orbit about {pivot_words(drag)}"
        self._log_camera(f"drag {what} from ({x0:.0f}, {y0:.0f}) to ({x:.0f}, {y:.0f})")

    def _hand_follow(self) -> None:
        """While a button is down: the gesture follows the pointer (the latest camera wins:
        the worker renders only the newest request)."""
        if self.hands.drag is None:
            return
        x, y = glfw.get_cursor_pos(self.window)
        if (self._pressed is not None and not self._clicks
                and glfw.get_mouse_button(self.window, self._pressed[0]) != glfw.PRESS):
            self._hand_release(self._pressed[0], x, y)    # a release the window never saw
            return
        scale = self._scale()
        if self._loupe_drag is not None:
            d = self.hands.drag
            if np.hypot(x * scale - d.x, y * scale - d.y) > self._drag_threshold():
                self._pan_loupe(self._loupe_drag, x * scale - d.x, y * scale - d.y)
            return
        if self.hands.move(x * scale, y * scale, self._drag_threshold()):
            self._wake()

    def _frame_pixel(self, x: float, y: float) -> tuple[int, int]:
        """The frame pixel shown at screen point (x, y): through the loupe, and stretched as
        the blit stretches a frame of the old size after a resize (app.viewer.loupe)."""
        scale = self._scale()
        texel = self.loupe.texel_at(x * scale, y * scale)
        frame = self.state.frame
        if frame is None:
            return texel
        return stretched(texel, self.state.size, frame.color.shape[1::-1])

    def _resizing(self) -> bool:
        """Is the frame shown of another size than the picture (a resize, its frame due)?"""
        frame = self.state.frame
        return frame is not None and frame.color.shape[1::-1] != tuple(self.state.size)

    def _point_under(self, x: float, y: float):
        """The world point drawn at screen point (x, y), from the shown frame's depth
        (app.session.pick); None off the model or where the frame keeps no depth."""
        from app.session.pick import PICK_KEY, point_at
        frame = self.state.frame
        if frame is None or self.hands.pivot != "cursor":
            return None
        return point_at(frame.stats.get(PICK_KEY), *self._frame_pixel(x, y))

    def set_rotation(self, rotation: str, how: str) -> None:
        self.hands.set_rotation(rotation)
        log.info("action: %s -> rotation %s", how, rotation)
        self._wake()

    def set_pivot(self, pivot: str, how: str) -> None:
        self.hands.set_pivot(pivot)
        log.info("action: %s -> orbit about %s", how, PIVOTS[pivot])
        self._wake()

    def _pan_loupe(self, start, dx: float, dy: float) -> None:
        self.loupe.pan_from(start, dx, dy)
        self.blit.loupe(**self.loupe.uniforms())
        self._wake()

    def set_loupe(self, m: int, how: str) -> None:
        """View > Loupe: 1:1 or a magnification round the picture's centre."""
        width, height = self.state.size
        self.loupe.set(m, width / 2, height / 2)
        self.blit.loupe(**self.loupe.uniforms())
        log.info("action: %s -> loupe %dx", how, self.loupe.magnification)
        self._wake()

    def _hand_wheel(self, notches: float) -> None:
        """The wheel on the picture: dolly; Ctrl: the window (field of view); Alt: the loupe."""
        x, y = glfw.get_cursor_pos(self.window)
        if imgui.get_io().want_capture_mouse or not self._on_picture(x, y) or not notches:
            return
        held = lambda *keys: any(glfw.get_key(self.window, k) == glfw.PRESS for k in keys)
        if held(glfw.KEY_LEFT_ALT, glfw.KEY_RIGHT_ALT):
            m = self.loupe.wheel(notches, x * self._scale(), y * self._scale())
            self.blit.loupe(**self.loupe.uniforms())
            log.info("action: Alt+wheel %+g at (%.0f, %.0f) -> loupe %dx", notches, x, y, m)
            return
        zoom = held(glfw.KEY_LEFT_CONTROL, glfw.KEY_RIGHT_CONTROL)
        if self.hands.wheel(notches, field_of_view=zoom):
            self._log_camera(f"wheel {notches:+g}{' with Ctrl (window)' if zoom else ' (dolly)'}")
        elif self.hands.message:
            log.info("action: wheel -> %s", self.hands.message)

    def _hand_key(self, key: int, mods: int) -> bool:
        """Enter: the file's view; F1: the keys' help; Ctrl+S: save the view. Returns whether
        the key was taken."""
        if key == glfw.KEY_S and mods & glfw.MOD_CONTROL:
            self.save_view("key Ctrl+S")
            return True
        if mods & glfw.MOD_CONTROL and (key == glfw.KEY_Y or (key == glfw.KEY_Z
                                                              and mods & glfw.MOD_SHIFT)):
            self.redo_camera("key Ctrl+Shift+Z" if key == glfw.KEY_Z else "key Ctrl+Y")
            return True
        if key == glfw.KEY_Z and mods & glfw.MOD_CONTROL:
            self.undo_camera("key Ctrl+Z")
            return True
        if key in (glfw.KEY_ENTER, glfw.KEY_KP_ENTER):
            self.reset_view("key Enter")
            return True
        if key == glfw.KEY_F1:
            self.toggle_help("key F1")
            return True
        return False

    def undo_camera(self, how: str) -> None:
        done = self.state.undo_camera()
        back, _ = self.state.camera_history
        log.info("action: %s -> %s", how, f"camera undone ({back} more to undo)" if done
                 else "nothing to undo")
        if done:
            self.hands.message = ""

    def redo_camera(self, how: str) -> None:
        done = self.state.redo_camera()
        _, ahead = self.state.camera_history
        log.info("action: %s -> %s", how, f"camera redone ({ahead} more to redo)" if done
                 else "nothing to redo")

    def reset_view(self, how: str) -> None:
        moved = self.hands.reset()
        log.info("action: %s -> %s", how, "the file's view again" if moved
                 else "already the file's view")
        self._wake()

    def fit_view(self, how: str) -> None:
        if self.hands.fit():
            self._log_camera(how + " (fit the scene's bounds)")
        else:
            log.info("action: %s -> %s", how, self.hands.message)
        self._wake()

    def toggle_help(self, how: str) -> None:
        self._help = not getattr(self, "_help", False)
        log.info("action: %s -> keys help %s", how, "shown" if self._help else "hidden")
        self._wake()

    def _log_camera(self, how: str) -> None:
        v = self.state.view
        numbers = lambda values: "(" + ", ".join(f"{float(c):.17g}" for c in values) + ")"
        log.info("action: %s -> camera VRP %s VPN %s VUP %s window %s PRP %s F %.17g B %.17g",
                 how, numbers(v.vrp), numbers(v.vpn), numbers(v.vup), numbers(v.window),
                 numbers(v.prp), v.front, v.back)
        self._wake()

    def save_view(self, how: str, path: Path | None = None) -> int | None:
        """Append the view shown to a view file (six lines); returns its number there."""
        view = self.state.view
        if view is None:
            return None
        if path is None:
            try:
                path = saved_views_file()
            except OSError as error:
                self._notice = f"could not make the folder for {SAVED_VIEWS}: {error}"
                log.info("action: %s -> %s", how, self._notice)
                return None
        path, s = Path(path), self.state
        comment = (f"saved from the viewer: {s.scene.name}, {s.projection}, {s.shading}, "
                   f"{s.size[0]}x{s.size[1]} ({view.label})")
        try:
            number = save_view(view, path, displayable(comment))
        except (OSError, ValueError) as error:
            self._notice = f"could not save the view to {path}: {error}"
            log.info("action: %s -> %s", how, self._notice)
            print(self._notice, file=sys.stderr)
            return None
        self._notice = f"view saved to {path} as view {number}"
        log.info("action: %s -> view saved to %s as view %d", how, path, number)
        return number

    # -- files: dropped, recent, the native dialog (app.viewer.files) -----------------------
    def _init_files(self) -> None:
        self.recent = RecentFiles()
        self.dialog = FileDialog()
        if self.state.scene_source != "-" and Path(self.state.scene_source).is_file():
            self.recent.add(self.state.scene_source)

    def _install_drop(self) -> None:
        """glfw's drop callback, given the raw bytes of each path: pyGLFW's own wrapper
        decodes them as UTF-8 and a name that is not would raise inside the callback."""
        dropfun = getattr(glfw, "_GLFWdropfun", None)
        library = getattr(glfw, "_glfw", None)
        if dropfun is None or not hasattr(library, "glfwSetDropCallback"):
            glfw.set_drop_callback(self.window, lambda _w, paths: self.on_drop(paths))
            return

        def raw(_window, count, c_paths):
            try:
                self.on_drop([c_paths[i] for i in range(count)])
            except Exception as error:        # never out of a C callback
                log.error("drop: %s", error, exc_info=error)
        self._drop_callback = dropfun(raw)    # kept: glfw holds only the C pointer
        library.glfwSetDropCallback(self.window, self._drop_callback)

    def on_drop(self, paths) -> bool:
        """Files dropped on the window: open the one dropped, or say why not (one message)."""
        path, why = check_drop(paths)
        if path is None:
            self.state.open_messages.append(why)
            log.info("action: drop -> %s", why)
            print(why, file=sys.stderr)
            self._wake()
            return False
        self.open_scene(path, "drop")
        return self.state.scene_source == path

    def _file_items(self) -> None:
        if imgui.menu_item_simple("Open with the file dialog...", None, False,
                                  not self.dialog.open):
            self._start_dialog("open", "Open a scene, mesh, .tri or view file")
        if imgui.begin_menu("Recent", bool(self.recent.paths)):
            for path, there in self.recent.items():
                if not there:
                    imgui.push_style_color(imgui.Col_.text,
                                           imgui.get_style_color_vec4(imgui.Col_.text_disabled))
                chosen = imgui.menu_item_simple(displayable(path), None,
                                                path == self.state.scene_source)
                if not there:
                    imgui.pop_style_color()
                if chosen:
                    self.open_recent(path)
            imgui.end_menu()
        if imgui.menu_item_simple("Save view as...", None, False, not self.dialog.open):
            self._start_dialog("save view", "Append the view to a view file", save=True)
        if imgui.menu_item_simple("Save screenshot as...", None, False,
                                  not self.dialog.open and self.state.frame is not None):
            self._start_dialog("save screenshot", "Save the frame as a PNG", save=True)

    def open_recent(self, path: str) -> None:
        if not Path(path).is_file():
            why = f"{path} is no longer there (moved or deleted since it was opened)"
            self.state.open_messages.append(why)
            log.info("action: menu File > Recent -> %s", why)
            self._wake()
            return
        self.open_scene(path, "menu File > Recent")

    def _start_dialog(self, purpose: str, title: str, save: bool = False) -> None:
        why = self.dialog.start(purpose, title, save=save)
        if why:
            self._notice = why
            log.info("action: file dialog (%s) -> %s", purpose, why)

    def _poll_dialog(self) -> None:
        done = self.dialog.poll()
        if done is None:
            return
        purpose, path = done
        if not path:
            log.info("action: file dialog (%s) -> cancelled", purpose)
        elif purpose == "open":
            self.open_scene(path, "file dialog")
        elif purpose == "save view":
            self.save_view("file dialog Save view as", Path(path))
        elif purpose == "save screenshot":
            self._save_frame_to(Path(path), "file dialog Save screenshot as")
        self._wake()

    def _cursor_line(self) -> None:
        """The status line's value under the cursor (through the loupe), and the loupe's m."""
        x, y = glfw.get_cursor_pos(self.window)
        if self.state.frame is None or not self._on_picture(x, y) or self._popup_open \
                or self.dialog.open:
            return                        # a menu or a dialog over the picture: not a pixel
        column, row = self._frame_pixel(x, y)
        zoom = f"loupe {self.loupe.magnification}x, " if self.loupe.magnification > 1 else ""
        if self._resizing():
            zoom = "resizing (the last frame, stretched): " + zoom
        ids, meshes = (None, ()) if imgui.is_any_mouse_down() else \
            self.tools.triangle_ids(self.state.frame)        # not while a drag moves the view
        imgui.text_disabled(zoom + value_at(self.state.frame, column, row, ids, meshes))

    def _save_frame_to(self, path: Path, how: str) -> None:
        """The CPU frame as a PNG at ``path`` (a dialog's choice; .png added when missing)."""
        from PIL import Image
        path = path if path.suffix.lower() == ".png" else path.with_name(path.name + ".png")
        try:
            Image.fromarray(self.state.frame.color).save(path)
        except (OSError, ValueError) as error:
            self._notice = f"could not save {path}: {error}"
        else:
            self._notice = f"saved {path.name}"
        log.info("action: %s -> %s", how, self._notice)

    def _help_strip(self) -> None:
        """F1 / Help > Keys: every key and mouse action, in the panel (never on the picture)."""
        if not getattr(self, "_help", False):
            return
        imgui.set_next_item_open(True, imgui.Cond_.always)
        if not imgui.collapsing_header("Keys and mouse (F1 closes)###help"):
            return
        imgui.push_text_wrap_pos(0.0)
        for key, what in KEYS_HELP:
            if not what:
                imgui.text_colored((0.55, 0.8, 1.0, 1.0), key)
            else:
                imgui.bullet()
                imgui.text_wrapped(displayable(f"{key}: {what}"))
        imgui.pop_text_wrap_pos()
        imgui.separator()

    def _camera_strip(self) -> None:
        """The view's numbers, live: VRP ... B and each factor of N_per / N_par."""
        view = self.state.view
        if view is None:
            return
        moved = " (moved)" if self.state.hand_view is not None else ""
        if not imgui.collapsing_header(f"Camera{moved}###camera",
                                       imgui.TreeNodeFlags_.default_open):
            if self.hands.message:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.hands.message))
            return
        imgui.push_text_wrap_pos(0.0)
        if self.hands.message:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.hands.message))
        for line in view_lines(view, self.state.projection):
            imgui.text(displayable(line))
        imgui.text_disabled(f"drag orbit ({self.hands.rotation}, about "
                            f"{PIVOTS[self.hands.pivot]}), Shift/middle drag pan, wheel dolly, "
                            "Ctrl+wheel window, F fit, Enter the file's view")
        imgui.pop_text_wrap_pos()

    def _log_frame(self) -> None:
        log.info("%s", self.state.frame_summary())
        if self.state.frame.message:
            print(self.state.frame.message, file=sys.stderr)
        glfw.set_window_title(self.window, self._title())

    def _title(self) -> str:
        s = self.state
        renderer = {"raytrace": " - ray traced", "radiosity": " - radiosity",
                    "pathtrace": " - path traced"}.get(s.renderer_name, "")
        return (f"FvD viewer - {s.scene.name} - {s.view_label} - {s.projection} - "
                f"{s.shading}{renderer}")

    # -- the GUI: the side panel and the pop-up ----------------------------------------------
    def _build_gui(self) -> None:
        self._panel()
        self._popup()
        self.dialog.draw(imgui, displayable, cancel=self._close_popups)   # Esc closes it
        self._popup_open = imgui.is_popup_open("", ANY_POPUP)
        self._close_popups = False

    def _closing(self) -> None:
        """Inside an open menu or pop-up: close it if Esc was pressed."""
        if self._close_popups:
            imgui.close_current_popup()

    def _projection_items(self, how: str) -> None:
        for value, label, key in PROJECTION_LABELS:
            if imgui.menu_item_simple(label, key, self.state.projection == value):
                self.choose("projection", value, how)

    def _shading_items(self, how: str) -> None:
        solid = self.state.has_triangles
        if not solid:
            imgui.push_text_wrap_pos(imgui.get_font_size() * 22)
            imgui.text_disabled(NO_TRIANGLES)
            imgui.pop_text_wrap_pos()
        from core.registry import shading_modes         # every registered mode, by its label
        for mode in shading_modes():
            if imgui.menu_item_simple(displayable(mode.label), mode.key,
                                      self.state.shading == mode.name, solid):
                self.choose("shading", mode.name, how)
        by_height = self.state.depth_shading == "height"
        if imgui.menu_item_simple("Depth colours by height (terrain map)", None, by_height,
                                  solid):
            self.choose("depth_shading", "view" if by_height else "height", how)

    def _panel(self) -> None:
        scale = self._scale()
        width, height = self.state.size
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        imgui.set_next_window_pos((width / scale, 0), imgui.Cond_.always)
        # no wider than the window, so that its text wraps where it can be read
        imgui.set_next_window_size((min(PANEL_WIDTH, fb_w / scale), fb_h / scale),
                                   imgui.Cond_.always)
        imgui.begin("panel", None, PANEL_FLAGS)
        self._menu_bar()
        self._help_strip()
        self._status()
        self._timeline()
        self.volume_panel.draw(imgui, displayable)
        self.tools.panel(imgui, displayable)
        self._draw_order()                    # the painter's draw-order slider
        options_panel.draw(imgui, self.state, displayable)   # the renderer's own options
        self._camera_strip()
        self._plan_strip()
        self._invalid_views_strip()
        self._messages_strip()
        imgui.end()

    def _menu_bar(self) -> None:
        if not imgui.begin_menu_bar():
            return
        for title, items, enabled in (("File", self._file_menu, True),
                                      ("Projection", lambda: self._projection_items(
                                          "menu Projection"), True),
                                      ("Shading", lambda: self._shading_items("menu Shading"),
                                       True),
                                      ("Render", self._render_items, True),
                                      ("View", self._view_menu, self.state.view_count > 0),
                                      ("?###Help", self._help_menu, True)):  # the bar is full
            if imgui.begin_menu(title, enabled):
                self._closing()
                items()
                imgui.end_menu()
        imgui.end_menu_bar()

    def _file_menu(self) -> None:
        if imgui.begin_menu("Open scene"):
            self._closing()
            imgui.text("Path:")               # first: on screen however long the list
            entered, self._path = imgui.input_text(
                "##path", self._path, flags=imgui.InputTextFlags_.enter_returns_true)
            imgui.same_line()
            if (imgui.button("Open") or entered) and self._path.strip():
                self.open_scene(self._path, "menu File > Open path")
                imgui.close_current_popup()
            imgui.separator()
            for path in self._scenes:
                if imgui.menu_item_simple(path.name, None,
                                          str(path) == self.state.scene_source):
                    self.open_scene(str(path), "menu File > Open")
            imgui.end_menu()
        self._file_items()
        if imgui.menu_item_simple("Save screenshot", "S"):
            self.save_screenshot("menu File > Save screenshot")
        imgui.separator()
        if imgui.menu_item_simple("Quit", "Q"):
            self.quit("menu File > Quit")

    def _view_menu(self) -> None:
        if imgui.menu_item_simple("Next view", "Right"):
            self.step_view(+1, "menu View > Next")
        if imgui.menu_item_simple("Previous view", "Left"):
            self.step_view(-1, "menu View > Previous")
        self._camera_items()
        imgui.separator()
        self._inspector_items()
        imgui.separator()
        from core.scene.view_numbers import file_number
        for i, view in enumerate(self.state.scene.views):
            number = file_number(self.state.scene, i)
            label = displayable(f"{number}: {view.label}###view{i}")
            if imgui.menu_item_simple(label, None, i == self.state.view_index):
                self.go_to_view(i, "menu View")

    def _help_menu(self) -> None:
        if imgui.menu_item_simple("Keys and mouse", "F1", getattr(self, "_help", False)):
            self.toggle_help("menu Help > Keys")

    def _camera_items(self) -> None:
        imgui.separator()
        if imgui.menu_item_simple("Reset to the file's view", "Enter", False,
                                  self.state.hand_view is not None):
            self.reset_view("menu View > Reset")
        if imgui.menu_item_simple("Fit the scene", "F"):
            self.fit_view("menu View > Fit")
        for pivot, words in PIVOTS.items():
            if imgui.menu_item_simple(f"Orbit about {words}", None, self.hands.pivot == pivot):
                self.set_pivot(pivot, "menu View > Orbit about")
        imgui.separator()
        for rotation, words in ROTATIONS.items():
            if imgui.menu_item_simple(words, "Y", self.hands.rotation == rotation):
                self.set_rotation(rotation, "menu View")
        back, ahead = self.state.camera_history
        if imgui.menu_item_simple("Undo camera", "Ctrl+Z", False, back > 0):
            self.undo_camera("menu View > Undo camera")
        if imgui.menu_item_simple("Redo camera", "Ctrl+Shift+Z", False, ahead > 0):
            self.redo_camera("menu View > Redo camera")
        if imgui.menu_item_simple(f"Save view (append to {SAVED_VIEWS}, state folder)",
                                  "Ctrl+S"):
            self.save_view("menu View > Save view")
        if imgui.begin_menu("Loupe (Alt+wheel)"):
            for m in (1, 2, 4, 8, 16, 32):
                if imgui.menu_item_simple("1:1" if m == 1 else f"{m}x", None,
                                          self.loupe.magnification == m):
                    self.set_loupe(m, "menu View > Loupe")
            imgui.end_menu()

    def _inspector_items(self) -> None:
        """The View menu's inspection tools: inspect mode, the buffer views, the comparison
        with OpenGL."""
        if imgui.menu_item_simple("Inspect mode (click a pixel)", "I", self.tools.inspecting):
            self.tools.toggle_inspect("menu View > Inspect mode")
        if imgui.begin_menu("Buffer view"):
            for name in ("picture", *self.tools.buffer_names()):
                if imgui.menu_item_simple(name, None, self.tools.buffer == name):
                    self.tools.choose_buffer(name, "menu View > Buffer view")
            imgui.end_menu()
        if imgui.menu_item_simple("Compare with OpenGL", "H", self.tools.showing_heat):
            self.tools.flip("menu View > Compare with OpenGL")

    def _lighting_model_items(self) -> None:
        """Every material lit by one registered lighting model, or each by its own."""
        from core.shading.models import lighting_models
        imgui.text_disabled("Lighting model")
        for value, label in (("", "Each material's own"),) + tuple(
                (m.name, m.label) for m in lighting_models()):
            if imgui.menu_item_simple(displayable(label), None,
                                      self.state.lighting_model == value):
                self.choose("lighting_model", value, "menu Render")

    def _render_items(self) -> None:
        from core.renderers import renderers
        imgui.text_disabled("Renderer")
        for entry in renderers():
            if entry.in_menu and imgui.menu_item_simple(
                    displayable(entry.label), RENDERER_KEYS.get(entry.name, ""),
                    self.state.renderer_name == entry.name):
                self.choose("renderer", entry.name, "menu Render")
        imgui.separator()
        self._lighting_model_items()
        if imgui.menu_item_simple("Headlight (a light at the eye)", "L", self.state.headlight):
            self.choose("headlight", not self.state.headlight, "menu Render")
        imgui.separator()
        imgui.text_disabled("Texture filter")
        for value, label in FILTER_LABELS:
            if imgui.menu_item_simple(label, "T", self.state.texture_filter == value):
                self.choose("texture_filter", value, "menu Render")
        if imgui.menu_item_simple("Bump and normal maps", "B", self.state.bump):
            self.choose("bump", not self.state.bump, "menu Render")
        imgui.separator()
        imgui.text_disabled("Rasterizer")
        for value, label in RASTERIZER_LABELS:
            if imgui.menu_item_simple(label, None, self.state.rasterizer == value,
                               self.state.has_triangles):
                self.choose("rasterizer", value, "menu Render")
        imgui.separator()
        if imgui.menu_item_simple("Keep the window's aspect (letterbox)", "A",
                           bool(self.state.keep_aspect)):
            self.choose("keep_aspect", not self.state.keep_aspect, "menu Render")
        if imgui.menu_item_simple("Course .tri rules (back faces, mouse)", None,
                           self.state.course_tri):
            self.choose("course_tri", not self.state.course_tri, "menu Render")
        self._painter_items()

    # -- depth cueing, transparency, the painter's draw-order slider ---------------------------
    def _painter_items(self) -> None:
        imgui.separator()
        cued = bool(self.state.settings().depth_cue)
        if imgui.menu_item_simple("Depth cueing", None, cued):
            self.choose("depth_cue", not cued, "menu Render")
        imgui.text_disabled("Transparency (k_t > 0)")
        current = self.state.settings().transparency
        from core.settings import TRANSPARENCIES
        for value, label in TRANSPARENCIES.items():
            if imgui.menu_item_simple(label, None, current == value):
                self.choose("transparency", value, "menu Render")

    def _draw_order(self) -> None:
        """The painter's renderers: a slider that paints only the first K triangles."""
        s = self.state
        total = s.painted_total
        if not s.renderer_entry.has_option("paint_first") or not total:
            return
        imgui.text("draw order (triangles painted)")
        imgui.push_item_width(-1)
        shown = total if s.paint_first is None else min(s.paint_first, total)
        changed, k = imgui.slider_int("##paint_first", shown, 0, total)
        imgui.pop_item_width()
        if changed:
            self.choose("paint_first", None if k >= total else k, "slider draw order")
        imgui.separator()

    def _popup(self) -> None:
        # The course's GLUT pop-up menu: projection and shading at the click.
        if imgui.begin_popup("popup"):
            self._closing()
            imgui.text_disabled("Projection")
            self._projection_items("pop-up")
            imgui.separator()
            imgui.text_disabled("Shading")
            self._shading_items("pop-up")
            imgui.separator()
            if imgui.menu_item_simple("Next view", "Right", False, self.state.view_count > 0):
                self.step_view(+1, "pop-up Next view")
            imgui.end_popup()

    def _status(self) -> None:
        s = self.state
        imgui.push_text_wrap_pos(0.0)
        problem = s.problem or self.hands.message
        if problem:                       # where the eye is, until the next success clears it
            imgui.text_colored(PROBLEM_COLOUR, displayable(problem))
        imgui.text(displayable(f"{s.scene.name}: {s.view_label}"))
        if s.view_count:
            imgui.text_disabled(displayable(s.view.label))
        rasterizer = (f", {s.rasterizer} rasterizer"                 # the tracers have none
                      if s.has_triangles and s.renderer_entry.rasterizes else "")
        imgui.text(f"{s.projection}, {s.shading}{rasterizer}")
        imgui.text("aspect kept (letterbox)" if s.keep_aspect
                   else "window stretched over the viewport")
        if s.course_tri:
            imgui.text_disabled("course .tri rules: left Phong, middle Gouraud, right flat")
        words = s.renderer_entry.status                   # the registry entry's status words
        extras = [words + (" (refining)" if s.frame_partial else "")] if words else []
        if s.has_textures:
            extras.append(f"{s.texture_filter} textures" + ("" if s.bump else ", no bump maps"))
        if s.shading == "depth":
            extras.append("depth: " + ("height, terrain map" if s.depth_shading == "height"
                                       else "distance from the eye, near bright"))
        if s.headlight_note:
            extras.append(s.headlight_note)
        if extras:
            imgui.text(", ".join(extras))
        for note in (s.frame.stats.get("not drawn", []) if s.frame is not None else []):
            imgui.text_colored((1.0, 0.7, 0.3, 1.0), displayable(f"not drawn: {note}"))
        if s.bump_label:
            imgui.text_colored((0.6, 0.7, 1.0, 1.0), displayable(s.bump_label))
            imgui.text_disabled("left click: bump / Phong; other buttons: next map")
        if not s.renderable:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0),
                               "the panel takes the whole window: widen it to see the picture")
        elif s.frame is None:
            imgui.text("")
        else:
            imgui.text(f"{s.size[0]} x {s.size[1]}, frame {s.frame_seconds * 1e3:.1f} ms")
        self._progress_line(displayable(self._progress_text()))
        if self._notice:
            imgui.text_disabled(displayable(self._notice))
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
        p = self.worker.progress()
        compiling = status(self.warmup) if self.warmup is not None else ""
        if compiling and not self.warmup.finished and not (p.what and p.frame):
            return compiling
        compiled = compile_count() - self._compiles_at_request
        extra = f", compiling kernels ({compiled} so far)" if compiled else ""
        if p.what and p.frame:
            how_far = (f", {p.detail}" if p.detail else "") + (
                f" ({p.fraction * 100:.0f}%)" if p.fraction is not None else "")
            return f"rendering {p.what}: {time.perf_counter() - p.since:.1f} s{how_far}{extra}"
        if p.what and self.worker.waiting:
            return (f"your frame is next; loading kernels ({p.done + 1} of {p.total}: "
                    f"{p.what}) {time.perf_counter() - p.since:.1f} s{extra}")
        if self.tools.busy:
            return f"{self.tools.busy} (the picture stays until it is there)"
        if p.done < p.total:
            return f"loading kernels in the background: {p.done} of {p.total}"
        return compiling or "ready"

    def _timeline(self) -> None:
        """An animated scene: play / pause, step, the timeline slider and the speed."""
        playback = self.state.playback
        if playback is None:
            return
        from app.session.playback import SPEEDS
        if imgui.button("Pause" if playback.playing else "Play"):
            self.toggle_play("button Play")
        imgui.same_line()
        if imgui.button("<"):
            self.step_frame(-1, "button <")
        imgui.same_line()
        if imgui.button(">"):
            self.step_frame(+1, "button >")
        imgui.same_line()
        imgui.text(f"frame {playback.frame_index + 1} of {playback.frame_count}")
        imgui.push_item_width(-1)
        changed, t = imgui.slider_float("##time", playback.time, 0.0,
                                        max(playback.end, 1e-6), "%.2f s")
        if changed:
            self.state.seek(t, time.perf_counter())
            self._wake()
        labels = [f"{v:g}x" for v in SPEEDS]
        current = min(range(len(SPEEDS)), key=lambda i: abs(SPEEDS[i] - playback.speed))
        changed, chosen = imgui.combo("##speed", current, labels)
        if changed:
            self.state.set_speed(SPEEDS[chosen])
            log.info("action: speed -> %gx", SPEEDS[chosen])
        imgui.pop_item_width()
        imgui.text_disabled("space play/pause, , . step, [ ] speed")
        imgui.separator()

    def _plan_strip(self) -> None:
        frame = self.state.frame
        if frame is None:
            return
        expanded = imgui.collapsing_header(f"Plan  {self.state.frame_seconds * 1e3:.1f} ms"
                                           "###plan")
        if not expanded:
            return
        stage_ms = frame.stats.get("ms", {}) if isinstance(frame.stats, dict) else {}
        imgui.push_text_wrap_pos(0.0)
        for stage in frame.plan:
            name = getattr(stage, "name", str(stage))
            ms = stage_ms.get(name)
            timing = f" ({ms:.1f} ms)" if ms is not None else ""
            if getattr(stage, "runs", True):
                imgui.text_colored((0.55, 0.9, 0.55, 1.0), displayable(f"run   {name}{timing}"))
            else:
                imgui.text_colored((0.6, 0.6, 0.6, 1.0), displayable(f"skip  {name}"))
            reason = getattr(stage, "reason", "")
            if reason:
                imgui.indent(16)
                imgui.text_disabled(displayable(reason))
                imgui.unindent(16)
        imgui.pop_text_wrap_pos()

    def _invalid_views_strip(self) -> None:
        invalid = self.state.invalid_messages
        if not invalid:
            return
        expanded = imgui.collapsing_header(f"Invalid views ({len(invalid)})###invalid")
        if expanded:
            imgui.push_text_wrap_pos(0.0)
            for message in invalid:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(message))
            imgui.pop_text_wrap_pos()

    def _messages_strip(self) -> None:
        notices = self.state.notices
        if not notices:
            return
        expanded = imgui.collapsing_header(f"Messages ({len(notices)})###messages",
                                           imgui.TreeNodeFlags_.default_open)
        if expanded:
            if self.state.open_messages and imgui.small_button("Clear"):
                self.state.clear_messages()
            imgui.push_text_wrap_pos(0.0)
            for message in notices:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(message))
            imgui.pop_text_wrap_pos()

    def close(self) -> None:
        self.worker.stop()
        if self.warmup is not None:
            self.warmup.stop()            # its processes end with the window
        self.gui.release()
        self.blit.release()
        imgui.destroy_context(self.gui_context)
        glfw.destroy_window(self.window)
        glfw.terminate()
