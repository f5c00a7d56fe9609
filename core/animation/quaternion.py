"""Unit quaternions for orientation in-betweening (course notes, 16 April; Shoemake 1985).

A quaternion is ``(s, v)`` = ``s + v_x i + v_y j + v_z k``, stored as a float64 array
``[s, x, y, z]``. The notes' product is the implementation::

    (s1, v1)(s2, v2) = (s1 s2 - v1 . v2,  s1 v2 + s2 v1 + v1 x v2)

and a vector ``v`` is rotated as the notes write it, ``v' = q^-1 [0, v] q``. With that form,
rotating by ``q1`` and then by ``q2`` is rotating by the product ``q1 q2`` (left to right, in the
order the rotations happen), and the unit quaternion that turns vectors counter-clockwise by
``theta`` about the unit axis ``a`` is ``(cos theta/2, -sin theta/2 a)``
(:func:`from_axis_angle`). ``q`` and ``-q`` are the same rotation.

In-betweening: :func:`slerp` (the great arc on the unit sphere, constant angular speed,
shortest path) and :func:`squad` (Shoemake's spherical cubic through several keys, C1 at the
keys).
"""

from __future__ import annotations

import numpy as np

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def quat(s: float, x: float, y: float, z: float) -> np.ndarray:
    return np.array([s, x, y, z], dtype=np.float64)


def multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """The notes' product: scalar ``s1 s2 - v1.v2``, vector ``s1 v2 + s2 v1 + v1 x v2``."""
    s1, v1 = q1[0], q1[1:]
    s2, v2 = q2[0], q2[1:]
    out = np.empty(4)
    out[0] = s1 * s2 - v1 @ v2
    out[1:] = s1 * v2 + s2 * v1 + np.cross(v1, v2)
    return out


def conjugate(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def inverse(q: np.ndarray) -> np.ndarray:
    """``q^-1 = (s, -v) / (s^2 + v.v)`` (the notes' formula; the conjugate for unit q)."""
    return conjugate(q) / (q @ q)


def normalize(q: np.ndarray) -> np.ndarray:
    length = np.sqrt(q @ q)
    if not length > 0.0:
        raise ValueError("a zero quaternion has no orientation")
    return q / length


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v' = q^-1 [0, v] q``: the vector part of the notes' sandwich product."""
    return multiply(multiply(inverse(q), np.concatenate([[0.0], v])), q)[1:]


def from_axis_angle(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` radians counter-clockwise about ``axis`` (looking down it)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    return np.concatenate([[np.cos(angle / 2)], -np.sin(angle / 2) * a])


def to_matrix(q: np.ndarray) -> np.ndarray:
    """The 3 x 3 matrix R with ``R v = rotate(q, v)`` (columns are the rotated unit axes)."""
    return np.column_stack([rotate(q, e) for e in np.eye(3)])


def from_matrix(m: np.ndarray) -> np.ndarray:
    """The unit quaternion (scalar >= 0) of a 3 x 3 rotation matrix (Shoemake's method).

    The branch on the largest diagonal term keeps the square root away from zero.
    """
    m = np.asarray(m, dtype=np.float64)[:3, :3]
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0.0:
        r = np.sqrt(1.0 + trace)
        s, f = 0.5 * r, 0.5 / r
        # the standard form q v q^-1 gives (s, x, y, z); ours is its conjugate
        q = np.array([s, (m[2, 1] - m[1, 2]) * f, (m[0, 2] - m[2, 0]) * f, (m[1, 0] - m[0, 1]) * f])
    else:
        i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
        j, k = (i + 1) % 3, (i + 2) % 3
        r = np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        f = 0.5 / r
        q = np.empty(4)
        q[0] = (m[k, j] - m[j, k]) * f
        q[1 + i] = 0.5 * r
        q[1 + j] = (m[j, i] + m[i, j]) * f
        q[1 + k] = (m[k, i] + m[i, k]) * f
    q = conjugate(normalize(q))
    return q if q[0] >= 0.0 else -q


def from_euler_degrees(rx: float, ry: float, rz: float) -> np.ndarray:
    """The scene files' rotation ``R_z R_y R_x`` (x first) as one quaternion: q_x q_y q_z."""
    qx = from_axis_angle((1, 0, 0), np.radians(rx))
    qy = from_axis_angle((0, 1, 0), np.radians(ry))
    qz = from_axis_angle((0, 0, 1), np.radians(rz))
    return multiply(multiply(qx, qy), qz)


def angle_between(q0: np.ndarray, q1: np.ndarray) -> float:
    """The rotation angle (radians, in [0, pi]) that takes orientation q0 to q1."""
    d = multiply(inverse(q0), q1)          # atan2, not arccos: exact near 0 as well
    return 2.0 * float(np.arctan2(np.sqrt(d[1:] @ d[1:]), abs(d[0])))


def slerp(q0: np.ndarray, q1: np.ndarray, u: float, shortest: bool = True) -> np.ndarray:
    """Spherical linear interpolation: ``sin((1-u)W)/sin W q0 + sin(uW)/sin W q1``, cos W = q0.q1.

    With ``shortest`` the arc goes to whichever of q1 and -q1 (the same rotation) is nearer, so
    the turn is never the long way round. Nearly equal keys fall back to a normalized lerp (the
    two agree to within rounding there, and sin W would lose all digits).
    """
    d = float(q0 @ q1)
    if shortest and d < 0.0:
        q1, d = -q1, -d
    d = min(1.0, max(-1.0, d))
    if d > 1.0 - 1e-12:
        return normalize(q0 + u * (q1 - q0))
    omega = np.arccos(d)
    so = np.sin(omega)
    return (np.sin((1.0 - u) * omega) / so) * q0 + (np.sin(u * omega) / so) * q1


def log(q: np.ndarray) -> np.ndarray:
    """For unit q = (cos a, sin a n): the pure quaternion (0, a n)."""
    v = q[1:]
    sin_a = np.sqrt(v @ v)
    if sin_a < 1e-15:
        return np.zeros(4)
    a = np.arctan2(sin_a, q[0])
    return np.concatenate([[0.0], v * (a / sin_a)])


def exp(p: np.ndarray) -> np.ndarray:
    """For a pure quaternion (0, a n): (cos a, sin a n)."""
    v = p[1:]
    a = np.sqrt(v @ v)
    if a < 1e-15:
        return IDENTITY.copy()
    return np.concatenate([[np.cos(a)], v * (np.sin(a) / a)])


def hemisphere(keys: np.ndarray) -> np.ndarray:
    """Flip keys so that neighbours have q_i . q_{i+1} >= 0 (each step the short way)."""
    out = np.array(keys, dtype=np.float64)
    for i in range(1, len(out)):
        if out[i] @ out[i - 1] < 0.0:
            out[i] = -out[i]
    return out


def squad_controls(keys: np.ndarray) -> np.ndarray:
    """Shoemake's inner points ``s_i = q_i exp(-(log(q_i^-1 q_{i+1}) + log(q_i^-1 q_{i-1})) / 4)``.

    The end keys use themselves as the missing neighbour (the curve starts and ends along the
    first and last arcs).
    """
    n = len(keys)
    s = np.empty_like(keys)
    for i in range(n):
        q = keys[i]
        prev, nxt = keys[max(i - 1, 0)], keys[min(i + 1, n - 1)]
        inv = inverse(q)
        t = (log(multiply(inv, nxt)) + log(multiply(inv, prev))) / -4.0
        s[i] = normalize(multiply(q, exp(t)))
    return s


def squad(q0, q1, s0, s1, u: float) -> np.ndarray:
    """``slerp(slerp(q0, q1, u), slerp(s0, s1, u), 2u(1-u))`` (no shortest-path flips inside:
    the keys were put in one hemisphere first, and flipping here would break continuity)."""
    return slerp(slerp(q0, q1, u, shortest=False), slerp(s0, s1, u, shortest=False),
                 2.0 * u * (1.0 - u), shortest=False)
