"""A scene's radiosity solution: mesh, solve, subdivide where it changes fast, solve again.

:func:`solve` takes a scene and :class:`Options` and returns a :class:`Solution` (the elements,
their radiosity and the ambient term for display, what it cost). It does not depend on any
view: every view of the scene draws from the same solution (``core.renderers.radiosity.draw``).

Adaptive subdivision (Cohen et al. 1986): after a solve, the elements whose radiosity differs
most from the mean at their corners (a large gradient: shadow edges, corners) are cut into
four, while the budget ``max_elements`` allows, and the scene is solved again on the finer
elements (the patches that shoot stay the same).

:func:`save` / :func:`load` keep a solution in a ``.npz`` keyed to :func:`scene_hash` (the
geometry, materials and lights); loading it for any other scene is refused.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field

import numpy as np

from core.radiosity import mesh as meshing
from core.radiosity.mesh import Elements, RadiosityError
from core.renderers.radiosity.options import RadiosityOptions
from core.radiosity.solve import Progressive, Shooter, direct_light, gauss_seidel, scene_bvh

FORMAT = 1


@dataclass(frozen=True)
class Options(RadiosityOptions):
    """The user's radiosity options (checked by :class:`RadiosityOptions`) and the solver's
    own limits: its most shooting steps, and whether to subdivide where the gradient is large
    and solve again."""

    max_steps: int = 100_000
    adaptive: bool = True

    @classmethod
    def from_settings(cls, settings) -> "Options":
        own = settings.options_of("radiosity")
        return cls(**{name: getattr(own, name) for name in RadiosityOptions.__dataclass_fields__})


@dataclass
class Solution:
    elements: Elements
    radiosity: np.ndarray                 # (E, 3)
    ambient: np.ndarray                   # (E, 3) the display's stand-in for unshot light
    scene_hash: str
    options: Options
    stats: dict = field(default_factory=dict)

    def shown(self) -> np.ndarray:
        """What the display draws: radiosity plus the ambient term."""
        return self.radiosity + self.ambient


def scene_hash(scene) -> str:
    """sha256 of what the solution depends on: triangles, materials, lights."""
    h = hashlib.sha256()
    for m in scene.meshes:
        h.update(np.ascontiguousarray(m.positions).tobytes())
        h.update(np.ascontiguousarray(m.triangles).tobytes())
        mat = m.material
        h.update(json.dumps([mat.kd, list(mat.od), list(mat.emission), mat.two_sided,
                             m.closed]).encode())
    for light in scene.lights:
        h.update(json.dumps([list(light.intensity), light.position and list(light.position),
                             light.direction and list(light.direction),
                             list(light.attenuation)]).encode())
    return h.hexdigest()


def start(scene, options: Options, elements: Elements | None = None):
    """``(elements, shooter, source)`` ready to solve: raises RadiosityError for a scene
    the equation cannot use."""
    if not meshing.has_light(scene):
        raise RadiosityError("nothing emits light (no material with emission, "
                             "no [[light]] of any intensity)")
    budget = options.max_elements // 2 if options.adaptive else options.max_elements
    e = elements if elements is not None else meshing.mesh_scene(scene, max(1, budget))
    bvh = scene_bvh(scene)
    shooter = Shooter(e, options.form_factors, options.hemicube_resolution, bvh)
    source = e.emission + direct_light(e, scene.lights, bvh)
    return e, shooter, source


def solve(scene, options: Options = Options(), callback=None) -> Solution:
    """The radiosity of every element of ``scene``. ``callback(progressive)`` after each
    shot (the window's progress); returning False stops early."""
    began = time.perf_counter()
    e, shooter, source = start(scene, options)
    rounds = []
    while True:
        radiosity, ambient, info = _solve_once(e, shooter, source, options, callback)
        rounds.append({"elements": len(e), **info})
        room = options.max_elements - len(e)
        if not options.adaptive or room < 3 or info.get("stopped"):
            break
        chosen = steepest(e, radiosity, room // 3)
        if len(chosen) == 0:
            break
        e = meshing.split(e, chosen)
        e, shooter, source = start(scene, options, e)
    stats = {"elements": len(e), "patches": e.patches, "rounds": rounds,
             "seconds": time.perf_counter() - began,
             "form factor rows": sum(r["rows"] for r in rounds),
             "form factor seconds": sum(r["form factor seconds"] for r in rounds)}
    return Solution(e, radiosity, ambient, scene_hash(scene), options, stats)


def _solve_once(e, shooter, source, options, callback):
    began = time.perf_counter()
    if options.solver == "gauss-seidel":
        radiosity, sweeps = gauss_seidel(e, shooter, source)
        info = {"sweeps": sweeps, "unshot": 0.0}
        ambient = np.zeros_like(radiosity)
    else:
        solver = Progressive(e, shooter, source)
        solver.run(options.converge, options.max_steps, callback)
        radiosity, ambient = solver.radiosity, solver.ambient()
        info = {"steps": solver.steps, "unshot": solver.unshot_fraction(),
                "stopped": solver.unshot_fraction() > options.converge
                and solver.steps < options.max_steps}
    info.update({"rows": shooter.computed, "form factor seconds": shooter.seconds,
                 "seconds": time.perf_counter() - began})
    return radiosity, ambient, info


def steepest(e: Elements, radiosity: np.ndarray, count: int, threshold: float = 0.05
             ) -> np.ndarray:
    """Up to ``count`` elements whose radiosity differs from the mean at their corners by
    more than ``threshold`` of the mean reflected radiosity, largest difference first."""
    _, corners, at_vertex = meshing.vertex_values(e, radiosity)
    luminance = radiosity.sum(axis=1)
    difference = np.abs(at_vertex.sum(axis=1)[corners] - luminance[:, None]).max(axis=1)
    reflecting = ~np.any(e.emission > 0, axis=1)
    scale = max(float(luminance[reflecting].mean()) if reflecting.any() else 0.0, 1e-300)
    difference[~reflecting] = 0.0
    order = np.argsort(-difference)[:count]
    return np.sort(order[difference[order] > threshold * scale])


def save(solution: Solution, path) -> None:
    e = solution.elements
    arrays = {name: getattr(e, name) for name in e.__dataclass_fields__ if name != "scale"}
    np.savez_compressed(path, format=np.array(FORMAT), scene_hash=np.array(solution.scene_hash),
                        radiosity=solution.radiosity, ambient=solution.ambient,
                        scale=np.array(e.scale),
                        options=np.array(json.dumps(solution.options.__dict__)),
                        stats=np.array(json.dumps(solution.stats, default=float)), **arrays)


def load(path, scene) -> Solution:
    """The solution in ``path`` for ``scene``; RadiosityError if it belongs to another scene
    or is not a solution file."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if "scene_hash" not in data or int(data["format"]) != FORMAT:
                raise RadiosityError(f"{path}: not a radiosity solution file")
            if str(data["scene_hash"]) != scene_hash(scene):
                raise RadiosityError(f"{path}: the solution belongs to another scene (its hash "
                                     f"{str(data['scene_hash'])[:12]} is not {scene.name}'s "
                                     f"{scene_hash(scene)[:12]})")
            fields = {name: data[name] for name in Elements.__dataclass_fields__
                      if name != "scale"}
            e = Elements(**fields, scale=float(data["scale"]))
            return Solution(e, data["radiosity"], data["ambient"], str(data["scene_hash"]),
                            Options(**json.loads(str(data["options"]))),
                            json.loads(str(data["stats"])))
    except (OSError, ValueError, KeyError) as error:
        if isinstance(error, RadiosityError):
            raise
        raise RadiosityError(f"{path}: cannot read a radiosity solution: {error}") from None
