"""The scene file's ``[[mocap]]`` tables → :class:`~core.animation.mocap.Figure` movers.

::

    [[mocap]]
    name = "walker"                 # the limbs' mesh names are NAME.JOINT
    file = "mocap/walk.bvh"         # a BVH file, relative to this scene file
    position = [0, 0, 0]            # G = T(position) · R(rotate) · S(scale), the take into
    rotate = [0, 0, 0]              # the scene (degrees, as a geometry's transform turns)
    scale = 0.01                    # the file's units to the scene's (centimetres → metres)
    start = 0.0                     # the scene time of the take's first frame (held before)
    speed = 1.0                     # the take's seconds per scene second
    loop = true                     # the take repeats (else it holds its ends)
    interpolation = "linear"        # between the take's frames: slerp and lerp, or "step"
    limb = "cylinder"               # or "box": the prism along each bone
    segments = 10                   # a cylinder's sides
    radius = 0.035                  # the limbs' (scene units; default: 2.5 % of the figure)
    radii = { Head = 0.09 }         # a joint's own limbs (those from it to its children)
    joint_radius = 0.04             # the sphere at each joint (0: none; default: its limbs')
    material = { od = [0.8, 0.6, 0.3] }
    materials = { LeftHip = { od = [0.3, 0.5, 0.9] } }   # a joint and all below it

Without an ``[animation]`` table one is made: the take's length (over ``speed``, after
``start``) at 30 frames a second, looping; an ``[animation]`` without a ``duration`` gets that
length too.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from core.animation.bvh import load_bvh
from core.animation.mocap import INTERPOLATIONS, Figure, default_material, limbs, subtree_values
from core.scene.formats.keys import register_scene_keys

MOCAP_KEYS = ("name", "file", "position", "rotate", "scale", "start", "speed", "loop",
              "interpolation", "limb", "segments", "radius", "radii", "joint_radius",
              "material", "materials")
LIMBS = {"box": 4, "cylinder": None}
MAX_FIGURES = 16
RADIUS_SHARE = 0.025            # the default limb radius: of the pose's bounding-box diagonal


def read_mocap(reader, doc: dict, scene) -> None:
    if "mocap" not in doc:
        return
    from core.animation.keys import animation_of, attach
    from core.animation.animation import Animation
    from core.scene.generators import MAX_TRIANGLES
    tables = reader.tables(doc["mocap"], ("mocap",))
    if len(tables) > MAX_FIGURES:
        raise reader.fail(("mocap",), f"{len(tables)} figures; at most {MAX_FIGURES}")
    anim = animation_of(scene)
    made = anim is None
    if made:
        anim = Animation(scene=scene, fps=30.0, loop=True)
    keyed_duration = isinstance(doc.get("animation"), dict) and "duration" in doc["animation"]
    for i, table in enumerate(tables):
        path = ("mocap", i + 1)
        figure, options = _figure(reader, table, path)
        meshes = limbs(figure, options["radius"], options["sides"], options["joint_radius"],
                       options["material"], len(scene.meshes), reader.crease_angle)
        total = sum(len(m.triangles) for m in scene.meshes) + sum(len(m.triangles) for m in meshes)
        if total > MAX_TRIANGLES:
            raise reader.fail(path, f"the figure's limbs bring the scene to {total:,} "
                                    f"triangles; the limit is {MAX_TRIANGLES:,}")
        scene.meshes.extend(meshes)
        anim.movers.append(figure)
        if not keyed_duration:
            length = figure.start + figure.motion.length / figure.speed
            anim.duration = max(anim.duration, length)
    if made:
        attach(scene, anim)


def _figure(reader, table, path):
    from core.scene.formats.errors import ReaderError
    from core.transforms import rotate_x, rotate_y, rotate_z
    t = reader.table(table, path, MOCAP_KEYS)
    if "file" not in t:
        raise reader.fail(path, "a figure needs file = \"NAME.bvh\" (its motion capture)")
    name = reader.string(t["file"], path + ("file",))
    if Path(name).suffix.lower() != ".bvh":
        raise reader.fail(path + ("file",), f"{name!r}: not a BVH file (.bvh)")
    shown = str(Path(reader.file).parent / name)
    try:
        motion = load_bvh(reader.folder / name, shown)
    except ReaderError as error:
        raise ReaderError(error.file, f"{error.reason} (the motion of mocap[{path[1]}] in "
                                      f"{reader.file})", error.line) from None
    rx, ry, rz = reader.vector(t.get("rotate", [0, 0, 0]), path + ("rotate",), 3, -1e6, 1e6)
    scale = reader.number(t.get("scale", 1.0), path + ("scale",), 1e-6, 1e6)
    placement = rotate_z(math.radians(rz)) @ rotate_y(math.radians(ry)) @ rotate_x(math.radians(rx))
    placement[:3, :3] *= scale
    placement[:3, 3] = reader.vector(t.get("position", [0, 0, 0]), path + ("position",), 3,
                                     -1e6, 1e6)
    figure = Figure(motion, placement,
                    start=reader.number(t.get("start", 0.0), path + ("start",), 0.0, 86400.0),
                    speed=reader.number(t.get("speed", 1.0), path + ("speed",), 0.0, 100.0,
                                        above=0.0),
                    loop=reader.boolean(t.get("loop", True), path + ("loop",)),
                    interpolation=reader.choice(t.get("interpolation", "linear"),
                                                path + ("interpolation",), INTERPOLATIONS),
                    name=reader.string(t.get("name", f"figure {path[1]}"), path + ("name",)))
    points, _, ends = figure.rest()
    every = np.concatenate([points, ends])
    if not np.all(np.abs(every) <= 1e6):
        raise reader.fail(path + ("scale",), "the placed figure reaches beyond 1e6 (a scale "
                                             "for the file's units?)")
    extent = float(np.linalg.norm(every.max(axis=0) - every.min(axis=0)))
    default = RADIUS_SHARE * extent if extent > 0.0 else 0.05
    radius = reader.number(t.get("radius", default), path + ("radius",), 0.0, 1e6, above=0.0)
    limb = reader.choice(t.get("limb", "cylinder"), path + ("limb",), tuple(LIMBS))
    sides = LIMBS[limb] or int(_whole(reader, t.get("segments", 10), path + ("segments",), 3, 64))
    if limb == "box" and "segments" in t:
        raise reader.fail(path + ("segments",), "segments are a cylinder's sides (limb = "
                                                "\"box\" has four)")
    radii = _per_joint(reader, t.get("radii", {}), path + ("radii",), motion,
                       lambda v, p: reader.number(v, p, 0.0, 1e6, above=0.0))
    joint_radius = (reader.number(t["joint_radius"], path + ("joint_radius",), 0.0, 1e6)
                    if "joint_radius" in t else None)
    material = (reader.material(t["material"], path + ("material",), default_material())
                if "material" in t else default_material())
    materials = _per_joint(reader, t.get("materials", {}), path + ("materials",), motion,
                           lambda v, p: reader.material(v, p, material))
    by_joint = subtree_values(motion, materials, material)
    return figure, {"radius": lambda j: radii.get(motion.names[j], radius), "sides": sides,
                    "joint_radius": lambda j: (radii.get(motion.names[j], radius)
                                               if joint_radius is None else joint_radius),
                    "material": lambda j: by_joint[j]}


def _whole(reader, value, path, low, high):
    n = reader.number(value, path, low, high)
    if n != int(n):
        raise reader.fail(path, f"expected a whole number, got {value!r}")
    return int(n)


def _per_joint(reader, value, path, motion, read) -> dict:
    if not isinstance(value, dict):
        raise reader.fail(path, "expected a table of joint names")
    out = {}
    for joint, v in value.items():
        if joint not in motion.names:
            shown = ", ".join(motion.names[:12]) + (", ..." if len(motion.names) > 12 else "")
            raise reader.fail(path + (joint,), f"no joint is named {joint!r} in "
                                               f"{motion.file} (joints: {shown})")
        out[joint] = read(v, path + (joint,))
    return out


register_scene_keys("mocap", ("mocap",), read_mocap, arrays=("mocap",))
