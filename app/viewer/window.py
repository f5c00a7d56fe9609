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

The window is made of parts, one job each, all acting on the one
:class:`app.session.state.ViewerState`: the loop and the frames coming in
(:mod:`app.viewer.loop`), the keys (:mod:`app.viewer.keys`), the mouse and the camera's hands
(:mod:`app.viewer.pointer`), the actions they call (:mod:`app.viewer.actions`), the menus
(:mod:`app.viewer.menus`), the side panel (:mod:`app.viewer.panel`) and its status lines
(:mod:`app.viewer.status`), and the files (:mod:`app.viewer.file_handling`). This module
makes the glfw window and its GL context, holds the parts and the objects they share, and
knows where the picture and the panel lie.

Every user action and every new frame is logged (logger ``fvd``; ``app.viewer`` sends it to
stderr and to ``$FVD_LOG``). On HiDPI screens sizes in points are scaled so that the picture
gets the requested pixels; a minimised (0 x 0) window renders nothing.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path


# imgui-bundle points pyGLFW at the libglfw in its own wheel (``PYGLFW_LIBRARY``) unless the user
# named one: one GLFW in the process, and pyGLFW does not load every libglfw it finds in a
# Python subprocess to compare their versions (~40 ms at every start).
from imgui_bundle import imgui  # noqa: E402,I001  (first: it names the library glfw loads)
import glfw  # noqa: E402
import moderngl  # noqa: E402

from app.session.state import ViewerState
from app.viewer.actions import Actions
from app.viewer.blit import Blit
from app.viewer.file_handling import FileHandling, shipped_scenes  # noqa: F401
from app.viewer.gui_backend import GlfwInput, GuiRenderer
from app.viewer.gui_text import displayable  # noqa: F401  (the tests read it here)
from app.viewer.hands import CameraHands
from app.viewer.inspector_tools import InspectorTools
from app.viewer.keys import Keys
from app.viewer.loop import FRAMES_AFTER_EVENT, FrameLoop
from app.viewer.loupe import Loupe
from app.viewer.menus import Menus
from app.viewer.panel import PANEL_WIDTH, SidePanel
from app.viewer.pointer import Pointer
from app.viewer.status import StatusLine
from app.viewer.volume_panel import VolumePanel
from app.viewer.window_sizes import WindowSizes
from app.viewer.worker import RenderWorker

log = logging.getLogger("fvd")

SCREENSHOTS_DIR = "screenshots"


def window_title(s: ViewerState) -> str:
    """The window's title: scene, view, projection, shading and the renderer's title words
    (its registry entry's ``title``)."""
    words = s.choices.renderer_entry.title
    renderer = f" - {words}" if words else ""
    return (f"FvD viewer - {s.scene.name} - {s.views.label} - {s.projection} - "
            f"{s.shading}{renderer}")


class WindowError(RuntimeError):
    """No window could be made (no display, no OpenGL 3.3)."""


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
    """The window around one :class:`ViewerState`. ``run()`` returns when the user quits.

    It holds what the parts share (the state, the glfw window, the blit, the worker, the
    inspector's tools, the camera's hands, the loupe) and the parts themselves, each made with
    this window as its one way to the others."""

    def __init__(self, state: ViewerState, out_dir: Path | None = None,
                 started: float | None = None):
        self.state = state
        self.out_dir = Path(out_dir) if out_dir is not None else Path.cwd() / SCREENSHOTS_DIR
        self.started = started            # process start, in time.perf_counter() seconds
        width, height = state.size
        self.window = create_window((width + PANEL_WIDTH, height), self.title())
        glfw.ERROR_REPORTING = "log"      # later glfw errors are not fatal
        self.sizes = WindowSizes(self.window)     # kept from the callbacks: no X round trips
        self.fit_window(width, height)
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
            self.input = GlfwInput(self.window, self.sizes)
        except Exception as error:        # e.g. a shader that does not compile: close it all
            if self.gui_context is not None:
                imgui.destroy_context(self.gui_context)
            self.ctx.release()
            glfw.destroy_window(self.window)
            glfw.terminate()
            raise WindowError(f"could not set up the window: {error}") from error
        self.worker = RenderWorker(wake=glfw.post_empty_event)
        self.busy = FRAMES_AFTER_EVENT    # frames still to draw before sleeping
        self.notice = ""                  # the last screenshot or saved view, for the status line
        self.help_shown = False           # F1: the keys' help in the panel
        self.tools = InspectorTools(state)    # inspect mode, buffer views, compare
        self.tools.wake = glfw.post_empty_event
        self.volume_panel = VolumePanel(state, self.tools)   # transfer, iso, slices
        self.hands = CameraHands(state)
        self.loupe = Loupe()
        self._make_parts()
        self._install_callbacks()
        self._drop_callback = self.files.drop_callback    # glfw's, for the tests to call
        self.loop.start_kernel_processes()

    def _make_parts(self) -> None:
        self.loop = FrameLoop(self)       # the loop, the frames in, the kernels
        self.pointer = Pointer(self)      # clicks, drags, the wheel
        self.keys = Keys(self)
        self.actions = Actions(self)      # what keys, mouse and menus ask for, logged
        self.files = FileHandling(self)   # drops, recent files, the file dialog
        self.menus = Menus(self)
        self.status = StatusLine(self)
        self.panel = SidePanel(self)

    # -- what the tests and the launcher call --------------------------------------------------
    def run(self) -> int:
        return self.loop.run()

    def draw_frame(self) -> bool:
        return self.loop.draw_frame()

    def open_scene(self, source: str, how: str) -> None:
        self.actions.open_scene(source, how)

    def on_drop(self, paths) -> bool:
        return self.files.on_drop(paths)

    # -- geometry: the picture at the top-left, the panel to its right -----------------------
    def scale(self) -> float:
        """Framebuffer pixels per screen point (1 except on HiDPI screens)."""
        window_w, fb_w = self.sizes.window[0], self.sizes.framebuffer[0]
        return fb_w / window_w if window_w > 0 and fb_w > 0 else 1.0

    def panel_pixels(self) -> int:
        return round(PANEL_WIDTH * self.scale())

    def fit_window(self, width: int, height: int) -> None:
        """Size the window so the picture gets ``width x height`` framebuffer pixels."""
        scale = self.scale()
        glfw.set_window_size(self.window, max(1, round(width / scale) + PANEL_WIDTH),
                             max(1, round(height / scale)))
        glfw.set_window_size_limits(self.window, PANEL_WIDTH + 16, 120, glfw.DONT_CARE,
                                    glfw.DONT_CARE)

    def picture_size(self) -> tuple[int, int]:
        """The picture's size in framebuffer pixels: the window less the panel."""
        fb_w, fb_h = self.sizes.framebuffer
        return max(fb_w - self.panel_pixels(), 0), max(fb_h, 0)

    def on_picture(self, x: float, y: float) -> bool:
        """Is the screen point (x, y) (from the window's top-left) on the picture?"""
        scale = self.scale()
        width, height = self.state.size
        return 0 <= x * scale < width and 0 <= y * scale < height

    def _install_callbacks(self) -> None:
        w = self.window
        glfw.set_mouse_button_callback(w, self.pointer.on_mouse_button)
        glfw.set_key_callback(w, self.keys.on_key)
        glfw.set_char_callback(w, self.keys.on_char)
        glfw.set_scroll_callback(w, self._on_scroll)
        glfw.set_cursor_pos_callback(w, self._on_cursor)
        glfw.set_cursor_enter_callback(w, self._on_cursor_enter)
        glfw.set_framebuffer_size_callback(w, self._on_framebuffer_size)
        glfw.set_window_size_callback(w, lambda _, *size: self.sizes.on_window_size(*size))
        glfw.set_window_iconify_callback(w, lambda _, iconified: self.sizes.on_iconify(iconified))
        glfw.set_window_refresh_callback(w, lambda *_: self.wake())
        glfw.set_window_focus_callback(w, lambda *_: self.wake())
        self.files.install_drop()

    def wake(self) -> None:
        self.busy = FRAMES_AFTER_EVENT

    def _on_cursor(self, window, x, y) -> None:
        self.sizes.on_cursor(x, y)
        self.input.on_cursor(x, y)
        self.wake()
        if self.hands.drag is not None:      # a move that turns the camera: its wait counts
            self.loop.latency.input(time.perf_counter())

    def _on_cursor_enter(self, window, entered) -> None:
        self.input.on_cursor_enter(bool(entered))
        self.wake()

    def _on_scroll(self, window, x_offset, y_offset) -> None:
        self.input.on_scroll(x_offset, y_offset)
        self.wake()
        self.loop.latency.input(time.perf_counter())
        self.pointer.wheel(y_offset)

    def _on_framebuffer_size(self, window, width, height) -> None:
        self.sizes.on_framebuffer_size(width, height)
        self.fit_picture()
        self.wake()

    def fit_picture(self) -> None:
        """Give the picture what the panel leaves; say when that is nothing."""
        shown = self.state.renderable
        fb_w, fb_h = self.sizes.framebuffer
        self.state.resize(*self.picture_size())
        if shown != self.state.renderable and fb_w > 0 and fb_h > 0:
            log.info("picture %s", "shown" if self.state.renderable
                     else "hidden: the panel takes the whole window")

    def title(self) -> str:
        return window_title(self.state)

    def close(self) -> None:
        self.worker.stop()
        if self.loop.warmup is not None:
            self.loop.warmup.stop()       # its processes end with the window
        self.gui.release()
        self.blit.release()
        imgui.destroy_context(self.gui_context)
        glfw.destroy_window(self.window)
        glfw.terminate()
