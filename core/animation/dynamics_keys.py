"""The scene file's ``[dynamics]`` and ``[[body]]`` tables → a :class:`~core.animation.dynamics.World`.

::

    [dynamics]
    gravity = [0, -9.8, 0]          # m/s² (the default)
    step = 0.004166667              # seconds a step, fixed whatever the fps (default 1/240)
    iterations = 8                  # contact passes a step
    planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]       # static, infinite
    spheres = [{ center = [2, 1, 0], radius = 0.5 }]           # static

    [[body]]
    mesh = "ball"                   # a [[geometry]] name: its meshes move as one rigid body
    mass = 1.0                      # > 0; the inertia comes from the closed mesh
    velocity = [1, 0, 0]            # at t = 0
    spin = [0, 0, 90]               # angular velocity at t = 0, degrees per second
    restitution = 0.5               # e, 0 to 1 (two bodies: the geometric mean of theirs)
    friction = 0.3                  # Coulomb's μ
    shape = "sphere"                # "sphere" (the default for a sphere primitive) or "hull"

A body's pose at t = 0 is the file's; its mesh must not also be keyed. The file needs an
``[animation]`` table (its duration and fps say how far the bodies are simulated).
"""

from __future__ import annotations

import math

import numpy as np

from core.animation.dynamics import (DEFAULT_STEP, HULL, MAX_BODIES, MAX_DYNAMICS_WORK,
                                     MAX_HULL_VERTICES, MAX_SIMULATION_STEPS, MIN_STEP, SHAPES,
                                     SPHERE, Body, World, face_planes,
                                     mass_properties)
from core.scene.formats.keys import register_scene_keys

TOP_KEYS = ("dynamics", "body")
DYNAMICS_KEYS = ("gravity", "step", "iterations", "planes", "spheres")
BODY_KEYS = ("mesh", "mass", "velocity", "spin", "restitution", "friction", "shape")
MIN_MASS = 1e-9                  # a mass whose inertia (mass x size²) still has an inverse
MAX_MASS = 1e12
START_GAP = 1e-9            # overlaps at t = 0 deeper than this (relative to the size) refuse


def read_dynamics(reader, doc: dict, scene) -> None:
    if not any(k in doc for k in TOP_KEYS):
        return
    from core.animation.keys import animation_of
    anim = animation_of(scene)
    if anim is None:
        raise reader.fail(("body",), "rigid bodies need an [animation] table: its duration "
                                     "and fps say how far they are simulated")
    settings = reader.table(doc.get("dynamics", {}), ("dynamics",), DYNAMICS_KEYS)
    tables = reader.tables(doc.get("body", []), ("body",))
    if len(tables) > MAX_BODIES:
        raise reader.fail(("body",), f"{len(tables):,} bodies; at most {MAX_BODIES:,} (every "
                                     "pair of bodies is tested for contact every step)")
    if not tables:
        raise reader.fail(("dynamics",), "a [dynamics] table without any [[body]] to move")
    world = World(bodies=[_body(reader, t, ("body", i + 1), scene, anim, tables)
                          for i, t in enumerate(tables)],
                  gravity=np.array(reader.vector(settings.get("gravity", [0, -9.8, 0]),
                                                 ("dynamics", "gravity"), 3, -1e6, 1e6)),
                  dt=_step(reader, settings, anim),
                  iterations=int(_whole(reader, settings.get("iterations", 8),
                                        ("dynamics", "iterations"), 1, 100)),
                  planes=_planes(reader, settings.get("planes", [])),
                  spheres=_spheres(reader, settings.get("spheres", [])))
    _check_budget(reader, world, anim)
    _check_apart(reader, world)
    anim.movers.append(world)


def _whole(reader, value, path, low, high) -> float:
    n = reader.number(value, path, low, high)
    if n != int(n):
        raise reader.fail(path, f"expected a whole number, got {value!r}")
    return n


def _step(reader, settings: dict, anim) -> float:
    path = ("dynamics", "step")
    dt = reader.number(settings.get("step", DEFAULT_STEP), path)
    frame = 1.0 / anim.fps
    if not dt > 0.0:
        raise reader.fail(path, f"the time step must be a positive number of seconds, got {dt:g}")
    if dt > frame:
        raise reader.fail(path, f"a step of {dt:g} s is longer than a frame (1/fps = "
                                f"{frame:.6g} s): frames between two steps would all show "
                                "the same state; take a step at most one frame long")
    if dt < MIN_STEP:
        raise reader.fail(path, f"a step of {dt:g} s is below {MIN_STEP:g} s (over "
                                f"{1 / MIN_STEP:,.0f} steps a simulated second)")
    return dt


def _planes(reader, value) -> list:
    out = []
    for i, t in enumerate(reader.tables(value, ("dynamics", "planes"))):
        path = ("dynamics", "planes", i + 1)
        t = reader.table(t, path, ("point", "normal"))
        normal = np.array(reader.vector(t.get("normal", [0, 1, 0]), path + ("normal",)))
        if not np.linalg.norm(normal) > 0.0:
            raise reader.fail(path + ("normal",), "the plane's normal is the zero vector")
        out.append((np.array(reader.vector(t.get("point", [0, 0, 0]), path + ("point",))),
                    normal / np.linalg.norm(normal)))
    return out


def _spheres(reader, value) -> list:
    out = []
    for i, t in enumerate(reader.tables(value, ("dynamics", "spheres"))):
        path = ("dynamics", "spheres", i + 1)
        t = reader.table(t, path, ("center", "radius"))
        radius = reader.number(t.get("radius", 1.0), path + ("radius",), 0.0, 1e6, above=0.0)
        out.append((np.array(reader.vector(t.get("center", [0, 0, 0]), path + ("center",))),
                    radius))
    return out


def _body(reader, table, path, scene, anim, tables) -> Body:
    from core.scene.model import meshes_named
    from core.scene.primitives import Sphere
    t = reader.table(table, path, BODY_KEYS)
    if "mesh" not in t:
        raise reader.fail(path, "a body needs mesh = NAME (the [[geometry]] it moves)")
    name = reader.string(t["mesh"], path + ("mesh",))
    indices = meshes_named(scene, name) if any(m.name == name for m in scene.meshes) else []
    if not indices:
        raise reader.fail(path + ("mesh",), f"no geometry is named {name!r} (names: "
                                            f"{', '.join(sorted({m.name for m in scene.meshes}))})")
    if sum(1 for other in tables if isinstance(other, dict) and other.get("mesh") == name) > 1:
        raise reader.fail(path + ("mesh",), f"{name!r} is the mesh of more than one body")
    if any(i in anim.objects for i in indices):
        raise reader.fail(path + ("mesh",), f"{name!r} is keyed ([[key]] object.{name}) and a "
                                            "body: its motion comes from one or the other")
    mass = reader.number(t.get("mass", 1.0), path + ("mass",), -math.inf, MAX_MASS)
    if not mass >= MIN_MASS:         # 5e-324 is > 0, and its inertia has no inverse
        raise reader.fail(path + ("mass",), f"a body's mass must be at least {MIN_MASS:g}, "
                                            f"got {mass:g}")
    meshes = [scene.meshes[i] for i in indices]
    primitive = meshes[0].tessellates if isinstance(meshes[0].tessellates, Sphere) else None
    shape = reader.choice(t.get("shape", "sphere" if primitive else "hull"), path + ("shape",),
                          SHAPES)
    if primitive is not None:
        center, radius = np.array(primitive.center, np.float64), float(primitive.radius)
        inertia = 0.4 * mass * radius ** 2 * np.eye(3)
        hull, faces = np.zeros((0, 3)), np.zeros((0, 4))
    else:
        center, inertia, hull, faces = _solid(reader, meshes, mass, path + ("mesh",), name)
        radius = float(np.max(np.linalg.norm(hull, axis=1)))
    body = Body(name=name, meshes=list(indices), mass=mass, center=center, inertia=inertia,
                radius=radius, hull=hull if shape == "hull" else np.zeros((0, 3)),
                shape=HULL if shape == "hull" else SPHERE,
                faces=faces if shape == "hull" else np.zeros((0, 4)),
                velocity=np.array(reader.vector(t.get("velocity", [0, 0, 0]), path + ("velocity",),
                                                3, -1e6, 1e6)),
                spin=np.radians(reader.vector(t.get("spin", [0, 0, 0]), path + ("spin",), 3,
                                              -1e7, 1e7)),
                restitution=reader.number(t.get("restitution", 0.5), path + ("restitution",), 0.0, 1.0),
                friction=reader.number(t.get("friction", 0.3), path + ("friction",), 0.0, 10.0))
    if shape == "hull" and primitive is not None:
        raise reader.fail(path + ("shape",), f"{name!r} is a sphere primitive: it has no "
                                             "vertices to collide with (shape = \"sphere\")")
    return body


def _solid(reader, meshes, mass, path, name):
    """(centre of mass, inertia, hull vertices about the centre) of the meshes as one solid."""
    if not all(m.closed for m in meshes) or not all(len(m.triangles) for m in meshes):
        raise reader.fail(path, f"{name!r} is not a closed mesh: a body's mass properties "
                                "need a closed, outward-wound solid")
    base = np.cumsum([0] + [len(m.positions) for m in meshes[:-1]])
    positions = np.concatenate([m.positions for m in meshes])
    triangles = np.concatenate([m.triangles + b for m, b in zip(meshes, base)])
    volume, centroid, unit = mass_properties(positions, triangles)
    if not volume > 0.0:
        raise reader.fail(path, f"{name!r} encloses no volume ({volume:.3g}: flat, or wound "
                                "inside out) and so has no inertia")
    points = _contact_points(positions, triangles) - centroid
    if len(points) > MAX_HULL_VERTICES:
        raise reader.fail(path, f"{name!r} has {len(points):,} contact points (vertices and "
                                f"points along the edges); a hull body has at most "
                                f"{MAX_HULL_VERTICES:,} (use a coarser mesh or shape = "
                                "\"sphere\")")
    return centroid, unit * (mass / volume), points, face_planes(points, positions - centroid,
                                                                 triangles)


EDGE_POINTS = (0.25, 0.5, 0.75)   # along each edge too: where two boxes meet edge on edge,
                                  # no corner of either is inside the other


def _contact_points(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The points a hull body collides by: its vertices and points along its edges."""
    edges = np.unique(np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                              triangles[:, [2, 0]]]), axis=1), axis=0)
    a, b = positions[edges[:, 0]], positions[edges[:, 1]]
    along = [a + f * (b - a) for f in EDGE_POINTS]
    return np.unique(np.concatenate([positions] + along), axis=0)


def _check_budget(reader, world: World, anim) -> None:
    steps = world.steps_to(anim.duration)
    if steps > MAX_SIMULATION_STEPS:
        raise reader.fail(("dynamics", "step"), f"duration / step = {steps:,} steps; at most "
                                                f"{MAX_SIMULATION_STEPS:,} (a longer step or a "
                                                "shorter animation)")
    work = world.work_to(anim.duration)
    if work > MAX_DYNAMICS_WORK:
        raise reader.fail(("body",), f"{len(world.bodies):,} bodies over {steps:,} steps are "
                                     f"{work:.3g} contact tests; at most {MAX_DYNAMICS_WORK:.3g} "
                                     "(fewer bodies, a longer step or a shorter animation)")


def _check_apart(reader, world: World) -> None:
    """No body starts inside a plane, a static sphere or another body (the impulses would
    fling them apart on the first step)."""
    x, r = world.x0, world.radius
    for i, body in enumerate(world.bodies):
        path = ("body", i + 1)
        tol = START_GAP * max(1.0, body.radius)
        for k, (point, normal) in enumerate(world.planes):
            low = (np.min(body.hull @ normal) if body.shape == HULL else -body.radius)
            if (x[i] - point) @ normal + low < -tol:
                raise reader.fail(path, f"{body.name!r} starts through plane {k + 1} of "
                                        "[dynamics] planes (it must start on or above it)")
        for k, (center, radius) in enumerate(world.spheres):
            if np.linalg.norm(x[i] - center) < r[i] + radius - tol:
                raise reader.fail(path, f"{body.name!r} starts inside sphere {k + 1} of "
                                        "[dynamics] spheres (their bounding spheres overlap)")
    if len(x) > 1:
        gap = np.linalg.norm(x[:, None] - x[None], axis=2) - (r[:, None] + r[None])
        gap[np.tril_indices(len(x))] = np.inf
        for i, j in zip(*np.nonzero(gap < -START_GAP * np.maximum(1.0, np.maximum(r[:, None], r[None])))):
            a, b = world.bodies[i], world.bodies[j]
            if len(a.faces) and len(b.faces):          # convex: by vertices against faces
                depth = max(_inside(a.hull + x[i] - x[j], b.faces),
                            _inside(b.hull + x[j] - x[i], a.faces))
                if depth <= START_GAP * max(1.0, r[i], r[j]):
                    continue
                what = f"a corner of one is {depth:.3g} inside the other"
            else:
                what = f"their bounding spheres overlap by {-gap[i, j]:.3g}"
            raise reader.fail(("body", int(j) + 1), f"{b.name!r} starts inside {a.name!r} "
                                                    f"({what}); move them apart")


def _inside(points: np.ndarray, faces: np.ndarray) -> float:
    """How deep the deepest of ``points`` is inside the convex solid of ``faces`` (0: none)."""
    gaps = np.max(points @ faces[:, :3].T - faces[:, 3], axis=1)
    return float(max(0.0, -gaps.min()))


register_scene_keys("dynamics", TOP_KEYS, read_dynamics, arrays=("body",))
