"""The scene file's ``[animation]``, ``[[key]]`` and ``[[emitter]]`` tables → an :class:`Animation`.

Called from the TOML scene reader (``core/scene/formats/scenefile.py``) with its reader, so
that every message names the key's path and line the way the rest of the file's do::

    [animation]
    duration = 8.0              # seconds (default: the last key's time)
    fps = 30
    loop = true
    interpolation = "catmull-rom"   # linear | ease | catmull-rom | kochanek-bartels | double
    orientation = "squad"           # slerp | squad  (VPN/VUP frames and object rotations)
    tension = 0.0                   # Kochanek–Bartels T, C, B for every track ...
    constant_speed = false          # arc-length parametrisation of the position tracks
    level = [0, 1, 0]               # optional: the view's VUP held fixed (no roll between keys)
    seed = 1                        # particle systems
    motion_blur = 16                # samples a frame over the shutter (default 1: sharp)
    shutter = [-0.25, 0.25]         # when it opens and closes, in frames from the frame
    [animation.track."view.vrp"]    # ... or per track, by its channel name
    interpolation = "kochanek-bartels"
    tension = 0.5

    [[key]]
    time = 0.0
    view = { vrp = [0, 0, 0], vpn = [0, 0, 1], vup = [0, 1, 0], prp = [0, 0, 8] }
    object.ring = { translate = [0, 0, 0], rotate = [0, 0, 0], scale = 1.0 }
    light.1 = { position = [3, 4, 6], intensity = [1, 0.9, 0.8] }
    material.ring = { od = [0.2, 0.4, 0.9], kt = 0.5 }

A key gives any subset of the channels; each channel's track is made of the keys that give it.
``vpn`` and ``vup`` come together (they are one orientation). Channel names: ``view.vrp``,
``view.frame``, ``view.window``, ``view.prp``, ``view.front``, ``view.back``,
``object.NAME.translate|rotate|scale``, ``light.N.position|intensity``,
``material.NAME.od|kt``: the notes' update dynamics (L2274: "changes in shape, color,
transparency, size") and environmental changes (the lighting) beside the motion dynamics.
"""

from __future__ import annotations


import numpy as np

from core.animation import quaternion as qt
from core.animation.animation import Animation, ObjectTracks, ViewTracks, frame_quaternion
from core.scene.formats.keys import register_scene_keys
from core.scene.model import meshes_named
from core.animation.tracks import METHODS, ORIENTATION_METHODS, OrientationTrack, Track

TOP_KEYS = ("animation", "key", "emitter", "influence")   # the top-level tables we read
TABLE_ARRAYS = ("key", "emitter", "influence")      # written [[key]], [[emitter]], [[influence]]
ANIMATION_KEYS = ("duration", "fps", "loop", "interpolation", "orientation", "tension",
                  "continuity", "bias", "constant_speed", "seed", "level", "track",
                  "motion_blur", "shutter")
TRACK_KEYS = ("interpolation", "orientation", "tension", "continuity", "bias", "constant_speed")
KEY_KEYS = ("time", "view", "object", "light", "material")
KEY_VIEW_KEYS = ("vrp", "vpn", "vup", "window", "prp", "front", "back")
KEY_OBJECT_KEYS = ("translate", "rotate", "scale")
MAX_FPS = 1000.0
MAX_DURATION = 24 * 3600.0

def animation_of(scene) -> Animation | None:
    """The animation a scene file described for ``scene`` (None for a still scene), kept in
    ``Scene.systems``."""
    return scene.systems.get("animation")


def attach(scene, animation: Animation) -> None:
    scene.systems = {**scene.systems, "animation": animation}


def read_animation(reader, doc: dict, scene) -> None:
    """Read the animation tables of ``doc`` (a parsed scene file) and attach them to ``scene``."""
    if not any(k in doc for k in TOP_KEYS):
        return
    settings = reader.table(doc.get("animation", {}), ("animation",), ANIMATION_KEYS)
    samples = _samples(reader, doc, scene)
    defaults = _track_settings(reader, settings, ("animation",))
    per_track = settings.get("track", {})        # channel names are checked below
    if not isinstance(per_track, dict):
        raise reader.fail(("animation", "track"), "expected a table of channels")
    for name in per_track:
        if name not in samples:
            raise reader.fail(("animation", "track", name),
                              f"no key gives the channel {name!r} (keyed: "
                              f"{', '.join(sorted(samples)) or 'none'})")
    last = max((t for ks in samples.values() for t, _, _ in ks), default=0.0)
    anim = Animation(scene=scene)
    anim.duration = reader.number(settings.get("duration", last), ("animation", "duration"),
                                  0.0, MAX_DURATION)
    anim.fps = reader.number(settings.get("fps", 30), ("animation", "fps"), 0.0, MAX_FPS, above=0.0)
    anim.loop = reader.boolean(settings.get("loop", False), ("animation", "loop"))
    seed = reader.number(settings.get("seed", 0), ("animation", "seed"), 0, 2**63 - 1)
    if seed != int(seed):
        raise reader.fail(("animation", "seed"), "expected a whole number")
    anim.seed = int(seed)
    anim.shutter = _shutter(reader, settings)
    for channel, keys in samples.items():
        options = dict(defaults)
        if channel in per_track:
            options.update(_track_settings(reader, per_track[channel],
                                           ("animation", "track", channel)))
        _install(reader, anim, channel, keys, options)
    if "level" in settings:
        level = reader.vector(settings["level"], ("animation", "level"))
        if not any(level):
            raise reader.fail(("animation", "level"), "the up vector is zero")
        if anim.view is None or anim.view.frame is None:
            raise reader.fail(("animation", "level"), "no key gives the view's vpn and vup")
        anim.view.level = level
    if anim.view is not None:
        _check_in_betweens(reader, anim, samples)
    if "emitter" in doc:
        from core.animation.particles import read_emitters
        anim.emitters = read_emitters(reader, doc["emitter"], scene)
        _check_simulation_length(reader, anim)
    if "influence" in doc:
        if not anim.emitters:
            raise reader.fail(("influence",), "a region of influence acts on particles: the "
                                              "scene has no [[emitter]]")
        from core.animation.particle_influence import read_influences
        read_influences(reader, doc["influence"], anim.emitters)
    attach(scene, anim)


def _shutter(reader, settings):
    """``motion_blur`` and ``shutter`` → a :class:`~core.animation.frames.Shutter` (None:
    sharp frames)."""
    from core.animation.frames import MAX_BLUR_SAMPLES, Shutter
    samples = reader.number(settings.get("motion_blur", 1), ("animation", "motion_blur"), 1,
                            MAX_BLUR_SAMPLES)
    if samples != int(samples):
        raise reader.fail(("animation", "motion_blur"), f"expected a whole number, got {samples!r}")
    if "shutter" in settings and samples == 1:
        raise reader.fail(("animation", "shutter"), "a shutter without motion_blur samples")
    opening = reader.vector(settings.get("shutter", [Shutter.open, Shutter.close]),
                            ("animation", "shutter"), 2, -1.0, 1.0)
    if opening[0] > opening[1]:
        raise reader.fail(("animation", "shutter"), "the shutter closes before it opens")
    return Shutter(int(samples), *opening) if samples > 1 else None


# The in-between views checked at load: this many between two keys, fewer (at least one) when
# the keys are so many that the whole would pass MAX_VIEW_SAMPLES.
VIEW_SAMPLES_PER_INTERVAL = 32
MAX_VIEW_SAMPLES = 4096


def _check_in_betweens(reader, anim: Animation, samples: dict) -> None:
    """Every key may be a valid view and the views between them not: a window whose sides
    cross, F and B swapping, a PRP crossing the view plane. The keyed view is checked at load,
    at samples between every two keys, with the still views' rules (a view no projection can
    draw), and for the signs of ``PRP_n``, ``u_max − u_min``, ``v_max − v_min`` and ``F − B``
    changing between two samples (the crossing itself falls between them)."""
    from core.camera.view import load_problems
    channels = [c for c in samples if c.startswith("view.")]
    times = np.unique([t for c in channels for t, _, _ in samples[c]])
    if len(times) < 2:
        return
    per = max(1, min(VIEW_SAMPLES_PER_INTERVAL, MAX_VIEW_SAMPLES // (len(times) - 1)))
    u = np.arange(per + 1) / (per + 1)
    ts = np.append((times[:-1, None] + np.diff(times)[:, None] * u).reshape(-1), times[-1])
    before = None
    for t in ts:
        view = anim.view.at(float(t), "")
        found = load_problems(view)
        w = view.window
        signs = np.sign([view.prp[2], w[1] - w[0], w[3] - w[2], view.front - view.back])
        if not found and before is not None and np.any(signs != before[1]):
            found = [["PRP crosses the view plane (PRP_n changes sign)",
                      "u_min and u_max cross", "v_min and v_max cross",
                      "F and B cross"][int(np.flatnonzero(signs != before[1])[0])]]
            t = before[0], t
        if found:
            k = int(np.searchsorted(times, t if np.isscalar(t) else t[1], side="right"))
            k = min(max(k, 1), len(times) - 1)
            when = (f"at t = {t:.6g} s" if np.isscalar(t)
                    else f"between t = {t[0]:.6g} s and t = {t[1]:.6g} s")
            raise reader.fail(("key",), f"the keyed view is invalid {when}, between the keys "
                                        f"at t = {times[k - 1]:g} and t = {times[k]:g}: "
                                        + "; ".join(found))
        before = (t, signs)


def _check_simulation_length(reader, anim: Animation) -> None:
    """Particles are simulated step by step from 0 to any time asked for (at most the
    duration): the steps that takes are bounded before any is taken."""
    from core.animation.particles import MAX_SIMULATION_STEPS, SUBSTEPS
    steps = anim.duration * anim.fps * SUBSTEPS
    if steps > MAX_SIMULATION_STEPS:
        raise reader.fail(("animation", "duration"),
                          f"with particles, duration · fps · {SUBSTEPS} steps a frame = "
                          f"{steps:,.0f} simulation steps; at most {MAX_SIMULATION_STEPS:,} "
                          "(shorten the animation or lower the fps)")


def _track_settings(reader, table, path) -> dict:
    keys = TRACK_KEYS if path != ("animation",) else ANIMATION_KEYS
    t = reader.table(table, path, keys)
    out = {}
    if "interpolation" in t:
        out["method"] = reader.choice(t["interpolation"], path + ("interpolation",), METHODS)
    if "orientation" in t:
        out["orientation"] = reader.choice(t["orientation"], path + ("orientation",),
                                           ORIENTATION_METHODS)
    for key in ("tension", "continuity", "bias"):
        if key in t:
            out[key] = reader.number(t[key], path + (key,), -1.0, 1.0)
    if "constant_speed" in t:
        out["constant_speed"] = reader.boolean(t["constant_speed"], path + ("constant_speed",))
    return out


def _samples(reader, doc: dict, scene) -> dict[str, list]:
    """channel → [(time, value, path)] from every ``[[key]]``, in file order."""
    names = {m.name for m in scene.meshes}
    out: dict[str, list] = {}
    add = lambda channel, time, value, path: out.setdefault(channel, []).append((time, value, path))
    for i, key in enumerate(reader.tables(doc.get("key", []), ("key",))):
        path = ("key", i + 1)
        reader.table(key, path, KEY_KEYS)
        if "time" not in key:
            raise reader.fail(path, "a key needs a time (seconds)")
        time = reader.number(key["time"], path + ("time",), 0.0, MAX_DURATION)
        if "view" in key:
            _view_key(reader, key["view"], path + ("view",), time, add)
        for name, value in reader.table(key.get("object", {}), path + ("object",), tuple(names)).items():
            p = path + ("object", name)
            for what, v in reader.table(value, p, KEY_OBJECT_KEYS).items():
                add(f"object.{name}.{what}", time, _object_value(reader, what, v, p + (what,)), p + (what,))
        lights = key.get("light", {})
        allowed = tuple(str(k + 1) for k in range(len(scene.lights)))
        for number, value in reader.table(lights, path + ("light",), allowed).items():
            p = path + ("light", number)
            t = reader.table(value, p, ("position", "intensity"))
            if "position" in t:
                if scene.lights[int(number) - 1].position is None:
                    raise reader.fail(p, "a directional light has no position to key")
                add(f"light.{number}.position", time,
                    np.array(reader.vector(t["position"], p + ("position",))), p + ("position",))
            if "intensity" in t:                 # I_p, as the [[light]] table's range
                add(f"light.{number}.intensity", time,
                    np.array(reader.vector(t["intensity"], p + ("intensity",), 3, 0.0, 1e6)),
                    p + ("intensity",))
        for name, value in reader.table(key.get("material", {}), path + ("material",), tuple(names)).items():
            p = path + ("material", name)
            t = reader.table(value, p, ("od", "kt"))
            if "od" in t:
                add(f"material.{name}.od", time, np.array(reader.vector(t["od"], p + ("od",), 3, 0.0, 1.0)),
                    p + ("od",))
            if "kt" in t:                         # the transparency, 0 to 1 as in a material
                add(f"material.{name}.kt", time,
                    np.array([reader.number(t["kt"], p + ("kt",), 0.0, 1.0)]), p + ("kt",))
    return out


def _view_key(reader, value, path, time, add) -> None:
    t = reader.table(value, path, KEY_VIEW_KEYS)
    if ("vpn" in t) != ("vup" in t):
        raise reader.fail(path, "vpn and vup are keyed together (they are one orientation)")
    if "vpn" in t:
        vpn, vup = reader.vector(t["vpn"], path + ("vpn",)), reader.vector(t["vup"], path + ("vup",))
        n = np.linalg.norm(vpn)
        if n == 0.0 or np.linalg.norm(np.cross(vup, np.asarray(vpn) / n)) <= 1e-12 * np.linalg.norm(vup):
            raise reader.fail(path, "VPN is zero or VUP is parallel to it: no frame to key")
        add("view.frame", time, frame_quaternion(vpn, vup), path + ("vpn",))
    for what in ("vrp", "prp"):
        if what in t:
            add(f"view.{what}", time, np.array(reader.vector(t[what], path + (what,))), path + (what,))
    if "window" in t:
        add("view.window", time, np.array(reader.vector(t["window"], path + ("window",), 4)),
            path + ("window",))
    for what in ("front", "back"):
        if what in t:
            add(f"view.{what}", time, np.array([reader.number(t[what], path + (what,))]), path + (what,))


def _object_value(reader, what, value, path) -> np.ndarray:
    if what == "translate":
        return np.array(reader.vector(value, path))
    if what == "rotate":
        return qt.from_euler_degrees(*reader.vector(value, path, 3, -1e6, 1e6))
    s = reader.vector(value, path, 3, -1e6, 1e6) if isinstance(value, list) else \
        (reader.number(value, path, -1e6, 1e6),) * 3
    if any(abs(c) < 1e-6 for c in s):
        raise reader.fail(path, "a scale factor is zero (or below 1e-6 in size)")
    return np.array(s)


def _install(reader, anim: Animation, channel: str, keys: list, options: dict) -> None:
    keys = sorted(keys, key=lambda k: k[0])
    for (t0, _, _), (t1, _, p1) in zip(keys, keys[1:]):
        if t1 == t0:
            raise reader.fail(p1, f"a second key for {channel} at time {t1:g}")
    times = np.array([k[0] for k in keys])
    values = np.array([k[1] for k in keys])
    if channel in ("view.frame",) or channel.endswith(".rotate"):
        track = OrientationTrack(times, values, options.get("orientation", "squad"))
    else:
        position = channel in ("view.vrp", "view.prp") or channel.endswith(".translate") \
            or channel.endswith(".position")
        track = Track(times, values, options.get("method", "catmull-rom"),
                      options.get("tension", 0.0), options.get("continuity", 0.0),
                      options.get("bias", 0.0), position and options.get("constant_speed", False))
    if channel.endswith(".scale"):
        _check_scale(reader, channel, track, keys)
    kind, _, rest = channel.partition(".")
    scene = anim.scene
    if kind == "view":
        if anim.view is None:
            anim.view = ViewTracks(base=_base_view(reader, scene, keys[0][2]))
        setattr(anim.view, rest, track)
    elif kind == "object":
        name, what = rest.rsplit(".", 1)
        for index in meshes_named(scene, name):
            setattr(anim.objects.setdefault(index, ObjectTracks()), what, track)
    elif kind == "light":
        number, what = rest.split(".")
        (anim.lights if what == "position" else anim.intensities)[int(number) - 1] = track
    else:
        name, what = rest.rsplit(".", 1)
        for index in meshes_named(scene, name, own_material=True):
            (anim.colors if what == "od" else anim.transparencies)[index] = track



def _check_scale(reader, channel: str, track: Track, keys: list) -> None:
    """A scale factor keeps its sign and its size between the keys too: in-betweened through 0
    the mesh would flatten (and its normals have no inverse transpose)."""
    low, high = track.interval_ranges()
    small = (low < 1e-6) & (high > -1e-6)
    if small.any():
        i = int(np.flatnonzero(small.any(axis=1))[0])
        raise reader.fail(keys[i + 1][2], f"the scale passes through zero between the keys at "
                                          f"t = {keys[i][0]:g} and t = {keys[i + 1][0]:g} (a "
                                          "factor must keep its sign and stay at least 1e-6 in "
                                          "size all along; key a mirror as its own object)")


def _base_view(reader, scene, path):
    """The view whose unkeyed fields the keyed view keeps: the scene's first view."""
    if not scene.views:
        raise reader.fail(path, "a keyed view needs a still view for the fields no key gives "
                                "(add a [[view]] or views = \"auto\")")
    return scene.views[0]


register_scene_keys("animation", TOP_KEYS, read_animation, arrays=TABLE_ARRAYS)
