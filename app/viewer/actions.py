"""The user's commands, each logged as ``action: HOW -> WHAT``: views, the settings chosen,
playing an animation, opening a scene, screenshots and saved views, the camera's undo, reset and
fit, the loupe, the keys' help, quitting. The keys, the mouse and the menus all call these, so a
command reads the same in the log however it was given.
"""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

from imgui_bundle import imgui  # noqa: F401,I001  (first: it names the library glfw loads)
import glfw

from app.naming import picture_name, unused
from app.viewer.files import SAVED_VIEWS, saved_views_file
from app.viewer.gui_text import displayable
from app.viewer.hands import PIVOTS, save_view

log = logging.getLogger("fvd")


class Actions:
    """What the user asks the window to do, on the one state."""

    def __init__(self, win):
        self.win, self.state = win, win.state


    def step_view(self, step: int, how: str) -> None:
        before = self.state.views.label
        self.state.views.next_view() if step > 0 else self.state.views.prev_view()
        log.info("action: %s -> %s %s -> %s", how, "next" if step > 0 else "previous",
                 before, self.state.views.label)

    def go_to_view(self, index: int, how: str) -> None:
        self.state.views.set_view(index)
        log.info("action: %s -> %s", how, self.state.views.label)

    def choose(self, what: str, value, how: str) -> None:
        """Set the projection, shading, rasterizer, kept aspect or course rules; the frame is
        re-rendered at once."""
        choices = self.state.choices
        setter = {"projection": choices.set_projection, "shading": choices.set_shading,
                  "rasterizer": choices.set_rasterizer,
                  "keep_aspect": choices.set_keep_aspect,
                  "course_tri": choices.set_course_tri,
                  "renderer": choices.set_renderer,
                  "texture_filter": choices.set_texture_filter,
                  "bump": choices.set_bump,
                  "depth_cue": choices.set_depth_cue,
                  "transparency": choices.set_transparency,
                  "paint_first": choices.set_paint_first,
                  "lighting_model": choices.set_lighting_model,
                  "headlight": self.state.lighting.set_headlight,
                  "depth_shading": choices.set_depth_shading}[what]
        setter(value)
        log.info("action: %s -> %s %s", how, what, value)
        if what == "projection":
            self.win.hands.projection_changed()     # a moved camera's F and B for the new one
        self.win.wake()

    def toggle_play(self, how: str) -> None:
        player = self.state.player
        if not player.animated:
            log.info("action: %s -> nothing to play (the scene is not animated)", how)
            return
        player.toggle(time.perf_counter())
        log.info("action: %s -> %s at t=%.3f", how, "play" if player.playing else "pause",
                 self.state.playback.time)
        self.win.wake()

    def step_frame(self, frames: int, how: str) -> None:
        self.state.player.step(frames)
        log.info("action: %s -> %s frame: %s", how, "next" if frames > 0 else "previous",
                 self.state.playback.label())
        self.win.wake()

    def change_speed(self, factor: float, how: str) -> None:
        from app.session.playback import SPEEDS
        speed = min(max(self.state.playback.speed * factor, SPEEDS[0]), SPEEDS[-1])
        self.state.player.set_speed(speed)
        log.info("action: %s -> speed %gx", how, speed)
        self.win.wake()

    def open_scene(self, source: str, how: str) -> None:
        source = source.strip()
        if not source:
            return
        earlier = len(self.state.open_messages)
        if self.state.open_scene(source):
            log.info("action: %s -> opened %s (%s)", how, source, self.state.views.label)
            self.win.files.recent.add(source)
            self.win.notice = ""             # what the panel said of the last scene goes with it
            self.win.tools.scene_changed()
            self.win.hands.message = ""
            for message in self.state.scene.view_messages:
                print(f"invalid view: {message}", file=sys.stderr)
            self.win.sizes.set_title(self.win.title())
        else:                             # this failure's messages only, not the earlier ones
            new = self.state.open_messages[earlier:]
            log.info("action: %s -> %s", how, new[0] if new else "not opened")
            print("\n".join(new), file=sys.stderr)
        self.win.wake()

    def save_screenshot(self, how: str) -> Path | None:
        """The CPU frame (not the screen: no panel) as a PNG in ``screenshots/``."""
        frame = self.state.frame
        if frame is None:
            log.info("action: %s -> no frame to save yet", how)
            return None
        from PIL import Image

        s = self.state
        path = unused(self.win.out_dir / picture_name(s.scene.name, s.views.number, s.projection,
                                                  s.shading, s.renderer_name))
        try:
            self.win.out_dir.mkdir(parents=True, exist_ok=True)
            Image.fromarray(frame.color).save(path)
        except OSError as error:
            self.win.notice = f"could not save {path}: {error}"
            log.info("action: %s -> %s", how, self.win.notice)
            print(self.win.notice, file=sys.stderr)
            return None
        self.win.notice = f"saved {path.name}"
        log.info("action: %s -> screenshot saved to %s", how, path)
        print(f"screenshot saved to {path}", flush=True)
        return path

    def quit(self, how: str) -> None:
        log.info("action: %s -> quit", how)
        glfw.set_window_should_close(self.win.window, True)

    def set_rotation(self, rotation: str, how: str) -> None:
        self.win.hands.set_rotation(rotation)
        log.info("action: %s -> rotation %s", how, rotation)
        self.win.wake()

    def set_pivot(self, pivot: str, how: str) -> None:
        self.win.hands.set_pivot(pivot)
        log.info("action: %s -> orbit about %s", how, PIVOTS[pivot])
        self.win.wake()

    def set_loupe(self, m: int, how: str) -> None:
        """View > Loupe: 1:1 or a magnification round the picture's centre."""
        width, height = self.state.size
        self.win.loupe.set(m, width / 2, height / 2)
        self.win.blit.loupe(**self.win.loupe.uniforms())
        log.info("action: %s -> loupe %dx", how, self.win.loupe.magnification)
        self.win.wake()

    def undo_camera(self, how: str) -> None:
        done = self.state.views.undo()
        back, _ = self.state.views.history
        log.info("action: %s -> %s", how, f"camera undone ({back} more to undo)" if done
                 else "nothing to undo")
        if done:
            self.win.hands.message = ""

    def redo_camera(self, how: str) -> None:
        done = self.state.views.redo()
        _, ahead = self.state.views.history
        log.info("action: %s -> %s", how, f"camera redone ({ahead} more to redo)" if done
                 else "nothing to redo")

    def reset_view(self, how: str) -> None:
        moved = self.win.hands.reset()
        log.info("action: %s -> %s", how, "the file's view again" if moved
                 else "already the file's view")
        self.win.wake()

    def fit_view(self, how: str) -> None:
        if self.win.hands.fit():
            self.log_camera(how + " (fit the scene's bounds)")
        else:
            log.info("action: %s -> %s", how, self.win.hands.message)
        self.win.wake()

    def toggle_help(self, how: str) -> None:
        self.win.help_shown = not self.win.help_shown
        log.info("action: %s -> keys help %s", how, "shown" if self.win.help_shown else "hidden")
        self.win.wake()

    def log_camera(self, how: str) -> None:
        v = self.state.views.current
        numbers = lambda values: "(" + ", ".join(f"{float(c):.17g}" for c in values) + ")"
        log.info("action: %s -> camera VRP %s VPN %s VUP %s window %s PRP %s F %.17g B %.17g",
                 how, numbers(v.vrp), numbers(v.vpn), numbers(v.vup), numbers(v.window),
                 numbers(v.prp), v.front, v.back)
        self.win.wake()

    def save_view(self, how: str, path: Path | None = None) -> int | None:
        """Append the view shown to a view file (six lines); returns its number there."""
        view = self.state.views.current
        if view is None:
            return None
        if path is None:
            try:
                path = saved_views_file()
            except OSError as error:
                self.win.notice = f"could not make the folder for {SAVED_VIEWS}: {error}"
                log.info("action: %s -> %s", how, self.win.notice)
                return None
        path, s = Path(path), self.state
        comment = (f"saved from the viewer: {s.scene.name}, {s.projection}, {s.shading}, "
                   f"{s.size[0]}x{s.size[1]} ({view.label})")
        try:
            number = save_view(view, path, displayable(comment))
        except (OSError, ValueError) as error:
            self.win.notice = f"could not save the view to {path}: {error}"
            log.info("action: %s -> %s", how, self.win.notice)
            print(self.win.notice, file=sys.stderr)
            return None
        self.win.notice = f"view saved to {path} as view {number}"
        log.info("action: %s -> view saved to %s as view %d", how, path, number)
        return number
