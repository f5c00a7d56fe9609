"""The stability suite's kit: results, the case registry, the judge, and the helpers cases use.

:mod:`core.analysis.stability_cases` registers the cases with :func:`case`;
:mod:`core.analysis.stability` is the suite (kit + cases) that the CLI and the tests run.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from core.settings import RenderSettings
from core.settings import PROJECTIONS, SOLID_SHADINGS
from core.analysis import exact
from core.pipeline import project
from core.scene.generators import cube, uv_sphere
from core.scene.model import Light, Material, Mesh, Scene
from core.transforms import apply
from core.camera.view import View, normalizing_transform

U = 2.0 ** -53                # unit round-off of float64
TOLERANCE = 1e-9              # well-conditioned cases agree with exact to this
GROWTH = 100.0                # allowed error growth over κ·u (ill-conditioned cases)
SIZE = (64, 64)
MAX_EXACT_POINTS = 48         # points pushed through the exact chain per case

RED = Material(ka=0.3, kd=0.6, ks=0.3, n=20.0, od=(0.9, 0.2, 0.2))
BLUE = Material(ka=0.3, kd=0.6, ks=0.3, n=20.0, od=(0.2, 0.3, 0.9))
GREY = Material(ka=0.3, kd=0.6, ks=0.4, n=30.0, od=(0.7, 0.7, 0.7))


@dataclass
class Result:
    """One row of the stability table."""

    name: str
    expected: str
    measured: str = ""
    passed: bool = False
    error: float | None = None          # relative error against exact arithmetic
    condition: float | None = None      # κ of the quantity the error is about
    conditioning: str = "n/a"           # well-conditioned / ill-conditioned: ...
    quantity: str = ""                  # what the error is about
    seconds: float = 0.0

    def as_dict(self) -> dict:
        d = asdict(self)
        for key in ("error", "condition"):           # JSON has no inf
            if d[key] is not None and not math.isfinite(d[key]):
                d[key] = str(d[key])
        return d


@dataclass
class Outcome:
    """What a case function returns: its checks and, where it has one, its accuracy."""

    checks: list[tuple[str, bool]] = field(default_factory=list)
    error: float | None = None
    condition: float | None = None
    quantity: str = ""
    # Set for a case whose accuracy is judged by its own rule (e.g. an ill-posed quantity).
    conditioning: str | None = None
    accurate: bool | None = None

    def check(self, text: str, ok) -> None:
        self.checks.append((text, bool(ok)))

    def note(self, text: str) -> None:
        """A measured fact shown beside the checks (an example message, say); it cannot fail."""
        self.checks.append((text, True))

    def accuracy(self, error: float, condition: float, quantity: str) -> None:
        """Record an error and condition; several calls keep the worst ratio error / bound."""
        if self.error is None or _excess(error, condition) > _excess(self.error, self.condition):
            self.error, self.condition, self.quantity = error, condition, quantity


@dataclass
class Case:
    name: str
    expected: str
    run: Callable[[], Outcome]


CASES: list[Case] = []


def case(name: str, expected: str):
    """Register a case function under ``name`` with its expected behaviour."""
    def register(fn: Callable[[], Outcome]) -> Callable[[], Outcome]:
        CASES.append(Case(name, expected, fn))
        return fn
    return register


def _bound(condition: float) -> float:
    """The error allowed for a quantity of condition number κ."""
    if condition * U <= TOLERANCE / GROWTH:
        return TOLERANCE
    return GROWTH * condition * U


def _excess(error: float, condition: float | None) -> float:
    return error / _bound(condition or 1.0)


def judge(outcome: Outcome) -> tuple[bool, str]:
    """``(accuracy holds, conditioning note)`` for an outcome (see the module docstring)."""
    if outcome.conditioning is not None:
        return bool(outcome.accurate), outcome.conditioning
    if outcome.error is None:
        return True, "n/a"
    kappa = outcome.condition if outcome.condition is not None else 1.0
    ok = math.isfinite(outcome.error) and outcome.error <= _bound(kappa)
    if kappa * U <= TOLERANCE / GROWTH:
        return ok, f"well-conditioned (κ·u = {kappa * U:.1e}); error <= {TOLERANCE:g}"
    return ok, (f"ill-conditioned (κ·u = {kappa * U:.1e}); error <= {GROWTH:g}·κ·u "
                f"= {_bound(kappa):.1e}")


def run_case(c: Case) -> Result:
    """Run one case under strict floating point; any exception is a FAIL with its message."""
    result = Result(name=c.name, expected=c.expected)
    start = time.perf_counter()
    try:
        with np.errstate(all="raise", under="ignore"):
            outcome = c.run()
    except Exception as error:          # the case's own failure, reported rather than raised
        result.measured = f"{type(error).__name__}: {error}"
        result.seconds = time.perf_counter() - start
        return result
    result.seconds = time.perf_counter() - start
    accurate, result.conditioning = judge(outcome)
    result.error, result.condition, result.quantity = (outcome.error, outcome.condition,
                                                       outcome.quantity)
    failed = [text for text, ok in outcome.checks if not ok]
    result.measured = "; ".join(text for text, _ in outcome.checks)
    if failed:
        result.measured = "FAILED: " + "; ".join(failed) + " | " + result.measured
    if not accurate:
        result.measured += f" | error {outcome.error:.2e} exceeds the bound"
    result.passed = accurate and not failed
    return result


def run_suite(names: list[str] | None = None, progress: Callable[[str], None] | None = None
              ) -> list[Result]:
    """Every case (or those named), in order."""
    results = []
    for c in CASES:
        if names is not None and c.name not in names:
            continue
        if progress:
            progress(c.name)
        results.append(run_case(c))
    return results


# --------------------------------------------------------------------------------------------
# Tools the cases share


def render_image(scene: Scene, projection: str, shading: str, size=SIZE, view_index: int = 0):
    """``core.render.render``'s colour image and message."""
    from core.render import render
    frame = render(scene, scene.views[view_index],
                   RenderSettings.for_scene(scene, projection=projection, shading=shading, size=size))
    return frame.color, frame.message


def probe(scene: Scene, projection: str, shading: str, size=SIZE, view_index: int = 0
          ) -> list[str]:
    """The names of the non-finite arrays between the stages of the real triangle path.

    Also flags ``1/W <= 0`` at a vertex a triangle uses and barycentric weights outside
    [-1e-9, 1 + 1e-9] (both would mean a point at or behind the eye got through). Vertices no
    triangle uses (the clipper keeps its input array whole) are not the rasterizer's concern.
    """
    from core.render import render
    arrays: dict[str, np.ndarray] = {}
    # The real pipeline, each stage's arrays copied as they pass (the z-buffer is reused).
    render(scene, scene.views[view_index],
           RenderSettings.for_scene(scene, projection=projection, shading=shading, size=size),
           inspect=lambda stage, found: arrays.update({k: np.array(v) for k, v in found.items()}))
    bad = []
    if "vertex_attrs" not in arrays:             # no triangle stage ran (e.g. an invalid view)
        return bad

    def finite(name, array):
        if not np.all(np.isfinite(array)):
            bad.append(name)

    finite("vertex attributes", arrays["vertex_attrs"])
    if "face_rgb" in arrays:
        finite("face colours", arrays["face_rgb"])
    finite("canonical points", arrays["canonical_points"])
    finite("clipped points", arrays["clipped_points"])
    finite("clipped attributes", arrays["clipped_attrs"])
    used = np.unique(arrays["clipped_triangles"])
    finite("device points", arrays["device_points"][used])
    finite("1/W", arrays["inv_w"][used])
    if len(used) and not np.all(arrays["inv_w"][used] > 0.0):
        bad.append("1/W <= 0")
    covered = arrays["tri"] >= 0
    finite("depth", arrays["depth"][covered])
    for name in ("b1", "b2"):
        b = arrays[name]
        finite(name, b[covered])
        if covered.any() and not (np.all(b[covered] >= -1e-9) and np.all(b[covered] <= 1 + 1e-9)):
            bad.append(f"{name} outside [0, 1]")
    return bad


def probe_all(out: Outcome, scene: Scene, projections=PROJECTIONS,
              shadings=SOLID_SHADINGS, size=SIZE) -> None:
    """One check: every stage finite for every projection and shading."""
    found = []
    for projection in projections:
        for shading in shadings:
            found += [f"{projection}/{shading}: {b}" for b in probe(scene, projection, shading, size)]
    out.check("every intermediate array finite" if not found else "non-finite: " + ", ".join(found),
              not found)


def one_pixel_mismatches(a: np.ndarray, b: np.ndarray, levels: int = 1) -> int:
    """Pixels of either image with no pixel within one of them in the other within ``levels``.

    ``a`` and ``b`` are ``(H, W, 3)`` (or ``(H, W)``) arrays of the same shape.
    """
    a = np.asarray(a, dtype=np.int32)
    b = np.asarray(b, dtype=np.int32)
    if a.ndim == 2:
        a, b = a[..., None], b[..., None]

    def unmatched(x, y):
        height, width = x.shape[:2]
        padded = np.pad(y, ((1, 1), (1, 1), (0, 0)), mode="edge")
        best = np.full((height, width), np.iinfo(np.int32).max)
        for dy in range(3):
            for dx in range(3):
                shifted = padded[dy:dy + height, dx:dx + width]
                best = np.minimum(best, np.max(np.abs(x - shifted), axis=2))
        return int(np.count_nonzero(best > levels))

    return unmatched(a, b) + unmatched(b, a)


def covered(image: np.ndarray) -> np.ndarray:
    """Coverage of an image rendered on a black background (see the module docstring)."""
    return np.any(image != 0, axis=2)


def quad(corners, material=GREY, closed=False, name="quad") -> Mesh:
    """Two triangles over four corners given counter-clockwise."""
    return Mesh(positions=np.asarray(corners, dtype=np.float64),
                triangles=np.array([[0, 1, 2], [0, 2, 3]]), material=material, closed=closed,
                name=name)


def square_xy(half: float, z: float, material=GREY, cx=0.0, cy=0.0) -> Mesh:
    return quad([(cx - half, cy - half, z), (cx + half, cy - half, z), (cx + half, cy + half, z),
                 (cx - half, cy + half, z)], material)


def scene_of(meshes, view: View, lights=None, ambient=(0.2, 0.2, 0.2), name="case") -> Scene:
    return Scene(name=name, meshes=list(meshes), views=[view],
                 lights=lights if lights is not None else [Light(position=(2.0, 3.0, 6.0))],
                 ambient=ambient, background=(0.0, 0.0, 0.0), size=SIZE)


def _sample(points: np.ndarray, limit: int = MAX_EXACT_POINTS) -> np.ndarray:
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) <= limit:
        return points
    return points[np.linspace(0, len(points) - 1, limit).round().astype(int)]


def coordinates(view: View, projection: str, points, size=SIZE) -> tuple[float, float]:
    """``(relative error, κ)`` of the canonical and device coordinates of ``points``.

    The float64 side is what the renderer runs (``normalizing_transform``, ``apply``,
    ``project_triangles``); the exact side :func:`core.analysis.exact.chain` on the same float inputs.
    Points at or behind the eye (W <= 0) have no device coordinates and are compared only in
    canonical coordinates.
    """
    points = _sample(points)
    vp = project.viewport(view.window, *size)
    n, z_min = normalizing_transform(view, projection)
    canonical = apply(n, points)[:, :3]
    numbers = exact.view_numbers(view)
    exact_points = [tuple(exact.q(c) for c in p) for p in points]
    ex_canonical, ex_device = exact.chain(numbers, exact_points, projection, vp)
    front = [i for i, d in enumerate(ex_device) if d is not None]
    device, _ = project.project_triangles(canonical[front], projection, z_min, vp)
    error = max(exact.relative_error(canonical, ex_canonical),
                exact.relative_error(device, [ex_device[i] for i in front]) if front else 0.0)

    def blocks(values):
        pts = [tuple(values[18 + 3 * i:21 + 3 * i]) for i in range(len(exact_points))]
        c, d = exact.chain(values[:18], pts, projection, vp)
        return [c, [d[i] for i in front]]

    return error, exact.condition(blocks, numbers + [c for p in exact_points for c in p])


def coordinate_accuracy(out: Outcome, view: View, projection: str, points, size=SIZE) -> None:
    error, kappa = coordinates(view, projection, points, size)
    out.accuracy(error, kappa, f"canonical and device coordinates ({projection})")


def scaled_view(view: View, s: float, offset=(0.0, 0.0, 0.0)) -> View:
    """The same camera for a scene scaled by ``s`` and then moved by ``offset``."""
    return View(vrp=tuple(s * np.asarray(view.vrp) + offset), vpn=view.vpn, vup=view.vup,
                window=tuple(s * np.asarray(view.window)), prp=tuple(s * np.asarray(view.prp)),
                front=s * view.front, back=s * view.back, label=view.label)


def scaled_scene(scene: Scene, s: float, offset=(0.0, 0.0, 0.0)) -> Scene:
    """Every position, view and light of ``scene`` scaled by ``s`` then moved by ``offset``."""
    offset = np.asarray(offset, dtype=np.float64)
    meshes = [Mesh(positions=s * m.positions + offset, triangles=m.triangles, edges=m.edges,
                   normals=m.normals, closed=m.closed, material=m.material, name=m.name)
              for m in scene.meshes]
    lights = [Light(intensity=l.intensity, direction=l.direction, attenuation=l.attenuation,
                    position=None if l.position is None else tuple(s * np.asarray(l.position) + offset))
              for l in scene.lights]
    return Scene(name=scene.name, meshes=meshes, views=[scaled_view(v, s, offset) for v in scene.views],
                 lights=lights, ambient=scene.ambient, background=scene.background, size=scene.size)


def sphere_and_cube() -> list[Mesh]:
    """A unit-sized, asymmetric little scene: a UV sphere and a cube beside it."""
    ball = uv_sphere(radius=0.5, segments=24, rings=12)
    ball.material = RED
    box = cube(size=0.3)
    box.positions = box.positions + (0.45, 0.35, 0.1)
    box.material = BLUE
    return [ball, box]


SMALL_VIEW = View(vrp=(0.0, 0.0, 0.0), vpn=(0.3, 0.4, 1.0), vup=(0.0, 1.0, 0.0),
                  window=(-0.8, 0.8, -0.8, 0.8), prp=(0.0, 0.0, 4.0), front=1.0, back=-1.0,
                  label="small")


def compare_images(out: Outcome, name: str, first: np.ndarray, second: np.ndarray) -> None:
    count = one_pixel_mismatches(first, second)
    out.check(f"{name}: {count} pixels differ beyond one pixel and one level", count == 0)

