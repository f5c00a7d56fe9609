"""``python -m app view [SCENE]``: open the viewer window, or render PNGs when there is no display.

``main(scene_source, size)`` loads the scene (the house, ``core.paths.DEFAULT_SCENE``, when
``scene_source`` is None), prints the reader's invalid-view messages on stderr, and opens
:class:`app.viewer.window.ViewerWindow`. Without a display (no ``DISPLAY``/``WAYLAND_DISPLAY``, or glfw
cannot make a window) it says so and renders every view with the scene's default projection
and shading to PNG files instead (``--out`` dir, else ``$FVD_OUT``, else ``./fvd-views/``),
naming each file.

Logging: logger ``fvd`` goes to stderr and, when ``$FVD_LOG`` names a file, to that file too
(the Xvfb test reads it). Start-up time is logged: the window shows its first frame within
about a second when numba's cache is warm, so heavy modules are imported only when needed.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
from pathlib import Path

from app import startup_gc
from app.naming import picture_name

log = logging.getLogger("fvd")

DEFAULT_OUT_DIR = "fvd-views"


def process_age() -> float:
    """Seconds since this process started (from /proc where there is one)."""
    try:
        with open("/proc/self/stat") as f:
            # Field 22 is the start time in clock ticks after boot; the command name (field 2)
            # may contain spaces, so count from the closing parenthesis.
            start_ticks = int(f.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime") as f:
            uptime = float(f.read().split()[0])
        return max(uptime - start_ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError):
        return time.perf_counter() - _IMPORTED_AT


_IMPORTED_AT = time.perf_counter()


def setup_logging(level: int | None = None) -> None:
    """Logger ``fvd``: to stderr at ``level`` and up (WARNING unless told: the command line's
    ``-v`` gives INFO, ``-q`` ERROR), and every INFO line to ``$FVD_LOG`` when it is set,
    whatever ``level`` is (the window tests read it). Called again, only the level changes.

    What a user must see is not logged but printed (the no-display notice, the files written,
    a saved screenshot's path, errors), so the quiet default hides only the timings and the
    record of actions."""
    if getattr(log, "_fvd_configured", False):
        if level is not None:
            log._fvd_stderr.setLevel(level)
        return
    log._fvd_configured = True
    log.setLevel(logging.INFO)
    log.propagate = False
    fmt = logging.Formatter("fvd %(relativeCreated)8.0fms %(message)s")
    stderr = logging.StreamHandler(sys.stderr)
    stderr.setFormatter(fmt)
    stderr.setLevel(logging.WARNING if level is None else level)
    log.addHandler(stderr)
    log._fvd_stderr = stderr
    path = os.environ.get("FVD_LOG")
    if path:
        try:
            handler = logging.FileHandler(path, encoding="utf-8")
        except OSError as error:
            print(f"FVD_LOG={path}: cannot write the log: {error}", file=sys.stderr)
        else:
            handler.setFormatter(fmt)
            handler.setLevel(logging.INFO)
            log.addHandler(handler)


def display_available() -> bool:
    """Is there a display to open a window on? (Windows and macOS always have one.)"""
    if sys.platform.startswith(("win", "darwin")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def main(scene_source: str | None, size: tuple[int, int] | None = None,
         out_dir: str | Path | None = None, options: dict | None = None,
         reference: str | None = None) -> int:
    """Open the viewer on ``scene_source`` with a ``size`` framebuffer; 0 on success.

    ``size`` None means the scene's own size (500 x 500 unless it says otherwise).
    ``out_dir``: where screenshots go (default: ``./screenshots``) and, with no display,
    the per-view PNGs (default ``$FVD_OUT`` or ``./fvd-views``). ``options``: ``rasterizer``,
    ``keep_aspect``, ``course_tri`` (None: the scene's own). ``reference``: a PNG that ``h``
    holds the picture against (app.viewer.reference).
    """
    setup_logging()
    reference_image = None
    if reference is not None:
        from app.viewer.reference import load_reference
        try:
            reference_image = load_reference(reference)
        except ValueError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    started = time.perf_counter() - process_age()
    state = _open_state(scene_source, size, options, started)
    if state is None:
        return 2
    window, reason, what = _open_window(state, out_dir, started, reference_image, reference,
                                        enlarge=size is None)
    if reason is not None:
        return render_all_views(state, out_dir, reason, what)
    log.info("window open, %dx%d framebuffer (%.3f s after process start)",
             state.size[0], state.size[1], time.perf_counter() - started)
    return window.run()


def _default_scene_source() -> str:
    """The default scene's path, shown in every view's label: relative to the working
    directory when that is shorter."""
    from core.paths import DEFAULT_SCENE
    try:
        relative = os.path.relpath(DEFAULT_SCENE)
    except ValueError:                    # another drive (Windows): no relative path
        relative = ".."
    return relative if not relative.startswith("..") else str(DEFAULT_SCENE)


def _open_state(scene_source, size, options, started):
    """The viewer's state on the scene (its messages printed), or None when it cannot be read
    (said why)."""
    from app.session.state import ViewerState, reader_errors
    if scene_source is None:
        scene_source = _default_scene_source()
    prime_while_loading(scene_source, (options or {}).get("renderer_name"))
    try:
        chosen = {k: v for k, v in (options or {}).items() if v is not None}
        state = ViewerState.open(scene_source, size=tuple(size) if size else None, **chosen)
    except reader_errors() as error:
        reason = str(error)                # the readers' messages start with the file's name
        print(f"error: cannot open {reason}" if reason.startswith(str(scene_source))
              else f"error: cannot open {scene_source}: {reason}", file=sys.stderr)
        return None
    for message in state.scene.view_messages:
        print(f"invalid view: {message}", file=sys.stderr)
    for message in state.scene.messages:
        print(f"warning: {message}", file=sys.stderr)
    log.info("scene %s: %d valid views, %d invalid (%.3f s after process start)",
             scene_source, state.views.count, len(state.scene.view_messages),
             time.perf_counter() - started)
    return state


MIN_PICTURE_HEIGHT = 480    # a window shorter than this cuts the panel off (robot_arm: 240)


def enlarged(size: tuple[int, int]) -> tuple[int, int]:
    """A scene's own picture size, scaled up (its aspect kept) to at least
    :data:`MIN_PICTURE_HEIGHT` high, so that the panel beside it can be read."""
    width, height = size
    if height >= MIN_PICTURE_HEIGHT:
        return width, height
    k = MIN_PICTURE_HEIGHT / height
    return max(1, round(width * k)), MIN_PICTURE_HEIGHT


def _open_window(state, out_dir, started, reference_image, reference, enlarge=False):
    """(the window, None, _) once it is open; else (None, why not, what was missing), for
    the PNGs rendered instead. ``enlarge``: the size is the scene's own (no ``--size``), so a
    small one is scaled up for the window (:func:`enlarged`)."""
    reason = None if display_available() else "DISPLAY and WAYLAND_DISPLAY are not set"
    what = "no display found"
    window = None
    if reason is None:
        what = "no window could be opened on this display"
        if enlarge and enlarged(state.size) != state.size:
            log.info("picture %dx%d: the scene's %dx%d scaled up so that the panel fits",
                     *enlarged(state.size), *state.size)
            state.resize(*enlarged(state.size))
        prime_kernels(state)
        try:
            from app.viewer.window import ViewerWindow, WindowError
            window = ViewerWindow(state, out_dir=out_dir, started=started)
            if reference_image is not None:
                from app.viewer.reference import ReferenceView
                window.tools.reference = ReferenceView(reference_image, Path(reference).name)
        except (WindowError, ImportError) as error:
            reason = str(error)
        except Exception as error:           # e.g. moderngl: no OpenGL 3.3 on this display
            reason = f"{type(error).__name__}: {error}"
    return window, reason, what


def prime_kernels(state) -> threading.Thread | None:
    """Load numba and the first frame's kernels on a thread while the window opens.

    numba's first use costs ~0.2 s before any kernel runs (its typing and target registries),
    and each cached kernel ~10 ms to load; the window's own set-up (X11, the GL context, the
    panel) takes as long again. A 16 x 16 frame with the window's settings needs the same
    compiled code, so when the window asks for its first frame most kernels are in memory.
    The default scene (lines only) needs no kernel: nothing is started for it; nor on a cold
    kernel cache, which the window's worker processes fill (a compile here would hold the GIL
    the window needs).
    """
    settings = state.choices.settings()
    if settings.shading == "wireframe" or not state.scene.triangle_count or not state.renderable:
        return None
    from app.distribution.warm_stamp import is_warm
    if not is_warm():
        return None

    def prime():
        from app.distribution.warmup_steps import quick
        from app.session.state import render
        from core.context import RenderContext
        try:
            render(state.scene, state.views.current, quick(settings.replace(size=(16, 16))),
                   RenderContext())
        except Exception as error:        # the window's own frame will say what is wrong
            log.info("kernels not primed: %s", error)

    thread = threading.Thread(target=prime, name="prime kernels", daemon=True)
    thread.start()
    return thread


def prime_while_loading(source: str, renderer: str | None) -> threading.Thread | None:
    """Load the kernels of the scene's renderer on a thread while the scene loads (numba
    itself is imported here first, see below).

    A scene that takes a while to read (a mesh to parse, textures to build, creases to
    split) otherwise loads them after it, in :func:`prime_kernels`. The renderer and shading
    come from the scene file's top level (the command line's renderer first); a stand-in of
    200 triangles is drawn 16 x 16 with them, and the real scene's priming loads the rest
    (textures, ...). Measured, alternating: the glass bunny's first picture 1.35-1.47 s
    without, 1.26-1.30 s with. Nothing for a wireframe scene (no kernel) or another file."""
    settings = _peeked_settings(source, renderer)
    if settings is None:
        return None
    from app.distribution.warm_stamp import is_warm
    if not is_warm():
        return None                       # a cold cache: the window's worker processes fill it
    # numba's modules import one another: imported on two threads at once (this one and the
    # scene reader's, for creases), one thread may meet the other's half-made module and the
    # viewer exits ("partially initialized module 'numba.core.event'", seen once in CI). So
    # numba, and what the thread imports, come in here before it starts.
    import core.jit  # noqa: F401
    from app.distribution.warmup_steps import quick
    from app.session.state import render
    from core.context import RenderContext
    from core.scene.generators import sphere_torus

    def prime():
        stand_in = sphere_torus(triangles=200)
        try:
            render(stand_in, stand_in.views[0], quick(settings), RenderContext())
        except Exception as error:        # the scene's own priming and frame will say it
            log.info("kernels not primed early: %s", error)

    thread = threading.Thread(target=prime, name="prime kernels early", daemon=True)
    thread.start()
    return thread


def _peeked_settings(source: str, renderer: str | None):
    """16 x 16 settings with the renderer and shading a TOML scene file names at its top
    level, or None (not a TOML scene file, unreadable, or wireframe)."""
    if not str(source).endswith(".toml"):
        return None
    import tomllib
    try:
        with open(source, "rb") as file:
            top = tomllib.load(file)
        from core.settings import RenderSettings
        shading = top.get("shading", "flat")
        if shading == "wireframe":
            return None
        return RenderSettings(renderer=renderer or top.get("renderer", "zbuffer"),
                              shading=shading, size=(16, 16))
    except Exception:                     # (the scene's reader says what is wrong with it)
        return None


def render_all_views(state, out_dir: str | Path | None, reason: str,
                     what: str = "no display found") -> int:
    """No display (or no window on it, ``what``): every view (the scene's projection and
    shading) to a PNG; 0 if all were written."""
    startup_gc.resume()                 # no first frame on screen to wait for
    from PIL import Image

    out = Path(out_dir or os.environ.get("FVD_OUT") or DEFAULT_OUT_DIR)
    scene = state.scene
    print(f"{what} ({reason}): rendering the {len(scene.views)} views to PNG in "
          f"{out}{os.sep} instead", file=sys.stderr)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        print(f"error: cannot create {out}: {error}", file=sys.stderr)
        return 1
    failed = 0
    for index in range(len(scene.views)):
        state.views.set_view(index)
        state.frames.update()
        number = state.views.number              # its position in the file
        if state.render_error:
            print(f"error: view {number}: {state.render_error}", file=sys.stderr)
            failed += 1
            continue
        frame = state.frame
        if frame.message:
            print(f"view {number}: {frame.message}", file=sys.stderr)
        path = out / picture_name(scene.name, number, state.projection, state.shading,
                                  state.renderer_name)
        try:
            Image.fromarray(frame.color).save(path)
        except OSError as error:
            print(f"error: cannot write {path}: {error}", file=sys.stderr)
            failed += 1
            continue
        log.info("%s", state.frames.summary())
        print(f"wrote {path}")
    if not scene.views:
        print(f"{scene.name}: no valid view to render", file=sys.stderr)
        return 1
    return 1 if failed else 0
