"""Particles constrained to a subspace (the course notes of 18 April).

"It is also possible to constrain particle movement within some subspace (e.g. to a
cylinder, or a trajectory), in general to geometrical constraints." A constrained system's
particles move on a cylinder's surface or along a curve (a polyline), and only there:

- each step, the emitter's forces act as they do on a free particle (semi-implicit Euler,
  ``v1 = v0 + a dt``), then the constraint keeps of ``v1`` only its part along the subspace
  (the normal part is what the constraint's reaction cancels) and moves the particle *on*
  the subspace by it, exactly: on a cylinder the angle about the axis advances by
  ``v_t dt / r`` and the height by ``v_h dt``, and the velocity turns with the point (the
  reaction also supplies the centripetal ``v_t² / r``), so a particle with no force runs a
  helix at constant speed; on a curve the arc length advances by ``v_s dt`` and the velocity
  follows the curve's tangent with its speed kept;
- a particle that runs off the cylinder's ends (``height``) or an open curve's ends is
  annihilated, as one that leaves its emitter's region is.

The position after every step lies on the subspace to round-off (it is computed there, never
pulled back to it). Particles are born on it: by ``shape = "constraint"`` (uniform over the
cylinder's area, or along the curve's length) or at a ``point`` that lies on it (checked at
load); ``speed`` is along the subspace's forward direction (counter-clockwise about the
cylinder's axis; the curve's direction of travel).

Scene file, a key of an ``[[emitter]]``::

    constraint = { type = "cylinder", point = [0, 0, 0], axis = [0, 1, 0], radius = 1,
                   height = 3 }            # point: the centre of the base; no height: endless
    constraint = { type = "curve", points = [[0, 0, 0], [1, 1, 0], ...], closed = true }
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.jit import njit

TYPES = ("cylinder", "curve")
NONE, CYLINDER, CURVE = 0, 1, 2
MAX_CURVE_POINTS = 1024           # each step finds a particle's segment among them
CONSTRAINT_KEYS = ("type", "point", "axis", "radius", "height", "points", "closed")
ON_TOLERANCE = 1e-9               # a birth point this close (relative) is on the subspace


@dataclass(frozen=True)
class Cylinder:
    point: np.ndarray             # the centre of the base (h = 0)
    axis: np.ndarray              # unit
    radius: float
    height: float                 # np.inf: endless both ways

    @property
    def span(self) -> tuple[float, float]:
        return (0.0, self.height) if np.isfinite(self.height) else (-np.inf, np.inf)

    def distance(self, x: np.ndarray) -> np.ndarray:
        """How far the points ``x`` (n, 3) are from the surface."""
        d = x - self.point
        radial = d - np.outer(d @ self.axis, self.axis)
        return np.abs(np.linalg.norm(radial, axis=1) - self.radius)

    def tangent(self, x: np.ndarray) -> np.ndarray:
        """The forward direction at ``x``: counter-clockwise about the axis (a × e_r)."""
        d = x - self.point
        radial = d - np.outer(d @ self.axis, self.axis)
        e_r = radial / np.linalg.norm(radial, axis=1, keepdims=True)
        return np.cross(self.axis, e_r)

    def births(self, rng, n: int) -> np.ndarray:
        """n points uniform over the surface's area (angle and height uniform)."""
        e1, e2 = basis(self.axis)
        phi = rng.uniform(0.0, 2 * np.pi, n)
        h = rng.uniform(0.0, self.height, n)
        return (self.point + h[:, None] * self.axis
                + self.radius * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))


@dataclass(frozen=True)
class Curve:
    points: np.ndarray            # (m, 3) the polyline's vertices; closed: the first again last
    closed: bool

    @property
    def arc(self) -> np.ndarray:
        """The arc length at each vertex, from 0."""
        return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.points, axis=0), axis=1))])

    def nearest(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each point of ``x`` (n, 3): its distance to the curve and the unit tangent of
        the nearest segment."""
        a, b = self.points[:-1], self.points[1:]
        ab = b - a
        u = np.clip(np.einsum("nsc,sc->ns", x[:, None] - a, ab) / np.sum(ab * ab, axis=1), 0, 1)
        gap = np.linalg.norm(x[:, None] - (a + u[..., None] * ab), axis=2)
        best = np.argmin(gap, axis=1)
        unit = ab / np.linalg.norm(ab, axis=1, keepdims=True)
        return gap[np.arange(len(x)), best], unit[best]

    def distance(self, x: np.ndarray) -> np.ndarray:
        return self.nearest(x)[0]

    def tangent(self, x: np.ndarray) -> np.ndarray:
        return self.nearest(x)[1]

    def births(self, rng, n: int) -> np.ndarray:
        """n points uniform along the length."""
        arc = self.arc
        s = rng.uniform(0.0, arc[-1], n)
        k = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(arc) - 2)
        unit = np.diff(self.points, axis=0)
        unit /= np.linalg.norm(unit, axis=1, keepdims=True)
        return self.points[k] + (s - arc[k])[:, None] * unit[k]


def basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to ``axis`` and to each other (e1 × e2 = axis)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(axis, e1)


# ---------------------------------------------------------------------- the step


@dataclass
class Packed:
    """Every system's constraint as arrays the kernel reads (kind NONE: free)."""

    kind: np.ndarray              # (S,)
    point: np.ndarray             # (S, 3) cylinder
    axis: np.ndarray              # (S, 3)
    radius: np.ndarray            # (S,)
    lo: np.ndarray                # (S,) the cylinder's height span
    hi: np.ndarray
    vertices: np.ndarray          # (P, 3) every curve's vertices, one after another
    arc: np.ndarray               # (P,) arc length at each, from its curve's start
    first: np.ndarray             # (S,) the curve's first vertex in ``vertices``
    count: np.ndarray             # (S,) its vertices
    closed: np.ndarray            # (S,) bool

    def apply(self, position, velocity, spec, dt, fate) -> None:
        """After a free step of length ``dt`` (a number, or one a particle): on the subspace."""
        if len(position):
            steps = np.broadcast_to(np.asarray(dt, np.float64), (len(position),))
            _constrain(position, velocity, spec, np.ascontiguousarray(steps), fate, self.kind,
                       self.point, self.axis, self.radius, self.lo, self.hi, self.vertices,
                       self.arc, self.first, self.count, self.closed)


def pack(specs) -> Packed | None:
    """The constraints of ``specs`` (each spec's ``constraint``) packed; None without any."""
    if not any(s.constraint is not None for s in specs):
        return None
    n = len(specs)
    out = Packed(kind=np.zeros(n, np.int64), point=np.zeros((n, 3)), axis=np.zeros((n, 3)),
                 radius=np.zeros(n), lo=np.zeros(n), hi=np.zeros(n), vertices=np.zeros((0, 3)),
                 arc=np.zeros(0), first=np.zeros(n, np.int64), count=np.zeros(n, np.int64),
                 closed=np.zeros(n, bool))
    vertices, arcs = [], []
    used = 0
    for i, s in enumerate(specs):
        c = s.constraint
        if isinstance(c, Cylinder):
            out.kind[i], out.point[i], out.axis[i], out.radius[i] = CYLINDER, c.point, c.axis, c.radius
            out.lo[i], out.hi[i] = c.span
        elif isinstance(c, Curve):
            out.kind[i], out.first[i], out.count[i], out.closed[i] = CURVE, used, len(c.points), c.closed
            vertices.append(c.points)
            arcs.append(c.arc)
            used += len(c.points)
    if vertices:
        out.vertices, out.arc = np.concatenate(vertices), np.concatenate(arcs)
    return out


@njit(cache=True)
def _constrain(position, velocity, spec, dt, fate, kind, point, axis, radius, lo, hi,
               vertices, arc, first, count, closed):
    for i in range(position.shape[0]):
        s = spec[i]
        if kind[s] == 1:
            _on_cylinder(position, velocity, i, dt[i], fate, point[s], axis[s], radius[s],
                         lo[s], hi[s])
        elif kind[s] == 2:
            _on_curve(position, velocity, i, dt[i], fate, vertices, arc, first[s], count[s],
                      closed[s])


@njit(cache=True)
def _on_cylinder(position, velocity, i, dt, fate, c, a, r, lo, hi):
    """The free step went from x0 = x1 - v1 dt; redo it on the surface: the angle by
    v_t dt / r, the height by v_h dt, the velocity turned with the point. (Scalars only:
    no array is made per particle.)"""
    x = position[i, 0] - velocity[i, 0] * dt - c[0]
    y = position[i, 1] - velocity[i, 1] * dt - c[1]
    z = position[i, 2] - velocity[i, 2] * dt - c[2]
    h = x * a[0] + y * a[1] + z * a[2]
    rx, ry, rz = x - h * a[0], y - h * a[1], z - h * a[2]
    norm = np.sqrt(rx * rx + ry * ry + rz * rz)
    rx, ry, rz = rx / norm, ry / norm, rz / norm                  # e_r
    tx = a[1] * rz - a[2] * ry                                    # e_t = a x e_r
    ty = a[2] * rx - a[0] * rz
    tz = a[0] * ry - a[1] * rx
    vt = velocity[i, 0] * tx + velocity[i, 1] * ty + velocity[i, 2] * tz
    vh = velocity[i, 0] * a[0] + velocity[i, 1] * a[1] + velocity[i, 2] * a[2]
    turn = vt * dt / r
    co, si = np.cos(turn), np.sin(turn)
    h += vh * dt
    er = (co * rx + si * tx, co * ry + si * ty, co * rz + si * tz)
    et = (co * tx - si * rx, co * ty - si * ry, co * tz - si * rz)
    for k in range(3):
        position[i, k] = c[k] + h * a[k] + r * er[k]
        velocity[i, k] = vt * et[k] + vh * a[k]
    if (h < lo or h > hi) and fate[i] == 0:
        fate[i] = 2


@njit(cache=True)
def _on_curve(position, velocity, i, dt, fate, vertices, arc, first, count, closed):
    """The free step went from x0 = x1 - v1 dt; redo it along the polyline: the arc length
    by v_s dt (v_s along x0's segment), the velocity along the new segment, speed kept."""
    best, best_gap, best_u = first, np.inf, 0.0
    for j in range(first, first + count - 1):
        d2, u = 0.0, 0.0
        ab2 = 0.0
        for k in range(3):
            ab = vertices[j + 1, k] - vertices[j, k]
            u += (position[i, k] - velocity[i, k] * dt - vertices[j, k]) * ab
            ab2 += ab * ab
        u = min(max(u / ab2, 0.0), 1.0)
        for k in range(3):
            x0 = position[i, k] - velocity[i, k] * dt
            q = vertices[j, k] + u * (vertices[j + 1, k] - vertices[j, k])
            d2 += (x0 - q) ** 2
        if d2 < best_gap:
            best, best_gap, best_u = j, d2, u
    length = arc[best + 1] - arc[best]
    vs = 0.0
    for k in range(3):
        vs += velocity[i, k] * (vertices[best + 1, k] - vertices[best, k]) / length
    s = arc[best] + best_u * length + vs * dt
    total = arc[first + count - 1]
    if closed:
        s = s % total
    elif s < 0.0 or s > total:
        if fate[i] == 0:
            fate[i] = 2
        s = min(max(s, 0.0), total)
    j = first
    while j < first + count - 2 and arc[j + 1] < s:
        j += 1
    length = arc[j + 1] - arc[j]
    for k in range(3):
        unit = (vertices[j + 1, k] - vertices[j, k]) / length
        position[i, k] = vertices[j, k] + (s - arc[j]) * unit
        velocity[i, k] = vs * unit


# ---------------------------------------------------------------------- the scene file


def read_constraint(reader, value, path):
    """An emitter's ``constraint`` table → a :class:`Cylinder` or a :class:`Curve`."""
    t = reader.table(value, path, CONSTRAINT_KEYS)
    if "type" not in t:
        raise reader.fail(path, f"a constraint needs a type ({' or '.join(TYPES)})")
    kind = reader.choice(t["type"], path + ("type",), TYPES)
    wrong = sorted(set(t) - {"type"} - set(("point", "axis", "radius", "height") if
                                            kind == "cylinder" else ("points", "closed")))
    if wrong:
        raise reader.fail(path + (wrong[0],), f"not a key of a {kind} constraint")
    return _cylinder(reader, t, path) if kind == "cylinder" else _curve(reader, t, path)


def _cylinder(reader, t, path) -> Cylinder:
    if "radius" not in t:
        raise reader.fail(path, "a cylinder needs a radius")
    radius = reader.number(t["radius"], path + ("radius",), 0.0, 1e6)
    if not radius > 0.0:
        raise reader.fail(path + ("radius",), "the cylinder's radius must be above 0")
    axis = np.array(reader.vector(t.get("axis", [0, 1, 0]), path + ("axis",), 3, -1e6, 1e6))
    if not np.linalg.norm(axis) > 0:
        raise reader.fail(path + ("axis",), "the cylinder's axis is zero")
    height = np.inf
    if "height" in t:
        height = reader.number(t["height"], path + ("height",), 0.0, 1e6)
        if not height > 0.0:
            raise reader.fail(path + ("height",), "the cylinder's height must be above 0")
    point = np.array(reader.vector(t.get("point", [0, 0, 0]), path + ("point",), 3, -1e6, 1e6))
    return Cylinder(point=point, axis=axis / np.linalg.norm(axis), radius=radius, height=height)


def _curve(reader, t, path) -> Curve:
    raw = t.get("points")
    if not isinstance(raw, list) or len(raw) < 2:
        raise reader.fail(path + ("points",), "a curve needs a list of at least 2 points")
    if len(raw) > MAX_CURVE_POINTS:
        raise reader.fail(path + ("points",), f"{len(raw)} points; at most {MAX_CURVE_POINTS}")
    points = np.array([reader.vector(p, path + ("points", k + 1), 3, -1e6, 1e6)
                       for k, p in enumerate(raw)])
    closed = reader.boolean(t.get("closed", False), path + ("closed",))
    if closed and not np.array_equal(points[0], points[-1]):
        points = np.vstack([points, points[:1]])
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    if not np.all(steps > 0):
        k = int(np.flatnonzero(~(steps > 0))[0])
        raise reader.fail(path + ("points", k + 2), "two points in a row are the same")
    return Curve(points=points, closed=closed)


def check_births(reader, spec, path) -> None:
    """A constrained emitter's particles are born on its subspace: ``shape = "constraint"``
    (a cylinder needs a height to spread over), or a ``point`` shape at a position on it."""
    c = spec.constraint
    if spec.plane is not None:
        raise reader.fail(path + ("plane",), "a constrained particle moves only on its "
                                             "constraint: no collision plane with it")
    if spec.shape == "constraint":
        if isinstance(c, Cylinder) and not np.isfinite(c.height):
            raise reader.fail(path + ("constraint",), "shape = \"constraint\" spreads the "
                              "births over the cylinder: give it a height")
        return
    if spec.shape != "point":
        raise reader.fail(path + ("shape",), f"a constrained emitter's particles are born on "
                          f"its {type(c).__name__.lower()}: shape = \"constraint\", or "
                          f"shape = \"point\" at a position on it (not {spec.shape!r})")
    gap = float(c.distance(spec.position[None])[0])
    scale = max(1.0, float(np.abs(spec.position).max()),
                c.radius if isinstance(c, Cylinder) else 0.0)
    if gap > ON_TOLERANCE * scale:
        what = "the cylinder's surface" if isinstance(c, Cylinder) else "the curve"
        raise reader.fail(path + ("position",), f"the particles would start off their "
                          f"constraint: {tuple(float(x) for x in spec.position)} is {gap:.6g} "
                          f"from {what}; put the position on it, or shape = \"constraint\"")
