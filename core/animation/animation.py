"""A keyframed scene: the still scene of a file plus its tracks, evaluated at any time.

``Animation.scene_at(t)`` returns a plain :class:`Scene` (every stage of ``core`` renders it as
it renders a still): each keyed mesh moved by its ``T(t) · R(t) · S(t)`` (applied after the
file's own ``transform``), each keyed light moved, each keyed material recoloured, and the
keyed view first in ``views`` (the file's other views follow, so the window can still step
through them). ``view_at(t)`` is that view alone: VRP, PRP, window, F and B from their tracks,
and the VPN/VUP frame from one orientation track (quaternions), never from the two vectors
interpolated apart (which would shear the frame and pass VUP through VPN).

Particle systems (``emitters``) are simulated from time 0 with a fixed step; see
:mod:`core.animation.particles`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from core.animation import quaternion as qt
from core.animation.tracks import OrientationTrack, Track
from core.camera.view import View
from core.scene.model import Light, Mesh, Scene
from core.transforms import apply, scale, translate


@dataclass
class ObjectTracks:
    """The keyed transform of one mesh; a missing track is the identity."""

    translate: Track | None = None
    rotate: OrientationTrack | None = None
    scale: Track | None = None

    def matrix(self, t: float) -> np.ndarray:
        m = np.eye(4)
        if self.scale is not None:
            m = scale(*self.scale(t)) @ m
        if self.rotate is not None:
            r = np.eye(4)
            r[:3, :3] = qt.to_matrix(self.rotate(t))
            m = r @ m
        if self.translate is not None:
            m = translate(*self.translate(t)) @ m
        return m


@dataclass
class ViewTracks:
    """The keyed view: one track per field; ``frame`` is the VRC rotation as a quaternion."""

    base: View
    vrp: Track | None = None
    frame: OrientationTrack | None = None
    window: Track | None = None
    prp: Track | None = None
    front: Track | None = None
    back: Track | None = None
    level: tuple | None = None        # a fixed VUP: the camera turns but never rolls

    def at(self, t: float, label: str) -> View:
        b = self.base
        vpn, vup = b.vpn, b.vup
        if self.frame is not None:
            rows = qt.to_matrix(self.frame(t)).T        # rows u, v, n of the world→VRC rotation
            vpn, vup = tuple(rows[2]), tuple(rows[1])
            if self.level is not None:
                # slerp between two level frames tilts the horizon in between (the level
                # frames are not a great circle); keeping VUP fixed re-levels u = VUP x n
                vup = self.level
        pick = lambda track, still: still if track is None else tuple(float(x) for x in track(t))
        front = b.front if self.front is None else float(self.front(t)[0])
        back = b.back if self.back is None else float(self.back(t)[0])
        return View(vrp=pick(self.vrp, b.vrp), vpn=tuple(map(float, vpn)), vup=tuple(map(float, vup)),
                    window=pick(self.window, b.window), prp=pick(self.prp, b.prp),
                    front=front, back=back, label=label)


def frame_quaternion(vpn, vup) -> np.ndarray:
    """The orientation of a view's VRC: the rotation whose matrix has rows u, v, n."""
    n = np.asarray(vpn, np.float64) / np.linalg.norm(vpn)
    u = np.cross(np.asarray(vup, np.float64), n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    return qt.from_matrix(np.array([u, v, n]).T)



@dataclass
class Animation:
    """A scene with tracks. ``frame_count`` frames at ``fps``, frame k at time ``k / fps``."""

    scene: Scene
    duration: float = 0.0
    fps: float = 30.0
    loop: bool = False
    view: ViewTracks | None = None
    objects: dict[int, ObjectTracks] = field(default_factory=dict)      # mesh index → tracks
    lights: dict[int, Track] = field(default_factory=dict)              # light index → position
    colors: dict[int, Track] = field(default_factory=dict)              # mesh index → O_d
    transparencies: dict[int, Track] = field(default_factory=dict)      # mesh index → k_t
    intensities: dict[int, Track] = field(default_factory=dict)         # light index → I_p
    emitters: list = field(default_factory=list)                        # particles.Spec, one per [[emitter]]
    seed: int = 0
    # Whatever else moves meshes each frame (rigid bodies, linkages, actors): objects with
    # ``matrices_at(t) -> {mesh index: 4 x 4}``, applied after the keyed transform; those that
    # simulate step by step also have ``snapshot()``, ``restore(state)`` and ``copy()``.
    movers: list = field(default_factory=list)
    shutter: object | None = None           # the file's motion blur (frames.Shutter); None: sharp
    _system: object = field(default=None, repr=False, compare=False)   # made on first use

    @property
    def frame_count(self) -> int:
        """Frames in the movie: ``duration · fps`` rounded, at least one."""
        return max(1, int(round(self.duration * self.fps)))

    def time_of(self, frame: int) -> float:
        return frame / self.fps

    def local_time(self, t: float) -> float:
        """``t`` wrapped into [0, duration) when the animation loops, else clamped to it."""
        if not math.isfinite(t):
            raise ValueError(f"the time must be a finite number of seconds, not {t}")
        if self.duration <= 0.0:
            return 0.0
        if self.loop:
            return math.fmod(t, self.duration) + (self.duration if t < 0 else 0.0)
        return min(max(t, 0.0), self.duration)

    def view_at(self, t: float) -> View | None:
        """The keyed view at time t (None when no view is keyed)."""
        if self.view is None:
            return None
        t = self.local_time(t)
        return self.view.at(t, f"{self.scene.name}: the keyed view at t = {t:.3f} s")

    def scene_at(self, t: float) -> Scene:
        """A plain Scene for time t: moved meshes, lights and colours, the keyed view first."""
        t = self.local_time(t)
        base = self.scene
        lights = [self._light_at(i, light, t) for i, light in enumerate(base.lights)]
        view = self.view_at(t)
        views = ([view] if view is not None else []) + list(base.views)
        moving = self.moved_at(t)
        meshes = [self._mesh_at(i, m, t, moving.get(i)) for i, m in enumerate(base.meshes)]
        # A keyed sphere or plane is moved and recoloured with its tessellation (the
        # ray tracer intersects the primitive, so it must move too).
        moved = {}
        for i, (old, new) in enumerate(zip(base.meshes, meshes)):
            if old.tessellates is None or new is old:
                continue
            if id(old.tessellates) not in moved:     # a checkered plane has two meshes
                moved[id(old.tessellates)] = moved_primitive(
                    old, self._matrix(i, t, moving.get(i)),
                    new.material if i in self.colors or i in self.transparencies else None)
            meshes[i] = dataclasses.replace(new, tessellates=moved[id(old.tessellates)])
        primitives = [moved.get(id(p), p) for p in base.primitives]
        return dataclasses.replace(base, meshes=meshes, lights=lights, views=views,
                                   primitives=primitives)

    def moved_at(self, t: float) -> dict[int, np.ndarray]:
        """mesh index → the movers' 4 x 4 at (local) time t."""
        out: dict[int, np.ndarray] = {}
        for mover in self.movers:
            out.update(mover.matrices_at(t))
        return out

    def _matrix(self, i: int, t: float, moved) -> np.ndarray | None:
        """Mesh i's whole transform at t: the keyed one, then a mover's (None: unmoved)."""
        tracks = self.objects.get(i)
        m = tracks.matrix(t) if tracks is not None else None
        if moved is not None:
            m = moved if m is None else moved @ m
        return m

    def _mesh_at(self, i: int, mesh: Mesh, t: float, moved=None) -> Mesh:
        color, kt = self.colors.get(i), self.transparencies.get(i)
        m = self._matrix(i, t, moved)
        if m is None and color is None and kt is None:
            return mesh
        changes = {}
        if m is not None:
            changes["positions"] = apply(m, mesh.positions)[:, :3]
            if mesh.normals is not None:
                normals = mesh.normals @ np.linalg.inv(m[:3, :3])        # rows: n' = M^-T n
                changes["normals"] = normals / np.linalg.norm(normals, axis=1, keepdims=True)
            if np.linalg.det(m[:3, :3]) < 0:                              # a mirror: rewind
                changes["triangles"] = mesh.triangles[:, [0, 2, 1]]
        material = {}
        if color is not None:
            material["od"] = tuple(float(c) for c in np.clip(color(t), 0.0, 1.0))
        if kt is not None:               # in-betweened past a key (Catmull-Rom): kept in 0..1
            material["kt"] = float(np.clip(kt(t)[0], 0.0, 1.0))
        if material:
            changes["material"] = dataclasses.replace(mesh.material, **material)
        return dataclasses.replace(mesh, **changes)

    def _light_at(self, i: int, light: Light, t: float) -> Light:
        track, intensity = self.lights.get(i), self.intensities.get(i)
        if track is not None:
            light = dataclasses.replace(light, position=tuple(float(x) for x in track(t)),
                                        direction=None)
        if intensity is not None:        # an overshoot below 0 would be a light that darkens
            light = dataclasses.replace(
                light, intensity=tuple(float(x) for x in np.maximum(intensity(t), 0.0)))
        return light

    # ------------------------------------------------------------------ particles

    @property
    def particle_system(self):
        """The emitters' :class:`~core.animation.particles.ParticleSystem` (None without any),
        made once and kept, so that playing forward steps on from the last frame."""
        if not self.emitters:
            return None
        if self._system is None:
            from core.animation.particles import ParticleSystem
            self._system = ParticleSystem(self.emitters, self.fps, self.seed)
        return self._system

    def sprites_at(self, t: float):
        """The particles at time t, ready for the particle stage (None without emitters)."""
        system = self.particle_system
        if system is None:
            return None
        from core.animation.particles import sprites_of
        return sprites_of(system, system.state_at(self.local_time(t)))


def moved_primitive(mesh: Mesh, m, material):
    """``mesh.tessellates`` moved by the 4 x 4 matrix ``m`` (None: not moved) and, where the
    mesh's material is the primitive's own, recoloured to ``material`` (None: kept). A
    sphere's radius scales by the cube root of the matrix's volume factor (keys scale
    uniformly); a plane's point moves and its normal turns by the inverse transpose."""
    from core.scene.primitives import Plane, Sphere
    primitive = mesh.tessellates
    changes = {}
    if material is not None and mesh.material is primitive.material:
        changes["material"] = material
    if m is not None and isinstance(primitive, Sphere):
        changes["center"] = tuple(float(c) for c in apply(m, np.array([primitive.center]))[0, :3])
        changes["radius"] = primitive.radius * abs(np.linalg.det(m[:3, :3])) ** (1.0 / 3.0)
    elif m is not None and isinstance(primitive, Plane):
        normal = np.linalg.solve(m[:3, :3].T, np.asarray(primitive.normal, dtype=np.float64))
        changes["point"] = tuple(float(c) for c in apply(m, np.array([primitive.point]))[0, :3])
        changes["normal"] = tuple(float(c) for c in normal / np.linalg.norm(normal))
    return dataclasses.replace(primitive, **changes) if changes else primitive
