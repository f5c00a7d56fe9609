"""The scene file's ``[[actor]]`` tables → :class:`~core.animation.actors.Group` movers.

::

    [[actor]]
    mesh = "bird"                   # a [[geometry]] name, modelled facing +x
    count = 24                      # copies of it in the group (default 1)
    behaviours = ["flock", "avoid"] # registered behaviours (built-in: flock, avoid, follow)
    position = [0, 2, 0]            # the group's start centre
    spread = 1.5                    # starts in the cube of this half-side (the seed's),
                                    # or [sx, sy, sz] per axis ([2, 0, 2]: on a level)
    velocity = [1, 0, 0]            # at the start, each ± velocity_var per axis (or [x, y, z])
    velocity_var = 0.5
    max_speed = 3.0
    [actor.flock]                   # each behaviour's parameters (defaults otherwise)
    radius = 1.5
    center = [0, 2, 0]
    [actor.avoid]
    planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]
    distance = 1.0
    [actor.follow]
    path = [[0, 0, 0], [2, 0, 0], [2, 0, 2]]    # a closed loop through these
    period = 4.0

Reactive control (core.animation.reactive): a group that senses, and behaviours that react
to what it senses::

    [[actor]]
    name = "fox"                    # other groups name it (default "actor K")
    mesh = "fox"
    behaviours = ["avoid_obstacles", "pursue", "wander"]
    steering = "priority"           # or "sum" (the default): how behaviours combine
    max_force = 6.0                 # the steering acceleration's cap (default: none)
    [actor.senses]
    radius = 4.0                    # perceives within this distance (finite, > 0)
    fov = 120                       # degrees, the whole cone about its heading (360: all round)
    [actor.avoid_obstacles]
    spheres = [{ center = [0, 0, 0], radius = 0.5 }]
    obstacles = ["rock"]            # [[geometry]] names: their bounding spheres
    [actor.pursue]
    target = "rabbits"              # another group's name (or its own)
"""

from __future__ import annotations

import dataclasses

import numpy as np

import math

from core.animation import reactive  # noqa: F401  (registers the reactive behaviours)
from core.animation.actors import (MAX_ACTOR_STEPS, MAX_ACTOR_WORK, MAX_ACTORS, STEP, Group,
                                   Senses, Stage, behaviours)
from core.scene.formats.keys import register_scene_keys

GROUP_KEYS = ("mesh", "count", "behaviours", "position", "spread", "velocity",
              "velocity_var", "max_speed", "name", "senses", "max_force", "steering")
SENSES_KEYS = ("radius", "fov")
STEERING = ("sum", "priority")
MAX_SENSING = 1e6              # a sensing radius beyond this is "everywhere": refused
MAX_OBSTACLES = 256
GROUP_NAMES = {"pursue": "target", "flee": "threat"}    # behaviour → its key naming a group


def read_actors(reader, doc: dict, scene) -> None:
    if "actor" not in doc:
        return
    from core.animation.keys import animation_of
    anim = animation_of(scene)
    if anim is None:
        raise reader.fail(("actor",), "actors need an [animation] table (its duration and fps)")
    tables = reader.tables(doc["actor"], ("actor",))
    total = 0
    groups = []
    for i, table in enumerate(tables):
        group = _group(reader, table, ("actor", i + 1), scene, anim, i)
        if any(g.name == group.name for g in groups):
            raise reader.fail(("actor", i + 1, "name"), f"a second group named {group.name!r}")
        groups.append(group)
        total += len(group.meshes)
        if total > MAX_ACTORS:
            raise reader.fail(("actor", i + 1, "count"), f"{total:,} actors; at most "
                                                         f"{MAX_ACTORS:,}")
        steps = anim.duration / STEP
        if steps > MAX_ACTOR_STEPS:
            raise reader.fail(("actor", i + 1), f"{anim.duration:g} s of actors is "
                              f"{steps:,.0f} steps of {STEP:.4g} s; at most "
                              f"{MAX_ACTOR_STEPS:,} (a shorter animation)")
        if steps * len(group.meshes) ** 2 > MAX_ACTOR_WORK:
            raise reader.fail(("actor", i + 1, "count"),
                              f"{len(group.meshes):,} actors over {steps:,.0f} steps are "
                              f"{steps * len(group.meshes) ** 2:.3g} neighbour tests; at "
                              f"most {MAX_ACTOR_WORK:.3g}")
    _check_names(reader, groups)
    if not any(b.senses for g in groups for b, _ in g.steps):
        anim.movers.extend(groups)
        return
    steps = anim.duration / STEP                  # all groups sense one another: total²
    if steps * total ** 2 > MAX_ACTOR_WORK:
        raise reader.fail(("actor",), f"{total:,} actors that sense one another over "
                                      f"{steps:,.0f} steps are {steps * total ** 2:.3g} "
                                      f"neighbour tests; at most {MAX_ACTOR_WORK:.3g}")
    anim.movers.append(Stage(groups))


def _check_names(reader, groups) -> None:
    """Each ``target`` or ``threat`` names a group of the scene."""
    names = [g.name for g in groups]
    for i, g in enumerate(groups):
        for behaviour, params in g.steps:
            for b, key in GROUP_NAMES.items():
                if behaviour is behaviours()[b] and params[key] not in names:
                    raise reader.fail(("actor", i + 1, b, key),
                                      f"no actor group is named {params[key]!r} (groups: "
                                      f"{', '.join(repr(n) for n in names)})")


def _group(reader, table, path, scene, anim, index) -> Group:
    from core.scene.model import meshes_named
    known = behaviours()
    t = reader.table(table, path, GROUP_KEYS + tuple(known))
    if "mesh" not in t:
        raise reader.fail(path, "an actor needs mesh = NAME (the [[geometry]] it carries)")
    name = reader.string(t["mesh"], path + ("mesh",))
    found = meshes_named(scene, name) if any(m.name == name for m in scene.meshes) else []
    if not found:
        raise reader.fail(path + ("mesh",), f"no geometry is named {name!r}")
    taken = {i for mover in anim.movers for i in mover.matrices_at(0.0)} | set(anim.objects)
    if any(i in taken for i in found):
        raise reader.fail(path + ("mesh",), f"{name!r} is moved already (keyed, a body, a "
                                            "joint's or another actor's): one motion a mesh")
    count = reader.number(t.get("count", 1), path + ("count",), 1, MAX_ACTORS)
    if count != int(count):
        raise reader.fail(path + ("count",), f"expected a whole number, got {count!r}")
    names = t.get("behaviours", [])
    if not isinstance(names, list) or not names:
        raise reader.fail(path + ("behaviours",), "expected a list of behaviours (registered: "
                                                  f"{', '.join(sorted(known))})")
    steps = []
    for k, b in enumerate(names):
        b = reader.choice(b, path + ("behaviours", k + 1), tuple(sorted(known)))
        if b in names[:k]:
            raise reader.fail(path + ("behaviours", k + 1), f"{b!r} is listed twice")
        params = _params(reader, t.get(b, {}), path + (b,), known[b].params, scene)
        if b in GROUP_NAMES and not params[GROUP_NAMES[b]]:
            raise reader.fail(path + (b,), f"{b} needs {GROUP_NAMES[b]} = \"NAME\" (the "
                                           "[[actor]] group it reacts to)")
        steps.append((known[b], params))
    senses = _senses(reader, t, path) if "senses" in t else None
    sensing = [b for b, (behaviour, _) in zip(names, steps) if behaviour.senses]
    if sensing and senses is None:
        raise reader.fail(path, f"{sensing[0]!r} reacts to what the actors sense: give "
                                "[actor.senses] radius = R (and fov = DEGREES)")
    for b in known:
        if b in t and b not in names:
            raise reader.fail(path + (b,), f"parameters for {b!r}, which is not in behaviours")
    meshes = [list(found)]
    for _ in range(int(count) - 1):                 # the copies, drawn as the original
        start = len(scene.meshes)
        scene.meshes.extend(dataclasses.replace(scene.meshes[i]) for i in found)
        meshes.append(list(range(start, len(scene.meshes))))
    points = np.concatenate([scene.meshes[i].positions for i in found])
    pivot = 0.5 * (points.min(axis=0) + points.max(axis=0))
    rng = np.random.default_rng([anim.seed, index])
    n = int(count)
    centre = np.array(reader.vector(t.get("position", list(pivot)), path + ("position",)))
    spread = _per_axis(reader, t.get("spread", 0.0 if n == 1 else 1.0), path + ("spread",))
    v = np.array(reader.vector(t.get("velocity", [0, 0, 0]), path + ("velocity",), 3, -1e6, 1e6))
    var = _per_axis(reader, t.get("velocity_var", 0.0), path + ("velocity_var",))
    return Group(meshes=meshes, pivot=pivot,
                 x0=centre + rng.uniform(-spread, spread, (n, 3)),
                 v0=v + rng.uniform(-var, var, (n, 3)), steps=steps,
                 max_speed=reader.number(t.get("max_speed", 3.0), path + ("max_speed",),
                                         0.0, 1e6, above=0.0),
                 name=reader.string(t.get("name", f"actor {index + 1}"), path + ("name",)),
                 senses=senses,
                 max_force=(reader.number(t["max_force"], path + ("max_force",), 0.0, 1e6,
                                          above=0.0) if "max_force" in t else math.inf),
                 steering=reader.choice(t.get("steering", "sum"), path + ("steering",),
                                        STEERING))


def _per_axis(reader, value, path):
    """A half-width: one number for every axis, or [x, y, z]."""
    if isinstance(value, list):
        return np.array(reader.vector(value, path, 3, 0.0, 1e6))
    return reader.number(value, path, 0.0, 1e6)


def _senses(reader, value, path) -> Senses:
    path = path + ("senses",)
    t = reader.table(value["senses"], path, SENSES_KEYS)
    if "radius" not in t:
        raise reader.fail(path, "senses need a radius (how far the actors perceive)")
    radius = t["radius"]
    if isinstance(radius, (int, float)) and not isinstance(radius, bool):
        if not radius > 0.0 and not math.isnan(radius):
            raise reader.fail(path + ("radius",), f"a sensing radius must be greater than 0 "
                                                  f"(an actor that senses nothing cannot "
                                                  f"react), got {radius:g}")
        if radius > MAX_SENSING:
            raise reader.fail(path + ("radius",), f"a sensing radius is finite (at most "
                                                  f"{MAX_SENSING:g}: an actor senses what is "
                                                  f"near it), got {radius:g}")
    radius = reader.number(radius, path + ("radius",), 0.0, MAX_SENSING, above=0.0)
    fov = t.get("fov", 360.0)
    if isinstance(fov, (int, float)) and not isinstance(fov, bool) and not 0.0 < fov <= 360.0:
        raise reader.fail(path + ("fov",), f"the field of view is the whole angle of a cone "
                                           f"about the heading, in (0, 360] degrees, got {fov:g}")
    return Senses(radius, reader.number(fov, path + ("fov",), 0.0, 360.0, above=0.0))


def _params(reader, table, path, defaults: dict, scene=None) -> dict:
    t = reader.table(table, path, tuple(defaults))
    out = dict(defaults)
    for key, raw in t.items():
        p = path + (key,)
        default = defaults[key]
        if key == "planes":
            out[key] = _planes(reader, raw, p)
        elif key == "spheres":
            out[key] = out[key] + _spheres(reader, raw, p)
        elif key == "obstacles":
            out["spheres"] = list(out["spheres"]) + _obstacles(reader, raw, p, scene)
        elif isinstance(default, bool):
            out[key] = reader.boolean(raw, p)
        elif isinstance(default, str):
            out[key] = reader.string(raw, p)
        elif key == "path":
            points = [reader.vector(v, p + (k + 1,)) for k, v in enumerate(raw if isinstance(raw, list) else [None])]
            if len(points) < 3:
                raise reader.fail(p, "a path needs at least 3 points (a closed loop through them)")
            out[key] = np.array(points)
        elif isinstance(default, (list, tuple)) and len(default) == 3:
            out[key] = np.array(reader.vector(raw, p))
        elif isinstance(default, (int, float)):
            out[key] = reader.number(raw, p, -1e6, 1e6)
        else:
            out[key] = raw
    for key in ("radius", "distance", "period", "reaction", "acceleration"):
        if key in out and not out[key] > 0.0:
            raise reader.fail(path + (key,), f"{key} must be greater than 0, got {out[key]:g}")
    for key in ("clearance", "prediction"):
        if key in out and not out[key] >= 0.0:
            raise reader.fail(path + (key,), f"{key} must be 0 or more, got {out[key]:g}")
    if len(out.get("spheres", ())) > MAX_OBSTACLES:
        raise reader.fail(path, f"{len(out['spheres'])} obstacles; at most {MAX_OBSTACLES}")
    if "path" in out and len(out["path"]) < 3:
        raise reader.fail(path + ("path",), "follow needs a path of at least 3 points")
    return out


def _spheres(reader, value, path) -> list:
    out = []
    for k, sphere in enumerate(reader.tables(value, path)):
        p = path + (k + 1,)
        t = reader.table(sphere, p, ("center", "radius"))
        if "center" not in t or "radius" not in t:
            raise reader.fail(p, "an obstacle sphere needs a center and a radius")
        out.append((np.array(reader.vector(t["center"], p + ("center",))),
                    reader.number(t["radius"], p + ("radius",), 0.0, 1e6, above=0.0)))
    return out


def _obstacles(reader, value, path, scene) -> list:
    """Named [[geometry]] as obstacles: each one's bounding sphere (the middle of its box,
    out to its farthest vertex), where the file places it."""
    from core.scene.model import meshes_named
    if not isinstance(value, list):
        raise reader.fail(path, "expected a list of [[geometry]] names")
    out = []
    for k, name in enumerate(value):
        name = reader.string(name, path + (k + 1,))
        found = meshes_named(scene, name) if any(m.name == name for m in scene.meshes) else []
        if not found:
            raise reader.fail(path + (k + 1,), f"no geometry is named {name!r}")
        points = np.concatenate([scene.meshes[i].positions for i in found])
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        out.append((centre, float(np.linalg.norm(points - centre, axis=1).max())))
    return out


def _planes(reader, value, path) -> list:
    out = []
    for k, plane in enumerate(reader.tables(value, path)):
        p = path + (k + 1,)
        t = reader.table(plane, p, ("point", "normal"))
        normal = np.array(reader.vector(t.get("normal", [0, 1, 0]), p + ("normal",)))
        if not np.linalg.norm(normal) > 0.0:
            raise reader.fail(p + ("normal",), "the plane's normal is the zero vector")
        out.append((np.array(reader.vector(t.get("point", [0, 0, 0]), p + ("point",))),
                    normal / np.linalg.norm(normal)))
    return out


register_scene_keys("actors", ("actor",), read_actors, arrays=("actor",))
