"""The mouse on the picture: clicks (the next view, the pop-up, the course's buttons, the
bump demo, inspect mode), the camera's hands (:mod:`app.viewer.hands`: a drag orbits or pans,
the wheel dollies; Ctrl+wheel the window, Alt+wheel the loupe) and the frame pixel under the
cursor (through the loupe, and stretched while a resize waits for its frame).
"""

from __future__ import annotations

import logging

from imgui_bundle import imgui  # noqa: I001  (first: it names the library glfw loads)
import glfw
import numpy as np

from app.viewer.loupe import stretched

log = logging.getLogger("fvd")
# The startup code's mouse (Assignment 3): left Phong, middle Gouraud, right flat.
COURSE_BUTTONS = {glfw.MOUSE_BUTTON_LEFT: "phong", glfw.MOUSE_BUTTON_MIDDLE: "gouraud",
                  glfw.MOUSE_BUTTON_RIGHT: "flat"}


def pivot_words(drag) -> str:
    """What a finished orbit turned about, for the log."""
    if drag.pivot is None:
        return "the VRP"
    where = "the point under the cursor" if drag.under is not None and np.array_equal(
        drag.pivot, drag.under) else "the scene's centre"
    return f"{where} ({', '.join(f'{c:.6g}' for c in drag.pivot)})"


class Pointer:
    """Presses, releases and the wheel since the last frame, and the gestures they make."""

    def __init__(self, win):
        self.win, self.state = win, win.state
        # (button, action, x, y, mods) since the last frame: presses and releases
        self.clicks: list[tuple[int, int, float, float, int]] = []
        self._loupe_drag: tuple[int, int] | None = None     # a drag moving the loupe's picture
        self._pressed: tuple[int, float, float, str] | None = None   # button, x, y, where


    def on_mouse_button(self, window, button, action, mods) -> None:
        self.win.input.on_mouse_button(button, action)
        # where it happened, asked: a warped pointer (xdotool) may have sent no motion first
        self.win.sizes.on_cursor(*glfw.get_cursor_pos(window))
        if action in (glfw.PRESS, glfw.RELEASE) and button in (
                glfw.MOUSE_BUTTON_LEFT, glfw.MOUSE_BUTTON_RIGHT, glfw.MOUSE_BUTTON_MIDDLE):
            # Decided in the next frame, once ImGui has seen this press at this position.
            self.clicks.append((button, action, *self.win.sizes.cursor, mods))
        self.win.wake()

    def handle_clicks(self) -> None:
        """Presses and releases since the last frame, in order. A left or middle press on the
        picture starts a gesture (app.viewer.hands): past ImGui's drag threshold it orbits or
        pans, released before it is a click. Right press: the pop-up (or, with the course's
        rules, the startup code's buttons) at once — only on the picture, and unless ImGui
        wants this click."""
        clicks, self.clicks = self.clicks, []
        captured = bool(clicks) and (imgui.get_io().want_capture_mouse
                                     or self.win.menus.popup_open)
        for button, action, x, y, mods in clicks:
            if action == glfw.RELEASE:
                self._release(button, x, y)
                continue
            name = {glfw.MOUSE_BUTTON_LEFT: "left", glfw.MOUSE_BUTTON_RIGHT: "right"}.get(
                button, "middle") + " click"
            where = f"{name} at ({x:.0f}, {y:.0f})"
            if captured or not self.win.on_picture(x, y):
                log.info("action: %s -> taken by the menu/panel, view unchanged", where)
            elif button == glfw.MOUSE_BUTTON_RIGHT:
                self.click(button, x, y, where)
            else:
                self._press(button, x, y, mods, where)
        self._follow()

    def click(self, button: int, x: float, y: float, where: str) -> None:
        """A click on the picture (a press released without a drag, or a right press)."""
        if (demo := self.state.choices.demo_click(button == glfw.MOUSE_BUTTON_LEFT)) is not None:
            log.info("action: %s -> the bump demo: %s", where, demo)
        elif self.state.player.playing and button == glfw.MOUSE_BUTTON_LEFT:
            self.win.actions.toggle_play(where)
        elif self.win.tools.inspecting and button == glfw.MOUSE_BUTTON_LEFT:
            self.win.tools.inspect(*self.frame_pixel(x, y), where)
        elif self.state.course_tri:
            self.win.actions.choose("shading", COURSE_BUTTONS[button], f"{where} (course buttons)")
        elif button == glfw.MOUSE_BUTTON_LEFT:
            self.win.actions.step_view(+1, where)
        elif button == glfw.MOUSE_BUTTON_RIGHT:
            log.info("action: %s -> pop-up menu", where)
            imgui.open_popup("popup")

    def _drag_threshold(self) -> float:
        """ImGui's drag threshold, in framebuffer pixels."""
        return float(imgui.get_io().mouse_drag_threshold) * self.win.scale()

    def _press(self, button: int, x: float, y: float, mods: int, where: str) -> None:
        pan = button == glfw.MOUSE_BUTTON_MIDDLE or bool(mods & glfw.MOD_SHIFT)
        scale = self.win.scale()
        self.win.hands.press(x * scale, y * scale, pan, None if pan else self._point_under(x, y))
        self._pressed = (button, x, y, where)
        # magnified, a drag moves the loupe's picture instead of the camera
        self._loupe_drag = self.win.loupe.screen if self.win.loupe.magnification > 1 else None

    def _release(self, button: int, x: float, y: float) -> None:
        if self._pressed is None or self._pressed[0] != button:
            return
        _, x0, y0, where = self._pressed
        self._pressed = None
        scale = self.win.scale()
        drag = self.win.hands.drag
        pan = drag is not None and drag.pan
        if self._loupe_drag is not None:
            self.win.hands.drag, start, self._loupe_drag = None, self._loupe_drag, None
            if np.hypot(x - x0, y - y0) * scale <= self._drag_threshold():
                self.click(button, x0, y0, where)
            else:
                self._pan_loupe(start, x - x0, y - y0)
                log.info("action: drag the loupe by (%.0f, %.0f)", x - x0, y - y0)
            return
        if not self.win.hands.release(x * scale, y * scale, self._drag_threshold()):
            self.click(button, x0, y0, where)
            return
        what = "pan" if pan else f"{self.win.hands.rotation} orbit about {pivot_words(drag)}"
        self.win.actions.log_camera(f"drag {what} from ({x0:.0f}, {y0:.0f}) to ({x:.0f}, {y:.0f})")

    def _follow(self) -> None:
        """While a button is down: the gesture follows the pointer (the latest camera wins:
        the worker renders only the newest request)."""
        if self.win.hands.drag is None:
            return
        x, y = self.win.sizes.cursor
        if (self._pressed is not None and not self.clicks
                and glfw.get_mouse_button(self.win.window, self._pressed[0]) != glfw.PRESS):
            self._release(self._pressed[0], x, y)    # a release the window never saw
            return
        scale = self.win.scale()
        if self._loupe_drag is not None:
            d = self.win.hands.drag
            if np.hypot(x * scale - d.x, y * scale - d.y) > self._drag_threshold():
                self._pan_loupe(self._loupe_drag, x * scale - d.x, y * scale - d.y)
            return
        if self.win.hands.move(x * scale, y * scale, self._drag_threshold()):
            self.win.wake()

    def frame_pixel(self, x: float, y: float) -> tuple[int, int]:
        """The frame pixel shown at screen point (x, y): through the loupe, and stretched as
        the blit stretches a frame of the old size after a resize (app.viewer.loupe)."""
        scale = self.win.scale()
        texel = self.win.loupe.texel_at(x * scale, y * scale)
        frame = self.state.frame
        if frame is None:
            return texel
        return stretched(texel, self.state.size, frame.color.shape[1::-1])

    def resizing(self) -> bool:
        """Is the frame shown of another size than the picture (a resize, its frame due)?"""
        frame = self.state.frame
        return frame is not None and frame.color.shape[1::-1] != tuple(self.state.size)

    def _point_under(self, x: float, y: float):
        """The world point drawn at screen point (x, y), from the shown frame's depth
        (app.session.pick); None off the model or where the frame keeps no depth."""
        from app.session.pick import PICK_KEY, point_at
        frame = self.state.frame
        if frame is None or self.win.hands.pivot != "cursor":
            return None
        return point_at(frame.stats.get(PICK_KEY), *self.frame_pixel(x, y))

    def _pan_loupe(self, start, dx: float, dy: float) -> None:
        self.win.loupe.pan_from(start, dx, dy)
        self.win.blit.loupe(**self.win.loupe.uniforms())
        self.win.wake()

    def wheel(self, notches: float) -> None:
        """The wheel on the picture: dolly; Ctrl: the window (field of view); Alt: the loupe."""
        x, y = self.win.sizes.cursor
        if imgui.get_io().want_capture_mouse or not self.win.on_picture(x, y) or not notches:
            return
        held = lambda *keys: any(glfw.get_key(self.win.window, k) == glfw.PRESS for k in keys)
        if held(glfw.KEY_LEFT_ALT, glfw.KEY_RIGHT_ALT):
            m = self.win.loupe.wheel(notches, x * self.win.scale(), y * self.win.scale())
            self.win.blit.loupe(**self.win.loupe.uniforms())
            log.info("action: Alt+wheel %+g at (%.0f, %.0f) -> loupe %dx", notches, x, y, m)
            return
        zoom = held(glfw.KEY_LEFT_CONTROL, glfw.KEY_RIGHT_CONTROL)
        if self.win.hands.wheel(notches, field_of_view=zoom):
            how = " with Ctrl (window)" if zoom else " (dolly)"
            self.win.actions.log_camera(f"wheel {notches:+g}{how}")
        elif self.win.hands.message:
            log.info("action: wheel -> %s", self.win.hands.message)
