"""The hemicube draws each face with only the triangles that may be in its frustum
(core.radiosity.hemicube._face_frusta): the form factors are those of drawing every triangle
above the tangent plane on every face, to the bit (a consistency check: both draw through
our own pipeline), and a triangle left out of a face draws nothing there when drawn alone."""

from __future__ import annotations

import numpy as np
import pytest

from core.radiosity import hemicube
from core.radiosity.mesh import mesh_scene
from core.radiosity.solve import Shooter
from core.scene.formats import load_scene

from tests.conftest import ROOT

RES = 64


def _every_triangle_on_every_face(positions, triangles, point, normal, scale):
    """The form factors as the hemicube drew them before the faces chose their triangles."""
    top_df, side_df = hemicube.delta_factors(RES)
    out = np.zeros(len(triangles))
    height = (positions - point) @ normal
    above = np.flatnonzero(height[triangles].max(axis=1) > 0.0)
    for look, up, top in hemicube.faces(point, normal):
        items = hemicube.item_buffer(positions, np.ascontiguousarray(triangles[above]), point,
                                     look, up, top, RES, scale)
        seen = items >= 0
        out += np.bincount(above[items[seen]], weights=(top_df if top else side_df)[seen],
                           minlength=len(triangles))
    return out


def test_each_face_drawing_its_own_triangles_gives_the_same_form_factors_to_the_bit():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    e = mesh_scene(scene, max_elements=1500)
    shooter = Shooter(e, "hemicube", RES)
    rng = np.random.default_rng(2)
    for p in rng.choice(len(e.patch_centre), 12, replace=False):
        point, normal = e.patch_centre[p], e.patch_normal[p]
        got = hemicube.form_factors(shooter.positions, shooter.triangles, point, normal, RES,
                                    e.scale)
        want = _every_triangle_on_every_face(shooter.positions, shooter.triangles, point,
                                             normal, e.scale)
        assert got.sum() > 0.1
        assert np.array_equal(got, want)


@pytest.mark.parametrize("seed", range(3))
def test_a_triangle_left_out_of_a_face_draws_nothing_there_and_one_inside_is_kept(seed):
    rng = np.random.default_rng(seed)
    point, normal = np.array([0.1, -0.2, 0.3]), np.array([0.3, 0.5, 0.8])
    normal = normal / np.linalg.norm(normal)
    positions = point + rng.normal(size=(3 * 300, 3)) * rng.uniform(0.05, 2.0, (3 * 300, 1))
    triangles = np.arange(len(positions), dtype=np.int64).reshape(-1, 3)
    kept = np.empty((5, len(triangles)), np.bool_)
    frame = np.stack([*hemicube._basis(normal), normal])
    hemicube._face_frusta(positions, triangles, point, frame, 1e-9, kept)
    local = (positions - point) @ frame.T                       # (a, b, c) per corner
    a, b, c = local[:, 0], local[:, 1], local[:, 2]
    inside = [(abs(a) < c) & (abs(b) < c)] + [
        (abs(o) < s * w) & (c > 0) & (c < s * w) for w, o in ((a, b), (b, a)) for s in (1, -1)]
    # each face's pyramid as the planes x <= 0 it lies behind: left out exactly when all
    # three corners are beyond one of them
    planes = [[-c, a - c, -a - c, b - c, -b - c]] + [
        [-c, c - s * w, o - s * w, -o - s * w] for w, o in ((a, b), (b, a)) for s in (1, -1)]
    faces = hemicube.faces(point, normal)
    for f, (look, up, top) in enumerate(faces):
        beyond_one = np.any([(x[triangles] > 0).all(axis=1) for x in planes[f]], axis=0)
        assert np.array_equal(kept[f], ~beyond_one)
        has_inside_corner = inside[f][triangles].any(axis=1)
        assert kept[f][has_inside_corner].all()                 # never drops a visible one
        assert 0 < kept[f].sum() < len(triangles)
        for t in np.flatnonzero(~kept[f])[:40]:                 # the clipper rejects them
            items = hemicube.item_buffer(positions, triangles[t:t + 1], point, look, up, top,
                                         RES, 1.0)
            assert (items < 0).all()
