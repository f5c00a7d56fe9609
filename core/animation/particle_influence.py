"""Regions of influence for particle systems (the course notes of 18 April).

"One can create global effects by defining regions of influence in which some parameters
change in a specific manner (e.g. adding a larger component to V_x to simulate the effects
of forces)." A region is a box or a sphere with its own acceleration (a force per unit mass,
as the emitters' gravity is) and its own drag; a particle whose position is inside the region
at the start of a step has its velocity changed by it for that step::

    v += (a_region - k_region v) dt          (inside only; outside, nothing)

before the emitter's own forces move it (:func:`core.animation.particles._step`). So a
particle that crosses a region at speed s along a chord of length L takes the impulse
``a L / s`` (the steps it starts inside, times ``a dt``): the gust, the thick air, the updraft
of a chimney, each only where it is.

Scene file: ``[[influence]]`` tables, each acting on every particle system of the scene (or
on those its ``emitters`` name, with their children)::

    [[influence]]
    name = "gust"
    box = { min = [1, 0, -2], max = [2, 3, 2] }     # or sphere = { center = [...], radius = r }
    acceleration = [6, 0, 0]
    drag = 0.0
    emitters = ["water"]                             # default: all
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.jit import njit

MAX_REGIONS = 64
MAX_EXTENT = 1e6                  # a region lies within this of the origin (finite, and drawn)
INFLUENCE_KEYS = ("name", "box", "sphere", "acceleration", "drag", "emitters")
BOX, SPHERE = 0, 1


@dataclass(frozen=True)
class Region:
    """One region of influence. A box is ``lo <= x <= hi``; a sphere ``|x - lo| <= radius``."""

    name: str
    kind: int                     # BOX or SPHERE
    lo: np.ndarray                # the box's min corner, or the sphere's centre
    hi: np.ndarray                # the box's max corner (a sphere: unused)
    radius: float
    acceleration: np.ndarray
    drag: float = 0.0

    def inside(self, x: np.ndarray) -> np.ndarray:
        """Which of the points ``x`` (n, 3) the region holds (what the kernel tests)."""
        if self.kind == BOX:
            return np.all((x >= self.lo) & (x <= self.hi), axis=1)
        return np.sum((x - self.lo) ** 2, axis=1) <= self.radius * self.radius


@dataclass
class Packed:
    """Every region as arrays the kernel reads, and which system each one acts on."""

    kind: np.ndarray              # (R,)
    lo: np.ndarray                # (R, 3)
    hi: np.ndarray                # (R, 3)
    radius: np.ndarray            # (R,)
    acceleration: np.ndarray      # (R, 3)
    drag: np.ndarray              # (R,)
    acts_on: np.ndarray           # (S, R) bool: system s feels region r

    def apply(self, position, velocity, spec, dt: float) -> None:
        if len(self.kind) and len(position):
            _influence(position, velocity, spec, dt, self.kind, self.lo, self.hi, self.radius,
                       self.acceleration, self.drag, self.acts_on)


def pack(specs) -> Packed | None:
    """The regions of ``specs`` (each spec's ``influences``) packed once; None without any."""
    regions = list({id(r): r for s in specs for r in s.influences}.values())
    if not regions:
        return None
    acts = np.array([[any(r is q for q in s.influences) for r in regions] for s in specs], bool)
    return Packed(kind=np.array([r.kind for r in regions], np.int64),
                  lo=np.array([r.lo for r in regions], np.float64),
                  hi=np.array([r.hi for r in regions], np.float64),
                  radius=np.array([r.radius for r in regions], np.float64),
                  acceleration=np.array([r.acceleration for r in regions], np.float64),
                  drag=np.array([r.drag for r in regions], np.float64),
                  acts_on=acts.reshape(len(specs), len(regions)))


@njit(cache=True)
def _influence(position, velocity, spec, dt, kind, lo, hi, radius, acceleration, drag, acts_on):
    """Each particle inside a region it feels: ``v += (a - k v) dt`` (position at step start)."""
    for i in range(position.shape[0]):
        s = spec[i]
        for r in range(kind.shape[0]):
            if not acts_on[s, r]:
                continue
            inside = True
            if kind[r] == 0:
                for c in range(3):
                    if position[i, c] < lo[r, c] or position[i, c] > hi[r, c]:
                        inside = False
            else:
                d2 = 0.0
                for c in range(3):
                    d2 += (position[i, c] - lo[r, c]) ** 2
                inside = d2 <= radius[r] * radius[r]
            if inside:
                for c in range(3):
                    velocity[i, c] += (acceleration[r, c] - drag[r] * velocity[i, c]) * dt


# ---------------------------------------------------------------------- the scene file


def read_influences(reader, tables, emitters) -> None:
    """The ``[[influence]]`` tables, each given to the systems it acts on (and their
    children): ``spec.influences`` of every :class:`~core.animation.particles.Spec`."""
    tables = reader.tables(tables, ("influence",))
    if len(tables) > MAX_REGIONS:
        raise reader.fail(("influence",), f"{len(tables)} regions of influence; at most "
                                          f"{MAX_REGIONS}")
    names = [e.name for e in emitters]
    for i, t in enumerate(tables):
        path = ("influence", i + 1)
        region, targets = read_region(reader, t, path, names)
        for spec in emitters:
            if targets is None or spec.name in targets:
                _give(spec, region)


def _give(spec, region: Region) -> None:
    while spec is not None:                      # the system and every generation under it
        spec.influences = tuple(spec.influences) + (region,)
        spec = spec.child


def read_region(reader, t, path, emitter_names) -> tuple[Region, set | None]:
    """One ``[[influence]]`` table: the region, and the names of the emitters it acts on
    (None: all)."""
    t = reader.table(t, path, INFLUENCE_KEYS)
    if ("box" in t) == ("sphere" in t):
        raise reader.fail(path, "a region of influence is one box = { min, max } or one "
                                "sphere = { center, radius }")
    if "acceleration" not in t and "drag" not in t:
        raise reader.fail(path, "a region of influence needs an acceleration or a drag "
                                "(what it changes inside)")
    acceleration = np.array(reader.vector(t.get("acceleration", [0, 0, 0]),
                                          path + ("acceleration",), 3, -1e6, 1e6))
    drag = reader.number(t.get("drag", 0.0), path + ("drag",), 0.0, 1e3)
    name = reader.string(t.get("name", f"influence {path[1]}"), path + ("name",))
    shape = _box(reader, t["box"], path + ("box",)) if "box" in t else \
        _sphere(reader, t["sphere"], path + ("sphere",))
    region = Region(name=name, acceleration=acceleration, drag=drag, **shape)
    targets = None
    if "emitters" in t:
        value = t["emitters"]
        if not isinstance(value, list) or not value:
            raise reader.fail(path + ("emitters",), "expected a list of emitter names")
        targets = {reader.string(v, path + ("emitters", k + 1)) for k, v in enumerate(value)}
        unknown = sorted(targets - set(emitter_names))
        if unknown:
            raise reader.fail(path + ("emitters",), f"no emitter is named {unknown[0]!r} "
                                                    f"(names: {', '.join(emitter_names) or 'none'})")
    return region, targets


def _finite(reader, value, path) -> np.ndarray:
    """A point of a region: finite, within MAX_EXTENT (an endless region is a global force)."""
    if isinstance(value, list) and any(isinstance(v, float) and np.isinf(v) for v in value):
        raise reader.fail(path, "a region of influence has a finite size: for a force "
                                "everywhere give the emitters gravity or wind")
    point = np.array(reader.vector(value, path), np.float64)
    if np.any(np.abs(point) > MAX_EXTENT):
        raise reader.fail(path, f"a region of influence lies within {MAX_EXTENT:g} of the "
                                "origin: for a force everywhere give the emitters gravity or wind")
    return point


def _box(reader, value, path) -> dict:
    b = reader.table(value, path, ("min", "max"))
    if "min" not in b or "max" not in b:
        raise reader.fail(path, "a box needs both 'min' and 'max' corners")
    lo, hi = _finite(reader, b["min"], path + ("min",)), _finite(reader, b["max"], path + ("max",))
    thin = np.flatnonzero(~(hi > lo))
    if len(thin):
        axis = "xyz"[int(thin[0])]
        raise reader.fail(path, f"the box has zero size along {axis} (min {lo[thin[0]]:g}, "
                                f"max {hi[thin[0]]:g}): no particle could be inside it")
    return {"kind": BOX, "lo": lo, "hi": hi, "radius": 0.0}


def _sphere(reader, value, path) -> dict:
    s = reader.table(value, path, ("center", "radius"))
    if "center" not in s or "radius" not in s:
        raise reader.fail(path, "a sphere needs a 'center' and a 'radius'")
    centre = _finite(reader, s["center"], path + ("center",))
    raw = s["radius"]
    if isinstance(raw, float) and np.isinf(raw):
        raise reader.fail(path + ("radius",), "a region of influence has a finite size: for a "
                                              "force everywhere give the emitters gravity or wind")
    radius = reader.number(raw, path + ("radius",), 0.0, MAX_EXTENT)
    if not radius > 0.0:
        raise reader.fail(path + ("radius",), "the sphere has zero size: no particle could be "
                                              "inside it")
    return {"kind": SPHERE, "lo": centre, "hi": centre.copy(), "radius": radius}
