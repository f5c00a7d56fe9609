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
    senses: bool = False               # run(t, x, v, params, surroundings): reactive control


_BEHAVIOURS: dict[str, Behaviour] = {}


def register_behaviour(name: str, run: Callable, params: dict, senses: bool = False) -> None:
    """``run(t, x, v, params) -> accelerations`` under ``name``; ``params``: the table keys
    it reads and their defaults (registered again, it replaces the earlier one). With
    ``senses``, it is called ``run(t, x, v, params, surroundings)`` (a :class:`Surroundings`:
    what the group's actors perceive through its ``senses``, the other groups included)."""
    _BEHAVIOURS[name] = Behaviour(run, dict(params), senses)


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


@dataclass(frozen=True)
class Senses:
    """What an actor perceives: points within ``radius`` of it and within ``fov`` degrees
    (the whole angle of a cone about its heading; 360: all round)."""

    radius: float
    fov: float = 360.0

    def see(self, x: np.ndarray, v: np.ndarray, points: np.ndarray,
            sizes: np.ndarray | float = 0.0) -> np.ndarray:
        """``(N, M)``: does actor i (at x[i], heading along v[i]) perceive point j — a sphere
        of radius ``sizes[j]`` about it — nearer than ``radius`` (to its surface) and inside
        its field of view (the centre's direction within fov/2 of the heading; an actor at
        rest has no heading and sees all round)?"""
        d = points[None, :, :] - x[:, None, :]
        dist = np.linalg.norm(d, axis=2)
        near = dist - sizes <= self.radius
        if self.fov >= 360.0:
            return near
        speed = np.linalg.norm(v, axis=1)
        h = v / np.maximum(speed, 1e-300)[:, None]
        cos = np.einsum("nmk,nk->nm", d, h) / np.maximum(dist, 1e-300)
        inside = (cos >= math.cos(math.radians(self.fov / 2.0)) - 1e-12) | (dist == 0.0)
        return near & (inside | (speed == 0.0)[:, None])


class Surroundings:
    """One group's view of the stage at the start of a step: every group's positions and
    velocities (``others(name)``), its own ``senses``, ``max_speed`` and ``max_force``."""

    def __init__(self, groups: list, index: int):
        self.groups, self.index = groups, index
        me = groups[index]
        self.senses, self.max_speed, self.max_force = me.senses, me.max_speed, me.max_force

    def others(self, name: str) -> tuple[np.ndarray, np.ndarray, bool]:
        """(x, v, same): the group named ``name``'s actors now; ``same`` when it is the
        asking group (an actor does not sense itself: the behaviour leaves the diagonal out)."""
        for k, g in enumerate(self.groups):
            if g.name == name:
                return g.state.x, g.state.v, k == self.index
        raise KeyError(name)

    def see(self, x, v, points, sizes=0.0) -> np.ndarray:
        if self.senses is None:
            return np.ones((len(x), len(points)), bool)
        return self.senses.see(x, v, points, sizes)


@dataclass
class Group:
    """The actors of one ``[[actor]]`` table: ``meshes[k]`` the mesh indices actor k carries
    (modelled at ``pivot`` facing +x). The behaviours' accelerations are summed
    (``steering = "sum"``) or taken in priority (``"priority"``: for each actor, the first
    behaviour in the list that asks for any), then cut to ``max_force`` (per unit mass)."""

    meshes: list
    pivot: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    steps: list                                   # (Behaviour, params)
    max_speed: float = 3.0
    dt: float = STEP
    name: str = "actors"
    senses: Senses | None = None
    max_force: float = math.inf
    steering: str = "sum"
    state: GroupState = field(init=False)

    def __post_init__(self) -> None:
        self.rewind = Rewind()
        self.reset()

    def reset(self) -> None:
        self.state = GroupState(0, self.x0.copy(), self.v0.copy())

    def accelerations(self, t: float, world: Surroundings) -> np.ndarray:
        """Every actor's steering at t from the state now (nothing moves)."""
        s = self.state
        a = np.zeros_like(s.x)
        undecided = np.ones(len(s.x), bool)
        for behaviour, params in self.steps:
            b = (behaviour.run(t, s.x, s.v, params, world) if behaviour.senses
                 else behaviour.run(t, s.x, s.v, params))
            if self.steering == "priority":
                asks = undecided & np.any(b != 0.0, axis=1)
                a[asks] = b[asks]
                undecided &= ~asks
            else:
                a += b
        if math.isfinite(self.max_force):
            size = np.linalg.norm(a, axis=1, keepdims=True)
            a *= np.minimum(1.0, self.max_force / np.maximum(size, 1e-300))
        return a

    def integrate(self, a: np.ndarray) -> None:
        """Semi-implicit Euler: v += a dt, the speed cut to max_speed, x += v dt."""
        s = self.state
        s.v += a * self.dt
        speed = np.linalg.norm(s.v, axis=1, keepdims=True)
        s.v *= np.minimum(1.0, self.max_speed / np.maximum(speed, 1e-300))
        s.x += s.v * self.dt
        s.step_index += 1

    def step(self) -> None:
        t = self.state.step_index * self.dt
        self.integrate(self.accelerations(t, Surroundings([self], 0)))

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
        return self.placed()

    def placed(self) -> dict[int, np.ndarray]:
        """mesh index → its 4 x 4 in the state now."""
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
                      self.dt, self.name, self.senses, self.max_force, self.steering)
        other.restore(self.snapshot())
        return other


@dataclass
class StageState:
    groups: list                                  # each group's GroupState


class Stage:
    """Groups that sense one another (reactive control), stepped together: each step every
    group's steering is found from the state of all of them at its start, then all move.
    A mover like a :class:`Group` (``state_at``, ``matrices_at``, ``snapshot``, ``restore``,
    ``copy``)."""

    def __init__(self, groups: list):
        self.groups = groups
        self.dt = groups[0].dt
        self.rewind = Rewind()

    @property
    def step_index(self) -> int:
        return self.groups[0].state.step_index

    def reset(self) -> None:
        for g in self.groups:
            g.reset()

    def step(self) -> None:
        t = self.step_index * self.dt
        steering = [g.accelerations(t, Surroundings(self.groups, k))
                    for k, g in enumerate(self.groups)]
        for g, a in zip(self.groups, steering):
            g.integrate(a)

    def state_at(self, t: float) -> "Stage":
        target = int(math.floor(max(t, 0.0) / self.dt + 1e-9))
        if target < self.step_index:
            saved = self.rewind.nearest(target)
            self.restore(saved) if saved is not None else self.reset()
        if self.step_index < target:
            advance("simulating the actors", self.step_index, target, self.step_on)
        return self

    def step_on(self, n: int) -> None:
        for _ in range(n):
            self.rewind.note(self.step_index, self.snapshot)
            self.step()

    def matrices_at(self, t: float) -> dict[int, np.ndarray]:
        self.state_at(t)
        out = {}
        for g in self.groups:
            out.update(g.placed())
        return out

    def snapshot(self) -> StageState:
        return StageState([g.snapshot() for g in self.groups])

    def restore(self, state: StageState) -> None:
        for g, s in zip(self.groups, state.groups):
            g.restore(s)

    def copy(self) -> "Stage":
        return Stage([g.copy() for g in self.groups])


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
