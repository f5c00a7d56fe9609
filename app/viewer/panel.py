"""The side panel to the right of the picture: the menu bar, the keys' help, the status, the
timeline, the volume, inspector and renderer's options sections, the camera's numbers, the
plan, the invalid views and the messages; and the pop-up and the window's own file dialog
over it.
"""

from __future__ import annotations

import logging
import time

from imgui_bundle import imgui

from app.viewer import options_panel
from app.viewer.gui_text import displayable
from app.viewer.hands import PIVOTS, keys_help, view_lines

log = logging.getLogger("fvd")
PANEL_WIDTH = 340            # the side panel, in screen points
_W = imgui.WindowFlags_
PANEL_FLAGS = (_W.no_title_bar | _W.no_resize | _W.no_move | _W.no_collapse | _W.menu_bar
               | _W.no_saved_settings | _W.no_bring_to_front_on_focus)
ANY_POPUP = imgui.PopupFlags_.any_popup_id | imgui.PopupFlags_.any_popup_level


class SidePanel:
    """The panel's sections, top to bottom, in one ImGui window."""

    def __init__(self, win):
        self.win, self.state = win, win.state


    def _help_strip(self) -> None:
        """F1 / Help > Keys: every key and mouse action, in the panel (never on the picture)."""
        if not self.win.help_shown:
            return
        imgui.set_next_item_open(True, imgui.Cond_.always)
        if not imgui.collapsing_header("Keys and mouse (F1 closes)###help"):
            return
        imgui.push_text_wrap_pos(0.0)
        for key, what in keys_help():
            if not what:
                imgui.text_colored((0.55, 0.8, 1.0, 1.0), key)
            else:
                imgui.bullet()
                imgui.text_wrapped(displayable(f"{key}: {what}"))
        imgui.pop_text_wrap_pos()
        imgui.separator()

    def _camera_strip(self) -> None:
        """The view's numbers, live: VRP ... B and each factor of N_per / N_par."""
        view = self.state.views.current
        if view is None:
            return
        moved = " (moved)" if self.state.hand_view is not None else ""
        if not imgui.collapsing_header(f"Camera{moved}###camera",
                                       imgui.TreeNodeFlags_.default_open):
            if self.win.hands.message:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.win.hands.message))
            return
        imgui.push_text_wrap_pos(0.0)
        if self.win.hands.message:
            imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(self.win.hands.message))
        for line in view_lines(view, self.state.projection):
            imgui.text(displayable(line))
        imgui.text_disabled(f"drag orbit ({self.win.hands.rotation}, about "
                            f"{PIVOTS[self.win.hands.pivot]}), Shift/middle drag pan, "
                            "wheel dolly, "
                            "Ctrl+wheel window, F fit, Enter the file's view")
        imgui.pop_text_wrap_pos()

    def build(self) -> None:
        self.draw()
        self.win.menus.draw_popup()
        # Esc closes the window's own file dialog too
        self.win.files.dialog.draw(imgui, displayable, cancel=self.win.menus.close_popups)
        self.win.menus.popup_open = imgui.is_popup_open("", ANY_POPUP)
        self.win.menus.close_popups = False

    def draw(self) -> None:
        scale = self.win.scale()
        width, height = self.state.size
        fb_w, fb_h = self.win.sizes.framebuffer
        imgui.set_next_window_pos((width / scale, 0), imgui.Cond_.always)
        # no wider than the window, so that its text wraps where it can be read
        imgui.set_next_window_size((min(PANEL_WIDTH, fb_w / scale), fb_h / scale),
                                   imgui.Cond_.always)
        imgui.begin("panel", None, PANEL_FLAGS)
        self.win.menus.draw_bar()
        self._help_strip()
        self.win.status.draw()
        self._timeline()
        self.win.volume_panel.draw(imgui, displayable)
        self.win.tools.panel(imgui, displayable)
        self._draw_order()                    # the painter's draw-order slider
        options_panel.draw(imgui, self.state, displayable)   # the renderer's own options
        self._camera_strip()
        self._plan_strip()
        self._invalid_views_strip()
        self._messages_strip()
        imgui.end()

    def _draw_order(self) -> None:
        """The painter's renderers: a slider that paints only the first K triangles."""
        s = self.state
        total = s.choices.painted_total
        if not s.choices.renderer_entry.has_option("paint_first") or not total:
            return
        imgui.text("draw order (triangles painted)")
        imgui.push_item_width(-1)
        shown = total if s.paint_first is None else min(s.paint_first, total)
        changed, k = imgui.slider_int("##paint_first", shown, 0, total)
        imgui.pop_item_width()
        if changed:
            self.win.actions.choose("paint_first", None if k >= total else k, "slider draw order")
        imgui.separator()

    def _timeline(self) -> None:
        """An animated scene: play / pause, step, the timeline slider and the speed."""
        playback = self.state.playback
        if playback is None:
            return
        from app.session.playback import SPEEDS
        if imgui.button("Pause" if playback.playing else "Play"):
            self.win.actions.toggle_play("button Play")
        imgui.same_line()
        if imgui.button("<"):
            self.win.actions.step_frame(-1, "button <")
        imgui.same_line()
        if imgui.button(">"):
            self.win.actions.step_frame(+1, "button >")
        imgui.same_line()
        imgui.text(f"frame {playback.frame_index + 1} of {playback.frame_count}")
        imgui.push_item_width(-1)
        changed, t = imgui.slider_float("##time", playback.time, 0.0,
                                        max(playback.end, 1e-6), "%.2f s")
        if changed:
            self.state.player.seek(t, time.perf_counter())
            self.win.wake()
        labels = [f"{v:g}x" for v in SPEEDS]
        current = min(range(len(SPEEDS)), key=lambda i: abs(SPEEDS[i] - playback.speed))
        changed, chosen = imgui.combo("##speed", current, labels)
        if changed:
            self.state.player.set_speed(SPEEDS[chosen])
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
        invalid = self.state.messages.invalid
        if not invalid:
            return
        expanded = imgui.collapsing_header(f"Invalid views ({len(invalid)})###invalid")
        if expanded:
            imgui.push_text_wrap_pos(0.0)
            for message in invalid:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(message))
            imgui.pop_text_wrap_pos()

    def _messages_strip(self) -> None:
        notices = self.state.messages.notices
        if not notices:
            return
        expanded = imgui.collapsing_header(f"Messages ({len(notices)})###messages",
                                           imgui.TreeNodeFlags_.default_open)
        if expanded:
            if self.state.open_messages and imgui.small_button("Clear"):
                self.state.messages.clear()
            imgui.push_text_wrap_pos(0.0)
            for message in notices:
                imgui.text_colored((1.0, 0.75, 0.4, 1.0), displayable(message))
            imgui.pop_text_wrap_pos()
