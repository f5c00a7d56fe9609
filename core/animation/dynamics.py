"""Rigid bodies: mass, inertia from the mesh, gravity, collisions, restitution and friction.

The physically based control of the course's animation lecture (F = ma, then the collisions
that keep bodies out of each other). Each ``[[body]]`` of a scene file moves one named
geometry as a rigid body: its centre of mass ``x``, velocity ``v``, orientation ``q`` and
angular momentum ``L`` (world frame) are the state; its mass is given, its centre of mass and
inertia tensor come from the closed mesh (the divergence theorem over the tetrahedra that
each triangle makes with the origin, Mirtich's mass properties at uniform density).

The integrator takes a fixed step ``dt`` (``[dynamics] step``, default 1/240 s) whatever
the frame rate; a frame at time t shows the state after ``floor(t / dt)`` steps.

- Translation: **velocity Verlet**, ``x += v dt + g dt²/2; v += g dt``. Gravity is the only
  force, constant, so this is the closed-form parabola (second order in general; exact here
  to rounding, the dropped-sphere test's point).
- Rotation: torque-free between contacts, ``L`` is conserved and ``q`` turned by the angular
  velocity ``ω = R I⁻¹ Rᵀ L`` taken at the half step (the explicit midpoint rule on the
  rotation group: second order; the energy test states the drift).
- Sphere against plane: the time of impact inside the step is solved from the parabola and
  the bounce happens there (so a bounce's height falls by exactly e²); every other contact
  is found at the end of the step — a hull's vertices against the planes and against a
  convex body's face planes, bounding spheres otherwise (static spheres, sphere bodies,
  meshes that are not convex) — resolved by impulses (restitution e for a closing speed
  above REST_SPEED_STEPS · |g| dt, Coulomb friction μ on the tangential impulse) in
  ``iterations`` passes, and the bodies pushed apart along the contact normal.

The state is deterministic (no random numbers, a fixed order of contacts), so a
:class:`World` restored from a :func:`snapshot` steps on to exactly the numbers of one that
played from 0: what lets ``animate --workers`` split a movie.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from core.animation.rewind import Rewind
from core.jit import call_compiled, compiled_at, njit
from core.vectors import dot3, mat_t_vec3, mat_vec3

DEFAULT_STEP = 1.0 / 240.0
MIN_STEP = 1e-5                    # below this a second of motion is over 100,000 steps
MAX_BODIES = 1000                  # the pair test is N² / 2 a step
MAX_HULL_VERTICES = 4096           # per body: the vertices tested against the planes
# steps x (pairs + vertices x planes) x passes to the last frame: measured at ~200 ns a unit
# here (blocks_falling.toml), so about a minute at most
MAX_DYNAMICS_WORK = 300_000_000
MAX_SIMULATION_STEPS = 10_000_000
MAX_CONTACTS = 65_536              # contacts a step that accumulate their impulses over the passes
REST_SPEED_STEPS = 2.0             # closing speeds below this many steps of gravity do not bounce
SPHERE, HULL = 0, 1
SHAPES = ("sphere", "hull")


@dataclass
class Body:
    """One rigid body as the scene file gives it (world units, the file's pose at t = 0)."""

    name: str
    meshes: list[int]                      # the scene's mesh indices it moves
    mass: float
    center: np.ndarray                     # centre of mass at t = 0
    inertia: np.ndarray                    # 3 x 3 about the centre, world axes at t = 0
    radius: float                          # bounding sphere about the centre
    hull: np.ndarray                       # (V, 3) vertices relative to the centre
    shape: int = HULL
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    spin: np.ndarray = field(default_factory=lambda: np.zeros(3))       # ω at t = 0, rad/s
    restitution: float = 0.5
    friction: float = 0.3
    # (F, 4) face planes n·p <= d of a convex hull body, about the centre (none: not convex,
    # and it meets other bodies as its bounding sphere)
    faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))


def face_planes(points: np.ndarray, positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(F, 4) rows (n, d) of the distinct face planes n·p = d of a closed mesh (positions
    about the centre), when every point lies behind every plane (the mesh is convex);
    else no rows."""
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1)
    keep = length > 1e-12 * max(1.0, float(length.max(initial=0.0)))
    n = n[keep] / length[keep, None]
    d = np.einsum("ij,ij->i", n, a[keep])
    size = float(np.max(np.linalg.norm(points, axis=1), initial=1.0))
    planes = np.unique(np.round(np.column_stack([n, d / size]), 9), axis=0)
    planes[:, 3] *= size
    if len(planes) == 0 or np.max(points @ planes[:, :3].T - planes[:, 3]) > 1e-9 * size:
        return np.zeros((0, 4))
    return planes


def mass_properties(positions: np.ndarray, triangles: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """``(volume, centroid, inertia per unit density about the centroid)`` of a closed mesh
    wound counter-clockwise from outside: each triangle (a, b, c) and the origin make a
    tetrahedron of signed volume det[a b c] / 6 and second moment det · A C Aᵀ with
    A = [a b c] and C the canonical tetrahedron's covariance (2 on the diagonal, 1 off it,
    over 120); the sums over the triangles are the solid's."""
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = det.sum() / 6.0
    if not volume > 0.0:
        return float(volume), np.zeros(3), np.zeros((3, 3))
    centroid = (det[:, None] * (a + b + c)).sum(axis=0) / (24.0 * volume)
    canonical = (np.ones((3, 3)) + np.eye(3)) / 120.0
    A = np.stack([a, b, c], axis=2)                           # columns a, b, c
    second = np.einsum("t,tij,jk,tlk->il", det, A, canonical, A)
    second -= volume * np.outer(centroid, centroid)          # about the centroid
    inertia = np.trace(second) * np.eye(3) - second
    return float(volume), centroid, inertia


# ---------------------------------------------------------------------- the kernels


@njit(cache=True)
def _matrix(q):
    """The rotation matrix of the unit quaternion q = (w, x, y, z), R v = q v q*."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    r = np.empty((3, 3))
    r[0, 0] = 1 - 2 * (y * y + z * z); r[0, 1] = 2 * (x * y - w * z); r[0, 2] = 2 * (x * z + w * y)
    r[1, 0] = 2 * (x * y + w * z); r[1, 1] = 1 - 2 * (x * x + z * z); r[1, 2] = 2 * (y * z - w * x)
    r[2, 0] = 2 * (x * z - w * y); r[2, 1] = 2 * (y * z + w * x); r[2, 2] = 1 - 2 * (x * x + y * y)
    return r


@njit(cache=True)
def _turned(q, w, h):
    """q turned by the angular velocity w for the time h: exp(w h / 2) ⊗ q, renormalised."""
    n = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if n * h == 0.0:
        return q.copy()
    s = math.sin(0.5 * n * h) / n
    d = np.array([math.cos(0.5 * n * h), w[0] * s, w[1] * s, w[2] * s])
    out = np.empty(4)
    out[0] = d[0] * q[0] - d[1] * q[1] - d[2] * q[2] - d[3] * q[3]
    out[1] = d[0] * q[1] + d[1] * q[0] + d[2] * q[3] - d[3] * q[2]
    out[2] = d[0] * q[2] - d[1] * q[3] + d[2] * q[0] + d[3] * q[1]
    out[3] = d[0] * q[3] + d[1] * q[2] - d[2] * q[1] + d[3] * q[0]
    return out / math.sqrt(out[0] ** 2 + out[1] ** 2 + out[2] ** 2 + out[3] ** 2)


@njit(cache=True)
def _omega(q, inv_body, L):
    """ω = R I_body⁻¹ Rᵀ L."""
    r = _matrix(q)
    return mat_vec3(r, mat_vec3(inv_body, mat_t_vec3(r, L)))


@njit(cache=True)
def _rotate(q, inv_body, L, h):
    """The explicit midpoint rule: ω at q turned half a step, then the whole step by it."""
    half = _turned(q, _omega(q, inv_body, L), 0.5 * h)
    return _turned(q, _omega(half, inv_body, L), h)


@njit(cache=True)
def _impact_time(d0, vn, an, h):
    """The first τ in (0, h] with d0 + vn τ + an τ²/2 = 0 for d0 >= 0 and vn < 0 (closing),
    or -1 when the gap stays open over the step."""
    disc = vn * vn - 2.0 * an * d0
    if disc < 0.0:
        return -1.0
    tau = 2.0 * d0 / (-vn + math.sqrt(disc))          # the stable form of the smaller root
    return tau if tau <= h else -1.0


@njit(cache=True)
def _apply(b, point, normal_j, vel, L, inv_mass):
    """The impulse ``normal_j`` (a vector) at the arm ``point`` (from the centre) on body b."""
    vel[b] += normal_j * inv_mass[b]
    L[b] += np.cross(point, normal_j)


@njit(cache=True)
def _point_velocity(b, arm, vel, q, L, inv_body):
    return vel[b] + np.cross(_omega(q[b], inv_body[b], L[b]), arm)


@njit(cache=True)
def _k(b, arm, direction, q, inv_body, inv_mass):
    """1 / effective mass of body b along ``direction`` at ``arm``: 1/m + ((I⁻¹(r×d))×r)·d."""
    if inv_mass[b] == 0.0:
        return 0.0
    r = _matrix(q[b])
    # I_world⁻¹ (r × d)
    turned = mat_vec3(r, mat_vec3(inv_body[b], mat_t_vec3(r, np.cross(arm, direction))))
    return inv_mass[b] + dot3(np.cross(turned, arm), direction)


@njit(cache=True)
def _resolve(a, b, point, normal, e, mu, x, vel, q, L, inv_mass, inv_body, v_rest, cache,
             counter):
    """The impulses of one contact between body a and body b (-1: the static world) at
    ``point``, ``normal`` pointing from b into a: restitution e on a closing speed above
    ``v_rest`` (none below: a resting contact), then Coulomb friction capped at μ · jn.

    Within a step the passes meet the same contacts in the same order; contact k's row of
    ``cache`` keeps its accumulated normal impulse, the separating speed it aims at (set on
    the first pass) and its accumulated friction, so that a later pass can take back what
    an earlier one gave too much (the total clamped at 0: Catto's sequential impulses).
    Without a row (``counter`` past the cache) each pass's impulse stands alone."""
    ra = point - x[a]
    rel = _point_velocity(a, ra, vel, q, L, inv_body)
    rb = np.zeros(3)
    if b >= 0:
        rb = point - x[b]
        rel = rel - _point_velocity(b, rb, vel, q, L, inv_body)
    vn = dot3(rel, normal)
    c = counter[0]
    counter[0] += 1
    if c < len(cache) and c >= counter[1]:   # a row's first use this step: empty it (the
        cache[c, 0] = cache[c, 1] = 0.0      # cache is not cleared whole: 2 MB a step was
        cache[c, 2] = cache[c, 3] = 0.0      # three quarters of a lone ball's step)
        counter[1] = c + 1
    kn = _k(a, ra, normal, q, inv_body, inv_mass) + (_k(b, rb, normal, q, inv_body, inv_mass) if b >= 0 else 0.0)
    if c < len(cache):
        if cache[c, 2] == 0.0:
            cache[c, 2] = 1.0
            cache[c, 1] = -e * vn if vn < -v_rest else 0.0
        total = max(cache[c, 0] + (cache[c, 1] - vn) / kn, 0.0)
        jn = total - cache[c, 0]
        cache[c, 0] = total
        cap = mu * total - cache[c, 3]
    else:
        if vn >= 0.0:
            return
        jn = -(1.0 + (e if vn < -v_rest else 0.0)) * vn / kn
        cap = mu * jn
    if jn != 0.0:
        _apply(a, ra, jn * normal, vel, L, inv_mass)
        if b >= 0:
            _apply(b, rb, -jn * normal, vel, L, inv_mass)
    rel = _point_velocity(a, ra, vel, q, L, inv_body)
    if b >= 0:
        rel = rel - _point_velocity(b, rb, vel, q, L, inv_body)
    slip = rel - dot3(rel, normal) * normal
    speed = math.sqrt(dot3(slip, slip))
    if speed == 0.0 or cap <= 0.0:
        return
    t = slip / speed
    kt = _k(a, ra, t, q, inv_body, inv_mass) + (_k(b, rb, t, q, inv_body, inv_mass) if b >= 0 else 0.0)
    jt = min(speed / kt, cap)
    if c < len(cache):
        cache[c, 3] += jt
    _apply(a, ra, -jt * t, vel, L, inv_mass)
    if b >= 0:
        _apply(b, rb, jt * t, vel, L, inv_mass)


@njit(cache=True)
def _flight(b, x, vel, q, L, inv_body, g, h):
    """Free flight for the time h: the parabola (velocity Verlet) and the midpoint turn."""
    x[b] += vel[b] * h + 0.5 * g * h * h
    vel[b] += g * h
    q[b] = _rotate(q[b], inv_body[b], L[b], h)


@njit(cache=True)
def _sphere_flight(b, x, vel, q, L, inv_mass, inv_body, radius, rest, fric, plane_p, plane_n,
                   g, dt, v_rest, at):
    """A sphere's step with its plane impacts at their exact times inside the step (at most
    four a step; a fifth waits for the end-of-step contacts)."""
    left = dt
    for _ in range(4):
        first, which = left + 1.0, -1
        for p in range(len(plane_p)):
            n = plane_n[p]
            vn = dot3(vel[b], n)
            d0 = dot3(x[b] - plane_p[p], n) - radius[b]
            if vn < -v_rest and d0 >= 0.0:
                tau = _impact_time(d0, vn, dot3(g, n), left)
                if 0.0 <= tau < first:
                    first, which = tau, p
        if which < 0:
            break
        _flight(b, x, vel, q, L, inv_body, g, first)
        n = plane_n[which]
        call_compiled(at, _resolve, b, -1, x[b] - radius[b] * n, n, rest[b], fric[b], x, vel,
                      q, L, inv_mass, inv_body, v_rest, np.zeros((0, 4)), np.zeros(1, np.int64))
        left -= first
    _flight(b, x, vel, q, L, inv_body, g, left)


@njit(cache=True)
def _plane_pass(b, x, vel, q, L, inv_mass, inv_body, radius, shape, hull, hull_start, rest,
                fric, plane_p, plane_n, v_rest, push, cache, counter, at):
    """Body b against every plane: the velocity impulses at each point below it, or (with
    ``push``) the body moved out by the deepest point's depth."""
    for p in range(len(plane_p)):
        n = plane_n[p]
        deepest = 0.0
        if shape[b] == 0:
            depth = radius[b] - dot3(x[b] - plane_p[p], n)
            if depth > 0.0:
                deepest = depth
                if not push:
                    call_compiled(at, _resolve, b, -1, x[b] - radius[b] * n, n, rest[b],
                                  fric[b], x, vel, q, L, inv_mass, inv_body, v_rest, cache,
                                  counter)
        else:
            r = _matrix(q[b])
            for k in range(hull_start[b], hull_start[b + 1]):
                point = x[b] + mat_vec3(r, hull[k])
                depth = -dot3(point - plane_p[p], n)
                if depth > 0.0:
                    deepest = max(deepest, depth)
                    if not push:
                        call_compiled(at, _resolve, b, -1, point, n, rest[b], fric[b], x, vel,
                                      q, L, inv_mass, inv_body, v_rest, cache, counter)
        if push and deepest > 0.0:
            x[b] += deepest * n


@njit(cache=True)
def _sphere_pass(a, b, c, rc, x, vel, q, L, inv_mass, inv_body, radius, rest, fric, v_rest,
                 push, cache, counter, at):
    """Body a against body b's bounding sphere, or (b = -1) the static sphere (c, rc)."""
    other = c if b < 0 else x[b]
    reach = radius[a] + (rc if b < 0 else radius[b])
    d = x[a] - other
    dist = math.sqrt(dot3(d, d))
    if dist >= reach or dist == 0.0:
        return
    n = d / dist
    if push:
        depth = reach - dist
        share = 1.0 if b < 0 else inv_mass[a] / (inv_mass[a] + inv_mass[b])
        x[a] += depth * share * n
        if b >= 0:
            x[b] -= depth * (1.0 - share) * n
        return
    e = rest[a] if b < 0 else math.sqrt(rest[a] * rest[b])
    mu = fric[a] if b < 0 else math.sqrt(fric[a] * fric[b])
    call_compiled(at, _resolve, a, b, x[a] - radius[a] * n, n, e, mu, x, vel, q, L, inv_mass,
                  inv_body, v_rest, cache, counter)


@njit(cache=True)
def _separation(a, b, x, q, hull, hull_start, faces, face_start):
    """Over b's face planes, the one that a's points are least far behind (the separating
    axis test over one body's face normals): ``(separation, face)``; a separation above 0
    is a gap."""
    ra, rb = _matrix(q[a]), _matrix(q[b])
    best, which = -1e300, -1
    for f in range(face_start[b], face_start[b + 1]):
        n = mat_vec3(rb, faces[f, :3])
        d = faces[f, 3] + dot3(n, x[b]) - dot3(n, x[a])
        m = mat_t_vec3(ra, n)               # n · (x_a + R_a h) = n · x_a + (R_aᵀ n) · h
        low = 1e300
        for k in range(hull_start[a], hull_start[a + 1]):
            low = min(low, dot3(m, hull[k]) - d)
        if low > best:
            best, which = low, f
    return best, which


@njit(cache=True)
def _hull_pass(a, b, x, vel, q, L, inv_mass, inv_body, hull, hull_start, faces, face_start,
               rest, fric, v_rest, push, cache, counter, at):
    """Two convex bodies: the axis of least overlap among both bodies' face normals (none
    with a gap: they touch), then every point of the other body inside the face's body gets
    an impulse along that one normal; or (with ``push``) the two are moved apart by the
    overlap. One normal for the whole contact keeps a resting stack from being pushed
    sideways by the nearest side face of a corner."""
    sep_ab, face_ab = _separation(a, b, x, q, hull, hull_start, faces, face_start)
    if sep_ab >= 0.0:
        return
    sep_ba, face_ba = _separation(b, a, x, q, hull, hull_start, faces, face_start)
    if sep_ba >= 0.0:
        return
    if sep_ab >= sep_ba:                    # b's face: a's points go in
        ref, inc, face, depth, sign = b, a, face_ab, -sep_ab, 1.0
    else:
        ref, inc, face, depth, sign = a, b, face_ba, -sep_ba, -1.0
    rr, ri = _matrix(q[ref]), _matrix(q[inc])
    n = mat_vec3(rr, faces[face, :3])            # out of ref, into inc
    if push:
        share = inv_mass[inc] / (inv_mass[inc] + inv_mass[ref])
        x[inc] += depth * share * n
        x[ref] -= depth * (1.0 - share) * n
        return
    e = math.sqrt(rest[a] * rest[b])
    mu = math.sqrt(fric[a] * fric[b])
    for k in range(hull_start[inc], hull_start[inc + 1]):
        point = x[inc] + mat_vec3(ri, hull[k])
        local = mat_t_vec3(rr, point - x[ref])
        inside = True
        for f in range(face_start[ref], face_start[ref + 1]):
            if faces[f, 0] * local[0] + faces[f, 1] * local[1] + faces[f, 2] * local[2] > faces[f, 3]:
                inside = False
                break
        if inside:
            call_compiled(at, _resolve, inc, ref, point, n, e, mu, x, vel, q, L, inv_mass,
                          inv_body, v_rest, cache, counter)


@njit(cache=True)
def _pair(a, b, x, vel, q, L, inv_mass, inv_body, radius, shape, hull, hull_start, faces,
          face_start, rest, fric, v_rest, push, cache, counter, at):
    """Two bodies: convex hulls by their vertices against each other's faces (once their
    bounding spheres meet), anything else by the bounding spheres."""
    _, _, at_sphere, at_hull, at_resolve = at
    convex = face_start[a + 1] > face_start[a] and face_start[b + 1] > face_start[b]
    if not convex:
        call_compiled(at_sphere, _sphere_pass, a, b, x[a], 0.0, x, vel, q, L, inv_mass,
                      inv_body, radius, rest, fric, v_rest, push, cache, counter, at_resolve)
        return
    d = x[a] - x[b]
    if dot3(d, d) >= (radius[a] + radius[b]) ** 2:
        return
    call_compiled(at_hull, _hull_pass, a, b, x, vel, q, L, inv_mass, inv_body, hull,
                  hull_start, faces, face_start, rest, fric, v_rest, push, cache, counter,
                  at_resolve)


@njit(cache=True)
def step_world(x, vel, q, L, inv_mass, inv_body, radius, shape, hull, hull_start, faces,
               face_start, rest, fric, plane_p, plane_n, sphere_c, sphere_r, g, dt, iterations,
               v_rest, at, cache):
    """One fixed step of every body: flight, ``iterations`` passes of contact impulses, then
    ``iterations`` passes pushing the bodies out of what they entered. ``at``: the passes'
    and the contact's machine code (:func:`kernels_at`), called by its address: each is
    optimised once, on its own, not again inside every kernel that calls it (the rigid
    bodies' compile from an empty cache: see docs/speed.md). ``cache`` ``(MAX_CONTACTS, 4)``:
    the contacts' rows (their contents need not be kept between steps)."""
    at_flight, at_plane, at_sphere, _, at_resolve = at
    n = len(x)
    for b in range(n):
        if shape[b] == 0:
            call_compiled(at_flight, _sphere_flight, b, x, vel, q, L, inv_mass, inv_body,
                          radius, rest, fric, plane_p, plane_n, g, dt, v_rest, at_resolve)
        else:
            _flight(b, x, vel, q, L, inv_body, g, dt)
    counter = np.zeros(2, np.int64)          # this pass's next row; the rows emptied so far
    for stage in range(2):
        push = stage == 1
        for it in range(iterations):
            counter[0] = 0
            # (a contact's bounce is set on its first pass; a later pass bounces nothing)
            bounce = v_rest if it == 0 else np.inf
            for b in range(n):
                call_compiled(at_plane, _plane_pass, b, x, vel, q, L, inv_mass, inv_body,
                              radius, shape, hull, hull_start, rest, fric, plane_p, plane_n,
                              bounce, push, cache, counter, at_resolve)
                for s in range(len(sphere_c)):
                    call_compiled(at_sphere, _sphere_pass, b, -1, sphere_c[s], sphere_r[s], x,
                                  vel, q, L, inv_mass, inv_body, radius, rest, fric, bounce,
                                  push, cache, counter, at_resolve)
            for a in range(n):
                for b in range(a + 1, n):
                    _pair(a, b, x, vel, q, L, inv_mass, inv_body, radius, shape, hull,
                          hull_start, faces, face_start, rest, fric, bounce, push, cache,
                          counter, at)


def kernels_at(x, vel, q, L, inv_mass, inv_body, radius, shape, hull, hull_start, faces,
               face_start, rest, fric, plane_p, plane_n, g, dt, v_rest) -> tuple:
    """The machine code :func:`step_world` calls for these arrays' types (``at``): the
    sphere's flight, the plane pass, the sphere pass, the hull pass and the contact, each
    typed as step_world calls it (its scratch arrays made here alike)."""
    cache, counter, point = np.empty((0, 4)), np.zeros(2, np.int64), np.zeros(3)
    dt, v_rest = float(dt), float(v_rest)
    resolve = compiled_at(_resolve, (0, 0, point, point, 0.0, 0.0, x, vel, q, L, inv_mass,
                                     inv_body, v_rest, cache, counter))
    flight = compiled_at(_sphere_flight, (0, x, vel, q, L, inv_mass, inv_body, radius, rest,
                                          fric, plane_p, plane_n, g, dt, v_rest, resolve))
    plane = compiled_at(_plane_pass, (0, x, vel, q, L, inv_mass, inv_body, radius, shape, hull,
                                      hull_start, rest, fric, plane_p, plane_n, v_rest, False,
                                      cache, counter, resolve))
    sphere = compiled_at(_sphere_pass, (0, 0, point, 0.0, x, vel, q, L, inv_mass, inv_body,
                                        radius, rest, fric, v_rest, False, cache, counter,
                                        resolve))
    hull_pass = compiled_at(_hull_pass, (0, 0, x, vel, q, L, inv_mass, inv_body, hull,
                                         hull_start, faces, face_start, rest, fric, v_rest,
                                         False, cache, counter, resolve))
    return flight, plane, sphere, hull_pass, resolve


# ---------------------------------------------------------------------- the world


@dataclass
class WorldState:
    """What a :class:`World` is at one step: pickled to a worker as a checkpoint."""

    step_index: int
    x: np.ndarray
    v: np.ndarray
    q: np.ndarray
    L: np.ndarray


@dataclass
class World:
    """Every body of a scene, its colliders and the integrator's settings."""

    bodies: list[Body]
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, -9.8, 0.0]))
    dt: float = DEFAULT_STEP
    iterations: int = 8
    planes: list = field(default_factory=list)       # (point, unit normal)
    spheres: list = field(default_factory=list)      # (center, radius)

    def __post_init__(self) -> None:
        b = self.bodies
        self.inv_mass = np.array([1.0 / body.mass for body in b])
        self.inv_body = np.array([np.linalg.inv(body.inertia) for body in b]).reshape(-1, 3, 3)
        self.radius = np.array([body.radius for body in b], np.float64)
        self.shape = np.array([body.shape for body in b], np.int64)
        self.hull = np.concatenate([body.hull for body in b] + [np.zeros((0, 3))])
        self.hull_start = np.concatenate([[0], np.cumsum([len(body.hull) for body in b])]).astype(np.int64)
        self.faces = np.concatenate([body.faces for body in b] + [np.zeros((0, 4))])
        self.face_start = np.concatenate([[0], np.cumsum([len(body.faces) for body in b])]).astype(np.int64)
        self.rest = np.array([body.restitution for body in b], np.float64)
        self.fric = np.array([body.friction for body in b], np.float64)
        self.plane_p = np.array([p for p, _ in self.planes], np.float64).reshape(-1, 3)
        self.plane_n = np.array([n for _, n in self.planes], np.float64).reshape(-1, 3)
        self.sphere_c = np.array([c for c, _ in self.spheres], np.float64).reshape(-1, 3)
        self.sphere_r = np.array([r for _, r in self.spheres], np.float64)
        self.x0 = np.array([body.center for body in b], np.float64).reshape(-1, 3)
        self.rewind = Rewind()
        self.reset()

    @property
    def v_rest(self) -> float:
        return REST_SPEED_STEPS * float(np.linalg.norm(self.gravity)) * self.dt

    def reset(self) -> None:
        b = self.bodies
        self.step_index = 0
        self.x = self.x0.copy()
        self.v = np.array([body.velocity for body in b], np.float64).reshape(-1, 3)
        self.q = np.tile([1.0, 0.0, 0.0, 0.0], (len(b), 1))
        self.L = np.array([body.inertia @ body.spin for body in b], np.float64).reshape(-1, 3)

    def _arrays(self) -> tuple:
        return (self.x, self.v, self.q, self.L, self.inv_mass, self.inv_body, self.radius,
                self.shape, self.hull, self.hull_start, self.faces, self.face_start, self.rest,
                self.fric, self.plane_p, self.plane_n)

    def scratch(self) -> tuple:
        """What a run of steps shares: the kernels' machine code and the contacts' rows
        (2 MB, allocated once a run: a fresh buffer every step cost a few tenths of a
        millisecond of a step's ~1 ms)."""
        return (kernels_at(*self._arrays(), self.gravity, self.dt, self.v_rest),
                np.empty((MAX_CONTACTS, 4)))

    def step(self, scratch: tuple | None = None) -> None:
        """One step; ``scratch``: :meth:`scratch`'s, when stepping many."""
        at, cache = scratch if scratch is not None else self.scratch()
        step_world(*self._arrays(), self.sphere_c, self.sphere_r, self.gravity,
                   float(self.dt), int(self.iterations), self.v_rest, at, cache)
        self.step_index += 1

    def steps_to(self, t: float) -> int:
        return int(math.floor(t / self.dt + 1e-9))

    def state_at(self, t: float) -> "World":
        """The bodies after the last whole step at or before t (stepping on, or from the
        nearest earlier snapshot: :mod:`core.animation.rewind`)."""
        target = self.steps_to(t)
        if target < self.step_index:
            saved = self.rewind.nearest(target)        # the nearest snapshot, else from 0
            self.restore(saved) if saved is not None else self.reset()
        if self.step_index < target:                   # in chunks, reported
            from core.work import advance              # (here: the kernels keep their lines)
            advance("simulating the rigid bodies", self.step_index, target, self.step_on)
        return self

    def step_on(self, n: int) -> None:
        """n steps on, snapshots noted on the way."""
        scratch = self.scratch()
        for _ in range(n):
            self.rewind.note(self.step_index, self.snapshot)
            self.step(scratch)

    def rotations(self) -> np.ndarray:
        """(N, 3, 3): each body's rotation since t = 0."""
        return np.array([_matrix(q) for q in self.q]).reshape(-1, 3, 3)

    def matrices_at(self, t: float) -> dict[int, np.ndarray]:
        """mesh index → the 4 x 4 that takes its t = 0 pose to its pose at t."""
        self.state_at(t)
        out = {}
        for i, (body, r) in enumerate(zip(self.bodies, self.rotations())):
            m = np.eye(4)
            m[:3, :3] = r
            m[:3, 3] = self.x[i] - r @ self.x0[i]
            for index in body.meshes:
                out[index] = m
        return out

    def energy(self) -> float:
        """Kinetic (translation and rotation) plus potential energy in the gravity field."""
        total = 0.0
        for i, body in enumerate(self.bodies):
            w = _omega(self.q[i], self.inv_body[i], self.L[i])
            total += 0.5 * body.mass * self.v[i] @ self.v[i] + 0.5 * self.L[i] @ w
            total -= body.mass * self.gravity @ self.x[i]
        return float(total)

    def snapshot(self) -> WorldState:
        return WorldState(self.step_index, self.x.copy(), self.v.copy(), self.q.copy(),
                          self.L.copy())

    def restore(self, state: WorldState) -> None:
        self.step_index = state.step_index
        self.x, self.v = state.x.copy(), state.v.copy()
        self.q, self.L = state.q.copy(), state.L.copy()

    def copy(self) -> "World":
        """A second world of the same rules, at the same state (steps on by itself)."""
        other = World(self.bodies, self.gravity, self.dt, self.iterations, self.planes,
                      self.spheres)
        other.restore(self.snapshot())
        return other

    def work_to(self, t: float) -> float:
        """Steps to t times the tests a step makes: what MAX_DYNAMICS_WORK bounds."""
        n = len(self.bodies)
        per_step = n * (n - 1) / 2 + len(self.hull) * max(1, len(self.planes)) \
            + n * (len(self.planes) + len(self.spheres))
        return self.steps_to(t) * per_step * (2 * self.iterations + 1)
