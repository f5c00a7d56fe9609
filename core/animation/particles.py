"""Particle systems (Reeves 1983, as the course notes of 18 April give them).

A particle system is a set of particles, each *created*, *transformed* and *annihilated* over
time by rules with random variation. Every parameter is a mean and a variance, drawn as the
notes write it, ``X = X_mean + Rand · V`` with ``Rand`` uniform in [-1, 1]:

- **creation**: per animation frame ``N(t) = N_mean + Rand · V`` new particles, placed by a
  *generation shape* (a point, a sphere, a disc, or the surface of a named mesh, uniformly by
  area), each with an initial velocity (mean vector ± variance per component, plus a speed
  along the shape's outward normal), size, colour, transparency and lifetime;
- **transformation**: a fixed time step moves every particle under gravity, wind and drag
  (``a = g + wind - k v``), bounces it off a plane (restitution e, friction f), and carries its
  colour, transparency and size from their initial to their final values over its life;
- **annihilation**: when its age passes its lifetime, when it leaves the emitter's region (a
  box), or when its transparency or size falls below a threshold;
- **generations**: a particle that dies of age spawns ``children = N_mean ± V`` particles of
  the ``child`` system at its place (fireworks: rocket → burst → sparks).
- **constraints and regions of influence**: a system's particles may be held to a subspace
  (a cylinder or a curve, :mod:`core.animation.particle_constraint`), and regions of the
  scene may change the velocity of those inside (:mod:`core.animation.particle_influence`).

State is a structure of arrays (numpy), stepped by one numba kernel. The simulation is
deterministic for a seed: the random numbers of step k come from their own generator, seeded
by ``(seed, k)``, so a frame computed from scratch equals the same frame reached by playing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from core.animation import particle_constraint, particle_influence
from core.animation.rewind import Rewind
from core.jit import njit
from core.work import advance

SHAPES = ("point", "sphere", "disc", "mesh", "constraint")   # constraint: on its subspace
DRAW_MODES = ("point", "sprite", "streak")
SUBSTEPS = 4                      # fixed simulation steps per animation frame
MAX_PARTICLES = 2_000_000         # live particles, all systems together (memory guard)
MAX_PER_FRAME = 200_000
# Time guards. The state at t is simulated from 0, so the animation's length bounds the steps
# (checked when the scene is read), and the particle-steps done since 0 bound the work (checked
# as it is done: how many particles live is known only by simulating). At about 10 ns a
# particle-step, the work budget is a minute or two of one core.
MAX_SIMULATION_STEPS = 400_000    # duration · fps · SUBSTEPS (an hour of 30 fps is 432,000)
MAX_PARTICLE_WORK = 4_000_000_000


class ParticleBudgetError(ValueError):
    """The simulation would take longer than its budget; the message says what to change."""


@dataclass
class Spec:
    """One particle system's rules (an ``[[emitter]]``, or an emitter's ``child``)."""

    name: str = "emitter"
    shape: str = "point"
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    radius: float = 1.0
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    mesh_points: np.ndarray | None = None          # (T, 3, 3) triangles of the named mesh
    rate: tuple[float, float] = (10.0, 0.0)        # N_mean, V particles per frame
    start: float = 0.0                             # emitting from ... to ... (seconds)
    stop: float = math.inf
    velocity: tuple[np.ndarray, np.ndarray] = field(
        default_factory=lambda: (np.zeros(3), np.zeros(3)))
    speed: tuple[float, float] = (0.0, 0.0)        # along the outward normal of the shape
    inherit: float = 1.0                           # children: fraction of the parent's velocity
    size: tuple[float, float] = (0.05, 0.0)
    size_end: float = 1.0                          # size at death, as a factor of the initial
    color: tuple[np.ndarray, np.ndarray] = field(
        default_factory=lambda: (np.ones(3), np.zeros(3)))
    color_end: np.ndarray | None = None
    alpha: tuple[float, float] = (1.0, 0.0)        # opacity = 1 - transparency
    alpha_end: float | None = None
    lifetime: tuple[float, float] = (1.0, 0.0)
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    wind: np.ndarray = field(default_factory=lambda: np.zeros(3))
    drag: float = 0.0
    plane: tuple[np.ndarray, np.ndarray] | None = None     # (point, unit normal)
    restitution: float = 0.5
    friction: float = 0.2
    region: tuple[np.ndarray, np.ndarray] | None = None    # (min corner, max corner)
    alpha_min: float = 0.0
    size_min: float = 0.0
    draw: str = "sprite"
    streak: float = 0.05                           # streak length in seconds of velocity
    children: tuple[float, float] = (0.0, 0.0)
    child: "Spec | None" = None
    # the subspace its particles move on (particle_constraint.Cylinder or Curve; None: free)
    constraint: object | None = None
    influences: tuple = ()                         # particle_influence.Region it feels


def draw(rng, mean, var, n):
    """The notes' ``X_mean ± V · RN``: n draws, Rand uniform in [-1, 1]."""
    mean, var = np.asarray(mean, np.float64), np.asarray(var, np.float64)
    return mean + var * rng.uniform(-1.0, 1.0, (n,) + mean.shape)


def count(rng, mean: float, var: float) -> int:
    """``N = N_mean + Rand · V`` rounded to a whole number of particles (never below 0)."""
    return max(0, int(round(mean + var * rng.uniform(-1.0, 1.0))))


def _unit_vectors(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _disc_basis(normal):
    n = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    a = np.cross(n, helper)
    a /= np.linalg.norm(a)
    return a, np.cross(n, a), n


def generate(spec: Spec, rng, n: int, origin=None):
    """Initial positions and outward directions of n particles on the generation shape.

    ``origin`` (n, 3) replaces the shape's centre (children are born where their parent died).
    """
    centre = spec.position if origin is None else origin
    if spec.constraint is not None:                # on the subspace, forward along it
        points = spec.constraint.births(rng, n) if spec.shape == "constraint" \
            else centre + np.zeros((n, 3))
        return points, spec.constraint.tangent(points)
    if spec.shape == "point":
        return centre + np.zeros((n, 3)), _unit_vectors(rng, n)
    if spec.shape == "sphere":                     # uniform on the surface, pointing out
        out = _unit_vectors(rng, n)
        return centre + spec.radius * out, out
    if spec.shape == "disc":                       # uniform over the area, normal out
        a, b, normal = _disc_basis(spec.normal)
        r = spec.radius * np.sqrt(rng.uniform(0.0, 1.0, n))
        phi = rng.uniform(0.0, 2 * np.pi, n)
        points = centre + (r * np.cos(phi))[:, None] * a + (r * np.sin(phi))[:, None] * b
        return points, np.tile(normal, (n, 1))
    tris = spec.mesh_points                        # uniform by area over the triangles
    e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    cross = np.cross(e1, e2)
    area = np.linalg.norm(cross, axis=1)
    pick = rng.choice(len(tris), size=n, p=area / area.sum())
    s, t = rng.uniform(0.0, 1.0, n), rng.uniform(0.0, 1.0, n)
    flip = s + t > 1.0
    s[flip], t[flip] = 1.0 - s[flip], 1.0 - t[flip]
    points = tris[pick, 0] + s[:, None] * e1[pick] + t[:, None] * e2[pick]
    return points, cross[pick] / area[pick, None]


# ---------------------------------------------------------------------- state


ARRAYS = ("position", "velocity", "age", "life", "size", "color", "color_end", "alpha",
          "alpha_end", "size_end", "spec", "generation")


@dataclass
class Particles:
    """Every live particle, one array per attribute (structure of arrays).

    ``spec`` indexes :attr:`ParticleSystem.specs` (the rules the particle follows),
    ``generation`` counts from 0 for particles an emitter made.
    """

    position: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    age: np.ndarray = field(default_factory=lambda: np.zeros(0))
    life: np.ndarray = field(default_factory=lambda: np.zeros(0))
    size: np.ndarray = field(default_factory=lambda: np.zeros(0))
    color: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    color_end: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    alpha: np.ndarray = field(default_factory=lambda: np.zeros(0))
    alpha_end: np.ndarray = field(default_factory=lambda: np.zeros(0))
    size_end: np.ndarray = field(default_factory=lambda: np.zeros(0))
    spec: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    generation: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    def __len__(self) -> int:
        return len(self.age)

    def extend(self, other: "Particles") -> "Particles":
        return Particles(**{k: np.concatenate([getattr(self, k), getattr(other, k)])
                            for k in ARRAYS})

    def fraction(self) -> np.ndarray:
        """How far through its life each particle is, in [0, 1]."""
        return np.clip(self.age / self.life, 0.0, 1.0)

    def current(self):
        """``(size, rgb, alpha)`` now: each carried linearly from its initial to its final value."""
        f = self.fraction()
        size = self.size * (1.0 + (self.size_end - 1.0) * f)
        rgb = self.color + (self.color_end - self.color) * f[:, None]
        alpha = self.alpha + (self.alpha_end - self.alpha) * f
        return size, rgb, alpha


class ParticlePool:
    """The live particles of a system: the same arrays as :class:`Particles`, kept with spare
    capacity so that a step allocates nothing. Rows ``[0, n)`` are live; the attributes are
    views of them. New particles are appended (capacity doubles when full); the dead are
    squeezed out in place by one compiled pass that keeps the order of the living."""

    def __init__(self, capacity: int = 1024) -> None:
        empty = Particles()
        self._store = {k: np.zeros((capacity,) + getattr(empty, k).shape[1:],
                                   getattr(empty, k).dtype) for k in ARRAYS}
        self.n = 0

    def __len__(self) -> int:
        return self.n

    def __getattr__(self, name):
        if name in ARRAYS:
            return self._store[name][:self.n]
        raise AttributeError(name)

    fraction = Particles.fraction
    current = Particles.current

    def append(self, batch: Particles) -> None:
        m = len(batch)
        if self.n + m > len(self._store["age"]):
            capacity = max(2 * len(self._store["age"]), self.n + m)
            for k, a in self._store.items():
                grown = np.zeros((capacity,) + a.shape[1:], a.dtype)
                grown[:self.n] = a[:self.n]
                self._store[k] = grown
        for k in ARRAYS:
            self._store[k][self.n:self.n + m] = getattr(batch, k)
        self.n += m

    def compact(self, fate: np.ndarray) -> None:
        """Drop every particle whose ``fate`` is not 0."""
        st = self._store
        self.n = _compact(fate, st["position"], st["velocity"], st["color"], st["color_end"],
                          st["age"], st["life"], st["size"], st["alpha"], st["alpha_end"],
                          st["size_end"], st["spec"], st["generation"])


@njit(cache=True)
def _compact(fate, v0, v1, v2, v3, s0, s1, s2, s3, s4, s5, i0, i1):
    """Move the living (fate 0) to the front, in order; returns how many live."""
    w = 0
    for r in range(fate.shape[0]):
        if fate[r] != 0:
            continue
        if w != r:
            for c in range(3):
                v0[w, c] = v0[r, c]
                v1[w, c] = v1[r, c]
                v2[w, c] = v2[r, c]
                v3[w, c] = v3[r, c]
            s0[w] = s0[r]
            s1[w] = s1[r]
            s2[w] = s2[r]
            s3[w] = s3[r]
            s4[w] = s4[r]
            s5[w] = s5[r]
            i0[w] = i0[r]
            i1[w] = i1[r]
        w += 1
    return w


def _new_particles(spec: Spec, index: int, rng, n: int, frame_dt: float, origin=None,
                   parent_velocity=None, generation=0) -> Particles:
    """n particles of ``spec``, their creation spread over one frame (each one's age starts
    uniform in [0, frame_dt) and its position moved on by that much) so that a stream does not
    come out in clumps, one per frame."""
    position, outward = generate(spec, rng, n, origin)
    velocity = draw(rng, *spec.velocity, n) + draw(rng, *spec.speed, n)[:, None] * outward
    if parent_velocity is not None:
        velocity += spec.inherit * parent_velocity
    age = rng.uniform(0.0, frame_dt, n) if origin is None else np.zeros(n)
    acceleration = spec.gravity + spec.wind                  # (drag is left to the steps)
    if spec.constraint is not None:          # one free step of length age, then onto it
        velocity = velocity + acceleration * age[:, None]
        position = position + velocity * age[:, None]
        particle_constraint.pack([spec]).apply(position, velocity, np.zeros(n, np.int64), age,
                                               np.zeros(n, np.int64))
    else:
        position = position + velocity * age[:, None] + 0.5 * acceleration * (age * age)[:, None]
        velocity = velocity + acceleration * age[:, None]
    color = np.clip(draw(rng, *spec.color, n), 0.0, 1.0)
    alpha = np.clip(draw(rng, *spec.alpha, n), 0.0, 1.0)
    return Particles(
        position=position, velocity=velocity, age=age,
        life=np.maximum(draw(rng, *spec.lifetime, n), 1e-6),
        size=np.maximum(draw(rng, *spec.size, n), 0.0),
        color=color,
        color_end=color.copy() if spec.color_end is None else np.tile(spec.color_end, (n, 1)),
        alpha=alpha, alpha_end=alpha.copy() if spec.alpha_end is None else np.full(n, spec.alpha_end),
        size_end=np.full(n, spec.size_end), spec=np.full(n, index, np.int64),
        generation=np.full(n, generation, np.int64))


@njit(cache=True)
def _step(position, velocity, age, life, size, size_end, alpha, alpha_end, spec, dt,
          gravity, wind, drag, has_plane, plane_point, plane_normal, restitution, friction,
          has_region, region_lo, region_hi, alpha_min, size_min, fate):
    """One fixed step for every particle: forces, motion, the plane, ageing, removal.

    ``fate[i]`` becomes 0 (lives on), 1 (died of age: may have children) or 2 (left its region
    or fell below a threshold). Semi-implicit Euler: velocity first, then position with the
    new velocity (stable for drag, and energy does not creep up in a bounce).
    """
    for i in range(position.shape[0]):
        s = spec[i]
        for c in range(3):
            a = gravity[s, c] + wind[s, c] - drag[s] * velocity[i, c]
            velocity[i, c] += a * dt
            position[i, c] += velocity[i, c] * dt
        if has_plane[s]:
            # signed height above the plane; below it, put the particle back on the plane and
            # reflect the normal part of its velocity (restitution), damp the tangential part
            h = 0.0
            vn = 0.0
            for c in range(3):
                h += (position[i, c] - plane_point[s, c]) * plane_normal[s, c]
                vn += velocity[i, c] * plane_normal[s, c]
            if h < 0.0:
                for c in range(3):
                    position[i, c] -= h * plane_normal[s, c]
                    normal_part = vn * plane_normal[s, c]
                    tangent_part = velocity[i, c] - normal_part
                    if vn < 0.0:
                        velocity[i, c] = (1.0 - friction[s]) * tangent_part - restitution[s] * normal_part
        age[i] += dt
        fate[i] = 0
        if age[i] >= life[i]:
            fate[i] = 1
            continue
        if has_region[s]:
            for c in range(3):
                if position[i, c] < region_lo[s, c] or position[i, c] > region_hi[s, c]:
                    fate[i] = 2
        f = age[i] / life[i]
        if alpha[i] + (alpha_end[i] - alpha[i]) * f < alpha_min[s]:
            fate[i] = 2
        if size[i] * (1.0 + (size_end[i] - 1.0) * f) < size_min[s]:
            fate[i] = 2


@dataclass
class Checkpoint:
    """A particle system's state at one step (:mod:`core.animation.checkpoint`)."""

    step_index: int
    particles: Particles          # the live particles, compact copies (what is pickled)

    @property
    def nbytes(self) -> int:
        return sum(getattr(self.particles, k).nbytes for k in ARRAYS)


class ParticleSystem:
    """All emitters of an animation (and their child systems), stepped at a fixed rate.

    ``state_at(t)`` gives the particles at time t; sequential calls continue from the last
    state, any other call starts again from 0, and both give the same numbers.
    """

    def __init__(self, emitters: list[Spec], fps: float, seed: int = 0, substeps: int = SUBSTEPS):
        self.specs: list[Spec] = []
        self.roots: list[int] = []
        for e in emitters:
            self.roots.append(self._add(e))
        self.fps, self.seed, self.substeps = float(fps), int(seed), int(substeps)
        self.dt = 1.0 / (self.fps * self.substeps)
        self._pack()
        self.rewind = Rewind()         # snapshots to go back to (core.animation.rewind)
        self.reset()

    def _add(self, spec: Spec) -> int:
        index = len(self.specs)
        self.specs.append(spec)
        if spec.child is not None:
            self._add(spec.child)
        return index

    def child_index(self, index: int) -> int | None:
        """The spec index of ``specs[index]``'s child system (added right after it)."""
        return index + 1 if self.specs[index].child is not None else None

    def _pack(self) -> None:
        """The per-system rules as arrays the kernel can read."""
        s = self.specs
        self.k_gravity = np.array([p.gravity for p in s], np.float64).reshape(-1, 3)
        self.k_wind = np.array([p.wind for p in s], np.float64).reshape(-1, 3)
        self.k_drag = np.array([p.drag for p in s], np.float64)
        self.k_has_plane = np.array([p.plane is not None for p in s])
        self.k_plane_point = np.array([p.plane[0] if p.plane else np.zeros(3) for p in s]).reshape(-1, 3)
        self.k_plane_normal = np.array([p.plane[1] if p.plane else np.zeros(3) for p in s]).reshape(-1, 3)
        self.k_restitution = np.array([p.restitution for p in s], np.float64)
        self.k_friction = np.array([p.friction for p in s], np.float64)
        self.k_has_region = np.array([p.region is not None for p in s])
        self.k_region_lo = np.array([p.region[0] if p.region else np.zeros(3) for p in s]).reshape(-1, 3)
        self.k_region_hi = np.array([p.region[1] if p.region else np.zeros(3) for p in s]).reshape(-1, 3)
        self.k_alpha_min = np.array([p.alpha_min for p in s], np.float64)
        self.k_size_min = np.array([p.size_min for p in s], np.float64)
        self.constraints = particle_constraint.pack(s)       # None: every particle is free
        self.influences = particle_influence.pack(s)         # None: no region of influence

    def reset(self) -> None:
        self.particles = ParticlePool()
        self.step_index = 0                 # steps done; time = step_index · dt
        self.emitted: list[list[int]] = []  # per frame, per root emitter: N(t) drawn
        self.work = 0                       # particle-steps since 0 (MAX_PARTICLE_WORK)
        self.unborn = 0                     # particles and children the MAX_PARTICLES cap refused

    def state_at(self, t: float) -> "ParticlePool":
        """The particles at time t (after the last whole step at or before t)."""
        target = int(math.floor(t / self.dt + 1e-9))
        what = "simulating the particles"
        if target < self.step_index:
            self.go_back(target)
            what += f" again from step {self.step_index:,}"
        if self.step_index < target:                   # in chunks, reported (core.work)
            advance(what, self.step_index, target, self.step_on)
        return self.particles

    def step_on(self, n: int) -> None:
        """n steps on, snapshots noted on the way."""
        for _ in range(n):
            self.note()
            self.step()

    def go_back(self, target: int) -> None:
        """To the nearest snapshot at or before step ``target``, else to step 0."""
        saved = self.rewind.nearest(target)
        self.restore(saved) if saved is not None else self.reset()

    def note(self) -> None:
        """A snapshot of this step, when one is due (:class:`core.animation.rewind.Rewind`)."""
        self.rewind.note(self.step_index, self.snapshot)

    def snapshot(self) -> "Checkpoint":
        """The state now (copies: the system steps on without changing it)."""
        pool = self.particles
        return Checkpoint(self.step_index,
                          Particles(**{k: getattr(pool, k).copy() for k in ARRAYS}))

    def restore(self, checkpoint: "Checkpoint") -> None:
        """The state of ``checkpoint`` (made by a system of the same rules)."""
        self.reset()
        pool = ParticlePool(max(1024, len(checkpoint.particles)))
        pool.append(checkpoint.particles)
        self.particles = pool
        self.step_index = checkpoint.step_index

    def step(self) -> None:
        """One fixed step; at each frame boundary, first the emission of that frame."""
        k = self.step_index
        p = self.particles
        self.work += len(p)
        if self.work > MAX_PARTICLE_WORK:
            raise ParticleBudgetError(
                f"the particles need more than {MAX_PARTICLE_WORK:,} particle-steps to reach "
                f"t = {k * self.dt:.3f} s ({len(p):,} alive, {self.substeps} steps a frame): "
                "emit fewer, shorter-lived particles, or a shorter animation")
        rng = np.random.default_rng([self.seed, k])
        if k % self.substeps == 0:
            self._emit(rng, k * self.dt)
        fate = np.zeros(len(p), np.int64)
        if len(p) and self.influences is not None:    # regions act where the step starts
            self.influences.apply(p.position, p.velocity, p.spec, self.dt)
        if len(p):
            _step(p.position, p.velocity, p.age, p.life, p.size, p.size_end, p.alpha,
                  p.alpha_end, p.spec, self.dt, self.k_gravity, self.k_wind, self.k_drag,
                  self.k_has_plane, self.k_plane_point, self.k_plane_normal, self.k_restitution,
                  self.k_friction, self.k_has_region, self.k_region_lo, self.k_region_hi,
                  self.k_alpha_min, self.k_size_min, fate)
        if len(p) and self.constraints is not None:
            self.constraints.apply(p.position, p.velocity, p.spec, self.dt, fate)
        if np.any(fate):
            children = self._children(p, fate, rng) if np.any(fate == 1) else None
            p.compact(fate)
            if children is not None:
                p.append(children)
        self.step_index = k + 1

    def _emit(self, rng, t: float) -> None:
        frame_dt = 1.0 / self.fps
        counts, new = [], []
        for index in self.roots:
            spec = self.specs[index]
            wanted = count(rng, *spec.rate) if spec.start <= t < spec.stop else 0
            n = min(wanted, MAX_PER_FRAME, max(0, MAX_PARTICLES - len(self.particles)))
            self.unborn += wanted - n
            counts.append(n)
            if n:
                new.append(_new_particles(spec, index, rng, n, frame_dt))
        self.emitted.append(counts)
        for batch in new:
            self.particles.append(batch)

    def _children(self, p: Particles, fate: np.ndarray, rng) -> Particles:
        """The next generation: ``children = N_mean ± V`` for each particle that died of age."""
        out = Particles()
        dead = np.flatnonzero(fate == 1)
        for s in np.unique(p.spec[dead]):
            child = self.child_index(int(s))
            if child is None:
                continue
            parents = dead[p.spec[dead] == s]
            spec = self.specs[int(s)]
            n_each = np.array([count(rng, *spec.children) for _ in parents], np.int64)
            room = max(0, MAX_PARTICLES - len(p) - len(out))
            if n_each.sum() > room:             # the cap: none of this batch, and it is counted
                self.unborn += int(n_each.sum())
                n_each[:] = 0
            if n_each.sum() == 0:
                continue
            rows = np.repeat(parents, n_each)
            batch = _new_particles(self.specs[child], child, rng, len(rows), 0.0,
                                   origin=p.position[rows], parent_velocity=p.velocity[rows],
                                   generation=0)
            batch.generation = p.generation[rows] + 1
            out = out.extend(batch)
        return out


# ---------------------------------------------------------------------- the scene file

# key → (kind, low, high): "v3" a vector, "n" a number, "s:..." a choice
_VEC, _NUM = "v3", "n"
EMITTER_KEYS = {
    "name": ("str", 0, 0), "shape": ("choice", SHAPES, 0), "mesh": ("str", 0, 0),
    "position": (_VEC, -1e6, 1e6), "radius": (_NUM, 0.0, 1e6), "normal": (_VEC, -1e6, 1e6),
    "rate": (_NUM, 0.0, MAX_PER_FRAME), "rate_var": (_NUM, 0.0, MAX_PER_FRAME),
    "start": (_NUM, 0.0, 1e6), "stop": (_NUM, 0.0, 1e6),
    "velocity": (_VEC, -1e6, 1e6), "velocity_var": (_VEC, 0.0, 1e6),
    "speed": (_NUM, -1e6, 1e6), "speed_var": (_NUM, 0.0, 1e6), "inherit": (_NUM, -10.0, 10.0),
    "size": (_NUM, 0.0, 1e6), "size_var": (_NUM, 0.0, 1e6), "size_end": (_NUM, 0.0, 1e6),
    "color": ("rgb", 0.0, 1.0), "color_var": ("rgb", 0.0, 1.0), "color_end": ("rgb", 0.0, 1.0),
    "alpha": (_NUM, 0.0, 1.0), "alpha_var": (_NUM, 0.0, 1.0), "alpha_end": (_NUM, 0.0, 1.0),
    "lifetime": (_NUM, 0.0, 1e6), "lifetime_var": (_NUM, 0.0, 1e6),
    "gravity": (_VEC, -1e6, 1e6), "wind": (_VEC, -1e6, 1e6), "drag": (_NUM, 0.0, 1e3),
    "plane": ("plane", 0, 0), "region": ("region", 0, 0),
    "alpha_min": (_NUM, 0.0, 1.0), "size_min": (_NUM, 0.0, 1e6),
    "draw": ("choice", DRAW_MODES, 0), "streak": (_NUM, 0.0, 10.0),
    "children": (_NUM, 0.0, 10_000), "children_var": (_NUM, 0.0, 10_000), "child": ("child", 0, 0),
    "constraint": ("constraint", 0, 0),
}
MAX_GENERATIONS = 4


def read_emitters(reader, tables, scene) -> list[Spec]:
    """The ``[[emitter]]`` tables of a scene file, each checked key by key."""
    return [read_spec(reader, t, ("emitter", i + 1), scene, 1)
            for i, t in enumerate(reader.tables(tables, ("emitter",)))]


def read_spec(reader, value, path, scene, depth: int) -> Spec:
    t = reader.table(value, path, tuple(EMITTER_KEYS))
    got = {}
    for key, raw in t.items():
        kind, low, high = EMITTER_KEYS[key]
        p = path + (key,)
        if kind == _VEC or kind == "rgb":
            got[key] = np.array(reader.vector(raw, p, 3, low, high))
        elif kind == _NUM:
            got[key] = reader.number(raw, p, low, high)
        elif kind == "str":
            got[key] = reader.string(raw, p)
        elif kind == "choice":
            got[key] = reader.choice(raw, p, low)
        elif kind == "plane":
            pt = reader.table(raw, p, ("point", "normal", "restitution", "friction"))
            normal = np.array(reader.vector(pt.get("normal", [0, 1, 0]), p + ("normal",)))
            if not np.linalg.norm(normal) > 0:
                raise reader.fail(p + ("normal",), "the plane's normal is zero")
            got[key] = (np.array(reader.vector(pt.get("point", [0, 0, 0]), p + ("point",))),
                        normal / np.linalg.norm(normal))
            got["restitution"] = reader.number(pt.get("restitution", 0.5), p + ("restitution",), 0.0, 1.0)
            got["friction"] = reader.number(pt.get("friction", 0.2), p + ("friction",), 0.0, 1.0)
        elif kind == "region":
            rt = reader.table(raw, p, ("min", "max"))
            for corner in ("min", "max"):
                if corner not in rt:
                    raise reader.fail(p, "a region needs both 'min' and 'max' corners")
            lo, hi = (np.array(reader.vector(rt[c], p + (c,))) for c in ("min", "max"))
            if np.any(lo >= hi):
                raise reader.fail(p, "the region's min corner is not below its max corner")
            got[key] = (lo, hi)
        elif kind == "child":
            if depth >= MAX_GENERATIONS:
                raise reader.fail(p, f"at most {MAX_GENERATIONS} generations")
            got[key] = read_spec(reader, raw, p, scene, depth + 1)
        elif kind == "constraint":
            if depth > 1:
                raise reader.fail(p, "children are born where their parents die, off any "
                                     "subspace of their own: a constraint belongs to an "
                                     "[[emitter]] table")
            got[key] = particle_constraint.read_constraint(reader, raw, p)
    return _spec(reader, got, path, scene)


def _spec(reader, got: dict, path, scene) -> Spec:
    spec = Spec(name=got.get("name", f"{path[0]} {path[1]}" if len(path) > 1 else "emitter"))
    spec.shape = got.get("shape", "point")
    spec.position = got.get("position", np.zeros(3))
    spec.radius = got.get("radius", 1.0)
    if "normal" in got:
        if not np.linalg.norm(got["normal"]) > 0:
            raise reader.fail(path + ("normal",), "the normal is zero")
        spec.normal = got["normal"] / np.linalg.norm(got["normal"])
    if spec.shape == "mesh":
        spec.mesh_points = _mesh_triangles(reader, got, path, scene)
    elif "mesh" in got:
        raise reader.fail(path + ("mesh",), "a mesh is used only with shape = \"mesh\"")
    spec.rate = (got.get("rate", 10.0), got.get("rate_var", 0.0))
    spec.start, spec.stop = got.get("start", 0.0), got.get("stop", math.inf)
    spec.velocity = (got.get("velocity", np.zeros(3)), got.get("velocity_var", np.zeros(3)))
    spec.speed = (got.get("speed", 0.0), got.get("speed_var", 0.0))
    spec.inherit = got.get("inherit", 1.0)
    spec.size = (got.get("size", 0.05), got.get("size_var", 0.0))
    spec.size_end = got.get("size_end", 1.0)
    spec.color = (got.get("color", np.ones(3)), got.get("color_var", np.zeros(3)))
    spec.color_end = got.get("color_end")
    spec.alpha = (got.get("alpha", 1.0), got.get("alpha_var", 0.0))
    spec.alpha_end = got.get("alpha_end")
    spec.lifetime = (got.get("lifetime", 1.0), got.get("lifetime_var", 0.0))
    if spec.lifetime[0] - spec.lifetime[1] <= 0.0:
        raise reader.fail(path + ("lifetime",), "lifetime - lifetime_var must stay above 0")
    for key in ("gravity", "wind"):
        setattr(spec, key, got.get(key, np.zeros(3)))
    spec.drag = got.get("drag", 0.0)
    spec.plane = got.get("plane")
    spec.restitution, spec.friction = got.get("restitution", 0.5), got.get("friction", 0.2)
    spec.region = got.get("region")
    spec.alpha_min, spec.size_min = got.get("alpha_min", 0.0), got.get("size_min", 0.0)
    spec.draw, spec.streak = got.get("draw", "sprite"), got.get("streak", 0.05)
    spec.children = (got.get("children", 0.0), got.get("children_var", 0.0))
    spec.child = got.get("child")
    if spec.children[0] + spec.children[1] > 0 and spec.child is None:
        raise reader.fail(path + ("children",), "children need a 'child' table (their rules)")
    spec.constraint = got.get("constraint")
    if spec.constraint is not None:
        particle_constraint.check_births(reader, spec, path)
    elif spec.shape == "constraint":
        raise reader.fail(path + ("shape",), "shape = \"constraint\" needs a constraint table")
    return spec


def _mesh_triangles(reader, got, path, scene) -> np.ndarray:
    names = [m.name for m in scene.meshes]
    if "mesh" not in got:
        raise reader.fail(path, "shape = \"mesh\" needs mesh = NAME (a [[geometry]] name)")
    if got["mesh"] not in names:
        raise reader.fail(path + ("mesh",), f"no geometry is named {got['mesh']!r} "
                                            f"(names: {', '.join(names)})")
    from core.scene.model import meshes_named
    meshes = [scene.meshes[i] for i in meshes_named(scene, got["mesh"])]   # all of a checker
    tris = np.concatenate([m.positions[m.triangles] for m in meshes])
    if len(tris) == 0:
        raise reader.fail(path + ("mesh",), f"{got['mesh']!r} has no triangles to emit from")
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    if not area.sum() > 0:
        raise reader.fail(path + ("mesh",), f"{got['mesh']!r} has no area")
    return tris[area > 0]


def sprites_of(system: ParticleSystem, particles: Particles):
    """The particles as the particle stage draws them (:class:`core.animation.draw.Sprites`)."""
    from core.animation.draw import DRAW_CODES, Sprites
    size, rgb, alpha = particles.current()
    modes = np.array([DRAW_CODES[s.draw] for s in system.specs], np.int64)
    streaks = np.array([s.streak for s in system.specs], np.float64)
    mode = modes[particles.spec] if len(particles) else np.zeros(0, np.int64)
    back = (streaks[particles.spec] * (mode == DRAW_CODES["streak"]))[:, None] if len(particles) \
        else np.zeros((0, 1))
    return Sprites(position=particles.position.copy(), tail=particles.position - particles.velocity * back,
                   radius=size, rgb=rgb, alpha=alpha, mode=mode)
