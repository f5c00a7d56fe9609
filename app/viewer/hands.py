"""The window's camera hands: mouse gestures turned into course views, and the view's numbers.

Takes the :class:`app.session.state.ViewerState` and gestures in picture pixels (from the
picture's top-left, y down) and gives the state a new :class:`core.camera.view.View` made by
:mod:`core.camera.orbit`: a drag orbits with Shoemake's arcball or the turntable (yaw about
the world's up axis, pitch about the camera's right axis) about the point under the cursor at
the press (the window reads it from the frame's depth: :mod:`app.session.pick`), the scene's
centre when the press misses, or the VRP (:data:`PIVOTS`); Shift+drag or the middle button pans, the wheel dollies, Ctrl+wheel changes the window (the field of view);
F fits the scene's bounds, Enter returns to the file's view exactly. Each drag works from the
view it started at (back at the start point, the view is the start view again). After every
gesture F and B follow the scene's bounds; a pose that :func:`core.camera.orbit.pose_problems`
refuses is not taken: the last good view stays and :attr:`CameraHands.message` says why.

:func:`view_lines` is the panel's section (VRP … B and each factor of N_per / N_par, the
numbers ``python -m app matrices`` prints) and :func:`save_view` appends the view shown to a
view file as six lines whose numbers read back bit for bit.

No GL and no window library here: the window calls these from its callbacks.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from core.camera import orbit
from core.camera.view import View, n_par_factors, n_per_factors

log = logging.getLogger("fvd")

# Every key and mouse action of the window, for the help (F1, Help > Keys).
KEYS_HELP = (
    ("Mouse on the picture", ""),
    ("left click", "next view (inspect mode: the pixel's record)"),
    ("left drag", "orbit about the point under the cursor (the scene's centre off the "
                  "model; View menu: the centre or the VRP)"),
    ("Shift+drag, middle drag", "pan the VRP in the view plane"),
    ("wheel", "dolly (perspective: the PRP along VPN; parallel: the window)"),
    ("Ctrl+wheel", "the window alone (field of view)"),
    ("Alt+wheel", "loupe: magnify the picture's pixels (up to 32x)"),
    ("right click", "pop-up menu: projection, shading"),
    ("drop a file", "open it (scene, mesh, .tri or view file)"),
    ("Camera", ""),
    ("Enter", "the file's view again, exactly"),
    ("f", "fit the scene's bounds"),
    ("y", "arcball / turntable (yaw about the up axis, pitch, no roll)"),
    ("Left / Right, Up / Down", "previous / next view"),
    ("Picture", ""),
    ("p / o", "perspective / parallel"),
    ("shading keys", ""),                  # keys_help: the registered modes' keys
    ("a", "keep the window's aspect (letterbox) or stretch it"),
    ("renderer keys", ""),                 # keys_help: the registered renderers' keys
    ("l", "headlight on / off (a light at the eye in place of the scene's)"),
    ("t / b", "next texture filter / bump maps on-off"),
    ("i / v / h", "inspect mode / next buffer view / compare (OpenGL or --reference)"),
    ("Animation", ""),
    ("space", "play / pause"),
    (", .  [ ]", "step a frame back / forward, halve / double the speed"),
    ("Window", ""),
    ("s", "save the frame as a PNG in screenshots/"),
    ("Ctrl+S", "save the view: six lines appended to saved.views in the user's state "
               "folder (~/.local/state/fvd-viewer)"),
    ("Ctrl+Z / Ctrl+Shift+Z", "undo / redo a camera move (a drag, a wheel spin, a view)"),
    ("F1", "this help"),
    ("Esc", "close a menu, dismiss a message, else quit"),
    ("q", "quit"),
)



def keys_help() -> tuple[tuple[str, str], ...]:
    """:data:`KEYS_HELP` with the shading modes' and the renderers' keys as registered (each
    entry's ``key`` and ``label``): a mode or renderer registered with a key is in the help."""
    from core.registry import shading_modes
    from core.renderers import renderers
    modes = [m for m in shading_modes() if m.key]
    shading = [(" ".join(m.key.lower() for m in modes), ", ".join(m.label for m in modes))]
    keys = dict.fromkeys(r.key for r in renderers() if r.key)
    render = [(key.lower(), " / ".join(r.label for r in renderers() if r.key == key))
              for key in keys]
    rows = {"shading keys": shading, "renderer keys": render}
    return tuple(row for key, what in KEYS_HELP for row in rows.get(key, [(key, what)]))


WHEEL_STEP = 0.9             # one wheel notch nearer: the eye's distance (or window) x 0.9
PIVOTS = {"cursor": "the point under the cursor", "scene": "the scene's centre",
          "vrp": "the VRP (the course's)"}
ROTATIONS = {"arcball": "Arcball (Shoemake)", "turntable": "Turntable (no roll)"}
VIEW_FILE_LIMIT = 16 * 1024 * 1024       # bytes of a view file Ctrl+S reads before appending
WHEEL_GESTURE_S = 0.6       # wheel notches closer than this in time are one gesture (one undo step)
TURNTABLE_TURN = np.pi       # radians a drag across the picture's shorter side turns


def scene_bounds(scene) -> tuple[np.ndarray, np.ndarray]:
    """The box holding every finite vertex of the scene (a unit box about 0 when empty)."""
    parts = [np.asarray(m.positions, dtype=np.float64).reshape(-1, 3) for m in scene.meshes]
    points = np.concatenate(parts) if parts else np.zeros((0, 3))
    points = points[np.isfinite(points).all(axis=1)]
    if not len(points):
        return -np.ones(3), np.ones(3)
    return points.min(axis=0), points.max(axis=0)


@dataclass
class Drag:
    """One press on the picture: where, which gesture, and the view it started from."""

    x: float
    y: float
    pan: bool
    start: View | None = None       # set once the drag passes the threshold
    moved: bool = False
    under: np.ndarray | None = None     # the world point under the press (None: a miss)
    pivot: np.ndarray | None = None     # what it orbits about (None: the VRP), at its start


class CameraHands:
    """Gestures on ``state``'s view. Each returns whether a new view was taken."""

    def __init__(self, state):
        self.state = state
        self.message = ""           # why the last gesture was refused ("" when it was taken)
        self._bounds_of = None
        self._bounds = (-np.ones(3), np.ones(3))
        self.drag: Drag | None = None
        self._wheel_at, self._wheel_gesture = -1e9, None
        # a drag orbits about: "cursor" (the point under the press, else the scene's centre),
        # "scene" (its bounds' centre) or "vrp"; by the arcball or the turntable
        self.pivot = "cursor"
        self.rotation = "arcball"

    # -- what the gestures work on -----------------------------------------------------------
    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        scene = self.state.scene
        if self._bounds_of is not scene:
            self._bounds_of, self._bounds = scene, scene_bounds(scene)
        return self._bounds

    @property
    def usable(self) -> str:
        """"" when the camera can move; else why not."""
        if self.state.views.current is None:
            return "there is no valid view to move"
        return ""

    def _take(self, candidate: View, what: str) -> bool:
        """Make F and B follow the bounds, judge the pose, and show it or keep the last one."""
        projection = self.state.projection
        candidate = orbit.follow_bounds(candidate, *self.bounds, projection)
        source = self.state.views.file_view
        candidate = replace(candidate, label=f"{source.label if source else 'view'}, moved")
        found = orbit.pose_problems(candidate, projection, *self.bounds)
        if found:
            self.message = f"{what} refused, the last good view kept: " + "; ".join(found)
            log.info("camera: %s", self.message)
            return False
        self.message = ""
        self.state.views.set_hand_view(candidate)
        return True

    def _base(self, what: str) -> View | None:
        why = self.usable
        if why:
            self.message = f"{what}: {why}"
            return None
        return self.state.views.current

    # -- drags -------------------------------------------------------------------------------
    def press(self, x: float, y: float, pan: bool, under=None) -> None:
        """A left (``pan``: Shift or middle) press at picture pixel (x, y); ``under``: the
        world point drawn there, or None where the press misses the model."""
        self.drag = Drag(x, y, pan, under=None if under is None
                         else np.asarray(under, dtype=np.float64))

    def move(self, x: float, y: float, threshold: float) -> bool:
        """The pointer at (x, y) with the button down; a drag starts once it is more than
        ``threshold`` pixels from the press. Returns whether the view changed."""
        d = self.drag
        if d is None:
            return False
        if d.start is None:
            if np.hypot(x - d.x, y - d.y) <= threshold:
                return False
            d.start = self._base("drag")
            if d.start is None:
                return False
            d.pivot = self.pivot_point(d.under)
            self.state.camera_gesture = d         # the whole drag is one undo step
        d.moved = True
        width, height = self.state.size
        if d.pan:
            candidate = orbit.pan(d.start, x - d.x, y - d.y, width, height)
        elif self.rotation == "turntable":
            per_pixel = TURNTABLE_TURN / max(min(width, height), 1)
            candidate = orbit.turntable(d.start, (x - d.x) * per_pixel, (y - d.y) * per_pixel,
                                        self.up(), d.pivot)
        else:
            p0 = orbit.ball_point(*orbit.screen_to_ball(d.x, d.y, width, height))
            p1 = orbit.ball_point(*orbit.screen_to_ball(x, y, width, height))
            candidate = orbit.orbit(d.start, orbit.arcball(p0, p1), d.pivot)
        return self._take(candidate, "pan" if d.pan else "orbit")

    def release(self, x: float, y: float, threshold: float) -> bool:
        """The button released at (x, y): True when this was a drag (not a click)."""
        self.move(x, y, threshold)
        d, self.drag = self.drag, None
        return d is not None and d.start is not None

    def pivot_point(self, under=None):
        """The world point a drag orbits about: ``under`` (the point under the press) when the
        pivot is the cursor's and the press hit the model, else the centre of the scene's
        bounds; None for the VRP (the course's views turn about it; the Cornell box's VRP is
        at the eye, so there the camera would turn away from the box)."""
        if self.pivot == "vrp":
            return None
        if self.pivot == "cursor" and under is not None:
            return under
        return orbit.sphere(*self.bounds)[0]

    def up(self) -> np.ndarray:
        """The world's up axis of the turntable: the file's view's VUP (the scene's up)."""
        source = self.state.views.file_view
        return np.asarray(source.vup if source is not None else (0.0, 1.0, 0.0),
                          dtype=np.float64)

    def set_pivot(self, pivot: str) -> None:
        if pivot not in PIVOTS:
            raise ValueError(f"the orbit pivot must be one of {', '.join(PIVOTS)}, not {pivot!r}")
        self.pivot = pivot

    def set_rotation(self, rotation: str) -> None:
        if rotation not in ROTATIONS:
            raise ValueError(f"the rotation must be one of {', '.join(ROTATIONS)}, "
                             f"not {rotation!r}")
        self.rotation = rotation

    # -- the wheel, fit, reset ---------------------------------------------------------------
    def wheel(self, notches: float, field_of_view: bool = False) -> bool:
        """Up (positive) comes nearer; with ``field_of_view`` the window alone narrows."""
        what = "zoom" if field_of_view else "dolly"
        base = self._base(what)
        if base is None or not notches:
            return False
        now = time.monotonic()                    # notches in quick succession: one step
        if now - self._wheel_at > WHEEL_GESTURE_S:
            self._wheel_gesture = object()
        self._wheel_at = now
        self.state.camera_gesture = self._wheel_gesture
        factor = WHEEL_STEP ** float(notches)
        candidate = (orbit.zoom(base, factor) if field_of_view
                     else orbit.dolly(base, factor, self.state.projection))
        return self._take(candidate, what)

    def fit(self) -> bool:
        base = self._base("fit")
        if base is None:
            return False
        self.state.camera_gesture = None
        return self._take(orbit.fit(base, *self.bounds, self.state.projection), "fit")

    def reset(self) -> bool:
        """The file's view again, exactly (its own F and B too)."""
        self.message = ""
        return self.state.views.reset()

    def projection_changed(self) -> None:
        """A moved camera's F and B redone for the new projection (perspective keeps F in
        front of the eye, parallel need not)."""
        if self.state.hand_view is not None:
            self._take(self.state.hand_view, "projection change")


def _numbers(values) -> str:
    return " ".join(f"{float(v):.6g}" for v in values)


def view_lines(view: View, projection: str) -> list[str]:
    """The panel's camera section: the view's numbers, then each factor of N_per (or N_par)
    as the matrices command names and computes them, one matrix row a line."""
    lines = [f"VRP {_numbers(view.vrp)}", f"VPN {_numbers(view.vpn)}",
             f"VUP {_numbers(view.vup)}", f"window {_numbers(view.window)}",
             f"PRP {_numbers(view.prp)}", f"F {view.front:.6g}  B {view.back:.6g}"]
    try:
        factors = (n_per_factors if projection == "perspective" else n_par_factors)(view)
    except ValueError as error:
        return lines + [f"no matrices: {error}"]
    for name, m in factors.items():
        if m.ndim == 0:
            lines.append(f"{name} = {float(m):.6g}")
            continue
        lines.append(f"{name} =")
        lines.extend(" ".join(f"{c:>9.4g}" for c in row) for row in m)
    return lines


def view_text(view: View, comment: str) -> str:
    """Six lines of Assignment #1 (after a comment line), each number the shortest decimal
    that reads back as the same float64 (``repr``)."""
    rows = (view.vrp, view.vpn, view.vup, view.window, view.prp, (view.front, view.back))
    body = "\n".join(" ".join(repr(float(c)) for c in row) for row in rows)
    return f"# {comment}\n{body}\n"


def save_view(view: View, path: Path, comment: str) -> int:
    """Append ``view`` to the view file at ``path`` (made if missing); returns its number in
    the file (counting every view, as ``render --view`` does). Raises OSError when the file
    cannot be read or written, ValueError when it is not a view file we can add to (a
    truncated last view would swallow the new numbers)."""
    from core.scene.formats.viewfile import read_view_entries
    from app.viewer.files import read_small_text
    path = Path(path)
    try:
        text = read_small_text(path, VIEW_FILE_LIMIT, "the view file") \
            if os.path.lexists(path) else ""
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not a text file: the view was not saved") from None
    entries = read_view_entries(text, str(path))
    if entries and isinstance(entries[-1], str) and ": truncated:" in entries[-1]:
        raise ValueError(f"{entries[-1]}: a view added after it would be read as its end, "
                         f"so the view was not saved")
    separator = "" if not text or text.endswith("\n") else "\n"
    with path.open("a", encoding="utf-8") as out:
        out.write(separator + ("\n" if text else "") + view_text(view, comment))
    return len(entries) + 1
