"""The window's files: a file dropped on it, File > Recent, the native file dialog (or the
window's own, :mod:`app.viewer.path_dialog`) and what it chose, and the scenes shipped in
``scenes/`` for File > Open. The files themselves are :mod:`app.viewer.files`.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

from imgui_bundle import imgui  # noqa: F401,I001  (first: it names the library glfw loads)
import glfw

from app.viewer.files import FileDialog, RecentFiles, check_drop
from core.paths import SCENES_DIR

log = logging.getLogger("fvd")
# Files in scenes/ that are not scenes.
NOT_SCENES = {".md", ".py", ".pyc", ".txt", ".png"}


def shipped_scenes() -> list[Path]:
    """The scene files in ``scenes/``, for File > Open."""
    if not SCENES_DIR.is_dir():
        return []
    return sorted(p for p in SCENES_DIR.iterdir()
                  if p.is_file() and not p.name.startswith((".", "_"))
                  and p.suffix not in NOT_SCENES)


class FileHandling:
    """Drops, recent files and the file dialog, and what they open or save."""

    def __init__(self, win):
        self.win, self.state = win, win.state
        self.recent = RecentFiles()
        self.dialog = FileDialog()
        self.drop_callback = None         # kept: glfw holds only the C pointer
        if self.state.scene_source != "-" and Path(self.state.scene_source).is_file():
            self.recent.add(self.state.scene_source)


    def install_drop(self) -> None:
        """glfw's drop callback, given the raw bytes of each path: pyGLFW's own wrapper
        decodes them as UTF-8 and a name that is not would raise inside the callback."""
        dropfun = getattr(glfw, "_GLFWdropfun", None)
        library = getattr(glfw, "_glfw", None)
        if dropfun is None or not hasattr(library, "glfwSetDropCallback"):
            glfw.set_drop_callback(self.win.window, lambda _w, paths: self.on_drop(paths))
            return

        def raw(_window, count, c_paths):
            try:
                self.on_drop([c_paths[i] for i in range(count)])
            except Exception as error:        # never out of a C callback
                log.error("drop: %s", error, exc_info=error)
        self.drop_callback = dropfun(raw)    # kept: glfw holds only the C pointer
        library.glfwSetDropCallback(self.win.window, self.drop_callback)

    def on_drop(self, paths) -> bool:
        """Files dropped on the window: open the one dropped, or say why not (one message)."""
        path, why = check_drop(paths)
        if path is None:
            self.state.open_messages.append(why)
            log.info("action: drop -> %s", why)
            print(why, file=sys.stderr)
            self.win.wake()
            return False
        self.win.actions.open_scene(path, "drop")
        return self.state.scene_source == path

    def open_recent(self, path: str) -> None:
        if not Path(path).is_file():
            why = f"{path} is no longer there (moved or deleted since it was opened)"
            self.state.open_messages.append(why)
            log.info("action: menu File > Recent -> %s", why)
            self.win.wake()
            return
        self.win.actions.open_scene(path, "menu File > Recent")

    def start_dialog(self, purpose: str, title: str, save: bool = False) -> None:
        why = self.dialog.start(purpose, title, save=save)
        if why:
            self.win.notice = why
            log.info("action: file dialog (%s) -> %s", purpose, why)

    def poll_dialog(self) -> None:
        done = self.dialog.poll()
        if done is None:
            return
        purpose, path = done
        if not path:
            log.info("action: file dialog (%s) -> cancelled", purpose)
        elif purpose == "open":
            self.win.actions.open_scene(path, "file dialog")
        elif purpose == "save view":
            self.win.actions.save_view("file dialog Save view as", Path(path))
        elif purpose == "save screenshot":
            self.save_frame_to(Path(path), "file dialog Save screenshot as")
        self.win.wake()

    def save_frame_to(self, path: Path, how: str) -> None:
        """The CPU frame as a PNG at ``path`` (a dialog's choice; .png added when missing)."""
        from PIL import Image
        path = path if path.suffix.lower() == ".png" else path.with_name(path.name + ".png")
        try:
            Image.fromarray(self.state.frame.color).save(path)
        except (OSError, ValueError) as error:
            self.win.notice = f"could not save {path}: {error}"
        else:
            self.win.notice = f"saved {path.name}"
        log.info("action: %s -> %s", how, self.win.notice)
