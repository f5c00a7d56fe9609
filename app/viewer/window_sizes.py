"""The window's size, its framebuffer's, whether it is minimised, the pointer's position and
the title shown, kept from glfw's callbacks.

Asking glfw for them is an X round trip each (0.13 ms under Xvfb): the loop asked about
fifteen times a turn, 2 ms of the UI thread for every picture of a drag. glfw says when they
change (the window-size, framebuffer-size, iconify and cursor-position callbacks), so the
window keeps them here and asks the server only once, at the start; and the title is sent
only when it changes (it was sent with every frame).
"""

from __future__ import annotations

from imgui_bundle import imgui  # noqa: F401,I001  (first: it names the library glfw loads)
import glfw


class WindowSizes:
    """``window`` (screen points), ``framebuffer`` (pixels), ``iconified`` and ``cursor``
    (points from the window's top left), current as of the last callback."""

    def __init__(self, window):
        self._handle = window
        self.window = tuple(glfw.get_window_size(window))
        self.framebuffer = tuple(glfw.get_framebuffer_size(window))
        self.iconified = bool(glfw.get_window_attrib(window, glfw.ICONIFIED))
        self.cursor = tuple(glfw.get_cursor_pos(window))
        self._title: str | None = None

    def set_title(self, title: str) -> None:
        """The window's title, sent to the server only when it changed."""
        if title != self._title:
            glfw.set_window_title(self._handle, title)
            self._title = title

    def on_iconify(self, iconified: bool) -> None:
        self.iconified = bool(iconified)

    def on_window_size(self, width: int, height: int) -> None:
        self.window = (width, height)

    def on_framebuffer_size(self, width: int, height: int) -> None:
        self.framebuffer = (width, height)

    def on_cursor(self, x: float, y: float) -> None:
        self.cursor = (x, y)
