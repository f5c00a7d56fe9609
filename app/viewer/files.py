"""Files as a desktop program takes them: dropped on the window, the recent list, dialogs.

- :func:`check_drop` takes what glfw's drop callback gives (paths as ``str``, or the raw
  ``bytes`` when a name is not UTF-8) and returns the one path to open, or ``None`` and the
  one message that says why nothing opens: several files at once, a folder, an empty file, a
  FIFO or device, a file over every reader's limit, a name that is not UTF-8, a path that does
  not exist. The readers check again (and say what is wrong inside a file).
- :class:`RecentFiles`: the last ten files opened, kept as JSON in the user's config
  directory (``platformdirs``; ``$XDG_CONFIG_HOME`` on Linux; ``$FVD_CONFIG_DIR`` first). A list that cannot be read or
  parsed, or a directory that cannot be written, is ignored with one warning: the viewer works
  without it. A file that has since gone stays listed, greyed, and says so when chosen.
- :class:`FileDialog`: the native open / save dialog of imgui-bundle's portable file dialogs,
  polled once a frame so that it never blocks the window's thread; where no dialog program
  exists (Linux without zenity, kdialog, matedialog or qarma) the window's own dialog on
  ImGui's widgets (:mod:`app.viewer.path_dialog`) takes its place.

No GL and no window library here.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import stat
import sys
from pathlib import Path

from core.scene.formats.errors import MAX_INPUT_BYTES, printable

log = logging.getLogger("fvd")

RECENT_COUNT = 10
RECENT_FILE = "recent.json"
APP_NAME = "fvd-viewer"
# The largest file any reader takes (a mesh): beyond it a dropped file is refused unread.
LARGEST_INPUT = max(MAX_INPUT_BYTES.values())
DIALOG_PROGRAMS = ("zenity", "kdialog", "matedialog", "qarma")


def _kind(mode: int) -> str:
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def check_drop(paths) -> tuple[str | None, str]:
    """``(path to open, "")`` or ``(None, why not)`` for the paths of one drop."""
    paths = list(paths)
    if not paths:
        return None, "dropped nothing"
    if len(paths) > 1:
        return None, (f"dropped {len(paths)} files at once: the viewer shows one scene at a "
                      f"time, so drop one scene, mesh, .tri or view file")
    path = paths[0]
    if isinstance(path, bytes):
        try:
            path = path.decode("utf-8")
        except UnicodeDecodeError:
            return None, (f"dropped a file whose name is not UTF-8 ({printable(repr(path))}): "
                          f"rename it to open it")
    shown = printable(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return None, f"dropped {shown}: no such file"
    except (OSError, ValueError) as error:
        return None, f"dropped {shown}: cannot read it: {getattr(error, 'strerror', None) or error}"
    if stat.S_ISDIR(mode):
        return None, f"dropped {shown}: a folder; drop a scene, mesh, .tri or view file"
    if not stat.S_ISREG(mode):
        return None, f"dropped {shown}: {_kind(mode)}, not a file to open"
    size = os.stat(path).st_size
    if size == 0:
        return None, f"dropped {shown}: the file is empty (0 bytes)"
    if size > LARGEST_INPUT:
        return None, (f"dropped {shown}: {size} bytes, more than any reader takes "
                      f"({LARGEST_INPUT >> 20} MiB)")
    return path, ""


# -- the recent list ---------------------------------------------------------------------------
def config_dir() -> Path:
    """``$FVD_CONFIG_DIR`` when set (the tests' own), else the user's config directory."""
    if os.environ.get("FVD_CONFIG_DIR"):
        return Path(os.environ["FVD_CONFIG_DIR"])
    import platformdirs
    return Path(platformdirs.user_config_dir(APP_NAME))


SAVED_VIEWS = "saved.views"          # Ctrl+S appends the view shown here


def state_dir() -> Path:
    """The user's state folder: ``$XDG_STATE_HOME/fvd-viewer`` on Linux, else
    ``~/.local/state/fvd-viewer`` (``platformdirs``; the platform's own elsewhere)."""
    import platformdirs
    return Path(platformdirs.user_state_dir(APP_NAME))


def saved_views_file() -> Path:
    """The view file Ctrl+S appends to, in :func:`state_dir`; the folder is made, readable by
    its owner only, when missing. Raises OSError when it cannot be made or is not a folder
    (a file or a dangling link of that name). A ``saved.views`` that an earlier version
    wrote into the folder it was started from stays there, and reads as before."""
    folder = state_dir()
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    if not folder.is_dir():
        raise NotADirectoryError(f"{folder} is not a folder")
    return folder / SAVED_VIEWS


def read_small_text(path: Path, limit: int, what: str) -> str:
    """The text of ``path``, a regular file of at most ``limit`` bytes (a FIFO would block the
    window for good, /dev/zero fill its memory): else ValueError saying which and why."""
    try:
        mode = os.stat(path)
    except OSError as error:
        raise ValueError(f"{what} {printable(path)} cannot be read: "
                         f"{error.strerror or error}") from None
    if not stat.S_ISREG(mode.st_mode):
        raise ValueError(f"{what} {printable(path)} is {_kind(mode.st_mode)}, not a file")
    if mode.st_size > limit:
        raise ValueError(f"{what} {printable(path)} has {mode.st_size:,} bytes; at most "
                         f"{limit:,} are read")
    with open(path, "rb") as fh:
        data = fh.read(limit + 1)            # a file that grew since: still no more than this
    if len(data) > limit:
        raise ValueError(f"{what} {printable(path)} has more than {limit:,} bytes")
    return data.decode("utf-8")


RECENT_LIMIT = 64 * 1024                 # bytes: ten paths take a few hundred


class RecentFiles:
    """The last :data:`RECENT_COUNT` files opened, newest first, kept across sessions."""

    def __init__(self, path: Path | None = None):
        self.path = Path(path) if path is not None else config_dir() / RECENT_FILE
        self.paths: list[str] = []
        self.warning = ""
        self._load()

    def _warn(self, text: str) -> None:
        self.warning = text
        log.warning("%s", text)
        print(f"warning: {text}", file=sys.stderr)

    def _load(self) -> None:
        if not os.path.lexists(self.path):
            return
        try:
            data = json.loads(read_small_text(self.path, RECENT_LIMIT, "the list"))
            listed = data["recent"] if isinstance(data, dict) else None
            if not isinstance(listed, list) or not all(isinstance(p, str) for p in listed):
                raise ValueError('expected {"recent": [paths]}')
        except RecursionError:
            self._warn(f"the recent-files list {printable(self.path)} is ignored: it is nested "
                       f"too deep to be a list of paths")
            return
        except (OSError, ValueError, KeyError) as error:
            self._warn(f"the recent-files list {printable(self.path)} is ignored: it cannot be "
                       f"read ({printable(error)})")
            return
        self.paths = list(dict.fromkeys(listed))[:RECENT_COUNT]

    def add(self, source: str) -> None:
        """``source`` opened: first in the list, then saved (a failure is one warning)."""
        if source == "-":
            return
        path = str(Path(source).resolve())
        self.paths = [path] + [p for p in self.paths if p != path][:RECENT_COUNT - 1]
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_name(self.path.name + ".tmp")
            tmp.write_text(json.dumps({"recent": self.paths}, indent=1), encoding="utf-8")
            os.replace(tmp, self.path)
        except OSError as error:
            self._warn(f"the recent-files list could not be saved to {printable(self.path)}: "
                       f"{error.strerror or error}")

    def items(self) -> list[tuple[str, bool]]:
        """(path, still there) for each, newest first."""
        return [(p, os.path.isfile(p)) for p in self.paths]


# -- the native dialog -----------------------------------------------------------------------
def dialog_missing() -> str:
    """"" when a native dialog can be shown here; else why not."""
    if sys.platform.startswith("linux") and not any(shutil.which(p) for p in DIALOG_PROGRAMS):
        return ("no file dialog program found (zenity, kdialog, matedialog or qarma): type "
                "the path in File > Open scene instead")
    return ""


# What the in-window dialog lists besides folders, for each purpose (empty: every file).
DIALOG_SUFFIXES = {"save view": (".views",), "save screenshot": (".png",)}


class FileDialog:
    """One dialog at a time, polled without blocking: the desktop's (imgui-bundle's
    portable_file_dialogs runs the system's dialog in another process) where there is one,
    else the window's own (:mod:`app.viewer.path_dialog`, drawn by :meth:`draw` each frame)."""

    def __init__(self):
        self._dialog = None
        self._purpose = ""
        self.chooser = None                 # the in-window dialog, while it is open
        self._title = ""
        self._chosen: tuple[str, str] | None = None

    @property
    def open(self) -> bool:
        return self._dialog is not None or self.chooser is not None

    def start(self, purpose: str, title: str, save: bool = False, default: str = "") -> str:
        """Show the dialog for ``purpose`` ("open", "save view" ...); returns "" or why not."""
        if self.open:
            return "a file dialog is already open"
        if dialog_missing():
            from app.viewer.path_dialog import PathChooser
            self.chooser = PathChooser(purpose, save, suffixes=DIALOG_SUFFIXES.get(purpose, ()))
            self._title = title
            return ""
        from imgui_bundle import portable_file_dialogs as pfd
        make = pfd.save_file if save else pfd.open_file
        try:
            self._dialog = make(title, default)
        except Exception as error:          # the dialog program failed to start
            return f"the file dialog could not be shown: {error}"
        self._purpose = purpose
        return ""

    def draw(self, imgui, displayable, cancel: bool = False) -> None:
        """The in-window dialog, inside the GUI frame (nothing when it is not open);
        ``cancel``: Esc closes it."""
        if self.chooser is None:
            return
        from app.viewer.path_dialog import draw
        still, path = draw(imgui, self.chooser, self._title, displayable, cancel)
        if not still:
            self._chosen = (self.chooser.purpose, str(path) if path is not None else "")
            self.chooser = None

    def poll(self) -> tuple[str, str] | None:
        """``(purpose, path)`` once the user has chosen ("" path: cancelled); else None."""
        if self._chosen is not None:
            chosen, self._chosen = self._chosen, None
            return chosen
        if self._dialog is None or not self._dialog.ready(0):
            return None
        result = self._dialog.result()
        self._dialog = None
        path = result[0] if isinstance(result, list) and result else (result or "")
        return self._purpose, str(path)
