"""Camera hands that keep the course's views: orbit, pan, dolly, zoom and fit, as new Views.

Takes a :class:`core.camera.view.View` (VRP, VPN, VUP, window, PRP, F, B) and a gesture, and
returns another View of the same kind, so that every camera a user makes with the mouse is a
six-line view of Assignment #1 that ``python -m app matrices`` and ``render`` read back.

- **Orbit** (Shoemake 1992, *ARCBALL*): a drag from screen point ``p0`` to ``p1`` is mapped to
  two points on a unit ball in the VRC (u right, v up, n towards the viewer), and the unit
  quaternion ``p1 p0*`` turns the scene by twice the arc between them about ``p0 x p1``. The
  scene turns in front of the viewer, so the camera's frame (u, v, n) turns the other way
  about the VRP, or about a pivot (the window's: the scene's centre), the VRP turning round
  it with the frame; PRP, window, F and B are in VRC and go with it. The quaternions are written
  as the course's animation notes write them (``(s, v)``, the notes' product, ``v' = q^-1 v q``)
  and kept here because the camera ranks below the animation package.
- **Turntable** (:func:`turntable`): yaw about the world's up axis and pitch about the
  camera's right axis, with no roll (VUP becomes the up axis); the elevation stops short of
  the poles, where VUP would be parallel to VPN.
- **Pan**: the VRP moves in the view plane (along u and v) by the window's units per pixel.
- **Dolly** (perspective): the PRP moves along VPN, and the window shrinks with the eye's
  distance about the PRP's foot, so the field of view stays and everything grows as the eye
  comes nearer (moving the PRP alone, with the window fixed, would shrink what lies behind the
  view plane). Parallel: the window is scaled about its centre.
- **Zoom** (the field of view): the window alone is scaled about its centre.
- **Fit**: VRP at the centre of the scene's bounds, an on-axis PRP far enough for the
  bounding sphere to fill the window's short side, keeping the view's field of view.
- **Front and back planes follow the bounds** (:func:`follow_bounds`): F and B enclose the
  scene along n, F kept in front of the eye in perspective, so nothing is clipped by surprise.

:func:`pose_problems` is the one judge of a new pose: the view's own checks
(:func:`core.camera.view.problems`) and sizes kept within a billion times the scene's either
way; a caller keeps the last good view when it says no.
"""

from __future__ import annotations

import math

import numpy as np

from core.camera.view import View, cross3, problems, unit3, vrc_basis

# How much of the depth range the front plane keeps from the eye in perspective (z_min), and
# the margin F and B leave around the bounds (a fraction of the bounding sphere's radius).
NEAR_FRACTION = 1e-3
DEPTH_MARGIN = 0.02
# Sizes a pose may reach, in bounding-sphere radii, before it is refused as degenerate.
SMALLEST, LARGEST = 1e-9, 1e9
# The turntable's elevation stops this short of the poles (VUP parallel to VPN there).
MAX_ELEVATION = math.radians(89.0)
# The field of view fit uses when the view's own is unusable (half angle, radians).
DEFAULT_HALF_ANGLE = math.radians(25.0)


# -- quaternions, as the course's animation notes write them -------------------------------
def q_multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """``(s1 s2 - v1.v2, s1 v2 + s2 v1 + v1 x v2)``."""
    s1, v1, s2, v2 = q1[0], q1[1:], q2[0], q2[1:]
    return np.concatenate([[s1 * s2 - v1 @ v2], s1 * v2 + s2 * v1 + cross3(v1, v2)])


def q_conjugate(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def q_rotate(q: np.ndarray, v) -> np.ndarray:
    """``v' = q^-1 [0, v] q`` for a unit quaternion (the notes' sandwich)."""
    pure = np.concatenate([[0.0], np.asarray(v, dtype=np.float64)])
    return q_multiply(q_multiply(q_conjugate(q), pure), q)[1:]


def q_from_axis_angle(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` radians counter-clockwise about ``axis``: in the notes' form
    ``(cos angle/2, -sin angle/2 a)``."""
    a = unit3(axis)[0]
    return np.concatenate([[math.cos(angle / 2)], -math.sin(angle / 2) * a])


def q_matrix(q: np.ndarray) -> np.ndarray:
    """The 3 x 3 matrix R with ``R v = q_rotate(q, v)`` for a unit ``q = (s, x, y, z)``: the
    usual rotation matrix of the conjugate, since the notes rotate by ``q^-1 v q``."""
    s, x, y, z = (float(c) for c in q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y + s * z), 2 * (x * z - s * y)],
                     [2 * (x * y - s * z), 1 - 2 * (x * x + z * z), 2 * (y * z + s * x)],
                     [2 * (x * z + s * y), 2 * (y * z - s * x), 1 - 2 * (x * x + y * y)]])


# -- the arcball -----------------------------------------------------------------------------
def ball_point(x: float, y: float) -> np.ndarray:
    """Shoemake's mapping of a screen point (in ball radii from the centre, y up) onto the unit
    ball: inside the circle the sphere's front, ``z = sqrt(1 - r^2)``; outside, its rim."""
    r2 = x * x + y * y
    if r2 <= 1.0:
        return np.array([x, y, math.sqrt(1.0 - r2)])
    r = math.sqrt(r2)
    return np.array([x / r, y / r, 0.0])


def arcball(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """The unit quaternion that turns ``p0`` towards ``p1`` by twice their arc (Shoemake's
    ``p1 p0*``), in the notes' form (so that ``q_rotate`` applies it)."""
    standard = np.concatenate([[p0 @ p1], cross3(p0, p1)])   # p1 p0* for pure unit p0, p1
    q = q_conjugate(standard)                               # the notes rotate by q^-1 v q
    return q / math.sqrt(q @ q)


def screen_to_ball(px: float, py: float, width: int, height: int) -> tuple[float, float]:
    """A pixel (from the picture's top-left, y down) in ball radii from the picture's centre,
    y up; the ball's radius is half the picture's shorter side."""
    radius = max(min(width, height), 1) / 2.0
    return (px - width / 2.0) / radius, (height / 2.0 - py) / radius


# -- gestures: each returns a new View (F and B as they were: see follow_bounds) ------------
def _with(view: View, **changes) -> View:
    numbers = {"vrp": view.vrp, "vpn": view.vpn, "vup": view.vup, "window": view.window,
               "prp": view.prp, "front": view.front, "back": view.back}
    numbers.update(changes)
    floats = {k: (float(v) if k in ("front", "back") else tuple(float(c) for c in v))
              for k, v in numbers.items()}
    return View(**floats, label=view.label)


def orbit(view: View, q: np.ndarray, pivot=None) -> View:
    """The camera turned about the VRP — or about the world point ``pivot`` — so that the
    scene turns by ``q`` (given in the VRC).

    The camera's frame ``C = [u v n]`` becomes ``C Q^T``: the inverse turn, seen from the world.
    VPN and VUP become the new n and v, orthonormal to the last bit, so the frame never drifts
    into a degenerate one however many drags add up. About a pivot P the VRP turns with the
    frame, ``VRP' = P + W (VRP - P)`` with ``W = C' C^T`` the world's turn; PRP and the window
    stay, being in the VRC, so the eye keeps its place relative to the VRP."""
    before = np.column_stack(vrc_basis(view))
    frame = before @ q_matrix(q).T
    n = unit3(frame[:, 2])[0]
    u = unit3(cross3(frame[:, 1], n))[0]
    v = cross3(n, u)
    return _turned(view, before, (u, v, n), v, pivot)


def _turned(view: View, before: np.ndarray, after, vup, pivot) -> View:
    """``view`` with the camera frame ``before`` (columns u, v, n) turned to ``after``
    (u, v, n): VPN n, VUP ``vup``, and the VRP carried round ``pivot`` by the same turn
    (kept where it is when ``pivot`` is None)."""
    u, v, n = after
    if pivot is None:
        return _with(view, vpn=n, vup=vup)
    p = np.asarray(pivot, dtype=np.float64)
    turn = np.column_stack((u, v, n)) @ before.T
    vrp = p + turn @ (np.asarray(view.vrp, dtype=np.float64) - p)
    return _with(view, vrp=vrp, vpn=n, vup=vup)


def rotate_about(v, axis, angle: float) -> np.ndarray:
    """``v`` turned counter-clockwise by ``angle`` radians about the unit ``axis``
    (Rodrigues)."""
    v, axis = np.asarray(v, dtype=np.float64), np.asarray(axis, dtype=np.float64)
    c, s = math.cos(angle), math.sin(angle)
    return v * c + cross3(axis, v) * s + axis * (axis @ v) * (1.0 - c)


def turntable(view: View, yaw: float, pitch: float, up, pivot=None) -> View:
    """The camera of a turntable: the scene turned by ``yaw`` radians about the world axis
    ``up`` (positive: its front moves right) and by ``pitch`` about the camera's right axis
    (positive: its front moves down, the eye rises), with no roll: VUP becomes ``up``.

    VPN is written as its elevation over the horizon and its horizontal direction; the yaw
    turns the direction about ``up`` by ``-yaw`` (the camera turns against the scene), the
    pitch adds to the elevation, kept within ``MAX_ELEVATION`` of the horizon. The camera's
    frame and the VRP turn as :func:`orbit` turns them (about ``pivot``, or the VRP when
    None); PRP, window, F and B stay in the VRC."""
    up = unit3(up)[0]
    before = np.column_stack(vrc_basis(view))
    u0, v0, n0 = before.T
    level = n0 - (n0 @ up) * up
    if np.linalg.norm(level) < 1e-12:             # looking along the up axis: tip backwards
        level = -(v0 - (v0 @ up) * up)
    level = unit3(level)[0]
    elevation = math.asin(min(max(float(n0 @ up), -1.0), 1.0)) + pitch
    elevation = min(max(elevation, -MAX_ELEVATION), MAX_ELEVATION)
    level = rotate_about(level, up, -yaw)
    n = unit3(math.cos(elevation) * level + math.sin(elevation) * up)[0]
    u = unit3(cross3(up, n))[0]
    return _turned(view, before, (u, cross3(n, u), n), up, pivot)


def pan(view: View, dx: float, dy: float, width: int, height: int) -> View:
    """The VRP moved in the view plane so that the view plane's content follows a drag of
    ``(dx, dy)`` pixels (y down): the window's units per pixel, along -u and +v."""
    u, v, _ = vrc_basis(view)
    u_min, u_max, v_min, v_max = view.window
    du = -dx * (u_max - u_min) / max(width, 1)
    dv = dy * (v_max - v_min) / max(height, 1)
    return _with(view, vrp=np.asarray(view.vrp, dtype=np.float64) + du * u + dv * v)


def dolly(view: View, factor: float, projection: str) -> View:
    """Nearer (``factor < 1``) or farther. Perspective: PRP_n times ``factor`` (the PRP moves
    along VPN) and the window scaled by it about the PRP's foot ``(prp_u, prp_v)``, so the
    rays keep their directions. Parallel: the window scaled about its centre."""
    if projection != "perspective":
        return zoom(view, factor)
    pu, pv, pn = view.prp
    u_min, u_max, v_min, v_max = view.window
    window = (pu + factor * (u_min - pu), pu + factor * (u_max - pu),
              pv + factor * (v_min - pv), pv + factor * (v_max - pv))
    return _with(view, prp=(pu, pv, pn * factor), window=window)


def zoom(view: View, factor: float) -> View:
    """The window scaled by ``factor`` about its centre: a narrower or wider field of view."""
    u_min, u_max, v_min, v_max = view.window
    cu, cv = (u_min + u_max) / 2, (v_min + v_max) / 2
    hu, hv = (u_max - u_min) / 2 * factor, (v_max - v_min) / 2 * factor
    return _with(view, window=(cu - hu, cu + hu, cv - hv, cv + hv))


def sphere(lo, hi) -> tuple[np.ndarray, float]:
    """Centre and radius of the sphere about the box ``lo``..``hi`` (a point: radius 1)."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    centre = (lo + hi) / 2
    radius = float(np.linalg.norm(hi - lo)) / 2
    return centre, radius if radius > 0.0 else 1.0


def follow_bounds(view: View, lo, hi, projection: str) -> View:
    """F and B enclosing the box ``lo``..``hi`` along n (with a margin); in perspective F stays
    in front of the eye by a thousandth of the eye's reach, and B behind F."""
    centre, radius = sphere(lo, hi)
    _, _, n = vrc_basis(view)
    # the box's extreme depths along n: each axis contributes its nearer or farther end
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    base = (lo + hi) / 2 - np.asarray(view.vrp, dtype=np.float64)
    reach = float(np.abs(n) @ ((hi - lo) / 2))
    depth = np.array([base @ n - reach, base @ n + reach])
    margin = DEPTH_MARGIN * radius
    front, back = float(depth.max()) + margin, float(depth.min()) - margin
    if projection == "perspective":
        eye = float(view.prp[2])
        near = NEAR_FRACTION * max(eye - back, radius)
        front = min(front, eye - near)
        back = min(back, front - near)
    return _with(view, front=front, back=back)


def fit(view: View, lo, hi, projection: str) -> View:
    """The bounds framed: VRP at their centre, the PRP on the axis at the distance where the
    bounding sphere just fills the window's short side at the view's own field of view (or
    25 degrees when that is unusable), the window's aspect kept; VPN and VUP kept."""
    centre, radius = sphere(lo, hi)
    u_min, u_max, v_min, v_max = view.window
    half_u, half_v = (u_max - u_min) / 2, (v_max - v_min) / 2
    short = min(half_u, half_v)
    angle = math.atan2(short, view.prp[2]) if view.prp[2] > 0 else DEFAULT_HALF_ANGLE
    if not math.radians(1.0) <= angle <= math.radians(80.0):
        angle = DEFAULT_HALF_ANGLE
    distance = radius / math.sin(angle)
    half = radius / math.cos(angle) if projection == "perspective" else radius
    su, sv = half * half_u / short, half * half_v / short
    framed = _with(view, vrp=centre, window=(-su, su, -sv, sv), prp=(0.0, 0.0, distance))
    return follow_bounds(framed, lo, hi, projection)


def pose_problems(view: View, projection: str, lo, hi) -> list[str]:
    """Why the pose must be refused (empty when it is good): the view's own checks for
    ``projection`` and sizes within a billion times the scene's either way."""
    found = problems(view, projection)
    if found:
        return found
    centre, radius = sphere(lo, hi)
    u_min, u_max, v_min, v_max = view.window
    small, large = SMALLEST * radius, LARGEST * radius
    if min(u_max - u_min, v_max - v_min) < small:
        found.append(f"the window would be narrower than {SMALLEST:g} of the scene's size")
    if max(u_max - u_min, v_max - v_min) > large:
        found.append(f"the window would be wider than {LARGEST:g} times the scene's size")
    if projection == "perspective" and abs(view.prp[2]) < small:
        found.append("the eye would be on the view plane (PRP_n near 0)")
    if np.linalg.norm(np.asarray(view.vrp) - centre) > large or abs(view.prp[2]) > large:
        found.append(f"the camera would be over {LARGEST:g} times the scene's size away")
    _, n_len = unit3(view.vpn)
    across = cross3(unit3(view.vup)[0], unit3(view.vpn)[0])
    if n_len == 0.0 or math.sqrt(across @ across) < 1e-6:
        found.append("VUP would be parallel to VPN")
    return found
