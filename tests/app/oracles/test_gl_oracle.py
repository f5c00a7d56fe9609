"""The oracle nobody here wrote: our CPU pipeline against OpenGL (Mesa llvmpipe through EGL).

- Coverage: the same scenes, the same matrices; the CPU's covered pixels (those not of the
  background colour) against GL's flat-colour coverage: no pixel may differ (both snap to 8
  sub-pixel bits with the top-left rule). On a failure the report says which differing pixels
  lie off every triangle edge: the post-clip edges of the triangles drawn, projected to the
  device, traced and dilated by one pixel (our own Sutherland–Hodgman and line tracing here,
  not the core's). What is shared with the product: the scene, its views and N_per/N_par
  (``normalizing_transform``), whose factors test_course_views.py holds to hand values.
- Shading: flat, Gouraud and Phong against GLSL shaders implementing the same Phong
  illumination model (``app/oracles/reference_gl.py``): on pixels away from triangle edges and
  silhouettes, at most 2/255 per channel.

A failing comparison writes the two images and the difference to ``tests/_failures/``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tools import llvmpipe_context, need_module                    # noqa: E402

moderngl = need_module("moderngl", "the OpenGL oracle needs moderngl")

from core.settings import RenderSettings
from core.render import render                                   # noqa: E402
from core.scene.model import Light, Material, Mesh, Scene              # noqa: E402
from core.transforms import apply                                # noqa: E402
from core.scene.formats import load_scene                              # noqa: E402
from core.paths import SCENES_DIR                                # noqa: E402
from core.camera.view import View, normalizing_transform, problems      # noqa: E402
from app.bench.bench import bench_scene                                # noqa: E402
from app.oracles.reference_gl import GLRenderer, eye_of                  # noqa: E402
from core.scene.normals import face_normals                             # noqa: E402
from app.oracles.reference_gl import clip_from_world                      # noqa: E402

from tests.conftest import FAILURES                          # noqa: E402
SIZE = (500, 500)
MAGENTA = (1.0, 0.0, 1.0)          # a background no test scene's shading produces


@pytest.fixture(scope="module")
def gl():
    renderer = GLRenderer(SIZE, ctx=llvmpipe_context())   # only the context may be missing
    yield renderer
    renderer.release()


def _save_failure(name: str, **images: np.ndarray) -> str:
    from PIL import Image
    FAILURES.mkdir(exist_ok=True)
    for key, image in images.items():
        if image.dtype == bool:
            image = image.astype(np.uint8) * 255
        Image.fromarray(image).save(FAILURES / f"{name}-{key}.png")
    return f"images in {FAILURES}/{name}-*.png"


# ------------------------------------------------------------------ the edges the two may disagree on

def _planes(points: np.ndarray, projection: str, z_min: float) -> np.ndarray:
    """Signed distances ``(N, 6)`` to the canonical volume's planes; inside is >= 0."""
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    if projection == "parallel":
        return np.stack([1 - x, 1 + x, 1 - y, 1 + y, -z, z + 1], axis=1)
    return np.stack([-z - x, x - z, -z - y, y - z, z + 1, z_min - z], axis=1)


def _clip_polygon(polygon: np.ndarray, projection: str, z_min: float) -> np.ndarray:
    """Sutherland–Hodgman against the six planes, one plane at a time."""
    for k in range(6):
        if len(polygon) == 0:
            break
        d = _planes(polygon, projection, z_min)[:, k]
        out = []
        for i in range(len(polygon)):
            j = (i + 1) % len(polygon)
            if d[i] >= 0:
                out.append(polygon[i])
            if (d[i] >= 0) != (d[j] >= 0):
                t = d[i] / (d[i] - d[j])
                out.append(polygon[i] + t * (polygon[j] - polygon[i]))
        polygon = np.array(out).reshape(-1, 3)
    return polygon


def _drawn_triangles(mesh: Mesh, view: View, projection: str) -> np.ndarray:
    """The triangles the CPU draws: all, or for a closed mesh those not facing away."""
    if not mesh.closed:
        return mesh.triangles
    eye, toward = eye_of(view)
    normal = face_normals(mesh.positions, mesh.triangles)[0]
    if projection == "perspective":
        to_eye = eye - mesh.positions[mesh.triangles[:, 0]]
    else:
        to_eye = np.broadcast_to(toward, normal.shape)
    facing = np.einsum("ij,ij->i", normal, to_eye)
    # Keep edge-on faces too: a larger edge mask only makes the test stricter elsewhere.
    return mesh.triangles[facing >= -1e-9 * np.linalg.norm(to_eye, axis=1)]


def edge_mask(scene: Scene, view_index: int, projection: str, size=SIZE) -> np.ndarray:
    """``(H, W)`` bool, image order: pixels within about a pixel of a drawn triangle's edge."""
    width, height = size
    view = scene.views[view_index]
    n, z_min = normalizing_transform(view, projection)
    # Canonical coordinates to GL clip coordinates: the oracle's L·M (clip_from_world = L·M·N).
    to_clip = clip_from_world(view, projection, size) @ np.linalg.inv(n)
    segments = []
    for mesh in scene.meshes:
        triangles = _drawn_triangles(mesh, view, projection)
        if len(triangles) == 0:
            continue
        canonical = apply(n, mesh.positions)[:, :3]
        d = _planes(canonical, projection, z_min)[triangles]          # (T, 3 corners, 6)
        inside = np.all(d >= 0, axis=(1, 2))
        rejected = np.any(np.all(d < 0, axis=1), axis=1)
        corners = canonical[triangles[inside]]
        for k in range(3):
            segments.append(np.stack([corners[:, k], corners[:, (k + 1) % 3]], axis=1))
        for t in np.flatnonzero(~inside & ~rejected):
            polygon = _clip_polygon(canonical[triangles[t]], projection, z_min)
            if len(polygon) >= 2:
                segments.append(np.stack([polygon, np.roll(polygon, -1, axis=0)], axis=1))
    mask = np.zeros((height, width), dtype=bool)
    if not segments:
        return mask
    seg = np.concatenate(segments)                                     # (S, 2, 3) canonical
    h = np.concatenate([seg, np.ones(seg.shape[:2] + (1,))], axis=2) @ to_clip.T
    ndc = h[..., :2] / h[..., 3:4]
    device = (ndc + 1.0) / 2.0 * np.array([width, height])             # x right, y up, pixels
    # Trace each segment at quarter-pixel steps and mark the pixel under each sample.
    length = np.linalg.norm(device[:, 1] - device[:, 0], axis=1)
    steps = np.ceil(4 * length).astype(np.int64) + 1
    which = np.repeat(np.arange(len(seg)), steps)
    first = np.cumsum(steps) - steps
    t = (np.arange(steps.sum()) - first[which]) / np.maximum(steps[which] - 1, 1)
    p = device[which, 0] + t[:, None] * (device[which, 1] - device[which, 0])
    col = np.floor(p[:, 0]).astype(np.int64)
    row = height - 1 - np.floor(p[:, 1]).astype(np.int64)
    ok = (col >= 0) & (col < width) & (row >= 0) & (row < height)
    mask[row[ok], col[ok]] = True
    # Dilate by one pixel (3 x 3).
    padded = np.pad(mask, 1)
    grown = np.zeros_like(mask)
    for dr in range(3):
        for dc in range(3):
            grown |= padded[dr:dr + height, dc:dc + width]
    return grown


# ------------------------------------------------------------------ test scenes

def _view(vrp, vpn, vup, window, prp, front, back, label="test view") -> View:
    return View(vrp=vrp, vpn=vpn, vup=vup, window=window, prp=prp, front=front, back=back,
                label=label)


def few_triangles() -> Scene:
    """Three open triangles of mixed winding and size, one a sliver, one crossing another."""
    positions = np.array([
        (-3.0, -2.5, 0.0), (2.5, -2.0, -1.0), (-0.5, 3.0, 0.5),            # large, CCW
        (0.3, -0.4, 2.0), (1.1, 2.7, -2.0), (2.9, 0.2, 0.0),               # crosses the first
        (-3.5, 3.2, 0.0), (3.4, 3.0, 0.3), (-3.4, 3.45, -0.2),             # a long sliver
    ])
    mesh = Mesh(positions=positions, triangles=np.arange(9).reshape(3, 3), closed=False,
                material=Material(od=(0.9, 0.8, 0.3)))
    views = [_view((0, 0, 0), (0.2, -0.1, 1), (0, 1, 0), (-4, 4, -4, 4), (0.5, 0.3, 12), 5, -5),
             _view((0, 0, 0), (0, 0, 1), (0, 1, 0), (-4.3, 4.3, -2.5, 4.1), (0.4, -0.2, 9), 4, -4)]
    return Scene("few triangles", [mesh], views, lights=[Light(position=(3.0, 5.0, 10.0))])


def crossing_the_eye() -> Scene:
    """A floor of triangles running from far behind the window to behind the eye: the front
    plane and the eye plane cut it (perspective), the back plane too."""
    xs, zs = np.linspace(-6, 6, 7), np.linspace(-30, 12, 8)
    gx, gz = np.meshgrid(xs, zs, indexing="ij")
    positions = np.stack([gx.ravel(), np.full(gx.size, -1.5), gz.ravel()], axis=1)
    positions[:, 1] += 0.05 * np.sin(positions[:, 0] * 3 + positions[:, 2])   # not quite planar
    cols = len(zs)
    tris = []
    for i in range(len(xs) - 1):
        for j in range(cols - 1):
            a, b, c, d = i * cols + j, (i + 1) * cols + j, i * cols + j + 1, (i + 1) * cols + j + 1
            tris += [(a, c, b), (b, c, d)]
    floor = Mesh(positions=positions, triangles=np.array(tris), closed=False,
                 material=Material(od=(0.4, 0.8, 0.5)))
    views = [_view((0, 0, 0), (0, 0.15, 1), (0, 1, 0), (-2, 2, -2, 2), (0, 0, 6), 2, -20)]
    return Scene("crossing the eye", [floor], views, lights=[Light(direction=(0.3, 1.0, 0.4))])


def scene_file(name: str, triangles: int = 1000) -> Scene:
    """A shipped scene (``scenes/NAME``), or the bench's sphere + torus for ``sphere_torus``."""
    if name == "sphere_torus":
        return bench_scene(triangles)        # at 1000 triangles, big enough to leave room off edges
    return load_scene(SCENES_DIR / name)


HAND_MADE = {"few triangles": few_triangles, "crossing the eye": crossing_the_eye}
COVERAGE_SCENES = [*HAND_MADE, "cube.toml", "torus.toml", "few_triangles.tri",
                   "interpenetrating.tri", "crossing_front_plane.tri", "sphere_torus"]


def coverage_scene(name: str) -> Scene:
    return HAND_MADE[name]() if name in HAND_MADE else scene_file(name)


def valid_views(scene: Scene, projection: str) -> list[int]:
    return [i for i, view in enumerate(scene.views) if not problems(view, projection)]


# ------------------------------------------------------------------ coverage

def cpu_coverage(scene: Scene, view_index: int, projection: str) -> np.ndarray:
    on_magenta = dataclasses.replace(scene, background=MAGENTA)
    frame = render(on_magenta, on_magenta.views[view_index],
                   RenderSettings.for_scene(on_magenta, projection=projection, shading="flat", size=SIZE))
    assert frame.message is None, frame.message
    return np.any(frame.color != np.array([255, 0, 255], np.uint8), axis=2)


def gl_coverage(gl: GLRenderer, scene: Scene, view_index: int, projection: str) -> np.ndarray:
    gl.load(scene, modes=("coverage",))
    return gl.render(gl.scene.views[view_index], projection, "coverage")[:, :, 0] > 127


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("name", COVERAGE_SCENES)
def test_coverage_matches_llvmpipe_except_on_edges(gl, name, projection):
    scene = coverage_scene(name)
    views = valid_views(scene, projection)
    assert views, f"{name}: no view valid for {projection}"
    for view_index in views:
        ours = cpu_coverage(scene, view_index, projection)
        theirs = gl_coverage(gl, scene, view_index, projection)
        edges = edge_mask(scene, view_index, projection)
        differ = ours ^ theirs
        label = f"{name}-{projection}-view{view_index + 1}"
        # The comparison must mean something: both draw, and edges leave most pixels free.
        assert theirs.sum() > 100, f"{label}: llvmpipe drew almost nothing"
        assert edges.mean() < 0.5, f"{label}: the edge mask covers {edges.mean():.0%} of the image"
        off_edge = differ & ~edges
        if differ.any():        # measured: 0 differing pixels in every case (the README's claim)
            where = _save_failure(label, ours=ours, llvmpipe=theirs, differ=differ, off_edge=off_edge)
            rows, cols = np.nonzero(off_edge)
            pytest.fail(f"{label}: {differ.sum()} pixels differ ({differ.mean():.3%}; limit: none), "
                        f"{off_edge.sum()} of them off every triangle edge "
                        f"(first at row, col {list(zip(rows[:5], cols[:5]))}); {where}")


def test_edge_mask_traces_a_known_triangle():
    """The helper itself: one triangle's edges, traced, are where they should be."""
    scene = few_triangles()
    scene.meshes[0] = Mesh(positions=[(-2.0, -2.0, 0.0), (2.0, -2.0, 0.0), (-2.0, 2.0, 0.0)],
                           triangles=[(0, 1, 2)])
    view = _view((0, 0, 0), (0, 0, 1), (0, 1, 0), (-4, 4, -4, 4), (0, 0, 10), 1, -1)
    scene.views = [view]
    mask = edge_mask(scene, 0, "parallel")
    # Window -4..4 on 500 px: x = -2 is device x 125 (the left edge of column 125), y = -2 is
    # device row 125, image row 499 - 125 = 374; the hypotenuse passes device (250, 250).
    assert mask[130:370, 124:127].all()              # the left edge, dilated one pixel
    assert mask[373:376, 130:370].all()              # the bottom edge
    assert mask[249, 250] and mask[499 - 300, 200]   # the hypotenuse
    assert not mask[130:370, 122].any()              # three pixels left of the left edge
    assert not mask[291, 208]                        # the centroid, far from every edge
    assert not mask[50, 450]                         # outside
    assert mask.mean() < 0.02


# ------------------------------------------------------------------ shading

def _lit(scene: Scene, variant: str) -> Scene:
    """The scene's own lights, or a set that exercises the rest of the model."""
    if variant == "own lights":
        return scene
    lights = [Light(intensity=(0.9, 0.8, 0.7), position=(3.0, 4.0, 6.0), attenuation=(0.5, 0.05, 0.01)),
              Light(intensity=(0.3, 0.4, 0.6), direction=(-1.0, 0.5, 0.8))]
    return dataclasses.replace(scene, specular="halfway", lights=lights, ambient=(0.2, 0.25, 0.3))


@pytest.mark.parametrize("variant", ["own lights", "halfway, attenuated"])
@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
@pytest.mark.parametrize("name", ["sphere.toml", "torus.toml", "interpenetrating.tri"])
def test_shading_matches_llvmpipe_away_from_edges(gl, name, shading, projection, variant):
    scene = _lit(scene_file(name), variant)
    gl.load(scene, modes=(shading, "coverage"))
    views = valid_views(scene, projection)
    assert views, f"{name}: no view valid for {projection}"
    for view_index in views:
        frame = render(scene, scene.views[view_index],
                       RenderSettings.for_scene(scene, projection=projection, shading=shading, size=SIZE))
        assert frame.message is None, frame.message
        theirs = gl.render(gl.scene.views[view_index], projection, shading)
        covered = gl.render(gl.scene.views[view_index], projection, "coverage")[:, :, 0] > 127
        away = covered & ~edge_mask(scene, view_index, projection)
        label = f"shading-{name}-{shading}-{projection}-{variant}-view{view_index + 1}"
        # Dense meshes leave a minority of pixels off every edge; still thousands to compare.
        assert away.sum() >= 2000, f"{label}: only {away.sum()} pixels away from edges"
        diff = np.abs(frame.color.astype(np.int16) - theirs.astype(np.int16)).max(axis=2)
        worst = int(diff[away].max())
        if worst > 2:
            where = _save_failure(label, ours=frame.color, llvmpipe=theirs,
                                  differ=((diff > 2) & away))
            pytest.fail(f"{label}: {np.count_nonzero((diff > 2) & away)} pixels away from edges "
                        f"differ by more than 2/255 (worst {worst}); {where}")


def test_shading_comparison_can_fail(gl):
    """The control: 2/255 is tight enough to tell Gouraud from Phong, and a changed exponent."""
    scene = scene_file("sphere.toml")
    gl.load(scene, modes=("gouraud", "phong", "coverage"))
    covered = gl.render(gl.scene.views[0], "perspective", "coverage")[:, :, 0] > 127
    away = covered & ~edge_mask(scene, 0, "perspective")
    ours_phong = render(scene, scene.views[0],
                        RenderSettings.for_scene(scene, projection="perspective", shading="phong", size=SIZE)).color.astype(np.int16)
    gouraud = gl.render(gl.scene.views[0], "perspective", "gouraud").astype(np.int16)
    assert np.abs(ours_phong - gouraud).max(axis=2)[away].max() > 2
    shinier = dataclasses.replace(scene, meshes=[dataclasses.replace(
        scene.meshes[0], material=dataclasses.replace(scene.meshes[0].material,
                                                      n=scene.meshes[0].material.n * 1.5))])
    gl.load(shinier, modes=("phong",))
    assert np.abs(ours_phong - gl.render(gl.scene.views[0], "perspective", "phong")).max(axis=2)[away].max() > 2
