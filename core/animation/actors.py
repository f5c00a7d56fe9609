"""Actors: objects with a small behaviour of their own, run at a fixed simulation step.

The procedural control of the course's animation lecture (after particles): each actor is
a point with a velocity, steered by the sum of its behaviours' accelerations, integrated by
semi-implicit Euler (``v += a dt``, speed clamped to ``max_speed``, then ``x += v dt``) at a
fixed step of STEP seconds; its mesh is carried at the point, its forward axis (+x at rest)
turned along the velocity with +y kept up (the heading).

A behaviour is a registered Python function ``behaviour(t, x, v, params) -> a``: the time,
the positions and velocities of every actor of the group (N x 3 arrays) and the table's
parameters, returning N x 3 accelerations. :func:`register_behaviour` adds one (with the
parameter names and defaults it reads); the built-ins:

- ``flock``: Reynolds' boids (1987): separation from neighbours nearer than ``separation``,
  alignment with and cohesion toward the neighbours within ``radius``, each weighted, and a
  pull toward ``center`` that keeps the flock in view;
- ``avoid``: planes to keep away from: within ``distance`` of a plane the actor is pushed
  along its normal, the harder the nearer (``strength / depth``-like, capped);
- ``follow``: a path (the points of a closed Catmull-Rom loop) run once every ``period``
  seconds: the path's acceleration, a spring ``gain`` toward its point at t and a damper
  matching its velocity.

The groups are deterministic (the start comes from the animation's seed and the group's
index; no random number is drawn while stepping), so they are checkpointed like the
particles and rigid bodies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from core.animation.rewind import Rewind
from core.work import advance

STEP = 1.0 / 120.0
MAX_ACTORS = 2000
# steps x N² (the neighbour tests) to the last frame, measured at ~100 ns a test here (400
# actors), and the steps alone (~180 µs each with few actors): about a minute at most each
MAX_ACTOR_WORK = 500_000_000
MAX_ACTOR_STEPS = 300_000


@dataclass(frozen=True)
class Behaviour:
    run: Callable
    params: dict                       # name → default (a number, a 3-vector, or a list)


_BEHAVIOURS: dict[str, Behaviour] = {}


def register_behaviour(name: str, run: Callable, params: dict) -> None:
    """``run(t, x, v, params) -> accelerations`` under ``name``; ``params``: the table keys
    it reads and their defaults (registered again, it replaces the earlier one)."""
    _BEHAVIOURS[name] = Behaviour(run, dict(params))


def behaviours() -> dict[str, Behaviour]:
    return dict(_BEHAVIOURS)


# ---------------------------------------------------------------------- the built-ins


def flock(t, x, v, p) -> np.ndarray:
    """Separation, alignment and cohesion over the neighbours within ``radius``."""
    d = x[None, :, :] - x[:, None, :]                          # d[i, j] = x_j - x_i
    dist = np.linalg.norm(d, axis=2)
    np.fill_diagonal(dist, np.inf)
    near = dist < p["radius"]
    count = np.maximum(near.sum(axis=1, keepdims=True), 1)
    cohesion = (np.where(near[..., None], d, 0.0).sum(axis=1)) / count
    alignment = (np.where(near[..., None], v[None, :, :], 0.0).sum(axis=1)) / count - v
    alignment[near.sum(axis=1) == 0] = 0.0
    close = dist < p["separation"]
    push = np.where(close[..., None], -d / np.maximum(dist, 1e-9)[..., None] ** 2, 0.0).sum(axis=1)
    home = np.asarray(p["center"], np.float64) - x
    return (p["cohesion"] * cohesion + p["alignment"] * alignment
            + p["separation_weight"] * push + p["centering"] * home)


def avoid(t, x, v, p) -> np.ndarray:
    """Pushed off each plane within ``distance`` of it: strength · (1 − depth/distance)²
    along the normal, growing to ``strength`` at the plane."""
    a = np.zeros_like(x)
    for plane in p["planes"]:
        point, normal = np.asarray(plane[0], np.float64), np.asarray(plane[1], np.float64)
        height = (x - point) @ normal
        inside = np.clip(1.0 - height / p["distance"], 0.0, 1.0)
        a += p["strength"] * (inside ** 2)[:, None] * normal
    return a


def follow(t, x, v, p) -> np.ndarray:
    """The path's own acceleration, plus a spring toward its point at t and a damper
    matching its velocity (critically damped: the error dies as e^(−gain·t)); actor k of
    the group runs k / N of a period behind the first."""
    n = len(x)
    phase = (t / p["period"] + np.arange(n) / max(n, 1)) % 1.0
    h = 1e-4
    at = lambda shift: np.array([loop_point(p["path"], (u + shift) % 1.0) for u in phase])
    here, ahead, behind = at(0.0), at(h), at(-h)
    speed = (ahead - behind) / (2 * h * p["period"])
    accel = (ahead - 2 * here + behind) / (h * p["period"]) ** 2
    k = p["gain"]
    return accel + k * k * (here - x) + 2.0 * k * (speed - v)


def loop_point(points, u: float) -> np.ndarray:
    """The closed uniform Catmull-Rom loop through ``points`` at u in [0, 1)."""
    pts = np.asarray(points, np.float64)
    n = len(pts)
    s = u * n
    i = int(math.floor(s)) % n
    f = s - math.floor(s)
    p0, p1, p2, p3 = pts[(i - 1) % n], pts[i], pts[(i + 1) % n], pts[(i + 2) % n]
    return 0.5 * ((2 * p1) + (-p0 + p2) * f + (2 * p0 - 5 * p1 + 4 * p2 - p3) * f * f
                  + (-p0 + 3 * p1 - 3 * p2 + p3) * f ** 3)


register_behaviour("flock", flock, {"radius": 1.5, "separation": 0.4, "cohesion": 1.0,
                                    "alignment": 1.5, "separation_weight": 0.6,
                                    "centering": 0.4, "center": [0.0, 0.0, 0.0]})
register_behaviour("avoid", avoid, {"planes": [], "distance": 1.0, "strength": 30.0})
register_behaviour("follow", follow, {"path": [], "period": 4.0, "gain": 4.0})


# ---------------------------------------------------------------------- a group


@dataclass
class GroupState:
    step_index: int
    x: np.ndarray
    v: np.ndarray


@dataclass
class Group:
    """The actors of one ``[[actor]]`` table: ``meshes[k]`` the mesh indices actor k carries
    (modelled at ``pivot`` facing +x)."""

    meshes: list
    pivot: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    steps: list                                   # (Behaviour, params)
    max_speed: float = 3.0
    dt: float = STEP
    state: GroupState = field(init=False)

    def __post_init__(self) -> None:
        self.rewind = Rewind()
        self.reset()

    def reset(self) -> None:
        self.state = GroupState(0, self.x0.copy(), self.v0.copy())

    def step(self) -> None:
        s = self.state
        t = s.step_index * self.dt
        a = np.zeros_like(s.x)
        for behaviour, params in self.steps:
            a += behaviour.run(t, s.x, s.v, params)
        s.v += a * self.dt
        speed = np.linalg.norm(s.v, axis=1, keepdims=True)
        s.v *= np.minimum(1.0, self.max_speed / np.maximum(speed, 1e-300))
        s.x += s.v * self.dt
        s.step_index += 1

    def state_at(self, t: float) -> "Group":
        target = int(math.floor(max(t, 0.0) / self.dt + 1e-9))
        if target < self.state.step_index:
            saved = self.rewind.nearest(target)        # the nearest snapshot, else from 0
            self.restore(saved) if saved is not None else self.reset()
        if self.state.step_index < target:             # in chunks, reported (core.work)
            advance("simulating the actors", self.state.step_index, target, self.step_on)
        return self

    def step_on(self, n: int) -> None:
        """n steps on, snapshots noted on the way."""
        for _ in range(n):
            self.rewind.note(self.state.step_index, self.snapshot)
            self.step()

    def matrices_at(self, t: float) -> dict[int, np.ndarray]:
        self.state_at(t)
        out = {}
        for k, meshes in enumerate(self.meshes):
            m = np.eye(4)
            m[:3, :3] = heading(self.state.v[k])
            m[:3, 3] = self.state.x[k] - m[:3, :3] @ self.pivot
            for index in meshes:
                out[index] = m
        return out

    def snapshot(self) -> GroupState:
        s = self.state
        return GroupState(s.step_index, s.x.copy(), s.v.copy())

    def restore(self, state: GroupState) -> None:
        self.state = GroupState(state.step_index, state.x.copy(), state.v.copy())

    def copy(self) -> "Group":
        other = Group(self.meshes, self.pivot, self.x0, self.v0, self.steps, self.max_speed,
                      self.dt)
        other.restore(self.snapshot())
        return other


def heading(v: np.ndarray) -> np.ndarray:
    """The rotation taking +x to v's direction with +y kept as near up as it can be."""
    n = np.linalg.norm(v)
    if n == 0.0:
        return np.eye(3)
    f = v / n
    side = np.cross(f, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 1e-9:                # straight up or down: any side will do
        side = np.cross(f, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    up = np.cross(side, f)
    return np.column_stack([f, up, side])           # x → f, y → up, z → f x up = side
