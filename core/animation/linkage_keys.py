"""The scene file's ``[[linkage]]`` tables → :class:`~core.animation.linkage.Linkage` movers.

::

    [[linkage]]
    name = "arm"
    base = [0, 0, 0]                # where the root joints are
    solver = "dls"                  # "dls" (damped least squares, the default) or "ccd"
    effector = "wrist"              # the joint whose bone's end reaches (default: the last)
    interpolation = "catmull-rom"   # of the keyed targets and angles (as [animation]'s)
    [[linkage.joint]]
    name = "shoulder"
    axis = [0, 0, 1]                # turns about this (the rest frame; not zero)
    bone = [1, 0, 0]                # to the next joint, at rest (not zero)
    min = -90                       # degrees from the rest pose (default -180)
    max = 90                        # (default 180)
    meshes = ["upper arm"]          # [[geometry]] names it carries
    parent = "..."                  # (default: the joint before it; the first: the root)
    [[linkage.key]]
    time = 0
    target = [1.2, 0.8, 0]          # inverse kinematics to this point ...
    angles = { shoulder = 30 }      # ... from these angles (degrees; unnamed joints: 0)

The meshes are modelled in the rest pose (every angle 0). A joint angle about its one
axis in-betweened by a quaternion slerp is the angle in-betweened linearly (the arc of a
single-axis rotation is its angle), so angles are keyed as numbers.
"""

from __future__ import annotations

import math

import numpy as np

from core.animation.linkage import SOLVERS, Linkage
from core.scene.formats.keys import register_scene_keys

LINKAGE_KEYS = ("name", "base", "solver", "effector", "interpolation", "damping", "joint", "key",
                "gravity", "load")
JOINT_KEYS = ("name", "axis", "bone", "min", "max", "meshes", "parent", "mass", "center",
              "inertia")
KEY_KEYS = ("time", "target", "angles")
MAX_JOINTS = 256
MAX_SCENE_JOINTS = 1024         # all linkages together: measured 0.17 s a frame here (IK)


def read_linkages(reader, doc: dict, scene) -> None:
    if "linkage" not in doc:
        return
    from core.animation.keys import animation_of
    anim = animation_of(scene)
    if anim is None:
        raise reader.fail(("linkage",), "a linkage needs an [animation] table (its duration "
                                        "and fps)")
    taken = {i for mover in anim.movers for i in mover.matrices_at(0.0)}
    joints = 0
    for i, table in enumerate(reader.tables(doc["linkage"], ("linkage",))):
        linkage = read_linkage(reader, table, ("linkage", i + 1), scene, anim, taken)
        joints += len(linkage.parent)
        if joints > MAX_SCENE_JOINTS:       # each frame solves every joint
            raise reader.fail(("linkage", i + 1), f"{joints:,} joints in the scene's linkages "
                                                  f"by here; at most {MAX_SCENE_JOINTS:,} (a "
                                                  f"frame solves every one)")
        taken |= {m for meshes in linkage.carried for m in meshes}
        anim.movers.append(linkage)


def read_linkage(reader, table, path, scene, anim, taken) -> Linkage:
    from core.animation.tracks import METHODS
    t = reader.table(table, path, LINKAGE_KEYS)
    name = reader.string(t.get("name", f"linkage {path[1]}"), path + ("name",))
    joints = reader.tables(t.get("joint", []), path + ("joint",))
    if not joints:
        raise reader.fail(path, "a linkage needs at least one [[linkage.joint]]")
    if len(joints) > MAX_JOINTS:
        raise reader.fail(path + ("joint",), f"{len(joints)} joints; at most {MAX_JOINTS}")
    names = [reader.string(j.get("name", f"joint {k + 1}"), path + ("joint", k + 1, "name"))
             for k, j in enumerate(joints)]
    for k, n in enumerate(names):
        if names.index(n) != k:
            raise reader.fail(path + ("joint", k + 1, "name"), f"a second joint named {n!r}")
    parent = _parents(reader, joints, names, path)
    order = _order(reader, parent, names, path)
    fields = [_joint(reader, joints[k], path + ("joint", k + 1), scene, anim, taken)
              for k in order]
    index = {k: n for n, k in enumerate(order)}                 # file order → parents first
    parents = [index[parent[k]] if parent[k] >= 0 else -1 for k in order]
    effector_name = reader.string(t.get("effector", names[-1]), path + ("effector",))
    if effector_name not in names:
        raise reader.fail(path + ("effector",), f"no joint is named {effector_name!r} "
                                                f"(joints: {', '.join(names)})")
    method = reader.choice(t.get("interpolation", "catmull-rom"), path + ("interpolation",), METHODS)
    angles, target = _tracks(reader, t.get("key", []), path, [names[k] for k in order], method)
    lo = [f[2] for f in fields]
    hi = [f[3] for f in fields]
    linkage = Linkage(name, reader.vector(t.get("base", [0, 0, 0]), path + ("base",)), parents,
                   [f[0] for f in fields], [f[1] for f in fields], lo, hi,
                   [f[4] for f in fields], index[names.index(effector_name)],
                   SOLVERS.index(reader.choice(t.get("solver", "dls"), path + ("solver",), SOLVERS)),
                   reader.number(t.get("damping", 0.5), path + ("damping",), 1e-6, 1e3),
                   angles, target)
    linkage.masses = read_masses(reader, t, [joints[k] for k in order], path, order, fields)
    linkage.key_times = _key_times(t.get("key", []))
    linkage.joint_names = [names[k] for k in order]
    linkage.key_places = _key_places(reader, t.get("key", []), path)
    if linkage.masses is not None:
        _check_smooth(reader, t.get("key", []), path, [names[k] for k in order],
                      {"angles": angles, "target": target})
    return linkage


def read_masses(reader, t, joints, path, order, fields):
    """The links' masses for inverse dynamics (core.animation.inverse_dynamics), or None when
    no joint has a ``mass`` and the linkage holds no ``load``."""
    from core.animation.inverse_dynamics import GRAVITY, LinkMasses, rod_inertia
    if "load" not in t and not any("mass" in j for j in joints):
        return None
    mass, center, inertia = [], [], []
    for j, k, field in zip(joints, order, fields):
        p = path + ("joint", k + 1)
        bone = field[1]
        m = reader.number(j.get("mass", 0.0), p + ("mass",), 0.0, 1e9)
        mass.append(m)
        center.append(reader.vector(j.get("center", list(bone / 2)), p + ("center",)))
        inertia.append(_inertia(reader, j["inertia"], p + ("inertia",)) if "inertia" in j
                       else rod_inertia(m, bone))
    return LinkMasses(np.array(mass), np.array(center, np.float64), np.array(inertia),
                      reader.number(t.get("load", 0.0), path + ("load",), 0.0, 1e9),
                      np.array(reader.vector(t.get("gravity", list(GRAVITY)), path + ("gravity",))))


def _inertia(reader, value, path) -> np.ndarray:
    """``inertia = k`` (k I: 0 for a point mass, 2/5 m r² for a ball) or a symmetric 3 x 3."""
    if not isinstance(value, list):
        return reader.number(value, path, 0.0, 1e12) * np.eye(3)
    if len(value) != 3:
        raise reader.fail(path, "expected a number or a 3 x 3 list of rows")
    rows = np.array([reader.vector(row, path + (i + 1,)) for i, row in enumerate(value)])
    if not np.allclose(rows, rows.T, rtol=0, atol=1e-12 * (1 + np.abs(rows).max())):
        raise reader.fail(path, "an inertia tensor is symmetric (row i, column j equals row j, "
                                "column i)")
    return rows


def _key_times(keys) -> list[float]:
    """Every key time, sorted: where the keyed motion may change its curve."""
    return sorted({float(k["time"]) for k in keys if isinstance(k, dict) and "time" in k})


def _key_places(reader, keys, path) -> list[tuple[float, str]]:
    """(time, "file:line: linkage[i].key[k]") of each key: plain text, so a linkage that
    travels to a worker process carries no reader."""
    from core.scene.formats.errors import path_text
    out = []
    for k, key in enumerate(keys):
        p = path + ("key", k + 1)
        line = reader.locate(p)
        out.append((float(key["time"]), f"{reader.file}{'' if line is None else f':{line}'}: "
                                        f"{path_text(p)}"))
    return sorted(out)


def _check_smooth(reader, keys, path, names, tracks) -> None:
    """A linkage with masses must move with continuous rates: a keyed corner (a rate that
    changes at once, as linear keys do) is an impulse, which no finite torque gives."""
    from core.animation.inverse_dynamics import corner
    from core.animation.tracks import Track
    for what, track in tracks.items():
        if not isinstance(track, Track):
            continue
        times = track.times
        where = sorted((float(k["time"]), i) for i, k in enumerate(keys) if what in k)
        for i in range(1, len(times) - 1):
            gap = min(times[i] - times[i - 1], times[i + 1] - times[i])
            before, after = corner(track, times[i], gap)
            jump = np.abs(after - before)
            worst = int(np.argmax(jump))
            if jump[worst] > 1e-5 * (1.0 + max(np.abs(before).max(), np.abs(after).max())):
                label = (f"the angle of {names[worst]!r} changes its rate from "
                         f"{np.degrees(before[worst]):.4g} to {np.degrees(after[worst]):.4g} deg/s"
                         if what == "angles" else
                         f"the target's {'xyz'[worst]} changes its speed from "
                         f"{before[worst]:.4g} to {after[worst]:.4g} m/s")
                raise reader.fail(path + ("key", where[i][1] + 1),
                                  f"the keyed motion turns a corner at t = {times[i]:g} s ({label} "
                                  "at once): that is an impulse, and no finite torque makes it; "
                                  "a linkage with masses needs smooth keys (interpolation = "
                                  "\"catmull-rom\" or \"ease\")")


def _parents(reader, joints, names, path) -> list[int]:
    out = []
    for k, j in enumerate(joints):
        if "parent" not in j:
            out.append(k - 1)
            continue
        p = reader.string(j["parent"], path + ("joint", k + 1, "parent"))
        if p not in names:
            raise reader.fail(path + ("joint", k + 1, "parent"),
                              f"no joint is named {p!r} (joints: {', '.join(names)})")
        out.append(names.index(p))
    return out


def _order(reader, parent, names, path) -> list[int]:
    """The joints parents first; a chain of parents that comes back to a joint is refused."""
    order, placed = [], set()
    for k in range(len(parent)):
        trail, j = [], k
        while j >= 0 and j not in placed:
            if j in trail:
                loop = trail[trail.index(j):] + [j]
                raise reader.fail(path + ("joint", j + 1, "parent"),
                                  "the joints' parents make a cycle ("
                                  + " → ".join(names[i] for i in loop)
                                  + "): a linkage is a tree, each joint hanging from one parent")
            trail.append(j)
            j = parent[j]
        for j in reversed(trail):
            order.append(j)
            placed.add(j)
    return order


def _joint(reader, j, path, scene, anim, taken):
    from core.scene.model import meshes_named
    j = reader.table(j, path, JOINT_KEYS)
    axis = np.array(reader.vector(j.get("axis", [0, 0, 1]), path + ("axis",)))
    if not np.linalg.norm(axis) > 0.0:
        raise reader.fail(path + ("axis",), "the joint's axis is the zero vector: it turns "
                                            "about no direction")
    bone = np.array(reader.vector(j.get("bone", [1, 0, 0]), path + ("bone",)))
    if not np.linalg.norm(bone) > 1e-9:
        raise reader.fail(path + ("bone",), "the bone has zero length: the joint after it "
                                            "would sit on this one (give it a length)")
    lo = reader.number(j.get("min", -180.0), path + ("min",), -360.0, 360.0)
    hi = reader.number(j.get("max", 180.0), path + ("max",), -360.0, 360.0)
    if lo > 0.0 or hi < 0.0 or lo > hi:
        raise reader.fail(path, f"the limits [{lo:g}, {hi:g}] degrees must hold the rest pose "
                                "(min <= 0 <= max)")
    carried = []
    for k, mesh in enumerate(j.get("meshes", []) if isinstance(j.get("meshes", []), list)
                             else [None]):
        p = path + ("meshes", k + 1)
        name = reader.string(mesh, p)
        found = meshes_named(scene, name) if any(m.name == name for m in scene.meshes) else []
        if not found:
            raise reader.fail(p, f"no geometry is named {name!r}")
        if any(i in taken or i in anim.objects for i in found):
            raise reader.fail(p, f"{name!r} is moved already (keyed, a body or another "
                                 "joint's): one motion a mesh")
        taken |= set(found)
        carried.extend(found)
    return axis / np.linalg.norm(axis), bone, math.radians(lo), math.radians(hi), carried


def _tracks(reader, keys, path, names, method):
    """(angles track, target track) from the ``[[linkage.key]]`` tables (None: not keyed)."""
    from core.animation.keys import MAX_DURATION
    from core.animation.tracks import Track
    angles, targets = [], []
    for k, key in enumerate(reader.tables(keys, path + ("key",))):
        p = path + ("key", k + 1)
        key = reader.table(key, p, KEY_KEYS)
        if "time" not in key:
            raise reader.fail(p, "a key needs a time (seconds)")
        time = reader.number(key["time"], p + ("time",), 0.0, MAX_DURATION)
        if "target" in key:
            targets.append((time, reader.vector(key["target"], p + ("target",)), p))
        if "angles" in key:
            given = reader.table(key["angles"], p + ("angles",), tuple(names))
            angles.append((time, [math.radians(reader.number(given.get(n, 0.0),
                                                             p + ("angles", n), -360.0, 360.0))
                                  for n in names], p))
    out = []
    for keyed in (angles, targets):
        keyed.sort(key=lambda k: k[0])
        for (t0, _, _), (t1, _, p1) in zip(keyed, keyed[1:]):
            if t1 == t0:
                raise reader.fail(p1, f"a second key at time {t1:g}")
        if not keyed:
            out.append(None)
        elif len(keyed) == 1:
            value = np.array(keyed[0][1], np.float64)
            out.append(lambda t, v=value: v.copy())
        else:
            out.append(Track([k[0] for k in keyed], [k[1] for k in keyed], method))
    return out[0], out[1]


register_scene_keys("linkage", ("linkage",), read_linkages, arrays=("linkage",))
