"""The menus: the panel's menu bar (File, Projection, Shading, Render, View, Help) and the
course's right-click pop-up. The Shading menu lists the registered shading modes, the Render
menu the registered renderers and lighting models (:mod:`core.registry`), each by its label
and key. Esc closes an open menu (``close_popups``, set by the keys).
"""

from __future__ import annotations

import logging

from imgui_bundle import imgui

from app.viewer.file_handling import shipped_scenes
from app.viewer.files import SAVED_VIEWS
from app.viewer.gui_text import displayable
from app.viewer.hands import PIVOTS, ROTATIONS

log = logging.getLogger("fvd")

PROJECTION_LABELS = (("perspective", "Perspective", "P"), ("parallel", "Parallel", "O"))
FILTER_LABELS = (("nearest", "Nearest"), ("bilinear", "Bilinear"),
                 ("trilinear", "Trilinear (MIP map)"), ("anisotropic", "Anisotropic"))
RASTERIZER_LABELS = (("edge", "Edge functions (perspective-correct)"),
                     ("scanline", "Scan line, ET/AET (course, screen-linear)"))
NO_TRIANGLES = ("This scene has no triangles: it is drawn as lines whatever the shading, "
                "so the shading modes change nothing.")


class Menus:
    """The menu bar and the pop-up; each item calls an action."""

    def __init__(self, win):
        self.win, self.state = win, win.state
        self._path = ""                   # File > Open: the path being typed
        self._scenes = shipped_scenes()
        self.popup_open = False           # a menu or the pop-up was open in the last frame
        self.close_popups = False         # Esc: close them in the next frame


    def _file_items(self) -> None:
        if imgui.menu_item_simple("Open with the file dialog...", None, False,
                                  not self.win.files.dialog.open):
            self.win.files.start_dialog("open", "Open a scene, mesh, .tri or view file")
        if imgui.begin_menu("Recent", bool(self.win.files.recent.paths)):
            for path, there in self.win.files.recent.items():
                if not there:
                    imgui.push_style_color(imgui.Col_.text,
                                           imgui.get_style_color_vec4(imgui.Col_.text_disabled))
                chosen = imgui.menu_item_simple(displayable(path), None,
                                                path == self.state.scene_source)
                if not there:
                    imgui.pop_style_color()
                if chosen:
                    self.win.files.open_recent(path)
            imgui.end_menu()
        if imgui.menu_item_simple("Save view as...", None, False, not self.win.files.dialog.open):
            self.win.files.start_dialog("save view", "Append the view to a view file", save=True)
        if imgui.menu_item_simple("Save screenshot as...", None, False,
                                  not self.win.files.dialog.open and self.state.frame is not None):
            self.win.files.start_dialog("save screenshot", "Save the frame as a PNG", save=True)

    def closing(self) -> None:
        """Inside an open menu or pop-up: close it if Esc was pressed."""
        if self.close_popups:
            imgui.close_current_popup()

    def projection_items(self, how: str) -> None:
        for value, label, key in PROJECTION_LABELS:
            if imgui.menu_item_simple(label, key, self.state.projection == value):
                self.win.actions.choose("projection", value, how)

    def shading_items(self, how: str) -> None:
        solid = self.state.choices.has_triangles
        if not solid:
            imgui.push_text_wrap_pos(imgui.get_font_size() * 22)
            imgui.text_disabled(NO_TRIANGLES)
            imgui.pop_text_wrap_pos()
        from core.registry import shading_modes         # every registered mode, by its label
        for mode in shading_modes():
            if imgui.menu_item_simple(displayable(mode.label), mode.key,
                                      self.state.shading == mode.name, solid):
                self.win.actions.choose("shading", mode.name, how)
        by_height = self.state.depth_shading == "height"
        if imgui.menu_item_simple("Depth colours by height (terrain map)", None, by_height,
                                  solid):
            self.win.actions.choose("depth_shading", "view" if by_height else "height", how)

    def draw_bar(self) -> None:
        if not imgui.begin_menu_bar():
            return
        for title, items, enabled in (("File", self._file_menu, True),
                                      ("Projection", lambda: self.projection_items(
                                          "menu Projection"), True),
                                      ("Shading", lambda: self.shading_items("menu Shading"),
                                       True),
                                      ("Render", self._render_items, True),
                                      ("View", self._view_menu, self.state.views.count > 0),
                                      ("?###Help", self._help_menu, True)):  # the bar is full
            if imgui.begin_menu(title, enabled):
                self.closing()
                items()
                imgui.end_menu()
        imgui.end_menu_bar()

    def _file_menu(self) -> None:
        if imgui.begin_menu("Open scene"):
            self.closing()
            imgui.text("Path:")               # first: on screen however long the list
            entered, self._path = imgui.input_text(
                "##path", self._path, flags=imgui.InputTextFlags_.enter_returns_true)
            imgui.same_line()
            if (imgui.button("Open") or entered) and self._path.strip():
                self.win.actions.open_scene(self._path, "menu File > Open path")
                imgui.close_current_popup()
            imgui.separator()
            for path in self._scenes:
                if imgui.menu_item_simple(path.name, None,
                                          str(path) == self.state.scene_source):
                    self.win.actions.open_scene(str(path), "menu File > Open")
            imgui.end_menu()
        self._file_items()
        if imgui.menu_item_simple("Save screenshot", "S"):
            self.win.actions.save_screenshot("menu File > Save screenshot")
        imgui.separator()
        if imgui.menu_item_simple("Quit", "Q"):
            self.win.actions.quit("menu File > Quit")

    def _view_menu(self) -> None:
        if imgui.menu_item_simple("Next view", "Right"):
            self.win.actions.step_view(+1, "menu View > Next")
        if imgui.menu_item_simple("Previous view", "Left"):
            self.win.actions.step_view(-1, "menu View > Previous")
        self._camera_items()
        imgui.separator()
        self._inspector_items()
        imgui.separator()
        from core.scene.view_numbers import file_number
        for i, view in enumerate(self.state.scene.views):
            number = file_number(self.state.scene, i)
            label = displayable(f"{number}: {view.label}###view{i}")
            if imgui.menu_item_simple(label, None, i == self.state.view_index):
                self.win.actions.go_to_view(i, "menu View")

    def _help_menu(self) -> None:
        if imgui.menu_item_simple("Keys and mouse", "F1", self.win.help_shown):
            self.win.actions.toggle_help("menu Help > Keys")

    def _camera_items(self) -> None:
        imgui.separator()
        if imgui.menu_item_simple("Reset to the file's view", "Enter", False,
                                  self.state.hand_view is not None):
            self.win.actions.reset_view("menu View > Reset")
        if imgui.menu_item_simple("Fit the scene", "F"):
            self.win.actions.fit_view("menu View > Fit")
        for pivot, words in PIVOTS.items():
            if imgui.menu_item_simple(f"Orbit about {words}", None, self.win.hands.pivot == pivot):
                self.win.actions.set_pivot(pivot, "menu View > Orbit about")
        imgui.separator()
        for rotation, words in ROTATIONS.items():
            if imgui.menu_item_simple(words, "Y", self.win.hands.rotation == rotation):
                self.win.actions.set_rotation(rotation, "menu View")
        back, ahead = self.state.views.history
        if imgui.menu_item_simple("Undo camera", "Ctrl+Z", False, back > 0):
            self.win.actions.undo_camera("menu View > Undo camera")
        if imgui.menu_item_simple("Redo camera", "Ctrl+Shift+Z", False, ahead > 0):
            self.win.actions.redo_camera("menu View > Redo camera")
        if imgui.menu_item_simple(f"Save view (append to {SAVED_VIEWS}, state folder)",
                                  "Ctrl+S"):
            self.win.actions.save_view("menu View > Save view")
        if imgui.begin_menu("Loupe (Alt+wheel)"):
            for m in (1, 2, 4, 8, 16, 32):
                if imgui.menu_item_simple("1:1" if m == 1 else f"{m}x", None,
                                          self.win.loupe.magnification == m):
                    self.win.actions.set_loupe(m, "menu View > Loupe")
            imgui.end_menu()

    def _inspector_items(self) -> None:
        """The View menu's inspection tools: inspect mode, the buffer views, the comparison
        with OpenGL."""
        if imgui.menu_item_simple("Inspect mode (click a pixel)", "I", self.win.tools.inspecting):
            self.win.tools.toggle_inspect("menu View > Inspect mode")
        if imgui.begin_menu("Buffer view"):
            for name in ("picture", *self.win.tools.buffer_names()):
                if imgui.menu_item_simple(name, None, self.win.tools.buffer == name):
                    self.win.tools.choose_buffer(name, "menu View > Buffer view")
            imgui.end_menu()
        if imgui.menu_item_simple("Compare with OpenGL", "H", self.win.tools.showing_heat):
            self.win.tools.flip("menu View > Compare with OpenGL")

    def _lighting_model_items(self) -> None:
        """Every material lit by one registered lighting model, or each by its own."""
        from core.shading.models import lighting_models
        imgui.text_disabled("Lighting model")
        for value, label in (("", "Each material's own"),) + tuple(
                (m.name, m.label) for m in lighting_models()):
            if imgui.menu_item_simple(displayable(label), None,
                                      self.state.lighting_model == value):
                self.win.actions.choose("lighting_model", value, "menu Render")

    def _render_items(self) -> None:
        from core.renderers import renderers
        imgui.text_disabled("Renderer")
        for entry in renderers():
            if entry.in_menu and imgui.menu_item_simple(
                    displayable(entry.label), entry.key,
                    self.state.renderer_name == entry.name):
                self.win.actions.choose("renderer", entry.name, "menu Render")
        imgui.separator()
        self._lighting_model_items()
        if imgui.menu_item_simple("Headlight (a light at the eye)", "L", self.state.headlight):
            self.win.actions.choose("headlight", not self.state.headlight, "menu Render")
        imgui.separator()
        imgui.text_disabled("Texture filter")
        for value, label in FILTER_LABELS:
            if imgui.menu_item_simple(label, "T", self.state.texture_filter == value):
                self.win.actions.choose("texture_filter", value, "menu Render")
        if imgui.menu_item_simple("Bump and normal maps", "B", self.state.bump):
            self.win.actions.choose("bump", not self.state.bump, "menu Render")
        imgui.separator()
        imgui.text_disabled("Rasterizer")
        for value, label in RASTERIZER_LABELS:
            if imgui.menu_item_simple(label, None, self.state.rasterizer == value,
                               self.state.choices.has_triangles):
                self.win.actions.choose("rasterizer", value, "menu Render")
        imgui.separator()
        if imgui.menu_item_simple("Keep the window's aspect (letterbox)", "A",
                           bool(self.state.keep_aspect)):
            self.win.actions.choose("keep_aspect", not self.state.keep_aspect, "menu Render")
        if imgui.menu_item_simple("Course .tri rules (back faces, mouse)", None,
                           self.state.course_tri):
            self.win.actions.choose("course_tri", not self.state.course_tri, "menu Render")
        self._painter_items()

    def _painter_items(self) -> None:
        imgui.separator()
        cued = bool(self.state.choices.settings().depth_cue)
        if imgui.menu_item_simple("Depth cueing", None, cued):
            self.win.actions.choose("depth_cue", not cued, "menu Render")
        imgui.text_disabled("Transparency (k_t > 0)")
        current = self.state.choices.settings().transparency
        from core.settings import TRANSPARENCIES
        for value, label in TRANSPARENCIES.items():
            if imgui.menu_item_simple(label, None, current == value):
                self.win.actions.choose("transparency", value, "menu Render")

    def draw_popup(self) -> None:
        # The course's GLUT pop-up menu: projection and shading at the click.
        if imgui.begin_popup("popup"):
            self.closing()
            imgui.text_disabled("Projection")
            self.projection_items("pop-up")
            imgui.separator()
            imgui.text_disabled("Shading")
            self.shading_items("pop-up")
            imgui.separator()
            if imgui.menu_item_simple("Next view", "Right", False, self.state.views.count > 0):
                self.win.actions.step_view(+1, "pop-up Next view")
            imgui.end_popup()
