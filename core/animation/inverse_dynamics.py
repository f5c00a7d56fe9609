"""Inverse dynamics of a linkage: the joint torques that produce a keyed motion.

The course's animation lecture: "Inverse Dynamics: what force(s) must have been applied to
reach final state given initial state?" For a tree of revolute joints (core.animation.linkage)
whose links have masses, this is the recursive Newton–Euler method (Luh, Walker and Paul,
1980), in the world frame:

- outward, parents first: each link's angular velocity ``ω_j = ω_p + z_j θ'_j`` and
  acceleration ``α_j = α_p + z_j θ''_j + ω_p × z_j θ'_j``, the joint's linear acceleration
  carried along the parent's bone, gravity entering as the base accelerating at ``−g``;
- each body's force ``F = m a_c`` and moment ``N = I α + ω × I ω`` about its centre of mass;
- inward, children first: the force and moment each joint passes to its link, and the
  torque its motor gives, ``τ_j = n_j · z_j`` (counter-clockwise about the joint's axis).

θ' and θ'' of a keyed motion are the motion's own derivatives, taken by finite differences
of :meth:`Linkage.angles_at` (keyed angles, or inverse kinematics to a keyed target), with a
one-sided stencil at a key so that the two sides of a key are never mixed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

STEP = 1e-3            # seconds: the finite differences' step (θ'' to ~1e-7 of θ'''' and rounding)
GRAVITY = (0.0, -9.8, 0.0)


@dataclass
class LinkMasses:
    """What moves with each joint: ``mass`` (J,) kg, ``center`` (J, 3) the centre of mass
    from the joint at rest, ``inertia`` (J, 3, 3) about the centre of mass at rest, and a
    point ``load`` (kg) held at the end of the effector's bone."""

    mass: np.ndarray
    center: np.ndarray
    inertia: np.ndarray
    load: float = 0.0
    gravity: np.ndarray = field(default_factory=lambda: np.array(GRAVITY))


def rod_inertia(mass: float, bone: np.ndarray) -> np.ndarray:
    """A uniform thin rod along ``bone`` about its middle: ``m L²/12`` across it, 0 along it."""
    length2 = float(bone @ bone)
    u = bone / np.sqrt(length2)
    return mass * length2 / 12.0 * (np.eye(3) - np.outer(u, u))


def _bodies(linkage, masses: LinkMasses, rotations):
    """Per joint, the bodies it carries: (mass, offset from the joint now, world inertia)."""
    out = []
    for j in range(len(linkage.parent)):
        r = rotations[j]
        bodies = [(masses.mass[j], r @ masses.center[j], r @ masses.inertia[j] @ r.T)]
        if j == linkage.effector and masses.load > 0.0:
            bodies.append((masses.load, r @ linkage.bones[j], np.zeros((3, 3))))
        out.append(bodies)
    return out


def joint_torques(linkage, masses: LinkMasses, theta, dtheta, ddtheta) -> np.ndarray:
    """τ (J,) in N·m: the torque of each joint's motor that gives the linkage the
    accelerations ``ddtheta`` at the angles ``theta`` and rates ``dtheta`` (radians, /s, /s²)."""
    points, rotations = linkage.pose(np.asarray(theta, np.float64))
    n = len(linkage.parent)
    z = np.empty((n, 3))
    omega, alpha, acc = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    for j in range(n):                        # outward: parents come first
        p = int(linkage.parent[j])
        z[j] = rotations[j] @ linkage.axes[j]     # Rot(axis, θ) keeps its own axis
        if p < 0:
            w0, al0, acc[j] = np.zeros(3), np.zeros(3), -np.asarray(masses.gravity)
        else:
            w0, al0, r = omega[p], alpha[p], points[j] - points[p]
            acc[j] = acc[p] + np.cross(al0, r) + np.cross(w0, np.cross(w0, r))
        omega[j] = w0 + z[j] * dtheta[j]
        alpha[j] = al0 + z[j] * ddtheta[j] + np.cross(w0, z[j]) * dtheta[j]
    force, moment = np.zeros((n, 3)), np.zeros((n, 3))
    for j, bodies in enumerate(_bodies(linkage, masses, rotations)):
        for m, c, inertia in bodies:
            f = m * (acc[j] + np.cross(alpha[j], c) + np.cross(omega[j], np.cross(omega[j], c)))
            force[j] += f
            moment[j] += inertia @ alpha[j] + np.cross(omega[j], inertia @ omega[j]) + np.cross(c, f)
    tau = np.empty(n)
    for j in range(n - 1, -1, -1):           # inward: children pass their load to the parent
        tau[j] = moment[j] @ z[j]
        p = int(linkage.parent[j])
        if p >= 0:
            force[p] += force[j]
            moment[p] += moment[j] + np.cross(points[j] - points[p], force[j])
    return tau


def motion_at(linkage, t: float, breaks=(), step: float = STEP):
    """(θ, θ', θ'') at t of the linkage's keyed motion. Near a key time in ``breaks`` (sorted)
    the stencil lies on one side of it (after it; before the last one, where the motion ends),
    second order either way."""
    h = step
    f = linkage.angles_at
    near = [b for b in breaks if abs(b - t) < 3 * h]
    if not near:
        a, b, c = f(t - h), f(t), f(t + h)
        return b, (c - a) / (2 * h), (a - 2 * b + c) / (h * h)
    # after the key; before it if t lies before it, or if it is the last key (the motion's end)
    s = 1.0 if near[0] <= t and near[0] != breaks[-1] else -1.0
    v = [f(t + s * k * h) for k in range(4)]
    d1 = (-3 * v[0] + 4 * v[1] - v[2]) / (2 * s * h)
    d2 = (2 * v[0] - 5 * v[1] + 4 * v[2] - v[3]) / (h * h)
    return f(t), d1, d2


def torques_at(linkage, masses: LinkMasses, t: float, breaks=(), step: float = STEP) -> tuple:
    """(θ, θ', θ'', τ) of the keyed motion at time t."""
    theta, d1, d2 = motion_at(linkage, t, breaks, step)
    return theta, d1, d2, joint_torques(linkage, masses, theta, d1, d2)


def corner(track, t: float, gap: float):
    """The jump of a keyed track's rate at its key time t: (rate before, rate after), from
    one-sided differences (second order) a small fraction of the key gap long."""
    h = gap * 1e-4
    before = (3 * track(t) - 4 * track(t - h) + track(t - 2 * h)) / (2 * h)
    after = (-3 * track(t) + 4 * track(t + h) - track(t + 2 * h)) / (2 * h)
    return np.asarray(before, np.float64), np.asarray(after, np.float64)


JUMP_SPLITS = 40       # halvings of a frame: a change left over ~1e-13 s of it is a jump


def find_jump(angles_at, t0: float, t1: float, theta0, theta1, least: float = 0.05):
    """Where the angles jump between t0 and t1 (inverse kinematics changing its solution's
    branch), as (t, before, after), or None. Bisection keeps the half that changes more; a
    change of at least half the whole's left in a sliver of time is no motion at all."""
    theta0, theta1 = np.asarray(theta0), np.asarray(theta1)
    whole = float(np.max(np.abs(theta1 - theta0)))
    if whole < least:
        return None
    for _ in range(JUMP_SPLITS):
        tm = 0.5 * (t0 + t1)
        middle = np.asarray(angles_at(tm))
        if np.max(np.abs(middle - theta0)) >= np.max(np.abs(theta1 - middle)):
            t1, theta1 = tm, middle
        else:
            t0, theta0 = tm, middle
    if float(np.max(np.abs(theta1 - theta0))) < 0.5 * whole:
        return None
    return 0.5 * (t0 + t1), theta0, theta1

