"""The keyboard: keys (Esc, arrows, Space, Enter, F1, Ctrl+S/Z/Y) and characters (the
letters follow the keyboard layout). The projection and shading letters come from the
registries (:mod:`core.registry`): a registered shading mode's key works with no line here;
so does a renderer's (``r`` steps through the renderers registered with the key R).
"""

from __future__ import annotations

import logging
import time

from imgui_bundle import imgui  # noqa: I001  (first: it names the library glfw loads)
import glfw

from core.registry import shading_modes


log = logging.getLogger("fvd")
PROJECTION_KEYS = {"p": "perspective", "o": "parallel"}


def char_shortcuts() -> dict[str, tuple[str, str]]:
    """The characters that choose a setting: the projections, and each registered shading
    mode's key (read at each key press, so a mode registered later has its key too)."""
    found = {char: ("projection", value) for char, value in PROJECTION_KEYS.items()}
    for mode in shading_modes():
        if mode.key:
            found.setdefault(mode.key.lower(), ("shading", mode.name))
    return found


def next_renderer(char: str, current: str) -> str | None:
    """The renderer ``char`` chooses: the next of those registered with that key (from any
    other renderer, the one after the first: ``r`` flips the z-buffer and the ray tracer);
    None when no renderer has it."""
    from core.renderers import renderers          # the built-in renderers registered
    keyed = [entry.name for entry in renderers() if entry.key.lower() == char]
    if not keyed:
        return None
    here = keyed.index(current) if current in keyed else 0
    return keyed[(here + 1) % len(keyed)]


class Keys:
    """The key and character callbacks: each key becomes an action."""

    def __init__(self, win):
        self.win, self.state = win, win.state


    def on_key(self, window, key, scancode, action, mods) -> None:
        self.win.input.on_key(key, action, mods)
        self.win.wake()
        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        self.win.loop.latency.input(time.perf_counter())     # how long until it shows
        if key == glfw.KEY_ESCAPE and self.win.menus.popup_open:
            self.win.menus.close_popups = True    # Esc closes the open menu or pop-up only
            log.info("action: key Esc -> close the open menu")
            return
        if key == glfw.KEY_ESCAPE and self.state.open_messages:
            self.state.messages.clear()   # an error is a message to dismiss, not a reason to quit
            log.info("action: key Esc -> dismiss the message")
            return
        if imgui.get_io().want_capture_keyboard:
            return                        # typing in a text field
        if self._hand_key(key, mods):
            return
        if key == glfw.KEY_ESCAPE:
            self.win.actions.quit("key Esc")
        elif key == glfw.KEY_SPACE and action == glfw.PRESS:
            self.win.actions.toggle_play("key Space")
        elif key in (glfw.KEY_RIGHT, glfw.KEY_DOWN):
            self.win.actions.step_view(+1, "key Right" if key == glfw.KEY_RIGHT else "key Down")
        elif key in (glfw.KEY_LEFT, glfw.KEY_UP):
            self.win.actions.step_view(-1, "key Left" if key == glfw.KEY_LEFT else "key Up")

    def on_char(self, window, codepoint) -> None:
        # Letters come as characters, so that the shortcuts follow the keyboard layout.
        self.win.input.on_char(codepoint)
        self.win.wake()
        if imgui.get_io().want_capture_keyboard:
            return
        char = chr(codepoint).lower()
        shortcuts = char_shortcuts()
        if char in shortcuts:
            what, value = shortcuts[char]
            self.win.actions.choose(what, value, f"key {char}")
        elif char == "a":
            self.win.actions.choose("keep_aspect", not self.state.keep_aspect, "key a")
        elif char == "t":                 # the next texture filter
            from core.texture.modes import FILTERS
            names = tuple(FILTERS)
            after = names[(names.index(self.state.texture_filter) + 1) % len(names)]
            self.win.actions.choose("texture_filter", after, "key t")
        elif char == "s":
            self.win.actions.save_screenshot("key s")
        elif (renderer := next_renderer(char, self.state.renderer_name)) is not None:
            self.win.actions.choose("renderer", renderer, f"key {char}")
        elif char == "b":
            self.win.actions.choose("bump", not self.state.bump, "key b")
        elif char in ",." and self.state.player.animated:
            self.win.actions.step_frame(-1 if char == "," else +1, f"key {char}")
        elif char in "[]" and self.state.player.animated:
            self.win.actions.change_speed(0.5 if char == "[" else 2.0, f"key {char}")
        elif char == "q":
            self.win.actions.quit("key q")
        elif char == "i":                 # inspect mode, buffer views, compare
            self.win.tools.toggle_inspect("key i")
        elif char == "v":
            self.win.tools.next_buffer("key v")
        elif char == "h":
            self.win.tools.flip("key h")
        elif char == "f":
            self.win.actions.fit_view("key f")
        elif char == "y":
            turned = "turntable" if self.win.hands.rotation == "arcball" else "arcball"
            self.win.actions.set_rotation(turned,
                              "key y")
        elif char == "l":
            self.win.actions.choose("headlight", not self.state.headlight, "key l")

    def _hand_key(self, key: int, mods: int) -> bool:
        """Enter: the file's view; F1: the keys' help; Ctrl+S: save the view. Returns whether
        the key was taken."""
        if key == glfw.KEY_S and mods & glfw.MOD_CONTROL:
            self.win.actions.save_view("key Ctrl+S")
            return True
        if mods & glfw.MOD_CONTROL and (key == glfw.KEY_Y or (key == glfw.KEY_Z
                                                              and mods & glfw.MOD_SHIFT)):
            self.win.actions.redo_camera("key Ctrl+Shift+Z" if key == glfw.KEY_Z else "key Ctrl+Y")
            return True
        if key == glfw.KEY_Z and mods & glfw.MOD_CONTROL:
            self.win.actions.undo_camera("key Ctrl+Z")
            return True
        if key in (glfw.KEY_ENTER, glfw.KEY_KP_ENTER):
            self.win.actions.reset_view("key Enter")
            return True
        if key == glfw.KEY_F1:
            self.win.actions.toggle_help("key F1")
            return True
        return False
