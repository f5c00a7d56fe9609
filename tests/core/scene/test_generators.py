"""The generators (core.scene.generators): closed and outward where closed, counts, exact normals."""

from __future__ import annotations

import numpy as np
import pytest

from core.scene import generators as g
from core.scene.formats.mesh import edge_problem, signed_volume


def directed_edges_pair_up(triangles: np.ndarray) -> bool:
    """Every directed edge occurs once, and so does its reverse (an independent count)."""
    t = np.asarray(triangles)
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    seen = {}
    for a, b in edges.tolist():
        seen[(a, b)] = seen.get((a, b), 0) + 1
    return all(count == 1 and seen.get((b, a)) == 1 for (a, b), count in seen.items())


def face_normals(mesh) -> np.ndarray:
    p = mesh.positions[mesh.triangles]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


CLOSED = {
    "cube": (lambda: g.cube(), 12, 8),
    "cube 4x4": (lambda: g.cube(size=3.0, subdivisions=4), 12 * 16, 6 * 16 + 2),
    "uv_sphere": (lambda: g.uv_sphere(segments=12, rings=7), 2 * 12 * 6, 12 * 6 + 2),
    "icosphere 0": (lambda: g.icosphere(0), 20, 12),
    "icosphere 3": (lambda: g.icosphere(3), 20 * 4 ** 3, 10 * 4 ** 3 + 2),
    "torus": (lambda: g.torus(R=2.0, r=0.5, segments=10, sides=6), 2 * 10 * 6, 60),
    "torus_knot": (lambda: g.torus_knot(segments=90, sides=8), 2 * 90 * 8, 720),
}


@pytest.mark.parametrize("name", list(CLOSED))
def test_closed_meshes_are_closed_consistent_and_outward(name):
    make, triangles, vertices = CLOSED[name]
    mesh = make()
    # Texture seams double vertices (exact copies): the solid is judged on distinct positions.
    distinct, inverse = np.unique(mesh.positions, axis=0, return_inverse=True)
    welded = inverse.reshape(-1)[mesh.triangles]
    assert len(mesh.triangles) == triangles and len(distinct) == vertices
    assert mesh.closed
    assert directed_edges_pair_up(welded)
    assert edge_problem(welded) is None
    assert signed_volume(mesh.positions, mesh.triangles) > 0
    assert mesh.triangles.min() == 0 and mesh.triangles.max() == len(mesh.positions) - 1


@pytest.mark.parametrize("make, u_steps, v_steps", [
    (lambda: g.uv_sphere(segments=12, rings=7), 12, 7),
    (lambda: g.torus(R=2.0, r=0.5, segments=10, sides=6), 10, 6),
    (lambda: g.torus_knot(segments=90, sides=8), 90, 8),
    (lambda: g.bezier_surface(patches=2, resolution=4), 8, 8),
])
def test_generators_keep_their_texture_coordinates(make, u_steps, v_steps):
    """(u, v) in [0, 1]², one grid step across any triangle (no triangle spans the seam),
    and every value of the grid present: u = i / u_steps, v = j / v_steps."""
    mesh = make()
    uv = mesh.uv
    assert uv is not None and uv.shape == (len(mesh.positions), 2)
    assert uv.min() >= 0.0 and uv.max() <= 1.0
    span = np.ptp(uv[mesh.triangles], axis=1)
    assert span[:, 0].max() <= 1.0 / u_steps + 1e-12 and span[:, 1].max() <= 1.0 / v_steps + 1e-12
    assert np.allclose(np.unique(np.round(uv[:, 1] * v_steps, 9)) % 1, 0)
    assert set(mesh.attributes) >= {"position", "normal", "uv"}


def test_sphere_uv_is_longitude_and_latitude():
    mesh = g.uv_sphere(segments=16, rings=8)
    p, (u, v) = mesh.positions, mesh.uv.T
    body = (v > 0) & (v < 1)
    phi = np.mod(np.arctan2(-p[body, 2], p[body, 0]), 2 * np.pi)
    seam = np.isclose(u[body], 1.0)
    phi[seam & (phi < 1e-9)] = 2 * np.pi
    assert np.allclose(u[body] * 2 * np.pi, phi)
    assert np.allclose(np.arccos(np.clip(p[body, 1], -1, 1)), (1 - v[body]) * np.pi)


def test_volumes_converge_to_the_true_solids():
    assert signed_volume(*_pt(g.cube(size=3.0, subdivisions=3))) == pytest.approx(27.0)
    sphere = g.uv_sphere(radius=2.0, segments=256, rings=128)
    assert signed_volume(*_pt(sphere)) == pytest.approx(4 / 3 * np.pi * 8, rel=1e-3)
    torus = g.torus(R=2.0, r=0.5, segments=256, sides=128)
    assert signed_volume(*_pt(torus)) == pytest.approx(2 * np.pi ** 2 * 2.0 * 0.25, rel=1e-3)
    # A tube of radius rho along a curve of length L encloses pi rho^2 L.
    knot = g.torus_knot(segments=2048, sides=64)
    t = np.linspace(0, 2 * np.pi, 20001)
    radial = 1.0 + 0.45 * np.cos(3 * t)
    curve = np.stack([radial * np.cos(2 * t), radial * np.sin(2 * t), 0.45 * np.sin(3 * t)], 1)
    length = np.linalg.norm(np.diff(curve, axis=0), axis=1).sum()
    assert signed_volume(*_pt(knot)) == pytest.approx(np.pi * 0.22 ** 2 * length, rel=2e-3)


def _pt(mesh):
    return mesh.positions, mesh.triangles


@pytest.mark.parametrize("make", [lambda: g.uv_sphere(radius=1.5), lambda: g.icosphere(2, radius=1.5),
                                  lambda: g.torus(R=1.0, r=0.3), lambda: g.bezier_surface(),
                                  lambda: g.torus_knot(segments=200, sides=12)])
def test_analytic_normals_are_unit_and_agree_with_the_winding(make):
    mesh = make()
    assert mesh.normals is not None and mesh.normals.shape == mesh.positions.shape
    assert np.linalg.norm(mesh.normals, axis=1) == pytest.approx(1.0)
    corner_normals = mesh.normals[mesh.triangles].sum(axis=1)
    assert np.all(np.einsum("ij,ij->i", face_normals(mesh), corner_normals) > 0)


def test_sphere_and_torus_normals_are_exact():
    sphere = g.uv_sphere(radius=1.5, segments=16, rings=9)
    assert np.linalg.norm(sphere.positions, axis=1) == pytest.approx(1.5)
    assert np.allclose(sphere.normals * 1.5, sphere.positions)
    torus = g.torus(R=1.0, r=0.3, segments=16, sides=9)
    p = torus.positions
    core = np.column_stack([p[:, :2] / np.linalg.norm(p[:, :2], axis=1, keepdims=True), np.zeros(len(p))])
    # The point lies r from the core circle, along its normal.
    assert np.allclose(core + 0.3 * torus.normals, p)
    ico = g.icosphere(2, radius=2.0)
    assert np.allclose(ico.normals * 2.0, ico.positions)


def test_bezier_surface_is_open_smooth_and_interpolates_its_corners():
    patches, res = 3, 8
    mesh = g.bezier_surface(patches=patches, resolution=res)
    k = patches * res + 1
    assert len(mesh.positions) == k * k and len(mesh.triangles) == 2 * (k - 1) ** 2
    assert not mesh.closed and edge_problem(mesh.triangles) is not None
    net = g.bezier_control_net(patches)
    grid = mesh.positions.reshape(k, k, 3)
    # A Bezier patch passes through its corner control points; the seams hold all of them.
    for a in range(patches + 1):
        for b in range(patches + 1):
            assert grid[a * res, b * res] == pytest.approx(net[3 * a, 3 * b])
    # C1 across the seams: each seam control point is the midpoint of its neighbours across
    # the seam, so the tangents of the two patches meeting there are equal (FvDFH 11.3.4)...
    for seam in range(3, 3 * patches, 3):
        assert np.allclose(2 * net[seam], net[seam - 1] + net[seam + 1])
        assert np.allclose(2 * net[:, seam], net[:, seam - 1] + net[:, seam + 1])
    # ... and the normal turns smoothly, from one patch to the next as within a patch.
    fine = g.bezier_surface(patches=patches, resolution=16)
    k = patches * 16 + 1
    normals = fine.normals.reshape(k, k, 3)
    turn_s = np.einsum("abc,abc->ab", normals[1:], normals[:-1])
    turn_t = np.einsum("abc,abc->ab", normals[:, 1:], normals[:, :-1])
    assert turn_s.min() > np.cos(np.radians(12)) and turn_t.min() > np.cos(np.radians(12))
    # The analytic normal is perpendicular to the surface's edges meeting at the vertex.
    grid = fine.positions.reshape(k, k, 3)
    along = grid[1:, :, :] - grid[:-1, :, :]
    dots = np.einsum("abc,abc->ab", along, normals[:-1]) / np.linalg.norm(along, axis=2)
    assert np.abs(dots).max() < 0.1


def test_big_mesh_is_over_100k_triangles_and_closed():
    mesh = g.torus_knot()
    assert len(mesh.triangles) >= 100_000 and mesh.closed
    _, inverse = np.unique(mesh.positions, axis=0, return_inverse=True)
    assert edge_problem(inverse.reshape(-1)[mesh.triangles]) is None
    assert signed_volume(mesh.positions, mesh.triangles) > 0


@pytest.mark.parametrize("n", [1_000, 10_000, 100_000, 1_000_000])
def test_sphere_torus_has_about_the_requested_triangles(n):
    scene = g.sphere_torus(triangles=n)
    total = scene.triangle_count
    assert abs(total - n) <= 0.02 * n, total
    assert len(scene.meshes) == 2 and len(scene.views) >= 2 and scene.lights
    for mesh in scene.meshes:
        assert mesh.closed and mesh.normals is not None
        if n <= 10_000:
            _, inverse = np.unique(mesh.positions, axis=0, return_inverse=True)
            assert edge_problem(inverse.reshape(-1)[mesh.triangles]) is None
            assert signed_volume(mesh.positions, mesh.triangles) > 0
    sphere, ring = scene.meshes
    assert abs(len(sphere.triangles) - len(ring.triangles)) <= 0.1 * n


def test_house_is_unchanged():
    house = g.house()
    assert len(house.positions) == 10 and len(house.edges) == 15 and len(house.triangles) == 0
    assert house.positions[:, 2].tolist() == [54.0] * 5 + [30.0] * 5


@pytest.mark.parametrize("call, reason", [
    (lambda: g.torus(R=1.0, r=1.0), "r (1) must be smaller than R (1)"),
    (lambda: g.torus(segments=2), "segments must lie in 3..100000, got 2"),
    (lambda: g.uv_sphere(radius=-1.0), "radius must lie in"),
    (lambda: g.uv_sphere(radius=float("nan")), "radius must lie in"),
    (lambda: g.uv_sphere(segments=True), "segments must be a whole number"),
    (lambda: g.cube(subdivisions=2.5), "subdivisions must be a whole number"),
    (lambda: g.icosphere(10), "the limit is 4000000"),
    (lambda: g.uv_sphere(segments=100_000, rings=100_000), "the limit is 4000000"),
    (lambda: g.torus_knot(p=2, q=4), "no common factor"),
    (lambda: g.sphere_torus(triangles=10 ** 12), "triangles must lie in"),
])
def test_bad_parameters_are_refused_by_name(call, reason):
    with pytest.raises(ValueError) as caught:
        call()
    assert reason in str(caught.value)


def test_every_registered_generator_runs_with_its_defaults():
    for name, make in g.GENERATORS.items():
        mesh = make()
        assert len(mesh.positions) and (len(mesh.triangles) or len(mesh.edges)), name
        assert np.all(np.isfinite(mesh.positions)), name
