"""Dynamic control: a motion-capture take (BVH) played back on a figure of limbs.

The course's "dynamic control (tracking live action)": the motion is not keyed or simulated
but recorded from a performer (reflectors, data gloves) and played back. A :class:`Figure`
is a mover of the :class:`~core.animation.animation.Animation`: the take's skeleton
(:mod:`core.animation.bvh`) placed in the scene by ``G = T(position) · R(rotate) · S(scale)``,
its time mapped from the scene's (``start``, ``speed``, ``loop``), and between two of the
take's frames each joint's local turn in-betweened by a quaternion slerp and its local
translation (offset plus position channels) linearly — the take's frames are samples of one
motion, and in-betweening the Euler angles apart would not be a rotation's shortest path.

The figure is drawn as limbs: a closed prism (4 sides, a box; or ``segments`` sides, a
cylinder) along each bone, from a joint to each child and to each End Site, and a small
sphere at each joint so that a bent knee has no notch. Each limb is carried by the joint at
its start: modelled in the pose at scene time 0 and moved by
``A_j(t) · A_j(0)⁻¹``, ``A_j`` the joint's frame in the scene (its turn and its place).
"""

from __future__ import annotations

import math

import numpy as np

from core.animation.bvh import Motion
from core.scene.model import Material, Mesh

INTERPOLATIONS = ("linear", "step")


# ---------------------------------------------------------------------- quaternions
# Here in the usual convention, ``R v = q v q*`` with q = (w, x, y, z), vectorised over
# joints; core.animation.quaternion keeps the notes' ``q⁻¹ v q`` for single keys.


def matrix_quaternions(m: np.ndarray) -> np.ndarray:
    """``(..., 4)`` unit quaternions of rotation matrices ``(..., 3, 3)`` (Shepperd: the
    largest of w², x², y², z² is the square root taken)."""
    m = np.asarray(m, np.float64)
    t = np.stack([1 + m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2],
                  1 + m[..., 0, 0] - m[..., 1, 1] - m[..., 2, 2],
                  1 - m[..., 0, 0] + m[..., 1, 1] - m[..., 2, 2],
                  1 - m[..., 0, 0] - m[..., 1, 1] + m[..., 2, 2]], axis=-1)
    k = np.argmax(t, axis=-1)
    s = 0.5 / np.sqrt(np.take_along_axis(t, k[..., None], -1)[..., 0])
    d21, d02 = m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0]
    d10 = m[..., 1, 0] - m[..., 0, 1]
    s01, s02 = m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0]
    s12 = m[..., 1, 2] + m[..., 2, 1]
    big = np.take_along_axis(t, k[..., None], -1)[..., 0] * s
    candidates = np.stack([
        np.stack([big, d21 * s, d02 * s, d10 * s], -1),
        np.stack([d21 * s, big, s01 * s, s02 * s], -1),
        np.stack([d02 * s, s01 * s, big, s12 * s], -1),
        np.stack([d10 * s, s02 * s, s12 * s, big], -1)], -2)
    q = np.take_along_axis(candidates, k[..., None, None], -2)[..., 0, :]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    w, x, y, z = np.moveaxis(np.asarray(q, np.float64), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def slerp_many(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """Row by row, the shortest great arc from q0 to q1 at u in [0, 1]."""
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0.0, -q1, q1)
    dot = np.abs(dot)
    angle = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(angle)
    near = sin < 1e-9                                    # the same turn: lerp is exact enough
    safe = np.where(near, 1.0, sin)
    a = np.where(near, 1.0 - u, np.sin((1.0 - u) * angle) / safe)
    b = np.where(near, u, np.sin(u * angle) / safe)
    q = a * q0 + b * q1
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


# ---------------------------------------------------------------------- the figure


class Figure:
    """A take placed in the scene and played on its limbs (a mover: ``matrices_at``).

    ``placement`` is G (4 x 4, a uniform scale); ``carried[j]`` the mesh indices joint j
    moves (filled in by :func:`limbs`). The clip's time is ``(t − start) · speed``, wrapped
    into ``[0, length)`` when ``loop`` (frame F−1 then meets frame 0: a take made to loop
    repeats its first pose as its last frame), else held at its ends; before ``start``,
    the first frame."""

    def __init__(self, motion: Motion, placement: np.ndarray, start: float = 0.0,
                 speed: float = 1.0, loop: bool = True, interpolation: str = "linear",
                 name: str = "figure"):
        self.motion, self.name = motion, name
        self.placement = np.asarray(placement, np.float64)
        self.scale = float(np.cbrt(np.linalg.det(self.placement[:3, :3])))
        self.turn = self.placement[:3, :3] / self.scale
        self.start, self.speed, self.loop = float(start), float(speed), bool(loop)
        self.interpolation = interpolation
        translations, rotations = motion.local(motion.frames)
        self.translations = translations                          # (F, J, 3)
        self.quaternions = matrix_quaternions(rotations)          # (F, J, 4)
        self.carried: list[list[int]] = [[] for _ in motion.names]
        self._rest = None

    def clip_time(self, t: float) -> float:
        """Seconds into the take at scene time t."""
        u = (t - self.start) * self.speed
        length = self.motion.length
        if length <= 0.0 or u <= 0.0:               # before its start: the first frame
            return 0.0
        if self.loop:
            return u % length
        return min(max(u, 0.0), length)

    def local_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Every joint's translation (J, 3) and turn (J, 3, 3) from its parent, at scene t."""
        u = self.clip_time(t) / self.motion.frame_time
        last = self.motion.frame_count - 1
        k = min(int(math.floor(u)), last)
        f = u - k
        if self.interpolation == "step" or k == last or f <= 0.0:
            return self.translations[k], quaternion_matrices(self.quaternions[k])
        tr = (1.0 - f) * self.translations[k] + f * self.translations[k + 1]
        q = slerp_many(self.quaternions[k], self.quaternions[k + 1], f)
        return tr, quaternion_matrices(q)

    def pose_at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """In the scene at t: joint positions (J, 3), joint frames (J, 3, 3) and End Sites
        (E, 3)."""
        local_t, local_r = self.local_at(t)
        m = self.motion
        points, frames = np.empty_like(local_t), np.empty_like(local_r)
        for j, p in enumerate(m.parent):
            if p < 0:
                points[j], frames[j] = local_t[j], local_r[j]
            else:
                points[j] = points[p] + frames[p] @ local_t[j]
                frames[j] = frames[p] @ local_r[j]
        ends = np.array([points[j] + frames[j] @ o for j, o in m.ends]).reshape(-1, 3)
        g = self.placement
        return (points @ g[:3, :3].T + g[:3, 3], self.turn @ frames,
                ends @ g[:3, :3].T + g[:3, 3])

    def rest(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pose at scene time 0, in which the limbs are modelled."""
        if self._rest is None:
            self._rest = self.pose_at(0.0)
        return self._rest

    def matrices_at(self, t: float) -> dict[int, np.ndarray]:
        points, frames, _ = self.pose_at(t)
        points0, frames0, _ = self.rest()
        out = {}
        for j, meshes in enumerate(self.carried):
            if not meshes:
                continue
            m = np.eye(4)
            m[:3, :3] = frames[j] @ frames0[j].T
            m[:3, 3] = points[j] - m[:3, :3] @ points0[j]
            for index in meshes:
                out[index] = m
        return out


# ---------------------------------------------------------------------- its limbs


def prism(a, b, radius: float, sides: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed prism of ``sides`` sides about the segment a → b, its corners ``radius``
    from the axis, wound counter-clockwise seen from outside: (positions, triangles)."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    u = (b - a) / np.linalg.norm(b - a)
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    theta = 2.0 * np.pi * (np.arange(sides) + 0.5) / sides
    ring = radius * (np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2)
    positions = np.concatenate([a + ring, b + ring, [a, b]])
    k = np.arange(sides)
    k1 = (k + 1) % sides
    n, ca, cb = sides, 2 * sides, 2 * sides + 1
    triangles = np.concatenate([
        np.column_stack([k, k1, n + k1]), np.column_stack([k, n + k1, n + k]),   # the side
        np.column_stack([np.full(n, cb), n + k, n + k1]),                           # b's cap
        np.column_stack([np.full(n, ca), k1, k])])                                  # a's cap
    return positions, triangles


def limbs(figure: Figure, radius, sides: int, joint_radius, material, first_index: int,
          crease_angle: float) -> list[Mesh]:
    """The figure's meshes, modelled in its pose at t = 0, each noted in ``figure.carried``
    (its index counted from ``first_index``): ``radius(j)``, ``joint_radius(j)`` and
    ``material(j)`` give joint j's limbs' radius, its sphere's (0: none) and their material."""
    from core.scene.generators import icosphere
    from core.scene.normals import with_creases
    m = figure.motion
    points, _, ends = figure.rest()
    out: list[Mesh] = []

    def add(mesh: Mesh, joint: int) -> None:
        figure.carried[joint].append(first_index + len(out))
        out.append(mesh)

    for j, name in enumerate(m.names):
        r = radius(j)
        tips = [points[k] for k, p in enumerate(m.parent) if p == j]
        tips += [ends[e] for e, (owner, _) in enumerate(m.ends) if owner == j]
        for tip in tips:
            if np.linalg.norm(tip - points[j]) <= 1e-9 * (1.0 + np.abs(tip).max()):
                continue                                         # a zero-length bone: none
            positions, triangles = prism(points[j], tip, r, sides)
            mesh = Mesh(positions=positions, triangles=triangles, closed=True,
                        material=material(j), name=f"{figure.name}.{name}")
            add(with_creases(mesh, crease_angle), j)
        rj = joint_radius(j)
        if rj > 0.0:
            ball = icosphere(1, rj)
            add(Mesh(positions=ball.positions + points[j], triangles=ball.triangles,
                     normals=ball.normals, closed=True, material=material(j),
                     name=f"{figure.name}.{name}"), j)
    return out


def subtree_values(motion: Motion, given: dict, default):
    """joint → the value given for it or for its nearest ancestor that has one, else
    ``default`` (a material for the left leg given at its hip)."""
    out = []
    for j, p in enumerate(motion.parent):
        name = motion.names[j]
        out.append(given[name] if name in given else (out[p] if p >= 0 else default))
    return out


def default_material() -> Material:
    return Material(ka=0.3, kd=0.65, ks=0.35, n=30.0, od=(0.85, 0.62, 0.35))
