"""The window's own file dialog, on ImGui's widgets: used where the desktop has no dialog
program (Linux without zenity, kdialog, matedialog or qarma), so that File > Open, Save view
as… and Save screenshot as… work everywhere.

:class:`PathChooser` is the dialog without a window (a folder, its entries, the name typed,
and the checks made before a path is handed back); :func:`draw` shows it as a modal pop-up
and returns the chosen path once OK is pressed. What it refuses, it says in the dialog in one
line, and the dialog stays open: a folder that cannot be listed, a name with a line break or a
NUL, a folder that cannot be written into (saving), a file that is not there (opening).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

MAX_ENTRIES = 2000                 # a folder's entries listed (the rest: "… and N more")
POPUP = "Choose a file###path-dialog"


@dataclass
class PathChooser:
    purpose: str                   # "open", "save view", "save screenshot"
    save: bool
    folder: Path = field(default_factory=Path.cwd)
    name: str = ""
    message: str = ""
    suffixes: tuple[str, ...] = ()  # shown (folders always are); empty: every file
    _listed: tuple | None = None

    def entries(self) -> tuple[list[str], list[str], int]:
        """(folders, files, how many more) in :attr:`folder`, sorted; said in
        :attr:`message` when the folder cannot be read."""
        if self._listed is not None and self._listed[0] == self.folder:
            return self._listed[1]
        folders, files, more = [], [], 0
        try:
            with os.scandir(self.folder) as found:
                for entry in found:
                    if len(folders) + len(files) >= MAX_ENTRIES:
                        more += 1
                        continue
                    try:
                        if entry.is_dir():
                            folders.append(entry.name)
                        elif not self.suffixes or Path(entry.name).suffix.lower() \
                                in self.suffixes:
                            files.append(entry.name)
                    except OSError:
                        continue
        except OSError as error:
            self.message = f"cannot list {self.folder}: {error.strerror or error}"
        listed = (sorted(folders, key=str.lower), sorted(files, key=str.lower), more)
        self._listed = (self.folder, listed)
        return listed

    def enter(self, name: str) -> None:
        """Into the folder ``name`` (".." is up)."""
        target = self.folder.parent if name == ".." else self.folder / name
        if not os.access(target, os.R_OK | os.X_OK):
            self.message = f"cannot open the folder {target}"
            return
        self.folder, self.message, self._listed = target.resolve(), "", None

    def chosen(self) -> Path | None:
        """The path for the name typed or picked, checked; None (and :attr:`message`) when
        it cannot be used."""
        name = self.name.strip()
        if not name:
            self.message = "type a file name or pick one"
            return None
        if any(c in name for c in "\n\r\0"):
            self.message = "a file name cannot hold a line break or a NUL"
            return None
        path = Path(name).expanduser()
        path = path if path.is_absolute() else self.folder / path
        if self.save:
            parent = path.parent
            if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
                self.message = f"cannot write into {parent}"
                return None
            if path.is_dir():
                self.message = f"{path} is a folder"
                return None
        elif not path.is_file():
            self.message = f"{path}: no such file" if not path.exists() else \
                f"{path} is not a file"
            return None
        self.message = ""
        return path


def draw(imgui, chooser: PathChooser, title: str, displayable,
         cancel: bool = False) -> tuple[bool, Path | None]:
    """Show the dialog (call every frame while it is open): ``(still open, path chosen)``.
    ``cancel``: Esc was pressed, the dialog closes as Cancel would close it."""
    if not imgui.is_popup_open(POPUP):
        imgui.open_popup(POPUP)
    width, height = imgui.get_io().display_size     # within the window, however small
    size = (max(200.0, min(520.0, width - 16)), max(150.0, min(420.0, height - 16)))
    imgui.set_next_window_size(size, imgui.Cond_.appearing)
    imgui.set_next_window_pos(((width - size[0]) / 2, (height - size[1]) / 2),
                              imgui.Cond_.appearing)
    shown, _ = imgui.begin_popup_modal(POPUP, None)
    if not shown:
        return False, None
    imgui.text(displayable(title))
    imgui.text_disabled(displayable(str(chooser.folder)))
    folders, files, more = chooser.entries()
    imgui.begin_child("entries", (0, -90))
    if imgui.selectable("../", False)[0]:
        chooser.enter("..")
    for name in folders:
        if imgui.selectable(displayable(name) + "/", False)[0]:
            chooser.enter(name)
    for name in files:
        if imgui.selectable(displayable(name), chooser.name == name)[0]:
            chooser.name = name
    if more:
        imgui.text_disabled(f"... and {more} more")
    imgui.end_child()
    enter = imgui.input_text("name", chooser.name,
                             imgui.InputTextFlags_.enter_returns_true)
    chooser.name = enter[1]
    if chooser.message:
        imgui.text_colored((1.0, 0.45, 0.4, 1.0), displayable(chooser.message))
    path, done = None, False
    if imgui.button("Save" if chooser.save else "Open") or enter[0]:
        path = chooser.chosen()
        done = path is not None
    imgui.same_line()
    if imgui.button("Cancel") or cancel:
        done, path = True, None
    if done:
        imgui.close_current_popup()
    imgui.end_popup()
    return not done, path
