"""Linkages: chains (and trees) of revolute joints, forward and inverse kinematics.

The constraint-based control of the course's animation lecture. A linkage is a root
position and joints, each turning about an ``axis`` (in its parent's frame) through an
angle θ within ``[min, max]``, with a bone (a vector, at rest) from it to its children; the
file's pose is θ = 0 for every joint, and a mesh a joint carries moves with that joint's
frame: ``x ↦ p_j(θ) + R_j(θ) (x − p_j(0))``.

Forward kinematics: ``R_j = R_parent · Rot(axis_j, θ_j)``, ``p_child = p_j + R_j bone_j``.

Inverse kinematics to a keyed target, for the chain from the root to the effector joint
(the end of its bone), from the keyed angles (or the rest pose) at every frame, so that each
frame is solved by itself (any frame renders alone):

- ``dls`` (the default): damped least squares (Wampler; Nakamura and Hanafusa),
  ``Δθ = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` with ``J_i = w_i × (p_end − p_i)``, the damping
  ``λ = damping · min(|e|, reach)`` shrinking with the error, so that near a reachable target
  it becomes Gauss–Newton (quadratic convergence, 1e-9 reached) while far from one, or at a
  singular, stretched-out pose, it stays a short, stable step toward the nearest point;
  a step that does not bring the end nearer is refused and damped more (Levenberg–Marquardt);
  where none helps (a pose whose Jacobian is blind to the error: the target straight along
  a stretched or folded arm) one CCD sweep turns it off that pose, or confirms the optimum;
- ``ccd``: cyclic coordinate descent (Wang and Chen): from the last joint to the first, each
  turned by the angle that best points the end at the target, about its own axis.

Each update is clamped to the joint's limits, so the limits hold at every iteration.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import call_compiled, compiled_at, njit
from core.vectors import mat_vec3

DLS, CCD = 0, 1
SOLVERS = ("dls", "ccd")
MAX_ITERATIONS = 100         # DLS steps (Levenberg–Marquardt converges in tens)
CCD_SWEEPS = 500
POLISH_SWEEPS = 50
MIN_DAMPING = 1e-6         # λ at least this fraction of the reach
NUDGE = 1e-3              # radians: off a saddle of the error, once
TOLERANCE = 1e-12          # distance to the target (a fraction of the reach) that stops it


@njit(cache=True)
def _axis_rotation(a, angle):
    """The matrix turning counter-clockwise by ``angle`` about the unit vector a (Rodrigues)."""
    c, s = math.cos(angle), math.sin(angle)
    x, y, z = a[0], a[1], a[2]
    r = np.empty((3, 3))
    r[0, 0] = c + x * x * (1 - c); r[0, 1] = x * y * (1 - c) - z * s; r[0, 2] = x * z * (1 - c) + y * s
    r[1, 0] = y * x * (1 - c) + z * s; r[1, 1] = c + y * y * (1 - c); r[1, 2] = y * z * (1 - c) - x * s
    r[2, 0] = z * x * (1 - c) - y * s; r[2, 1] = z * y * (1 - c) + x * s; r[2, 2] = c + z * z * (1 - c)
    return r


@njit(cache=True)
def _mat_mat(a, b):
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]
    return out


@njit(cache=True)
def chain_pose(base, axes, bones, theta, points, world_axes):
    """Forward kinematics of a chain: ``points[i]`` joint i's position (``points[n]`` the
    end), ``world_axes[i]`` its axis in the world; returns the last joint's rotation.
    (The 3 x 3 products are written out: BLAS calls on such small matrices cost more than
    the arithmetic.)"""
    r = np.eye(3)
    points[0] = base
    for i in range(len(theta)):
        world_axes[i] = mat_vec3(r, axes[i])
        r = _mat_mat(r, _axis_rotation(axes[i], theta[i]))
        points[i + 1] = points[i] + mat_vec3(r, bones[i])
    return r


@njit(cache=True)
def _solve3(a, e):
    """a⁻¹ e for a symmetric positive definite 3 x 3 (Cramer's rule)."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    inv = np.empty((3, 3))
    inv[0, 0], inv[1, 0], inv[2, 0] = c00, c01, c02
    inv[0, 1] = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    inv[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    inv[2, 1] = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    inv[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    inv[1, 2] = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    inv[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    return mat_vec3(inv, e) / det


@njit(cache=True)
def _dls_step(points, world_axes, target, lam):
    n = len(world_axes)
    e = target - points[n]
    jac = np.empty((3, n))
    for i in range(n):
        jac[:, i] = np.cross(world_axes[i], points[n] - points[i])
    a = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for k in range(n):
                a[i, j] += jac[i, k] * jac[j, k]
        a[i, i] += lam * lam
    y = _solve3(a, e)
    step = np.empty(n)
    for k in range(n):
        step[k] = jac[0, k] * y[0] + jac[1, k] * y[1] + jac[2, k] * y[2]
    return step


@njit(cache=True)
def _ccd_sweep(base, axes, bones, theta, lo, hi, target, points, world_axes):
    """One sweep of cyclic coordinate descent, last joint first."""
    n = len(theta)
    for i in range(n - 1, -1, -1):
        chain_pose(base, axes, bones, theta, points, world_axes)
        w = world_axes[i]
        to_end = points[n] - points[i]
        to_goal = target - points[i]
        to_end = to_end - np.dot(to_end, w) * w            # both seen down the axis
        to_goal = to_goal - np.dot(to_goal, w) * w
        if np.dot(to_end, to_end) == 0.0 or np.dot(to_goal, to_goal) == 0.0:
            continue
        turn = math.atan2(np.dot(w, np.cross(to_end, to_goal)), np.dot(to_end, to_goal))
        theta[i] = min(max(theta[i] + turn, lo[i]), hi[i])


@njit(cache=True)
def _error(base, axes, bones, theta, target, points, world_axes):
    chain_pose(base, axes, bones, theta, points, world_axes)
    d = target - points[len(theta)]
    return math.sqrt(np.dot(d, d))


def solve_chain(base, axes, bones, theta0, lo, hi, target, solver, damping, iterations):
    """The chain's angles that bring its end to ``target`` (or as near as the limits and
    the reach allow), from ``theta0``; every iterate within ``[lo, hi]``. A descent that
    ends short of the target may be held at a limit it started on (the elbow, straight at
    its stop, pushed the wrong way): a second descent from the middle of every joint's
    range is made then, and the nearer of the two kept."""
    given = _given(base, axes, bones, theta0, lo, hi, target, solver, damping, iterations)
    return _solve_chain(*given, _descend_at(given))


def _given(base, axes, bones, theta0, lo, hi, target, solver, damping, iterations) -> tuple:
    """The solver's arguments as its kernels take them (every array C-ordered float64, so
    that a descent from ``theta0`` and one from the middle of the range are one kernel)."""
    arrays = (np.ascontiguousarray(a, dtype=np.float64)
              for a in (base, axes, bones, theta0, lo, hi, target))
    return (*arrays, int(solver), float(damping), int(iterations))


def _descend_at(given) -> tuple[int, int]:
    """:func:`_descend`'s machine code for the solver's arguments ``given``."""
    return compiled_at(_descend, given)


@njit(cache=True)
def _solve_chain(base, axes, bones, theta0, lo, hi, target, solver, damping, iterations, at):
    """:func:`solve_chain`, its descents called by their address ``at`` (core.jit.
    call_compiled): ``_descend`` is optimised once, not again in every kernel above it."""
    theta = call_compiled(at, _descend, base, axes, bones, theta0, lo, hi, target, solver,
                          damping, iterations)
    n = len(theta0)
    points, world_axes = np.empty((n + 1, 3)), np.empty((n, 3))
    reach = 0.0
    for i in range(n):
        reach += math.sqrt(np.dot(bones[i], bones[i]))
    error = _error(base, axes, bones, theta, target, points, world_axes)
    if error <= 1e3 * TOLERANCE * reach:
        return theta
    middle = 0.5 * (np.maximum(lo, -math.pi) + np.minimum(hi, math.pi))
    other = call_compiled(at, _descend, base, axes, bones, middle, lo, hi, target, solver,
                          damping, iterations)
    if _error(base, axes, bones, other, target, points, world_axes) < error:
        return other
    return theta


@njit(cache=True)
def _descend(base, axes, bones, theta0, lo, hi, target, solver, damping, iterations):
    """One descent: the chain's angles that bring its end to ``target`` (or as near as the limits and
    the reach allow), from ``theta0``; every iterate within ``[lo, hi]``.

    DLS adapts its damping as Levenberg and Marquardt do: a step that does not bring the
    end nearer is refused and tried again damped four times as much; one that does is kept
    and the damping cut by three. Where no damping helps (a stationary pose), one CCD sweep
    is tried; where that does not help either, the joints are nudged once (a saddle) and
    the descent goes on; at a stationary pose again, that pose is the nearest one. CCD sweeps
    finish (while they bring the end nearer)."""
    n = len(theta0)
    theta = np.minimum(np.maximum(theta0.copy(), lo), hi)
    points = np.empty((n + 1, 3))
    world_axes = np.empty((n, 3))
    reach = 0.0
    for i in range(n):
        reach += math.sqrt(np.dot(bones[i], bones[i]))
    error = _error(base, axes, bones, theta, target, points, world_axes)
    mu = damping
    trial = theta.copy()
    nudged = False
    for _ in range(iterations):
        if error <= TOLERANCE * reach:
            break
        if solver == 1:
            _ccd_sweep(base, axes, bones, theta, lo, hi, target, points, world_axes)
            error = _error(base, axes, bones, theta, target, points, world_axes)
            continue
        # (a floor on λ: a planar arm's J Jᵀ has a zero row, singular undamped)
        step = _dls_step(points, world_axes, target,
                         max(mu * min(error, reach), MIN_DAMPING * reach))
        for i in range(n):
            trial[i] = min(max(theta[i] + step[i], lo[i]), hi[i])
        tried = _error(base, axes, bones, trial, target, points, world_axes)
        if tried < error:
            theta[:] = trial
            error, mu = tried, max(mu / 3.0, 1e-9)
        elif mu < 1e6:
            mu *= 4.0
        else:
            trial[:] = theta
            _ccd_sweep(base, axes, bones, trial, lo, hi, target, points, world_axes)
            tried = _error(base, axes, bones, trial, target, points, world_axes)
            if not tried < error:
                if nudged:
                    break
                # a saddle on the axis of symmetry (the target straight along a folded
                # arm): nudged off it once, every joint by NUDGE, the descent goes on
                nudged = True
                for i in range(n):
                    trial[i] = min(max(theta[i] + NUDGE * (1 - 2 * (i % 2)), lo[i]), hi[i])
                tried = _error(base, axes, bones, trial, target, points, world_axes)
            theta[:] = trial
            error, mu = tried, damping
        chain_pose(base, axes, bones, theta, points, world_axes)
    if solver == 0:
        # DLS's last approach to an out-of-reach target is linear (the Jacobian vanishes as
        # the arm straightens out); CCD sweeps finish it while they bring the end nearer
        # (a sweep that leaves the distance as it was, to its rounding, is kept too: beside
        # the target's direction the distance changes only to second order)
        for _ in range(POLISH_SWEEPS):
            trial[:] = theta
            _ccd_sweep(base, axes, bones, trial, lo, hi, target, points, world_axes)
            tried = _error(base, axes, bones, trial, target, points, world_axes)
            if not tried <= error + 1e-15 * reach or np.max(np.abs(trial - theta)) < 1e-15:
                break
            theta[:] = trial
            error = tried
    return theta


def solve_many(base, axes, bones, theta0, lo, hi, targets, solver, damping, iterations):
    """:func:`solve_chain` for each row of ``targets`` (a batch: tests, tables of poses)."""
    targets = np.ascontiguousarray(targets, dtype=np.float64).reshape(-1, 3)
    given = _given(base, axes, bones, theta0, lo, hi, np.zeros(3), solver, damping, iterations)
    descend = _descend_at(given)
    chain = compiled_at(_solve_chain, (*given, descend))
    base, axes, bones, theta0, lo, hi, _, solver, damping, iterations = given
    return _solve_many(base, axes, bones, theta0, lo, hi, targets, solver, damping, iterations,
                       chain, descend)


@njit(cache=True)
def _solve_many(base, axes, bones, theta0, lo, hi, targets, solver, damping, iterations, chain,
                descend):
    out = np.empty((len(targets), len(theta0)))
    for k in range(len(targets)):
        out[k] = call_compiled(chain, _solve_chain, base, axes, bones, theta0, lo, hi,
                               targets[k], solver, damping, iterations, descend)
    return out


# ---------------------------------------------------------------------- the linkage


class Linkage:
    """A tree of joints as the scene file gives it, and its pose at any time.

    ``parent[j]`` is joint j's parent (-1: a root, at ``base``), parents before children;
    ``axes`` and ``bones`` are in the rest frame; ``carried[j]`` the mesh indices joint j
    moves. ``angles(t)`` (radians, every joint) and ``target(t)`` are keyed tracks or None.
    """

    masses = None       # inverse dynamics' LinkMasses (core.animation.inverse_dynamics)
    joint_names = ()    # the file's names, parents first
    key_times = ()      # where the keyed motion may turn: finite differences stay on one side
    key_places = ()     # (time, "file:line: linkage[i].key[k]") of each key, for messages

    def __init__(self, name, base, parent, axes, bones, lo, hi, carried, effector,
                 solver=DLS, damping=0.5, angles=None, target=None):
        self.name = name
        self.base = np.asarray(base, np.float64)
        self.parent = np.asarray(parent, np.int64)
        self.axes = np.asarray(axes, np.float64).reshape(-1, 3)
        self.bones = np.asarray(bones, np.float64).reshape(-1, 3)
        self.lo, self.hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        self.carried, self.effector = carried, effector
        self.solver, self.damping = solver, damping
        self.angles, self.target = angles, target
        chain, j = [], effector
        while j >= 0:
            chain.append(j)
            j = int(self.parent[j])
        self.chain = np.array(chain[::-1], np.int64)           # root → effector
        self.rest_points = self.pose(np.zeros(len(self.parent)))[0]

    def pose(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: ``(points (J, 3), rotations (J, 3, 3))``, joint j at
        ``points[j]`` turned by ``rotations[j]`` (its bone is ``rotations[j] @ bones[j]``)."""
        n = len(self.parent)
        points, rotations = np.empty((n, 3)), np.empty((n, 3, 3))
        for j in range(n):
            p = self.parent[j]
            if p < 0:
                points[j], frame = self.base, np.eye(3)
            else:
                points[j], frame = points[p] + rotations[p] @ self.bones[p], rotations[p]
            rotations[j] = frame @ _axis_rotation(self.axes[j], float(theta[j]))
        return points, rotations

    def end(self, theta: np.ndarray) -> np.ndarray:
        """Where the effector's bone ends."""
        points, rotations = self.pose(theta)
        return points[self.effector] + rotations[self.effector] @ self.bones[self.effector]

    def angles_at(self, t: float) -> np.ndarray:
        """Every joint's angle at t: the keyed angles, the chain then solved for the target."""
        theta = np.zeros(len(self.parent)) if self.angles is None else self.angles(t)
        theta = np.clip(theta, self.lo, self.hi)
        if self.target is not None:
            c = self.chain
            theta[c] = solve_chain(self.base, self.axes[c], self.bones[c], theta[c],
                                   self.lo[c], self.hi[c], np.asarray(self.target(t), np.float64),
                                   self.solver, self.damping,
                                   CCD_SWEEPS if self.solver == CCD else MAX_ITERATIONS)
        return theta

    def matrices_at(self, t: float) -> dict[int, np.ndarray]:
        """mesh index → the 4 x 4 that takes it from the rest pose to its pose at t."""
        points, rotations = self.pose(self.angles_at(t))
        out = {}
        for j, meshes in enumerate(self.carried):
            m = np.eye(4)
            m[:3, :3] = rotations[j]
            m[:3, 3] = points[j] - rotations[j] @ self.rest_points[j]
            for index in meshes:
                out[index] = m
        return out
