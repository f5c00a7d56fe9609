"""The departures from the course stated in docs/departures.md, each held to its evidence:
the attenuation cap and the option that lifts it, Möller–Trumbore against the notes'
"plane, then inside?" test, the startup code's vertex normals under ``--course-tri``, and
the TA's VRP note on the notes' Assignment #1 view.

Oracles: hand arithmetic, exact rationals (core.analysis.exact runs the model's own source in
Fractions: a consistency check of the float64 kernel, not an independent model), an
even-odd crossing count written here from the notes' words, numpy's cross products.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from core.analysis.exact import phong as exact_phong
from core.scene.formats import ReaderError, load_scene
from core.scene.formats.scenefile import read_scene_file
from core.scene.model import Light, Material
from core.shading import illumination as il

WHITE = Material(ka=0.0, kd=1.0, ks=0.0, n=1.0, od=(1.0, 1.0, 1.0))


def _lit(light: Light) -> np.ndarray:
    """The model at the origin, normal +z, light straight above: k_d N·L f_att = f_att."""
    surfaces, lights = il.pack_surfaces([WHITE], [False]), il.pack_lights([light])
    eye = il.pack_eye(il.Eye(np.array([0.0, 0.0, 5.0]), None))
    rgb = il.illuminate(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.zeros(1, np.int64),
                        surfaces, lights, np.zeros(3), eye, False)[0]
    twin = il.phong_point(0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0, surfaces, lights, np.zeros(3), eye,
                          False)
    assert np.array_equal(rgb, np.array(twin))
    return rgb


@pytest.mark.parametrize("c, capped, notes", [
    ((0.25, 0.0, 0.0), 1.0, 4.0),              # 1 / 0.25: FvDFH caps it, the notes do not
    ((0.25, 0.0, 0.25), 0.8, 0.8),             # 1 / (0.25 + 0.25 * 4) = 1 / 1.25
    ((0.25, 0.0, 1.0), 1 / 4.25, 1 / 4.25),    # the quiz's 1/R^2 with c1 = 0.25 beside it
    ((0.25, 0.5, 0.0), 0.8, 0.8),              # 1 / (0.25 + 0.5 * 2)
])
def test_attenuation_at_distance_two_capped_and_as_the_notes_write_it(c, capped, notes):
    # I_p = 1/8 so that the notes' 4 is not clipped by the model's clamp to 1
    position, dim = (0.0, 0.0, 2.0), (0.125, 0.125, 0.125)
    capped_light = Light(position=position, intensity=dim, attenuation=c)
    assert _lit(capped_light) == pytest.approx([capped / 8] * 3, rel=1e-15)
    uncapped = Light(position=position, intensity=dim, attenuation=c, attenuation_cap=False)
    assert _lit(uncapped) == pytest.approx([notes / 8] * 3, rel=1e-15)
    exact = exact_phong((0, 0, 0), (0, 0, 1), WHITE, [uncapped], (0, 0, 0), (0, 0, 5), None,
                        False)
    assert exact[0] == Fraction(1, 8) / (Fraction(c[0]) + 2 * Fraction(c[1])
                                         + 4 * Fraction(c[2]))


def test_the_scene_key_lifts_the_cap_and_refuses_what_is_not_a_boolean():
    text = ('[[light]]\nposition = [0, 0, 2]\nattenuation = [0.25, 0, 0]\n'
            'attenuation_cap = false\n[[geometry]]\ngenerator = "cube"\n')
    scene = read_scene_file(text, "cap.toml")
    assert scene.lights[0].attenuation_cap is False
    assert il.pack_lights(scene.lights)[0, il.LIGHT_CAP] == 0.0
    with pytest.raises(ReaderError, match=r"light\[1\]\.attenuation_cap: must be true .* not 'no'"):
        read_scene_file(text.replace("false", '"no"'), "cap.toml")


def _parity_inside(p, a, b, c, normal) -> bool:
    """The notes' test: a ray from P in the triangle's plane, odd crossings of its edges: in."""
    axis = int(np.argmax(np.abs(normal)))           # project onto the plane most face-on
    keep = [k for k in range(3) if k != axis]
    q, corners = p[keep], [v[keep] for v in (a, b, c)]
    crossings = 0
    for s, e in zip(corners, corners[1:] + corners[:1]):      # the ray: +u from q
        if (s[1] > q[1]) != (e[1] > q[1]):
            u = s[0] + (q[1] - s[1]) * (e[0] - s[0]) / (e[1] - s[1])
            crossings += u > q[0]
    return crossings % 2 == 1


def test_moller_trumbore_hits_what_the_notes_plane_and_parity_test_hits():
    from core.raytrace.intersect import triangle
    rng = np.random.default_rng(35)
    agree = near_edge = 0
    for _ in range(3000):
        a, b, c = rng.uniform(-1, 1, (3, 3))
        o, d = rng.uniform(-3, 3, 3), rng.normal(size=3)
        normal = np.cross(b - a, c - a)
        t_mt, u, v = triangle(*o, *d, a, b - a, c - a, 0.0, np.inf)
        # the notes: the plane A x + B y + C z + D = 0, t = -(A x0 + ... + D) / (A dx + ...)
        den = normal @ d
        t_plane = -(normal @ o - normal @ a) / den if den != 0 else np.inf
        hit = t_plane > 0 and _parity_inside(o + t_plane * d, a, b, c, normal)
        if np.isfinite(t_mt):
            assert t_mt == pytest.approx(t_plane, rel=1e-9, abs=1e-12)
            margin = min(u, v, 1 - u - v)
        else:
            margin = 1.0
        if hit == np.isfinite(t_mt):
            agree += 1
        else:                   # they may part only on an edge, where the parity ray grazes
            near_edge += 1
            assert margin < 1e-9 or not np.isfinite(t_mt)
    assert agree >= 2990 and agree + near_edge == 3000


def test_course_tri_averages_every_face_at_a_vertex_as_the_startup_code_does():
    from core.scene.course_tri import course_tri_scene
    scene = load_scene("scenes/few_triangles.tri")
    mesh = scene.meshes[0]
    distinct = np.unique(mesh.positions, axis=0)
    assert len(mesh.positions) > len(distinct)          # our reader split it at creases
    course = course_tri_scene(scene, scene.views[0]).meshes[0]
    assert len(course.positions) == len(distinct)       # one vertex per coordinate triple
    # each vertex normal: the mean of the unit normals of every face naming the vertex
    full = np.unique(mesh.positions, axis=0, return_inverse=True)[1].reshape(-1)[mesh.triangles]
    p = course.positions
    from core.scene.normals import orient_consistently
    oriented = orient_consistently(full)
    cross = np.cross(p[oriented[:, 1]] - p[oriented[:, 0]], p[oriented[:, 2]] - p[oriented[:, 0]])
    unit = cross / np.linalg.norm(cross, axis=1, keepdims=True)
    for vertex in range(len(p)):
        faces = np.flatnonzero((full == vertex).any(axis=1))
        mean = unit[faces].sum(axis=0)
        assert course.normals[vertex] == pytest.approx(mean / np.linalg.norm(mean), abs=1e-12)


def test_course_tri_changes_the_gouraud_picture_where_creases_were_split():
    from core.render import render
    from core.scene.course_tri import course_tri_scene
    from core.settings import RenderSettings
    scene = load_scene("scenes/few_triangles.tri")
    settings = RenderSettings.for_scene(scene, shading="gouraud", size=(100, 100))
    ours = render(scene, scene.views[0], settings).color
    course = render(course_tri_scene(scene, scene.views[0]), scene.views[0], settings).color
    assert (ours != course).any(axis=-1).sum() > 50


def test_the_tas_vrp_puts_the_house_behind_the_eye():
    """Assignment #1's view: the notes' VRP [0 0 54] frames the house; the TA's [0 0 -54]
    (the note that calls +54 wrong) leaves every edge outside the view volume."""
    from core.camera.view import View, normalizing_transform
    from core.pipeline.clip import clip_lines
    from core.scene.generators import house
    from core.transforms import apply
    mesh = house()
    edges = mesh.all_edges()
    drawn = {}
    for z in (54.0, -54.0):
        view = View(vrp=(0, 0, z), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 17),
                    prp=(8, 6, 30), front=10, back=-50)
        n, z_min = normalizing_transform(view, "perspective")
        points = apply(n, mesh.positions)[:, :3]
        q0, _ = clip_lines(points[edges[:, 0]], points[edges[:, 1]], "perspective", z_min)
        drawn[z] = len(q0)
        if z > 0:       # the notes' T(-VRP) has -54 in its last column: VRP_z = +54
            from core.camera.view import n_per_factors
            assert n_per_factors(view)["T_vrp"][2, 3] == -54.0
    assert drawn[54.0] == len(edges) and drawn[-54.0] == 0
