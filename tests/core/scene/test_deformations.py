"""Barr's taper, twist and bend on a [[geometry]], held to numbers worked by hand: a
twisted box's corner at height h turned by k·h, a taper's factor 1 + k h, a bent bar's centre
line wound onto a circle of radius 1/k with its length kept, and the normals J⁻ᵀ n against
the faces of the deformed mesh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.scene.formats import ReaderError, read_scene_file


def mesh_of(deform: str, generator: str = 'generator = "cube"\nparams = { subdivisions = 4 }',
            transform: str = "") -> object:
    text = f"""
[[geometry]]
{generator}
{transform}
deform = {deform}
"""
    return read_scene_file(text, "scene.toml").meshes[0]


def test_a_twisted_box_turns_each_height_by_k_h():
    """Twist about y at 30 degrees a unit: the corner (1, 1, 1) turns 30 degrees
    counter-clockwise seen from +y: z' = cos 30 - sin 30 = 0.3660, x' = sin 30 + cos 30 =
    1.3660; (1, -1, 1) turns -30 degrees: x' = cos 30 - sin 30, z' = sin 30 + cos 30."""
    plain = mesh_of('[{ twist = { axis = "y", rate = 0 } }]')
    twisted = mesh_of('[{ twist = { axis = "y", rate = 30 } }]')
    assert len(plain.positions) == len(twisted.positions)
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    for before, after in (((1, 1, 1), (s + c, 1, c - s)), ((1, -1, 1), (c - s, -1, s + c))):
        i = np.flatnonzero(np.all(np.isclose(plain.positions, before), axis=1))
        assert len(i) and np.allclose(twisted.positions[i], after, atol=1e-12)
    # every vertex: the same height, the same distance from the axis, turned by 30° · y
    p, q = plain.positions, twisted.positions
    assert np.allclose(q[:, 1], p[:, 1], atol=0)
    assert np.allclose(np.hypot(q[:, 0], q[:, 2]), np.hypot(p[:, 0], p[:, 2]), atol=1e-12)
    turn = np.arctan2(q[:, 0], q[:, 2]) - np.arctan2(p[:, 0], p[:, 2])
    off = np.hypot(p[:, 0], p[:, 2]) > 0
    assert np.allclose(np.angle(np.exp(1j * (turn[off] - np.radians(30) * p[off, 1]))), 0, atol=1e-12)


def test_a_taper_scales_across_the_axis_by_one_plus_k_h():
    plain = mesh_of('[{ taper = { axis = "z", rate = 0 } }]')
    tapered = mesh_of('[{ taper = { axis = "z", rate = 0.25 } }]')
    r = 1 + 0.25 * plain.positions[:, 2]                  # 0.75 at z = -1, 1.25 at z = 1
    assert np.allclose(tapered.positions[:, :2], plain.positions[:, :2] * r[:, None], atol=1e-15)
    assert np.array_equal(tapered.positions[:, 2], plain.positions[:, 2])
    top = np.flatnonzero(np.all(np.isclose(plain.positions, (1, -1, 1)), axis=1))
    assert np.allclose(tapered.positions[top], (1.25, -1.25, 1), atol=1e-15)


def test_a_bend_winds_the_axis_onto_a_circle_of_radius_one_over_k():
    """A bar along y from 0 to 3 bent at 30 degrees a unit toward +x from y0 = 0 over
    [0, 3]: its centre line (x = z = 0) goes to (1 - cos θ, sin θ) / k with θ = k y — on the
    circle about (1/k, 0), at arc length y; the part beyond y = 3 goes on straight along the
    tangent (at 90 degrees: along +x); a fibre at x = w lies at radius 1/k - w."""
    mesh = mesh_of('[{ bend = { axis = "y", toward = "x", rate = 30, range = [0, 3] } }]',
                   generator='generator = "cube"\nparams = { subdivisions = 12 }',
                   transform="transform = { scale = [0.25, 2, 0.25], translate = [0, 1.5, 0] }")
    k = math.radians(30)
    plain = mesh_of('[{ twist = { axis = "y", rate = 0 } }]',
                    generator='generator = "cube"\nparams = { subdivisions = 12 }',
                    transform="transform = { scale = [0.25, 2, 0.25], translate = [0, 1.5, 0] }")
    # the deformation acts in the object frame (before the translate): h runs from -2 to 2,
    # bent over [0, 3] of the object's own y; redo it by hand from the object's coordinates
    obj = plain.positions - [0, 1.5, 0]
    x, y, z = obj.T
    t = np.clip(y, 0, 3)
    theta = k * t
    X = -np.sin(theta) * (x - 1 / k) + 0 + np.cos(theta) * (y - t)
    Xs = np.cos(theta) * (x - 1 / k) + 1 / k + np.sin(theta) * (y - t)
    # Barr's (x, y, z) here are (z, y, x): Y_barr goes to y, Z_barr to x
    expected = np.column_stack([Xs, X, z]) + [0, 1.5, 0]
    assert np.allclose(mesh.positions, expected, atol=1e-12)
    # and the geometry, without the formula: the centre line's points lie 1/k from (1/k, 0)
    on_axis = (np.abs(x) < 1e-12) & (np.abs(z) < 1e-12) & (y >= 0) & (y <= 2)
    assert on_axis.sum() >= 1
    for w in (0.25, -0.25):
        fibre = np.isclose(x, w) & (y > 0) & (y <= 2)
        bent = mesh.positions[fibre] - [0, 1.5, 0]
        radius = np.hypot(bent[:, 0] - 1 / k, bent[:, 1])
        assert np.allclose(radius, 1 / k - w, atol=1e-12)
        # arc length along the fibre: the angle swept times the radius = y (1 - k w)
        angle = np.arctan2(bent[:, 1], 1 / k - bent[:, 0])
        assert np.allclose(angle * (1 / k - w), y[fibre] * (1 - k * w), atol=1e-12)
    below = y < 0                                    # the part before the range stays put
    assert np.allclose(mesh.positions[below], plain.positions[below], atol=1e-12)


def angles_to_the_faces(segments: int) -> np.ndarray:
    """Degrees between each vertex normal J^-T n of a twisted, tapered UV sphere and the
    area-weighted normal of the deformed faces around it (away from the poles' fans)."""
    mesh = mesh_of('[{ taper = { axis = "y", rate = -0.3 } }, { twist = { axis = "y", rate = 60 } }]',
                   generator=f'generator = "uv_sphere"\nparams = {{ segments = {segments}, '
                             f'rings = {segments // 2} }}')
    p, tri = mesh.positions, mesh.triangles
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    around = np.zeros_like(p)
    for corner in range(3):
        np.add.at(around, tri[:, corner], face)
    around /= np.linalg.norm(around, axis=1, keepdims=True)
    away = np.abs(p[:, 1]) < 0.9
    cos = np.sum(around[away] * mesh.normals[away], axis=1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def test_normals_follow_barrs_inverse_transpose_rule():
    """The faces know nothing of the Jacobian; as the sphere is tessellated finer they close
    in on J^-T n: the mean gap falls 4x for each halving of the facets (second order, as a
    face-averaged normal does on a smooth surface) and the largest (at the seam's one-sided
    vertices) 2x. A wrong rule would leave a gap that does not shrink."""
    coarse, fine = angles_to_the_faces(128), angles_to_the_faces(256)
    assert fine.mean() < 0.03 and coarse.mean() / fine.mean() > 3.5
    assert fine.max() < 1.5 and coarse.max() / fine.max() > 1.8


@pytest.mark.parametrize("deform,message", [
    ('[{ twist = { axis = "y", rate = nan } }]', ":6: geometry[1].deform[1].twist.rate: expected a finite number, got nan"),
    ('[{ taper = { axis = "y", rate = inf } }]', "geometry[1].deform[1].taper.rate: expected a finite number, got inf"),
    ('[{ bend = { rate = nan } }]', "geometry[1].deform[1].bend.rate: expected a finite number, got nan"),
    ('[{ bend = { rate = 30, range = [0, nan] } }]', "geometry[1].deform[1].bend.range[2]: expected a finite number"),
    ('[{ taper = { axis = "y", rate = 2 } }]',
     "geometry[1].deform[1]: the taper's scale 1 + k·y reaches 0 at y = -0.5, inside the mesh"),
    ('[{ bend = { axis = "y", rate = 80 } }]', "geometry[1].deform[1]: the bend's radius 1/k"),
    ('[{ bend = { axis = "y", rate = 0 } }]', "geometry[1].deform[1].bend.rate: a bend of rate 0"),
    ('[{ bend = { axis = "y", toward = "y", rate = 10 } }]', "the axis bends toward another axis"),
    ('[{ squash = { axis = "y" } }]', "geometry[1].deform[1].squash: unknown key 'squash' (allowed: taper, twist, bend)"),
    ('[{ twist = { axis = "w", rate = 1 } }]', "geometry[1].deform[1].twist.axis: 'w' is not one of x, y, z"),
    ('{ twist = { rate = 1 } }', "geometry[1].deform: expected a list of deformations"),
    ('[{ twist = { axis = "y" } }]', "geometry[1].deform[1].twist: a twist needs a rate"),
])
def test_bad_deformations_are_one_line_naming_file_line_and_key(deform, message):
    with pytest.raises(ReaderError) as error:
        mesh_of(deform)
    said = str(error.value)
    assert said.startswith("scene.toml:") and "\n" not in said and message in said, said


def test_the_shipped_scene_bends_its_bar_a_quarter_circle():
    """30 degrees a unit over the bar's 3 units: its top end face, turned 90 degrees, stands
    at x = 0.6 + 1/k (its translate plus the radius) for every one of its vertices."""
    scene = read_scene_file(open("scenes/barr_deformations.toml").read(),
                            "scenes/barr_deformations.toml")
    assert [m.name for m in scene.meshes][:4] == ["tapered", "twisted", "bent", "drill bit"]
    bent = scene.meshes[2].positions
    end = np.abs(bent[:, 0] - (0.6 + 1 / math.radians(30))) < 1e-9
    assert end.sum() >= 4 * 17 and bent[:, 0].max() <= 0.6 + 1 / math.radians(30) + 1e-9
