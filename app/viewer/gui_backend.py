"""Dear ImGui in the window: imgui-bundle's own OpenGL 3 renderer, and glfw input fed to ImGui.

The GUI is Dear ImGui 1.92 through imgui-bundle (wheels for CPython 3.11-3.14 on Linux,
macOS and Windows; nothing to compile at install).

- :class:`GuiRenderer` is Dear ImGui's own ``imgui_impl_opengl3`` backend, as the binding
  ships it: it draws ``imgui.get_draw_data()`` into the framebuffer that is bound (the one the
  moderngl context made current), uploads the font atlas and any other texture Dear ImGui
  asks for (1.92's texture API), saves the GL state it touches and restores it afterwards, so
  moderngl's blit is unaffected. It never sees a vertex of the scene: the scene is a texture
  the blit drew before it.
- :class:`GlfwInput` turns the window's glfw callbacks into Dear ImGui's input events (display
  size, framebuffer scale, time step, mouse, wheel, keys, characters). It is ours rather than
  the binding's ``imgui_impl_glfw``: that one takes the C pointer of a window made by its own
  copy of libglfw, and the window here is made by pyGLFW's; the window also needs the
  callbacks itself (clicks on the picture, shortcuts), so it forwards each event here first
  and then asks ``io.want_capture_*`` whether the event was ImGui's.
"""

from __future__ import annotations

import math

import numpy as np
from imgui_bundle import imgui

GLSL_VERSION = "#version 330"        # the window's context is OpenGL 3.3 core


class GuiRenderer:
    """Dear ImGui's OpenGL 3 renderer on the current context (make the context first)."""

    def __init__(self):
        if imgui.get_current_context() is None:
            raise RuntimeError("create the ImGui context (imgui.create_context()) first")
        if not imgui.backends.opengl3_init(GLSL_VERSION):
            raise RuntimeError("Dear ImGui's OpenGL 3 renderer did not start (GLSL 3.30)")
        self._running = True

    def new_frame(self) -> None:
        """Before ``imgui.new_frame()``: the renderer's per-frame set-up."""
        imgui.backends.opengl3_new_frame()

    def render(self, draw_data) -> None:
        """Draw ``draw_data`` over the whole framebuffer (the backend sets its viewport)."""
        imgui.backends.opengl3_render_draw_data(draw_data)

    def release(self) -> None:
        if self._running:
            self._running = False
            imgui.backends.opengl3_shutdown()


def framebuffer_scale(points: int, pixels: int) -> float:
    """Pixels per point, as the float32 Dear ImGui keeps, whose product with ``points`` is
    at least ``pixels``: the OpenGL 3 backend truncates ``display_size * scale`` to size its
    viewport, and 401 points at 501/401 would give 500.99997, one pixel short, which moves
    every scissor rectangle by a row."""
    if points <= 0 or pixels <= 0:
        return 1.0
    scale = np.float32(pixels / points)
    while np.float32(points) * scale < pixels:
        scale = np.nextafter(scale, np.float32(math.inf))
    return float(scale)


def set_display(io, window_size: tuple[int, int], fb_size: tuple[int, int]) -> None:
    """The display in points and its framebuffer scale (HiDPI) for this frame."""
    (window_w, window_h), (fb_w, fb_h) = window_size, fb_size
    io.display_size = (window_w, window_h)
    if window_w > 0 and window_h > 0:
        io.display_framebuffer_scale = (framebuffer_scale(window_w, fb_w),
                                        framebuffer_scale(window_h, fb_h))


def _key_map(glfw) -> dict[int, int]:
    """glfw key codes to Dear ImGui's keys: the ones the panel's widgets use (text fields,
    sliders, menus' navigation) and the letters of the copy/paste/undo shortcuts."""
    keys = imgui.Key
    named = {
        glfw.KEY_TAB: keys.tab, glfw.KEY_LEFT: keys.left_arrow,
        glfw.KEY_RIGHT: keys.right_arrow, glfw.KEY_UP: keys.up_arrow,
        glfw.KEY_DOWN: keys.down_arrow, glfw.KEY_PAGE_UP: keys.page_up,
        glfw.KEY_PAGE_DOWN: keys.page_down, glfw.KEY_HOME: keys.home, glfw.KEY_END: keys.end,
        glfw.KEY_INSERT: keys.insert, glfw.KEY_DELETE: keys.delete,
        glfw.KEY_BACKSPACE: keys.backspace, glfw.KEY_SPACE: keys.space,
        glfw.KEY_ENTER: keys.enter, glfw.KEY_ESCAPE: keys.escape,
        glfw.KEY_KP_ENTER: keys.keypad_enter,
        glfw.KEY_LEFT_SHIFT: keys.left_shift, glfw.KEY_RIGHT_SHIFT: keys.right_shift,
        glfw.KEY_LEFT_CONTROL: keys.left_ctrl, glfw.KEY_RIGHT_CONTROL: keys.right_ctrl,
        glfw.KEY_LEFT_ALT: keys.left_alt, glfw.KEY_RIGHT_ALT: keys.right_alt,
        glfw.KEY_LEFT_SUPER: keys.left_super, glfw.KEY_RIGHT_SUPER: keys.right_super,
    }
    letters = {getattr(glfw, f"KEY_{c.upper()}"): getattr(keys, c) for c in "acvxyz"}
    return {**named, **letters}


class GlfwInput:
    """Feeds one glfw window's input to Dear ImGui; call :meth:`new_frame` before ImGui's.

    Events go into Dear ImGui's input queue as they arrive, so a press and a release between
    two frames are both seen, each where it happened.
    """

    def __init__(self, window, sizes):
        import glfw                      # only the window needs glfw; the renderer does not

        self._glfw = glfw
        self.window = window
        self.sizes = sizes               # the window's kept sizes (app.viewer.window_sizes)
        self.io = imgui.get_io()
        self._time = None
        self._keys = _key_map(glfw)

    # -- events, forwarded by the window's glfw callbacks ------------------------------------
    def on_key(self, key: int, action: int, mods: int) -> None:
        glfw, io = self._glfw, self.io
        if action not in (glfw.PRESS, glfw.RELEASE):
            return                       # a repeat: Dear ImGui repeats held keys itself
        io.add_key_event(imgui.Key.mod_ctrl, bool(mods & glfw.MOD_CONTROL))
        io.add_key_event(imgui.Key.mod_shift, bool(mods & glfw.MOD_SHIFT))
        io.add_key_event(imgui.Key.mod_alt, bool(mods & glfw.MOD_ALT))
        io.add_key_event(imgui.Key.mod_super, bool(mods & glfw.MOD_SUPER))
        if key in self._keys:
            io.add_key_event(self._keys[key], action == glfw.PRESS)

    def on_char(self, codepoint: int) -> None:
        if 0 < codepoint < 0x110000:
            self.io.add_input_character(codepoint)

    def on_scroll(self, x_offset: float, y_offset: float) -> None:
        self.io.add_mouse_wheel_event(x_offset, y_offset)

    def on_cursor(self, x: float, y: float) -> None:
        self.io.add_mouse_pos_event(x, y)

    def on_cursor_enter(self, entered: bool) -> None:
        if not entered:
            self.io.add_mouse_pos_event(-math.inf, -math.inf)    # Dear ImGui's "no mouse"

    def on_mouse_button(self, button: int, action: int) -> None:
        glfw = self._glfw
        if 0 <= button < 5:
            # Where the press happened: a motion event may not have come before it (a
            # pointer warped by xdotool), and ImGui must judge the click where it was made.
            self.io.add_mouse_pos_event(*glfw.get_cursor_pos(self.window))
            self.io.add_mouse_button_event(button, action == glfw.PRESS)

    # -- once per frame ----------------------------------------------------------------------
    def new_frame(self) -> None:
        """Display size, framebuffer scale and time step."""
        glfw = self._glfw
        set_display(self.io, self.sizes.window, self.sizes.framebuffer)
        now = glfw.get_time()
        self.io.delta_time = max(now - self._time, 1e-4) if self._time is not None else 1 / 60
        self._time = now
