"""Flat, Gouraud and Phong shading (core/shading/shade.py): the vertex step (prepare) and the per-pixel
resolve on hand-built visibility buffers, then end to end through the real z-buffer."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from core.settings import SOLID_SHADINGS
from core.shading import illumination as il
from core.shading import shade
from core.scene.model import Light, Material, Mesh, Scene
from core.camera.view import View

RED = Material(ka=0.2, kd=0.6, ks=0.3, n=10.0, od=(1.0, 0.1, 0.1))
BLUE = Material(ka=0.2, kd=0.6, ks=0.0, n=10.0, od=(0.1, 0.1, 1.0))
VIEW = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-2, 2, -2, 2), prp=(0, 0, 6),
            front=2, back=-2)
EYE = shade.eye_from_view(VIEW, "perspective")            # (0, 0, 6)


def quad_scene(closed=False, flip_second=False, light=(0.5, 0.5, 4.0)) -> Scene:
    """Two meshes: a red unit square at z = 0 (2 triangles) and a blue one at z = 0.5."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    second = tris[:, [0, 2, 1]] if flip_second else tris
    meshes = [Mesh(positions=square, triangles=tris, material=RED, closed=closed, name="red"),
              Mesh(positions=square + [-1.0, -1.0, 0.5], triangles=second, material=BLUE,
                   closed=closed, name="blue")]
    return Scene(name="quads", meshes=meshes, views=[VIEW], lights=[Light(position=light)],
                 ambient=(0.2, 0.2, 0.2), background=(0.0, 0.0, 0.2))


def visibility(tri, b1=None, b2=None):
    """A hand-built visibility buffer (the fields resolve reads)."""
    tri = np.asarray(tri, dtype=np.int32)
    zeros = np.zeros(tri.shape)
    return SimpleNamespace(tri=tri, b1=zeros if b1 is None else np.asarray(b1, float),
                           b2=zeros if b2 is None else np.asarray(b2, float))


# --- prepare ------------------------------------------------------------------------------

def test_prepare_concatenates_meshes_and_computes_only_what_the_mode_needs():
    scene = quad_scene()
    flat = shade.prepare("flat", scene, EYE)
    assert flat.positions.shape == (8, 3) and flat.triangles.shape == (4, 3)
    np.testing.assert_array_equal(flat.triangles[2:], [[4, 5, 6], [4, 6, 7]])
    np.testing.assert_array_equal(flat.face_surface, [0, 0, 1, 1])
    np.testing.assert_array_equal(flat.vertex_surface, [0] * 4 + [1] * 4)
    assert flat.vertex_attrs.shape == (8, 0) and flat.face_rgb.shape == (4, 3)
    assert flat.computed == ["face normals", "illuminate faces"]        # no vertex normals
    gouraud = shade.prepare("gouraud", scene, EYE)
    assert gouraud.vertex_attrs.shape == (8, 3) and gouraud.face_rgb is None
    assert gouraud.computed == ["vertex normals", "illuminate vertices"]
    phong = shade.prepare("phong", scene, EYE)
    assert phong.vertex_attrs.shape == (8, 6)
    np.testing.assert_array_equal(phong.vertex_attrs[:, 3:], phong.positions)
    np.testing.assert_array_equal(phong.vertex_attrs[:, :3], [[0, 0, 1]] * 8)
    assert phong.computed == ["vertex normals", "illuminate pixels"]


def test_flat_colour_is_the_model_once_at_the_polygons_centroid():
    # each unit square is one planar polygon of two triangles: lit once, at the square's
    # centre (the area-weighted centroid of its triangles), so both halves get one colour
    scene = quad_scene(light=(0.9, 0.1, 1.0))      # near one half: per-triangle lighting differs
    s = shade.prepare("flat", scene, EYE)
    centre = np.array([[0.5, 0.5, 0.0], [-0.5, -0.5, 0.5]])
    expected = il.illuminate(centre, [[0, 0, 1]] * 2, [0, 1], s.surfaces, s.lights, s.ambient,
                             s.eye, False)
    # float32 passes (core.shading.wide): the float64 model to float32's rounding
    np.testing.assert_allclose(s.face_rgb[[0, 2]], expected, rtol=2e-6)
    np.testing.assert_array_equal(s.face_rgb[0], s.face_rgb[1])          # no seam
    np.testing.assert_array_equal(s.face_rgb[2], s.face_rgb[3])
    halves = il.illuminate(np.array([[2, 1, 0], [1, 2, 0]]) / 3.0, [[0, 0, 1]] * 2, [0, 0],
                           s.surfaces, s.lights, s.ambient, s.eye, False)
    assert np.abs(halves[0] - halves[1]).max() > 0.02   # what lighting each triangle gave
    assert s.face_rgb[0, 0] > s.face_rgb[0, 2] and s.face_rgb[2, 2] > s.face_rgb[2, 0]  # mixed materials


def test_planar_polygons_join_coplanar_neighbours_only():
    from core.scene.generators import cube, icosphere, torus
    from core.scene.normals import face_normals, planar_polygons

    def polygons(positions, triangles):
        positions, triangles = np.asarray(positions, float), np.asarray(triangles)
        return planar_polygons(positions, triangles, face_normals(positions, triangles)[0])

    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    assert polygons(square, [[0, 1, 2], [0, 2, 3]]).tolist() == [0, 0]
    bent = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1e-3]]
    assert polygons(bent, [[0, 1, 2], [0, 2, 3]]).tolist() == [0, 1]
    folded = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0], [1, 1, 0], [0, 1, 0]]   # split vertices
    assert polygons(folded, [[0, 1, 2], [3, 4, 5]]).tolist() == [0, 0]
    flipped = polygons(square, [[0, 1, 2], [0, 3, 2]])                  # facing the other way
    assert flipped.tolist() == [0, 1]
    apart = square + [[3, 0, 0], [4, 0, 0], [4, 1, 0]]                  # coplanar, no shared edge
    assert polygons(apart, [[0, 1, 2], [4, 5, 6]]).tolist() == [0, 1]
    for mesh, expected in ((cube(), 6), (torus(segments=24, sides=12), 24 * 12),
                           (icosphere(subdivisions=2), 320)):
        found = polygons(mesh.positions, mesh.triangles)
        assert len(np.unique(found)) == expected, mesh.name     # a torus's quads are planar


def test_a_flat_square_has_no_seam_on_the_screen():
    from core import render
    from core.settings import RenderSettings

    scene = quad_scene(light=(0.9, 0.1, 1.0))
    frame = render(scene, VIEW, RenderSettings(projection="perspective", shading="flat",
                                               size=(80, 80)))
    red = frame.color[:, 40:][:40]                        # the red square: x, y in [0, 1]
    colours = np.unique(red.reshape(-1, 3), axis=0)
    colours = colours[np.any(colours != frame.color[0, 0], axis=1)]      # not the background
    assert len(colours) == 1, colours


def test_gouraud_vertex_colours_are_the_model_at_the_vertices():
    scene = quad_scene()
    s = shade.prepare("gouraud", scene, EYE)
    expected = il.illuminate(s.positions, [[0, 0, 1]] * 8, s.vertex_surface, s.surfaces,
                             s.lights, s.ambient, s.eye, False)
    np.testing.assert_allclose(s.vertex_attrs, expected, rtol=2e-6)      # float32 passes


def test_two_sided_flat_faces_are_lit_on_the_side_the_viewer_sees():
    # The blue square wound clockwise (normal -z) but open: lit as if its normal were +z.
    # Closed, the same winding faces away from the light: ambient only.
    open_ = shade.prepare("flat", quad_scene(closed=False, flip_second=True), EYE).face_rgb
    ref = shade.prepare("flat", quad_scene(closed=False, flip_second=False), EYE).face_rgb
    np.testing.assert_array_equal(open_[2:], ref[2:])      # same centroids, normal turned up
    closed = shade.prepare("flat", quad_scene(closed=True, flip_second=True), EYE).face_rgb
    np.testing.assert_allclose(closed[2:], [[0.2 * 0.2 * 0.1, 0.2 * 0.2 * 0.1, 0.2 * 0.2 * 1.0]] * 2)


def test_replacing_a_meshs_arrays_recomputes_its_normals():
    scene = quad_scene()
    before = shade.prepare("phong", scene, EYE).vertex_attrs[:4, :3]
    np.testing.assert_array_equal(before, [[0, 0, 1]] * 4)
    again = shade.prepare("phong", scene, EYE)
    assert again.vertex_attrs is shade.prepare("phong", scene, EYE).vertex_attrs   # kept
    assert not again.vertex_attrs.flags.writeable and not again.positions.flags.writeable
    red = scene.meshes[0]
    red.positions = red.positions[:, [2, 1, 0]]             # the square turned into x = 0
    after = shade.prepare("phong", scene, EYE).vertex_attrs[:4, :3]
    np.testing.assert_array_equal(after, [[-1, 0, 0]] * 4)


def test_unknown_mode_is_refused():
    with pytest.raises(ValueError, match="shading must be one of"):
        shade.prepare("toon", quad_scene(), EYE)


# --- resolve on hand-built buffers --------------------------------------------------------

def test_resolve_flat_looks_up_the_source_face():
    s = shade.prepare("flat", quad_scene(), EYE)
    # Three post-clip triangles: 0 and 1 came from face 2, triangle 2 from face 0.
    source = np.array([2, 2, 0])
    vis = visibility([[-1, 0, 1], [2, 2, -1]])
    image = shade.resolve(s, vis, np.zeros((3, 3), np.int64), np.zeros((0, 0)), source,
                          (0.0, 0.0, 0.2))
    rgb8 = il.to_uint8(s.face_rgb)
    assert image.shape == (2, 3, 3) and image.dtype == np.uint8
    np.testing.assert_array_equal(image[0, 0], [0, 0, 51])              # 0.2 * 255 = 51
    np.testing.assert_array_equal(image[0, 1], rgb8[2])
    np.testing.assert_array_equal(image[0, 2], rgb8[2])
    np.testing.assert_array_equal(image[1, 0], rgb8[0])
    np.testing.assert_array_equal(image[1, 2], [0, 0, 51])


def test_resolve_gouraud_interpolates_vertex_colours():
    s = shade.prepare("gouraud", quad_scene(), EYE)
    colours = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    b1 = np.array([[0.0, 1.0, 0.0, 0.25]])
    b2 = np.array([[0.0, 0.0, 1.0, 0.5]])
    vis = visibility([[0, 0, 0, 0]], b1, b2)
    image = shade.resolve(s, vis, np.array([[0, 1, 2]]), colours, np.array([0]), (0, 0, 0))
    # weights (1-b1-b2, b1, b2) of the three colours, times 255, rounded half up
    np.testing.assert_array_equal(image[0], [[255, 0, 0], [0, 255, 0], [0, 0, 255],
                                             [64, 64, 128]])             # 63.75 → 64, 127.5 → 128


def test_resolve_phong_evaluates_the_model_per_pixel():
    scene = quad_scene(closed=True)
    s = shade.prepare("phong", scene, EYE)
    # Clipped triangle 0 is original face 0 (red square); interpolate at three pixels.
    b1 = np.array([[0.2, 0.5, 0.1]])
    b2 = np.array([[0.3, 0.25, 0.8]])
    vis = visibility([[0, 0, 0]], b1, b2)
    image = shade.resolve(s, vis, s.triangles[:1], s.vertex_attrs, np.array([0]), (0, 0, 0))
    corners = s.positions[s.triangles[0]]
    w = np.stack([1 - b1[0] - b2[0], b1[0], b2[0]], axis=1)
    points = w @ corners
    expected = il.illuminate(points, [[0, 0, 1]] * 3, [0, 0, 0], s.surfaces, s.lights,
                             s.ambient, s.eye, False)
    np.testing.assert_array_equal(image[0], il.to_uint8(expected))
    assert len(np.unique(image[0], axis=0)) == 3          # the highlight varies across the face


def test_resolve_phong_renormalises_and_flips_per_pixel():
    # Vertex normals (0,0,1) and (0,0,-1)-ish: the interpolated normal is renormalised; a
    # normal interpolated to zero gives ambient only; an open mesh flips it to the viewer.
    scene = quad_scene(closed=False)
    s = shade.prepare("phong", scene, EYE)
    attrs = s.vertex_attrs[:3].copy()
    attrs[:, :3] = [[0, 0, 2.0], [0, 0, -2.0], [0, 0, 2.0]]
    vis = visibility([[0, 0]], [[0.5, 1.0]], [[0.0, 0.0]])           # centre of edge 0-1; vertex 1
    image = shade.resolve(s, vis, np.array([[0, 1, 2]]), attrs, np.array([0]), (0, 0, 0))
    ambient_only = il.to_uint8(0.2 * 0.2 * np.array(RED.od))
    np.testing.assert_array_equal(image[0, 0], ambient_only)
    lit_up = il.illuminate(s.positions[1:2], [[0, 0, 1]], [0], s.surfaces, s.lights, s.ambient,
                           s.eye, False)
    np.testing.assert_array_equal(image[0, 1], il.to_uint8(lit_up[0]))   # (0,0,-1) flipped up


def test_resolve_writes_into_out_and_checks_the_attribute_count():
    s = shade.prepare("gouraud", quad_scene(), EYE)
    out = np.zeros((1, 2, 3), np.uint8)
    result = shade.resolve(s, visibility([[-1, -1]]), np.zeros((0, 3), np.int64),
                           np.zeros((0, 3)), np.zeros(0, np.int64), (1.0, 1.0, 1.0), out=out)
    assert result is out and np.all(out == 255)
    with pytest.raises(ValueError, match="carries 3 attributes per vertex, the clipper gave an array of shape .0, 6."):
        shade.resolve(s, visibility([[-1]]), np.zeros((0, 3), np.int64), np.zeros((0, 6)),
                      np.zeros(0, np.int64), (0, 0, 0))


def test_resolve_refuses_indices_that_point_nowhere():
    s = shade.prepare("phong", quad_scene(), EYE)
    one = np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="names triangle 1, but only 1 were clipped"):
        shade.resolve(s, visibility([[1]]), one, s.vertex_attrs, np.array([0]), (0, 0, 0))
    with pytest.raises(ValueError, match="source must give"):
        shade.resolve(s, visibility([[0]]), one, s.vertex_attrs, np.array([4]), (0, 0, 0))
    with pytest.raises(ValueError, match="attribute rows out of range"):
        shade.resolve(s, visibility([[0]]), one, s.vertex_attrs[:2], np.array([0]), (0, 0, 0))


def test_empty_scene_resolves_to_background():
    scene = Scene(name="empty", meshes=[], views=[VIEW], background=(1.0, 0.5, 0.0))
    for mode in SOLID_SHADINGS:
        s = shade.prepare(mode, scene, EYE)
        image = shade.resolve(s, visibility(np.full((2, 2), -1)), np.zeros((0, 3), np.int64),
                              s.vertex_attrs, np.zeros(0, np.int64), scene.background)
        assert np.all(image == [255, 128, 0])


# --- end to end through the real z-buffer -------------------------------------------------

def render_with_raster(scene: Scene, view: View, projection: str, mode: str, size):
    """Normalize, project, rasterize and resolve (no clipping: the scene lies inside the
    view volume); what core.render does for the solid pipeline, reduced to the minimum."""
    from core.pipeline import project
    from core.pipeline import raster
    from core.transforms import apply
    from core.camera.view import normalizing_transform
    width, height = size
    n, z_min = normalizing_transform(view, projection)
    s = shade.prepare(mode, scene, shade.eye_from_view(view, projection))
    points = apply(n, s.positions)[:, :3]
    assert np.all(points[:, 2] <= z_min if projection == "perspective" else points[:, 2] <= 0)
    xy_z, inv_w = project.project_triangles(points, projection, z_min,
                                            project.viewport(view.window, width, height))
    vis = raster.rasterize(xy_z, inv_w, s.triangles, width, height)
    return shade.resolve(s, vis, s.triangles, s.vertex_attrs, np.arange(len(s.triangles)),
                         scene.background), vis


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_nearer_mesh_wins_and_modes_agree_on_a_flat_face(projection):
    # The blue square (z = 0.5) hides part of the red one (z = 0). Matte faces under a
    # directional light have one colour each, so flat, Gouraud and Phong agree.
    scene = quad_scene()
    scene.lights = [Light(direction=(0.0, 0.0, 1.0))]
    for mesh in scene.meshes:
        mesh.material = Material(ka=0.2, kd=0.6, ks=0.0, od=mesh.material.od)
    images = {m: render_with_raster(scene, VIEW, projection, m, (40, 40))[0] for m in SOLID_SHADINGS}
    image = images["flat"]
    # device (x, y) of world (-0.25, -0.25) and (0.75, 0.75): only blue, only red
    blue, red = image[40 - 18, 18], image[40 - 28, 28]
    assert blue[2] > blue[0] and red[0] > red[2]
    np.testing.assert_array_equal(image[0, 0], [0, 0, 51])               # background
    for mode in ("gouraud", "phong"):
        assert np.max(np.abs(images[mode].astype(int) - image.astype(int))) <= 1


def test_resolve_speed_at_500x500(benchmark):
    """Every pixel covered (the worst case): run with --benchmark-enable to time it."""
    scene = quad_scene()
    rng = np.random.default_rng(0)
    tri = rng.integers(0, 4, (500, 500)).astype(np.int32)
    b1 = rng.random((500, 500)) * 0.5
    b2 = rng.random((500, 500)) * 0.5
    vis = visibility(tri, b1, b2)
    s = shade.prepare("phong", scene, EYE)
    out = np.empty((500, 500, 3), np.uint8)
    image = benchmark(shade.resolve, s, vis, s.triangles, s.vertex_attrs, np.arange(4),
                      scene.background, out)
    assert image.shape == (500, 500, 3) and image.any()


def test_flat_faces_are_lit_at_their_polygons_centroid_from_points_made_once_per_scene():
    # Each square is one planar polygon: both of its triangles are lit once, at the square's
    # centroid with its normal (FvDFH 16.2.3), whatever the eye. The points and normals are
    # the scene's: a second frame from another eye reads the same arrays, not new ones.
    from core.context import RenderContext
    scene, context = quad_scene(), RenderContext()
    s = shade.prepare("flat", scene, EYE, context=context)
    centroids = [[0.5, 0.5, 0.0]] * 2 + [[-0.5, -0.5, 0.5]] * 2
    expected = il.illuminate(np.array(centroids), [[0, 0, 1]] * 4, s.face_surface, s.surfaces,
                             s.lights, s.ambient, s.eye, False)
    np.testing.assert_allclose(s.face_rgb, expected, rtol=2e-6)         # float32 passes
    points, normals = s.face_points
    np.testing.assert_array_equal(points, centroids)
    np.testing.assert_array_equal(normals, [[0, 0, 1]] * 4)
    other = shade.prepare("flat", scene, shade.eye_from_view(VIEW, "parallel"), context=context)
    assert other.face_points[0] is points and other.face_points[1] is normals
