"""The scene file's ``[[actor]]`` tables → :class:`~core.animation.actors.Group` movers.

::

    [[actor]]
    mesh = "bird"                   # a [[geometry]] name, modelled facing +x
    count = 24                      # copies of it in the group (default 1)
    behaviours = ["flock", "avoid"] # registered behaviours (built-in: flock, avoid, follow)
    position = [0, 2, 0]            # the group's start centre
    spread = 1.5                    # starts in the cube of this half-side (the seed's)
    velocity = [1, 0, 0]            # at the start, each ± velocity_var per axis
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
"""

from __future__ import annotations

import dataclasses

import numpy as np

from core.animation.actors import (MAX_ACTOR_STEPS, MAX_ACTOR_WORK, MAX_ACTORS, STEP, Group,
                                   behaviours)
from core.scene.formats.keys import register_scene_keys

GROUP_KEYS = ("mesh", "count", "behaviours", "position", "spread", "velocity",
              "velocity_var", "max_speed")


def read_actors(reader, doc: dict, scene) -> None:
    if "actor" not in doc:
        return
    from core.animation.keys import animation_of
    anim = animation_of(scene)
    if anim is None:
        raise reader.fail(("actor",), "actors need an [animation] table (its duration and fps)")
    tables = reader.tables(doc["actor"], ("actor",))
    total = 0
    for i, table in enumerate(tables):
        group = _group(reader, table, ("actor", i + 1), scene, anim, i)
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
        anim.movers.append(group)


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
        steps.append((known[b], _params(reader, t.get(b, {}), path + (b,), known[b].params)))
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
    spread = reader.number(t.get("spread", 0.0 if n == 1 else 1.0), path + ("spread",), 0.0, 1e6)
    v = np.array(reader.vector(t.get("velocity", [0, 0, 0]), path + ("velocity",), 3, -1e6, 1e6))
    var = reader.number(t.get("velocity_var", 0.0), path + ("velocity_var",), 0.0, 1e6)
    return Group(meshes=meshes, pivot=pivot,
                 x0=centre + rng.uniform(-spread, spread, (n, 3)),
                 v0=v + rng.uniform(-var, var, (n, 3)), steps=steps,
                 max_speed=reader.number(t.get("max_speed", 3.0), path + ("max_speed",),
                                         0.0, 1e6, above=0.0))


def _params(reader, table, path, defaults: dict) -> dict:
    t = reader.table(table, path, tuple(defaults))
    out = dict(defaults)
    for key, raw in t.items():
        p = path + (key,)
        default = defaults[key]
        if key == "planes":
            out[key] = _planes(reader, raw, p)
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
    for key in ("radius", "distance", "period"):
        if key in out and not out[key] > 0.0:
            raise reader.fail(path + (key,), f"{key} must be greater than 0, got {out[key]:g}")
    if "path" in out and len(out["path"]) < 3:
        raise reader.fail(path + ("path",), "follow needs a path of at least 3 points")
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
